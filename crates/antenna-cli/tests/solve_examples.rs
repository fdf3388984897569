//! `antenna solve` on every `examples/*.toml`: each converges (exit 0) and `--json` prints
//! exactly the fields of docs/scene-format.md with the right lengths and consistent values; the
//! pinned examples reach the C and S shapes they name, and `--all-minima` lists at least two
//! stable equilibria sorted by energy. A scene with walls reports its placed and settled
//! posture: step 0 of its sweep, with the tip's force on the walls.
#![allow(clippy::unwrap_used)]

mod common;

use antenna_scene::{Scene, StiffnessSpec};
use common::{example, example_scenes, run, stderr, stdout};
use serde_json::Value;

const FIELDS: [&str; 10] = [
    "theta_rad",
    "joints_m",
    "tip_m",
    "energy_j",
    "tip_force_n",
    "iterations",
    "residual",
    "converged",
    "inflections",
    "stable",
];

fn point(v: &Value) -> [f64; 2] {
    let a = v.as_array().unwrap();
    assert_eq!(a.len(), 2, "{v}");
    [a[0].as_f64().unwrap(), a[1].as_f64().unwrap()]
}

/// Checks one solve object against its scene; returns it.
fn check_report(v: &Value, scene: &Scene, label: &str) {
    let obj = v.as_object().unwrap();
    let mut keys: Vec<&str> = obj.keys().map(String::as_str).collect();
    keys.sort_unstable();
    let mut expected = FIELDS.to_vec();
    expected.sort_unstable();
    assert_eq!(
        keys, expected,
        "{label}: exactly the fields of docs/scene-format.md"
    );

    let n = scene.n();
    let theta: Vec<f64> = v["theta_rad"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_f64().unwrap())
        .collect();
    assert_eq!(theta.len(), n + 1, "{label}: theta_rad has n + 1 entries");
    assert!(
        (theta[0] - scene.chain.base_angle_rad()).abs() < 1e-12,
        "{label}: theta_0"
    );
    let joints: Vec<[f64; 2]> = v["joints_m"]
        .as_array()
        .unwrap()
        .iter()
        .map(point)
        .collect();
    assert_eq!(joints.len(), n + 1, "{label}: joints_m has frames 0..=n");
    let tip = point(&v["tip_m"]);
    assert_eq!(tip, joints[n], "{label}: the tip is frame n");
    let force = point(&v["tip_force_n"]);

    // Frame 0 is the end of the base link, shifted by the base position.
    let l = scene.chain.link_lengths_m();
    let b = scene.base_position_m;
    let expected0 = [b.x + l[0] * theta[0].cos(), b.y + l[0] * theta[0].sin()];
    assert!(
        (joints[0][0] - expected0[0]).abs() < 1e-12 && (joints[0][1] - expected0[1]).abs() < 1e-12,
        "{label}: frame 0 {:?} vs {expected0:?}",
        joints[0]
    );
    // Consecutive frames are one link length apart.
    for i in 1..=n {
        let d = ((joints[i][0] - joints[i - 1][0]).powi(2)
            + (joints[i][1] - joints[i - 1][1]).powi(2))
        .sqrt();
        assert!(
            (d - l[i]).abs() < 1e-12,
            "{label}: link {i} is {d} m, not {} m",
            l[i]
        );
    }
    match scene.tip_pin_m {
        // A scene with walls: the tip's force on the walls (checked in
        // `wall_scenes_report_the_settled_posture`).
        None if scene.has_walls() => {}
        Some(pin) => {
            assert!(
                (tip[0] - pin.x).abs() < 1e-8 && (tip[1] - pin.y).abs() < 1e-8,
                "{label}: tip {tip:?} on the pin {pin:?}"
            );
            assert!(
                force[0].hypot(force[1]) > 0.0,
                "{label}: a pinned tip pushes"
            );
        }
        None => assert_eq!(force, [0.0, 0.0], "{label}: nothing holds the tip"),
    }
    let energy = v["energy_j"].as_f64().unwrap();
    assert!(
        energy.is_finite() && energy >= 0.0,
        "{label}: energy {energy}"
    );
    assert!(v["iterations"].as_u64().is_some(), "{label}: iterations");
    let residual = v["residual"].as_f64().unwrap();
    let tolerance = if scene.has_walls() {
        scene.contact.tolerance_m
    } else {
        scene.solver.tolerance.unwrap_or(1e-10)
    };
    assert!(residual <= tolerance, "{label}: residual {residual}");
    assert_eq!(v["converged"], Value::Bool(true), "{label}");
    assert!(v["stable"].is_boolean(), "{label}");
    assert!(v["inflections"].as_u64().is_some(), "{label}");
}

fn solve_json(path: &str) -> Value {
    let out = run(&["solve", path, "--json"]);
    assert_eq!(out.status.code(), Some(0), "{path}: {}", stderr(&out));
    assert!(stderr(&out).is_empty(), "{path}: {}", stderr(&out));
    serde_json::from_str(&stdout(&out)).unwrap()
}

#[test]
fn every_example_converges_with_every_field() {
    let scenes = example_scenes();
    assert!(scenes.len() >= 6, "{scenes:?}");
    for path in scenes {
        let label = path.display().to_string();
        let scene = Scene::from_path(&path).unwrap();
        let v = solve_json(&label);
        check_report(&v, &scene, &label);
        assert_eq!(
            v["stable"],
            Value::Bool(true),
            "{label}: examples rest in a minimum"
        );

        let human = run(&["solve", &label]);
        assert_eq!(human.status.code(), Some(0), "{label}");
        let text = stdout(&human);
        assert!(
            text.contains("converged: yes") && text.contains("theta_1"),
            "{text}"
        );
    }
}

#[test]
fn examples_cover_every_profile_and_explicit_values() {
    let mut profiles = Vec::new();
    let mut explicit = false;
    for path in example_scenes() {
        match Scene::from_path(&path).unwrap().stiffness {
            StiffnessSpec::Profile { profile, .. } => profiles.push(profile.name()),
            StiffnessSpec::Values => explicit = true,
        }
    }
    for named in sim_core::StiffnessProfile::NAMED {
        assert!(
            profiles.contains(&named.name()),
            "no example uses {}",
            named.name()
        );
    }
    assert!(explicit, "no example gives values_n_m_per_rad");
}

#[test]
fn pinned_examples_reach_the_shapes_they_name() {
    let c = solve_json(&example("pinned_c.toml"));
    let s = solve_json(&example("pinned_s.toml"));
    assert_eq!(c["inflections"], 0, "C start -> C shape: {c}");
    assert_eq!(s["inflections"], 1, "S start -> S shape: {s}");
    assert!(c["energy_j"].as_f64().unwrap() < s["energy_j"].as_f64().unwrap());
}

#[test]
fn all_minima_lists_stable_equilibria_lowest_energy_first() {
    let path = example("pinned_c.toml");
    let scene = Scene::from_path(std::path::Path::new(&path)).unwrap();
    let out = run(&["solve", &path, "--all-minima", "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let v: Value = serde_json::from_str(&stdout(&out)).unwrap();
    let minima = v.as_array().unwrap();
    assert!(minima.len() >= 2, "{v}");
    for (i, m) in minima.iter().enumerate() {
        check_report(m, &scene, &format!("minimum {i}"));
        assert_eq!(m["stable"], Value::Bool(true));
    }
    let energies: Vec<f64> = minima
        .iter()
        .map(|m| m["energy_j"].as_f64().unwrap())
        .collect();
    assert!(energies.windows(2).all(|w| w[0] <= w[1]), "{energies:?}");
    // The C and S shapes the single solves reach are among them; the C is the lowest.
    let c = solve_json(&path)["energy_j"].as_f64().unwrap();
    let s = solve_json(&example("pinned_s.toml"))["energy_j"]
        .as_f64()
        .unwrap();
    for e in [c, s] {
        assert!(
            energies.iter().any(|m| (m - e).abs() <= 1e-9 * e),
            "{e} in {energies:?}"
        );
    }
    assert!((energies[0] - c).abs() <= 1e-9 * c);

    let human = run(&["solve", &path, "--all-minima"]);
    assert_eq!(human.status.code(), Some(0));
    assert!(
        stdout(&human).contains("stable equilibria found"),
        "{}",
        stdout(&human)
    );
}

#[test]
fn wall_scenes_report_the_settled_posture() {
    let mut walls = 0;
    for path in example_scenes() {
        let scene = Scene::from_path(&path).unwrap();
        if !scene.has_walls() {
            continue;
        }
        walls += 1;
        let label = path.display().to_string();
        let v = solve_json(&label);
        // The posture is step 0 of the sweep, and the tip's force is minus the walls' force
        // on the tip (the distal end of link n) when the tip touches.
        let out = run(&["sweep", &label, "--jsonl", "--duration-s", "0"]);
        assert_eq!(out.status.code(), Some(0), "{label}: {}", stderr(&out));
        let text = stdout(&out);
        let step0: Value = serde_json::from_str(text.lines().nth(1).unwrap()).unwrap();
        assert_eq!(step0["step"], 0);
        assert_eq!(v["theta_rad"], step0["theta_rad"], "{label}");
        assert_eq!(v["joints_m"], step0["joints_m"], "{label}");
        let n = scene.n() as u64;
        let mut on_tip = [0.0, 0.0];
        for c in step0["contacts"].as_array().unwrap() {
            if c["link"] == n && c["kind"] == "vertex" {
                let f = point(&c["force_n"]);
                on_tip = [on_tip[0] + f[0], on_tip[1] + f[1]];
            }
        }
        let force = point(&v["tip_force_n"]);
        assert!(
            (force[0] + on_tip[0]).abs() < 1e-12 && (force[1] + on_tip[1]).abs() < 1e-12,
            "{label}: tip force {force:?}, walls on the tip {on_tip:?}"
        );
        let human = stdout(&run(&["solve", &label]));
        assert!(
            human.contains("placement: ") && human.contains("contacts: "),
            "{human}"
        );
    }
    assert!(walls >= 7, "{walls} example scenes with walls");
    // --all-minima is for scenes without walls.
    let out = run(&["solve", &example("sweep_line_wall.toml"), "--all-minima"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--all-minima searches the equilibria of scenes without walls"));
}
