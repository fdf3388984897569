//! Writes the "Kinematics" section of docs/benchmarks/kinematics.md (BENCHMARKS.md's detail) from criterion's results
//! (`target/criterion/kinematics/<function>/<n>/new/estimates.json`, median point estimates: robust to interference from other work on the machine).
//! Only the text between `<!-- kinematics:begin -->` and `<!-- kinematics:end -->` is
//! replaced; the section is appended if the markers are missing.
//!
//! Run by `scripts/bench-kinematics` after `cargo bench -p sim-core --bench kinematics`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const BEGIN: &str = "<!-- kinematics:begin -->";
const END: &str = "<!-- kinematics:end -->";
const SIZES: [usize; 5] = [9, 150, 512, 1000, 4096];

fn mean_ns(root: &Path, function: &str, n: usize) -> Option<f64> {
    let path = root
        .join(function)
        .join(n.to_string())
        .join("new")
        .join("estimates.json");
    let text = std::fs::read_to_string(path).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v["median"]["point_estimate"].as_f64()
}

fn fmt_time(ns: f64) -> String {
    if ns < 1e3 {
        format!("{ns:.0} ns")
    } else if ns < 1e6 {
        format!("{:.2} µs", ns / 1e3)
    } else if ns < 1e9 {
        format!("{:.2} ms", ns / 1e6)
    } else {
        format!("{:.2} s", ns / 1e9)
    }
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".to_string())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let workspace = manifest.parent().ok_or("no workspace dir")?.to_path_buf();
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map_or_else(|| workspace.join("target"), PathBuf::from);
    let root = target.join("criterion").join("kinematics");
    let t = |f: &str, n: usize| mean_ns(&root, f, n);

    let mut s = String::new();
    writeln!(s, "{BEGIN}")?;
    writeln!(s, "## Kinematics (sim-core)\n")?;
    writeln!(
        s,
        "Regenerate with `scripts/bench-kinematics` (criterion, `cargo bench -p sim-core --bench kinematics`, \
         then `cargo run -p sim-core --release --example kinematics_bench_table`). Median time per call, \
         ground frame as spatial frame, random joint angles in [-0.3, 0.3] rad whose link angles \
         meander within +-1.2 rad at every n (so `sin_cos` sees the same arguments at every n), link lengths 30-50 mm. Machine: {}, {} logical CPUs.\n",
        cpu_model(),
        std::thread::available_parallelism().map_or(0, |p| p.get())
    )?;
    writeln!(
        s,
        "The floor is n + 1 `sin_cos` calls plus the prefix sums of angles and positions (the tip position), \
         measured in the same run. The fast paths write into caller buffers (`_into`); \"all Jacobians\" fills \
         the dense 3(n+2) x (n+1) stack, O(n^2) by the size of its answer.\n"
    )?;

    let fast = [
        ("positions", "all-frame positions"),
        ("velocities", "all-frame velocities"),
        ("tip_jacobian", "tip Jacobian"),
        (
            "tip_force",
            "tip force from the joint angles (least squares)",
        ),
        ("all_jacobians", "all Jacobians"),
    ];
    let seed = [
        ("seed_positions", "thesis positions (2.2.3.3)"),
        ("seed_velocities", "thesis velocities (2.2.3.6)"),
        ("seed_tip_jacobian", "thesis tip Jacobian (2.2.2.1)"),
        (
            "seed_all_jacobians",
            "thesis all Jacobians (2.2.3.6, O(n^3))",
        ),
    ];

    // Fast paths with their ratio to the floor.
    write!(s, "| n | floor |")?;
    for (_, name) in &fast {
        write!(s, " {name} (x floor) |")?;
    }
    writeln!(s)?;
    writeln!(s, "|---:|---:|{}", "---:|".repeat(fast.len()))?;
    for n in SIZES {
        let floor = t("floor", n);
        write!(s, "| {n} | {} |", floor.map_or("-".into(), fmt_time))?;
        for (f, _) in &fast {
            match (t(f, n), floor) {
                (Some(v), Some(fl)) => write!(s, " {} ({:.2}) |", fmt_time(v), v / fl)?,
                (Some(v), None) => write!(s, " {} |", fmt_time(v))?,
                _ => write!(s, " - |")?,
            }
        }
        writeln!(s)?;
    }
    writeln!(s)?;

    // The thesis's matrix forms and what the fast paths save.
    write!(s, "| n |")?;
    for (_, name) in &seed {
        write!(s, " {name} (x fast path) |")?;
    }
    writeln!(s)?;
    writeln!(s, "|---:|{}", "---:|".repeat(seed.len()))?;
    for n in SIZES {
        write!(s, "| {n} |")?;
        for ((f, _), (fast_f, _)) in seed.iter().zip(&fast) {
            match (t(f, n), t(fast_f, n)) {
                (Some(v), Some(fv)) => write!(s, " {} ({:.0}) |", fmt_time(v), v / fv)?,
                (Some(v), None) => write!(s, " {} |", fmt_time(v))?,
                (None, _) if *f == "seed_all_jacobians" && n > 1000 => {
                    write!(s, " skipped (O(n^3)) |")?
                }
                _ => write!(s, " - |")?,
            }
        }
        writeln!(s)?;
    }
    writeln!(s)?;

    // Goals.
    writeln!(s, "| goal | measured | met |")?;
    writeln!(s, "|---|---:|:---:|")?;
    for (f, name) in &fast[..2] {
        if let (Some(v), Some(fl)) = (t(f, 150), t("floor", 150)) {
            let r = v / fl;
            writeln!(
                s,
                "| {name} within 2x of the floor at n = 150 | {r:.2}x | {} |",
                yes(r <= 2.0)
            )?;
        }
    }
    for (f, name) in fast.iter().chain([("floor", "floor")].iter()) {
        if let (Some(a), Some(b)) = (t(f, 4096), t(f, 512)) {
            let r = a / b;
            let (goal, ok) = if *f == "all_jacobians" {
                ("O(n^2): 64 expected, not an O(n) path".to_string(), None)
            } else {
                ("<= 10 (O(n))".to_string(), Some(r <= 10.0))
            };
            writeln!(
                s,
                "| {name}: time(4096) / time(512) {goal} | {r:.2} | {} |",
                ok.map_or("n/a", yes)
            )?;
        }
    }
    writeln!(
        s,
        "\n\"All Jacobians\" is O(n^2) by the size of its answer (3(n+2)(n+1) doubles, 400 MB at n = 4096): \
         above 64 its ratio measures memory bandwidth once the output no longer fits in cache. \
         The thesis's all-Jacobians product (O(n^3), about 1.4e11 flops at n = 4096) is skipped above n = 1000."
    )?;
    writeln!(s, "{END}")?;

    let md_path = workspace.join("docs/benchmarks/kinematics.md");
    let old = std::fs::read_to_string(&md_path)
        .unwrap_or_else(|_| "# Benchmarks: Kinematics (sim-core)\n\n".to_string());
    let new = match (old.find(BEGIN), old.find(END)) {
        (Some(b), Some(e)) if e > b => {
            format!("{}{}{}", &old[..b], s.trim_end(), &old[e + END.len()..])
        }
        _ => format!("{}\n\n{}", old.trim_end(), s),
    };
    let new = if new.ends_with('\n') { new } else { new + "\n" };
    std::fs::write(&md_path, new)?;
    println!("{s}");
    println!("wrote {}", md_path.display());
    Ok(())
}

fn yes(ok: bool) -> &'static str {
    if ok { "yes" } else { "NO" }
}
