//! Thesis 3.3.1: the sufficiency of distally pointing hairs. Eight segments (`links = 8`),
//! the cockroach profile, base angle 30 deg, a wall 135 mm from the base, 15 mm/s, starting
//! projecting forward (an approach onto the wall); six experiments (rough or smooth wall x
//! distal hairs, the three distal-most removed, proximal hairs), then rough + distal at base
//! angles 10, 20, 60 and 70 deg with the wall distance scaled like the reach
//! (`135 mm sin(theta_0) / sin(30 deg)`). `examples/flipping_3_3_1.toml` is the base scene.
//!
//! A flip is the distal segment beyond 90 deg to the wall (docs/model.md 7).

use nalgebra::Vector2;
use sim_core::sweep::{Sweep, SweepScene};
use sim_core::{Hair, HairDirection, Line, SolidSide, Surface, SurfaceMap, Wall};

use super::ReproduceError;

/// The wall surface of an experiment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WallSurface {
    /// Felt: hair tips anchor.
    Rough,
    /// Glossy paper: Coulomb friction only.
    Smooth,
}

/// The hair layout of an experiment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HairLayout {
    /// A distally pointing hair on every flagellar segment.
    Distal,
    /// Distal hairs, the three distal-most removed.
    DistalWithoutLastThree,
    /// A proximally pointing hair on every flagellar segment.
    Proximal,
}

impl HairLayout {
    /// Every layout, in the thesis's order.
    pub const ALL: [HairLayout; 3] = [
        HairLayout::Distal,
        HairLayout::DistalWithoutLastThree,
        HairLayout::Proximal,
    ];

    /// A short name.
    pub fn name(&self) -> &'static str {
        match self {
            HairLayout::Distal => "distal hairs",
            HairLayout::DistalWithoutLastThree => "distal, 3 distal-most removed",
            HairLayout::Proximal => "proximal hairs",
        }
    }
}

/// One experiment's outcome.
#[derive(Clone, Debug)]
pub struct FlipRun {
    /// The surface.
    pub surface: WallSurface,
    /// The hairs.
    pub layout: HairLayout,
    /// The base angle, degrees.
    pub base_angle_deg: f64,
    /// The hair length used, metres.
    pub hair_length_m: f64,
    /// When the distal segment first passed 90 deg to the wall, seconds.
    pub flip_t_s: Option<f64>,
    /// The largest angle of the distal segment to the wall, degrees.
    pub max_distal_angle_deg: f64,
    /// Per step: time, s.
    pub t_s: Vec<f64>,
    /// Per step: the distal segment's angle to the wall, degrees.
    pub distal_angle_deg: Vec<f64>,
    /// Steps with an anchored hair.
    pub anchored_steps: usize,
    /// Steps that snapped.
    pub snaps: usize,
    /// What the placement did.
    pub placement: String,
}

impl FlipRun {
    /// Whether the antenna flipped.
    pub fn flipped(&self) -> bool {
        self.flip_t_s.is_some()
    }
}

/// The geometric lock angle of docs/model.md 7: with the hair anchored and unable to pull, the
/// distal segment stops where its end meets the wall, `tan(phi) = (w + l_h sin a) / (d - l_h
/// cos a)` (`d` the pivot's distance from the segment's end, `a` the open angle), degrees.
pub fn lock_angle_deg(hair: &Hair) -> f64 {
    let a = hair.open_angle_rad;
    let rise = hair.lateral_offset_m + hair.length_m * a.sin();
    let run = hair.pivot_from_distal_end_m - hair.length_m * a.cos();
    rise.atan2(run).to_degrees()
}

/// `base` with every hair's root stiffness set to `root_stiffness_nm_per_rad` (`None`: rigid
/// hairs, the scene as written). [`scene_for`] copies it to the hairs it lays out.
///
/// # Errors
/// [`ReproduceError`] for a root stiffness that is not positive and finite.
pub fn with_root_stiffness(
    base: &SweepScene,
    root_stiffness_nm_per_rad: Option<f64>,
) -> Result<SweepScene, ReproduceError> {
    let mut builder = base.chain.to_builder().without_hairs();
    for (link, hair) in base.chain.hairs().iter().enumerate() {
        if let Some(hair) = hair {
            builder = builder.hair(
                link,
                Hair {
                    root_stiffness_nm_per_rad,
                    ..*hair
                },
            );
        }
    }
    Ok(SweepScene {
        chain: builder.build()?,
        ..base.clone()
    })
}

/// The base scene with `surface`, `layout`, `base_angle_deg` and the hair length changed.
///
/// # Errors
/// [`ReproduceError`] for an invalid chain or wall.
pub fn scene_for(
    base: &SweepScene,
    surface: WallSurface,
    layout: HairLayout,
    base_angle_deg: f64,
    hair_length_m: f64,
) -> Result<SweepScene, ReproduceError> {
    let chain = &base.chain;
    let n = chain.n();
    let template = chain
        .hairs()
        .iter()
        .flatten()
        .next()
        .copied()
        .unwrap_or_else(|| Hair::seed(chain.link_lengths_m()[n]));
    let mut builder = chain
        .to_builder()
        .without_hairs()
        .base_angle_rad(base_angle_deg.to_radians());
    for link in 1..=n {
        let mut hair = Hair {
            length_m: hair_length_m,
            ..template
        };
        match layout {
            HairLayout::Distal => hair.direction = HairDirection::Distal,
            HairLayout::Proximal => hair.direction = HairDirection::Proximal,
            HairLayout::DistalWithoutLastThree => {
                if link + 3 > n {
                    continue;
                }
                hair.direction = HairDirection::Distal;
            }
        }
        builder = builder.hair(link, hair);
    }
    let chain = builder.build()?;
    // The wall: the base scene's first wall, moved to the scaled distance, with its surface.
    let Some(wall) = base.walls.first() else {
        return Err(ReproduceError::Scene {
            path: "flipping".into(),
            message: "the base scene has no wall".into(),
        });
    };
    let distance_30 = wall.signed_distance(&base.base_start_m).gap_m;
    let distance = distance_30 * base_angle_deg.to_radians().sin() / 30f64.to_radians().sin();
    let first = wall.surfaces.first();
    let rough = match first {
        Surface::Rough { .. } => first,
        Surface::Smooth { mu } => Surface::Rough {
            mu,
            hold_shear_n: 1.0,
            hold_tension_n: 0.5,
        },
    };
    let smooth = Surface::Smooth { mu: first.mu() };
    let surface_now = match surface {
        WallSurface::Rough => rough,
        WallSurface::Smooth => smooth,
    };
    let wall = Wall::new(
        Line::new(
            base.base_start_m + Vector2::new(0.0, distance),
            0.0,
            SolidSide::Left,
        )?,
        SurfaceMap::uniform(surface_now)?,
    );
    Ok(SweepScene {
        chain,
        walls: vec![wall],
        ..base.clone()
    })
}

/// Runs one experiment.
///
/// # Errors
/// [`ReproduceError`] when the scene is invalid or a step fails.
pub fn run(
    base: &SweepScene,
    surface: WallSurface,
    layout: HairLayout,
    base_angle_deg: f64,
    hair_length_m: f64,
) -> Result<FlipRun, ReproduceError> {
    let scene = scene_for(base, surface, layout, base_angle_deg, hair_length_m)?;
    let label = format!(
        "3.3.1 {surface:?} {} {base_angle_deg} deg {hair_length_m} m",
        layout.name()
    );
    let mut sweep = Sweep::new(scene).map_err(|source| ReproduceError::Sweep {
        label: label.clone(),
        source,
    })?;
    let mut out = FlipRun {
        surface,
        layout,
        base_angle_deg,
        hair_length_m,
        flip_t_s: None,
        max_distal_angle_deg: 0.0,
        t_s: Vec::new(),
        distal_angle_deg: Vec::new(),
        anchored_steps: 0,
        snaps: 0,
        placement: sweep.placement_note().to_owned(),
    };
    while let Some(step) = sweep.next_step() {
        let step = step.map_err(|source| ReproduceError::Sweep {
            label: label.clone(),
            source,
        })?;
        let angle = step
            .flip
            .map_or(f64::NAN, |f| f.angle_to_wall_rad.to_degrees());
        out.t_s.push(step.t_s);
        out.distal_angle_deg.push(angle);
        out.max_distal_angle_deg = out.max_distal_angle_deg.max(angle);
        if step.flipped() && out.flip_t_s.is_none() {
            out.flip_t_s = Some(step.t_s);
        }
        if step.contacts.iter().any(|c| c.is_anchored()) {
            out.anchored_steps += 1;
        }
        if step.report.snapped {
            out.snaps += 1;
        }
    }
    Ok(out)
}
