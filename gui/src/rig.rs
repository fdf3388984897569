//! [`RigGeometry`]: the antenna and the wall as the daemon describes them (the `rig` object
//! of the stream's `hello`, or a recording's configuration), and the conversion of one
//! sample into a [`ChainFrame`] with sim-core's kinematics.

use antenna_data::stream::RigInfo;
use sim_core::{Chain, Frame, frame_poses};

use crate::error::MonitorError;
use crate::frame::{ChainFrame, PointM, SegmentState};
use crate::history::{Health, History};

/// How many samples back a failed segment's last valid angle is looked for.
const HOLD_SAMPLES: usize = 2000;

/// A flat wall beside the track (see `docs/stream-protocol.md`, `rig.wall`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallLine {
    /// Distance from the track at its origin, metres.
    pub distance_m: f64,
    /// Angle to the track, radians (positive: closer as the stage moves forward).
    pub angle_rad: f64,
    /// Penalty stiffness of the simulated contact, N/m.
    pub stiffness_n_per_m: f64,
}

impl WallLine {
    /// Unit normal into the wall.
    fn normal(&self) -> PointM {
        let (s, c) = self.angle_rad.sin_cos();
        [s, c]
    }

    /// Signed distance of `p` into the wall, metres (negative: in front of it).
    pub fn penetration_m(&self, p: PointM) -> f64 {
        let n = self.normal();
        p[0] * n[0] + (p[1] - self.distance_m) * n[1]
    }

    /// The wall as a two-point polyline centred on the foot of the perpendicular from
    /// `near_m`, `half_length_m` to either side.
    pub fn polyline_m(&self, near_m: PointM, half_length_m: f64) -> Vec<PointM> {
        let n = self.normal();
        let along = [n[1], -n[0]];
        let origin = [0.0, self.distance_m];
        let s = (near_m[0] - origin[0]) * along[0] + (near_m[1] - origin[1]) * along[1];
        [s - half_length_m, s + half_length_m]
            .iter()
            .map(|t| [origin[0] + t * along[0], origin[1] + t * along[1]])
            .collect()
    }
}

/// The joint stiffness model the prediction uses.
#[derive(Debug, Clone, PartialEq)]
pub struct StiffnessModel {
    /// A profile name of sim-core (`linear`, `fast-exponential`, ...).
    pub profile: String,
    /// The profile's smallest stiffness, N m/rad.
    pub k_min_n_m_per_rad: f64,
    /// The profile's largest stiffness, N m/rad.
    pub k_max_n_m_per_rad: f64,
    /// Per joint, base to tip, N m/rad (empty if unknown).
    pub values_n_m_per_rad: Vec<f64>,
}

/// The rig's geometry (see the module documentation).
#[derive(Debug, Clone)]
pub struct RigGeometry {
    /// Every rigid link, the base link first (one more than there are segments), metres.
    pub link_lengths_m: Vec<f64>,
    /// The base link's angle from the track with the servo at 0, radians.
    pub base_mount_angle_rad: f64,
    /// The wall, if known.
    pub wall: Option<WallLine>,
    /// The joint stiffnesses, if known (needed for a prediction).
    pub stiffness: Option<StiffnessModel>,
    /// The stage's soft limits, metres.
    pub stage_range_m: Option<(f64, f64)>,
    /// Polls per second.
    pub poll_hz: f64,
    /// Where this geometry came from, for the status line.
    pub source: String,
    chain: Chain,
}

impl RigGeometry {
    /// The geometry of a `hello`'s `rig` object.
    pub fn from_rig_info(rig: &RigInfo, source: impl Into<String>) -> Result<Self, MonitorError> {
        let segments = rig.link_lengths_m.len().checked_sub(1).ok_or_else(|| {
            MonitorError::Geometry("`link_lengths_m` is empty; it needs the base link".to_owned())
        })?;
        let mut geometry = Self::with_links(
            rig.link_lengths_m.clone(),
            rig.base_mount_angle_deg.to_radians(),
            source,
        )?;
        geometry.wall = Some(WallLine {
            distance_m: rig.wall.distance_m,
            angle_rad: rig.wall.angle_deg.to_radians(),
            stiffness_n_per_m: rig.wall.stiffness_n_per_m,
        });
        geometry.stiffness = Some(StiffnessModel {
            profile: rig.stiffness_profile.clone(),
            k_min_n_m_per_rad: rig.k_min_n_m_per_rad,
            k_max_n_m_per_rad: rig.k_max_n_m_per_rad,
            values_n_m_per_rad: rig.stiffness_n_m_per_rad.clone(),
        });
        if !rig.stiffness_n_m_per_rad.is_empty() && rig.stiffness_n_m_per_rad.len() != segments {
            return Err(MonitorError::Geometry(format!(
                "{} stiffness values for {segments} segments",
                rig.stiffness_n_m_per_rad.len()
            )));
        }
        geometry.stage_range_m = Some((rig.stage_min_m, rig.stage_max_m));
        geometry.poll_hz = rig.poll_hz;
        Ok(geometry)
    }

    /// A stand-in when the daemon sends no geometry: `segments` links of 40 mm on a 40 mm base
    /// link along the track, no wall, no stiffness (so no prediction).
    pub fn fallback(segments: usize) -> Result<Self, MonitorError> {
        Self::with_links(
            vec![0.04; segments + 1],
            0.0,
            "no geometry from the source: assumed 40 mm links, no wall",
        )
    }

    /// A bare geometry: links and mounting angle, nothing else.
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
            wall: None,
            stiffness: None,
            stage_range_m: None,
            poll_hz: 1000.0,
            source: source.into(),
            chain,
        })
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
        let base_m = [stage_position_m.unwrap_or(0.0), 0.0];
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
        let walls_m = self
            .wall
            .iter()
            .map(|w| {
                let reach = self.total_length_m();
                let track = self.stage_range_m.map_or(0.0, |(lo, hi)| (hi - lo).abs());
                w.polyline_m(base_m, 1.5 * reach + track)
            })
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
    fn straight_chain_along_the_mounting_angle() {
        let rig = default_rig();
        assert_eq!(rig.segment_count(), 9);
        let frame = rig
            .frame(
                0.0,
                &[0.0; 9],
                vec![SegmentState::QUIET; 9],
                Some(0.1),
                Some(0.0),
            )
            .unwrap();
        assert_eq!(frame.joints_m.len(), 11);
        assert_eq!(frame.base_m, [0.1, 0.0]);
        let tip = frame.tip_m().unwrap();
        let a = 30f64.to_radians();
        assert!((tip[0] - (0.1 + 0.4 * a.cos())).abs() < 1e-12);
        assert!((tip[1] - 0.4 * a.sin()).abs() < 1e-12);
        // The wall polyline lies on the wall.
        let wall = rig.wall.unwrap();
        for p in &frame.walls_m[0] {
            assert!(wall.penetration_m(*p).abs() < 1e-12);
        }
        assert!(wall.penetration_m([0.1, 0.0]) < 0.0);
    }
}
