//! The closed loop, step by step: sense, estimate, command, integrate the body, carry the
//! antenna along (quasi-static, solved at least every `antenna_step_m` of its base's
//! travel), and judge against the truth.

use nalgebra::Vector2;

use super::body::{BodyState, step_body};
use super::config::{BodyModel, Estimator, FollowConfig, WallSide};
use super::control::{Command, ControlLoop};
use super::estimate::{BendTable, Estimate, NoEstimate, Odometry, bend_coordinate, ideal_preview};
use super::sensed::SensedWall;
use super::summary::{FollowStatus, FollowSummary, SummaryAccumulator};
use super::{FollowError, footprint};
use crate::contact::{Contact, QuasiStatic};
use crate::sensing::sensor::{SensorSettings, Sensors};
use crate::sweep::{BasePose, Motion, Placement, SweepScene, place_at};
use crate::{Line, SolidSide, Wall};

/// The most the body may turn in one step, radians: past it the run ends
/// [`FollowStatus::Unstable`] (a held command, a delay or a stiff gain has made the loop
/// unstable at this step; the antenna is not carried through such a turn).
pub const MAX_TURN_PER_STEP_RAD: f64 = 0.5;

/// One step of a run, in the scene's frame (a right-wall run is mirrored back).
#[derive(Clone, Debug, PartialEq)]
pub struct FollowStep {
    /// The time, seconds.
    pub t_s: f64,
    /// The point of rotation, ground frame, m.
    pub pose_m: Vector2<f64>,
    /// The heading, ground frame, counter-clockwise, radians.
    pub heading_rad: f64,
    /// The turning rate, positive away from the wall, rad/s.
    pub omega_rad_per_s: f64,
    /// What the controller applies over this step.
    pub command: Command,
    /// The moment of the antenna's contact forces about the point of rotation, positive
    /// away from the wall, N m (acting on the body only with `antenna_loads_body`).
    pub antenna_moment_n_m: f64,
    /// The smallest distance from the point of rotation to a wall, m.
    pub wall_distance_m: Option<f64>,
    /// The estimate the controller used (`None`: see `no_estimate`).
    pub estimate: Option<Estimate>,
    /// Why there was none.
    pub no_estimate: Option<NoEstimate>,
    /// The true `d` at the estimate's preview, m.
    pub true_distance_at_preview_m: Option<f64>,
    /// Contacts on the antenna.
    pub contacts: usize,
    /// The sensed touch bits per link (the last sample).
    pub touch: Vec<u8>,
    /// Whether the footprint overlaps a wall.
    pub collided: bool,
    /// The antenna's base pivot, ground frame, m (`None` without an antenna).
    pub base_m: Option<Vector2<f64>>,
    /// The antenna's joint angles, `theta_0` its base angle in the ground frame, radians.
    pub theta_rad: Vec<f64>,
    /// The estimator's points (the contact-line window), ground frame, m.
    pub estimated_points_m: Vec<Vector2<f64>>,
}

/// The antenna on the body: the quasi-static chain, its sensors and their buffers.
struct MountedAntenna {
    sim: QuasiStatic,
    sensors: Sensors,
    reach_m: f64,
    theta: Vec<f64>,
    sensed: Vec<f64>,
    touch: Vec<u8>,
    contacts: Vec<Contact>,
    /// The contact-line or bend estimator, fed by every sample (none for the ideal
    /// preview).
    sensed_wall: Option<SensedWall>,
}

/// A closed-loop run (see the [module documentation](super)).
///
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use nalgebra::Vector2;
/// use sim_core::follow::{Estimator, Follow, FollowConfig};
/// use sim_core::{Line, SolidSide, Wall};
///
/// // The template body with an ideal preview, along a straight wall at y = 0.2 m.
/// let wall = Wall::smooth(Line::new(Vector2::new(0.0, 0.2), 0.0, SolidSide::Left)?);
/// let mut config = FollowConfig::default();
/// config.controller.estimator = Estimator::IdealPreview { preview_m: 0.05 };
/// config.settings.duration_s = 2.0;
/// let mut run = Follow::without_antenna(vec![wall], &config)?;
/// while let Some(step) = run.next_step() {
///     step?;
/// }
/// let summary = run.summary();
/// assert_eq!(summary.status.name(), "ok");
/// # Ok(())
/// # }
/// ```
pub struct Follow {
    config: FollowConfig,
    /// The walls, mirrored for a right-wall run.
    walls: Vec<Wall>,
    mirror: bool,
    antenna: Option<MountedAntenna>,
    control: ControlLoop,
    body: BodyState,
    odometry: Odometry,
    step: usize,
    steps: usize,
    without_estimate_s: f64,
    estimate: Result<Estimate, NoEstimate>,
    in_collision: bool,
    stats: SummaryAccumulator,
    ended: Option<FollowStatus>,
    placement_note: String,
}

impl Follow {
    /// A run of the antenna of `scene` (its chain, walls, placement, contact settings; the
    /// chain's base angle is the mount angle) on the robot of `config`, sensing through
    /// `sensors`.
    ///
    /// # Errors
    /// [`FollowError::Invalid`], [`FollowError::StartsInWall`], [`FollowError::Sensors`],
    /// [`FollowError::Placement`], [`FollowError::Calibration`].
    pub fn new(
        scene: &SweepScene,
        sensors: &SensorSettings,
        config: &FollowConfig,
    ) -> Result<Follow, FollowError> {
        let mut run = Follow::start(scene.walls.clone(), config)?;
        let sensors = Sensors::new(sensors, scene.chain.n())
            .map_err(|e| FollowError::Sensors(e.to_string()))?;
        let (pose, motion) = run.antenna_pose();
        let placed_scene = SweepScene {
            walls: run.walls.clone(),
            motion,
            ..scene.clone()
        };
        let (sim, note, _) = place_at(&placed_scene, &pose).map_err(FollowError::Placement)?;
        run.placement_note = note;
        let layout = sensors.touch_layout();
        let sensed_wall = match config.controller.estimator {
            Estimator::ContactLine { window_s } => Some(SensedWall::contact_line(window_s, layout)),
            Estimator::Bend => Some(SensedWall::bend(calibrate_bend(scene, config)?, layout)),
            Estimator::IdealPreview { .. } => None,
        };
        let links = scene.chain.n() + 1;
        run.antenna = Some(MountedAntenna {
            reach_m: scene.chain.total_length_m(),
            sim,
            sensors,
            theta: vec![0.0; links],
            sensed: vec![0.0; links],
            touch: vec![0; links],
            contacts: Vec::new(),
            sensed_wall,
        });
        Ok(run)
    }

    /// A run of the body alone, with the ideal preview (the check against theory: no
    /// antenna is simulated).
    ///
    /// # Errors
    /// As [`Self::new`]; [`FollowError::Invalid`] for another estimator.
    pub fn without_antenna(walls: Vec<Wall>, config: &FollowConfig) -> Result<Follow, FollowError> {
        if !matches!(config.controller.estimator, Estimator::IdealPreview { .. }) {
            return Err(FollowError::Invalid {
                table: "controller",
                key: "estimator",
                reason: "a run without an antenna needs the ideal preview".to_string(),
            });
        }
        Follow::start(walls, config)
    }

    fn start(walls: Vec<Wall>, config: &FollowConfig) -> Result<Follow, FollowError> {
        config.validate()?;
        let mirror = config.robot.wall_side == WallSide::Right;
        let walls: Vec<Wall> = if mirror {
            walls.iter().map(Wall::mirrored_about_x_axis).collect()
        } else {
            walls
        };
        let s = &config.settings;
        let sign = if mirror { -1.0 } else { 1.0 };
        let body = BodyState {
            por_m: Vector2::new(s.pose_m.x, sign * s.pose_m.y),
            heading_rad: sign * s.heading_rad,
            omega_rad_per_s: 0.0,
        };
        if let Some((wall, depth_m)) = footprint::overlap(
            &walls,
            &body.por_m,
            body.heading_rad,
            config.robot.footprint_m,
        ) {
            return Err(FollowError::StartsInWall { wall, depth_m });
        }
        Ok(Follow {
            config: *config,
            walls,
            mirror,
            antenna: None,
            control: ControlLoop::new(config.controller, config.robot.body, config.delay_steps()),
            body,
            odometry: Odometry::default(),
            step: 0,
            steps: config.steps(),
            without_estimate_s: 0.0,
            estimate: Err(NoEstimate::NoContact),
            in_collision: false,
            stats: SummaryAccumulator::default(),
            ended: None,
            placement_note: String::new(),
        })
    }

    /// What the antenna's placement did, in words (empty without an antenna).
    pub fn placement_note(&self) -> &str {
        &self.placement_note
    }

    /// The bend estimator's calibration table, if it has one.
    pub fn bend_table(&self) -> Option<&BendTable> {
        self.antenna
            .as_ref()
            .and_then(|a| a.sensed_wall.as_ref())
            .and_then(SensedWall::bend_table)
    }

    /// The number of steps the run has (fewer are taken when it ends early).
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The run's description.
    pub fn config(&self) -> &FollowConfig {
        &self.config
    }

    /// The antenna's base pose for the body's state, and the motion whose direction the
    /// placement approaches along (the heading).
    fn antenna_pose(&self) -> (BasePose, Motion) {
        let r = &self.config.robot;
        let (sin, cos) = self.body.heading_rad.sin_cos();
        let m = r.mount_m;
        let base_m = self.body.por_m + Vector2::new(cos * m.x - sin * m.y, sin * m.x + cos * m.y);
        let pose = BasePose {
            base_m,
            base_angle_rad: self.body.heading_rad + r.mount_angle_rad,
        };
        let motion = Motion {
            velocity_m_per_s: Vector2::new(cos, sin) * r.speed_m_per_s,
            duration_s: self.config.settings.duration_s,
            step_s: self.config.settings.step_s,
        };
        (pose, motion)
    }

    /// The figures so far (the whole run's once [`Self::next_step`] returned `None`).
    pub fn summary(&self) -> FollowSummary {
        let status = match &self.ended {
            Some(s) => s.clone(),
            None if self.stats.collisions > 0 => FollowStatus::Collided,
            None => FollowStatus::Ok,
        };
        self.stats.summary(status)
    }

    /// Takes the next step; `None` once the run is over. A solver's refusal ends the run
    /// (its status says so) and is returned once as [`FollowError::Contact`].
    pub fn next_step(&mut self) -> Option<Result<FollowStep, FollowError>> {
        if self.ended.is_some() || self.step >= self.steps {
            return None;
        }
        let h = self.config.settings.step_s;
        let t_s = self.step as f64 * h;
        let v = self.config.robot.speed_m_per_s;
        // Sense and estimate.
        let sampled = match self.sense(t_s) {
            Ok(s) => s,
            Err(e) => return Some(Err(e)),
        };
        let (estimate, fresh) = self.estimate(sampled);
        self.estimate = estimate;
        let command = self.control.command(
            t_s,
            self.estimate.as_ref().ok(),
            fresh,
            self.body.omega_rad_per_s,
        );
        let antenna_moment_n_m = self.antenna_moment_n_m();
        let record = self.record(t_s, command, antenna_moment_n_m);
        let contact = record.contacts > 0;
        // Judge.
        let error_m = record
            .wall_distance_m
            .map(|d| d - self.config.controller.setpoint_m);
        let estimate_error_m = match (&record.estimate, record.true_distance_at_preview_m) {
            (Some(e), Some(d)) => Some(e.distance_m - d),
            _ => None,
        };
        if record.collided && !self.in_collision {
            self.stats.collisions += 1;
            self.stats.first_collision_s.get_or_insert(t_s);
        }
        self.in_collision = record.collided;
        let s = self.config.settings;
        self.stats.add(
            v * t_s,
            s.settling_window_m,
            s.settling_band_m,
            error_m,
            contact,
            record.estimate.is_some(),
            estimate_error_m,
        );
        self.stats.duration_s = t_s + h;
        self.without_estimate_s = if record.estimate.is_some() {
            0.0
        } else {
            self.without_estimate_s + h
        };
        let drifted = record
            .wall_distance_m
            .is_none_or(|d| d > self.config.lost_beyond_m());
        if self.without_estimate_s > s.lost_after_s + 1e-12 || drifted {
            self.ended = Some(FollowStatus::Lost);
            return Some(Ok(record));
        }
        // Act: the body over the step, then the antenna carried along.
        let mut u = command.value();
        if self.config.robot.antenna_loads_body
            && let BodyModel::Template { .. } = self.config.robot.body
        {
            u += antenna_moment_n_m;
        }
        let before = self.body;
        self.body = step_body(&self.config.robot.body, v, &before, u, h);
        self.odometry
            .advance(v, self.body.heading_rad - before.heading_rad, h);
        self.step += 1;
        let turn = (self.body.heading_rad - before.heading_rad).abs();
        if !(turn <= MAX_TURN_PER_STEP_RAD
            && self.body.por_m.iter().all(|x| x.is_finite())
            && self.body.omega_rad_per_s.is_finite())
        {
            self.ended = Some(FollowStatus::Unstable);
            return Some(Ok(record));
        }
        if let Err(e) = self.move_antenna(t_s + h) {
            let status = if self.stats.collisions > 0 {
                FollowStatus::Collided
            } else {
                FollowStatus::from_contact_error(&e)
            };
            self.ended = Some(status);
            return Some(Err(FollowError::Contact {
                t_s: t_s + h,
                source: e,
            }));
        }
        Some(Ok(record))
    }

    /// Reads the sensors if a sample is due: the touch bits and the mapped contact points
    /// (body frame) of this sample; whether one was taken.
    fn sense(&mut self, t_s: f64) -> Result<bool, FollowError> {
        let mount_m = self.config.robot.mount_m;
        let mount_angle = self.config.robot.mount_angle_rad;
        let Some(a) = self.antenna.as_mut() else {
            return Ok(false);
        };
        a.sim.contacts_into(&mut a.contacts);
        if !a.sensors.is_sample_due(t_s) {
            return Ok(false);
        }
        // The sensors see the antenna in its own frame: the base angle is the mount angle,
        // never the body's heading.
        a.theta.copy_from_slice(a.sim.theta_rad());
        a.theta[0] = mount_angle;
        let sensing = |e: crate::MappingError| FollowError::Sensors(e.to_string());
        a.sensors
            .sense_angles_rad(&a.theta, &mut a.sensed)
            .map_err(sensing)?;
        a.sensors
            .sense_touch(&a.contacts, &mut a.touch)
            .map_err(sensing)?;
        if let Some(wall) = &mut a.sensed_wall {
            wall.add_sample(
                t_s,
                &self.odometry,
                a.sim.chain(),
                &mount_m,
                &a.sensed,
                &a.touch,
            )
            .map_err(sensing)?;
        }
        Ok(true)
    }

    /// The estimator's answer at `t_s`, and whether it is fresh (made from a new sample).
    fn estimate(&mut self, sampled: bool) -> (Result<Estimate, NoEstimate>, bool) {
        match self.config.controller.estimator {
            Estimator::IdealPreview { preview_m } => (
                ideal_preview(
                    &self.walls,
                    &self.body.por_m,
                    self.body.heading_rad,
                    preview_m,
                ),
                true,
            ),
            // The contact line moves with the odometry at every step; the bend is the
            // newest sample's.
            Estimator::Bend if !sampled => (self.estimate, false),
            Estimator::ContactLine { .. } | Estimator::Bend => {
                match self.antenna.as_mut().and_then(|a| a.sensed_wall.as_mut()) {
                    Some(wall) => (wall.estimate(&self.odometry), sampled),
                    None => (Err(NoEstimate::NoTouch), true),
                }
            }
        }
    }

    /// The moment of the antenna's contact forces about the point of rotation, positive
    /// away from the wall (clockwise in the run's frame).
    fn antenna_moment_n_m(&self) -> f64 {
        let Some(a) = &self.antenna else {
            return 0.0;
        };
        -a.contacts
            .iter()
            .map(|c| {
                let r = c.point_m - self.body.por_m;
                let f = c.force_n();
                r.x * f.y - r.y * f.x
            })
            .sum::<f64>()
    }

    /// Carries the antenna to the body's pose, in steps of at most `antenna_step_m` of its
    /// base's travel (a turn counts by the antenna's reach times the angle).
    fn move_antenna(&mut self, _t_s: f64) -> Result<(), crate::contact::ContactError> {
        let (goal, _) = self.antenna_pose();
        let step_m = self.config.settings.antenna_step_m;
        let Some(a) = self.antenna.as_mut() else {
            return Ok(());
        };
        let from_m = a.sim.base_m();
        let from_angle = a.sim.theta_rad()[0];
        let d_angle = goal.base_angle_rad - from_angle;
        let travel = (goal.base_m - from_m).norm().max(a.reach_m * d_angle.abs());
        let pieces = (travel / step_m).ceil().max(1.0) as usize;
        for k in 1..=pieces {
            let f = k as f64 / pieces as f64;
            let pose = BasePose {
                base_m: from_m + (goal.base_m - from_m) * f,
                base_angle_rad: from_angle + d_angle * f,
            };
            step_antenna(&mut a.sim, &pose)?;
        }
        Ok(())
    }

    /// The step's record in the scene's frame.
    fn record(&self, t_s: f64, command: Command, antenna_moment_n_m: f64) -> FollowStep {
        let b = &self.body;
        let wall_distance_m = self
            .walls
            .iter()
            .map(|w| w.signed_distance(&b.por_m).gap_m.abs())
            .reduce(f64::min);
        let estimate = self.estimate.ok();
        let true_distance_at_preview_m = estimate.and_then(|e| {
            ideal_preview(&self.walls, &b.por_m, b.heading_rad, e.preview_m)
                .ok()
                .map(|t| t.distance_m)
        });
        let collided = footprint::overlap(
            &self.walls,
            &b.por_m,
            b.heading_rad,
            self.config.robot.footprint_m,
        )
        .is_some();
        let sign = if self.mirror { -1.0 } else { 1.0 };
        let flip = |p: Vector2<f64>| Vector2::new(p.x, sign * p.y);
        let (contacts, touch, base_m, theta_rad) = match &self.antenna {
            Some(a) => (
                a.contacts.len(),
                a.touch.clone(),
                Some(flip(a.sim.base_m())),
                a.sim.theta_rad().iter().map(|t| sign * t).collect(),
            ),
            None => (0, Vec::new(), None, Vec::new()),
        };
        let window_points = self
            .antenna
            .as_ref()
            .and_then(|a| a.sensed_wall.as_ref())
            .map(SensedWall::window_points_m);
        let estimated_points_m = match window_points {
            Some(points) => {
                let (sin, cos) = b.heading_rad.sin_cos();
                points
                    .iter()
                    .map(|p| {
                        flip(b.por_m + Vector2::new(cos * p.x - sin * p.y, sin * p.x + cos * p.y))
                    })
                    .collect()
            }
            None => Vec::new(),
        };
        FollowStep {
            t_s,
            pose_m: flip(b.por_m),
            heading_rad: sign * b.heading_rad,
            omega_rad_per_s: b.omega_rad_per_s,
            command,
            antenna_moment_n_m,
            wall_distance_m,
            estimate,
            no_estimate: self.estimate.err(),
            true_distance_at_preview_m,
            contacts,
            touch,
            collided,
            base_m,
            theta_rad,
            estimated_points_m,
        }
    }
}

/// One solve of the antenna at a base pose: the base moves and turns in one step
/// ([`QuasiStatic::step_to_pose`]), its contacts and hairs carried along.
fn step_antenna(
    sim: &mut QuasiStatic,
    pose: &BasePose,
) -> Result<(), crate::contact::ContactError> {
    sim.step_to_pose(pose.base_m, pose.base_angle_rad)
        .map(|_| ())
}

/// Distances of the calibration's straight walls beyond the mount, as fractions of the
/// antenna's reach.
const CALIBRATION_POINTS: usize = 24;

/// The bend estimator's calibration table for this antenna on this robot: the body
/// parallel to a straight wall (`theta = 0`) at distances from just beyond the mount to
/// nearly the antenna's reach, the antenna placed by the scene's approach or tip-on-wall
/// placement (or a default approach), its continuous point of bend recorded against the
/// distance.
///
/// # Errors
/// [`FollowError::Calibration`] when fewer than two distances give a bend.
pub fn calibrate_bend(scene: &SweepScene, config: &FollowConfig) -> Result<BendTable, FollowError> {
    let r = &config.robot;
    calibrate_bend_at(
        scene,
        &BasePose {
            base_m: r.mount_m,
            base_angle_rad: r.mount_angle_rad,
        },
        r.speed_m_per_s,
    )
}

/// [`calibrate_bend`] for an antenna whose base pivot is at `mount.base_m` in the body frame
/// and whose base link makes `mount.base_angle_rad` with the body's x axis, moving along x at
/// `speed_m_per_s` (the direction the placement approaches along): antennad's stage, for
/// one.
///
/// # Errors
/// [`FollowError::Calibration`] when fewer than two distances give a bend.
pub fn calibrate_bend_at(
    scene: &SweepScene,
    mount: &BasePose,
    speed_m_per_s: f64,
) -> Result<BendTable, FollowError> {
    let reach_m = scene.chain.total_length_m();
    let placement = match &scene.placement {
        Placement::Approach {
            distance_m,
            along_m,
            steps,
            ..
        } => Placement::Approach {
            wall: 0,
            distance_m: *distance_m,
            along_m: *along_m,
            steps: *steps,
        },
        // The tip on each wall as the scene puts it there (antennad's rigs start so).
        Placement::TipOnWall { ahead_m, start, .. } => Placement::TipOnWall {
            wall: 0,
            ahead_m: *ahead_m,
            start: start.clone(),
        },
        _ => Placement::Approach {
            wall: 0,
            distance_m: 0.05,
            along_m: 0.0,
            steps: 100,
        },
    };
    let lo = mount.base_m.y + 0.005;
    let hi = mount.base_m.y + 0.95 * reach_m;
    let mut rows = Vec::new();
    for k in 0..CALIBRATION_POINTS {
        let distance_m = lo + (hi - lo) * k as f64 / (CALIBRATION_POINTS - 1) as f64;
        let Ok(line) = Line::new(Vector2::new(0.0, distance_m), 0.0, SolidSide::Left) else {
            continue;
        };
        let at = SweepScene {
            walls: vec![Wall::new(
                line,
                scene
                    .walls
                    .first()
                    .map(|w| w.surfaces.clone())
                    .unwrap_or_default(),
            )],
            placement: placement.clone(),
            motion: Motion {
                velocity_m_per_s: Vector2::new(speed_m_per_s, 0.0),
                ..Motion::default()
            },
            ..scene.clone()
        };
        let Ok((sim, _, _)) = place_at(&at, mount) else {
            continue;
        };
        if sim.contacts().is_empty() {
            continue;
        }
        if let Some(bend) = bend_coordinate(sim.theta_rad()) {
            rows.push((bend, distance_m));
        }
    }
    let table = BendTable::from_measurements(rows);
    if table.rows.len() < 2 {
        return Err(FollowError::Calibration(format!(
            "fewer than 2 of {CALIBRATION_POINTS} straight walls from {lo:.3} to {hi:.3} m gave \
             the antenna a bend"
        )));
    }
    Ok(table)
}
