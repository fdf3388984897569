//! Non-penetration of every link, not only the joints (model.md 6): a polyline corner poking
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
