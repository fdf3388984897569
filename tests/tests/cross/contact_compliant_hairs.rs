//! Hairs with a compliant root (docs/model.md 7, issue #18): on the thesis's 3.3.1 scene
//! (`examples/flipping_3_3_1.toml`, rough wall, 18 mm distal hairs, base angle 30 deg) an
//! anchored hair with a root stiffness bends past its stop, and every such state passes the
//! independent equilibrium check with the hair as an interior coordinate (its torque
//! balanced, not a stop's multiplier); a very stiff root gives the rigid hair's results.
#![allow(clippy::unwrap_used)]

use antenna_tests::reproduce::{self, flipping};
use flipping::{HairLayout, WallSurface};
use sim_core::contact::Feature;
use sim_core::sweep::Sweep;

/// Runs the rough-wall, distal-hair 3.3.1 scene with root stiffness `k_r` until an anchored
/// hair is bent `bend_rad` past its stop (every step checked); how many steps it took and
/// the bend, radians.
fn run_until_bent(k_r: f64, bend_rad: f64) -> (usize, f64) {
    let base = reproduce::load_scene("flipping_3_3_1.toml").unwrap();
    let base = flipping::with_root_stiffness(&base, Some(k_r)).unwrap();
    let hair_m = base.chain.hairs().iter().flatten().next().unwrap().length_m;
    let scene =
        flipping::scene_for(&base, WallSurface::Rough, HairLayout::Distal, 30.0, hair_m).unwrap();
    let mut sweep = Sweep::new(scene).unwrap();
    let mut largest_bend = f64::NEG_INFINITY;
    let mut steps = 0;
    while let Some(step) = sweep.next_step() {
        let step = step.unwrap();
        steps += 1;
        let sim = sweep.sim();
        let tolerances = sim.certify_tolerances();
        let check = sim.check();
        assert!(
            check.holds_within(&tolerances),
            "t {}: {:?}",
            step.t_s,
            check.failures(&tolerances)
        );
        for c in step.contacts.iter().filter(|c| c.is_anchored()) {
            let Feature::HairTip { link } = c.feature else {
                continue;
            };
            let hair = sim.chain().hairs()[link].unwrap();
            let beta = step.hair_angles_rad[link];
            assert!(beta <= hair.max_angle_rad());
            largest_bend = largest_bend.max(beta - hair.open_angle_rad);
        }
        if largest_bend > bend_rad {
            // Interior: the check balanced its torque (a hair on its bend limit would be
            // checked as a stop).
            return (steps, largest_bend);
        }
    }
    panic!(
        "k_r {k_r}: no anchored hair bent {bend_rad} rad past its stop in {steps} steps (largest {largest_bend})"
    );
}

#[test]
fn an_anchored_compliant_hair_bends_past_its_stop_in_certified_equilibrium() {
    // A soft root bends far (10 deg), a stiffer one a little (0.5 deg).
    let (_, bend) = run_until_bent(2e-3, 10f64.to_radians());
    assert!(bend > 10f64.to_radians());
    let (_, bend) = run_until_bent(0.05, 0.5f64.to_radians());
    assert!(bend < 1.5);
}

#[test]
fn a_very_stiff_root_gives_the_rigid_hairs_results() {
    let base = reproduce::load_scene("flipping_3_3_1.toml").unwrap();
    let hair_m = base.chain.hairs().iter().flatten().next().unwrap().length_m;
    let run = |k_r: Option<f64>| {
        let scene = flipping::with_root_stiffness(&base, k_r).unwrap();
        flipping::run(&scene, WallSurface::Rough, HairLayout::Distal, 30.0, hair_m).unwrap()
    };
    let rigid = run(None);
    let stiff = run(Some(1e3));
    assert_eq!(stiff.flipped(), rigid.flipped());
    assert_eq!(stiff.t_s.len(), rigid.t_s.len());
    // Step by step, the distal segment's angle to the wall within 0.01 deg.
    let worst = stiff
        .distal_angle_deg
        .iter()
        .zip(&rigid.distal_angle_deg)
        .map(|(a, b)| {
            assert_eq!(a.is_finite(), b.is_finite());
            if a.is_finite() { (a - b).abs() } else { 0.0 }
        })
        .fold(0.0, f64::max);
    assert!(worst < 0.01, "worst difference {worst} deg");
    assert!((stiff.max_distal_angle_deg - rigid.max_distal_angle_deg).abs() < 0.01);
}
