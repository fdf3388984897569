//! Wall geometry (docs/model.md 6): analytic signed distances for a line and the thesis's
//! trapezoid, the sign and normal conventions, translation, surface zones and the
//! constructors' errors.
#![allow(clippy::unwrap_used)]

use nalgebra::Vector2;
use sim_core::walls::SegmentContact;
use sim_core::{
    Line, Polyline, Sinusoid, SolidSide, Surface, SurfaceMap, Wall, WallError, ZoneAxis,
};

fn v(x: f64, y: f64) -> Vector2<f64> {
    Vector2::new(x, y)
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

/// A trapezoidal bump hanging from a wall at y = 0.10 m (solid above): down to y = 0.07
/// between x = 0.10 and 0.16, slopes 0.03 m wide each side; flat from x = 0 to 0.07 and from
/// 0.19 to 0.26, and beyond along the end rays.
fn trapezoid() -> Polyline {
    Polyline::new(
        vec![
            v(0.0, 0.10),
            v(0.07, 0.10),
            v(0.10, 0.07),
            v(0.16, 0.07),
            v(0.19, 0.10),
            v(0.26, 0.10),
        ],
        SolidSide::Left,
    )
    .unwrap()
}

#[test]
fn line_signed_distance_is_analytic() {
    // A wall at 8 degrees through (0, 0.2), solid on the left of its tangent (above).
    let angle = 8f64.to_radians();
    let line = Line::new(v(0.0, 0.2), angle, SolidSide::Left).unwrap();
    let t = v(angle.cos(), angle.sin());
    let n = v(angle.sin(), -angle.cos()); // into free space (below)
    for &(along, off) in &[(0.0, 0.05), (0.3, -0.01), (-0.2, 0.0), (1.0, 0.2)] {
        let p = v(0.0, 0.2) + t * along + n * off;
        let w = line.signed_distance(&p);
        assert!(close(w.gap_m, off, 1e-14), "{} vs {off}", w.gap_m);
        assert!(close(w.arclength_m, along, 1e-14));
        assert!((w.closest_m - (v(0.0, 0.2) + t * along)).norm() < 1e-14);
        assert!((w.normal - n).norm() < 1e-15 && (w.tangent - t).norm() < 1e-15);
    }
    // Solid on the other side flips the sign and the normal, not the tangent.
    let right = Line::new(v(0.0, 0.2), angle, SolidSide::Right).unwrap();
    let w = right.signed_distance(&v(0.0, 0.1));
    assert!(close(
        w.gap_m,
        -line.signed_distance(&v(0.0, 0.1)).gap_m,
        1e-15
    ));
    assert!((w.normal + n).norm() < 1e-15 && (w.tangent - t).norm() < 1e-15);
}

/// A link standing steeply beside the bump, left of it: the bump's bottom-right corner
/// projects onto the link, but the link's normal is outside the corner's normal cone, so the
/// corner is not measured along it (that would put the corner 0.11 m deep into the link).
#[test]
fn a_corner_off_to_the_side_of_a_segment_is_not_a_contact_of_it() {
    let wall = trapezoid();
    let (a, b) = (v(0.05, 0.0), v(0.05, 0.09));
    let c = wall.segment_interior_contact(&a, &b).unwrap();
    let again = wall.signed_distance(&c.point_m);
    assert!(c.wall.gap_m > 0.0, "{c:?}");
    assert!(
        close(c.wall.gap_m, again.gap_m, 1e-14),
        "{c:?} vs {again:?}"
    );
    // Resting on the corner from below, the link's normal is in the cone: the corner's
    // contact is measured along the link's normal (1 mm below the corner).
    let (a, b) = (v(0.12, 0.069), v(0.20, 0.069));
    let c = wall.segment_interior_contact(&a, &b).unwrap();
    assert!(close(c.wall.gap_m, 0.001, 1e-12), "{c:?}");
    assert!((c.point_m - v(0.16, 0.069)).norm() < 1e-12, "{c:?}");
}

#[test]
fn trapezoid_signed_distance_is_analytic() {
    let wall = trapezoid();
    let s45 = core::f64::consts::FRAC_1_SQRT_2;
    let slope_len = 0.03 * 2f64.sqrt();
    // Below the flat bottom: plain vertical distance, arclength past the first slope.
    let w = wall.signed_distance(&v(0.13, 0.05));
    assert!(close(w.gap_m, 0.02, 1e-14));
    assert!((w.closest_m - v(0.13, 0.07)).norm() < 1e-14);
    assert!((w.normal - v(0.0, -1.0)).norm() < 1e-14);
    assert!((w.tangent - v(1.0, 0.0)).norm() < 1e-14);
    assert!(close(w.arclength_m, 0.07 + slope_len + 0.03, 1e-14));
    // Inside the bump, nearer the bottom than the slopes.
    let w = wall.signed_distance(&v(0.13, 0.075));
    assert!(close(w.gap_m, -0.005, 1e-14));
    // Diagonally off a bottom corner: the corner is nearest, the normal points at the point.
    let w = wall.signed_distance(&v(0.10 - 0.01, 0.07 - 0.02));
    let r = v(-0.01, -0.02);
    assert!(close(w.gap_m, r.norm(), 1e-14));
    assert!((w.closest_m - v(0.10, 0.07)).norm() < 1e-15);
    assert!((w.normal - r / r.norm()).norm() < 1e-14);
    assert!(close(w.arclength_m, 0.07 + slope_len, 1e-14));
    // Off the left slope (45 deg): distance along its normal (-1, -1)/sqrt 2.
    let foot = v(0.085, 0.085);
    let w = wall.signed_distance(&(foot + v(-s45, -s45) * 0.01));
    assert!(close(w.gap_m, 0.01, 1e-14));
    assert!((w.closest_m - foot).norm() < 1e-14);
    // Far left along the extended first edge (a ray) and the baseline beyond the last vertex.
    let w = wall.signed_distance(&v(-1.0, 0.13));
    assert!(close(w.gap_m, -0.03, 1e-14) && close(w.arclength_m, -1.0, 1e-14));
    let w = wall.signed_distance(&v(2.0, 0.09));
    assert!(close(w.gap_m, 0.01, 1e-14));
    // Just inside the bump near its upper left corner: the slope is nearest.
    let w = wall.signed_distance(&v(0.075, 0.099));
    assert!(close(w.gap_m, -0.004 * s45, 1e-14), "{w:?}");
    // Just below that corner, in free space: the slope is nearer than the corner.
    let w = wall.signed_distance(&v(0.07, 0.095));
    assert!(close(w.gap_m, 0.005 * s45, 1e-14), "{w:?}");
}

#[test]
fn translation_moves_everything() {
    let offset = v(0.3, -0.02);
    let p = v(0.11, 0.06);
    let shapes: [Wall; 3] = [
        Wall::smooth(Line::new(v(0.0, 0.1), 0.1, SolidSide::Left).unwrap()),
        Wall::smooth(trapezoid()),
        Wall::smooth(Sinusoid::new(v(0.0, 0.1), 0.0, 0.02, 9.5, 0.3, SolidSide::Left).unwrap()),
    ];
    for wall in &shapes {
        let moved = wall.translated(offset);
        let a = wall.signed_distance(&p);
        let b = moved.signed_distance(&(p + offset));
        assert!(close(a.gap_m, b.gap_m, 1e-12), "{a:?} {b:?}");
        assert!((a.closest_m + offset - b.closest_m).norm() < 1e-12);
        assert!(close(a.arclength_m, b.arclength_m, 1e-12));
        let mut in_place = wall.clone();
        in_place.translate(offset);
        assert_eq!(in_place, moved);
    }
}

#[test]
fn surface_zones_by_world_x_and_by_arclength() {
    let felt = Surface::Rough {
        mu: 0.6,
        hold_shear_n: 0.5,
        hold_tension_n: 0.2,
    };
    let line = Line::new(v(-1.0, 0.1), 0.0, SolidSide::Left).unwrap();
    let by_x = SurfaceMap::zoned(ZoneAxis::WorldX, Surface::default(), vec![(0.5, felt)]).unwrap();
    let wall = Wall::new(line, by_x);
    let at = |x: f64| wall.surface_at(&wall.signed_distance(&v(x, 0.0)));
    assert_eq!(at(0.49), Surface::Smooth { mu: 0.3 });
    assert_eq!(at(0.5), felt);
    assert!(at(2.0).is_rough() && !at(-3.0).is_rough());
    // Translating shifts world-x zones with the wall.
    let moved = wall.translated(v(0.2, 0.0));
    assert_eq!(
        moved.surface_at(&moved.signed_distance(&v(0.6, 0.0))),
        Surface::default()
    );
    assert_eq!(moved.surface_at(&moved.signed_distance(&v(0.7, 0.0))), felt);
    // By arclength: from the line's point (x = -1), felt from 1.5 m on: the same boundary.
    let by_s =
        SurfaceMap::zoned(ZoneAxis::Arclength, Surface::default(), vec![(1.5, felt)]).unwrap();
    let wall = Wall::new(line, by_s);
    assert!(
        !wall
            .surface_at(&wall.signed_distance(&v(0.49, 0.0)))
            .is_rough()
    );
    assert!(
        wall.surface_at(&wall.signed_distance(&v(0.51, 0.0)))
            .is_rough()
    );
    assert_eq!(Surface::default().mu(), 0.3);
    assert_eq!(felt.mu(), 0.6);
}

#[test]
fn constructors_reject_bad_input() {
    let side = SolidSide::Left;
    assert_eq!(
        Polyline::new(vec![v(0.0, 0.0)], side),
        Err(WallError::TooFewVertices { count: 1 })
    );
    assert_eq!(
        Polyline::new(vec![v(0.0, 0.0), v(1.0, 0.0), v(1.0, 0.0)], side),
        Err(WallError::ZeroLengthEdge { index: 1 })
    );
    assert!(matches!(
        Polyline::new(vec![v(0.0, 0.0), v(f64::NAN, 0.0)], side),
        Err(WallError::NotFinite { index: 1, .. })
    ));
    assert_eq!(
        Polyline::new(vec![v(0.0, 0.0), v(1.0, 0.0), v(0.5, 0.0)], side),
        Err(WallError::EdgeDoublesBack { vertex: 1 })
    );
    // A zigzag whose last ray comes back across the first edge.
    assert_eq!(
        Polyline::new(
            vec![v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.5, -1.0)],
            side
        ),
        Err(WallError::EdgesCross {
            first: 0,
            second: 2
        })
    );
    assert!(matches!(
        Line::new(v(0.0, f64::INFINITY), 0.0, side),
        Err(WallError::NotFinite { .. })
    ));
    assert_eq!(
        Sinusoid::new(v(0.0, 0.0), 0.0, -0.01, 5.0, 0.0, side),
        Err(WallError::NegativeAmplitude { amplitude_m: -0.01 })
    );
    assert_eq!(
        Sinusoid::new(v(0.0, 0.0), 0.0, 0.01, 0.0, 0.0, side),
        Err(WallError::NonPositiveFrequency {
            frequency_per_m: 0.0
        })
    );
    assert_eq!(
        SurfaceMap::uniform(Surface::Smooth { mu: -0.1 }),
        Err(WallError::NegativeFriction { mu: -0.1 })
    );
    assert!(matches!(
        SurfaceMap::uniform(Surface::Rough {
            mu: 0.5,
            hold_shear_n: f64::NAN,
            hold_tension_n: 0.0
        }),
        Err(WallError::NegativeHold {
            field: "hold_shear_n",
            ..
        })
    ));
    assert_eq!(
        SurfaceMap::zoned(
            ZoneAxis::WorldX,
            Surface::default(),
            vec![(0.5, Surface::default()), (0.5, Surface::default())]
        ),
        Err(WallError::ZonesNotIncreasing { index: 1 })
    );
}

/// The docs/model.md 6 warning: joints alone miss a corner that pokes into the middle of a link.
#[test]
fn trapezoid_bottom_inside_a_link_is_found() {
    let wall = trapezoid();
    // A horizontal link at y = 0.075 from x = 0.04 to 0.22: both ends are in free space...
    let (a, b) = (v(0.04, 0.075), v(0.22, 0.075));
    assert!(wall.signed_distance(&a).gap_m > 0.0 && wall.signed_distance(&b).gap_m > 0.0);
    // ...but the bump's bottom sinks 5 mm into it, deepest where the bottom is nearer than
    // the slopes: x in [0.095 + 0.005 sqrt 2, 0.165 - 0.005 sqrt 2].
    let c: SegmentContact = wall.segment_contact(&a, &b);
    assert!(close(c.wall.gap_m, -0.005, 1e-14), "{c:?}");
    let inset = 0.005 * 2f64.sqrt();
    assert!(c.point_m.x >= 0.095 + inset - 1e-12 && c.point_m.x <= 0.165 - inset + 1e-12);
    assert_eq!(c.wall, wall.signed_distance(&c.point_m));
}

#[test]
fn pointed_corner_inside_a_link_is_found_on_the_medial_axis() {
    // A V-shaped spike (right angle) hanging to (0.1, 0.05) from a wall at y = 0.1.
    let wall = Polyline::new(
        vec![v(0.0, 0.15), v(0.1, 0.05), v(0.2, 0.15)],
        SolidSide::Left,
    )
    .unwrap();
    // A link 10 mm above the tip, horizontal: deepest on the spike's axis, where the depth is
    // the distance to either flank: 0.01 / sqrt 2.
    let c = wall.segment_contact(&v(0.0, 0.06), &v(0.2, 0.06));
    assert!(
        close(
            c.wall.gap_m,
            -0.01 * core::f64::consts::FRAC_1_SQRT_2,
            1e-14
        ),
        "{c:?}"
    );
    assert!(close(c.point_m.x, 0.1, 1e-12));
    // 10 mm below the tip: the tip is the closest approach, straight above the link.
    let c = wall.segment_contact(&v(0.02, 0.04), &v(0.22, 0.04));
    assert!(close(c.wall.gap_m, 0.01, 1e-14) && close(c.s, 0.4, 1e-12));
    assert!((c.wall.normal - v(0.0, -1.0)).norm() < 1e-12);
}

#[test]
fn sinusoid_crest_inside_a_link_is_found() {
    // 20 mm amplitude, 9.5 cycles/m (105 mm wavelength), solid above; a crest (lowest point,
    // poking down into free space) at t = 3/4 wavelength with phase 0.
    let wall = Sinusoid::new(v(0.0, 0.1), 0.0, 0.02, 9.5, 0.0, SolidSide::Left).unwrap();
    let crest_x = 0.75 / 9.5;
    // A 60 mm link 2 mm below the wall's lowest point, centred under the crest: free, and its
    // closest approach is right under the crest though its ends are far from it.
    let (a, b) = (v(crest_x - 0.03, 0.078), v(crest_x + 0.03, 0.078));
    let c = wall.segment_contact(&a, &b);
    assert!(close(c.wall.gap_m, 0.002, 1e-12), "{c:?}");
    assert!(close(c.s, 0.5, 1e-9));
    assert!(wall.signed_distance(&a).gap_m > 0.01);
    // Raised 3 mm, the crest pokes 1 mm into it.
    let c = wall.segment_contact(&(a + v(0.0, 0.003)), &(b + v(0.0, 0.003)));
    assert!(close(c.wall.gap_m, -0.001, 1e-12), "{c:?}");
    // The wavelength is 1 / f: one cycle per 1 / 9.5 m.
    assert!(close(wall.wavelength_m(), 1.0 / 9.5, 1e-15));
    let p0 = wall.point_at_m(0.1);
    let p1 = wall.point_at_m(0.1 + wall.wavelength_m());
    assert!(close(p0.y, p1.y, 1e-14));
}

#[test]
fn sinusoid_arclength_matches_dense_quadrature() {
    let wall = Sinusoid::new(v(0.02, 0.1), 0.3, 0.05, 20.0, 1.0, SolidSide::Right).unwrap();
    // Dense midpoint rule along the curve from t = 0.
    let arclength = |t_end: f64| {
        let steps = 200_000;
        let h = t_end / steps as f64;
        (0..steps)
            .map(|i| {
                let t = (i as f64 + 0.5) * h;
                (wall.point_at_m(t + 0.5 * h) - wall.point_at_m(t - 0.5 * h)).norm()
            })
            .sum::<f64>()
            * t_end.signum()
    };
    for &t in &[0.013, 0.05, 0.137, -0.061] {
        let expected = arclength(t);
        assert!(
            close(wall.arclength_at_m(t), expected, 1e-7),
            "{t}: {} vs {expected}",
            wall.arclength_at_m(t)
        );
    }
}

#[test]
fn non_finite_and_far_queries_answer_without_panicking() {
    let walls = [
        Wall::smooth(Line::new(v(0.0, 0.1), 0.0, SolidSide::Left).unwrap()),
        Wall::smooth(trapezoid()),
        Wall::smooth(Sinusoid::new(v(0.0, 0.1), 0.0, 0.05, 20.0, 0.0, SolidSide::Left).unwrap()),
    ];
    for wall in &walls {
        assert!(!wall.signed_distance(&v(f64::NAN, 0.0)).gap_m.is_finite());
        assert!(
            !wall
                .signed_distance(&v(0.0, f64::INFINITY))
                .gap_m
                .is_finite()
        );
        let c = wall.segment_contact(&v(0.0, f64::NAN), &v(0.1, 0.0));
        assert!(!c.wall.gap_m.is_finite() || c.s == 1.0);
        // 100 m below the wall: the distance to its nearest lowest point.
        let lowest = match &wall.shape {
            sim_core::WallShape::Sinusoid(_) => v(0.1375, 0.05),
            sim_core::WallShape::Polyline(_) => v(0.13, 0.07),
            sim_core::WallShape::Line(_) => v(0.13, 0.1),
        };
        let w = wall.signed_distance(&v(0.13, -100.0));
        assert!(
            close(w.gap_m, (v(0.13, -100.0) - lowest).norm(), 1e-9),
            "{w:?}"
        );
    }
}

/// The normals a wall presses with at a point's signed distance: one on an edge, a line or
/// a sinusoid (the signed distance's), the two edges' at a polyline corner and within
/// `within_m` of it along an edge, and the end edge's along the rays past the polyline's
/// ends.
#[test]
fn normal_cones_are_an_edges_normal_or_a_corners_two() {
    // A V, solid below: edges (0,0)->(1,-1) and (1,-1)->(2,0); the corner at (1,-1).
    let vee = Wall::smooth(
        Polyline::new(
            vec![v(0.0, 0.0), v(1.0, -1.0), v(2.0, 0.0)],
            SolidSide::Right,
        )
        .unwrap(),
    );
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let first = vee.signed_distance(&v(0.5, 0.0)).normal;
    let second = vee.signed_distance(&v(1.5, 0.0)).normal;
    assert!((first - v(s, s)).norm() < 1e-12 || (first - v(-s, -s)).norm() < 1e-12);
    assert!((first - second).norm() > 1.0, "two edges, two normals");
    let within_m = 1e-4;
    assert_eq!(
        vee.shape
            .normal_cone(&vee.signed_distance(&v(0.5, 0.0)), within_m),
        [first; 2]
    );
    assert_eq!(
        vee.shape
            .normal_cone(&vee.signed_distance(&v(1.5, 0.0)), within_m),
        [second; 2]
    );
    // On the corner, below it (nearest to the corner itself), and on the first edge 0.5e-4 m
    // (along it) from the corner.
    let near = v(1.0, -1.0) - v(s, -s) * 0.5e-4 + v(s, s) * 1e-9;
    for p in [v(1.0, -1.0), v(1.0, -1.5), near] {
        assert_eq!(
            vee.shape.normal_cone(&vee.signed_distance(&p), within_m),
            [first, second],
            "at {p:?}"
        );
    }
    // 2e-4 m from the corner along the first edge: that edge's alone.
    let far = v(1.0, -1.0) - v(s, -s) * 2e-4 + v(s, s) * 1e-9;
    assert_eq!(
        vee.shape.normal_cone(&vee.signed_distance(&far), within_m),
        [first; 2]
    );
    // Past the ends, along the end rays.
    assert_eq!(
        vee.shape
            .normal_cone(&vee.signed_distance(&v(-1.0, 1.5)), within_m),
        [first; 2]
    );
    assert_eq!(
        vee.shape
            .normal_cone(&vee.signed_distance(&v(3.0, 1.5)), within_m),
        [second; 2]
    );
    // A line and a sinusoid: the signed distance's normal.
    let line = Wall::smooth(Line::new(v(0.0, 0.1), 0.2, SolidSide::Left).unwrap());
    let p = v(0.3, -0.2);
    assert_eq!(
        line.shape.normal_cone(&line.signed_distance(&p), within_m),
        [line.signed_distance(&p).normal; 2]
    );
    let wave =
        Wall::smooth(Sinusoid::new(v(0.0, 0.1), 0.0, 0.01, 8.0, 0.3, SolidSide::Left).unwrap());
    assert_eq!(
        wave.shape.normal_cone(&wave.signed_distance(&p), within_m),
        [wave.signed_distance(&p).normal; 2]
    );
}
