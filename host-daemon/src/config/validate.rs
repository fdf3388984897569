//! What serde cannot check: ranges, the pieces that must fit one another (the bus budget, the
//! stage's geometry, the servo's calibration, the scene's joints and `[sensors]` against the
//! bus), the old `[sim.*]` tables that a scene replaces, and where the control token comes
//! from. Each failure is the dotted key and why; [`super::locate`] finds
//! where the key is written.

use super::Config;
use super::bus_budget::BusBudget;
use super::geometry::GeometryError;
use super::scene::RigScene;
use super::token::ControlToken;
use antenna_bus::config::SegmentsError;
use sim_core::{SensorError, SensorField};
use std::path::Path;

impl Config {
    /// Checks the values serde cannot: the failing key (dotted) and why.
    pub(super) fn validate(&self) -> Result<(), (String, String)> {
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
            && let Err(why) = BusBudget::new(bus.segments.len(), bus.poll_hz, speed_hz).check()
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
        if let Err(e) = bus.check_segments() {
            let key = match e {
                SegmentsError::Address { index, .. } | SegmentsError::Duplicate { index, .. } => {
                    format!("bus.segments[{index}].address")
                }
                SegmentsError::ZeroCounts { index, .. } => {
                    format!("bus.segments[{index}].zero_counts")
                }
            };
            let message = e.to_string();
            let message = message
                .split_once(": ")
                .map_or(message.as_str(), |(_, why)| why)
                .to_owned();
            return fail(&key, message);
        }
        if let Err(e) = self.stage_geometry() {
            let key = match e {
                GeometryError::StepsPerMm(_) => "stage.steps_per_mm",
                GeometryError::Limits { .. } => "stage.max_mm",
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
        self.validate_estimate_and_foxglove()?;
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
        let joints = self.sim.rig.joints();
        if joints != bus.segments.len() {
            return fail(
                "bus.segments",
                format!(
                    "the rig has one segment per flexible joint of its scene: {} has \
                     links = {} (the base link and {joints} flexible joints), so {joints} \
                     [[bus.segments]] are needed, not {}",
                    self.sim.rig.source,
                    joints + 1,
                    bus.segments.len()
                ),
            );
        }
        self.validate_sensors()
    }

    /// `[estimate]` and `[foxglove]`: ranges against the poll rate, the ideal preview on the
    /// simulated rig only, the listen address.
    fn validate_estimate_and_foxglove(&self) -> Result<(), (String, String)> {
        let fail = |key: &str, message: String| Err((key.to_owned(), message));
        let poll_hz = self.bus.poll_hz;
        let estimate = &self.estimate;
        if !(estimate.window_s.is_finite() && estimate.window_s > 0.0 && estimate.window_s <= 60.0)
        {
            return fail(
                "estimate.window_s",
                format!("must be in (0, 60] seconds, got {}", estimate.window_s),
            );
        }
        if !(estimate.rate_hz.is_finite() && estimate.rate_hz > 0.0 && estimate.rate_hz <= poll_hz)
        {
            return fail(
                "estimate.rate_hz",
                format!(
                    "must be in (0, bus.poll_hz = {poll_hz}], got {}",
                    estimate.rate_hz
                ),
            );
        }
        if estimate.estimator == super::EstimatorName::IdealPreview && self.has_hardware() {
            return fail(
                "estimate.estimator",
                "\"ideal-preview\" reads the simulated rig's true wall: only with the bus, the \
                 stage and the servo all \"sim\""
                    .to_owned(),
            );
        }
        let foxglove = &self.foxglove;
        if foxglove.listen.parse::<std::net::SocketAddr>().is_err() {
            return fail(
                "foxglove.listen",
                format!("not an address:port, got {:?}", foxglove.listen),
            );
        }
        if !(foxglove.scene_hz.is_finite()
            && foxglove.scene_hz > 0.0
            && foxglove.scene_hz <= poll_hz)
        {
            return fail(
                "foxglove.scene_hz",
                format!(
                    "must be in (0, bus.poll_hz = {poll_hz}], got {}",
                    foxglove.scene_hz
                ),
            );
        }
        Ok(())
    }

    /// Reads the token from `server.token_file` or `server.token_env`: the failing key and
    /// why (never the token).
    pub(super) fn resolve_token(&mut self) -> Result<(), (String, String)> {
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

    /// `[sim.antenna]`, `[sim.wall]` and `[sim.sensors]` are gone: the first one given and
    /// what replaces it.
    pub(super) fn refuse_old_sim_keys(&self) -> Result<(), (String, String)> {
        let sim = &self.sim;
        for (table, value, replaced_by) in [
            (
                "antenna",
                &sim.antenna,
                "the scene's [antenna] and [antenna.stiffness] (its `links` counts the base \
                 link: one more than the segments; `min_n_m_per_rad`, `max_n_m_per_rad`, \
                 `profile`)",
            ),
            (
                "wall",
                &sim.wall,
                "the scene's [[walls]] (a line, polyline, sinusoid or digitized wall, with its \
                 `mu` and zones)",
            ),
            (
                "sensors",
                &sim.sensors,
                "the scene's [sensors] (the same keys; `sample_rate_hz` and the debounce are \
                 the rig's own)",
            ),
        ] {
            if value.is_none() {
                continue;
            }
            return Err((
                format!("sim.{table}"),
                format!(
                    "[sim.{table}] is gone: the simulated rig runs a scene file, \
                     `[sim] scene = \"FILE.toml\"` (relative to this file), and {replaced_by} \
                     replace it"
                ),
            ));
        }
        Ok(())
    }

    /// Reads the scene of `[sim] scene` (relative to `folder`), keeping the resolved path.
    pub(super) fn read_scene(&mut self, folder: &Path) -> Result<(), (String, String)> {
        let Some(file) = &self.sim.scene else {
            return Ok(());
        };
        let path = folder.join(file);
        self.sim.rig =
            RigScene::read(&path).map_err(|message| ("sim.scene".to_owned(), message))?;
        self.sim.scene = Some(path);
        Ok(())
    }

    /// Checks the scene's `[sensors]` against the bus: the failing key (dotted) and why.
    fn validate_sensors(&self) -> Result<(), (String, String)> {
        let key = |name: &str| {
            (
                "sim.scene".to_owned(),
                format!("{}: [sensors] {name}", self.sim.rig.source),
            )
        };
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
                    let (k, at) = key(field.key());
                    (k, format!("{at} {message}"))
                }
                SensorError::WrongLength {
                    field,
                    expected,
                    actual,
                } => {
                    let (k, at) = key(field.key());
                    (
                        k,
                        format!(
                            "{at} has {actual} entries; a list needs one per segment on the \
                             bus, base to tip ({expected}), or give a number, the spread each \
                             segment's value is drawn from"
                        ),
                    )
                }
            })
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
