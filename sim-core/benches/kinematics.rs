//! Kinematics benchmarks: the O(n) fast paths next to a "floor" measured in the same run
//! (n + 1 `sin_cos` calls plus the prefix sums of angles and positions: what any forward
//! kinematics must at least do), and the thesis's matrix forms at the same n.
//!
//! Run through `scripts/bench-kinematics`, which also rewrites the table in docs/benchmarks/kinematics.md.
//! Results land in `target/criterion/kinematics/<function>/<n>/new/estimates.json`.
#![allow(missing_docs, clippy::unwrap_used)]

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, SamplingMode, criterion_group, criterion_main};
use nalgebra::{DMatrix, Matrix3xX};
use sim_core::kinematics::jacobian::{all_jacobians_into, tip_jacobian_into};
use sim_core::kinematics::matrix_forms::{
    seed_all_jacobians, seed_frame_poses, seed_frame_velocities, seed_hybrid_jacobian,
};
use sim_core::kinematics::positions::{FramePoses, frame_poses_into};
use sim_core::kinematics::velocity::{FrameVelocities, frame_velocities_into};
use sim_core::{Chain, Frame};

/// The sizes measured: the thesis's robot (n = 8 gives 9 links), the cockroach's ~150 annuli,
/// and long chains for the O(n) ratio time(4096) / time(512).
pub const SIZES: [usize; 5] = [9, 150, 512, 1000, 4096];

/// The O(n^3) thesis form is skipped above this n.
pub const SEED_CUBIC_MAX_N: usize = 1000;

fn setup(n: usize) -> (Chain, Vec<f64>, Vec<f64>) {
    // deterministic pseudo-random angles inside the limits, lengths 30-50 mm
    let mut state = 0x2545_f491_4f6c_dd1d_u64 ^ n as u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let lengths: Vec<f64> = (0..=n).map(|_| 0.03 + 0.02 * next()).collect();
    let chain = Chain::builder(n)
        .link_lengths_m(lengths)
        .base_angle_rad(0.5)
        .build()
        .unwrap();
    // Joint angles in [-0.3, 0.3] rad, inside the limits, with signs chosen so the absolute
    // link angles meander within +-1.2 rad at every n. (A plain random walk drifts to
    // |phi| ~ sqrt(n) and the benchmark would then measure libm's argument reduction, which
    // grows with |phi|, rather than the algorithm.)
    let mut theta = vec![0.5; n + 1];
    let mut phi = theta[0];
    for t in theta.iter_mut().skip(1) {
        let mut step = (next() - 0.5) * 0.6;
        if (phi + step).abs() > 1.2 {
            step = -step;
        }
        phi += step;
        *t = step;
    }
    let theta_dot: Vec<f64> = (0..=n).map(|_| next() - 0.5).collect();
    (chain, theta, theta_dot)
}

/// The floor: prefix sums of angles, one `sin_cos` per link, prefix sums of positions.
#[inline(never)]
fn floor(theta: &[f64], lengths: &[f64]) -> (f64, f64) {
    let (mut phi, mut x, mut y) = (0.0_f64, 0.0_f64, 0.0_f64);
    for (&t, &l) in theta.iter().zip(lengths) {
        phi += t;
        let (s, c) = phi.sin_cos();
        x += l * c;
        y += l * s;
    }
    (x, y)
}

fn fast_paths(c: &mut Criterion) {
    let mut g = c.benchmark_group("kinematics");
    g.warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_millis(1500))
        .sample_size(30);
    for n in SIZES {
        let (chain, theta, theta_dot) = setup(n);
        let lengths = chain.link_lengths_m().to_vec();
        g.bench_with_input(BenchmarkId::new("floor", n), &n, |b, _| {
            b.iter(|| floor(black_box(&theta), black_box(&lengths)))
        });
        let mut poses = FramePoses::zeros(n);
        g.bench_with_input(BenchmarkId::new("positions", n), &n, |b, _| {
            b.iter(|| {
                frame_poses_into(&chain, black_box(&theta), Frame::GROUND, &mut poses).unwrap()
            })
        });
        let mut vels = FrameVelocities::zeros(n);
        g.bench_with_input(BenchmarkId::new("velocities", n), &n, |b, _| {
            b.iter(|| {
                frame_velocities_into(
                    &chain,
                    black_box(&theta),
                    black_box(&theta_dot),
                    Frame::GROUND,
                    &mut vels,
                )
                .unwrap()
            })
        });
        let mut jac = Matrix3xX::zeros(n + 1);
        g.bench_with_input(BenchmarkId::new("tip_jacobian", n), &n, |b, _| {
            b.iter(|| tip_jacobian_into(&chain, black_box(&theta), &mut jac).unwrap())
        });
        // The tip force that explains the joint angles (tests/integration/tip_force.rs
        // `long_chain` checks its answer at n = 4096; its O(n) cost is measured here).
        g.bench_with_input(BenchmarkId::new("tip_force", n), &n, |b, _| {
            b.iter(|| {
                sim_core::statics::tip_force::tip_force_least_squares(&chain, black_box(&theta))
                    .unwrap()
            })
        });
    }
    g.finish();

    // O(n^2) output: fewer samples.
    let mut g = c.benchmark_group("kinematics");
    g.warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1))
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat);
    for n in SIZES {
        let (chain, theta, _) = setup(n);
        let mut poses = FramePoses::zeros(n);
        let mut all = DMatrix::zeros(3 * (n + 2), n + 1);
        g.bench_with_input(BenchmarkId::new("all_jacobians", n), &n, |b, _| {
            b.iter(|| {
                all_jacobians_into(
                    &chain,
                    black_box(&theta),
                    Frame::GROUND,
                    &mut poses,
                    &mut all,
                )
                .unwrap()
            })
        });
    }
    g.finish();
}

fn seed_forms(c: &mut Criterion) {
    let mut g = c.benchmark_group("kinematics");
    g.warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1))
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat);
    for n in SIZES {
        let (chain, theta, theta_dot) = setup(n);
        let tip = chain.tip();
        g.bench_with_input(BenchmarkId::new("seed_positions", n), &n, |b, _| {
            b.iter(|| seed_frame_poses(&chain, black_box(&theta), Frame::GROUND).unwrap())
        });
        g.bench_with_input(BenchmarkId::new("seed_velocities", n), &n, |b, _| {
            b.iter(|| {
                seed_frame_velocities(
                    &chain,
                    black_box(&theta),
                    black_box(&theta_dot),
                    Frame::GROUND,
                )
                .unwrap()
            })
        });
        g.bench_with_input(BenchmarkId::new("seed_tip_jacobian", n), &n, |b, _| {
            b.iter(|| seed_hybrid_jacobian(&chain, black_box(&theta), Frame::GROUND, tip).unwrap())
        });
        if n <= SEED_CUBIC_MAX_N {
            g.bench_with_input(BenchmarkId::new("seed_all_jacobians", n), &n, |b, _| {
                b.iter(|| seed_all_jacobians(&chain, black_box(&theta), Frame::GROUND).unwrap())
            });
        }
    }
    g.finish();
}

criterion_group!(benches, fast_paths, seed_forms);
criterion_main!(benches);
