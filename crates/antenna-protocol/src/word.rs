//! The 16-bit sample word: `word = (angle << 4) | touch` (thesis 2.3.1).

use crate::{ProtocolError, pec};

/// Counts in one full turn of the Hall sensor's magnet (12 bits).
pub const ANGLE_COUNTS_PER_TURN: u16 = 4096;
/// The largest angle count.
pub const MAX_ANGLE_COUNT: u16 = ANGLE_COUNTS_PER_TURN - 1;
/// The four touch bits of a word.
pub const TOUCH_MASK: u8 = 0x0F;

/// The four touch switches along a segment; bit 0 is the most proximal, 1 means contact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct TouchBits(u8);

impl TouchBits {
    /// No switch in contact.
    pub const NONE: Self = Self(0);

    /// Touch bits from a 4-bit value; bits above bit 3 are an error.
    pub const fn from_bits(bits: u8) -> Result<Self, ProtocolError> {
        if bits & !TOUCH_MASK != 0 {
            Err(ProtocolError::TouchOutOfRange(bits))
        } else {
            Ok(Self(bits))
        }
    }

    /// Touch bits from the low four bits of `bits`, ignoring the rest (as the firmware does
    /// when it reads a port).
    pub const fn from_bits_truncate(bits: u8) -> Self {
        Self(bits & TOUCH_MASK)
    }

    /// The 4-bit value.
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// Whether switch `index` (0 = most proximal .. 3) is in contact; false past 3.
    pub const fn is_touched(self, index: u8) -> bool {
        index < 4 && self.0 & (1 << index) != 0
    }

    /// Whether any switch is in contact.
    pub const fn any(self) -> bool {
        self.0 != 0
    }
}

/// One sample of a segment: a 12-bit joint angle count and four touch bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SampleWord(u16);

impl SampleWord {
    /// Packs an angle count (0..=4095) and touch bits.
    pub const fn new(angle_counts: u16, touch: TouchBits) -> Result<Self, ProtocolError> {
        if angle_counts > MAX_ANGLE_COUNT {
            return Err(ProtocolError::AngleOutOfRange(angle_counts));
        }
        Ok(Self::pack_truncate(angle_counts, touch.0))
    }

    /// Packs the low 12 bits of `angle_counts` and the low 4 bits of `touch`, as the firmware
    /// (Rust and C) does: `(angle << 4) | touch`.
    pub const fn pack_truncate(angle_counts: u16, touch: u8) -> Self {
        Self(((angle_counts & MAX_ANGLE_COUNT) << 4) | (touch & TOUCH_MASK) as u16)
    }

    /// The word as it travels: any 16-bit value is a valid word.
    pub const fn from_raw(raw: u16) -> Self {
        Self(raw)
    }

    /// The raw 16-bit word.
    pub const fn raw(self) -> u16 {
        self.0
    }

    /// The 12-bit angle count (bits 15..4).
    pub const fn angle_counts(self) -> u16 {
        self.0 >> 4
    }

    /// The touch bits (bits 3..0).
    pub const fn touch(self) -> TouchBits {
        TouchBits((self.0 & TOUCH_MASK as u16) as u8)
    }

    /// The two bytes on the bus, high byte first.
    pub const fn to_be_bytes(self) -> [u8; 2] {
        self.0.to_be_bytes()
    }

    /// The word from the two bytes of a plain read, high byte first.
    pub const fn from_be_bytes(bytes: [u8; 2]) -> Self {
        Self(u16::from_be_bytes(bytes))
    }

    /// The word from a 3-byte read (high, low, PEC) from the 7-bit `address`, checking the PEC.
    pub fn from_read_with_pec(address: u8, bytes: [u8; 3]) -> Result<Self, ProtocolError> {
        let computed = pec::word_read_pec(address, [bytes[0], bytes[1]]);
        if computed != bytes[2] {
            return Err(ProtocolError::PecMismatch {
                received: bytes[2],
                computed,
            });
        }
        Ok(Self::from_be_bytes([bytes[0], bytes[1]]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_angle_and_touch_round_trips() {
        for angle in 0..=MAX_ANGLE_COUNT {
            for touch in 0..16u8 {
                let word = SampleWord::new(angle, TouchBits::from_bits(touch).unwrap()).unwrap();
                assert_eq!(word.raw(), (angle << 4) | u16::from(touch));
                assert_eq!(word.angle_counts(), angle);
                assert_eq!(word.touch().bits(), touch);
                assert_eq!(SampleWord::from_be_bytes(word.to_be_bytes()), word);
            }
        }
    }

    #[test]
    fn out_of_range_inputs_are_errors() {
        assert_eq!(
            SampleWord::new(4096, TouchBits::NONE),
            Err(ProtocolError::AngleOutOfRange(4096))
        );
        assert_eq!(
            TouchBits::from_bits(0x10),
            Err(ProtocolError::TouchOutOfRange(0x10))
        );
        assert_eq!(SampleWord::pack_truncate(0x1FFF, 0xFF).raw(), 0xFFFF);
        assert_eq!(SampleWord::pack_truncate(0x1000, 0x10).raw(), 0);
    }

    #[test]
    fn touch_bit_zero_is_most_proximal() {
        let touch = TouchBits::from_bits(0b0001).unwrap();
        assert!(touch.is_touched(0));
        assert!(!touch.is_touched(1));
        assert!(!touch.is_touched(7));
        assert!(touch.any());
        assert!(!TouchBits::NONE.any());
    }

    #[test]
    fn corrupted_pec_is_detected() {
        let word = SampleWord::new(1234, TouchBits::from_bits(5).unwrap()).unwrap();
        let [hi, lo] = word.to_be_bytes();
        let good = pec::word_read_pec(0x30, [hi, lo]);
        assert_eq!(
            SampleWord::from_read_with_pec(0x30, [hi, lo, good]),
            Ok(word)
        );
        for bit in 0..8 {
            let bad = good ^ (1 << bit);
            assert!(matches!(
                SampleWord::from_read_with_pec(0x30, [hi, lo, bad]),
                Err(ProtocolError::PecMismatch { .. })
            ));
            assert!(SampleWord::from_read_with_pec(0x30, [hi ^ (1 << bit), lo, good]).is_err());
        }
    }
}
