//! Fakes behind the segment's hardware traits, and the tests' own constants.
#![allow(dead_code, clippy::unwrap_used)]

use antenna_protocol::TouchBits;
use embedded_hal_mock::eh1::digital::{Mock as PinMock, State, Transaction as PinTransaction};
use firmware_segment::{
    AddressStore, AngleSource, BusEvent, I2cTarget, StepResult, TargetMachine, TargetRequest,
    TouchPins, TouchPort,
};
use std::collections::VecDeque;

/// An address the tests assign (not the default 0x77).
pub const ASSIGNED_ADDRESS: u8 = 0x21;
/// A mid-scale conversion: 16 of them oversample to 2048.
pub const MID_SCALE: u16 = 512;

/// Why a fake failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FakeError;

/// An ADC returning scripted conversions, then failing.
#[derive(Debug, Default)]
pub struct FakeAdc {
    pub conversions: VecDeque<u16>,
}

impl FakeAdc {
    pub fn new() -> Self {
        Self::default()
    }

    /// Scripts one sample of 16 conversions.
    pub fn push_sample(&mut self, conversions: [u16; 16]) {
        self.conversions.extend(conversions);
    }

    /// Scripts `samples` samples of 16 equal conversions.
    pub fn push_constant(&mut self, value: u16, samples: usize) {
        self.conversions
            .extend(std::iter::repeat_n(value, 16 * samples));
    }
}

impl AngleSource for FakeAdc {
    type Error = FakeError;

    fn convert(&mut self) -> Result<u16, FakeError> {
        self.conversions.pop_front().ok_or(FakeError)
    }
}

/// A touch port returning one fixed raw value (for long runs).
#[derive(Debug, Default)]
pub struct FakeTouch {
    pub raw: u8,
}

impl TouchPort for FakeTouch {
    type Error = FakeError;

    fn read_touch(&mut self) -> Result<TouchBits, FakeError> {
        Ok(TouchBits::from_bits_truncate(self.raw))
    }
}

/// Four mock pins scripted for a sequence of raw touch reads (bit i is pin i).
pub fn touch_pins(raw_reads: &[u8]) -> TouchPins<PinMock> {
    let pin = |bit: u8| {
        let transactions: Vec<PinTransaction> = raw_reads
            .iter()
            .map(|raw| {
                PinTransaction::get(if raw & (1 << bit) != 0 {
                    State::High
                } else {
                    State::Low
                })
            })
            .collect();
        PinMock::new(&transactions)
    };
    TouchPins::new([pin(0), pin(1), pin(2), pin(3)])
}

/// Checks every scripted pin transaction was consumed.
pub fn pins_done(pins: TouchPins<PinMock>) {
    for mut pin in pins.destroy() {
        pin.done();
    }
}

/// One scripted controller transaction.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Scripted {
    /// The controller writes these bytes.
    Write(Vec<u8>),
    /// The controller reads this many bytes.
    Read(usize),
    /// The peripheral fails during the transfer.
    Fail(TargetRequest),
}

/// A target peripheral playing scripted controller transactions.
#[derive(Debug, Default)]
pub struct FakeBus {
    pub script: VecDeque<Scripted>,
    current: Option<Scripted>,
    /// The bytes each read got, in order.
    pub reads: Vec<Vec<u8>>,
    /// The address last programmed.
    pub address: Option<u8>,
}

impl FakeBus {
    pub fn new(script: impl IntoIterator<Item = Scripted>) -> Self {
        Self {
            script: script.into_iter().collect(),
            ..Self::default()
        }
    }
}

impl I2cTarget for FakeBus {
    type Error = FakeError;

    fn set_address(&mut self, address: u8) -> Result<(), FakeError> {
        self.address = Some(address);
        Ok(())
    }

    fn listen(&mut self) -> Result<Option<TargetRequest>, FakeError> {
        self.current = self.script.pop_front();
        Ok(self.current.as_ref().map(|s| match s {
            Scripted::Write(_) => TargetRequest::Write,
            Scripted::Read(_) => TargetRequest::Read,
            Scripted::Fail(request) => *request,
        }))
    }

    fn respond_to_write(&mut self, buf: &mut [u8]) -> Result<usize, FakeError> {
        match self.current.take() {
            Some(Scripted::Write(bytes)) => {
                for (slot, byte) in buf.iter_mut().zip(&bytes) {
                    *slot = *byte;
                }
                Ok(bytes.len())
            }
            _ => Err(FakeError),
        }
    }

    fn respond_to_read(&mut self, buf: &[u8]) -> Result<usize, FakeError> {
        match self.current.take() {
            Some(Scripted::Read(n)) => {
                let got = (0..n)
                    .map(|i| buf.get(i).copied().unwrap_or(0xFF))
                    .collect();
                self.reads.push(got);
                Ok(n)
            }
            _ => Err(FakeError),
        }
    }
}

/// A non-volatile store in RAM, optionally failing writes.
#[derive(Debug, Default)]
pub struct FakeStore {
    pub stored: Option<u8>,
    pub fail_load: bool,
    pub fail_store: bool,
}

impl AddressStore for FakeStore {
    type Error = FakeError;

    fn load(&mut self) -> Result<Option<u8>, FakeError> {
        if self.fail_load {
            Err(FakeError)
        } else {
            Ok(self.stored)
        }
    }

    fn store(&mut self, address: u8) -> Result<(), FakeError> {
        if self.fail_store {
            return Err(FakeError);
        }
        self.stored = Some(address);
        Ok(())
    }
}

/// What the target answered to one controller write, byte by byte.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WriteAnswer {
    /// Per byte: whether it was ACKed (whether it arrived as `DataAcked`).
    pub acked: Vec<bool>,
    /// The STOP's result.
    pub stop: StepResult,
}

/// A controller write at byte level: START+W, each byte ACKed or NACKed as the target's
/// previous AA bit said, STOP.
pub fn write(target: &mut TargetMachine, bytes: &[u8]) -> WriteAnswer {
    let mut ack = target.step(BusEvent::StartWrite).ack_next;
    let mut acked = Vec::new();
    for &byte in bytes {
        acked.push(ack);
        let event = if ack {
            BusEvent::DataAcked(byte)
        } else {
            BusEvent::DataNacked(byte)
        };
        ack = target.step(event).ack_next;
    }
    let stop = target.step(BusEvent::Stop);
    WriteAnswer { acked, stop }
}

/// A controller read of `n` bytes at byte level: START+R, ByteAcked for each further byte,
/// ReadDone.
pub fn read(target: &mut TargetMachine, n: usize) -> Vec<u8> {
    let mut bytes = Vec::new();
    if n == 0 {
        return bytes;
    }
    bytes.push(target.step(BusEvent::StartRead).tx);
    for _ in 1..n {
        bytes.push(target.step(BusEvent::ByteAcked).tx);
    }
    let done = target.step(BusEvent::ReadDone);
    assert!(done.ack_next);
    bytes
}
