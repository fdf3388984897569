//! `antenna study`: the grid is the product of the axes, one row per grid point in grid
//! order; `--shard i/n` splits it so that the shards' rows together are the unsharded rows,
//! each grid index exactly once; CSV and JSON lines carry the same rows; bad study files
//! exit 2 naming the key, the line and the column.
#![allow(clippy::unwrap_used)]

mod common;

use std::collections::BTreeMap;

use common::{WALL_SCENE, run, scratch, stderr, stdout};
use serde_json::Value;

/// A study of the short wall scene: 2 profiles x 2 base angles x 2 hair layouts x 2
/// surfaces = 16 sweeps of 5 steps.
fn study_file() -> String {
    let scene = scratch("study_scene.toml", WALL_SCENE);
    let text = format!(
        r#"[study]
scene = "{scene}"
duration_s = 0.05

[axes]
profiles = ["linear", "fast-exponential"]
base_angles_deg = [25.0, 30.0]
hairs = ["none", "distal-without-3"]
surfaces = [{{ surface = "smooth", mu = 0.3 }}, {{ surface = "rough", mu = 0.4, hold_shear_n = 0.05, hold_tension_n = 0.02 }}]
"#
    );
    scratch("study.toml", &text)
}

fn rows(text: &str) -> Vec<Value> {
    text.lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// The rows without the wall-clock time (which differs from run to run).
fn comparable(rows: &[Value]) -> BTreeMap<u64, Value> {
    rows.iter()
        .map(|r| {
            let mut r = r.clone();
            r.as_object_mut().unwrap().remove("wall_clock_ms");
            (r["index"].as_u64().unwrap(), r)
        })
        .collect()
}

#[test]
fn shards_partition_the_grid_exactly() {
    let study = study_file();
    let out = run(&["study", &study, "--format", "jsonl", "--jobs", "2"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let all = rows(&stdout(&out));
    assert_eq!(all.len(), 16);
    let indices: Vec<u64> = all.iter().map(|r| r["index"].as_u64().unwrap()).collect();
    assert_eq!(
        indices,
        (0..16).collect::<Vec<_>>(),
        "rows come in grid order"
    );
    assert!(
        stderr(&out)
            .contains("16 grid points (2 profiles x 2 base angles x 2 hair layouts x 2 surfaces)")
    );

    // The last axis varies fastest.
    assert_eq!(all[0]["profile"], "linear");
    assert_eq!(all[0]["base_angle_deg"], 25.0);
    assert_eq!(all[0]["hairs"], "none");
    assert_eq!(all[0]["surface"], "smooth mu=0.3");
    assert_eq!(
        all[1]["surface"],
        "rough mu=0.4 hold_shear_n=0.05 hold_tension_n=0.02"
    );
    assert_eq!(all[2]["hairs"], "distal-without-3");
    assert_eq!(all[4]["base_angle_deg"], 30.0);
    assert_eq!(all[8]["profile"], "fast-exponential");
    for r in &all {
        assert_eq!(r["status"], "ok", "{r}");
        assert_eq!(r["steps"], 5);
        assert!(r["preview_mean_m"].is_number(), "{r}");
        assert!(r["flipped"].is_boolean() && r["snaps"].is_u64() && r["wall_clock_ms"].is_number());
        let d = r["wall_distance_m"].as_f64().unwrap();
        assert!((d - 0.2 * 8f64.to_radians().cos()).abs() < 1e-12, "{d}");
    }

    let mut union = Vec::new();
    for i in 1..=3 {
        let shard = format!("{i}/3");
        let out = run(&[
            "study", &study, "--format", "jsonl", "--shard", &shard, "-j", "1",
        ]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        let part = rows(&stdout(&out));
        for r in &part {
            assert_eq!(
                r["index"].as_u64().unwrap() % 3,
                i - 1,
                "shard {shard}: {r}"
            );
        }
        union.extend(part);
    }
    assert_eq!(union.len(), 16, "each grid point once");
    assert_eq!(
        comparable(&union),
        comparable(&all),
        "the shards' rows are the grid's rows"
    );
}

#[test]
fn csv_has_the_header_and_the_same_rows() {
    let study = study_file();
    let out = run(&["study", &study, "--shard", "2/5"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        &header[..8],
        [
            "index",
            "profile",
            "base_angle_deg",
            "wall_distance_m",
            "hairs",
            "surface",
            "status",
            "error"
        ]
    );
    assert!(header.contains(&"preview_median_m") && header.contains(&"mapping_mean_error_mm"));
    let rows: Vec<&str> = lines.collect();
    let indices: Vec<&str> = rows.iter().map(|r| r.split(',').next().unwrap()).collect();
    assert_eq!(indices, ["1", "6", "11"]);
    for r in &rows {
        assert_eq!(r.split(',').count(), header.len(), "{r}");
        assert!(r.contains(",ok,,"), "status ok, no error: {r}");
    }
    // --output writes the same to a file.
    let file = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("antenna-cli-tests/rows.csv");
    let out = run(&[
        "study",
        &study,
        "--shard",
        "2/5",
        "-o",
        file.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(stdout(&out).is_empty());
    let written = std::fs::read_to_string(&file).unwrap();
    assert_eq!(written.lines().count(), 4);
}

#[test]
fn bad_study_files_name_the_key() {
    let scene = scratch("study_scene_bad.toml", WALL_SCENE);
    let cases = [
        (
            format!("[study]\nscene = \"{scene}\"\n[axes]\nprofile = [\"linear\"]\n"),
            ":4:1: unknown key `profile` in [axes]; allowed: profiles, base_angles_deg, wall_distances_m, hairs, surfaces, speeds_m_per_s, kp_n, kd_n_s, kp_rad_per_s_per_m, kd_rad_per_m, delays_s",
        ),
        (
            format!("[study]\nscene = \"{scene}\"\n[axes]\nprofiles = [\"lin\"]\n"),
            ":4:12: `profiles` in [axes]: unknown stiffness profile name \"lin\"",
        ),
        (
            format!("[study]\nscene = \"{scene}\"\n[axes]\nhairs = [\"distal-without-8\"]\n"),
            ":4:9: `hairs` in [axes]: \"distal-without-8\" leaves no hair",
        ),
        (
            format!("[study]\nscene = \"{scene}\"\n[axes]\nwall_distances_m = [0.1, -0.1]\n"),
            ":4:20: `wall_distances_m` in [axes]: -0.1 m would put the base pivot in the wall",
        ),
        (
            format!("[study]\nscene = \"{scene}\"\n[axes]\nbase_angles_deg = []\n"),
            ":4:19: `base_angles_deg` in [axes]: no values",
        ),
        (
            format!("[study]\nscene = \"{scene}\"\nduration_s = -2.0\n"),
            ":3:14: `duration_s` in [study]: -2 must be >= 0",
        ),
        (
            "[study]\nduration_s = 1.0\n".to_string(),
            ":1:1: missing key `scene` in [study]",
        ),
        (
            format!(
                "[study]\nscene = \"{scene}\"\n[axes]\nsurfaces = [{{ surface = \"rough\" }}]\n"
            ),
            "missing key `hold_shear_n` in [axes] surfaces (entry 0)",
        ),
    ];
    for (i, (text, wanted)) in cases.iter().enumerate() {
        let path = scratch(&format!("bad_study_{i}.toml"), text);
        let out = run(&["study", &path]);
        assert_eq!(out.status.code(), Some(2), "{text}: {}", stderr(&out));
        assert!(stdout(&out).is_empty());
        let err = stderr(&out);
        assert!(
            err.contains(&format!("{path}{wanted}")) || err.contains(wanted),
            "{text}: {err}"
        );
    }
    // The base scene's own errors name the scene file.
    let broken = scratch(
        "study_scene_broken.toml",
        &WALL_SCENE.replace("links = 9", "links = 1"),
    );
    let path = scratch(
        "bad_study_scene.toml",
        &format!("[study]\nscene = \"{broken}\"\n"),
    );
    let out = run(&["study", &path]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains(&format!("{broken}:2:9: `links` in [antenna]")),
        "{}",
        stderr(&out)
    );
    let out = run(&["study", &study_file(), "--shard", "4/3"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn the_example_study_parses_into_its_grid() {
    let study =
        antenna_cli::study::Study::from_path(&common::examples_dir().join("studies/profiles.toml"))
            .unwrap();
    assert_eq!(study.len(), 14);
    assert_eq!(study.scene.motion.duration_s, 50.0);
    assert_eq!(study.bounds, Some((0.004, 0.082)));
}
