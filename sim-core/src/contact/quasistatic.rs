//! Quasi-static stepping of a chain against walls: the step driver (candidate contacts,
//! missed contacts, hair anchoring, substeps and snaps) around the semismooth Newton solve.

// Links are indexed with their ends and hair angles together: index loops say what they do.
#![allow(clippy::needless_range_loop)]

use nalgebra::Vector2;

use super::ContactError;
use super::feature::{Contact, Feature, FrictionLaw};
use super::posture::Posture;
use super::settings::ContactSettings;
use super::ssn::{
    Candidate, InteriorOwner, Proximal, Site, Ssn, SsnOutcome, StepProblem, hair_of,
    interior_contact, interior_owners, located, window_contact,
};
use crate::{Chain, Surface, Wall};

/// What one call of [`QuasiStatic::step_to`] took.
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
    /// Solves repeated because a contact was missed, or a hair anchored or let go.
    pub resolves: usize,
    /// Anchored hairs torn out: where an anchored hair and its segment wedge the antenna
    /// against the wall so that no posture nearby is an equilibrium, the anchors give (the
    /// rough surface lets go) and the step is solved again without them.
    pub anchors_released: usize,
    /// Solves that needed the fixed point on the normal forces (Tresca problems) instead of
    /// Coulomb's law directly: where a sliding contact's friction drives it into the wall.
    pub fixed_point_solves: usize,
    /// Contacts that jammed (Coulomb's law has no quasi-static answer for them: sliding
    /// would need ever more normal force) and slid without friction for the step.
    pub jams: usize,
    /// The final residual of the equations, metres.
    pub residual_m: f64,
}

/// Why one attempt at a (sub)step was not accepted.
enum Reject {
    /// Newton did not converge.
    NoConvergence,
    /// It converged, but a joint moved more than the jump threshold.
    Jump,
}

/// An accepted (sub)step, not yet committed.
struct Accepted {
    x: Vec<f64>,
    hair_links: Vec<usize>,
    cands: Vec<Candidate>,
    residual_m: f64,
    hand_force_n: Vector2<f64>,
}

/// A chain moving quasi-statically against walls with friction and hairs (model.md 6-7).
///
/// The state carries from step to step: joint and hair angles, and every contact with its
/// forces and friction state (anchored hairs stay anchored). See the
/// [module documentation](super) for the method.
#[derive(Debug)]
pub struct QuasiStatic {
    chain: Chain,
    walls: Vec<Wall>,
    /// The walls as the contacts see them: polylines cut at their concave corners
    /// ([`crate::Polyline::split_at_concave_corners`]); `piece_of[i]` is the wall piece `i`
    /// belongs to. Contacts are reported against `walls`.
    contact_walls: Vec<Wall>,
    piece_of: Vec<usize>,
    tip_force_n: Vector2<f64>,
    settings: ContactSettings,
    base_m: Vector2<f64>,
    theta: Vec<f64>,
    beta: Vec<f64>,
    contacts: Vec<Candidate>,
    ssn: Ssn,
    start: Posture,
    probe: Posture,
    /// A hand holding the tip at this offset from the base pivot.
    hand_offset_m: Option<Vector2<f64>>,
    hand_force_n: Vector2<f64>,
    /// No hair anchors during the rest of this step (set after anchors were torn out).
    anchoring_blocked: bool,
    /// Who holds each link's interior contact in the current step, per wall.
    owners: Vec<Vec<InteriorOwner>>,
}

impl QuasiStatic {
    /// A chain at `theta_rad` (`n + 1` entries, `theta_0` the base angle) with its base pivot
    /// at `base_m`, among `walls`. Hairs start open. No contact forces act yet: call
    /// [`Self::settle`] to let a posture touching a wall come to rest.
    ///
    /// # Errors
    /// [`ContactError::WrongLength`], [`ContactError::NotFinite`],
    /// [`ContactError::OutsideLimits`], [`ContactError::BadSetting`], and
    /// [`ContactError::BaseInsideWall`] or [`ContactError::StartInsideWall`] if the posture
    /// is inside a wall by more than the penetration tolerance.
    pub fn new(
        chain: Chain,
        walls: Vec<Wall>,
        base_m: Vector2<f64>,
        theta_rad: &[f64],
        settings: ContactSettings,
    ) -> Result<QuasiStatic, ContactError> {
        settings.validate()?;
        if theta_rad.len() != chain.dof() {
            return Err(ContactError::WrongLength {
                argument: "theta_rad",
                expected: chain.dof(),
                actual: theta_rad.len(),
            });
        }
        finite("base_m", &[base_m.x, base_m.y])?;
        finite("theta_rad", theta_rad)?;
        for (j, (&t, lim)) in theta_rad
            .iter()
            .zip(chain.joint_limits())
            .enumerate()
            .skip(1)
        {
            if !lim.contains(t) {
                return Err(ContactError::OutsideLimits {
                    joint: j,
                    angle_rad: t,
                    cw_rad: lim.cw_rad,
                    ccw_rad: lim.ccw_rad,
                });
            }
        }
        let mut theta = theta_rad.to_vec();
        theta[0] = chain.base_angle_rad();
        let beta = chain
            .hairs()
            .iter()
            .map(|h| h.map_or(0.0, |h| h.open_angle_rad))
            .collect();
        let (contact_walls, piece_of) = contact_pieces(&walls);
        let mut sim = QuasiStatic {
            chain,
            contact_walls,
            piece_of,
            walls,
            tip_force_n: Vector2::zeros(),
            settings,
            base_m,
            theta,
            beta,
            contacts: Vec::new(),
            ssn: Ssn::default(),
            start: Posture::default(),
            probe: Posture::default(),
            hand_offset_m: None,
            hand_force_n: Vector2::zeros(),
            anchoring_blocked: false,
            owners: Vec::new(),
        };
        sim.check_start()?;
        Ok(sim)
    }

    /// A dead load at the tip (ground frame, newtons) from now on.
    pub fn set_tip_force_n(&mut self, tip_force_n: Vector2<f64>) {
        self.tip_force_n = tip_force_n;
    }

    /// The dead load at the tip, newtons.
    pub fn tip_force_n(&self) -> Vector2<f64> {
        self.tip_force_n
    }

    /// Holds the tip near `offset_m` from the base pivot (a hand moving with the base, for
    /// placing the antenna) by a stiff spring, or lets go (`None`). While held,
    /// [`Self::hand_force_n`] is the hand's force on the tip.
    pub fn hold_tip(&mut self, offset_m: Option<Vector2<f64>>) {
        self.hand_offset_m = offset_m;
        if offset_m.is_none() {
            self.hand_force_n = Vector2::zeros();
        }
    }

    /// The force of the hand on the tip after the last step, newtons.
    pub fn hand_force_n(&self) -> Vector2<f64> {
        self.hand_force_n
    }

    /// The chain.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// The walls.
    pub fn walls(&self) -> &[Wall] {
        &self.walls
    }

    /// The base pivot, ground frame, metres.
    pub fn base_m(&self) -> Vector2<f64> {
        self.base_m
    }

    /// The joint angles `theta_0..theta_n`, radians.
    pub fn theta_rad(&self) -> &[f64] {
        &self.theta
    }

    /// The hair angles per link (`n + 1`; `0` on links without a hair), radians: the open
    /// angle unless a contact folds the hair.
    pub fn hair_angles_rad(&self) -> &[f64] {
        &self.beta
    }

    /// The settings.
    pub fn settings(&self) -> &ContactSettings {
        &self.settings
    }

    /// The contacts after the last step, ordered by link then kind.
    pub fn contacts(&self) -> Vec<Contact> {
        let mut out = Vec::with_capacity(self.contacts.len());
        self.contacts_into(&mut out);
        out
    }

    /// [`Self::contacts`] into a caller's buffer (cleared first).
    pub fn contacts_into(&self, out: &mut Vec<Contact>) {
        out.clear();
        out.extend(self.contacts.iter().map(|c| Contact {
            feature: c.feature,
            wall: self.piece_of[c.wall],
            s: c.s,
            point_m: c.point_m,
            normal: c.normal,
            tangent: c.tangent,
            normal_force_n: c.normal_force_n,
            shear_force_n: c.shear_force_n,
            law: c.law,
            slip: c.slip,
            slip_m: c.slip_m,
        }));
    }

    /// Whether the current state is a strict local minimum of the step's potential: the
    /// Hessian of the Lagrangian (springs, the contact forces' and the tip load's curvature)
    /// is positive definite on the tangent space of the active constraints (joints on a
    /// limit held, contacts carrying a force kept touching, stuck ones kept in place). The
    /// walls' own curvature is not part of it.
    pub fn is_stable(&mut self) -> bool {
        self.stability_margin() > 0.0
    }

    /// The smallest eigenvalue of that reduced Hessian divided by the largest joint
    /// stiffness (dimensionless; `> 0` stable). `+inf` when nothing can move.
    pub fn stability_margin(&mut self) -> f64 {
        let n = self.chain.n();
        let mut hair_links: Vec<usize> = self
            .contacts
            .iter()
            .filter(|c| c.feature.is_hair())
            .map(|c| c.feature.link())
            .collect();
        hair_links.sort_unstable();
        hair_links.dedup();
        let mut x: Vec<f64> = self.theta[1..].to_vec();
        x.extend(hair_links.iter().map(|&l| self.beta[l]));
        let mut cands: Vec<Candidate> = self
            .contacts
            .iter()
            .map(|c| {
                let (material_link, material_s) = match c.feature {
                    Feature::Vertex { link } => (link, 1.0),
                    Feature::Link { link } | Feature::HairTip { link } => (link, c.s),
                };
                Candidate {
                    start_m: c.point_m,
                    material_link,
                    material_s,
                    ..*c
                }
            })
            .collect();
        let problem = StepProblem {
            chain: &self.chain,
            walls: &self.contact_walls,
            tip_force_n: self.tip_force_n,
            base_m: self.base_m,
            hair_links: &hair_links,
            hair_beta_rad: &self.beta,
            proximal: None,
            owners: &self.owners,
            hand_m: self.hand_offset_m.map(|o| self.base_m + o),
            tolerance_m: self.settings.tolerance_m,
            acceptable_m: self.settings.acceptable_m,
            max_departure_rad: f64::INFINITY,
            max_iterations: 1,
        };
        let reduced = self.ssn.tangent_hessian(&problem, &x, &mut cands);
        if reduced.nrows() == 0 {
            return f64::INFINITY;
        }
        let k_max = self.chain.stiffness_nm_per_rad()[1..=n]
            .iter()
            .copied()
            .fold(f64::MIN_POSITIVE, f64::max);
        let min = reduced
            .symmetric_eigen()
            .eigenvalues
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        min / k_max
    }

    /// Replaces the posture (joint angles), dropping every contact: for placing the antenna
    /// by hand before a sweep. The same checks as [`Self::new`].
    ///
    /// # Errors
    /// As [`Self::new`].
    pub fn set_posture(
        &mut self,
        base_m: Vector2<f64>,
        theta_rad: &[f64],
    ) -> Result<(), ContactError> {
        let fresh = QuasiStatic::new(
            self.chain.clone(),
            self.walls.clone(),
            base_m,
            theta_rad,
            self.settings,
        )?;
        self.base_m = fresh.base_m;
        self.theta = fresh.theta;
        self.beta = fresh.beta;
        self.contacts.clear();
        Ok(())
    }

    /// Lets the current posture come to rest where it is (the base does not move): a step of
    /// length zero. A posture that is not an equilibrium follows its downhill path.
    ///
    /// # Errors
    /// As [`Self::step_to`].
    pub fn settle(&mut self) -> Result<StepReport, ContactError> {
        self.step_to(self.base_m)
    }

    /// Moves the base pivot to `base_m` and solves the equilibrium there with friction
    /// remembered from the last step. A step that does not converge, or jumps, is split in
    /// halves (up to `2^max_substep_depth` substeps); where the posture's branch of
    /// equilibria ends, the posture follows the downhill path to the next one (a snap).
    ///
    /// # Errors
    /// [`ContactError::NotFinite`], [`ContactError::BaseInsideWall`], or
    /// [`ContactError::NoConvergence`] (the state is then that of the last substep solved).
    pub fn step_to(&mut self, base_m: Vector2<f64>) -> Result<StepReport, ContactError> {
        finite("base_m", &[base_m.x, base_m.y])?;
        let mut report = StepReport::default();
        if self.walls.is_empty() {
            // No wall, no contact: the posture is the free equilibrium under the tip load,
            // which the base's translation does not change.
            self.base_m = base_m;
            if self.tip_force_n == Vector2::zeros()
                && self.hand_offset_m.is_none()
                && self.at_rest()
            {
                report.substeps = 1;
                return Ok(report);
            }
        }
        let full_m = (base_m - self.base_m).norm();
        let min_m = full_m / f64::powi(2.0, self.settings.max_substep_depth as i32);
        let mut goals = vec![base_m];
        while let Some(&goal) = goals.last() {
            if report.iterations > self.settings.max_step_iterations {
                return Err(ContactError::no_convergence(
                    goal,
                    "the step took more Newton iterations than max_step_iterations",
                    report.iterations,
                ));
            }
            match self.attempt(goal, None, &mut report) {
                Ok(accepted) => {
                    report.residual_m = accepted.residual_m;
                    self.commit(goal, accepted);
                    report.substeps += 1;
                    goals.pop();
                }
                Err(_) => {
                    let d = goal - self.base_m;
                    if d.norm() > min_m && d.norm() > 0.0 {
                        goals.push(self.base_m + d * 0.5);
                    } else {
                        let followed = match self.follow_snap(goal, &mut report) {
                            Err(e) if self.release_anchors(&mut report) => {
                                let retry = self.follow_snap(goal, &mut report);
                                retry.map_err(|_| e)
                            }
                            other => other,
                        };
                        self.anchoring_blocked = false;
                        followed?;
                        report.substeps += 1;
                        goals.pop();
                    }
                }
            }
        }
        Ok(report)
    }

    /// Whether every joint sits at its rest angle within its limits (the free equilibrium
    /// without loads).
    fn at_rest(&self) -> bool {
        self.chain
            .rest_theta()
            .iter()
            .zip(&self.theta)
            .skip(1)
            .all(|(r, t)| r == t)
    }

    /// Follows a vanished branch downhill at the base position `goal`: implicit steps of the
    /// friction-aware gradient flow (proximal solves), until a plain solve from the posture
    /// reached converges without a jump.
    fn follow_snap(
        &mut self,
        goal: Vector2<f64>,
        report: &mut StepReport,
    ) -> Result<(), ContactError> {
        report.snapped = true;
        let mut gamma = 1.0;
        for _ in 0..self.settings.max_snap_steps {
            if report.iterations > self.settings.max_step_iterations {
                break;
            }
            report.snap_steps += 1;
            let x_prev = self.coordinates();
            let r = self.attempt(goal, Some((gamma, &x_prev)), report);
            match r {
                Ok(accepted) => {
                    let moved = accepted
                        .x
                        .iter()
                        .zip(&x_prev)
                        .take(self.chain.n())
                        .fold(0.0_f64, |a, (x, y)| a.max((x - y).abs()));
                    report.residual_m = accepted.residual_m;
                    self.commit(goal, accepted);
                    if (moved < 1e-7 || gamma < 1e-6)
                        && let Ok(plain) = self.attempt(goal, None, report)
                    {
                        report.residual_m = plain.residual_m;
                        self.commit(goal, plain);
                        return Ok(());
                    }
                    gamma = (gamma * 0.5).max(1e-8);
                }
                Err(_) => {
                    gamma *= 4.0;
                    if gamma > 1e12 {
                        break;
                    }
                }
            }
        }
        Err(ContactError::no_convergence(
            goal,
            "the downhill path did not come to rest",
            report.iterations,
        ))
    }

    /// Tears out every anchored hair (they become Coulomb contacts) and blocks anchoring for
    /// the rest of the step; whether there was any.
    fn release_anchors(&mut self, report: &mut StepReport) -> bool {
        let mut released = 0;
        for c in &mut self.contacts {
            if c.law.is_anchored() {
                let piece = c.wall;
                let wall = &self.walls[self.piece_of[piece]];
                c.law = FrictionLaw::Coulomb {
                    mu: wall.surface_at(&wall.signed_distance(&c.point_m)).mu(),
                };
                released += 1;
            }
        }
        report.anchors_released += released;
        self.anchoring_blocked = released > 0;
        released > 0
    }

    /// The joint angles `theta_1..theta_n` (the hair angles are not carried).
    fn coordinates(&self) -> Vec<f64> {
        self.theta[1..].to_vec()
    }

    /// Tries one (sub)step from the committed state to the base at `goal`.
    fn attempt(
        &mut self,
        goal: Vector2<f64>,
        proximal: Option<(f64, &[f64])>,
        report: &mut StepReport,
    ) -> Result<Accepted, Reject> {
        let n = self.chain.n();
        self.start.update(&self.chain, self.base_m, &self.theta);
        self.probe.update(&self.chain, goal, &self.theta);
        self.owners = interior_owners(&self.contact_walls, &self.probe, n);
        let mut cands = self.candidates(goal).map_err(|_| Reject::NoConvergence)?;
        let mut demoted: Vec<usize> = Vec::new();
        let mut promoted: Vec<usize> = Vec::new();
        for _round in 0..8 {
            let mut hair_links: Vec<usize> = cands
                .iter()
                .filter(|c| c.feature.is_hair())
                .map(|c| c.feature.link())
                .collect();
            hair_links.sort_unstable();
            hair_links.dedup();
            let mut x: Vec<f64> = self.theta[1..].to_vec();
            x.extend(hair_links.iter().map(|&l| self.beta[l]));
            let prox_x: Vec<f64>;
            let prox = match proximal {
                Some((gamma, x_prev)) => {
                    prox_x = x_prev
                        .iter()
                        .copied()
                        .chain(hair_links.iter().map(|&l| self.beta[l]))
                        .collect();
                    Some(Proximal {
                        gamma,
                        x_prev: &prox_x,
                    })
                }
                None => None,
            };
            let problem = StepProblem {
                chain: &self.chain,
                walls: &self.contact_walls,
                tip_force_n: self.tip_force_n,
                base_m: goal,
                hair_links: &hair_links,
                hair_beta_rad: &self.beta,
                proximal: prox,
                owners: &self.owners,
                hand_m: self.hand_offset_m.map(|o| goal + o),
                tolerance_m: self.settings.tolerance_m,
                // A pseudo-time step of a snap is held to the same residual as a step: a
                // looser one lets the flow creep by stalled solves where a contact sits on
                // the edge of its friction cone, and never come to rest.
                acceptable_m: self.settings.acceptable_m,
                max_departure_rad: 2.0 * self.settings.jump_rad,
                max_iterations: self.settings.max_iterations,
            };
            let x_start = x.clone();
            let cands_start = cands.clone();
            let mut outcome = self.ssn.solve(&problem, &mut x, &mut cands);
            report.iterations += outcome.iterations;
            if !outcome.converged {
                // Coulomb's law makes the step's equations non-monotone (the friction of a
                // sliding contact can drive it into the wall): solve instead the Tresca
                // problems with the normal forces held and iterate them to a fixed point
                // (model.md 6), starting from the last step's forces.
                x.clone_from(&x_start);
                cands.clone_from(&cands_start);
                outcome = solve_by_fixed_point(&mut self.ssn, &problem, &mut x, &mut cands, report);
                if !outcome.converged {
                    return Err(Reject::NoConvergence);
                }
            }
            // Missed contacts: any point now inside a wall joins and the step is re-solved.
            let missed = self.missed_contacts(&x, &hair_links, &cands, goal);
            let mut changed = !missed.is_empty();
            cands.extend(missed);
            // Hair anchoring on rough surfaces (model.md 7).
            for (k, cand) in cands.iter_mut().enumerate() {
                let Site::HairTip(link) = cand.site else {
                    continue;
                };
                let hair = hair_of(&self.chain, link);
                let v = n + hair_links.iter().position(|&l| l == link).unwrap_or(0);
                let beta = x.get(v).copied().unwrap_or(hair.open_angle_rad);
                let on_stop = beta >= hair.open_angle_rad - 1e-12;
                let surface = self.surface_at(cand.wall, &cand.point_m);
                match (cand.law, surface) {
                    (FrictionLaw::Anchored { hold_tension_n, .. }, _)
                        if !on_stop || cand.normal_force_n < -hold_tension_n =>
                    {
                        cand.law = FrictionLaw::Coulomb { mu: surface.mu() };
                        demoted.push(k);
                        changed = true;
                    }
                    (
                        FrictionLaw::Coulomb { .. },
                        Surface::Rough {
                            hold_shear_n,
                            hold_tension_n,
                            ..
                        },
                    ) if on_stop
                        && !self.anchoring_blocked
                        && cand.normal_active
                        && cand.normal_force_n > 0.0
                        && !demoted.contains(&k)
                        && !promoted.contains(&k) =>
                    {
                        // Touching a rough zone open against its stop: the asperities hook
                        // the tip. The anchored solve decides whether the load presses the
                        // hair against its stop (it stays) or folds it (it is let go again).
                        cand.law = FrictionLaw::Anchored {
                            hold_shear_n,
                            hold_tension_n,
                        };
                        promoted.push(k);
                        changed = true;
                    }
                    _ => {}
                }
            }
            if changed {
                report.resolves += 1;
                continue;
            }
            let jump = x
                .iter()
                .zip(&self.theta[1..])
                .take(n)
                .fold(0.0_f64, |a, (x, t)| a.max((x - t).abs()));
            if jump > self.settings.jump_rad {
                return Err(Reject::Jump);
            }
            return Ok(Accepted {
                x,
                hair_links,
                cands,
                residual_m: outcome.residual_m,
                hand_force_n: outcome.hand_force_n,
            });
        }
        Err(Reject::NoConvergence)
    }

    /// Makes an accepted (sub)step the state.
    fn commit(&mut self, goal: Vector2<f64>, accepted: Accepted) {
        let n = self.chain.n();
        self.base_m = goal;
        self.hand_force_n = accepted.hand_force_n;
        self.theta[1..].copy_from_slice(&accepted.x[..n]);
        for (link, hair) in self.chain.hairs().iter().enumerate() {
            if let Some(hair) = hair {
                self.beta[link] = hair.open_angle_rad;
            }
        }
        for (h, &link) in accepted.hair_links.iter().enumerate() {
            self.beta[link] = accepted.x[n + h];
        }
        self.contacts.clear();
        self.contacts.extend(
            accepted
                .cands
                .into_iter()
                // Touching ones only: a contact that let go ends its solve with a normal
                // force of rounding size (1e-25 N), not zero, and would be carried (and
                // reported, with its touch bit) however far the chain moves from the wall.
                .filter(|c| c.normal_active),
        );
        self.contacts.sort_by(|a, b| {
            (a.feature.link(), a.feature, a.wall).cmp(&(b.feature.link(), b.feature, b.wall))
        });
    }

    /// The candidate contacts of a step to the base at `goal`: every link end, link interior
    /// and hair tip within the margin of a wall with the posture carried to `goal`, and the
    /// contacts of the last step (their forces and friction state as the start). A contact
    /// follows its link interior contact from site to site ([`interior_owners`]): into the
    /// window of an end it came near (or left the link by), out to the link's own site when
    /// it moved away from the end; where the new site already has a contact, that one takes
    /// on its forces.
    fn candidates(&self, goal: Vector2<f64>) -> Result<Vec<Candidate>, ContactError> {
        let margin = self.settings.margin_m;
        let mut out: Vec<Candidate> = Vec::new();
        for (w, wall) in self.walls.iter().enumerate() {
            self.check_base(w, wall, &self.probe, goal)?;
        }
        for w in 0..self.contact_walls.len() {
            for site in self.touching_sites(w, &self.probe, &self.beta, margin) {
                out.push(self.candidate(site, w));
            }
        }
        // Where each contact of the last step goes now: a link interior contact that came
        // within reach of an end joins that end's window, one that moved away from it gets
        // a site of its own.
        let mut moves: Vec<(Site, &Candidate)> = Vec::with_capacity(self.contacts.len());
        for old in &self.contacts {
            let owners = &self.owners[old.wall];
            let site = match (old.site, old.feature) {
                (Site::Window(_), Feature::Link { link }) if owners[link] == InteriorOwner::Own => {
                    Site::Interior(link)
                }
                (Site::Interior(link), _) => match owners[link] {
                    InteriorOwner::Window(i) => Site::Window(i),
                    InteriorOwner::Own => {
                        let wall = &self.contact_walls[old.wall];
                        let now = interior_contact(wall, &self.probe, link, old.s);
                        match (now.inside, now.s < 0.5) {
                            (true, _) => old.site,
                            (false, true) => Site::Window(link - 1),
                            (false, false) => Site::Window(link),
                        }
                    }
                },
                (site, _) => site,
            };
            moves.push((site, old));
        }
        // Contacts staying at their site first, so that one moving in finds it taken.
        moves.sort_by_key(|(site, old)| *site != old.site);
        for (site, old) in moves {
            match out
                .iter_mut()
                .find(|c| c.site == site && c.wall == old.wall)
            {
                // The site kept a contact of its own: it takes on the other's forces.
                Some(c) if c.normal_active => {
                    c.normal_force_n += old.normal_force_n;
                    c.shear_force_n += old.shear_force_n;
                }
                Some(c) => carry(c, old),
                None => {
                    let mut c = self.candidate(site, old.wall);
                    carry(&mut c, old);
                    out.push(c);
                }
            }
        }
        Ok(out)
    }

    /// The sites of the chain in `posture` (hair angles `beta`) nearer than `within_m` to
    /// contact-wall piece `w`: windows, link interiors holding their own contact, and hair
    /// tips.
    fn touching_sites(
        &self,
        w: usize,
        posture: &Posture,
        beta: &[f64],
        within_m: f64,
    ) -> Vec<Site> {
        let wall = &self.contact_walls[w];
        let owners = &self.owners[w];
        let n = self.chain.n();
        let mut sites = Vec::new();
        for i in 0..=n {
            if window_contact(wall, owners, posture, n, i).wall.gap_m < within_m {
                sites.push(Site::Window(i));
            }
        }
        for link in 1..=n {
            if owners[link] == InteriorOwner::Own {
                let inside = interior_contact(wall, posture, link, 0.5);
                if inside.inside && inside.wall.gap_m < within_m {
                    sites.push(Site::Interior(link));
                }
            }
            if let Some(Some(hair)) = self.chain.hairs().get(link) {
                let tip = posture.hair_tip(hair, link, beta[link]);
                if wall.signed_distance(&tip).gap_m < within_m {
                    sites.push(Site::HairTip(link));
                }
            }
        }
        sites
    }

    /// A fresh candidate: its material point where the site touches (or comes nearest) at
    /// the start of the step, and the surface's Coulomb law (a hair tip anchors only once
    /// it touches, see [`Self::attempt`]).
    fn candidate(&self, site: Site, wall: usize) -> Candidate {
        let w = &self.contact_walls[wall];
        let (link, s, start) = match site {
            Site::Window(i) => {
                let (link, s) = located(&window_contact(
                    w,
                    &self.owners[wall],
                    &self.start,
                    self.chain.n(),
                    i,
                ));
                (link, s, self.start.link_point(link, s))
            }
            Site::Interior(link) => {
                // Where the crest or corner is at the start of the step; one that had not
                // reached the link yet then (a contact found after a solve) enters it by
                // the end nearer to where it is in the probe posture.
                let at_start = interior_contact(w, &self.start, link, 0.5);
                let s = if at_start.inside {
                    at_start.s
                } else {
                    let now = interior_contact(w, &self.probe, link, 0.5);
                    if now.s < 0.5 { 0.0 } else { 1.0 }
                };
                (link, s, self.start.link_point(link, s))
            }
            Site::HairTip(link) => (
                link,
                1.0,
                self.start
                    .hair_tip(hair_of(&self.chain, link), link, self.beta[link]),
            ),
        };
        let law = FrictionLaw::Coulomb {
            mu: self.surface_at(wall, &start).mu(),
        };
        Candidate::new(site, wall, law, link, s, start)
    }

    /// The surface of the wall that contact-wall piece `piece` belongs to, at the point of it
    /// nearest to `point_m`.
    fn surface_at(&self, piece: usize, point_m: &Vector2<f64>) -> Surface {
        let wall = &self.walls[self.piece_of[piece]];
        wall.surface_at(&wall.signed_distance(point_m))
    }

    /// Windows and hair tips inside a wall after a solve that are not candidates yet.
    fn missed_contacts(
        &mut self,
        x: &[f64],
        hair_links: &[usize],
        cands: &[Candidate],
        goal: Vector2<f64>,
    ) -> Vec<Candidate> {
        let n = self.chain.n();
        let tol = self.settings.penetration_tolerance_m;
        let theta = theta_of(&self.theta, x);
        self.probe.update(&self.chain, goal, &theta);
        let mut beta = self.beta.clone();
        for (h, &l) in hair_links.iter().enumerate() {
            beta[l] = x[n + h];
        }
        let known = |site: Site, w: usize| cands.iter().any(|c| c.site == site && c.wall == w);
        let mut found = Vec::new();
        for w in 0..self.contact_walls.len() {
            for site in self.touching_sites(w, &self.probe, &beta, -tol) {
                if !known(site, w) {
                    found.push((site, w));
                }
            }
        }
        found
            .into_iter()
            .map(|(site, w)| self.candidate(site, w))
            .collect()
    }

    /// The base link must stay out of every wall.
    fn check_base(
        &self,
        w: usize,
        wall: &Wall,
        posture: &Posture,
        base_m: Vector2<f64>,
    ) -> Result<(), ContactError> {
        let sc = wall.segment_contact(&posture.base_m, &posture.end_m[0]);
        if sc.wall.gap_m < -self.settings.penetration_tolerance_m {
            return Err(ContactError::BaseInsideWall {
                wall: w,
                depth_m: -sc.wall.gap_m,
                base_x_m: base_m.x,
                base_y_m: base_m.y,
            });
        }
        Ok(())
    }

    /// The start posture must be outside every wall.
    fn check_start(&mut self) -> Result<(), ContactError> {
        let tol = self.settings.penetration_tolerance_m;
        self.probe.update(&self.chain, self.base_m, &self.theta);
        for (w, wall) in self.walls.iter().enumerate() {
            self.check_base(w, wall, &self.probe, self.base_m)?;
            for link in 1..=self.chain.n() {
                let sc = wall.segment_contact(&self.probe.start_of(link), &self.probe.end_m[link]);
                if sc.wall.gap_m < -tol {
                    return Err(ContactError::StartInsideWall {
                        wall: w,
                        link,
                        hair: "",
                        depth_m: -sc.wall.gap_m,
                    });
                }
                if let Some(Some(hair)) = self.chain.hairs().get(link) {
                    let tip = self.probe.hair_tip(hair, link, self.beta[link]);
                    let gap = wall.signed_distance(&tip).gap_m;
                    if gap < -tol {
                        return Err(ContactError::StartInsideWall {
                            wall: w,
                            link,
                            hair: " (its hair tip)",
                            depth_m: -gap,
                        });
                    }
                }
            }
        }
        Ok(())
    }
}

/// Model.md 6's fixed point: Tresca solves with the normal forces held, each started from
/// the last, until the normal forces stop changing (then the answer is Coulomb's). An
/// iteration that does not settle in [`TRESCA_ITERATIONS`] is not converged.
fn solve_by_fixed_point(
    ssn: &mut Ssn,
    problem: &StepProblem<'_>,
    x: &mut [f64],
    cands: &mut [Candidate],
    report: &mut StepReport,
) -> SsnOutcome {
    for c in cands.iter_mut() {
        c.tresca_n = Some(c.normal_force_n.max(0.0));
    }
    let mut outcome = SsnOutcome {
        converged: false,
        iterations: 0,
        residual_m: f64::INFINITY,
        hand_force_n: Vector2::zeros(),
    };
    for _ in 0..TRESCA_ITERATIONS {
        outcome = ssn.solve(problem, x, cands);
        report.iterations += outcome.iterations;
        if !outcome.converged {
            break;
        }
        let mut settled = true;
        for c in cands.iter_mut() {
            let held = c.tresca_n.unwrap_or(0.0);
            let now = c.normal_force_n.max(0.0);
            if (now - held).abs() > TRESCA_TOLERANCE_N * (1.0 + now) {
                settled = false;
            }
            c.tresca_n = Some(now);
        }
        if settled {
            report.fixed_point_solves += 1;
            for c in cands.iter_mut() {
                c.tresca_n = None;
            }
            return outcome;
        }
    }
    // No fixed point: a jam (a frictional paradox: sliding needs more normal force the more
    // friction it has, without bound). The jamming contacts slide without friction for this
    // step, the others keep their last friction bound; reported, and it keeps the cone.
    let mut jammed = 0;
    for c in cands.iter_mut() {
        let held = c.tresca_n.unwrap_or(0.0);
        if (c.normal_force_n.max(0.0) - held).abs() > 1e-3 * (1e-9 + held) {
            c.tresca_n = Some(0.0);
            jammed += 1;
        } else {
            c.tresca_n = Some(held.min(c.normal_force_n.max(0.0)));
        }
    }
    if jammed > 0 {
        // Any other contact whose friction bound then exceeds mu N loses its friction too,
        // until every contact is inside its cone.
        for _ in 0..=cands.len() {
            outcome = ssn.solve(problem, x, cands);
            report.iterations += outcome.iterations;
            if !outcome.converged {
                break;
            }
            let mut outside = false;
            for c in cands.iter_mut() {
                let bound = c.law.shear_bound(c.normal_force_n).0;
                if c.shear_force_n.abs() > bound + 1e-12 && c.tresca_n != Some(0.0) {
                    c.tresca_n = Some(0.0);
                    jammed += 1;
                    outside = true;
                }
            }
            if !outside {
                break;
            }
        }
        report.jams += jammed;
    }
    for c in cands.iter_mut() {
        c.tresca_n = None;
    }
    outcome.converged &= jammed > 0;
    outcome
}

/// The walls as the contacts see them ([`QuasiStatic`]'s `contact_walls`) and the wall each
/// piece belongs to.
fn contact_pieces(walls: &[Wall]) -> (Vec<Wall>, Vec<usize>) {
    let mut pieces = Vec::new();
    let mut piece_of = Vec::new();
    for (w, wall) in walls.iter().enumerate() {
        match &wall.shape {
            crate::WallShape::Polyline(polyline) => {
                for piece in polyline.split_at_concave_corners() {
                    pieces.push(Wall::new(piece, wall.surfaces.clone()));
                    piece_of.push(w);
                }
            }
            _ => {
                pieces.push(wall.clone());
                piece_of.push(w);
            }
        }
    }
    (pieces, piece_of)
}

/// Fixed-point iterations on the normal forces before a step is given up.
const TRESCA_ITERATIONS: usize = 30;
/// When the held normal forces count as settled, relative.
const TRESCA_TOLERANCE_N: f64 = 1e-10;

/// A contact of the last step carries its forces, law and modes into the next step's
/// candidate (the friction state the model remembers).
fn carry(c: &mut Candidate, old: &Candidate) {
    c.normal_force_n = old.normal_force_n;
    c.shear_force_n = old.shear_force_n;
    c.law = old.law;
    c.normal_active = old.normal_active;
    c.slip = old.slip;
}

/// `theta` with its flexible joints replaced by the first `n` coordinates of `x`.
fn theta_of(theta: &[f64], x: &[f64]) -> Vec<f64> {
    let mut out = theta.to_vec();
    let n = out.len() - 1;
    out[1..].copy_from_slice(&x[..n]);
    out
}

fn finite(argument: &'static str, values: &[f64]) -> Result<(), ContactError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(ContactError::NotFinite {
            argument,
            index,
            value: values[index],
        }),
        None => Ok(()),
    }
}
