//! Non-penetration of every link, not only the joints (docs/model.md 6): a polyline corner poking
//! into a link between its joints, a sinusoid's crests, a link lying flat on a wall; and the
//! independent check after every step.
#![allow(clippy::unwrap_used)]

use nalgebra::Vector2;
use sim_core::contact::{ContactSettings, Feature, QuasiStatic};
use sim_core::{Chain, Line, Polyline, Sinusoid, SolidSide, Wall};

fn chain(n: usize, base_deg: f64, k: f64) -> Chain {
    Chain::builder(n)
        .link_length_m(0.04)
        .base_angle_rad(base_deg.to_radians())
        .stiffness_nm_per_rad(k)
        .build()
        .unwrap()
}

#[test]
fn a_polyline_corner_between_two_joints_is_a_mid_link_contact_without_penetration() {
    // A straight antenna along x (base angle 0); a wedge-shaped wall below it whose corner
    // points up at x = 0.1 m, the middle of link 2 (links from 0.04 to 0.08, 0.08 to 0.12).
    let chain = chain(3, 0.0, 0.02);
    let wedge = Polyline::new(
        vec![
            Vector2::new(0.055, -0.05),
            Vector2::new(0.095, -0.01),
            Vector2::new(0.135, -0.05),
        ],
        SolidSide::Right,
    )
    .unwrap();
    let theta = chain.rest_theta();
    let mut sim = QuasiStatic::new(
        chain,
        vec![Wall::smooth(wedge)],
        Vector2::zeros(),
        &theta,
        ContactSettings::default(),
    )
    .unwrap();
    // Lower the antenna onto the corner: the base moves down 2 cm.
    for k in 1..=40 {
        sim.step_to(Vector2::new(0.0, -0.02 * k as f64 / 40.0))
            .unwrap();
        let check = sim.check();
        assert!(check.holds(1e-10, 1e-10, 1e-10), "step {k}: {check:?}");
    }
    let contacts = sim.contacts();
    let mid = contacts
        .iter()
        .find(|c| matches!(c.feature, Feature::Link { .. }))
        .unwrap_or_else(|| panic!("no mid-link contact: {contacts:?}"));
    assert!(mid.s > 0.0 && mid.s < 1.0);
    assert!(mid.normal_force_n > 0.0);
    // The corner is where the link touches.
    assert!(
        (mid.point_m - Vector2::new(0.095, -0.01)).norm() < 1e-9,
        "{mid:?}"
    );
}

#[test]
fn a_sweep_along_a_sinusoid_keeps_every_link_out_of_its_crests() {
    let chain = Chain::builder(8)
        .link_length_m(0.04)
        .base_angle_rad(30f64.to_radians())
        .stiffnesses_nm_per_rad(vec![0.08, 0.06, 0.04, 0.03, 0.02, 0.01, 0.006, 0.004])
        .build()
        .unwrap();
    let wall = Wall::smooth(
        Sinusoid::new(
            Vector2::new(0.0, 0.17),
            0.0,
            0.01,
            6.3,
            0.0,
            SolidSide::Left,
        )
        .unwrap(),
    );
    let theta = chain.rest_theta();
    // Start clear of the wall (it is 0.16 m above the base at its lowest; the antenna
    // reaches 0.18 m) by starting 0.03 m lower and coming up.
    let mut sim = QuasiStatic::new(
        chain,
        vec![wall],
        Vector2::new(0.0, -0.03),
        &theta,
        ContactSettings::default(),
    )
    .unwrap();
    let mut touched = 0;
    for k in 1..=300 {
        let up = (k as f64 / 100.0).min(1.0);
        sim.step_to(Vector2::new(0.0002 * k as f64, -0.03 + 0.03 * up))
            .unwrap();
        let check = sim.check();
        assert!(check.holds(1e-9, 1e-9, 1e-9), "step {k}: {check:?}");
        if !sim.contacts().is_empty() {
            touched += 1;
        }
    }
    assert!(touched > 100, "touched in {touched} steps");
}

#[test]
fn a_link_lying_flat_on_a_wall_bears_at_both_ends() {
    // Two links, the second pressed flat against a wall along x by a tip load.
    let chain = Chain::builder(2)
        .link_length_m(0.04)
        .base_angle_rad(0.0)
        .stiffnesses_nm_per_rad(vec![0.02, 0.02])
        .build()
        .unwrap();
    let wall = Wall::smooth(Line::new(Vector2::new(0.0, -0.001), 0.0, SolidSide::Right).unwrap());
    let theta = chain.rest_theta();
    let mut sim = QuasiStatic::new(
        chain,
        vec![wall],
        Vector2::zeros(),
        &theta,
        ContactSettings::default(),
    )
    .unwrap();
    sim.set_tip_force_n(Vector2::new(0.0, -0.5));
    sim.settle().unwrap();
    let check = sim.check();
    assert!(check.holds(1e-10, 1e-10, 1e-10), "{check:?}");
    let contacts = sim.contacts();
    assert!(
        contacts
            .iter()
            .any(|c| c.feature == Feature::Vertex { link: 2 } && c.normal_force_n > 0.0),
        "{contacts:?}"
    );
    assert!(
        check.penetration_m <= 1e-10,
        "penetration {}",
        check.penetration_m
    );
}

#[test]
fn a_sweep_across_the_trapezoid_keeps_every_link_out_of_it() {
    // `examples/wall_polyline.toml` run past the whole bump (two convex and two concave
    // corners, corners sliding along links and across joints), every step checked.
    let scene = antenna_tests::reproduce::load_scene("wall_polyline.toml").unwrap();
    let steps = scene.motion.steps();
    let mut sweep = sim_core::sweep::Sweep::new(scene).unwrap();
    let (mut mid_link, mut run) = (0, 0);
    while let Some(step) = sweep.next_step() {
        let step = step.unwrap();
        run += 1;
        let check = sweep.sim().check();
        assert!(
            check.holds(1e-9, 1e-9, 1e-9),
            "step {}: {check:?}",
            step.step
        );
        if step
            .contacts
            .iter()
            .any(|c| matches!(c.feature, Feature::Link { .. }))
        {
            mid_link += 1;
        }
        // Every reported contact touches: a contact that let go is gone, not kept with a
        // force of rounding size while the chain moves away.
        for c in &step.contacts {
            let gap = sweep.sim().walls()[c.wall]
                .signed_distance(&c.point_m)
                .gap_m;
            assert!(gap.abs() < 1e-8, "step {}: {c:?} is {gap} m off", step.step);
        }
    }
    assert_eq!(run, steps);
    assert!(mid_link > 100, "a corner inside a link in {mid_link} steps");
}

/// A 0.16 m antenna (3 joints of 0.02 N m/rad) at `base_deg`, at rest with its base at the
/// origin, beside a polyline wall through `vertices_m` with friction `mu`.
fn antenna_beside(
    base_deg: f64,
    vertices_m: Vec<Vector2<f64>>,
    solid: SolidSide,
    mu: f64,
) -> QuasiStatic {
    let chain = chain(3, base_deg, 0.02);
    let wall = Wall::new(
        Polyline::new(vertices_m, solid).unwrap(),
        sim_core::SurfaceMap::uniform(sim_core::Surface::Smooth { mu }).unwrap(),
    );
    let theta = chain.rest_theta();
    QuasiStatic::new(
        chain,
        vec![wall],
        Vector2::zeros(),
        &theta,
        ContactSettings::default(),
    )
    .unwrap()
}

/// Moves the base to `base_m` and checks the step's certificate; `what` names the case.
fn step_checked(sim: &mut QuasiStatic, base_m: Vector2<f64>, what: &str) {
    sim.step_to(base_m)
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    let check = sim.check();
    assert!(check.holds(1e-9, 1e-9, 1e-9), "{what}: {check:?}");
}

#[test]
fn a_tip_pushed_onto_a_convex_corner_slips_off_it_unless_friction_holds_it() {
    // A 0.16 m antenna along x, tilted up 4 deg, pushed tip first onto the apex of a blunt
    // wedge (half-angle 70 deg, pointing back at the base): a point meeting a point, where
    // the distance's normal turns without bound. Without friction no load can hold a point
    // on a convex corner (any force in the apex's cone slides it onto one edge or the
    // other): the tip slips off onto an edge. With mu = 0.5 (friction angle 26.6 deg, more
    // than the 20 deg between the push and an edge's normal) it sticks where it touched.
    let half = 70f64.to_radians();
    let tilt = 4f64.to_radians();
    for (mu, stays) in [(0.0, false), (0.5, true)] {
        // 2 mm straight ahead of the tip at rest.
        let apex = 0.16 * Vector2::new(tilt.cos(), tilt.sin()) + Vector2::new(0.002, 0.0);
        let wedge = vec![
            apex + Vector2::new(half.cos(), half.sin()) * 0.05,
            apex,
            apex + Vector2::new(half.cos(), -half.sin()) * 0.05,
        ];
        let mut sim = antenna_beside(tilt.to_degrees(), wedge, SolidSide::Left, mu);
        for k in 1..=40 {
            let base = Vector2::new(0.006 * k as f64 / 40.0, 0.0);
            step_checked(&mut sim, base, &format!("mu {mu}, step {k}"));
        }
        let contacts = sim.contacts();
        let tip = contacts
            .iter()
            .find(|c| c.feature == Feature::Vertex { link: 3 } && c.normal_force_n > 0.0)
            .unwrap_or_else(|| panic!("mu {mu}: the tip is not loaded: {contacts:?}"));
        let from_apex_m = (tip.point_m - apex).norm();
        if stays {
            // Where it first touched, within a step's travel of the apex, and stuck.
            assert!(from_apex_m < 1e-4, "mu {mu}: {tip:?}");
            assert_eq!(tip.slip, sim_core::contact::Slip::Stuck, "mu {mu}: {tip:?}");
        } else {
            assert!(from_apex_m > 1e-3, "mu {mu}: {tip:?}");
        }
    }
}

#[test]
fn a_tip_sliding_over_a_convex_corner_passes_it_certified() {
    // A 0.16 m antenna angled 12 deg down onto a flat wall that bends down by `drop_deg` at
    // x = 0.17 m; the base moves down and along x so that the tip, pressed on the wall and
    // sliding, passes over the corner (where the distance to the wall turns its normal
    // without bound) and goes on, on the far edge or with a link on the corner. Every step
    // certified.
    for (mu, drop_deg) in [(0.0, 10.0), (0.0, 35.0), (0.3, 20.0)] {
        let mut over = false;
        // 1.7 mm below the tip at rest (at y = -0.0333 m).
        let corner = Vector2::new(0.17, -0.035);
        let down = -f64::to_radians(drop_deg);
        let wall = vec![
            Vector2::new(-0.2, corner.y),
            corner,
            corner + Vector2::new(down.cos(), down.sin()) * 0.2,
        ];
        let mut sim = antenna_beside(-12.0, wall, SolidSide::Right, mu);
        for k in 1..=120 {
            // Along x, and down 4 mm over the first 20 steps to press the tip on.
            let base = Vector2::new(0.04 * k as f64 / 120.0, -0.004 * (k.min(20) as f64) / 20.0);
            step_checked(
                &mut sim,
                base,
                &format!("mu {mu}, drop {drop_deg}: step {k}"),
            );
            // Bearing on the corner or beyond it.
            over |= sim
                .contacts()
                .iter()
                .any(|c| c.normal_force_n > 0.0 && c.point_m.x >= corner.x - 1e-9);
        }
        assert!(
            over,
            "mu {mu}, drop {drop_deg}: nothing bore on the corner or past it"
        );
    }
}
