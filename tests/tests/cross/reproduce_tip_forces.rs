//! Thesis 3.3.2 on sim-core (`examples/tip_forces_3_3_2.toml`): the distal hair anchors on the
//! abrasive strip and the antenna flips at base angles 30 and 60 deg; through the flip the
//! 60 deg one presses harder for its shear (the higher normal-to-shear ratio). Figure:
//! docs/reproduction.md.
#![allow(clippy::unwrap_used)]

use antenna_tests::reproduce::{self, tip_forces};

#[test]
fn the_steeper_flip_has_the_higher_normal_to_shear_ratio() {
    let base = reproduce::load_scene("tip_forces_3_3_2.toml").unwrap();
    let shallow = tip_forces::run(&base, 30.0).unwrap();
    let steep = tip_forces::run(&base, 60.0).unwrap();
    for run in [&shallow, &steep] {
        assert!(
            run.flip_t_s.is_some(),
            "{} deg did not flip: {}",
            run.base_angle_deg,
            run.placement
        );
        // The strip pushes (never pulls) on the distal segment.
        assert!(run.normal_n.iter().all(|&n| n >= -1e-9));
        assert!(run.normal_n.iter().any(|&n| n > 1e-4));
    }
    let (a, b) = (
        shallow.normal_to_shear_ratio().unwrap(),
        steep.normal_to_shear_ratio().unwrap(),
    );
    assert!(b > a, "N/|T|: 30 deg {a:.3}, 60 deg {b:.3}");
}
