//! Wall-following metrics (docs/model.md 8) on hand-built postures: point of bend with its
//! tie rule, point of contact, preview distance (ahead, behind, reversed motion), flip
//! detection against the local wall tangent, and the correlations (undefined for a constant
//! index).
#![allow(clippy::unwrap_used)]

use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::Vector2;
use sim_core::sensing::metrics::{
    angle_to_wall_rad, flip_state, point_of_bend, point_of_contact, preview_distance_m,
};
use sim_core::{
    Chain, ChainContact, Frame, Line, Polyline, SolidSide, Wall, frame_poses, pearson_correlation,
    spearman_correlation,
};

fn v(x: f64, y: f64) -> Vector2<f64> {
    Vector2::new(x, y)
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn point_of_bend_takes_the_largest_joint_angle_ties_proximal() {
    // theta_0 (the base angle, 0.5 rad) is never the point of bend.
    assert_eq!(point_of_bend(&[0.5, 0.1, -0.3, 0.3, 0.2]), Some(2));
    assert_eq!(point_of_bend(&[0.5, 0.1, 0.2, -0.4]), Some(3));
    assert_eq!(point_of_bend(&[0.5, 0.0, 0.0, 0.0]), Some(1));
    assert_eq!(point_of_bend(&[0.5, f64::NAN, 0.1]), Some(2));
    assert_eq!(point_of_bend(&[0.5]), None);
    assert_eq!(point_of_bend(&[]), None);
}

/// A 9-link antenna (eight 40 mm flagellar links on a 40 mm base link) bent back against a
/// wall: base at 30 degrees, joint 4 turns it parallel to the wall, joint 7 folds it back.
#[test]
fn contact_and_preview_on_a_bent_posture() {
    let chain = Chain::builder(8)
        .link_length_m(0.04)
        .base_angle_rad(30f64.to_radians())
        .stiffness_nm_per_rad(0.01)
        .build()
        .unwrap();
    let mut theta = vec![0.0; 9];
    theta[0] = 30f64.to_radians();
    theta[4] = -30f64.to_radians(); // links 4.. run along +x
    theta[7] = -150f64.to_radians(); // links 7.. run back along -x... turned down-back
    let poses = frame_poses(&chain, &theta, Frame::GROUND).unwrap();
    let p = |frame: isize| poses.position_m(Frame::new(frame)).unwrap();
    // Joints 4 and 5 sit at p_3 and p_4; links 4..6 run at y = 4 * 0.04 * sin 30 = 0.08.
    assert!(close(p(3).y, 0.08, 1e-15) && close(p(6).y, 0.08, 1e-15));
    // A wall along y = 0.08 (solid above): links 4, 5, 6 lie on it.
    let wall = Wall::smooth(Line::new(v(0.0, 0.08), 0.0, SolidSide::Left).unwrap());
    let contacts: Vec<ChainContact> = (0..=8)
        .filter_map(|link| {
            let (a, b) = (p(link as isize - 1), p(link as isize));
            let c = wall.segment_contact(&a, &b);
            (c.wall.gap_m.abs() < 1e-12).then_some(ChainContact {
                link,
                s: c.s,
                point_m: c.point_m,
            })
        })
        .collect();
    // Link 3 ends on the wall (s = 1), links 4..6 touch along their length (ties to s = 0),
    // link 7 starts on it and leaves.
    let touching: Vec<usize> = contacts.iter().map(|c| c.link).collect();
    assert_eq!(touching, vec![3, 4, 5, 6, 7]);
    let poc = point_of_contact(&contacts).unwrap();
    assert_eq!((poc.link, poc.joint), (3, 4)); // the end of link 3 is joint 4
    assert!(close(poc.chain_coordinate, 4.0, 1e-12));
    // Preview: the farthest-forward contact is joint 7 = p_6, at x = 4 * 0.04 cos 30 + 0.12.
    let x_joint_7 = 0.16 * 30f64.to_radians().cos() + 0.12;
    let base = v(0.0, 0.0);
    let preview = preview_distance_m(&contacts, &base, 0.0).unwrap();
    assert!(close(preview, x_joint_7, 1e-12), "{preview}");
    // Behind the base: every contact is behind a base moved 0.5 m ahead: negative.
    let preview = preview_distance_m(&contacts, &v(0.5, 0.0), 0.0).unwrap();
    assert!(close(preview, x_joint_7 - 0.5, 1e-12));
    // Moving the other way, the most forward contact is the rearmost one (joint 4).
    let preview = preview_distance_m(&contacts, &base, PI).unwrap();
    assert!(close(preview, -p(3).x, 1e-12), "{preview}");
    assert_eq!(preview_distance_m(&[], &base, 0.0), None);
    assert_eq!(point_of_contact(&[]), None);
}

#[test]
fn point_of_contact_ranks_by_chain_coordinate() {
    let at = |link: usize, s: f64| ChainContact {
        link,
        s,
        point_m: v(0.0, 0.0),
    };
    let poc = point_of_contact(&[at(6, 0.2), at(5, 0.9), at(8, 1.0)]).unwrap();
    assert_eq!((poc.link, poc.joint), (5, 6));
    assert!(close(poc.chain_coordinate, 5.9, 1e-15));
    // The tip of an 8-link chain is point n + 1 = 9.
    assert_eq!(point_of_contact(&[at(8, 1.0)]).unwrap().joint, 9);
    assert_eq!(point_of_contact(&[at(4, 0.3)]).unwrap().joint, 4);
}

#[test]
fn flip_is_the_distal_segment_past_ninety_degrees_to_the_wall() {
    let wall = Wall::smooth(Line::new(v(0.0, 0.1), 0.0, SolidSide::Left).unwrap());
    let tip = v(0.2, 0.1);
    let from_angle = |deg: f64| tip - v(deg.to_radians().cos(), deg.to_radians().sin()) * 0.04;
    // Projecting forward at 60 degrees to the wall: not flipped.
    let state = flip_state(&wall, &from_angle(60.0), &tip, 0.0).unwrap();
    assert!(close(state.angle_to_wall_rad, 60f64.to_radians(), 1e-12) && !state.flipped);
    // Trailing at 120 degrees: flipped.
    let state = flip_state(&wall, &from_angle(120.0), &tip, 0.0).unwrap();
    assert!(close(state.angle_to_wall_rad, 120f64.to_radians(), 1e-12) && state.flipped);
    // Exactly perpendicular is not yet a flip (strictly beyond 90 degrees).
    let state = flip_state(&wall, &from_angle(90.0), &tip, 0.0).unwrap();
    assert!(close(state.angle_to_wall_rad, FRAC_PI_2, 1e-12));
    // The wall's own tangent orientation does not matter; the motion direction does.
    let reversed = Wall::smooth(Line::new(v(0.0, 0.1), PI, SolidSide::Right).unwrap());
    let state = flip_state(&reversed, &from_angle(120.0), &tip, 0.0).unwrap();
    assert!(state.flipped);
    let state = flip_state(&wall, &from_angle(120.0), &tip, PI).unwrap();
    assert!(close(state.angle_to_wall_rad, 60f64.to_radians(), 1e-12) && !state.flipped);
    assert_eq!(angle_to_wall_rad(&v(0.0, 0.0), &v(1.0, 0.0), 0.0), None);
}

#[test]
fn flip_uses_the_local_wall_tangent() {
    // The tip rests on a 45 degree up-slope (a ramp in a wall at y = 0.1, solid above).
    let wall = Wall::smooth(
        Polyline::new(
            vec![v(0.0, 0.05), v(0.1, 0.05), v(0.2, 0.15), v(0.3, 0.15)],
            SolidSide::Left,
        )
        .unwrap(),
    );
    let tip = v(0.15, 0.10);
    // Distal segment at 120 degrees from x: against the baseline a flip, against the ramp
    // (tangent at 45 degrees) only 75 degrees.
    let start = tip - v(120f64.to_radians().cos(), 120f64.to_radians().sin()) * 0.04;
    let state = flip_state(&wall, &start, &tip, 0.0).unwrap();
    assert!(
        close(state.angle_to_wall_rad, 75f64.to_radians(), 1e-12),
        "{state:?}"
    );
    assert!(!state.flipped);
    assert!(close(state.contact.wall.gap_m, 0.0, 1e-12) && close(state.contact.s, 1.0, 1e-12));
}

#[test]
fn correlations_and_the_undefined_case() {
    let x = [1.0, 2.0, 3.0, 4.0];
    assert!(close(
        pearson_correlation(&x, &[2.0, 4.0, 6.0, 8.0]).unwrap(),
        1.0,
        1e-15
    ));
    assert!(close(
        pearson_correlation(&x, &[8.0, 6.0, 4.0, 2.0]).unwrap(),
        -1.0,
        1e-15
    ));
    assert!(close(
        pearson_correlation(&[1.0, 2.0, 3.0], &[1.0, 3.0, 2.0]).unwrap(),
        0.5,
        1e-15
    ));
    // A point of bend that never moves: the correlation is undefined, not 0 or NaN.
    let bend_joints = [3.0, 3.0, 3.0, 3.0];
    let wall_distances = [0.2, 0.15, 0.1, 0.09];
    assert_eq!(pearson_correlation(&bend_joints, &wall_distances), None);
    assert_eq!(spearman_correlation(&bend_joints, &wall_distances), None);
    assert_eq!(pearson_correlation(&x, &[1.0, 2.0]), None);
    assert_eq!(pearson_correlation(&[1.0], &[2.0]), None);
    assert_eq!(pearson_correlation(&[1.0, f64::NAN], &[2.0, 3.0]), None);
    // Spearman with a tie: ranks (1, 2.5, 2.5, 4) against (1, 2, 3, 4): 3 / sqrt 10.
    let rho = spearman_correlation(&[1.0, 2.0, 2.0, 3.0], &x).unwrap();
    assert!(close(rho, 3.0 / 10f64.sqrt(), 1e-15), "{rho}");
    // Monotone but not linear: Spearman 1, Pearson below 1.
    let y = [1.0, 8.0, 27.0, 64.0];
    assert!(close(spearman_correlation(&x, &y).unwrap(), 1.0, 1e-15));
    assert!(pearson_correlation(&x, &y).unwrap() < 0.99);
}
