//! Thesis 3.3.1 on sim-core (`examples/flipping_3_3_1.toml`): the six experiments (rough or
//! smooth wall x distal hairs, the three distal-most removed, proximal hairs) and rough +
//! distal at base angles 10, 20, 60 and 70 deg.
//!
//! With the thesis's hair geometry (18 mm) docs/model.md 7's anchored hair locks the distal segment
//! at 60.3 deg to the wall, short of a flip: the model cannot flip at 30 deg, and the test
//! says so. With 30 mm hairs (lock beyond 90 deg) the thesis's claims hold: only rough + distal
//! flips, and it flips at every base angle. docs/reproduction.md shows both.
//!
//! With a compliant root (issue #18) the thesis's 18 mm hairs bend past the lock: at a root
//! stiffness of 1.5e-3 N m/rad (a 0.1 mm Nitinol tip protruding about 6 mm; 10 deg of bend
//! take 15 mN at the tip) the six experiments at 30 deg come out as the thesis's: only the
//! rough wall with distal hairs flips (it flips from 1e-3 to 2e-3 N m/rad, and at some
//! softer roots down to 3e-4). A root of 2.5e-3 N m/rad or stiffer holds the segment short of 90 deg again, and
//! a stiff one (0.1) locks it near the rigid hair's lock angle. At 10 and 20 deg no root
//! stiffness flips it (docs/reproduction.md, the compliant table).
#![allow(clippy::unwrap_used)]

use antenna_tests::reproduce::{self, flipping};
use flipping::{HairLayout, WallSurface};

#[test]
fn the_seed_hair_locks_short_of_a_flip() {
    let base = reproduce::load_scene("flipping_3_3_1.toml").unwrap();
    let hair = base.chain.hairs().iter().flatten().next().copied().unwrap();
    let lock = flipping::lock_angle_deg(&hair);
    assert!((lock - 60.3).abs() < 0.1, "lock {lock} deg");
    let run = flipping::run(
        &base,
        WallSurface::Rough,
        HairLayout::Distal,
        30.0,
        hair.length_m,
    )
    .unwrap();
    assert!(!run.flipped(), "flipped at {:?}", run.flip_t_s);
    assert!(run.anchored_steps > 0);
    // It rises to the lock and stops there.
    assert!(
        (run.max_distal_angle_deg - lock).abs() < 1.0,
        "max {} deg, lock {lock} deg",
        run.max_distal_angle_deg
    );
}

#[test]
fn with_longer_hairs_only_rough_and_distal_flips_at_every_base_angle() {
    let base = reproduce::load_scene("flipping_3_3_1.toml").unwrap();
    let hair_m = 0.03;
    for surface in [WallSurface::Rough, WallSurface::Smooth] {
        for layout in HairLayout::ALL {
            let run = flipping::run(&base, surface, layout, 30.0, hair_m).unwrap();
            let expected = surface == WallSurface::Rough && layout == HairLayout::Distal;
            assert_eq!(
                run.flipped(),
                expected,
                "{surface:?} {}: flip {:?}, max {:.1} deg",
                layout.name(),
                run.flip_t_s,
                run.max_distal_angle_deg
            );
            if !expected {
                assert!(
                    run.max_distal_angle_deg < 45.0,
                    "{surface:?} {}",
                    layout.name()
                );
            }
        }
    }
    for deg in [10.0, 20.0, 60.0, 70.0] {
        let run =
            flipping::run(&base, WallSurface::Rough, HairLayout::Distal, deg, hair_m).unwrap();
        assert!(run.flipped(), "{deg} deg: {}", run.placement);
    }
}

/// The root stiffness at which the compliant 18 mm hairs reproduce 3.3.1, N m/rad.
const COMPLIANT_ROOT_NM_PER_RAD: f64 = 1.5e-3;

#[test]
fn compliant_seed_hairs_flip_only_on_the_rough_wall_with_distal_hairs() {
    let base = reproduce::load_scene("flipping_3_3_1.toml").unwrap();
    let hair = base.chain.hairs().iter().flatten().next().copied().unwrap();
    let compliant = flipping::with_root_stiffness(&base, Some(COMPLIANT_ROOT_NM_PER_RAD)).unwrap();
    for surface in [WallSurface::Rough, WallSurface::Smooth] {
        for layout in HairLayout::ALL {
            let run = flipping::run(&compliant, surface, layout, 30.0, hair.length_m).unwrap();
            let expected = surface == WallSurface::Rough && layout == HairLayout::Distal;
            assert_eq!(
                run.flipped(),
                expected,
                "{surface:?} {}: flip {:?}, max {:.1} deg",
                layout.name(),
                run.flip_t_s,
                run.max_distal_angle_deg
            );
            if expected {
                assert!(run.anchored_steps > 0);
            } else {
                assert!(
                    run.max_distal_angle_deg < 45.0,
                    "{surface:?} {}",
                    layout.name()
                );
            }
        }
    }
    // The thesis's base-angle control (rough wall, distal hairs): it flipped at 10, 20, 60 and
    // 70 deg too. At this root 60 and 70 deg flip; 10 and 20 deg do not (docs/reproduction.md
    // says so).
    for (deg, flips) in [(10.0, false), (20.0, false), (60.0, true), (70.0, true)] {
        let run = flipping::run(
            &compliant,
            WallSurface::Rough,
            HairLayout::Distal,
            deg,
            hair.length_m,
        )
        .unwrap();
        assert_eq!(
            run.flipped(),
            flips,
            "{deg} deg: flip {:?}, max {:.1} deg",
            run.flip_t_s,
            run.max_distal_angle_deg
        );
    }
    // Stiffer roots hold the distal segment short of a flip again; a stiff one near the
    // rigid hair's lock.
    let lock = flipping::lock_angle_deg(&hair);
    for (k_r, near_lock) in [(2.5e-3, false), (5e-3, false), (0.1, true)] {
        let stiff = flipping::with_root_stiffness(&base, Some(k_r)).unwrap();
        let run = flipping::run(
            &stiff,
            WallSurface::Rough,
            HairLayout::Distal,
            30.0,
            hair.length_m,
        )
        .unwrap();
        assert!(!run.flipped(), "k_r {k_r}: flipped at {:?}", run.flip_t_s);
        assert!(run.max_distal_angle_deg < lock + 0.1, "k_r {k_r}");
        if near_lock {
            assert!(
                (run.max_distal_angle_deg - lock).abs() < 1.0,
                "k_r {k_r}: max {} deg, lock {lock} deg",
                run.max_distal_angle_deg
            );
        }
    }
}
