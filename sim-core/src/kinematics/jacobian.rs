//! Jacobians (thesis 2.2.2, docs/model.md 2) for any frame pair `(s, b)` in `O(n)`, and the stacked
//! Jacobians of every frame in `O(n^2)` (the size of the answer).
//!
//! Column `j` of the hybrid Jacobian `J_sb` (3 x (n+1)) is
//! `alpha_sb,j (R90 (p_sb - p_s,j-1), 1)`: joint `j` sits at frame `j - 1`, and only joints
//! between `s` and `b` move `b` relative to `s`. The translational part is a suffix sum
//! (`s < b`) or prefix sum (`s > b`) of `l_i (cos psi_i, sin psi_i)`, turned by 90 degrees.

use nalgebra::{DMatrix, Matrix3xX, Vector2};

use crate::kinematics::positions::FramePoses;
use crate::kinematics::positions::frame_poses_into;
use crate::{Chain, Frame, KinematicsError};

/// Which Jacobian of the pair `(s, b)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum JacobianKind {
    /// `J_sb` (thesis 2.2.2.1): maps `theta_dot` to the hybrid velocity `(p_dot_sb, omega_sb)`,
    /// written in `C_s`.
    Hybrid,
    /// `J_b = blockdiag(R_sb^T, 1) J_sb` (thesis 2.2.2.2): the same velocity written in `C_b`.
    Body,
    /// `J_sigma = [I, -R90 p_sb; 0, 1] J_sb` (thesis 2.2.2.3): the spatial velocity
    /// `(p_dot_sb - omega R90 p_sb, omega)`, the velocity of the point of `b`'s body that is
    /// momentarily at the origin of `C_s`.
    Spatial,
}

fn check_shape(out: &Matrix3xX<f64>, n: usize) -> Result<(), KinematicsError> {
    if out.ncols() == n + 1 {
        Ok(())
    } else {
        Err(KinematicsError::WrongShape {
            argument: "jacobian",
            expected_rows: 3,
            expected_cols: n + 1,
            rows: 3,
            cols: out.ncols(),
        })
    }
}

/// The hybrid Jacobian `J_sb` (thesis 2.2.2.1) in `O(n)`.
///
/// # Errors
/// [`KinematicsError::WrongLength`] if `theta` does not have `n + 1` entries,
/// [`KinematicsError::FrameOutOfRange`] if `s` or `b` is outside `-1..=n`.
pub fn hybrid_jacobian(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
    b: Frame,
) -> Result<Matrix3xX<f64>, KinematicsError> {
    jacobian(chain, theta, s, b, JacobianKind::Hybrid)
}

/// The body Jacobian `J_b` (thesis 2.2.2.2) in `O(n)`.
///
/// # Errors
/// As [`hybrid_jacobian`].
pub fn body_jacobian(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
    b: Frame,
) -> Result<Matrix3xX<f64>, KinematicsError> {
    jacobian(chain, theta, s, b, JacobianKind::Body)
}

/// The spatial Jacobian `J_sigma` (thesis 2.2.2.3) in `O(n)`.
///
/// # Errors
/// As [`hybrid_jacobian`].
pub fn spatial_jacobian(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
    b: Frame,
) -> Result<Matrix3xX<f64>, KinematicsError> {
    jacobian(chain, theta, s, b, JacobianKind::Spatial)
}

/// The tip Jacobian `J_Gn`: the hybrid Jacobian of the tip relative to the ground frame.
/// `O(n)`; computes no other frame.
///
/// # Errors
/// [`KinematicsError::WrongLength`] if `theta` does not have `n + 1` entries.
pub fn tip_jacobian(chain: &Chain, theta: &[f64]) -> Result<Matrix3xX<f64>, KinematicsError> {
    hybrid_jacobian(chain, theta, Frame::GROUND, chain.tip())
}

/// [`tip_jacobian`] into a caller-supplied `3 x (n+1)` matrix; no allocation.
///
/// # Errors
/// As [`tip_jacobian`], plus [`KinematicsError::WrongShape`] for a wrongly sized `out`.
pub fn tip_jacobian_into(
    chain: &Chain,
    theta: &[f64],
    out: &mut Matrix3xX<f64>,
) -> Result<(), KinematicsError> {
    jacobian_into(
        chain,
        theta,
        Frame::GROUND,
        chain.tip(),
        JacobianKind::Hybrid,
        out,
    )
}

/// The Jacobian of the given kind for the pair `(s, b)`, `3 x (n+1)`, in `O(n)`.
///
/// # Errors
/// As [`hybrid_jacobian`].
pub fn jacobian(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
    b: Frame,
    kind: JacobianKind,
) -> Result<Matrix3xX<f64>, KinematicsError> {
    let mut out = Matrix3xX::zeros(chain.dof());
    jacobian_into(chain, theta, s, b, kind, &mut out)?;
    Ok(out)
}

/// [`jacobian`] into a caller-supplied `3 x (n+1)` matrix; no allocation. Columns of joints
/// that do not lie between `s` and `b` are set to zero.
///
/// # Errors
/// As [`hybrid_jacobian`], plus [`KinematicsError::WrongShape`] for a wrongly sized `out`.
pub fn jacobian_into(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
    b: Frame,
    kind: JacobianKind,
    out: &mut Matrix3xX<f64>,
) -> Result<(), KinematicsError> {
    chain.check_len("theta", theta.len())?;
    let n = chain.n();
    s.check(n, "s")?;
    b.check(n, "b")?;
    check_shape(out, n)?;
    let (p_sb, psi_b) =
        hybrid_into_unchecked(chain.link_lengths_m(), theta, s, b, out.as_mut_slice());
    let active = if b > s {
        s.slot()..b.slot()
    } else {
        b.slot()..s.slot()
    };
    let cols = out.as_mut_slice()[3 * active.start..3 * active.end].chunks_exact_mut(3);
    match kind {
        JacobianKind::Hybrid => {}
        JacobianKind::Body => {
            // R_sb^T v = (c vx + s vy, -s vx + c vy)
            let (sn, cs) = psi_b.sin_cos();
            for col in cols {
                let (vx, vy) = (col[0], col[1]);
                col[0] = cs * vx + sn * vy;
                col[1] = -sn * vx + cs * vy;
            }
        }
        JacobianKind::Spatial => {
            // v - omega R90 p_sb, omega = alpha_j = col[2]
            for col in cols {
                col[0] += col[2] * p_sb.y;
                col[1] -= col[2] * p_sb.x;
            }
        }
    }
    Ok(())
}

/// Writes the hybrid `J_sb` into a column-major `3 x (n+1)` slice and returns `(p_sb,
/// theta_sb)`. Frames and lengths are assumed checked.
pub(crate) fn hybrid_into_unchecked(
    lengths: &[f64],
    theta: &[f64],
    s: Frame,
    b: Frame,
    out: &mut [f64],
) -> (Vector2<f64>, f64) {
    out.fill(0.0);
    let mut psi = 0.0_f64;
    let (mut ax, mut ay) = (0.0_f64, 0.0_f64);
    if b > s {
        // Links s+1..=b = indices s.slot()..b.slot(). Forward: psi_i and l_i e(psi_i).
        let r = s.slot()..b.slot();
        let cols = out[3 * r.start..3 * r.end].chunks_exact_mut(3);
        for ((&t, &l), col) in theta[r.clone()].iter().zip(&lengths[r.clone()]).zip(cols) {
            psi += t;
            let (sn, cs) = psi.sin_cos();
            col[0] = l * cs;
            col[1] = l * sn;
        }
        // Backward: suffix sums sum_{i >= j} l_i e(psi_i) = p_sb - p_s,j-1, turned by R90.
        for col in out[3 * r.start..3 * r.end].chunks_exact_mut(3).rev() {
            ax += col[0];
            ay += col[1];
            col[0] = -ay;
            col[1] = ax;
            col[2] = 1.0;
        }
        (Vector2::new(ax, ay), psi)
    } else if b < s {
        // Links b+1..=s = indices b.slot()..s.slot(). Backward from s: psi_i, l_i e(psi_i).
        let r = b.slot()..s.slot();
        let cols = out[3 * r.start..3 * r.end].chunks_exact_mut(3).rev();
        for ((&t, &l), col) in theta[r.clone()]
            .iter()
            .zip(&lengths[r.clone()])
            .rev()
            .zip(cols)
        {
            let (sn, cs) = psi.sin_cos();
            col[0] = l * cs;
            col[1] = l * sn;
            psi -= t;
        }
        // Forward: exclusive prefix sums sum_{b < i < j} l_i e(psi_i) = p_s,j-1 - p_sb.
        for col in out[3 * r.start..3 * r.end].chunks_exact_mut(3) {
            let (ex, ey) = (col[0], col[1]);
            col[0] = -ay;
            col[1] = ax;
            col[2] = -1.0;
            ax += ex;
            ay += ey;
        }
        (Vector2::new(-ax, -ay), psi)
    } else {
        (Vector2::zeros(), 0.0)
    }
}

/// The hybrid Jacobians of every frame relative to `s`, stacked `3(n+2) x (n+1)`: rows
/// `3(b+1)..3(b+1)+3` are `J_sb` for `b = -1..=n` (the thesis's `P_dot_s` / `Theta_dot_s`
/// Jacobian, 2.2.3.6-7, regrouped per frame). `O(n^2)`, the size of the answer; use
/// [`hybrid_jacobian`] or [`crate::kinematics::velocity::frame_velocities`] when less is needed.
///
/// # Errors
/// [`KinematicsError::WrongLength`] if `theta` does not have `n + 1` entries,
/// [`KinematicsError::FrameOutOfRange`] if `s` is outside `-1..=n`.
pub fn all_jacobians(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
) -> Result<DMatrix<f64>, KinematicsError> {
    let n = chain.n();
    let mut out = DMatrix::zeros(3 * (n + 2), n + 1);
    let mut poses = FramePoses::zeros(n);
    all_jacobians_into(chain, theta, s, &mut poses, &mut out)?;
    Ok(out)
}

/// [`all_jacobians`] into caller-supplied buffers: `poses` (scratch, left holding the frame
/// poses relative to `s`) and `out` (`3(n+2) x (n+1)`).
///
/// # Errors
/// As [`all_jacobians`], plus [`KinematicsError::WrongShape`] for wrongly sized buffers.
pub fn all_jacobians_into(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
    poses: &mut FramePoses,
    out: &mut DMatrix<f64>,
) -> Result<(), KinematicsError> {
    let n = chain.n();
    frame_poses_into(chain, theta, s, poses)?;
    if out.nrows() != 3 * (n + 2) || out.ncols() != n + 1 {
        return Err(KinematicsError::WrongShape {
            argument: "all_jacobians",
            expected_rows: 3 * (n + 2),
            expected_cols: n + 1,
            rows: out.nrows(),
            cols: out.ncols(),
        });
    }
    let p = poses.positions_m.as_slice();
    let si = s.index();
    let rows = 3 * (n + 2);
    for (j, col) in out.as_mut_slice().chunks_exact_mut(rows).enumerate() {
        col.fill(0.0);
        // Joint j sits at frame j - 1 (slot j).
        let (jx, jy) = (p[2 * j], p[2 * j + 1]);
        let j = j as isize;
        let (frames, sign) = if j > si {
            // Frames b >= j (slots j+1..=n+1) move with +1.
            (j + 1..(n as isize) + 2, 1.0)
        } else {
            // Frames -1 <= b < j (slots 0..=j) move with -1 (here j <= s). The frame at the
            // joint itself (b = j - 1) turns but does not translate.
            (0..j + 1, -1.0)
        };
        for slot in frames {
            let slot = slot as usize;
            let (dx, dy) = (p[2 * slot] - jx, p[2 * slot + 1] - jy);
            let c = &mut col[3 * slot..3 * slot + 3];
            c[0] = -sign * dy;
            c[1] = sign * dx;
            c[2] = sign;
        }
    }
    Ok(())
}
