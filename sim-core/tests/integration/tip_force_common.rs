//! Shared strategies for the `tip_force*` tests: exact equilibria built without a solver.
//!
//! Pick a chain's geometry, a posture `theta` inside the limits, a tip force `F` (on the
//! tip, ground frame) and stop torques `s` at some joints; then choose the rest angles so
//! that `k_j (theta_j - rest_j) = (J_Gn^T F)_j + s_j` holds (up to rounding) at every
//! flexible joint, and put each joint with `s_j != 0` on the stop that pushes that way
//! (`s_j > 0`: the clockwise stop sits at `theta_j`). `J_Gn^T F` comes from
//! `sim_core::kinematics::jacobian::tip_jacobian`, not from the code under test.
#![allow(dead_code, clippy::unwrap_used)]

use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::{DMatrix, DVector, Vector2};
use proptest::prelude::*;
use sim_core::kinematics::jacobian::tip_jacobian;
use sim_core::{Chain, JointLimit};

/// An exact equilibrium.
#[derive(Clone, Debug)]
pub struct Equilibrium {
    pub chain: Chain,
    pub theta: Vec<f64>,
    /// The force on the tip, N.
    pub force_n: Vector2<f64>,
    /// `n + 1` stop torques (zero where free and at the base), N m.
    pub stop_nm: Vec<f64>,
    /// `n + 1` flags: joint on a limit.
    pub on_limit: Vec<bool>,
}

impl Equilibrium {
    /// `J_Gn^T F` (translational rows), `n + 1` entries.
    pub fn jt_f(&self) -> DVector<f64> {
        jt(&self.chain, &self.theta) * self.force_n
    }

    /// A bound on the rounding of the construction, per the `n` joint equations together:
    /// `k_j (theta_j - rest_j)` recomputed from the rounded rest angles differs from
    /// `(J^T F)_j + s_j` by a few ulps of `k_j (|theta_j| + |rest_j|)` and of `|J^T F|`.
    pub fn rounding_nm(&self) -> f64 {
        let k = self.chain.stiffness_nm_per_rad();
        let r = self.chain.rest_angles_rad();
        let jt_f = self.jt_f();
        let worst = (1..self.chain.dof())
            .map(|j| k[j] * (self.theta[j].abs() + r[j].abs()) + jt_f[j].abs())
            .fold(0.0, f64::max);
        8.0 * f64::EPSILON * (self.chain.n() as f64).sqrt() * worst
    }

    /// The smallest singular value of `J^T` over the joints not on a limit (metres).
    pub fn sigma_min_free_m(&self) -> f64 {
        let a = jt(&self.chain, &self.theta);
        let free: Vec<usize> = (1..self.chain.dof())
            .filter(|&j| !self.on_limit[j])
            .collect();
        let a = DMatrix::from_fn(free.len(), 2, |r, c| a[(free[r], c)]);
        singular_values_2(&a).1
    }

    /// What a backward-stable fit may miss `F` by on this construction: `1e-9 |F|` plus the
    /// construction's rounding over the smallest singular value (perturbation bound).
    pub fn force_tol_n(&self) -> f64 {
        1e-9 * self.force_n.norm() + self.rounding_nm() / self.sigma_min_free_m()
    }

    /// What "zero residual" means here: the construction's rounding plus `1e-12 sqrt(n)`
    /// of the torque scale (the fit's own rounding).
    pub fn residual_tol_nm(&self) -> f64 {
        4.0 * self.rounding_nm() + 1e-12 * (self.chain.n() as f64).sqrt() * self.torque_scale()
    }

    /// The condition number of `J^T` over the joints not on a limit.
    pub fn condition_number(&self) -> f64 {
        let a = jt(&self.chain, &self.theta);
        let free: Vec<usize> = (1..self.chain.dof())
            .filter(|&j| !self.on_limit[j])
            .collect();
        let a = DMatrix::from_fn(free.len(), 2, |r, c| a[(free[r], c)]);
        let (max, min) = singular_values_2(&a);
        max / min
    }

    /// Scale of the spring torques: `max_j |k_j (theta_j - rest_j)|`.
    pub fn torque_scale(&self) -> f64 {
        let k = self.chain.stiffness_nm_per_rad();
        let r = self.chain.rest_angles_rad();
        (1..self.chain.dof())
            .map(|j| (k[j] * (self.theta[j] - r[j])).abs())
            .fold(0.0, f64::max)
    }
}

/// `(sigma_max, sigma_min)` of an `m x 2` matrix, from its Gram-Schmidt factor
/// `R = [r11 r12; 0 r22]`: `sigma_max^2 + sigma_min^2 = |R|_F^2` and
/// `sigma_max sigma_min = |r11 r22|`. (nalgebra's SVD is avoided: see `tip_force.rs`.)
pub fn singular_values_2(a: &DMatrix<f64>) -> (f64, f64) {
    let (c0, c1) = (a.column(0), a.column(1));
    let r11 = c0.norm();
    if r11 == 0.0 {
        return (c1.norm(), 0.0);
    }
    let q = c0 / r11;
    let r12 = q.dot(&c1);
    let r22 = (c1 - q * r12).norm();
    let f2 = r11 * r11 + r12 * r12 + r22 * r22;
    let det = r11 * r22;
    let max = ((f2 + (f2 * f2 - 4.0 * det * det).max(0.0).sqrt()) / 2.0).sqrt();
    (max, if max == 0.0 { 0.0 } else { det / max })
}

/// `J_Gn^T` restricted to the translational rows: `(n + 1) x 2`.
pub fn jt(chain: &Chain, theta: &[f64]) -> DMatrix<f64> {
    let j = tip_jacobian(chain, theta).unwrap();
    DMatrix::from_fn(chain.dof(), 2, |r, c| j[(c, r)])
}

/// Geometry: `n + 1` link lengths (5-100 mm), base angle, `n` joint angles inside
/// `[-pi/2, pi/2]` (the default limits), `n` stiffnesses (log-uniform 1e-3..1e-1 N m/rad).
pub fn geometry(
    n: std::ops::RangeInclusive<usize>,
) -> impl Strategy<Value = (Vec<f64>, f64, Vec<f64>, Vec<f64>)> {
    n.prop_flat_map(|n| {
        (
            prop::collection::vec(0.005..0.1f64, n + 1),
            -PI..PI,
            prop::collection::vec(-FRAC_PI_2 + 0.01..FRAC_PI_2 - 0.01, n),
            prop::collection::vec((-3.0..-1.0f64).prop_map(|e| 10f64.powf(e)), n),
        )
    })
}

/// A tip force with components in [-1, 1] N and magnitude at least 0.05 N.
pub fn force() -> impl Strategy<Value = Vector2<f64>> {
    (0.05..1.0f64, -PI..PI).prop_map(|(m, a)| Vector2::new(m * a.cos(), m * a.sin()))
}

/// Builds the exact equilibrium; `stop_factor[j - 1]` (one per flexible joint) is the stop
/// torque at joint `j` relative to the scale of `J^T F` (zero: the joint is free).
pub fn build(
    lengths: Vec<f64>,
    base: f64,
    joints: Vec<f64>,
    stiffness: Vec<f64>,
    force_n: Vector2<f64>,
    stop_factor: &[f64],
) -> Equilibrium {
    let n = joints.len();
    let mut theta = vec![base];
    theta.extend(&joints);
    let probe = Chain::builder(n)
        .link_lengths_m(lengths.clone())
        .base_angle_rad(base)
        .build()
        .unwrap();
    let jt_f = jt(&probe, &theta) * force_n;
    let scale = force_n.norm() * lengths.iter().sum::<f64>();
    let mut stop_nm = vec![0.0; n + 1];
    let mut on_limit = vec![false; n + 1];
    let mut limits = Vec::with_capacity(n);
    let mut rest = Vec::with_capacity(n);
    for j in 1..=n {
        let s = stop_factor.get(j - 1).copied().unwrap_or(0.0) * scale;
        stop_nm[j] = s;
        on_limit[j] = s != 0.0;
        limits.push(if s > 0.0 {
            JointLimit::new(theta[j], FRAC_PI_2)
        } else if s < 0.0 {
            JointLimit::new(-FRAC_PI_2, theta[j])
        } else {
            JointLimit::new(-FRAC_PI_2, FRAC_PI_2)
        });
        rest.push(theta[j] - (jt_f[j] + s) / stiffness[j - 1]);
    }
    let chain = Chain::builder(n)
        .link_lengths_m(lengths)
        .base_angle_rad(base)
        .joint_limits(limits)
        .stiffnesses_nm_per_rad(stiffness)
        .rest_angles_rad(rest)
        .build()
        .unwrap();
    Equilibrium {
        chain,
        theta,
        force_n,
        stop_nm,
        on_limit,
    }
}

/// Free equilibria (no joint on a limit) with `n` in the range.
pub fn free_equilibrium(n: std::ops::RangeInclusive<usize>) -> impl Strategy<Value = Equilibrium> {
    (geometry(n), force()).prop_map(|((l, b, j, k), f)| build(l, b, j, k, f, &[]))
}

/// Equilibria with some joints on a limit: each flexible joint is on a limit with
/// probability about 1/3, with a stop torque of 0.2-1 times the scale `|F| L` and either
/// sign, keeping at least three joints free.
pub fn limited_equilibrium(
    n: std::ops::RangeInclusive<usize>,
) -> impl Strategy<Value = Equilibrium> {
    (geometry(n), force())
        .prop_flat_map(|(g, f)| {
            let n = g.2.len();
            let stop = prop_oneof![
                2 => Just(0.0),
                1 => (0.2..1.0f64, any::<bool>()).prop_map(|(m, neg)| if neg { -m } else { m }),
            ];
            (Just(g), Just(f), prop::collection::vec(stop, n))
        })
        .prop_filter("three free joints and one on a limit", |(_, _, s)| {
            s.iter().filter(|&&x| x == 0.0).count() >= 3 && s.iter().any(|&x| x != 0.0)
        })
        .prop_map(|((l, b, j, k), f, s)| build(l, b, j, k, f, &s))
}

/// `|a - b| <= tol * scale`.
pub fn close(what: &str, a: f64, b: f64, tol: f64, scale: f64) -> Result<(), TestCaseError> {
    let d = (a - b).abs();
    prop_assert!(
        d <= tol * scale,
        "{what}: {a:e} vs {b:e}, diff {d:e} > {tol:e} * {scale:e}"
    );
    Ok(())
}

/// `|a - b| <= tol * scale` for 2-vectors.
pub fn close2(
    what: &str,
    a: Vector2<f64>,
    b: Vector2<f64>,
    tol: f64,
    scale: f64,
) -> Result<(), TestCaseError> {
    let d = (a - b).norm();
    prop_assert!(
        d <= tol * scale,
        "{what}: {a:?} vs {b:?}, diff {d:e} > {tol:e} * {scale:e}"
    );
    Ok(())
}
