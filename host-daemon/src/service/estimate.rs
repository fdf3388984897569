//! The live wall estimate (`[estimate]`, stream message `estimate`): `antenna follow`'s
//! estimators ([`sim_core::follow::SensedWall`], the one implementation) run on every poll's
//! calibrated joint angles and touch bits, where they meet the stage and servo readings (the
//! hub's `on_poll`).
//!
//! # Frame
//! The carriage frame: origin at the base pivot, x along the stage's travel (the scene's
//! direction of motion), y toward the wall (left of x with `wall_side = "left"`, right of it
//! with `"right"`: the right-hand case is solved as the mirror image). The antenna's base link
//! makes the scene's base angle (less the direction of travel) plus the servo's angle with x.
//! Odometry is the measured stage position along x; the carriage does not turn.
//!
//! # Estimators
//! - `contact-line`: every poll's touched switches mapped to points (the scene's chain and
//!   `[sensors]` hair layout), kept for `window_s` and carried by the stage's position; a
//!   line fitted through them: distance and angle.
//! - `bend`: the point of bend of the newest poll through a calibration table that antennad
//!   builds **when it starts**, from the scene's antenna (the simulated rig's scene, or on
//!   hardware the scene that models the antenna): 24 straight walls parallel to the travel,
//!   the antenna placed against each with the servo at 0 (`calibrate_bend_at`); distance
//!   only. A servo turned away from 0 bends the antenna differently from the table.
//! - `ideal-preview`: the simulated rig's true wall along y from the base pivot (the check;
//!   refused with hardware).
//!
//! An estimate is made at `rate_hz` from the newest poll (every poll feeds the window); on
//! the simulated rig each carries the true wall at its preview from the pose the physics was
//! solved at for that poll.

use crate::config::{Config, EstimatorName, WallSideName};
use antenna_data::stream::{EstimateMessage, SegmentSample};
use nalgebra::Vector2;
use sim_core::follow::estimate::{Estimate, NoEstimate, Odometry};
use sim_core::follow::{SensedWall, calibrate_bend_at};
use sim_core::sweep::{BasePose, SweepScene};
use sim_core::walls::first_ray_hit;
use sim_core::{Chain, TouchLayout, Wall};

/// How far the truth's ray looks for a wall, m.
const TRUTH_RANGE_M: f64 = 10.0;

/// Half the spacing of the two rays that give the true wall's angle, m.
const TRUTH_ANGLE_HALF_SPAN_M: f64 = 1e-3;

/// One poll as the estimate reads it.
#[derive(Clone, Copy, Debug)]
pub struct PollInput<'a> {
    /// The poll's number.
    pub seq: u64,
    /// Its time on the daemon's clock, ns.
    pub t_ns: u64,
    /// Each segment's reading as streamed, base to tip: its calibrated joint angle and touch
    /// bits (`None`: the read failed).
    pub segments: &'a [SegmentSample],
    /// The stage's measured position, m (`None`: no stage, or not known yet).
    pub stage_m: Option<f64>,
    /// The servo's measured angle, rad (`None`: no servo).
    pub servo_rad: Option<f64>,
    /// The simulated rig only: the stage position and base pose the physics was solved at
    /// for this poll.
    pub solved_at: Option<(f64, BasePose)>,
}

/// The estimator with its state.
enum Method {
    Sensed(SensedWall),
    IdealPreview,
}

/// The true walls (simulated rig).
struct Truth {
    walls: Vec<Wall>,
    /// The unit direction of travel, scene frame.
    travel: Vector2<f64>,
}

/// The live estimate (see the [module documentation](self)).
pub struct LiveEstimate {
    method: Method,
    name: &'static str,
    chain: Chain,
    /// The base link's angle to the travel with the servo at 0, rad (unmirrored).
    mount_angle_rad: f64,
    /// +1 with the wall on the left, -1 on the right.
    sign: f64,
    period_ns: u64,
    next_due_ns: u64,
    theta: Vec<f64>,
    touch: Vec<u8>,
    stage_m: f64,
    truth: Option<Truth>,
    /// Polls fed to the estimator, and polls skipped (a failed read, a refused sample).
    fed: u64,
    skipped: u64,
}

impl std::fmt::Debug for LiveEstimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LiveEstimate")
            .field("estimator", &self.name)
            .field("fed", &self.fed)
            .field("skipped", &self.skipped)
            .finish_non_exhaustive()
    }
}

impl LiveEstimate {
    /// The estimate `config` asks for (`None` with `estimator = "none"`).
    ///
    /// # Errors
    /// The key and why: the scene cannot be built, or the bend estimator's calibration finds
    /// no bend.
    pub fn from_config(config: &Config) -> Result<Option<LiveEstimate>, (String, String)> {
        let e = &config.estimate;
        let key = || "estimate.estimator".to_owned();
        let scene = config
            .sim
            .rig
            .sweep_scene()
            .map_err(|why| (key(), format!("the scene {}: {why}", config.sim.rig.source)))?;
        let travel = travel_direction(&scene);
        let travel_angle_rad = travel.y.atan2(travel.x);
        let mount_angle_rad = scene.chain.base_angle_rad() - travel_angle_rad;
        let sign = match e.wall_side {
            WallSideName::Left => 1.0,
            WallSideName::Right => -1.0,
        };
        let layout = TouchLayout {
            hair_tips: config.sensor_settings().hair_tip_points,
            ..TouchLayout::default()
        };
        let method = match e.estimator {
            EstimatorName::None => return Ok(None),
            EstimatorName::ContactLine => {
                Method::Sensed(SensedWall::contact_line(e.window_s, layout))
            }
            EstimatorName::Bend => {
                let mount = BasePose {
                    base_m: Vector2::zeros(),
                    base_angle_rad: sign * mount_angle_rad,
                };
                let table = calibrate_bend_at(&scene, &mount, 1.0).map_err(|why| {
                    (
                        key(),
                        format!(
                            "\"bend\" calibrates on the scene {} at start: {why}",
                            config.sim.rig.source
                        ),
                    )
                })?;
                Method::Sensed(SensedWall::bend(table, layout))
            }
            EstimatorName::IdealPreview => Method::IdealPreview,
        };
        let links = scene.chain.n() + 1;
        let period_ns = (1e9 / e.rate_hz).round().max(1.0) as u64;
        Ok(Some(LiveEstimate {
            method,
            name: e.estimator.name(),
            truth: (!config.has_hardware()).then(|| Truth {
                walls: scene.walls.clone(),
                travel,
            }),
            chain: scene.chain,
            mount_angle_rad,
            sign,
            period_ns,
            next_due_ns: 0,
            theta: vec![0.0; links],
            touch: vec![0; links],
            stage_m: 0.0,
            fed: 0,
            skipped: 0,
        }))
    }

    /// The estimator's name, as in `[estimate] estimator`.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// Polls fed to the estimator so far, and polls it could not use (a failed read).
    pub fn polls(&self) -> (u64, u64) {
        (self.fed, self.skipped)
    }

    /// Feeds one poll; when an estimate is due (every `1 / rate_hz`), makes it from this
    /// poll and returns it, `estimated_ns` read from `now_ns` once it is made.
    pub fn on_poll(
        &mut self,
        poll: &PollInput<'_>,
        now_ns: impl FnOnce() -> u64,
    ) -> Option<EstimateMessage> {
        if let Some(stage_m) = poll.stage_m {
            self.stage_m = stage_m;
        }
        let odometry = Odometry {
            por_m: Vector2::new(self.stage_m, 0.0),
            heading_rad: 0.0,
        };
        let filled = matches!(self.method, Method::Sensed(_)) && self.fill(poll);
        if let Method::Sensed(wall) = &mut self.method {
            if filled {
                let fed = wall.add_sample(
                    poll.t_ns as f64 * 1e-9,
                    &odometry,
                    &self.chain,
                    &Vector2::zeros(),
                    &self.theta,
                    &self.touch,
                );
                match fed {
                    Ok(()) => self.fed += 1,
                    Err(_) => self.skipped += 1,
                }
            } else {
                self.skipped += 1;
            }
        }
        if poll.t_ns < self.next_due_ns {
            return None;
        }
        self.next_due_ns = if self.next_due_ns == 0 {
            poll.t_ns + self.period_ns
        } else {
            let behind = (poll.t_ns - self.next_due_ns) / self.period_ns + 1;
            self.next_due_ns + behind * self.period_ns
        };
        let estimate: Result<Estimate, NoEstimate> = match &mut self.method {
            Method::Sensed(wall) => wall.estimate(&odometry),
            Method::IdealPreview => match self.truth_at(poll, 0.0) {
                Some((distance_m, _)) => Ok(Estimate {
                    distance_m,
                    angle_rad: None,
                    preview_m: 0.0,
                }),
                None => Err(NoEstimate::NoWallOnRay),
            },
        };
        let preview_m = estimate.as_ref().map_or(0.0, |e| e.preview_m);
        let truth = self.truth_at(poll, preview_m);
        let estimated_ns = now_ns();
        Some(EstimateMessage {
            seq: poll.seq,
            t_ns: poll.t_ns,
            estimated_ns,
            estimator: self.name.to_owned(),
            distance_m: estimate.as_ref().ok().map(|e| e.distance_m),
            angle_rad: estimate.as_ref().ok().and_then(|e| e.angle_rad),
            preview_m: estimate.as_ref().ok().map(|e| e.preview_m),
            reason: estimate.err().map(|why| why.reason().to_owned()),
            true_distance_m: truth.map(|t| t.0),
            true_angle_rad: truth.map(|t| t.1),
        })
    }

    /// The sensed angles and touch bits of `poll` in the (mirrored) carriage frame; false
    /// when a read failed.
    fn fill(&mut self, poll: &PollInput<'_>) -> bool {
        if poll.segments.len() + 1 != self.theta.len() {
            return false;
        }
        self.theta[0] = self.sign * (self.mount_angle_rad + poll.servo_rad.unwrap_or(0.0));
        self.touch[0] = 0;
        for (k, segment) in poll.segments.iter().enumerate() {
            let (Some(angle), Some(bits)) = (segment.angle_rad, segment.touch_bits) else {
                return false;
            };
            self.theta[k + 1] = self.sign * angle;
            self.touch[k + 1] = bits;
        }
        true
    }

    /// The true wall along the carriage's y axis at `preview_m` along x, from the pose the
    /// physics was solved at for `poll`: its distance, m, and its angle to x (the estimate's
    /// convention: `y = d + (x - preview) tan(angle)`), rad.
    fn truth_at(&self, poll: &PollInput<'_>, preview_m: f64) -> Option<(f64, f64)> {
        let truth = self.truth.as_ref()?;
        let (_, pose) = poll.solved_at?;
        let u = truth.travel;
        let toward = Vector2::new(-u.y, u.x) * self.sign;
        let distance = |x_m: f64| {
            first_ray_hit(
                &truth.walls,
                &(pose.base_m + u * x_m),
                &toward,
                TRUTH_RANGE_M,
            )
            .map(|(_, t_m)| t_m)
        };
        let d = distance(preview_m)?;
        let h = TRUTH_ANGLE_HALF_SPAN_M;
        let angle = match (distance(preview_m + h), distance(preview_m - h)) {
            (Some(ahead), Some(behind)) => ((ahead - behind) / (2.0 * h)).atan(),
            _ => 0.0,
        };
        Some((d, angle))
    }
}

/// The scene's unit direction of motion (x when it has none), as the simulated rig reads it.
fn travel_direction(scene: &SweepScene) -> Vector2<f64> {
    let v = scene.motion.velocity_m_per_s;
    if v == Vector2::zeros() || !v.iter().all(|c| c.is_finite()) {
        Vector2::new(1.0, 0.0)
    } else {
        v.normalize()
    }
}
