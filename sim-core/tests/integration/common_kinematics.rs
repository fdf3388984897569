//! Shared strategies and comparisons for the `kinematics*` tests of sim-core.
//!
//! Random chains: `n` links on a base link, lengths 5-100 mm (uniform or per link), base
//! angle in [-pi, pi], joint angles inside the robot's limits [-pi/2, pi/2], joint rates in
//! [-2, 2] rad/s, and any frame pair `(s, b)` in `-1..=n`.
#![allow(dead_code, clippy::unwrap_used)]

use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::{DMatrix, Dyn, Matrix, RawStorage, U1, Vector2};
use proptest::prelude::*;
use sim_core::{Chain, Frame};

/// A chain, a state and a frame pair.
#[derive(Clone, Debug)]
pub struct Case {
    pub chain: Chain,
    pub theta: Vec<f64>,
    pub theta_dot: Vec<f64>,
    pub s: Frame,
    pub b: Frame,
}

impl Case {
    /// The sum of the link lengths: the scale of every position.
    pub fn length_scale(&self) -> f64 {
        self.chain.total_length_m()
    }

    /// A bound on every velocity: total length times the sum of |theta_dot|.
    pub fn velocity_scale(&self) -> f64 {
        self.length_scale() * self.theta_dot.iter().map(|v| v.abs()).sum::<f64>().max(1.0)
    }

    /// A bound on every angular velocity: the sum of |theta_dot| (at least 1).
    pub fn angular_velocity_scale(&self) -> f64 {
        self.theta_dot.iter().map(|v| v.abs()).sum::<f64>().max(1.0)
    }

    /// A bound on every frame angle: the sum of |theta|.
    pub fn angle_scale(&self) -> f64 {
        self.theta.iter().map(|v| v.abs()).sum::<f64>().max(1.0)
    }
}

/// Link lengths: one for all, or one per link.
fn lengths(n: usize) -> impl Strategy<Value = Vec<f64>> {
    prop_oneof![
        (0.005..0.1f64).prop_map(move |l| vec![l; n + 1]),
        prop::collection::vec(0.005..0.1f64, n + 1),
    ]
}

/// A random chain with `n` in `n_range` and a random state and frame pair.
pub fn case(n_range: std::ops::RangeInclusive<usize>) -> impl Strategy<Value = Case> {
    n_range.prop_flat_map(|n| {
        let frame = -1..=(n as isize);
        (
            lengths(n),
            -PI..PI,
            prop::collection::vec(-FRAC_PI_2..FRAC_PI_2, n),
            prop::collection::vec(-2.0..2.0f64, n + 1),
            frame.clone(),
            frame,
        )
            .prop_map(move |(lengths, base, joints, theta_dot, s, b)| {
                let chain = Chain::builder(n)
                    .link_lengths_m(lengths)
                    .base_angle_rad(base)
                    .build()
                    .unwrap();
                let mut theta = Vec::with_capacity(n + 1);
                theta.push(base);
                theta.extend(joints);
                Case {
                    chain,
                    theta,
                    theta_dot,
                    s: Frame::new(s),
                    b: Frame::new(b),
                }
            })
    })
}

/// Max absolute entry-wise difference of two matrices of the same shape.
pub fn max_diff<R1, C1, S1, R2, C2, S2>(
    a: &Matrix<f64, R1, C1, S1>,
    b: &Matrix<f64, R2, C2, S2>,
) -> f64
where
    R1: nalgebra::Dim,
    C1: nalgebra::Dim,
    S1: RawStorage<f64, R1, C1>,
    R2: nalgebra::Dim,
    C2: nalgebra::Dim,
    S2: RawStorage<f64, R2, C2>,
{
    assert_eq!(a.shape(), b.shape(), "shapes differ");
    a.iter()
        .zip(b.iter())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// `|a - b|_max <= tol * scale`, with a message.
pub fn assert_close<R1, C1, S1, R2, C2, S2>(
    what: &str,
    a: &Matrix<f64, R1, C1, S1>,
    b: &Matrix<f64, R2, C2, S2>,
    tol: f64,
    scale: f64,
) -> Result<(), TestCaseError>
where
    R1: nalgebra::Dim,
    C1: nalgebra::Dim,
    S1: RawStorage<f64, R1, C1>,
    R2: nalgebra::Dim,
    C2: nalgebra::Dim,
    S2: RawStorage<f64, R2, C2>,
{
    let d = max_diff(a, b);
    prop_assert!(
        d <= tol * scale,
        "{what}: max diff {d:e} > {tol:e} * scale {scale:e} (relative {:e})",
        d / scale
    );
    Ok(())
}

/// [`assert_close`] for stacked planar quantities, rows `(x, y, angle)` repeated: the linear
/// rows are compared at `tol * linear_scale`, the angular rows at `tol * angular_scale`.
/// Position rows scale with the chain's length and angle rows with the size of the frame
/// angles; one scale for both is wrong in units (regression seed in
/// `tests/proptest-regressions/kinematics_finite_differences.txt`).
pub fn assert_close_planar<R1, C1, S1, R2, C2, S2>(
    what: &str,
    a: &Matrix<f64, R1, C1, S1>,
    b: &Matrix<f64, R2, C2, S2>,
    tol: f64,
    linear_scale: f64,
    angular_scale: f64,
) -> Result<(), TestCaseError>
where
    R1: nalgebra::Dim,
    C1: nalgebra::Dim,
    S1: RawStorage<f64, R1, C1>,
    R2: nalgebra::Dim,
    C2: nalgebra::Dim,
    S2: RawStorage<f64, R2, C2>,
{
    prop_assert_eq!(a.shape(), b.shape(), "{}: shapes differ", what);
    for r in 0..a.nrows() {
        let (kind, scale) = if r % 3 == 2 {
            ("angular", angular_scale)
        } else {
            ("linear", linear_scale)
        };
        for c in 0..a.ncols() {
            let d = (a[(r, c)] - b[(r, c)]).abs();
            prop_assert!(
                d <= tol * scale,
                "{what}: {kind} row {r}, column {c}: diff {d:e} > {tol:e} * scale {scale:e} (relative {:e})",
                d / scale
            );
        }
    }
    Ok(())
}

/// Scalar version of [`assert_close`].
pub fn assert_close_f(
    what: &str,
    a: f64,
    b: f64,
    tol: f64,
    scale: f64,
) -> Result<(), TestCaseError> {
    let d = (a - b).abs();
    prop_assert!(
        d <= tol * scale,
        "{what}: {a} vs {b}, diff {d:e} > {tol:e} * {scale:e}"
    );
    Ok(())
}

/// Central differences of a vector function `f: R^m -> R^k` at `x`, step `h`: a `k x m`
/// matrix.
///
/// The quotient divides by the step actually taken, `(x + h) - (x - h)` as rounded, not by
/// `2 h`, which removes the step's own rounding from the quotient. What remains is the
/// rounding of `f` itself, `eps |f| / h`: see [`assert_close_planar`] for why the angular
/// rows need their own scale.
pub fn central_jacobian(x: &[f64], h: f64, f: impl Fn(&[f64]) -> Vec<f64>) -> DMatrix<f64> {
    let k = f(x).len();
    let mut j = DMatrix::zeros(k, x.len());
    let mut xp = x.to_vec();
    for c in 0..x.len() {
        let (plus, minus) = (x[c] + h, x[c] - h);
        xp[c] = plus;
        let fp = f(&xp);
        xp[c] = minus;
        let fm = f(&xp);
        xp[c] = x[c];
        let step = plus - minus;
        for r in 0..k {
            j[(r, c)] = (fp[r] - fm[r]) / step;
        }
    }
    j
}

/// A 2-vector as a Vec.
pub fn v2(v: Vector2<f64>) -> Vec<f64> {
    vec![v.x, v.y]
}

/// A column vector (any storage) as a dynamic matrix, for comparisons.
pub fn col<S: RawStorage<f64, Dyn, U1>>(v: &Matrix<f64, Dyn, U1, S>) -> DMatrix<f64> {
    DMatrix::from_iterator(v.nrows(), 1, v.iter().copied())
}
