//! Thesis 4.2.2 on sim-core (`examples/mapping_4_2_2.toml`, `mapping_trapezoid_4_2_2.toml`):
//! mapping a wall from what the robot senses. Asserted:
//! - the sweeps run to their end, including the ones where a link rests on a crest while a
//!   joint also touches and the ones where a crest crosses a joint, and with ideal sensors
//!   the estimated points lie within a few millimetres of the wall (the 12-bit angles and four
//!   switches per link bound the point error);
//! - with the robot's sensors (`examples/mapping_4_2_2_sensors.toml`), the thesis's claims
//!   about the coverage (docs/reproduction.md, section 3): the error grows with the wall's
//!   frequency from 2.8 to 9.5 1/m for both profiles; the decreasing profile maps every
//!   frequency and the trapezoid better than the constant one, and at 14.2 1/m at least as
//!   well as the constant one at 6.3 1/m;
//! - and that this comes from the touch switch's force: with ideal sensors the decreasing
//!   profile at 14.2 1/m is worse than the constant one at 6.3 1/m (the claim fails).
#![allow(clippy::unwrap_used)]

use antenna_tests::reproduce::{self, mapping};
use rayon::prelude::*;
use sim_core::{SensorSettings, StiffnessProfile};

/// The bound on the mean point error with ideal sensors: half the switch spacing along a
/// 40 mm link (5 mm) is the worst a touching point can be placed; the quantization adds well
/// under a millimetre.
const MEAN_ERROR_BOUND_MM: f64 = 5.0;

fn check(run: &mapping::MappingRun) {
    let what = format!("{} at {:?} 1/m", run.profile.name(), run.frequency_per_m);
    assert!(run.failure.is_none(), "{what}: {:?}", run.failure);
    assert!(run.points > 1000, "{what}: {} points", run.points);
    assert!(
        run.mean_error_mm > 0.0 && run.mean_error_mm < MEAN_ERROR_BOUND_MM,
        "{what}: {} mm",
        run.mean_error_mm
    );
    assert!(
        run.coverage_error_mm.is_finite() && (0.0..=1.0).contains(&run.completeness),
        "{what}: coverage {} mm, completeness {}",
        run.coverage_error_mm,
        run.completeness
    );
}

/// Every (profile, frequency) run of `sensors`, in the jobs' order, on rayon's pool (every
/// core).
fn sinusoids(
    jobs: &[(StiffnessProfile, f64)],
    sensors: &SensorSettings,
) -> Vec<mapping::MappingRun> {
    let base = reproduce::load_scene("mapping_4_2_2.toml").unwrap();
    jobs.par_iter()
        .map(|(p, f)| mapping::run(&base, p.clone(), *f, sensors).unwrap())
        .collect()
}

fn coverage(runs: &[mapping::MappingRun], p: &StiffnessProfile, f: f64) -> f64 {
    let run = runs
        .iter()
        .find(|r| r.profile == *p && r.frequency_per_m == Some(f))
        .unwrap();
    assert!(run.failure.is_none(), "{:?}", run.failure);
    run.coverage_error_mm
}

#[test]
fn sinusoid_sweeps_run_to_the_end_and_map_within_the_sensing_resolution() {
    let base = reproduce::load_scene("mapping_4_2_2.toml").unwrap();
    // The lowest and highest frequencies: a link on a crest while its joint touches (2.8),
    // crests crossing joints every few steps (14.2).
    let jobs = [
        (StiffnessProfile::Constant, 2.8),
        (StiffnessProfile::FastExponential, 2.8),
        (StiffnessProfile::Constant, 14.2),
        (StiffnessProfile::FastExponential, 14.2),
    ];
    let runs = sinusoids(&jobs, &SensorSettings::IDEAL);
    assert_eq!(runs.len(), jobs.len());
    for run in &runs {
        assert_eq!(run.steps, base.motion.steps(), "{:?}", run.failure);
        check(run);
    }
    // With ideal sensors the decreasing profile at 14.2 1/m maps worse than the constant one
    // at 6.3 1/m does (the thesis's comparison needs a switch that takes a force).
    let c63 = sinusoids(&[(StiffnessProfile::Constant, 6.3)], &SensorSettings::IDEAL);
    let fe142 = coverage(&runs, &StiffnessProfile::FastExponential, 14.2);
    let c63 = coverage(&c63, &StiffnessProfile::Constant, 6.3);
    assert!(fe142 > c63, "ideal: {fe142} mm at 14.2 against {c63} mm");
}

#[test]
fn with_the_robots_sensors_the_decreasing_profile_maps_finer_walls() {
    let robot = reproduce::load_sensors("mapping_4_2_2_sensors.toml").unwrap();
    assert!(!robot.is_ideal());
    let fe = StiffnessProfile::FastExponential;
    let c = StiffnessProfile::Constant;
    let jobs: Vec<(StiffnessProfile, f64)> = mapping::FREQUENCIES_PER_M
        .iter()
        .flat_map(|&f| [(fe.clone(), f), (c.clone(), f)])
        .collect();
    let runs = sinusoids(&jobs, &robot);
    let cov = |p: &StiffnessProfile, f: f64| coverage(&runs, p, f);
    // The error grows with the frequency from 2.8 to 9.5 1/m, for both profiles.
    for p in [&fe, &c] {
        for w in mapping::FREQUENCIES_PER_M[..4].windows(2) {
            assert!(
                cov(p, w[0]) < cov(p, w[1]),
                "{}: {} mm at {} 1/m, {} mm at {} 1/m",
                p.name(),
                cov(p, w[0]),
                w[0],
                cov(p, w[1]),
                w[1]
            );
        }
    }
    // The decreasing profile maps every frequency better.
    for &f in &mapping::FREQUENCIES_PER_M {
        assert!(
            cov(&fe, f) < cov(&c, f),
            "{f} 1/m: {} against {}",
            cov(&fe, f),
            cov(&c, f)
        );
    }
    // At 14.2 1/m, at least as well as the constant profile at 6.3 1/m.
    assert!(
        cov(&fe, 14.2) <= cov(&c, 6.3),
        "{} against {}",
        cov(&fe, 14.2),
        cov(&c, 6.3)
    );
}

#[test]
fn trapezoid_sweeps_run_to_the_end_and_the_decreasing_profile_maps_it_better() {
    let base = reproduce::load_scene("mapping_trapezoid_4_2_2.toml").unwrap();
    let robot = reproduce::load_sensors("mapping_4_2_2_sensors.toml").unwrap();
    let mut robot_coverage = Vec::new();
    for profile in [
        StiffnessProfile::FastExponential,
        StiffnessProfile::Constant,
    ] {
        let run = mapping::run_trapezoid(&base, profile.clone(), &SensorSettings::IDEAL).unwrap();
        assert_eq!(run.steps, base.motion.steps());
        check(&run);
        let run = mapping::run_trapezoid(&base, profile, &robot).unwrap();
        assert!(run.failure.is_none(), "{:?}", run.failure);
        robot_coverage.push(run.coverage_error_mm);
    }
    // The seed: 5.0 mm for the decreasing profile, 9.4 mm for the constant one.
    assert!(
        robot_coverage[0] < robot_coverage[1],
        "robot sensors: fast-exponential {} mm, constant {} mm",
        robot_coverage[0],
        robot_coverage[1]
    );
}
