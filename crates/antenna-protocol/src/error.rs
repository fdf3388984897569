//! Errors of the protocol crate.

/// What was wrong with a value handed to the protocol crate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum ProtocolError {
    /// An angle count above [`crate::MAX_ANGLE_COUNT`] (4095) cannot be packed.
    #[error("angle count {0} is out of range 0..=4095")]
    AngleOutOfRange(u16),
    /// Touch bits above bit 3: a segment has four switches.
    #[error("touch value {0:#04x} has bits above bit 3 (a segment has four switches)")]
    TouchOutOfRange(u8),
    /// The PEC byte of a read did not match the one computed over the received bytes.
    #[error("PEC mismatch: received {received:#04x}, computed {computed:#04x}")]
    PecMismatch {
        /// The PEC byte that came over the bus.
        received: u8,
        /// The PEC computed over the address byte and the data bytes.
        computed: u8,
    },
    /// A register number that is not in the map.
    #[error("register {0:#04x} is not in the register map")]
    UnknownRegister(u8),
    /// A 7-bit address outside the assignable range 0x08..=0x77.
    #[error("address {0:#04x} is outside the assignable range 0x08..=0x77")]
    AddressOutOfRange(u8),
    /// An address-assignment message whose second byte is not the complement of the first.
    #[error(
        "address assignment {address:#04x} with complement {complement:#04x}: expected {expected:#04x}"
    )]
    BadComplement {
        /// The requested address.
        address: u8,
        /// The byte sent as its complement.
        complement: u8,
        /// The true complement of `address`.
        expected: u8,
    },
    /// A message of the wrong length.
    #[error("message of {actual} bytes, expected {expected}")]
    BadLength {
        /// Bytes expected.
        expected: usize,
        /// Bytes received.
        actual: usize,
    },
}
