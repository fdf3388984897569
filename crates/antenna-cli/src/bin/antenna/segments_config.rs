//! The part of antennad's configuration that `antenna segments` reads: `[bus] device` and the
//! `[[bus.segments]]` (address, zero_counts, direction). The command reads them here rather
//! than through `host-daemon`, which the CLI does not depend on
//! (`tests/tests/cross/crate_boundaries.rs`); every other key is antennad's, checked when it starts.
//! A file without `[[bus.segments]]` has the built-in rig's nine, as antennad gives it
//! (`host-daemon/config/sim.toml`, compiled in).

use std::path::Path;

use antenna_protocol::{Calibration, Direction, is_assignable_address};
use anyhow::{Context as _, bail};
use serde::Deserialize;

/// The built-in configuration, written out with every key (antennad's default rig).
const BUILT_IN: &str = include_str!("../../../../../host-daemon/config/sim.toml");

/// `[bus]` as far as commissioning reads it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct BusConfig {
    /// `sim` or a Linux I2C device.
    pub device: String,
    /// The segments, base to tip.
    pub segments: Vec<SegmentConfig>,
}

/// One `[[bus.segments]]` entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SegmentConfig {
    pub address: u8,
    pub zero_counts: u16,
    #[serde(default)]
    pub direction: DirectionName,
}

/// `ccw` or `cw`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum DirectionName {
    #[default]
    Ccw,
    Cw,
}

impl SegmentConfig {
    /// The calibration the segment's counts are converted with.
    pub fn calibration(&self) -> Calibration {
        let direction = match self.direction {
            DirectionName::Ccw => Direction::CounterClockwise,
            DirectionName::Cw => Direction::Clockwise,
        };
        Calibration::new(self.zero_counts, direction)
    }
}

#[derive(Deserialize)]
struct File {
    #[serde(default)]
    bus: Option<BusTable>,
}

#[derive(Deserialize)]
struct BusTable {
    device: Option<String>,
    segments: Option<Vec<SegmentConfig>>,
}

impl BusConfig {
    /// The built-in rig's bus (antennad without a configuration).
    pub fn built_in() -> anyhow::Result<Self> {
        Self::from_toml_str(
            BUILT_IN,
            "the built-in configuration (host-daemon/config/sim.toml)",
        )
    }

    /// Reads the bus of the configuration file at `path`.
    pub fn from_file(path: &Path) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read", path.display()))?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// Reads the bus of configuration text; errors name `origin`, the key and the entry.
    pub fn from_toml_str(text: &str, origin: &str) -> anyhow::Result<Self> {
        let file: File = toml::from_str(text).with_context(|| format!("{origin}: [bus]"))?;
        let bus = file.bus.unwrap_or(BusTable {
            device: None,
            segments: None,
        });
        let segments = match bus.segments {
            Some(segments) => segments,
            None if text == BUILT_IN => bail!("{origin}: no [[bus.segments]]"),
            None => Self::built_in()?.segments,
        };
        for (k, segment) in segments.iter().enumerate() {
            if !is_assignable_address(segment.address) {
                bail!(
                    "{origin}: bus.segments[{k}].address = {:#04x}: must be in 0x08..=0x77",
                    segment.address
                );
            }
            if segment.zero_counts > antenna_protocol::MAX_ANGLE_COUNT {
                bail!(
                    "{origin}: bus.segments[{k}].zero_counts = {}: must be in 0..=4095",
                    segment.zero_counts
                );
            }
            if let Some(j) = segments[..k]
                .iter()
                .position(|s| s.address == segment.address)
            {
                bail!(
                    "{origin}: bus.segments[{k}].address = {:#04x}: also bus.segments[{j}]'s",
                    segment.address
                );
            }
        }
        Ok(Self {
            device: bus.device.unwrap_or_else(|| "sim".to_owned()),
            segments,
        })
    }

    /// The segments' addresses, base to tip.
    pub fn addresses(&self) -> Vec<u8> {
        self.segments.iter().map(|s| s.address).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_built_in_rig_has_nine_segments_on_the_simulated_bus() {
        let bus = BusConfig::built_in().unwrap();
        assert_eq!(bus.device, "sim");
        assert_eq!(bus.segments.len(), 9);
        assert_eq!(bus.segments[0].zero_counts, 1500);
        assert_eq!(bus.segments[1].direction, DirectionName::Cw);
    }

    #[test]
    fn other_keys_are_antennads_and_bad_segments_are_located() {
        let bus = BusConfig::from_toml_str(
            "data_dir = \"x\"\n[bus]\ndevice = \"/dev/i2c-1\"\npoll_hz = 500.0\n\
             [[bus.segments]]\naddress = 0x30\nzero_counts = 7\n",
            "t.toml",
        )
        .unwrap();
        assert_eq!(bus.device, "/dev/i2c-1");
        assert_eq!(bus.addresses(), vec![0x30]);
        let e = BusConfig::from_toml_str(
            "[[bus.segments]]\naddress = 0x30\nzero_counts = 4096\n",
            "t.toml",
        )
        .unwrap_err();
        assert!(
            e.to_string().contains("bus.segments[0].zero_counts = 4096"),
            "{e}"
        );
        let e = BusConfig::from_toml_str(
            "[[bus.segments]]\naddress = 0x30\nzero_counts = 1\n\
             [[bus.segments]]\naddress = 0x30\nzero_counts = 2\n",
            "t.toml",
        )
        .unwrap_err();
        assert!(e.to_string().contains("also bus.segments[0]'s"), "{e}");
    }
}
