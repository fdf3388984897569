//! Seeded random walls: lines (the 4.2.1 control), polylines with steps and bumps (convex
//! and concave corners from 5 to 85 degrees, edges shorter than a link, corners placed
//! exactly at a posture's joints), sinusoids whose crests bend down to a radius of half a
//! link, and noisy digitized lines and trapezoids.
//!
//! Every wall is drawn in its own frame ([`WallFrame`]): `u` along the wall's direction,
//! `v` into the solid (away from the antenna), the baseline at `v = 0`, solid on the left of
//! the direction ([`SolidSide::Left`]). A polyline's shape is a graph `v(u)` (knots with
//! strictly increasing `u`), so it never crosses itself. A corner's angle is the angle the
//! wall turns through there (a ramp of slope `s` between two flats turns by `s` at each
//! end); it is convex where the solid juts into free space and concave where free space
//! pockets into the solid.

use std::f64::consts::TAU;

use nalgebra::Vector2;
use rand::Rng;
use sim_core::{Line, Polyline, Sinusoid, SolidSide, Surface, SurfaceMap, Wall, WallShape};

use super::StressError;

/// Step heights of polylines and trapezoids, metres.
pub const STEP_HEIGHT_M: (f64, f64) = (0.01, 0.07);
/// Ramp slopes, degrees: the corners' angles.
pub const SLOPE_DEG: (f64, f64) = (5.0, 85.0);
/// Sinusoid amplitudes, metres.
pub const AMPLITUDE_M: (f64, f64) = (0.005, 0.03);
/// The largest crest radius a sinusoid is drawn with, metres (1 cycle/m at 5 mm amplitude).
pub const MAX_CREST_RADIUS_M: f64 = 5.0;
/// The smallest crest radius, in link lengths.
pub const MIN_CREST_RADIUS_LINKS: f64 = 0.5;
/// Digitized walls: sample spacing, metres.
pub const SPACING_M: (f64, f64) = (0.001, 0.005);
/// Digitized walls: the noise's standard deviation, metres.
pub const NOISE_M: (f64, f64) = (0.000_05, 0.000_5);
/// Digitized walls: at most this many vertices (the solver's polyline queries are
/// `O(vertices)`).
pub const MAX_DIGITIZED_POINTS: usize = 300;
/// How far steps may take a wall from its baseline: toward the antenna (negative) and into
/// the solid, metres.
const LEVEL_RANGE_M: (f64, f64) = (-0.08, 0.10);
/// The flat run before the first and after the last feature, metres (the end rays go on
/// from there).
const RUN_OUT_M: f64 = 1.0;

/// The kinds of wall.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum WallKind {
    /// A straight line (the 4.2.1 wall): the control.
    Line,
    /// A polyline: a baseline with 1-3 steps, bumps or notches.
    Polyline,
    /// A sinusoid.
    Sinusoid,
    /// A line or a trapezoid sampled every 1-5 mm with noise.
    Digitized,
}

impl WallKind {
    /// Every kind.
    pub const ALL: [WallKind; 4] = [
        WallKind::Line,
        WallKind::Polyline,
        WallKind::Sinusoid,
        WallKind::Digitized,
    ];

    /// Its name in tables and replay lines.
    pub fn name(self) -> &'static str {
        match self {
            WallKind::Line => "line",
            WallKind::Polyline => "polyline",
            WallKind::Sinusoid => "sinusoid",
            WallKind::Digitized => "digitized",
        }
    }
}

/// A wall's own frame in the ground frame: its baseline through `origin_m` along
/// `angle_rad`; `u` along it, `v` into the solid (90 degrees counter-clockwise of `u`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallFrame {
    /// The point `u = v = 0`, metres.
    pub origin_m: Vector2<f64>,
    /// The direction of `u`, radians from the ground x-axis.
    pub angle_rad: f64,
}

impl WallFrame {
    /// The unit vector along `u`.
    pub fn tangent(&self) -> Vector2<f64> {
        Vector2::new(self.angle_rad.cos(), self.angle_rad.sin())
    }

    /// The unit vector along `v` (into the solid).
    pub fn into_solid(&self) -> Vector2<f64> {
        Vector2::new(-self.angle_rad.sin(), self.angle_rad.cos())
    }

    /// The ground point of `(u, v)`; `(0, 0)` is `origin_m` exactly.
    pub fn to_ground(&self, u: f64, v: f64) -> Vector2<f64> {
        self.origin_m + self.tangent() * u + self.into_solid() * v
    }

    /// `(u, v)` of a ground point.
    pub fn to_wall(&self, p: &Vector2<f64>) -> (f64, f64) {
        let d = p - self.origin_m;
        (d.dot(&self.tangent()), d.dot(&self.into_solid()))
    }

    /// The same frame moved `delta_m` into the solid (away from the antenna).
    pub fn shifted_into_solid(&self, delta_m: f64) -> WallFrame {
        WallFrame {
            origin_m: self.origin_m + self.into_solid() * delta_m,
            angle_rad: self.angle_rad,
        }
    }
}

/// The line or trapezoid a digitized wall samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Underlying {
    /// A straight line.
    Line,
    /// A trapezoidal bump or notch.
    Trapezoid,
}

/// A wall's shape in its frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Profile {
    /// The baseline itself.
    Line,
    /// A graph `v(u)` through `knots` (strictly increasing `u`), metres.
    Polyline {
        /// The vertices `(u, v)`.
        knots: Vec<(f64, f64)>,
        /// Knots placed exactly at a posture's joint (or hair tip).
        anchors: Vec<usize>,
    },
    /// `v = amplitude sin(2 pi frequency u + phase)`.
    Sinusoid {
        /// Amplitude, metres.
        amplitude_m: f64,
        /// Cycles per metre.
        frequency_per_m: f64,
        /// Phase at `u = 0`, radians.
        phase_rad: f64,
    },
    /// Noisy samples `(u, v)` of a line or a trapezoid, with a clean vertex 1 m beyond each
    /// end so the end rays run along the baseline.
    Digitized {
        /// The vertices.
        points: Vec<(f64, f64)>,
        /// What was sampled.
        underlying: Underlying,
        /// The sample spacing along the wall, metres.
        spacing_m: f64,
        /// The noise's standard deviation, metres.
        noise_m: f64,
    },
}

/// A corner of a polyline wall.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Corner {
    /// The vertex.
    pub vertex: usize,
    /// The angle the wall turns through there, degrees (> 0).
    pub turn_deg: f64,
    /// The solid juts into free space (it can press on a link between its joints); else
    /// free space pockets into the solid.
    pub convex: bool,
}

/// The corners of a polyline through `vertices` with its solid on `solid`'s side (vertices
/// where the wall goes straight on are skipped).
pub fn polyline_corners(vertices: &[Vector2<f64>], solid: SolidSide) -> Vec<Corner> {
    let mut out = Vec::new();
    for i in 1..vertices.len().saturating_sub(1) {
        let a = vertices[i] - vertices[i - 1];
        let b = vertices[i + 1] - vertices[i];
        let turn = (a.x * b.y - a.y * b.x).atan2(a.dot(&b));
        if turn.abs() < 1e-12 {
            continue;
        }
        // Turning toward the solid side makes the solid's angle there less than 180 deg.
        let toward_left = turn > 0.0;
        out.push(Corner {
            vertex: i,
            turn_deg: turn.abs().to_degrees(),
            convex: toward_left == (solid == SolidSide::Left),
        });
    }
    out
}

/// The curvature radius of a sinusoid's crests, `1 / (A (2 pi f)^2)`, metres.
pub fn crest_radius_m(amplitude_m: f64, frequency_per_m: f64) -> f64 {
    1.0 / (amplitude_m * (TAU * frequency_per_m).powi(2))
}

/// A wall of the suite: its kind, frame, shape and friction.
#[derive(Clone, Debug, PartialEq)]
pub struct WallSpec {
    /// The kind.
    pub kind: WallKind,
    /// Where it is.
    pub frame: WallFrame,
    /// Its shape.
    pub profile: Profile,
    /// Coulomb friction of its smooth surface.
    pub mu: f64,
    /// Which point of the start posture a corner was placed on exactly (`"joint 5"`,
    /// `"tip"`, `"hair tip of link 3"`, `"tip and joint 8"`), if any.
    pub corner_at: Option<String>,
}

impl WallSpec {
    /// The vertices of a polyline or digitized wall, ground frame (empty for the others).
    pub fn vertices_m(&self) -> Vec<Vector2<f64>> {
        match &self.profile {
            Profile::Polyline { knots: p, .. } | Profile::Digitized { points: p, .. } => {
                p.iter().map(|&(u, v)| self.frame.to_ground(u, v)).collect()
            }
            Profile::Line | Profile::Sinusoid { .. } => Vec::new(),
        }
    }

    /// The sim-core wall.
    ///
    /// # Errors
    /// [`StressError::Wall`] when sim-core refuses the shape.
    pub fn build(&self) -> Result<Wall, StressError> {
        let surfaces = SurfaceMap::uniform(Surface::Smooth { mu: self.mu })?;
        let f = &self.frame;
        let shape: WallShape = match &self.profile {
            Profile::Line => Line::new(f.origin_m, f.angle_rad, SolidSide::Left)?.into(),
            Profile::Polyline { .. } | Profile::Digitized { .. } => {
                Polyline::new(self.vertices_m(), SolidSide::Left)?.into()
            }
            Profile::Sinusoid {
                amplitude_m,
                frequency_per_m,
                phase_rad,
            } => Sinusoid::new(
                f.origin_m,
                f.angle_rad,
                *amplitude_m,
                *frequency_per_m,
                *phase_rad,
                SolidSide::Left,
            )?
            .into(),
        };
        Ok(Wall::new(shape, surfaces))
    }

    /// The corners of a polyline or digitized wall (none for the others).
    pub fn corners(&self) -> Vec<Corner> {
        polyline_corners(&self.vertices_m(), SolidSide::Left)
    }

    /// The corners at anchored knots (placed exactly on a posture's point).
    pub fn anchored_vertices(&self) -> Vec<usize> {
        match &self.profile {
            Profile::Polyline { anchors, .. } => anchors.clone(),
            _ => Vec::new(),
        }
    }

    /// The shortest edge of a polyline or digitized wall, metres (`None` for the others).
    pub fn shortest_edge_m(&self) -> Option<f64> {
        let v = self.vertices_m();
        v.windows(2).map(|w| (w[1] - w[0]).norm()).reduce(f64::min)
    }

    /// A sinusoid's crest radius, metres.
    pub fn crest_radius_m(&self) -> Option<f64> {
        match self.profile {
            Profile::Sinusoid {
                amplitude_m,
                frequency_per_m,
                ..
            } => Some(crest_radius_m(amplitude_m, frequency_per_m)),
            _ => None,
        }
    }

    /// The same wall moved `delta_m` into the solid.
    pub fn shifted_into_solid(&self, delta_m: f64) -> WallSpec {
        WallSpec {
            frame: self.frame.shifted_into_solid(delta_m),
            ..self.clone()
        }
    }

    /// The wall in a few words, for replay lines.
    pub fn describe(&self) -> String {
        let f = &self.frame;
        let mut s = format!(
            "{} mu={} angle={:.2}deg origin=({:.4},{:.4})",
            self.kind.name(),
            self.mu,
            f.angle_rad.to_degrees(),
            f.origin_m.x,
            f.origin_m.y
        );
        match &self.profile {
            Profile::Line => {}
            Profile::Polyline { knots, .. } => {
                let corners = self.corners();
                let list: Vec<String> = corners
                    .iter()
                    .map(|c| format!("{}{:.1}", if c.convex { "+" } else { "-" }, c.turn_deg))
                    .collect();
                s += &format!(
                    " vertices={} corners(deg,+convex)=[{}] shortest-edge={:.1}mm",
                    knots.len(),
                    list.join(" "),
                    1e3 * self.shortest_edge_m().unwrap_or(f64::NAN)
                );
            }
            Profile::Sinusoid {
                amplitude_m,
                frequency_per_m,
                phase_rad,
            } => {
                s += &format!(
                    " A={:.1}mm f={:.2}/m phase={:.1}deg crest-radius={:.2}mm",
                    amplitude_m * 1e3,
                    frequency_per_m,
                    phase_rad.to_degrees(),
                    1e3 * crest_radius_m(*amplitude_m, *frequency_per_m)
                );
            }
            Profile::Digitized {
                points,
                underlying,
                spacing_m,
                noise_m,
            } => {
                s += &format!(
                    " of a {} points={} spacing={:.2}mm noise={:.3}mm",
                    match underlying {
                        Underlying::Line => "line",
                        Underlying::Trapezoid => "trapezoid",
                    },
                    points.len(),
                    spacing_m * 1e3,
                    noise_m * 1e3
                );
            }
        }
        if let Some(at) = &self.corner_at {
            s += &format!(" corner-at={at}");
        }
        s
    }
}

/// A standard normal deviate (Box-Muller).
fn gaussian(rng: &mut impl Rng) -> f64 {
    let u1: f64 = rng.random::<f64>().max(1e-300);
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
}

/// A ramp slope, radians.
fn slope(rng: &mut impl Rng) -> f64 {
    rng.random_range(SLOPE_DEG.0..=SLOPE_DEG.1).to_radians()
}

/// A flat stretch: half the time shorter than a link.
fn plateau(rng: &mut impl Rng, link_m: f64) -> f64 {
    if rng.random_bool(0.5) {
        link_m * rng.random_range(0.2..1.0)
    } else {
        rng.random_range(link_m..(2.0 * link_m).max(0.12))
    }
}

/// The flat between two features.
fn gap(rng: &mut impl Rng, link_m: f64) -> f64 {
    if rng.random_bool(0.4) {
        link_m * rng.random_range(0.2..1.0)
    } else {
        rng.random_range(0.02..0.15)
    }
}

/// One feature of a stepped wall.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Feature {
    /// A ramp into the solid (the wall retreats).
    StepUp,
    /// A ramp toward the antenna.
    StepDown,
    /// Toward the antenna and back.
    Bump,
    /// Into the solid and back.
    Notch,
}

/// Builds a graph `v(u)` knot by knot.
struct Knots {
    knots: Vec<(f64, f64)>,
}

impl Knots {
    fn start(u: f64, v: f64) -> Knots {
        Knots {
            knots: vec![(u, v)],
        }
    }

    fn last(&self) -> (f64, f64) {
        self.knots.last().copied().unwrap_or((0.0, 0.0))
    }

    fn push(&mut self, u: f64, v: f64) {
        let (u0, _) = self.last();
        if u > u0 + 1e-9 {
            self.knots.push((u, v));
        }
    }

    /// A flat run to `u`.
    fn flat_to(&mut self, u: f64) {
        let (_, v) = self.last();
        self.push(u, v);
    }

    /// A ramp changing the level by `dv` at `slope_rad`.
    fn ramp(&mut self, dv: f64, slope_rad: f64) {
        let (u, v) = self.last();
        self.push(u + dv.abs() / slope_rad.tan(), v + dv);
    }

    /// One feature of height 1-7 cm within the level range `bounds`.
    fn feature(&mut self, rng: &mut impl Rng, link_m: f64, bounds: (f64, f64)) {
        let (_, level) = self.last();
        let room = (bounds.1 - level).max(level - bounds.0);
        let h = rng
            .random_range(STEP_HEIGHT_M.0..=STEP_HEIGHT_M.1)
            .min(room)
            .max(1e-3);
        let up = level + h <= bounds.1 + 1e-12;
        let down = level - h >= bounds.0 - 1e-12;
        let mut options = Vec::new();
        if up {
            options.extend([Feature::StepUp, Feature::Notch]);
        }
        if down {
            options.extend([Feature::StepDown, Feature::Bump]);
        }
        if options.is_empty() {
            return;
        }
        match options[rng.random_range(0..options.len())] {
            Feature::StepUp => self.ramp(h, slope(rng)),
            Feature::StepDown => self.ramp(-h, slope(rng)),
            Feature::Bump => {
                self.ramp(-h, slope(rng));
                let (u, _) = self.last();
                self.flat_to(u + plateau(rng, link_m));
                self.ramp(h, slope(rng));
            }
            Feature::Notch => {
                self.ramp(h, slope(rng));
                let (u, _) = self.last();
                self.flat_to(u + plateau(rng, link_m));
                self.ramp(-h, slope(rng));
            }
        }
    }

    /// `count` features separated by flats, then a flat run to `end_u + RUN_OUT_M`.
    fn features_then_end(
        &mut self,
        rng: &mut impl Rng,
        link_m: f64,
        count: usize,
        bounds: (f64, f64),
        end_u: f64,
    ) {
        for k in 0..count {
            if k > 0 {
                let (u, _) = self.last();
                self.flat_to(u + gap(rng, link_m));
            }
            self.feature(rng, link_m, bounds);
        }
        let (u, _) = self.last();
        self.flat_to(u.max(end_u) + RUN_OUT_M);
    }
}

/// A stepped polyline over `span` (the `u` range the antenna meets): a baseline with 1-3
/// steps, bumps or notches at random places.
pub fn draw_polyline(rng: &mut impl Rng, link_m: f64, span: (f64, f64)) -> Profile {
    let (lo, hi) = span;
    let count = rng.random_range(1..=3);
    let mut k = Knots::start(lo - RUN_OUT_M, 0.0);
    k.flat_to(lo + rng.random_range(0.0..0.5) * (hi - lo));
    k.features_then_end(rng, link_m, count, LEVEL_RANGE_M, hi);
    Profile::Polyline {
        knots: k.knots,
        anchors: Vec::new(),
    }
}

/// How a corner is put on a posture's point (the knot `(0, 0)`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AnchorStyle {
    /// Flat, then a ramp into the solid: a convex corner.
    StepUp,
    /// A ramp down from the solid, then flat: a convex corner.
    StepDown,
    /// Ramps into the solid on both sides: a convex tooth.
    Tooth,
    /// Ramps toward the antenna on both sides: a concave pocket.
    Pocket,
    /// An edge from a second anchored point `(u, v)` (`u < 0`) to `(0, 0)`, flat before and
    /// after: a link lying on the wall's edge with corners at both its ends.
    Edge(f64, f64),
}

impl AnchorStyle {
    /// Whether every point of the wall stays at `v >= 0` (so a posture with `v <= 0`
    /// everywhere is clear of it).
    pub fn stays_behind_anchor(self) -> bool {
        matches!(
            self,
            AnchorStyle::StepUp | AnchorStyle::StepDown | AnchorStyle::Tooth
        )
    }
}

/// A stepped polyline with a corner exactly at `(0, 0)`, more features after it, over
/// `span`. With a convex style the wall stays at `v >= 0` everywhere.
pub fn draw_anchored_polyline(
    rng: &mut impl Rng,
    link_m: f64,
    span: (f64, f64),
    style: AnchorStyle,
) -> Profile {
    let (lo, hi) = span;
    let bounds = if style.stays_behind_anchor() {
        (0.0, LEVEL_RANGE_M.1)
    } else {
        LEVEL_RANGE_M
    };
    let height = |rng: &mut dyn rand::RngCore| rng.random_range(STEP_HEIGHT_M.0..=STEP_HEIGHT_M.1);
    // Two slopes of a tooth or pocket that turn 10-85 deg together, each at least 5.
    let split = |rng: &mut dyn rand::RngCore| {
        let total: f64 = rng.random_range(2.0 * SLOPE_DEG.0..=SLOPE_DEG.1);
        let first: f64 = rng.random_range(SLOPE_DEG.0..=total - SLOPE_DEG.0);
        (first.to_radians(), (total - first).to_radians())
    };
    let start = lo.min(-0.01) - RUN_OUT_M;
    let mut anchors = Vec::new();
    let mut k;
    match style {
        AnchorStyle::StepUp => {
            k = Knots::start(start, 0.0);
            k.push(0.0, 0.0);
            anchors.push(k.knots.len() - 1);
            let h = height(rng);
            k.ramp(h, slope(rng));
        }
        AnchorStyle::StepDown => {
            let h = height(rng);
            let s = slope(rng);
            k = Knots::start(start - h / s.tan(), h);
            k.push(-h / s.tan(), h);
            k.push(0.0, 0.0);
            anchors.push(k.knots.len() - 1);
        }
        AnchorStyle::Tooth | AnchorStyle::Pocket => {
            let sign = if style == AnchorStyle::Tooth {
                1.0
            } else {
                -1.0
            };
            let (s1, s2) = split(rng);
            let (h1, h2) = (height(rng), height(rng));
            k = Knots::start(start - h1 / s1.tan(), sign * h1);
            k.push(-h1 / s1.tan(), sign * h1);
            k.push(0.0, 0.0);
            anchors.push(k.knots.len() - 1);
            k.ramp(sign * h2, s2);
        }
        AnchorStyle::Edge(ua, va) => {
            let s = slope(rng);
            let before = ua - gap(rng, link_m);
            let ramp_start = before - va.abs() / s.tan();
            k = Knots::start(ramp_start.min(start) - RUN_OUT_M, 0.0);
            k.push(ramp_start, 0.0);
            k.push(before, va);
            k.push(ua, va);
            anchors.push(k.knots.len() - 1);
            k.push(0.0, 0.0);
            anchors.push(k.knots.len() - 1);
        }
    }
    let (u, _) = k.last();
    k.flat_to(u + gap(rng, link_m));
    let count = rng.random_range(0..=2);
    k.features_then_end(rng, link_m, count, bounds, hi);
    Profile::Polyline {
        knots: k.knots,
        anchors,
    }
}

/// A sinusoid: amplitude 0.5-3 cm, the crest radius `1 / (A (2 pi f)^2)` a quarter of the
/// time exactly half a link, else log-uniform from half a link to 5 m.
pub fn draw_sinusoid(rng: &mut impl Rng, link_m: f64) -> Profile {
    let amplitude_m = rng.random_range(AMPLITUDE_M.0..=AMPLITUDE_M.1);
    let r_min = MIN_CREST_RADIUS_LINKS * link_m;
    let radius = if rng.random_bool(0.25) {
        r_min
    } else {
        rng.random_range(r_min.ln()..MAX_CREST_RADIUS_M.ln()).exp()
    };
    Profile::Sinusoid {
        amplitude_m,
        frequency_per_m: 1.0 / (TAU * (radius * amplitude_m).sqrt()),
        phase_rad: rng.random_range(0.0..TAU),
    }
}

/// Points every `spacing` of arclength along the graph through `knots`, from `u = a` to
/// `u = b`, each with the unit normal of its edge (toward `+v`) and tangent.
fn sample_graph(knots: &[(f64, f64)], a: f64, b: f64, spacing: f64) -> Vec<[f64; 6]> {
    let mut out = Vec::new();
    let mut carry = 0.0; // arclength from the last sample to the current edge's start
    let mut started = false;
    for w in knots.windows(2) {
        let (p, q) = (Vector2::new(w[0].0, w[0].1), Vector2::new(w[1].0, w[1].1));
        if q.x <= a || p.x >= b {
            continue;
        }
        // Clip the edge to [a, b].
        let d = q - p;
        let clip = |u: f64| p + d * ((u - p.x) / d.x);
        let from = if p.x < a { clip(a) } else { p };
        let to = if q.x > b { clip(b) } else { q };
        let len = (to - from).norm();
        if len <= 0.0 {
            continue;
        }
        let t = (to - from) / len;
        let n = Vector2::new(-t.y, t.x);
        let mut s = if started { spacing - carry } else { 0.0 };
        started = true;
        while s <= len {
            let x = from + t * s;
            out.push([x.x, x.y, n.x, n.y, t.x, t.y]);
            s += spacing;
        }
        carry = len - (s - spacing);
    }
    out
}

/// A noisy digitized line or trapezoid over `span`, valid in `frame` (resampled until
/// sim-core accepts it as a polyline).
///
/// # Errors
/// [`StressError::Other`] when no valid sample was found.
pub fn draw_digitized(
    rng: &mut impl Rng,
    link_m: f64,
    span: (f64, f64),
    frame: &WallFrame,
) -> Result<Profile, StressError> {
    let spacing = rng.random_range(SPACING_M.0..=SPACING_M.1);
    let noise = rng.random_range(NOISE_M.0..=NOISE_M.1);
    let a = span.0 + 0.1;
    let b = span.1.min(a + (MAX_DIGITIZED_POINTS - 4) as f64 * spacing);
    let underlying = if rng.random_bool(0.5) {
        Underlying::Line
    } else {
        Underlying::Trapezoid
    };
    let knots = match underlying {
        Underlying::Line => vec![(a - RUN_OUT_M, 0.0), (b + RUN_OUT_M, 0.0)],
        Underlying::Trapezoid => {
            let mut k = Knots::start(a - RUN_OUT_M, 0.0);
            k.flat_to(a + rng.random_range(0.05..0.5) * (b - a));
            k.feature(rng, link_m, LEVEL_RANGE_M);
            let (u, _) = k.last();
            k.flat_to(u.max(b) + RUN_OUT_M);
            k.knots
        }
    };
    let level_at = |u: f64| {
        knots
            .windows(2)
            .find(|w| w[0].0 <= u && u <= w[1].0)
            .map_or(0.0, |w| {
                w[0].1 + (w[1].1 - w[0].1) * (u - w[0].0) / (w[1].0 - w[0].0)
            })
    };
    // The steep sides of a trapezoid add samples: keep the first ones that fit, and run the
    // wall on flat from the last one.
    let mut samples = sample_graph(&knots, a, b, spacing);
    samples.truncate(MAX_DIGITIZED_POINTS - 2);
    let end_u = samples.last().map_or(b, |s| s[0]);
    let end_v = level_at(end_u);
    let mut along_noise = 0.5 * noise;
    for attempt in 0..60 {
        if attempt == 30 {
            along_noise *= 0.25;
        }
        let mut points = Vec::with_capacity(samples.len() + 2);
        points.push((a - RUN_OUT_M, level_at(a - RUN_OUT_M)));
        for s in &samples {
            let e_n = noise * gaussian(rng);
            let e_t = along_noise * gaussian(rng);
            points.push((
                s[0] + e_n * s[2] + e_t * s[4],
                s[1] + e_n * s[3] + e_t * s[5],
            ));
        }
        points.push((end_u + RUN_OUT_M, end_v));
        let ground: Vec<Vector2<f64>> =
            points.iter().map(|&(u, v)| frame.to_ground(u, v)).collect();
        if Polyline::new(ground, SolidSide::Left).is_ok() {
            return Ok(Profile::Digitized {
                points,
                underlying,
                spacing_m: spacing,
                noise_m: noise,
            });
        }
    }
    Err(StressError::Other(format!(
        "no valid digitized wall in 60 draws (spacing {spacing} m, noise {noise} m)"
    )))
}
