//! Shared chains and independent checks for the `equilibrium_*` and `stress_*` tests.
//!
//! The checks use the kinematics of sim-core (`tip_jacobian`, `tip_pose`) and nalgebra, not
//! the solver's own structured code: equilibrium is `K (theta - rest) = J^T (F + lambda)`
//! on the free joints, computed here from the dense 3 x (n+1) tip Jacobian.
#![allow(dead_code, clippy::unwrap_used)]

use nalgebra::{DMatrix, DVector, Matrix2, Vector2};
use sim_core::kinematics::jacobian::tip_jacobian;
use sim_core::{Chain, Equilibrium, tip_pose};

/// The thesis's robot as in docs/scene-format.md: 9 links (n = 8 flexible joints) of 40 mm, the
/// fast-exponential profile of docs/model.md 5 between 0.004 and 0.082 N m/rad, limits +-90 deg.
pub fn seed_exponential_chain(base_angle_rad: f64) -> Chain {
    let n = 8;
    let f: Vec<f64> = (1..=n)
        .map(|j| (-12.0 * j as f64 / (n + 1) as f64).exp())
        .collect();
    let (lo, hi) = (f[n - 1], f[0]);
    let k: Vec<f64> = f
        .iter()
        .map(|v| 0.004 + (0.082 - 0.004) * (v - lo) / (hi - lo))
        .collect();
    Chain::builder(n)
        .link_length_m(0.04)
        .base_angle_rad(base_angle_rad)
        .stiffnesses_nm_per_rad(k)
        .build()
        .unwrap()
}

/// `p_0`, the first flexible joint.
pub fn first_joint(chain: &Chain) -> Vector2<f64> {
    let (l0, t0) = (chain.link_lengths_m()[0], chain.base_angle_rad());
    Vector2::new(l0 * t0.cos(), l0 * t0.sin())
}

/// The translational tip Jacobian columns of the flexible joints (2 x n).
pub fn flexible_jacobian(chain: &Chain, theta: &[f64]) -> DMatrix<f64> {
    let j = tip_jacobian(chain, theta).unwrap();
    let n = chain.n();
    DMatrix::from_fn(2, n, |r, c| j[(r, c + 1)])
}

/// `K (theta - rest) - J^T f` on the flexible joints: the generalized force the stops must
/// supply (zero on free joints at equilibrium).
pub fn residual_torques(chain: &Chain, theta: &[f64], f: Vector2<f64>) -> DVector<f64> {
    let j = flexible_jacobian(chain, theta);
    let n = chain.n();
    let k = chain.stiffness_nm_per_rad();
    let r = chain.rest_angles_rad();
    let spring = DVector::from_fn(n, |i, _| k[i + 1] * (theta[i + 1] - r[i + 1]));
    spring - j.transpose() * f
}

/// The least-squares force on the tip from `J^T F = K (theta - rest) - J^T F_dead` over the
/// free joints (thesis 3.2.2.11, computed here with nalgebra's SVD).
pub fn least_squares_pin_force(
    chain: &Chain,
    eq: &Equilibrium,
    dead: Vector2<f64>,
) -> Vector2<f64> {
    let theta = &eq.theta_rad;
    let j = flexible_jacobian(chain, theta);
    let rhs = residual_torques(chain, theta, dead);
    let svd = j.transpose().svd(true, true);
    let sol = svd.solve(&rhs, 1e-14).unwrap();
    Vector2::new(sol[0], sol[1])
}

/// The total potential `U - F . p_n` at `theta`, computed with sim-core's kinematics.
pub fn potential(chain: &Chain, theta: &[f64], f: Vector2<f64>) -> f64 {
    let k = chain.stiffness_nm_per_rad();
    let r = chain.rest_angles_rad();
    let u: f64 = (1..theta.len())
        .map(|j| 0.5 * k[j] * (theta[j] - r[j]).powi(2))
        .sum();
    u - f.dot(&tip_pose(chain, theta).unwrap().position_m)
}

/// The torque scale `max k + |f| L` of the solver's KKT residual.
pub fn torque_scale(chain: &Chain, f: Vector2<f64>) -> f64 {
    let kmax = chain
        .stiffness_nm_per_rad()
        .iter()
        .copied()
        .fold(0.0, f64::max);
    let l: f64 = chain.link_lengths_m()[1..].iter().sum();
    kmax + f.norm() * l
}

/// Solves a 2x2 system (for tests that need it).
pub fn solve2(m: Matrix2<f64>, b: Vector2<f64>) -> Vector2<f64> {
    m.try_inverse().unwrap() * b
}
