//! The I2C target peripheral: our own trait, shaped like embedded-mcu-hal 0.3's target trait
//! (listen / respond_to_read / respond_to_write), since embedded-hal 1.0 has none.

/// What a controller asked of us when it addressed us.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TargetRequest {
    /// Addressed for write (own address + W): the controller sends bytes.
    Write,
    /// Addressed for read (own address + R): the controller clocks bytes out.
    Read,
}

/// A transaction-level I2C target (slave) peripheral.
///
/// # Contract
///
/// Ownership: the implementation owns the peripheral and its SDA/SCL pins; the
/// [`crate::Segment`] owns the implementation (taken by value, handed back by
/// [`crate::Segment::destroy`]) and owns all protocol state: registers, pointer, address.
/// The driver knows nothing of registers.
///
/// One transaction is [`listen`](I2cTarget::listen) returning a request, then exactly one
/// [`respond_to_write`](I2cTarget::respond_to_write) or
/// [`respond_to_read`](I2cTarget::respond_to_read) matching it. Bus events:
///
/// ```text
/// write:  Controller: ST SAD+W     B0     B1    ... Bn     SP|SR
///         Target:            SAK    ACK    ACK  ...  ACK/NACK
/// read:   Controller: ST SAD+R        ACK    ACK ... NACK SP
///         Target:            SAK  T0     T1  ...  Tn
/// ```
///
/// A write followed by a repeated START and a read (the register read) is two transactions:
/// `respond_to_write` returns at the repeated START, and the next `listen` returns
/// [`TargetRequest::Read`].
pub trait I2cTarget {
    /// Why the peripheral failed (bus error, arbitration, timeout).
    type Error: core::fmt::Debug;

    /// Answers at the 7-bit `address` from the next transaction on.
    fn set_address(&mut self, address: u8) -> Result<(), Self::Error>;

    /// The request of a controller that has addressed us since the last call, or `None`.
    /// Never blocks: the segment polls it between samples (an interrupt-driven
    /// implementation queues the request).
    fn listen(&mut self) -> Result<Option<TargetRequest>, Self::Error>;

    /// Receives the bytes of a write into `buf` until STOP or repeated START. The first
    /// `buf.len()` bytes are ACKed and stored; any further byte is NACKed and dropped. Returns
    /// how many bytes the controller sent, which exceeds `buf.len()` when it wrote past the
    /// buffer.
    fn respond_to_write(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error>;

    /// Sends `buf` to the controller, then 0xFF for every further byte it clocks, until it
    /// NACKs a byte or stops. Returns how many bytes the controller took.
    fn respond_to_read(&mut self, buf: &[u8]) -> Result<usize, Self::Error>;
}

impl<T: I2cTarget + ?Sized> I2cTarget for &mut T {
    type Error = T::Error;

    fn set_address(&mut self, address: u8) -> Result<(), Self::Error> {
        T::set_address(self, address)
    }

    fn listen(&mut self) -> Result<Option<TargetRequest>, Self::Error> {
        T::listen(self)
    }

    fn respond_to_write(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        T::respond_to_write(self, buf)
    }

    fn respond_to_read(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        T::respond_to_read(self, buf)
    }
}
