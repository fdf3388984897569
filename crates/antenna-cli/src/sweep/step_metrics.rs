//! What the CLI derives from each sweep step besides sim-core's own metrics: the base's
//! distance to the walls, the joint positions, and the wall mapping from what the robot
//! would sense (12-bit joint angles and touch bits, seed 4.2.2).

use nalgebra::Vector2;
use sim_core::sweep::SweepStep;
use sim_core::{
    Chain, EstimatedContact, Frame, MappingAccumulator, MappingScore, TouchLayout, Wall,
    estimate_contacts, frame_poses, point_error_mm, sensed_theta_rad,
};

/// The CLI's own per-step quantities.
#[derive(Debug, Clone, PartialEq)]
pub struct StepMetrics {
    /// The signed distance from the base pivot to the nearest wall (positive in free
    /// space), metres; `None` without walls.
    pub wall_distance_m: Option<f64>,
    /// The base pivot then frames `0..=n` (the joints, the tip last), ground frame, metres.
    pub points_m: Vec<Vector2<f64>>,
    /// The contact points estimated from the sensed joint angles and touch bits, scored
    /// against the walls.
    pub mapping: MappingScore,
    /// The estimated points themselves.
    pub estimates: Vec<EstimatedContact>,
    /// Each estimated point's distance to the nearest wall, millimetres (in the order of
    /// `estimates`).
    pub errors_mm: Vec<f64>,
}

impl StepMetrics {
    /// The metrics of `step` for `chain` among `walls`.
    pub fn of(chain: &Chain, walls: &[Wall], step: &SweepStep) -> StepMetrics {
        let base = step.base_m;
        let wall_distance_m = walls
            .iter()
            .map(|w| w.signed_distance(&base).gap_m)
            .reduce(f64::min);
        let mut points_m = Vec::with_capacity(chain.n() + 2);
        points_m.push(base);
        if let Ok(poses) = frame_poses(chain, &step.theta_rad, Frame::GROUND) {
            points_m.extend(
                (0..=chain.n()).filter_map(|i| poses.position_m(Frame::link(i)).map(|p| p + base)),
            );
        }
        let mut sensed = vec![0.0; step.theta_rad.len()];
        let mut estimates = Vec::new();
        let mapped = sensed_theta_rad(&step.theta_rad, &mut sensed).is_ok()
            && estimate_contacts(
                chain,
                &base,
                &sensed,
                &step.touch_bits,
                &TouchLayout::default(),
                &mut estimates,
            )
            .is_ok();
        if !mapped {
            estimates.clear();
        }
        let errors_mm: Vec<f64> = estimates
            .iter()
            .filter_map(|e| point_error_mm(walls, &e.point_m))
            .collect();
        let mut accumulator = MappingAccumulator::default();
        for &e in &errors_mm {
            accumulator.push(e);
        }
        StepMetrics {
            wall_distance_m,
            points_m,
            mapping: accumulator.score(),
            estimates,
            errors_mm,
        }
    }

    /// The joint positions `0..=n` (frames 0..n, ground frame), without the base pivot.
    pub fn joints_m(&self) -> &[Vector2<f64>] {
        self.points_m.get(1..).unwrap_or_default()
    }
}
