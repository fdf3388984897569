//! Wall mapping (thesis 4.2.2, docs/model.md 8): contact points estimated from 12-bit joint angles
//! and touch bits. An exact posture on a line wall maps with only quantization error, which
//! stays under its first-order bound; a wall offset by a known distance gives that distance;
//! touch bits come from contacts as the switches would set them; bad input is rejected.
#![allow(clippy::unwrap_used)]

use antenna_protocol::RAD_PER_COUNT;
use nalgebra::Vector2;
use proptest::prelude::*;
use sim_core::sensing::mapping::{mapping_score, quantize_angle_rad};
use sim_core::{
    Chain, ChainContact, EstimatedContact, Frame, Line, MappingAccumulator, MappingError,
    SolidSide, TouchLayout, Wall, estimate_contacts, frame_poses, point_error_mm, sensed_theta_rad,
    switch_for_fraction, touch_bits_from_contacts,
};

fn v(x: f64, y: f64) -> Vector2<f64> {
    Vector2::new(x, y)
}

fn chain(n: usize) -> Chain {
    Chain::builder(n)
        .link_length_m(0.04)
        .base_angle_rad(30f64.to_radians())
        .stiffness_nm_per_rad(0.01)
        .build()
        .unwrap()
}

/// Estimates with every switch of links 5..=8 touched, from `theta` as given.
fn estimates(chain: &Chain, base: Vector2<f64>, theta: &[f64]) -> Vec<EstimatedContact> {
    let mut bits = vec![0u8; chain.n() + 1];
    for b in &mut bits[5..] {
        *b = 0b1111;
    }
    let mut out = Vec::new();
    estimate_contacts(
        chain,
        &base,
        theta,
        &bits,
        &TouchLayout::default(),
        &mut out,
    )
    .unwrap();
    out
}

/// Links 5..=8 of an 8-link chain at 30 degrees (with a kink at joints 2-3), turned parallel
/// to x by joint 5: they lie on the line `y = base.y + height(posture)`.
fn posture() -> Vec<f64> {
    let mut theta = vec![0.0; 9];
    theta[0] = 30f64.to_radians();
    theta[2] = 0.1;
    theta[3] = -0.1;
    theta[5] = -30f64.to_radians();
    theta
}

/// The height of joint 5 (`p_4`) above the base, and its x.
fn joint_5(chain: &Chain, theta: &[f64]) -> Vector2<f64> {
    frame_poses(chain, theta, Frame::GROUND)
        .unwrap()
        .position_m(Frame::new(4))
        .unwrap()
}

#[test]
fn exact_posture_on_a_line_wall_maps_with_only_quantization_error() {
    let chain = chain(8);
    let base = v(0.3, -0.02);
    let theta = posture();
    let height = joint_5(&chain, &theta).y;
    let wall = [Wall::smooth(
        Line::new(v(0.0, base.y + height), 0.0, SolidSide::Left).unwrap(),
    )];
    // Unquantized: every estimate is on the wall.
    let exact = estimates(&chain, base, &theta);
    assert_eq!(exact.len(), 16);
    let score = mapping_score(&wall, &exact);
    assert_eq!(score.count, 16);
    assert!(score.max_error_mm.unwrap() < 1e-9, "{score:?}");
    // Quantized as the segments report: small but not zero, and under the first-order bound
    // sum_j (q / 2) |p - p_joint_j| for each point.
    let mut sensed = vec![0.0; 9];
    sensed_theta_rad(&theta, &mut sensed).unwrap();
    assert_eq!(sensed[0], theta[0]);
    let quantized = estimates(&chain, base, &sensed);
    let score = mapping_score(&wall, &quantized);
    assert!(score.mean_error_mm.unwrap() > 1e-4, "{score:?}");
    let poses = frame_poses(&chain, &theta, Frame::GROUND).unwrap();
    for (q, e) in quantized.iter().zip(&exact) {
        let bound_m: f64 = (1..=q.link)
            .map(|j| {
                let joint = base + poses.position_m(Frame::new(j as isize - 1)).unwrap();
                0.5 * RAD_PER_COUNT * (e.point_m - joint).norm()
            })
            .sum();
        let error_mm = point_error_mm(&wall, &q.point_m).unwrap();
        assert!(
            error_mm <= bound_m * 1e3 * 1.001,
            "{error_mm} mm > {bound_m} m"
        );
        assert!((q.point_m - e.point_m).norm() <= bound_m * 1.001);
    }
}

#[test]
fn a_known_offset_gives_the_known_error() {
    let chain = chain(8);
    let base = v(0.0, 0.0);
    let theta = posture();
    let p5 = joint_5(&chain, &theta);
    // The true wall 5 mm above the links that touched it (and 5 mm inside them, below): 5 mm.
    for offset in [0.005, -0.005] {
        let wall = [Wall::smooth(
            Line::new(v(0.0, p5.y + offset), 0.0, SolidSide::Left).unwrap(),
        )];
        let score = mapping_score(&wall, &estimates(&chain, base, &theta));
        assert!(
            (score.mean_error_mm.unwrap() - 5.0).abs() < 1e-9,
            "{score:?}"
        );
        assert!((score.max_error_mm.unwrap() - 5.0).abs() < 1e-9);
    }
    // The lateral offset moves the estimate along the link's left normal (+y here).
    let wall = [Wall::smooth(
        Line::new(v(0.0, p5.y + 0.003), 0.0, SolidSide::Left).unwrap(),
    )];
    let mut bits = vec![0u8; 9];
    bits[6] = 0b0010;
    let mut out = Vec::new();
    let layout = TouchLayout {
        lateral_offset_m: 0.003,
        ..TouchLayout::default()
    };
    estimate_contacts(&chain, &base, &theta, &bits, &layout, &mut out).unwrap();
    assert_eq!((out.len(), out[0].link, out[0].switch), (1, 6, 1));
    assert!(point_error_mm(&wall, &out[0].point_m).unwrap() < 1e-9);
    // Switch 1 sits 3/8 of the way along link 6: 1.375 links along x from joint 5.
    let x = p5.x + 1.375 * 0.04;
    assert!((out[0].point_m.x - x).abs() < 1e-12);
}

#[test]
fn a_running_score_averages_over_steps() {
    let wall = [Wall::smooth(
        Line::new(v(0.0, 0.0), 0.0, SolidSide::Left).unwrap(),
    )];
    let mut acc = MappingAccumulator::default();
    assert_eq!(acc.score().mean_error_mm, None);
    let at = |y: f64| EstimatedContact {
        link: 1,
        switch: 0,
        point_m: v(0.0, y),
    };
    acc.add(&wall, &[at(0.001), at(-0.003)]);
    acc.add(&wall, &[at(0.002)]);
    let score = acc.score();
    assert_eq!(score.count, 3);
    assert!((score.mean_error_mm.unwrap() - 2.0).abs() < 1e-12);
    assert!((score.max_error_mm.unwrap() - 3.0).abs() < 1e-12);
    assert_eq!(point_error_mm(&[], &v(0.0, 0.0)), None);
}

#[test]
fn touch_bits_follow_the_switch_quarters() {
    assert_eq!(switch_for_fraction(0.0), 0);
    assert_eq!(switch_for_fraction(0.2499), 0);
    assert_eq!(switch_for_fraction(0.25), 1);
    assert_eq!(switch_for_fraction(0.74), 2);
    assert_eq!(switch_for_fraction(1.0), 3);
    assert_eq!(switch_for_fraction(7.0), 3);
    let at = |link: usize, s: f64| ChainContact {
        link,
        s,
        point_m: v(0.0, 0.0),
    };
    let mut bits = [0xFFu8; 4];
    touch_bits_from_contacts(&[at(1, 0.1), at(1, 0.9), at(3, 0.5), at(3, 0.6)], &mut bits).unwrap();
    assert_eq!(bits, [0, 0b1001, 0, 0b0100]);
    assert_eq!(
        touch_bits_from_contacts(&[at(4, 0.5)], &mut bits),
        Err(MappingError::LinkOutOfRange { link: 4, n: 3 })
    );
}

#[test]
fn quantization_is_twelve_bits_per_turn() {
    assert!((RAD_PER_COUNT * 4096.0 - std::f64::consts::TAU).abs() < 1e-15);
    assert_eq!(quantize_angle_rad(0.0), 0.0);
    assert!((quantize_angle_rad(0.6 * RAD_PER_COUNT) - RAD_PER_COUNT).abs() < 1e-18);
    assert!((quantize_angle_rad(-0.4 * RAD_PER_COUNT)).abs() < 1e-18);
    assert!((quantize_angle_rad(-1.5 * RAD_PER_COUNT) + 2.0 * RAD_PER_COUNT).abs() < 1e-18);
}

#[test]
fn bad_input_is_rejected() {
    let chain = chain(3);
    let mut out = Vec::new();
    let theta = [0.5, 0.0, 0.0, 0.0];
    let layout = TouchLayout::default();
    let base = v(0.0, 0.0);
    assert_eq!(
        estimate_contacts(&chain, &base, &theta[..3], &[0; 4], &layout, &mut out),
        Err(MappingError::WrongLength {
            argument: "sensed_theta_rad",
            expected: 4,
            actual: 3
        })
    );
    assert_eq!(
        estimate_contacts(&chain, &base, &theta, &[0, 0x10, 0, 0], &layout, &mut out),
        Err(MappingError::TouchOutOfRange {
            link: 1,
            bits: 0x10
        })
    );
    assert_eq!(
        estimate_contacts(
            &chain,
            &base,
            &[0.5, f64::NAN, 0.0, 0.0],
            &[0; 4],
            &layout,
            &mut out
        ),
        Err(MappingError::NotFinite {
            argument: "sensed_theta_rad",
            index: 1
        })
    );
    assert_eq!(
        sensed_theta_rad(&theta, &mut [0.0; 3]),
        Err(MappingError::WrongLength {
            argument: "out",
            expected: 4,
            actual: 3
        })
    );
    assert!(out.is_empty());
}

proptest! {
    /// For any posture, the quantized estimate of every switch point stays within
    /// sum_j (q / 2) |p - p_joint_j| of the exact one (first order; 0.1 % slack).
    #[test]
    fn quantization_error_is_bounded(
        joints in prop::collection::vec(-1.5..1.5f64, 8),
        bits in prop::collection::vec(0u8..16, 9),
    ) {
        let chain = chain(8);
        let mut theta = vec![30f64.to_radians()];
        theta.extend(joints);
        let mut sensed = vec![0.0; 9];
        sensed_theta_rad(&theta, &mut sensed).unwrap();
        let layout = TouchLayout::default();
        let base = v(0.1, 0.2);
        let (mut exact, mut quantized) = (Vec::new(), Vec::new());
        estimate_contacts(&chain, &base, &theta, &bits, &layout, &mut exact).unwrap();
        estimate_contacts(&chain, &base, &sensed, &bits, &layout, &mut quantized).unwrap();
        prop_assert_eq!(exact.len(), bits.iter().map(|b| b.count_ones() as usize).sum::<usize>());
        let poses = frame_poses(&chain, &theta, Frame::GROUND).unwrap();
        for (q, e) in quantized.iter().zip(&exact) {
            prop_assert_eq!((q.link, q.switch), (e.link, e.switch));
            let bound_m: f64 = (1..=e.link)
                .map(|j| {
                    let joint = base + poses.position_m(Frame::new(j as isize - 1)).unwrap();
                    0.5 * RAD_PER_COUNT * (e.point_m - joint).norm()
                })
                .sum();
            prop_assert!((q.point_m - e.point_m).norm() <= bound_m * 1.001 + 1e-15);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// With `hair_tips`, the switch under a hair's pivot places its point at the hair's tip
    /// open against its stop (sim-core's own hair kinematics, `hair_poses`); every other
    /// switch, and every switch without `hair_tips`, stays on the link.
    #[test]
    fn hair_switches_estimate_the_open_hair_tip(
        counts in prop::collection::vec(-300i32..300, 8),
        link in 1usize..=8,
        right in any::<bool>(),
        proximal in any::<bool>(),
        pivot_fraction in 0.05..0.95f64,
    ) {
        use sim_core::{Hair, HairDirection, HairSide, hair_poses};
        let hair = Hair {
            side: if right { HairSide::Right } else { HairSide::Left },
            direction: if proximal { HairDirection::Proximal } else { HairDirection::Distal },
            pivot_from_distal_end_m: pivot_fraction * 0.04,
            ..Hair::seed(0.04)
        };
        let chain = Chain::builder(8)
            .link_length_m(0.04)
            .base_angle_rad(30f64.to_radians())
            .stiffness_nm_per_rad(0.01)
            .hair_on_every_flagellar_link(hair)
            .build()
            .unwrap();
        let base = v(0.01, -0.02);
        let mut theta = vec![30f64.to_radians()];
        theta.extend(counts.iter().map(|&c| f64::from(c) * RAD_PER_COUNT));
        let pivot_switch = switch_for_fraction(1.0 - pivot_fraction);
        let mut bits = vec![0u8; 9];
        bits[link] = 0b1111;
        let mut with_tips = Vec::new();
        let tips = TouchLayout { hair_tips: true, ..TouchLayout::default() };
        estimate_contacts(&chain, &base, &theta, &bits, &tips, &mut with_tips).unwrap();
        let mut on_link = Vec::new();
        estimate_contacts(&chain, &base, &theta, &bits, &TouchLayout::default(), &mut on_link)
            .unwrap();
        let open: Vec<f64> = chain
            .hairs()
            .iter()
            .map(|h| h.map_or(0.0, |h| h.open_angle_rad))
            .collect();
        let poses = hair_poses(&chain, &theta, &open, Frame::GROUND).unwrap();
        let tip = poses.iter().find(|p| p.link == link).unwrap().tip_m + base;
        prop_assert_eq!(with_tips.len(), 4);
        for (a, b) in with_tips.iter().zip(&on_link) {
            prop_assert_eq!((a.link, a.switch), (b.link, b.switch));
            if a.switch == pivot_switch {
                prop_assert!((a.point_m - tip).norm() < 1e-12, "{:?} vs {:?}", a.point_m, tip);
            } else {
                prop_assert_eq!(a.point_m, b.point_m);
            }
        }
    }
}
