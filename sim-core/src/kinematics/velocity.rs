//! Differential kinematics (thesis 2.2.1.2, 2.2.3.2, 6.1.2): the hybrid velocity of one frame
//! or of every frame relative to `s`, by prefix sums, without forming a Jacobian.
//!
//! Relative to `s`, `psi_dot_i = phi_dot_i - phi_dot_s` is a running sum of `theta_dot` away
//! from `s`, and `p_dot_sb` is the running sum of `l_i R90 (cos psi_i, sin psi_i) psi_dot_i`
//! over the links between `s` and `b` (with the sign of `alpha_sb`).

use nalgebra::{DVector, Matrix2xX, Vector2};

use crate::{Chain, Frame, KinematicsError};

/// The hybrid velocity `V_h = (p_dot_sb, omega_sb)` of a frame or point: its velocity
/// relative to `C_s`, written in `C_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Twist2 {
    /// Translational velocity in m/s (per rad/s of joint rate).
    pub linear_m_per_s: Vector2<f64>,
    /// Angular velocity in rad/s.
    pub angular_rad_per_s: f64,
}

/// The hybrid velocities of every frame `-1..=n` relative to `s` (thesis `P_dot_s`,
/// `Theta_dot_s`, 2.2.3.2): column/entry `b + 1` belongs to frame `b`.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameVelocities {
    /// `[p_dot_sG ... p_dot_sn]`, 2 x (n + 2), m/s.
    pub linear_m_per_s: Matrix2xX<f64>,
    /// `(omega_sG, ..., omega_sn)`, n + 2 entries, rad/s.
    pub angular_rad_per_s: DVector<f64>,
}

impl FrameVelocities {
    /// A zeroed buffer for a chain with `n` flagellar links, for the `_into` functions.
    pub fn zeros(n: usize) -> FrameVelocities {
        FrameVelocities {
            linear_m_per_s: Matrix2xX::zeros(n + 2),
            angular_rad_per_s: DVector::zeros(n + 2),
        }
    }

    /// The velocity of frame `b` (`None` if `b` is outside the chain).
    pub fn twist(&self, b: Frame) -> Option<Twist2> {
        let slot = usize::try_from(b.index() + 1).ok()?;
        (slot < self.linear_m_per_s.ncols()).then(|| Twist2 {
            linear_m_per_s: self.linear_m_per_s.column(slot).into_owned(),
            angular_rad_per_s: self.angular_rad_per_s[slot],
        })
    }
}

/// The hybrid velocity of frame `b` relative to `s` (thesis 2.2.1.14, 2.2.1.9) in
/// `O(|b - s|)` without allocating.
///
/// # Errors
/// [`KinematicsError::WrongLength`] if `theta` or `theta_dot` does not have `n + 1` entries,
/// [`KinematicsError::FrameOutOfRange`] if `s` or `b` is outside `-1..=n`.
pub fn frame_velocity(
    chain: &Chain,
    theta: &[f64],
    theta_dot: &[f64],
    s: Frame,
    b: Frame,
) -> Result<Twist2, KinematicsError> {
    chain.check_len("theta", theta.len())?;
    chain.check_len("theta_dot", theta_dot.len())?;
    let n = chain.n();
    s.check(n, "s")?;
    b.check(n, "b")?;
    let lengths = chain.link_lengths_m();
    let (mut psi, mut rate) = (0.0_f64, 0.0_f64);
    let (mut vx, mut vy) = (0.0_f64, 0.0_f64);
    if b > s {
        let r = s.slot()..b.slot();
        for ((&t, &td), &l) in theta[r.clone()]
            .iter()
            .zip(&theta_dot[r.clone()])
            .zip(&lengths[r])
        {
            psi += t;
            rate += td;
            let (sn, cs) = psi.sin_cos();
            vx -= l * sn * rate;
            vy += l * cs * rate;
        }
    } else if b < s {
        let r = b.slot()..s.slot();
        for ((&t, &td), &l) in theta[r.clone()]
            .iter()
            .zip(&theta_dot[r.clone()])
            .zip(&lengths[r])
            .rev()
        {
            let (sn, cs) = psi.sin_cos();
            vx += l * sn * rate;
            vy -= l * cs * rate;
            psi -= t;
            rate -= td;
        }
    }
    Ok(Twist2 {
        linear_m_per_s: Vector2::new(vx, vy),
        angular_rad_per_s: rate,
    })
}

/// The hybrid velocities of every frame relative to `s` (thesis 2.2.3.6-7) in `O(n)`.
///
/// # Errors
/// As [`frame_velocity`].
pub fn frame_velocities(
    chain: &Chain,
    theta: &[f64],
    theta_dot: &[f64],
    s: Frame,
) -> Result<FrameVelocities, KinematicsError> {
    let mut out = FrameVelocities::zeros(chain.n());
    frame_velocities_into(chain, theta, theta_dot, s, &mut out)?;
    Ok(out)
}

/// [`frame_velocities`] into a caller-supplied buffer (see [`FrameVelocities::zeros`]); no
/// allocation.
///
/// # Errors
/// As [`frame_velocity`], plus [`KinematicsError::WrongShape`] /
/// [`KinematicsError::WrongLength`] if `out` is not sized for the chain.
pub fn frame_velocities_into(
    chain: &Chain,
    theta: &[f64],
    theta_dot: &[f64],
    s: Frame,
    out: &mut FrameVelocities,
) -> Result<(), KinematicsError> {
    chain.check_len("theta", theta.len())?;
    chain.check_len("theta_dot", theta_dot.len())?;
    let n = chain.n();
    s.check(n, "s")?;
    if out.linear_m_per_s.ncols() != n + 2 {
        return Err(KinematicsError::WrongShape {
            argument: "linear_m_per_s",
            expected_rows: 2,
            expected_cols: n + 2,
            rows: 2,
            cols: out.linear_m_per_s.ncols(),
        });
    }
    if out.angular_rad_per_s.len() != n + 2 {
        return Err(KinematicsError::WrongLength {
            argument: "angular_rad_per_s",
            expected: n + 2,
            actual: out.angular_rad_per_s.len(),
        });
    }
    let lengths = chain.link_lengths_m();
    let lin = out.linear_m_per_s.as_mut_slice();
    let ang = out.angular_rad_per_s.as_mut_slice();
    let k = s.slot();
    lin[2 * k] = 0.0;
    lin[2 * k + 1] = 0.0;
    ang[k] = 0.0;
    {
        let (mut psi, mut rate, mut vx, mut vy) = (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
        let v_out = lin[2 * (k + 1)..].chunks_exact_mut(2);
        let w_out = &mut ang[k + 1..];
        let inputs = theta[k..].iter().zip(&theta_dot[k..]).zip(&lengths[k..]);
        for (((&t, &td), &l), (v, w)) in inputs.zip(v_out.zip(w_out)) {
            psi += t;
            rate += td;
            let (sn, cs) = psi.sin_cos();
            vx -= l * sn * rate;
            vy += l * cs * rate;
            v[0] = vx;
            v[1] = vy;
            *w = rate;
        }
    }
    {
        let (mut psi, mut rate, mut vx, mut vy) = (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
        let v_out = lin[..2 * k].chunks_exact_mut(2).rev();
        let w_out = ang[..k].iter_mut().rev();
        let inputs = theta[..k]
            .iter()
            .zip(&theta_dot[..k])
            .zip(&lengths[..k])
            .rev();
        for (((&t, &td), &l), (v, w)) in inputs.zip(v_out.zip(w_out)) {
            let (sn, cs) = psi.sin_cos();
            vx += l * sn * rate;
            vy -= l * cs * rate;
            psi -= t;
            rate -= td;
            v[0] = vx;
            v[1] = vy;
            *w = rate;
        }
    }
    Ok(())
}
