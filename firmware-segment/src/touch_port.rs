//! The four touch switches, read at one instant.

use antenna_protocol::TouchBits;
use embedded_hal::digital::{Error as _, ErrorKind, InputPin};

/// The four touch switches of a segment, read together.
///
/// Contract: one call returns all four raw (not debounced) switch states from one instant,
/// bit 0 the most proximal switch, 1 = contact. On the 8051 that is one port read; on a
/// generic port [`TouchPins`] reads four pins back to back.
pub trait TouchPort {
    /// Why the read failed.
    type Error: core::fmt::Debug;

    /// The four raw switch states.
    fn read_touch(&mut self) -> Result<TouchBits, Self::Error>;
}

impl<T: TouchPort + ?Sized> TouchPort for &mut T {
    type Error = T::Error;

    fn read_touch(&mut self) -> Result<TouchBits, Self::Error> {
        T::read_touch(self)
    }
}

/// A [`TouchPort`] over four embedded-hal [`InputPin`]s, switch 0 (most proximal) first.
///
/// The pins are read back to back, pin 0 to pin 3, with nothing in between: on a
/// microcontroller that is a few bus cycles, far below the switches' millisecond bounce, so
/// the four bits are one instant for the debouncer. A pin reading high is a contact (wire the
/// switches, or configure the HAL's pins, so). A pin error is reported as its
/// [`ErrorKind`] and ends the read.
///
/// ```
/// use embedded_hal_mock::eh1::digital::{Mock, State, Transaction};
/// use firmware_segment::{TouchPins, TouchPort};
///
/// let pin = |state| Mock::new(&[Transaction::get(state)]);
/// let mut port = TouchPins::new([
///     pin(State::High),
///     pin(State::Low),
///     pin(State::Low),
///     pin(State::High),
/// ]);
/// assert_eq!(port.read_touch()?.bits(), 0b1001);
/// for mut pin in port.destroy() {
///     pin.done();
/// }
/// # Ok::<(), embedded_hal::digital::ErrorKind>(())
/// ```
#[derive(Debug)]
pub struct TouchPins<P> {
    pins: [P; 4],
}

impl<P: InputPin> TouchPins<P> {
    /// Takes the four pins, switch 0 first.
    pub const fn new(pins: [P; 4]) -> Self {
        Self { pins }
    }

    /// Hands the pins back.
    pub fn destroy(self) -> [P; 4] {
        self.pins
    }
}

impl<P: InputPin> TouchPort for TouchPins<P> {
    type Error = ErrorKind;

    fn read_touch(&mut self) -> Result<TouchBits, ErrorKind> {
        let mut bits = 0u8;
        for (bit, pin) in self.pins.iter_mut().enumerate() {
            if pin.is_high().map_err(|e| e.kind())? {
                bits |= 1 << bit;
            }
        }
        Ok(TouchBits::from_bits_truncate(bits))
    }
}
