//! Debouncing the four touch switches, and the stuck-switch detector.

use antenna_protocol::{TOUCH_MASK, TouchBits};

/// Consecutive samples a debounced touch bit may read 1 before it counts as stuck: one minute
/// at 1 kHz.
pub const TOUCH_STUCK_SAMPLES: u16 = 60000;

/// Three-sample debouncer over the four touch bits, with a per-bit hold counter.
///
/// A bit changes its debounced value only when the last three raw reads of it agree; all
/// state starts at 0. Each debounced bit that reads 1 counts consecutive samples (saturating);
/// [`Debouncer::touch_stuck`] reports a count that reached [`TOUCH_STUCK_SAMPLES`], and the
/// bit's release clears its count. Bit-exact with the C shim's `seg_debounce_t`.
///
/// ```
/// use firmware_segment::Debouncer;
/// let mut debouncer = Debouncer::new();
/// assert_eq!(debouncer.step(0b0001).bits(), 0); // one read is a bounce
/// assert_eq!(debouncer.step(0b0001).bits(), 0);
/// assert_eq!(debouncer.step(0b0001).bits(), 0b0001); // three agreeing reads
/// assert!(!debouncer.touch_stuck());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Debouncer {
    h1: u8,
    h2: u8,
    stable: u8,
    held: [u16; 4],
}

impl Debouncer {
    /// A debouncer with all state 0 (no touch, nothing held).
    pub const fn new() -> Self {
        Self {
            h1: 0,
            h2: 0,
            stable: 0,
            held: [0; 4],
        }
    }

    /// Feeds one raw read of the four touch bits (bits above bit 3 ignored) and returns the
    /// debounced bits.
    pub fn step(&mut self, raw: u8) -> TouchBits {
        let raw = raw & TOUCH_MASK;
        let agree = !((raw ^ self.h1) | (raw ^ self.h2)) & TOUCH_MASK;
        self.stable = (self.stable & !agree) | (raw & agree);
        self.h2 = self.h1;
        self.h1 = raw;
        for (bit, held) in self.held.iter_mut().enumerate() {
            if self.stable & (1 << bit) != 0 {
                *held = held.saturating_add(1);
            } else {
                *held = 0;
            }
        }
        TouchBits::from_bits_truncate(self.stable)
    }

    /// Whether any debounced bit has read 1 for [`TOUCH_STUCK_SAMPLES`] samples or more.
    pub fn touch_stuck(&self) -> bool {
        self.held.iter().any(|&held| held >= TOUCH_STUCK_SAMPLES)
    }

    /// The debounced bits.
    pub const fn stable(&self) -> TouchBits {
        TouchBits::from_bits_truncate(self.stable)
    }

    /// The last two raw reads: (previous, the one before).
    pub const fn history(&self) -> (u8, u8) {
        (self.h1, self.h2)
    }

    /// Consecutive samples each debounced bit has read 1 (saturating), bit 0 first.
    pub const fn held(&self) -> [u16; 4] {
        self.held
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bounce_is_rejected() {
        let mut debouncer = Debouncer::new();
        for raw in [0b0100, 0, 0b0100, 0b0100, 0, 0b0100] {
            assert_eq!(debouncer.step(raw).bits(), 0, "raw {raw:#06b}");
        }
    }

    #[test]
    fn three_agreeing_reads_set_and_three_clear() {
        let mut debouncer = Debouncer::new();
        assert_eq!(debouncer.step(0b1010).bits(), 0);
        assert_eq!(debouncer.step(0b1010).bits(), 0);
        assert_eq!(debouncer.step(0b1010).bits(), 0b1010);
        // A one-sample dropout does not release.
        assert_eq!(debouncer.step(0b0010).bits(), 0b1010);
        assert_eq!(debouncer.step(0b0010).bits(), 0b1010);
        assert_eq!(debouncer.step(0b0010).bits(), 0b0010);
        // Bits above bit 3 are ignored.
        assert_eq!(debouncer.step(0xF2).bits(), 0b0010);
        assert_eq!(debouncer.history(), (0b0010, 0b0010));
    }

    #[test]
    fn stuck_sets_at_the_threshold_and_release_clears() {
        let mut debouncer = Debouncer::new();
        debouncer.step(0b0001);
        debouncer.step(0b0001);
        // The third read makes bit 0 stable: count 1.
        for n in 1..TOUCH_STUCK_SAMPLES {
            debouncer.step(0b0001);
            assert!(!debouncer.touch_stuck(), "after {n} held samples");
        }
        debouncer.step(0b0001);
        assert_eq!(debouncer.held()[0], TOUCH_STUCK_SAMPLES);
        assert!(debouncer.touch_stuck());
        for _ in 0..10_000 {
            debouncer.step(0b0001);
        }
        assert!(debouncer.touch_stuck());
        for _ in 0..3 {
            debouncer.step(0);
        }
        assert!(!debouncer.touch_stuck());
        assert_eq!(debouncer.held(), [0; 4]);
    }

    #[test]
    fn hold_count_saturates() {
        let mut debouncer = Debouncer::new();
        for _ in 0..70_000 {
            debouncer.step(0b1000);
        }
        assert_eq!(debouncer.held()[3], u16::MAX);
        assert!(debouncer.touch_stuck());
    }
}
