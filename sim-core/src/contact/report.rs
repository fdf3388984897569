//! What one step of the quasi-static solver took, and what it relaxed to get through.

/// What one call of [`super::QuasiStatic::step_to_pose`] (or
/// [`super::QuasiStatic::step_to`]) took.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Substeps solved (1 when the step was solved whole).
    pub substeps: usize,
    /// Whether the posture left its branch of equilibria during the step (a flip or a spring
    /// forward) and was followed downhill to the next one.
    pub snapped: bool,
    /// Pseudo-time steps taken following snaps.
    pub snap_steps: usize,
    /// Newton iterations over all solves of the step.
    pub iterations: usize,
    /// Solves repeated because a contact was missed or let go of its feature, or a hair
    /// anchored or let go.
    pub resolves: usize,
    /// **Relaxed:** anchored hairs torn out. Where an anchored hair and its segment wedge the
    /// antenna against the wall so that no posture nearby is an equilibrium, the anchors give
    /// (the rough surface lets go) and the step is solved again without them.
    pub anchors_released: usize,
    /// Solves that needed the fixed point on the normal forces (Tresca problems) instead of
    /// Coulomb's law directly: where a sliding contact's friction drives it into the wall.
    pub fixed_point_solves: usize,
    /// **Relaxed:** contacts that jammed (Coulomb's law has no quasi-static answer for them:
    /// sliding would need ever more normal force) and slid without friction for the step.
    pub jams: usize,
    /// **Relaxed:** no frictional equilibrium was found near the state (friction locks the
    /// antenna against the wall: sliding would need ever more normal force), and friction
    /// was dropped at every contact for the rest of the step.
    pub friction_dropped: bool,
    /// The final residual of the equations, metres.
    pub residual_m: f64,
    /// **Relaxed:** the residual of some solve was accepted above
    /// [`super::ContactSettings::tolerance_m`] (within
    /// [`super::ContactSettings::acceptable_m`]): a solve that stalled at a degenerate point.
    pub residual_above_tolerance: bool,
    /// Linear solves that fell back from the chain's `O(n)` elimination to a dense
    /// factorization (an indefinite Newton matrix with a vanishing pivot). Not a relaxation:
    /// the answer is the same, only slower.
    pub dense_solves: usize,
    /// The independent check of the state after the step ([`super::QuasiStatic::check`]),
    /// which held within [`super::QuasiStatic::certify_tolerances`] (a step that fails it
    /// is refused).
    pub certificate: super::EquilibriumCheck,
}

impl StepReport {
    /// Whether the solver relaxed anything to get through the step: friction dropped on a
    /// jam, an anchor torn out, a residual accepted above the tolerance.
    pub fn relaxed(&self) -> bool {
        self.jams > 0
            || self.anchors_released > 0
            || self.residual_above_tolerance
            || self.friction_dropped
    }

    /// What was relaxed, in words (empty when nothing was).
    pub fn relaxations(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.jams > 0 {
            out.push(format!(
                "friction dropped at {} jammed contact(s)",
                self.jams
            ));
        }
        if self.friction_dropped {
            out.push("friction dropped at every contact (friction locked the antenna)".to_owned());
        }
        if self.anchors_released > 0 {
            out.push(format!(
                "{} anchored hair(s) torn out",
                self.anchors_released
            ));
        }
        if self.residual_above_tolerance {
            out.push("a residual accepted above the tolerance".to_owned());
        }
        out
    }

    /// Records the residual of an accepted solve (and whether it was above the tolerance).
    pub(crate) fn note_residual(&mut self, residual_m: f64, settings: &super::ContactSettings) {
        self.residual_m = residual_m;
        if residual_m > settings.tolerance_m {
            self.residual_above_tolerance = true;
        }
    }

    /// Adds another (sub)step's report to this one (the last residual wins).
    pub fn accumulate(&mut self, r: &StepReport) {
        self.substeps += r.substeps;
        self.snapped |= r.snapped;
        self.snap_steps += r.snap_steps;
        self.iterations += r.iterations;
        self.resolves += r.resolves;
        self.anchors_released += r.anchors_released;
        self.fixed_point_solves += r.fixed_point_solves;
        self.jams += r.jams;
        self.friction_dropped |= r.friction_dropped;
        self.residual_m = r.residual_m;
        self.residual_above_tolerance |= r.residual_above_tolerance;
        self.dense_solves += r.dense_solves;
        self.certificate = r.certificate;
    }
}
