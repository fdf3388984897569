//! SMBus packet error code: CRC-8 with polynomial x^8 + x^2 + x + 1 (0x07), initial value 0,
//! no reflection, no final XOR (SMBus 2.0, section 5.4.1.4).

/// The CRC-8 polynomial of SMBus PEC.
pub const POLYNOMIAL: u8 = 0x07;

/// Folds one byte into a running PEC, MSB first.
pub const fn update(crc: u8, byte: u8) -> u8 {
    let mut crc = crc ^ byte;
    let mut bit = 0;
    while bit < 8 {
        crc = if crc & 0x80 != 0 {
            (crc << 1) ^ POLYNOMIAL
        } else {
            crc << 1
        };
        bit += 1;
    }
    crc
}

/// The PEC of a whole byte sequence, starting from 0.
pub const fn compute(bytes: &[u8]) -> u8 {
    let mut crc = 0;
    let mut i = 0;
    while i < bytes.len() {
        crc = update(crc, bytes[i]);
        i += 1;
    }
    crc
}

/// The address byte of a read from the 7-bit `address`: `address << 1 | 1`.
pub const fn read_address_byte(address: u8) -> u8 {
    (address << 1) | 1
}

/// The PEC a segment appends to a 2-byte word read: over the read address byte, then the high
/// and low bytes.
pub const fn word_read_pec(address: u8, word_bytes: [u8; 2]) -> u8 {
    compute(&[read_address_byte(address), word_bytes[0], word_bytes[1]])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The CRC-8/SMBUS catalogue check value: CRC of ASCII "123456789" is 0xF4.
    #[test]
    fn catalogue_check_value() {
        assert_eq!(compute(b"123456789"), 0xF4);
    }

    /// Bitwise reference over the polynomial division, independent of `update`'s loop.
    fn reference(bytes: &[u8]) -> u8 {
        // Long division of the message followed by 8 zero bits by 0x107.
        let mut register: u32 = 0;
        for &byte in bytes.iter().chain([0u8].iter()) {
            for bit in (0..8).rev() {
                register = (register << 1) | u32::from((byte >> bit) & 1);
                if register & 0x100 != 0 {
                    register ^= 0x107;
                }
            }
        }
        register as u8
    }

    #[test]
    fn every_byte_pair_matches_the_long_division() {
        for a in 0..=255u8 {
            for b in 0..=255u8 {
                assert_eq!(
                    compute(&[a, b]),
                    reference(&[a, b]),
                    "bytes {a:#04x} {b:#04x}"
                );
            }
        }
    }

    #[test]
    fn appending_the_pec_gives_zero() {
        let message = [read_address_byte(0x21), 0x80, 0x09];
        let pec = compute(&message);
        assert_eq!(update(compute(&message), pec), 0);
    }
}
