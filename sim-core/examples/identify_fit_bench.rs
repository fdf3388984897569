//! The ring-down fit of `sim_core::design::identify` side by side with varpro (issue #17): accuracy
//! and time of fitting `c + exp(-sigma t)(a cos w t + b sin w t)` to seeded noisy ring-downs.
//!
//! Both fits start where `identify_stiffness` starts its fit: the spectrum peak `w0` and the
//! best of a coarse scan of damping ratios (a linear least-squares fit of `a, b, c` at each).
//!
//! - **hand LM**: the hand-written Levenberg-Marquardt fit of all five parameters that
//!   identify.rs used before issue #17, kept here as the baseline.
//! - **varpro**: `design/identify/`'s fit now (through its hidden `fit_bench` hooks): variable
//!   projection (`varpro` 0.14, its Levenberg-Marquardt on the two nonlinear parameters
//!   `sigma, w`; `a, b, c` solved for at each step).
//!
//! Records: `ring_down` of `design/identify/`'s tests (amplitude 0.3 rad, offset 0.05 rad, phase
//! `0.37 seed`, xorshift64* Gaussian noise) over natural frequency, damping ratio, sample rate,
//! record length in periods and noise level (0, 1 and 3 mrad as the tests use, and 10 mrad),
//! three noise seeds per noisy configuration. Errors: `f_n = sqrt(sigma^2 + w^2) / 2 pi` and
//! `sigma` of the fit against the true ones. A failure is an error returned, a non-finite
//! result or `f_n` off by more than 5 %. Time per fit: per record the median of the rounds,
//! the two fits interleaved (the order alternating by round), one thread; compare the
//! columns as ratios within one run only. Both times include the common seed scan, timed
//! alone too ("of which seed scan").
//!
//! `cargo run -p sim-core --release --example identify_fit_bench [-- --rounds N]`

mod bench_common;

use std::f64::consts::PI;
use std::hint::black_box;
use std::time::Instant;

use bench_common::{human, median};
use nalgebra::{Matrix5, Vector5};
use sim_core::design::identify::fit_bench::{self, cost_of, ring_down, scan_seed};

const F_N_HZ: [f64; 4] = [2.0, 3.7, 8.0, 20.0];
const ZETAS: [f64; 5] = [0.01, 0.03, 0.1, 0.2, 0.3];
const RATES_HZ: [f64; 3] = [100.0, 250.0, 1000.0];
const PERIODS: [f64; 3] = [3.0, 10.0, 30.0];
const NOISE_RAD: [f64; 4] = [0.0, 0.001, 0.003, 0.01];
const SEEDS_PER_NOISY: u64 = 3;
const ROUNDS: usize = 5;

/// A fit's decay rate, 1/s, and angular frequency, rad/s.
#[derive(Clone, Copy, Debug)]
struct Fit {
    sigma: f64,
    omega: f64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Method {
    Hand,
    Varpro,
}

impl Method {
    const ALL: [Method; 2] = [Method::Hand, Method::Varpro];

    fn label(self) -> &'static str {
        match self {
            Method::Hand => "hand LM",
            Method::Varpro => "varpro",
        }
    }

    fn fit(self, x: &[f64], fs: f64, omega0: f64) -> Option<Fit> {
        match self {
            Method::Hand => hand::fit(x, fs, omega0),
            Method::Varpro => fit_bench::fit(x, fs, omega0)
                .ok()
                .map(|(sigma, omega)| Fit { sigma, omega }),
        }
    }
}

struct Record {
    f_n_hz: f64,
    sigma: f64,
    noise_rad: f64,
    fs_hz: f64,
    x: Vec<f64>,
    omega0: f64,
    label: String,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut rounds = ROUNDS;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--rounds" {
            rounds = args.next().ok_or("--rounds needs a value")?.parse()?;
        }
    }
    let rounds = rounds.max(1);

    let mut records = Vec::new();
    let mut seed_failures = 0usize;
    let mut seed = 1u64;
    for &f in &F_N_HZ {
        for &zeta in &ZETAS {
            for &fs in &RATES_HZ {
                for &periods in &PERIODS {
                    for &noise in &NOISE_RAD {
                        let copies = if noise == 0.0 { 1 } else { SEEDS_PER_NOISY };
                        for _ in 0..copies {
                            seed += 1;
                            let dur = periods / f;
                            let x = ring_down(
                                f,
                                zeta,
                                fs,
                                dur,
                                0.3,
                                0.37 * seed as f64,
                                0.05,
                                noise,
                                seed,
                            );
                            let label = format!(
                                "f {f} zeta {zeta} fs {fs} {periods} periods noise {noise} seed {seed}"
                            );
                            match fit_bench::seed_rad_s(&x, fs) {
                                Ok(omega0) => records.push(Record {
                                    f_n_hz: f,
                                    sigma: zeta * 2.0 * PI * f,
                                    noise_rad: noise,
                                    fs_hz: fs,
                                    x,
                                    omega0,
                                    label,
                                }),
                                Err(e) => {
                                    seed_failures += 1;
                                    eprintln!("no seed for {label}: {e}");
                                }
                            }
                        }
                    }
                }
            }
        }
    }

    // results[method][record], times[method][record][round], scan_times[record][round]
    let mut results: Vec<Vec<Option<Fit>>> = vec![Vec::new(); 2];
    let mut times = vec![vec![Vec::with_capacity(rounds); records.len()]; 2];
    let mut scan_times = vec![Vec::with_capacity(rounds); records.len()];
    for round in 0..rounds {
        for (r, rec) in records.iter().enumerate() {
            let start = Instant::now();
            black_box(scan_seed(black_box(&rec.x), rec.fs_hz, rec.omega0));
            scan_times[r].push(start.elapsed().as_secs_f64());
            let order = if round % 2 == 0 {
                Method::ALL
            } else {
                [Method::Varpro, Method::Hand]
            };
            for m in order {
                let k = m as usize;
                let start = Instant::now();
                let fit = black_box(m.fit(black_box(&rec.x), rec.fs_hz, rec.omega0));
                times[k][r].push(start.elapsed().as_secs_f64());
                if round == 0 {
                    results[k].push(fit);
                }
            }
        }
    }

    println!(
        "{} records ({} without a spectrum seed, skipped), {rounds} rounds\n",
        records.len(),
        seed_failures
    );
    println!(
        "| noise (rad) | fit | records | failures | f_n rel. error median | p90 | max | sigma rel. error median | p90 | max | time per fit, median | of which seed scan | time vs hand LM (median of per-record ratios) |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let per_record: Vec<Vec<f64>> = times
        .iter()
        .map(|t| t.iter().map(|r| median(r)).collect())
        .collect();
    let mut groups: Vec<Option<f64>> = NOISE_RAD.iter().map(|&n| Some(n)).collect();
    groups.push(None);
    for group in groups {
        let idx: Vec<usize> = (0..records.len())
            .filter(|&r| group.is_none_or(|n| records[r].noise_rad == n))
            .collect();
        for m in Method::ALL {
            let k = m as usize;
            let mut fails = 0;
            let (mut ef, mut es) = (Vec::new(), Vec::new());
            let mut worst = (0.0f64, String::new());
            for &r in &idx {
                let rec = &records[r];
                let Some(fit) = results[k][r] else {
                    fails += 1;
                    eprintln!("{}: failed on {}", m.label(), rec.label);
                    continue;
                };
                let f_n = fit.sigma.hypot(fit.omega) / (2.0 * PI);
                let e_f = (f_n / rec.f_n_hz - 1.0).abs();
                let e_s = (fit.sigma / rec.sigma - 1.0).abs();
                if !(e_f.is_finite() && e_s.is_finite()) || e_f > 0.05 {
                    fails += 1;
                    eprintln!("{}: f_n off by {e_f:.2e} on {}", m.label(), rec.label);
                    continue;
                }
                if e_f > worst.0 {
                    worst = (e_f, rec.label.clone());
                }
                ef.push(e_f);
                es.push(e_s);
            }
            let t: Vec<f64> = idx.iter().map(|&r| per_record[k][r]).collect();
            let ratio: Vec<f64> = idx
                .iter()
                .map(|&r| per_record[k][r] / per_record[Method::Hand as usize][r])
                .collect();
            let scan: Vec<f64> = idx.iter().map(|&r| median(&scan_times[r])).collect();
            let noise = group.map_or("all".to_string(), |n| format!("{n}"));
            println!(
                "| {noise} | {} | {} | {fails} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2} |",
                m.label(),
                idx.len(),
                sci(median(&ef)),
                sci(quantile(&ef, 0.9)),
                sci(ef.iter().copied().fold(0.0, f64::max)),
                sci(median(&es)),
                sci(quantile(&es, 0.9)),
                sci(es.iter().copied().fold(0.0, f64::max)),
                human(median(&t)),
                human(median(&scan)),
                median(&ratio),
            );
            eprintln!(
                "{noise} {}: worst f_n error {:.2e} at {}",
                m.label(),
                worst.0,
                worst.1
            );
        }
    }
    Ok(())
}

fn sci(v: f64) -> String {
    format!("{v:.1e}")
}

/// The `q` quantile (nearest rank; NaN for no values).
fn quantile(values: &[f64], q: f64) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return f64::NAN;
    }
    let rank = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

/// The hand-written Levenberg-Marquardt fit of identify.rs before issue #17.
mod hand {
    use super::*;

    pub fn fit(x: &[f64], fs_hz: f64, omega_start: f64) -> Option<Fit> {
        let (mut p, mut cost) = scan_seed(x, fs_hz, omega_start)?;
        let mut lambda = 1e-3;
        for _ in 1..=200 {
            let mut jtj = Matrix5::zeros();
            let mut jtr = Vector5::zeros();
            for (i, &v) in x.iter().enumerate() {
                let t = i as f64 / fs_hz;
                let e = (-p[3] * t).exp();
                let (s, c) = (p[4] * t).sin_cos();
                let osc = p[0] * c + p[1] * s;
                let r = v - (p[2] + e * osc);
                let jac = Vector5::new(
                    e * c,
                    e * s,
                    1.0,
                    -t * e * osc,
                    t * e * (-p[0] * s + p[1] * c),
                );
                jtj += jac * jac.transpose();
                jtr += jac * r;
            }
            let mut improved = false;
            while lambda < 1e12 {
                let mut a = jtj;
                for k in 0..5 {
                    a[(k, k)] += lambda * jtj[(k, k)].max(1e-300);
                }
                if let Some(ch) = a.cholesky() {
                    let d = ch.solve(&jtr);
                    let trial = [
                        p[0] + d[0],
                        p[1] + d[1],
                        p[2] + d[2],
                        p[3] + d[3],
                        p[4] + d[4],
                    ];
                    let trial_cost = cost_of(x, fs_hz, &trial);
                    if trial_cost.is_finite() && trial_cost <= cost {
                        let small = d[4].abs() <= 1e-13 * p[4].abs()
                            && d[3].abs() <= 1e-13 * p[4].abs()
                            && cost - trial_cost <= 1e-15 * cost;
                        p = trial;
                        cost = trial_cost;
                        lambda = (lambda * 0.1).max(1e-15);
                        improved = !small;
                        break;
                    }
                }
                lambda *= 10.0;
            }
            if !improved {
                break;
            }
        }
        let rms = (cost / x.len() as f64).sqrt();
        (p.iter().all(|v| v.is_finite()) && rms.is_finite()).then_some(Fit {
            sigma: p[3],
            omega: p[4].abs(),
        })
    }
}
