//! A base that moves and turns: [`QuasiStatic::step_to_pose`] against the scene turned
//! rigidly, one turn against many, a stuck contact under a turn, a held tip, the
//! certificate's own slips, and the plain step it generalizes, bit for bit.

#![allow(clippy::unwrap_used)]

use nalgebra::Vector2;

use crate::contact::certifier::Certifier;
use crate::contact::posture::rotate;
use crate::contact::{ContactError, ContactSettings, QuasiStatic, Slip};
use crate::{Chain, Line, Polyline, SolidSide, Surface, SurfaceMap, Wall};

/// A 7-link antenna (30 mm links, 0.01 N m/rad joints) with its base link at
/// `base_angle_rad`.
fn antenna(base_angle_rad: f64) -> Chain {
    Chain::builder(6)
        .link_length_m(0.03)
        .base_angle_rad(base_angle_rad)
        .stiffness_nm_per_rad(0.01)
        .build()
        .unwrap()
}

fn surface(mu: f64) -> SurfaceMap {
    SurfaceMap::uniform(Surface::Smooth { mu }).unwrap()
}

/// A line wall through (0, 0.09) m sloping down by 5 degrees, solid above, turned by
/// `phi_rad` about the origin.
fn line_wall(phi_rad: f64, mu: f64) -> Wall {
    let point = rotate(phi_rad, Vector2::new(0.0, 0.09));
    let line = Line::new(point, -5f64.to_radians() + phi_rad, SolidSide::Left).unwrap();
    Wall::new(line, surface(mu))
}

/// A polyline wall, solid above, with a convex corner ahead of the tip (the wall falls away
/// past x = 0.2 m), turned by `phi_rad` about the origin.
fn polyline_wall(phi_rad: f64, mu: f64) -> Wall {
    let vertices = [(-0.3, 0.08), (0.2, 0.075), (0.5, 0.03)]
        .iter()
        .map(|&(x, y)| rotate(phi_rad, Vector2::new(x, y)))
        .collect();
    Wall::new(
        Polyline::new(vertices, SolidSide::Left).unwrap(),
        surface(mu),
    )
}

/// The antenna at 30 degrees (plus `phi_rad`), its base at `(0, -0.04)` turned by
/// `phi_rad`, among `walls`.
fn sim_among(phi_rad: f64, walls: Vec<Wall>) -> QuasiStatic {
    let chain = antenna(30f64.to_radians() + phi_rad);
    let theta = chain.rest_theta();
    let base = rotate(phi_rad, Vector2::new(0.0, -0.04));
    QuasiStatic::new(chain, walls, base, &theta, ContactSettings::default()).unwrap()
}

/// The steps of [`poses`] that bring the base up onto the wall.
const APPROACH: usize = 50;

/// The base poses of a run: up onto the wall (0.5 mm steps, the first [`APPROACH`]; the
/// tip touches after some 20), then along it 0.5 mm a step while the base turns back and
/// forth by up to 3 degrees.
fn poses() -> Vec<(Vector2<f64>, f64)> {
    let start = 30f64.to_radians();
    let mut out: Vec<(Vector2<f64>, f64)> = (1..=APPROACH)
        .map(|k| (Vector2::new(0.0, approach_y_m(k)), start))
        .collect();
    for k in 1..=40 {
        let t = f64::from(k);
        let turn = 3f64.to_radians() * (t * 0.25).sin();
        out.push((
            Vector2::new(0.0005 * t, approach_y_m(APPROACH)),
            start + turn,
        ));
    }
    out
}

/// The base's height at approach step `k`, metres.
fn approach_y_m(k: usize) -> f64 {
    -0.04 + 0.0005 * k as f64
}

/// Turned rigidly about the origin by `phi_rad` (walls, base, base angle), a run of turning
/// steps takes the same joint angles, forces and slips, its contact points turned with it.
///
/// Within 1e-9 relative: joint angles to 1e-9 rad, forces to 1e-9 of the step's largest
/// contact force, slips and contact points to 1e-9 of the chain's reach (0.21 m). The
/// turned scene differs from the first by rounding alone and its solves take the same
/// path: measured, the two runs differ by 4e-16 rad, 3e-17 N and 2e-16 m at most.
#[test]
fn a_scene_turned_rigidly_takes_the_same_steps() {
    type Walls = fn(f64, f64) -> Wall;
    for (name, walls, mu) in [
        ("line", line_wall as Walls, 0.3),
        ("polyline", polyline_wall as Walls, 0.3),
        ("frictionless line", line_wall as Walls, 0.0),
    ] {
        for phi_deg in [37.0_f64, -120.0, 180.0] {
            let phi = phi_deg.to_radians();
            let mut plain = sim_among(0.0, vec![walls(0.0, mu)]);
            let mut turned = sim_among(phi, vec![walls(phi, mu)]);
            let mut touched = 0;
            for (k, &(base, angle)) in poses().iter().enumerate() {
                let what = format!("{name}, turned by {phi_deg} degrees, step {k}");
                plain.step_to_pose(base, angle).unwrap();
                turned.step_to_pose(rotate(phi, base), angle + phi).unwrap();
                assert!(
                    (turned.base_angle_rad() - plain.base_angle_rad() - phi).abs() < 1e-12,
                    "{what}"
                );
                for (a, b) in plain.theta_rad()[1..].iter().zip(&turned.theta_rad()[1..]) {
                    assert!((a - b).abs() < 1e-9, "{what}: joint angles {a} and {b}");
                }
                let (ca, cb) = (plain.contacts(), turned.contacts());
                assert_eq!(ca.len(), cb.len(), "{what}: contacts");
                touched += usize::from(!ca.is_empty());
                let force_n = ca
                    .iter()
                    .map(|c| c.force_n().norm())
                    .fold(0.0_f64, f64::max);
                let length_m = 1e-9 * plain.reach_m();
                for (a, b) in ca.iter().zip(&cb) {
                    assert_eq!(a.feature, b.feature, "{what}");
                    assert_eq!(a.slip, b.slip, "{what}");
                    assert!(
                        (a.normal_force_n - b.normal_force_n).abs() <= 1e-9 * force_n,
                        "{what}: normal forces {} and {} N",
                        a.normal_force_n,
                        b.normal_force_n
                    );
                    assert!(
                        (a.shear_force_n - b.shear_force_n).abs() <= 1e-9 * force_n,
                        "{what}: shear forces {} and {} N",
                        a.shear_force_n,
                        b.shear_force_n
                    );
                    assert!((a.slip_m - b.slip_m).abs() < length_m, "{what}: slips");
                    assert!(
                        (rotate(phi, a.point_m) - b.point_m).norm() < length_m,
                        "{what}: contact points"
                    );
                }
            }
            assert!(
                touched > 40,
                "{name}: the antenna touched in {touched} steps"
            );
        }
    }
}

/// The antenna pressed onto a frictionless wall, then its base turned toward the wall by 10
/// degrees: in one step or in 16, it ends in the same posture (without friction the
/// equilibrium does not depend on the path).
#[test]
fn one_turn_and_sixteen_small_ones_end_alike_without_friction() {
    let settle = || {
        let mut sim = sim_among(0.0, vec![line_wall(0.0, 0.0)]);
        for &(base, angle) in &poses()[..APPROACH] {
            sim.step_to_pose(base, angle).unwrap();
        }
        assert!(!sim.contacts().is_empty());
        sim
    };
    let mut whole = settle();
    let mut parts = settle();
    let base = whole.base_m();
    let from = whole.base_angle_rad();
    let turn = 10f64.to_radians();
    let report = whole.step_to_pose(base, from + turn).unwrap();
    for k in 1..=16 {
        parts
            .step_to_pose(base, from + turn * f64::from(k) / 16.0)
            .unwrap();
    }
    assert_eq!(whole.theta_rad()[0], parts.theta_rad()[0]);
    for (a, b) in whole.theta_rad().iter().zip(parts.theta_rad()) {
        assert!(
            (a - b).abs() < 1e-9,
            "joint angles {a} and {b} ({report:?})"
        );
    }
    let (ca, cb) = (whole.contacts(), parts.contacts());
    assert_eq!(ca.len(), cb.len());
    for (a, b) in ca.iter().zip(&cb) {
        assert_eq!(a.feature, b.feature);
        assert!((a.normal_force_n - b.normal_force_n).abs() < 1e-8);
    }
    // The turn pressed the antenna further onto the wall.
    assert!(ca.iter().any(|c| c.normal_force_n > 0.0));
}

/// A contact stuck on a wall with mu = 1 stays where it is on the wall (to a micrometre)
/// while the base turns a little, and is still reported stuck: the antenna at 70 degrees
/// pushed up onto a level wall (its tip link steep on the wall, well inside the cone).
#[test]
fn a_stuck_contact_stays_put_in_the_ground_frame_during_a_turn() {
    let chain = antenna(70f64.to_radians());
    let theta = chain.rest_theta();
    let wall = Wall::new(
        Line::new(Vector2::new(0.0, 0.15), 0.0, SolidSide::Left).unwrap(),
        surface(1.0),
    );
    let mut sim = QuasiStatic::new(
        chain,
        vec![wall],
        Vector2::new(0.0, -0.06),
        &theta,
        ContactSettings::default(),
    )
    .unwrap();
    for k in 1..=STUCK_APPROACH {
        sim.step_to(Vector2::new(0.0, -0.06 + 0.0005 * k as f64))
            .unwrap();
    }
    let before = sim.contacts();
    let stuck: Vec<_> = before
        .iter()
        .filter(|c| c.slip == Slip::Stuck && c.normal_force_n > 1e-6)
        .copied()
        .collect();
    assert!(!stuck.is_empty(), "no stuck contact: {before:?}");
    let base = sim.base_m();
    let from = sim.base_angle_rad();
    for k in 1..=4 {
        sim.step_to_pose(base, from + STUCK_TURN_DEG.to_radians() * f64::from(k))
            .unwrap();
        let after = sim.contacts();
        for c in &stuck {
            let now = after
                .iter()
                .find(|a| a.feature == c.feature && a.wall == c.wall)
                .unwrap_or_else(|| panic!("turn {k}: {:?} let go: {after:?}", c.feature));
            assert_eq!(now.slip, Slip::Stuck, "turn {k}: {now:?}");
            assert!(
                (now.point_m - c.point_m).norm() < 1e-6,
                "turn {k}: the stuck contact moved by {} m",
                (now.point_m - c.point_m).norm()
            );
        }
    }
    assert_eq!(
        sim.base_angle_rad(),
        from + STUCK_TURN_DEG.to_radians() * 4.0
    );
}

const STUCK_APPROACH: usize = 40;
const STUCK_TURN_DEG: f64 = 0.25;

/// `step_to(b)` and `step_to_pose(b, current angle)` are the same step, bit for bit: the
/// joint angles, the contacts and the reports of a sweep onto a rough wall and along it.
#[test]
fn step_to_is_step_to_pose_at_the_current_angle_bit_for_bit() {
    for walls in [line_wall as fn(f64, f64) -> Wall, polyline_wall] {
        let mut a = sim_among(0.0, vec![walls(0.0, 0.5)]);
        let mut b = sim_among(0.0, vec![walls(0.0, 0.5)]);
        for k in 1..=90 {
            let k = f64::from(k);
            let base = if k <= 60.0 {
                Vector2::new(0.0, -0.04 + 0.0005 * k)
            } else {
                Vector2::new(0.0007 * (k - 60.0), -0.01)
            };
            let ra = a.step_to(base).unwrap();
            let rb = b.step_to_pose(base, b.base_angle_rad()).unwrap();
            assert_eq!(ra, rb);
            assert_eq!(a.theta_rad(), b.theta_rad());
            assert_eq!(a.hair_angles_rad(), b.hair_angles_rad());
            assert_eq!(a.contacts(), b.contacts());
        }
        assert!(!a.contacts().is_empty());
    }
}

/// The chain's base angle follows every step; a base angle that is not a number is refused
/// before anything moves.
#[test]
fn the_chain_turns_with_the_base_and_a_nan_angle_is_refused() {
    let mut sim = sim_among(0.0, vec![line_wall(0.0, 0.3)]);
    for &(base, angle) in &poses() {
        sim.step_to_pose(base, angle).unwrap();
        assert_eq!(sim.chain().base_angle_rad(), sim.theta_rad()[0]);
        assert_eq!(sim.base_angle_rad(), angle);
    }
    let theta = sim.theta_rad().to_vec();
    let base = sim.base_m();
    for bad in [f64::NAN, f64::INFINITY] {
        match sim.step_to_pose(base, bad) {
            Err(ContactError::NotFinite { argument, .. }) => {
                assert_eq!(argument, "base_angle_rad");
            }
            other => panic!("{other:?}"),
        }
    }
    assert_eq!(sim.theta_rad(), theta.as_slice());
    assert!(matches!(
        sim.step_to_pose(Vector2::new(f64::NAN, 0.0), 0.5),
        Err(ContactError::NotFinite {
            argument: "base_m",
            ..
        })
    ));
}

/// A big turn into the wall (40 and 90 degrees at once, the base still) is split into
/// substeps, a pure turn too, and ends certified or in a typed error, never a panic; the
/// state is then a certified one all the same where it went through.
#[test]
fn a_big_turn_into_a_wall_is_split_and_ends_typed() {
    for turn_deg in [40.0_f64, 90.0, -60.0] {
        let mut sim = sim_among(0.0, vec![line_wall(0.0, 0.3)]);
        for &(base, angle) in &poses()[..APPROACH] {
            sim.step_to_pose(base, angle).unwrap();
        }
        let base = sim.base_m();
        let to = sim.base_angle_rad() + turn_deg.to_radians();
        match sim.step_to_pose(base, to) {
            Ok(report) => {
                assert!(report.substeps > 1, "{turn_deg} degrees: {report:?}");
                assert_eq!(sim.base_angle_rad(), to);
                let tolerances = sim.certify_tolerances();
                assert!(sim.check().holds_within(&tolerances));
            }
            Err(
                ContactError::Jammed(_)
                | ContactError::NoConvergence { .. }
                | ContactError::BaseInsideWall { .. }
                | ContactError::Uncertified { .. },
            ) => {}
            Err(other) => panic!("{turn_deg} degrees: {other}"),
        }
        assert_eq!(sim.chain().base_angle_rad(), sim.theta_rad()[0]);
    }
}

/// A tip held by a hand turns with the base: turned by 90 degrees without walls, the
/// antenna keeps its joint angles (bent by the hand as before) and the tip is where the
/// hand's offset, turned, puts it.
#[test]
fn a_held_tip_turns_with_the_base() {
    let chain = antenna(30f64.to_radians());
    let theta = chain.rest_theta();
    let mut sim = QuasiStatic::new(
        chain,
        Vec::new(),
        Vector2::zeros(),
        &theta,
        ContactSettings::default(),
    )
    .unwrap();
    let tip = |sim: &QuasiStatic| {
        let poses = crate::frame_poses(sim.chain(), sim.theta_rad(), crate::Frame::GROUND).unwrap();
        sim.base_m() + poses.position_m(sim.chain().tip()).unwrap()
    };
    let offset = tip(&sim) + Vector2::new(0.01, -0.02);
    sim.hold_tip(Some(offset));
    sim.settle().unwrap();
    // The hand's spring is stiff, not rigid: the tip stays a little off where it is held.
    let off = tip(&sim) - offset;
    assert!(off.norm() < 1e-3, "{off:?}");
    let bent = sim.theta_rad()[1..].to_vec();
    assert!(bent.iter().any(|t| t.abs() > 1e-3), "the hand bends it");
    let base = Vector2::new(0.05, 0.02);
    let quarter = std::f64::consts::FRAC_PI_2;
    let report = sim
        .step_to_pose(base, sim.base_angle_rad() + quarter)
        .unwrap();
    for (a, b) in bent.iter().zip(&sim.theta_rad()[1..]) {
        assert!(
            (a - b).abs() < 1e-9,
            "joint angles {a} and {b} ({report:?})"
        );
    }
    // As far off the hand, turned with it.
    let held_at = base + rotate(quarter, offset);
    let turned_off = tip(&sim) - held_at;
    assert!(
        (turned_off - rotate(quarter, off)).norm() < 1e-9,
        "{turned_off:?} against {off:?}"
    );
}

/// The certificate computes each contact's slip from the committed state the step started
/// from, not from the solver's own `slip_m`: a wrong slip in the solver's pairs changes
/// nothing, a start turned by a milliradian fails the stuck contacts.
#[test]
fn the_certificate_recomputes_slip_from_the_committed_start() {
    let mut sim = sim_among(0.0, vec![line_wall(0.0, 1.0)]);
    for &(base, angle) in &poses()[..APPROACH] {
        sim.step_to_pose(base, angle).unwrap();
    }
    let base = sim.base_m();
    let report = sim
        .step_to_pose(base, sim.base_angle_rad() + 0.001)
        .unwrap();
    let check = sim.check();
    assert_eq!(report.certificate, check);
    let tolerances = sim.certify_tolerances();
    assert!(check.holds_within(&tolerances));
    assert!(
        sim.committed()
            .pairs()
            .iter()
            .any(|p| p.slip == Slip::Stuck)
    );
    // The solver's own slips, wrong: the check does not read them.
    let mut wrong = sim.committed().clone();
    for p in wrong.pairs_mut() {
        p.slip_m = 1.0;
    }
    assert_eq!(Certifier::new(sim.world(), &wrong).check(), check);
    // The start the step was taken from, turned: the stuck contacts slipped by as much.
    let mut turned_start = sim.committed().clone();
    turned_start.step_start_theta_mut()[0] -= 1e-3;
    let turned = Certifier::new(sim.world(), &turned_start).check();
    assert!(turned.stuck_slip_m > 1e-5, "{turned:?}");
    assert!(!turned.holds_within(&tolerances));
}
