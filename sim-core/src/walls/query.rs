//! What the wall queries answer, shared by every shape: the nearest point of a wall
//! ([`WallPoint`]), the deepest point of a segment ([`SegmentContact`]), a convex feature
//! ([`ConvexFeature`]) and a segment resting on one ([`FeatureContact`]); and the helpers the
//! shapes' queries share.

use nalgebra::Vector2;

/// The nearest point of a wall curve to a query point, and the local frame there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallPoint {
    /// Signed distance from the query point to the curve, metres: positive in free space,
    /// negative inside the solid.
    pub gap_m: f64,
    /// The nearest point of the curve (ground frame, metres).
    pub closest_m: Vector2<f64>,
    /// Unit normal into free space at `closest_m`. At a polyline corner it is the direction
    /// from the corner to the query point (signed into free space), or the corner's
    /// pseudo-normal (the mean of its edges' normals) when the query point is the corner.
    pub normal: Vector2<f64>,
    /// Unit tangent at `closest_m`, in the direction of increasing `arclength_m`; tied to
    /// `normal` as [`SolidSide::free_normal`](super::SolidSide::free_normal) says.
    pub tangent: Vector2<f64>,
    /// Arclength of `closest_m` along the curve from the curve's origin, metres (see each
    /// shape; negative before the origin).
    pub arclength_m: f64,
    /// The wall's signed curvature at `closest_m`, 1/m: positive where the wall bulges into
    /// free space (a crest seen from the free side), negative where it is hollow, `0` on a
    /// straight piece and `+inf` (`-inf`) at a convex (concave) polyline corner. The normal
    /// turns as the query point moves by `dp`: `d normal = k (t . dp) t` with
    /// `k = curvature / (1 + curvature gap)` (`1 / gap` at a corner), see
    /// [`WallPoint::normal_turn_rate_per_m`].
    pub curvature_per_m: f64,
}

impl WallPoint {
    /// How fast the normal turns as the query point moves along the tangent, radians per
    /// metre: the curvature of the level set of the signed distance through the query point,
    /// `curvature / (1 + curvature gap)` (`1 / gap` at a corner, where the level set is a
    /// circle about it). Zero on a straight piece; `0` also where the query point sits on the
    /// wall at a corner (there the distance has no curvature to speak of).
    pub fn normal_turn_rate_per_m(&self) -> f64 {
        let k = self.curvature_per_m;
        if k.is_infinite() {
            if self.gap_m != 0.0 {
                1.0 / self.gap_m
            } else {
                0.0
            }
        } else if k == 0.0 {
            0.0
        } else {
            let denominator = 1.0 + k * self.gap_m;
            if denominator.abs() > 1e-12 {
                k / denominator
            } else {
                k / 1e-12_f64.copysign(denominator)
            }
        }
    }
}

/// A convex feature of a wall that can press on a link between its ends: a polyline corner
/// that bulges into free space, or a sinusoid's crest (the part of each period that bulges
/// into free space). Identifies the same feature from step to step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ConvexFeature {
    /// A convex corner of a polyline: its vertex index.
    Corner {
        /// The vertex.
        vertex: usize,
    },
    /// The crest of period `index` of a sinusoid (the one whose phase `k t + phase` lies in
    /// `[2 pi index, 2 pi (index + 1))` shifted to its crest).
    Crest {
        /// The period.
        index: i64,
    },
}

/// A segment resting on a [`ConvexFeature`]: the wall point where the segment's direction is
/// a tangent of the wall (the corner itself, or the crest's tangent point), and the gap from
/// it to the segment's line along the segment's normal. Unlike [`SegmentContact`], `s` is not
/// clamped to the segment: the caller decides whether the foot lies on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeatureContact {
    /// Which feature.
    pub feature: ConvexFeature,
    /// The foot of the wall point on the segment's line: `point_m = a + s (b - a)`.
    pub s: f64,
    /// That point of the segment's line, metres.
    pub point_m: Vector2<f64>,
    /// The wall point (the corner, or the crest's tangent point), metres.
    pub wall_m: Vector2<f64>,
    /// The gap from the wall point to the segment's line along `normal`, metres (negative
    /// when the feature pokes through the line).
    pub gap_m: f64,
    /// The segment's unit normal, oriented into free space (the direction the wall pushes
    /// the segment).
    pub normal: Vector2<f64>,
    /// The unit tangent tied to `normal` as
    /// [`SolidSide::free_normal`](super::SolidSide::free_normal) says.
    pub tangent: Vector2<f64>,
    /// Arclength of the wall point along the curve, metres.
    pub arclength_m: f64,
    /// How far the wall point moves along the segment's direction per radian the segment
    /// turns, metres (`0` at a corner; at a crest the tangent point rolls along the curve).
    pub roll_m_per_rad: f64,
    /// The wall's signed curvature at the wall point, 1/m (`+inf` at a corner).
    pub curvature_per_m: f64,
    /// Whether the segment can rest on the feature: at a corner, whether the segment's
    /// normal lies in the corner's normal cone (between the normals of its two edges); a
    /// segment standing steeply beside a corner rests on one of the corner's edges instead,
    /// and its gap here (measured along its own normal, across that edge) means nothing.
    /// Always `true` at a crest.
    pub supported: bool,
}

/// The point of a segment `a -> b` with the smallest signed gap to a wall: its deepest
/// penetration, or its closest approach if it is entirely in free space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentContact {
    /// Where along the segment, in `[0, 1]`: `point_m = a + s (b - a)`.
    pub s: f64,
    /// That point of the segment (ground frame, metres).
    pub point_m: Vector2<f64>,
    /// The wall's nearest point to `point_m` (`signed_distance(point_m)`).
    pub wall: WallPoint,
}

/// Whether `origin + t direction`, `t` in `[0, max_m]`, is a ray the queries answer: a
/// finite origin, a finite unit direction (within `1e-9`), `max_m >= 0` (`+inf` allowed).
pub(crate) fn ray_is_valid(origin_m: &Vector2<f64>, direction: &Vector2<f64>, max_m: f64) -> bool {
    origin_m.x.is_finite()
        && origin_m.y.is_finite()
        && direction.x.is_finite()
        && direction.y.is_finite()
        && (direction.norm() - 1.0).abs() <= 1e-9
        && max_m >= 0.0
}

/// The point of `a -> b` at parameter `s`.
pub(crate) fn lerp(a_m: &Vector2<f64>, b_m: &Vector2<f64>, s: f64) -> Vector2<f64> {
    a_m + (b_m - a_m) * s
}

/// Keeps the better of two segment candidates: the smaller gap, ties to the smaller `s`.
pub(crate) fn better(best: SegmentContact, candidate: SegmentContact) -> SegmentContact {
    if candidate.wall.gap_m < best.wall.gap_m
        || (candidate.wall.gap_m == best.wall.gap_m && candidate.s < best.s)
    {
        candidate
    } else {
        best
    }
}
