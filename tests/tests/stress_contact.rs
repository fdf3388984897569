//! The contact stress suite (`antenna_tests::stress`): random walls (polylines with convex
//! and concave corners of 5-85 deg and edges shorter than a link, corners exactly on the
//! start posture's joints, sinusoids down to a crest radius of half a link, noisy digitized
//! walls, lines), mu in {0, 0.3, 0.6, 1.0}, the seven Table 4.1 profiles, no hairs or distal
//! hairs, N in {4, 9, 18, 36, 72, 150}, every placement. Every sweep must finish with every
//! step certified, or end with a typed outcome: jammed (the antenna physically cannot go on)
//! (a `ContactError::Jammed` that names the contacts pinning it) or its placement refused
//! with a reason. Solver failures (a placement the solver failed under included), uncertified
//! steps, timeouts and panics fail the test, each printed with its replay line.
//!
//! - `cargo test -p antenna-tests --test stress_contact -- --nocapture`: the CI sample (a
//!   fixed seed), with its table.
//! - `ANTENNA_SOAK=1 cargo test -p antenna-tests --release --test stress_contact --
//!   --nocapture`: at least 2,000 sweeps (`ANTENNA_SOAK_SWEEPS`, default 2000) from
//!   `ANTENNA_SOAK_SEED` (default below), longer ones, the table, every unfinished sweep.
//! - `ANTENNA_SOAK=wide ...`: the same soak with `N` drawn from {4, 9, 18, 36, 72, 150, 300}
//!   (`Sample::SoakWide`, issue #49: the solver's budgets and jump test at every `N`).
//! - `ANTENNA_STRESS_REPLAY=ci:SEED:INDEX[,INDEX...]` (or `soak:...`, `soak-wide:...`): reruns those cases
//!   alone, in this process and without a time limit, and prints what happened (the replay
//!   lines printed for unfinished sweeps say which). With `ANTENNA_STRESS_TRACE=1` it also
//!   prints what each step cost and why (Newton iterations, substeps, snaps, jams, the fixed
//!   point) and counts the steps over 40 iterations by kind: where a Newton p99 comes from.
//! - `ANTENNA_STRESS_ALL=1`: the CI sample with its known failures too.
//! - `ANTENNA_STRESS_THREADS`: worker threads (default: every core).
//! - Each sweep runs in a child process (this binary, running only the main test with
//!   `ANTENNA_STRESS_CHILD` set) that is killed past its time limit (a hung sweep must not
//!   hang CI). `ANTENNA_STRESS_LIST=1` prints every sweep's outcome.
#![allow(clippy::unwrap_used)]

use std::time::Instant;

use antenna_tests::stress::case::{
    ANTENNA_LENGTH_M, Case, LINK_COUNTS, MUS, PlacementKind, PosturePoints, Sample,
};
use antenna_tests::stress::walls::{
    self, AnchorStyle, Profile, Underlying, WallFrame, WallKind, crest_radius_m,
    draw_anchored_polyline, draw_digitized, draw_polyline, draw_sinusoid,
};
use antenna_tests::stress::{
    CHILD_ENV, ChildCommand, GOLDEN_FILE, Outcome, RunOptions, STEP_TOLERANCE, SweepRecord,
    TimeLimit, case_rng, child_main, compare, default_threads, expensive_by_kind, golden_file,
    parse_golden, run_cases, run_index, summary_markdown, unfinished_report,
};
use nalgebra::Vector2;
use sim_core::sweep::Placement;
use sim_core::{Polyline, SolidSide, WallShape};

/// The CI sample's seed.
const CI_SEED: u64 = 20_261_122;
/// The CI sample's size (tuned to about 60 s in the test profile on two shared cores).
const CI_SWEEPS: u64 = 80;
/// The CI sample's sweeps that the solver does not finish yet (issue #13 stays open on
/// them), with why, as of this commit: left out of the CI run so that any other failure
/// fails it. Remove an entry when its sweep finishes (`ANTENNA_STRESS_REPLAY=ci:SEED:INDEX`).
const KNOWN_CI_FAILURES: &[(u64, &str)] = &[];

/// Soak sweeps that once failed, fixed since, with what failed: each must still finish.
const SOAK_REGRESSIONS: &[(u64, &str)] = &[
    (
        258,
        "step 149: a sinusoid's crest poking 6 cm through the line of the steep tip link, just \
         past the tip and out of the link's reach, joined as a pair of the tip link that no \
         posture could satisfy (\"the downhill path did not come to rest\")",
    ),
    (
        383,
        "uncertified at step 405: on a step whose friction was let go, a pair handed over to a \
         point's stand-in kept its friction (9 mN of shear where none was allowed)",
    ),
    (
        176,
        "step 212: a corner standing for joint 16 (link 16 resting on it at the joint) whose \
         foot slid past the link's end was dropped without handing its force back to the joint's \
         own pair, and the joint swung into the wall (\"the downhill path did not come to \
         rest\")",
    ),
    (
        755,
        "step 526: a hair tip pressed onto the lip of a step, on the line of the lip's edge, \
         slid past the corner, let go, and came back to the corner as a point pair whose \
         normal turns at 1 / gap (\"the downhill path did not come to rest\"); it is now \
         handed to the line of the corner's other edge, and kept on that line along its edge",
    ),
    (
        748,
        "uncertified at step 42: a contact grazing a sinusoid's crest (N = -1.1e-9 N, pressed \
         within the modes' hysteresis) slid with a shear of 3.3e-10 N in its own direction, a \
         force far inside the certificate's force tolerance, whose sign the check \
         held against the slip",
    ),
    (
        1093,
        "step 158: a link pressed flat on a digitized wall's edge, resting on the edge's \
         corner, ended its solves 1e-7 outside the corner's normal cone, lost the corner, and \
         took turns between the corner and its joint on the wall beyond (\"the downhill path \
         did not come to rest\")",
    ),
    (
        1229,
        "a hair tip held by friction on a polyline corner: friction locked one step, and the \
         next failed with the quick solve with friction and again without friction \
         (\"friction still locks the antenna\"); that step is now taken again with friction in \
         full before it fails",
    ),
    (
        1729,
        "step 160: a corner on link 1 90 um short of joint 2, bent 0.15 rad, stood for the joint \
         with both links' pairs; link 2's, its foot just past the link's start, measured its \
         line run on past the joint as 13 um inside the corner, which no posture could undo \
         (\"the downhill path did not come to rest\")",
    ),
    (
        1747,
        "step 128: a frictionless snap (N = 36, distal hairs, a sinusoid) whose failing proximal \
         solves each went on to the fixed point on the normal forces, which without friction \
         solves the same problem again: 240-500 Newton iterations a failed pseudo-time step, \
         and the downhill path ran out of its budget (\"the downhill path did not come to \
         rest\"); since 2026-11-27 step 179's flow, whose rounds hand a crest's force from \
         link 23 to joints 22 and 23 and back, comes to rest within its budget only because \
         rounds whose solves failed for want of a pair count as rounds taking turns (9,606 of \
         10,000 Newton iterations; 10,046 without)",
    ),
    (
        1393,
        "placement (tip-on-wall S, a corner at the tip): as soak 176, a corner standing for a \
         joint dropped without handing its force back",
    ),
    (
        939,
        "uncertified at step 76 (N = 150, a digitized trapezoid, mu = 0.3): the tip, pressed \
         with 2 uN, crossing a concave corner from one piece to the next; the plain solve \
         stalled within the acceptable residual with the next piece's pair holding the force \
         1.2 um off the wall (a loaded contact's gap); such a stall now takes the fixed \
         point's answer where it converges",
    ),
    (
        680,
        "placement uncertified (N = 150, a frictionless polyline, tip-on-wall C): the settle's \
         flow wedged the tip where the line of two collinear edges (before and after a dip, one \
         piece for both and so run on without end) leaves the wall through another edge, \
         3.4 mm short of the concave corner the tip slides into; a pair on that run-on pressed with a \
         normal the wall has not there (friction cone violated by 4.2e-5 N). Past its own \
         edges' reach a piece's line is now the wall only where the wall's normal cone holds \
         the line's normal",
    ),
];

/// The soak's default seed.
const SOAK_SEED: u64 = 4_221;
/// The soak's default (and least) size.
const SOAK_SWEEPS: u64 = 2_000;

fn env_u64(name: &str) -> Option<u64> {
    std::env::var(name).ok().and_then(|v| v.trim().parse().ok())
}

/// `ANTENNA_STRESS_REPLAY=ci:SEED:I,J,...`: rerun those cases and print them (with
/// `ANTENNA_STRESS_TRACE=1`, what each step cost and why, and the steps over
/// [`antenna_tests::stress::EXPENSIVE_ITERATIONS`] Newton iterations by kind).
fn replay(spec: &str) {
    let trace = std::env::var("ANTENNA_STRESS_TRACE").is_ok_and(|v| v.trim() == "1");
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
        let case = Case::generate(seed, index, sample).unwrap();
        println!("{}", case.replay_line());
        println!("scene: {:?}", case.scene);
        let rec = run_index(seed, index, sample, false);
        println!("placement: {}", rec.placement_note);
        println!(
            "{} ({} steps in contact, {} relaxed)",
            rec.outcome_line(),
            rec.contact_steps,
            rec.relaxed_steps
        );
        if trace {
            for cost in &rec.costs {
                println!("{}", cost.line());
            }
            print!("{}", expensive_by_kind(&rec.costs));
        }
    }
}

/// This test's name: children run it with [`CHILD_ENV`] set.
const MAIN_TEST: &str = "contact_sweeps_finish_with_every_step_certified";

/// Per-sweep time limits, `base + per link-step * N * steps` up to a most. The limit only
/// catches a sweep that hangs (stuck in its placement or in one step for minutes); how much
/// work a sweep may do is bounded by the solver's own counters (Newton iterations, halvings),
/// which the outcomes and the golden trajectories check. So the CI sample's limits are ten
/// times the soak's, and hold on a loaded 2-core machine: the slowest finished sweep of the
/// CI sample takes 2.4 s alone in the test profile (N = 72 on a sinusoid; most take
/// milliseconds) and some 10 s with the machine's cores shared three ways. The soak, a
/// benchmark run on a quiet machine (`BENCHMARKS.md`), keeps the tight limits: in the test
/// profile (opt-level 1, debug assertions) 4 s + 1 ms * N * steps up to 15 s, in a release
/// build 3 s + 0.3 ms * N * steps up to 20 s.
fn time_limit(optimized: bool, sample: Sample) -> TimeLimit {
    let scale = match sample {
        Sample::Ci => 10.0,
        Sample::Soak | Sample::SoakWide => 1.0,
    };
    let tight = if optimized {
        TimeLimit {
            base_s: 3.0,
            per_link_step_s: 3e-4,
            max_s: 20.0,
        }
    } else {
        TimeLimit {
            base_s: 4.0,
            per_link_step_s: 1e-3,
            max_s: 15.0,
        }
    };
    TimeLimit {
        base_s: tight.base_s * scale,
        per_link_step_s: tight.per_link_step_s * scale,
        max_s: tight.max_s * scale,
    }
}

#[test]
fn contact_sweeps_finish_with_every_step_certified() {
    if let Ok(spec) = std::env::var(CHILD_ENV) {
        child_main(&spec).unwrap();
        return;
    }
    if let Ok(spec) = std::env::var("ANTENNA_STRESS_REPLAY") {
        replay(&spec);
        return;
    }
    let soak_sample = match std::env::var("ANTENNA_SOAK").as_deref().map(str::trim) {
        Ok("1") => Some(Sample::Soak),
        Ok("wide") => Some(Sample::SoakWide),
        _ => None,
    };
    let soak = soak_sample.is_some();
    let (seed, count, sample) = if let Some(sample) = soak_sample {
        (
            env_u64("ANTENNA_SOAK_SEED").unwrap_or(SOAK_SEED),
            env_u64("ANTENNA_SOAK_SWEEPS").unwrap_or(SOAK_SWEEPS),
            sample,
        )
    } else {
        (CI_SEED, CI_SWEEPS, Sample::Ci)
    };
    let optimized = !cfg!(debug_assertions);
    let options = RunOptions {
        threads: default_threads(),
        progress_every: if soak { 100 } else { 0 },
        command: ChildCommand::current_test(MAIN_TEST).unwrap(),
        limit: time_limit(optimized, sample),
    };
    let started = Instant::now();
    // The CI sample leaves out its known failures (issue #13 is open on them; the soak and
    // `ANTENNA_STRESS_REPLAY` still run them): every other sweep must finish or end in a
    // typed outcome, so a new failure fails the check.
    let all = std::env::var("ANTENNA_STRESS_ALL").is_ok_and(|v| v.trim() == "1");
    let skipped: &[(u64, &str)] = if soak || all { &[] } else { KNOWN_CI_FAILURES };
    let indices: Vec<u64> = (0..count)
        .filter(|i| !skipped.iter().any(|(k, _)| k == i))
        .collect();
    if !skipped.is_empty() {
        println!(
            "\nKnown failures of the CI sample, not run here (issue #13; rerun one with \
             ANTENNA_STRESS_REPLAY=ci:{seed}:INDEX):"
        );
        for (index, why) in skipped {
            println!("- ci:{seed}:{index}: {why}");
        }
    }
    let records = run_cases(seed, &indices, sample, &options);
    let elapsed = started.elapsed().as_secs_f64();
    println!(
        "\n# Contact stress: {} sample, seed {seed}, {count} sweeps, {} thread(s), {} build, \
         {elapsed:.1} s\n",
        sample.name(),
        options.threads,
        if optimized { "release" } else { "test-profile" },
    );
    println!("{}", summary_markdown(&records));
    if std::env::var("ANTENNA_STRESS_LIST").is_ok_and(|v| v.trim() == "1") {
        for r in &records {
            println!("- {}\n  -> {}", r.replay, r.outcome_line());
        }
    }
    println!("{}", unfinished_report(&records));
    println!(
        "Rerun one case: ANTENNA_STRESS_REPLAY={}:{seed}:INDEX cargo test -p antenna-tests{} \
         --test stress_contact -- {MAIN_TEST} --nocapture",
        sample.name(),
        if optimized { " --release" } else { "" }
    );
    let failures = records.iter().filter(|r| r.outcome.is_failure()).count();
    assert_eq!(
        failures, 0,
        "{failures} of {count} sweeps ended in a solver failure, a timeout, an uncertified step \
         or an invalid case (listed above with their replay lines)"
    );
    if sample == Sample::Ci && !all && seed == CI_SEED {
        same_results_as_golden(seed, &records);
    }
}

/// The CI sample's results are those kept in [`GOLDEN_FILE`] (issue #14: work done for speed
/// leaves them where they were), within [`STEP_TOLERANCE`]; with
/// `ANTENNA_STRESS_WRITE_GOLDEN=1` the file is written instead.
fn same_results_as_golden(seed: u64, records: &[SweepRecord]) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(GOLDEN_FILE);
    if std::env::var("ANTENNA_STRESS_WRITE_GOLDEN").is_ok_and(|v| v.trim() == "1") {
        std::fs::write(&path, golden_file(seed, records)).unwrap();
        println!("wrote {}", path.display());
        return;
    }
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let golden = parse_golden(&text).unwrap();
    assert_eq!(
        golden.len() as u64,
        CI_SWEEPS,
        "the golden file holds every sweep"
    );
    match compare(&golden, records, STEP_TOLERANCE) {
        Ok(deviation) => println!(
            "Results as in {GOLDEN_FILE} (tolerance {:e} m, {:e} rad): largest differences: \
             tip {:.1e} m, preview {:.1e} m, final joint angle {:.1e} rad",
            STEP_TOLERANCE.position_m,
            STEP_TOLERANCE.angle_rad,
            deviation.tip_m,
            deviation.preview_m,
            deviation.angle_rad
        ),
        Err(differences) => panic!(
            "{} difference(s) from {GOLDEN_FILE} beyond the step's tolerance:\n{}",
            differences.len(),
            differences.join("\n")
        ),
    }
}

#[test]
fn soak_sweeps_fixed_since_still_finish() {
    for (index, what) in SOAK_REGRESSIONS {
        let record = run_index(SOAK_SEED, *index, Sample::Soak, false);
        assert_eq!(
            record.outcome,
            Outcome::Finished,
            "soak:{SOAK_SEED}:{index} ({what}) no longer finishes: {}",
            record.outcome_line()
        );
    }
}

/// A held antenna that jams on its way onto the wall is a placement refused with the jam in
/// words, not a solver failure (soak 1110: N = 4, tip-on-wall S with the tip held 20 mm
/// behind the base, joint 2 on its stop and joint 3 pressed on the wall; the search for a
/// posture out of the wall used to move the held tip and found one, so the stalled solve was
/// reported as "the downhill path did not come to rest"). Which link the jam names, and
/// which joints pin it, depend on the path the held antenna took: link 2 with joint 2 on
/// its stop until 2026-11-27, link 1 pinned by joints 2 and 3 since a solve's first Newton
/// step keeps an unloaded contact free.
#[test]
fn a_held_antenna_that_jams_on_its_way_onto_the_wall_is_refused_with_the_jam() {
    let record = run_index(SOAK_SEED, 1110, Sample::Soak, false);
    let Outcome::PlacementRefused { message } = &record.outcome else {
        panic!("soak:{SOAK_SEED}:1110: {}", record.outcome_line());
    };
    for words in [
        "bringing the antenna onto the wall held by its tip failed: the antenna jammed",
        "no posture near the last one with the tip where the hand holds it keeps link",
        "out of the walls",
        "pinned by joint",
        "try another ahead_m or start",
    ] {
        assert!(message.contains(words), "{words:?} not in: {message}");
    }
}

/// A hair tip wedged in a concave corner, its hair unable to fold out of it, jams the
/// antenna (soak 1666: N = 4, distal hairs, a polyline with 78 deg corners, step 38); the
/// jam names the hair tip. The search for a posture out of the walls used to move the joints
/// only and leave hair tips out, found the links clear, and the stalled step was reported
/// as "the downhill path did not come to rest".
#[test]
fn a_hair_tip_wedged_in_a_concave_corner_jams_the_antenna() {
    let record = run_index(SOAK_SEED, 1666, Sample::Soak, false);
    let Outcome::Jammed {
        step, description, ..
    } = &record.outcome
    else {
        panic!("soak:{SOAK_SEED}:1666: {}", record.outcome_line());
    };
    assert_eq!(*step, 38);
    assert!(
        description.contains("keeps the hair tip of link 1 out of the walls")
            && description.contains("pinned by the hair tip of link 1 against wall 0"),
        "{description}"
    );
}

/// A 150-link antenna held by its tip on a fine sinusoid (crests of 1.2 mm radius, half a
/// link) and let go springs onto the wall in a long snap: the placement's settle has ten
/// steps' budget and says what it took (soak 975 ran out of one step's 10,000 Newton
/// iterations: "the downhill path did not come to rest").
#[test]
fn a_long_antenna_let_go_on_a_fine_sinusoid_snaps_to_rest_within_the_placement_budget() {
    let case = Case::generate(SOAK_SEED, 975, Sample::Soak).unwrap();
    let sweep = sim_core::sweep::Sweep::new(case.scene).unwrap();
    let note = sweep.placement_note();
    assert!(
        note.contains("so it was held by the tip and brought") && note.contains("snapped to rest"),
        "{note}"
    );
}

/// Corners of drawn polylines (not the ones placed on a posture): every one turns 5-85 deg,
/// and over a sample both convex and concave corners reach both ends of the range; some
/// edges are shorter than a link.
#[test]
fn polyline_corners_span_5_to_85_degrees_both_ways() {
    let mut convex = (f64::INFINITY, 0.0_f64);
    let mut concave = (f64::INFINITY, 0.0_f64);
    let mut short_edges = 0;
    let frame = WallFrame {
        origin_m: Vector2::new(0.0, 0.2),
        angle_rad: -8f64.to_radians(),
    };
    for i in 0..600 {
        let mut rng = case_rng(7, i);
        let link_m = ANTENNA_LENGTH_M / LINK_COUNTS[i as usize % LINK_COUNTS.len()] as f64;
        let profile = if i % 2 == 0 {
            draw_polyline(&mut rng, link_m, (-0.3, 0.5))
        } else {
            let style = [
                AnchorStyle::StepUp,
                AnchorStyle::StepDown,
                AnchorStyle::Tooth,
                AnchorStyle::Pocket,
            ][(i as usize / 2) % 4];
            draw_anchored_polyline(&mut rng, link_m, (-0.3, 0.5), style)
        };
        let Profile::Polyline { knots, .. } = &profile else {
            panic!("not a polyline");
        };
        assert!(knots.windows(2).all(|w| w[1].0 > w[0].0), "not a graph");
        let spec = walls::WallSpec {
            kind: WallKind::Polyline,
            frame,
            profile,
            mu: 0.3,
            corner_at: None,
        };
        spec.build().unwrap();
        for c in spec.corners() {
            assert!(
                (5.0 - 1e-9..=85.0 + 1e-9).contains(&c.turn_deg),
                "corner of {} deg",
                c.turn_deg
            );
            let e = if c.convex { &mut convex } else { &mut concave };
            e.0 = e.0.min(c.turn_deg);
            e.1 = e.1.max(c.turn_deg);
        }
        short_edges += usize::from(spec.shortest_edge_m().unwrap() < link_m);
    }
    for (name, (lo, hi)) in [("convex", convex), ("concave", concave)] {
        assert!(
            lo < 7.0 && hi > 83.0,
            "{name} corners span only {lo}..{hi} deg"
        );
    }
    assert!(
        short_edges > 300,
        "{short_edges} of 600 walls have an edge shorter than a link"
    );
}

/// Corners are put exactly on a point of the start posture: for rest and angles placements
/// a vertex of the wall is bit for bit a joint, the tip or a hair tip of the posture (and
/// the posture is clear of the wall); for tip-on-wall a vertex lies on the pin line.
#[test]
fn corners_sit_exactly_on_start_posture_points() {
    let (mut on_rest_or_angles, mut on_tip) = (0, 0);
    for index in 0..400 {
        let case = Case::generate(11, index, Sample::Soak).unwrap();
        let Some(at) = &case.wall.corner_at else {
            continue;
        };
        let vertices = case.wall.vertices_m();
        let chain = &case.scene.chain;
        match &case.scene.placement {
            Placement::Rest | Placement::Angles(_) => {
                let theta = match &case.scene.placement {
                    Placement::Angles(a) => {
                        let mut t = vec![chain.base_angle_rad()];
                        t.extend_from_slice(a);
                        t
                    }
                    _ => chain.rest_theta(),
                };
                let posture = PosturePoints::new(chain, &theta, Vector2::zeros()).unwrap();
                let points: Vec<Vector2<f64>> = posture
                    .ends_m
                    .iter()
                    .copied()
                    .chain(posture.hair_tips_m.iter().map(|h| h.1))
                    .collect();
                assert!(
                    vertices.iter().any(|v| points.contains(v)),
                    "{}: no vertex on the posture ({at})",
                    case.replay_line()
                );
                let gap = posture.min_gap(&case.scene.walls[0]).0;
                assert!(
                    gap >= -1e-12,
                    "{}: posture {gap} m inside",
                    case.replay_line()
                );
                on_rest_or_angles += 1;
            }
            Placement::TipOnWall { ahead_m, .. } => {
                assert!(
                    vertices.iter().any(|v| (v.x - ahead_m).abs() < 1e-12),
                    "{}: no vertex at the pin",
                    case.replay_line()
                );
                on_tip += 1;
            }
            Placement::Approach { .. } => panic!("approach cases are not anchored"),
        }
    }
    assert!(
        on_rest_or_angles >= 10 && on_tip >= 10,
        "{on_rest_or_angles} rest/angles and {on_tip} tip-on-wall cases with anchored corners"
    );
}

/// Sinusoid crests bend down to a radius of exactly half a link (and no tighter), as
/// sim-core's own curvature at the crest says too.
#[test]
fn sinusoid_crests_reach_half_a_link() {
    for links in LINK_COUNTS {
        let link_m = ANTENNA_LENGTH_M / links as f64;
        let mut smallest = f64::INFINITY;
        for i in 0..200 {
            let mut rng = case_rng(links as u64, i);
            let Profile::Sinusoid {
                amplitude_m,
                frequency_per_m,
                phase_rad,
            } = draw_sinusoid(&mut rng, link_m)
            else {
                panic!("not a sinusoid");
            };
            assert!((walls::AMPLITUDE_M.0..=walls::AMPLITUDE_M.1).contains(&amplitude_m));
            let r = crest_radius_m(amplitude_m, frequency_per_m);
            assert!(
                r >= 0.5 * link_m * (1.0 - 1e-9),
                "radius {r} under half a link"
            );
            assert!(r <= walls::MAX_CREST_RADIUS_M * (1.0 + 1e-9));
            smallest = smallest.min(r);
            // The crest that bulges toward the antenna (v = -A): sim-core's curvature there.
            let frame = WallFrame {
                origin_m: Vector2::new(0.01, 0.2),
                angle_rad: -0.1,
            };
            let spec = walls::WallSpec {
                kind: WallKind::Sinusoid,
                frame,
                profile: Profile::Sinusoid {
                    amplitude_m,
                    frequency_per_m,
                    phase_rad,
                },
                mu: 0.0,
                corner_at: None,
            };
            let wall = spec.build().unwrap();
            let k = std::f64::consts::TAU * frequency_per_m;
            let u = (1.5 * std::f64::consts::PI - phase_rad) / k;
            let probe = frame.to_ground(u, -amplitude_m - 1e-4);
            let at = wall.signed_distance(&probe);
            assert!(
                (at.curvature_per_m * r - 1.0).abs() < 1e-6,
                "sim-core's crest curvature {} 1/m, drawn radius {r} m",
                at.curvature_per_m
            );
        }
        assert!(
            (smallest / link_m - 0.5).abs() < 1e-9,
            "N = {links}: the tightest crest is {} links",
            smallest / link_m
        );
    }
}

/// Digitized walls: valid sim-core polylines of at most 300 vertices, sampled every 1-5 mm
/// with noise of the drawn size.
#[test]
fn digitized_walls_are_valid_polylines() {
    let frame = WallFrame {
        origin_m: Vector2::new(0.0, 0.18),
        angle_rad: -5f64.to_radians(),
    };
    let (mut lines, mut trapezoids) = (0, 0);
    for i in 0..120 {
        let mut rng = case_rng(3, i);
        let link_m = ANTENNA_LENGTH_M / LINK_COUNTS[i as usize % LINK_COUNTS.len()] as f64;
        let profile = draw_digitized(&mut rng, link_m, (-0.3, 0.5), &frame).unwrap();
        let Profile::Digitized {
            points,
            underlying,
            spacing_m,
            noise_m,
        } = &profile
        else {
            panic!("not digitized");
        };
        assert!(
            points.len() <= walls::MAX_DIGITIZED_POINTS,
            "{} points",
            points.len()
        );
        assert!((walls::SPACING_M.0..=walls::SPACING_M.1).contains(spacing_m));
        assert!((walls::NOISE_M.0..=walls::NOISE_M.1).contains(noise_m));
        let ground: Vec<Vector2<f64>> =
            points.iter().map(|&(u, v)| frame.to_ground(u, v)).collect();
        let polyline = Polyline::new(ground.clone(), SolidSide::Left).unwrap();
        let spec = walls::WallSpec {
            kind: WallKind::Digitized,
            frame,
            profile: profile.clone(),
            mu: 0.6,
            corner_at: None,
        };
        let wall = spec.build().unwrap();
        assert_eq!(wall.shape, WallShape::Polyline(polyline));
        let interior = &points[1..points.len() - 1];
        match underlying {
            Underlying::Line => {
                lines += 1;
                // The noise across the line is what was drawn.
                let var = interior.iter().map(|p| p.1 * p.1).sum::<f64>() / interior.len() as f64;
                let ratio = var.sqrt() / noise_m;
                assert!(
                    (0.7..1.3).contains(&ratio),
                    "noise {ratio} x the drawn size"
                );
                let mean_step =
                    (interior[interior.len() - 1].0 - interior[0].0) / (interior.len() - 1) as f64;
                assert!((mean_step / spacing_m - 1.0).abs() < 0.05);
            }
            Underlying::Trapezoid => trapezoids += 1,
        }
    }
    assert!(lines > 30 && trapezoids > 30);
}

/// A case is a pure function of (seed, index, sample).
#[test]
fn same_seed_same_case() {
    for index in 0..40 {
        let a = Case::generate(CI_SEED, index, Sample::Ci).unwrap();
        let b = Case::generate(CI_SEED, index, Sample::Ci).unwrap();
        assert_eq!(format!("{:?}", a.scene), format!("{:?}", b.scene));
        assert_eq!(a.replay_line(), b.replay_line());
        let c = Case::generate(CI_SEED, index + 1, Sample::Ci).unwrap();
        assert_ne!(format!("{:?}", a.scene), format!("{:?}", c.scene));
    }
}

/// The CI sample reaches every axis: every N (72 and 150 only in short sweeps), wall kind,
/// placement, mu, profile, hair layout, and corners on the posture.
#[test]
fn ci_sample_spans_every_axis() {
    let cases: Vec<Case> = (0..CI_SWEEPS)
        .map(|i| Case::generate(CI_SEED, i, Sample::Ci).unwrap())
        .collect();
    for n in LINK_COUNTS {
        let of_n: Vec<&Case> = cases.iter().filter(|c| c.links == n).collect();
        assert!(!of_n.is_empty(), "no case with N = {n}");
        if n >= 72 {
            assert!(of_n.len() <= 10 && of_n.iter().all(|c| c.steps() <= 50));
        }
    }
    for kind in WallKind::ALL {
        assert!(
            cases.iter().any(|c| c.wall.kind == kind),
            "no {kind:?} wall"
        );
    }
    for kind in PlacementKind::ALL {
        assert!(
            cases.iter().any(|c| c.placement_kind == kind),
            "no {kind:?}"
        );
    }
    for mu in MUS {
        assert!(cases.iter().any(|c| c.wall.mu == mu), "no mu = {mu}");
    }
    for p in antenna_tests::reproduce::TABLE_4_1_PROFILES {
        assert!(cases.iter().any(|c| c.profile == p), "no {}", p.name());
    }
    assert!(cases.iter().any(|c| c.hairs) && cases.iter().any(|c| !c.hairs));
    // Compliant hairs over a wide range, and rigid ones beside them.
    let roots: Vec<f64> = cases
        .iter()
        .flat_map(|c| c.root_stiffnesses_nm_per_rad())
        .collect();
    assert!(roots.iter().any(|&k| k < 1e-3) && roots.iter().any(|&k| k > 1.0));
    assert!(cases.iter().any(|c| {
        c.scene
            .chain
            .hairs()
            .iter()
            .flatten()
            .any(|h| h.root_stiffness_nm_per_rad.is_none())
    }));
    assert!(cases.iter().any(|c| c.wall.corner_at.is_some()));
}

/// A record survives the trip through a child process's output, every outcome.
#[test]
fn records_round_trip_through_text() {
    let case = Case::generate(CI_SEED, 3, Sample::Ci).unwrap();
    let outcomes = [
        Outcome::Finished,
        Outcome::Jammed {
            step: 17,
            description: "tip\tpinned\nby a corner \\ and link 3".into(),
            contacts: vec!["Vertex { link: 8 } on wall 0".into(), "x".into()],
            joints_on_stops: vec![3, 4],
        },
        Outcome::PlacementRefused {
            message: "placement: no".into(),
        },
        Outcome::SolverFailure {
            step: None,
            message: "panic: x".into(),
        },
        Outcome::SolverFailure {
            step: Some(4),
            message: String::new(),
        },
        Outcome::Uncertified {
            step: 2,
            failures: vec!["penetration 1e-3 m".into()],
        },
        Outcome::InvalidCase {
            message: "bad".into(),
        },
        Outcome::TimedOut {
            limit_s: 12.5,
            last_step: Some(40),
        },
    ];
    for outcome in outcomes {
        let mut rec = SweepRecord::new(&case);
        rec.outcome = outcome;
        rec.steps = 41;
        rec.iterations = vec![1, 2, 300];
        rec.relaxations
            .insert("friction dropped at # jammed contact(s)".into(), 2);
        rec.wall_clock_s = 0.123_456_789;
        rec.placement_note = "tip placed\ton the wall".into();
        let text = format!("running 1 test\n{}test ok\n", rec.to_wire());
        let back = SweepRecord::from_wire(&text).unwrap();
        assert_eq!(format!("{back:?}"), format!("{rec:?}"));
    }
    assert!(SweepRecord::from_wire("<<<stress-record\nseed\t1\n").is_none());
}
