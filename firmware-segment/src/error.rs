//! The segment's errors.

/// Which peripheral failed, with its error. `A`, `T`, `I`, `S` are the error types of the
/// [`crate::AngleSource`], [`crate::TouchPort`], [`crate::I2cTarget`] and
/// [`crate::AddressStore`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SegmentError<A, T, I, S> {
    /// An angle conversion failed; no sample was published (the host sees the counter stop).
    #[error("angle conversion failed: {0:?}")]
    Adc(A),
    /// The touch port could not be read; no sample was published.
    #[error("touch port read failed: {0:?}")]
    Touch(T),
    /// The I2C target peripheral failed; the transfer in progress was dropped (a write
    /// commits nothing).
    #[error("I2C target failed: {0:?}")]
    I2c(I),
    /// The address store failed: at start-up the address could not be loaded, or an assigned
    /// address could not be persisted (the segment then stays at its previous address).
    #[error("address store failed: {0:?}")]
    Store(S),
}
