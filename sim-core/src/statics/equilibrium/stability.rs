//! Stability of an equilibrium: is it a strict local minimum?
//!
//! The test is second order: the Hessian of the Lagrangian,
//! `H = K + [f . (p_n - p_(max(i,j)-1))]` with `f = F + lambda` (the dead load plus the pin
//! force), must be positive definite on the tangent space of the active constraints. The
//! joints on a limit are held fixed (strict complementarity is assumed: a joint on its stop
//! with a zero stop torque is treated as held, which can only err towards calling a weak
//! minimum strict in that degenerate case); `H_FF` is `H` restricted to the other joints.
//!
//! - **No pin**: `H_FF` positive definite, i.e. every pivot of the `O(n)` factorization of
//!   [`super::structured`] positive (Sylvester's law of inertia).
//! - **Pin**: with `J_F` the 2 x |F| pin Jacobian, `H_FF` is positive definite on
//!   `null(J_F)` exactly when the bordered matrix `[H_FF J_F^T; J_F 0]` has inertia
//!   `(|F|, 2, 0)` (Gould 1985). By the Schur complement on `H_FF`,
//!   `In([H J^T; J 0]) = In(H) + In(-S)` with `S = J H^-1 J^T` (2 x 2, two `O(n)` solves),
//!   so the test is: `H_FF` nonsingular, `S` nonsingular, and
//!   `neg(H_FF) = neg(S)`. All `O(n)`. With at most two free joints the pinned set is
//!   (generically) isolated and the equilibrium counts as stable.
//!
//! Pivots or eigenvalues within `1e-12 T` of zero (`T` the torque scale of the KKT
//! residual) count as zero: such an equilibrium is reported not stable (not provably
//! strict). The dense reference computes the eigenvalues of the bordered matrix.

use nalgebra::{DMatrix, Vector2};

use super::newton::{inertia_2x2, pin_columns_solved};
use super::options::LinearSolver;
use super::structured::factor_masked;
use super::workspace::Workspace;

/// Whether `ws.x` is a strict local minimum for the tip force `f` (dead load plus pin force),
/// with or without the pin constraint. Needs `ws.kinematics()` at `ws.x`.
pub(crate) fn is_stable(
    ws: &mut Workspace,
    f: Vector2<f64>,
    pinned: bool,
    linear: LinearSolver,
) -> bool {
    for j in 0..ws.n {
        ws.free[j] = ws.lo[j] < ws.x[j] && ws.x[j] < ws.hi[j];
        ws.a[j] = f.x * ws.qx[j] + f.y * ws.qy[j];
    }
    let nfree = ws.free.iter().filter(|&&b| b).count();
    if nfree == 0 || (pinned && nfree <= 2) {
        return true;
    }
    let scale = ws.torque_scale(f);
    match linear {
        LinearSolver::Structured => structured(ws, pinned, scale),
        LinearSolver::Dense => dense(ws, pinned, scale),
    }
}

fn structured(ws: &mut Workspace, pinned: bool, scale: f64) -> bool {
    let zero_tol = 1e-12 * scale;
    let inertia = factor_masked(
        &ws.k,
        &ws.a,
        &ws.free,
        None,
        zero_tol,
        &mut ws.piv,
        &mut ws.cc,
    );
    if inertia.near_zero > 0 {
        return false;
    }
    if !pinned {
        return inertia.negative == 0;
    }
    if inertia.negative > 2 {
        return false;
    }
    let s = pin_columns_solved(ws);
    let (pos, nonsingular) = inertia_2x2(s);
    nonsingular && inertia.negative == 2 - pos
}

fn dense(ws: &Workspace, pinned: bool, scale: f64) -> bool {
    let idx: Vec<usize> = (0..ws.n).filter(|&j| ws.free[j]).collect();
    let m = idx.len();
    let extra = if pinned { 2 } else { 0 };
    let b = DMatrix::from_fn(m + extra, m + extra, |r, c| {
        if r < m && c < m {
            let (i, j) = (idx[r], idx[c]);
            ws.a[i.max(j)] + if i == j { ws.k[i] } else { 0.0 }
        } else if r < m || c < m {
            let (row, col) = if r < m {
                (c - m, idx[r])
            } else {
                (r - m, idx[c])
            };
            if row == 0 { -ws.qy[col] } else { ws.qx[col] }
        } else {
            0.0
        }
    });
    let eig = b.symmetric_eigen();
    let tol = 1e-12 * scale;
    if eig.eigenvalues.iter().any(|l| l.abs() <= tol) {
        return false;
    }
    let neg = eig.eigenvalues.iter().filter(|&&l| l < 0.0).count();
    neg == extra
}
