//! What the sweep benchmark examples share: writing their generated section of
//! `docs/benchmarks/sweeps.md` (the detail page of BENCHMARKS.md's "Sweeps"), medians, human-readable times and today's date.
// Each example uses a part of it.
#![allow(dead_code)]

use std::path::Path;

/// Replaces the text between `begin` and `end` in the workspace's `docs/benchmarks/sweeps.md` with
/// `section` (which carries both markers), or appends it where the markers are missing.
pub fn write_section(
    workspace: &Path,
    begin: &str,
    end: &str,
    section: &str,
) -> std::io::Result<()> {
    let path = workspace.join("docs/benchmarks/sweeps.md");
    let old = std::fs::read_to_string(&path)
        .unwrap_or_else(|_| "# Benchmarks: Sweeps (sim-core)\n".to_string());
    let new = match (old.find(begin), old.find(end)) {
        (Some(b), Some(e)) if b < e => format!(
            "{}{}{}",
            &old[..b],
            section.trim_end(),
            &old[e + end.len()..]
        ),
        _ => format!("{}\n{}", old.trim_end_matches('\n'), section),
    };
    std::fs::write(&path, new)
}

/// The median (NaN for no values).
pub fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// A duration in seconds with the unit that reads best.
pub fn human(seconds: f64) -> String {
    if seconds >= 1.0 {
        format!("{seconds:.2} s")
    } else if seconds >= 1e-3 {
        format!("{:.1} ms", seconds * 1e3)
    } else if seconds >= 1e-6 {
        format!("{:.2} µs", seconds * 1e6)
    } else {
        format!("{:.0} ns", seconds * 1e9)
    }
}

/// Today's date (UTC), from the system clock.
pub fn date() -> String {
    let days = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() / 86_400) as i64;
    // Civil from days (H. Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}")
}

/// The thesis's 4.2.2 trapezoid (a 6 cm deep recess from x = 0.25 m to 0.65 m, solid above),
/// with friction `mu`.
pub fn trapezoid_4_2_2(mu: f64) -> Result<sim_core::Wall, Box<dyn std::error::Error>> {
    let vertices = [
        (0.0, 0.2),
        (0.25, 0.2),
        (0.35, 0.14),
        (0.55, 0.14),
        (0.65, 0.2),
        (1.0, 0.2),
    ]
    .map(|(x, y)| nalgebra::Vector2::new(x, y))
    .to_vec();
    Ok(sim_core::Wall::new(
        sim_core::Polyline::new(vertices, sim_core::SolidSide::Left)?,
        sim_core::SurfaceMap::uniform(sim_core::Surface::Smooth { mu })?,
    ))
}

/// The sinusoid of the thesis's highest spatial frequency (4.2.2: 14.2 cycles/m), 10 mm
/// amplitude about y = 0.17 m (crests of 12.6 mm radius), solid above, with friction `mu`.
pub fn sinusoid_14_2(mu: f64) -> Result<sim_core::Wall, Box<dyn std::error::Error>> {
    Ok(sim_core::Wall::new(
        sim_core::Sinusoid::new(
            nalgebra::Vector2::new(0.0, 0.17),
            0.0,
            0.01,
            14.2,
            0.0,
            sim_core::SolidSide::Left,
        )?,
        sim_core::SurfaceMap::uniform(sim_core::Surface::Smooth { mu })?,
    ))
}

/// The thesis's 0.36 m antenna cut into `links` equal links (`links - 1` flexible joints), base
/// angle 30 deg, joint limits +-90 deg, the fast-exponential profile scaled to stay the same
/// beam (the thesis's 0.004..0.082 N m/rad for 40 mm links times 40 mm / link).
pub fn scaled_antenna(links: usize) -> Result<sim_core::Chain, Box<dyn std::error::Error>> {
    use sim_core::design::profile::{
        SEED_K_MAX_N_M_PER_RAD, SEED_K_MIN_N_M_PER_RAD, StiffnessProfile,
    };
    let n = links - 1;
    let l = ANTENNA_LENGTH_M / links as f64;
    let lengths = vec![l; links];
    let scale = SEED_LINK_M / l;
    let k = StiffnessProfile::FastExponential.stiffness_n_m_per_rad(
        &lengths,
        SEED_K_MIN_N_M_PER_RAD * scale,
        SEED_K_MAX_N_M_PER_RAD * scale,
    )?;
    Ok(sim_core::Chain::builder(n)
        .link_length_m(l)
        .base_angle_rad(30f64.to_radians())
        .stiffnesses_nm_per_rad(k)
        .joint_limit(sim_core::JointLimit::new(
            (-90f64).to_radians(),
            90f64.to_radians(),
        ))
        .build()?)
}

/// The thesis's antenna, metres.
pub const ANTENNA_LENGTH_M: f64 = 0.36;
/// The thesis's link, metres.
pub const SEED_LINK_M: f64 = 0.04;

/// The solver's settings for `links` links: the defaults (the jump threshold scaled to the
/// link by the solver, `jump_rad` x link / 40 mm: the same change of curvature flags a jump at
/// every N; the budgets scaled with the joints), or, with `scaled_jump` false, the rule
/// before issue #49 (`jump_rad` per joint whatever the link, the budgets as given at every N).
/// (The solver scales both to the chain itself: `_links` is no longer needed.)
pub fn scaled_settings(_links: usize, scaled_jump: bool) -> sim_core::contact::ContactSettings {
    let default = sim_core::contact::ContactSettings::default();
    if scaled_jump {
        default
    } else {
        sim_core::contact::ContactSettings {
            jump_reference_link_m: None,
            budget_reference_joints: None,
            ..default
        }
    }
}
