//! The configuration's schema: every table and key, its default, and what the rest of the
//! daemon reads from it.

use super::geometry::{
    CalibrationError as PulseCalibrationError, GeometryError, PulseCalibration, StageGeometry,
};
use super::scene::RigScene;
use super::token::ControlToken;
use antenna_data::record::{ChunkCompression, RecorderOptions};
use serde::{Deserialize, Serialize};
use sim_core::{FIRMWARE_DEBOUNCE_SAMPLES, SensorSettings};
use std::collections::BTreeMap;
use std::path::PathBuf;

pub use super::geometry::HomingDirection;

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
    /// The live wall estimate.
    pub estimate: EstimateConfig,
    /// The Foxglove WebSocket server.
    pub foxglove: FoxgloveConfig,
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
            estimate: EstimateConfig::default(),
            foxglove: FoxgloveConfig::default(),
        }
    }
}

/// The `[bus]` table: antenna-bus's, which `antenna segments` reads too (the device, the
/// poll rate, the bus clock, the counter checks, the scheduling and the segments, base to
/// tip; the built-in rig's 8 simulated segments by default).
pub use antenna_bus::config::{BusConfig, DirectionName, SegmentConfig};

impl Config {
    /// Whether any hardware is configured (the bus, the stage or the servo is not `sim`):
    /// then no trial starts by itself.
    pub fn has_hardware(&self) -> bool {
        !self.bus.is_sim() || self.stage.port != "sim" || self.servo.port != "sim"
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

impl Default for StageConfig {
    fn default() -> Self {
        Self {
            port: "sim".to_owned(),
            baud: 9600,
            reply_timeout_ms: 2000,
            steps_per_mm: 80.0,
            min_mm: 0.0,
            max_mm: 600.0,
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
    /// The built-in rig's trial: the thesis's 4.2.1 sweep, the base carried 500 mm along the
    /// wall at 25 mm/s (the wall closes in by 70 mm: the point of bend moves toward the base),
    /// a pause, and back at 50 mm/s.
    fn default() -> Self {
        Self {
            name: "wall-sweep".to_owned(),
            base_angle_deg: 0.0,
            duration_s: 32.0,
            moves: vec![
                MoveConfig {
                    distance_mm: 500.0,
                    speed_mm_per_s: 25.0,
                    pause_s: 1.0,
                },
                MoveConfig {
                    distance_mm: -500.0,
                    speed_mm_per_s: 50.0,
                    pause_s: 0.0,
                },
            ],
            metadata: BTreeMap::from([
                (
                    "wall".to_owned(),
                    "thesis 4.2.1: smooth wall at 8 deg, mu 0.3".to_owned(),
                ),
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

/// The simulated rig (used when the bus is `sim`): the scene it runs and the faults injected
/// into its segments. The scene's mapping onto the rig is [`super::scene`]'s.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct SimConfig {
    /// `scene`: the scene file the simulated rig runs (`docs/scene-format.md`), relative to
    /// the configuration file's directory; left out, the built-in scene
    /// ([`super::scene::BUILT_IN_SCENE`], the thesis's 4.2.1 rig). Resolved when read: the
    /// path here is the file's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scene: Option<PathBuf>,
    /// Faults to inject into simulated segments (none by default), to see and test how the
    /// daemon copes.
    pub faults: Vec<SimFaultConfig>,
    /// `[sim.antenna]`, gone: refused, naming the scene's `[antenna]` that replaces it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub antenna: Option<toml::Value>,
    /// `[sim.wall]`, gone: refused, naming the scene's `[[walls]]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wall: Option<toml::Value>,
    /// `[sim.sensors]`, gone: refused, naming the scene's `[sensors]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sensors: Option<toml::Value>,
    /// The scene as read (the built-in one until [`Config::from_toml_str`] reads `scene`).
    #[serde(skip)]
    pub rig: RigScene,
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

impl Config {
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

    /// The simulated segments' sensors as in force: the scene's `[sensors]` (noise,
    /// calibration offsets and gain errors, touch threshold, seed), with the segment
    /// firmware's touch debounce ([`FIRMWARE_DEBOUNCE_SAMPLES`]) and a sample at every poll
    /// (`sample_rate_hz` = `bus.poll_hz`).
    pub fn sensor_settings(&self) -> SensorSettings {
        SensorSettings {
            touch_debounce_samples: FIRMWARE_DEBOUNCE_SAMPLES,
            sample_rate_hz: Some(self.bus.poll_hz),
            // The daemon reports words; where a hair's touch is placed is the host's estimate.
            hair_tip_points: false,
            ..self.sim.rig.scene.sensors.clone()
        }
    }

    /// The trial called `name`, or the first one.
    pub fn trial(&self, name: Option<&str>) -> Option<&TrialConfig> {
        match name {
            Some(name) => self.trials.iter().find(|t| t.name == name),
            None => self.trials.first(),
        }
    }

    /// The stage's scale and soft limits.
    pub fn stage_geometry(&self) -> Result<StageGeometry, GeometryError> {
        StageGeometry::new(
            self.stage.steps_per_mm,
            self.stage.min_mm,
            self.stage.max_mm,
        )
    }

    /// The servo's pulse calibration.
    pub fn pulse_calibration(&self) -> Result<PulseCalibration, PulseCalibrationError> {
        PulseCalibration::new(
            self.servo.angle_a_deg.to_radians(),
            self.servo.pulse_a_us,
            self.servo.angle_b_deg.to_radians(),
            self.servo.pulse_b_us,
        )
    }
}

/// The `[estimate]` table: the live wall estimate antennad makes from the calibrated joint
/// angles and touch bits with `antenna follow`'s estimators (`sim_core::follow`), in the
/// carriage frame: origin at the base pivot, x along the stage's travel, y toward the wall.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct EstimateConfig {
    /// `"contact-line"` (default: the mapped contact points of the last `window_s` carried by
    /// the stage's odometry, a line fitted through them: distance and angle), `"bend"` (the
    /// point of bend through a calibration table that antennad builds from the scene when it
    /// starts: distance only), `"ideal-preview"` (the simulated rig's true wall along the
    /// carriage's normal at the base pivot: the check, refused with hardware) or `"none"`.
    pub estimator: EstimatorName,
    /// The contact-line estimator's window, seconds (default 0.5).
    pub window_s: f64,
    /// Estimates per second (default 100), at most `bus.poll_hz`; every poll feeds the
    /// window, an estimate is made from the newest poll when one is due.
    pub rate_hz: f64,
    /// Which side of the stage's travel the wall is on: `"left"` (default) or `"right"`.
    pub wall_side: WallSideName,
}

impl Default for EstimateConfig {
    fn default() -> Self {
        Self {
            estimator: EstimatorName::ContactLine,
            window_s: 0.5,
            rate_hz: 100.0,
            wall_side: WallSideName::Left,
        }
    }
}

/// An estimator's name in `[estimate] estimator`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum EstimatorName {
    /// The contact-line estimator.
    ContactLine,
    /// The bend estimator.
    Bend,
    /// The true wall (simulated rig only).
    IdealPreview,
    /// No estimate.
    None,
}

impl EstimatorName {
    /// As written in the file.
    pub fn name(self) -> &'static str {
        match self {
            EstimatorName::ContactLine => "contact-line",
            EstimatorName::Bend => "bend",
            EstimatorName::IdealPreview => "ideal-preview",
            EstimatorName::None => "none",
        }
    }
}

/// The wall's side of the stage's travel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum WallSideName {
    /// Left of the direction of travel (counter-clockwise from it).
    Left,
    /// Right of it.
    Right,
}

/// The `[foxglove]` table: a Foxglove WebSocket server (view-only: no client publishing, no
/// services; control stays on the token-protected `[server]` port).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct FoxgloveConfig {
    /// Whether the server runs. Left out: on for the simulated rig, off when any hardware is
    /// configured ([`Config::foxglove_enabled`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub enabled: Option<bool>,
    /// Address and port to listen on (default `127.0.0.1:8765`); loopback unless you mean
    /// otherwise: anyone who reaches it sees the antenna.
    pub listen: String,
    /// A port that cannot be bound stops antennad from starting (default `true`); `false`:
    /// a warning and no Foxglove.
    pub required: bool,
    /// The 3D channels' rate (transforms and scene), per second (default 50), at most
    /// `bus.poll_hz`.
    pub scene_hz: f64,
}

impl Default for FoxgloveConfig {
    fn default() -> Self {
        Self {
            enabled: None,
            listen: "127.0.0.1:8765".to_owned(),
            required: true,
            scene_hz: 50.0,
        }
    }
}

impl Config {
    /// Whether the Foxglove server runs: `[foxglove] enabled`, or left out, whether the rig
    /// is all simulated.
    pub fn foxglove_enabled(&self) -> bool {
        self.foxglove.enabled.unwrap_or(!self.has_hardware())
    }
}
