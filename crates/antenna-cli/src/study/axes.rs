//! The axes of a study and how one value of each changes the base scene: the stiffness
//! profile, the base angle, the base's start distance from the wall, the hair layout and
//! the walls' surface; in a follow scene also the robot's speed, the controller's gains and
//! its delay.

use nalgebra::Vector2;
use sim_core::sweep::Placement;
use sim_core::{
    Chain, ChainError, Hair, HairDirection, ProfileError, StiffnessProfile, Surface, SurfaceMap,
    Wall, WallError,
};

use antenna_scene::{HairSpec, Scene, StiffnessSpec};

/// Why a variant of the base scene is not a valid scene.
#[derive(Debug, thiserror::Error)]
pub enum VariantError {
    /// The profile could not be normalized to the bounds.
    #[error("stiffness profile: {0}")]
    Profile(#[from] ProfileError),
    /// The chain is not valid (a hair that does not fit its link).
    #[error("antenna: {0}")]
    Chain(#[from] ChainError),
    /// The surface is not valid.
    #[error("surface: {0}")]
    Surface(#[from] WallError),
}

/// A hair layout (the `hairs` axis).
#[derive(Debug, Clone, PartialEq)]
pub enum HairLayout {
    /// `"scene"`: the base scene's own hairs (or none).
    Scene,
    /// `"none"`: no hairs.
    None,
    /// `"distal"`, `"proximal"`, `"distal-without-K"`, `"proximal-without-K"`: a hair
    /// pointing that way on every flagellar link but the `without` distal-most ones.
    On {
        /// Which way the hairs point.
        direction: HairDirection,
        /// How many of the distal-most links go without.
        without: usize,
    },
}

impl HairLayout {
    /// Reads a layout name for a chain with `n` flexible links.
    ///
    /// # Errors
    /// In words, when the name is not a layout or leaves no hair.
    pub fn parse(name: &str, n: usize) -> Result<HairLayout, String> {
        let expected = "\"scene\", \"none\", \"distal\", \"proximal\", \"distal-without-K\" or \
                        \"proximal-without-K\" (K the number of distal-most links without a hair)";
        match name {
            "scene" => return Ok(HairLayout::Scene),
            "none" => return Ok(HairLayout::None),
            _ => {}
        }
        let (direction, rest) = if let Some(rest) = name.strip_prefix("distal") {
            (HairDirection::Distal, rest)
        } else if let Some(rest) = name.strip_prefix("proximal") {
            (HairDirection::Proximal, rest)
        } else {
            return Err(format!("\"{name}\" is not a hair layout: use {expected}"));
        };
        let without = match rest {
            "" => 0,
            _ => rest
                .strip_prefix("-without-")
                .and_then(|k| k.parse::<usize>().ok())
                .ok_or_else(|| format!("\"{name}\" is not a hair layout: use {expected}"))?,
        };
        if without >= n {
            return Err(format!(
                "\"{name}\" leaves no hair: the antenna has {n} flagellar links"
            ));
        }
        Ok(HairLayout::On { direction, without })
    }

    /// The layout's name as written in results.
    pub fn label(&self) -> String {
        match self {
            HairLayout::Scene => "scene".to_string(),
            HairLayout::None => "none".to_string(),
            HairLayout::On { direction, without } => {
                let way = match direction {
                    HairDirection::Distal => "distal",
                    HairDirection::Proximal => "proximal",
                };
                if *without == 0 {
                    way.to_string()
                } else {
                    format!("{way}-without-{without}")
                }
            }
        }
    }

    /// The hairs of this layout on a chain of `n` flexible links whose scene has `scene`'s
    /// hairs (their parameters are kept; without any, the thesis's hair).
    pub fn spec(&self, scene: Option<&HairSpec>, link_lengths_m: &[f64]) -> Option<HairSpec> {
        let n = link_lengths_m.len().saturating_sub(1);
        match self {
            HairLayout::Scene => scene.cloned(),
            HairLayout::None => None,
            HairLayout::On { direction, without } => {
                let mut spec = scene.cloned().unwrap_or_else(|| HairSpec {
                    links: Vec::new(),
                    hair: Hair::seed(link_lengths_m.get(1).copied().unwrap_or_default()),
                    pivot_given: false,
                });
                spec.hair.direction = *direction;
                Some(spec.on_links((1..=n - without).collect()))
            }
        }
    }
}

/// A wall surface (the `surfaces` axis): every wall of the scene gets it, uniform.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceChoice(pub Surface);

impl SurfaceChoice {
    /// The surface as written in results, e.g. `smooth mu=0.3` or
    /// `rough mu=0.3 hold_shear_n=0.05 hold_tension_n=0.02`.
    pub fn label(&self) -> String {
        match self.0 {
            Surface::Smooth { mu } => format!("smooth mu={mu}"),
            Surface::Rough {
                mu,
                hold_shear_n,
                hold_tension_n,
            } => {
                format!("rough mu={mu} hold_shear_n={hold_shear_n} hold_tension_n={hold_tension_n}")
            }
        }
    }
}

/// One value of each axis (`None`: the axis is absent, the base scene's value holds).
#[derive(Debug, Clone, PartialEq)]
pub struct Variant {
    /// The stiffness profile, normalized to the study's bounds.
    pub profile: Option<StiffnessProfile>,
    /// The base angle, degrees.
    pub base_angle_deg: Option<f64>,
    /// The base pivot's start distance from the reference wall, metres.
    pub wall_distance_m: Option<f64>,
    /// The hair layout.
    pub hairs: Option<HairLayout>,
    /// The walls' surface.
    pub surface: Option<SurfaceChoice>,
    /// A follow scene's forward speed, m/s.
    pub speed_m_per_s: Option<f64>,
    /// A follow scene's template gain `kp_n`, N m per m.
    pub kp_n: Option<f64>,
    /// A follow scene's template gain `kd_n_s`, N m per m/s.
    pub kd_n_s: Option<f64>,
    /// A follow scene's wheeled gain `kp_rad_per_s_per_m`, rad/s per m.
    pub kp_rad_per_s_per_m: Option<f64>,
    /// A follow scene's wheeled gain `kd_rad_per_m`, rad per m.
    pub kd_rad_per_m: Option<f64>,
    /// A follow scene's sensing-to-actuation delay, s.
    pub delay_s: Option<f64>,
}

/// The wall a study measures the base's distance from: the placement's wall, else wall 0.
pub fn reference_wall(scene: &Scene) -> usize {
    match scene.placement {
        Placement::Approach { wall, .. } | Placement::TipOnWall { wall, .. } => wall,
        Placement::Rest | Placement::Angles(_) => 0,
    }
}

/// The base pivot moved along the wall's normal until its signed distance from `wall` is
/// `distance_m` (exact for a line; a few corrections for curved walls).
pub fn base_at_distance(wall: &Wall, base_m: Vector2<f64>, distance_m: f64) -> Vector2<f64> {
    let mut base = base_m;
    for _ in 0..100 {
        let point = wall.signed_distance(&base);
        let error_m = distance_m - point.gap_m;
        if error_m.abs() <= 1e-13 {
            break;
        }
        base += point.normal * error_m;
    }
    base
}

impl Variant {
    /// The base scene changed by this variant; `bounds` normalizes the profile. The follow
    /// values change a follow scene's `[robot]` and `[controller]` (a scene without them
    /// ignores them: the study refuses such axes when it reads the file).
    ///
    /// # Errors
    /// [`VariantError`] when the changed scene is not valid (a hair that does not fit its
    /// link, a profile that cannot be normalized, a bad surface).
    pub fn apply(&self, base: &Scene, bounds: Option<(f64, f64)>) -> Result<Scene, VariantError> {
        let mut scene = base.clone();
        let chain = &base.chain;
        let lengths = chain.link_lengths_m().to_vec();
        let mut stiffness = chain.stiffness_nm_per_rad()[1..].to_vec();
        if let (Some(profile), Some((min, max))) = (&self.profile, bounds) {
            stiffness = profile.stiffness_n_m_per_rad(&lengths, min, max)?;
            scene.stiffness = StiffnessSpec::Profile {
                profile: profile.clone(),
                min_n_m_per_rad: min,
                max_n_m_per_rad: max,
            };
        }
        let base_angle_rad = self
            .base_angle_deg
            .map_or(chain.base_angle_rad(), f64::to_radians);
        if let Some(layout) = &self.hairs {
            scene.hairs = layout.spec(base.hairs.as_ref(), &lengths);
        }
        let mut builder = Chain::builder(chain.n())
            .link_lengths_m(lengths.clone())
            .base_angle_rad(base_angle_rad)
            .joint_limits(chain.joint_limits()[1..].to_vec())
            .stiffnesses_nm_per_rad(stiffness)
            .rest_angles_rad(chain.rest_angles_rad()[1..].to_vec());
        if let Some(spec) = &scene.hairs {
            for (link, hair) in spec.hairs(&lengths) {
                builder = builder.hair(link, hair);
            }
        }
        scene.chain = builder.build()?;
        if let Some(SurfaceChoice(surface)) = self.surface {
            for wall in &mut scene.walls {
                wall.surfaces = SurfaceMap::uniform(surface)?;
            }
        }
        if let Some(d) = self.wall_distance_m
            && let Some(wall) = scene.walls.get(reference_wall(&scene))
        {
            scene.base_position_m = base_at_distance(wall, scene.base_position_m, d);
        }
        if let Some(follow) = scene.follow.as_mut() {
            let (robot, controller) = (&mut follow.config.robot, &mut follow.config.controller);
            let set = |to: &mut f64, value: Option<f64>| {
                if let Some(v) = value {
                    *to = v;
                }
            };
            set(&mut robot.speed_m_per_s, self.speed_m_per_s);
            set(&mut controller.kp_n, self.kp_n);
            set(&mut controller.kd_n_s, self.kd_n_s);
            set(&mut controller.kp_rad_per_s_per_m, self.kp_rad_per_s_per_m);
            set(&mut controller.kd_rad_per_m, self.kd_rad_per_m);
            set(&mut controller.delay_s, self.delay_s);
        }
        Ok(scene)
    }
}
