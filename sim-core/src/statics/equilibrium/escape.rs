//! Leaving a saddle: a step along a direction of negative curvature.
//!
//! Newton with line search stops wherever the gradient vanishes, saddles included: a
//! straight column under an axial load, or the straight start of a pinned chain whose
//! target lies on its axis, is an exact stationary point by symmetry. When a stage ends at
//! a stationary point whose merit Hessian (on the joints strictly inside their limits) is
//! not positive semidefinite, the solver takes one step along the eigenvector of its lowest
//! eigenvalue, found in `O(n)` per trial:
//! - **Sturm-like bisection** on the shift `tau`: the number of negative eigenvalues of
//!   `H - tau I` is the number of negative pivots of its structured factorization
//!   (plus the Woodbury correction for the pin penalty, [`super::newton`]); 40 bisections
//!   bracket the lowest eigenvalue;
//! - **inverse iteration** with the shift just below it (8 solves).
//!
//! The step is scaled to at most 0.25 rad per joint, its sign chosen against the gradient
//! (or, at an exact symmetry, so that its largest entry is positive: the choice of side
//! is deterministic and documented, not physical), and backtracked until the merit strictly
//! decreases: an escape never increases the merit either.

use nalgebra::DMatrix;

use super::newton::{Recorder, factor_full, solve_full};
use super::options::LinearSolver;
use super::report::TraceStep;
use super::workspace::{Merit, Workspace};

/// Tries one negative-curvature step from `ws.x` (needs `ws.kinematics()` and `ws.g` there).
/// Returns the change of the merit if a step was taken.
pub(crate) fn escape_saddle(
    ws: &mut Workspace,
    merit: &Merit,
    linear: LinearSolver,
    iterations: &mut usize,
    rec: &mut Recorder<'_>,
) -> Option<f64> {
    let f = merit.effective_force(ws.tip);
    for j in 0..ws.n {
        ws.free[j] = ws.lo[j] < ws.x[j] && ws.x[j] < ws.hi[j];
        ws.a[j] = f.x * ws.qx[j] + f.y * ws.qy[j];
    }
    if !ws.free.iter().any(|&b| b) {
        return None;
    }
    let rho = if merit.target.is_some() {
        merit.rho
    } else {
        0.0
    };
    let scale = ws.torque_scale(f) + rho * ws.l_flex * ws.l_flex;
    let found = match linear {
        LinearSolver::Structured => lowest_structured(ws, rho, scale),
        LinearSolver::Dense => lowest_dense(ws, rho, scale),
    };
    if !found {
        return None;
    }
    // Scale and orient.
    let (mut dmax, mut big) = (0.0_f64, 0.0_f64);
    for &d in &ws.dir {
        if d.abs() > dmax {
            dmax = d.abs();
            big = d;
        }
    }
    if !(dmax.is_finite() && dmax > 0.0) {
        return None;
    }
    let slope: f64 = ws.g.iter().zip(&ws.dir).map(|(g, d)| g * d).sum();
    let sign = if slope > 0.0 || (slope == 0.0 && big < 0.0) {
        -1.0
    } else {
        1.0
    };
    let s = sign * 0.25 / dmax;
    ws.dir.iter_mut().for_each(|d| *d *= s);
    let mut t = 1.0_f64;
    for _ in 0..30 {
        let mut pred = 0.0;
        for j in 0..ws.n {
            let v = (ws.x[j] + t * ws.dir[j]).clamp(ws.lo[j], ws.hi[j]);
            ws.trial[j] = v;
            pred += ws.g[j] * (v - ws.x[j]);
        }
        let change = ws.merit_change(merit);
        if change < 0.0 && change <= 1e-4 * pred.min(0.0) {
            core::mem::swap(&mut ws.x, &mut ws.trial);
            *iterations += 1;
            if let Some(trace) = rec.trace.as_deref_mut() {
                let last = trace.steps.last().map_or(0.0, |s| s.merit_j);
                trace.steps.push(TraceStep {
                    segment: rec.segment,
                    merit_j: last + change,
                    change_j: change,
                    step_length: t,
                    residual: 0.0,
                    modified: true,
                });
            }
            return Some(change);
        }
        t *= 0.5;
    }
    None
}

/// The eigenvector of the lowest eigenvalue of the merit Hessian into `ws.dir`, if that
/// eigenvalue is negative. Structured: bisection on the inertia, then inverse iteration.
fn lowest_structured(ws: &mut Workspace, rho: f64, scale: f64) -> bool {
    ws.dshift.copy_from_slice(&ws.k);
    if factor_full(ws, rho, scale, false).negative == Some(0) {
        return false;
    }
    let amax = ws.a.iter().fold(0.0_f64, |m, a| m.max(a.abs()));
    let q2: f64 = ws.qx.iter().zip(&ws.qy).map(|(x, y)| x * x + y * y).sum();
    let bound = ws.k_max + ws.n as f64 * amax + rho * q2 + scale;
    let (mut lo, mut hi) = (-bound, 0.0_f64);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        for j in 0..ws.n {
            ws.dshift[j] = ws.k[j] - mid;
        }
        if factor_full(ws, rho, scale, false).negative == Some(0) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    if hi >= -1e-12 * scale {
        return false;
    }
    for j in 0..ws.n {
        ws.dshift[j] = ws.k[j] - lo;
    }
    let fac = factor_full(ws, rho, scale, false);
    let mut v = core::mem::take(&mut ws.dir);
    for (j, x) in v.iter_mut().enumerate() {
        *x = (1.3 * j as f64 + 0.7).sin();
    }
    for _ in 0..8 {
        solve_full(ws, &fac, &mut v);
        let m = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        if !(m.is_finite() && m > 0.0) {
            ws.dir = v;
            return false;
        }
        v.iter_mut().for_each(|x| *x /= m);
    }
    ws.dir = v;
    true
}

fn lowest_dense(ws: &mut Workspace, rho: f64, scale: f64) -> bool {
    let idx: Vec<usize> = (0..ws.n).filter(|&j| ws.free[j]).collect();
    let m = idx.len();
    let h = DMatrix::from_fn(m, m, |r, c| {
        let (i, j) = (idx[r], idx[c]);
        let ji = (-ws.qy[i], ws.qx[i]);
        let jj = (-ws.qy[j], ws.qx[j]);
        ws.a[i.max(j)] + if i == j { ws.k[i] } else { 0.0 } + rho * (ji.0 * jj.0 + ji.1 * jj.1)
    });
    let eig = h.symmetric_eigen();
    let (mut best, mut arg) = (f64::INFINITY, 0);
    for (r, &l) in eig.eigenvalues.iter().enumerate() {
        if l < best {
            best = l;
            arg = r;
        }
    }
    if best.is_nan() || best >= -1e-12 * scale {
        return false;
    }
    ws.dir.fill(0.0);
    for (r, &j) in idx.iter().enumerate() {
        ws.dir[j] = eig.eigenvectors[(r, arg)];
    }
    true
}
