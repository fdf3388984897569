//! Thesis 3.3.2: the tip forces through a flip. Nine segments with distal hairs run along a
//! smooth wall that ends in an abrasive strip; the distal hair anchors there and the antenna
//! flips with its tip pivoting on the strip (the thesis's force pad). The normal and shear
//! forces on the distal segment from the wall (its tip and its hair: what the pad measures)
//! are recorded through the flip at base angles 30 and 60 deg, the wall distance scaled like
//! the reach. `examples/tip_forces_3_3_2.toml` is the base scene.

use nalgebra::Vector2;
use sim_core::contact::Feature;
use sim_core::sweep::{Placement, Sweep, SweepScene};
use sim_core::{Line, SolidSide, Wall, WallShape};

use super::ReproduceError;

/// One run through a flip.
#[derive(Clone, Debug)]
pub struct TipForceRun {
    /// The base angle, degrees.
    pub base_angle_deg: f64,
    /// Per step: time, s.
    pub t_s: Vec<f64>,
    /// Per step: the normal force of the wall on the distal segment (tip and hair), N.
    pub normal_n: Vec<f64>,
    /// Per step: the shear force along the wall on it, N (signed, along the motion).
    pub shear_n: Vec<f64>,
    /// Per step: the distal segment's angle to the wall, degrees.
    pub distal_angle_deg: Vec<f64>,
    /// When the distal segment passed 90 deg, seconds.
    pub flip_t_s: Option<f64>,
    /// What the placement did.
    pub placement: String,
}

impl TipForceRun {
    /// Over the transition (from the first step with force on the strip to the flip, the
    /// distal segment past 90 deg), the mean normal force over the mean |shear| force.
    pub fn normal_to_shear_ratio(&self) -> Option<f64> {
        let end = self
            .flip_t_s
            .and_then(|t| self.t_s.iter().position(|&s| s >= t))?;
        let start = self.normal_n[..end].iter().position(|&n| n > 0.0)?;
        let window = start..=end;
        let count = (end - start + 1) as f64;
        let normal = self.normal_n[window.clone()].iter().sum::<f64>() / count;
        let shear = self.shear_n[window].iter().map(|t| t.abs()).sum::<f64>() / count;
        (shear > 0.0).then_some(normal / shear)
    }
}

/// Runs the base scene at `base_angle_deg` (the wall moved to keep the reach ratio).
///
/// # Errors
/// [`ReproduceError`] for an invalid scene or a failed step.
pub fn run(base: &SweepScene, base_angle_deg: f64) -> Result<TipForceRun, ReproduceError> {
    let label = format!("3.3.2 {base_angle_deg} deg");
    let chain = base
        .chain
        .to_builder()
        .base_angle_rad(base_angle_deg.to_radians())
        .build()?;
    let mut walls = base.walls.clone();
    let Some(wall) = walls.first_mut() else {
        return Err(ReproduceError::Scene {
            path: "tip forces".into(),
            message: "the base scene has no wall".into(),
        });
    };
    let WallShape::Line(line) = &wall.shape else {
        return Err(ReproduceError::Scene {
            path: "tip forces".into(),
            message: "the base scene's wall 0 is not a line".into(),
        });
    };
    let distance_30 = wall.signed_distance(&base.base_start_m).gap_m;
    let distance = distance_30 * base_angle_deg.to_radians().sin() / 30f64.to_radians().sin();
    let along = Vector2::new(line.angle_rad().cos(), line.angle_rad().sin());
    let normal = Vector2::new(-along.y, along.x);
    *wall = Wall::new(
        Line::new(
            base.base_start_m + normal * distance,
            line.angle_rad(),
            SolidSide::Left,
        )?,
        wall.surfaces.clone(),
    );
    // The thesis put the tip on the pad "at a forward looking configuration": the base comes
    // onto the wall sliding back as far as it comes in, so a steep antenna is not buckled
    // backward by meeting the wall head-on.
    let placement = match &base.placement {
        Placement::Approach {
            wall,
            distance_m,
            steps,
            ..
        } => Placement::Approach {
            wall: *wall,
            distance_m: *distance_m,
            along_m: -*distance_m,
            steps: *steps,
        },
        other => other.clone(),
    };
    let scene = SweepScene {
        chain,
        walls,
        placement,
        ..base.clone()
    };
    let n = scene.chain.n();
    let mut sweep = Sweep::new(scene).map_err(|source| ReproduceError::Sweep {
        label: label.clone(),
        source,
    })?;
    let mut out = TipForceRun {
        base_angle_deg,
        t_s: Vec::new(),
        normal_n: Vec::new(),
        shear_n: Vec::new(),
        distal_angle_deg: Vec::new(),
        flip_t_s: None,
        placement: sweep.placement_note().to_owned(),
    };
    let motion = sweep.motion().velocity_m_per_s;
    while let Some(step) = sweep.next_step() {
        let step = step.map_err(|source| ReproduceError::Sweep {
            label: label.clone(),
            source,
        })?;
        let sim = sweep.sim();
        let mut normal_n = 0.0;
        let mut shear_n = 0.0;
        for c in step.contacts.iter().filter(|c| {
            matches!(c.feature, Feature::Vertex { link } | Feature::HairTip { link } if link == n)
        }) {
            let surface = sim.walls()[c.wall].surface_at(&sim.walls()[c.wall].signed_distance(&c.point_m));
            if !surface.is_rough() {
                continue;
            }
            normal_n += c.normal_force_n;
            let forward = if c.tangent.dot(&motion) >= 0.0 { 1.0 } else { -1.0 };
            shear_n += forward * c.shear_force_n;
        }
        out.t_s.push(step.t_s);
        out.normal_n.push(normal_n);
        out.shear_n.push(shear_n);
        out.distal_angle_deg.push(
            step.flip
                .map_or(f64::NAN, |f| f.angle_to_wall_rad.to_degrees()),
        );
        if step.flipped() && out.flip_t_s.is_none() {
            out.flip_t_s = Some(step.t_s);
        }
    }
    Ok(out)
}
