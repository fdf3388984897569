//! A polyline wall's `points_file` (issue #14): a CSV file of `x_m,y_m` points, read relative
//! to the scene's folder, makes the same wall as its points given as `vertices_m`, with or
//! without a header, with CRLF line ends, spaces and trailing empty lines. Every bad file
//! exits 2 under `antenna solve` and `antenna sweep` with nothing on stdout and a message
//! naming the scene's `points_file` key (file, line and column), the points file and the
//! line in it. The committed `examples/walls/trapezoid_10k.csv` is what its generator writes.
#![allow(clippy::unwrap_used)]

mod common;

use std::path::{Path, PathBuf};

use antenna_cli::digitize::{TRAPEZOID_10K, digitize, points_csv, sample_edges};
use antenna_scene::Scene;
use common::{WALL_SCENE, examples_dir, run, stderr, stdout};
use serde_json::Value;
use sim_core::WallShape;

/// The thesis's trapezoid (`examples/wall_polyline.toml`) as `vertices_m`.
const TRAPEZOID_VERTICES: &str =
    "[[0.0, 0.2], [0.25, 0.2], [0.35, 0.14], [0.55, 0.14], [0.65, 0.2], [1.0, 0.2]]";

/// The same points as a points file with a header.
const TRAPEZOID_CSV: &str = "x_m,y_m\n0.0,0.2\n0.25,0.2\n0.35,0.14\n0.55,0.14\n0.65,0.2\n1.0,0.2\n";

/// A fresh, empty folder for one case.
fn folder(case: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("antenna-cli-points-file")
        .join(case);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `WALL_SCENE` with its line wall made a polyline with `keys` (from line 13 on).
fn polyline_scene(keys: &str) -> String {
    WALL_SCENE.replace(
        "shape = \"line\"\npoint_m = [0.0, 0.2]\nangle_deg = -8.0",
        &format!("shape = \"polyline\"\n{keys}"),
    )
}

/// Writes `scene` as `scene.toml` and, when given, `csv` as `walls/points.csv` into a fresh
/// folder for `case`; returns the scene's and the points file's paths.
fn write_case(case: &str, scene: &str, csv: Option<&str>) -> (String, String) {
    let dir = folder(case);
    let scene_path = dir.join("scene.toml");
    std::fs::write(&scene_path, scene).unwrap();
    let csv_path = dir.join("walls").join("points.csv");
    if let Some(csv) = csv {
        std::fs::create_dir_all(dir.join("walls")).unwrap();
        std::fs::write(&csv_path, csv).unwrap();
    }
    (
        scene_path.display().to_string(),
        csv_path.display().to_string(),
    )
}

/// Runs the scene through `solve --json` and `sweep --jsonl`, checks the bad-input contract
/// of both, and returns the message.
fn bad(case: &str, scene_path: &str) -> String {
    let mut message = String::new();
    for args in [
        vec!["solve", scene_path, "--json"],
        vec!["sweep", scene_path, "--jsonl"],
    ] {
        let out = run(&args);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{case} {args:?}: {}",
            stderr(&out)
        );
        assert!(stdout(&out).is_empty(), "{case}: stdout {}", stdout(&out));
        message = stderr(&out);
    }
    message
}

/// The points file's key in the scene of [`polyline_scene`]: line 13, its value at column 15.
const KEY_AT: &str = "13:15: `points_file` in [[walls]] (wall 0)";

/// A points file `csv` that fails with `wanted` at `line` of the file.
fn bad_file(case: &str, csv: &str, line: usize, wanted: &str) {
    let scene = polyline_scene("points_file = \"walls/points.csv\"");
    let (scene_path, csv_path) = write_case(case, &scene, Some(csv));
    let err = bad(case, &scene_path);
    let expected = format!("{scene_path}:{KEY_AT}: {csv_path}:{line}: {wanted}");
    assert!(err.contains(&expected), "{case}: {err}\nwanted: {expected}");
}

#[test]
fn a_points_file_is_the_same_wall_as_its_vertices() {
    let reference = Scene::parse(
        &polyline_scene(&format!("vertices_m = {TRAPEZOID_VERTICES}")),
        "s.toml",
    )
    .unwrap();
    let crlf_spaces = TRAPEZOID_CSV
        .lines()
        .skip(1)
        .map(|l| format!("  {} \r\n", l.replace(',', " ,\t")))
        .collect::<String>()
        + "\r\n  \r\n";
    for (case, csv) in [
        ("header", TRAPEZOID_CSV.to_string()),
        ("no_header_crlf", crlf_spaces),
        ("no_final_line_end", TRAPEZOID_CSV.trim_end().to_string()),
    ] {
        let scene = polyline_scene("points_file = \"walls/points.csv\"");
        let (scene_path, _) = write_case(case, &scene, Some(&csv));
        let read = Scene::from_path(Path::new(&scene_path)).unwrap();
        assert_eq!(read.walls, reference.walls, "{case}");
        assert!(
            matches!(&read.walls[0].shape, WallShape::Polyline(p) if p.vertices_m().len() == 6),
            "{case}"
        );
    }
    // Through the command: the same posture and the same sweep as with `vertices_m`.
    let (by_vertices, _) = write_case(
        "vertices",
        &polyline_scene(&format!("vertices_m = {TRAPEZOID_VERTICES}")),
        None,
    );
    let (by_file, _) = write_case(
        "file",
        &polyline_scene("points_file = \"walls/points.csv\""),
        Some(TRAPEZOID_CSV),
    );
    for args in [&["solve", "--json"][..], &["sweep", "--jsonl"][..]] {
        let outputs: Vec<Vec<Value>> = [&by_vertices, &by_file]
            .iter()
            .map(|path| {
                let out = run(&[args[0], path, args[1]]);
                assert_eq!(out.status.code(), Some(0), "{args:?}: {}", stderr(&out));
                let text = stdout(&out);
                // `solve --json` prints one object over several lines, `sweep --jsonl` one
                // object a line.
                let objects: Vec<&str> = if args[0] == "solve" {
                    vec![text.as_str()]
                } else {
                    text.lines().collect()
                };
                objects
                    .into_iter()
                    .map(|line| {
                        let mut v: Value = serde_json::from_str(line).unwrap();
                        // The sweep's lines name the scene and time the run.
                        if let Some(object) = v.as_object_mut() {
                            object.remove("scene");
                            object.remove("wall_clock_ms");
                        }
                        v
                    })
                    .collect()
            })
            .collect();
        assert_eq!(outputs[0], outputs[1], "{args:?}");
    }
}

#[test]
fn bad_points_files_name_the_file_and_the_line() {
    bad_file(
        "empty",
        "",
        1,
        "the file is empty; a points file has one `x_m,y_m` point per line",
    );
    bad_file("blank", "\r\n  \n", 1, "the file is empty");
    bad_file(
        "one_point",
        "x_m,y_m\n0.0,0.2\n",
        2,
        "1 point(s) in the file; a polyline needs at least 2",
    );
    bad_file(
        "header_only",
        "x_m,y_m\n",
        1,
        "0 point(s) in the file; a polyline needs at least 2",
    );
    bad_file(
        "nan",
        "x_m,y_m\n0.0,0.2\n0.25,0.2\nnan,0.14\n",
        4,
        "`x_m` is NaN; every coordinate is a finite number of metres",
    );
    bad_file(
        "infinite",
        "0.0,0.2\n0.25,1e999\n",
        2,
        "`y_m` is inf; every coordinate is a finite number of metres",
    );
    bad_file(
        "not_a_number",
        "x_m,y_m\n0.0,0.2\n0.25,0.2\n0.35,0.14\n0.55o,0.14\n",
        5,
        "`x_m` is \"0.55o\", not a number",
    );
    bad_file(
        "three_fields",
        "x_m,y_m\n0.0,0.2\n0.25,0.2,0.0\n",
        3,
        "3 field(s); expected 2 (`x_m,y_m`)",
    );
    bad_file(
        "one_field",
        "x_m,y_m\n0.0,0.2\n0.25\n",
        3,
        "1 field(s); expected 2 (`x_m,y_m`)",
    );
    bad_file(
        "empty_line",
        "x_m,y_m\n0.0,0.2\n\n0.25,0.2\n",
        3,
        "an empty line between points",
    );
    bad_file(
        "repeated_point",
        "x_m,y_m\n0.0,0.2\n0.25,0.2\n0.25,0.2\n1.0,0.2\n",
        4,
        "the same point as line 3; consecutive points must differ",
    );
    bad_file(
        "doubles_back",
        "x_m,y_m\n0.0,0.2\n0.5,0.2\n0.3,0.2\n",
        3,
        "the polyline doubles back on itself at this point (lines 2 and 4 lie in the same \
         direction from it)",
    );
    // The edge from (0.3, 0.1) up to (0.3, 0.3) crosses the edge along y = 0.2.
    bad_file(
        "crossing",
        "x_m,y_m\n0.0,0.2\n0.1,0.2\n0.4,0.2\n0.4,0.1\n0.3,0.1\n0.3,0.3\n1.0,0.3\n",
        3,
        "the polyline crosses itself: the edge from line 3 to line 4 meets the edge from line \
         6 to line 7",
    );
    // The first edge runs on backward: the last edge crossing it back there.
    bad_file(
        "crossing_ray",
        "0.0,0.2\n0.1,0.2\n0.1,0.3\n-0.5,0.3\n-0.5,0.1\n",
        1,
        "the polyline crosses itself: the edge from line 1 to line 2 (run on backward past \
         line 1) meets the edge from line 4 to line 5 (run on past line 5)",
    );
}

#[test]
fn a_missing_points_file_names_the_resolved_path_and_the_key() {
    let scene = polyline_scene("points_file = \"walls/points.csv\"");
    let (scene_path, csv_path) = write_case("missing", &scene, None);
    let err = bad("missing", &scene_path);
    assert!(
        err.contains(&format!(
            "{scene_path}:{KEY_AT}: {csv_path}: cannot read the points file:"
        )),
        "{err}"
    );
}

#[test]
fn points_file_key_errors() {
    let case = |case: &str, scene: &str, wanted: &str| {
        let (scene_path, _) = write_case(case, scene, Some(TRAPEZOID_CSV));
        let err = bad(case, &scene_path);
        assert!(
            err.contains(&format!("{scene_path}:{wanted}")),
            "{case}: {err}"
        );
    };
    case(
        "both",
        &polyline_scene(&format!(
            "vertices_m = {TRAPEZOID_VERTICES}\npoints_file = \"walls/points.csv\""
        )),
        "14:15: `points_file` and `vertices_m` in [[walls]] (wall 0) exclude each other; give \
         one of them",
    );
    case(
        "neither",
        &polyline_scene(""),
        "11:1: missing key `vertices_m` or `points_file` in [[walls]] (wall 0)",
    );
    case(
        "line",
        &WALL_SCENE.replace(
            "angle_deg = -8.0",
            "angle_deg = -8.0\npoints_file = \"walls/points.csv\"",
        ),
        "15:15: `points_file` in [[walls]] (wall 0): not a key of a line wall (it takes \
         point_m, angle_deg)",
    );
    case(
        "sinusoid",
        &WALL_SCENE
            .replace("shape = \"line\"", "shape = \"sinusoid\"")
            .replace(
                "angle_deg = -8.0",
                "amplitude_m = 0.01\nfrequency_per_m = 5.0\npoints_file = \"walls/points.csv\"",
            ),
        "16:15: `points_file` in [[walls]] (wall 0): not a key of a sinusoid wall (it takes \
         point_m, angle_deg, amplitude_m, frequency_per_m, phase_deg)",
    );
    case(
        "type",
        &polyline_scene("points_file = 3"),
        "13:15: `points_file` in [[walls]] (wall 0):",
    );
}

#[test]
fn the_committed_trapezoid_is_what_the_generator_writes() {
    let trapezoid_scene = Scene::from_path(&examples_dir().join("wall_polyline.toml")).unwrap();
    let WallShape::Polyline(trapezoid) = &trapezoid_scene.walls[0].shape else {
        panic!("{:?}", trapezoid_scene.walls[0].shape)
    };
    let points_m = digitize(
        trapezoid.vertices_m(),
        trapezoid.solid_side(),
        &TRAPEZOID_10K,
    )
    .unwrap();
    let committed =
        std::fs::read_to_string(examples_dir().join("walls/trapezoid_10k.csv")).unwrap();
    // (A checkout that turns line ends into CRLF reads the same points.)
    assert!(
        committed.replace("\r\n", "\n") == points_csv(&points_m),
        "examples/walls/trapezoid_10k.csv is not what `cargo run -p antenna-cli --example \
         digitize_trapezoid` writes: regenerate it"
    );

    // The example scene reads it: 10,000 points within 0.5 mm of the trapezoid, and
    // everything else as in wall_polyline.toml.
    let digitized = Scene::from_path(&examples_dir().join("wall_digitized.toml")).unwrap();
    let WallShape::Polyline(wall) = &digitized.walls[0].shape else {
        panic!("{:?}", digitized.walls[0].shape)
    };
    assert_eq!(wall.vertices_m(), points_m.as_slice());
    assert_eq!(wall.vertices_m().len(), 10_000);
    assert_eq!(wall.solid_side(), trapezoid.solid_side());
    let farthest_m = wall
        .vertices_m()
        .iter()
        .map(|p| trapezoid.signed_distance(p).gap_m.abs())
        .fold(0.0, f64::max);
    assert!(farthest_m < 5e-4, "{farthest_m} m");
    assert!(farthest_m > 2e-4, "the noise is there: {farthest_m} m");
    assert_eq!(
        digitized.walls[0].surfaces,
        trapezoid_scene.walls[0].surfaces
    );
    assert_eq!(digitized.chain, trapezoid_scene.chain);
    assert_eq!(digitized.motion, trapezoid_scene.motion);
    assert_eq!(digitized.placement, trapezoid_scene.placement);
    assert_eq!(digitized.contact, trapezoid_scene.contact);
}

/// The noiseless samplings of the trapezoid (issue #49's finely sampled walls) are what
/// `digitize_trapezoid --per-edge N` writes, their scenes read them, and every point lies on
/// the trapezoid to within the nanometre rounding, its six vertices among them.
#[test]
fn the_committed_sampled_trapezoids_are_what_the_generator_writes() {
    let trapezoid_scene = Scene::from_path(&examples_dir().join("wall_polyline.toml")).unwrap();
    let WallShape::Polyline(trapezoid) = &trapezoid_scene.walls[0].shape else {
        panic!("{:?}", trapezoid_scene.walls[0].shape)
    };
    for per_edge in [2000, 1999] {
        let points_m =
            sample_edges(trapezoid.vertices_m(), trapezoid.solid_side(), per_edge).unwrap();
        assert_eq!(points_m.len(), 5 * per_edge + 1);
        let file = format!("walls/trapezoid_{per_edge}_per_edge.csv");
        let committed = std::fs::read_to_string(examples_dir().join(&file)).unwrap();
        assert!(
            committed.replace("\r\n", "\n") == points_csv(&points_m),
            "examples/{file} is not what `cargo run -p antenna-cli --example \
             digitize_trapezoid -- --per-edge {per_edge}` writes: regenerate it"
        );
        let scene = Scene::from_path(&examples_dir().join(format!("wall_sampled_{per_edge}.toml")))
            .unwrap();
        let WallShape::Polyline(wall) = &scene.walls[0].shape else {
            panic!("{:?}", scene.walls[0].shape)
        };
        assert_eq!(wall.vertices_m(), points_m.as_slice());
        for v in trapezoid.vertices_m() {
            assert!(wall.vertices_m().contains(v), "vertex {v:?} kept exactly");
        }
        let farthest_m = wall
            .vertices_m()
            .iter()
            .map(|p| trapezoid.signed_distance(p).gap_m.abs())
            .fold(0.0, f64::max);
        assert!(farthest_m < 1e-9, "{farthest_m} m off the trapezoid");
        assert_eq!(scene.chain, trapezoid_scene.chain);
        assert_eq!(scene.motion, trapezoid_scene.motion);
        assert_eq!(scene.placement, trapezoid_scene.placement);
        assert_eq!(scene.contact, trapezoid_scene.contact);
    }
}
