//! The controller: PD on the estimated distance with a setpoint, a sensing-to-actuation
//! delay in whole steps, and a search turn toward the wall when there is no estimate.

use std::collections::VecDeque;

use super::config::{BodyModel, Controller};
use super::estimate::Estimate;

/// The search turn's rate loop on a template body: the moment that holds the turning rate
/// at the target settles it within about this time constant, seconds.
const SEARCH_TIME_CONSTANT_S: f64 = 0.1;

/// What the controller asks of the body over one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Command {
    /// A template body's moment, N m (positive turning away from the wall).
    Moment(f64),
    /// A wheeled body's wanted turning rate, rad/s (positive away from the wall).
    TurnRate(f64),
}

impl Command {
    /// The value, in the body's units.
    pub fn value(self) -> f64 {
        match self {
            Command::Moment(v) | Command::TurnRate(v) => v,
        }
    }
}

/// The controller's state: the last estimate (for the derivative), the commands on their
/// way through the delay.
#[derive(Clone, Debug)]
pub struct ControlLoop {
    controller: Controller,
    body: BodyModel,
    /// The last estimate's time and distance, while estimates keep coming.
    last: Option<(f64, f64)>,
    /// The error's rate from the last two estimates, m/s.
    rate_m_per_s: f64,
    /// Commands computed but not yet applied, oldest first (`delay_steps` of them).
    queue: VecDeque<Command>,
    delay_steps: usize,
}

impl ControlLoop {
    /// A controller for `body`, with the delay `delay_steps` (see
    /// [`super::FollowConfig::delay_steps`]).
    pub fn new(controller: Controller, body: BodyModel, delay_steps: usize) -> ControlLoop {
        let idle = match body {
            BodyModel::Template { .. } => Command::Moment(0.0),
            BodyModel::Wheeled { .. } => Command::TurnRate(0.0),
        };
        ControlLoop {
            controller,
            body,
            last: None,
            rate_m_per_s: 0.0,
            queue: std::iter::repeat_n(idle, delay_steps).collect(),
            delay_steps,
        }
    }

    /// The command for this step from the estimate at `t_s` (`fresh`: the estimator made it
    /// from a new sample, so the derivative moves on) and the body's turning rate; returns
    /// the command to apply now, the one computed `delay_steps` steps ago.
    pub fn command(
        &mut self,
        t_s: f64,
        estimate: Option<&Estimate>,
        fresh: bool,
        omega_rad_per_s: f64,
    ) -> Command {
        let c = &self.controller;
        let computed = match estimate {
            Some(e) => {
                if fresh {
                    self.rate_m_per_s = match self.last {
                        Some((t0, d0)) if t_s > t0 => (e.distance_m - d0) / (t_s - t0),
                        _ => 0.0,
                    };
                    self.last = Some((t_s, e.distance_m));
                }
                let error_m = e.distance_m - c.setpoint_m;
                match self.body {
                    BodyModel::Template { .. } => {
                        Command::Moment(-c.kp_n * error_m - c.kd_n_s * self.rate_m_per_s)
                    }
                    BodyModel::Wheeled { .. } => Command::TurnRate(
                        -c.kp_rad_per_s_per_m * error_m - c.kd_rad_per_m * self.rate_m_per_s,
                    ),
                }
            }
            None => {
                self.last = None;
                self.rate_m_per_s = 0.0;
                // Turn toward the wall (negative: away is positive).
                let target = -c.search_turn_rate_rad_per_s;
                match self.body {
                    BodyModel::Template {
                        inertia_kg_m2,
                        damping_n_m_s_per_rad,
                    } => Command::Moment(
                        damping_n_m_s_per_rad * target
                            + inertia_kg_m2 / SEARCH_TIME_CONSTANT_S * (target - omega_rad_per_s),
                    ),
                    BodyModel::Wheeled { .. } => Command::TurnRate(target),
                }
            }
        };
        if self.delay_steps == 0 {
            return computed;
        }
        self.queue.push_back(computed);
        self.queue.pop_front().unwrap_or(computed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn estimate(distance_m: f64) -> Estimate {
        Estimate {
            distance_m,
            angle_rad: None,
            preview_m: 0.05,
        }
    }

    #[test]
    fn pd_on_the_error_and_its_rate() {
        let controller = Controller {
            kp_n: 0.05,
            kd_n_s: 0.002,
            setpoint_m: 0.1,
            ..Controller::default()
        };
        let body = BodyModel::Template {
            inertia_kg_m2: 2e-4,
            damping_n_m_s_per_rad: 4e-3,
        };
        let mut c = ControlLoop::new(controller, body, 0);
        // Too far from the wall: turn toward it (negative).
        let u0 = c.command(0.0, Some(&estimate(0.12)), true, 0.0).value();
        assert!((u0 + 0.05 * 0.02).abs() < 1e-15);
        // Closing at 0.1 m/s: the derivative acts against it.
        let u1 = c.command(0.1, Some(&estimate(0.11)), true, 0.0).value();
        assert!((u1 - (-0.05 * 0.01 - 0.002 * -0.1)).abs() < 1e-15);
    }

    #[test]
    fn the_delay_applies_the_command_of_whole_steps_ago() {
        let body = BodyModel::Wheeled {
            max_turn_rate_rad_per_s: 3.0,
            max_turn_accel_rad_per_s2: 10.0,
        };
        let controller = Controller {
            kd_rad_per_m: 0.0,
            ..Controller::default()
        };
        let mut c = ControlLoop::new(controller, body, 2);
        let out: Vec<f64> = [0.11, 0.12, 0.13, 0.14]
            .iter()
            .enumerate()
            .map(|(k, &d)| c.command(k as f64, Some(&estimate(d)), true, 0.0).value())
            .collect();
        assert_eq!(out[0], 0.0);
        assert_eq!(out[1], 0.0);
        assert!((out[2] + 40.0 * 0.01).abs() < 1e-12);
        assert!((out[3] + 40.0 * 0.02).abs() < 1e-12);
    }

    #[test]
    fn without_an_estimate_the_body_turns_toward_the_wall() {
        let body = BodyModel::Template {
            inertia_kg_m2: 2e-4,
            damping_n_m_s_per_rad: 4e-3,
        };
        let mut c = ControlLoop::new(Controller::default(), body, 0);
        let rate = Controller::default().search_turn_rate_rad_per_s;
        // At the target rate the moment only balances the damping.
        let u = c.command(0.0, None, true, -rate).value();
        assert!((u - 4e-3 * -rate).abs() < 1e-15);
    }
}
