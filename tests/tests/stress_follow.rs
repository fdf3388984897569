//! The follow stress suite (`antenna_tests::stress::follow`, issue #47): seeded random
//! closed-loop runs over the whole parameter space (walls of every kind, smooth or rough,
//! 4-36 links, the seven Table 4.1 profiles, no or distal hairs, noisy and slow sensors, the
//! template and the wheeled body, the three estimators, gains from zero to large, delays,
//! 0.05-2 m/s, the wall on either side, the antenna loading the body or not, starts inside
//! the wall). Every run must refuse to start with a typed error or end with a status of
//! `sim_core::follow::STATUS_NAMES`, every step it reports finite; panics, timeouts and
//! broken contracts fail the test, each printed with its replay line.
//!
//! Its own test binary, as `stress_contact` is (tests/tests/cross/main.rs says why: each
//! runs a child process per case on every core).
//!
//! - `cargo test -p antenna-tests --test stress_follow -- --nocapture`: the CI sample (a
//!   fixed seed), with its table.
//! - `ANTENNA_SOAK=1 cargo test -p antenna-tests --release --test stress_follow --
//!   --nocapture`: 2,000 runs (`ANTENNA_SOAK_RUNS`, default 2000) from
//!   `ANTENNA_SOAK_SEED` (default below), 1-4 s each, the table, every failure.
//! - `ANTENNA_STRESS_REPLAY=ci:SEED:INDEX[,INDEX...]` (or `soak:...`): reruns those cases
//!   alone, in this process and without a time limit, and prints what happened; with
//!   `ANTENNA_STRESS_TRACE=1` every step too.
//! - `ANTENNA_STRESS_ALL=1`: the CI sample with its known failures too.
//! - `ANTENNA_STRESS_THREADS`: worker threads (default: every core).
//! - `ANTENNA_STRESS_LIST=1` prints every run's outcome.
#![allow(clippy::unwrap_used)]

use std::time::Instant;

use antenna_tests::stress::follow::{
    FollowCase, FollowOutcome, FollowPlacement, FollowRecord, StartCheck, follow_child_main,
    follow_table, run_follow_cases, run_follow_index,
};
use antenna_tests::stress::{
    CHILD_ENV, ChildCommand, Sample, TimeLimit, WallKind, default_threads,
};
use sim_core::follow::{BodyModel, Estimator, Follow, FollowError, WallSide};

/// The CI sample's seed.
const CI_SEED: u64 = 20_261_206;
/// The CI sample's size: 128 runs took 12-19 s in the test profile on two cores with the
/// machine's load at 2-3 (64 took 34 s with its load at 5.5): about 30-60 s on two shared cores.
const CI_RUNS: u64 = 128;
/// The CI sample's runs that break the contract as of this commit, with why: left out of
/// the CI run so that any other failure fails it (the soak and `ANTENNA_STRESS_REPLAY` still
/// run them). Remove an entry when its run keeps the contract.
const KNOWN_CI_FAILURES: &[(u64, &str)] = &[];

/// The soak's default seed.
const SOAK_SEED: u64 = 4_747;
/// The soak's default size.
const SOAK_RUNS: u64 = 2_000;

fn env_u64(name: &str) -> Option<u64> {
    std::env::var(name).ok().and_then(|v| v.trim().parse().ok())
}

fn env_flag(name: &str) -> bool {
    std::env::var(name).is_ok_and(|v| v.trim() == "1")
}

/// `ANTENNA_STRESS_REPLAY=ci:SEED:I,J,...`: rerun those cases and print them (with
/// `ANTENNA_STRESS_TRACE=1`, every step).
fn replay(spec: &str) {
    let trace = env_flag("ANTENNA_STRESS_TRACE");
    let mut parts = spec.split(':');
    let sample = parts.next().and_then(Sample::parse).expect("ci or soak");
    let seed: u64 = parts.next().and_then(|s| s.parse().ok()).expect("a seed");
    let indices: Vec<u64> = parts
        .next()
        .expect("indices")
        .split(',')
        .map(|i| i.trim().parse().unwrap())
        .collect();
    for index in indices {
        let case = FollowCase::generate(seed, index, sample).unwrap();
        println!("{}", case.replay_line());
        if trace {
            match Follow::new(&case.scene, &case.sensors, &case.config) {
                Err(e) => println!("start: {e}"),
                Ok(mut run) => {
                    println!("placement: {}", run.placement_note());
                    while let Some(step) = run.next_step() {
                        match step {
                            Ok(s) => println!(
                                "t={:.3} pose=({:.4},{:.4}) heading={:.4} omega={:.4} u={:.3e} \
                                 wall={:?} estimate={:?} contacts={} collided={}",
                                s.t_s,
                                s.pose_m.x,
                                s.pose_m.y,
                                s.heading_rad,
                                s.omega_rad_per_s,
                                s.command.value(),
                                s.wall_distance_m,
                                s.estimate.map(|e| e.distance_m),
                                s.contacts,
                                s.collided
                            ),
                            Err(e) => println!("refused: {e}"),
                        }
                    }
                    println!("summary: {:?}", run.summary());
                }
            }
        }
        let rec = run_follow_index(seed, index, sample, false);
        println!("{}", rec.outcome_line());
    }
}

/// This test's name: children run it with [`CHILD_ENV`] set.
const MAIN_TEST: &str = "follow_runs_end_in_a_typed_status";

/// Per-run time limits, `base + per link-solve * N * antenna solves` up to a most. As in the
/// contact suite, the limit catches a run that hangs. Some runs are slow without hanging: a
/// solve of the antenna carried along a turning base can take over a millisecond per link
/// (soak:4747:392, N = 18, 307 steps: 21 s in a release build with the cores shared), and a
/// failing step may take seconds before it refuses (ci:20261206:37, N = 4: 4.2 s in a release
/// build on its first 4 steps). The soak's limits: in a release build 20 s plus 1 ms per link
/// and solve of the antenna, at most 60 s; in the test profile 30 s plus 3 ms, at most 120 s.
/// The CI sample's are twice those.
fn time_limit(optimized: bool, sample: Sample) -> TimeLimit {
    let scale = match sample {
        Sample::Ci => 2.0,
        Sample::Soak | Sample::SoakWide => 1.0,
    };
    let tight = if optimized {
        TimeLimit {
            base_s: 20.0,
            per_link_step_s: 1e-3,
            max_s: 60.0,
        }
    } else {
        TimeLimit {
            base_s: 30.0,
            per_link_step_s: 3e-3,
            max_s: 120.0,
        }
    };
    TimeLimit {
        base_s: tight.base_s * scale,
        per_link_step_s: tight.per_link_step_s * scale,
        max_s: tight.max_s * scale,
    }
}

#[test]
fn follow_runs_end_in_a_typed_status() {
    if let Ok(spec) = std::env::var(CHILD_ENV) {
        follow_child_main(&spec).unwrap();
        return;
    }
    if let Ok(spec) = std::env::var("ANTENNA_STRESS_REPLAY") {
        replay(&spec);
        return;
    }
    let soak = env_flag("ANTENNA_SOAK");
    let (seed, count, sample) = if soak {
        (
            env_u64("ANTENNA_SOAK_SEED").unwrap_or(SOAK_SEED),
            env_u64("ANTENNA_SOAK_RUNS").unwrap_or(SOAK_RUNS),
            Sample::Soak,
        )
    } else {
        (CI_SEED, CI_RUNS, Sample::Ci)
    };
    let skipped: &[(u64, &str)] = if soak || env_flag("ANTENNA_STRESS_ALL") {
        &[]
    } else {
        KNOWN_CI_FAILURES
    };
    if !skipped.is_empty() {
        println!("\nKnown failures of the CI sample, not run here:");
        for (index, why) in skipped {
            println!("- ci:{CI_SEED}:{index}: {why}");
        }
    }
    let indices: Vec<u64> = (0..count)
        .filter(|i| !skipped.iter().any(|(k, _)| k == i))
        .collect();
    let started = Instant::now();
    let records = run_follow_cases(
        seed,
        &indices,
        sample,
        default_threads(),
        if soak { 100 } else { 0 },
        &ChildCommand::current_test(MAIN_TEST).unwrap(),
        &time_limit(!cfg!(debug_assertions), sample),
    );
    let elapsed_s = started.elapsed().as_secs_f64();
    println!(
        "\nFollow stress, {} sample, seed {seed}: {} runs in {elapsed_s:.1} s on {} worker(s)\n",
        sample.name(),
        records.len(),
        default_threads()
    );
    print!("{}", follow_table(&records));
    if env_flag("ANTENNA_STRESS_LIST") {
        println!();
        for r in &records {
            println!("{}", r.outcome_line());
        }
    }
    let failures: Vec<&FollowRecord> = records.iter().filter(|r| r.outcome.is_failure()).collect();
    if !failures.is_empty() {
        println!("\nFailures ({}):", failures.len());
        for r in &failures {
            println!("- {}\n  {}", r.outcome_line(), r.replay);
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} follow runs broke the contract (see above)",
        failures.len(),
        records.len()
    );
}

/// A case is a pure function of (seed, index, sample).
#[test]
fn same_seed_same_follow_case() {
    for index in 0..30 {
        let a = FollowCase::generate(CI_SEED, index, Sample::Ci).unwrap();
        let b = FollowCase::generate(CI_SEED, index, Sample::Ci).unwrap();
        assert_eq!(format!("{:?}", a.scene), format!("{:?}", b.scene));
        assert_eq!(a.config, b.config);
        assert_eq!(a.sensors, b.sensors);
        assert_eq!(a.replay_line(), b.replay_line());
        let c = FollowCase::generate(CI_SEED, index + 1, Sample::Ci).unwrap();
        assert_ne!(a.replay_line(), c.replay_line());
    }
}

/// The CI sample reaches every axis the issue names.
#[test]
fn ci_sample_spans_every_axis() {
    let cases: Vec<FollowCase> = (0..CI_RUNS)
        .map(|i| FollowCase::generate(CI_SEED, i, Sample::Ci).unwrap())
        .collect();
    let any = |f: &dyn Fn(&FollowCase) -> bool| cases.iter().any(f);
    for n in antenna_tests::stress::follow::FOLLOW_LINK_COUNTS {
        assert!(any(&|c| c.links == n), "no N = {n}");
    }
    for kind in WallKind::ALL {
        assert!(any(&|c| c.wall.kind == kind), "no {kind:?} wall");
    }
    for p in antenna_tests::reproduce::TABLE_4_1_PROFILES {
        assert!(any(&|c| c.profile == p), "no {}", p.name());
    }
    for e in ["contact-line", "bend", "ideal-preview"] {
        assert!(any(&|c| c.estimator() == e), "no {e}");
    }
    for p in [
        FollowPlacement::DefaultApproach,
        FollowPlacement::Rest,
        FollowPlacement::TipOnWall,
    ] {
        assert!(any(&|c| c.placement == p), "no {p:?}");
    }
    for side in [WallSide::Left, WallSide::Right] {
        assert!(any(&|c| c.config.robot.wall_side == side), "no {side:?}");
    }
    assert!(any(&|c| matches!(
        c.config.robot.body,
        BodyModel::Template { .. }
    )));
    assert!(any(&|c| matches!(
        c.config.robot.body,
        BodyModel::Wheeled { .. }
    )));
    assert!(any(&|c| c.hairs) && any(&|c| !c.hairs));
    assert!(any(&|c| c.rough.is_some()) && any(&|c| c.rough.is_none()));
    assert!(any(&|c| c.config.robot.antenna_loads_body));
    assert!(any(&|c| c.drawn_inside));
    assert!(any(&|c| c.start_check == StartCheck::Clear));
    assert!(any(&|c| c.config.controller.kp_n == 0.0));
    assert!(any(&|c| c.config.controller.kp_n > 0.4));
    assert!(any(&|c| c.config.controller.delay_s > 0.0));
    assert!(any(&|c| c.config.controller.delay_s == 0.0));
    assert!(
        any(&|c| c.sensors.sample_rate_hz.is_some())
            && any(&|c| c.sensors.sample_rate_hz.is_none())
    );
    assert!(any(&|c| c.sensors.touch_debounce_samples > 1));
    assert!(any(&|c| c.config.robot.speed_m_per_s < 0.2));
    assert!(any(&|c| c.config.robot.speed_m_per_s > 1.0));
    for c in &cases {
        let s = c.config.robot.speed_m_per_s;
        assert!((0.05..=2.0).contains(&s), "{s} m/s");
        assert!((0.0..=0.05).contains(&c.config.controller.delay_s));
        assert!((0.5..=2.0).contains(&c.config.settings.duration_s));
        assert_eq!(
            c.config.settings.step_s,
            antenna_tests::stress::follow::FOLLOW_STEP_S
        );
        assert_eq!(c.config.validate(), Ok(()), "{}", c.replay_line());
        if let Estimator::IdealPreview { preview_m } = c.config.controller.estimator {
            assert!((0.0..=0.3).contains(&preview_m));
        }
    }
}

/// A start with the point of rotation inside the wall is refused as `StartsInWall`, a typed
/// refusal, before anything else is done.
#[test]
fn a_start_inside_the_wall_is_refused_as_starts_in_wall() {
    let mut seen = 0;
    for index in 0..200 {
        let case = FollowCase::generate(CI_SEED, index, Sample::Ci).unwrap();
        if !case.drawn_inside {
            continue;
        }
        assert_eq!(
            case.start_check,
            StartCheck::Inside,
            "{}",
            case.replay_line()
        );
        let started = Follow::new(&case.scene, &case.sensors, &case.config);
        assert!(
            matches!(started, Err(FollowError::StartsInWall { .. })),
            "{}: {:?}",
            case.replay_line(),
            started.err()
        );
        seen += 1;
    }
    assert!(seen >= 5, "{seen} starts inside the wall in 200 cases");
}

/// A record survives the trip through a child process's output, every outcome.
#[test]
fn follow_records_round_trip_through_text() {
    let case = FollowCase::generate(CI_SEED, 3, Sample::Ci).unwrap();
    let outcomes = [
        FollowOutcome::Ran {
            status: "ok".into(),
            refusal: None,
        },
        FollowOutcome::Ran {
            status: "jammed".into(),
            refusal: Some("at t = 0.3 s:\tpinned\nby \\ a corner".into()),
        },
        FollowOutcome::Refused {
            kind: "starts-in-wall".into(),
            message: "overlaps".into(),
        },
        FollowOutcome::Violation {
            message: "step 3: not finite".into(),
        },
        FollowOutcome::Panicked {
            message: "index out of bounds".into(),
        },
        FollowOutcome::TimedOut {
            limit_s: 40.5,
            last_step: Some(30),
        },
        FollowOutcome::TimedOut {
            limit_s: 40.5,
            last_step: None,
        },
        FollowOutcome::Invalid {
            message: "bad".into(),
        },
    ];
    let mut rec = FollowRecord::new(&case);
    assert_eq!(rec.replay, case.replay_line());
    for outcome in outcomes {
        rec.outcome = outcome;
        rec.wall_clock_s = 0.123_456_789;
        let text = format!(
            "running 1 test\nstress-progress 10\n{}test ok\n",
            rec.to_wire()
        );
        assert_eq!(FollowRecord::from_wire(&text), Some(rec.clone()));
    }
    assert!(FollowRecord::from_wire("<<<stress-record\nseed\t1\n").is_none());
}
