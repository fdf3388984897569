//! Where antennad's configuration comes from, and what a re-read of it changed.
//!
//! The search: `--config FILE` if given, else the first file of the search path that exists
//! ([`SYSTEM_CONFIG`], `/etc/antenna/antennad.toml`), else the built-in simulated rig
//! ([`Config::default`]). A relative `data_dir` in a file is taken relative to that file's
//! directory, so a service's recordings do not depend on its working directory; the built-in
//! default `data` stays relative to the working directory (the README's first command).
//!
//! ```
//! use host_daemon::service::config_source::ConfigSource;
//! use std::path::{Path, PathBuf};
//!
//! let dir = std::env::temp_dir().join(format!("config-source-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir)?;
//! std::fs::write(dir.join("rig.toml"), "data_dir = \"recordings\"\n")?;
//! let missing = dir.join("missing.toml");
//! let source = ConfigSource::find(None, &[missing, dir.join("rig.toml")]);
//! assert_eq!(source, ConfigSource::Found(dir.join("rig.toml")));
//! assert_eq!(source.load()?.data_dir, dir.join("recordings"));
//! assert_eq!(ConfigSource::find(None, &[]), ConfigSource::BuiltIn);
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::config::{Config, ConfigError};
use std::fmt;
use std::path::{Path, PathBuf};

/// The system-wide configuration file, read when no `--config` is given.
pub const SYSTEM_CONFIG: &str = "/etc/antenna/antennad.toml";

/// Where the configuration in force came from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ConfigSource {
    /// The file given with `--config`.
    Given(PathBuf),
    /// The first file of the search path that exists.
    Found(PathBuf),
    /// No file: the built-in simulated rig.
    BuiltIn,
}

impl ConfigSource {
    /// `given` if there is one, else the first of `search` that exists, else the built-in
    /// configuration.
    pub fn find(given: Option<&Path>, search: &[PathBuf]) -> Self {
        if let Some(path) = given {
            return Self::Given(path.to_path_buf());
        }
        search
            .iter()
            .find(|p| p.is_file())
            .map_or(Self::BuiltIn, |p| Self::Found(p.clone()))
    }

    /// The default search path: [`SYSTEM_CONFIG`].
    pub fn system_search_path() -> Vec<PathBuf> {
        vec![PathBuf::from(SYSTEM_CONFIG)]
    }

    /// The file, if the configuration comes from one.
    pub fn path(&self) -> Option<&Path> {
        match self {
            Self::Given(path) | Self::Found(path) => Some(path),
            Self::BuiltIn => None,
        }
    }

    /// Reads and checks the configuration (again, on a reload), with a relative `data_dir`
    /// taken relative to the file's directory.
    pub fn load(&self) -> Result<Config, ConfigError> {
        let Some(path) = self.path() else {
            return Ok(Config::default());
        };
        let mut config = Config::from_file(path)?;
        if config.data_dir.is_relative() {
            let dir = path.parent().unwrap_or_else(|| Path::new(""));
            config.data_dir = dir.join(&config.data_dir);
        }
        Ok(config)
    }
}

impl fmt::Display for ConfigSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Given(path) => write!(f, "{} (--config)", path.display()),
            Self::Found(path) => write!(f, "{} (found on the search path)", path.display()),
            Self::BuiltIn => write!(
                f,
                "the built-in simulated rig (no --config, no {SYSTEM_CONFIG})"
            ),
        }
    }
}

/// The keys (dotted, list entries indexed: `trials[0].duration_s`) whose values differ
/// between `running` and `reread`, the token included (named, never shown). A list whose
/// length changed is named once (`trials`).
pub fn changed_keys(running: &Config, reread: &Config) -> Vec<String> {
    let mut keys = Vec::new();
    match (
        toml::Value::try_from(running),
        toml::Value::try_from(reread),
    ) {
        (Ok(a), Ok(b)) => diff("", &a, &b, &mut keys),
        // Not expected (every configuration serializes): compare as a whole.
        _ if running != reread => keys.push("(the configuration)".to_owned()),
        _ => {}
    }
    if running.server.token != reread.server.token {
        keys.push("server.token".to_owned());
    }
    keys
}

fn diff(key: &str, a: &toml::Value, b: &toml::Value, keys: &mut Vec<String>) {
    use toml::Value;
    match (a, b) {
        (Value::Table(a), Value::Table(b)) => {
            let mut names: Vec<&String> = a.keys().chain(b.keys()).collect();
            names.sort();
            names.dedup();
            for name in names {
                let sub = if key.is_empty() {
                    name.clone()
                } else {
                    format!("{key}.{name}")
                };
                match (a.get(name), b.get(name)) {
                    (Some(x), Some(y)) => diff(&sub, x, y, keys),
                    _ => keys.push(sub),
                }
            }
        }
        (Value::Array(a), Value::Array(b)) if a.len() == b.len() => {
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                diff(&format!("{key}[{i}]"), x, y, keys);
            }
        }
        _ if a != b => keys.push(key.to_owned()),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("config-source-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn the_given_file_comes_first_then_the_search_path_then_the_built_in_rig() {
        let dir = scratch("order");
        let (a, b) = (dir.join("a.toml"), dir.join("b.toml"));
        std::fs::write(&b, "").unwrap();
        let search = [a.clone(), b.clone()];
        let given = dir.join("given.toml");
        assert_eq!(
            ConfigSource::find(Some(&given), &search),
            ConfigSource::Given(given.clone())
        );
        assert_eq!(
            ConfigSource::find(None, &search),
            ConfigSource::Found(b.clone())
        );
        std::fs::write(&a, "").unwrap();
        assert_eq!(ConfigSource::find(None, &search), ConfigSource::Found(a));
        assert_eq!(
            ConfigSource::find(None, &[dir.join("none.toml")]),
            ConfigSource::BuiltIn
        );
        assert!(ConfigSource::BuiltIn.to_string().contains(SYSTEM_CONFIG));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_relative_data_dir_is_taken_from_the_file_directory_an_absolute_one_as_it_is() {
        let dir = scratch("data-dir");
        let file = dir.join("rig.toml");
        std::fs::write(&file, "data_dir = \"rec/trials\"\n").unwrap();
        let config = ConfigSource::Given(file.clone()).load().unwrap();
        assert_eq!(config.data_dir, dir.join("rec/trials"));
        std::fs::write(&file, "data_dir = \"/var/lib/antennad\"\n").unwrap();
        let config = ConfigSource::Given(file).load().unwrap();
        assert_eq!(config.data_dir, Path::new("/var/lib/antennad"));
        assert_eq!(
            ConfigSource::BuiltIn.load().unwrap().data_dir,
            Path::new("data")
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn changed_keys_name_each_difference_and_the_token_without_its_value() {
        let running = Config::default();
        assert!(changed_keys(&running, &running.clone()).is_empty());
        let mut reread = running.clone();
        reread.bus.poll_hz = 500.0;
        reread.trials[0].duration_s = 3.0;
        reread.bus.segments[2].zero_counts = 7;
        reread.server.token = Some(crate::ControlToken::new("a-new-token-0123456789").unwrap());
        assert_eq!(
            changed_keys(&running, &reread),
            [
                "bus.poll_hz",
                "bus.segments[2].zero_counts",
                "trials[0].duration_s",
                "server.token"
            ]
        );
        let mut fewer = running.clone();
        fewer.bus.segments.pop();
        fewer.sim.scene = Some(PathBuf::from("other.toml"));
        assert_eq!(
            changed_keys(&running, &fewer),
            ["bus.segments", "sim.scene"]
        );
        let mut listed = running.clone();
        listed.server.token_env = Some("ANTENNAD_TOKEN".to_owned());
        assert_eq!(changed_keys(&running, &listed), ["server.token_env"]);
    }
}
