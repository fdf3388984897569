//! Which side of a wall curve is solid.

use nalgebra::Vector2;

/// Which side of a wall curve is solid, relative to the curve's tangent orientation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SolidSide {
    /// Solid on the `+90 deg` (counter-clockwise) side of the tangent: a wall along `+x`
    /// with the solid at larger `y`.
    Left,
    /// Solid on the `-90 deg` (clockwise) side of the tangent.
    Right,
}

impl SolidSide {
    /// The unit normal into free space for a unit tangent `t`.
    pub fn free_normal(self, tangent: &Vector2<f64>) -> Vector2<f64> {
        match self {
            SolidSide::Left => Vector2::new(tangent.y, -tangent.x),
            SolidSide::Right => Vector2::new(-tangent.y, tangent.x),
        }
    }

    /// The other side.
    pub fn swapped(self) -> SolidSide {
        match self {
            SolidSide::Left => SolidSide::Right,
            SolidSide::Right => SolidSide::Left,
        }
    }

    /// The unit tangent for a unit normal `n` into free space (the inverse of
    /// [`Self::free_normal`]).
    pub fn tangent_from_normal(self, normal: &Vector2<f64>) -> Vector2<f64> {
        match self {
            SolidSide::Left => Vector2::new(-normal.y, normal.x),
            SolidSide::Right => Vector2::new(normal.y, -normal.x),
        }
    }
}
