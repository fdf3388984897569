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
    /// A step that fails, or moves a joint by more than its jump threshold
    /// ([`Self::jump_threshold_rad`]), is split in halves, at most this many times over
    /// (`2^depth` substeps). Default 12.
    pub max_substep_depth: usize,
    /// The largest joint change one step may make before it is refined, at a joint between
    /// links of [`Self::jump_reference_link_m`]: a larger one means the posture left its
    /// branch of equilibria (a snap), which is then followed downhill. Other joints scale it
    /// with their links ([`Self::jump_threshold_rad`]): the test bounds a change of
    /// curvature, `jump_rad / jump_reference_link_m` (1.25 rad/m by default), the same at
    /// every N. Default 0.05 rad.
    pub jump_rad: f64,
    /// The link length at which [`Self::jump_rad`] applies as given, metres: joint `j`'s
    /// threshold is `jump_rad` times the mean length of the two links it joins over this
    /// (the thesis's 40 mm links: 0.05 rad, as given; its 0.36 m antenna cut into 150 links
    /// of 2.4 mm: 3 mrad). `None`: `jump_rad` at every joint whatever its links (the rule
    /// before issue #49, under which a step may bend an antenna of many short links by
    /// `n jump_rad` in all without a joint over the threshold). Default `Some(0.04)`.
    pub jump_reference_link_m: Option<f64>,
    /// The number of flexible joints [`Self::max_step_iterations`] and
    /// [`Self::max_snap_steps`] are given for: a chain of `n` joints, more than this, gets
    /// both budgets times `n / budget_reference_joints` (rounded up; fewer joints keep them
    /// as given), see [`Self::step_iteration_budget`] and [`Self::snap_step_budget`].
    /// `None`: as given at every `n`. Default `Some(8)` (the thesis's 9-link antenna).
    pub budget_reference_joints: Option<usize>,
    /// Points within this distance of a wall at the start of a step take part in it as
    /// candidate contacts, metres. Default `2e-3`.
    pub margin_m: f64,
    /// A penetration deeper than this after a step is a missed contact: it joins and the step
    /// is solved again, metres. Default `1e-9`.
    pub penetration_tolerance_m: f64,
    /// Pseudo-time steps allowed to follow one snap downhill, for
    /// [`Self::budget_reference_joints`] joints (scaled with the chain's,
    /// [`Self::snap_step_budget`]). Default 2000.
    pub max_snap_steps: usize,
    /// Newton iterations allowed for one call of `step_to`, substeps and snaps included (and
    /// again for the step without friction where friction locked the antenna), for
    /// [`Self::budget_reference_joints`] joints (scaled with the chain's,
    /// [`Self::step_iteration_budget`]): a step that needs more fails with
    /// [`ContactError::NoConvergence`] rather than run on. Default 10000.
    pub max_step_iterations: usize,
}

/// The link length at which the default [`ContactSettings::jump_rad`] applies as given: the
/// thesis's robot's 40 mm links, metres.
pub const JUMP_REFERENCE_LINK_M: f64 = 0.04;

/// The flexible joints the default budgets are given for: the thesis's 9-link antenna's 8.
pub const BUDGET_REFERENCE_JOINTS: usize = 8;

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings {
            tolerance_m: 1e-12,
            acceptable_m: 1e-9,
            max_iterations: 60,
            max_substep_depth: 12,
            jump_rad: 0.05,
            jump_reference_link_m: Some(JUMP_REFERENCE_LINK_M),
            budget_reference_joints: Some(BUDGET_REFERENCE_JOINTS),
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
        if let Some(reference) = self.jump_reference_link_m {
            positive("jump_reference_link_m", reference)?;
        }
        if self.budget_reference_joints == Some(0) {
            return Err(ContactError::BadSetting {
                setting: "budget_reference_joints",
                value: 0.0,
                expected: "at least 1",
            });
        }
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

    /// The jump threshold of joint `joint` (`1..=n`, between links `joint - 1` and `joint`)
    /// of a chain with links `link_lengths_m` (`n + 1`), radians: [`Self::jump_rad`] times
    /// the mean of the two links' lengths over [`Self::jump_reference_link_m`] (a joint's
    /// angle is the bend of the stretch from the middle of one link to the middle of the
    /// next), or `jump_rad` where that is `None` or the joint does not exist. At the
    /// reference link, `jump_rad` bit for bit.
    ///
    /// Scaled so, the test bounds the change of curvature, and what one accepted step can
    /// change in all is the same at every N: at most `jump_rad L / reference` of turn
    /// between the base and the tip of an antenna of length `L` (0.45 rad for the thesis's
    /// 0.36 m), however finely it is cut. Per joint, it grew with N: the thesis's antenna cut
    /// into 130 links was released from a bent-back posture onto one projecting forward (the
    /// tip 0.33 m away, 2.6 rad of bending) in one step with no joint over 0.05 rad.
    pub fn jump_threshold_rad(&self, link_lengths_m: &[f64], joint: usize) -> f64 {
        match (
            self.jump_reference_link_m,
            joint.checked_sub(1).and_then(|j| link_lengths_m.get(j)),
            link_lengths_m.get(joint),
        ) {
            (Some(reference_m), Some(before_m), Some(after_m)) => {
                self.jump_rad * (0.5 * (before_m + after_m)) / reference_m
            }
            _ => self.jump_rad,
        }
    }

    /// The largest of the chain's jump thresholds ([`Self::jump_threshold_rad`]) over its
    /// joints `1..=n`, radians (`jump_rad` without joints).
    pub fn max_jump_threshold_rad(&self, link_lengths_m: &[f64]) -> f64 {
        let n = link_lengths_m.len().saturating_sub(1);
        if n == 0 {
            return self.jump_rad;
        }
        (1..=n)
            .map(|j| self.jump_threshold_rad(link_lengths_m, j))
            .fold(0.0_f64, f64::max)
    }

    /// `budget` for a chain of `joints` flexible joints: times `joints / reference`, rounded
    /// up, where that is more (see [`Self::budget_reference_joints`]).
    fn scaled_budget(&self, budget: usize, joints: usize) -> usize {
        match self.budget_reference_joints {
            Some(reference) if reference > 0 && joints > reference => budget
                .saturating_mul(joints)
                .div_ceil(reference)
                .max(budget),
            _ => budget,
        }
    }

    /// Newton iterations allowed for one step of a chain of `joints` flexible joints:
    /// [`Self::max_step_iterations`], times `joints / 8` above 8 joints by default (a step at
    /// N = 150 links may take 18.6 times the 9-link antenna's: a snap's path carries its
    /// contacts across up to `n` links, each a few solves).
    pub fn step_iteration_budget(&self, joints: usize) -> usize {
        self.scaled_budget(self.max_step_iterations, joints)
    }

    /// Pseudo-time steps allowed to follow one snap of a chain of `joints` flexible joints:
    /// [`Self::max_snap_steps`], scaled as [`Self::step_iteration_budget`].
    pub fn snap_step_budget(&self, joints: usize) -> usize {
        self.scaled_budget(self.max_snap_steps, joints)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// At the thesis's 40 mm links the threshold is `jump_rad` bit for bit; the 0.36 m
    /// antenna cut finer gets the same change of curvature; `None` keeps `jump_rad`.
    #[test]
    fn the_jump_threshold_scales_with_the_links() {
        let s = ContactSettings::default();
        assert_eq!(s.jump_threshold_rad(&[0.04; 9], 3), s.jump_rad);
        assert_eq!(s.jump_threshold_rad(&[0.36 / 9.0; 9], 8), s.jump_rad);
        let l = 0.36 / 150.0;
        let t = s.jump_threshold_rad(&vec![l; 150], 75);
        assert!((t - 0.05 * l / 0.04).abs() < 1e-17, "{t}");
        // The mean of the two links a joint joins.
        let t = s.jump_threshold_rad(&[0.02, 0.06, 0.04], 1);
        assert!((t - 0.05).abs() < 1e-16, "{t}");
        assert!((s.max_jump_threshold_rad(&[0.02, 0.06, 0.04]) - 0.0625).abs() < 1e-16);
        let per_joint = ContactSettings {
            jump_reference_link_m: None,
            ..s
        };
        assert_eq!(per_joint.jump_threshold_rad(&vec![l; 150], 75), s.jump_rad);
    }

    /// Budgets as given up to 8 joints, then in proportion.
    #[test]
    fn budgets_scale_with_the_joints() {
        let s = ContactSettings::default();
        for joints in [0, 3, 8] {
            assert_eq!(s.step_iteration_budget(joints), s.max_step_iterations);
            assert_eq!(s.snap_step_budget(joints), s.max_snap_steps);
        }
        assert_eq!(s.step_iteration_budget(149), 186_250);
        assert_eq!(s.snap_step_budget(149), 37_250);
        assert_eq!(s.snap_step_budget(9), 2_250);
        let fixed = ContactSettings {
            budget_reference_joints: None,
            ..s
        };
        assert_eq!(fixed.step_iteration_budget(149), s.max_step_iterations);
        assert!(
            ContactSettings {
                budget_reference_joints: Some(0),
                ..s
            }
            .validate()
            .is_err()
        );
        assert!(
            ContactSettings {
                jump_reference_link_m: Some(-1.0),
                ..s
            }
            .validate()
            .is_err()
        );
    }
}
