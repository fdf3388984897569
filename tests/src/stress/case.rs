//! A case of the suite: an antenna, one wall, a placement and a motion, drawn from
//! `(seed, index, sample)` alone.
//!
//! The antenna is the 4.2.1 robot stretched or cut into `N` links: 0.36 m long, `N` links of
//! `0.36 / N` m (`N - 1` flexible joints), joint limits +-90 deg, stiffness normalized to
//! 0.004..0.082 N m/rad by one of the seven Table 4.1 profiles, and on every flexible link
//! either no hair or a distal hair of 0.45 link lengths pivoting at the link's middle, each
//! hair rigid or (half of them, from a random stream of their own so that every other draw
//! is as it was before compliant hairs) with a compliant root of 1e-4..10 N m/rad,
//! log-uniform. The
//! base starts at the origin at 20-40 deg and moves along `+x` at 16.7 or 24 mm/s in steps of
//! 0.01 s. The wall (see [`super::walls`]) lies on the antenna's left, its baseline at
//! -15..+5 deg (closing in on the base or about level), smooth with `mu` in
//! {0, 0.3, 0.6, 1.0}, and is placed for the placement so that the antenna meets it:
//! - **rest**: the straight antenna 0.2-15 mm short of the wall;
//! - **angles**: a random bent posture (C toward or away from the wall, S, or wavy; now and
//!   then a joint on its stop) touching the wall or up to 5 mm short of it;
//! - **approach**: the straight antenna would reach 0-40 mm into the wall at the start
//!   position; the base comes in from 5-20 mm beyond that, sliding back 0-50 mm;
//! - **tip-on-wall** (C or S start): the baseline 0.10-0.25 m from the base, the tip pinned
//!   0.05 m behind to 0.10 m ahead of the base.
//!
//! For 40% of polyline walls with a rest, angles or tip-on-wall placement a corner is put
//! exactly on a point of the start posture: on rest and angles the posture's point nearest
//! the wall (a joint, the tip, or a hair tip), as a convex step, tooth or a concave pocket
//! (checked clear of the posture; else a convex one); on tip-on-wall the pinned tip of the
//! same pinned equilibrium the placement solves, sometimes with the distal link's proximal
//! joint as a second corner (the distal link is then an edge of the wall).
//!
//! The sweep is cut short where the base link would come within 3 mm of the wall (the base
//! cannot be driven into a wall; the antenna in front of it can jam).

use std::f64::consts::FRAC_PI_2;

use nalgebra::Vector2;
use rand::Rng;
use sim_core::sweep::{Motion, Placement, SweepScene};
use sim_core::{
    Chain, EquilibriumProblem, Frame, Hair, HairDirection, InitialGuess, JointLimit, SolveOptions,
    StiffnessProfile, Wall, frame_poses, hair_poses, solve_equilibrium,
};

use super::walls::{
    self, AnchorStyle, Profile, WallFrame, WallKind, WallSpec, draw_anchored_polyline,
    draw_digitized, draw_polyline, draw_sinusoid,
};
use super::{StressError, case_rng};
use crate::reproduce::{K_MAX_N_M_PER_RAD, K_MIN_N_M_PER_RAD, TABLE_4_1_PROFILES};

/// The antenna's length, metres.
pub const ANTENNA_LENGTH_M: f64 = 0.36;
/// The link counts `N` (the base link included).
pub const LINK_COUNTS: [usize; 6] = [4, 9, 18, 36, 72, 150];
/// The link counts of the wide soak ([`Sample::SoakWide`]): [`LINK_COUNTS`] and 300.
pub const WIDE_LINK_COUNTS: [usize; 7] = [4, 9, 18, 36, 72, 150, 300];
/// The friction coefficients.
pub const MUS: [f64; 4] = [0.0, 0.3, 0.6, 1.0];
/// The base speeds, m/s.
pub const SPEEDS_M_PER_S: [f64; 2] = [0.0167, 0.024];
/// The time step, seconds.
pub const STEP_S: f64 = 0.01;
/// A hair's length, in link lengths.
pub const HAIR_LENGTH_LINKS: f64 = 0.45;
/// The base link keeps this far from the wall over the whole sweep, metres.
pub const BASE_CLEARANCE_M: f64 = 0.003;
/// A drawn polyline gets a corner on the start posture this often (rest, angles and
/// tip-on-wall placements).
pub const ANCHOR_SHARE: f64 = 0.4;

/// Which sample a case belongs to: the CI's fixed sample (short sweeps, mostly small `N`)
/// or the soak (longer sweeps, more large `N`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Sample {
    /// `scripts/check`'s sample.
    Ci,
    /// `ANTENNA_SOAK=1`.
    Soak,
    /// `ANTENNA_SOAK=wide`: the soak with `N` drawn from [`WIDE_LINK_COUNTS`] (up to 300
    /// links: budgets and jump tests that scale with `N`, issue #49).
    SoakWide,
}

impl Sample {
    /// Its name in replay lines.
    pub fn name(self) -> &'static str {
        match self {
            Sample::Ci => "ci",
            Sample::Soak => "soak",
            Sample::SoakWide => "soak-wide",
        }
    }

    /// The sample of a name.
    pub fn parse(name: &str) -> Option<Sample> {
        match name {
            "ci" => Some(Sample::Ci),
            "soak" => Some(Sample::Soak),
            "soak-wide" => Some(Sample::SoakWide),
            _ => None,
        }
    }

    /// Relative weights of [`LINK_COUNTS`] in the soak.
    pub const SOAK_LINK_WEIGHTS: [f64; 6] = [20.0, 25.0, 20.0, 15.0, 12.0, 8.0];

    /// Relative weights of [`WIDE_LINK_COUNTS`] in the wide soak.
    pub const SOAK_WIDE_LINK_WEIGHTS: [f64; 7] = [18.0, 20.0, 17.0, 14.0, 11.0, 10.0, 10.0];

    /// The CI sample's link counts, in turn (every 25 cases: 8 of `N = 4`, 7 of 9, 5 of 18,
    /// 3 of 36, one each of 72 and 150), so a small sample has them all in fixed shares.
    pub const CI_LINK_CYCLE: [usize; 25] = [
        4, 9, 18, 4, 9, 36, 4, 9, 18, 72, 4, 9, 18, 4, 9, 36, 4, 9, 18, 150, 4, 9, 18, 36, 4,
    ];

    /// `N` for case `index`.
    fn links(self, rng: &mut impl Rng, index: u64) -> usize {
        match self {
            Sample::Ci => Self::CI_LINK_CYCLE[(index % Self::CI_LINK_CYCLE.len() as u64) as usize],
            Sample::Soak => LINK_COUNTS[weighted(rng, &Self::SOAK_LINK_WEIGHTS)],
            Sample::SoakWide => WIDE_LINK_COUNTS[weighted(rng, &Self::SOAK_WIDE_LINK_WEIGHTS)],
        }
    }

    /// The sweep's duration for `links` links, seconds.
    fn duration_s(self, rng: &mut impl Rng, links: usize) -> f64 {
        match (self, links >= 72) {
            (Sample::Ci, false) => rng.random_range(0.5..=2.0),
            (Sample::Ci, true) => 0.5,
            (Sample::Soak | Sample::SoakWide, false) => rng.random_range(2.0..=6.0),
            (Sample::Soak | Sample::SoakWide, true) => rng.random_range(1.0..=2.0),
        }
    }
}

/// The kinds of placement.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PlacementKind {
    /// [`Placement::Rest`].
    Rest,
    /// [`Placement::Angles`].
    Angles,
    /// [`Placement::Approach`].
    Approach,
    /// [`Placement::TipOnWall`] from a C.
    TipOnWallC,
    /// [`Placement::TipOnWall`] from an S.
    TipOnWallS,
}

impl PlacementKind {
    /// Every kind.
    pub const ALL: [PlacementKind; 5] = [
        PlacementKind::Rest,
        PlacementKind::Angles,
        PlacementKind::Approach,
        PlacementKind::TipOnWallC,
        PlacementKind::TipOnWallS,
    ];

    /// Its name in tables and replay lines.
    pub fn name(self) -> &'static str {
        match self {
            PlacementKind::Rest => "rest",
            PlacementKind::Angles => "angles",
            PlacementKind::Approach => "approach",
            PlacementKind::TipOnWallC => "tip-on-wall C",
            PlacementKind::TipOnWallS => "tip-on-wall S",
        }
    }
}

/// One case: what was drawn, and the scene to sweep.
#[derive(Clone, Debug)]
pub struct Case {
    /// The seed.
    pub seed: u64,
    /// The index under the seed.
    pub index: u64,
    /// The sample.
    pub sample: Sample,
    /// `N`, the links (the base link included).
    pub links: usize,
    /// The stiffness profile.
    pub profile: StiffnessProfile,
    /// Distal hairs on every flexible link.
    pub hairs: bool,
    /// The base angle, degrees.
    pub base_angle_deg: f64,
    /// The base speed along `+x`, m/s.
    pub speed_m_per_s: f64,
    /// The placement's kind.
    pub placement_kind: PlacementKind,
    /// The placement's parameters, in words.
    pub placement_detail: String,
    /// The wall.
    pub wall: WallSpec,
    /// The steps drawn, before the sweep was cut short to keep the base link clear.
    pub drawn_steps: usize,
    /// The scene.
    pub scene: SweepScene,
}

/// The points of a posture, ground frame.
#[derive(Clone, Debug, PartialEq)]
pub struct PosturePoints {
    /// The base pivot.
    pub base_m: Vector2<f64>,
    /// The distal ends of links `0..=n`: joint `i + 1` at index `i`, the tip last.
    pub ends_m: Vec<Vector2<f64>>,
    /// The hair tips (open against their stops), with their links.
    pub hair_tips_m: Vec<(usize, Vector2<f64>)>,
}

impl PosturePoints {
    /// The posture `theta` of `chain` with its base at `base_m`.
    ///
    /// # Errors
    /// [`StressError::Kinematics`].
    pub fn new(
        chain: &Chain,
        theta: &[f64],
        base_m: Vector2<f64>,
    ) -> Result<PosturePoints, StressError> {
        let poses = frame_poses(chain, theta, Frame::GROUND)?;
        let ends_m = (0..=chain.n())
            .map(|i| {
                poses
                    .position_m(Frame::link(i))
                    .map(|p| base_m + p)
                    .ok_or_else(|| StressError::Other(format!("no frame {i}")))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let open: Vec<f64> = chain
            .hairs()
            .iter()
            .map(|h| h.map_or(0.0, |h| h.rest_angle_rad()))
            .collect();
        let hair_tips_m = hair_poses(chain, theta, &open, Frame::GROUND)?
            .into_iter()
            .map(|h| (h.link, base_m + h.tip_m))
            .collect();
        Ok(PosturePoints {
            base_m,
            ends_m,
            hair_tips_m,
        })
    }

    /// The smallest gap of any link (the base link included) or hair tip to `wall`, and the
    /// wall's free normal there.
    pub fn min_gap(&self, wall: &Wall) -> (f64, Vector2<f64>) {
        let mut best = (f64::INFINITY, Vector2::zeros());
        let mut from = self.base_m;
        for end in &self.ends_m {
            let c = wall.segment_contact(&from, end);
            if c.wall.gap_m < best.0 {
                best = (c.wall.gap_m, c.wall.normal);
            }
            from = *end;
        }
        for (_, tip) in &self.hair_tips_m {
            let w = wall.signed_distance(tip);
            if w.gap_m < best.0 {
                best = (w.gap_m, w.normal);
            }
        }
        best
    }

    /// The point farthest along `direction` among the flexible links' ends (joints `2..=n`
    /// and the tip) and the hair tips, and its name.
    fn extreme(&self, direction: &Vector2<f64>) -> (Vector2<f64>, String) {
        let n = self.ends_m.len() - 1;
        let mut best = (f64::NEG_INFINITY, Vector2::zeros(), String::new());
        for (i, p) in self.ends_m.iter().enumerate().skip(1) {
            let h = p.dot(direction);
            if h > best.0 {
                let name = if i == n {
                    "tip".to_owned()
                } else {
                    format!("joint {}", i + 1)
                };
                best = (h, *p, name);
            }
        }
        for (link, p) in &self.hair_tips_m {
            let h = p.dot(direction);
            if h > best.0 {
                best = (h, *p, format!("hair tip of link {link}"));
            }
        }
        (best.1, best.2)
    }
}

/// An index drawn with the relative `weights`.
pub fn weighted(rng: &mut impl Rng, weights: &[f64]) -> usize {
    let total: f64 = weights.iter().sum();
    let mut x = rng.random_range(0.0..total);
    for (i, w) in weights.iter().enumerate() {
        if x < *w {
            return i;
        }
        x -= w;
    }
    weights.len() - 1
}

/// The antenna of a case.
///
/// # Errors
/// [`StressError::Profile`], [`StressError::Chain`].
pub fn antenna(
    links: usize,
    profile: &StiffnessProfile,
    hairs: bool,
    base_angle_rad: f64,
) -> Result<Chain, StressError> {
    let n = links - 1;
    let l = ANTENNA_LENGTH_M / links as f64;
    let k = profile.stiffness_n_m_per_rad(&vec![l; links], K_MIN_N_M_PER_RAD, K_MAX_N_M_PER_RAD)?;
    let mut builder = Chain::builder(n)
        .link_length_m(l)
        .base_angle_rad(base_angle_rad)
        .stiffnesses_nm_per_rad(k)
        .joint_limit(JointLimit::new(-FRAC_PI_2, FRAC_PI_2));
    if hairs {
        for link in 1..=n {
            builder = builder.hair(
                link,
                Hair {
                    direction: HairDirection::Distal,
                    length_m: HAIR_LENGTH_LINKS * l,
                    ..Hair::seed(l)
                },
            );
        }
    }
    Ok(builder.build()?)
}

/// The share of hairs given a compliant root.
pub const COMPLIANT_SHARE: f64 = 0.5;
/// The range of root stiffnesses, N m/rad (log-uniform).
pub const ROOT_STIFFNESS_RANGE_NM_PER_RAD: (f64, f64) = (1e-4, 10.0);
/// Mixed into the case's seed for the root stiffnesses' own stream.
const ROOT_STREAM: u64 = 0x726f_6f74;

/// `chain` with a compliant root on [`COMPLIANT_SHARE`] of its hairs, drawn from `rng`.
///
/// # Errors
/// [`StressError::Chain`].
pub fn with_compliant_roots(chain: Chain, rng: &mut impl Rng) -> Result<Chain, StressError> {
    if chain.hairs().iter().all(Option::is_none) {
        return Ok(chain);
    }
    let (lo, hi) = ROOT_STIFFNESS_RANGE_NM_PER_RAD;
    let mut builder = chain.to_builder().without_hairs();
    for (link, hair) in chain.hairs().iter().enumerate() {
        if let Some(hair) = hair {
            let mut hair = *hair;
            if rng.random_bool(COMPLIANT_SHARE) {
                let k = lo * (hi / lo).powf(rng.random::<f64>());
                hair.root_stiffness_nm_per_rad = Some(k);
            }
            builder = builder.hair(link, hair);
        }
    }
    Ok(builder.build()?)
}

/// A bent posture `theta_1..theta_n`: a C toward the wall (counter-clockwise) or away from
/// it, an S, or wavy; 20-160 deg of bend in all; 15% of the time one joint on its stop.
fn draw_angles(rng: &mut impl Rng, chain: &Chain) -> Vec<f64> {
    let n = chain.n();
    let style = rng.random_range(0..4);
    let per = rng.random_range(20f64..=160.0).to_radians() / n as f64;
    let cap = 85f64.to_radians();
    let mut angles: Vec<f64> = (0..n)
        .map(|j| {
            let wobble = 1.0 + 0.3 * (rng.random::<f64>() - 0.5);
            let a = match style {
                0 => per * wobble,
                1 => -per * wobble,
                2 if j < n / 2 => per * wobble,
                2 => -per * wobble,
                _ => 2.0 * per * (rng.random::<f64>() - 0.5),
            };
            a.clamp(-cap, cap)
        })
        .collect();
    if rng.random_bool(0.15) {
        let j = rng.random_range(0..n);
        let limit = chain.joint_limits()[j + 1];
        angles[j] = if rng.random_bool(0.5) {
            limit.ccw_rad
        } else {
            limit.cw_rad
        };
    }
    angles
}

/// Moves `spec` along its normal until `posture`'s smallest gap to it is `target_m`.
fn place_at_gap(
    mut spec: WallSpec,
    posture: &PosturePoints,
    target_m: f64,
) -> Result<WallSpec, StressError> {
    for _ in 0..60 {
        let (gap, normal) = posture.min_gap(&spec.build()?);
        let error = target_m - gap;
        if error.abs() <= 1e-13 {
            break;
        }
        // Moving the wall by d into the solid opens a gap whose normal is n by -(n . v) d.
        let rate = (-normal.dot(&spec.frame.into_solid())).max(0.05);
        spec = spec.shifted_into_solid(error / rate);
    }
    Ok(spec)
}

/// The base link's gap to `wall` with the base at `base_m`.
fn base_link_gap(chain: &Chain, wall: &Wall, base_m: Vector2<f64>) -> f64 {
    let (s, c) = chain.base_angle_rad().sin_cos();
    let end = base_m + chain.link_lengths_m()[0] * Vector2::new(c, s);
    wall.segment_contact(&base_m, &end).wall.gap_m
}

/// The steps (of `steps`) before the base link comes within [`BASE_CLEARANCE_M`] of `wall`.
fn steps_with_base_clear(chain: &Chain, wall: &Wall, speed_m_per_s: f64, steps: usize) -> usize {
    for k in 0..=steps {
        let base = Vector2::new(speed_m_per_s * (k as f64 * STEP_S), 0.0);
        if base_link_gap(chain, wall, base) < BASE_CLEARANCE_M {
            return k.saturating_sub(1);
        }
    }
    steps
}

/// How far back along the wall's normal (at the point nearest the straight antenna's tip,
/// as [`Placement::Approach`] takes it) the base must start, sliding `along_m` along `+x`,
/// for the straight antenna to start `clearance_m` clear of `wall`.
fn approach_distance(
    chain: &Chain,
    wall: &Wall,
    along_m: f64,
    clearance_m: f64,
) -> Result<f64, StressError> {
    let rest = chain.rest_theta();
    let at_base = PosturePoints::new(chain, &rest, Vector2::zeros())?;
    let tip = at_base.ends_m[chain.n()];
    let away = wall.signed_distance(&tip).normal;
    let forward = Vector2::new(1.0, 0.0);
    let mut distance = clearance_m - at_base.min_gap(wall).0;
    for _ in 0..60 {
        let from = away * distance - forward * along_m;
        let (gap, normal) = PosturePoints::new(chain, &rest, from)?.min_gap(wall);
        let error = clearance_m - gap;
        if error.abs() < 1e-9 {
            break;
        }
        distance = (distance + error / normal.dot(&away).max(0.05)).max(0.0);
    }
    Ok(distance)
}

/// The `u` range of `frame` that the antenna meets over a sweep travelling `travel_m`.
fn span(frame: &WallFrame, travel_m: f64) -> (f64, f64) {
    let (u_base, _) = frame.to_wall(&Vector2::zeros());
    (u_base - 0.25, u_base + 0.40 + travel_m)
}

/// A wall of `kind` in `frame` (not anchored).
fn free_wall(
    rng: &mut impl Rng,
    kind: WallKind,
    frame: WallFrame,
    link_m: f64,
    travel_m: f64,
    mu: f64,
) -> Result<WallSpec, StressError> {
    let sp = span(&frame, travel_m);
    let profile = match kind {
        WallKind::Line => Profile::Line,
        WallKind::Polyline => draw_polyline(rng, link_m, sp),
        WallKind::Sinusoid => draw_sinusoid(rng, link_m),
        WallKind::Digitized => draw_digitized(rng, link_m, sp, &frame)?,
    };
    Ok(WallSpec {
        kind,
        frame,
        profile,
        mu,
        corner_at: None,
    })
}

/// A convex anchor style (the wall stays behind the anchor).
fn convex_style(rng: &mut impl Rng) -> AnchorStyle {
    [
        AnchorStyle::StepUp,
        AnchorStyle::StepDown,
        AnchorStyle::Tooth,
    ][rng.random_range(0..3)]
}

/// A polyline with a corner exactly on `posture`'s point nearest the wall, clear of the
/// posture; `None` when that point is the base link's end.
fn anchored_on_posture(
    rng: &mut impl Rng,
    posture: &PosturePoints,
    angle_rad: f64,
    link_m: f64,
    travel_m: f64,
    mu: f64,
) -> Result<Option<WallSpec>, StressError> {
    let probe = WallFrame {
        origin_m: Vector2::zeros(),
        angle_rad,
    };
    let (point, name) = posture.extreme(&probe.into_solid());
    let frame = WallFrame {
        origin_m: point,
        angle_rad,
    };
    let sp = span(&frame, travel_m);
    let want_pocket = rng.random_bool(0.5);
    for attempt in 0..4 {
        let style = if want_pocket && attempt < 3 {
            AnchorStyle::Pocket
        } else {
            convex_style(rng)
        };
        let spec = WallSpec {
            kind: WallKind::Polyline,
            frame,
            profile: draw_anchored_polyline(rng, link_m, sp, style),
            mu,
            corner_at: Some(name.clone()),
        };
        if posture.min_gap(&spec.build()?).0 >= -1e-12 {
            return Ok(Some(spec));
        }
    }
    Ok(None)
}

impl Case {
    /// Case `index` of `sample` under `seed`.
    ///
    /// # Errors
    /// [`StressError`]: the generator could not build it (a bug of the generator).
    pub fn generate(seed: u64, index: u64, sample: Sample) -> Result<Case, StressError> {
        let mut rng = case_rng(seed, index);
        let rng = &mut rng;
        let links = sample.links(rng, index);
        let profile = TABLE_4_1_PROFILES[rng.random_range(0..TABLE_4_1_PROFILES.len())].clone();
        let hairs = rng.random_bool(0.5);
        let mu = MUS[rng.random_range(0..MUS.len())];
        let base_angle_deg: f64 = rng.random_range(20.0..=40.0);
        let speed = SPEEDS_M_PER_S[rng.random_range(0..SPEEDS_M_PER_S.len())];
        let kind = WallKind::ALL[weighted(rng, &[0.15, 0.35, 0.25, 0.25])];
        let placement_kind = PlacementKind::ALL[rng.random_range(0..PlacementKind::ALL.len())];
        let angle_rad = rng.random_range(-15f64..=5.0).to_radians();
        let drawn_steps = (sample.duration_s(rng, links) / STEP_S).round() as usize;
        let travel = speed * drawn_steps as f64 * STEP_S;
        let chain = antenna(links, &profile, hairs, base_angle_deg.to_radians())?;
        let chain = with_compliant_roots(chain, &mut case_rng(seed ^ ROOT_STREAM, index))?;
        let link_m = ANTENNA_LENGTH_M / links as f64;
        let base = Vector2::zeros();
        let anchor = kind == WallKind::Polyline && rng.random_bool(ANCHOR_SHARE);
        let frame_at = |d: f64| {
            WallFrame {
                origin_m: Vector2::zeros(),
                angle_rad,
            }
            .shifted_into_solid(d)
        };

        let (wall, placement, placement_detail) = match placement_kind {
            PlacementKind::Rest | PlacementKind::Angles => {
                let (theta, detail, target) = if placement_kind == PlacementKind::Rest {
                    let gap = rng.random_range(0.0002..=0.015);
                    (
                        chain.rest_theta(),
                        format!("rest, {:.2} mm short", gap * 1e3),
                        gap,
                    )
                } else {
                    let angles = draw_angles(rng, &chain);
                    let gap = if rng.random_bool(0.25) {
                        0.0
                    } else {
                        rng.random_range(0.0..=0.005)
                    };
                    let mut theta = vec![chain.base_angle_rad()];
                    theta.extend_from_slice(&angles);
                    let deg: Vec<String> = angles
                        .iter()
                        .map(|a| format!("{:.2}", a.to_degrees()))
                        .collect();
                    (
                        theta,
                        format!("angles [{}] deg, {:.2} mm short", deg.join(","), gap * 1e3),
                        gap,
                    )
                };
                let posture = PosturePoints::new(&chain, &theta, base)?;
                let anchored = if anchor {
                    anchored_on_posture(rng, &posture, angle_rad, link_m, travel, mu)?
                } else {
                    None
                };
                let (wall, detail) = match anchored {
                    Some(w) => {
                        let detail = match detail.split_once(" deg, ") {
                            Some((angles, _)) => format!("{angles} deg, touching at the corner"),
                            None => "rest, touching at the corner".to_owned(),
                        };
                        (w, detail)
                    }
                    None => {
                        let spec = free_wall(rng, kind, frame_at(0.2), link_m, travel, mu)?;
                        (place_at_gap(spec, &posture, target)?, detail)
                    }
                };
                let placement = if placement_kind == PlacementKind::Rest {
                    Placement::Rest
                } else {
                    Placement::Angles(theta[1..].to_vec())
                };
                (wall, placement, detail)
            }
            PlacementKind::Approach => {
                let depth = if rng.random_bool(0.2) {
                    0.0
                } else {
                    rng.random_range(0.001..=0.04)
                };
                let posture = PosturePoints::new(&chain, &chain.rest_theta(), base)?;
                let spec = free_wall(rng, kind, frame_at(0.2), link_m, travel, mu)?;
                let mut spec = place_at_gap(spec, &posture, -depth)?;
                // The base link must end clear of the wall: take depth off where it would not.
                for _ in 0..20 {
                    let short = BASE_CLEARANCE_M - base_link_gap(&chain, &spec.build()?, base);
                    if short <= 0.0 {
                        break;
                    }
                    spec = spec.shifted_into_solid(short + 1e-4);
                }
                let built = spec.build()?;
                let depth = (-posture.min_gap(&built).0).max(0.0);
                let along_m = rng.random_range(-0.05..=0.0);
                let clearance = rng.random_range(0.005..=0.02);
                let distance_m = approach_distance(&chain, &built, along_m, clearance)?;
                let steps = rng.random_range(20..=100);
                let detail = format!(
                    "approach, {:.2} mm deep, from {:.2} mm along the normal ({:.2} mm clear), \
                     {:.2} mm along the motion, {steps} steps",
                    depth * 1e3,
                    distance_m * 1e3,
                    clearance * 1e3,
                    along_m * 1e3
                );
                (
                    spec,
                    Placement::Approach {
                        wall: 0,
                        distance_m,
                        along_m,
                        steps,
                    },
                    detail,
                )
            }
            PlacementKind::TipOnWallC | PlacementKind::TipOnWallS => {
                let start = if placement_kind == PlacementKind::TipOnWallC {
                    InitialGuess::C
                } else {
                    InitialGuess::S
                };
                let d = rng.random_range(0.10..=0.25);
                let ahead_m = rng.random_range(-0.05..=0.10);
                let frame0 = frame_at(d);
                let detail = format!(
                    "tip-on-wall {start:?}, baseline {:.2} mm away, tip {:.2} mm ahead",
                    d * 1e3,
                    ahead_m * 1e3
                );
                let mut wall = None;
                if anchor {
                    // The pin the placement will find: the baseline's point `ahead_m` along x.
                    let u = (ahead_m - frame0.origin_m.x) / frame0.tangent().x;
                    let pin = frame0.to_ground(u, 0.0);
                    let frame = WallFrame {
                        origin_m: pin,
                        angle_rad,
                    };
                    let problem = EquilibriumProblem::new(&chain).with_tip_pin_m(pin - base);
                    let pinned = solve_equilibrium(&problem, &start, &SolveOptions::default())
                        .ok()
                        .filter(|e| e.converged);
                    if let Some(eq) = pinned {
                        let posture = PosturePoints::new(&chain, &eq.theta_rad, base)?;
                        let n = chain.n();
                        let (ua, va) = frame.to_wall(&posture.ends_m[n - 1]);
                        let edge_ok = ua < -1e-3
                            && va.abs() <= ua.abs() * walls::SLOPE_DEG.1.to_radians().tan()
                            && va.abs() <= 0.08;
                        let (style, at) = if edge_ok && rng.random_bool(0.4) {
                            (AnchorStyle::Edge(ua, va), format!("tip and joint {n}"))
                        } else if rng.random_bool(0.3) {
                            (AnchorStyle::Pocket, "tip".to_owned())
                        } else {
                            (convex_style(rng), "tip".to_owned())
                        };
                        wall = Some(WallSpec {
                            kind,
                            frame,
                            profile: draw_anchored_polyline(
                                rng,
                                link_m,
                                span(&frame, travel),
                                style,
                            ),
                            mu,
                            corner_at: Some(at),
                        });
                    }
                }
                let wall = match wall {
                    Some(w) => w,
                    None => free_wall(rng, kind, frame0, link_m, travel, mu)?,
                };
                (
                    wall,
                    Placement::TipOnWall {
                        wall: 0,
                        ahead_m,
                        start,
                    },
                    detail,
                )
            }
        };

        let built = wall.build()?;
        let steps = steps_with_base_clear(&chain, &built, speed, drawn_steps);
        let scene = SweepScene {
            motion: Motion {
                velocity_m_per_s: Vector2::new(speed, 0.0),
                duration_s: steps as f64 * STEP_S,
                step_s: STEP_S,
            },
            placement,
            ..SweepScene::new(chain, vec![built])
        };
        Ok(Case {
            seed,
            index,
            sample,
            links,
            profile,
            hairs,
            base_angle_deg,
            speed_m_per_s: speed,
            placement_kind,
            placement_detail,
            wall,
            drawn_steps,
            scene,
        })
    }

    /// The root stiffnesses of the compliant hairs, N m/rad, by link.
    pub fn root_stiffnesses_nm_per_rad(&self) -> Vec<f64> {
        self.scene
            .chain
            .hairs()
            .iter()
            .flatten()
            .filter_map(|h| h.root_stiffness_nm_per_rad)
            .collect()
    }

    /// `none`, `distal`, or `distal` and the compliant hairs' range of root stiffness.
    fn hairs_name(&self) -> String {
        if !self.hairs {
            return "none".into();
        }
        let k = self.root_stiffnesses_nm_per_rad();
        if k.is_empty() {
            return "distal".into();
        }
        let lo = k.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = k.iter().copied().fold(0.0, f64::max);
        format!(
            "distal({}-compliant,k_r={lo:.1e}..{hi:.1e}N*m/rad)",
            k.len()
        )
    }

    /// The steps the sweep takes.
    pub fn steps(&self) -> usize {
        self.scene.motion.steps()
    }

    /// One line that names the case and its parameters (rerun it with
    /// `ANTENNA_STRESS_REPLAY=<sample>:<seed>:<index>`).
    pub fn replay_line(&self) -> String {
        format!(
            "ANTENNA_STRESS_REPLAY={}:{}:{} | N={} profile={} hairs={} base={:.3}deg v={}mm/s steps={}{} | \
             placement: {} | wall: {}",
            self.sample.name(),
            self.seed,
            self.index,
            self.links,
            self.profile.name(),
            self.hairs_name(),
            self.base_angle_deg,
            self.speed_m_per_s * 1e3,
            self.steps(),
            if self.steps() < self.drawn_steps {
                format!(" (cut from {})", self.drawn_steps)
            } else {
                String::new()
            },
            self.placement_detail,
            self.wall.describe()
        )
    }
}
