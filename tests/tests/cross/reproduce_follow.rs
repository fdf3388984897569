//! The thesis's closing claim in the closed loop (`tests/src/reproduce/follow.rs`,
//! docs/reproduction.md section 5), on a reduced grid fit for CI: three profiles (constant,
//! fast-exponential, fast-reciprocal) on two walls (straight, 45 deg inward), no hairs, the
//! protocol's coarse speed grid (0.25, 0.5, 1 and 2 m/s, no bisection); and four runs of the
//! fast-exponential antenna with and without distal hairs.
//!
//! What holds, asserted: the fast-exponential antenna follows where the constant one does
//! not (the constant antenna drifts from the setpoint at every speed); at 0.5 m/s it follows
//! with a smaller RMS error than the antenna stiffer at the tip; distal hairs on rough walls
//! lower its error and let it follow the sinusoid at 1 m/s. What the claim says and this
//! model does not give, asserted too so that a change shows: a profile stiffer at the tip
//! (fast-reciprocal) follows the inward wall at least as fast as the fast-exponential one.
#![allow(clippy::unwrap_used)]

use antenna_tests::reproduce::follow::{self, Cell, FollowWall, Hairs, Protocol};
use sim_core::StiffnessProfile;

#[test]
fn the_fast_exponential_antenna_follows_where_the_constant_one_drifts() {
    let protocol = Protocol::coarse();
    let profiles = [
        StiffnessProfile::Constant,
        StiffnessProfile::FastExponential,
        StiffnessProfile::FastReciprocal,
    ];
    let walls = [FollowWall::Straight, FollowWall::Inward45];
    let cells = follow::run_grid(&profiles, &walls, &[Hairs::None], &protocol).unwrap();
    assert_eq!(cells.len(), 6);
    let cell = |p: StiffnessProfile, w: FollowWall| -> &Cell {
        cells
            .iter()
            .find(|c| c.profile == p && c.wall == w)
            .unwrap()
    };
    let v = |p: StiffnessProfile, w: FollowWall| cell(p, w).v_max.v_max_m_per_s.unwrap_or(0.0);
    let rms = |p: StiffnessProfile, w: FollowWall| {
        let run = &cell(p, w).common;
        assert_eq!(run.speed_m_per_s, 0.5);
        run.rms_error_m.unwrap()
    };
    for w in walls {
        // Every grid speed was run, the common one among them.
        for p in &profiles {
            let c = cell(p.clone(), w);
            assert_eq!(c.v_max.runs.len(), 4, "{} on {}", p.name(), w.name());
            for (_, status) in &c.v_max.runs {
                assert!(
                    ["ok", "drifted", "collided", "lost"].contains(&status.as_str())
                        || sim_core::follow::STATUS_NAMES.contains(&status.as_str()),
                    "{status}"
                );
            }
        }
        // The constant antenna does not follow even at the slowest speed; the
        // fast-exponential one follows at 1 m/s.
        let constant = cell(StiffnessProfile::Constant, w);
        assert_eq!(constant.v_max.v_max_m_per_s, None, "{}", w.name());
        assert_eq!(
            constant.v_max.failure.as_deref(),
            Some("drifted"),
            "{}",
            w.name()
        );
        let fe = v(StiffnessProfile::FastExponential, w);
        assert!(fe >= 1.0, "{}: fast-exponential v_max {fe}", w.name());
        // At 0.5 m/s: the constant antenna drifts; the fast-exponential one has a smaller
        // RMS error than the fast-reciprocal one.
        assert!(
            !cell(StiffnessProfile::Constant, w).common.good(),
            "{}",
            w.name()
        );
        let (fe_rms, fr_rms) = (
            rms(StiffnessProfile::FastExponential, w),
            rms(StiffnessProfile::FastReciprocal, w),
        );
        assert!(
            fe_rms < fr_rms,
            "{}: fast-exponential {:.1} mm, fast-reciprocal {:.1} mm",
            w.name(),
            fe_rms * 1e3,
            fr_rms * 1e3
        );
    }
    // Not the claim: on the 45 deg inward wall the antenna stiffer at the tip is as fast.
    let (fe, fr) = (
        v(StiffnessProfile::FastExponential, FollowWall::Inward45),
        v(StiffnessProfile::FastReciprocal, FollowWall::Inward45),
    );
    assert!(
        fr >= fe,
        "fast-reciprocal {fr} m/s, fast-exponential {fe} m/s"
    );
}

#[test]
fn distal_hairs_on_rough_walls_lower_the_error_and_open_the_sinusoid() {
    let protocol = Protocol::coarse();
    let fe = StiffnessProfile::FastExponential;
    let run = |wall: FollowWall, hairs: Hairs, speed_m_per_s: f64| {
        let base = follow::load_case(wall).unwrap();
        let case = follow::case_for(&base, fe.clone(), hairs).unwrap();
        follow::run_at(&case, speed_m_per_s, &protocol).unwrap()
    };
    // Along the straight wall at 0.5 m/s both follow, the one with hairs closer.
    let (bare, hairy) = (
        run(FollowWall::Straight, Hairs::None, 0.5),
        run(FollowWall::Straight, Hairs::DistalRough, 0.5),
    );
    assert!(
        bare.good() && hairy.good(),
        "{} {}",
        bare.status,
        hairy.status
    );
    let (bare_rms, hairy_rms) = (bare.rms_error_m.unwrap(), hairy.rms_error_m.unwrap());
    assert!(
        hairy_rms < bare_rms,
        "with hairs {:.1} mm, without {:.1} mm",
        hairy_rms * 1e3,
        bare_rms * 1e3
    );
    // Along the sinusoid at 1 m/s only the antenna with hairs follows.
    let (bare, hairy) = (
        run(FollowWall::Sinusoid, Hairs::None, 1.0),
        run(FollowWall::Sinusoid, Hairs::DistalRough, 1.0),
    );
    assert!(!bare.good(), "without hairs: {}", bare.status);
    assert!(hairy.good(), "with hairs: {}", hairy.status);
}
