//! The part of antennad's configuration that `antenna segments` reads: the `[bus]` table
//! ([`antenna_bus::config`], the types antennad reads it with), its `[[bus.segments]]`
//! checked (address, zero_counts, no address twice). Every other table of the file is
//! antennad's, checked when it starts. A file without `[[bus.segments]]`, or without a
//! configuration, has the built-in rig's segments, as antennad gives it.

use std::path::Path;

use antenna_bus::config::{BusConfig, BusFile};
use anyhow::{Context as _, anyhow};

/// `[bus]` as commissioning reads it.
#[derive(Debug, Clone, PartialEq)]
pub struct Config(pub BusConfig);

impl std::ops::Deref for Config {
    type Target = BusConfig;
    fn deref(&self) -> &BusConfig {
        &self.0
    }
}

impl Config {
    /// The built-in rig's bus (antennad without a configuration).
    pub fn built_in() -> Self {
        Self(BusConfig::default())
    }

    /// Reads the bus of the configuration file at `path`.
    ///
    /// # Errors
    /// The file cannot be read, its `[bus]` is not antennad's, or a segment is bad; the
    /// message names the file and the key.
    pub fn from_file(path: &Path) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read", path.display()))?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// Reads the bus of configuration text; errors name `origin`, the key and the entry.
    ///
    /// # Errors
    /// As [`Config::from_file`].
    pub fn from_toml_str(text: &str, origin: &str) -> anyhow::Result<Self> {
        let file: BusFile = toml::from_str(text).with_context(|| format!("{origin}: [bus]"))?;
        file.bus
            .check_segments()
            .map_err(|e| anyhow!("{origin}: {e}"))?;
        Ok(Self(file.bus))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn other_keys_are_antennads_and_bad_segments_are_located() {
        let bus = Config::from_toml_str(
            "data_dir = \"x\"\n[bus]\ndevice = \"/dev/i2c-1\"\npoll_hz = 500.0\n\
             [[bus.segments]]\naddress = 0x30\nzero_counts = 7\ndirection = \"ccw\"\n",
            "t.toml",
        )
        .unwrap();
        assert_eq!(bus.device, "/dev/i2c-1");
        assert_eq!(bus.addresses(), vec![0x30]);
        let e = Config::from_toml_str(
            "[[bus.segments]]\naddress = 0x30\nzero_counts = 4096\ndirection = \"ccw\"\n",
            "t.toml",
        )
        .unwrap_err();
        assert_eq!(
            format!("{e:#}"),
            "t.toml: bus.segments[0].zero_counts = 4096: must be in 0..=4095"
        );
        let e = Config::from_toml_str(
            "[[bus.segments]]\naddress = 0x30\nzero_counts = 1\ndirection = \"ccw\"\n\
             [[bus.segments]]\naddress = 0x30\nzero_counts = 2\ndirection = \"cw\"\n",
            "t.toml",
        )
        .unwrap_err();
        assert!(format!("{e:#}").contains("also bus.segments[0]'s"), "{e:#}");
        let without_segments =
            Config::from_toml_str("[bus]\ndevice = \"sim\"\n", "t.toml").unwrap();
        assert_eq!(without_segments, Config::built_in());
    }
}
