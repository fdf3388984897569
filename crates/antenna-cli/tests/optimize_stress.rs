//! `antenna optimize` on optimizations nobody designed (issue #17): seeded random files over
//! the whole space (links, wall, start, objective, parameters, wires, method, budget, seed,
//! a scene that jams) through the library. Every run must keep its budget, report the
//! running best as its history and at least the best named profile, give only stiffnesses
//! within the bounds (a wire's with `wires = "available"`), count every infeasible
//! evaluation, be the same run on 1 thread as on 2, and its result must sweep back to its
//! objective exactly. 10 cases in CI; `ANTENNA_SOAK=1` runs 200.
#![allow(clippy::unwrap_used)]

use std::path::Path;

use antenna_cli::optimize::{OptimizeOptions, OptimizeSpec, run_optimization, with_stiffness};
use antenna_cli::sweep::SweepRun;
use rand::rngs::StdRng;
use rand::{Rng as _, SeedableRng as _};
use sim_core::{available_wires, wire_stiffness_n_m_per_rad};

const OBJECTIVES: [&str; 3] = ["preview-mean", "mapping-error", "flip-free-preview"];

/// A random sweepable scene along a line wall.
fn random_scene(rng: &mut StdRng) -> String {
    let links = rng.random_range(2..=7);
    let start = if rng.random_bool(0.5) {
        "[start]\nplacement = \"tip-on-wall\"\nwall = 0\nahead_m = 0.0\nshape = \"C\"\n"
    } else {
        ""
    };
    format!(
        "[antenna]\nlinks = {links}\nlink_length_m = 0.04\nbase_angle_deg = {:.1}\n\
         joint_limits_deg = [-90.0, 90.0]\n\
         [antenna.stiffness]\nprofile = \"linear\"\nmin_n_m_per_rad = 0.004\nmax_n_m_per_rad = 0.082\n\
         [[walls]]\nshape = \"line\"\npoint_m = [0.0, {:.3}]\nangle_deg = {:.1}\nsolid = \"left\"\n\
         surface = \"smooth\"\nmu = {:.2}\n\
         [sweep]\nvelocity_m_per_s = [0.0167, 0.0]\nduration_s = {:.2}\nstep_s = 0.05\n{start}",
        rng.random_range(15.0..70.0),
        rng.random_range(0.3..0.95) * 0.04 * links as f64,
        rng.random_range(-15.0..0.0),
        rng.random_range(0.0..0.6),
        rng.random_range(0.2..1.5),
    )
}

#[test]
fn random_optimizations_keep_their_budget_and_report_what_they_swept() {
    let cases = if std::env::var_os("ANTENNA_SOAK").is_some() {
        200
    } else {
        10
    };
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("antenna-cli-optimize-stress");
    let wires: Vec<f64> = available_wires()
        .into_iter()
        .map(wire_stiffness_n_m_per_rad)
        .collect();
    let mut refused = 0;
    for case in 0..cases {
        let mut rng = StdRng::seed_from_u64(20_261_128 + case);
        let dir = root.join(format!("case-{case}"));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("a.toml"), random_scene(&mut rng)).unwrap();
        let mut scenes = vec!["\"a.toml\"".to_string()];
        if rng.random_bool(0.2) {
            // the same antenna driven head-on into a wall: jams
            let a = std::fs::read_to_string(dir.join("a.toml")).unwrap();
            let jam = a.replace("[-90.0, 90.0]", "[-0.5, 0.5]").replace(
                "velocity_m_per_s = [0.0167, 0.0]",
                "velocity_m_per_s = [0.0, 0.05]",
            );
            std::fs::write(dir.join("b.toml"), jam).unwrap();
            scenes.push("\"b.toml\"".to_string());
        }
        let text = format!(
            "[optimize]\nscenes = [{}]\nobjective = \"{}\"\nparameters = \"{}\"\nwires = \"{}\"\n\
             method = \"{}\"\nbudget = {}\nseed = {}\n",
            scenes.join(", "),
            OBJECTIVES[rng.random_range(0..3)],
            ["per-joint", "exponential-taper"][rng.random_range(0..2)],
            ["any", "available"][rng.random_range(0..2)],
            ["nelder-mead", "particle-swarm"][rng.random_range(0..2)],
            rng.random_range(8..60),
            rng.random_range(0..1000),
        );
        let spec = match OptimizeSpec::parse(&text, "opt.toml", &dir) {
            Ok(spec) => spec,
            Err(e) => {
                // a budget below the start, or a start the scene cannot take: a located error
                let message = e.to_string();
                assert!(
                    message.starts_with("opt.toml:") || message.contains(".toml"),
                    "{e}"
                );
                refused += 1;
                continue;
            }
        };
        let options = |jobs| OptimizeOptions {
            jobs,
            ..OptimizeOptions::default()
        };
        let report = run_optimization(&spec, &options(2)).unwrap();
        let label = format!("case {case}: {text}");
        assert!(report.sweeps <= spec.budget, "{label}");
        assert_eq!(report.history.len(), report.evaluations, "{label}");
        let mut best = None::<f64>;
        for (own, history) in report.objective_values.iter().zip(&report.history) {
            if let Some(v) = own {
                best = Some(best.map_or(*v, |b| b.max(*v)));
            }
            assert_eq!(*history, best, "{label}");
        }
        assert_eq!(report.objective_value, best, "{label}");
        let failed = report
            .objective_values
            .iter()
            .filter(|v| v.is_none())
            .count();
        assert_eq!(report.failed_evaluations, failed, "{label}");
        if let Some(named) = report
            .best_named_profile
            .as_ref()
            .and_then(|n| n.objective_value)
        {
            assert!(report.objective_value.unwrap() >= named, "{label}");
        }
        let [lo, hi] = report.stiffness_bounds_n_m_per_rad;
        for &k in &report.values_n_m_per_rad {
            assert!((lo..=hi).contains(&k), "{label}: {k}");
            if report.wires == "available" {
                assert!(wires.contains(&k), "{label}: {k} is no wire's");
            }
        }
        let mut again = run_optimization(&spec, &options(1)).unwrap();
        again.elapsed_s = report.elapsed_s;
        assert_eq!(again, report, "{label}: 1 thread and 2 differ");
        if let (Some(value), [(_, scene)]) = (report.objective_value, spec.scenes.as_slice()) {
            let scene = with_stiffness(scene, &report.values_n_m_per_rad).unwrap();
            let mut run = SweepRun::start(&scene).unwrap();
            while let Some(state) = run.next_state() {
                state.unwrap();
            }
            let swept = spec.objective.of_summary(&run.summary()).unwrap();
            assert_eq!(swept, value, "{label}");
        }
    }
    assert!(refused < cases / 2, "{refused} of {cases} files refused");
}
