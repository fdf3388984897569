//! Options of the quasi-static contact solver.

use super::ContactError;

/// Options of [`super::QuasiStatic`], with defaults that suit the thesis's robot (40 mm links,
/// stiffness 0.004-0.082 N m / rad, base steps of a fraction of a millimetre).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactSettings {
    /// Convergence: every residual of the step's equations below this, metres (joint
    /// equations are scaled to metres by the mean link length). Default `1e-12`.
    pub tolerance_m: f64,
    /// A solve that stalls above [`Self::tolerance_m`] (at a degenerate point: a contact
    /// touching with zero force, or sliding at exactly the friction limit) is accepted
    /// within this residual, metres. Default `1e-9`.
    pub acceptable_m: f64,
    /// Newton iterations per solve. Default 60.
    pub max_iterations: usize,
    /// A step that fails, or moves a joint by more than [`Self::jump_rad`], is split in
    /// halves, at most this many times over (`2^depth` substeps). Default 12.
    pub max_substep_depth: usize,
    /// The largest joint change one step may make before it is refined: a larger one means
    /// the posture left its branch of equilibria (a snap), which is then followed downhill.
    /// Default 0.05 rad.
    pub jump_rad: f64,
    /// Points within this distance of a wall at the start of a step take part in it as
    /// candidate contacts, metres. Default `2e-3`.
    pub margin_m: f64,
    /// A penetration deeper than this after a step is a missed contact: it joins and the step
    /// is solved again, metres. Default `1e-9`.
    pub penetration_tolerance_m: f64,
    /// Pseudo-time steps allowed to follow one snap downhill. Default 2000.
    pub max_snap_steps: usize,
    /// Newton iterations allowed for one call of `step_to`, substeps and snaps included (and
    /// again for the step without friction where friction locked the antenna): a step that
    /// needs more fails with [`ContactError::NoConvergence`] rather than run on. Default
    /// 10000.
    pub max_step_iterations: usize,
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings {
            tolerance_m: 1e-12,
            acceptable_m: 1e-9,
            max_iterations: 60,
            max_substep_depth: 12,
            jump_rad: 0.05,
            margin_m: 2e-3,
            penetration_tolerance_m: 1e-9,
            max_snap_steps: 2_000,
            max_step_iterations: 10_000,
        }
    }
}

impl ContactSettings {
    /// Checks every setting.
    ///
    /// # Errors
    /// [`ContactError::BadSetting`] naming the first one out of range.
    pub fn validate(&self) -> Result<(), ContactError> {
        let positive = |setting, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(ContactError::BadSetting {
                    setting,
                    value,
                    expected: "finite and > 0",
                })
            }
        };
        positive("tolerance_m", self.tolerance_m)?;
        positive("acceptable_m", self.acceptable_m)?;
        positive("jump_rad", self.jump_rad)?;
        positive("margin_m", self.margin_m)?;
        positive("penetration_tolerance_m", self.penetration_tolerance_m)?;
        for (setting, value) in [
            ("max_iterations", self.max_iterations),
            ("max_snap_steps", self.max_snap_steps),
            ("max_step_iterations", self.max_step_iterations),
        ] {
            if value == 0 {
                return Err(ContactError::BadSetting {
                    setting,
                    value: 0.0,
                    expected: "at least 1",
                });
            }
        }
        if self.max_substep_depth > 40 {
            return Err(ContactError::BadSetting {
                setting: "max_substep_depth",
                value: self.max_substep_depth as f64,
                expected: "at most 40",
            });
        }
        Ok(())
    }
}
