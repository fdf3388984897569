//! The thesis's bookkeeping (2.2.1, 2.2.3): the active frames vector `alpha_sb`, the active
//! frames matrix `A_sb` and the all-frames matrix `A`. Entries are `-1, 0, 1` stored as
//! `f64` so they multiply `theta` directly.
//!
//! Indices: rows/entries `0..=n` are links (and joints) `0..=n`; the columns of `A` are the
//! frames `-1..=n` (column `b + 1` is frame `b`).
//!
//! These build dense `(n+1) x (n+1)` matrices: they are the reference for the `O(n)` fast
//! paths, not a way to compute.

use nalgebra::{DMatrix, DVector};

use crate::{Frame, KinematicsError};

/// `alpha_sb` (thesis 2.2.1.1): entry `i` is `1` if `s < i <= b`, `-1` if `b < i <= s`, else
/// `0`. `alpha_sb^T theta` is the angle of `C_b` in `C_s`.
///
/// # Errors
/// [`KinematicsError::FrameOutOfRange`] if `s` or `b` is outside `-1..=n`.
pub fn active_frames_vector(n: usize, s: Frame, b: Frame) -> Result<DVector<f64>, KinematicsError> {
    s.check(n, "s")?;
    b.check(n, "b")?;
    Ok(DVector::from_fn(n + 1, |i, _| alpha_entry(i, s, b)))
}

/// Entry `i` of `alpha_sb` (frames assumed valid).
pub(crate) fn alpha_entry(i: usize, s: Frame, b: Frame) -> f64 {
    let i = i as isize;
    let (s, b) = (s.index(), b.index());
    if b < i && i <= s {
        -1.0
    } else if s < i && i <= b {
        1.0
    } else {
        0.0
    }
}

/// `A_sb` built from `alpha` by the thesis's formula 2.2.1.2:
/// `A = (alpha alpha^T)^lower + 1/2 (alpha |alpha|^T - alpha alpha^T)`, where `^lower` keeps
/// the lower triangle with the diagonal. Works for any `alpha` with entries in `{-1, 0, 1}`
/// (the thesis also applies it to `alpha_sG + alpha_sn`, 2.2.3.2).
pub fn active_frames_matrix_from_vector(alpha: &DVector<f64>) -> DMatrix<f64> {
    let m = alpha.len();
    DMatrix::from_fn(m, m, |i, j| {
        let aa = alpha[i] * alpha[j];
        let lower = if i >= j { aa } else { 0.0 };
        lower + 0.5 * (alpha[i] * alpha[j].abs() - aa)
    })
}

/// `A_sb` (thesis 2.2.1.2), `(n+1) x (n+1)`. Row `i` of `A_sb theta` is `phi_i - phi_s` for the
/// links `i` between `s` and `b`, zero elsewhere.
///
/// # Errors
/// [`KinematicsError::FrameOutOfRange`] if `s` or `b` is outside `-1..=n`.
pub fn active_frames_matrix(n: usize, s: Frame, b: Frame) -> Result<DMatrix<f64>, KinematicsError> {
    let alpha = active_frames_vector(n, s, b)?;
    Ok(active_frames_matrix_from_vector(&alpha))
}

/// The all-frames matrix `A = [alpha_sG | alpha_s0 | ... | alpha_sn]` (thesis 2.2.3.1),
/// `(n+1) x (n+2)`; column `b + 1` is `alpha_sb` and column `s + 1` is zero.
/// `A^T theta` is `Theta_s` (2.2.3.4).
///
/// # Errors
/// [`KinematicsError::FrameOutOfRange`] if `s` is outside `-1..=n`.
pub fn all_frames_matrix(n: usize, s: Frame) -> Result<DMatrix<f64>, KinematicsError> {
    s.check(n, "s")?;
    Ok(DMatrix::from_fn(n + 1, n + 2, |i, col| {
        alpha_entry(i, s, Frame::new(col as isize - 1))
    }))
}

/// `A` synthesised from the two extreme vectors (thesis 2.2.3.2):
/// `A = [alpha_sG | A_sG^T + A_sn^T]`.
///
/// # Errors
/// [`KinematicsError::FrameOutOfRange`] if `s` is outside `-1..=n`.
pub fn all_frames_matrix_from_extremes(
    n: usize,
    s: Frame,
) -> Result<DMatrix<f64>, KinematicsError> {
    let tip = Frame::link(n);
    let alpha_sg = active_frames_vector(n, s, Frame::GROUND)?;
    let a_sg = active_frames_matrix(n, s, Frame::GROUND)?;
    let a_sn = active_frames_matrix(n, s, tip)?;
    let rest = a_sg.transpose() + a_sn.transpose();
    let mut a = DMatrix::zeros(n + 1, n + 2);
    a.column_mut(0).copy_from(&alpha_sg);
    a.columns_mut(1, n + 1).copy_from(&rest);
    Ok(a)
}

/// `A_(sG+sn)`, the active frames matrix of `alpha_sG + alpha_sn` (thesis 2.2.3.2-3): row `i`
/// of `A_(sG+sn) theta` is `phi_i - phi_s` for every link `i`.
///
/// # Errors
/// [`KinematicsError::FrameOutOfRange`] if `s` is outside `-1..=n`.
pub fn all_frames_active_matrix(n: usize, s: Frame) -> Result<DMatrix<f64>, KinematicsError> {
    let alpha =
        active_frames_vector(n, s, Frame::GROUND)? + active_frames_vector(n, s, Frame::link(n))?;
    Ok(active_frames_matrix_from_vector(&alpha))
}
