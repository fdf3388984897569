//! A simulated sweep (sim-core's quasi-static sweep, [`sim_core::sweep`]) as chain frames,
//! ready for the chain panel and the same playback as a recording.
//!
//! [`frame_from_step`] turns one [`SweepStep`] into a [`ChainFrame`]: joint positions from
//! sim-core's kinematics shifted to the step's base, the step's touch bits per segment, its
//! contact points, the hair tips, and every wall drawn as a polyline around the antenna
//! ([`wall_polyline_m`]), with the base's straight path from its start to its end
//! ([`base_path_m`], in any direction: the stage along x is one case of it).
//! [`run_sweep`] runs a whole [`SweepScene`] into frames at once;
//! the monitor runs a scene file's sweep on a worker thread instead
//! ([`crate::sweep_run::SweepWorker`]), step by step, with these frames drawn at the cursor.

use nalgebra::Vector2;
use sim_core::sweep::{Sweep, SweepScene, SweepStep};
use sim_core::{Chain, Frame, Wall, WallShape, frame_poses, hair_poses};

use crate::error::MonitorError;
use crate::frame::{ChainFrame, HairDrawing, PointM, SegmentState};
use crate::history::Health;

/// A sweep's frames, one per step (the placed posture first).
#[derive(Debug, Clone, PartialEq)]
pub struct SweepFrames {
    /// The frames, in time order.
    pub frames: Vec<ChainFrame>,
    /// What the placement did (sim-core's note).
    pub placement_note: String,
}

impl SweepFrames {
    /// The frame showing instant `t_s`: the last one at or before it (the first if all are
    /// later).
    pub fn frame_at(&self, t_s: f64) -> Option<&ChainFrame> {
        let after = self.frames.partition_point(|f| f.t_s <= t_s);
        self.frames.get(after.saturating_sub(1))
    }
}

/// The stage track a sweep's base runs along, `(min, max)` x in metres: the base starting
/// on the x axis and moving along it, as on the rig's stage. `None` for any other motion
/// (the chain panel then draws no track).
pub fn track_m(scene: &SweepScene) -> Option<(f64, f64)> {
    let start_m = scene.base_start_m;
    let velocity = scene.motion.velocity_m_per_s;
    if start_m.y != 0.0 || velocity.y != 0.0 {
        return None;
    }
    let end_x_m = start_m.x + velocity.x * scene.motion.duration_s;
    (start_m.x.is_finite() && end_x_m.is_finite())
        .then(|| (start_m.x.min(end_x_m), start_m.x.max(end_x_m)))
}

/// The straight path a sweep's base takes, from its start to its planned end, ground frame,
/// metres (in any direction; empty when not finite).
pub fn base_path_m(scene: &SweepScene) -> Vec<PointM> {
    let start_m = scene.base_start_m;
    let end_m = start_m + scene.motion.velocity_m_per_s * scene.motion.duration_s;
    if start_m.iter().chain(end_m.iter()).all(|v| v.is_finite()) {
        vec![[start_m.x, start_m.y], [end_m.x, end_m.y]]
    } else {
        Vec::new()
    }
}

/// Runs `scene` to the end (at most `max_steps` steps after the placement) and returns its
/// frames.
pub fn run_sweep(scene: SweepScene, max_steps: usize) -> Result<SweepFrames, MonitorError> {
    let chain = scene.chain.clone();
    let walls = scene.walls.clone();
    let track = track_m(&scene);
    let path_m = base_path_m(&scene);
    let mut sweep = Sweep::new(scene).map_err(|e| MonitorError::Sweep(e.to_string()))?;
    let mut frames = Vec::new();
    let with_path = |mut frame: ChainFrame| {
        frame.path_m.clone_from(&path_m);
        frame
    };
    if let Some(placed) = sweep.placed() {
        frames.push(with_path(frame_from_step(&chain, &walls, track, placed)?));
    }
    while frames.len() <= max_steps {
        match sweep.next_step() {
            Some(Ok(step)) => {
                frames.push(with_path(frame_from_step(&chain, &walls, track, &step)?));
            }
            Some(Err(e)) => {
                return Err(MonitorError::Sweep(format!(
                    "after {} steps: {e}",
                    frames.len()
                )));
            }
            None => break,
        }
    }
    Ok(SweepFrames {
        frames,
        placement_note: sweep.placement_note().to_owned(),
    })
}

/// One step of a sweep of `chain` among `walls` as a frame; `track_m` is the base's track
/// ([`track_m`]), drawn as the stage's range, with the walls drawn along all of it.
pub fn frame_from_step(
    chain: &Chain,
    walls: &[Wall],
    track_m: Option<(f64, f64)>,
    step: &SweepStep,
) -> Result<ChainFrame, MonitorError> {
    let kinematics = |e: sim_core::KinematicsError| MonitorError::Sweep(e.to_string());
    let poses = frame_poses(chain, &step.theta_rad, Frame::GROUND).map_err(kinematics)?;
    let base = step.base_m;
    let at = |p: Vector2<f64>| [base.x + p.x, base.y + p.y];
    let n = chain.n();
    let joints_m: Vec<PointM> = (-1..=n as isize)
        .map(|i| at(poses.position_m(Frame::new(i)).unwrap_or_default()))
        .collect();
    let segments = (1..=n)
        .map(|link| SegmentState {
            touch_bits: step.touch_bits.get(link).copied().unwrap_or(0),
            health: Health::Ok,
            angle_current: true,
        })
        .collect();
    let hairs = if chain.hairs().iter().any(Option::is_some) {
        hair_poses(chain, &step.theta_rad, &step.hair_angles_rad, Frame::GROUND)
            .map_err(kinematics)?
            .iter()
            .map(|h| HairDrawing {
                link: h.link,
                root_m: at(h.pivot_m),
                tip_m: at(h.tip_m),
            })
            .collect()
    } else {
        Vec::new()
    };
    let track_length_m = track_m.map_or(0.0, |(lo, hi)| hi - lo);
    let reach = chain.total_length_m() * 1.5 + track_length_m;
    let base_m = [base.x, base.y];
    Ok(ChainFrame {
        t_s: step.t_s,
        walls_m: walls
            .iter()
            .map(|w| wall_polyline_m(w, base_m, reach))
            .collect(),
        contacts_m: step
            .contacts
            .iter()
            .map(|c| [c.point_m.x, c.point_m.y])
            .collect(),
        joints_m,
        segments,
        hairs,
        base_m,
        stage_position_m: Some(base.x),
        base_angle_rad: step.theta_rad.first().copied().unwrap_or(0.0),
        stage_range_m: track_m,
        ..ChainFrame::default()
    })
}

/// `wall` as a polyline for drawing: the part within about `half_length_m` of `near_m`
/// (a line's two end points, a polyline's vertices with its end rays, a sinusoid sampled 24
/// times per wavelength).
pub fn wall_polyline_m(wall: &Wall, near_m: PointM, half_length_m: f64) -> Vec<PointM> {
    let near = Vector2::new(near_m[0], near_m[1]);
    let to_point = |p: Vector2<f64>| [p.x, p.y];
    match &wall.shape {
        WallShape::Line(line) => {
            let d = Vector2::new(line.angle_rad().cos(), line.angle_rad().sin());
            let s = (near - line.point_m()).dot(&d);
            [s - half_length_m, s + half_length_m]
                .iter()
                .map(|t| to_point(line.point_m() + d * *t))
                .collect()
        }
        WallShape::Polyline(polyline) => {
            let v = polyline.vertices_m();
            let mut points: Vec<PointM> = v.iter().map(|p| to_point(*p)).collect();
            if let [a, b, ..] = v {
                let dir = (a - b).try_normalize(0.0).unwrap_or_default();
                points.insert(0, to_point(a + dir * half_length_m));
            }
            if let [.., a, b] = v {
                let dir = (b - a).try_normalize(0.0).unwrap_or_default();
                points.push(to_point(b + dir * half_length_m));
            }
            points
        }
        WallShape::Sinusoid(sinusoid) => {
            let d = Vector2::new(
                sinusoid.direction_rad().cos(),
                sinusoid.direction_rad().sin(),
            );
            let centre = (near - sinusoid.baseline_point_m()).dot(&d);
            let step = (sinusoid.wavelength_m() / 24.0).max(half_length_m / 2000.0);
            let count = (2.0 * half_length_m / step).ceil() as usize;
            (0..=count)
                .map(|k| to_point(sinusoid.point_at_m(centre - half_length_m + k as f64 * step)))
                .collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim_core::sweep::{Motion, Placement};
    use sim_core::{InitialGuess, Line, SolidSide};

    /// sim-core's own example sweep: the tip placed on a wall 8 degrees to the track, the
    /// base moving along it for 0.2 s.
    fn scene() -> (SweepScene, Wall) {
        let chain = Chain::builder(8)
            .link_length_m(0.04)
            .base_angle_rad(30f64.to_radians())
            .stiffness_nm_per_rad(0.01)
            .build()
            .unwrap();
        let wall = Wall::smooth(
            Line::new(Vector2::new(0.0, 0.2), -8f64.to_radians(), SolidSide::Left).unwrap(),
        );
        let scene = SweepScene {
            placement: Placement::TipOnWall {
                wall: 0,
                ahead_m: 0.05,
                start: InitialGuess::C,
            },
            motion: Motion {
                velocity_m_per_s: Vector2::new(0.0167, 0.0),
                duration_s: 0.2,
                step_s: 0.01,
            },
            ..SweepScene::new(chain, vec![wall.clone()])
        };
        (scene, wall)
    }

    #[test]
    fn a_sweep_becomes_frames_with_the_base_moving_and_the_tip_on_the_wall() {
        let (scene, wall) = scene();
        let frames = run_sweep(scene, 1000).unwrap();
        assert_eq!(frames.frames.len(), 21, "{}", frames.placement_note);
        let (first, last) = (&frames.frames[0], &frames.frames[20]);
        assert_eq!(first.joints_m.len(), 10);
        assert!((last.t_s - 0.2).abs() < 1e-9);
        assert!((last.base_m[0] - first.base_m[0] - 0.2 * 0.0167).abs() < 1e-9);
        // Frames are in the ground frame: the tip is on the wall, some segment touches it.
        for frame in &frames.frames {
            let tip = frame.tip_m().unwrap();
            let d = wall.signed_distance(&Vector2::new(tip[0], tip[1])).gap_m;
            assert!(d.abs() < 2e-3, "tip {d} m from the wall at {} s", frame.t_s);
            assert!(frame.segments.iter().any(SegmentState::touched));
            assert!(
                !frame.contacts_m.is_empty(),
                "no contact at {} s",
                frame.t_s
            );
            // Every switch lit is one a contact closed: within an eighth of its 40 mm link of
            // a contact point (switch i covers the quarter [i/4, (i+1)/4) of the link).
            let lit = frame.lit_switches();
            assert!(!lit.is_empty(), "no switch lit at {} s", frame.t_s);
            for l in &lit {
                let nearest_m = frame
                    .contacts_m
                    .iter()
                    .map(|c| (c[0] - l.point_m[0]).hypot(c[1] - l.point_m[1]))
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    nearest_m <= 0.005 + 1e-6,
                    "{l:?}: {nearest_m} m at {} s",
                    frame.t_s
                );
            }
            assert_eq!(frame.stage_range_m, Some((0.0, 0.2 * 0.0167)));
            assert_eq!(frame.path_m.len(), 2);
            assert!((frame.path_m[1][0] - 0.2 * 0.0167).abs() < 1e-12);
            for p in &frame.walls_m[0] {
                let d = wall.signed_distance(&Vector2::new(p[0], p[1])).gap_m;
                assert!(d.abs() < 1e-9);
            }
        }
        assert_eq!(frames.frame_at(0.105).unwrap().t_s, frames.frames[10].t_s);
        assert_eq!(frames.frame_at(-1.0).unwrap().t_s, first.t_s);
        let limited = run_sweep(self::scene().0, 5).unwrap();
        assert_eq!(limited.frames.len(), 6);
    }

    /// A base moving in any direction draws its track: the stage along x is one case.
    #[test]
    fn a_base_moving_across_the_track_has_its_path() {
        let (mut scene, _) = scene();
        scene.base_start_m = Vector2::new(0.01, -0.02);
        scene.motion.velocity_m_per_s = Vector2::new(0.0167, 0.01);
        assert_eq!(track_m(&scene), None);
        let path = base_path_m(&scene);
        assert_eq!(path.len(), 2);
        assert_eq!(path[0], [0.01, -0.02]);
        assert!((path[1][0] - (0.01 + 0.0167 * 0.2)).abs() < 1e-15);
        assert!((path[1][1] - (-0.02 + 0.01 * 0.2)).abs() < 1e-15);
        let frames = run_sweep(scene, 3).unwrap();
        for frame in &frames.frames {
            assert_eq!(frame.path_m, path);
            let (min, max) = frame.bounds_m();
            assert!(min[1] <= -0.02 && max[1] >= -0.018, "{min:?} {max:?}");
        }
    }
}
