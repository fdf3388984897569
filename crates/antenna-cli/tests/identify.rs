//! `antenna identify` on synthetic ring-downs with known stiffness, damping and frequency:
//! every CSV layout (time column, angle in degrees, a bare column with
//! `--sample-rate-hz`, stdin) recovers `k_eq = J w_n^2` within 1 %, `k_wire` is
//! `k_eq - 0.0016`, `--wire-radius` gives `r` with `C r^4 = k_wire`, and bad recordings exit 2.
#![allow(clippy::unwrap_used)]

mod common;

use std::f64::consts::PI;
use std::fmt::Write as _;

use common::{run, run_with_stdin, scratch, stderr, stdout};
use serde_json::Value;

const J: f64 = 3.25e-6;

/// `theta(t) = c + A exp(-zeta w_n t) cos(w_d t + phase)` sampled at `rate_hz`.
fn ringdown(k: f64, zeta: f64, rate_hz: f64, duration_s: f64) -> Vec<(f64, f64)> {
    let w_n = (k / J).sqrt();
    let w_d = w_n * (1.0 - zeta * zeta).sqrt();
    let samples = (duration_s * rate_hz) as usize;
    (0..samples)
        .map(|i| {
            let t = i as f64 / rate_hz;
            (
                t,
                0.05 + 0.3 * (-zeta * w_n * t).exp() * (w_d * t + 0.2).cos(),
            )
        })
        .collect()
}

fn identify_json(args: &[&str], stdin: Option<&str>) -> Value {
    let mut all = vec!["identify"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--inertia-kg-m2", "3.25e-6", "--json"]);
    let out = match stdin {
        Some(s) => run_with_stdin(&all, s),
        None => run(&all),
    };
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    serde_json::from_str(&stdout(&out)).unwrap()
}

fn check(v: &Value, k: f64, zeta: f64) {
    let k_eq = v["k_eq_n_m_per_rad"].as_f64().unwrap();
    assert!((k_eq / k - 1.0).abs() < 0.01, "k_eq {k_eq} vs {k}");
    let f_n = v["f_n_hz"].as_f64().unwrap();
    let f_n_true = (k / J).sqrt() / (2.0 * PI);
    assert!(
        (f_n / f_n_true - 1.0).abs() < 0.005,
        "f_n {f_n} vs {f_n_true}"
    );
    let f_d = v["f_d_hz"].as_f64().unwrap();
    assert!(
        (f_d / (f_n_true * (1.0 - zeta * zeta).sqrt()) - 1.0).abs() < 0.005,
        "f_d {f_d}"
    );
    let z = v["zeta"].as_f64().unwrap();
    assert!((z - zeta).abs() < 0.05 * zeta, "zeta {z} vs {zeta}");
    let k_wire = v["k_wire_n_m_per_rad"].as_f64().unwrap();
    assert!((k_wire - (k_eq - 0.0016)).abs() < 1e-15);
}

#[test]
fn csv_with_time_column_recovers_stiffness() {
    for (k, zeta) in [(0.01, 0.02), (0.004, 0.1), (0.045, 0.05)] {
        let mut csv = String::from("# synthetic ring-down\nt_s,angle_rad\n");
        for (t, a) in ringdown(k, zeta, 1000.0, 2.0) {
            let _ = writeln!(csv, "{t},{a}");
        }
        let path = scratch(&format!("ringdown_{k}_{zeta}.csv"), &csv);
        let v = identify_json(&[&path], None);
        check(&v, k, zeta);
        assert_eq!(v["sample_rate_hz"].as_f64().unwrap().round(), 1000.0);
        assert_eq!(v["samples"], 2000);
    }
}

#[test]
fn degrees_on_stdin_and_a_bare_column_with_a_rate() {
    let (k, zeta) = (0.02, 0.04);
    let samples = ringdown(k, zeta, 500.0, 1.5);

    let mut csv = String::from("t_s,angle_deg,segment\n");
    for (t, a) in &samples {
        let _ = writeln!(csv, "{t},{},3", a.to_degrees());
    }
    check(&identify_json(&["-"], Some(&csv)), k, zeta);

    let mut bare = String::new();
    for (_, a) in &samples {
        let _ = writeln!(bare, "{a}");
    }
    let path = scratch("bare.txt", &bare);
    let v = identify_json(&[&path, "--sample-rate-hz", "500", "--wire-radius"], None);
    check(&v, k, zeta);
    let r = v["wire_radius_m"].as_f64().unwrap();
    let c = v["wire_constant_n_m_per_rad_per_m4"].as_f64().unwrap();
    assert_eq!(c, 2.0614e12);
    let k_wire = v["k_wire_n_m_per_rad"].as_f64().unwrap();
    assert!((c * r.powi(4) / k_wire - 1.0).abs() < 1e-12);
    let d = v["wire_diameter_in"].as_f64().unwrap();
    assert!((d - 2.0 * r / 0.0254).abs() < 1e-15);

    // The human summary names every quantity.
    let out = run(&[
        "identify",
        &path,
        "--sample-rate-hz",
        "500",
        "--inertia-kg-m2",
        "3.25e-6",
    ]);
    assert_eq!(out.status.code(), Some(0));
    let text = stdout(&out);
    for name in ["f_d", "zeta", "f_n", "k_eq", "k_wire"] {
        assert!(text.contains(name), "{name}: {text}");
    }
}

#[test]
fn bad_recordings_exit_2() {
    let bare = scratch("bare_short.txt", "0.1\n0.2\n0.1\n");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["identify", &bare, "--inertia-kg-m2", "1e-6"],
            "give --sample-rate-hz",
        ),
        (
            vec![
                "identify",
                &bare,
                "--inertia-kg-m2",
                "1e-6",
                "--sample-rate-hz",
                "100",
            ],
            "samples",
        ),
        (
            vec!["identify", "/nonexistent.csv", "--inertia-kg-m2", "1e-6"],
            "cannot read",
        ),
        (
            vec!["identify", &bare, "--sample-rate-hz", "100"],
            "--inertia-kg-m2",
        ),
    ];
    for (args, needle) in cases {
        let out = run(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stdout(&out).is_empty());
        assert!(stderr(&out).contains(needle), "{args:?}: {}", stderr(&out));
    }
    let ragged = scratch("ragged.csv", "t_s,angle_rad\n0,1\n0.01\n");
    let out = run(&["identify", &ragged, "--inertia-kg-m2", "1e-6"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("line 3: 1 field(s), expected 2"),
        "{}",
        stderr(&out)
    );
}
