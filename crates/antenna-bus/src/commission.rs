//! Commissioning the segments on a bus: find them ([`scan`]), give each its address
//! ([`assign`], register 0x10 with the address's complement), measure each joint's
//! `zero_counts` at rest ([`measure_zero_counts`]) and read what each says about itself
//! ([`status`]: firmware version, status flags, angle and touch). `antenna segments` is the
//! command line over these; they work on any embedded-hal [`I2c`], the simulated rig's
//! [`crate::SimBus`] as well as a Linux `/dev/i2c-N`.
//!
//! Every read here is a register read with its PEC, tried [`READ_ATTEMPTS`] times. Two
//! segments at one address both acknowledge it and drive the bus together, so a read returns
//! the AND of their bytes and its PEC fails: a read whose PEC fails every time is reported as
//! [`CommissionError::Conflict`]. Two segments whose bytes agree in every register read
//! (same version, status, counter and angle) cannot be told from one on the bus; their angles
//! differ in practice, and connecting segments one at a time, assigning each as it comes,
//! avoids the question.
//!
//! ```
//! use antenna_protocol::{Calibration, DEFAULT_ADDRESS};
//! use antenna_bus::commission::{self, ASSIGNABLE};
//! use antenna_bus::{SimBus, SimSegment};
//! use std::time::Duration;
//!
//! let mut bus = SimBus::new(vec![SimSegment::unassigned(Calibration::default())]);
//! bus.sample_all();
//! let found = commission::scan(&mut bus, ASSIGNABLE)?;
//! assert_eq!(found[0].address, DEFAULT_ADDRESS);
//! assert!(found[0].answer.as_ref().is_ok_and(|s| s.flags.address_not_set()));
//!
//! let moved = commission::assign(&mut bus, DEFAULT_ADDRESS, 0x21, Duration::ZERO)?;
//! assert_eq!(moved.address, 0x21);
//! assert!(!moved.flags.address_not_set());
//! # Ok::<(), antenna_bus::commission::CommissionError>(())
//! ```

use antenna_protocol::{
    ANGLE_COUNTS_PER_TURN, AddressAssignment, DEFAULT_ADDRESS, FIRMWARE_VERSION,
    MAX_ASSIGNABLE_ADDRESS, MIN_ASSIGNABLE_ADDRESS, ProtocolError, Register, SampleWord,
    StatusFlags, pec,
};
use embedded_hal::i2c::{Error as _, ErrorKind, I2c};
use std::f64::consts::TAU;
use std::ops::RangeInclusive;
use std::time::Duration;

/// The addresses a segment can be assigned, and so the ones a scan looks at by default.
pub const ASSIGNABLE: RangeInclusive<u8> = MIN_ASSIGNABLE_ADDRESS..=MAX_ASSIGNABLE_ADDRESS;

/// How many times a register read is tried before a failing PEC is taken as a conflict.
pub const READ_ATTEMPTS: usize = 3;

/// How long a segment is given after an assignment to store the address and answer at it
/// (the firmware persists the address before it moves): what `antenna segments assign` waits.
pub const ASSIGN_SETTLE: Duration = Duration::from_millis(20);

/// What went wrong while commissioning, and at which address.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CommissionError {
    /// Nothing acknowledged the address.
    #[error("no segment answers at {0:#04x}")]
    NoSegment(u8),
    /// The address is acknowledged but every read of a register failed its PEC.
    #[error(
        "more than one segment answers at {address:#04x} (every read of register \
         {register:#04x} failed its PEC: segments sharing an address read back as the AND of \
         their bytes, or the line is corrupting transfers); connect them one at a time"
    )]
    Conflict {
        /// The address.
        address: u8,
        /// The register whose reads failed.
        register: u8,
    },
    /// Any other bus error.
    #[error("bus error at {address:#04x}: {kind}")]
    Bus {
        /// The address.
        address: u8,
        /// What the bus reported.
        kind: ErrorKind,
    },
    /// The new address is outside 0x08..=0x77.
    #[error("cannot assign {address:#04x}: {source}")]
    OutOfRange {
        /// The requested address.
        address: u8,
        /// The protocol's refusal.
        source: ProtocolError,
    },
    /// The new address is the default one, which every unassigned segment answers at.
    #[error(
        "cannot assign {DEFAULT_ADDRESS:#04x}: it is the default address every unassigned \
         segment answers at"
    )]
    DefaultAddress,
    /// Something already answers at the new address.
    #[error("cannot assign {0:#04x}: a device already answers there")]
    AddressTaken(u8),
    /// After the assignment the segment still answers at its old address.
    #[error("the segment at {from:#04x} still answers there after being assigned {to:#04x}")]
    StillAtOld {
        /// The old address.
        from: u8,
        /// The requested address.
        to: u8,
    },
    /// After the assignment nothing answers at the new address.
    #[error("the segment left {from:#04x} but does not answer at {to:#04x}")]
    Lost {
        /// The old address.
        from: u8,
        /// The requested address.
        to: u8,
    },
    /// After the assignment the segment answers at the new address but says it has none.
    #[error("the segment answers at {0:#04x} but still reports its address as not set")]
    NotStored(u8),
    /// A zero measurement of no samples.
    #[error("measuring zero_counts needs at least one sample")]
    NoSamples,
}

/// What one segment says about itself, every register read with a good PEC.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SegmentStatus {
    /// The address it answered at.
    pub address: u8,
    /// Firmware version (major, minor), register 0x01.
    pub version: (u8, u8),
    /// Status flags, register 0x02.
    pub flags: StatusFlags,
    /// Sample counter, register 0x03.
    pub counter: u8,
    /// The latest sample (angle counts and touch bits), register 0x00.
    pub word: SampleWord,
}

impl SegmentStatus {
    /// Whether the firmware's version is the one this host speaks ([`FIRMWARE_VERSION`]).
    pub fn version_matches(&self) -> bool {
        self.version == FIRMWARE_VERSION
    }

    /// Whether the segment has no address of its own yet: it says so, or it answers at the
    /// default address.
    pub fn unassigned(&self) -> bool {
        self.flags.address_not_set() || self.address == DEFAULT_ADDRESS
    }
}

/// An address something answered at, and what it said.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Found {
    /// The address.
    pub address: u8,
    /// The segment's registers, or why they could not be read (a conflict, a bus error).
    pub answer: Result<SegmentStatus, CommissionError>,
}

/// One joint's `zero_counts`, measured at rest.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ZeroMeasurement {
    /// The segment's address.
    pub address: u8,
    /// The circular mean of the samples, rounded: the count read at joint angle zero.
    pub zero_counts: u16,
    /// Samples averaged.
    pub samples: usize,
    /// The largest distance of a sample from the mean, counts (around the wrap).
    pub max_deviation_counts: u16,
    /// Whether any touch bit was set in any sample (a joint touching something is not at
    /// rest).
    pub touched: bool,
    /// The status flags read after the samples (an ADC fault makes the counts meaningless).
    pub flags: StatusFlags,
}

fn bus_error(address: u8, kind: ErrorKind) -> CommissionError {
    match kind {
        ErrorKind::NoAcknowledge(_) => CommissionError::NoSegment(address),
        kind => CommissionError::Bus { address, kind },
    }
}

/// The data bytes of `register` at `address` (a 1-byte register in the first), read with its
/// PEC, tried [`READ_ATTEMPTS`] times while the PEC fails.
fn read_register<I: I2c>(
    bus: &mut I,
    address: u8,
    register: Register,
) -> Result<[u8; 2], CommissionError> {
    let len = register.read_len();
    let mut buffer = [0u8; 3];
    for _ in 0..READ_ATTEMPTS {
        bus.write_read(address, &[register.number()], &mut buffer[..=len])
            .map_err(|e| bus_error(address, e.kind()))?;
        let computed = buffer[..len].iter().fold(
            pec::update(0, pec::read_address_byte(address)),
            |crc, &b| pec::update(crc, b),
        );
        if computed == buffer[len] {
            return Ok(if len == 2 {
                [buffer[0], buffer[1]]
            } else {
                [buffer[0], 0]
            });
        }
    }
    Err(CommissionError::Conflict {
        address,
        register: register.number(),
    })
}

/// Reads every register of the segment at `address`.
pub fn read_segment<I: I2c>(bus: &mut I, address: u8) -> Result<SegmentStatus, CommissionError> {
    let [major, minor] = read_register(bus, address, Register::Version)?;
    let [flags, _] = read_register(bus, address, Register::Status)?;
    let [counter, _] = read_register(bus, address, Register::Counter)?;
    let word = read_register(bus, address, Register::Word)?;
    Ok(SegmentStatus {
        address,
        version: (major, minor),
        flags: StatusFlags::from_bits(flags),
        counter,
        word: SampleWord::from_be_bytes(word),
    })
}

/// Whether anything acknowledges `address` (a read of the version register; any error,
/// a NACK or an adapter's own way of reporting one, counts as no).
fn answers<I: I2c>(bus: &mut I, address: u8) -> bool {
    let mut buffer = [0u8; 3];
    bus.write_read(address, &[Register::Version.number()], &mut buffer)
        .is_ok()
}

/// Every address in `range` that answers, with what the segment there says (or why it could
/// not be read: [`CommissionError::Conflict`] for two segments at one address).
///
/// An address that does not acknowledge, or whose probe fails with an error the bus adapter
/// uses for that ([`ErrorKind::NoAcknowledge`], [`ErrorKind::Other`]: Linux adapters report
/// a NACK as `ENXIO` or `EREMOTEIO`), is absent; a bus or arbitration fault stops the scan.
/// The probe writes register number 0x01 and reads 3 bytes, as a segment expects.
pub fn scan<I: I2c>(bus: &mut I, range: RangeInclusive<u8>) -> Result<Vec<Found>, CommissionError> {
    let mut found = Vec::new();
    for address in range {
        let mut buffer = [0u8; 3];
        match bus.write_read(address, &[Register::Version.number()], &mut buffer) {
            Ok(()) => found.push(Found {
                address,
                answer: read_segment(bus, address),
            }),
            Err(e) => match e.kind() {
                ErrorKind::NoAcknowledge(_) | ErrorKind::Other => {}
                kind => return Err(CommissionError::Bus { address, kind }),
            },
        }
    }
    Ok(found)
}

/// Moves the segment at `from` to `to` (register 0x10: the address and its complement) and
/// checks it: nothing may answer at `to` before (unless `to` is `from`), exactly one segment
/// must answer at `from` (a write to two would move both), and after `settle` the segment
/// must answer at `to`, say its address is set, and no longer answer at `from`. Returns what
/// it says at its new address.
pub fn assign<I: I2c>(
    bus: &mut I,
    from: u8,
    to: u8,
    settle: Duration,
) -> Result<SegmentStatus, CommissionError> {
    let message = AddressAssignment::new(to).map_err(|source| CommissionError::OutOfRange {
        address: to,
        source,
    })?;
    if to == DEFAULT_ADDRESS {
        return Err(CommissionError::DefaultAddress);
    }
    if to != from && answers(bus, to) {
        return Err(CommissionError::AddressTaken(to));
    }
    read_segment(bus, from)?;
    bus.write(from, &message.to_bytes())
        .map_err(|e| bus_error(from, e.kind()))?;
    if !settle.is_zero() {
        std::thread::sleep(settle);
    }
    if to != from && answers(bus, from) {
        return Err(CommissionError::StillAtOld { from, to });
    }
    let moved = read_segment(bus, to).map_err(|e| match e {
        CommissionError::NoSegment(_) => CommissionError::Lost { from, to },
        e => e,
    })?;
    if moved.flags.address_not_set() {
        return Err(CommissionError::NotStored(to));
    }
    Ok(moved)
}

/// Each segment's registers, or why they could not be read; one segment failing does not
/// stop the others.
pub fn status<I: I2c>(bus: &mut I, addresses: &[u8]) -> Vec<Found> {
    addresses
        .iter()
        .map(|&address| Found {
            address,
            answer: read_segment(bus, address),
        })
        .collect()
}

/// The circular mean of angle counts (the 4096-count turn wraps: 4094 and 2 average to 0)
/// and the largest distance of a count from it; `None` for no counts.
pub fn circular_mean_counts(counts: &[u16]) -> Option<(u16, u16)> {
    if counts.is_empty() {
        return None;
    }
    let turn = f64::from(ANGLE_COUNTS_PER_TURN);
    let to_rad = |c: u16| f64::from(c) * TAU / turn;
    let (sin, cos) = counts.iter().fold((0.0, 0.0), |(s, c), &count| {
        (s + to_rad(count).sin(), c + to_rad(count).cos())
    });
    let mean = (sin.atan2(cos) / TAU * turn).round().rem_euclid(turn);
    // `mean` is a whole number in 0..4096 (4096 itself after rounding 4095.6 folds to 0).
    let mean = (mean as u16) % ANGLE_COUNTS_PER_TURN;
    let deviation = counts
        .iter()
        .map(|&c| {
            let d = (c % ANGLE_COUNTS_PER_TURN).abs_diff(mean);
            d.min(ANGLE_COUNTS_PER_TURN - d)
        })
        .max()
        .unwrap_or(0);
    Some((mean, deviation))
}

/// Measures each segment's `zero_counts`: `samples` rounds, each calling `between` (let the
/// segments take a new sample: wait a sample period on hardware, sample the simulated ones)
/// and then reading every segment's word with its PEC; each joint's zero is the circular mean
/// of its counts. The joints must be at rest at angle zero (the antenna straight, touching
/// nothing) while this runs.
pub fn measure_zero_counts<I: I2c>(
    bus: &mut I,
    addresses: &[u8],
    samples: usize,
    mut between: impl FnMut(&mut I),
) -> Result<Vec<ZeroMeasurement>, CommissionError> {
    if samples == 0 {
        return Err(CommissionError::NoSamples);
    }
    let mut counts = vec![Vec::with_capacity(samples); addresses.len()];
    let mut touched = vec![false; addresses.len()];
    for _ in 0..samples {
        between(bus);
        for (k, &address) in addresses.iter().enumerate() {
            let word = SampleWord::from_be_bytes(read_register(bus, address, Register::Word)?);
            counts[k].push(word.angle_counts());
            touched[k] |= word.touch().any();
        }
    }
    addresses
        .iter()
        .zip(counts.iter().zip(touched))
        .map(|(&address, (counts, touched))| {
            let [flags, _] = read_register(bus, address, Register::Status)?;
            let (zero_counts, max_deviation_counts) =
                circular_mean_counts(counts).ok_or(CommissionError::NoSamples)?;
            Ok(ZeroMeasurement {
                address,
                zero_counts,
                samples: counts.len(),
                max_deviation_counts,
                touched,
                flags: StatusFlags::from_bits(flags),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{SegmentFault, SimBus, SimSegment};
    use antenna_protocol::{Calibration, Direction, TouchBits};
    use embedded_hal::i2c::{ErrorType, Operation};

    fn segment(address: u8, zero_counts: u16) -> SimSegment {
        SimSegment::new(
            address,
            Calibration::new(zero_counts, Direction::CounterClockwise),
        )
    }

    fn sampled(mut bus: SimBus) -> SimBus {
        bus.sample_all();
        bus
    }

    #[test]
    fn scan_finds_assigned_unassigned_and_conflicting_segments() {
        let mut bus = sampled(SimBus::new(vec![
            segment(0x20, 1500),
            SimSegment::unassigned(Calibration::new(2000, Direction::Clockwise)),
            segment(0x21, 0x0F0),
            segment(0x21, 0x00F),
        ]));
        let found = scan(&mut bus, ASSIGNABLE).unwrap();
        let addresses: Vec<u8> = found.iter().map(|f| f.address).collect();
        assert_eq!(addresses, vec![0x20, 0x21, 0x77]);
        let first = found[0].answer.as_ref().unwrap();
        assert_eq!(first.version, FIRMWARE_VERSION);
        assert!(first.version_matches() && !first.unassigned());
        assert_eq!(first.word.angle_counts(), 1500);
        assert!(matches!(
            found[1].answer,
            Err(CommissionError::Conflict { address: 0x21, .. })
        ));
        let fresh = found[2].answer.as_ref().unwrap();
        assert!(fresh.flags.address_not_set() && fresh.unassigned());
        assert_eq!(fresh.word.angle_counts(), 2000);
    }

    #[test]
    fn assign_moves_a_segment_and_refuses_taken_reserved_and_shared_addresses() {
        let mut bus = sampled(SimBus::new(vec![
            segment(0x20, 1500),
            SimSegment::unassigned(Calibration::default()),
        ]));
        assert_eq!(
            assign(&mut bus, DEFAULT_ADDRESS, 0x20, Duration::ZERO),
            Err(CommissionError::AddressTaken(0x20))
        );
        assert!(matches!(
            assign(&mut bus, DEFAULT_ADDRESS, 0x78, Duration::ZERO),
            Err(CommissionError::OutOfRange { address: 0x78, .. })
        ));
        assert!(matches!(
            assign(&mut bus, DEFAULT_ADDRESS, 0x07, Duration::ZERO),
            Err(CommissionError::OutOfRange { address: 0x07, .. })
        ));
        assert_eq!(
            assign(&mut bus, 0x20, DEFAULT_ADDRESS, Duration::ZERO),
            Err(CommissionError::DefaultAddress)
        );
        assert_eq!(
            assign(&mut bus, 0x30, 0x31, Duration::ZERO),
            Err(CommissionError::NoSegment(0x30))
        );
        // Nothing moved by the refusals.
        assert_eq!(bus.segments()[1].address(), DEFAULT_ADDRESS);

        let moved = assign(&mut bus, DEFAULT_ADDRESS, 0x21, Duration::ZERO).unwrap();
        assert_eq!(moved.address, 0x21);
        assert!(!moved.unassigned());
        assert_eq!(bus.segments()[1].address(), 0x21);
        assert_eq!(
            read_segment(&mut bus, DEFAULT_ADDRESS),
            Err(CommissionError::NoSegment(DEFAULT_ADDRESS))
        );

        // Two segments at one address: the write would move both, so it is refused.
        let mut shared = sampled(SimBus::new(vec![
            segment(0x21, 0x0F0),
            segment(0x21, 0x00F),
        ]));
        assert!(matches!(
            assign(&mut shared, 0x21, 0x22, Duration::ZERO),
            Err(CommissionError::Conflict { address: 0x21, .. })
        ));
        assert!(shared.segments().iter().all(|s| s.address() == 0x21));
    }

    #[test]
    fn status_reads_every_segment_and_reports_the_missing_one() {
        let mut bus = SimBus::new(vec![segment(0x20, 1500), segment(0x22, 100)]);
        bus.segment_mut(1)
            .unwrap()
            .set_fault(SegmentFault::SensorRail);
        bus.segment_mut(0)
            .unwrap()
            .set_touch(TouchBits::from_bits(0b0101).unwrap());
        for _ in 0..3 {
            bus.sample_all();
        }
        let found = status(&mut bus, &[0x20, 0x21, 0x22]);
        let first = found[0].answer.as_ref().unwrap();
        assert!(!first.flags.adc_fault());
        assert_eq!(first.word.touch().bits(), 0b0101);
        assert_eq!(first.counter, 3);
        assert_eq!(found[1].answer, Err(CommissionError::NoSegment(0x21)));
        assert!(found[2].answer.as_ref().unwrap().flags.adc_fault());
    }

    #[test]
    fn circular_mean_averages_around_the_wrap() {
        assert_eq!(circular_mean_counts(&[]), None);
        assert_eq!(circular_mean_counts(&[4094, 2]), Some((0, 2)));
        assert_eq!(
            circular_mean_counts(&[4090, 4094, 4, 4092]),
            Some((4094, 6))
        );
        assert_eq!(circular_mean_counts(&[1000, 1002, 1004]), Some((1002, 2)));
        // A plain average of the first would say 2048, the opposite side of the turn.
        assert_eq!(circular_mean_counts(&[4095, 1]), Some((0, 1)));
    }

    /// A bus whose one segment answers word reads with scripted counts, in turn.
    struct Scripted {
        address: u8,
        counts: Vec<u16>,
        next: usize,
    }

    impl ErrorType for Scripted {
        type Error = ErrorKind;
    }

    impl I2c for Scripted {
        fn transaction(
            &mut self,
            address: u8,
            operations: &mut [Operation<'_>],
        ) -> Result<(), Self::Error> {
            if address != self.address {
                return Err(ErrorKind::NoAcknowledge(
                    embedded_hal::i2c::NoAcknowledgeSource::Address,
                ));
            }
            let mut register = 0;
            for operation in operations {
                match operation {
                    Operation::Write(bytes) => register = bytes.first().copied().unwrap_or(0),
                    Operation::Read(buffer) => {
                        let data: Vec<u8> = if register == Register::Status.number() {
                            vec![0]
                        } else {
                            let counts = self.counts[self.next % self.counts.len()];
                            self.next += 1;
                            SampleWord::pack_truncate(counts, 0).to_be_bytes().to_vec()
                        };
                        let crc = data
                            .iter()
                            .fold(pec::update(0, pec::read_address_byte(address)), |c, &b| {
                                pec::update(c, b)
                            });
                        for (slot, byte) in buffer.iter_mut().zip(data.iter().chain([&crc])) {
                            *slot = *byte;
                        }
                    }
                }
            }
            Ok(())
        }
    }

    #[test]
    fn zero_counts_are_the_circular_mean_of_the_samples_at_rest() {
        let mut bus = Scripted {
            address: 0x25,
            counts: vec![4093, 1, 4095, 3],
            next: 0,
        };
        let mut rounds = 0;
        let measured = measure_zero_counts(&mut bus, &[0x25], 8, |_| rounds += 1).unwrap();
        assert_eq!(rounds, 8);
        assert_eq!(measured[0].zero_counts, 0);
        assert_eq!(measured[0].max_deviation_counts, 3);
        assert_eq!(measured[0].samples, 8);
        assert!(!measured[0].touched);
        assert_eq!(
            measure_zero_counts(&mut bus, &[0x25], 0, |_| {}),
            Err(CommissionError::NoSamples)
        );
        assert_eq!(
            measure_zero_counts(&mut bus, &[0x26], 1, |_| {}),
            Err(CommissionError::NoSegment(0x26))
        );
    }

    #[test]
    fn zero_counts_of_a_simulated_rig_at_rest_are_its_magnets_zeros() {
        let mut bus = SimBus::new(vec![segment(0x20, 1500), segment(0x21, 3)]);
        let measured = measure_zero_counts(&mut bus, &[0x20, 0x21], 5, SimBus::sample_all).unwrap();
        let zeros: Vec<u16> = measured.iter().map(|m| m.zero_counts).collect();
        assert_eq!(zeros, vec![1500, 3]);
        assert!(measured.iter().all(|m| m.max_deviation_counts == 0));
    }
}
