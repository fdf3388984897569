//! Bus events of the I2C target, named after the LPC938's I2STAT codes.

/// One event of the I2C target peripheral, as the LPC938 reports it in I2STAT.
///
/// | event | I2STAT |
/// |---|---|
/// | [`StartWrite`](BusEvent::StartWrite) | 0x60 0x68 0x70 0x78 |
/// | [`DataAcked`](BusEvent::DataAcked) | 0x80 0x90 |
/// | [`DataNacked`](BusEvent::DataNacked) | 0x88 0x98 |
/// | [`Stop`](BusEvent::Stop) | 0xA0 |
/// | [`StartRead`](BusEvent::StartRead) | 0xA8 0xB0 |
/// | [`ByteAcked`](BusEvent::ByteAcked) | 0xB8 |
/// | [`ReadDone`](BusEvent::ReadDone) | 0xC0 0xC8 |
/// | [`BusError`](BusEvent::BusError) | 0x00 |
/// | [`Other`](BusEvent::Other) | anything else |
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BusEvent {
    /// Addressed for write (own address or general call).
    StartWrite,
    /// A data byte was received and ACK returned.
    DataAcked(u8),
    /// A data byte was received and NACK returned.
    DataNacked(u8),
    /// STOP or repeated START while addressed.
    Stop,
    /// Addressed for read: load the first byte.
    StartRead,
    /// The byte sent was ACKed: load the next.
    ByteAcked,
    /// The controller finished reading (last byte NACKed, or ACKed with AA clear).
    ReadDone,
    /// Illegal START or STOP on the bus.
    BusError,
    /// Any other status code (controller-mode codes, 0xF8 "nothing to report").
    Other,
}

impl BusEvent {
    /// The event for an I2STAT status `code`; `rx` is the received byte (I2DAT), used by the
    /// data events only.
    ///
    /// ```
    /// use firmware_segment::BusEvent;
    /// assert_eq!(BusEvent::from_i2stat(0x80, 0x10), BusEvent::DataAcked(0x10));
    /// assert_eq!(BusEvent::from_i2stat(0xF8, 0x10), BusEvent::Other);
    /// ```
    pub const fn from_i2stat(code: u8, rx: u8) -> Self {
        match code {
            0x60 | 0x68 | 0x70 | 0x78 => Self::StartWrite,
            0x80 | 0x90 => Self::DataAcked(rx),
            0x88 | 0x98 => Self::DataNacked(rx),
            0xA0 => Self::Stop,
            0xA8 | 0xB0 => Self::StartRead,
            0xB8 => Self::ByteAcked,
            0xC0 | 0xC8 => Self::ReadDone,
            0x00 => Self::BusError,
            _ => Self::Other,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_code_maps_as_the_table_says() {
        let mut others = 0;
        for code in 0..=255u8 {
            let event = BusEvent::from_i2stat(code, 0x5A);
            match event {
                BusEvent::DataAcked(b) | BusEvent::DataNacked(b) => assert_eq!(b, 0x5A),
                BusEvent::Other => others += 1,
                _ => {}
            }
        }
        // 15 codes are target-mode codes; the rest are Other.
        assert_eq!(others, 256 - 15);
    }
}
