//! The angle sensor's ADC: our own small trait (embedded-hal 1.0 has no ADC trait).

/// One channel of a 10-bit ADC wired to the Hall sensor's analog output.
///
/// Contract: each call starts one conversion, waits for it and returns the result in the low
/// 10 bits; bits above bit 9 are ignored by the caller (masked). The implementation owns the
/// ADC and its pin; [`crate::Segment`] calls it 16 times per sample, back to back.
pub trait AngleSource {
    /// Why a conversion failed.
    type Error: core::fmt::Debug;

    /// One 10-bit conversion.
    fn convert(&mut self) -> Result<u16, Self::Error>;
}

impl<T: AngleSource + ?Sized> AngleSource for &mut T {
    type Error = T::Error;

    fn convert(&mut self) -> Result<u16, Self::Error> {
        T::convert(self)
    }
}
