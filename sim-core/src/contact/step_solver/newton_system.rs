//! The semismooth Newton system of a step ([`super::equations`]) with exact derivatives,
//! built in the chain's `O(n)` structure and solved by
//! [`crate::statics::equilibrium::bordered::BorderedSystem`] in `O(n k + k^3)` (`k` the pairs'
//! force unknowns and a few rank-one terms).
//!
//! # The Jacobian
//! On the current modes, a free coordinate's row is `H dx - sum_k (J_k^T n_k dN_k +
//! J_k^T t_k dT_k) = -r`, with `H = dr/dx` at fixed forces:
//! - the springs (and the proximal term, and Levenberg-Marquardt damping): diagonal;
//! - every point force `F` at `X` on link `L` (contacts, the tip load): `F . (X - p_(m-1))`
//!   in entry `(i, j)` with `m = max(i, j) <= L`: together the semiseparable part `a_m`;
//! - per pair, rank-one terms from its normal turning and its point sliding
//!   ([`crate::contact::geometry::Turn`]): against a surface `-rate J^T (N t - T n) (J^T t)^T`; a
//!   feature on a link `-(R90 dir . F) e_L v_slide^T - J^T (R90 F) e_L^T` (`e_L` the
//!   indicator of joints `<= L`, `v_slide . dx = l ds`); the hand spring `k J_tip^T J_tip`
//!   (rank two);
//! - hair angles: the mixed terms `-(R90 rate . F)` with the joints of their link and
//!   `F . (X - pivot)` on their own diagonal.
//!
//! An active normal row is `J_k^T n_k . dx = -gap_k`, a stuck row `grad u_k . dx = -u_k`
//! (`grad u` of the material point, plus the tangent's turning), the rest fix the force
//! increments (`dN = -N` for a pair letting go, `dT = -(T -+ B) +- B' dN` for one sliding)
//! and are substituted. What remains unknown besides the joints (hair angles, active `dN`,
//! stuck `dT`, one per rank-one term) is the border of the bordered system.

// Joint `j` (1-based), its coordinate `j - 1` and the link ends `p_(j-1)` are indexed
// together throughout: index loops say what they do here.
#![allow(clippy::needless_range_loop)]

use nalgebra::Vector2;

use super::equations::{Equations, StepProblem, hair_index, sliding_bound_of};
use crate::contact::feature::Slip;
use crate::contact::geometry::{PairGeometry, Turn, generalized, hair_of};
use crate::contact::pair::Pair;
use crate::contact::posture::{cross, perp};
use crate::statics::equilibrium::bordered::{BorderedSystem, SolveStats};

/// A least-squares step leaving more than this fraction of the constraint rows' right-hand
/// side means the linearized constraints are inconsistent.
const INCONSISTENT: f64 = 1e-2;

/// The dual regularization of inconsistent constraints, relative to `1 / c`.
const DUAL_REGULARIZATION: f64 = 1e-10;

/// The Newton system's scratch space, reused from iteration to iteration.
#[derive(Debug, Default)]
pub(super) struct NewtonSystem {
    sys: BorderedSystem,
    /// Per pair, `J^T n` and `J^T t` on the joints (`n` entries each) and on the hair.
    gn: Vec<f64>,
    gt: Vec<f64>,
    gn_hair: Vec<f64>,
    gt_hair: Vec<f64>,
    col_n: Vec<Option<usize>>,
    col_t: Vec<Option<usize>>,
    x: Vec<f64>,
    w: Vec<f64>,
    tmp: Vec<f64>,
    ranks: Vec<RankOne>,
    /// Linear solves that fell back to the dense factorization, and that were rank
    /// deficient, since the counters were last read.
    pub(super) dense_solves: usize,
    pub(super) truncated_solves: usize,
}

/// One border unknown standing for a rank-one term `u v^T` of `H`.
#[derive(Debug)]
struct RankOne {
    u: Vec<f64>,
    u_hair: f64,
    v: Vec<f64>,
    v_hair: f64,
    /// The hair coordinate the `_hair` entries belong to.
    hair: Option<usize>,
}

impl NewtonSystem {
    /// The Newton direction `dz` (`m + 2c`) at the unknowns `eq` was last evaluated at, with
    /// Levenberg-Marquardt `damping` (relative to each coordinate's scale); `None` if the
    /// system is singular or not finite.
    pub fn direction(
        &mut self,
        eq: &Equations,
        p: &StepProblem<'_>,
        pairs: &[Pair],
        damping: f64,
        dz: &mut Vec<f64>,
    ) -> Option<SolveStats> {
        let chain = p.chain;
        let n = chain.n();
        let nh = p.hair_links.len();
        let m = n + nh;
        let c = pairs.len();
        let posture = &eq.posture;

        self.prepare_terms(eq, p, pairs);
        let ranks = std::mem::take(&mut self.ranks);
        // Border columns: hair angles, active dN, stuck dT, rank-one terms.
        self.col_n.clear();
        self.col_t.clear();
        let mut next = nh;
        for pair in pairs {
            self.col_n.push(pair.normal_active.then(|| {
                next += 1;
                next - 1
            }));
            self.col_t.push((pair.slip == Slip::Stuck).then(|| {
                next += 1;
                next - 1
            }));
        }
        let first_rank = next;
        let kdim = next + ranks.len();
        self.sys.reset(n, kdim);
        let sys = &mut self.sys;

        // The chain block: springs, damping, proximal term; the semiseparable part.
        let k = chain.stiffness_nm_per_rad();
        let prox = p.proximal.map_or(0.0, |q| q.gamma);
        for j in 0..n {
            sys.diagonal[j] = k[j + 1] + (prox + damping) * eq.scale[j];
        }
        let mut force = Vector2::zeros();
        let mut work = 0.0;
        for j in (0..n).rev() {
            force += eq.link_force_n[j + 1];
            work += eq.link_work_nm[j + 1];
            sys.coefficients[j] = work - force.dot(&posture.end_m[j]);
        }
        for j in 0..n {
            match eq.held[j] {
                Some(b) => sys.held[j] = Some(b - eq.z[j]),
                None => sys.rhs_x[j] = -eq.r[j],
            }
        }
        // Hair rows and columns.
        let hair_row_free = |v: usize| eq.held[v].is_none();
        for h in 0..nh {
            let v = n + h;
            let (link, mixed, diag) = hair_terms(eq, p, pairs, h);
            for j in 0..link.min(n) {
                sys.p_col(h)[j] += mixed;
                if hair_row_free(v) {
                    sys.q_row(h)[j] += mixed;
                }
            }
            match eq.held[v] {
                Some(b) => {
                    *sys.r_at(h, h) = 1.0;
                    sys.rhs_w[h] = b - eq.z[v];
                }
                None => {
                    *sys.r_at(h, h) += diag + (prox + damping) * eq.scale[v];
                    sys.rhs_w[h] = -eq.r[v];
                }
            }
        }

        // The pairs.
        reset(&mut self.tmp, n);
        for (kk, pair) in pairs.iter().enumerate() {
            let hair_col = pair
                .key
                .hair_link()
                .map(|link| hair_index(p.hair_links, link));
            let hair_row = hair_col.filter(|&h| hair_row_free(n + h));
            let (gn, gt) = (
                &self.gn[kk * n..(kk + 1) * n],
                &self.gt[kk * n..(kk + 1) * n],
            );
            let (gn_h, gt_h) = (self.gn_hair[kk], self.gt_hair[kk]);
            let (bound, dbound) = sliding_bound_of(pair);
            let sign = match pair.slip {
                Slip::Backward => 1.0,
                Slip::Forward => -1.0,
                Slip::Stuck => 0.0,
            };
            // dT of a sliding pair: tau0 + sign B' dN.
            let tau0 = -(pair.shear_force_n - sign * bound);
            let slope = sign * dbound;
            // The normal.
            let dn_known = match self.col_n[kk] {
                Some(col) => {
                    let merged = if pair.slip == Slip::Stuck { 0.0 } else { slope };
                    for j in 0..n {
                        sys.p_col(col)[j] = -gn[j] - merged * gt[j];
                    }
                    if let Some(h) = hair_row {
                        *sys.r_at(h, col) += -(gn_h + merged * gt_h);
                    }
                    sys.q_row(col).copy_from_slice(gn);
                    if let Some(h) = hair_col {
                        *sys.r_at(col, h) += gn_h;
                    }
                    // The dual side of the damping: where the constraints themselves are
                    // nearly singular (a straight chain pressed end-on: buckling), the
                    // damping relaxes them in the step, never in the solution.
                    *sys.r_at(col, col) = -damping / eq.c_n_per_m;
                    sys.rhs_w[col] = -pair.geo.gap_m;
                    None
                }
                None => {
                    let dn = -(pair.normal_force_n - pair.law.min_normal_n());
                    add_known(sys, gn, gn_h, hair_row, dn);
                    Some(dn)
                }
            };
            // The tangent.
            match self.col_t[kk] {
                Some(col) => {
                    for j in 0..n {
                        sys.p_col(col)[j] = -gt[j];
                    }
                    if let Some(h) = hair_row {
                        *sys.r_at(h, col) += -gt_h;
                    }
                    let slip_hair = slip_gradient(pair, posture, n, gt, gt_h, &mut self.tmp);
                    sys.q_row(col).copy_from_slice(&self.tmp);
                    if let Some(h) = hair_col {
                        *sys.r_at(col, h) += slip_hair;
                    }
                    *sys.r_at(col, col) = -damping / eq.c_n_per_m;
                    sys.rhs_w[col] = -pair.slip_m;
                }
                None => {
                    let dt = tau0 + dn_known.map_or(0.0, |dn| slope * dn);
                    add_known(sys, gt, gt_h, hair_row, dt);
                }
            }
        }

        // The rank-one terms: u in the rows, v . dz - w = 0 as their own rows.
        for (i, rank) in ranks.iter().enumerate() {
            let col = first_rank + i;
            sys.p_col(col).copy_from_slice(&rank.u);
            sys.q_row(col).copy_from_slice(&rank.v);
            *sys.r_at(col, col) = -1.0;
            if let Some(v) = rank.hair {
                let h = v - n;
                if hair_row_free(v) {
                    *sys.r_at(h, col) += rank.u_hair;
                }
                *sys.r_at(col, h) += rank.v_hair;
            }
        }

        self.ranks = ranks;
        // Solve and map back to dz.
        reset(&mut self.x, n);
        reset(&mut self.w, kdim);
        let mut stats = self.sys.solve(&mut self.x, &mut self.w)?;
        if stats.truncated && stats.border_residual > INCONSISTENT {
            // The linearized constraints cannot all hold (stuck contacts that the joints
            // free of their stops cannot keep in place): regularize them, so that the forces
            // grow toward the cone's edge and the modes change, instead of a least-squares
            // step that leaves the residual where it is.
            let dual = damping.max(DUAL_REGULARIZATION) / eq.c_n_per_m;
            for (kk, _) in pairs.iter().enumerate() {
                for col in [self.col_n[kk], self.col_t[kk]].into_iter().flatten() {
                    *self.sys.r_at(col, col) = -dual;
                }
            }
            stats = self.sys.solve(&mut self.x, &mut self.w)?;
        }
        if stats.dense {
            self.dense_solves += 1;
        }
        if stats.truncated {
            self.truncated_solves += 1;
        }
        dz.clear();
        dz.resize(m + 2 * c, 0.0);
        dz[..n].copy_from_slice(&self.x);
        dz[n..m].copy_from_slice(&self.w[..nh]);
        for (kk, pair) in pairs.iter().enumerate() {
            let (bound, dbound) = sliding_bound_of(pair);
            let sign = match pair.slip {
                Slip::Backward => 1.0,
                Slip::Forward => -1.0,
                Slip::Stuck => 0.0,
            };
            let dn = match self.col_n[kk] {
                Some(col) => self.w[col],
                None => -(pair.normal_force_n - pair.law.min_normal_n()),
            };
            let dt = match self.col_t[kk] {
                Some(col) => self.w[col],
                None => -(pair.shear_force_n - sign * bound) + sign * dbound * dn,
            };
            dz[m + kk] = dn;
            dz[m + c + kk] = dt;
        }
        dz.iter().all(|v| v.is_finite()).then_some(stats)
    }

    /// `H` (the Jacobian of `r` in the coordinates at fixed forces, `m x m`, no damping) at
    /// the point `eq` was last evaluated at: for the stability of a state.
    pub fn dense_hessian(
        &mut self,
        eq: &Equations,
        p: &StepProblem<'_>,
        pairs: &[Pair],
    ) -> nalgebra::DMatrix<f64> {
        self.prepare_terms(eq, p, pairs);
        let chain = p.chain;
        let n = chain.n();
        let nh = p.hair_links.len();
        let m = n + nh;
        let posture = &eq.posture;
        let mut hess = nalgebra::DMatrix::<f64>::zeros(m, m);
        let k = chain.stiffness_nm_per_rad();
        let prox = p.proximal.map_or(0.0, |q| q.gamma);
        let mut coefficients = vec![0.0; n];
        let mut force = Vector2::zeros();
        let mut work = 0.0;
        for j in (0..n).rev() {
            force += eq.link_force_n[j + 1];
            work += eq.link_work_nm[j + 1];
            coefficients[j] = work - force.dot(&posture.end_m[j]);
        }
        for i in 0..n {
            for j in 0..n {
                hess[(i, j)] = coefficients[i.max(j)];
            }
            hess[(i, i)] += k[i + 1] + prox * eq.scale[i];
        }
        for h in 0..nh {
            let v = n + h;
            let (link, mixed, diag) = hair_terms(eq, p, pairs, h);
            for j in 0..link.min(n) {
                hess[(j, v)] += mixed;
                hess[(v, j)] += mixed;
            }
            hess[(v, v)] += diag + prox * eq.scale[v];
        }
        for rank in &self.ranks {
            for i in 0..m {
                let ui = if i < n {
                    rank.u[i]
                } else if rank.hair == Some(i) {
                    rank.u_hair
                } else {
                    0.0
                };
                if ui == 0.0 {
                    continue;
                }
                for j in 0..m {
                    let vj = if j < n {
                        rank.v[j]
                    } else if rank.hair == Some(j) {
                        rank.v_hair
                    } else {
                        0.0
                    };
                    hess[(i, j)] += ui * vj;
                }
            }
        }
        hess
    }

    /// The constraint gradients of the pairs that carry a force and touch, on the
    /// coordinates (`m` entries each): the normal's, and the slip's for a stuck pair.
    pub fn active_constraint_rows(
        &mut self,
        eq: &Equations,
        p: &StepProblem<'_>,
        pairs: &[Pair],
    ) -> Vec<Vec<f64>> {
        self.prepare_terms(eq, p, pairs);
        let n = p.chain.n();
        let m = n + p.hair_links.len();
        let mut rows = Vec::new();
        reset(&mut self.tmp, n);
        for (k, pair) in pairs.iter().enumerate() {
            if !(pair.normal_active && pair.normal_force_n != 0.0) {
                continue;
            }
            let hair = pair
                .key
                .hair_link()
                .map(|link| n + hair_index(p.hair_links, link));
            let mut row = vec![0.0; m];
            row[..n].copy_from_slice(&self.gn[k * n..(k + 1) * n]);
            if let Some(v) = hair {
                row[v] = self.gn_hair[k];
            }
            rows.push(row);
            if pair.slip == Slip::Stuck {
                let mut row = vec![0.0; m];
                let gt = &self.gt[k * n..(k + 1) * n];
                let hair_entry =
                    slip_gradient(pair, &eq.posture, n, gt, self.gt_hair[k], &mut self.tmp);
                row[..n].copy_from_slice(&self.tmp);
                if let Some(v) = hair {
                    row[v] = hair_entry;
                }
                rows.push(row);
            }
        }
        rows
    }

    /// The pairs' generalized normals and tangents and the rank-one terms of `H` at the
    /// point `eq` was last evaluated at.
    fn prepare_terms(&mut self, eq: &Equations, p: &StepProblem<'_>, pairs: &[Pair]) {
        let chain = p.chain;
        let n = chain.n();
        let c = pairs.len();
        let posture = &eq.posture;
        // The pairs' generalized normals and tangents.
        reset(&mut self.gn, c * n);
        reset(&mut self.gt, c * n);
        reset(&mut self.gn_hair, c);
        reset(&mut self.gt_hair, c);
        for (k, pair) in pairs.iter().enumerate() {
            self.gn_hair[k] = generalized(
                posture,
                &pair.geo,
                pair.geo.normal,
                &mut self.gn[k * n..(k + 1) * n],
            );
            self.gt_hair[k] = generalized(
                posture,
                &pair.geo,
                pair.geo.tangent,
                &mut self.gt[k * n..(k + 1) * n],
            );
        }

        // The rank-one terms.
        let mut ranks = std::mem::take(&mut self.ranks);
        ranks.clear();
        for (k, pair) in pairs.iter().enumerate() {
            let force = pair.force_n();
            if force == Vector2::zeros() {
                continue;
            }
            let hair = pair
                .key
                .hair_link()
                .map(|link| n + hair_index(p.hair_links, link));
            let (nf, tf) = (pair.normal_force_n, pair.shear_force_n);
            let (gn, gt) = (&self.gn[k * n..(k + 1) * n], &self.gt[k * n..(k + 1) * n]);
            match pair.geo.turn {
                Turn::Field { rate_per_m } if rate_per_m != 0.0 => {
                    ranks.push(RankOne {
                        u: (0..n)
                            .map(|j| -rate_per_m * (nf * gt[j] - tf * gn[j]))
                            .collect(),
                        u_hair: -rate_per_m * (nf * self.gt_hair[k] - tf * self.gn_hair[k]),
                        v: gt.to_vec(),
                        v_hair: self.gt_hair[k],
                        hair,
                    });
                }
                Turn::Field { .. } => {}
                Turn::WithLink {
                    dir,
                    slide_m_per_rad,
                    ..
                } => {
                    let link = pair.geo.link;
                    let e = |j: usize| if j < link { 1.0 } else { 0.0 };
                    let a = posture.start_of(link);
                    // The slide: -(R90 dir . F) e_L (l ds), l ds = slide dphi_L - dir . da.
                    let push = perp(dir).dot(&force);
                    ranks.push(RankOne {
                        u: (0..n).map(|j| -push * e(j)).collect(),
                        u_hair: 0.0,
                        v: (0..n)
                            .map(|j| {
                                let da = if j + 1 < link {
                                    cross(a - posture.end_m[j], dir)
                                } else {
                                    0.0
                                };
                                slide_m_per_rad * e(j) - da
                            })
                            .collect(),
                        v_hair: 0.0,
                        hair: None,
                    });
                    // The turn: -J^T (R90 F) e_L^T.
                    let mut u = vec![0.0; n];
                    generalized(posture, &pair.geo, perp(force), &mut u);
                    for v in &mut u {
                        *v = -*v;
                    }
                    ranks.push(RankOne {
                        u,
                        u_hair: 0.0,
                        v: (0..n).map(e).collect(),
                        v_hair: 0.0,
                        hair: None,
                    });
                }
            }
        }
        if p.hand_m.is_some() {
            let k_hand = eq.hand_stiffness_n_per_m;
            let tip = posture.end_m[n];
            for axis in [Vector2::x(), Vector2::y()] {
                let v: Vec<f64> = (0..n)
                    .map(|j| cross(tip - posture.end_m[j], axis))
                    .collect();
                ranks.push(RankOne {
                    u: v.iter().map(|x| k_hand * x).collect(),
                    u_hair: 0.0,
                    v,
                    v_hair: 0.0,
                    hair: None,
                });
            }
        }

        self.ranks = ranks;
    }
}

/// Hair coordinate `h`'s terms of `H`: its link, the mixed entry with each joint of the
/// link (`-(R90 rate . F)` summed over its tip's pairs, the same for every such joint) and
/// its diagonal (spring, `F . (X - pivot)`).
fn hair_terms(eq: &Equations, p: &StepProblem<'_>, pairs: &[Pair], h: usize) -> (usize, f64, f64) {
    let link = p.hair_links[h];
    let hair = hair_of(p.chain, link);
    let pivot = eq.posture.hair_pivot(hair, link);
    let mut mixed = 0.0;
    let mut diag = hair.spring_hessian_nm_per_rad(eq.beta[link]);
    for pair in pairs.iter().filter(|q| q.key.hair_link() == Some(link)) {
        if let Some(rate) = pair.geo.hair_rate {
            let force = pair.force_n();
            mixed -= perp(rate).dot(&force);
            diag += force.dot(&(pair.geo.point_m - pivot));
        }
    }
    (link, mixed, diag)
}

/// Moves a known force increment `d` along the generalized direction `(g, g_hair)` to the
/// right-hand sides (the rows hold `-g d`).
fn add_known(sys: &mut BorderedSystem, g: &[f64], g_hair: f64, hair_row: Option<usize>, d: f64) {
    if d == 0.0 {
        return;
    }
    for j in 0..g.len() {
        sys.rhs_x[j] += g[j] * d;
    }
    if let Some(h) = hair_row {
        sys.rhs_w[h] += g_hair * d;
    }
}

/// The gradient of a pair's slip `u = t . (X_mat - X_start)` on the joints (into `out`) and
/// its hair entry: the material point's Jacobian along `t`, plus the tangent's turning.
fn slip_gradient(
    pair: &Pair,
    posture: &crate::contact::posture::Posture,
    n: usize,
    gt: &[f64],
    gt_hair: f64,
    out: &mut [f64],
) -> f64 {
    let delta = pair.material_m - pair.start_m;
    match pair.geo.turn {
        Turn::Field { rate_per_m } => {
            // The material point is the contact point; dt = -rate (t . dX) n.
            let f = 1.0 - rate_per_m * pair.geo.normal.dot(&delta);
            for j in 0..n {
                out[j] = f * gt[j];
            }
            f * gt_hair
        }
        Turn::WithLink { .. } => {
            // The material point of the link; dt = R90 t dphi_L.
            let material = PairGeometry {
                link: pair.material_link,
                point_m: pair.material_m,
                hair_rate: None,
                ..pair.geo
            };
            generalized(posture, &material, pair.geo.tangent, out);
            let turn = delta.dot(&perp(pair.geo.tangent));
            for j in 0..n.min(pair.geo.link) {
                out[j] += turn;
            }
            0.0
        }
    }
}

fn reset(v: &mut Vec<f64>, len: usize) {
    v.clear();
    v.resize(len, 0.0);
}

#[cfg(test)]
mod tests {
    //! The closed-form derivatives against central differences of the equations
    //! themselves, on walls of every shape, pairs of every kind, hairs and a hand.
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::contact::feature::FrictionLaw;
    use crate::contact::pair::{ChainPoint, PairKey};
    use crate::contact::posture::Posture;
    use crate::walls::ConvexFeature;
    use crate::{Chain, Hair, Line, Polyline, Sinusoid, SolidSide, Surface, SurfaceMap, Wall};

    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((*state >> 11) as f64) / ((1u64 << 53) as f64)
    }

    struct Case {
        chain: Chain,
        pieces: Vec<Wall>,
        x: Vec<f64>,
        hair_links: Vec<usize>,
        beta: Vec<f64>,
        pairs: Vec<Pair>,
        hand: Option<Vector2<f64>>,
    }

    /// A chain of `n` links bent at random, walls placed so that every kind of pair exists,
    /// and pairs with random forces and modes.
    fn case(seed: u64, wall_kind: usize) -> Case {
        let mut s = seed;
        let n = 3 + (lcg(&mut s) * 5.0) as usize;
        let k: Vec<f64> = (0..n).map(|_| 0.005 + 0.05 * lcg(&mut s)).collect();
        let mut builder = Chain::builder(n)
            .link_length_m(0.04)
            .base_angle_rad(0.3 + 0.5 * lcg(&mut s))
            .stiffnesses_nm_per_rad(k);
        builder = builder
            .hair(n, Hair::seed(0.04))
            .hair(n - 1, Hair::seed(0.04));
        let chain = builder.build().unwrap();
        let mut x: Vec<f64> = (0..n).map(|_| 0.6 * (lcg(&mut s) - 0.5)).collect();
        let hair_links = vec![n - 1, n];
        let mut beta = vec![0.0; n + 1];
        for &l in &hair_links {
            beta[l] = 0.2 + 0.4 * lcg(&mut s);
            x.push(beta[l]);
        }
        let mut theta = vec![chain.base_angle_rad()];
        theta.extend_from_slice(&x[..n]);
        let mut posture = Posture::default();
        posture.update(&chain, Vector2::zeros(), &theta);
        // A wall through the middle of the chain.
        let mid = 0.5 * (posture.end_m[n / 2] + posture.end_m[n / 2 + 1]);
        let along = (posture.end_m[n] - posture.end_m[0]).normalize();
        let angle = along.y.atan2(along.x) + 0.2 * (lcg(&mut s) - 0.5);
        let surface = SurfaceMap::uniform(Surface::Smooth { mu: 0.4 }).unwrap();
        let wall = match wall_kind {
            0 => Wall::new(
                Line::new(mid + Vector2::new(0.0, 0.01), angle, SolidSide::Left).unwrap(),
                surface,
            ),
            1 => {
                // A bump with corners under links.
                let t = Vector2::new(angle.cos(), angle.sin());
                let nrm = Vector2::new(-t.y, t.x);
                let o = mid + nrm * 0.004;
                Wall::new(
                    Polyline::new(
                        vec![
                            o - t * 0.2 + nrm * 0.03,
                            o - t * 0.05,
                            o + t * 0.013,
                            o + t * 0.08 + nrm * 0.02,
                        ],
                        SolidSide::Left,
                    )
                    .unwrap(),
                    surface,
                )
            }
            _ => Wall::new(
                Sinusoid::new(
                    mid + Vector2::new(0.0, 0.012),
                    angle,
                    0.006,
                    6.0 + 4.0 * lcg(&mut s),
                    lcg(&mut s) * 6.0,
                    SolidSide::Left,
                )
                .unwrap(),
                surface,
            ),
        };
        let pieces = vec![wall];
        let mut pairs = Vec::new();
        let law = FrictionLaw::Coulomb { mu: 0.4 };
        for link in 1..=n {
            let key = PairKey::point(ChainPoint::Vertex(link), 0);
            pairs.push(Pair::new(key, law, link, 1.0, posture.end_m[link]));
            let mut found = Vec::new();
            pieces[0].shape.features_near_segment(
                &posture.start_of(link),
                &posture.end_m[link],
                1.0,
                &mut found,
            );
            for fc in found.iter().take(2) {
                let key = PairKey::link(link, fc.feature, 0);
                let s0 = fc.s.clamp(0.0, 1.0);
                let start = posture.link_point(link, s0) + Vector2::new(1e-4, -2e-4);
                pairs.push(Pair::new(key, law, link, s0, start));
            }
            // The link's end against the edge lines of the first corner near it.
            if let Some(fc) = found
                .iter()
                .find(|fc| matches!(fc.feature, ConvexFeature::Corner { .. }))
            {
                for after in [false, true] {
                    let key = PairKey::corner_edge(ChainPoint::Vertex(link), fc.feature, after, 0);
                    let start = posture.end_m[link] + Vector2::new(-2e-4, 1e-4);
                    pairs.push(Pair::new(key, law, link, 1.0, start));
                }
            }
        }
        for &l in &hair_links {
            let key = PairKey::point(ChainPoint::HairTip(l), 0);
            let hair = chain.hairs()[l].unwrap();
            let tip = posture.hair_tip(&hair, l, beta[l]);
            pairs.push(Pair::new(key, law, l, 1.0, tip + Vector2::new(-1e-4, 1e-4)));
        }
        for (i, pair) in pairs.iter_mut().enumerate() {
            pair.normal_force_n = 0.002 + 0.01 * lcg(&mut s);
            pair.shear_force_n = 0.01 * (lcg(&mut s) - 0.5);
            pair.normal_active = i % 3 != 2;
            pair.slip = match i % 4 {
                0 | 3 => Slip::Stuck,
                1 => Slip::Forward,
                _ => Slip::Backward,
            };
        }
        let hand = seed
            .is_multiple_of(2)
            .then(|| posture.end_m[n] + Vector2::new(0.003, -0.002));
        Case {
            chain,
            pieces,
            x,
            hair_links,
            beta,
            pairs,
            hand,
        }
    }

    /// [`case`] with compliant hairs (root stiffness 0.001 to 1 N m/rad): the last bent past
    /// its stop, the other folded short of it.
    fn compliant_case(seed: u64, wall_kind: usize) -> Case {
        let mut c = case(seed, wall_kind);
        let mut s = seed ^ 0x5eed;
        let n = c.chain.n();
        let mut builder = c.chain.to_builder();
        for (h, &l) in c.hair_links.iter().enumerate() {
            let mut hair = c.chain.hairs()[l].unwrap();
            hair.root_stiffness_nm_per_rad = Some(10f64.powf(-3.0 + 3.0 * lcg(&mut s)));
            builder = builder.hair(l, hair);
            let open = hair.open_angle_rad;
            c.beta[l] = if l == n {
                open + 0.05 + 0.8 * lcg(&mut s)
            } else {
                open - 0.05 - 0.3 * lcg(&mut s)
            };
            c.x[n + h] = c.beta[l];
        }
        c.chain = builder.build().unwrap();
        c
    }

    #[test]
    fn the_hessian_with_compliant_hairs_matches_central_differences() {
        for seed in 0..12u64 {
            let c = compliant_case(seed, (seed % 3) as usize);
            let p = problem(&c);
            let mut eq = Equations::default();
            eq.prepare(&p);
            let n = c.chain.n();
            assert!(eq.hi[n + 1] > c.x[n + 1], "the bent hair is inside its box");
            assert_hessian_matches_differences(&c, seed);
        }
    }

    /// The closed-form Hessian of case `c` against central differences of `r`.
    fn assert_hessian_matches_differences(c: &Case, seed: u64) {
        let p = problem(c);
        let mut eq = Equations::default();
        let mut pairs = c.pairs.clone();
        eq.prepare(&p);
        eq.load(&c.x, &pairs);
        eq.evaluate(&p, &mut pairs);
        let mut sys = NewtonSystem::default();
        let hess = sys.dense_hessian(&eq, &p, &pairs);
        let m = c.x.len();
        let h = 1e-6;
        for b in 0..m {
            let mut plus = c.x.clone();
            plus[b] += h;
            let mut minus = c.x.clone();
            minus[b] -= h;
            let rp = r_at(&mut eq, &p, &pairs, &plus);
            let rm = r_at(&mut eq, &p, &pairs, &minus);
            for a in 0..m {
                let fd = (rp[a] - rm[a]) / (2.0 * h);
                let an = hess[(a, b)];
                assert!(
                    (fd - an).abs() <= 1e-5 * (1.0 + an.abs().max(fd.abs())),
                    "seed {seed}: dr[{a}]/dx[{b}]: closed form {an}, differences {fd}"
                );
            }
        }
    }

    fn problem<'a>(c: &'a Case) -> StepProblem<'a> {
        StepProblem {
            chain: &c.chain,
            pieces: &c.pieces,
            tip_force_n: Vector2::new(0.01, -0.02),
            base_m: Vector2::zeros(),
            base_angle_rad: c.chain.base_angle_rad(),
            hair_links: &c.hair_links,
            hair_beta_rad: &c.beta,
            proximal: None,
            hand_m: c.hand,
            tolerance_m: 1e-12,
            acceptable_m: 1e-9,
            max_departure_rad: 1.0,
            max_iterations: 10,
            stall_after: Some(super::super::ssn::STALL_ITERATIONS),
        }
    }

    /// `r` at coordinates `x` with the pairs' forces held.
    fn r_at(eq: &mut Equations, p: &StepProblem<'_>, pairs: &[Pair], x: &[f64]) -> Vec<f64> {
        let mut pairs = pairs.to_vec();
        eq.prepare(p);
        eq.load(x, &pairs);
        eq.evaluate(p, &mut pairs);
        eq.r.clone()
    }

    #[test]
    fn the_hessian_of_every_pair_kind_matches_central_differences() {
        for seed in 0..24u64 {
            assert_hessian_matches_differences(&case(seed, (seed % 3) as usize), seed);
        }
    }

    #[test]
    fn the_constraint_gradients_match_central_differences() {
        for seed in 0..24u64 {
            let c = case(seed, (seed % 3) as usize);
            let p = problem(&c);
            let mut eq = Equations::default();
            let mut pairs = c.pairs.clone();
            for q in &mut pairs {
                q.normal_active = true;
            }
            eq.prepare(&p);
            eq.load(&c.x, &pairs);
            eq.evaluate(&p, &mut pairs);
            let mut sys = NewtonSystem::default();
            let rows = sys.active_constraint_rows(&eq, &p, &pairs);
            let m = c.x.len();
            let h = 1e-6;
            let values = |eq: &mut Equations, x: &[f64]| -> Vec<(f64, f64)> {
                let mut q = pairs.clone();
                eq.prepare(&p);
                eq.load(x, &q);
                eq.evaluate(&p, &mut q);
                q.iter().map(|q| (q.geo.gap_m, q.slip_m)).collect()
            };
            for b in 0..m {
                let mut plus = c.x.clone();
                plus[b] += h;
                let mut minus = c.x.clone();
                minus[b] -= h;
                let vp = values(&mut eq, &plus);
                let vm = values(&mut eq, &minus);
                let mut row = 0;
                for (k, q) in pairs.iter().enumerate() {
                    if !(q.normal_active && q.normal_force_n != 0.0) {
                        continue;
                    }
                    let fd = (vp[k].0 - vm[k].0) / (2.0 * h);
                    let an = rows[row][b];
                    assert!(
                        (fd - an).abs() <= 1e-6 * (1.0 + an.abs()),
                        "seed {seed}: d gap[{k}] / dx[{b}]: {an} vs {fd}"
                    );
                    row += 1;
                    if q.slip == Slip::Stuck {
                        let fd = (vp[k].1 - vm[k].1) / (2.0 * h);
                        let an = rows[row][b];
                        assert!(
                            (fd - an).abs() <= 1e-6 * (1.0 + an.abs()),
                            "seed {seed}: d slip[{k}] / dx[{b}]: {an} vs {fd}"
                        );
                        row += 1;
                    }
                }
            }
        }
    }

    #[test]
    fn the_newton_direction_solves_the_linearized_equations() {
        let mut checked = 0;
        for seed in 0..24u64 {
            let c = case(seed, (seed % 3) as usize);
            let p = problem(&c);
            let mut eq = Equations::default();
            let mut pairs = c.pairs.clone();
            eq.prepare(&p);
            eq.load(&c.x, &pairs);
            // The modes of a regular piece: every coordinate free but the last hair (held
            // on its stop); the tip touching and stuck, the first hair tip and the last
            // feature pair touching and sliding, the others letting go (stuck or sliding).
            eq.frozen_modes = true;
            let m = c.x.len();
            let n = c.chain.n();
            eq.held.fill(None);
            eq.held[m - 1] = Some(eq.hi[m - 1]);
            let last_feature = pairs
                .iter()
                .rposition(|q| matches!(q.key.kind, crate::contact::pair::PairKind::Link { .. }));
            for (i, q) in pairs.iter_mut().enumerate() {
                let tip =
                    q.key.kind == crate::contact::pair::PairKind::Point(ChainPoint::Vertex(n));
                let hair =
                    q.key.kind == crate::contact::pair::PairKind::Point(ChainPoint::HairTip(n - 1));
                q.normal_active = tip || hair || Some(i) == last_feature;
                q.slip = if tip {
                    Slip::Stuck
                } else if i % 3 == 0 {
                    Slip::Backward
                } else {
                    Slip::Forward
                };
            }
            eq.evaluate(&p, &mut pairs);
            let phi = eq.phi.clone();
            let z0 = eq.z.clone();
            let mut sys = NewtonSystem::default();
            let mut dz = Vec::new();
            let stats = sys.direction(&eq, &p, &pairs, 0.0, &mut dz).unwrap();
            assert!(!stats.truncated, "seed {seed}: {stats:?}");
            // d/dh Phi(z + h dz) at 0 is J dz, which must be -Phi.
            let scale = dz[..m]
                .iter()
                .fold(0.0_f64, |a, v| a.max(v.abs()))
                .max(1e-12);
            let h = 1e-7 / scale;
            let mut at = |sign: f64| {
                let mut q = pairs.clone();
                eq.z = z0.iter().zip(&dz).map(|(z, d)| z + sign * h * d).collect();
                eq.evaluate(&p, &mut q);
                eq.phi.clone()
            };
            let fp = at(1.0);
            let fm = at(-1.0);
            for (i, (a, b)) in fp.iter().zip(&fm).enumerate() {
                let derivative = (a - b) / (2.0 * h);
                assert!(
                    (derivative + phi[i]).abs() <= 1e-6 * (1.0 + phi[i].abs()) + 1e-9,
                    "seed {seed}: row {i}: J dz = {derivative}, -Phi = {}",
                    -phi[i]
                );
            }
            checked += 1;
        }
        assert_eq!(checked, 24);
    }
}
