//! Tests of the elastica: the closed form against the literature and mpmath, the shooting
//! solver against the closed form and linear theory, and the typed errors.

#![allow(clippy::excessive_precision)]

use super::*;
use proptest::prelude::*;

// mpmath digits kept beyond f64 precision on purpose (they are the reference).
/// Bisshopp-Drucker values computed independently with mpmath at 30 digits:
/// (alpha, tip angle, along / L, transverse / L).
const GOLDEN_BD: [(f64, f64, f64, f64); 5] = [
    (
        0.5,
        0.24453364713321830851,
        0.98408103752916250338,
        0.16214357565836960515,
    ),
    (
        1.0,
        0.46135194971187896071,
        0.94356676371662311691,
        0.30172077379981352954,
    ),
    (
        2.0,
        0.78174983155654304442,
        0.83935827917483276379,
        0.49345748039671182041,
    ),
    (
        5.0,
        1.2153681176116810959,
        0.61237163927557012814,
        0.71379152361191272809,
    ),
    (
        10.0,
        1.430285538803857529,
        0.44500440224624873043,
        0.81060902488029645323,
    ),
];

fn uniform(length_m: f64, ei: f64, theta0: f64, force: [f64; 2]) -> ElasticaProblem {
    ElasticaProblem {
        length_m,
        bending_stiffness: BendingStiffness::Uniform { ei_n_m2: ei },
        clamp_angle_rad: theta0,
        tip_force_n: force,
    }
}

/// The problem with a perpendicular load of given alpha, in a rotated frame.
fn perpendicular(alpha: f64, length_m: f64, ei: f64, theta0: f64) -> ElasticaProblem {
    let p = alpha * ei / (length_m * length_m);
    uniform(length_m, ei, theta0, [-p * theta0.sin(), p * theta0.cos()])
}

#[test]
fn closed_form_matches_literature_and_mpmath() {
    // The classical table (alpha = 1): 0.30172 and 0.05643 to five decimals.
    let one = perpendicular_load_closed_form(1.0).unwrap();
    assert!((one.tip_transverse_over_length - 0.30172).abs() < 5e-6);
    assert!((1.0 - one.tip_along_over_length - 0.05643).abs() < 5e-6);
    for (alpha, angle, along, transverse) in GOLDEN_BD {
        let cf = perpendicular_load_closed_form(alpha).unwrap();
        assert!((cf.tip_angle_rad - angle).abs() < 1e-14, "{alpha}");
        assert!((cf.tip_along_over_length - along).abs() < 1e-14, "{alpha}");
        assert!(
            (cf.tip_transverse_over_length - transverse).abs() < 1e-14,
            "{alpha}"
        );
    }
    // A negative alpha mirrors the shape.
    let neg = perpendicular_load_closed_form(-2.0).unwrap();
    assert!((neg.tip_transverse_over_length + GOLDEN_BD[2].3).abs() < 1e-14);
    assert!((neg.tip_angle_rad + GOLDEN_BD[2].1).abs() < 1e-14);
    assert!((neg.tip_along_over_length - GOLDEN_BD[2].2).abs() < 1e-14);
    assert_eq!(
        perpendicular_load_closed_form(0.0)
            .unwrap()
            .tip_along_over_length,
        1.0
    );
}

#[test]
fn shooting_matches_closed_form_to_1e_10() {
    let mut worst = 0.0f64;
    for (alpha, ..) in GOLDEN_BD {
        for theta0 in [0.0, 0.7, -2.0] {
            let (l, ei) = (0.36, 0.02);
            let sol = solve(
                &perpendicular(alpha, l, ei, theta0),
                &ElasticaOptions::default(),
            )
            .unwrap();
            let cf = perpendicular_load_closed_form(alpha).unwrap();
            let (c, s) = (theta0.cos(), theta0.sin());
            let want = [
                l * (c * cf.tip_along_over_length - s * cf.tip_transverse_over_length),
                l * (s * cf.tip_along_over_length + c * cf.tip_transverse_over_length),
            ];
            let dx = (sol.tip_position_m[0] - want[0]).abs() / l;
            let dy = (sol.tip_position_m[1] - want[1]).abs() / l;
            let da = (sol.tip_angle_rad - theta0 - cf.tip_angle_rad).abs();
            worst = worst.max(dx).max(dy).max(da);
            assert!(
                dx < 1e-10 && dy < 1e-10 && da < 1e-10,
                "alpha {alpha} theta0 {theta0}: {dx:e} {dy:e} {da:e}"
            );
            assert!(sol.moment_residual_n_m <= 1e-11 * alpha * ei / l);
        }
    }
    eprintln!("elastica vs closed form: worst |difference| / L (or rad) = {worst:.2e}");
}

#[test]
fn small_load_matches_linear_theory() {
    let (l, ei, p) = (0.5, 0.3, 1e-6);
    let sol = solve(&uniform(l, ei, 0.0, [0.0, p]), &ElasticaOptions::default()).unwrap();
    let delta = p * l.powi(3) / (3.0 * ei);
    let slope = p * l * l / (2.0 * ei);
    // Nonlinear corrections are O(alpha^2) relative, alpha = 8.3e-7 here.
    assert!((sol.tip_position_m[1] / delta - 1.0).abs() < 1e-9);
    assert!((sol.tip_angle_rad / slope - 1.0).abs() < 1e-9);
    assert!((sol.tip_position_m[0] - l).abs() < 1e-12 * l);
}

#[test]
fn piecewise_small_load_matches_linear_theory() {
    // y_L = P int (L - s)^2 / EI ds, theta_L = P int (L - s) / EI ds, section by section.
    let l = 0.36;
    let breaks = vec![0.04, 0.12, 0.2, 0.3];
    let eis = vec![0.08, 0.03, 0.01, 0.004, 0.001];
    let p = 1e-7;
    let problem = ElasticaProblem {
        length_m: l,
        bending_stiffness: BendingStiffness::PiecewiseConstant {
            breakpoints_m: breaks.clone(),
            ei_n_m2: eis.clone(),
        },
        clamp_angle_rad: 0.0,
        tip_force_n: [0.0, p],
    };
    let sol = solve(&problem, &ElasticaOptions::default()).unwrap();
    let mut ends = vec![0.0];
    ends.extend(&breaks);
    ends.push(l);
    let (mut y_lin, mut t_lin) = (0.0, 0.0);
    for (w, ei) in ends.windows(2).zip(&eis) {
        y_lin += p * ((l - w[0]).powi(3) - (l - w[1]).powi(3)) / (3.0 * ei);
        t_lin += p * ((l - w[0]).powi(2) - (l - w[1]).powi(2)) / (2.0 * ei);
    }
    assert!(
        (sol.tip_position_m[1] / y_lin - 1.0).abs() < 1e-8,
        "{} vs {y_lin}",
        sol.tip_position_m[1]
    );
    assert!((sol.tip_angle_rad / t_lin - 1.0).abs() < 1e-8);
}

#[test]
fn piecewise_equal_and_function_constant_agree_with_uniform() {
    let (l, ei, theta0, f) = (0.3, 0.05, 0.4, [0.2, -0.9]);
    let base = solve(&uniform(l, ei, theta0, f), &ElasticaOptions::default()).unwrap();
    let piecewise = ElasticaProblem {
        bending_stiffness: BendingStiffness::PiecewiseConstant {
            breakpoints_m: vec![0.1, 0.25],
            ei_n_m2: vec![ei; 3],
        },
        ..uniform(l, ei, theta0, f)
    };
    let function = ElasticaProblem {
        bending_stiffness: BendingStiffness::function(move |_| ei),
        ..uniform(l, ei, theta0, f)
    };
    for other in [piecewise, function] {
        let sol = solve(&other, &ElasticaOptions::default()).unwrap();
        for k in 0..2 {
            assert!((sol.tip_position_m[k] - base.tip_position_m[k]).abs() < 1e-12 * l);
        }
        assert!((sol.tip_angle_rad - base.tip_angle_rad).abs() < 1e-12);
    }
}

#[test]
fn tapered_function_is_between_its_bounds() {
    // EI decreasing from 0.08 to 0.004: tip deflection lies between the two uniform ones.
    let (l, f) = (0.36, [0.0, 0.05]);
    let tapered = ElasticaProblem {
        bending_stiffness: BendingStiffness::function(move |s| {
            0.004 + 0.076 * (-(s / l) * 3.0).exp()
        }),
        ..uniform(l, 1.0, 0.0, f)
    };
    let sol = solve(&tapered, &ElasticaOptions::default()).unwrap();
    let stiff = solve(&uniform(l, 0.08, 0.0, f), &ElasticaOptions::default()).unwrap();
    let soft = solve(&uniform(l, 0.004, 0.0, f), &ElasticaOptions::default()).unwrap();
    assert!(sol.tip_position_m[1] > stiff.tip_position_m[1]);
    assert!(sol.tip_position_m[1] < soft.tip_position_m[1]);
    assert!(sol.moment_residual_n_m <= 1e-12 * 0.05 * l);
}

#[test]
fn shape_samples_satisfy_moment_balance_and_end_at_tip() {
    let (l, ei) = (0.36, 0.01);
    let problem = uniform(l, ei, 0.3, [-0.05, 0.12]);
    let sol = solve(
        &problem,
        &ElasticaOptions {
            shape_samples: 37,
            ..ElasticaOptions::default()
        },
    )
    .unwrap();
    assert_eq!(sol.shape.len(), 37);
    let [fx, fy] = problem.tip_force_n;
    let [xl, yl] = sol.tip_position_m;
    for (i, p) in sol.shape.iter().enumerate() {
        assert!((p.arc_length_m - l * i as f64 / 36.0).abs() < 1e-15);
        // M is integrated from its own ODE; the algebraic balance checks it independently.
        let balance = (xl - p.position_m[0]) * fy - (yl - p.position_m[1]) * fx;
        assert!(
            (p.moment_n_m - balance).abs() < 1e-12 * 0.13 * l,
            "sample {i}"
        );
    }
    let last = sol.shape[36];
    assert_eq!(last.position_m, sol.tip_position_m);
    assert_eq!(last.angle_rad, sol.tip_angle_rad);
    assert_eq!(sol.shape[0].angle_rad, 0.3);
    // Inextensible: chords are shorter than arcs but not by much for smooth shapes.
    let chord: f64 = sol
        .shape
        .windows(2)
        .map(|w| {
            (w[1].position_m[0] - w[0].position_m[0]).hypot(w[1].position_m[1] - w[0].position_m[1])
        })
        .sum();
    assert!(chord < l && chord > l * (1.0 - 1e-3));
}

#[test]
fn zero_and_axial_loads_leave_the_beam_straight() {
    let l = 0.2;
    for force in [[0.0, 0.0], [3.0, 0.0], [-0.1, 0.0]] {
        // Compression -0.1 N is below the buckling load pi^2 EI / (4 L^2) = 0.62 N.
        let sol = solve(&uniform(l, 0.01, 0.0, force), &ElasticaOptions::default()).unwrap();
        assert!((sol.tip_position_m[0] - l).abs() < 1e-14);
        assert!(sol.tip_position_m[1].abs() < 1e-14);
        assert!(sol.tip_angle_rad.abs() < 1e-14);
    }
}

#[test]
fn bad_input_gives_typed_errors() {
    let ok = uniform(0.3, 0.01, 0.0, [0.0, 0.1]);
    let opts = ElasticaOptions::default();
    let with = |f: &dyn Fn(&mut ElasticaProblem)| {
        let mut p = ok.clone();
        f(&mut p);
        solve(&p, &opts)
    };
    assert!(matches!(
        with(&|p| p.length_m = -1.0),
        Err(ElasticaError::InvalidLength { .. })
    ));
    assert!(matches!(
        with(&|p| p.tip_force_n[1] = f64::NAN),
        Err(ElasticaError::InvalidForce { index: 1, .. })
    ));
    assert!(matches!(
        with(&|p| p.clamp_angle_rad = f64::INFINITY),
        Err(ElasticaError::InvalidClampAngle { .. })
    ));
    assert!(matches!(
        with(&|p| p.bending_stiffness = BendingStiffness::Uniform { ei_n_m2: 0.0 }),
        Err(ElasticaError::InvalidStiffness { .. })
    ));
    assert!(matches!(
        with(
            &|p| p.bending_stiffness = BendingStiffness::PiecewiseConstant {
                breakpoints_m: vec![0.2, 0.1],
                ei_n_m2: vec![0.01; 3]
            }
        ),
        Err(ElasticaError::InvalidBreakpoint { index: 1, .. })
    ));
    assert!(matches!(
        with(
            &|p| p.bending_stiffness = BendingStiffness::PiecewiseConstant {
                breakpoints_m: vec![0.1],
                ei_n_m2: vec![0.01; 3]
            }
        ),
        Err(ElasticaError::SectionCountMismatch {
            breakpoints: 1,
            values: 3
        })
    ));
    assert!(matches!(
        with(
            &|p| p.bending_stiffness = BendingStiffness::PiecewiseConstant {
                breakpoints_m: vec![0.1],
                ei_n_m2: vec![0.01, -1.0]
            }
        ),
        Err(ElasticaError::InvalidStiffness { .. })
    ));
    // A closure that goes negative mid-beam is caught where it is met.
    let err = with(&|p| {
        p.bending_stiffness =
            BendingStiffness::function(|s| if (0.1..0.2).contains(&s) { -1.0 } else { 0.01 })
    });
    assert!(
        matches!(err, Err(ElasticaError::InvalidStiffness { s_m, .. }) if (0.1..0.2).contains(&s_m))
    );
    assert!(matches!(
        solve(
            &ok,
            &ElasticaOptions {
                shape_samples: 1,
                ..ElasticaOptions::default()
            }
        ),
        Err(ElasticaError::InvalidOption {
            field: "shape_samples",
            ..
        })
    ));
    assert!(matches!(
        solve(
            &ok,
            &ElasticaOptions {
                integration_tolerance: 0.0,
                ..ElasticaOptions::default()
            }
        ),
        Err(ElasticaError::InvalidOption {
            field: "integration_tolerance",
            ..
        })
    ));
    assert!(matches!(
        perpendicular_load_closed_form(f64::NAN),
        Err(ElasticaError::InvalidAlpha { .. })
    ));
}

#[test]
fn non_convergence_reports_the_residual() {
    // One Newton iteration cannot reach 1e-12 from the straight start at alpha = 10, and
    // continuation with one iteration per level cannot either.
    let problem = perpendicular(10.0, 0.3, 0.01, 0.0);
    let err = solve(
        &problem,
        &ElasticaOptions {
            max_newton_iterations: 1,
            ..ElasticaOptions::default()
        },
    )
    .unwrap_err();
    match err {
        ElasticaError::NotConverged { residual_n_m, .. } => {
            assert!(residual_n_m.is_finite() && residual_n_m > 0.0)
        }
        other => panic!("unexpected {other:?}"),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    /// Rotating the clamp and the force together rotates the solution rigidly.
    #[test]
    fn rotation_equivariance(
        fx in -0.3f64..0.3,
        fy in -0.3f64..0.3,
        rot in -PI_F..PI_F,
    ) {
        let (l, ei) = (0.36, 0.02);
        let a = solve(&uniform(l, ei, 0.0, [fx, fy]), &ElasticaOptions::default()).unwrap();
        let (c, s) = (rot.cos(), rot.sin());
        let b = solve(&uniform(l, ei, rot, [c * fx - s * fy, s * fx + c * fy]), &ElasticaOptions::default()).unwrap();
        let [x, y] = a.tip_position_m;
        prop_assert!((b.tip_position_m[0] - (c * x - s * y)).abs() < 1e-11 * l);
        prop_assert!((b.tip_position_m[1] - (s * x + c * y)).abs() < 1e-11 * l);
        prop_assert!((b.tip_angle_rad - rot - a.tip_angle_rad).abs() < 1e-11);
    }
}

const PI_F: f64 = std::f64::consts::PI;
