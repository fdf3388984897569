//! Polling the segments: one PEC-checked read per segment, decoded with `antenna-protocol`,
//! with per-segment health kept as the poll goes on.

use antenna_protocol::{ProtocolError, SampleWord};
use embedded_hal::i2c::{Error as _, ErrorKind, I2c, NoAcknowledgeSource};

/// Why a segment's sample is missing from a poll.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum PollError {
    /// The segment did not acknowledge its address.
    #[error("segment {address:#04x} did not answer (NACK)")]
    Nack {
        /// The 7-bit address polled.
        address: u8,
    },
    /// The 3-byte read came back with a PEC that does not match its data.
    #[error("segment {address:#04x}: {source}")]
    Corrupted {
        /// The 7-bit address polled.
        address: u8,
        /// The PEC mismatch.
        source: ProtocolError,
    },
    /// Any other bus error.
    #[error("segment {address:#04x}: bus error {kind:?}")]
    Bus {
        /// The 7-bit address polled.
        address: u8,
        /// What the bus reported.
        kind: ErrorKind,
    },
}

/// Counts of what happened to one segment's polls.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SegmentHealth {
    /// Good samples.
    pub ok: u64,
    /// Polls the segment did not acknowledge.
    pub nacks: u64,
    /// Polls whose PEC did not match.
    pub pec_errors: u64,
    /// Other bus errors.
    pub bus_errors: u64,
    /// Counter checks ([`Poller::check_counters`]) that found the sample counter where the
    /// previous check left it: the segment answers but publishes no new samples.
    pub stale: u64,
}

impl SegmentHealth {
    /// Whether the last poll was good is not kept here; this says whether every poll and
    /// every counter check was.
    pub fn all_ok(&self) -> bool {
        self.nacks == 0 && self.pec_errors == 0 && self.bus_errors == 0 && self.stale == 0
    }
}

/// What a counter check ([`Poller::check_counters`]) found for one segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CounterCheck {
    /// The counter has moved since the last check (or this is the first check).
    Moving,
    /// The counter has not moved since the last check.
    Stale,
    /// The counter could not be read (NACK or bus error); nothing is concluded.
    Unread,
}

/// One segment's result in one poll.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SegmentReading {
    /// The 7-bit address polled.
    pub address: u8,
    /// The sample, or why there is none.
    pub result: Result<SampleWord, PollError>,
}

/// Polls a fixed list of segment addresses on a bus it owns.
#[derive(Debug)]
pub struct Poller<I> {
    bus: I,
    addresses: Vec<u8>,
    health: Vec<SegmentHealth>,
    counters: Vec<Option<u8>>,
}

impl<I: I2c> Poller<I> {
    /// A poller over `bus` (taken by value; [`Poller::destroy`] gives it back) for segments at
    /// `addresses`, base to tip.
    pub fn new(bus: I, addresses: &[u8]) -> Self {
        Self {
            bus,
            addresses: addresses.to_vec(),
            health: vec![SegmentHealth::default(); addresses.len()],
            counters: vec![None; addresses.len()],
        }
    }

    /// The addresses polled, base to tip.
    pub fn addresses(&self) -> &[u8] {
        &self.addresses
    }

    /// Reads every segment's sample counter (register 0x03) and compares it with the previous
    /// check: a counter that has not moved marks the segment stale (counted in its health).
    /// Call it less often than the segments sample, so a healthy counter always moves.
    pub fn check_counters(&mut self) -> Vec<CounterCheck> {
        let mut checks = Vec::with_capacity(self.addresses.len());
        for (index, &address) in self.addresses.iter().enumerate() {
            let mut counter = [0u8; 1];
            let check = match self.bus.write_read(
                address,
                &[antenna_protocol::Register::Counter.number()],
                &mut counter,
            ) {
                Err(_) => CounterCheck::Unread,
                Ok(()) => {
                    let previous = self.counters[index].replace(counter[0]);
                    if previous == Some(counter[0]) {
                        self.health[index].stale += 1;
                        CounterCheck::Stale
                    } else {
                        CounterCheck::Moving
                    }
                }
            };
            checks.push(check);
        }
        checks
    }

    /// Reads every segment once: word and PEC in one 3-byte read each. A failing segment is
    /// recorded in its health and the poll goes on to the next.
    pub fn poll_all(&mut self) -> Vec<SegmentReading> {
        let mut readings = Vec::with_capacity(self.addresses.len());
        for (index, &address) in self.addresses.iter().enumerate() {
            let result = read_word(&mut self.bus, address);
            let health = &mut self.health[index];
            match result {
                Ok(_) => health.ok += 1,
                Err(PollError::Nack { .. }) => health.nacks += 1,
                Err(PollError::Corrupted { .. }) => health.pec_errors += 1,
                Err(PollError::Bus { .. }) => health.bus_errors += 1,
            }
            readings.push(SegmentReading { address, result });
        }
        readings
    }

    /// Health per segment, in address-list order.
    pub fn health(&self) -> &[SegmentHealth] {
        &self.health
    }

    /// The bus, e.g. to change a simulated segment.
    pub fn bus_mut(&mut self) -> &mut I {
        &mut self.bus
    }

    /// Gives the bus back.
    pub fn destroy(self) -> I {
        self.bus
    }
}

fn read_word<I: I2c>(bus: &mut I, address: u8) -> Result<SampleWord, PollError> {
    let mut bytes = [0u8; 3];
    bus.read(address, &mut bytes)
        .map_err(|error| match error.kind() {
            ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address)
            | ErrorKind::NoAcknowledge(NoAcknowledgeSource::Unknown) => PollError::Nack { address },
            kind => PollError::Bus { address, kind },
        })?;
    SampleWord::from_read_with_pec(address, bytes)
        .map_err(|source| PollError::Corrupted { address, source })
}

#[cfg(test)]
mod tests {
    use super::*;
    use antenna_protocol::pec;
    use embedded_hal::i2c::ErrorKind;
    use embedded_hal_mock::eh1::i2c::{Mock, Transaction};

    #[test]
    fn good_corrupt_and_silent_segments_are_each_recorded() {
        let good = [0x80, 0x09, pec::word_read_pec(0x21, [0x80, 0x09])];
        let corrupt = [0x80, 0x09, good[2] ^ 0x01];
        let expectations = [
            Transaction::read(0x21, good.to_vec()),
            Transaction::read(0x22, corrupt.to_vec()),
            Transaction::read(0x23, vec![0, 0, 0])
                .with_error(ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address)),
        ];
        let mut poller = Poller::new(Mock::new(&expectations), &[0x21, 0x22, 0x23]);
        let readings = poller.poll_all();
        assert_eq!(readings[0].result, Ok(SampleWord::from_raw(0x8009)));
        assert!(matches!(
            readings[1].result,
            Err(PollError::Corrupted { address: 0x22, .. })
        ));
        assert_eq!(readings[2].result, Err(PollError::Nack { address: 0x23 }));
        let health = poller.health();
        assert_eq!(
            (health[0].ok, health[1].pec_errors, health[2].nacks),
            (1, 1, 1)
        );
        assert!(health[0].all_ok() && !health[1].all_ok());
        poller.destroy().done();
    }
}
