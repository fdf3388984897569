//! Writes `examples/walls/trapezoid_10k.csv`, the digitized wall of
//! `examples/wall_digitized.toml`: the trapezoid of `examples/wall_polyline.toml` (thesis
//! 4.2.2) sampled at 10,000 points along its arclength with 0.1 mm of Gaussian noise normal
//! to it, from a fixed seed ([`antenna_cli::digitize::TRAPEZOID_10K`]).
//!
//! ```sh
//! cargo run -p antenna-cli --example digitize_trapezoid            # the example's file
//! cargo run -p antenna-cli --example digitize_trapezoid -- out.csv # elsewhere
//! ```
//!
//! The CLI's test `the_committed_trapezoid_is_what_the_generator_writes`
//! (`crates/antenna-cli/tests/points_file.rs`) checks the committed file byte for byte.

use std::path::{Path, PathBuf};
use std::time::Instant;

use antenna_cli::digitize::{TRAPEZOID_10K, digitize, points_csv};
use antenna_scene::Scene;
use anyhow::{Context as _, bail};
use sim_core::{Polyline, WallShape};

fn main() -> anyhow::Result<()> {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let out = std::env::args_os()
        .nth(1)
        .map_or_else(|| examples.join("walls/trapezoid_10k.csv"), PathBuf::from);
    let scene = Scene::from_path(&examples.join("wall_polyline.toml"))?;
    let Some(WallShape::Polyline(trapezoid)) = scene.walls.first().map(|w| &w.shape) else {
        bail!("examples/wall_polyline.toml's first wall is not a polyline");
    };
    let points_m = digitize(
        trapezoid.vertices_m(),
        trapezoid.solid_side(),
        &TRAPEZOID_10K,
    )?;
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
