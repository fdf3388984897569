//! What the CLI derives from each sweep step besides sim-core's own metrics: the base's
//! distance to the walls, the joint positions, and the wall mapping from what the robot
//! would sense (12-bit joint angles and touch bits, thesis 4.2.2) through the scene's
//! `[sensors]` ([`Sensors`]: noise, calibration, the touch switches' threshold and debounce,
//! the sample rate). A step the robot does not sample maps no points.

use nalgebra::Vector2;
use sim_core::sweep::SweepStep;
use sim_core::{
    Chain, EstimatedContact, Frame, MappingAccumulator, MappingScore, SensorSettings, Sensors,
    TouchLayout, Wall, estimate_contacts, frame_poses, point_error_mm,
};

/// The CLI's own per-step quantities.
#[derive(Debug, Clone, PartialEq)]
pub struct StepMetrics {
    /// The signed distance from the base pivot to the nearest wall (positive in free
    /// space), metres; `None` without walls.
    pub wall_distance_m: Option<f64>,
    /// The base pivot then frames `0..=n` (the joints, the tip last), ground frame, metres.
    pub points_m: Vec<Vector2<f64>>,
    /// What the robot's sensors read at this step; `None` when they did not sample it (a
    /// `[sensors] sample_rate_hz` slower than the steps).
    pub sample: Option<SensorSample>,
    /// Whether the sensors are ideal ([`SensorSettings::is_ideal`]): the records then leave
    /// the sensed data out, as they did before the sensors had settings.
    pub ideal_sensors: bool,
    /// The contact points estimated from the sensed joint angles and touch bits, scored
    /// against the walls (none when the step was not sampled).
    pub mapping: MappingScore,
    /// The estimated points themselves.
    pub estimates: Vec<EstimatedContact>,
    /// Each estimated point's distance to the nearest wall, millimetres (in the order of
    /// `estimates`).
    pub errors_mm: Vec<f64>,
}

/// One sample of the robot's sensors: what the mapping uses.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorSample {
    /// The joint angles as reported, `theta_0..theta_n`, radians (`theta_0` exact).
    pub theta_rad: Vec<f64>,
    /// The debounced touch bits per link `0..=n`.
    pub touch_bits: Vec<u8>,
}

impl StepMetrics {
    /// The metrics of `step` for `chain` among `walls`, sensed by ideal sensors (the 12-bit
    /// angles and the true touch bits).
    pub fn of(chain: &Chain, walls: &[Wall], step: &SweepStep) -> StepMetrics {
        match Sensors::new(&SensorSettings::IDEAL, chain.n()) {
            Ok(mut sensors) => Self::sensed(chain, walls, step, &mut sensors),
            // Ideal settings are valid for any chain.
            Err(_) => Self::sensed_by(chain, walls, step, None, true, TouchLayout::default()),
        }
    }

    /// The metrics of `step` for `chain` among `walls`, as `sensors` sense it (one
    /// [`Sensors`] for a whole sweep, called step by step in order: it keeps the sample clock,
    /// the noise and the debouncers).
    pub fn sensed(
        chain: &Chain,
        walls: &[Wall],
        step: &SweepStep,
        sensors: &mut Sensors,
    ) -> StepMetrics {
        let ideal = sensors.settings().is_ideal();
        let sample = if sensors.is_sample_due(step.t_s) {
            let mut theta_rad = vec![0.0; step.theta_rad.len()];
            let mut touch_bits = vec![0; step.theta_rad.len()];
            let read = sensors
                .sense_angles_rad(&step.theta_rad, &mut theta_rad)
                .and_then(|()| sensors.sense_touch(&step.contacts, &mut touch_bits));
            read.ok().map(|()| SensorSample {
                theta_rad,
                touch_bits,
            })
        } else {
            None
        };
        let layout = sensors.touch_layout();
        Self::sensed_by(chain, walls, step, sample, ideal, layout)
    }

    fn sensed_by(
        chain: &Chain,
        walls: &[Wall],
        step: &SweepStep,
        sample: Option<SensorSample>,
        ideal_sensors: bool,
        layout: TouchLayout,
    ) -> StepMetrics {
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
        let mut estimates = Vec::new();
        if let Some(sample) = &sample {
            let mapped = estimate_contacts(
                chain,
                &base,
                &sample.theta_rad,
                &sample.touch_bits,
                &layout,
                &mut estimates,
            )
            .is_ok();
            if !mapped {
                estimates.clear();
            }
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
            sample,
            ideal_sensors,
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
