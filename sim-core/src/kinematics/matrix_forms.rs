//! The thesis's matrix forms, written as printed (with the thesis's uniform `l` generalised to
//! `diag(l_0, ..., l_n)`, which commutes through every formula because it is diagonal):
//! positions 2.2.1.6 and 2.2.3.3-4, velocities 2.2.1.14 and 2.2.3.6-7, Jacobians 2.2.2.1-3,
//! hair tips 3.2.1.1 and 3.2.1.3.
//!
//! They cost `O(n^2)` per frame pair (`O(n^3)` for [`seed_all_jacobians`]) and exist as the
//! reference the `O(n)` fast paths are tested and benchmarked against. Notation:
//! `C(x) = [cos(x)^T; sin(x)^T]` and `W(x) = [-sin(x)^T; cos(x)^T]`, both `2 x (n+1)`.

use nalgebra::{DMatrix, DVector, Matrix2, Matrix3, Matrix3xX, Vector2};

use crate::kinematics::active_frames::{
    active_frames_matrix, active_frames_vector, all_frames_active_matrix, all_frames_matrix,
};
use crate::kinematics::positions::{FramePoses, Pose2};
use crate::kinematics::velocity::{FrameVelocities, Twist2};
use crate::{Chain, Frame, KinematicsError};

/// `C(x) diag(l)` (`rot90 = false`) or `W(x) diag(l)` (`rot90 = true`).
fn trig_rows(x: &DVector<f64>, lengths: &[f64], rot90: bool) -> DMatrix<f64> {
    DMatrix::from_fn(2, x.len(), |r, i| {
        let (sn, cs) = x[i].sin_cos();
        let v = match (rot90, r) {
            (false, 0) => cs,
            (false, _) => sn,
            (true, 0) => -sn,
            (true, _) => cs,
        };
        v * lengths[i]
    })
}

fn check(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
    b: Frame,
) -> Result<DVector<f64>, KinematicsError> {
    chain.check_len("theta", theta.len())?;
    s.check(chain.n(), "s")?;
    b.check(chain.n(), "b")?;
    Ok(DVector::from_column_slice(theta))
}

/// The thesis's `H_sb` (2.2.1.6, Lemma 2.2.1), 3x3: `[R_sb, C(A_sb theta) diag(l) alpha_sb;
/// 0 0, alpha_sb^T theta]`. As printed, the bottom-right entry is the angle `theta_sb`, so
/// `H_sb (p_b^a, 1) = (p_sb^a, theta_sb)`; it is not an SE(2) matrix.
///
/// # Errors
/// [`KinematicsError`] for a wrong `theta` length or a frame outside `-1..=n`.
pub fn seed_transform(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
    b: Frame,
) -> Result<Matrix3<f64>, KinematicsError> {
    let th = check(chain, theta, s, b)?;
    let n = chain.n();
    let alpha = active_frames_vector(n, s, b)?;
    let a = active_frames_matrix(n, s, b)?;
    let angle = alpha.dot(&th);
    let p = trig_rows(&(&a * &th), chain.link_lengths_m(), false) * &alpha;
    let (sn, cs) = angle.sin_cos();
    Ok(Matrix3::new(cs, -sn, p[0], sn, cs, p[1], 0.0, 0.0, angle))
}

/// `(p_sb, theta_sb)`, the third column of [`seed_transform`].
///
/// # Errors
/// As [`seed_transform`].
pub fn seed_pose(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
    b: Frame,
) -> Result<Pose2, KinematicsError> {
    let h = seed_transform(chain, theta, s, b)?;
    Ok(Pose2 {
        position_m: Vector2::new(h[(0, 2)], h[(1, 2)]),
        angle_rad: h[(2, 2)],
    })
}

/// All frame positions and angles (thesis 2.2.3.3-4):
/// `[p_sG ... p_sn] = C(A_(sG+sn) theta) diag(l) A`, `Theta_s = A^T theta`.
///
/// # Errors
/// [`KinematicsError`] for a wrong `theta` length or `s` outside `-1..=n`.
pub fn seed_frame_poses(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
) -> Result<FramePoses, KinematicsError> {
    let th = check(chain, theta, s, s)?;
    let n = chain.n();
    let a_all = all_frames_matrix(n, s)?;
    let a_sgn = all_frames_active_matrix(n, s)?;
    let c = trig_rows(&(&a_sgn * &th), chain.link_lengths_m(), false);
    let p = c * &a_all;
    Ok(FramePoses {
        positions_m: nalgebra::Matrix2xX::from_column_slice(p.as_slice()),
        angles_rad: a_all.transpose() * th,
    })
}

/// The velocity of frame `b` relative to `s`, written in `s` (thesis 2.2.1.14, 2.2.1.9):
/// `p_dot_sb = W(A_sb theta) diag(l) |A_sb| theta_dot`, `omega_sb = alpha_sb^T theta_dot`.
///
/// # Errors
/// As [`seed_transform`], plus a wrong `theta_dot` length.
pub fn seed_velocity(
    chain: &Chain,
    theta: &[f64],
    theta_dot: &[f64],
    s: Frame,
    b: Frame,
) -> Result<Twist2, KinematicsError> {
    let th = check(chain, theta, s, b)?;
    chain.check_len("theta_dot", theta_dot.len())?;
    let thd = DVector::from_column_slice(theta_dot);
    let n = chain.n();
    let alpha = active_frames_vector(n, s, b)?;
    let a = active_frames_matrix(n, s, b)?;
    let v = trig_rows(&(&a * &th), chain.link_lengths_m(), true) * (a.abs() * &thd);
    Ok(Twist2 {
        linear_m_per_s: Vector2::new(v[0], v[1]),
        angular_rad_per_s: alpha.dot(&thd),
    })
}

/// The Khatri-Rao product `A^T (.) (W(A_(sG+sn) theta) diag(l))` of thesis 2.2.3.6,
/// `2(n+2) x (n+1)`: column `i` is `A^T[:, i] (x) l_i W[:, i]`.
fn seed_khatri_rao(
    chain: &Chain,
    th: &DVector<f64>,
    s: Frame,
) -> Result<DMatrix<f64>, KinematicsError> {
    let n = chain.n();
    let a_all = all_frames_matrix(n, s)?;
    let a_sgn = all_frames_active_matrix(n, s)?;
    let w = trig_rows(&(&a_sgn * th), chain.link_lengths_m(), true);
    let at = a_all.transpose();
    Ok(DMatrix::from_fn(2 * (n + 2), n + 1, |row, i| {
        at[(row / 2, i)] * w[(row % 2, i)]
    }))
}

/// All frame velocities (thesis 2.2.3.6-7):
/// `P_dot_s = [A^T (.) W(A_(sG+sn) theta) diag(l)] A_(sG+sn) theta_dot` (evaluated right to
/// left, `O(n^2)`), `Theta_dot_s = A^T theta_dot`.
///
/// # Errors
/// [`KinematicsError`] for wrong vector lengths or `s` outside `-1..=n`.
pub fn seed_frame_velocities(
    chain: &Chain,
    theta: &[f64],
    theta_dot: &[f64],
    s: Frame,
) -> Result<FrameVelocities, KinematicsError> {
    let th = check(chain, theta, s, s)?;
    chain.check_len("theta_dot", theta_dot.len())?;
    let thd = DVector::from_column_slice(theta_dot);
    let n = chain.n();
    let kr = seed_khatri_rao(chain, &th, s)?;
    let a_sgn = all_frames_active_matrix(n, s)?;
    let v = kr * (a_sgn * &thd);
    let a_all = all_frames_matrix(n, s)?;
    Ok(FrameVelocities {
        linear_m_per_s: nalgebra::Matrix2xX::from_column_slice(v.as_slice()),
        angular_rad_per_s: a_all.transpose() * thd,
    })
}

/// The hybrid Jacobian (thesis 2.2.2.1): `J_sb = [W(A_sb theta) diag(l) |A_sb|; alpha_sb^T]`.
///
/// # Errors
/// As [`seed_transform`].
pub fn seed_hybrid_jacobian(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
    b: Frame,
) -> Result<Matrix3xX<f64>, KinematicsError> {
    let th = check(chain, theta, s, b)?;
    let n = chain.n();
    let a = active_frames_matrix(n, s, b)?;
    let top = trig_rows(&(&a * &th), chain.link_lengths_m(), true) * a.abs();
    Ok(stack(&top, &active_frames_vector(n, s, b)?))
}

/// The body Jacobian (thesis 2.2.2.2): `J_b = [W(A_bs theta) diag(l) |A_sb|; alpha_sb^T]`.
///
/// # Errors
/// As [`seed_transform`].
pub fn seed_body_jacobian(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
    b: Frame,
) -> Result<Matrix3xX<f64>, KinematicsError> {
    let th = check(chain, theta, s, b)?;
    let n = chain.n();
    let a_sb = active_frames_matrix(n, s, b)?;
    let a_bs = active_frames_matrix(n, b, s)?;
    let top = trig_rows(&(&a_bs * &th), chain.link_lengths_m(), true) * a_sb.abs();
    Ok(stack(&top, &active_frames_vector(n, s, b)?))
}

/// The spatial Jacobian (thesis 2.2.2.3): `J_sigma = [-W(A_sb theta) diag(l) |A_bs|;
/// alpha_sb^T]`.
///
/// # Errors
/// As [`seed_transform`].
pub fn seed_spatial_jacobian(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
    b: Frame,
) -> Result<Matrix3xX<f64>, KinematicsError> {
    let th = check(chain, theta, s, b)?;
    let n = chain.n();
    let a_sb = active_frames_matrix(n, s, b)?;
    let a_bs = active_frames_matrix(n, b, s)?;
    let top = -(trig_rows(&(&a_sb * &th), chain.link_lengths_m(), true) * a_bs.abs());
    Ok(stack(&top, &active_frames_vector(n, s, b)?))
}

/// The hybrid Jacobians of every frame relative to `s`, stacked `3(n+2) x (n+1)` (rows
/// `3(b+1)..3(b+1)+3` are `J_sb`): translational rows from the matrix of thesis 2.2.3.6,
/// `[A^T (.) W diag(l)] A_(sG+sn)`, angular rows from `A^T` (2.2.3.7). `O(n^3)`.
///
/// # Errors
/// [`KinematicsError`] for a wrong `theta` length or `s` outside `-1..=n`.
pub fn seed_all_jacobians(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
) -> Result<DMatrix<f64>, KinematicsError> {
    let th = check(chain, theta, s, s)?;
    let n = chain.n();
    let lin = seed_khatri_rao(chain, &th, s)? * all_frames_active_matrix(n, s)?;
    let at = all_frames_matrix(n, s)?.transpose();
    Ok(DMatrix::from_fn(3 * (n + 2), n + 1, |row, j| {
        let (frame_slot, r) = (row / 3, row % 3);
        if r < 2 {
            lin[(2 * frame_slot + r, j)]
        } else {
            at[(frame_slot, j)]
        }
    }))
}

fn stack(top: &DMatrix<f64>, alpha: &DVector<f64>) -> Matrix3xX<f64> {
    Matrix3xX::from_fn(
        top.ncols(),
        |r, j| if r < 2 { top[(r, j)] } else { alpha[j] },
    )
}

/// The thesis's hair tip in the segment frame (3.2.1.1): `p'_b = R' (cos t, sin t) l' + p'`
/// with `R' = -I` and `p' = (-l_b / 2, 0)`, i.e. `-(l_b/2 + l' cos t, l' sin t)`, where `t` is
/// the thesis's hair angle `theta'_b` (measured in the hair base frame, which is turned by pi).
pub fn seed_hair_tip_in_segment(
    link_length_m: f64,
    hair_length_m: f64,
    hair_angle_seed_rad: f64,
) -> Vector2<f64> {
    let r_prime = -Matrix2::<f64>::identity();
    let p_prime = Vector2::new(-0.5 * link_length_m, 0.0);
    let (sn, cs) = hair_angle_seed_rad.sin_cos();
    r_prime * Vector2::new(cs, sn) * hair_length_m + p_prime
}

/// The thesis's hair tip of link `link` in frame `s` (3.2.1.1): `p'_sb = R_sb p'_b + p_sb`,
/// with `b = link` and `R_sb`, `p_sb` from [`seed_transform`].
///
/// # Errors
/// As [`seed_transform`], plus [`KinematicsError::LinkOutOfRange`] if `link > n`.
pub fn seed_hair_tip(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
    link: usize,
    hair_length_m: f64,
    hair_angle_seed_rad: f64,
) -> Result<Vector2<f64>, KinematicsError> {
    let lb = link_length(chain, link)?;
    let h = seed_transform(chain, theta, s, Frame::link(link))?;
    let tip_b = seed_hair_tip_in_segment(lb, hair_length_m, hair_angle_seed_rad);
    let r = h.fixed_view::<2, 2>(0, 0);
    Ok(r * tip_b + Vector2::new(h[(0, 2)], h[(1, 2)]))
}

fn link_length(chain: &Chain, link: usize) -> Result<f64, KinematicsError> {
    chain
        .link_lengths_m()
        .get(link)
        .copied()
        .ok_or(KinematicsError::LinkOutOfRange {
            argument: "link",
            index: link,
            n: chain.n(),
        })
}

/// The thesis's hair tip velocity (3.2.1.3): `(p_dot'_sb, omega'_sb) = H_dot_sb (p'_b, 1)` with
/// `H_dot_sb = [omega^ R_sb, p_dot_sb; 0, omega_sb]`, `omega = alpha_sb^T theta_dot`. The thesis
/// treats the hair as fixed on its segment here (no `theta_dot'` term).
///
/// # Errors
/// As [`seed_hair_tip`], plus a wrong `theta_dot` length.
pub fn seed_hair_tip_velocity(
    chain: &Chain,
    theta: &[f64],
    theta_dot: &[f64],
    s: Frame,
    link: usize,
    hair_length_m: f64,
    hair_angle_seed_rad: f64,
) -> Result<Twist2, KinematicsError> {
    let lb = link_length(chain, link)?;
    let b = Frame::link(link);
    let h = seed_transform(chain, theta, s, b)?;
    let v = seed_velocity(chain, theta, theta_dot, s, b)?;
    let tip_b = seed_hair_tip_in_segment(lb, hair_length_m, hair_angle_seed_rad);
    let w = v.angular_rad_per_s;
    let omega_hat = Matrix2::new(0.0, -w, w, 0.0);
    let r = h.fixed_view::<2, 2>(0, 0);
    Ok(Twist2 {
        linear_m_per_s: omega_hat * r * tip_b + v.linear_m_per_s,
        angular_rad_per_s: w,
    })
}
