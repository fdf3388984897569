//! The joint-limit map `theta = g(q)` (thesis 2.2.4, docs/model.md 3):
//! `g_j(q_j) = (ccw_j + cw_j)/2 + (ccw_j - cw_j)/2 sin q_j`, which turns the bound-constrained
//! problem in `theta` into an unconstrained one in `q`.
//!
//! `g` acts joint by joint, so its Jacobian is diagonal and its second derivative is a
//! diagonal third-order tensor; both are returned as vectors of the diagonal:
//! `dtheta_j/dq_j = +(ccw_j - cw_j)/2 cos q_j` and `d2theta_j/dq_j^2 = -(ccw_j - cw_j)/2 sin q_j`.
//! (The thesis prints the first with a minus sign, 2.2.4.5, and the second with `cos q`,
//! 2.2.4.6; docs/model.md 3 records the erratum and the tests check these against finite
//! differences.)

use nalgebra::DVector;

use crate::{Chain, JointLimit, KinematicsError};

impl JointLimit {
    /// `g(q)` for this joint.
    pub fn theta_from_q(&self, q_rad: f64) -> f64 {
        self.mid_rad() + self.half_range_rad() * q_rad.sin()
    }

    /// `dg/dq = (ccw - cw)/2 cos q`.
    pub fn dtheta_dq(&self, q_rad: f64) -> f64 {
        self.half_range_rad() * q_rad.cos()
    }

    /// `d2g/dq2 = -(ccw - cw)/2 sin q`.
    pub fn d2theta_dq2(&self, q_rad: f64) -> f64 {
        -self.half_range_rad() * q_rad.sin()
    }

    /// `g^-1(theta) = asin((2 theta - ccw - cw) / (ccw - cw))` in `[-pi/2, pi/2]`; `0` for a
    /// fixed joint (`cw = ccw`, the thesis's pseudo-inverse). `None` if `theta` is outside the
    /// limits by more than a few rounding errors (within that, it is clamped).
    pub fn q_from_theta(&self, theta_rad: f64) -> Option<f64> {
        let tol = 8.0 * f64::EPSILON * self.cw_rad.abs().max(self.ccw_rad.abs()).max(1.0);
        if !(theta_rad >= self.cw_rad - tol && theta_rad <= self.ccw_rad + tol) {
            return None;
        }
        let h = self.half_range_rad();
        if h == 0.0 {
            return Some(0.0);
        }
        Some(((theta_rad - self.mid_rad()) / h).clamp(-1.0, 1.0).asin())
    }
}

fn check(chain: &Chain, argument: &'static str, v: &[f64]) -> Result<(), KinematicsError> {
    chain.check_len(argument, v.len())
}

/// `theta = g(q)` for the whole chain (thesis 2.2.4.2). Joint 0 maps to the base angle for
/// every `q_0`.
///
/// # Errors
/// [`KinematicsError::WrongLength`] if `q` does not have `n + 1` entries.
pub fn theta_from_q(chain: &Chain, q: &[f64]) -> Result<DVector<f64>, KinematicsError> {
    check(chain, "q", q)?;
    Ok(DVector::from_iterator(
        q.len(),
        chain
            .joint_limits()
            .iter()
            .zip(q)
            .map(|(lim, &q)| lim.theta_from_q(q)),
    ))
}

/// `q = g^-1(theta)` (thesis 2.2.4.1), in `[-pi/2, pi/2]`, with `q_j = 0` where the limits are
/// equal (the thesis's pseudo-inverse).
///
/// # Errors
/// [`KinematicsError::WrongLength`] if `theta` does not have `n + 1` entries,
/// [`KinematicsError::OutsideLimits`] naming the first joint outside its limits (for joint
/// 0, any angle other than the base angle).
pub fn q_from_theta(chain: &Chain, theta: &[f64]) -> Result<DVector<f64>, KinematicsError> {
    check(chain, "theta", theta)?;
    let mut q = DVector::zeros(theta.len());
    for (index, (lim, &t)) in chain.joint_limits().iter().zip(theta).enumerate() {
        q[index] = lim.q_from_theta(t).ok_or(KinematicsError::OutsideLimits {
            index,
            value_rad: t,
            cw_rad: lim.cw_rad,
            ccw_rad: lim.ccw_rad,
        })?;
    }
    Ok(q)
}

/// The diagonal of the Jacobian `J_g = dtheta/dq` (thesis 2.2.4.5, sign corrected):
/// `(ccw_j - cw_j)/2 cos q_j`.
///
/// # Errors
/// [`KinematicsError::WrongLength`] if `q` does not have `n + 1` entries.
pub fn dtheta_dq(chain: &Chain, q: &[f64]) -> Result<DVector<f64>, KinematicsError> {
    check(chain, "q", q)?;
    Ok(DVector::from_iterator(
        q.len(),
        chain
            .joint_limits()
            .iter()
            .zip(q)
            .map(|(lim, &q)| lim.dtheta_dq(q)),
    ))
}

/// The diagonal of the second derivative `d2theta_j/dq_j^2` (thesis 2.2.4.6, corrected):
/// `-(ccw_j - cw_j)/2 sin q_j`.
///
/// # Errors
/// [`KinematicsError::WrongLength`] if `q` does not have `n + 1` entries.
pub fn d2theta_dq2(chain: &Chain, q: &[f64]) -> Result<DVector<f64>, KinematicsError> {
    check(chain, "q", q)?;
    Ok(DVector::from_iterator(
        q.len(),
        chain
            .joint_limits()
            .iter()
            .zip(q)
            .map(|(lim, &q)| lim.d2theta_dq2(q)),
    ))
}
