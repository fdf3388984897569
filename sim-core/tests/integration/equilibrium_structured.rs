//! (h) The `O(n)` solve of `diag(d) + [a_max(i,j)]` equals a dense nalgebra solve on random
//! structured matrices, its pivots count the negative eigenvalues, and at n = 4096 the
//! residual computed with an independent `O(n^2)` product is at rounding level.
#![allow(clippy::unwrap_used)]

use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;
use sim_core::statics::equilibrium::SemiseparableMatrix;

fn dense_product(m: &SemiseparableMatrix, x: &[f64]) -> Vec<f64> {
    let n = m.dim();
    (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    (m.coefficients[i.max(j)] + if i == j { m.diagonal[i] } else { 0.0 }) * x[j]
                })
                .sum()
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn structured_solve_equals_dense(n in 1usize..120, seed in proptest::collection::vec(-1.0f64..1.0, 360), spread in 0.0f64..6.0) {
        // Stiffness-like diagonal spanning up to 1e6, coefficients of either sign.
        let d: Vec<f64> = (0..n).map(|i| 10f64.powf(spread * (seed[i] + 1.0) / 2.0)).collect();
        let a: Vec<f64> = (0..n).map(|i| seed[n + i] * 3.0).collect();
        let b: Vec<f64> = (0..n).map(|i| seed[2 * n + i]).collect();
        let m = SemiseparableMatrix::new(d, a);
        let dense = m.to_dense();
        let f = m.factor();
        let x = f.solve(&b);
        let eig = dense.clone().symmetric_eigen();
        let neg = eig.eigenvalues.iter().filter(|&&l| l < 0.0).count();
        let min_abs = eig.eigenvalues.iter().fold(f64::INFINITY, |m, l| m.min(l.abs()));
        let max_abs = eig.eigenvalues.amax();
        if min_abs > 1e-8 * max_abs {
            prop_assert_eq!(f.inertia().negative, neg);
            let xd = dense.clone().lu().solve(&DVector::from_vec(b.clone())).unwrap();
            let cond = max_abs / min_abs;
            let err = (DVector::from_vec(x.clone()) - &xd).amax() / xd.amax().max(1e-300);
            prop_assert!(err <= 1e-13 * cond.max(1.0) * n as f64, "n {} err {} cond {}", n, err, cond);
        }
        // The O(n) product agrees with the dense one.
        let p1 = m.mul_vec(&b);
        let p2 = &dense * DVector::from_vec(b.clone());
        for (u, v) in p1.iter().zip(p2.iter()) {
            prop_assert!((u - v).abs() <= 1e-12 * (1.0 + v.abs()) * n as f64);
        }
        // The modified factorization is positive definite and solves H + E with E >= 0 diagonal.
        let fm = m.factor_modified(1e-6);
        prop_assert!(fm.pivots().iter().all(|&p| p >= 1e-6));
    }
}

/// n = 4096, positive definite (a stiffness-like diagonal with ratio 1e6 between neighbours
/// and a tensile load): residual against an independent O(n^2) product.
#[test]
fn large_structured_solve_has_small_residual() {
    let n = 4096;
    let d: Vec<f64> = (0..n)
        .map(|i| if i % 2 == 0 { 1.0 } else { 1e-6 })
        .collect();
    let a: Vec<f64> = (0..n).map(|i| 0.5 * (n - i) as f64 / n as f64).collect();
    let b: Vec<f64> = (0..n)
        .map(|i| ((i * 7919) % 113) as f64 / 113.0 - 0.5)
        .collect();
    let m = SemiseparableMatrix::new(d, a);
    let f = m.factor();
    assert_eq!(f.inertia().negative, 0);
    let x = f.solve(&b);
    let hx = dense_product(&m, &x);
    let res = hx
        .iter()
        .zip(&b)
        .map(|(u, v)| (u - v).abs())
        .fold(0.0, f64::max);
    let xmax = x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    assert!(res <= 1e-9 * (1.0 + xmax), "residual {res}, |x| {xmax}");
    let _ = DMatrix::<f64>::zeros(1, 1);
}
