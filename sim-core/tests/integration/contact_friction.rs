//! Coulomb friction in the quasi-static contact solver (docs/model.md 6): a stuck contact does not
//! creep, a sliding one slides at `|T| = mu N` against its motion, the forces agree with an
//! independent statics of the chain, and every step passes the independent check.
#![allow(clippy::unwrap_used)]

use nalgebra::{Matrix2, Vector2};
use sim_core::contact::{ContactSettings, Feature, QuasiStatic, Slip};
use sim_core::{Chain, Line, SolidSide, Surface, SurfaceMap, Wall};

fn wall(y_m: f64, mu: f64) -> Wall {
    Wall::new(
        Line::new(Vector2::new(0.0, y_m), 0.0, SolidSide::Left).unwrap(),
        SurfaceMap::uniform(Surface::Smooth { mu }).unwrap(),
    )
}

/// A 4-joint antenna at 60 deg pressed up against a wall along x by moving its base up.
fn pressed(mu: f64) -> QuasiStatic {
    let chain = Chain::builder(4)
        .link_length_m(0.04)
        .base_angle_rad(60f64.to_radians())
        .stiffnesses_nm_per_rad(vec![0.04, 0.03, 0.02, 0.01])
        .build()
        .unwrap();
    let theta = chain.rest_theta();
    // The straight antenna's tip is at y = 0.2 sin 60 = 0.173 m; the wall at 0.17 m is
    // reached after the base has come up 0.01 m from -0.013 m.
    let mut sim = QuasiStatic::new(
        chain,
        vec![wall(0.17, mu)],
        Vector2::new(0.0, -0.013),
        &theta,
        ContactSettings::default(),
    )
    .unwrap();
    for k in 1..=40 {
        sim.step_to(Vector2::new(0.0, -0.013 + 0.013 * k as f64 / 40.0))
            .unwrap();
    }
    sim
}

fn tip_contact(sim: &QuasiStatic) -> sim_core::contact::Contact {
    let n = sim.chain().n();
    *sim.contacts()
        .iter()
        .find(|c| c.feature == Feature::Vertex { link: n })
        .expect("the tip touches")
}

#[test]
fn a_stuck_contact_does_not_creep_then_slides_at_the_friction_limit() {
    let mut sim = pressed(0.6);
    let start = tip_contact(&sim);
    assert!(start.normal_force_n > 0.0);
    // Pressing made the tip slide forward (+x) as the antenna bent; moving the base back
    // (-x) in small steps reverses the friction: the tip sticks while |T| < mu N, to rounding.
    let mut x = 0.0;
    let mut stuck_steps = 0;
    loop {
        x -= 1e-6;
        let report = sim.step_to(Vector2::new(x, 0.0)).unwrap();
        assert!(sim.check().holds(1e-10, 1e-10, 1e-10), "{:?}", sim.check());
        let c = tip_contact(&sim);
        if c.slip != Slip::Stuck {
            // The first slip: at the limit, opposite to its motion.
            assert!(
                (c.shear_force_n.abs() - 0.6 * c.normal_force_n).abs() <= 1e-9 * c.normal_force_n,
                "{c:?}"
            );
            assert!(c.shear_force_n * c.slip_m < 0.0, "{c:?}");
            break;
        }
        stuck_steps += 1;
        assert!(c.shear_force_n.abs() < 0.6 * c.normal_force_n + 1e-12);
        assert!(
            (c.point_m - start.point_m).norm() < 1e-12,
            "crept {} m after {stuck_steps} stuck steps ({report:?})",
            (c.point_m - start.point_m).norm()
        );
        assert!(stuck_steps < 5000, "never slipped");
    }
    assert!(stuck_steps > 10, "slipped after {stuck_steps} steps");
}

#[test]
fn frictionless_contacts_have_no_shear_and_slide_at_once() {
    let mut sim = pressed(0.0);
    for k in 1..=20 {
        sim.step_to(Vector2::new(1e-4 * k as f64, 0.0)).unwrap();
        let c = tip_contact(&sim);
        assert_eq!(c.shear_force_n, 0.0);
        assert!(c.slip_m.abs() > 0.0);
        assert!(sim.check().holds(1e-10, 1e-10, 1e-10));
    }
}

#[test]
fn a_two_joint_chain_stuck_at_its_tip_matches_its_statics() {
    // Two flexible joints, tip on the wall: the wall's force on the tip solves
    // J^T F = k (theta - rest) (two equations, two unknowns), computed here by hand.
    let chain = Chain::builder(2)
        .link_length_m(0.05)
        .base_angle_rad(70f64.to_radians())
        .stiffnesses_nm_per_rad(vec![0.02, 0.01])
        .build()
        .unwrap();
    let theta = chain.rest_theta();
    let mut sim = QuasiStatic::new(
        chain.clone(),
        vec![wall(0.13, 0.8)],
        Vector2::new(0.0, -0.02),
        &theta,
        ContactSettings::default(),
    )
    .unwrap();
    for k in 1..=25 {
        sim.step_to(Vector2::new(0.0, -0.02 + 0.025 * k as f64 / 25.0))
            .unwrap();
    }
    sim.step_to(Vector2::new(0.002, 0.005)).unwrap();
    let c = tip_contact(&sim);
    let th = sim.theta_rad();
    let l = 0.05;
    let phi1 = th[0] + th[1];
    let phi2 = phi1 + th[2];
    let p0 = sim.base_m() + Vector2::new(th[0].cos(), th[0].sin()) * l;
    let p1 = p0 + Vector2::new(phi1.cos(), phi1.sin()) * l;
    let tip = p1 + Vector2::new(phi2.cos(), phi2.sin()) * l;
    // Rows: the torque of F about joint 1 (at p0) and joint 2 (at p1).
    let arm = |a: Vector2<f64>| Vector2::new(-a.y, a.x);
    let jt = Matrix2::from_rows(&[arm(tip - p0).transpose(), arm(tip - p1).transpose()]);
    let k = chain.stiffness_nm_per_rad();
    let tau = Vector2::new(k[1] * th[1], k[2] * th[2]);
    let f = jt.try_inverse().unwrap() * tau;
    let reported = c.force_n();
    assert!(
        (f - reported).norm() <= 1e-9 * f.norm(),
        "statics {f:?}, solver {reported:?}"
    );
    assert!((tip - c.point_m).norm() < 1e-12);
}

#[test]
fn settings_replaced_between_steps_are_checked_and_then_used() {
    let mut sim = pressed(0.3);
    let bad = ContactSettings {
        tolerance_m: -1.0,
        ..ContactSettings::default()
    };
    let refused = sim.set_settings(bad).unwrap_err();
    assert!(refused.to_string().contains("tolerance_m"), "{refused}");
    assert_eq!(*sim.settings(), ContactSettings::default());
    // A joint may change by at most 2 mrad a step: the same step is taken in more substeps.
    let fine = ContactSettings {
        jump_rad: 2e-3,
        ..ContactSettings::default()
    };
    let step_m = Vector2::new(0.0, 0.001);
    let mut sim_default = pressed(0.3);
    let whole = sim_default.step_to(step_m).unwrap();
    sim.set_settings(fine).unwrap();
    assert_eq!(*sim.settings(), fine);
    let refined = sim.step_to(step_m).unwrap();
    assert!(
        refined.substeps > whole.substeps,
        "{} substeps with jump_rad = 2e-3, {} with the default",
        refined.substeps,
        whole.substeps
    );
}
