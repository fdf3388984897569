//! One Newton stage: minimize a merit function over the box of joint limits by a projected Newton
//! method (Bertsekas' two-metric projection) with an Armijo backtracking search along the
//! projection arc.
//!
//! Per iteration, at `x` with gradient `g`:
//! 1. **Active set.** A joint is held when its limits are equal, or when it lies within
//!    `eps = min(0.01, residual)` rad of a limit and the gradient pushes it into that limit.
//!    Held joints move straight onto their limit; the others are free.
//! 2. **Newton direction on the free joints**: `(K + [f . q_max(i,j)] + rho J^T J)_FF d = -g_F`
//!    with `f` the effective tip force of the merit. The structured path factors the
//!    semiseparable part in `O(n)` ([`super::structured`]) and adds the rank-2 pin term by
//!    the Woodbury identity (two more `O(n)` solves and a 2x2 system). It checks the inertia
//!    of the whole matrix from the pivots: `neg(M + rho J^T J) = neg(M) + pos(I/rho + J M^-1 J^T) - 2`
//!    (Haynsworth, on the bordered matrix `[M J^T; J -I/rho]`). When the matrix is not
//!    positive definite (away from a minimum: snapping, compression) it is shifted,
//!    Levenberg-style, by `sigma I` with `sigma` starting at a quarter of the last shift that
//!    worked (at least `1e-10 T`) and growing fourfold until the inertia count says positive
//!    definite (each trial one `O(n)` factorization). The shifted direction is a descent
//!    direction and stays well scaled even when some joints are a million times softer than
//!    others (flipping or flooring single pivots, tried first, produced huge steps along the
//!    soft joints). The dense reference uses the same shift sequence with Cholesky.
//! 3. **Step cap.** The direction is scaled so no joint moves more than 0.5 rad.
//! 4. **Projected Armijo search.** `x(alpha) = clamp(x + alpha d)`, accepted when
//!    `merit(x(alpha)) - merit(x) <= 1e-4 g . (x(alpha) - x)`, halving `alpha` otherwise. The
//!    change of the merit is evaluated as an accurate difference
//!    (the workspace's `merit_change`) so the test stays meaningful down to the last digits.
//!    Should the Newton direction find no decrease (possible only through the projection),
//!    the scaled projected gradient `-g / T` is tried; if that fails too the stage reports a
//!    stall.
//!
//! Every accepted step decreases the merit (never increases it): the search cannot diverge.

use nalgebra::{DMatrix, DVector, Vector2};

use super::EquilibriumError;
use super::escape::escape_saddle;
use super::options::LinearSolver;
use super::report::{SolveTrace, TraceStep};
use super::structured::{factor_masked, solve_masked};
use super::workspace::{Merit, Workspace};

/// How a stage ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Status {
    Converged,
    Budget,
    Stalled,
}

/// Where accepted steps are recorded (when tracing).
pub(crate) struct Recorder<'t> {
    pub trace: Option<&'t mut SolveTrace>,
    pub segment: usize,
}

impl Recorder<'_> {
    fn push(&mut self, step: TraceStep) {
        if let Some(t) = self.trace.as_deref_mut() {
            t.steps.push(step);
        }
    }
}

const MAX_STEP_RAD: f64 = 0.5;
const ARMIJO: f64 = 1e-4;

/// Runs projected Newton on `merit` from `ws.x` until the stationarity residual is at most
/// `tolerance`, `*iterations` reaches `budget`, or no decrease can be found. Leaves
/// `ws.x` at the last accepted point (with `ws.kinematics()` and `ws.g` evaluated there) and
/// returns the status and the residual.
#[allow(clippy::too_many_arguments)]
pub(crate) fn minimize(
    ws: &mut Workspace,
    merit: &Merit,
    tolerance: f64,
    budget: usize,
    iterations: &mut usize,
    linear: LinearSolver,
    escape: bool,
    rec: &mut Recorder<'_>,
) -> Result<(Status, f64), EquilibriumError> {
    rec.segment += 1;
    let mut merit_now = if rec.trace.is_some() {
        ws.merit_value(merit, &ws.x)
    } else {
        0.0
    };
    let mut first = true;
    let mut stage_iterations = 0_usize;
    loop {
        ws.kinematics();
        let f = merit.effective_force(ws.tip);
        ws.gradient(f);
        let ts = ws.torque_scale(f);
        let residual = ws.stationarity(ts);
        if !residual.is_finite() {
            return Err(EquilibriumError::NumericalBreakdown {
                iteration: *iterations,
                reason: "non-finite gradient",
            });
        }
        if first {
            rec.push(TraceStep {
                segment: rec.segment,
                merit_j: merit_now,
                change_j: 0.0,
                step_length: 0.0,
                residual,
                modified: false,
            });
            first = false;
        }
        if *iterations >= budget {
            let status = if residual <= tolerance {
                Status::Converged
            } else {
                Status::Budget
            };
            return Ok((status, residual));
        }
        if residual <= tolerance {
            if escape && let Some(change) = escape_saddle(ws, merit, linear, iterations, rec) {
                merit_now += change;
                continue;
            }
            return Ok((Status::Converged, residual));
        }
        *iterations += 1;

        // 1. Active set.
        let eps = residual.min(1e-2);
        let sticky = stage_iterations >= STICKY_AFTER;
        let release = if sticky { free_residual(ws, ts) } else { 0.0 };
        stage_iterations += 1;
        for j in 0..ws.n {
            let (x, lo, hi, g) = (ws.x[j], ws.lo[j], ws.hi[j], ws.g[j]);
            let mut held = lo >= hi || (x <= lo + eps && g > 0.0) || (x >= hi - eps && g < 0.0);
            // Zig-zag guard: a joint held on its limit stays held while its multiplier has
            // the wrong sign by less than the rest of the face is from stationary.
            if sticky && !held && !ws.free[j] && (x <= lo || x >= hi) {
                held = g.abs() / ts <= release;
            }
            ws.free[j] = !held;
            ws.a[j] = f.x * ws.qx[j] + f.y * ws.qy[j];
        }
        // 2. Newton direction on the free joints.
        let pinned = merit.target.is_some() && merit.rho > 0.0;
        let rho = if pinned { merit.rho } else { 0.0 };
        let scale = ts + rho * ws.l_flex * ws.l_flex;
        let modified = match linear {
            LinearSolver::Structured => direction_structured(ws, rho, scale),
            LinearSolver::Dense => direction_dense(ws, rho, scale),
        };
        held_onto_limits(ws);
        let slope: f64 = ws.g.iter().zip(&ws.dir).map(|(g, d)| g * d).sum();
        if slope.is_nan() || slope >= 0.0 {
            steepest(ws, ts);
        }
        // 3-4. Cap and projected search; fall back to the projected gradient once.
        let mut accepted = line_search(ws, merit);
        if accepted.is_none() {
            steepest(ws, ts);
            accepted = line_search(ws, merit);
        }
        let Some((alpha, change)) = accepted else {
            return Ok((Status::Stalled, residual));
        };
        core::mem::swap(&mut ws.x, &mut ws.trial);
        if rec.trace.is_some() {
            merit_now += change;
            rec.push(TraceStep {
                segment: rec.segment,
                merit_j: merit_now,
                change_j: change,
                step_length: alpha,
                residual,
                modified,
            });
        }
    }
}

/// Iterations of one stage after which a joint held on a limit is released only once the
/// rest of the face is nearly stationary (see [`free_residual`]).
const STICKY_AFTER: usize = 50;

/// The largest scaled gradient `|g_j| / T` over the joints that were free in the last
/// iteration: how far the current face is from stationary. A joint held on its limit whose
/// multiplier has the wrong sign is released (after [`STICKY_AFTER`] iterations) only when
/// its `|g_j| / T` exceeds this, the classical guard against zig-zagging between faces of
/// the box (an active-set method releases a constraint once the face is minimized).
fn free_residual(ws: &Workspace, ts: f64) -> f64 {
    (0..ws.n)
        .filter(|&j| ws.free[j])
        .fold(0.0_f64, |m, j| m.max(ws.g[j].abs() / ts))
}

/// Held joints move onto the limit they are pushed into.
fn held_onto_limits(ws: &mut Workspace) {
    for j in 0..ws.n {
        if !ws.free[j] {
            let target = if ws.g[j] > 0.0 { ws.lo[j] } else { ws.hi[j] };
            ws.dir[j] = target - ws.x[j];
        }
    }
}

/// The scaled projected gradient `-g / T` on the free joints.
fn steepest(ws: &mut Workspace, ts: f64) {
    for j in 0..ws.n {
        if ws.free[j] {
            ws.dir[j] = -ws.g[j] / ts;
        }
    }
    held_onto_limits(ws);
}

/// Caps the step and backtracks along the projection arc; `Some((alpha, change))` on success,
/// with the accepted point in `ws.trial`.
fn line_search(ws: &mut Workspace, merit: &Merit) -> Option<(f64, f64)> {
    let dmax = ws.dir.iter().fold(0.0_f64, |m, d| m.max(d.abs()));
    if !dmax.is_finite() || dmax == 0.0 {
        return None;
    }
    let cap = if dmax > MAX_STEP_RAD {
        MAX_STEP_RAD / dmax
    } else {
        1.0
    };
    let mut alpha = 1.0_f64;
    while alpha > 1e-12 {
        let step = alpha * cap;
        let mut pred = 0.0;
        let mut moved = false;
        for j in 0..ws.n {
            let t = (ws.x[j] + step * ws.dir[j]).clamp(ws.lo[j], ws.hi[j]);
            ws.trial[j] = t;
            pred += ws.g[j] * (t - ws.x[j]);
            moved |= t != ws.x[j];
        }
        if !moved {
            return None;
        }
        if pred < 0.0 {
            let change = ws.merit_change(merit);
            if change <= ARMIJO * pred {
                return Some((step, change));
            }
        }
        alpha *= 0.5;
    }
    None
}

/// `S = J_F M^-1 J_F^T` (symmetrized) with `ws.y1`, `ws.y2` left holding `M^-1 J_F^T`,
/// `M` the factorization in `ws.piv`, `ws.cc`.
pub(crate) fn pin_columns_solved(ws: &mut Workspace) -> [[f64; 2]; 2] {
    for j in 0..ws.n {
        ws.y1[j] = -ws.qy[j];
        ws.y2[j] = ws.qx[j];
    }
    solve_masked(&ws.piv, &ws.cc, &ws.free, &mut ws.y1);
    solve_masked(&ws.piv, &ws.cc, &ws.free, &mut ws.y2);
    let mut s = [[0.0; 2]; 2];
    for j in 0..ws.n {
        if ws.free[j] {
            let (u, v) = (-ws.qy[j], ws.qx[j]);
            s[0][0] += u * ws.y1[j];
            s[0][1] += 0.5 * (u * ws.y2[j] + v * ws.y1[j]);
            s[1][1] += v * ws.y2[j];
        }
    }
    s[1][0] = s[0][1];
    s
}

/// The number of positive eigenvalues of a symmetric 2x2 matrix and whether it is
/// numerically nonsingular.
pub(crate) fn inertia_2x2(m: [[f64; 2]; 2]) -> (usize, bool) {
    let half_trace = 0.5 * (m[0][0] + m[1][1]);
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let disc = (half_trace * half_trace - det).max(0.0).sqrt();
    let (l1, l2) = (half_trace + disc, half_trace - disc);
    let size = l1.abs().max(l2.abs());
    let nonsingular = size > 0.0 && l1.abs().min(l2.abs()) > 1e-13 * size;
    (usize::from(l1 > 0.0) + usize::from(l2 > 0.0), nonsingular)
}

fn solve_2x2(m: [[f64; 2]; 2], b: Vector2<f64>) -> Vector2<f64> {
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    Vector2::new(
        (m[1][1] * b.x - m[0][1] * b.y) / det,
        (m[0][0] * b.y - m[1][0] * b.x) / det,
    )
}

/// A factorization of `diag(ws.dshift) + [a_max] + rho J_F^T J_F` on the free joints:
/// the semiseparable part in `ws.piv`, `ws.cc`, the Woodbury data in `ws.y1`, `ws.y2` and
/// the returned `W = I/rho + J M^-1 J^T`.
pub(crate) struct Factored {
    pub w: [[f64; 2]; 2],
    pub rho: f64,
    /// The number of negative eigenvalues of the whole matrix, `None` when (nearly)
    /// singular.
    pub negative: Option<usize>,
}

/// Factors with the diagonal in `ws.dshift`, modified (pivots `max(|p|, delta)`) when `modify`.
pub(crate) fn factor_full(ws: &mut Workspace, rho: f64, scale: f64, modify: bool) -> Factored {
    let zero_tol = 1e-12 * scale;
    let delta = modify.then_some(1e-8 * scale);
    let inertia = factor_masked(
        &ws.dshift,
        &ws.a,
        &ws.free,
        delta,
        zero_tol,
        &mut ws.piv,
        &mut ws.cc,
    );
    let base = if modify { 0 } else { inertia.negative };
    let mut negative = (inertia.near_zero == 0 || modify).then_some(base);
    let mut w = [[0.0; 2]; 2];
    if rho > 0.0 {
        let s = pin_columns_solved(ws);
        w = [
            [s[0][0] + 1.0 / rho, s[0][1]],
            [s[1][0], s[1][1] + 1.0 / rho],
        ];
        let (pos, nonsingular) = inertia_2x2(w);
        negative = match negative {
            Some(neg) if nonsingular && neg + pos >= 2 => Some(neg + pos - 2),
            _ => None,
        };
    }
    Factored { w, rho, negative }
}

/// Solves with a [`Factored`] in place (free joints; held ones set to 0).
#[allow(clippy::needless_range_loop)]
pub(crate) fn solve_full(ws: &mut Workspace, f: &Factored, b: &mut [f64]) {
    solve_masked(&ws.piv, &ws.cc, &ws.free, b);
    if f.rho > 0.0 {
        let mut v = Vector2::zeros();
        for j in 0..ws.n {
            if ws.free[j] {
                v.x -= ws.qy[j] * b[j];
                v.y += ws.qx[j] * b[j];
            }
        }
        let c = solve_2x2(f.w, v);
        for j in 0..ws.n {
            if ws.free[j] {
                b[j] -= ws.y1[j] * c.x + ws.y2[j] * c.y;
            }
        }
    }
}

/// The next Levenberg shift to try: the last successful one over 4 (at least `1e-10 T`),
/// then four times larger each time.
fn next_shift(ws: &Workspace, sigma: f64, scale: f64) -> f64 {
    if sigma == 0.0 {
        (ws.sigma / 4.0).max(1e-10 * scale)
    } else {
        sigma * 4.0
    }
}

/// The `O(n)` Newton direction into `ws.dir` (free joints); returns whether the matrix had
/// to be shifted.
fn direction_structured(ws: &mut Workspace, rho: f64, scale: f64) -> bool {
    let mut sigma = 0.0_f64;
    let fac = loop {
        for (d, k) in ws.dshift.iter_mut().zip(&ws.k) {
            *d = k + sigma;
        }
        let fac = factor_full(ws, rho, scale, false);
        if fac.negative == Some(0) {
            break fac;
        }
        if sigma > 1e12 * scale {
            break factor_full(ws, rho, scale, true);
        }
        sigma = next_shift(ws, sigma, scale);
    };
    if sigma > 0.0 {
        ws.sigma = sigma;
    }
    let mut dir = core::mem::take(&mut ws.dir);
    for (d, g) in dir.iter_mut().zip(&ws.g) {
        *d = -g;
    }
    solve_full(ws, &fac, &mut dir);
    ws.dir = dir;
    sigma > 0.0
}

/// The dense reference: the same matrix filled explicitly and factored with nalgebra's
/// Cholesky, shifted by the same Levenberg sequence `sigma I` until positive definite (a
/// symmetric eigen decomposition with eigenvalues `max(|lambda|, delta)` if even that
/// fails). `O(n^3)`.
fn direction_dense(ws: &mut Workspace, rho: f64, scale: f64) -> bool {
    let idx: Vec<usize> = (0..ws.n).filter(|&j| ws.free[j]).collect();
    let m = idx.len();
    let h = DMatrix::from_fn(m, m, |r, c| {
        let (i, j) = (idx[r], idx[c]);
        let jt = |k: usize| Vector2::new(-ws.qy[k], ws.qx[k]);
        ws.a[i.max(j)] + if i == j { ws.k[i] } else { 0.0 } + rho * jt(i).dot(&jt(j))
    });
    let b = DVector::from_fn(m, |r, _| -ws.g[idx[r]]);
    let mut sigma = 0.0_f64;
    let d = loop {
        let shifted = &h + DMatrix::identity(m, m) * sigma;
        if let Some(ch) = shifted.cholesky() {
            break ch.solve(&b);
        }
        if sigma > 1e12 * scale {
            let eig = h.clone().symmetric_eigen();
            let delta = 1e-8 * scale;
            let lam = eig.eigenvalues.map(|l| l.abs().max(delta));
            let qtb = eig.eigenvectors.transpose() * &b;
            let scaled = DVector::from_fn(m, |r, _| qtb[r] / lam[r]);
            break &eig.eigenvectors * scaled;
        }
        sigma = next_shift(ws, sigma, scale);
    };
    if sigma > 0.0 {
        ws.sigma = sigma;
    }
    for (r, &j) in idx.iter().enumerate() {
        ws.dir[j] = d[r];
    }
    sigma > 0.0
}
