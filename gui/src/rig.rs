//! [`RigGeometry`]: the rig as the daemon describes it (the `rig` object of the stream's
//! `hello`, or a recording's metadata): its scene (the antenna, its walls of any shape, hairs,
//! friction, placement), and the conversion of one sample into a [`ChainFrame`] with
//! sim-core's kinematics. Stage position `s` puts the base at the scene's base position plus
//! `s` along its direction of motion; the servo angle adds to its base angle.

use antenna_data::stream::RigInfo;
use antenna_scene::Scene;
use nalgebra::Vector2;
use sim_core::sweep::SweepScene;
use sim_core::{Chain, Frame, Wall, frame_poses};

use crate::error::MonitorError;
use crate::estimate::WallSide;
use crate::frame::{ChainFrame, PointM, SegmentState};
use crate::history::{Health, History};
use crate::sweep::wall_polyline_m;

/// How many samples back a failed segment's last valid angle is looked for.
const HOLD_SAMPLES: usize = 2000;

/// The rig's geometry (see the module documentation).
#[derive(Debug, Clone)]
pub struct RigGeometry {
    /// Every rigid link, the base link first (one more than there are segments), metres.
    pub link_lengths_m: Vec<f64>,
    /// The base link's angle from the track with the servo at 0, radians.
    pub base_mount_angle_rad: f64,
    /// The scene the rig runs (what the prediction is built from), if the source gives one
    /// (`None` for daemons and recordings from before the scene, issue #46).
    pub scene: Option<SweepScene>,
    /// The scene's walls (empty without a scene).
    pub walls: Vec<Wall>,
    /// The stage's soft limits, metres.
    pub stage_range_m: Option<(f64, f64)>,
    /// Polls per second.
    pub poll_hz: f64,
    /// The daemon's `[estimate] wall_side`, when its `hello` says it.
    pub declared_wall_side: Option<WallSide>,
    /// Where this geometry came from, for the status line.
    pub source: String,
    /// The force that closes a touch switch in the prediction, newtons: the scene's
    /// `[sensors] touch_threshold_n`, as the simulated rig's segments apply it (0: any
    /// contact).
    pub touch_threshold_n: f64,
    /// Where the base pivot is with the stage at 0, and the unit direction the stage carries
    /// it along (the scene's; the track's x-axis without one).
    base_start_m: Vector2<f64>,
    direction: Vector2<f64>,
    chain: Chain,
}

impl RigGeometry {
    /// The geometry of a `hello`'s (or a recording's) `rig` object: its scene when it has
    /// one, else (older daemons) the links and the mounting angle only, no walls (so no
    /// prediction).
    ///
    /// # Errors
    /// [`MonitorError::Geometry`] for a scene that does not read (its located error) or
    /// cannot be swept, or links that make no chain.
    pub fn from_rig_info(rig: &RigInfo, source: impl Into<String>) -> Result<Self, MonitorError> {
        let source = source.into();
        let mut geometry = match &rig.scene_toml {
            Some(text) => {
                let name = rig.scene_source.as_deref().unwrap_or("the rig's scene");
                let scene = Scene::parse_in(text, name, std::path::Path::new(""))
                    .map_err(|e| MonitorError::Geometry(e.to_string()))?;
                let sweep = scene
                    .sweep_scene()
                    .map_err(|e| MonitorError::Geometry(e.to_string()))?;
                let mut geometry = Self::from_scene(sweep, source);
                geometry.touch_threshold_n = scene.sensors.touch_threshold_n;
                geometry
            }
            None => {
                if rig.link_lengths_m.is_empty() {
                    return Err(MonitorError::Geometry(
                        "`link_lengths_m` is empty; it needs the base link".to_owned(),
                    ));
                }
                Self::with_links(
                    rig.link_lengths_m.clone(),
                    rig.base_mount_angle_deg.to_radians(),
                    source,
                )?
            }
        };
        geometry.stage_range_m = Some((rig.stage_min_m, rig.stage_max_m));
        geometry.poll_hz = rig.poll_hz;
        geometry.declared_wall_side = match rig.estimate_wall_side.as_deref() {
            Some("left") => Some(WallSide::Left),
            Some("right") => Some(WallSide::Right),
            _ => None,
        };
        Ok(geometry)
    }

    /// The geometry of a sweep scene: its chain, walls, base start and direction of motion.
    pub fn from_scene(scene: SweepScene, source: impl Into<String>) -> Self {
        let v = scene.motion.velocity_m_per_s;
        let direction = if v == Vector2::zeros() || !v.iter().all(|c| c.is_finite()) {
            Vector2::new(1.0, 0.0)
        } else {
            v.normalize()
        };
        Self {
            link_lengths_m: scene.chain.link_lengths_m().to_vec(),
            base_mount_angle_rad: scene.chain.base_angle_rad(),
            walls: scene.walls.clone(),
            stage_range_m: None,
            poll_hz: 1000.0,
            declared_wall_side: None,
            source: source.into(),
            touch_threshold_n: 0.0,
            base_start_m: scene.base_start_m,
            direction,
            chain: scene.chain.clone(),
            scene: Some(scene),
        }
    }

    /// A stand-in when the daemon sends no geometry: `segments` links of 40 mm on a 40 mm base
    /// link along the track, no wall, no scene (so no prediction).
    ///
    /// # Errors
    /// [`MonitorError::Geometry`] for no segments at all that make no chain.
    pub fn fallback(segments: usize) -> Result<Self, MonitorError> {
        Self::with_links(
            vec![0.04; segments + 1],
            0.0,
            "no geometry from the source: assumed 40 mm links, no wall",
        )
    }

    /// A bare geometry: links and mounting angle, nothing else.
    ///
    /// # Errors
    /// [`MonitorError::Geometry`] for links that make no chain.
    pub fn with_links(
        link_lengths_m: Vec<f64>,
        base_mount_angle_rad: f64,
        source: impl Into<String>,
    ) -> Result<Self, MonitorError> {
        let segments = link_lengths_m.len().checked_sub(1).ok_or_else(|| {
            MonitorError::Geometry("no links: the base link is needed".to_owned())
        })?;
        let chain = Chain::builder(segments)
            .link_lengths_m(link_lengths_m.clone())
            .build()
            .map_err(|e| MonitorError::Geometry(e.to_string()))?;
        Ok(Self {
            link_lengths_m,
            base_mount_angle_rad,
            scene: None,
            walls: Vec::new(),
            stage_range_m: None,
            poll_hz: 1000.0,
            declared_wall_side: None,
            source: source.into(),
            touch_threshold_n: 0.0,
            base_start_m: Vector2::zeros(),
            direction: Vector2::new(1.0, 0.0),
            chain,
        })
    }

    /// The base pivot for the stage at `stage_position_m` (0 when unknown).
    pub fn base_m(&self, stage_position_m: Option<f64>) -> PointM {
        let p = self.base_start_m + self.direction * stage_position_m.unwrap_or(0.0);
        [p.x, p.y]
    }

    /// The unit direction the stage carries the base pivot along (the estimate's x axis).
    pub fn travel_direction(&self) -> [f64; 2] {
        [self.direction.x, self.direction.y]
    }

    /// Which side of the stage's travel the wall is on (the estimate's y axis): antennad's
    /// `[estimate] wall_side` as its `hello` says it; from a daemon that does not say, the
    /// side of the scene's nearest wall to the base pivot (the stage in the middle of its
    /// range), left without a wall.
    pub fn wall_side(&self) -> WallSide {
        if let Some(side) = self.declared_wall_side {
            return side;
        }
        let middle = self.stage_range_m.map(|(lo, hi)| (lo + hi) / 2.0);
        let base = self.base_m(middle);
        let base = Vector2::new(base[0], base[1]);
        let nearest = self
            .walls
            .iter()
            .map(|w| w.signed_distance(&base))
            .filter(|p| p.gap_m.is_finite())
            .min_by(|a, b| a.gap_m.abs().total_cmp(&b.gap_m.abs()));
        let Some(point) = nearest else {
            return WallSide::Left;
        };
        let to_wall = point.closest_m - base;
        let cross = self.direction.x * to_wall.y - self.direction.y * to_wall.x;
        if cross < 0.0 {
            WallSide::Right
        } else {
            WallSide::Left
        }
    }

    /// Segments (flexible joints).
    pub fn segment_count(&self) -> usize {
        self.chain.n()
    }

    /// The antenna's length from the base attachment to the tip when straight, metres.
    pub fn total_length_m(&self) -> f64 {
        self.chain.total_length_m()
    }

    /// The frame of a posture: joint angles (one per segment), the segments' states, the
    /// stage position and the servo angle (the base angle is the mounting angle plus it).
    pub fn frame(
        &self,
        t_s: f64,
        joint_angles_rad: &[f64],
        segments: Vec<SegmentState>,
        stage_position_m: Option<f64>,
        servo_angle_rad: Option<f64>,
    ) -> Result<ChainFrame, MonitorError> {
        let n = self.segment_count();
        if joint_angles_rad.len() != n || segments.len() != n {
            return Err(MonitorError::Geometry(format!(
                "{} angles and {} segment states for a chain of {n} segments",
                joint_angles_rad.len(),
                segments.len()
            )));
        }
        let base_angle_rad = self.base_mount_angle_rad + servo_angle_rad.unwrap_or(0.0);
        let base_m = self.base_m(stage_position_m);
        let mut theta = Vec::with_capacity(n + 1);
        theta.push(base_angle_rad);
        theta.extend_from_slice(joint_angles_rad);
        let poses = frame_poses(&self.chain, &theta, Frame::GROUND)
            .map_err(|e| MonitorError::Geometry(e.to_string()))?;
        let joints_m: Vec<PointM> = (-1..=n as isize)
            .map(|i| {
                let p = poses.position_m(Frame::new(i)).unwrap_or_default();
                [base_m[0] + p[0], base_m[1] + p[1]]
            })
            .collect();
        let reach = self.total_length_m();
        let track = self.stage_range_m.map_or(0.0, |(lo, hi)| (hi - lo).abs());
        let walls_m = self
            .walls
            .iter()
            .map(|w| wall_polyline_m(w, base_m, 1.5 * reach + track))
            .collect();
        Ok(ChainFrame {
            t_s,
            joints_m,
            segments,
            hairs: Vec::new(),
            walls_m,
            contacts_m: Vec::new(),
            base_m,
            stage_position_m,
            base_angle_rad,
            stage_range_m: self.stage_range_m,
            ..ChainFrame::default()
        })
    }

    /// The frame of the sample at `index` of `history`. A segment whose read failed is drawn
    /// at its last valid angle (or 0 if none is recent) and marked unhealthy.
    pub fn frame_at(&self, history: &History, index: usize) -> Result<ChainFrame, MonitorError> {
        let t_s = history
            .t_s(index)
            .ok_or_else(|| MonitorError::Geometry(format!("no sample at index {index}")))?;
        let n = history.segment_count();
        let mut angles = Vec::with_capacity(n);
        let mut states = Vec::with_capacity(n);
        for k in 0..n {
            let (touch_bits, health) = history
                .touch_and_health(index, k)
                .unwrap_or((0, Health::Bus));
            let current = history.angle_rad(index, k);
            angles.push(current.unwrap_or_else(|| {
                history
                    .last_valid_angle_rad(index, k, HOLD_SAMPLES)
                    .unwrap_or(0.0)
            }));
            states.push(SegmentState {
                touch_bits,
                health,
                angle_current: current.is_some(),
            });
        }
        let sample = history.sample(index);
        let stage = sample.as_ref().and_then(|s| s.stage_position_m);
        let servo = sample.as_ref().and_then(|s| s.servo_angle_rad);
        self.frame(t_s, &angles, states, stage, servo)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The geometry antennad's default configuration sends in `hello`.
    pub(crate) fn default_rig() -> RigGeometry {
        let config = host_daemon::service::config::Config::default();
        RigGeometry::from_rig_info(&host_daemon::service::daemon::rig_info(&config), "test")
            .unwrap()
    }

    #[test]
    fn the_default_rig_is_its_scene_and_the_chain_starts_at_the_stage() {
        let rig = default_rig();
        assert_eq!(rig.segment_count(), 8);
        assert_eq!(rig.walls.len(), 1);
        assert!(rig.scene.is_some());
        let frame = rig
            .frame(
                0.0,
                &[0.0; 8],
                vec![SegmentState::QUIET; 8],
                Some(0.1),
                Some(0.0),
            )
            .unwrap();
        assert_eq!(frame.joints_m.len(), 10);
        assert_eq!(frame.base_m, [0.1, 0.0]);
        let tip = frame.tip_m().unwrap();
        let a = 30f64.to_radians();
        assert!((tip[0] - (0.1 + 0.36 * a.cos())).abs() < 1e-12);
        assert!((tip[1] - 0.36 * a.sin()).abs() < 1e-12);
        // The wall polyline lies on the wall, the base in front of it.
        for p in &frame.walls_m[0] {
            let d = rig.walls[0].signed_distance(&Vector2::new(p[0], p[1]));
            assert!(d.gap_m.abs() < 1e-12);
        }
        assert!(rig.walls[0].signed_distance(&Vector2::new(0.1, 0.0)).gap_m > 0.0);
    }

    /// The default rig's wall is on the left of the stage's travel (its y > 0), as its
    /// daemon says; from a daemon that does not say, the scene's: the same scene travelling
    /// the other way has it on the right. What the daemon says wins.
    #[test]
    fn the_wall_side_is_the_daemons_or_else_the_scenes() {
        let rig = default_rig();
        assert_eq!(rig.travel_direction(), [1.0, 0.0]);
        assert_eq!(rig.declared_wall_side, Some(WallSide::Left));
        assert_eq!(rig.wall_side(), WallSide::Left);
        let mut reversed = rig.clone();
        reversed.direction = -reversed.direction;
        reversed.declared_wall_side = None;
        assert_eq!(reversed.wall_side(), WallSide::Right);
        reversed.declared_wall_side = Some(WallSide::Left);
        assert_eq!(reversed.wall_side(), WallSide::Left);
        let bare = RigGeometry::fallback(3).unwrap();
        assert_eq!(bare.wall_side(), WallSide::Left);
    }

    /// A `hello` from before the scene (issue #46) still gives the chain to draw, no walls.
    #[test]
    fn an_old_hello_gives_the_links_only() {
        let old = r#"{"poll_hz":1000.0,"link_lengths_m":[0.04,0.04,0.04,0.04],"base_mount_angle_deg":30.0,"stiffness_profile":"linear","k_min_n_m_per_rad":0.01,"k_max_n_m_per_rad":0.05,"stiffness_n_m_per_rad":[0.05,0.03,0.01],"wall":{"distance_m":0.42,"angle_deg":30.0,"stiffness_n_per_m":200.0},"stage_min_m":0.0,"stage_max_m":0.3}"#;
        let info: RigInfo = serde_json::from_str(old).unwrap();
        let rig = RigGeometry::from_rig_info(&info, "old").unwrap();
        assert_eq!(rig.segment_count(), 3);
        assert!(rig.walls.is_empty() && rig.scene.is_none());
        assert_eq!(rig.stage_range_m, Some((0.0, 0.3)));
        assert_eq!(rig.base_m(Some(0.2)), [0.2, 0.0]);
    }

    /// A scene that does not read is said with its located error.
    #[test]
    fn a_scene_that_does_not_read_is_named() {
        let info = RigInfo {
            poll_hz: 1000.0,
            stage_min_m: 0.0,
            stage_max_m: 0.3,
            scene_toml: Some("[antenna]\nlinks = 9\nfoo = 1\n".to_owned()),
            scene_source: Some("rig.toml".to_owned()),
            link_lengths_m: Vec::new(),
            base_mount_angle_deg: 0.0,
            estimate_wall_side: None,
        };
        let error = RigGeometry::from_rig_info(&info, "hello")
            .unwrap_err()
            .to_string();
        assert!(error.contains("rig.toml:3:1: unknown key `foo`"), "{error}");
    }
}
