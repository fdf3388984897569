//! Writes the digitized walls of the examples: `examples/walls/trapezoid_10k.csv` (the wall
//! of `examples/wall_digitized.toml`: the trapezoid of `examples/wall_polyline.toml`, thesis
//! 4.2.2, sampled at 10,000 points along its arclength with 0.1 mm of Gaussian noise normal
//! to it, from a fixed seed, [`antenna_cli::digitize::TRAPEZOID_10K`]), and with
//! `--per-edge N` the same trapezoid sampled with no noise, `N` points on each of its five
//! edges ([`antenna_cli::digitize::sample_edges`]: `examples/walls/trapezoid_2000_per_edge.csv`
//! and `trapezoid_1999_per_edge.csv`, the walls of `examples/wall_sampled_2000.toml` and
//! `examples/wall_sampled_1999.toml`).
//!
//! ```sh
//! cargo run -p antenna-cli --example digitize_trapezoid                     # the noisy file
//! cargo run -p antenna-cli --example digitize_trapezoid -- out.csv          # elsewhere
//! cargo run -p antenna-cli --example digitize_trapezoid -- --per-edge 2000  # a noiseless one
//! ```
//!
//! The CLI's tests `the_committed_trapezoid_is_what_the_generator_writes` and
//! `the_committed_sampled_trapezoids_are_what_the_generator_writes`
//! (`crates/antenna-cli/tests/points_file.rs`) check the committed files byte for byte.

use std::path::{Path, PathBuf};
use std::time::Instant;

use antenna_cli::digitize::{TRAPEZOID_10K, digitize, points_csv, sample_edges};
use antenna_scene::Scene;
use anyhow::{Context as _, bail};
use sim_core::{Polyline, WallShape};

fn main() -> anyhow::Result<()> {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut per_edge: Option<usize> = None;
    let mut out: Option<PathBuf> = None;
    let mut args = std::env::args_os().skip(1);
    while let Some(arg) = args.next() {
        if arg == "--per-edge" {
            let value = args.next().context("--per-edge needs a number of points")?;
            let text = value.to_string_lossy();
            per_edge = Some(
                text.parse()
                    .with_context(|| format!("--per-edge {text}: not a whole number"))?,
            );
        } else {
            out = Some(PathBuf::from(arg));
        }
    }
    let scene = Scene::from_path(&examples.join("wall_polyline.toml"))?;
    let Some(WallShape::Polyline(trapezoid)) = scene.walls.first().map(|w| &w.shape) else {
        bail!("examples/wall_polyline.toml's first wall is not a polyline");
    };
    let (points_m, default_name) = match per_edge {
        None => (
            digitize(
                trapezoid.vertices_m(),
                trapezoid.solid_side(),
                &TRAPEZOID_10K,
            )?,
            "trapezoid_10k.csv".to_string(),
        ),
        Some(n) => (
            sample_edges(trapezoid.vertices_m(), trapezoid.solid_side(), n)?,
            format!("trapezoid_{n}_per_edge.csv"),
        ),
    };
    let out = out.unwrap_or_else(|| examples.join("walls").join(default_name));
    std::fs::write(&out, points_csv(&points_m))
        .with_context(|| format!("writing {}", out.display()))?;
    let start = Instant::now();
    let polyline = Polyline::new(points_m, trapezoid.solid_side())?;
    println!(
        "wrote {} points to {} (Polyline::new: {:.3} s)",
        polyline.vertices_m().len(),
        out.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
