//! The antenna segment's firmware logic (thesis 2.3.1): a Hall-effect angle sensor on a 10-bit
//! ADC, four touch switches, and an I2C target on the shared bus.
//!
//! `no_std`, no allocation, generic over small hardware traits. The behaviour is specified in
//! `firmware-segment/README.md`; `c-shim/` is the same logic in C for the P89LPC938, bit-exact
//! with this crate. The encoding (word, PEC, registers, address message) is
//! `antenna-protocol`'s.
//!
//! - Algorithms: [`oversample`] and [`adc_fault`], the [`Debouncer`], the byte-level I2C
//!   [`TargetMachine`] driven by [`BusEvent`]s (named after the LPC938's I2STAT codes).
//! - Hardware traits: [`AngleSource`] (one 10-bit conversion), [`TouchPort`] (four switches at
//!   one instant; [`TouchPins`] over embedded-hal pins), [`I2cTarget`] (a transaction-level
//!   target peripheral), [`AddressStore`] (the non-volatile address).
//! - [`Segment`]: owns the peripherals, [`Segment::sample`]s and [`Segment::serve`]s.
//!
//! # Example
//!
//! ```
//! use antenna_protocol::{SampleWord, TouchBits};
//! use core::convert::Infallible;
//! use firmware_segment::{
//!     AddressStore, AngleSource, I2cTarget, Parts, Segment, Served, TargetRequest, TouchPort,
//! };
//!
//! struct Adc(u16);
//! impl AngleSource for Adc {
//!     type Error = Infallible;
//!     fn convert(&mut self) -> Result<u16, Infallible> { Ok(self.0) }
//! }
//! struct Switches(u8);
//! impl TouchPort for Switches {
//!     type Error = Infallible;
//!     fn read_touch(&mut self) -> Result<TouchBits, Infallible> {
//!         Ok(TouchBits::from_bits_truncate(self.0))
//!     }
//! }
//! /// A controller that does one plain 2-byte read.
//! struct Bus { pending: Option<TargetRequest>, got: [u8; 2] }
//! impl I2cTarget for Bus {
//!     type Error = Infallible;
//!     fn set_address(&mut self, _: u8) -> Result<(), Infallible> { Ok(()) }
//!     fn listen(&mut self) -> Result<Option<TargetRequest>, Infallible> { Ok(self.pending.take()) }
//!     fn respond_to_write(&mut self, _: &mut [u8]) -> Result<usize, Infallible> { Ok(0) }
//!     fn respond_to_read(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
//!         self.got.copy_from_slice(&buf[..2]);
//!         Ok(2)
//!     }
//! }
//! struct Flash(Option<u8>);
//! impl AddressStore for Flash {
//!     type Error = Infallible;
//!     fn load(&mut self) -> Result<Option<u8>, Infallible> { Ok(self.0) }
//!     fn store(&mut self, address: u8) -> Result<(), Infallible> { self.0 = Some(address); Ok(()) }
//! }
//!
//! let parts = Parts {
//!     adc: Adc(512),
//!     touch: Switches(0b0001),
//!     i2c: Bus { pending: Some(TargetRequest::Read), got: [0; 2] },
//!     store: Flash(None),
//! };
//! let mut segment = Segment::new(parts).map_err(|e| e.error)?;
//! for _ in 0..3 {
//!     segment.sample()?; // three agreeing touch reads make the contact stable
//! }
//! assert_eq!(segment.target().word(), SampleWord::pack_truncate(2048, 0b0001));
//! assert_eq!(segment.target().counter(), 3);
//!
//! // The controller's pending plain read gets the word, high byte first.
//! assert_eq!(segment.serve()?, Served::Read { sent: 2 });
//! assert_eq!(segment.serve()?, Served::Nothing);
//! assert_eq!(segment.destroy().i2c.got, [0x80, 0x01]);
//! # Ok::<(), firmware_segment::SegmentError<Infallible, Infallible, Infallible, Infallible>>(())
//! ```
#![cfg_attr(not(test), no_std)]

mod address_store;
mod angle_source;
mod bus_event;
mod debounce;
mod error;
mod i2c_target;
mod oversample;
mod segment;
mod target;
mod touch_port;

pub use address_store::AddressStore;
pub use angle_source::AngleSource;
pub use bus_event::BusEvent;
pub use debounce::{Debouncer, TOUCH_STUCK_SAMPLES};
pub use error::SegmentError;
pub use i2c_target::{I2cTarget, TargetRequest};
pub use oversample::{ADC_MASK, OVERSAMPLE_COUNT, adc_fault, oversample};
pub use segment::{ErrorOf, InitError, Parts, Sample, Segment, Served};
pub use target::{IDLE_BYTE, Phase, StepResult, TargetMachine, TargetState};
pub use touch_port::{TouchPins, TouchPort};
