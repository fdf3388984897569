//! The `[bus]` table of antennad's configuration: the device, how it is polled and the
//! segments on it (address, `zero_counts`, direction), with the defaults antennad runs
//! without a configuration. antennad reads it as part of its whole configuration; `antenna
//! segments` reads it alone (every other table of the file is antennad's, checked when it
//! starts), so that both read the same keys the same way.
//!
//! ```
//! use antenna_bus::config::{BusConfig, BusFile};
//!
//! let file: BusFile = toml::from_str(
//!     "data_dir = \"x\"\n[bus]\ndevice = \"/dev/i2c-1\"\npoll_hz = 500.0\n\
//!      [[bus.segments]]\naddress = 0x30\nzero_counts = 7\ndirection = \"cw\"\n",
//! )
//! .unwrap();
//! assert_eq!(file.bus.device, "/dev/i2c-1");
//! assert_eq!(file.bus.addresses(), vec![0x30]);
//! file.bus.check_segments().unwrap();
//! assert_eq!(BusConfig::default().device, "sim");
//! ```

use antenna_protocol::{Calibration, Direction, MAX_ANGLE_COUNT, is_assignable_address};
use serde::{Deserialize, Serialize};

/// The bus clock a real device is checked against when `bus.speed_hz` is left out: 100 kHz,
/// I2C standard mode.
pub const DEFAULT_HARDWARE_SPEED_HZ: u32 = 100_000;

/// The `[bus]` table.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct BusConfig {
    /// `sim` for the simulated rig, or a Linux I2C device such as `/dev/i2c-1`.
    pub device: String,
    /// Poll rate, hertz (every segment read once per period).
    pub poll_hz: f64,
    /// The bus clock, hertz, as the board sets it (the device tree; antennad does not change
    /// it): a poll rate the bus cannot carry is refused, with the arithmetic. Left out:
    /// [`DEFAULT_HARDWARE_SPEED_HZ`] for a real device; the simulated bus moves no bits and is
    /// treated as unlimited unless this is given (then it is checked as a real bus would be,
    /// to try a hardware configuration on the simulator).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub speed_hz: Option<u32>,
    /// Read each segment's sample counter every this many polls (a counter that has not
    /// moved since the last check marks the segment stale). The counters are read one per
    /// poll, round-robin, so a cycle is never shorter than one poll more than there are
    /// segments.
    pub counter_check_every: u32,
    /// Busy-wait this many microseconds before each poll deadline instead of sleeping
    /// (0: sleep only). Cuts wake-up lateness to about a microsecond at the cost of CPU.
    pub spin_us: u64,
    /// Run the polling thread under `SCHED_FIFO` at this priority (1..=99) when the system
    /// permits it (root, `CAP_SYS_NICE` or an `RLIMIT_RTPRIO` allowance); refused, antennad
    /// says so once and polls on normal scheduling. 0: normal scheduling. Default 50: on a
    /// busy machine it is what keeps the p99 poll jitter in the tens of microseconds.
    pub realtime_priority: u8,
    /// The segments, base to tip.
    pub segments: Vec<SegmentConfig>,
}

/// The built-in rig's segments: one per flexible joint of antennad's built-in scene (8), at
/// 0x20 on, each magnet press-fit at its own angle (every segment has its own zero), the
/// directions alternating.
pub fn built_in_segments() -> Vec<SegmentConfig> {
    (0..8u8)
        .map(|k| SegmentConfig {
            address: 0x20 + k,
            zero_counts: 1500 + 97 * u16::from(k),
            direction: if k % 2 == 0 {
                DirectionName::Ccw
            } else {
                DirectionName::Cw
            },
        })
        .collect()
}

impl Default for BusConfig {
    /// The built-in rig's bus: simulated, polled at 1 kHz, [`built_in_segments`].
    fn default() -> Self {
        Self {
            device: "sim".to_owned(),
            poll_hz: 1000.0,
            speed_hz: None,
            counter_check_every: 50,
            spin_us: 0,
            realtime_priority: 50,
            segments: built_in_segments(),
        }
    }
}

impl BusConfig {
    /// Whether the bus is the simulated one.
    pub fn is_sim(&self) -> bool {
        self.device == "sim"
    }

    /// The segment addresses, base to tip.
    pub fn addresses(&self) -> Vec<u8> {
        self.segments.iter().map(|s| s.address).collect()
    }

    /// The segment calibrations, base to tip.
    pub fn calibrations(&self) -> Vec<Calibration> {
        self.segments
            .iter()
            .map(SegmentConfig::calibration)
            .collect()
    }

    /// The bus clock the poll rate is checked against: `bus.speed_hz`, or
    /// [`DEFAULT_HARDWARE_SPEED_HZ`] for a real device; `None` for the simulated bus without
    /// `bus.speed_hz` (unlimited).
    pub fn checked_speed_hz(&self) -> Option<u32> {
        match self.speed_hz {
            Some(speed_hz) => Some(speed_hz),
            None if self.is_sim() => None,
            None => Some(DEFAULT_HARDWARE_SPEED_HZ),
        }
    }

    /// Checks every segment: an assignable address (0x08..=0x77), `zero_counts` in
    /// 0..=4095, no address twice.
    ///
    /// # Errors
    /// The first bad entry, named by its key (`bus.segments[k].address`).
    pub fn check_segments(&self) -> Result<(), SegmentsError> {
        for (index, segment) in self.segments.iter().enumerate() {
            if !is_assignable_address(segment.address) {
                return Err(SegmentsError::Address {
                    index,
                    address: segment.address,
                });
            }
            if segment.zero_counts > MAX_ANGLE_COUNT {
                return Err(SegmentsError::ZeroCounts {
                    index,
                    zero_counts: segment.zero_counts,
                });
            }
            if let Some(first) = self.segments[..index]
                .iter()
                .position(|s| s.address == segment.address)
            {
                return Err(SegmentsError::Duplicate {
                    index,
                    address: segment.address,
                    first,
                });
            }
        }
        Ok(())
    }
}

/// A bad `[[bus.segments]]` entry.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SegmentsError {
    /// An address a segment cannot be given.
    #[error("bus.segments[{index}].address = {address:#04x}: must be in 0x08..=0x77")]
    Address {
        /// The entry, from 0.
        index: usize,
        /// Its address.
        address: u8,
    },
    /// A zero beyond the 12-bit angle.
    #[error("bus.segments[{index}].zero_counts = {zero_counts}: must be in 0..=4095")]
    ZeroCounts {
        /// The entry, from 0.
        index: usize,
        /// Its `zero_counts`.
        zero_counts: u16,
    },
    /// Two entries with one address.
    #[error("bus.segments[{index}].address = {address:#04x}: also bus.segments[{first}]'s")]
    Duplicate {
        /// The later entry, from 0.
        index: usize,
        /// The address.
        address: u8,
        /// The earlier entry with it.
        first: usize,
    },
}

/// Which way the magnet turns for a positive joint angle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DirectionName {
    /// Counter-clockwise.
    Ccw,
    /// Clockwise.
    Cw,
}

/// One `[[bus.segments]]` entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentConfig {
    /// Its 7-bit address (0x08..=0x77).
    pub address: u8,
    /// The count the Hall sensor reads at joint angle zero (0..=4095).
    pub zero_counts: u16,
    /// `ccw` or `cw`.
    pub direction: DirectionName,
}

impl SegmentConfig {
    /// The calibration the counts are converted with.
    pub fn calibration(&self) -> Calibration {
        let direction = match self.direction {
            DirectionName::Ccw => Direction::CounterClockwise,
            DirectionName::Cw => Direction::Clockwise,
        };
        Calibration::new(self.zero_counts, direction)
    }
}

/// A configuration file read for its `[bus]` table alone: every other table and key is
/// left to antennad (not refused here).
#[derive(Debug, Clone, PartialEq, Default, Deserialize)]
pub struct BusFile {
    /// `[bus]` ([`BusConfig::default`] when the file has none).
    #[serde(default)]
    pub bus: BusConfig,
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn the_built_in_bus_is_the_simulated_rigs_eight_segments() {
        let bus = BusConfig::default();
        assert!(bus.is_sim());
        assert_eq!(bus.segments.len(), 8);
        assert_eq!(bus.segments[0].zero_counts, 1500);
        assert_eq!(bus.segments[1].direction, DirectionName::Cw);
        assert_eq!(bus.checked_speed_hz(), None);
        bus.check_segments().unwrap();
        let file: BusFile = toml::from_str("[bus]\ndevice = \"/dev/i2c-1\"\n").unwrap();
        assert_eq!(file.bus.segments, bus.segments);
        assert_eq!(file.bus.checked_speed_hz(), Some(DEFAULT_HARDWARE_SPEED_HZ));
    }

    #[test]
    fn bad_segments_are_named_by_their_key() {
        let bus = |segments: &str| -> BusConfig {
            toml::from_str::<BusFile>(&format!("[bus]\nsegments = {segments}\n"))
                .unwrap()
                .bus
        };
        let e = bus("[{ address = 0x30, zero_counts = 4096, direction = \"ccw\" }]")
            .check_segments()
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "bus.segments[0].zero_counts = 4096: must be in 0..=4095"
        );
        let e = bus("[{ address = 0x78, zero_counts = 1, direction = \"ccw\" }]")
            .check_segments()
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "bus.segments[0].address = 0x78: must be in 0x08..=0x77"
        );
        let e = bus(
            "[{ address = 0x30, zero_counts = 1, direction = \"ccw\" }, \
             { address = 0x30, zero_counts = 2, direction = \"cw\" }]",
        )
        .check_segments()
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "bus.segments[1].address = 0x30: also bus.segments[0]'s"
        );
        let e = toml::from_str::<BusFile>("[bus]\npoll_hz = 1.0\nfoo = 2\n").unwrap_err();
        assert!(e.to_string().contains("unknown field `foo`"), "{e}");
    }
}
