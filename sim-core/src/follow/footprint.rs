//! The body's footprint against the walls: a rectangle centred on the point of rotation
//! (POR), its length along the heading, checked edge by edge with
//! [`Wall::segment_contact`] (which finds a polyline's corner or a sinusoid's crest inside
//! an edge, not only at its ends). A wall's solid is unbounded, so it cannot lie inside the
//! rectangle without crossing one of its edges: checking the edges finds every overlap.

use nalgebra::Vector2;

use crate::walls::Wall;

/// The rectangle's corners, ground frame, counter-clockwise from the rear corner on the
/// right: rear right, front right, front left, rear left (left: toward the wall in the
/// loop's frame). `footprint_m = [length, width]`, the length along `heading_rad`.
pub fn corners_m(
    por_m: &Vector2<f64>,
    heading_rad: f64,
    footprint_m: [f64; 2],
) -> [Vector2<f64>; 4] {
    let forward = Vector2::new(heading_rad.cos(), heading_rad.sin());
    let left = Vector2::new(-forward.y, forward.x);
    let (half_length, half_width) = (0.5 * footprint_m[0], 0.5 * footprint_m[1]);
    [
        por_m - forward * half_length - left * half_width,
        por_m + forward * half_length - left * half_width,
        por_m + forward * half_length + left * half_width,
        por_m - forward * half_length + left * half_width,
    ]
}

/// The deepest overlap of the footprint with a wall: the wall's index and the depth (m,
/// positive) of the rectangle edges' deepest point inside its solid; `None` when every
/// edge is clear (a rectangle touching a wall, at zero gap, is clear). Ties go to the
/// lower wall index. Non-finite input gives `None` (no panic).
pub fn overlap(
    walls: &[Wall],
    por_m: &Vector2<f64>,
    heading_rad: f64,
    footprint_m: [f64; 2],
) -> Option<(usize, f64)> {
    let corners = corners_m(por_m, heading_rad, footprint_m);
    let mut deepest: Option<(usize, f64)> = None;
    for (index, wall) in walls.iter().enumerate() {
        for k in 0..4 {
            let contact = wall.segment_contact(&corners[k], &corners[(k + 1) % 4]);
            let depth_m = -contact.wall.gap_m;
            if depth_m > 0.0 && deepest.is_none_or(|(_, d)| depth_m > d) {
                deepest = Some((index, depth_m));
            }
        }
    }
    deepest
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use core::f64::consts::FRAC_PI_2;

    use super::*;
    use crate::walls::{Line, Polyline, Sinusoid, SolidSide};

    fn v(x: f64, y: f64) -> Vector2<f64> {
        Vector2::new(x, y)
    }

    /// A wall along x at `y_m`, solid above (on the body's left when heading along +x).
    fn wall_at(y_m: f64) -> Wall {
        Wall::smooth(Line::new(v(0.0, y_m), 0.0, SolidSide::Left).unwrap())
    }

    #[test]
    fn the_corners_go_round_the_por() {
        let c = corners_m(&v(1.0, 2.0), 0.0, [0.12, 0.06]);
        assert_eq!(
            c,
            [v(0.94, 1.97), v(1.06, 1.97), v(1.06, 2.03), v(0.94, 2.03)]
        );
        let c = corners_m(&v(0.0, 0.0), FRAC_PI_2, [0.12, 0.06]);
        let expected = [
            v(0.03, -0.06),
            v(0.03, 0.06),
            v(-0.03, 0.06),
            v(-0.03, -0.06),
        ];
        for (a, b) in c.iter().zip(&expected) {
            assert!((a - b).norm() < 1e-15, "{a:?} vs {b:?}");
        }
    }

    #[test]
    fn a_line_wall_is_clear_touching_and_overlapping() {
        let footprint = [0.12, 0.06];
        // Clear, then touching (the left edge on the wall: clear), then 5 mm in.
        assert_eq!(overlap(&[wall_at(0.1)], &v(0.0, 0.0), 0.0, footprint), None);
        assert_eq!(
            overlap(&[wall_at(0.03)], &v(0.0, 0.0), 0.0, footprint),
            None
        );
        let (wall, depth) = overlap(&[wall_at(0.025)], &v(0.0, 0.0), 0.0, footprint).unwrap();
        assert_eq!(wall, 0);
        assert!((depth - 0.005).abs() < 1e-15, "{depth}");
        // Turned 30 degrees toward the wall: the front left corner is deepest, at
        // (l/2) sin 30 + (w/2) cos 30 from the POR's line along the wall.
        let heading = 30f64.to_radians();
        let reach = 0.06 * heading.sin() + 0.03 * heading.cos();
        let (_, depth) = overlap(&[wall_at(0.05)], &v(0.0, 0.0), heading, footprint).unwrap();
        assert!((depth - (reach - 0.05)).abs() < 1e-15, "{depth}");
        assert_eq!(
            overlap(&[wall_at(reach + 1e-9)], &v(0.0, 0.0), heading, footprint),
            None
        );
        // The deepest of several walls; a wall behind the body on its right side too.
        let behind = Wall::smooth(Line::new(v(0.0, -0.02), 0.0, SolidSide::Right).unwrap());
        let walls = [wall_at(0.029), behind, wall_at(0.01)];
        let (index, depth) = overlap(&walls, &v(0.0, 0.0), 0.0, footprint).unwrap();
        assert_eq!(index, 2);
        assert!((depth - 0.02).abs() < 1e-15);
        // NaN: no overlap, no panic.
        assert_eq!(overlap(&walls, &v(f64::NAN, 0.0), 0.0, footprint), None);
    }

    #[test]
    fn a_convex_corner_poking_into_an_edge_is_found_between_its_ends() {
        // A 90 degree corner pointing down at the middle of the body's left edge (at
        // y = 0.03), its tip 4 mm past it: both rectangle corners of that edge are clear,
        // and the edge's deepest point (below the tip) is 4 mm / sqrt(2) inside.
        let tip = v(0.01, 0.026);
        let corner = Wall::smooth(
            Polyline::new(
                vec![tip + v(-0.1, 0.1), tip, tip + v(0.1, 0.1)],
                SolidSide::Left,
            )
            .unwrap(),
        );
        let footprint = [0.12, 0.06];
        let corners = corners_m(&v(0.0, 0.0), 0.0, footprint);
        for c in &corners {
            assert!(corner.signed_distance(c).gap_m > 0.0, "{c:?}");
        }
        let (_, depth) =
            overlap(std::slice::from_ref(&corner), &v(0.0, 0.0), 0.0, footprint).unwrap();
        let expected = 0.004 / 2f64.sqrt();
        assert!((depth - expected).abs() < 1e-12, "{depth} vs {expected}");
        // Moved 5 mm away from it: clear.
        assert_eq!(overlap(&[corner], &v(0.0, -0.005), 0.0, footprint), None);
    }

    #[test]
    fn a_sinusoids_crest_inside_an_edge_is_found() {
        // Crests at y = 0.028 (amplitude 5 mm about 0.033, solid above), 2 mm past the left
        // edge, between its ends.
        let wall = Wall::smooth(
            Sinusoid::new(v(0.0, 0.033), 0.0, 0.005, 5.0, -FRAC_PI_2, SolidSide::Left).unwrap(),
        );
        let (_, depth) = overlap(&[wall], &v(0.0, 0.0), 0.0, [0.12, 0.06]).unwrap();
        assert!((depth - 0.002).abs() < 1e-9, "{depth}");
    }
}
