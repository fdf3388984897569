//! Address assignment: write register 0x10 with (new address, bitwise complement).

use crate::{ProtocolError, Register};

/// The 7-bit address a segment answers at before one is assigned.
pub const DEFAULT_ADDRESS: u8 = 0x77;
/// The lowest assignable 7-bit address (0x00..=0x07 are reserved by the I2C specification).
pub const MIN_ASSIGNABLE_ADDRESS: u8 = 0x08;
/// The highest assignable 7-bit address (0x78..=0x7F are reserved by the I2C specification).
pub const MAX_ASSIGNABLE_ADDRESS: u8 = 0x77;

/// Whether `address` is a 7-bit address a segment may be moved to.
pub const fn is_assignable_address(address: u8) -> bool {
    address >= MIN_ASSIGNABLE_ADDRESS && address <= MAX_ASSIGNABLE_ADDRESS
}

/// A validated address-assignment message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct AddressAssignment {
    new_address: u8,
}

impl AddressAssignment {
    /// A message moving a segment to `new_address` (0x08..=0x77).
    pub const fn new(new_address: u8) -> Result<Self, ProtocolError> {
        if is_assignable_address(new_address) {
            Ok(Self { new_address })
        } else {
            Err(ProtocolError::AddressOutOfRange(new_address))
        }
    }

    /// The address the segment moves to.
    pub const fn new_address(self) -> u8 {
        self.new_address
    }

    /// The bytes the host writes: register 0x10, the address, its complement.
    pub const fn to_bytes(self) -> [u8; 3] {
        [
            Register::AssignAddress.number(),
            self.new_address,
            !self.new_address,
        ]
    }

    /// Checks the two payload bytes a segment received after register 0x10.
    pub const fn from_payload(address: u8, complement: u8) -> Result<Self, ProtocolError> {
        if complement != !address {
            return Err(ProtocolError::BadComplement {
                address,
                complement,
                expected: !address,
            });
        }
        Self::new(address)
    }

    /// Checks a whole message (register number and payload).
    pub const fn from_bytes(bytes: &[u8]) -> Result<Self, ProtocolError> {
        if bytes.len() != 3 {
            return Err(ProtocolError::BadLength {
                expected: 3,
                actual: bytes.len(),
            });
        }
        if bytes[0] != Register::AssignAddress.number() {
            return Err(ProtocolError::UnknownRegister(bytes[0]));
        }
        Self::from_payload(bytes[1], bytes[2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_payload_pair_is_accepted_exactly_when_valid() {
        for address in 0..=255u8 {
            for complement in 0..=255u8 {
                let accepted = AddressAssignment::from_payload(address, complement).is_ok();
                let valid = complement == !address && (0x08..=0x77).contains(&address);
                assert_eq!(accepted, valid, "{address:#04x} {complement:#04x}");
            }
        }
    }

    #[test]
    fn message_round_trips() {
        let message = AddressAssignment::new(0x21).unwrap();
        assert_eq!(message.to_bytes(), [0x10, 0x21, 0xDE]);
        assert_eq!(
            AddressAssignment::from_bytes(&message.to_bytes()),
            Ok(message)
        );
        assert_eq!(
            AddressAssignment::from_bytes(&[0x10, 0x21]),
            Err(ProtocolError::BadLength {
                expected: 3,
                actual: 2
            })
        );
        assert_eq!(
            AddressAssignment::from_bytes(&[0x11, 0x21, 0xDE]),
            Err(ProtocolError::UnknownRegister(0x11))
        );
        assert_eq!(
            AddressAssignment::new(0x78),
            Err(ProtocolError::AddressOutOfRange(0x78))
        );
    }
}
