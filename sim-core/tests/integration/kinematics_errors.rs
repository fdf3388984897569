//! Invalid input is a typed error naming the field (or argument) and the index, never a
//! panic: chain descriptions (non-positive lengths, reversed limits, negative stiffness, NaN,
//! wrong counts, bad hairs) and kinematics arguments (frames outside -1..=n, vectors of the
//! wrong length, buffers of the wrong shape, angles outside the limits, links without hairs).
#![allow(clippy::unwrap_used)]

use nalgebra::Matrix3xX;
use sim_core::kinematics::active_frames::active_frames_vector;
use sim_core::kinematics::error::ChainField;
use sim_core::kinematics::hair::hair_pose;
use sim_core::kinematics::jacobian::{JacobianKind, hybrid_jacobian, jacobian_into, tip_jacobian};
use sim_core::kinematics::joint_limits::q_from_theta;
use sim_core::kinematics::positions::{FramePoses, frame_pose, frame_poses_into};
use sim_core::{Chain, ChainError, Frame, Hair, JointLimit, KinematicsError};

#[test]
fn non_positive_length_names_the_link() {
    let e = Chain::builder(3)
        .link_lengths_m(vec![0.04, 0.04, 0.0, 0.04])
        .build()
        .unwrap_err();
    assert_eq!(
        e,
        ChainError::NonPositiveLength {
            index: 2,
            value_m: 0.0
        }
    );
    let e = Chain::builder(1).link_length_m(-1.0).build().unwrap_err();
    assert_eq!(
        e,
        ChainError::NonPositiveLength {
            index: 0,
            value_m: -1.0
        }
    );
}

#[test]
fn nan_names_the_field_and_index() {
    let e = Chain::builder(2)
        .link_lengths_m(vec![0.04, f64::NAN, 0.04])
        .build()
        .unwrap_err();
    assert!(matches!(
        e,
        ChainError::NotFinite {
            field: ChainField::LinkLength,
            index: 1,
            ..
        }
    ));
    let e = Chain::builder(2)
        .base_angle_rad(f64::INFINITY)
        .build()
        .unwrap_err();
    assert!(matches!(
        e,
        ChainError::NotFinite {
            field: ChainField::BaseAngle,
            ..
        }
    ));
    let e = Chain::builder(2)
        .joint_limits(vec![
            JointLimit::new(-1.0, 1.0),
            JointLimit::new(f64::NAN, 1.0),
        ])
        .build()
        .unwrap_err();
    assert!(matches!(
        e,
        ChainError::NotFinite {
            field: ChainField::JointLimitCw,
            index: 2,
            ..
        }
    ));
    let e = Chain::builder(2)
        .stiffnesses_nm_per_rad(vec![0.1, f64::NAN])
        .build()
        .unwrap_err();
    assert!(matches!(
        e,
        ChainError::NotFinite {
            field: ChainField::Stiffness,
            index: 2,
            ..
        }
    ));
    let e = Chain::builder(2)
        .rest_angles_rad(vec![f64::NAN, 0.0])
        .build()
        .unwrap_err();
    assert!(matches!(
        e,
        ChainError::NotFinite {
            field: ChainField::RestAngle,
            index: 1,
            ..
        }
    ));
    let e = Chain::builder(2)
        .hair(
            2,
            Hair {
                length_m: f64::NAN,
                ..Hair::seed(0.04)
            },
        )
        .build()
        .unwrap_err();
    assert!(matches!(
        e,
        ChainError::NotFinite {
            field: ChainField::HairLength,
            index: 2,
            ..
        }
    ));
}

#[test]
fn reversed_limits_name_the_joint() {
    let e = Chain::builder(3)
        .joint_limits(vec![
            JointLimit::new(-1.0, 1.0),
            JointLimit::new(-1.0, 1.0),
            JointLimit::new(0.5, 0.4),
        ])
        .build()
        .unwrap_err();
    assert_eq!(
        e,
        ChainError::LimitsReversed {
            index: 3,
            cw_rad: 0.5,
            ccw_rad: 0.4
        }
    );
    assert!(e.to_string().contains("joint_limits[3]"));
}

#[test]
fn negative_stiffness_names_the_joint() {
    let e = Chain::builder(2)
        .stiffnesses_nm_per_rad(vec![0.1, -0.2])
        .build()
        .unwrap_err();
    assert_eq!(
        e,
        ChainError::NegativeStiffness {
            index: 2,
            value_nm_per_rad: -0.2
        }
    );
    assert!(e.to_string().contains("stiffness_nm_per_rad[2]"));
}

#[test]
fn wrong_counts_are_errors() {
    let e = Chain::builder(3)
        .link_lengths_m(vec![0.04; 3])
        .build()
        .unwrap_err();
    assert_eq!(
        e,
        ChainError::WrongCount {
            field: ChainField::LinkLength,
            expected: 4,
            actual: 3
        }
    );
    let e = Chain::builder(3)
        .stiffnesses_nm_per_rad(vec![0.1; 4])
        .build()
        .unwrap_err();
    assert_eq!(
        e,
        ChainError::WrongCount {
            field: ChainField::Stiffness,
            expected: 3,
            actual: 4
        }
    );
}

#[test]
fn bad_hairs_are_errors() {
    let e = Chain::builder(2)
        .hair(3, Hair::seed(0.04))
        .build()
        .unwrap_err();
    assert!(matches!(
        e,
        ChainError::IndexOutOfRange { index: 3, n: 2, .. }
    ));
    let e = Chain::builder(2)
        .hair(
            1,
            Hair {
                length_m: 0.0,
                ..Hair::seed(0.04)
            },
        )
        .build()
        .unwrap_err();
    assert!(matches!(
        e,
        ChainError::HairOutOfRange {
            field: ChainField::HairLength,
            index: 1,
            ..
        }
    ));
    let e = Chain::builder(2)
        .hair(
            1,
            Hair {
                pivot_from_distal_end_m: 0.05,
                ..Hair::seed(0.04)
            },
        )
        .build()
        .unwrap_err();
    assert!(matches!(
        e,
        ChainError::HairOutOfRange {
            field: ChainField::HairPivot,
            index: 1,
            ..
        }
    ));
    let e = Chain::builder(2)
        .hair(
            1,
            Hair {
                open_angle_rad: 0.0,
                ..Hair::seed(0.04)
            },
        )
        .build()
        .unwrap_err();
    assert!(matches!(
        e,
        ChainError::HairOutOfRange {
            field: ChainField::HairOpenAngle,
            ..
        }
    ));
}

#[test]
fn frames_out_of_range_are_errors() {
    let chain = Chain::builder(3).build().unwrap();
    let theta = [0.0; 4];
    let e = frame_pose(&chain, &theta, Frame::new(-2), Frame::GROUND).unwrap_err();
    assert_eq!(
        e,
        KinematicsError::FrameOutOfRange {
            argument: "s",
            index: -2,
            n: 3
        }
    );
    let e = hybrid_jacobian(&chain, &theta, Frame::GROUND, Frame::new(4)).unwrap_err();
    assert_eq!(
        e,
        KinematicsError::FrameOutOfRange {
            argument: "b",
            index: 4,
            n: 3
        }
    );
    let e = active_frames_vector(3, Frame::new(isize::MAX), Frame::GROUND).unwrap_err();
    assert!(matches!(
        e,
        KinematicsError::FrameOutOfRange { argument: "s", .. }
    ));
    let e = frame_pose(&chain, &theta, Frame::link(usize::MAX), Frame::GROUND).unwrap_err();
    assert!(matches!(e, KinematicsError::FrameOutOfRange { .. }));
}

#[test]
fn wrong_lengths_and_shapes_are_errors() {
    let chain = Chain::builder(3).build().unwrap();
    let e = tip_jacobian(&chain, &[0.0; 3]).unwrap_err();
    assert_eq!(
        e,
        KinematicsError::WrongLength {
            argument: "theta",
            expected: 4,
            actual: 3
        }
    );
    let mut small = Matrix3xX::zeros(3);
    let e = jacobian_into(
        &chain,
        &[0.0; 4],
        Frame::GROUND,
        Frame::new(2),
        JacobianKind::Body,
        &mut small,
    )
    .unwrap_err();
    assert!(matches!(
        e,
        KinematicsError::WrongShape {
            expected_cols: 4,
            cols: 3,
            ..
        }
    ));
    let mut poses = FramePoses::zeros(2);
    let e = frame_poses_into(&chain, &[0.0; 4], Frame::GROUND, &mut poses).unwrap_err();
    assert!(matches!(e, KinematicsError::WrongShape { .. }));
}

#[test]
fn angles_outside_limits_are_errors() {
    let chain = Chain::builder(2).base_angle_rad(0.3).build().unwrap();
    let e = q_from_theta(&chain, &[0.3, 2.0, 0.0]).unwrap_err();
    assert!(matches!(e, KinematicsError::OutsideLimits { index: 1, .. }));
    let e = q_from_theta(&chain, &[0.0, 0.0, 0.0]).unwrap_err();
    assert!(
        matches!(e, KinematicsError::OutsideLimits { index: 0, .. }),
        "theta_0 must be the base angle"
    );
}

#[test]
fn hair_on_a_bare_link_is_an_error() {
    let chain = Chain::builder(2).hair(2, Hair::seed(0.04)).build().unwrap();
    let e = hair_pose(&chain, &[0.0; 3], &[0.0; 3], Frame::GROUND, 1).unwrap_err();
    assert_eq!(e, KinematicsError::NoHair { link: 1 });
    let e = hair_pose(&chain, &[0.0; 3], &[0.0; 3], Frame::GROUND, 7).unwrap_err();
    assert!(matches!(
        e,
        KinematicsError::LinkOutOfRange { index: 7, .. }
    ));
}
