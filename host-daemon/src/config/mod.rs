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

use crate::net::ControlToken;
use antenna_data::record::{ChunkCompression, RecorderOptions};
use antenna_protocol::{Calibration, Direction};
use serde::{Deserialize, Serialize};
use sim_core::{
    CalibrationError, FIRMWARE_DEBOUNCE_SAMPLES, SensorError, SensorField, SensorSettings,
};
use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

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

/// The whole configuration.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct Config {
    /// Where trial recordings go (`<data_dir>/<trial>.mcap`).
    pub data_dir: PathBuf,
    /// The I2C bus and its segments.
    pub bus: BusConfig,
    /// The linear stage.
    pub stage: StageConfig,
    /// The base servo.
    pub servo: ServoConfig,
    /// The TCP endpoint.
    pub server: ServerConfig,
    /// How trials are recorded.
    pub recording: RecordingConfig,
    /// The trials, run by name (the first by default).
    pub trials: Vec<TrialConfig>,
    /// The simulated rig (used when the bus is `sim`).
    pub sim: SimConfig,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            data_dir: PathBuf::from("data"),
            bus: BusConfig::default(),
            stage: StageConfig::default(),
            servo: ServoConfig::default(),
            server: ServerConfig::default(),
            recording: RecordingConfig::default(),
            trials: vec![TrialConfig::default()],
            sim: SimConfig::default(),
        }
    }
}

/// The I2C bus.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct BusConfig {
    /// `sim` for the simulated rig, or a Linux I2C device such as `/dev/i2c-1`.
    pub device: String,
    /// Poll rate, hertz (every segment read once per period).
    pub poll_hz: f64,
    /// The bus clock, hertz, as the board sets it (the device tree; antennad does not change
    /// it): a poll rate the bus cannot carry is refused, with the arithmetic
    /// ([`crate::hardware::bus_budget`]). Left out: 100 kHz (standard mode) for a real device; the
    /// simulated bus moves no bits and is treated as unlimited unless this is given (then it
    /// is checked as a real bus would be, to try a hardware configuration on the simulator).
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
    /// busy machine it is what keeps the p99 poll jitter in the tens of microseconds
    /// (BENCHMARKS.md, "Host daemon").
    pub realtime_priority: u8,
    /// The segments, base to tip.
    pub segments: Vec<SegmentConfig>,
}

impl Default for BusConfig {
    fn default() -> Self {
        Self {
            device: "sim".to_owned(),
            poll_hz: 1000.0,
            speed_hz: None,
            counter_check_every: 50,
            spin_us: 0,
            realtime_priority: 50,
            // Each magnet is press-fit at its own angle: every segment has its own zero.
            segments: (0..9u8)
                .map(|k| SegmentConfig {
                    address: 0x20 + k,
                    zero_counts: 1500 + 97 * u16::from(k),
                    direction: if k % 2 == 0 {
                        DirectionName::Ccw
                    } else {
                        DirectionName::Cw
                    },
                })
                .collect(),
        }
    }
}

impl Config {
    /// Whether any hardware is configured (the bus, the stage or the servo is not `sim`):
    /// then no trial starts by itself.
    pub fn has_hardware(&self) -> bool {
        !self.bus.is_sim() || self.stage.port != "sim" || self.servo.port != "sim"
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

    /// The bus clock the poll rate is checked against: `bus.speed_hz`, or 100 kHz for a real
    /// device; `None` for the simulated bus without `bus.speed_hz` (unlimited).
    pub fn checked_speed_hz(&self) -> Option<u32> {
        match self.speed_hz {
            Some(speed_hz) => Some(speed_hz),
            None if self.is_sim() => None,
            None => Some(crate::hardware::bus_budget::DEFAULT_HARDWARE_SPEED_HZ),
        }
    }

    /// The segment calibrations, base to tip.
    pub fn calibrations(&self) -> Vec<Calibration> {
        self.segments
            .iter()
            .map(SegmentConfig::calibration)
            .collect()
    }
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

/// One segment on the bus.
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

/// The linear stage (a Velmex VXM, or simulated).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct StageConfig {
    /// `sim`, or the VXM's serial port such as `/dev/ttyUSB0`.
    pub port: String,
    /// Serial baud rate (the VXM's default is 9600).
    pub baud: u32,
    /// How long to wait for a reply from the VXM, milliseconds.
    pub reply_timeout_ms: u64,
    /// Motor steps per millimetre of travel.
    pub steps_per_mm: f64,
    /// Lower soft limit, millimetres from home.
    pub min_mm: f64,
    /// Upper soft limit, millimetres from home.
    pub max_mm: f64,
    /// Fastest move allowed, millimetres per second.
    pub max_speed_mm_per_s: f64,
    /// How often the position is sampled, hertz.
    pub sample_hz: f64,
    /// Which limit switch the stage homes against (the near end, where `min_mm` is):
    /// `"negative"` (the VXM's `I1M-0`) or `"positive"` (`I1M0`).
    pub homing_direction: HomingDirection,
    /// Homing speed, millimetres per second (at most `max_speed_mm_per_s`).
    pub homing_speed_mm_per_s: f64,
    /// How long homing may take before it counts as failed (the stage is killed), seconds.
    pub homing_timeout_s: f64,
}

pub use crate::hardware::stage::HomingDirection;

impl Default for StageConfig {
    fn default() -> Self {
        Self {
            port: "sim".to_owned(),
            baud: 9600,
            reply_timeout_ms: 2000,
            steps_per_mm: 80.0,
            min_mm: 0.0,
            max_mm: 300.0,
            max_speed_mm_per_s: 50.0,
            sample_hz: 50.0,
            homing_direction: HomingDirection::Negative,
            homing_speed_mm_per_s: 10.0,
            homing_timeout_s: 60.0,
        }
    }
}

/// The base servo (a Pololu Maestro channel, or simulated).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ServoConfig {
    /// `sim`, or the Maestro's command port such as `/dev/ttyACM0`.
    pub port: String,
    /// The Maestro channel the servo is on.
    pub channel: u8,
    /// Pulse-to-angle calibration, first point: angle, degrees...
    pub angle_a_deg: f64,
    /// ...and its pulse width, microseconds.
    pub pulse_a_us: f64,
    /// Second point: angle, degrees...
    pub angle_b_deg: f64,
    /// ...and its pulse width, microseconds.
    pub pulse_b_us: f64,
    /// How often the angle is sampled, hertz.
    pub sample_hz: f64,
}

impl Default for ServoConfig {
    fn default() -> Self {
        Self {
            port: "sim".to_owned(),
            channel: 0,
            angle_a_deg: -45.0,
            pulse_a_us: 1000.0,
            angle_b_deg: 45.0,
            pulse_b_us: 2000.0,
            sample_hz: 50.0,
        }
    }
}

/// The TCP endpoint.
///
/// The control token comes from at most one of `token` (in the file: at least 16
/// characters), `token_file` (a file only its owner may read, holding the token on one line)
/// and `token_env` (the name of an environment variable holding it); with none of them
/// antennad generates one at start (128 bits from the operating system's random source) and
/// prints it once. The token itself is never serialized: a recording keeps the configuration
/// without it.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ServerConfig {
    /// Address and port to listen on; loopback unless you mean otherwise.
    pub listen: String,
    /// The token control commands must carry (`stop_all` needs none); read from
    /// `token_file` or `token_env` when one of those is set.
    #[serde(skip_serializing)]
    pub token: Option<ControlToken>,
    /// A file holding the token (white space around it ignored); it must not be readable by
    /// the group or others (`chmod 600`). Relative to the working directory.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub token_file: Option<PathBuf>,
    /// An environment variable holding the token.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub token_env: Option<String>,
    /// Connections at most (default 32). When full, a new connection takes the place of the
    /// oldest one that never proved the token; operators' connections are never dropped.
    pub max_clients: usize,
    /// Connections from one address at most (default 16), by the same rule.
    pub max_clients_per_peer: usize,
}

impl Default for ServerConfig {
    fn default() -> Self {
        Self {
            listen: "127.0.0.1:7878".to_owned(),
            token: None,
            token_file: None,
            token_env: None,
            max_clients: 32,
            max_clients_per_peer: 16,
        }
    }
}

/// How trials are recorded.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RecordingConfig {
    /// Chunk compression: `zstd` (default) or `none`.
    pub compression: CompressionName,
    /// Sync the trial file to the disk this often, seconds (default 1; 0: only when the
    /// trial ends). The file is flushed to the OS every 100 ms whatever this says.
    pub sync_interval_s: f64,
    /// Free space the data directory's file system must keep, megabytes (10^6 bytes;
    /// default 100): a trial is refused below it and ends (with the reason recorded) when
    /// the free space falls below it; polling goes on.
    pub min_free_mb: f64,
}

impl Default for RecordingConfig {
    fn default() -> Self {
        Self {
            compression: CompressionName::Zstd,
            sync_interval_s: 1.0,
            min_free_mb: 100.0,
        }
    }
}

impl RecordingConfig {
    /// The recorder's options.
    pub fn recorder_options(&self) -> RecorderOptions {
        RecorderOptions {
            compression: match self.compression {
                CompressionName::Zstd => ChunkCompression::Zstd,
                CompressionName::None => ChunkCompression::None,
            },
            sync_interval_s: self.sync_interval_s,
        }
    }

    /// [`Self::min_free_mb`] in bytes.
    pub fn min_free_bytes(&self) -> u64 {
        (self.min_free_mb * 1e6) as u64
    }
}

/// A chunk compression's name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CompressionName {
    /// zstd.
    Zstd,
    /// No compression.
    None,
}

/// One trial.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrialConfig {
    /// Its name, also the recording's file name.
    pub name: String,
    /// Base (servo) angle for the trial, degrees.
    pub base_angle_deg: f64,
    /// Trial length, seconds; the moves that have not finished by then are stopped.
    pub duration_s: f64,
    /// Stage moves, one after another.
    pub moves: Vec<MoveConfig>,
    /// Free text kept with the recording (wall, hair layout, operator...).
    pub metadata: BTreeMap<String, String>,
}

impl Default for TrialConfig {
    fn default() -> Self {
        Self {
            name: "wall-sweep".to_owned(),
            base_angle_deg: 0.0,
            duration_s: 12.0,
            moves: vec![
                MoveConfig {
                    distance_mm: 150.0,
                    speed_mm_per_s: 30.0,
                    pause_s: 0.5,
                },
                MoveConfig {
                    distance_mm: -150.0,
                    speed_mm_per_s: 30.0,
                    pause_s: 0.0,
                },
            ],
            metadata: BTreeMap::from([
                ("wall".to_owned(), "simulated flat wall".to_owned()),
                ("hairs".to_owned(), "none".to_owned()),
            ]),
        }
    }
}

/// One relative stage move.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MoveConfig {
    /// Distance, millimetres (negative moves back).
    pub distance_mm: f64,
    /// Speed, millimetres per second.
    pub speed_mm_per_s: f64,
    /// Pause after the move, seconds.
    #[serde(default)]
    pub pause_s: f64,
}

/// The simulated rig.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct SimConfig {
    /// The wall.
    pub wall: WallConfig,
    /// The simulated antenna.
    pub antenna: AntennaConfig,
    /// Faults to inject into simulated segments (none by default), to see and test how the
    /// daemon copes.
    pub faults: Vec<SimFaultConfig>,
    /// The segments' sensors as they are (ideal by default).
    pub sensors: SimSensorsConfig,
}

/// `[sim.sensors]`: the simulated segments' sensors as they are (seed 2.3.1; issue #18), with
/// the keys and meaning of sim-core's [`SensorSettings`] (a scene's `[sensors]`), seeded so
/// that one seed gives one run. Left out, the sensors are ideal and the simulated rig's words
/// are exactly those of ideal sensors.
///
/// - Each segment's Hall sensor sees its joint angle turned by the joint's gain error and
///   calibration offset, and each of the 16 ten-bit conversions of a sample gets its own
///   Gaussian noise of `angle_noise_counts` ten-bit counts; the segment firmware's own
///   oversampling turns that into `angle_noise_counts` twelve-bit counts
///   ([`antenna_bus::hall_sensor`], which also says what the firmware's truncation and its ADC
///   fault bit make of noisy conversions).
/// - A touch switch closes for a contact whose force is at least `touch_threshold_n`.
/// - Two settings of [`SensorSettings`] are the rig's own and are not taken here: the touch
///   debounce is the segment firmware's, over [`FIRMWARE_DEBOUNCE_SAMPLES`] reads
///   (`touch_debounce_samples` may only repeat it), and the sensors are sampled once per poll,
///   at `bus.poll_hz` (`sample_rate_hz` is refused, naming `bus.poll_hz`).
///   [`Config::sensor_settings`] gives all of them as in force.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimSensorsConfig {
    /// Standard deviation of the Hall angle noise of one sample, twelve-bit counts (`>= 0`).
    pub angle_noise_counts: f64,
    /// Calibration offset per segment, twelve-bit counts: a number (the spread each segment's
    /// offset is drawn from with the seed, `>= 0`) or a list of one per segment, base to tip.
    pub offset_counts: CalibrationErrorConfig,
    /// Gain error per segment, a fraction (`0.01`: the angle reads 1 % large): a number (the
    /// spread of a draw) or a list of one per segment, each above -1.
    pub gain_error: CalibrationErrorConfig,
    /// The force that closes a touch switch, newtons (`>= 0`; 0: any contact).
    pub touch_threshold_n: f64,
    /// Only [`FIRMWARE_DEBOUNCE_SAMPLES`], the firmware's, if given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub touch_debounce_samples: Option<u32>,
    /// Refused if given: the sensors are sampled at `bus.poll_hz`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sample_rate_hz: Option<f64>,
    /// The seed of the noise and of the drawn calibration errors.
    pub seed: u64,
}

impl Default for SimSensorsConfig {
    fn default() -> Self {
        let ideal = SensorSettings::IDEAL;
        Self {
            angle_noise_counts: ideal.angle_noise_counts,
            offset_counts: CalibrationErrorConfig(ideal.offset_counts),
            gain_error: CalibrationErrorConfig(ideal.gain_error),
            touch_threshold_n: ideal.touch_threshold_n,
            touch_debounce_samples: None,
            sample_rate_hz: None,
            seed: ideal.seed,
        }
    }
}

/// `offset_counts` and `gain_error` of `[sim.sensors]`: a number (the spread each segment's
/// value is drawn from) or a list (one value per segment).
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationErrorConfig(pub CalibrationError);

impl Serialize for CalibrationErrorConfig {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match &self.0 {
            CalibrationError::Spread(sd) => serializer.serialize_f64(*sd),
            CalibrationError::PerJoint(values) => values.serialize(serializer),
        }
    }
}

impl<'de> Deserialize<'de> for CalibrationErrorConfig {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        use serde::de::{self, SeqAccess, Visitor};
        struct CalibrationVisitor;
        impl<'de> Visitor<'de> for CalibrationVisitor {
            type Value = CalibrationErrorConfig;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(
                    "a number (the spread each segment's value is drawn from) or a list of one \
                     number per segment",
                )
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Self::Value, E> {
                Ok(CalibrationErrorConfig(CalibrationError::Spread(v)))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
                Ok(CalibrationErrorConfig(CalibrationError::Spread(v as f64)))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
                Ok(CalibrationErrorConfig(CalibrationError::Spread(v as f64)))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut values = Vec::new();
                while let Some(v) = seq.next_element::<f64>()? {
                    values.push(v);
                }
                Ok(CalibrationErrorConfig(CalibrationError::PerJoint(values)))
            }
        }
        deserializer.deserialize_any(CalibrationVisitor)
    }
}

/// What an injected fault does to a simulated segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SimFaultKind {
    /// It stops acknowledging its address (a NACK storm).
    Nack,
    /// Its reads come back with a wrong PEC byte.
    Pec,
    /// Its main loop stops: it answers with its last word, its sample counter stuck.
    Stuck,
    /// The first transfer to it from `from_s` on never returns: the polling thread is stuck
    /// in it for good (`until_s` cannot end it), as behind an I2C driver without a timeout.
    Hang,
}

/// A fault injected into one simulated segment for a while.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SimFaultConfig {
    /// The segment's address (one of `bus.segments`).
    pub address: u8,
    /// `nack`, `pec`, `stuck` or `hang`.
    pub kind: SimFaultKind,
    /// From this many seconds after the daemon started...
    pub from_s: f64,
    /// ...until this many.
    pub until_s: f64,
}

/// A flat wall: a line `distance_m` from the stage's track (at the track's origin), tilted
/// `angle_deg` toward the track as the stage moves forward.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct WallConfig {
    /// Distance from the base track at the track's origin, metres.
    pub distance_m: f64,
    /// Angle between the wall and the track, degrees (positive: the wall comes closer as the
    /// stage moves forward).
    pub angle_deg: f64,
    /// Coulomb friction coefficient of the wall against the antenna.
    pub mu: f64,
    /// Penalty stiffness of the wall, newtons per metre of penetration: the tip-only
    /// stand-in's, before the rig used sim-core's contact solver (which keeps the antenna out
    /// of the wall exactly). Still accepted and sent in `hello`; the physics ignores it.
    pub stiffness_n_per_m: f64,
}

impl Default for WallConfig {
    fn default() -> Self {
        Self {
            distance_m: 0.42,
            angle_deg: 30.0,
            mu: 0.3,
            stiffness_n_per_m: 200.0,
        }
    }
}

/// The simulated antenna: one link per segment after the base link.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct AntennaConfig {
    /// Flexible links; must equal the number of segments on the bus.
    pub links: usize,
    /// Length of every link (the base link too), metres.
    pub link_length_m: f64,
    /// Stiffness profile name (`constant`, `linear`, `slow-exponential`, `fast-exponential`,
    /// `logarithmic`, `slow-reciprocal`, `fast-reciprocal`, `cockroach`).
    pub stiffness_profile: String,
    /// Smallest joint stiffness, N m/rad.
    pub k_min_n_m_per_rad: f64,
    /// Largest joint stiffness, N m/rad.
    pub k_max_n_m_per_rad: f64,
    /// Mounting angle of the base link from the track, degrees (the servo adds to it).
    pub base_angle_deg: f64,
}

impl Default for AntennaConfig {
    fn default() -> Self {
        Self {
            links: 9,
            link_length_m: 0.04,
            stiffness_profile: "linear".to_owned(),
            k_min_n_m_per_rad: 0.01,
            k_max_n_m_per_rad: 0.05,
            base_angle_deg: 30.0,
        }
    }
}

impl AntennaConfig {
    /// The named stiffness profile, or `None` if the name is unknown.
    pub fn profile(&self) -> Option<sim_core::StiffnessProfile> {
        sim_core::StiffnessProfile::NAMED
            .into_iter()
            .find(|p| p.name() == self.stiffness_profile)
    }
}

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

    /// Parses and checks `text`, naming it `path` in errors, and reads the control token
    /// from `server.token_file` or `server.token_env` if one is set.
    pub fn from_toml_str(text: &str, path: &str) -> Result<Self, ConfigError> {
        let mut config: Config = toml::from_str(text).map_err(|e| toml_error(text, path, &e))?;
        config
            .validate()
            .and_then(|()| config.resolve_token())
            .map_err(|(key, message)| {
                let (line, column) = locate_key(text, &key).unzip();
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

    /// The configuration as TOML, without the control token: what a recording keeps. Every
    /// key is written, defaults included, so the file says exactly what was in force (the
    /// command line's overrides too); `Config::from_toml_str` reads it back.
    pub fn to_recorded_toml(&self) -> String {
        let body = toml::to_string(self).unwrap_or_else(|e| format!("# not serializable: {e}\n"));
        format!(
            "# the configuration in force (server.token is never recorded; token_file and \
             token_env name where it came from)\n{body}"
        )
    }

    /// The servo's calibrated range, degrees: from the smaller to the larger of
    /// `servo.angle_a_deg` and `servo.angle_b_deg`. No commanded angle may leave it.
    pub fn servo_range_deg(&self) -> (f64, f64) {
        let (a, b) = (self.servo.angle_a_deg, self.servo.angle_b_deg);
        (a.min(b), a.max(b))
    }

    /// Reads the token from `server.token_file` or `server.token_env`: the failing key and
    /// why (never the token).
    fn resolve_token(&mut self) -> Result<(), (String, String)> {
        let server = &mut self.server;
        if let Some(file) = &server.token_file {
            let text = read_private_file(file)
                .map_err(|message| ("server.token_file".to_owned(), message))?;
            let token = ControlToken::new(text.trim()).map_err(|e| {
                (
                    "server.token_file".to_owned(),
                    format!("{}: {e}", file.display()),
                )
            })?;
            server.token = Some(token);
        } else if let Some(name) = &server.token_env {
            let value = std::env::var(name).map_err(|e| {
                (
                    "server.token_env".to_owned(),
                    format!("environment variable {name}: {e}"),
                )
            })?;
            let token = ControlToken::new(value.trim()).map_err(|e| {
                (
                    "server.token_env".to_owned(),
                    format!("environment variable {name}: {e}"),
                )
            })?;
            server.token = Some(token);
        }
        Ok(())
    }

    /// The simulated segments' sensors as in force: `[sim.sensors]`, with the segment
    /// firmware's touch debounce ([`FIRMWARE_DEBOUNCE_SAMPLES`]) and a sample at every poll
    /// (`sample_rate_hz` = `bus.poll_hz`).
    pub fn sensor_settings(&self) -> SensorSettings {
        let sensors = &self.sim.sensors;
        SensorSettings {
            angle_noise_counts: sensors.angle_noise_counts,
            offset_counts: sensors.offset_counts.0.clone(),
            gain_error: sensors.gain_error.0.clone(),
            touch_threshold_n: sensors.touch_threshold_n,
            touch_debounce_samples: FIRMWARE_DEBOUNCE_SAMPLES,
            sample_rate_hz: Some(self.bus.poll_hz),
            seed: sensors.seed,
            // The daemon reports words; where a hair's touch is placed is the host's estimate.
            hair_tip_points: false,
        }
    }

    /// Checks `[sim.sensors]`: the failing key (dotted) and why.
    fn validate_sensors(&self) -> Result<(), (String, String)> {
        let sensors = &self.sim.sensors;
        let key = |name: &str| format!("sim.sensors.{name}");
        if let Some(samples) = sensors.touch_debounce_samples
            && samples != FIRMWARE_DEBOUNCE_SAMPLES
        {
            return Err((
                key("touch_debounce_samples"),
                format!(
                    "must be {FIRMWARE_DEBOUNCE_SAMPLES} (or left out), got {samples}: the \
                     simulated segments run the segment firmware, which debounces its touch \
                     switches over {FIRMWARE_DEBOUNCE_SAMPLES} consecutive reads"
                ),
            ));
        }
        if let Some(rate_hz) = sensors.sample_rate_hz {
            return Err((
                key("sample_rate_hz"),
                format!(
                    "not taken here (got {rate_hz}): the simulated segments sample once per \
                     poll, so the sample rate is bus.poll_hz (now {} Hz); set that instead",
                    self.bus.poll_hz
                ),
            ));
        }
        let segments = self.bus.segments.len();
        self.sensor_settings()
            .validate(segments)
            .map_err(|e| match e {
                SensorError::OutOfRange {
                    field,
                    value,
                    expected,
                } => {
                    let spread = match (field, expected.starts_with("every")) {
                        (SensorField::Offset | SensorField::Gain, false) => {
                            " (a number is the spread each segment's value is drawn from)"
                        }
                        _ => "",
                    };
                    let message = if expected.starts_with("every") {
                        format!("has {value}; {expected}")
                    } else {
                        format!("{expected}{spread}, got {value}")
                    };
                    (key(field.key()), message)
                }
                SensorError::WrongLength {
                    field,
                    expected,
                    actual,
                } => (
                    key(field.key()),
                    format!(
                        "has {actual} entries; a list needs one per segment on the bus, base \
                         to tip ({expected}), or give a number, the spread each segment's \
                         value is drawn from"
                    ),
                ),
            })
    }

    /// The trial called `name`, or the first one.
    pub fn trial(&self, name: Option<&str>) -> Option<&TrialConfig> {
        match name {
            Some(name) => self.trials.iter().find(|t| t.name == name),
            None => self.trials.first(),
        }
    }

    /// The stage's scale and soft limits.
    pub fn stage_geometry(
        &self,
    ) -> Result<crate::StageGeometry, crate::hardware::stage::GeometryError> {
        crate::StageGeometry::new(
            self.stage.steps_per_mm,
            self.stage.min_mm,
            self.stage.max_mm,
        )
    }

    /// The servo's pulse calibration.
    pub fn pulse_calibration(
        &self,
    ) -> Result<crate::PulseCalibration, crate::hardware::servo::CalibrationError> {
        crate::PulseCalibration::new(
            self.servo.angle_a_deg.to_radians(),
            self.servo.pulse_a_us,
            self.servo.angle_b_deg.to_radians(),
            self.servo.pulse_b_us,
        )
    }

    /// Checks the values serde cannot: the failing key (dotted) and why.
    fn validate(&self) -> Result<(), (String, String)> {
        let fail = |key: &str, message: String| Err((key.to_owned(), message));
        let rate = |v: f64| v.is_finite() && v > 0.0 && v <= 10_000.0;
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let bus = &self.bus;
        if !(bus.is_sim() || bus.device.starts_with("/dev/")) {
            return fail(
                "bus.device",
                format!(
                    "must be \"sim\" or a device such as /dev/i2c-1, got {:?}",
                    bus.device
                ),
            );
        }
        if !rate(bus.poll_hz) {
            return fail(
                "bus.poll_hz",
                format!("must be in (0, 10000], got {}", bus.poll_hz),
            );
        }
        if bus.counter_check_every == 0 {
            return fail("bus.counter_check_every", "must be at least 1".to_owned());
        }
        if let Some(speed_hz) = bus.checked_speed_hz()
            && let Err(why) = crate::hardware::bus_budget::BusBudget::new(
                bus.segments.len(),
                bus.poll_hz,
                speed_hz,
            )
            .check()
        {
            // Named by the key the file gave (the rate when the speed was left out).
            let key = if bus.speed_hz.is_some() {
                "bus.speed_hz"
            } else {
                "bus.poll_hz"
            };
            return fail(key, why);
        }
        if bus.spin_us * 1000 >= (1e9 / bus.poll_hz) as u64 {
            return fail(
                "bus.spin_us",
                "must be shorter than the poll period".to_owned(),
            );
        }
        if bus.realtime_priority > 99 {
            return fail(
                "bus.realtime_priority",
                format!(
                    "must be 0 (normal scheduling) or 1..=99, got {}",
                    bus.realtime_priority
                ),
            );
        }
        if bus.segments.is_empty() {
            return fail("bus.segments", "needs at least one segment".to_owned());
        }
        for (i, segment) in bus.segments.iter().enumerate() {
            if !antenna_protocol::is_assignable_address(segment.address) {
                return fail(
                    &format!("bus.segments[{i}].address"),
                    format!("{:#04x} is outside 0x08..=0x77", segment.address),
                );
            }
            if bus.segments[..i]
                .iter()
                .any(|s| s.address == segment.address)
            {
                return fail(
                    &format!("bus.segments[{i}].address"),
                    format!("{:#04x} is used twice", segment.address),
                );
            }
            if segment.zero_counts > 4095 {
                return fail(
                    &format!("bus.segments[{i}].zero_counts"),
                    format!("must be 0..=4095, got {}", segment.zero_counts),
                );
            }
        }
        if let Err(e) = self.stage_geometry() {
            let key = match e {
                crate::hardware::stage::GeometryError::StepsPerMm(_) => "stage.steps_per_mm",
                crate::hardware::stage::GeometryError::Limits { .. } => "stage.max_mm",
            };
            return fail(key, e.to_string());
        }
        if !positive(self.stage.max_speed_mm_per_s) {
            return fail("stage.max_speed_mm_per_s", "must be positive".to_owned());
        }
        if !rate(self.stage.sample_hz) {
            return fail("stage.sample_hz", "must be in (0, 10000]".to_owned());
        }
        if !(positive(self.stage.homing_speed_mm_per_s)
            && self.stage.homing_speed_mm_per_s <= self.stage.max_speed_mm_per_s)
        {
            return fail(
                "stage.homing_speed_mm_per_s",
                format!(
                    "must be in (0, stage.max_speed_mm_per_s = {}]",
                    self.stage.max_speed_mm_per_s
                ),
            );
        }
        if !(positive(self.stage.homing_timeout_s) && self.stage.homing_timeout_s <= 3600.0) {
            return fail("stage.homing_timeout_s", "must be in (0, 3600]".to_owned());
        }
        if let Err(e) = self.pulse_calibration() {
            return fail("servo.pulse_b_us", e.to_string());
        }
        if !rate(self.servo.sample_hz) {
            return fail("servo.sample_hz", "must be in (0, 10000]".to_owned());
        }
        if self.server.listen.parse::<std::net::SocketAddr>().is_err() {
            return fail(
                "server.listen",
                format!("not an address:port, got {:?}", self.server.listen),
            );
        }
        let sources = [
            ("server.token", self.server.token.is_some()),
            ("server.token_file", self.server.token_file.is_some()),
            ("server.token_env", self.server.token_env.is_some()),
        ];
        let given: Vec<&str> = sources.iter().filter(|s| s.1).map(|s| s.0).collect();
        if given.len() > 1 {
            return fail(
                given[1],
                format!(
                    "the token comes from one place only; {} are both set",
                    given.join(" and ")
                ),
            );
        }
        if self.server.max_clients == 0 {
            return fail("server.max_clients", "must be at least 1".to_owned());
        }
        if !(1..=self.server.max_clients).contains(&self.server.max_clients_per_peer) {
            return fail(
                "server.max_clients_per_peer",
                format!(
                    "must be in 1..=server.max_clients ({}), got {}",
                    self.server.max_clients, self.server.max_clients_per_peer
                ),
            );
        }
        let recording = &self.recording;
        if !(recording.sync_interval_s.is_finite() && recording.sync_interval_s >= 0.0) {
            return fail(
                "recording.sync_interval_s",
                "must be finite and >= 0 (0: only when the trial ends)".to_owned(),
            );
        }
        if !(recording.min_free_mb.is_finite() && recording.min_free_mb >= 0.0) {
            return fail(
                "recording.min_free_mb",
                "must be finite and >= 0".to_owned(),
            );
        }
        let (servo_min_deg, servo_max_deg) = self.servo_range_deg();
        for (i, trial) in self.trials.iter().enumerate() {
            let ok_name = !trial.name.is_empty()
                && trial
                    .name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'));
            if !ok_name {
                return fail(
                    &format!("trials[{i}].name"),
                    format!(
                        "must be letters, digits, '-', '_', '.', got {:?}",
                        trial.name
                    ),
                );
            }
            if !(trial.duration_s.is_finite() && trial.duration_s >= 0.0) {
                return fail(
                    &format!("trials[{i}].duration_s"),
                    "must be finite and >= 0 (0: until the moves end)".to_owned(),
                );
            }
            if !(servo_min_deg..=servo_max_deg).contains(&trial.base_angle_deg) {
                return fail(
                    &format!("trials[{i}].base_angle_deg"),
                    format!(
                        "{} deg is outside the servo's calibrated range {servo_min_deg}..={servo_max_deg} \
                         deg (servo.angle_a_deg, servo.angle_b_deg)",
                        trial.base_angle_deg
                    ),
                );
            }
            for (j, m) in trial.moves.iter().enumerate() {
                if !m.distance_mm.is_finite() {
                    return fail(
                        &format!("trials[{i}].moves[{j}].distance_mm"),
                        "must be finite".to_owned(),
                    );
                }
                if !(positive(m.speed_mm_per_s)
                    && m.speed_mm_per_s <= self.stage.max_speed_mm_per_s)
                {
                    return fail(
                        &format!("trials[{i}].moves[{j}].speed_mm_per_s"),
                        format!(
                            "must be in (0, stage.max_speed_mm_per_s = {}], got {}",
                            self.stage.max_speed_mm_per_s, m.speed_mm_per_s
                        ),
                    );
                }
                if !(m.pause_s.is_finite() && m.pause_s >= 0.0) {
                    return fail(
                        &format!("trials[{i}].moves[{j}].pause_s"),
                        "must be finite and >= 0".to_owned(),
                    );
                }
            }
        }
        let wall = &self.sim.wall;
        if !positive(wall.distance_m) {
            return fail("sim.wall.distance_m", "must be positive".to_owned());
        }
        if !(wall.angle_deg.is_finite() && wall.angle_deg.abs() < 80.0) {
            return fail(
                "sim.wall.angle_deg",
                "must be within (-80, 80) degrees".to_owned(),
            );
        }
        if !(wall.mu.is_finite() && wall.mu >= 0.0) {
            return fail("sim.wall.mu", "must be finite and >= 0".to_owned());
        }
        if !positive(wall.stiffness_n_per_m) {
            return fail("sim.wall.stiffness_n_per_m", "must be positive".to_owned());
        }
        for (i, fault) in self.sim.faults.iter().enumerate() {
            if !bus.segments.iter().any(|s| s.address == fault.address) {
                return fail(
                    &format!("sim.faults[{i}].address"),
                    format!("{:#04x} is not one of bus.segments", fault.address),
                );
            }
            if !(fault.from_s.is_finite()
                && fault.until_s.is_finite()
                && 0.0 <= fault.from_s
                && fault.from_s < fault.until_s)
            {
                return fail(
                    &format!("sim.faults[{i}].until_s"),
                    format!(
                        "needs 0 <= from_s < until_s, got {} and {}",
                        fault.from_s, fault.until_s
                    ),
                );
            }
        }
        let antenna = &self.sim.antenna;
        if bus.is_sim() && antenna.links != bus.segments.len() {
            return fail(
                "sim.antenna.links",
                format!(
                    "must equal the number of segments on the bus ({}), got {}",
                    bus.segments.len(),
                    antenna.links
                ),
            );
        }
        if !positive(antenna.link_length_m) {
            return fail("sim.antenna.link_length_m", "must be positive".to_owned());
        }
        if antenna.profile().is_none() {
            let names: Vec<&str> = sim_core::StiffnessProfile::NAMED
                .iter()
                .map(|p| p.name())
                .collect();
            return fail(
                "sim.antenna.stiffness_profile",
                format!(
                    "unknown profile {:?}; one of {}",
                    antenna.stiffness_profile,
                    names.join(", ")
                ),
            );
        }
        if !(positive(antenna.k_min_n_m_per_rad) && antenna.k_min_n_m_per_rad.is_finite()) {
            return fail(
                "sim.antenna.k_min_n_m_per_rad",
                "must be positive".to_owned(),
            );
        }
        if !(antenna.k_max_n_m_per_rad.is_finite()
            && antenna.k_max_n_m_per_rad >= antenna.k_min_n_m_per_rad)
        {
            return fail(
                "sim.antenna.k_max_n_m_per_rad",
                "must be finite and >= k_min_n_m_per_rad".to_owned(),
            );
        }
        if !antenna.base_angle_deg.is_finite() {
            return fail("sim.antenna.base_angle_deg", "must be finite".to_owned());
        }
        self.validate_sensors()
    }
}

/// The contents of a token file, which must not be readable by its group or others.
fn read_private_file(path: &Path) -> Result<String, String> {
    let metadata =
        std::fs::metadata(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = metadata.permissions().mode() & 0o777;
        if mode & 0o077 != 0 {
            return Err(format!(
                "{}: readable by its group or others (mode {mode:03o}); the token must be \
                 private: chmod 600 {}",
                path.display(),
                path.display()
            ));
        }
    }
    #[cfg(not(unix))]
    let _ = metadata;
    std::fs::read_to_string(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))
}

/// Line and column (1-based) of byte `offset` in `text`.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

/// The dotted table path in force at byte `offset` (`stage`, `bus.segments`; the header
/// itself when `offset` is on one), or empty.
fn table_at(text: &str, offset: usize) -> String {
    let offset = offset.min(text.len());
    let line_end = text[offset..].find('\n').map_or(text.len(), |i| offset + i);
    text[..line_end]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .map(|l| l.trim_matches(|c| c == '[' || c == ']').trim().to_owned())
        .unwrap_or_default()
}

/// The key of the `key = value` line holding byte `offset`.
fn key_at(text: &str, offset: usize) -> Option<String> {
    let offset = offset.min(text.len());
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[offset..].find('\n').map_or(text.len(), |i| offset + i);
    let (key, _) = text[line_start..line_end].split_once('=')?;
    let key = key.trim().trim_matches('"');
    let plain = !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'));
    plain.then(|| key.to_owned())
}

fn dotted(table: &str, key: &str) -> String {
    if table.is_empty() {
        key.to_owned()
    } else {
        format!("{table}.{key}")
    }
}

/// A TOML or serde error as a [`ConfigError`] naming the key, line and column.
fn toml_error(text: &str, path: &str, e: &toml::de::Error) -> ConfigError {
    let offset = e.span().map_or(0, |s| s.start);
    let (line, column) = line_column(text, offset);
    let message = e.message().trim().to_owned();
    let table = table_at(text, offset);
    let key = if let Some(rest) = message.strip_prefix("unknown field `") {
        dotted(&table, rest.split('`').next().unwrap_or_default())
    } else if let Some(rest) = message.strip_prefix("missing field `") {
        dotted(&table, rest.split('`').next().unwrap_or_default())
    } else {
        match key_at(text, offset) {
            Some(key) => dotted(&table, &key),
            None if table.is_empty() => "(top level)".to_owned(),
            None => table,
        }
    };
    ConfigError {
        path: path.to_owned(),
        key,
        line: Some(line),
        column: Some(column),
        message,
    }
}

/// Where the dotted `key` (list indices dropped: `trials[0].moves[1].speed_mm_per_s` looks
/// for `speed_mm_per_s` after the first `[[trials]]`-style header, counting entries) is
/// written in `text`: line and column of the key, or of its table when the key is absent.
fn locate_key(text: &str, key: &str) -> Option<(usize, usize)> {
    let parts: Vec<&str> = key.split('.').collect();
    let (leaf, tables) = parts.split_last()?;
    let leaf_name = leaf.split('[').next().unwrap_or(leaf);
    let table: Vec<&str> = tables
        .iter()
        .map(|t| t.split('[').next().unwrap_or(t))
        .collect();
    let table = table.join(".");
    let index: usize = tables
        .first()
        .and_then(|t| t.split_once('['))
        .and_then(|(_, i)| i.trim_end_matches(']').parse().ok())
        .unwrap_or(0);
    let mut offset = 0;
    let mut in_table = table.is_empty();
    let mut seen = 0usize;
    let mut table_pos = None;
    for line in text.split_inclusive('\n') {
        let trimmed = line.trim();
        if trimmed.starts_with('[') {
            let name = trimmed.trim_matches(|c| c == '[' || c == ']').trim();
            let top = table.split('.').next().unwrap_or_default();
            in_table = name == table || name == top;
            if name == top && trimmed.starts_with("[[") {
                in_table = seen == index;
                seen += 1;
            }
            if in_table && table_pos.is_none() {
                table_pos = Some(offset + line.len() - line.trim_start().len());
            }
        } else if in_table {
            let found = key_at(text, offset + line.find('=').unwrap_or(0))
                .is_some_and(|k| k == leaf_name || k.ends_with(&format!(".{leaf_name}")))
                || line.contains(&format!("{leaf_name} ="))
                || line.contains(&format!("{leaf_name}="));
            if found && !trimmed.starts_with('#') {
                let column = line.find(leaf_name).unwrap_or(0);
                return Some(line_column(text, offset + column));
            }
        }
        offset += line.len();
    }
    table_pos.map(|p| line_column(text, p))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_is_valid_and_simulated() {
        let config = Config::from_toml_str("", "empty.toml").unwrap();
        assert_eq!(config, Config::default());
        assert!(config.bus.is_sim());
        assert_eq!(config.bus.segments.len(), 9);
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
        let config = Config::from_toml_str(&text, "robot.toml").unwrap();
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

    #[test]
    fn key_lines_are_located() {
        let text = "[stage]\nmin_mm = 0\n  max_mm = -1\n";
        assert_eq!(locate_key(text, "stage.max_mm"), Some((3, 3)));
        assert_eq!(line_column("ab\ncd", 4), (2, 2));
    }
}
