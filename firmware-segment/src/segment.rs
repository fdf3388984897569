//! The segment: sampling and the I2C target over the hardware traits.

use crate::{
    AddressStore, AngleSource, BusEvent, Debouncer, I2cTarget, IDLE_BYTE, OVERSAMPLE_COUNT,
    SegmentError, TargetMachine, TargetRequest, TouchPort, adc_fault, oversample,
};
use antenna_protocol::{DEFAULT_ADDRESS, SampleWord, StatusFlags, is_assignable_address};

/// The [`SegmentError`] of a segment built from these peripherals.
pub type ErrorOf<A, T, I, S> = SegmentError<
    <A as AngleSource>::Error,
    <T as TouchPort>::Error,
    <I as I2cTarget>::Error,
    <S as AddressStore>::Error,
>;

/// The peripherals of a segment, as handed to [`Segment::new`] and back by
/// [`Segment::destroy`].
#[derive(Debug)]
pub struct Parts<A, T, I, S> {
    /// The angle sensor's ADC.
    pub adc: A,
    /// The four touch switches.
    pub touch: T,
    /// The I2C target peripheral.
    pub i2c: I,
    /// The non-volatile address store.
    pub store: S,
}

/// [`Segment::new`] failed: the error, and the peripherals handed back.
#[derive(Debug, thiserror::Error)]
#[error("segment start-up failed: {error}")]
pub struct InitError<A: AngleSource, T: TouchPort, I: I2cTarget, S: AddressStore> {
    /// What failed.
    pub error: ErrorOf<A, T, I, S>,
    /// The peripherals, untouched by the segment after the failure.
    pub parts: Parts<A, T, I, S>,
}

/// One published sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Sample {
    /// `(angle12 << 4) | debounced touch`.
    pub word: SampleWord,
    /// ADC fault, touch stuck, address not set.
    pub status: StatusFlags,
}

/// What [`Segment::serve`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Served {
    /// No controller had addressed the segment.
    Nothing,
    /// A write transaction of `received` bytes (register number included) that changed at
    /// most the register pointer.
    Write {
        /// Bytes the controller sent.
        received: usize,
    },
    /// A write that moved the segment to `address`, now persisted and programmed.
    AddressChanged {
        /// The new 7-bit address.
        address: u8,
    },
    /// A read transaction.
    Read {
        /// Bytes the controller took.
        sent: usize,
    },
}

/// One antenna segment: owns its peripherals, samples, and serves the I2C target.
///
/// The main loop calls [`Segment::sample`] once per sample period and [`Segment::serve`]
/// whenever the target peripheral may have a request. All protocol behaviour is the
/// [`TargetMachine`]'s; the transaction-level [`I2cTarget`] is translated into its bus events.
#[derive(Debug)]
pub struct Segment<A, T, I, S> {
    adc: A,
    touch: T,
    i2c: I,
    store: S,
    debouncer: Debouncer,
    target: TargetMachine,
}

impl<A, T, I, S> Segment<A, T, I, S>
where
    A: AngleSource,
    T: TouchPort,
    I: I2cTarget,
    S: AddressStore,
{
    /// Takes the peripherals, loads the address from the store (an empty store or an
    /// unassignable stored address means the default address, not set) and programs the
    /// target peripheral with it. On failure the peripherals come back in the error.
    pub fn new(parts: Parts<A, T, I, S>) -> Result<Self, InitError<A, T, I, S>> {
        let Parts {
            adc,
            touch,
            mut i2c,
            mut store,
        } = parts;
        let loaded = match store.load() {
            Ok(loaded) => loaded,
            Err(e) => {
                return Err(Self::init_error(
                    SegmentError::Store(e),
                    adc,
                    touch,
                    i2c,
                    store,
                ));
            }
        };
        let (address, address_set) = match loaded {
            Some(address) if is_assignable_address(address) => (address, true),
            _ => (DEFAULT_ADDRESS, false),
        };
        if let Err(e) = i2c.set_address(address) {
            return Err(Self::init_error(
                SegmentError::I2c(e),
                adc,
                touch,
                i2c,
                store,
            ));
        }
        Ok(Self {
            adc,
            touch,
            i2c,
            store,
            debouncer: Debouncer::new(),
            target: TargetMachine::new(address, address_set),
        })
    }

    fn init_error(
        error: ErrorOf<A, T, I, S>,
        adc: A,
        touch: T,
        i2c: I,
        store: S,
    ) -> InitError<A, T, I, S> {
        InitError {
            error,
            parts: Parts {
                adc,
                touch,
                i2c,
                store,
            },
        }
    }

    /// Hands the peripherals back.
    pub fn destroy(self) -> Parts<A, T, I, S> {
        Parts {
            adc: self.adc,
            touch: self.touch,
            i2c: self.i2c,
            store: self.store,
        }
    }

    /// One sample period: 16 conversions oversampled to 12 bits with the rail check, one
    /// read of the four touch switches, debouncing and the stuck check, then publish (word,
    /// status, counter + 1). On a peripheral error nothing is published.
    pub fn sample(&mut self) -> Result<Sample, ErrorOf<A, T, I, S>> {
        let mut conversions = [0u16; OVERSAMPLE_COUNT];
        for conversion in conversions.iter_mut() {
            *conversion = self.adc.convert().map_err(SegmentError::Adc)?;
        }
        let raw = self.touch.read_touch().map_err(SegmentError::Touch)?;
        let touch = self.debouncer.step(raw.bits());
        let status = StatusFlags::default()
            .with(StatusFlags::ADC_FAULT, adc_fault(&conversions))
            .with(StatusFlags::TOUCH_STUCK, self.debouncer.touch_stuck())
            .with(StatusFlags::ADDRESS_NOT_SET, !self.target.address_set());
        let word = SampleWord::pack_truncate(oversample(&conversions), touch.bits());
        self.target.publish(word, status);
        Ok(Sample { word, status })
    }

    /// Serves at most one transaction: polls [`I2cTarget::listen`] and runs the request
    /// through the [`TargetMachine`].
    ///
    /// A write is received into a 3-byte buffer (register number and two payload bytes, the
    /// longest valid write) and fed to the machine byte by byte, then STOP; a byte the
    /// machine would have NACKed is fed as NACKed, so the outcome is the byte-level port's. A
    /// read latches its bytes at the start (word, or register bytes, then PEC), the
    /// controller gets them and 0xFF past the end, then the pointer returns to the word. An
    /// address assignment is persisted first, then programmed into the peripheral; if it
    /// cannot be persisted the segment stays at its previous address.
    pub fn serve(&mut self) -> Result<Served, ErrorOf<A, T, I, S>> {
        match self.i2c.listen().map_err(SegmentError::I2c)? {
            None => Ok(Served::Nothing),
            Some(TargetRequest::Write) => self.serve_write(),
            Some(TargetRequest::Read) => self.serve_read(),
        }
    }

    fn serve_write(&mut self) -> Result<Served, ErrorOf<A, T, I, S>> {
        let (old_address, old_set) = (self.target.address(), self.target.address_set());
        let mut ack = self.target.step(BusEvent::StartWrite).ack_next;
        let mut buf = [0u8; 3];
        let received = match self.i2c.respond_to_write(&mut buf) {
            Ok(received) => received,
            Err(e) => {
                self.target.step(BusEvent::BusError);
                return Err(SegmentError::I2c(e));
            }
        };
        for byte in (0..received).map(|i| buf.get(i).copied().unwrap_or(IDLE_BYTE)) {
            let event = if ack {
                BusEvent::DataAcked(byte)
            } else {
                BusEvent::DataNacked(byte)
            };
            ack = self.target.step(event).ack_next;
        }
        if !self.target.step(BusEvent::Stop).address_changed {
            return Ok(Served::Write { received });
        }
        let address = self.target.address();
        if let Err(e) = self.store.store(address) {
            self.target.set_address(old_address, old_set);
            return Err(SegmentError::Store(e));
        }
        self.i2c.set_address(address).map_err(SegmentError::I2c)?;
        Ok(Served::AddressChanged { address })
    }

    fn serve_read(&mut self) -> Result<Served, ErrorOf<A, T, I, S>> {
        // The machine latches at StartRead; a read never has more than 3 latched bytes and
        // both the machine and the driver answer 0xFF past them.
        let mut buf = [IDLE_BYTE; 3];
        buf[0] = self.target.step(BusEvent::StartRead).tx;
        for slot in &mut buf[1..] {
            *slot = self.target.step(BusEvent::ByteAcked).tx;
        }
        let result = self.i2c.respond_to_read(&buf);
        match result {
            Ok(sent) => {
                self.target.step(BusEvent::ReadDone);
                Ok(Served::Read { sent })
            }
            Err(e) => {
                self.target.step(BusEvent::BusError);
                Err(SegmentError::I2c(e))
            }
        }
    }

    /// The I2C target state machine (address, pointer, published sample, counter).
    pub const fn target(&self) -> &TargetMachine {
        &self.target
    }

    /// The touch debouncer.
    pub const fn debouncer(&self) -> &Debouncer {
        &self.debouncer
    }

    /// The 7-bit address the segment answers at.
    pub const fn address(&self) -> u8 {
        self.target.address()
    }
}
