//! What one poll costs on the I2C wire, and whether the bus speed carries the poll rate.
//!
//! Bit times per transfer, as the poller issues them (each byte is 8 bits and its
//! acknowledge bit; a start, a repeated start and a stop count one bit time each):
//!
//! - **a sample** ([`WORD_READ_BIT_TIMES`], 38): start, address+R, the 2-byte word and its
//!   PEC byte, stop: `1 + 9 * 4 + 1`;
//! - **one housekeeping register read** ([`REGISTER_READ_BIT_TIMES`], 57, the longest: the
//!   2-byte version register with its PEC): start, address+W, register number, repeated
//!   start, address+R, 3 bytes, stop: `1 + 9 + 9 + 1 + 9 + 27 + 1`. The sample counter
//!   (39) and the status register with its PEC (48) are shorter. The polling thread makes at
//!   most one such read per poll (round-robin over the segments).
//!
//! So a poll of `n` segments takes `n * 38 + 57` bit times, `(n * 38 + 57) / speed_hz`
//! seconds, and a configuration whose polls would fill more than [`MAX_BUS_SHARE`] of the
//! poll period is refused with that arithmetic in the message (the rest is left for clock
//! stretching, the driver's gaps between transfers and the wake-up jitter). A real I2C
//! controller adds gaps of its own, so the bound is a floor on what a poll costs, not a
//! promise that it fits.
//!
//! ```
//! use host_daemon::hardware::bus_budget::BusBudget;
//!
//! // Nine segments at 1 kHz do not fit a 100 kHz bus...
//! let error = BusBudget::new(9, 1000.0, 100_000).check().unwrap_err();
//! assert!(error.contains("9 segments x 38 + 57 = 399 bit times"), "{error}");
//! // ...and they do at 1 MHz (Fast-mode Plus): 40 % of the period.
//! assert!(BusBudget::new(9, 1000.0, 1_000_000).check().is_ok());
//! ```

/// Bit times of one sample read (a 3-byte read: word and PEC).
pub const WORD_READ_BIT_TIMES: u64 = 38;
/// Bit times of the longest housekeeping register read (the version register with its PEC).
pub const REGISTER_READ_BIT_TIMES: u64 = 57;
/// The share of the poll period the bus may be busy with a poll's transfers.
pub const MAX_BUS_SHARE: f64 = 0.8;
/// `bus.speed_hz` of a real device when the configuration leaves it out: standard-mode I2C
/// (antenna-bus's, whose `[bus]` table the configuration reads).
pub use antenna_bus::config::DEFAULT_HARDWARE_SPEED_HZ;

/// A poll's transfers against the bus speed and the poll period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BusBudget {
    /// Segments read every poll.
    pub segments: usize,
    /// Polls per second.
    pub poll_hz: f64,
    /// The bus clock, hertz.
    pub speed_hz: u32,
}

impl BusBudget {
    /// The budget of `segments` polled at `poll_hz` on a bus clocked at `speed_hz`.
    pub fn new(segments: usize, poll_hz: f64, speed_hz: u32) -> Self {
        Self {
            segments,
            poll_hz,
            speed_hz,
        }
    }

    /// Bit times of one poll: every sample and one housekeeping register read.
    pub fn bit_times_per_poll(&self) -> u64 {
        self.segments as u64 * WORD_READ_BIT_TIMES + REGISTER_READ_BIT_TIMES
    }

    /// How long one poll keeps the bus busy, microseconds.
    pub fn poll_us(&self) -> f64 {
        self.bit_times_per_poll() as f64 * 1e6 / f64::from(self.speed_hz.max(1))
    }

    /// The poll period, microseconds.
    pub fn period_us(&self) -> f64 {
        1e6 / self.poll_hz
    }

    /// The share of the poll period the bus is busy (1.0: all of it).
    pub fn share(&self) -> f64 {
        self.poll_us() / self.period_us()
    }

    /// The fastest poll rate that stays within [`MAX_BUS_SHARE`], hertz.
    pub fn max_poll_hz(&self) -> f64 {
        MAX_BUS_SHARE * f64::from(self.speed_hz) / self.bit_times_per_poll() as f64
    }

    /// The slowest bus clock that carries `poll_hz` within [`MAX_BUS_SHARE`], hertz.
    pub fn min_speed_hz(&self) -> f64 {
        self.bit_times_per_poll() as f64 * self.poll_hz / MAX_BUS_SHARE
    }

    /// Whether the bus carries the polls; if not, why, with the arithmetic.
    pub fn check(&self) -> Result<(), String> {
        if self.speed_hz == 0 {
            return Err("must be positive (the bus clock in hertz, e.g. 100000)".to_owned());
        }
        if self.share() <= MAX_BUS_SHARE {
            return Ok(());
        }
        Err(format!(
            "the bus cannot carry bus.poll_hz = {poll_hz} with {n} segments: a poll takes \
             {n} segments x {word} + {register} = {bits} bit times (a 3-byte sample read each, \
             and one housekeeping register read), which at bus.speed_hz = {speed} is {poll_us:.0} \
             us, {percent:.0} % of the {period_us:.0} us poll period, above the {max:.0} % \
             allowed; lower bus.poll_hz to {max_hz:.0} or less, raise bus.speed_hz to {min_speed:.0} \
             or more (if the controller and every segment support it), or poll fewer segments",
            poll_hz = self.poll_hz,
            n = self.segments,
            word = WORD_READ_BIT_TIMES,
            register = REGISTER_READ_BIT_TIMES,
            bits = self.bit_times_per_poll(),
            speed = self.speed_hz,
            poll_us = self.poll_us(),
            percent = self.share() * 100.0,
            period_us = self.period_us(),
            max = MAX_BUS_SHARE * 100.0,
            // Rounded off the float noise first: 498749.99999 asks for 498750.
            max_hz = (self.max_poll_hz() + 1e-6).floor(),
            min_speed = (self.min_speed_hz() - 1e-6).ceil(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nine_segments_at_1_khz_on_100_khz_are_refused_with_the_numbers() {
        let budget = BusBudget::new(9, 1000.0, 100_000);
        assert_eq!(budget.bit_times_per_poll(), 399);
        assert!((budget.poll_us() - 3990.0).abs() < 1e-9);
        let error = budget.check().unwrap_err();
        for part in [
            "bus.poll_hz = 1000",
            "9 segments x 38 + 57 = 399 bit times",
            "bus.speed_hz = 100000 is 3990 us",
            "399 % of the 1000 us poll period",
            "above the 80 % allowed",
            "lower bus.poll_hz to 200 or less",
            "raise bus.speed_hz to 498750 or more",
        ] {
            assert!(error.contains(part), "{part:?} missing from: {error}");
        }
    }

    #[test]
    fn the_limit_is_80_percent_of_the_period() {
        // 9 segments at 400 kHz: 997.5 us of every 1000 us, refused; 500 Hz fits (50 %).
        assert!(BusBudget::new(9, 1000.0, 400_000).check().is_err());
        assert!(BusBudget::new(9, 500.0, 400_000).check().is_ok());
        // The largest rate it names is accepted, and a little more is not.
        let budget = BusBudget::new(9, 1000.0, 100_000);
        let max = budget.max_poll_hz();
        assert!(BusBudget::new(9, max, 100_000).check().is_ok());
        assert!(BusBudget::new(9, max * 1.01, 100_000).check().is_err());
        assert!(BusBudget::new(9, 100.0, 0).check().is_err());
    }
}
