//! The I2C target state machine: byte-level, driven by [`BusEvent`]s, bit-exact with the C
//! shim's `seg_target_step` (`firmware-segment/README.md`, "I2C target state machine").

use crate::BusEvent;
use antenna_protocol::{
    AddressAssignment, FIRMWARE_VERSION, Register, SampleWord, StatusFlags, pec,
};

/// The byte transmitted when there is nothing to send (a read past the end).
pub const IDLE_BYTE: u8 = 0xFF;

/// What the target is in the middle of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[repr(u8)]
pub enum Phase {
    /// Not addressed.
    #[default]
    Idle = 0,
    /// Addressed for write: receiving a register number and payload.
    Writing = 1,
    /// Addressed for read: sending latched bytes.
    Reading = 2,
}

/// The whole state of a [`TargetMachine`], field for field as the C shim's `seg_target_t`.
///
/// Outside a transfer (phase [`Phase::Idle`]) every `write_*` and `read_*` field is zero, so
/// two idle machines with the same address, pointer and published sample compare equal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TargetState {
    /// The 7-bit address the segment answers at.
    pub address: u8,
    /// False while the segment still answers at its default address.
    pub address_set: bool,
    /// The register the next read returns (0x00 after reset and after every read).
    pub pointer: u8,
    /// What the target is in the middle of.
    pub phase: Phase,
    /// The register number of the write in progress.
    pub write_register: u8,
    /// Bytes received in the write in progress, register number included (saturating).
    pub write_len: u8,
    /// The first two payload bytes of a write to register 0x10.
    pub write_payload: [u8; 2],
    /// The write in progress will commit nothing (unknown register, over-long, NACKed data).
    pub write_bad: bool,
    /// The latched data bytes of the read in progress, then their PEC.
    pub read_buf: [u8; 3],
    /// Latched bytes, PEC included.
    pub read_len: u8,
    /// The next latched byte to send.
    pub read_index: u8,
    /// The last published sample word.
    pub word: u16,
    /// The last published status flags.
    pub status: u8,
    /// The sample counter, wrapping.
    pub counter: u8,
}

/// The answer to one [`BusEvent`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StepResult {
    /// The byte to transmit, for [`BusEvent::StartRead`] and [`BusEvent::ByteAcked`];
    /// [`IDLE_BYTE`] otherwise.
    pub tx: u8,
    /// Whether the next received byte is acknowledged (the AA bit).
    pub ack_next: bool,
    /// The segment moved to a new address ([`TargetMachine::address`]): persist it and
    /// reprogram the peripheral.
    pub address_changed: bool,
}

impl StepResult {
    const fn idle(ack_next: bool) -> Self {
        Self {
            tx: IDLE_BYTE,
            ack_next,
            address_changed: false,
        }
    }
}

/// The segment's I2C target: registers, pointer, read latching with PEC, address assignment.
///
/// ```
/// use antenna_protocol::{SampleWord, StatusFlags, DEFAULT_ADDRESS};
/// use firmware_segment::{BusEvent, TargetMachine};
///
/// let mut target = TargetMachine::new(DEFAULT_ADDRESS, false);
/// target.publish(SampleWord::pack_truncate(2048, 0b1001), StatusFlags::default());
/// // A plain read returns the word, high byte first.
/// assert_eq!(target.step(BusEvent::StartRead).tx, 0x80);
/// assert_eq!(target.step(BusEvent::ByteAcked).tx, 0x09);
/// target.step(BusEvent::ReadDone);
///
/// // Assign address 0x21: register 0x10, the address, its complement.
/// target.step(BusEvent::StartWrite);
/// for byte in [0x10, 0x21, 0xDE] {
///     target.step(BusEvent::DataAcked(byte));
/// }
/// assert!(target.step(BusEvent::Stop).address_changed);
/// assert_eq!(target.address(), 0x21);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TargetMachine {
    state: TargetState,
}

impl TargetMachine {
    /// A machine answering at `address` (`address_set` false while that is the default
    /// address), pointer 0x00, idle, nothing published yet (word, status and counter 0).
    pub const fn new(address: u8, address_set: bool) -> Self {
        Self {
            state: TargetState {
                address,
                address_set,
                pointer: Register::Word.number(),
                phase: Phase::Idle,
                write_register: 0,
                write_len: 0,
                write_payload: [0; 2],
                write_bad: false,
                read_buf: [0; 3],
                read_len: 0,
                read_index: 0,
                word: 0,
                status: 0,
                counter: 0,
            },
        }
    }

    /// A new sample: stores the word and status flags, and increments the sample counter
    /// (wrapping). A read already latched keeps the bytes it latched.
    pub fn publish(&mut self, word: SampleWord, status: StatusFlags) {
        self.state.word = word.raw();
        self.state.status = status.bits();
        self.state.counter = self.state.counter.wrapping_add(1);
    }

    /// Moves the machine to `address` without a bus transaction, e.g. to roll back an
    /// assignment that could not be persisted. Nothing else changes.
    pub fn set_address(&mut self, address: u8, address_set: bool) {
        self.state.address = address;
        self.state.address_set = address_set;
    }

    /// The 7-bit address the segment answers at.
    pub const fn address(&self) -> u8 {
        self.state.address
    }

    /// False while the segment still answers at its default address.
    pub const fn address_set(&self) -> bool {
        self.state.address_set
    }

    /// The register the next read returns.
    pub const fn pointer(&self) -> u8 {
        self.state.pointer
    }

    /// What the target is in the middle of.
    pub const fn phase(&self) -> Phase {
        self.state.phase
    }

    /// The last published sample word.
    pub const fn word(&self) -> SampleWord {
        SampleWord::from_raw(self.state.word)
    }

    /// The last published status flags (a read of register 0x02 takes bit 2 from
    /// [`TargetMachine::address_set`] at the time of the read instead).
    pub const fn status(&self) -> StatusFlags {
        StatusFlags::from_bits(self.state.status)
    }

    /// The sample counter.
    pub const fn counter(&self) -> u8 {
        self.state.counter
    }

    /// The whole state, for comparison with the C shim and for diagnostics.
    pub const fn state(&self) -> TargetState {
        self.state
    }

    /// Feeds one bus event and returns the byte to transmit and the AA bit.
    pub fn step(&mut self, event: BusEvent) -> StepResult {
        let s = &mut self.state;
        match event {
            BusEvent::StartWrite => {
                self.clear_transfer();
                self.state.phase = Phase::Writing;
                StepResult::idle(true)
            }
            BusEvent::DataAcked(byte) if s.phase == Phase::Writing => {
                let index = s.write_len;
                if index == 0 {
                    s.write_register = byte;
                    if Register::from_number(byte).is_err() {
                        s.write_bad = true;
                    }
                } else if s.write_register == Register::AssignAddress.number() && index <= 2 {
                    s.write_payload[usize::from(index - 1)] = byte;
                } else {
                    // A third payload byte, or any byte after a read-only register's number.
                    s.write_bad = true;
                }
                s.write_len = s.write_len.saturating_add(1);
                let ack_next = !s.write_bad
                    && s.write_register == Register::AssignAddress.number()
                    && s.write_len < 3;
                StepResult::idle(ack_next)
            }
            BusEvent::DataNacked(_) if s.phase == Phase::Writing => {
                s.write_bad = true;
                s.write_len = s.write_len.saturating_add(1);
                StepResult::idle(false)
            }
            BusEvent::Stop => {
                let mut result = StepResult::idle(true);
                match s.phase {
                    Phase::Writing if !s.write_bad => result.address_changed = self.commit_write(),
                    Phase::Reading => s.pointer = Register::Word.number(),
                    _ => {}
                }
                self.clear_transfer();
                self.state.phase = Phase::Idle;
                result
            }
            BusEvent::StartRead => {
                self.clear_transfer();
                self.latch();
                let s = &mut self.state;
                s.phase = Phase::Reading;
                s.read_index = 1;
                StepResult {
                    tx: s.read_buf[0],
                    ack_next: true,
                    address_changed: false,
                }
            }
            BusEvent::ByteAcked if s.phase == Phase::Reading => {
                let mut result = StepResult::idle(true);
                if let Some(&byte) =
                    s.read_buf[..usize::from(s.read_len)].get(usize::from(s.read_index))
                {
                    result.tx = byte;
                    s.read_index += 1;
                }
                result
            }
            BusEvent::ReadDone => {
                s.pointer = Register::Word.number();
                self.clear_transfer();
                self.state.phase = Phase::Idle;
                StepResult::idle(true)
            }
            BusEvent::BusError => {
                self.clear_transfer();
                self.state.phase = Phase::Idle;
                StepResult::idle(true)
            }
            BusEvent::DataAcked(_)
            | BusEvent::DataNacked(_)
            | BusEvent::ByteAcked
            | BusEvent::Other => StepResult::idle(true),
        }
    }

    /// Applies a complete, good write at STOP; returns whether the address changed.
    fn commit_write(&mut self) -> bool {
        let s = &mut self.state;
        match Register::from_number(s.write_register) {
            Ok(Register::AssignAddress) if s.write_len == 3 => {
                match AddressAssignment::from_payload(s.write_payload[0], s.write_payload[1]) {
                    Ok(assignment) => {
                        s.address = assignment.new_address();
                        s.address_set = true;
                        true
                    }
                    Err(_) => false,
                }
            }
            Ok(register) if s.write_len == 1 && register.read_len() > 0 => {
                s.pointer = register.number();
                false
            }
            _ => false,
        }
    }

    /// Latches the pointer register's bytes and their PEC into the read buffer.
    fn latch(&mut self) {
        let s = &mut self.state;
        let register = Register::from_number(s.pointer).unwrap_or(Register::Word);
        let status =
            StatusFlags::from_bits(s.status).with(StatusFlags::ADDRESS_NOT_SET, !s.address_set);
        let (data, len): ([u8; 2], usize) = match register {
            Register::Version => ([FIRMWARE_VERSION.0, FIRMWARE_VERSION.1], 2),
            Register::Status => ([status.bits(), 0], 1),
            Register::Counter => ([s.counter, 0], 1),
            // The pointer only ever holds a readable register; the word is the fallback.
            Register::Word | Register::AssignAddress => (s.word.to_be_bytes(), 2),
        };
        let mut crc = pec::update(0, pec::read_address_byte(s.address));
        for (slot, &byte) in s.read_buf.iter_mut().zip(&data[..len]) {
            *slot = byte;
            crc = pec::update(crc, byte);
        }
        s.read_buf[len] = crc;
        s.read_len = len as u8 + 1;
    }

    /// Drops the transfer in progress: every write and read field back to zero.
    fn clear_transfer(&mut self) {
        let s = &mut self.state;
        s.write_register = 0;
        s.write_len = 0;
        s.write_payload = [0; 2];
        s.write_bad = false;
        s.read_buf = [0; 3];
        s.read_len = 0;
        s.read_index = 0;
    }
}
