//! Thesis 4.2.1 / Table 4.1 on sim-core (`examples/wall_following_4_2_1.toml`, the seven
//! profiles): every decreasing profile previews further than the constant one; the
//! exponential and logarithmic ones beat linear, linear beats the reciprocals; the point of
//! bend follows the base-to-wall distance better for a decreasing profile than for the
//! constant one. Figure and table: docs/reproduction.md.
#![allow(clippy::unwrap_used)]

use antenna_tests::reproduce::{self, wall_following};
use sim_core::StiffnessProfile;

#[test]
fn table_4_1_orders_the_profiles_as_the_seed_does() {
    let base = reproduce::load_scene("wall_following_4_2_1.toml").unwrap();
    let runs = wall_following::run_all(&base).unwrap();
    let row = |p: StiffnessProfile| {
        let run = runs.iter().find(|r| r.profile == p).unwrap();
        // The tip stays on the wall for the whole run: every step has a contact.
        assert!(
            run.contact_joint.iter().all(|c| c.is_finite()),
            "{} lost the wall",
            p.name()
        );
        assert_eq!(run.t_s.len(), 5000, "{}", p.name());
        run.table_row()
    };
    let constant = row(StiffnessProfile::Constant);
    // Table 4.1's rows after the constant one: the decreasing profiles.
    let decreasing = reproduce::TABLE_4_1_PROFILES
        .iter()
        .filter(|p| **p != StiffnessProfile::Constant);
    for p in decreasing {
        let r = row(p.clone());
        assert!(
            r.preview_mean_cm > constant.preview_mean_cm,
            "{}: preview {:.2} cm, constant {:.2} cm",
            p.name(),
            r.preview_mean_cm,
            constant.preview_mean_cm
        );
        let (bend, bend_constant) = (r.bend_pearson.unwrap(), constant.bend_pearson.unwrap());
        assert!(
            bend > bend_constant,
            "{}: bend-distance r {bend:.3}, constant {bend_constant:.3}",
            p.name()
        );
    }
    let linear = row(StiffnessProfile::Linear).preview_mean_cm;
    for p in [
        StiffnessProfile::FastExponential,
        StiffnessProfile::SlowExponential,
        StiffnessProfile::Logarithmic,
    ] {
        let preview = row(p.clone()).preview_mean_cm;
        assert!(
            preview > linear,
            "{}: {preview:.2} cm, linear {linear:.2} cm",
            p.name()
        );
    }
    for p in [
        StiffnessProfile::SlowReciprocal,
        StiffnessProfile::FastReciprocal,
    ] {
        let preview = row(p.clone()).preview_mean_cm;
        assert!(
            linear > preview,
            "{}: {preview:.2} cm, linear {linear:.2} cm",
            p.name()
        );
    }
}
