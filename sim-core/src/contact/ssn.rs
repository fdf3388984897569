//! One quasi-static step as a nonlinear complementarity problem, solved by a semismooth
//! Newton method (the Alart-Curnier form of Coulomb contact).
//!
//! # Unknowns and equations
//! `z = (x, N_1..N_c, T_1..T_c)`: the free coordinates `x` (flexible joint angles, then the
//! angles of the hairs taking part), and per candidate contact its normal force `N_k` and
//! shear force `T_k` (on the chain, along the wall's normal and tangent). With the
//! generalized force `r(x, N, T) = grad U(x) - J_tip^T F - sum_k J_k^T (N_k n_k + T_k t_k)`
//! (plus a proximal term when following a snap), the step's equations are, with
//! `proj_[a,b]` the clamp and `c` a contact stiffness scale:
//! - coordinates (box `lo <= x_a <= hi`): `x_a - proj_[lo,hi](x_a - r_a / s_a) = 0`, i.e.
//!   `r_a = 0` inside the box, `r_a >= 0` at `lo`, `r_a <= 0` at `hi` (the KKT conditions of
//!   the joint limits, with the stop's multiplier of the right sign);
//! - normal: `N_k - proj_[N_min, inf)(N_k - c gap_k(x)) = 0`: `N >= N_min`, `gap >= 0`,
//!   complementary (`N_min = 0`, or minus the tension hold of an anchored hair tip);
//! - tangential: `T_k - proj_[-B_k, B_k](T_k - c u_k(x)) = 0` with `B_k = mu N_k` (Coulomb)
//!   or the shear hold of an anchored hair, and `u_k = t_k . (X_k(x) - X_k^0)` the slip of
//!   the contact's material point over the step: `u = 0` while `|T| < B` (stuck: no creep),
//!   else `T = -B sign(u)`.
//!
//! Each of these is piecewise smooth; Newton's method on them with the Jacobian of the active
//! piece is the semismooth Newton method (equivalently a primal-dual active-set method).
//! The Jacobian is dense, `(m + 2c)^2` with `m` coordinates and `c` candidates (tens for the
//! robot): an LU factorization costs microseconds. Globalization: a backtracking line search
//! on `|Phi|^2 / 2` and a cap on the joint change per iteration; a solve that does not
//! converge is reported, and the caller refines the step.
//!
//! Every residual is scaled to metres: joint rows by the mean link length `L` (`L r_a / s_a`
//! or `L (x_a - bound)`), normal and shear rows are gaps and slips, or forces divided by `c`.

// Joint `j` (1-based), its coordinate `j - 1` and the link ends `p_(j-1)` are indexed
// together throughout: index loops say what they do here.
#![allow(clippy::needless_range_loop)]

use nalgebra::{DMatrix, DVector, Vector2};

use super::feature::{Feature, FrictionLaw, Slip};
use super::posture::{Posture, cross, perp};
use crate::{Chain, Hair, Wall, WallPoint};

/// Where on the chain a candidate contact is looked for: its identity from step to step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) enum Site {
    /// The window around the link end `p_i` (`i = 0..=n`): the end itself and, when the
    /// step gives it to this window ([`interior_owners`]), the interior contact of link `i`
    /// or `i + 1` next to it. A wall touching the chain at a joint, or just beside it on
    /// either link, or sliding across it, is one contact, never two nearly equal copies (see
    /// [`window_contact`]).
    Window(usize),
    /// The inside of link `link`, when its interior contact is away from both its ends
    /// ([`InteriorOwner::Own`]): a crest or corner pressing on the middle of the link while
    /// its ends touch elsewhere is a contact of its own (see [`interior_contact`]).
    Interior(usize),
    /// The tip of the hair on a link.
    HairTip(usize),
}

/// Who holds a link's interior contact during one step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum InteriorOwner {
    /// The window of this link end (`link - 1` or `link`).
    Window(usize),
    /// The link's own [`Site::Interior`].
    Own,
}

/// How near a link end (as a fraction of the link) an interior contact is given to that
/// end's window rather than a site of its own: two contacts closer than this are one.
pub(crate) const NEAR_END: f64 = 0.1;

/// A candidate contact during one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Candidate {
    pub site: Site,
    /// Where the contact point is now (filled by the evaluation): the link end (a
    /// [`Feature::Vertex`]), a point inside a link, or a hair tip.
    pub feature: Feature,
    pub wall: usize,
    pub law: FrictionLaw,
    /// The link and fraction along it of the material point that was in contact at the
    /// start of the step (for a hair tip: its link).
    pub material_link: usize,
    pub material_s: f64,
    /// The material point's position at the start of the step.
    pub start_m: Vector2<f64>,
    pub normal_force_n: f64,
    pub shear_force_n: f64,
    // Filled by the evaluation:
    pub s: f64,
    pub point_m: Vector2<f64>,
    pub material_m: Vector2<f64>,
    pub gap_m: f64,
    pub normal: Vector2<f64>,
    pub tangent: Vector2<f64>,
    pub slip_m: f64,
    pub normal_active: bool,
    pub slip: Slip,
    /// When set, the shear bound is `mu` times this normal force instead of the current one
    /// (the Tresca problem of model.md 6's fixed-point iteration on the normal forces).
    pub tresca_n: Option<f64>,
}

impl Candidate {
    pub fn new(
        site: Site,
        wall: usize,
        law: FrictionLaw,
        material_link: usize,
        material_s: f64,
        start_m: Vector2<f64>,
    ) -> Candidate {
        Candidate {
            site,
            feature: match site {
                Site::HairTip(link) => Feature::HairTip { link },
                Site::Window(_) => Feature::Link {
                    link: material_link,
                },
                Site::Interior(link) => Feature::Link { link },
            },
            wall,
            law,
            material_link,
            material_s,
            start_m,
            normal_force_n: 0.0,
            shear_force_n: 0.0,
            s: material_s,
            point_m: start_m,
            material_m: start_m,
            gap_m: f64::INFINITY,
            normal: Vector2::zeros(),
            tangent: Vector2::zeros(),
            slip_m: 0.0,
            normal_active: false,
            slip: Slip::Stuck,
            tresca_n: None,
        }
    }
}

/// A proximal term `gamma/2 sum_a s_a (x_a - x_prev_a)^2`: one implicit step of the
/// (friction-aware) gradient flow, used to follow a snap downhill.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Proximal<'a> {
    pub gamma: f64,
    pub x_prev: &'a [f64],
}

/// What one step is about.
pub(crate) struct StepProblem<'a> {
    pub chain: &'a Chain,
    pub walls: &'a [Wall],
    pub tip_force_n: Vector2<f64>,
    pub base_m: Vector2<f64>,
    /// Links whose hair angle is a coordinate, in coordinate order after the joints.
    pub hair_links: &'a [usize],
    /// Hair angles of every link (`n + 1`; links without a hair, or whose hair is not a
    /// coordinate, keep theirs).
    pub hair_beta_rad: &'a [f64],
    pub proximal: Option<Proximal<'a>>,
    /// Who holds each link's interior contact, per wall ([`interior_owners`]).
    pub owners: &'a [Vec<InteriorOwner>],
    /// A hand holding the tip near this point (ground frame) with a stiff spring: the force
    /// `k_hand (target - p_n)` acts on the tip, `k_hand = 1000 c`.
    pub hand_m: Option<Vector2<f64>>,
    pub tolerance_m: f64,
    /// The residual accepted from a solve that stalls above `tolerance_m`.
    pub acceptable_m: f64,
    /// A solve whose joint angles wander farther than this from where it started gives up
    /// (its step would be refused as a jump anyway), radians.
    pub max_departure_rad: f64,
    pub max_iterations: usize,
}

/// How a solve ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SsnOutcome {
    pub converged: bool,
    pub iterations: usize,
    /// `max |Phi|`, metres.
    pub residual_m: f64,
    /// The hand's force on the tip, newtons (zero without a hand).
    pub hand_force_n: Vector2<f64>,
}

/// Scratch space, reused from step to step.
#[derive(Debug, Default)]
pub(crate) struct Ssn {
    pub posture: Posture,
    theta: Vec<f64>,
    beta: Vec<f64>,
    r: Vec<f64>,
    hess: DMatrix<f64>,
    /// Per candidate, `m` columns: the Jacobian of its contact point.
    jac: Vec<Vector2<f64>>,
    /// Per candidate, `m` columns: the Jacobian of its material point.
    jac_mat: Vec<Vector2<f64>>,
    phi: DVector<f64>,
    big: DMatrix<f64>,
    scale: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    z: DVector<f64>,
    z_trial: DVector<f64>,
    trial: Vec<Candidate>,
    length_m: f64,
    c_n_per_m: f64,
    fd_posture: Posture,
}

impl Ssn {
    /// Sets up the coordinate scales and bounds for `problem` (`m = n + hairs`).
    fn prepare(&mut self, p: &StepProblem<'_>) {
        let chain = p.chain;
        let n = chain.n();
        let m = n + p.hair_links.len();
        let k = chain.stiffness_nm_per_rad();
        let k_max = k[1..].iter().copied().fold(0.0_f64, f64::max);
        let k_mean = if n > 0 {
            k[1..].iter().sum::<f64>() / n as f64
        } else {
            0.0
        };
        let lengths = chain.link_lengths_m();
        self.length_m = lengths.iter().sum::<f64>() / lengths.len() as f64;
        let k_ref = if k_mean > 0.0 { k_mean } else { 1e-3 };
        self.c_n_per_m = k_ref / (self.length_m * self.length_m);
        self.scale.clear();
        self.lo.clear();
        self.hi.clear();
        for j in 1..=n {
            self.scale.push(k[j].max(1e-3 * k_max).max(1e-12));
            let lim = chain.joint_limits()[j];
            self.lo.push(lim.cw_rad);
            self.hi.push(lim.ccw_rad);
        }
        for &link in p.hair_links {
            let hair = hair_of(chain, link);
            let s = hair
                .stiffness_nm_per_rad
                .max(hair.preload_nm / hair.open_angle_rad)
                .max(1e-9);
            self.scale.push(s);
            self.lo.push(0.0);
            self.hi.push(hair.open_angle_rad);
        }
        self.r.resize(m, 0.0);
        self.theta.resize(n + 1, 0.0);
        self.theta[0] = chain.base_angle_rad();
        self.beta.clear();
        self.beta.extend_from_slice(p.hair_beta_rad);
    }

    /// Solves the step: `x` (the coordinates) and the candidates' forces are the start and
    /// receive the answer (the best point reached if it did not converge).
    pub fn solve(
        &mut self,
        p: &StepProblem<'_>,
        x: &mut [f64],
        cands: &mut [Candidate],
    ) -> SsnOutcome {
        self.prepare(p);
        let m = x.len();
        let c = cands.len();
        let dim = m + 2 * c;
        self.z = DVector::zeros(dim);
        for (a, &v) in x.iter().enumerate() {
            self.z[a] = v.clamp(self.lo[a], self.hi[a]);
        }
        for (k, cand) in cands.iter().enumerate() {
            self.z[m + k] = cand.normal_force_n;
            self.z[m + c + k] = cand.shear_force_n;
        }
        let mut merit = self.evaluate(p, m, cands, true);
        let mut outcome = SsnOutcome {
            converged: false,
            iterations: 0,
            residual_m: self.phi.amax(),
            hand_force_n: Vector2::zeros(),
        };
        // Levenberg-Marquardt damping of the Newton matrix, raised when a step fails (a
        // redundant or momentarily infeasible set of stuck contacts makes the plain Newton
        // matrix singular) and lowered again after successes. It changes the path, not the
        // solution: the residual `Phi` itself is never regularized.
        let mut damping = 0.0_f64;
        // A non-monotone line search (Grippo-Lampariello-Lucidi): a step is accepted against
        // the largest merit of the last few iterations, so that the active sets can settle
        // where a constraint is degenerate (a contact at the moment of touching: N = 0 and
        // gap = 0), where the min-based merit has a kink.
        let mut recent = [merit; NONMONOTONE_MEMORY];
        while outcome.residual_m > p.tolerance_m && outcome.iterations < p.max_iterations {
            let reference = recent.iter().copied().fold(merit, f64::max);
            outcome.iterations += 1;
            let Some(dz) = self.newton_direction(dim, damping) else {
                damping = next_damping(damping);
                if damping > MAX_DAMPING {
                    break;
                }
                continue;
            };
            // Cap the joint change per iteration (a trust region in angle).
            let max_dx = (0..m).fold(0.0_f64, |a, i| a.max(dz[i].abs()));
            let mut alpha = if max_dx > 0.25 { 0.25 / max_dx } else { 1.0 };
            let mut accepted = false;
            while alpha > 1e-6 {
                self.z_trial.clone_from(&self.z);
                self.z_trial.axpy(alpha, &dz, 1.0);
                for a in 0..m {
                    self.z_trial[a] = self.z_trial[a].clamp(self.lo[a], self.hi[a]);
                }
                self.trial.clear();
                self.trial.extend_from_slice(cands);
                std::mem::swap(&mut self.z, &mut self.z_trial);
                let mut trial = std::mem::take(&mut self.trial);
                let trial_merit = self.evaluate(p, m, &mut trial, false);
                if trial_merit.is_finite() && trial_merit <= (1.0 - 2e-4 * alpha) * reference {
                    cands.copy_from_slice(&trial);
                    self.trial = trial;
                    accepted = true;
                    break;
                }
                self.trial = trial;
                std::mem::swap(&mut self.z, &mut self.z_trial);
                alpha *= 0.5;
            }
            if accepted {
                damping = if damping > MIN_DAMPING {
                    damping * 0.01
                } else {
                    0.0
                };
            } else {
                // Rejected: evaluate again at the current point (the trials overwrote Phi).
                merit = self.evaluate(p, m, cands, true);
                damping = next_damping(damping);
                if damping > MAX_DAMPING {
                    break;
                }
                continue;
            }
            let n = p.chain.n();
            if (0..n).any(|a| (self.z[a] - x[a]).abs() > p.max_departure_rad) {
                break;
            }
            // The Jacobian at the accepted point.
            merit = self.evaluate(p, m, cands, true);
            recent[outcome.iterations % NONMONOTONE_MEMORY] = merit;
            outcome.residual_m = self.phi.amax();
        }
        // A solve that stalls at a degenerate point (a contact touching with N = 0 and
        // gap = 0: the modes trade places and Newton's method stops improving) is accepted
        // within the acceptable residual.
        outcome.converged = outcome.residual_m <= p.tolerance_m.max(p.acceptable_m);
        for (a, v) in x.iter_mut().enumerate() {
            *v = self.z[a];
        }
        for (k, cand) in cands.iter_mut().enumerate() {
            cand.normal_force_n = self.z[m + k];
            cand.shear_force_n = self.z[m + c + k];
        }
        outcome.hand_force_n = self.hand_force_n(p);
        outcome
    }

    /// The Newton direction `-J^-1 Phi`, with `J` damped by `damping`: `+damping L` on the
    /// coordinate rows and `-max(damping, 1e-10) / c` on the diagonal of the constraint rows
    /// that have none (active normal and stuck rows: the dual regularization of a
    /// saddle-point system).
    fn newton_direction(&self, dim: usize, damping: f64) -> Option<DVector<f64>> {
        let rhs = -&self.phi;
        let m = self.r.len();
        let finite = |dz: &DVector<f64>| dz.iter().all(|v| v.is_finite());
        // Always a tiny dual regularization: two stuck contacts on one rigid link (a link's
        // end and its hair on its stop) make identical rows, and the split of their forces is
        // then the least-norm one instead of an arbitrary one.
        let dual = damping.max(DUAL_REGULARIZATION);
        let mut reg = self.big.clone();
        for i in 0..m {
            reg[(i, i)] += damping * self.length_m;
        }
        for i in m..dim {
            if reg[(i, i)] == 0.0 {
                reg[(i, i)] = -dual / self.c_n_per_m;
            }
        }
        reg.lu().solve(&rhs).filter(finite)
    }

    /// Evaluates `Phi(z)` into `self.phi` (and its Jacobian into `self.big` when asked);
    /// returns the merit `|Phi|^2 / 2`.
    fn evaluate(
        &mut self,
        p: &StepProblem<'_>,
        m: usize,
        cands: &mut [Candidate],
        jacobian: bool,
    ) -> f64 {
        let chain = p.chain;
        let n = chain.n();
        let c = cands.len();
        let dim = m + 2 * c;
        for j in 1..=n {
            self.theta[j] = self.z[j - 1];
        }
        for (h, &link) in p.hair_links.iter().enumerate() {
            self.beta[link] = self.z[n + h];
        }
        self.posture.update(chain, p.base_m, &self.theta);

        // The gradient of the potential (springs, proximal term, dead load).
        let k = chain.stiffness_nm_per_rad();
        let rest = chain.rest_angles_rad();
        for j in 1..=n {
            self.r[j - 1] = k[j] * (self.theta[j] - rest[j]);
        }
        for (h, &link) in p.hair_links.iter().enumerate() {
            self.r[n + h] = hair_of(chain, link).spring_gradient_nm(self.beta[link]);
        }
        if let Some(prox) = p.proximal {
            for a in 0..m {
                self.r[a] += prox.gamma * self.scale[a] * (self.z[a] - prox.x_prev[a]);
            }
        }
        let tip = self.posture.end_m[n];
        let load = p.tip_force_n + self.hand_force_n(p);
        if load != Vector2::zeros() {
            for j in 1..=n {
                self.r[j - 1] -= cross(tip - self.posture.end_m[j - 1], load);
            }
        }

        // Contacts: geometry, Jacobians, forces.
        if jacobian {
            self.jac.resize(c * m, Vector2::zeros());
            self.jac_mat.resize(c * m, Vector2::zeros());
        }
        for (k_idx, cand) in cands.iter_mut().enumerate() {
            cand.normal_force_n = self.z[m + k_idx];
            cand.shear_force_n = self.z[m + c + k_idx];
            geometry(p, &self.posture, &self.beta, cand);
            let force = cand.normal * cand.normal_force_n + cand.tangent * cand.shear_force_n;
            let link = cand.feature.link();
            for j in 1..=link {
                self.r[j - 1] -= cross(cand.point_m - self.posture.end_m[j - 1], force);
            }
            if let Feature::HairTip { link } = cand.feature {
                let v = n + hair_index(p.hair_links, link);
                let rate = self
                    .posture
                    .hair_tip_rate(hair_of(chain, link), link, self.beta[link]);
                self.r[v] -= rate.dot(&force);
            }
            if jacobian {
                let hair_column = match cand.site {
                    Site::HairTip(link) => Some((
                        n + hair_index(p.hair_links, link),
                        self.posture
                            .hair_tip_rate(hair_of(chain, link), link, self.beta[link]),
                    )),
                    Site::Window(_) | Site::Interior(_) => None,
                };
                let cols = &mut self.jac[k_idx * m..(k_idx + 1) * m];
                point_columns(&self.posture, cand.feature.link(), cand.point_m, cols);
                if let Some((v, rate)) = hair_column {
                    cols[v] = rate;
                }
                let cols = &mut self.jac_mat[k_idx * m..(k_idx + 1) * m];
                point_columns(&self.posture, cand.material_link, cand.material_m, cols);
                if let Some((v, rate)) = hair_column {
                    cols[v] = rate;
                }
            }
        }

        // Phi and, if asked, its Jacobian.
        let cn = self.c_n_per_m;
        let len = self.length_m;
        self.phi = DVector::zeros(dim);
        if jacobian {
            self.assemble_hessian(p, m, cands);
            self.big = DMatrix::zeros(dim, dim);
        }
        for a in 0..m {
            let y = self.z[a] - self.r[a] / self.scale[a];
            let bound = if y <= self.lo[a] {
                Some(self.lo[a])
            } else if y >= self.hi[a] {
                Some(self.hi[a])
            } else {
                None
            };
            match bound {
                Some(b) => {
                    self.phi[a] = len * (self.z[a] - b);
                    if jacobian {
                        self.big[(a, a)] = len;
                    }
                }
                None => {
                    let w = len / self.scale[a];
                    self.phi[a] = w * self.r[a];
                    if jacobian {
                        for b in 0..m {
                            self.big[(a, b)] = w * self.hess[(a, b)];
                        }
                        for (k_idx, cand) in cands.iter().enumerate() {
                            let col = self.jac[k_idx * m + a];
                            self.big[(a, m + k_idx)] = -w * col.dot(&cand.normal);
                            self.big[(a, m + c + k_idx)] = -w * col.dot(&cand.tangent);
                        }
                    }
                }
            }
        }
        for (k_idx, cand) in cands.iter_mut().enumerate() {
            let row_n = m + k_idx;
            let row_t = m + c + k_idx;
            let n_min = cand.law.min_normal_n();
            let normal = cand.normal_force_n;
            // Hysteresis: a mode changes only when its condition is violated by more than
            // `hyst` (a force of `c` times 1e-11 m): at a degenerate point (a contact
            // touching with N = 0, or sliding at exactly |T| = B) the plain rule flips the
            // mode back and forth between iterations and Newton's method stalls.
            let hyst = HYSTERESIS_M * cn;
            let y_normal = normal - cn * cand.gap_m - n_min;
            cand.normal_active = if cand.normal_active {
                y_normal > -hyst
            } else {
                y_normal > hyst
            };
            if cand.normal_active {
                self.phi[row_n] = cand.gap_m;
                if jacobian {
                    for b in 0..m {
                        self.big[(row_n, b)] = self.jac[k_idx * m + b].dot(&cand.normal);
                    }
                }
            } else {
                self.phi[row_n] = (normal - n_min) / cn;
                if jacobian {
                    self.big[(row_n, row_n)] = 1.0 / cn;
                }
            }
            let (bound, dbound) = match cand.tresca_n {
                // Tresca: the bound from a given normal force, held fixed in this solve.
                Some(held) => (cand.law.shear_bound(held).0, 0.0),
                None => cand.law.shear_bound(normal),
            };
            let shear = cand.shear_force_n;
            let y = shear - cn * cand.slip_m;
            let margin = if cand.normal_active { hyst } else { 0.0 };
            let slip = match cand.slip {
                _ if !cand.normal_active => {
                    if y >= bound {
                        Slip::Backward
                    } else if y <= -bound {
                        Slip::Forward
                    } else {
                        Slip::Stuck
                    }
                }
                Slip::Stuck if y > bound + margin => Slip::Backward,
                Slip::Stuck if y < -bound - margin => Slip::Forward,
                Slip::Stuck => Slip::Stuck,
                Slip::Backward if y >= bound - margin => Slip::Backward,
                Slip::Forward if y <= -bound + margin => Slip::Forward,
                Slip::Backward | Slip::Forward => {
                    if y >= bound {
                        Slip::Backward
                    } else if y <= -bound {
                        Slip::Forward
                    } else {
                        Slip::Stuck
                    }
                }
            };
            let value = match slip {
                Slip::Backward => shear - bound,
                Slip::Forward => shear + bound,
                Slip::Stuck => f64::NAN,
            };
            cand.slip = slip;
            match slip {
                Slip::Stuck => {
                    self.phi[row_t] = cand.slip_m;
                    if jacobian {
                        for b in 0..m {
                            self.big[(row_t, b)] = self.jac_mat[k_idx * m + b].dot(&cand.tangent);
                        }
                    }
                }
                Slip::Backward | Slip::Forward => {
                    self.phi[row_t] = value / cn;
                    if jacobian {
                        let sign = if slip == Slip::Backward { -1.0 } else { 1.0 };
                        self.big[(row_t, row_t)] = 1.0 / cn;
                        self.big[(row_t, row_n)] = sign * dbound / cn;
                    }
                }
            }
        }
        0.5 * self.phi.norm_squared()
    }

    /// The Hessian of the Lagrangian at `x` with the candidates' forces, reduced to the
    /// tangent space of the active constraints: coordinates strictly inside their range,
    /// moved so that every contact carrying a force keeps touching (and a stuck one does not
    /// slide). Returns `Z^T H Z` for an orthonormal basis `Z` of that space (`0 x 0` when
    /// nothing can move).
    pub fn tangent_hessian(
        &mut self,
        p: &StepProblem<'_>,
        x: &[f64],
        cands: &mut [Candidate],
    ) -> DMatrix<f64> {
        self.prepare(p);
        let m = x.len();
        let c = cands.len();
        self.z = DVector::zeros(m + 2 * c);
        for (a, &v) in x.iter().enumerate() {
            self.z[a] = v;
        }
        for (k, cand) in cands.iter().enumerate() {
            self.z[m + k] = cand.normal_force_n;
            self.z[m + c + k] = cand.shear_force_n;
        }
        self.evaluate(p, m, cands, true);
        let free: Vec<usize> = (0..m)
            .filter(|&a| x[a] > self.lo[a] + 1e-12 && x[a] < self.hi[a] - 1e-12)
            .collect();
        let f = free.len();
        let mut rows: Vec<Vec<f64>> = Vec::new();
        for (k, cand) in cands.iter().enumerate() {
            if !(cand.normal_active && cand.normal_force_n != 0.0) {
                continue;
            }
            rows.push(
                free.iter()
                    .map(|&a| self.jac[k * m + a].dot(&cand.normal))
                    .collect(),
            );
            if cand.slip == Slip::Stuck {
                rows.push(
                    free.iter()
                        .map(|&a| self.jac_mat[k * m + a].dot(&cand.tangent))
                        .collect(),
                );
            }
        }
        // The null space of the constraint rows: eigenvectors of A^T A with (relatively)
        // zero eigenvalue.
        let mut ata = DMatrix::<f64>::zeros(f, f);
        for row in &rows {
            for i in 0..f {
                for j in 0..f {
                    ata[(i, j)] += row[i] * row[j];
                }
            }
        }
        let eig = ata.symmetric_eigen();
        let top = eig.eigenvalues.iter().copied().fold(0.0_f64, f64::max);
        let null: Vec<usize> = (0..f)
            .filter(|&i| eig.eigenvalues[i] <= 1e-10 * top.max(f64::MIN_POSITIVE))
            .collect();
        let mut basis = DMatrix::<f64>::zeros(f, null.len());
        for (col, &i) in null.iter().enumerate() {
            basis.set_column(col, &eig.eigenvectors.column(i));
        }
        let mut h = DMatrix::<f64>::zeros(f, f);
        for (i, &a) in free.iter().enumerate() {
            for (j, &b) in free.iter().enumerate() {
                h[(i, j)] = 0.5 * (self.hess[(a, b)] + self.hess[(b, a)]);
            }
        }
        basis.transpose() * h * basis
    }

    /// The contacts' part of the Hessian of the Lagrangian, `d/dx (-sum_k J_k^T F_k)` at
    /// fixed forces, by central differences: for contacts on curved walls (a sinusoid, a
    /// polyline's corner) and link-interior contacts, whose normals turn and whose contact
    /// points slide along the link as the posture changes (terms of the order of the force
    /// times the wall's radius of curvature, as large as the joint springs).
    fn add_contact_hessian_by_differences(
        &mut self,
        p: &StepProblem<'_>,
        m: usize,
        cands: &[Candidate],
    ) {
        let n = p.chain.n();
        let mut x: Vec<f64> = (0..m).map(|a| self.z[a]).collect();
        let mut plus = vec![0.0; m];
        let mut minus = vec![0.0; m];
        // At `x` itself, evaluated only if a one-sided difference needs it.
        let mut center: Option<Vec<f64>> = None;
        for b in 0..m {
            let h = FD_STEP_RAD;
            let saved = x[b];
            x[b] = saved + h;
            let plus_same = self.contact_force_into(p, n, &x, cands, &mut plus);
            x[b] = saved - h;
            let minus_same = self.contact_force_into(p, n, &x, cands, &mut minus);
            x[b] = saved;
            // A contact next to a kink of its window (a corner or crest crossing a joint:
            // the window's deepest point changes links) is differenced on the side where
            // it stays on its link: the derivative of the piece Newton's method is on.
            if plus_same == minus_same {
                for a in 0..m {
                    self.hess[(a, b)] += (plus[a] - minus[a]) / (2.0 * h);
                }
                continue;
            }
            let at_x = match &center {
                Some(at_x) => at_x,
                None => {
                    let mut at_x = vec![0.0; m];
                    self.contact_force_into(p, n, &x, cands, &mut at_x);
                    center.insert(at_x)
                }
            };
            for a in 0..m {
                self.hess[(a, b)] += if plus_same {
                    (plus[a] - at_x[a]) / h
                } else {
                    (at_x[a] - minus[a]) / h
                };
            }
        }
        // Not symmetrized: the shear forces' terms (a tangent that turns with the contact
        // point on a curved wall) are not a potential's, and their Jacobian is not symmetric.
    }

    /// `-sum_k J_k^T F_k` over the candidates at coordinates `x`, forces held, into `out`;
    /// whether every candidate touches with the same feature as in `cands`.
    fn contact_force_into(
        &mut self,
        p: &StepProblem<'_>,
        n: usize,
        x: &[f64],
        cands: &[Candidate],
        out: &mut [f64],
    ) -> bool {
        let mut same = true;
        let mut theta = std::mem::take(&mut self.theta);
        let mut beta = std::mem::take(&mut self.beta);
        theta[1..=n].copy_from_slice(&x[..n]);
        for (h, &link) in p.hair_links.iter().enumerate() {
            beta[link] = x[n + h];
        }
        let mut posture = std::mem::take(&mut self.fd_posture);
        posture.update(p.chain, p.base_m, &theta);
        out.fill(0.0);
        for cand in cands {
            let mut c = *cand;
            geometry(p, &posture, &beta, &mut c);
            same &= c.feature == cand.feature;
            let force = c.normal * c.normal_force_n + c.tangent * c.shear_force_n;
            let link = c.feature.link();
            for j in 1..=link {
                out[j - 1] -= cross(c.point_m - posture.end_m[j - 1], force);
            }
            if let Feature::HairTip { link } = c.feature {
                let v = n + hair_index(p.hair_links, link);
                out[v] -= posture
                    .hair_tip_rate(hair_of(p.chain, link), link, beta[link])
                    .dot(&force);
            }
        }
        self.fd_posture = posture;
        self.theta = theta;
        self.beta = beta;
        same
    }

    /// The hand spring's force on the tip (zero without a hand); valid after the posture
    /// is updated.
    fn hand_force_n(&self, p: &StepProblem<'_>) -> Vector2<f64> {
        match (p.hand_m, self.posture.end_m.last()) {
            (Some(target), Some(tip)) => (target - tip) * HAND_STIFFNESS * self.c_n_per_m,
            _ => Vector2::zeros(),
        }
    }

    /// `hess = grad^2 U + proximal + sum_forces F . (-grad^2 X)`: the Hessian of the
    /// Lagrangian in the coordinates (the walls' curvature is left out).
    fn assemble_hessian(&mut self, p: &StepProblem<'_>, m: usize, cands: &[Candidate]) {
        let chain = p.chain;
        let n = chain.n();
        self.hess = DMatrix::zeros(m, m);
        let k = chain.stiffness_nm_per_rad();
        for j in 1..=n {
            self.hess[(j - 1, j - 1)] = k[j];
        }
        for (h, &link) in p.hair_links.iter().enumerate() {
            self.hess[(n + h, n + h)] = hair_of(chain, link).stiffness_nm_per_rad;
        }
        if let Some(prox) = p.proximal {
            for a in 0..m {
                self.hess[(a, a)] += prox.gamma * self.scale[a];
            }
        }
        let tip = self.posture.end_m[n];
        let load = p.tip_force_n + self.hand_force_n(p);
        if load != Vector2::zeros() {
            add_point_curvature(&mut self.hess, &self.posture, n, tip, load);
        }
        if p.hand_m.is_some() {
            // The hand spring's k J^T J.
            let k_hand = HAND_STIFFNESS * self.c_n_per_m;
            for a in 0..n {
                let ca = self.posture.column(a + 1, tip);
                for b in 0..n {
                    let cb = self.posture.column(b + 1, tip);
                    self.hess[(a, b)] += k_hand * ca.dot(&cb);
                }
            }
        }
        if cands.iter().any(|c| needs_differences(p, c)) {
            self.add_contact_hessian_by_differences(p, m, cands);
            return;
        }
        for cand in cands {
            let force = cand.normal * cand.normal_force_n + cand.tangent * cand.shear_force_n;
            let link = cand.feature.link();
            add_point_curvature(&mut self.hess, &self.posture, link, cand.point_m, force);
            if let Feature::HairTip { link } = cand.feature {
                let hair = hair_of(chain, link);
                let v = n + hair_index(p.hair_links, link);
                let rate = self.posture.hair_tip_rate(hair, link, self.beta[link]);
                let mixed = -force.dot(&perp(rate));
                for a in 0..link {
                    self.hess[(a, v)] += mixed;
                    self.hess[(v, a)] += mixed;
                }
                let pivot = self.posture.hair_pivot(hair, link);
                self.hess[(v, v)] += force.dot(&(cand.point_m - pivot));
            }
        }
    }
}

/// The least dual regularization of the Newton matrix (relative to `1 / c`).
const DUAL_REGULARIZATION: f64 = 1e-10;

/// The step of the central differences of the contact Hessian, radians.
const FD_STEP_RAD: f64 = 1e-6;

/// Whether a candidate's curvature terms are left to differences: a link-interior contact,
/// or any contact on a wall that is not a straight line.
fn needs_differences(p: &StepProblem<'_>, cand: &Candidate) -> bool {
    matches!(cand.feature, Feature::Link { .. })
        || !matches!(p.walls[cand.wall].shape, crate::WallShape::Line(_))
}

/// The hysteresis of the contact modes, as a length (times `c` it is a force).
const HYSTERESIS_M: f64 = 1e-11;

/// How many past merits the non-monotone line search compares against.
const NONMONOTONE_MEMORY: usize = 6;

/// The hand spring's stiffness in units of the contact scale `c`.
const HAND_STIFFNESS: f64 = 1e3;

/// The first damping tried after a failure, and the limits of the damping.
const MIN_DAMPING: f64 = 1e-8;
const MAX_DAMPING: f64 = 1e4;

fn next_damping(damping: f64) -> f64 {
    if damping < MIN_DAMPING {
        MIN_DAMPING
    } else {
        damping * 100.0
    }
}

/// The contact point, material point, gap, normal, tangent and slip of `cand` in `posture`
/// (hair angles `beta`).
fn geometry(p: &StepProblem<'_>, posture: &Posture, beta: &[f64], cand: &mut Candidate) {
    let wall = &p.walls[cand.wall];
    let point = match cand.site {
        Site::Window(i) => {
            let contact = window_contact(wall, &p.owners[cand.wall], posture, p.chain.n(), i);
            cand.s = contact.s;
            cand.feature = contact.feature;
            cand.material_m = posture.link_point(cand.material_link, cand.material_s);
            (contact.point_m, contact.wall)
        }
        Site::Interior(link) => {
            let contact = interior_contact(wall, posture, link, cand.s);
            cand.s = contact.s;
            cand.feature = Feature::Link { link };
            cand.material_m = posture.link_point(cand.material_link, cand.material_s);
            (contact.point_m, contact.wall)
        }
        Site::HairTip(link) => {
            let hair = hair_of(p.chain, link);
            let x = posture.hair_tip(hair, link, beta[link]);
            cand.s = 1.0 - hair.pivot_from_distal_end_m / p.chain.link_lengths_m()[link];
            cand.feature = Feature::HairTip { link };
            cand.material_m = x;
            (x, wall.signed_distance(&x))
        }
    };
    cand.point_m = point.0;
    cand.gap_m = point.1.gap_m;
    cand.normal = point.1.normal;
    cand.tangent = point.1.tangent;
    cand.slip_m = cand.tangent.dot(&(cand.material_m - cand.start_m));
}

/// The deepest point of window `i` (see [`Site::Window`]) against `wall`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct WindowContact {
    /// [`Feature::Vertex`] at the link end `p_i`, else [`Feature::Link`] of the link it is on.
    pub feature: Feature,
    /// The fraction along that link.
    pub s: f64,
    pub point_m: Vector2<f64>,
    pub wall: WallPoint,
}

/// Who holds each link's interior contact for one step, per wall: `owners[w][link]`.
/// Decided once at the start of a step from where the link's interior contact is: within
/// [`NEAR_END`] of an end, that end's window; farther in, the link's own site; with none,
/// the window of the end nearer the wall (where a crest or corner enters the link). A
/// contact sliding along a link stays with one site for the whole step, so the sites'
/// contact points move continuously and no contact is handed over mid-solve.
pub(crate) fn interior_owners(
    walls: &[Wall],
    posture: &Posture,
    n: usize,
) -> Vec<Vec<InteriorOwner>> {
    walls
        .iter()
        .map(|wall| {
            (0..=n)
                .map(|link| {
                    if link == 0 {
                        return InteriorOwner::Window(0);
                    }
                    if matches!(wall.shape, crate::WallShape::Line(_)) {
                        // No interior contacts on a line: nothing to hold.
                        return InteriorOwner::Window(link - 1);
                    }
                    let (a_m, b_m) = (posture.start_of(link), posture.end_m[link]);
                    match wall.segment_interior_contact(&a_m, &b_m) {
                        Some(sc) if sc.s < NEAR_END => InteriorOwner::Window(link - 1),
                        Some(sc) if sc.s > 1.0 - NEAR_END => InteriorOwner::Window(link),
                        Some(_) => InteriorOwner::Own,
                        None => {
                            if wall.signed_distance(&a_m).gap_m < wall.signed_distance(&b_m).gap_m {
                                InteriorOwner::Window(link - 1)
                            } else {
                                InteriorOwner::Window(link)
                            }
                        }
                    }
                })
                .collect()
        })
        .collect()
}

/// The deepest point of window `i` against `wall`: the link end `p_i`, or a point strictly
/// inside one of its two links where that link's interior contact is, if this window holds
/// it ([`interior_owners`]) and it is deeper (a wall corner or crest poking into the link
/// beside the joint). A link whose deepest point is one of its ends (a flat wall) adds
/// nothing beyond the end itself: on a flat wall every window's contact is its link end,
/// and a link lying flat on a wall bears on the windows of its two ends.
pub(crate) fn window_contact(
    wall: &Wall,
    owners: &[InteriorOwner],
    posture: &Posture,
    n: usize,
    i: usize,
) -> WindowContact {
    let joint = posture.end_m[i];
    let mut best = WindowContact {
        feature: Feature::Vertex { link: i },
        s: 1.0,
        point_m: joint,
        wall: wall.signed_distance(&joint),
    };
    for link in [i, i + 1] {
        if link == 0 || link > n || owners.get(link) != Some(&InteriorOwner::Window(i)) {
            continue;
        }
        if let Some(sc) =
            wall.segment_interior_contact(&posture.start_of(link), &posture.end_m[link])
            && sc.wall.gap_m < best.wall.gap_m
        {
            best = WindowContact {
                feature: Feature::Link { link },
                s: sc.s,
                point_m: sc.point_m,
                wall: sc.wall,
            };
        }
    }
    best
}

/// The link and fraction of a window contact's point: a link end `p_i` is the end of link
/// `i` (`s = 1`).
pub(crate) fn located(contact: &WindowContact) -> (usize, f64) {
    match contact.feature {
        Feature::Vertex { link } => (link, 1.0),
        Feature::Link { link } | Feature::HairTip { link } => (link, contact.s),
    }
}

/// Where the inside of a link meets a wall (see [`Site::Interior`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct InteriorContact {
    /// The fraction along the link.
    pub s: f64,
    pub point_m: Vector2<f64>,
    pub wall: WallPoint,
    /// Whether the link has an interior contact; if not, the point is the link end nearer
    /// the `s` the site had.
    pub inside: bool,
}

/// The interior contact of `link` against `wall` (the deepest interior minimum of the gap
/// along the link: a crest, a convex corner), or, where the link has none (a degenerate
/// case mid-solve: the crest has moved past an end), the end nearer `last_s`, so that the
/// site's point stays continuous. The next step gives the contact to that end's window
/// (see `QuasiStatic::candidates`).
pub(crate) fn interior_contact(
    wall: &Wall,
    posture: &Posture,
    link: usize,
    last_s: f64,
) -> InteriorContact {
    let (a_m, b_m) = (posture.start_of(link), posture.end_m[link]);
    match wall.segment_interior_contact(&a_m, &b_m) {
        Some(sc) => InteriorContact {
            s: sc.s,
            point_m: sc.point_m,
            wall: sc.wall,
            inside: true,
        },
        None => {
            let (s, point_m) = if last_s < 0.5 { (0.0, a_m) } else { (1.0, b_m) };
            InteriorContact {
                s,
                point_m,
                wall: wall.signed_distance(&point_m),
                inside: false,
            }
        }
    }
}

/// Adds `-F . d^2X / dtheta_j dtheta_k = F . (X - p_(max(j,k)-1))` for a force `F` at a point
/// `X` fixed to link `link`.
fn add_point_curvature(
    hess: &mut DMatrix<f64>,
    posture: &Posture,
    link: usize,
    x_m: Vector2<f64>,
    force: Vector2<f64>,
) {
    for a in 0..link {
        let v = force.dot(&(x_m - posture.end_m[a]));
        // Entries whose larger index is a: (a, b) and (b, a) for b <= a.
        for b in 0..a {
            hess[(a, b)] += v;
            hess[(b, a)] += v;
        }
        hess[(a, a)] += v;
    }
}

/// The Jacobian columns (`m` of them) of the point `x_m` fixed to link `link`: joints
/// `1..=link`, zero elsewhere (a hair tip's own column is set by the caller).
fn point_columns(posture: &Posture, link: usize, x_m: Vector2<f64>, cols: &mut [Vector2<f64>]) {
    cols.fill(Vector2::zeros());
    for j in 1..=link {
        cols[j - 1] = posture.column(j, x_m);
    }
}

/// The hair on `link`: callers only ask for links that carry one.
pub(crate) fn hair_of(chain: &Chain, link: usize) -> &Hair {
    match chain.hairs().get(link) {
        Some(Some(hair)) => hair,
        // Candidates and hair coordinates are built from the chain's own hairs.
        _ => unreachable_hair(link),
    }
}

#[cold]
fn unreachable_hair(link: usize) -> ! {
    panic!("internal error: no hair on link {link}")
}

/// The position of `link` in `hair_links`.
fn hair_index(hair_links: &[usize], link: usize) -> usize {
    hair_links
        .iter()
        .position(|&l| l == link)
        .unwrap_or_else(|| unreachable_hair(link))
}

#[cfg(test)]
mod tests {
    //! The semismooth Jacobian against central differences of `Phi`, piece by piece.
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::{Line, SolidSide, Surface, SurfaceMap};

    fn chain() -> Chain {
        Chain::builder(4)
            .link_length_m(0.04)
            .base_angle_rad(0.5)
            .stiffnesses_nm_per_rad(vec![0.05, 0.03, 0.02, 0.01])
            .hair(4, Hair::seed(0.04))
            .hair(3, Hair::seed(0.04))
            .build()
            .unwrap()
    }

    /// Compares `big` with central differences of `phi` at `z` (steps of `step`), for every
    /// column.
    fn check_jacobian(
        p: &StepProblem<'_>,
        m: usize,
        cands: &mut [Candidate],
        z: &DVector<f64>,
        step: f64,
    ) {
        let mut ssn = Ssn::default();
        ssn.prepare(p);
        ssn.z = z.clone();
        ssn.evaluate(p, m, cands, true);
        let big = ssn.big.clone();
        let flags: Vec<(bool, Slip)> = cands.iter().map(|c| (c.normal_active, c.slip)).collect();
        let dim = z.len();
        for col in 0..dim {
            let h = step;
            let mut plus = z.clone();
            plus[col] += h;
            let mut minus = z.clone();
            minus[col] -= h;
            let mut cp = cands.to_vec();
            ssn.z = plus;
            ssn.evaluate(p, m, &mut cp, false);
            let fp = ssn.phi.clone();
            let same_plus: Vec<(bool, Slip)> =
                cp.iter().map(|c| (c.normal_active, c.slip)).collect();
            let mut cm = cands.to_vec();
            ssn.z = minus;
            ssn.evaluate(p, m, &mut cm, false);
            let fm = ssn.phi.clone();
            let same_minus: Vec<(bool, Slip)> =
                cm.iter().map(|c| (c.normal_active, c.slip)).collect();
            assert_eq!(flags, same_plus, "column {col} crosses a kink");
            assert_eq!(flags, same_minus, "column {col} crosses a kink");
            for row in 0..dim {
                let fd = (fp[row] - fm[row]) / (2.0 * h);
                let an = big[(row, col)];
                assert!(
                    (fd - an).abs() <= 1e-5 * (1.0 + an.abs().max(fd.abs())),
                    "d phi[{row}] / d z[{col}]: analytic {an}, differences {fd}"
                );
            }
        }
    }

    #[test]
    fn jacobian_matches_differences_for_vertex_link_and_hair_contacts() {
        let chain = chain();
        let wall = Wall::new(
            Line::new(Vector2::new(0.0, 0.12), 0.1, SolidSide::Left).unwrap(),
            SurfaceMap::uniform(Surface::Rough {
                mu: 0.3,
                hold_shear_n: 0.5,
                hold_tension_n: 0.2,
            })
            .unwrap(),
        );
        let walls = [wall];
        let owners = vec![vec![
            InteriorOwner::Window(0),
            InteriorOwner::Window(0),
            InteriorOwner::Window(1),
            InteriorOwner::Window(2),
            InteriorOwner::Window(3),
        ]];
        let hair_links = [3, 4];
        let beta = vec![0.0, 0.0, 0.0, 0.6, 0.5];
        for (law_tip, law_hair, normal_n, shear_n) in [
            (
                FrictionLaw::Coulomb { mu: 0.3 },
                FrictionLaw::Coulomb { mu: 0.3 },
                0.2,
                0.01,
            ),
            (
                FrictionLaw::Coulomb { mu: 0.3 },
                FrictionLaw::Coulomb { mu: 0.3 },
                0.2,
                0.5,
            ),
            (
                FrictionLaw::Coulomb { mu: 0.3 },
                FrictionLaw::Anchored {
                    hold_shear_n: 0.5,
                    hold_tension_n: 0.2,
                },
                -0.1,
                0.05,
            ),
        ] {
            let p = StepProblem {
                chain: &chain,
                walls: &walls,
                tip_force_n: Vector2::new(0.01, -0.02),
                base_m: Vector2::new(0.001, 0.0),
                hair_links: &hair_links,
                hair_beta_rad: &beta,
                proximal: None,
                owners: &owners,
                hand_m: Some(Vector2::new(0.1, 0.1)),
                tolerance_m: 1e-12,
                acceptable_m: 1e-12,
                max_departure_rad: 1.0,
                max_iterations: 10,
            };
            let x = [0.2, 0.3, 0.25, 0.4, 0.6, 0.5];
            let m = x.len();
            let mut cands = vec![
                Candidate::new(Site::Window(4), 0, law_tip, 4, 1.0, Vector2::new(0.1, 0.1)),
                Candidate::new(
                    Site::HairTip(4),
                    0,
                    law_hair,
                    4,
                    1.0,
                    Vector2::new(0.09, 0.11),
                ),
                Candidate::new(
                    Site::Window(2),
                    0,
                    law_tip,
                    2,
                    1.0,
                    Vector2::new(0.05, 0.05),
                ),
            ];
            let c = cands.len();
            let mut z = DVector::zeros(m + 2 * c);
            for (a, v) in x.iter().enumerate() {
                z[a] = *v;
            }
            for k in 0..c {
                z[m + k] = normal_n * (k as f64 + 1.0);
                z[m + c + k] = shear_n * (k as f64 + 1.0);
            }
            check_jacobian(&p, m, &mut cands, &z, 1e-7);
        }
    }

    /// A sinusoid's crest poking into a link's interior, stuck and sliding: the curvature
    /// terms come from differences of the contact forces, the rest is analytic.
    #[test]
    fn jacobian_matches_differences_for_a_crest_inside_a_link() {
        let chain = Chain::builder(4)
            .link_length_m(0.04)
            .base_angle_rad(0.5)
            .stiffnesses_nm_per_rad(vec![0.05, 0.03, 0.02, 0.01])
            .build()
            .unwrap();
        let x = [0.2, 0.3, 0.25, 0.4];
        let mut theta = vec![0.5];
        theta.extend_from_slice(&x);
        let base = Vector2::new(0.001, 0.0);
        let mut posture = Posture::default();
        posture.update(&chain, base, &theta);
        // Link 3 from p_2 to p_3; the crest (g = -a at t = 0, phase -pi/2) 0.1 mm past it.
        let (a_m, b_m) = (posture.end_m[2], posture.end_m[3]);
        let along = (b_m - a_m).normalize();
        let left = Vector2::new(-along.y, along.x);
        let amplitude = 0.01;
        let mid = 0.5 * (a_m + b_m) + 0.2 * 0.04 * along;
        let sine = crate::Sinusoid::new(
            mid + left * (amplitude - 1e-4),
            along.y.atan2(along.x),
            amplitude,
            2.8,
            -std::f64::consts::FRAC_PI_2,
            SolidSide::Left,
        )
        .unwrap();
        for (normal_n, shear_n) in [(0.2, 0.01), (0.2, 0.5), (0.2, -0.5)] {
            let wall = Wall::new(
                sine.clone(),
                SurfaceMap::uniform(Surface::Smooth { mu: 0.3 }).unwrap(),
            );
            let walls = [wall];
            // The crest 70% along link 3: the link's own site.
            let owners = interior_owners(&walls, &posture, chain.n());
            assert_eq!(owners[0][3], InteriorOwner::Own);
            let p = StepProblem {
                chain: &chain,
                walls: &walls,
                tip_force_n: Vector2::new(0.0, 0.0),
                base_m: base,
                hair_links: &[],
                hair_beta_rad: &[0.0; 5],
                proximal: None,
                owners: &owners,
                hand_m: None,
                tolerance_m: 1e-12,
                acceptable_m: 1e-12,
                max_departure_rad: 1.0,
                max_iterations: 10,
            };
            let mut cands = vec![Candidate::new(
                Site::Interior(3),
                0,
                FrictionLaw::Coulomb { mu: 0.3 },
                3,
                0.6,
                mid - left * 2e-4,
            )];
            let mut probe = cands[0];
            geometry(&p, &posture, &[0.0; 5], &mut probe);
            assert!(
                matches!(probe.feature, Feature::Link { link: 3 }),
                "{:?}",
                probe.feature
            );
            let m = x.len();
            let mut z = DVector::zeros(m + 2);
            for (i, v) in x.iter().enumerate() {
                z[i] = *v;
            }
            z[m] = normal_n;
            z[m + 1] = shear_n;
            // Steps of 1e-6 rad, the contact Hessian's own: below about 1e-7 rad the
            // differences of Phi change slope by a relative 1.6e-4 (the sinusoid's nearest
            // point search at that scale), which the test would report as a mismatch.
            check_jacobian(&p, m, &mut cands, &z, 1e-6);
        }
    }
}
