//! The daemon's configuration, read from TOML (examples with every key commented in
//! `host-daemon/config/`: `sim.toml`, the simulated rig, and `robot.toml`, the hardware).
//!
//! Every table and key is optional except where a list entry needs its fields (a segment's
//! address, a move's distance); what is left out takes the built-in default, which is the
//! simulated rig ([`Config::default`]). Unknown keys are errors. Every error names the key
//! and, where it is known, the line and column:
//!
//! ```
//! use host_daemon::service::config::Config;
//!
//! let error = Config::from_toml_str("[bus]\npoll_hz = -5\n", "rig.toml").unwrap_err();
//! assert_eq!(error.key, "bus.poll_hz");
//! assert_eq!((error.line, error.column), (Some(2), Some(1)));
//! assert!(error.to_string().starts_with("rig.toml:2:1: `bus.poll_hz`"));
//! ```
//!
//! # Layout
//!
//! The lowest layer of the crate: it imports no other module of it (the layering test,
//! `tests/layers.rs`, checks this). [`schema`](Config) holds the tables and their defaults,
//! `validate` what serde cannot check, `locate` where a key is written (the toml parser's
//! spans); [`token`], [`geometry`] and [`bus_budget`] are the values the configuration must
//! build to be valid (the control token, the stage's and servo's geometry, the bus's time
//! budget), which the drivers and the server use.

pub mod bus_budget;
pub mod geometry;
mod locate;
pub mod scene;
mod schema;
pub mod token;
mod validate;

pub use schema::*;

use std::fmt;
use std::path::Path;

/// A configuration error: the file, the key (dotted path) and, where known, its line and
/// column (1-based).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfigError {
    /// The file name given to the parser.
    pub path: String,
    /// The key, as a dotted path (`stage.max_mm`, `bus.segments[2].address`).
    pub key: String,
    /// Line of the key, 1-based, if known.
    pub line: Option<usize>,
    /// Column of the key, 1-based, if known.
    pub column: Option<usize>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path)?;
        if let (Some(line), Some(column)) = (self.line, self.column) {
            write!(f, ":{line}:{column}")?;
        }
        write!(f, ": `{}`: {}", self.key, self.message)
    }
}

impl std::error::Error for ConfigError {}

impl Config {
    /// Reads and checks the file at `path`.
    pub fn from_file(path: &Path) -> Result<Self, ConfigError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ConfigError {
            path: name.clone(),
            key: "(file)".to_owned(),
            line: None,
            column: None,
            message: format!("cannot read: {e}"),
        })?;
        Self::from_toml_str(&text, &name)
    }

    /// Parses and checks `text`, naming it `path` in errors, reads the scene of `[sim]
    /// scene` (relative to `path`'s directory) and reads the control token from
    /// `server.token_file` or `server.token_env` if one is set.
    pub fn from_toml_str(text: &str, path: &str) -> Result<Self, ConfigError> {
        let mut config: Config =
            toml::from_str(text).map_err(|e| locate::toml_error(text, path, &e))?;
        let folder = Path::new(path).parent().unwrap_or_else(|| Path::new(""));
        config
            .refuse_old_sim_keys()
            .and_then(|()| config.read_scene(folder))
            .and_then(|()| config.validate())
            .and_then(|()| config.resolve_token())
            .map_err(|(key, message)| {
                let (line, column) = locate::Spans::parse(text).locate(&key).unzip();
                ConfigError {
                    path: path.to_owned(),
                    key,
                    line,
                    column,
                    message,
                }
            })?;
        Ok(config)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_is_valid_and_simulated() {
        let config = Config::from_toml_str("", "empty.toml").unwrap();
        assert_eq!(config, Config::default());
        assert!(config.bus.is_sim());
        assert_eq!(config.bus.segments.len(), 8);
    }

    /// The recorded configuration reads back as the configuration in force, less the token.
    #[test]
    fn the_recorded_configuration_reads_back_without_the_token() {
        let text =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/config/robot.toml"))
                .unwrap();
        let text = text.replace(
            "token_env = \"ANTENNAD_TOKEN\"",
            "token = \"SECRET-TOKEN-12345\"",
        );
        // Its scene is read relative to the file.
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/config/robot.toml");
        let config = Config::from_toml_str(&text, path).unwrap();
        assert_eq!(config.sim.rig.joints(), config.bus.segments.len());
        assert!(config.server.token.is_some());
        let recorded = config.to_recorded_toml();
        assert!(!recorded.contains("SECRET"), "{recorded}");
        let back = Config::from_toml_str(&recorded, "recorded").unwrap();
        let mut expected = config.clone();
        expected.server.token = None;
        assert_eq!(back, expected);
        let default = Config::default().to_recorded_toml();
        assert_eq!(
            Config::from_toml_str(&default, "d").unwrap(),
            Config::default()
        );
    }

    #[test]
    fn a_short_token_is_refused_where_it_is_written() {
        let error = Config::from_toml_str("[server]\ntoken = \"a\"\n", "rig.toml").unwrap_err();
        assert_eq!(error.key, "server.token");
        assert_eq!((error.line, error.column), (Some(2), Some(9)));
        assert!(error.message.contains("at least 16 characters"), "{error}");
        let error = Config::from_toml_str(
            "[server]\ntoken = \"0123456789abcdef\"\ntoken_env = \"X\"\n",
            "rig.toml",
        )
        .unwrap_err();
        assert_eq!(error.key, "server.token_env");
        assert_eq!(error.line, Some(3));
    }

    #[test]
    fn the_token_comes_from_a_private_file_or_the_environment() {
        let dir = std::env::temp_dir().join(format!("token-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("token");
        std::fs::write(&file, "from-a-file-0123456789\n").unwrap();
        let text = format!("[server]\ntoken_file = {:?}\n", file.display().to_string());
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o644)).unwrap();
            let error = Config::from_toml_str(&text, "rig.toml").unwrap_err();
            assert_eq!(error.key, "server.token_file");
            assert!(error.message.contains("chmod 600"), "{error}");
            assert!(!error.to_string().contains("from-a-file"), "{error}");
            std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o600)).unwrap();
        }
        let config = Config::from_toml_str(&text, "rig.toml").unwrap();
        let token = config.server.token.as_ref().unwrap();
        assert!(token.matches("from-a-file-0123456789"));
        std::fs::write(&file, "short\n").unwrap();
        let error = Config::from_toml_str(&text, "rig.toml").unwrap_err();
        assert_eq!(error.key, "server.token_file");
        assert!(error.message.contains("at least 16"), "{error}");
        std::fs::remove_dir_all(&dir).unwrap();

        let error = Config::from_toml_str(
            "[server]\ntoken_env = \"ANTENNAD_TEST_TOKEN_UNSET_XYZ\"\n",
            "rig.toml",
        )
        .unwrap_err();
        assert_eq!(error.key, "server.token_env");
        assert!(
            error.message.contains("ANTENNAD_TEST_TOKEN_UNSET_XYZ"),
            "{error}"
        );
    }

    #[test]
    fn a_trial_base_angle_outside_the_servo_calibration_is_refused() {
        let error = Config::from_toml_str(
            "[[trials]]\nname = \"t\"\nbase_angle_deg = 90.0\n",
            "rig.toml",
        )
        .unwrap_err();
        assert_eq!(error.key, "trials[0].base_angle_deg");
        assert_eq!(error.line, Some(3));
        assert!(error.message.contains("-45..=45"), "{error}");
    }
}
