//! The broad phase (issue #14, item 4): a wall the antenna never comes near costs a bound per
//! link and step, not a contact solve, and gives the sweep of a scene without it; a wall it
//! does come near is not skipped.
#![allow(clippy::unwrap_used)]

use nalgebra::Vector2;
use sim_core::design::profile::{SEED_K_MAX_N_M_PER_RAD, SEED_K_MIN_N_M_PER_RAD, StiffnessProfile};
use sim_core::sweep::{Motion, Placement, Sweep, SweepScene};
use sim_core::{Chain, JointLimit, Line, Sinusoid, SolidSide, Wall, WallShape};

/// The thesis's 4.2.1 antenna: 9 links of 40 mm, fast-exponential.
fn antenna() -> Chain {
    let lengths = vec![0.04; 9];
    let k = StiffnessProfile::FastExponential
        .stiffness_n_m_per_rad(&lengths, SEED_K_MIN_N_M_PER_RAD, SEED_K_MAX_N_M_PER_RAD)
        .unwrap();
    Chain::builder(8)
        .link_length_m(0.04)
        .base_angle_rad(30f64.to_radians())
        .stiffnesses_nm_per_rad(k)
        .joint_limit(JointLimit::new((-90f64).to_radians(), 90f64.to_radians()))
        .build()
        .unwrap()
}

/// The postures and Newton iterations of a sweep from rest along `walls` for `duration_s`.
fn sweep(walls: Vec<Wall>, duration_s: f64) -> Vec<(Vec<f64>, usize, usize)> {
    let scene = SweepScene {
        motion: Motion {
            duration_s,
            ..Motion::default()
        },
        placement: Placement::Rest,
        ..SweepScene::new(antenna(), walls)
    };
    let mut sweep = Sweep::new(scene).unwrap();
    let mut out = Vec::new();
    while let Some(step) = sweep.next_step() {
        let step = step.unwrap();
        out.push((step.theta_rad, step.report.iterations, step.contacts.len()));
    }
    out
}

#[test]
fn a_wall_never_reached_is_the_sweep_without_it_at_no_newton_iteration() {
    let far_line = Wall::smooth(
        Line::new(
            Vector2::new(0.0, 1.2),
            (-8f64).to_radians(),
            SolidSide::Left,
        )
        .unwrap(),
    );
    let far_sinusoid = Wall::smooth(WallShape::from(
        Sinusoid::new(
            Vector2::new(0.0, 1.2),
            0.0,
            0.01,
            14.2,
            0.0,
            SolidSide::Left,
        )
        .unwrap(),
    ));
    let free = sweep(Vec::new(), 5.0);
    for wall in [far_line, far_sinusoid] {
        let with_wall = sweep(vec![wall], 5.0);
        assert_eq!(with_wall.len(), free.len());
        for (a, b) in with_wall.iter().zip(&free) {
            assert_eq!(a.0, b.0, "the posture of the sweep without the wall");
            assert_eq!((a.1, a.2), (0, 0), "no Newton iteration, no contact");
        }
    }
}

#[test]
fn a_wall_the_antenna_comes_near_is_solved_against() {
    // The 4.2.1 line 0.2 m out closing in at 8 deg: the resting antenna's tip (0.36 m at 30
    // deg, about 0.18 m out) meets it within a few seconds of travel.
    let wall = Wall::smooth(
        Line::new(
            Vector2::new(0.0, 0.25),
            (-8f64).to_radians(),
            SolidSide::Left,
        )
        .unwrap(),
    );
    let steps = sweep(vec![wall], 30.0);
    let first_contact = steps.iter().position(|s| s.2 > 0);
    assert!(first_contact.is_some(), "the antenna reaches the wall");
    assert!(steps.iter().any(|s| s.1 > 0), "and is solved against it");
}
