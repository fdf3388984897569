//! `[sim] scene`: the scene file the simulated rig runs (`docs/scene-format.md`, read through
//! `antenna-scene`, as `antenna sweep` reads it), and what the rig makes of it.
//!
//! The mapping from a scene to the rig:
//!
//! - the bus has one segment per flexible joint: the scene's `links - 1` (the scene's
//!   `links` counts the base link; 4.2.1's `links = 9` is 8 segments); a different number of
//!   `[[bus.segments]]` is an error (on hardware too: there the scene is the model the
//!   monitor predicts the measured chain with);
//! - stage position `s` puts the base pivot at the scene's `[base] position_m` plus `s` along
//!   the scene's direction of motion (`[sweep] velocity_m_per_s`, its direction only);
//! - the servo turns the base link: its angle is the scene's `base_angle_deg` plus the servo
//!   angle;
//! - the moves are the configuration's `[[trials]]`: the scene's `[sweep]` `duration_s` and
//!   `step_s` are the `antenna sweep` command's and the rig ignores them (said once at start);
//! - the scene's `[start]` placement is applied when a trial starts, after homing, with the
//!   stage and servo where they are (simulated rig only: a stage cannot hold a tip on a wall);
//! - the scene's `[sensors]` are the simulated segments' sensors (noise, calibration, touch
//!   threshold, seed), sampled once per poll through the segment firmware's own oversampling
//!   and debounce: a `sample_rate_hz` or `touch_debounce_samples` the rig cannot apply is
//!   ignored with a warning;
//! - a scene with `[tip_pin]` is refused (the base moves; a pin would hold the tip).
//!
//! The scene's text goes to clients in the stream's `hello` and into every recording
//! ([`RigScene::text`]), each wall's `points_file` written into the wall as its
//! `vertices_m`, so a client rebuilds the same physics without the file.

use antenna_scene::Scene;
use sim_core::FIRMWARE_DEBOUNCE_SAMPLES;
use sim_core::sweep::SweepScene;
use std::path::Path;

/// The built-in scene: the thesis's 4.2.1 rig (`host-daemon/config/wall_following_4_2_1.toml`).
pub const BUILT_IN_SCENE: &str = include_str!("../../config/wall_following_4_2_1.toml");

/// How the built-in scene is named in messages.
pub const BUILT_IN_SCENE_NAME: &str = "wall_following_4_2_1.toml (built in)";

/// The scene the simulated rig runs, as read.
#[derive(Debug, Clone, PartialEq)]
pub struct RigScene {
    /// Where it came from: the file as resolved, or [`BUILT_IN_SCENE_NAME`].
    pub source: String,
    /// The scene's text, with every wall's `points_file` written in as `vertices_m`.
    pub text: String,
    /// The scene.
    pub scene: Scene,
    /// Whether the scene's `[sensors]` gives `sample_rate_hz`, and
    /// `touch_debounce_samples` (which the rig cannot apply).
    sensor_keys_given: (bool, bool),
    /// Whether the scene's `[sweep]` gives `duration_s` or `step_s`.
    sweep_timing_given: bool,
}

impl Default for RigScene {
    fn default() -> Self {
        Self::built_in()
    }
}

impl RigScene {
    /// The built-in scene ([`BUILT_IN_SCENE`]).
    pub fn built_in() -> Self {
        #[allow(clippy::expect_used)]
        Self::from_text(BUILT_IN_SCENE, BUILT_IN_SCENE_NAME, Path::new(""))
            .expect("the built-in scene is valid (tested)")
    }

    /// Reads the scene file at `path` (its points files relative to its folder).
    ///
    /// # Errors
    /// What is wrong, in words: the file cannot be read, or the scene's located error
    /// (file:line:column, key, table).
    pub fn read(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read the scene file {}: {e}", path.display()))?;
        let folder = path.parent().unwrap_or_else(|| Path::new(""));
        Self::from_text(&text, &path.display().to_string(), folder)
    }

    /// The scene of `text`, named `source` in errors, its points files read from `folder`.
    ///
    /// # Errors
    /// The scene's located error, or a scene the rig cannot run (`[tip_pin]`).
    pub fn from_text(text: &str, source: &str, folder: &Path) -> Result<Self, String> {
        let scene = Scene::parse_in(text, source, folder).map_err(|e| e.to_string())?;
        scene.sweep_scene().map_err(|e| {
            format!("{e} (the simulated rig moves the base along the scene's direction of motion)")
        })?;
        let raw: toml::Table = toml::from_str(text).map_err(|e| e.to_string())?;
        let table_has = |table: &str, key: &str| {
            raw.get(table)
                .and_then(toml::Value::as_table)
                .is_some_and(|t| t.contains_key(key))
        };
        let sensor_keys_given = (
            table_has("sensors", "sample_rate_hz"),
            table_has("sensors", "touch_debounce_samples")
                && scene.sensors.touch_debounce_samples != FIRMWARE_DEBOUNCE_SAMPLES,
        );
        let sweep_timing_given = table_has("sweep", "duration_s") || table_has("sweep", "step_s");
        Ok(Self {
            source: source.to_owned(),
            text: inline_points_files(text, folder)?,
            scene,
            sensor_keys_given,
            sweep_timing_given,
        })
    }

    /// The scene as sim-core's sweep scene (what the physics is built from).
    ///
    /// # Errors
    /// Never for a scene that [`Self::from_text`] accepted (it checked this).
    pub fn sweep_scene(&self) -> Result<SweepScene, antenna_scene::SceneError> {
        self.scene.sweep_scene()
    }

    /// The flexible joints, one bus segment each: the scene's `links - 1`.
    pub fn joints(&self) -> usize {
        self.scene.chain.n()
    }

    /// What the rig ignores of the scene, in words, for the log at start (`poll_hz`: the
    /// rate the segments are sampled at). Each is a warning but the `[sweep]` note.
    pub fn ignored(&self, poll_hz: f64) -> Vec<(bool, String)> {
        let mut said = Vec::new();
        if self.sensor_keys_given.0 {
            said.push((
                true,
                format!(
                    "the scene's [sensors] sample_rate_hz ({}) is ignored: the simulated segments \
                     are sampled once per poll, at bus.poll_hz ({poll_hz} Hz)",
                    self.source
                ),
            ));
        }
        if self.sensor_keys_given.1 {
            said.push((
                true,
                format!(
                    "the scene's [sensors] touch_debounce_samples = {} ({}) is ignored: the \
                     segment firmware debounces its touch switches over \
                     {FIRMWARE_DEBOUNCE_SAMPLES} reads",
                    self.scene.sensors.touch_debounce_samples, self.source
                ),
            ));
        }
        if self.sweep_timing_given {
            said.push((
                false,
                format!(
                    "the scene's [sweep] ({}) gives the rig its direction of motion only; the \
                     trials' moves say how far and how fast the stage goes",
                    self.source
                ),
            ));
        }
        said
    }
}

/// `text` with every `[[walls]]` entry's `points_file` replaced by `vertices_m`, the points
/// read from the file (relative to `folder`), so that the text needs no other file.
fn inline_points_files(text: &str, folder: &Path) -> Result<String, String> {
    let mut document: toml_edit::DocumentMut = text.parse().map_err(|e| format!("{e}"))?;
    let Some(walls) = document
        .get_mut("walls")
        .and_then(toml_edit::Item::as_array_of_tables_mut)
    else {
        return Ok(text.to_owned());
    };
    let mut changed = false;
    for wall in walls.iter_mut() {
        let Some(file) = wall.get("points_file").and_then(toml_edit::Item::as_str) else {
            continue;
        };
        let path = folder.join(file);
        let points_text = std::fs::read_to_string(&path)
            .map_err(|e| format!("cannot read the points file {}: {e}", path.display()))?;
        let points = antenna_scene::points_file::parse_points(&points_text)
            .map_err(|(line, why)| format!("the points file {}:{line}: {why}", path.display()))?;
        let mut vertices = toml_edit::Array::new();
        for p in &points.points_m {
            let mut vertex = toml_edit::Array::new();
            vertex.push(p.x);
            vertex.push(p.y);
            vertices.push(vertex);
        }
        wall.remove("points_file");
        wall.insert("vertices_m", toml_edit::value(vertices));
        changed = true;
    }
    Ok(if changed {
        document.to_string()
    } else {
        text.to_owned()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_built_in_scene_is_the_thesis_4_2_1_rig() {
        let rig = RigScene::built_in();
        assert_eq!(rig.joints(), 8);
        assert_eq!(rig.scene.walls.len(), 1);
        assert!(rig.ignored(1000.0).is_empty());
        // The same physics as the example `antenna sweep` runs, [sweep]'s timing aside.
        let example = Scene::from_path(Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../examples/wall_following_4_2_1.toml"
        )))
        .unwrap();
        assert_eq!(example.chain, rig.scene.chain);
        assert_eq!(example.walls, rig.scene.walls);
        assert_eq!(example.placement, rig.scene.placement);
        assert_eq!(
            example.motion.velocity_m_per_s,
            rig.scene.motion.velocity_m_per_s
        );
    }

    #[test]
    fn a_points_file_is_written_into_the_text() {
        let dir = std::env::temp_dir().join(format!("rig-scene-points-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("wall.csv"),
            "x_m,y_m\n-0.5,0.2\n0.1,0.2125\n0.9,0.2\n",
        )
        .unwrap();
        let text = BUILT_IN_SCENE.replace(
            "shape = \"line\"\npoint_m = [0.0, 0.2]",
            "shape = \"polyline\"\npoints_file = \"wall.csv\"",
        );
        let text = text.replace("angle_deg = -8.0", "");
        let file = dir.join("scene.toml");
        std::fs::write(&file, &text).unwrap();
        let rig = RigScene::read(&file).unwrap();
        assert!(!rig.text.contains("points_file"), "{}", rig.text);
        assert!(rig.text.contains("vertices_m"), "{}", rig.text);
        // Read back from nowhere, the text is the same scene.
        let back = Scene::parse_in(&rig.text, "inlined", Path::new("/nonexistent")).unwrap();
        assert_eq!(back.walls, rig.scene.walls);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
