//! A scripted motion for the simulated rig until sim-core's solvers drive it: the stage
//! carries the antenna back and forth past a wall, and the flagellum bends against it.

use antenna_protocol::TouchBits;

/// The stage moves the base back and forth between 0 and `travel_m` at `speed_m_per_s`; the
/// wall comes into reach for the middle of the travel. The bend grows toward the tip (a
/// decreasing stiffness profile), and a segment's distal touch switches close while it is
/// pressed. This is a placeholder motion, not mechanics: the equilibrium and contact solvers
/// of sim-core replace it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScriptedSweep {
    /// Joints (flexible segments).
    pub joints: usize,
    /// Stage travel, metres.
    pub travel_m: f64,
    /// Stage speed, metres per second (the seed used 15 to 16.7 mm/s).
    pub speed_m_per_s: f64,
    /// Largest bend of the most distal joint, radians.
    pub max_bend_rad: f64,
}

impl Default for ScriptedSweep {
    fn default() -> Self {
        Self {
            joints: 9,
            travel_m: 0.3,
            speed_m_per_s: 0.0167,
            max_bend_rad: 0.5,
        }
    }
}

/// What the rig looks like at one instant.
#[derive(Debug, Clone, PartialEq)]
pub struct RigState {
    /// Stage position, metres.
    pub stage_m: f64,
    /// Joint angles, radians, base to tip.
    pub joint_angles_rad: Vec<f64>,
    /// Raw touch switches per segment.
    pub touch: Vec<TouchBits>,
}

impl ScriptedSweep {
    /// The rig at `time_s` seconds into the trial.
    pub fn at(&self, time_s: f64) -> RigState {
        let period_s = 2.0 * self.travel_m / self.speed_m_per_s.max(1e-9);
        let phase = (time_s.max(0.0) % period_s) / period_s;
        let stage_m = if phase < 0.5 {
            2.0 * phase * self.travel_m
        } else {
            2.0 * (1.0 - phase) * self.travel_m
        };
        // Wall contact: a smooth bump over the middle half of the travel.
        let x = stage_m / self.travel_m;
        let press = if (0.25..=0.75).contains(&x) {
            (std::f64::consts::PI * (x - 0.25) / 0.5).sin()
        } else {
            0.0
        };
        let n = self.joints.max(1) as f64;
        let joint_angles_rad = (0..self.joints)
            .map(|j| -self.max_bend_rad * press * ((j + 1) as f64 / n).powi(2))
            .collect();
        let touch = (0..self.joints)
            .map(|j| {
                let pressed = press > 0.2 && (j + 1) as f64 / n > 1.0 - press * 0.6;
                TouchBits::from_bits_truncate(if pressed { 0b1100 } else { 0 })
            })
            .collect();
        RigState {
            stage_m,
            joint_angles_rad,
            touch,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stage_goes_out_and_back_and_bends_only_near_the_wall() {
        let sweep = ScriptedSweep::default();
        let period_s = 2.0 * sweep.travel_m / sweep.speed_m_per_s;
        assert!(sweep.at(0.0).stage_m.abs() < 1e-12);
        assert!((sweep.at(period_s / 2.0).stage_m - sweep.travel_m).abs() < 1e-9);
        assert!(sweep.at(0.0).joint_angles_rad.iter().all(|&a| a == 0.0));
        let middle = sweep.at(period_s / 4.0);
        assert!(middle.joint_angles_rad[8] < middle.joint_angles_rad[0]);
        assert!(middle.touch[8].any() && !middle.touch[0].any());
    }
}
