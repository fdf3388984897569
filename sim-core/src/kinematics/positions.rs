//! Forward kinematics (thesis 2.2.1.1, 2.2.3.1, 6.1.1): the pose of one frame or of every
//! frame relative to any spatial frame `s`, by prefix sums of the joint angles.
//!
//! Relative to `s`, the angle of link `i` is `psi_i = phi_i - phi_s` (a running sum of
//! `theta` away from `s`), and `p_sb` is the running sum of `l_i (cos psi_i, sin psi_i)` over
//! the links between `s` and `b`. One pair costs `|b - s|` `sin_cos` calls; all frames cost
//! `n + 1`.

use nalgebra::{DVector, Matrix2xX, Vector2};

use crate::{Chain, Frame, KinematicsError};

/// The position and orientation of a frame `C_b` relative to a spatial frame `C_s`,
/// written in `C_s` (the third column of the thesis's `H_sb`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose2 {
    /// `p_sb`, the origin of `C_b` in `C_s` coordinates, in metres.
    pub position_m: Vector2<f64>,
    /// `theta_sb = alpha_sb^T theta`, the angle of `C_b`'s x-axis from `C_s`'s, in radians.
    pub angle_rad: f64,
}

impl Pose2 {
    /// The rotation `R_sb` as a 2x2 matrix.
    pub fn rotation(&self) -> nalgebra::Matrix2<f64> {
        let (s, c) = self.angle_rad.sin_cos();
        nalgebra::Matrix2::new(c, -s, s, c)
    }

    /// A point given in `C_b` coordinates, written in `C_s`: `R_sb p_b + p_sb`.
    pub fn transform_point(&self, point_in_b_m: &Vector2<f64>) -> Vector2<f64> {
        self.rotation() * point_in_b_m + self.position_m
    }
}

/// The poses of every frame `-1..=n` relative to one spatial frame `s` (the thesis's `P_s` and
/// `Theta_s`, 2.2.3): column/entry `b + 1` belongs to frame `b`.
#[derive(Clone, Debug, PartialEq)]
pub struct FramePoses {
    /// `[p_sG p_s0 ... p_sn]`, 2 x (n + 2), metres.
    pub positions_m: Matrix2xX<f64>,
    /// `Theta_s = (theta_sG, theta_s0, ..., theta_sn)`, n + 2 entries, radians.
    pub angles_rad: DVector<f64>,
}

impl FramePoses {
    /// A zeroed buffer for a chain with `n` flagellar links, for the `_into` functions.
    pub fn zeros(n: usize) -> FramePoses {
        FramePoses {
            positions_m: Matrix2xX::zeros(n + 2),
            angles_rad: DVector::zeros(n + 2),
        }
    }

    /// The position of frame `b` (`None` if `b` is outside the chain).
    pub fn position_m(&self, b: Frame) -> Option<Vector2<f64>> {
        let slot = usize::try_from(b.index() + 1).ok()?;
        (slot < self.positions_m.ncols()).then(|| self.positions_m.column(slot).into_owned())
    }

    /// The angle of frame `b` (`None` if `b` is outside the chain).
    pub fn angle_rad(&self, b: Frame) -> Option<f64> {
        let slot = usize::try_from(b.index() + 1).ok()?;
        self.angles_rad.get(slot).copied()
    }

    pub(crate) fn check_shape(&self, n: usize) -> Result<(), KinematicsError> {
        if self.positions_m.ncols() != n + 2 {
            return Err(KinematicsError::WrongShape {
                argument: "positions_m",
                expected_rows: 2,
                expected_cols: n + 2,
                rows: 2,
                cols: self.positions_m.ncols(),
            });
        }
        if self.angles_rad.len() != n + 2 {
            return Err(KinematicsError::WrongLength {
                argument: "angles_rad",
                expected: n + 2,
                actual: self.angles_rad.len(),
            });
        }
        Ok(())
    }
}

/// The pose of frame `b` relative to frame `s` (thesis 2.2.1.6), in `O(|b - s|)` without
/// allocating.
///
/// # Errors
/// [`KinematicsError::WrongLength`] if `theta` does not have `n + 1` entries,
/// [`KinematicsError::FrameOutOfRange`] if `s` or `b` is outside `-1..=n`.
pub fn frame_pose(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
    b: Frame,
) -> Result<Pose2, KinematicsError> {
    chain.check_len("theta", theta.len())?;
    let n = chain.n();
    s.check(n, "s")?;
    b.check(n, "b")?;
    Ok(frame_pose_unchecked(chain.link_lengths_m(), theta, s, b))
}

/// The tip pose `(p_Gn, theta_Gn)` relative to the ground frame, in `O(n)` without
/// allocating.
///
/// # Errors
/// [`KinematicsError::WrongLength`] if `theta` does not have `n + 1` entries.
pub fn tip_pose(chain: &Chain, theta: &[f64]) -> Result<Pose2, KinematicsError> {
    frame_pose(chain, theta, Frame::GROUND, chain.tip())
}

pub(crate) fn frame_pose_unchecked(lengths: &[f64], theta: &[f64], s: Frame, b: Frame) -> Pose2 {
    let (si, bi) = (s.index(), b.index());
    let mut psi = 0.0_f64;
    let (mut x, mut y) = (0.0_f64, 0.0_f64);
    if bi > si {
        let range = s.slot()..b.slot();
        for (&t, &l) in theta[range.clone()].iter().zip(&lengths[range]) {
            psi += t;
            let (sn, cs) = psi.sin_cos();
            x += l * cs;
            y += l * sn;
        }
    } else if bi < si {
        let range = b.slot()..s.slot();
        for (&t, &l) in theta[range.clone()].iter().zip(&lengths[range]).rev() {
            let (sn, cs) = psi.sin_cos();
            x -= l * cs;
            y -= l * sn;
            psi -= t;
        }
    }
    Pose2 {
        position_m: Vector2::new(x, y),
        angle_rad: psi,
    }
}

/// The poses of every frame relative to `s` (thesis 2.2.3.3-4) in `O(n)`.
///
/// # Errors
/// As [`frame_pose`].
pub fn frame_poses(chain: &Chain, theta: &[f64], s: Frame) -> Result<FramePoses, KinematicsError> {
    let mut out = FramePoses::zeros(chain.n());
    frame_poses_into(chain, theta, s, &mut out)?;
    Ok(out)
}

/// [`frame_poses`] into a caller-supplied buffer (see [`FramePoses::zeros`]); no allocation.
///
/// # Errors
/// As [`frame_pose`], plus [`KinematicsError::WrongShape`] / [`KinematicsError::WrongLength`]
/// if `out` is not sized for the chain.
pub fn frame_poses_into(
    chain: &Chain,
    theta: &[f64],
    s: Frame,
    out: &mut FramePoses,
) -> Result<(), KinematicsError> {
    chain.check_len("theta", theta.len())?;
    let n = chain.n();
    s.check(n, "s")?;
    out.check_shape(n)?;
    let lengths = chain.link_lengths_m();
    let pos = out.positions_m.as_mut_slice();
    let ang = out.angles_rad.as_mut_slice();
    let k = s.slot(); // slot of s; link i lives in slot i + 1
    pos[2 * k] = 0.0;
    pos[2 * k + 1] = 0.0;
    ang[k] = 0.0;

    // Distal of s: slots k+1..=n+1 hold frames s+1..=n (links s+1..=n = theta indices k..=n).
    {
        let (mut psi, mut x, mut y) = (0.0_f64, 0.0_f64, 0.0_f64);
        let p_out = pos[2 * (k + 1)..].chunks_exact_mut(2);
        let a_out = &mut ang[k + 1..];
        for (((&t, &l), p), a) in theta[k..].iter().zip(&lengths[k..]).zip(p_out).zip(a_out) {
            psi += t;
            let (sn, cs) = psi.sin_cos();
            x += l * cs;
            y += l * sn;
            p[0] = x;
            p[1] = y;
            *a = psi;
        }
    }
    // Proximal of s: slots k-1 down to 0 hold frames s-1..=-1 (links s..=0 = theta k-1..=0).
    {
        let (mut psi, mut x, mut y) = (0.0_f64, 0.0_f64, 0.0_f64);
        let p_out = pos[..2 * k].chunks_exact_mut(2).rev();
        let a_out = ang[..k].iter_mut().rev();
        for (((&t, &l), p), a) in theta[..k]
            .iter()
            .zip(&lengths[..k])
            .rev()
            .zip(p_out)
            .zip(a_out)
        {
            let (sn, cs) = psi.sin_cos();
            x -= l * cs;
            y -= l * sn;
            psi -= t;
            p[0] = x;
            p[1] = y;
            *a = psi;
        }
    }
    Ok(())
}
