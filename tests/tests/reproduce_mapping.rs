//! Seed 4.2.2 on sim-core (`examples/mapping_4_2_2.toml`, `mapping_trapezoid_4_2_2.toml`):
//! mapping a wall from what the robot senses. The seed's claims (the error grows with the
//! wall's frequency, the decreasing profile wins) are not reproduced, and no test asserts
//! them (docs/reproduction.md says why). What is asserted: the sweeps run to their end,
//! including the ones where a link rests on a crest while a joint also touches and the ones
//! where a crest crosses a joint, and the sensed contact points lie within a few millimetres
//! of the wall (the 12-bit angles and four switches per link bound the error).
#![allow(clippy::unwrap_used)]

use antenna_tests::reproduce::{self, mapping};
use sim_core::StiffnessProfile;

/// The bound on the mean error: half the switch spacing along a 40 mm link (5 mm) is the
/// worst a touching point can be placed; the quantization adds well under a millimetre.
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
    std::thread::scope(|scope| {
        let handles: Vec<_> = jobs
            .iter()
            .map(|(p, f)| {
                let base = &base;
                scope.spawn(move || mapping::run(base, p.clone(), *f).unwrap())
            })
            .collect();
        for h in handles {
            let run = h.join().unwrap();
            assert_eq!(run.steps, base.motion.steps(), "{:?}", run.failure);
            check(&run);
        }
    });
}

#[test]
fn trapezoid_sweeps_run_to_the_end_and_map_within_the_sensing_resolution() {
    let base = reproduce::load_scene("mapping_trapezoid_4_2_2.toml").unwrap();
    for profile in [
        StiffnessProfile::FastExponential,
        StiffnessProfile::Constant,
    ] {
        let run = mapping::run_trapezoid(&base, profile).unwrap();
        assert_eq!(run.steps, base.motion.steps());
        check(&run);
    }
}
