//! The segment's register map (docs/segment-protocol.md, "Register access").

use crate::ProtocolError;

/// Firmware version reported by register [`Register::Version`]: (major, minor).
pub const FIRMWARE_VERSION: (u8, u8) = (1, 0);

/// A register of the segment. Write its number (one byte), then read.
///
/// Every register read returns the register's bytes followed by one PEC byte over the read
/// address byte and those bytes; bytes past that read as `0xFF`. A plain read with no register
/// written first reads [`Register::Word`]. See `firmware-segment/README.md` for the state
/// machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Register {
    /// 0x00: the sample word, 2 bytes, high byte first.
    Word = 0x00,
    /// 0x01: firmware version, 2 bytes (major, minor).
    Version = 0x01,
    /// 0x02: status flags, 1 byte ([`StatusFlags`]).
    Status = 0x02,
    /// 0x03: sample counter, 1 byte, incremented at every new sample, wraps.
    Counter = 0x03,
    /// 0x10: address assignment, write only: (new address, its bitwise complement).
    AssignAddress = 0x10,
}

impl Register {
    /// Every register, in register-number order.
    pub const ALL: [Register; 5] = [
        Register::Word,
        Register::Version,
        Register::Status,
        Register::Counter,
        Register::AssignAddress,
    ];

    /// The register number.
    pub const fn number(self) -> u8 {
        self as u8
    }

    /// The register with this number.
    pub const fn from_number(number: u8) -> Result<Self, ProtocolError> {
        match number {
            0x00 => Ok(Register::Word),
            0x01 => Ok(Register::Version),
            0x02 => Ok(Register::Status),
            0x03 => Ok(Register::Counter),
            0x10 => Ok(Register::AssignAddress),
            other => Err(ProtocolError::UnknownRegister(other)),
        }
    }

    /// Data bytes a read of this register returns before its PEC byte (0: write only).
    pub const fn read_len(self) -> usize {
        match self {
            Register::Word | Register::Version => 2,
            Register::Status | Register::Counter => 1,
            Register::AssignAddress => 0,
        }
    }

    /// Data bytes a write to this register carries after the register number.
    pub const fn write_len(self) -> usize {
        match self {
            Register::AssignAddress => 2,
            _ => 0,
        }
    }
}

/// The status flags of register 0x02.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct StatusFlags(u8);

impl StatusFlags {
    /// Bit 0: the angle sensor's output sat on a rail (the Hall sensor's diagnostic clamp or a
    /// broken wire) in the last sample.
    pub const ADC_FAULT: u8 = 1 << 0;
    /// Bit 1: a touch switch has read closed for too long to be a contact (see the firmware).
    pub const TOUCH_STUCK: u8 = 1 << 1;
    /// Bit 2: the segment still answers at its default address.
    pub const ADDRESS_NOT_SET: u8 = 1 << 2;
    /// The bits defined so far.
    pub const DEFINED: u8 = Self::ADC_FAULT | Self::TOUCH_STUCK | Self::ADDRESS_NOT_SET;

    /// Flags from the register byte; undefined bits are kept so a newer firmware's flags are
    /// not lost.
    pub const fn from_bits(bits: u8) -> Self {
        Self(bits)
    }

    /// The register byte.
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// Bit 0 is set.
    pub const fn adc_fault(self) -> bool {
        self.0 & Self::ADC_FAULT != 0
    }

    /// Bit 1 is set.
    pub const fn touch_stuck(self) -> bool {
        self.0 & Self::TOUCH_STUCK != 0
    }

    /// Bit 2 is set.
    pub const fn address_not_set(self) -> bool {
        self.0 & Self::ADDRESS_NOT_SET != 0
    }

    /// The flags with `mask` set or cleared.
    pub const fn with(self, mask: u8, set: bool) -> Self {
        if set {
            Self(self.0 | mask)
        } else {
            Self(self.0 & !mask)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn register_numbers_round_trip_and_nothing_else_is_a_register() {
        for number in 0..=255u8 {
            match Register::from_number(number) {
                Ok(register) => {
                    assert_eq!(register.number(), number);
                    assert!(Register::ALL.contains(&register));
                }
                Err(error) => assert_eq!(error, ProtocolError::UnknownRegister(number)),
            }
        }
        assert_eq!(Register::Word.read_len(), 2);
        assert_eq!(Register::AssignAddress.write_len(), 2);
    }

    #[test]
    fn status_flags_are_the_documented_bits() {
        let flags = StatusFlags::from_bits(0b101);
        assert!(flags.adc_fault());
        assert!(!flags.touch_stuck());
        assert!(flags.address_not_set());
        assert_eq!(flags.with(StatusFlags::ADC_FAULT, false).bits(), 0b100);
        assert_eq!(flags.with(StatusFlags::TOUCH_STUCK, true).bits(), 0b111);
    }
}
