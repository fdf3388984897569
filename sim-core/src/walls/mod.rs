//! Walls (docs/model.md 6, thesis 3.3, 4.2): curves with a solid side, in the ground frame.
//!
//! # Conventions
//! - Every wall curve has a **tangent orientation**: the direction of increasing arclength
//!   (for a [`Line`] its angle, for a [`Polyline`] from the first vertex to the last, for a
//!   [`Sinusoid`] the direction of its baseline).
//! - The **solid side** ([`SolidSide`]) is given relative to that tangent, and the unit
//!   **normal** always points into free space: for [`SolidSide::Left`] `normal = (t_y, -t_x)`,
//!   for [`SolidSide::Right`] `normal = (-t_y, t_x)`.
//! - **Signed distance** `gap_m` is the Euclidean distance to the curve, positive in free
//!   space and negative inside the solid; its gradient is the normal wherever the nearest point
//!   is unique.
//! - **Moving a wall.** A chain's positions are relative to its base pivot; to test a chain
//!   whose base is at `base_m`, add `base_m` to its points or move the wall by `-base_m`
//!   ([`Wall::translate`] works in place and does not allocate).
//!   `gap(p; wall moved by o) = gap(p - o; wall)`.
//!
//! Queries ([`Wall::signed_distance`], [`Wall::segment_contact`], [`Wall::surface_at`]) do
//! not allocate.
//!
//! # What is where
//! One concept a file; each shape a folder with one query a file, as parry does:
//! - this file: the dispatch over the shapes ([`WallShape`]), the wall with its surfaces
//!   ([`Wall`]) and the first wall along a ray ([`first_ray_hit`]);
//! - `side.rs`: the solid side ([`SolidSide`]); `query.rs`: what the queries answer
//!   ([`WallPoint`], [`SegmentContact`], [`ConvexFeature`], [`FeatureContact`]) and the helpers
//!   the shapes share;
//! - `line.rs`: [`Line`];
//! - `polyline/`: [`Polyline`], the shape in `mod.rs`, then `crossing.rs`, `distance.rs`,
//!   `segment_contact.rs`, `features.rs` (its convex corners), `concave.rs` (the cut at
//!   concave corners), `flat.rs` (vertices that are no corners), `ray.rs`;
//! - `sinusoid/`: [`Sinusoid`], the shape in `mod.rs`, then `distance.rs`,
//!   `segment_contact.rs`, `features.rs` (its crests), `bounds.rs` (gap lower bounds without
//!   a search), `ray.rs`;
//! - `edge_tree.rs`: the bounding boxes, a hierarchy over runs of a long polyline's edges
//!   that makes its queries cost what is near them, with the point, segment and box
//!   distances it prunes by (the contact's broad phase builds one over a wall's pieces);
//! - `surface.rs`: surfaces and their zones ([`Surface`], [`SurfaceMap`]); `error.rs`:
//!   [`WallError`]; `ray_tests.rs`: the ray and mirror tests across the shapes.
//!
//! # Example: a link against the thesis's 4.2.1 wall
//! ```
//! use nalgebra::Vector2;
//! use sim_core::{Line, SolidSide, Wall};
//!
//! # fn main() -> Result<(), sim_core::WallError> {
//! // A smooth wall (mu = 0.3) at 8 degrees, 0.2 m from the base pivot, solid beyond it.
//! let wall = Wall::smooth(Line::new(Vector2::new(0.0, 0.2), 8f64.to_radians(), SolidSide::Left)?);
//! // A 40 mm link poking 1 mm into it.
//! let a = Vector2::new(0.0, 0.161);
//! let b = Vector2::new(0.0, 0.201);
//! let c = wall.segment_contact(&a, &b);
//! assert_eq!(c.s, 1.0); // its distal end is deepest
//! assert!((c.wall.gap_m + 0.001 * 8f64.to_radians().cos()).abs() < 1e-12);
//! assert!(c.wall.normal.y < 0.0); // into free space, toward the antenna
//! assert_eq!(wall.surface_at(&c.wall).mu(), 0.3);
//! // The base has moved 0.1 m along x: move the wall the other way instead of the chain.
//! let seen_from_base = wall.translated(Vector2::new(-0.1, 0.0));
//! let moved = seen_from_base.signed_distance(&a).gap_m;
//! assert!((moved - wall.signed_distance(&(a + Vector2::new(0.1, 0.0))).gap_m).abs() < 1e-15);
//! # Ok(())
//! # }
//! ```

pub(crate) mod edge_tree;
mod error;
mod line;
mod polyline;
mod query;
#[cfg(test)]
mod ray_tests;
mod side;
mod sinusoid;
mod surface;

use nalgebra::Vector2;

pub use error::WallError;
pub use line::Line;
pub use polyline::{ConcavePiece, Polyline};
pub use query::{ConvexFeature, FeatureContact, SegmentContact, WallPoint};
pub(crate) use query::{better, lerp, ray_is_valid};
pub use side::SolidSide;
pub use sinusoid::Sinusoid;
pub use surface::{SMOOTH_MU_DEFAULT, Surface, SurfaceMap, ZoneAxis};

/// The geometry of a wall.
#[derive(Clone, Debug, PartialEq)]
pub enum WallShape {
    /// A straight line.
    Line(Line),
    /// An open polyline with infinite end rays (the thesis's trapezoid).
    Polyline(Polyline),
    /// A sinusoid about a straight baseline (thesis 4.2.2).
    Sinusoid(Sinusoid),
}

impl From<Line> for WallShape {
    fn from(line: Line) -> Self {
        WallShape::Line(line)
    }
}

impl From<Polyline> for WallShape {
    fn from(polyline: Polyline) -> Self {
        WallShape::Polyline(polyline)
    }
}

impl From<Sinusoid> for WallShape {
    fn from(sinusoid: Sinusoid) -> Self {
        WallShape::Sinusoid(sinusoid)
    }
}

impl WallShape {
    /// The signed distance and nearest point (see [`WallPoint`]).
    pub fn signed_distance(&self, p_m: &Vector2<f64>) -> WallPoint {
        match self {
            WallShape::Line(w) => w.signed_distance(p_m),
            WallShape::Polyline(w) => w.signed_distance(p_m),
            WallShape::Sinusoid(w) => w.signed_distance(p_m),
        }
    }

    /// The normals the wall can press with at `wall_point` (this shape's
    /// [`Self::signed_distance`] of some point), as the two ends of their cone: the
    /// point's normal twice on a line, a sinusoid or an edge; a polyline corner's two edge
    /// normals at the corner or within `within_m` of it.
    pub fn normal_cone(&self, wall_point: &WallPoint, within_m: f64) -> [Vector2<f64>; 2] {
        match self {
            WallShape::Line(_) | WallShape::Sinusoid(_) => [wall_point.normal; 2],
            WallShape::Polyline(w) => w.normal_cone(wall_point, within_m),
        }
    }

    /// The deepest (or closest) point of the segment `a -> b` (see [`SegmentContact`]).
    pub fn segment_contact(&self, a_m: &Vector2<f64>, b_m: &Vector2<f64>) -> SegmentContact {
        match self {
            WallShape::Line(w) => w.segment_contact(a_m, b_m),
            WallShape::Polyline(w) => w.segment_contact(a_m, b_m),
            WallShape::Sinusoid(w) => w.segment_contact(a_m, b_m),
        }
    }

    /// The deepest point strictly inside the segment `a -> b` among the points where the gap
    /// along it can have an interior minimum (a polyline's corners and equidistance points, a
    /// sinusoid's crests and tangencies), or `None` (always for a line, whose gap along a
    /// segment is linear). Continuous where [`Self::segment_contact`] jumps between an end
    /// and an interior point of equal depth.
    pub fn segment_interior_contact(
        &self,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
    ) -> Option<SegmentContact> {
        match self {
            WallShape::Line(_) => None,
            WallShape::Polyline(w) => w.segment_interior_contact(a_m, b_m),
            WallShape::Sinusoid(w) => w.segment_interior_contact(a_m, b_m),
        }
    }

    /// The broad phase: a lower bound of the signed distance of every point of the segment
    /// `a -> b` (so of [`Self::segment_contact`]'s gap) that costs no nearest-point search:
    /// a line's smaller end gap (exact); a sinusoid's height beyond its amplitude band on the
    /// free side, or within the band its lowest vertical gap as a distance (below zero where
    /// the segment dips into the wall); none yet for a polyline (`-inf`: every query of a
    /// polyline searches, by runs of edges with their boxes). A non-finite end gives NaN,
    /// which no bound comparison passes.
    pub fn segment_gap_lower_bound_m(&self, a_m: &Vector2<f64>, b_m: &Vector2<f64>) -> f64 {
        if !(a_m.x.is_finite() && a_m.y.is_finite() && b_m.x.is_finite() && b_m.y.is_finite()) {
            return f64::NAN;
        }
        match self {
            WallShape::Line(w) => w
                .signed_distance(a_m)
                .gap_m
                .min(w.signed_distance(b_m).gap_m),
            WallShape::Polyline(w) => w.segment_gap_lower_bound_m(a_m, b_m),
            WallShape::Sinusoid(w) => w.segment_gap_lower_bound_m(a_m, b_m),
        }
    }

    /// [`Self::segment_gap_lower_bound_m`] of a point.
    pub fn gap_lower_bound_m(&self, p_m: &Vector2<f64>) -> f64 {
        self.segment_gap_lower_bound_m(p_m, p_m)
    }

    /// [`Self::segment_contact`] if the segment comes within `max_gap_m` of the wall (its
    /// smallest gap `<= max_gap_m`), else `None`; a segment whose
    /// [`Self::segment_gap_lower_bound_m`] is above `max_gap_m` is answered without a
    /// search.
    pub fn segment_contact_within(
        &self,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
        max_gap_m: f64,
    ) -> Option<SegmentContact> {
        if self.segment_gap_lower_bound_m(a_m, b_m) > max_gap_m {
            return None;
        }
        let contact = self.segment_contact(a_m, b_m);
        (contact.wall.gap_m <= max_gap_m).then_some(contact)
    }

    /// The convex features nearest to `wall_point` (an answer of this shape's signed
    /// distance): a polyline's convex corners at the ends of the edge it lies on, or the
    /// corner it is (a sinusoid's crests are smooth, and a point nearest to one is on the
    /// surface like any other).
    pub fn convex_features_by(&self, wall_point: &WallPoint) -> [Option<ConvexFeature>; 2] {
        match self {
            WallShape::Polyline(w) => w
                .convex_corners_by(wall_point)
                .map(|corner| corner.map(|vertex| ConvexFeature::Corner { vertex })),
            WallShape::Line(_) | WallShape::Sinusoid(_) => [None, None],
        }
    }

    /// Where convex `feature` is, if it is a corner (a crest has no single point).
    pub fn corner_m(&self, feature: ConvexFeature) -> Option<Vector2<f64>> {
        match (self, feature) {
            (WallShape::Polyline(w), ConvexFeature::Corner { vertex }) => {
                w.vertices_m().get(vertex).copied()
            }
            _ => None,
        }
    }

    /// A point against one edge of a convex corner, the edge taken as its line
    /// ([`Polyline::corner_edge_point`]); `None` for a feature that is not a convex corner
    /// of this shape.
    pub fn corner_edge_point(
        &self,
        feature: ConvexFeature,
        after: bool,
        p_m: &Vector2<f64>,
    ) -> Option<WallPoint> {
        match (self, feature) {
            (WallShape::Polyline(w), ConvexFeature::Corner { vertex }) => {
                w.corner_edge_point(vertex, after, p_m)
            }
            _ => None,
        }
    }

    /// The convex features of the wall that could press on the inside of the segment
    /// `a -> b` with a gap below `within_m` (every one is evaluated: the caller filters by
    /// `s`), appended to `out`. A line has none.
    pub fn features_near_segment(
        &self,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
        within_m: f64,
        out: &mut Vec<FeatureContact>,
    ) {
        match self {
            WallShape::Line(_) => {}
            WallShape::Polyline(w) => w.features_near_segment(a_m, b_m, within_m, out),
            WallShape::Sinusoid(w) => w.features_near_segment(a_m, b_m, within_m, out),
        }
    }

    /// The segment `a -> b` resting on `feature` (see [`FeatureContact`], whose `supported`
    /// says whether the corner's cone holds the segment's normal), or `None` where it cannot
    /// be measured (a corner that is not convex, a segment steeper than the crest can be
    /// tangent to, a feature of another shape).
    pub fn feature_contact(
        &self,
        feature: ConvexFeature,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
    ) -> Option<FeatureContact> {
        match (self, feature) {
            (WallShape::Polyline(w), ConvexFeature::Corner { vertex }) => {
                w.corner_feature_contact(vertex, a_m, b_m)
            }
            (WallShape::Sinusoid(w), ConvexFeature::Crest { index }) => {
                w.crest_feature_contact(index, a_m, b_m)
            }
            _ => None,
        }
    }

    /// The first point of the ray `origin + t direction` on the curve (see
    /// [`Wall::ray_hit_m`]).
    pub fn ray_hit_m(
        &self,
        origin_m: &Vector2<f64>,
        direction: &Vector2<f64>,
        max_m: f64,
    ) -> Option<f64> {
        match self {
            WallShape::Line(w) => w.ray_hit_m(origin_m, direction, max_m),
            WallShape::Polyline(w) => w.ray_hit_m(origin_m, direction, max_m),
            WallShape::Sinusoid(w) => w.ray_hit_m(origin_m, direction, max_m),
        }
    }

    /// The curve reflected `y -> -y`, solid side swapped so that the reflected points of
    /// the solid are solid, arclength kept (see each shape's `mirrored_about_x_axis`).
    pub fn mirrored_about_x_axis(&self) -> WallShape {
        match self {
            WallShape::Line(w) => WallShape::Line(w.mirrored_about_x_axis()),
            WallShape::Polyline(w) => WallShape::Polyline(w.mirrored_about_x_axis()),
            WallShape::Sinusoid(w) => WallShape::Sinusoid(w.mirrored_about_x_axis()),
        }
    }

    /// Moves the curve by `offset_m`, in place.
    pub fn translate(&mut self, offset_m: Vector2<f64>) {
        match self {
            WallShape::Line(w) => w.translate(offset_m),
            WallShape::Polyline(w) => w.translate(offset_m),
            WallShape::Sinusoid(w) => w.translate(offset_m),
        }
    }

    /// Which side is solid.
    pub fn solid_side(&self) -> SolidSide {
        match self {
            WallShape::Line(w) => w.solid_side(),
            WallShape::Polyline(w) => w.solid_side(),
            WallShape::Sinusoid(w) => w.solid_side(),
        }
    }
}

/// A wall: a curve with a solid side and a surface along it.
#[derive(Clone, Debug, PartialEq)]
pub struct Wall {
    /// The geometry.
    pub shape: WallShape,
    /// The surface zones along the wall.
    pub surfaces: SurfaceMap,
}

impl Wall {
    /// A wall of the given shape and surfaces.
    pub fn new(shape: impl Into<WallShape>, surfaces: SurfaceMap) -> Wall {
        Wall {
            shape: shape.into(),
            surfaces,
        }
    }

    /// A smooth wall with the default friction (`mu = 0.3`, docs/model.md 6) everywhere.
    pub fn smooth(shape: impl Into<WallShape>) -> Wall {
        Wall::new(shape, SurfaceMap::default())
    }

    /// The signed distance and nearest point (see [`WallPoint`]); no allocation.
    pub fn signed_distance(&self, p_m: &Vector2<f64>) -> WallPoint {
        self.shape.signed_distance(p_m)
    }

    /// The deepest (or closest) point of the segment `a -> b` (see [`SegmentContact`]); no
    /// allocation. Checks the whole segment, not only its ends: a polyline corner or a
    /// sinusoid crest inside the segment is found.
    pub fn segment_contact(&self, a_m: &Vector2<f64>, b_m: &Vector2<f64>) -> SegmentContact {
        self.shape.segment_contact(a_m, b_m)
    }

    /// [`WallShape::segment_gap_lower_bound_m`]: the broad phase, no search.
    pub fn segment_gap_lower_bound_m(&self, a_m: &Vector2<f64>, b_m: &Vector2<f64>) -> f64 {
        self.shape.segment_gap_lower_bound_m(a_m, b_m)
    }

    /// [`WallShape::gap_lower_bound_m`]: the broad phase, no search.
    pub fn gap_lower_bound_m(&self, p_m: &Vector2<f64>) -> f64 {
        self.shape.gap_lower_bound_m(p_m)
    }

    /// See [`WallShape::segment_interior_contact`]; no allocation.
    pub fn segment_interior_contact(
        &self,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
    ) -> Option<SegmentContact> {
        self.shape.segment_interior_contact(a_m, b_m)
    }

    /// [`Self::segment_contact`] if the segment comes within `max_gap_m` of the wall, else
    /// `None` (see [`WallShape::segment_contact_within`]); no allocation.
    pub fn segment_contact_within(
        &self,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
        max_gap_m: f64,
    ) -> Option<SegmentContact> {
        self.shape.segment_contact_within(a_m, b_m, max_gap_m)
    }

    /// The surface at a wall point found by [`Self::signed_distance`].
    pub fn surface_at(&self, point: &WallPoint) -> Surface {
        self.surfaces.surface_at(point)
    }

    /// Moves the wall (curve and world-x zone boundaries) by `offset_m`, in place, without
    /// allocating.
    pub fn translate(&mut self, offset_m: Vector2<f64>) {
        self.shape.translate(offset_m);
        self.surfaces.translate_x(offset_m.x);
    }

    /// The wall without the polyline vertices that are no corners at `tolerance_m`
    /// ([`Polyline::without_flat_vertices`]); a line or a sinusoid as it is.
    pub fn without_flat_vertices(&self, tolerance_m: f64) -> Wall {
        match &self.shape {
            WallShape::Polyline(p) => Wall {
                shape: WallShape::Polyline(p.without_flat_vertices(tolerance_m)),
                surfaces: self.surfaces.clone(),
            },
            _ => self.clone(),
        }
    }

    /// A copy of the wall moved by `offset_m`.
    pub fn translated(&self, offset_m: Vector2<f64>) -> Wall {
        let mut moved = self.clone();
        moved.translate(offset_m);
        moved
    }

    /// The ray query: the smallest `t` in `[0, max_m]` with `origin + t direction` on the
    /// wall's curve (from either side), or `None` when the ray meets it nowhere within
    /// `max_m`. `direction` must be a unit vector (within `1e-9`) and everything finite
    /// (`max_m` may be `+inf`); otherwise `None`, no panic. Closed forms for a line and a
    /// polyline's edges and end rays; a sinusoid's crossings bracketed between the
    /// stationary points of the ray's offset from it and refined to `1e-12` m
    /// ([`Sinusoid::ray_hit_m`]). No allocation.
    pub fn ray_hit_m(
        &self,
        origin_m: &Vector2<f64>,
        direction: &Vector2<f64>,
        max_m: f64,
    ) -> Option<f64> {
        self.shape.ray_hit_m(origin_m, direction, max_m)
    }

    /// The wall reflected `y -> -y` in the ground frame (a right-wall run solved as a
    /// left-wall one): the reflected points of the solid are solid (the curve's solid side
    /// is swapped, since a reflection flips the orientation), and the surface of a point's
    /// mirror image is the point's (world-x zones keep their x, arclength zones their
    /// arclength, which the reflected curve keeps).
    pub fn mirrored_about_x_axis(&self) -> Wall {
        Wall {
            shape: self.shape.mirrored_about_x_axis(),
            surfaces: self.surfaces.clone(),
        }
    }
}

/// The first wall the ray `origin + t direction` meets within `max_m`: its index in `walls`
/// and the distance `t` (see [`Wall::ray_hit_m`]; ties go to the lower index). `None` when
/// it meets none, or is not a ray.
pub fn first_ray_hit(
    walls: &[Wall],
    origin_m: &Vector2<f64>,
    direction: &Vector2<f64>,
    max_m: f64,
) -> Option<(usize, f64)> {
    let mut best: Option<(usize, f64)> = None;
    for (index, wall) in walls.iter().enumerate() {
        let reach_m = best.map_or(max_m, |(_, t)| t);
        if let Some(t) = wall.ray_hit_m(origin_m, direction, reach_m)
            && best.is_none_or(|(_, b)| t < b)
        {
            best = Some((index, t));
        }
    }
    best
}
