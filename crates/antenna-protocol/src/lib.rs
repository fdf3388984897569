//! The antenna segment protocol: the one owner of the encoding.
//!
//! Every segment of the robotic antenna (thesis 2.3.1) is an I2C target on one shared bus. The
//! firmware, its 8051 C shim, the host daemon and the simulated rig all speak the protocol
//! defined here (`docs/segment-protocol.md`); nothing else re-implements it.
//!
//! - [`SampleWord`]: 12-bit joint angle and 4 touch bits in one 16-bit word.
//! - [`pec`]: SMBus packet error code (CRC-8, polynomial 0x07, init 0).
//! - [`Register`]: the register map, [`StatusFlags`], [`FIRMWARE_VERSION`].
//! - [`AddressAssignment`]: the message that moves a segment to a new address.
//! - [`Calibration`]: counts to radians with a per-segment zero offset and direction.
//!
//! The crate is `no_std` and allocates nothing.
//!
//! # Example
//!
//! ```
//! use antenna_protocol::{Calibration, Direction, SampleWord, TouchBits, pec};
//!
//! // The segment packs angle count 2048 and touch switches 0 and 3.
//! let word = SampleWord::new(2048, TouchBits::from_bits(0b1001)?)?;
//! let bytes = word.to_be_bytes();
//! assert_eq!(bytes, [0x80, 0x09]);
//!
//! // A 3-byte read carries the PEC over (address << 1 | 1, high, low).
//! let address = 0x21;
//! let expected_pec = pec::word_read_pec(address, bytes);
//! let decoded = SampleWord::from_read_with_pec(address, [bytes[0], bytes[1], expected_pec])?;
//! assert_eq!(decoded, word);
//!
//! // The host turns counts into radians with the segment's calibration.
//! let calibration = Calibration::new(2048, Direction::CounterClockwise);
//! assert!(calibration.angle_rad(decoded.angle_counts()).abs() < 1e-12);
//! # Ok::<(), antenna_protocol::ProtocolError>(())
//! ```
#![cfg_attr(not(test), no_std)]

mod address;
mod calibration;
mod error;
pub mod pec;
mod register;
mod word;

pub use address::{
    AddressAssignment, DEFAULT_ADDRESS, MAX_ASSIGNABLE_ADDRESS, MIN_ASSIGNABLE_ADDRESS,
    is_assignable_address,
};
pub use calibration::{Calibration, Direction, RAD_PER_COUNT};
pub use error::ProtocolError;
pub use register::{FIRMWARE_VERSION, Register, StatusFlags};
pub use word::{ANGLE_COUNTS_PER_TURN, MAX_ANGLE_COUNT, SampleWord, TOUCH_MASK, TouchBits};
