//! The closed loop's truth against theory (issue #47, item 6): the template body under an
//! ideal-preview PD controller, no delay, a step of 1 ms, along a straight wall. Bisected on
//! the sign of the error envelope's fitted growth rate over 60 s of following, the
//! simulated stability boundary in speed lies within 5 % of the linearized one,
//! `(b + Kd l) Kp l / (J Kp - (b + Kd l) Kd)`, at three parameter sets with
//! `J Kp > (b + Kd l) Kd` (one of them P-only, the example, `b l / J = 1 m/s`).

use sim_core::follow::theory::{PreviewRun, TemplateLinear, ideal_preview_boundary_speed};

fn check(linear: TemplateLinear) {
    let theory = linear
        .boundary_speed_m_per_s()
        .unwrap_or_else(|| panic!("{linear:?} has no speed limit"));
    assert!((0.2..3.0).contains(&theory), "{linear:?}: {theory}");
    let run = PreviewRun {
        step_s: 0.001,
        duration_s: 60.0,
        ..PreviewRun::default()
    };
    assert!(run.duration_s - run.skip_s >= 50.0);
    let simulated = ideal_preview_boundary_speed(&linear, &run, [0.5 * theory, 2.0 * theory])
        .unwrap_or_else(|| panic!("{linear:?}: no sign change in [v/2, 2v]"));
    let shift = simulated / theory - 1.0;
    println!(
        "{linear:?}: theory {theory:.4} m/s, simulated {simulated:.4} m/s ({:+.2} %)",
        100.0 * shift
    );
    assert!(shift.abs() < 0.05, "{linear:?}: {simulated} vs {theory}");
}

#[test]
fn the_p_only_boundary_is_b_l_over_j() {
    let linear = TemplateLinear::example();
    assert_eq!(linear.kd_n_s, 0.0);
    check(linear);
}

#[test]
fn a_pd_boundary_with_the_examples_body() {
    check(TemplateLinear {
        kd_n_s: 0.001,
        ..TemplateLinear::example()
    });
}

#[test]
fn a_pd_boundary_with_a_heavier_body_and_a_longer_preview() {
    check(TemplateLinear {
        inertia_kg_m2: 5.0e-4,
        damping_n_m_s_per_rad: 2.0e-3,
        kp_n: 0.1,
        kd_n_s: 0.002,
        preview_m: 0.08,
    });
}
