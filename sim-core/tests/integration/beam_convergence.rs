//! Chains converge to the elastica (docs/model.md 5), at the orders `sim_core::statics::beam` documents:
//! measured here for a cantilever with a perpendicular tip load, `alpha = F L^2 / EI` in
//! {0.5, 1, 2, 5, 10}, against the Bisshopp-Drucker closed form, and for a tapered beam with an
//! oblique load against the elastica shooting solver.
//!
//! The observed order between `n` and `2n` links is `log2(e(n) / e(2n))` of the relative error
//! `e` of the tip deflection.
#![allow(clippy::unwrap_used)]

use nalgebra::Vector2;
use sim_core::statics::beam::{
    Beam, BeamLayout, RichardsonOptions, richardson_tip, solve_beam_chain,
};
use sim_core::statics::elastica::{BendingStiffness, ElasticaOptions};
use sim_core::statics::elastica::{perpendicular_load_closed_form, solve as solve_elastica};
use sim_core::statics::equilibrium::{InitialGuess, SolveOptions};

const ALPHAS: [f64; 5] = [0.5, 1.0, 2.0, 5.0, 10.0];
const LENGTH_M: f64 = 0.36;
const EI_N_M2: f64 = 0.02;

fn cantilever() -> Beam {
    Beam::uniform(LENGTH_M, EI_N_M2, 0.0)
}

fn force(alpha: f64) -> Vector2<f64> {
    Vector2::new(0.0, alpha * EI_N_M2 / (LENGTH_M * LENGTH_M))
}

fn exact_deflection_m(alpha: f64) -> f64 {
    perpendicular_load_closed_form(alpha)
        .unwrap()
        .tip_transverse_over_length
        * LENGTH_M
}

fn chain_error(alpha: f64, n: usize, layout: BeamLayout) -> f64 {
    let tip = solve_beam_chain(
        &cantilever(),
        n,
        layout,
        force(alpha),
        &InitialGuess::Straight,
        &SolveOptions::default(),
    )
    .unwrap();
    tip.tip_position_m.y / exact_deflection_m(alpha) - 1.0
}

fn sci(values: &[f64]) -> String {
    let parts: Vec<String> = values.iter().map(|v| format!("{v:.3e}")).collect();
    parts.join(" ")
}

fn orders(errors: &[f64]) -> Vec<f64> {
    errors
        .windows(2)
        .map(|w| (w[0] / w[1]).abs().log2())
        .collect()
}

#[test]
fn equal_links_converge_at_first_order() {
    for alpha in ALPHAS {
        let errors: Vec<f64> = [16, 32, 64]
            .iter()
            .map(|&n| chain_error(alpha, n, BeamLayout::EqualLinks))
            .collect();
        let p = orders(&errors);
        eprintln!(
            "equal links, alpha {alpha}: errors {}, orders {p:.3?}",
            sci(&errors)
        );
        // The chain is too flexible-short: the rigid base link is the beam's stiffest stretch.
        assert!(errors.iter().all(|&e| e < 0.0));
        assert!(p.iter().all(|&p| (0.8..1.2).contains(&p)), "{p:?}");
    }
}

#[test]
fn hencky_layout_converges_at_second_order() {
    for alpha in ALPHAS {
        let errors: Vec<f64> = [8, 16, 32, 64, 128]
            .iter()
            .map(|&n| chain_error(alpha, n, BeamLayout::Hencky))
            .collect();
        let p = orders(&errors);
        eprintln!(
            "Hencky, alpha {alpha}: errors {}, orders {p:.3?}",
            sci(&errors)
        );
        assert!(p.iter().all(|&p| (1.8..2.2).contains(&p)), "{p:?}");
        // The leading coefficient e n^2 is between -0.2 and -0.6 (documented in beam.rs).
        let c2 = errors[4] * 128.0 * 128.0;
        assert!((-0.6..-0.2).contains(&c2), "{c2}");
    }
}

fn richardson_error(alpha: f64, coarsest_links: usize, solves: usize) -> f64 {
    let options = RichardsonOptions {
        coarsest_links,
        solves,
        ..RichardsonOptions::default()
    };
    let r = richardson_tip(&cantilever(), force(alpha), &options).unwrap();
    assert_eq!(r.order, 2 * solves);
    assert_eq!(r.solves.len(), solves);
    r.tip_position_m.y / exact_deflection_m(alpha) - 1.0
}

#[test]
fn one_richardson_step_gives_fourth_order() {
    for alpha in ALPHAS {
        let errors: Vec<f64> = [4, 8, 16]
            .iter()
            .map(|&n0| richardson_error(alpha, n0, 2))
            .collect();
        let p = orders(&errors);
        eprintln!(
            "Richardson 2 solves, alpha {alpha}: errors {}, orders {p:.3?}",
            sci(&errors)
        );
        assert!(p.iter().all(|&p| (3.6..4.4).contains(&p)), "{p:?}");
    }
}

#[test]
fn two_richardson_steps_give_sixth_order() {
    for alpha in ALPHAS {
        let errors: Vec<f64> = [4, 8, 16]
            .iter()
            .map(|&n0| richardson_error(alpha, n0, 3))
            .collect();
        let p = orders(&errors);
        eprintln!(
            "Richardson 3 solves, alpha {alpha}: errors {}, orders {p:.3?}",
            sci(&errors)
        );
        // Pre-asymptotic at alpha = 10 from 4 links (the h^8 term is still large); 6 once
        // the coarsest chain has 8 links.
        assert!(p.iter().all(|&p| (5.5..7.5).contains(&p)), "{p:?}");
        assert!((5.7..6.6).contains(&p[1]), "{p:?}");
    }
}

#[test]
fn richardson_over_8_16_32_links_is_within_1e_6_for_every_alpha() {
    for alpha in ALPHAS {
        let e = richardson_error(alpha, 8, 3);
        eprintln!("Richardson 8/16/32, alpha {alpha}: relative error {e:.2e}");
        assert!(e.abs() < 1e-6, "alpha {alpha}: {e:e}");
    }
}

#[test]
fn warm_and_cold_richardson_agree_and_warm_saves_iterations() {
    let beam = cantilever();
    let run = |warm_start| {
        let options = RichardsonOptions {
            coarsest_links: 16,
            solves: 3,
            warm_start,
            ..RichardsonOptions::default()
        };
        richardson_tip(&beam, force(10.0), &options).unwrap()
    };
    let (warm, cold) = (run(true), run(false));
    assert!((warm.tip_position_m - cold.tip_position_m).norm() < 1e-10 * LENGTH_M);
    let its = |r: &sim_core::statics::beam::RichardsonTip| {
        r.solves.iter().map(|s| s.iterations).sum::<usize>()
    };
    eprintln!("iterations: warm {}, cold {}", its(&warm), its(&cold));
    assert!(its(&warm) < its(&cold));
    // The error estimate bounds the true error of the extrapolated tip here.
    let truth = exact_deflection_m(10.0);
    assert!((warm.tip_position_m.y - truth).abs() <= warm.error_estimate_m);
}

#[test]
fn tapered_beam_with_oblique_load_and_clamp_angle() {
    // A fast-exponential taper, EI from 0.066 down to 0.0032 N m^2, clamped at 30 degrees, under
    // a load pulling down and back.
    let l = 0.36;
    let beam = Beam {
        length_m: l,
        bending_stiffness: BendingStiffness::function(move |s| {
            0.0032 + 0.0032 * 19.5 * (-12.0 * s / l).exp()
        }),
        clamp_angle_rad: 30f64.to_radians(),
    };
    let f = Vector2::new(-0.01, -0.02);
    let reference = solve_elastica(&beam.elastica_problem(f), &ElasticaOptions::default()).unwrap();
    let truth = Vector2::from(reference.tip_position_m);
    let start = Vector2::new(
        l * beam.clamp_angle_rad.cos(),
        l * beam.clamp_angle_rad.sin(),
    );
    let deflection = (truth - start).norm();
    let errors: Vec<f64> = [16, 32, 64, 128]
        .iter()
        .map(|&n| {
            let tip = solve_beam_chain(
                &beam,
                n,
                BeamLayout::Hencky,
                f,
                &InitialGuess::Straight,
                &SolveOptions::default(),
            )
            .unwrap();
            (tip.tip_position_m - truth).norm() / deflection
        })
        .collect();
    let p = orders(&errors);
    eprintln!(
        "tapered: deflection {deflection:.4} m, errors {}, orders {p:.3?}",
        sci(&errors)
    );
    assert!(p.iter().all(|&p| (1.8..2.2).contains(&p)), "{p:?}");
    let r = richardson_tip(
        &beam,
        f,
        &RichardsonOptions {
            coarsest_links: 16,
            solves: 3,
            ..RichardsonOptions::default()
        },
    )
    .unwrap();
    let e = (r.tip_position_m - truth).norm() / deflection;
    eprintln!("tapered Richardson 16/32/64: {e:.2e}");
    assert!(e < 1e-6, "{e:e}");
}
