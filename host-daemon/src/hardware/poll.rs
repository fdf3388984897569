//! Polling the segments: one PEC-checked read per segment, decoded with `antenna-protocol`,
//! with per-segment health kept as the poll goes on; and the housekeeping reads of one
//! segment's register at a time (its sample counter, its status flags, its firmware version).
//!
//! A bus error is sorted by its [`ErrorKind`]: a missing acknowledge of the address (or of
//! unknown source, which is how Linux drivers that answer `EREMOTEIO` report it, see
//! [`crate::hardware::i2c_bus`]) is a [`PollError::Nack`]; anything else a [`PollError::Bus`]. Both
//! are counted per segment in its [`SegmentHealth`].

use antenna_protocol::{ProtocolError, Register, SampleWord, StatusFlags, pec};
use embedded_hal::i2c::{Error as _, ErrorKind, I2c, NoAcknowledgeSource};

/// Why a segment's sample is missing from a poll.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum PollError {
    /// The segment did not acknowledge its address.
    #[error("segment {address:#04x} did not answer (NACK)")]
    Nack {
        /// The 7-bit address polled.
        address: u8,
    },
    /// The 3-byte read came back with a PEC that does not match its data.
    #[error("segment {address:#04x}: {source}")]
    Corrupted {
        /// The 7-bit address polled.
        address: u8,
        /// The PEC mismatch.
        source: ProtocolError,
    },
    /// Any other bus error.
    #[error("segment {address:#04x}: bus error {kind:?}")]
    Bus {
        /// The 7-bit address polled.
        address: u8,
        /// What the bus reported.
        kind: ErrorKind,
    },
}

/// Counts of what happened to one segment's polls.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SegmentHealth {
    /// Good samples.
    pub ok: u64,
    /// Polls the segment did not acknowledge.
    pub nacks: u64,
    /// Polls whose PEC did not match.
    pub pec_errors: u64,
    /// Other bus errors.
    pub bus_errors: u64,
    /// Counter checks ([`Poller::check_counters`]) that found the sample counter where the
    /// previous check left it: the segment answers but publishes no new samples.
    pub stale: u64,
}

impl SegmentHealth {
    /// Whether the last poll was good is not kept here; this says whether every poll and
    /// every counter check was.
    pub fn all_ok(&self) -> bool {
        self.nacks == 0 && self.pec_errors == 0 && self.bus_errors == 0 && self.stale == 0
    }
}

/// What a counter check ([`Poller::check_counters`]) found for one segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CounterCheck {
    /// The counter has moved since the last check (or this is the first check).
    Moving,
    /// The counter has not moved since the last check.
    Stale,
    /// The counter could not be read (NACK or bus error); nothing is concluded.
    Unread,
}

/// One segment's result in one poll.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SegmentReading {
    /// The 7-bit address polled.
    pub address: u8,
    /// The sample, or why there is none.
    pub result: Result<SampleWord, PollError>,
}

/// Polls a fixed list of segment addresses on a bus it owns.
#[derive(Debug)]
pub struct Poller<I> {
    bus: I,
    addresses: Vec<u8>,
    health: Vec<SegmentHealth>,
    counters: Vec<Option<u8>>,
}

impl<I: I2c> Poller<I> {
    /// A poller over `bus` (taken by value; [`Poller::destroy`] gives it back) for segments at
    /// `addresses`, base to tip.
    pub fn new(bus: I, addresses: &[u8]) -> Self {
        Self {
            bus,
            addresses: addresses.to_vec(),
            health: vec![SegmentHealth::default(); addresses.len()],
            counters: vec![None; addresses.len()],
        }
    }

    /// The addresses polled, base to tip.
    pub fn addresses(&self) -> &[u8] {
        &self.addresses
    }

    /// Reads every segment's sample counter ([`Poller::check_counter`] on each in turn).
    pub fn check_counters(&mut self) -> Vec<CounterCheck> {
        (0..self.addresses.len())
            .map(|index| self.check_counter(index))
            .collect()
    }

    /// Reads segment `index`'s sample counter (register 0x03) and compares it with its
    /// previous check: a counter that has not moved marks the segment stale (counted in its
    /// health). Check a segment less often than it samples, so a healthy counter always
    /// moves. [`CounterCheck::Unread`] for an index past the end.
    pub fn check_counter(&mut self, index: usize) -> CounterCheck {
        let Some(&address) = self.addresses.get(index) else {
            return CounterCheck::Unread;
        };
        let mut counter = [0u8; 1];
        match self
            .bus
            .write_read(address, &[Register::Counter.number()], &mut counter)
        {
            Err(_) => CounterCheck::Unread,
            Ok(()) => {
                let previous = self.counters[index].replace(counter[0]);
                if previous == Some(counter[0]) {
                    self.health[index].stale += 1;
                    CounterCheck::Stale
                } else {
                    CounterCheck::Moving
                }
            }
        }
    }

    /// Reads segment `index`'s status register (0x02) with its PEC. Not counted in the
    /// segment's health (which counts polls).
    pub fn read_status(&mut self, index: usize) -> Result<StatusFlags, PollError> {
        let address = self.address_at(index)?;
        let [flags] = read_register::<_, 1>(&mut self.bus, address, Register::Status)?;
        Ok(StatusFlags::from_bits(flags))
    }

    /// Reads segment `index`'s firmware version register (0x01) with its PEC: (major,
    /// minor). Not counted in the segment's health.
    pub fn read_version(&mut self, index: usize) -> Result<(u8, u8), PollError> {
        let address = self.address_at(index)?;
        let [major, minor] = read_register::<_, 2>(&mut self.bus, address, Register::Version)?;
        Ok((major, minor))
    }

    /// The address of segment `index`; past the end, a NACK from the general-call address
    /// (nothing was sent).
    fn address_at(&self, index: usize) -> Result<u8, PollError> {
        self.addresses
            .get(index)
            .copied()
            .ok_or(PollError::Nack { address: 0 })
    }

    /// Reads every segment once: word and PEC in one 3-byte read each. A failing segment is
    /// recorded in its health and the poll goes on to the next.
    pub fn poll_all(&mut self) -> Vec<SegmentReading> {
        let mut readings = Vec::with_capacity(self.addresses.len());
        for (index, &address) in self.addresses.iter().enumerate() {
            let result = read_word(&mut self.bus, address);
            let health = &mut self.health[index];
            match result {
                Ok(_) => health.ok += 1,
                Err(PollError::Nack { .. }) => health.nacks += 1,
                Err(PollError::Corrupted { .. }) => health.pec_errors += 1,
                Err(PollError::Bus { .. }) => health.bus_errors += 1,
            }
            readings.push(SegmentReading { address, result });
        }
        readings
    }

    /// Health per segment, in address-list order.
    pub fn health(&self) -> &[SegmentHealth] {
        &self.health
    }

    /// The bus, e.g. to change a simulated segment.
    pub fn bus_mut(&mut self) -> &mut I {
        &mut self.bus
    }

    /// Gives the bus back.
    pub fn destroy(self) -> I {
        self.bus
    }
}

/// A bus error of a transfer to `address`, sorted: a missing acknowledge of the address (or
/// of unknown source) is a NACK, anything else a bus error.
fn bus_error(address: u8, kind: ErrorKind) -> PollError {
    match kind {
        ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address)
        | ErrorKind::NoAcknowledge(NoAcknowledgeSource::Unknown) => PollError::Nack { address },
        kind => PollError::Bus { address, kind },
    }
}

fn read_word<I: I2c>(bus: &mut I, address: u8) -> Result<SampleWord, PollError> {
    let mut bytes = [0u8; 3];
    bus.read(address, &mut bytes)
        .map_err(|error| bus_error(address, error.kind()))?;
    SampleWord::from_read_with_pec(address, bytes)
        .map_err(|source| PollError::Corrupted { address, source })
}

/// Reads `register`'s `N` bytes and its PEC byte (over the read address byte and the data).
fn read_register<I: I2c, const N: usize>(
    bus: &mut I,
    address: u8,
    register: Register,
) -> Result<[u8; N], PollError> {
    // N + 1 <= 3: the registers read here are at most 2 bytes.
    let mut bytes = [0u8; 3];
    let received = bytes.get_mut(..=N).ok_or(PollError::Corrupted {
        address,
        source: ProtocolError::BadLength {
            expected: 3,
            actual: N + 1,
        },
    })?;
    bus.write_read(address, &[register.number()], received)
        .map_err(|error| bus_error(address, error.kind()))?;
    let mut crc = pec::update(0, pec::read_address_byte(address));
    let mut data = [0u8; N];
    for (slot, &byte) in data.iter_mut().zip(received.iter()) {
        *slot = byte;
        crc = pec::update(crc, byte);
    }
    if crc != received[N] {
        return Err(PollError::Corrupted {
            address,
            source: ProtocolError::PecMismatch {
                received: received[N],
                computed: crc,
            },
        });
    }
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::*;
    use antenna_protocol::pec;
    use embedded_hal::i2c::ErrorKind;
    use embedded_hal_mock::eh1::i2c::{Mock, Transaction};

    #[test]
    fn good_corrupt_and_silent_segments_are_each_recorded() {
        let good = [0x80, 0x09, pec::word_read_pec(0x21, [0x80, 0x09])];
        let corrupt = [0x80, 0x09, good[2] ^ 0x01];
        let expectations = [
            Transaction::read(0x21, good.to_vec()),
            Transaction::read(0x22, corrupt.to_vec()),
            Transaction::read(0x23, vec![0, 0, 0])
                .with_error(ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address)),
        ];
        let mut poller = Poller::new(Mock::new(&expectations), &[0x21, 0x22, 0x23]);
        let readings = poller.poll_all();
        assert_eq!(readings[0].result, Ok(SampleWord::from_raw(0x8009)));
        assert!(matches!(
            readings[1].result,
            Err(PollError::Corrupted { address: 0x22, .. })
        ));
        assert_eq!(readings[2].result, Err(PollError::Nack { address: 0x23 }));
        let health = poller.health();
        assert_eq!(
            (health[0].ok, health[1].pec_errors, health[2].nacks),
            (1, 1, 1)
        );
        assert!(health[0].all_ok() && !health[1].all_ok());
        poller.destroy().done();
    }

    #[test]
    fn bus_errors_are_counted_per_segment_apart_from_nacks() {
        let good = [0x80, 0x09, pec::word_read_pec(0x21, [0x80, 0x09])];
        let expectations = [
            Transaction::read(0x21, good.to_vec()),
            Transaction::read(0x22, vec![0, 0, 0]).with_error(ErrorKind::Bus),
            Transaction::read(0x23, vec![0, 0, 0]).with_error(ErrorKind::ArbitrationLoss),
            Transaction::read(0x21, vec![0, 0, 0])
                .with_error(ErrorKind::NoAcknowledge(NoAcknowledgeSource::Unknown)),
            Transaction::read(0x22, vec![0, 0, 0]).with_error(ErrorKind::Other),
            Transaction::read(0x23, good.to_vec()),
        ];
        let mut poller = Poller::new(Mock::new(&expectations), &[0x21, 0x22, 0x23]);
        poller.poll_all();
        let readings = poller.poll_all();
        assert_eq!(readings[0].result, Err(PollError::Nack { address: 0x21 }));
        assert_eq!(
            readings[1].result,
            Err(PollError::Bus {
                address: 0x22,
                kind: ErrorKind::Other
            })
        );
        let counts: Vec<_> = poller
            .health()
            .iter()
            .map(|h| (h.ok, h.nacks, h.bus_errors))
            .collect();
        assert_eq!(counts, vec![(1, 1, 0), (0, 0, 2), (0, 0, 1)]);
        poller.destroy().done();
    }

    #[test]
    fn status_and_version_registers_are_read_with_their_pec() {
        let register_pec = |address: u8, data: &[u8]| {
            let mut bytes = vec![pec::read_address_byte(address)];
            bytes.extend_from_slice(data);
            pec::compute(&bytes)
        };
        let flags = StatusFlags::ADC_FAULT | StatusFlags::TOUCH_STUCK;
        let expectations = [
            Transaction::write_read(
                0x21,
                vec![Register::Status.number()],
                vec![flags, register_pec(0x21, &[flags])],
            ),
            Transaction::write_read(
                0x22,
                vec![Register::Version.number()],
                vec![1, 0, register_pec(0x22, &[1, 0])],
            ),
            // A corrupted version read is refused, not believed.
            Transaction::write_read(
                0x22,
                vec![Register::Version.number()],
                vec![9, 9, register_pec(0x22, &[1, 0])],
            ),
            Transaction::write_read(0x21, vec![Register::Status.number()], vec![0, 0])
                .with_error(ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address)),
        ];
        let mut poller = Poller::new(Mock::new(&expectations), &[0x21, 0x22]);
        let status = poller.read_status(0).unwrap();
        assert!(status.adc_fault() && status.touch_stuck() && !status.address_not_set());
        assert_eq!(poller.read_version(1), Ok((1, 0)));
        assert!(matches!(
            poller.read_version(1),
            Err(PollError::Corrupted { address: 0x22, .. })
        ));
        assert_eq!(
            poller.read_status(0),
            Err(PollError::Nack { address: 0x21 })
        );
        // Past the end nothing is sent.
        assert!(poller.read_status(2).is_err());
        // Housekeeping reads are not polls: the health counts none of them.
        assert!(
            poller
                .health()
                .iter()
                .all(|h| *h == SegmentHealth::default())
        );
        poller.destroy().done();
    }

    #[test]
    fn the_simulated_firmware_answers_its_status_and_version() {
        use crate::{SimBus, SimSegment};
        use antenna_protocol::{Calibration, Direction, FIRMWARE_VERSION};
        // Segment 0x22's zero is at count 0: straight, its Hall sensor sits on the rail.
        let bus = SimBus::new(vec![
            SimSegment::new(0x21, Calibration::new(2048, Direction::CounterClockwise)),
            SimSegment::new(0x22, Calibration::new(0, Direction::CounterClockwise)),
        ]);
        let mut poller = Poller::new(bus, &[0x21, 0x22]);
        poller.bus_mut().sample_all();
        assert_eq!(poller.read_version(0), Ok(FIRMWARE_VERSION));
        assert_eq!(poller.read_status(0), Ok(StatusFlags::default()));
        assert!(poller.read_status(1).unwrap().adc_fault());
        // The register pointer is back on the word: the next poll reads a sample.
        assert!(poller.poll_all()[0].result.is_ok());
    }
}
