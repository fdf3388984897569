//! The lines `antenna sweep --jsonl` prints, one JSON object each, told apart by `type`: a
//! `placement` line first, then one `step` line per step (step 0, the placed posture, first),
//! then a `summary` line. Every field is documented in `docs/sweeps.md`.

use serde::{Deserialize, Serialize};
use sim_core::contact::{Contact, EquilibriumCheck, Feature, Slip};
use sim_core::sweep::{Motion, SweepStep};

use super::{StepMetrics, SweepSummary};

/// One line of `antenna sweep --jsonl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum SweepLine {
    /// The first line: the scene and what the placement did.
    Placement(PlacementRecord),
    /// One per step, step 0 (the placed posture) first.
    Step(StepRecord),
    /// The last line.
    Summary(SweepSummary),
}

/// The `placement` line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlacementRecord {
    /// The scene file as given.
    pub scene: String,
    /// What the placement did, in words (sim-core's note).
    pub note: String,
    /// Links `N` (the base link included); the chain has `n = N - 1` flexible joints.
    pub links: usize,
    /// The number of walls.
    pub walls: usize,
    /// Steps the sweep will take after the placement.
    pub steps: usize,
    /// The time step, seconds.
    pub step_s: f64,
    /// The sweep's duration, seconds.
    pub duration_s: f64,
    /// The base velocity, ground frame, m/s.
    pub velocity_m_per_s: [f64; 2],
}

impl PlacementRecord {
    /// The line for a sweep of `scene` (the file name) with `links` links among `walls`
    /// walls, moving by `motion`.
    pub fn new(scene: &str, note: &str, links: usize, walls: usize, motion: &Motion) -> Self {
        PlacementRecord {
            scene: scene.to_string(),
            note: note.to_string(),
            links,
            walls,
            steps: motion.steps(),
            step_s: motion.step_s,
            duration_s: motion.duration_s,
            velocity_m_per_s: [motion.velocity_m_per_s.x, motion.velocity_m_per_s.y],
        }
    }
}

/// A `step` line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepRecord {
    /// The step number: 0 is the placed posture, then `1..=steps`.
    pub step: usize,
    /// Time since the sweep started, seconds.
    pub t_s: f64,
    /// The base pivot, ground frame, metres.
    pub base_m: [f64; 2],
    /// Signed distance from the base pivot to the nearest wall, metres (`null` without
    /// walls).
    pub wall_distance_m: Option<f64>,
    /// Joint angles `theta_0..theta_n`, radians (`theta_0` the base angle).
    pub theta_rad: Vec<f64>,
    /// Positions of frames `0..=n` (the end of the base link, the joints, the tip last),
    /// ground frame, metres.
    pub joints_m: Vec<[f64; 2]>,
    /// Hair angles per link `0..=n`, radians (0 where there is no hair; the open angle
    /// unless a contact folds the hair).
    pub hair_angles_rad: Vec<f64>,
    /// The contacts, by link then kind.
    pub contacts: Vec<ContactRecord>,
    /// The point of bend: the joint with the greatest `|theta_j|` (`null` when straight).
    pub bend_joint: Option<usize>,
    /// The point of contact: the most proximal contact's nearest point number (joint `j`,
    /// or `n + 1` for the tip); `null` without contacts.
    pub contact_joint: Option<usize>,
    /// The preview distance, metres (`null` without contacts).
    pub preview_m: Option<f64>,
    /// Whether the distal segment is beyond 90 degrees to the nearest wall.
    pub flipped: bool,
    /// The distal segment's angle to the nearest wall, radians in `[0, pi]` (`null` without
    /// walls).
    pub distal_angle_to_wall_rad: Option<f64>,
    /// Touch bits per link `0..=n` (bit `k`: switch `k`, bit 0 the most proximal quarter):
    /// the true ones, every contact closing the switch under it.
    pub touch_bits: Vec<u8>,
    /// What the robot's sensors read, when the scene's `[sensors]` are not ideal (absent
    /// otherwise: the mapping then uses the 12-bit angles and `touch_bits`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensed: Option<SensedRecord>,
    /// Contact points estimated from the sensed angles and touch bits in this step (the
    /// 12-bit angles and `touch_bits` with ideal sensors; none in a step not sampled).
    pub mapping_points: usize,
    /// The estimated points themselves, ground frame, metres (the map: the summary's wall
    /// coverage scores all steps' points together).
    pub mapping_points_m: Vec<[f64; 2]>,
    /// Their mean distance to the true wall, millimetres (`null` without points).
    pub mapping_error_mm: Option<f64>,
    /// Whether the posture snapped during the step (left its branch of equilibria and was
    /// followed downhill).
    pub snapped: bool,
    /// Substeps solved.
    pub substeps: usize,
    /// Pseudo-time steps following snaps.
    pub snap_steps: usize,
    /// Newton iterations.
    pub iterations: usize,
    /// The final residual of the step's equations, metres.
    pub residual_m: f64,
    /// What the solver relaxed to get through the step, in words (empty when nothing):
    /// friction dropped on a jam or where friction locked the antenna, anchored hairs torn
    /// out, a residual accepted above the tolerance.
    pub relaxations: Vec<String>,
    /// The independent check of the step's state (every step passes it, or the sweep
    /// stops): the largest residual of each equilibrium condition.
    pub certificate: CertificateRecord,
}

/// What the robot's sensors read at a step (`sensed` in a `step` line).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensedRecord {
    /// Whether the robot sampled its sensors at this step (`[sensors] sample_rate_hz`); a
    /// step not sampled maps no points.
    pub sampled: bool,
    /// The joint angles as reported, `theta_0..theta_n`, radians (`null` when not sampled).
    pub theta_rad: Option<Vec<f64>>,
    /// The debounced touch bits per link `0..=n` the mapping used (`null` when not sampled).
    pub touch_bits: Option<Vec<u8>>,
}

impl SensedRecord {
    /// The record of a step's sensing; `None` with ideal sensors.
    pub fn new(metrics: &StepMetrics) -> Option<SensedRecord> {
        if metrics.ideal_sensors {
            return None;
        }
        Some(SensedRecord {
            sampled: metrics.sample.is_some(),
            theta_rad: metrics.sample.as_ref().map(|s| s.theta_rad.clone()),
            touch_bits: metrics.sample.as_ref().map(|s| s.touch_bits.clone()),
        })
    }
}

/// The independent check of a step's state ([`EquilibriumCheck`]): the largest residual of
/// each condition.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CertificateRecord {
    /// Torque imbalance at a joint inside its limits or a hair inside its range, N m.
    pub torque_residual_nm: f64,
    /// A stop torque of the wrong sign, N m.
    pub limit_sign_violation_nm: f64,
    /// Penetration of a link or a hair tip into a wall, m.
    pub penetration_m: f64,
    /// Violation of the friction cone (or an anchored hair's holds), N.
    pub cone_violation_n: f64,
    /// Gap of a contact carrying a force, m.
    pub separation_m: f64,
    /// Slip of a stuck contact, m.
    pub stuck_slip_m: f64,
    /// Departure of a slipping contact's shear force from its friction limit, N.
    pub slip_force_violation_n: f64,
    /// Slip of a slipping contact along its own shear force, m.
    pub wrong_way_slip_m: f64,
}

impl CertificateRecord {
    /// The record of a check.
    pub fn new(c: &EquilibriumCheck) -> CertificateRecord {
        CertificateRecord {
            torque_residual_nm: c.torque_residual_nm,
            limit_sign_violation_nm: c.limit_sign_violation_nm,
            penetration_m: c.penetration_m,
            cone_violation_n: c.cone_violation_n,
            separation_m: c.separation_m,
            stuck_slip_m: c.stuck_slip_m,
            slip_force_violation_n: c.slip_force_violation_n,
            wrong_way_slip_m: c.wrong_way_slip_m,
        }
    }
}

impl StepRecord {
    /// The line of one step.
    pub fn new(step: &SweepStep, metrics: &StepMetrics) -> StepRecord {
        StepRecord {
            step: step.step,
            t_s: step.t_s,
            base_m: [step.base_m.x, step.base_m.y],
            wall_distance_m: metrics.wall_distance_m,
            theta_rad: step.theta_rad.clone(),
            joints_m: metrics.joints_m().iter().map(|p| [p.x, p.y]).collect(),
            hair_angles_rad: step.hair_angles_rad.clone(),
            contacts: step.contacts.iter().map(ContactRecord::new).collect(),
            bend_joint: step.bend_joint,
            contact_joint: step.contact_joint,
            preview_m: step.preview_m,
            flipped: step.flipped(),
            distal_angle_to_wall_rad: step.flip.map(|f| f.angle_to_wall_rad),
            touch_bits: step.touch_bits.clone(),
            sensed: SensedRecord::new(metrics),
            mapping_points: metrics.mapping.count,
            mapping_points_m: metrics
                .estimates
                .iter()
                .map(|e| [e.point_m.x, e.point_m.y])
                .collect(),
            mapping_error_mm: metrics.mapping.mean_error_mm,
            snapped: step.report.snapped,
            substeps: step.report.substeps,
            snap_steps: step.report.snap_steps,
            iterations: step.report.iterations,
            residual_m: step.report.residual_m,
            relaxations: step.report.relaxations(),
            certificate: CertificateRecord::new(&step.report.certificate),
        }
    }
}

/// One contact in a `step` line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ContactRecord {
    /// The link touching (`1..=n`).
    pub link: usize,
    /// What touches: `"vertex"` (the link's distal end: joint `link + 1`, or the tip),
    /// `"link"` (a point inside the link, at a wall corner or crest) or `"hair"` (the tip of
    /// the link's hair).
    pub kind: String,
    /// The wall (0 is the first `[[walls]]`).
    pub wall: usize,
    /// Where along the link, 0 (proximal end) to 1 (distal end); for a hair the fraction of
    /// its pivot.
    pub s: f64,
    /// The touching point, ground frame, metres.
    pub point_m: [f64; 2],
    /// The wall's normal force on the chain, newtons (>= 0; negative only for an anchored
    /// hair holding in tension).
    pub normal_force_n: f64,
    /// The wall's shear force on the chain along the wall's tangent, newtons.
    pub shear_force_n: f64,
    /// The wall's force on the chain, ground frame, newtons (the normal and the shear force
    /// along the wall's normal and tangent).
    pub force_n: [f64; 2],
    /// `"stuck"`, `"slipping-forward"` (along the wall's tangent) or `"slipping-backward"`.
    pub state: String,
    /// Where this step's friction was relaxed at the contact (a jam), the shear bound that
    /// held instead of the law's, newtons (`0`: it slid without friction); `null` otherwise.
    pub relaxed_shear_bound_n: Option<f64>,
    /// Whether the contact is a hair tip anchored in a rough surface.
    pub anchored: bool,
    /// How far the contact slid along the wall's tangent during the step, metres.
    pub slip_m: f64,
}

impl ContactRecord {
    /// The record of one sim-core contact.
    pub fn new(c: &Contact) -> ContactRecord {
        let kind = match c.feature {
            Feature::Vertex { .. } => "vertex",
            Feature::Link { .. } => "link",
            Feature::HairTip { .. } => "hair",
        };
        let state = match c.slip {
            Slip::Stuck => "stuck",
            Slip::Forward => "slipping-forward",
            Slip::Backward => "slipping-backward",
        };
        ContactRecord {
            link: c.feature.link(),
            kind: kind.to_string(),
            wall: c.wall,
            s: c.s,
            point_m: [c.point_m.x, c.point_m.y],
            normal_force_n: c.normal_force_n,
            shear_force_n: c.shear_force_n,
            force_n: {
                let f = c.force_n();
                [f.x, f.y]
            },
            state: state.to_string(),
            relaxed_shear_bound_n: c.relaxed_shear_bound_n,
            anchored: c.is_anchored(),
            slip_m: c.slip_m,
        }
    }
}
