//! The non-volatile home of the segment's assigned address.

/// Non-volatile storage for the segment's 7-bit address (flash or EEPROM on the real part).
///
/// Contract: [`AddressStore::load`] returns what the last successful
/// [`AddressStore::store`] wrote, across resets, or `None` when nothing was ever stored (or
/// the stored record is invalid). The segment validates a loaded address and falls back to
/// the default address when it is not assignable.
pub trait AddressStore {
    /// Why the storage failed.
    type Error: core::fmt::Debug;

    /// The stored address, if any.
    fn load(&mut self) -> Result<Option<u8>, Self::Error>;

    /// Stores `address`, replacing what was stored.
    fn store(&mut self, address: u8) -> Result<(), Self::Error>;
}

impl<T: AddressStore + ?Sized> AddressStore for &mut T {
    type Error = T::Error;

    fn load(&mut self) -> Result<Option<u8>, Self::Error> {
        T::load(self)
    }

    fn store(&mut self, address: u8) -> Result<(), Self::Error> {
        T::store(self, address)
    }
}
