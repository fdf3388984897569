//! Castigliano's deflection (thesis 3.2.2.12-15, docs/model.md 4): the joint deflections a small
//! tip load causes, `delta theta = K^-1 J_Gn^T (F, M)`.
//!
//! With the spring energy written in the joint torques, `U = 1/2 sum tau_j^2 / k_j`
//! (3.2.2.13), Castigliano's second theorem gives `delta theta_j = dU/dtau_j = tau_j / k_j`
//! (3.2.2.14), and a tip load `(F, M)` loads the joints with `tau = J_Gn^T (F, M)` (3.2.2.10),
//! hence 3.2.2.15. Signs as in [`crate::statics::tip_force`]: `F` and `M` act on the tip (ground
//! frame, counter-clockwise positive), and the base (`theta_0`, held by the servo) does not
//! move.
//!
//! This is the first-order response about an **unloaded** posture: it neglects how the
//! posture change turns the load's lever arms (the load part of the Hessian in
//! [`crate::statics::energy::Potential::hessian_theta`]). About a posture already carrying a load `F_0`, the
//! first-order response is `H^-1 J^T (dF, dM)` with `H = K + [F_0 . (p_n - p_(max(i,j)-1))]`
//! instead; Castigliano's formula is then off by a relative `O(|F_0| L / k)`.

use nalgebra::Vector2;

use crate::Chain;
use crate::statics::tip_force::{TipForceError, check_finite, check_theta, cross, lever_arms_m};

/// `delta theta_j = (J_Gn^T (F, M))_j / k_j` for `j = 1..=n`, radians, `n + 1` entries with
/// `delta theta_0 = 0` (the base is held). `tip_force_n` is the force on the tip (ground
/// frame, N), `tip_moment_nm` the moment on it (N m, zero for a pin). `O(n)`.
///
/// # Errors
/// [`TipForceError::Kinematics`] if `theta` does not have `n + 1` entries,
/// [`TipForceError::NotFinite`] for a NaN or infinite angle or load,
/// [`TipForceError::ZeroStiffness`] if a flexible joint has `k_j = 0`.
///
/// # Example
/// ```
/// use nalgebra::Vector2;
/// use sim_core::statics::castigliano::castigliano_deflection_rad;
/// use sim_core::Chain;
///
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// // A straight horizontal 3-joint chain, 0.05 m links, k = 0.1 N m/rad, pushed up at the
/// // tip with 0.01 N: joint j carries the tip force's moment about it, 0.01 (3 - j + 1) 0.05.
/// let chain = Chain::builder(3).link_length_m(0.05).stiffness_nm_per_rad(0.1).build()?;
/// let d = castigliano_deflection_rad(&chain, &[0.0; 4], Vector2::new(0.0, 0.01), 0.0)?;
/// assert_eq!(d[0], 0.0);
/// assert!((d[1] - 0.01 * 0.15 / 0.1).abs() < 1e-15);
/// assert!((d[3] - 0.01 * 0.05 / 0.1).abs() < 1e-15);
/// # Ok(())
/// # }
/// ```
pub fn castigliano_deflection_rad(
    chain: &Chain,
    theta: &[f64],
    tip_force_n: Vector2<f64>,
    tip_moment_nm: f64,
) -> Result<Vec<f64>, TipForceError> {
    check_theta(chain, theta)?;
    check_finite("tip_force_n", tip_force_n.as_slice())?;
    check_finite("tip_moment_nm", &[tip_moment_nm])?;
    let k = chain.stiffness_nm_per_rad();
    if let Some(joint) = (1..chain.dof()).find(|&j| k[j] == 0.0) {
        return Err(TipForceError::ZeroStiffness { joint });
    }
    let arms = lever_arms_m(chain, theta);
    Ok((0..chain.dof())
        .map(|j| {
            if j == 0 {
                0.0
            } else {
                (cross(arms[j], tip_force_n) + tip_moment_nm) / k[j]
            }
        })
        .collect())
}
