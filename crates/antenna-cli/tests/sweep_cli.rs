//! `antenna sweep`: the JSON lines (a placement line, one line per step with every
//! documented field of the right type, a summary line), the human summary, the plots (an
//! SVG with the chain, the walls and the panels' labels; a PNG with its signature), and the
//! exit statuses of bad input and of a pinned scene.
#![allow(clippy::unwrap_used)]

mod common;

use common::{WALL_SCENE, run, scratch, stderr, stdout};
use serde_json::Value;

/// The JSON type a documented field must have.
#[derive(Clone, Copy, Debug)]
enum Kind {
    Int,
    Num,
    Bool,
    Str,
    Point,
    Nums,
    Points,
    Ints,
    OptInt,
    OptNum,
    Array,
    Object,
    OptStr,
}

fn has_kind(v: &Value, kind: Kind) -> bool {
    let point = |p: &Value| {
        p.as_array()
            .is_some_and(|a| a.len() == 2 && a.iter().all(Value::is_f64))
    };
    match kind {
        Kind::Int => v.is_u64(),
        Kind::Num => v.is_number(),
        Kind::Bool => v.is_boolean(),
        Kind::Str => v.is_string(),
        Kind::Point => point(v),
        Kind::Nums => v.as_array().is_some_and(|a| a.iter().all(Value::is_number)),
        Kind::Points => v.as_array().is_some_and(|a| a.iter().all(point)),
        Kind::Ints => v.as_array().is_some_and(|a| a.iter().all(Value::is_u64)),
        Kind::OptInt => v.is_null() || v.is_u64(),
        Kind::OptNum => v.is_null() || v.is_number(),
        Kind::Array => v.is_array(),
        Kind::Object => v.is_object(),
        Kind::OptStr => v.is_null() || v.is_string(),
    }
}

/// Checks that `v` has exactly `fields` with their kinds.
fn check_fields(v: &Value, fields: &[(&str, Kind)], what: &str) {
    let obj = v.as_object().unwrap();
    for (name, kind) in fields {
        let value = obj
            .get(*name)
            .unwrap_or_else(|| panic!("{what}: no `{name}` in {v}"));
        assert!(
            has_kind(value, *kind),
            "{what}: `{name}` = {value} is not {kind:?}"
        );
    }
    assert_eq!(
        obj.len(),
        fields.len(),
        "{what}: exactly the documented fields: {v}"
    );
}

const PLACEMENT_FIELDS: &[(&str, Kind)] = &[
    ("type", Kind::Str),
    ("scene", Kind::Str),
    ("note", Kind::Str),
    ("links", Kind::Int),
    ("walls", Kind::Int),
    ("steps", Kind::Int),
    ("step_s", Kind::Num),
    ("duration_s", Kind::Num),
    ("velocity_m_per_s", Kind::Point),
];

const STEP_FIELDS: &[(&str, Kind)] = &[
    ("type", Kind::Str),
    ("step", Kind::Int),
    ("t_s", Kind::Num),
    ("base_m", Kind::Point),
    ("wall_distance_m", Kind::OptNum),
    ("theta_rad", Kind::Nums),
    ("joints_m", Kind::Points),
    ("hair_angles_rad", Kind::Nums),
    ("contacts", Kind::Array),
    ("bend_joint", Kind::OptInt),
    ("contact_joint", Kind::OptInt),
    ("preview_m", Kind::OptNum),
    ("flipped", Kind::Bool),
    ("distal_angle_to_wall_rad", Kind::OptNum),
    ("touch_bits", Kind::Ints),
    ("mapping_points", Kind::Int),
    ("mapping_points_m", Kind::Points),
    ("mapping_error_mm", Kind::OptNum),
    ("snapped", Kind::Bool),
    ("substeps", Kind::Int),
    ("snap_steps", Kind::Int),
    ("iterations", Kind::Int),
    ("residual_m", Kind::Num),
    ("relaxations", Kind::Array),
    ("certificate", Kind::Object),
];

const CERTIFICATE_FIELDS: &[(&str, Kind)] = &[
    ("torque_residual_nm", Kind::Num),
    ("limit_sign_violation_nm", Kind::Num),
    ("penetration_m", Kind::Num),
    ("cone_violation_n", Kind::Num),
    ("separation_m", Kind::Num),
    ("stuck_slip_m", Kind::Num),
    ("slip_force_violation_n", Kind::Num),
    ("wrong_way_slip_m", Kind::Num),
];

const CONTACT_FIELDS: &[(&str, Kind)] = &[
    ("link", Kind::Int),
    ("kind", Kind::Str),
    ("wall", Kind::Int),
    ("s", Kind::Num),
    ("point_m", Kind::Point),
    ("normal_force_n", Kind::Num),
    ("shear_force_n", Kind::Num),
    ("force_n", Kind::Point),
    ("state", Kind::Str),
    ("relaxed_shear_bound_n", Kind::OptNum),
    ("anchored", Kind::Bool),
    ("slip_m", Kind::Num),
];

const SUMMARY_FIELDS: &[(&str, Kind)] = &[
    ("type", Kind::Str),
    ("steps", Kind::Int),
    ("sweep_time_s", Kind::Num),
    ("wall_clock_ms", Kind::Num),
    ("steps_with_contact", Kind::Int),
    ("mean_contacts", Kind::Num),
    ("max_contacts", Kind::Int),
    ("snaps", Kind::Int),
    ("flipped_at_start", Kind::Bool),
    ("flips", Kind::Int),
    ("first_flip_t_s", Kind::OptNum),
    ("flipped_at_end", Kind::Bool),
    ("preview_mean_m", Kind::OptNum),
    ("preview_median_m", Kind::OptNum),
    ("bend_distance_pearson", Kind::OptNum),
    ("bend_distance_spearman", Kind::OptNum),
    ("contact_distance_pearson", Kind::OptNum),
    ("contact_distance_spearman", Kind::OptNum),
    ("mapping_points", Kind::Int),
    ("mapping_mean_error_mm", Kind::OptNum),
    ("mapping_max_error_mm", Kind::OptNum),
    ("mapping_coverage_error_mm", Kind::OptNum),
    ("mapping_coverage_p90_mm", Kind::OptNum),
    ("mapping_completeness", Kind::OptNum),
    ("substeps", Kind::Int),
    ("iterations", Kind::Int),
    ("iterations_median", Kind::OptInt),
    ("iterations_p99", Kind::OptInt),
    ("relaxed_steps", Kind::Int),
    ("friction_dropped_steps", Kind::Int),
    ("jammed_contacts", Kind::Int),
    ("anchors_released", Kind::Int),
    ("residual_above_tolerance_steps", Kind::Int),
    ("max_torque_residual_nm", Kind::Num),
    ("max_penetration_m", Kind::Num),
    ("outcome", Kind::Str),
    ("stopped_by", Kind::OptStr),
];

#[test]
fn jsonl_has_a_placement_line_one_line_per_step_and_a_summary() {
    let path = scratch("sweep_jsonl.toml", WALL_SCENE);
    let out = run(&["sweep", &path, "--jsonl"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(
        stderr(&out).is_empty(),
        "no progress bar off a terminal: {}",
        stderr(&out)
    );
    let lines: Vec<Value> = stdout(&out)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    // 0.2 s at 0.01 s: the placement line, steps 0..=20, the summary.
    assert_eq!(lines.len(), 1 + 21 + 1);

    let head = &lines[0];
    check_fields(head, PLACEMENT_FIELDS, "placement");
    assert_eq!(head["type"], "placement");
    assert_eq!(head["scene"], path.as_str());
    assert!(
        head["note"]
            .as_str()
            .unwrap()
            .starts_with("tip placed on wall 0"),
        "{head}"
    );
    assert_eq!(
        (head["links"].as_u64(), head["walls"].as_u64()),
        (Some(9), Some(1))
    );
    assert_eq!(head["steps"], 20);

    let mut contacts = 0;
    for (k, line) in lines[1..lines.len() - 1].iter().enumerate() {
        check_fields(line, STEP_FIELDS, &format!("step line {k}"));
        check_fields(
            &line["certificate"],
            CERTIFICATE_FIELDS,
            &format!("step line {k}: certificate"),
        );
        assert!(
            line["relaxations"]
                .as_array()
                .is_some_and(|a| a.iter().all(Value::is_string)),
            "step line {k}: relaxations"
        );
        assert_eq!(line["type"], "step");
        assert_eq!(line["step"].as_u64(), Some(k as u64));
        let t = line["t_s"].as_f64().unwrap();
        assert!((t - 0.01 * k as f64).abs() < 1e-9, "t_s {t}");
        let base = &line["base_m"];
        assert!(
            (base[0].as_f64().unwrap() - 0.0167 * t).abs() < 1e-9,
            "{base}"
        );
        assert_eq!(line["theta_rad"].as_array().unwrap().len(), 9);
        assert_eq!(line["joints_m"].as_array().unwrap().len(), 9);
        assert_eq!(line["hair_angles_rad"].as_array().unwrap().len(), 9);
        assert_eq!(line["touch_bits"].as_array().unwrap().len(), 9);
        // The base pivot's distance to the 8-degree wall through (0, 0.2).
        let d = line["wall_distance_m"].as_f64().unwrap();
        let x = base[0].as_f64().unwrap();
        let expected = (0.2 - x * 8f64.to_radians().tan()) * 8f64.to_radians().cos();
        assert!(
            (d - expected).abs() < 1e-9,
            "wall distance {d} vs {expected}"
        );
        for c in line["contacts"].as_array().unwrap() {
            check_fields(c, CONTACT_FIELDS, "contact");
            assert!(["vertex", "link", "hair"].contains(&c["kind"].as_str().unwrap()));
            assert!(
                ["stuck", "slipping-forward", "slipping-backward"]
                    .contains(&c["state"].as_str().unwrap())
            );
            assert!(c["normal_force_n"].as_f64().unwrap() >= 0.0);
            let mu_n = 0.3 * c["normal_force_n"].as_f64().unwrap();
            assert!(
                c["shear_force_n"].as_f64().unwrap().abs() <= mu_n + 1e-9,
                "{c}"
            );
            contacts += 1;
        }
        if !line["contacts"].as_array().unwrap().is_empty() {
            assert!(line["preview_m"].is_number() && line["contact_joint"].is_u64());
        }
    }
    assert!(contacts > 0, "the antenna touches the wall");

    let summary = lines.last().unwrap();
    check_fields(summary, SUMMARY_FIELDS, "summary");
    assert_eq!(summary["outcome"], "finished");
    assert_eq!(summary["stopped_by"], Value::Null);
    assert_eq!(summary["type"], "summary");
    assert_eq!(summary["steps"], 20);
    assert!((summary["sweep_time_s"].as_f64().unwrap() - 0.2).abs() < 1e-9);
    assert_eq!(summary["steps_with_contact"], 21);
}

#[test]
fn the_human_summary_names_every_metric() {
    let path = scratch("sweep_human.toml", WALL_SCENE);
    let out = run(&["sweep", &path]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    for needle in [
        "9 links (8 flexible joints), 1 wall(s), 20 steps of 0.01 s",
        "placement: tip placed on wall 0",
        "20 steps, 0.200 s swept in",
        "contacts: 21 of 21 steps touch a wall",
        "snaps: ",
        "flips: 0",
        "preview distance: mean ",
        "correlation with the base-to-wall distance: point of bend ",
        "mapping from sensed angles and touch bits: ",
    ] {
        assert!(text.contains(needle), "no {needle:?} in\n{text}");
    }
    // --duration-s shortens the sweep.
    let out = run(&["sweep", &path, "--duration-s", "0.05", "--jsonl"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert_eq!(stdout(&out).lines().count(), 1 + 6 + 1);
}

#[test]
fn plots_are_svg_with_the_figure_or_png() {
    let path = scratch("sweep_plot.toml", WALL_SCENE);
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("antenna-cli-tests");
    let svg = dir.join("sweep_plot.svg");
    let png = dir.join("sweep_plot.png");
    for file in [&svg, &png] {
        let _ = std::fs::remove_file(file);
        let out = run(&[
            "sweep",
            &path,
            "--plot",
            file.to_str().unwrap(),
            "--plot-every",
            "5",
        ]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        assert!(stdout(&out).contains(&format!("plot: {}", file.display())));
    }
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(
        text.starts_with("<svg") && text.trim_end().ends_with("</svg>"),
        "{}",
        &text[..80]
    );
    for needle in [
        "sweep_plot.toml (20 steps, 0.2 s)",
        "x (m)",
        "y (m)",
        "preview (mm)",
        "point of bend",
        "point of contact",
        "distal angle to wall (deg)",
        "flip threshold (90 deg)",
        "chain (every 5 steps; the last bold)",
        "<polyline",
        "<circle",
    ] {
        assert!(text.contains(needle), "no {needle:?} in the SVG");
    }
    // Five snapshots (steps 0, 5, 10, 15, 20) and the bold last one, in the chain's colour.
    let chain = text.matches("stroke=\"#005AC8\"").count();
    assert!(chain >= 6, "{chain} chain polylines");
    let bytes = std::fs::read(&png).unwrap();
    assert!(bytes.len() > 10_000, "{} bytes", bytes.len());
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");

    let out = run(&["sweep", &path, "--plot", "figure.pdf"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--plot figure.pdf: the file name must end in .svg or .png"));
}

#[test]
fn bad_input_exits_2_with_the_file_and_the_key() {
    // The rest posture reaches through a wall 0.1 m away: the placement says so.
    let rest = WALL_SCENE
        .replace("point_m = [0.0, 0.2]", "point_m = [0.0, 0.1]")
        .replace(
            "placement = \"tip-on-wall\"\nahead_m = 0.0\nshape = \"C\"",
            "placement = \"rest\"",
        );
    let path = scratch("sweep_rest_in_wall.toml", &rest);
    for args in [
        vec!["sweep", &path, "--jsonl"],
        vec!["solve", &path, "--json"],
    ] {
        let out = run(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stdout(&out).is_empty());
        let err = stderr(&out);
        assert!(
            err.contains(&format!(
                "{path}:23:13: `placement` in [start]: the start posture puts link"
            )),
            "{err}"
        );
    }
    // A pinned scene cannot be swept.
    let pinned = common::example("pinned_c.toml");
    let out = run(&["sweep", &pinned]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains(&format!(
            "{pinned}:27:14: `position_m` in [tip_pin]: a sweep moves the base and cannot hold \
             the tip on a fixed pin"
        )),
        "{}",
        stderr(&out)
    );
    let out = run(&["sweep", "/nonexistent.toml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("/nonexistent.toml: cannot read the scene file"));
    let out = run(&["sweep", &path, "--duration-s", "-1"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--duration-s -1: must be finite, >= 0"));
}

/// The four bad scenes of issue #13: a wall through the base, a placement inside a wall, a
/// NaN in a scene, a negative friction coefficient. Each is a located error with exit status
/// 2, nothing on stdout and no plot written, from `sweep` (with `--jsonl` and `--plot`) and
/// from `solve`.
#[test]
fn bad_scenes_are_located_exit_2_and_write_nothing() {
    let rest = "placement = \"rest\"";
    let tip_on_wall = "placement = \"tip-on-wall\"\nahead_m = 0.0\nshape = \"C\"";
    let cases: [(&str, String, String); 4] = [
        (
            "bad_wall_base",
            WALL_SCENE.replace("point_m = [0.0, 0.2]", "point_m = [0.0, 0.01]"),
            ":11:1: [[walls]] (wall 0): wall 0 crosses the base link".to_owned(),
        ),
        (
            "bad_inside",
            WALL_SCENE
                .replace("point_m = [0.0, 0.2]", "point_m = [0.0, 0.1]")
                .replace(tip_on_wall, rest),
            ":23:13: `placement` in [start]: the start posture puts link".to_owned(),
        ),
        (
            "bad_nan",
            WALL_SCENE.replace("angle_deg = -8.0", "angle_deg = nan"),
            ":14:13: `angle_deg` in [[walls]] (wall 0): NaN is not a finite number".to_owned(),
        ),
        (
            "bad_mu",
            WALL_SCENE.replace("solid = \"left\"", "solid = \"left\"\nmu = -0.3"),
            ":16:6: `mu` in [[walls]] (wall 0): -0.3 must be >= 0".to_owned(),
        ),
    ];
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("antenna-cli-tests");
    for (name, text, expected) in cases {
        assert_ne!(text, WALL_SCENE, "{name}: the scene was not changed");
        let path = scratch(&format!("{name}.toml"), &text);
        let plot = dir.join(format!("{name}.svg"));
        let _ = std::fs::remove_file(&plot);
        let plot_arg = plot.display().to_string();
        for args in [
            vec!["sweep", &path, "--jsonl", "--plot", &plot_arg],
            vec!["solve", &path, "--json"],
        ] {
            let out = run(&args);
            let err = stderr(&out);
            assert_eq!(out.status.code(), Some(2), "{name} {args:?}: {err}");
            assert!(stdout(&out).is_empty(), "{name} {args:?}: {}", stdout(&out));
            assert!(
                err.contains(&format!("{path}{expected}")),
                "{name} {args:?}: expected `{path}{expected}` in: {err}"
            );
            assert!(!plot.exists(), "{name}: a plot was written");
        }
    }
}

#[test]
fn help_has_examples() {
    for cmd in ["sweep", "study"] {
        let out = run(&[cmd, "--help"]);
        assert_eq!(out.status.code(), Some(0));
        assert!(
            stdout(&out).contains("Examples:"),
            "{cmd}: {}",
            stdout(&out)
        );
    }
}
