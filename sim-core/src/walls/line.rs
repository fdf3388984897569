//! A straight wall: a line through a point at an angle, solid on one side.

use nalgebra::Vector2;

use super::error::{WallError, finite};
use super::{SegmentContact, SolidSide, WallPoint, ray_is_valid};

/// An infinite straight wall through `point_m` with tangent `(cos angle, sin angle)`.
/// Arclength is measured from `point_m` along the tangent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    point_m: Vector2<f64>,
    angle_rad: f64,
    tangent: Vector2<f64>,
    normal: Vector2<f64>,
    solid: SolidSide,
}

impl Line {
    /// The line through `point_m` at `angle_rad` from the ground x-axis, solid on `solid`'s
    /// side of its tangent. A wall along `+x` at `y = d`, solid above: `Line::new((0, d), 0,
    /// SolidSide::Left)`.
    ///
    /// # Errors
    /// [`WallError::NotFinite`] for a non-finite point or angle.
    pub fn new(point_m: Vector2<f64>, angle_rad: f64, solid: SolidSide) -> Result<Line, WallError> {
        finite("point_m.x", 0, point_m.x)?;
        finite("point_m.y", 0, point_m.y)?;
        finite("angle_rad", 0, angle_rad)?;
        let (sin, cos) = angle_rad.sin_cos();
        let tangent = Vector2::new(cos, sin);
        Ok(Line {
            point_m,
            angle_rad,
            tangent,
            normal: solid.free_normal(&tangent),
            solid,
        })
    }

    /// A point of the line (the arclength origin), metres.
    pub fn point_m(&self) -> Vector2<f64> {
        self.point_m
    }

    /// The tangent's angle from the ground x-axis, radians.
    pub fn angle_rad(&self) -> f64 {
        self.angle_rad
    }

    /// Which side is solid.
    pub fn solid_side(&self) -> SolidSide {
        self.solid
    }

    /// The signed distance and nearest point (see [`WallPoint`]).
    pub fn signed_distance(&self, p_m: &Vector2<f64>) -> WallPoint {
        let r = p_m - self.point_m;
        let gap_m = self.normal.dot(&r);
        WallPoint {
            gap_m,
            closest_m: p_m - self.normal * gap_m,
            normal: self.normal,
            tangent: self.tangent,
            arclength_m: self.tangent.dot(&r),
            curvature_per_m: 0.0,
        }
    }

    /// The deepest (or closest) point of `a -> b`: the gap is linear along the segment, so
    /// it is the end with the smaller gap (`s = 0` when parallel).
    pub fn segment_contact(&self, a_m: &Vector2<f64>, b_m: &Vector2<f64>) -> SegmentContact {
        let at_a = self.signed_distance(a_m);
        let at_b = self.signed_distance(b_m);
        if at_b.gap_m < at_a.gap_m {
            SegmentContact {
                s: 1.0,
                point_m: *b_m,
                wall: at_b,
            }
        } else {
            SegmentContact {
                s: 0.0,
                point_m: *a_m,
                wall: at_a,
            }
        }
    }

    /// The first point of the ray `origin + t direction`, `t` in `[0, max_m]`, on the line:
    /// the closed form `t = -gap(origin) / (normal . direction)` (`0` when the origin is on
    /// the line). `None` for a ray parallel to the line (off it), pointing away from it,
    /// ending short of it, or not a ray (a non-unit or non-finite direction, a non-finite
    /// origin, a negative or NaN `max_m`).
    pub fn ray_hit_m(
        &self,
        origin_m: &Vector2<f64>,
        direction: &Vector2<f64>,
        max_m: f64,
    ) -> Option<f64> {
        if !ray_is_valid(origin_m, direction, max_m) {
            return None;
        }
        let gap_m = self.normal.dot(&(origin_m - self.point_m));
        if gap_m == 0.0 {
            return Some(0.0);
        }
        let closing = self.normal.dot(direction);
        if closing == 0.0 {
            return None;
        }
        let t_m = -gap_m / closing;
        (t_m >= 0.0 && t_m <= max_m).then_some(t_m)
    }

    /// The line reflected `y -> -y` (ground frame), solid on the other side of its reflected
    /// tangent so that the reflected points of the solid are solid (a reflection flips the
    /// orientation); arclength is kept: a point's mirror image has its arclength.
    pub fn mirrored_about_x_axis(&self) -> Line {
        let tangent = Vector2::new(self.tangent.x, -self.tangent.y);
        let solid = self.solid.swapped();
        Line {
            point_m: Vector2::new(self.point_m.x, -self.point_m.y),
            angle_rad: -self.angle_rad,
            tangent,
            normal: solid.free_normal(&tangent),
            solid,
        }
    }

    /// Moves the line by `offset_m`.
    pub fn translate(&mut self, offset_m: Vector2<f64>) {
        self.point_m += offset_m;
    }

    /// A copy moved by `offset_m`.
    pub fn translated(&self, offset_m: Vector2<f64>) -> Line {
        let mut moved = *self;
        moved.translate(offset_m);
        moved
    }
}
