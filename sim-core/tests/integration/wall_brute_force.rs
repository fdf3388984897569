//! Wall queries against brute force (docs/model.md 6): the sinusoid's nearest point against dense
//! sampling of the curve, the polyline's signed distance against an independent
//! point-to-segment computation, and `segment_contact` against dense sampling along the
//! segment for all three shapes (amplitudes up to 5 cm, 1 to 20 cycles/m, links 5 to 60 mm,
//! and some up to 150 mm).
#![allow(clippy::unwrap_used)]

use nalgebra::Vector2;
use proptest::prelude::*;
use sim_core::{Line, Polyline, Sinusoid, SolidSide, Wall, WallShape};

fn v(x: f64, y: f64) -> Vector2<f64> {
    Vector2::new(x, y)
}

fn side(left: bool) -> SolidSide {
    if left {
        SolidSide::Left
    } else {
        SolidSide::Right
    }
}

/// Distance from `p` to the segment `a -> b`.
fn point_segment_distance(p: Vector2<f64>, a: Vector2<f64>, b: Vector2<f64>) -> f64 {
    let d = b - a;
    let s = ((p - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0);
    (p - (a + d * s)).norm()
}

/// The local frame `(x, y)` of a point for a sinusoid along `direction` through `o`.
fn local(o: Vector2<f64>, direction: f64, p: Vector2<f64>) -> (f64, f64) {
    let (s, c) = direction.sin_cos();
    let r = p - o;
    (c * r.x + s * r.y, -s * r.x + c * r.y)
}

fn sinusoid_strategy() -> impl Strategy<Value = (Sinusoid, f64, f64, f64)> {
    (
        0.0..0.05f64,
        1.0..20.0f64,
        -3.2..3.2f64,
        -1.0..1.0f64,
        any::<bool>(),
    )
        .prop_map(|(amplitude, frequency, phase, direction, left)| {
            let wall = Sinusoid::new(
                v(0.01, 0.1),
                direction,
                amplitude,
                frequency,
                phase,
                side(left),
            )
            .unwrap();
            (wall, amplitude, frequency, phase)
        })
}

/// A polyline over increasing x (so the vertical test gives the sign): 2 to 7 vertices.
fn polyline_strategy() -> impl Strategy<Value = (Vec<Vector2<f64>>, bool)> {
    (
        prop::collection::vec((0.005..0.08f64, -0.04..0.04f64), 2..7),
        any::<bool>(),
    )
        .prop_map(|(steps, left)| {
            let mut x = -0.1;
            let vertices = steps
                .into_iter()
                .map(|(dx, y)| {
                    x += dx;
                    v(x, 0.1 + y)
                })
                .collect();
            (vertices, left)
        })
}

/// A digitized wall over increasing x: 40 to 150 vertices 1 to 4 mm apart with up to 1 mm of
/// noise (many edges beyond any one segment's reach, which `segment_contact` leaves out).
fn dense_polyline_strategy() -> impl Strategy<Value = (Vec<Vector2<f64>>, bool)> {
    (
        prop::collection::vec((0.001..0.004f64, -0.001..0.001f64), 40..150),
        -0.3..0.3f64,
        any::<bool>(),
    )
        .prop_map(|(steps, slope, left)| {
            let mut x = -0.1;
            let vertices = steps
                .into_iter()
                .map(|(dx, y)| {
                    x += dx;
                    v(x, 0.1 + slope * (x - 0.1) + y)
                })
                .collect();
            (vertices, left)
        })
}

/// A segment near the wall band: start within `reach` of y = 0.1, random direction.
fn segment_strategy(reach: f64) -> impl Strategy<Value = (Vector2<f64>, Vector2<f64>)> {
    (
        -0.1..0.3f64,
        -reach..reach,
        -3.2..3.2f64,
        prop_oneof![4 => 0.005..0.06f64, 1 => 0.06..0.15f64],
    )
        .prop_map(|(x, y, angle, length)| {
            let a = v(x, 0.1 + y);
            (a, a + v(angle.cos(), angle.sin()) * length)
        })
}

/// Checks `segment_contact` against sampling `samples + 1` points along the segment.
fn check_segment(wall: &WallShape, a: Vector2<f64>, b: Vector2<f64>, samples: usize) {
    let c = wall.segment_contact(&a, &b);
    assert!((0.0..=1.0).contains(&c.s));
    assert!((c.point_m - (a + (b - a) * c.s)).norm() < 1e-15);
    let again = wall.signed_distance(&c.point_m);
    assert!((again.gap_m - c.wall.gap_m).abs() < 1e-15);
    let sampled = (0..=samples)
        .map(|i| {
            wall.signed_distance(&(a + (b - a) * (i as f64 / samples as f64)))
                .gap_m
        })
        .fold(f64::INFINITY, f64::min);
    // Never shallower than any sample; no deeper than the true minimum, which the samples
    // bound to within half their spacing (the signed distance is 1-Lipschitz).
    assert!(
        c.wall.gap_m <= sampled + 1e-12,
        "segment_contact {} > sampled {sampled} for {a:?} -> {b:?}",
        c.wall.gap_m
    );
    let spacing = (b - a).norm() / samples as f64;
    assert!(c.wall.gap_m >= sampled - 0.5 * spacing - 1e-12);
    // The broad phase's bound is a lower bound: of the deepest point's gap and of every
    // sample's (the end points' own bounds too).
    let bound = wall.segment_gap_lower_bound_m(&a, &b);
    assert!(
        bound <= c.wall.gap_m + 1e-15,
        "lower bound {bound} above the gap {} for {a:?} -> {b:?}",
        c.wall.gap_m
    );
    for p in [a, b] {
        let gap = wall.signed_distance(&p).gap_m;
        assert!(wall.gap_lower_bound_m(&p) <= gap + 1e-15);
    }
    // The early-out agrees with the full answer on both sides of the threshold.
    for margin in [0.0, 0.002, 0.02] {
        let within = wall.segment_contact_within(&a, &b, margin);
        assert_eq!(within.is_some(), c.wall.gap_m <= margin);
        if let Some(w) = within {
            assert_eq!(w, c);
        }
    }
}

/// A point 8.76 mm inside a steep sinusoid (37 mm amplitude, 9.13 cycles/m: a smallest
/// radius of curvature of 8.2 mm), past the centre of curvature of the crest above it, has
/// two nearest-point candidates 6 mm apart on either side of the crest, nearly level with
/// the maximum between them; the nearest-point search once refined only the one its samples
/// showed and came out 4 um too deep (found by `sinusoid_segment_contact_beats_sampling` on
/// a proptest seed CI does not pin). Along the segment through it the signed distance must
/// stay 1-Lipschitz, and the segment's deepest point must beat dense sampling.
#[test]
fn a_point_past_a_crests_centre_of_curvature_finds_its_nearest_point() {
    let wall = Sinusoid::new(
        v(0.01, 0.1),
        -0.627_255_553_913_206_3,
        0.036_991_922_761_345_18,
        9.129_304_270_248_262,
        -0.833_766_115_396_753_6,
        SolidSide::Right,
    )
    .unwrap();
    let a = v(0.060_255_318_039_237_345, 0.098_401_460_121_233_92);
    let b = v(0.078_684_006_361_575_08, 0.086_116_770_787_776_96);
    // Dense sampling of the curve for one point: its parameter in the baseline frame.
    let (o, direction) = (wall.baseline_point_m(), wall.direction_rad());
    let (amplitude, k) = (
        0.036_991_922_761_345_18,
        std::f64::consts::TAU * 9.129_304_270_248_262,
    );
    let g = |t: f64| amplitude * (k * t - 0.833_766_115_396_753_6).sin();
    let sampled_distance = |p: Vector2<f64>| {
        let (px, py) = local(o, direction, p);
        let step = 1e-6;
        (0..=40_000)
            .map(|i| {
                let t = px - 0.02 + i as f64 * step;
                ((t - px).powi(2) + (g(t) - py).powi(2)).sqrt()
            })
            .fold(f64::INFINITY, f64::min)
    };
    // The steepest slope is A k = 2.12: sampling the curve every 1 um of its parameter
    // finds a point within 1.2 um (half a step along a curve that steep) of the nearest.
    let slack = 0.5e-6 * (1.0 + (amplitude * k).powi(2)).sqrt();
    let mut last: Option<f64> = None;
    for i in 0..=200 {
        let s = 0.012 + 0.002 * f64::from(i) / 200.0;
        let p = a + (b - a) * s;
        let gap = wall.signed_distance(&p).gap_m;
        let sampled = sampled_distance(p);
        assert!(gap < 0.0);
        assert!(
            gap.abs() <= sampled + 1e-12,
            "s = {s}: {} > sampled {sampled}",
            gap.abs()
        );
        assert!(
            gap.abs() >= sampled - slack - 1e-12,
            "s = {s}: {} < sampled {sampled}",
            gap.abs()
        );
        if let Some(before) = last {
            // 1-Lipschitz along the segment.
            assert!((gap - before).abs() <= 0.002 / 200.0 * (b - a).norm() + 1e-15);
        }
        last = Some(gap);
    }
    check_segment(&WallShape::Sinusoid(wall), a, b, 20_000);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn sinusoid_nearest_point_beats_dense_sampling(
        (wall, amplitude, frequency, phase) in sinusoid_strategy(),
        x in -0.2..0.3f64,
        height in -0.08..0.08f64,
    ) {
        let direction = wall.direction_rad();
        let o = wall.baseline_point_m();
        let p = o + v(direction.cos(), direction.sin()) * x
            + v(-direction.sin(), direction.cos()) * height;
        let w = wall.signed_distance(&p);
        let (px, py) = local(o, direction, p);
        let g = |t: f64| amplitude * (std::f64::consts::TAU * frequency * t + phase).sin();
        // The closest point is on the curve, at distance |gap|, along the normal.
        let (cx, cy) = local(o, direction, w.closest_m);
        prop_assert!((cy - g(cx)).abs() < 1e-12);
        prop_assert!(((p - w.closest_m).norm() - w.gap_m.abs()).abs() < 1e-12);
        prop_assert!((p - w.closest_m - w.normal * w.gap_m).norm() < 1e-9);
        prop_assert!((w.normal.norm() - 1.0).abs() < 1e-12 && w.normal.dot(&w.tangent).abs() < 1e-12);
        // The sign: free side by the vertical test.
        let free_above = wall.solid_side() == SolidSide::Right;
        let vertical = py - g(px);
        if vertical.abs() > 1e-12 {
            prop_assert_eq!(w.gap_m > 0.0, (vertical > 0.0) == free_above);
        }
        // Dense sampling of the curve around the point (step 10 um, covering the bracket).
        let reach = vertical.abs() + 0.01;
        let step = 1e-5;
        let count = (2.0 * reach / step) as usize + 1;
        let sampled = (0..=count)
            .map(|i| {
                let t = px - reach + i as f64 * step;
                ((t - px).powi(2) + (g(t) - py).powi(2)).sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        prop_assert!(w.gap_m.abs() <= sampled + 1e-12, "{} > sampled {}", w.gap_m.abs(), sampled);
        let lipschitz = (1.0 + (amplitude * std::f64::consts::TAU * frequency).powi(2)).sqrt();
        prop_assert!(w.gap_m.abs() >= sampled - 0.5 * step * lipschitz - 1e-12);
    }

    #[test]
    fn polyline_signed_distance_matches_point_to_segment(
        (vertices, left) in polyline_strategy(),
        p in (-0.3..0.5f64, 0.0..0.2f64).prop_map(|(x, y)| v(x, y)),
    ) {
        let wall = Polyline::new(vertices.clone(), side(left)).unwrap();
        let w = wall.signed_distance(&p);
        // Independent: distance to the edges, the end edges extended 100 m.
        let k = vertices.len() - 1;
        let mut ends = vertices.clone();
        ends[0] = vertices[0] - (vertices[1] - vertices[0]).normalize() * 100.0;
        ends[k] = vertices[k] + (vertices[k] - vertices[k - 1]).normalize() * 100.0;
        let distance = ends
            .windows(2)
            .map(|e| point_segment_distance(p, e[0], e[1]))
            .fold(f64::INFINITY, f64::min);
        prop_assert!((w.gap_m.abs() - distance).abs() < 1e-12, "{} vs {distance}", w.gap_m);
        prop_assert!(((p - w.closest_m).norm() - distance).abs() < 1e-12);
        // Sign: the polyline is a graph over x; solid above for Left.
        let i = ends.windows(2).position(|e| p.x <= e[1].x).unwrap();
        let (e0, e1) = (ends[i], ends[i + 1]);
        let y_wall = e0.y + (e1.y - e0.y) * (p.x - e0.x) / (e1.x - e0.x);
        if (p.y - y_wall).abs() > 1e-9 && distance > 1e-9 {
            prop_assert_eq!(w.gap_m > 0.0, (p.y < y_wall) == left);
        }
        prop_assert!((w.normal.norm() - 1.0).abs() < 1e-12);
        prop_assert!((p - w.closest_m - w.normal * w.gap_m).norm() < 1e-9);
    }

    #[test]
    fn line_segment_contact_beats_sampling(
        angle in -3.2..3.2f64,
        left in any::<bool>(),
        (a, b) in segment_strategy(0.08),
    ) {
        let wall = WallShape::Line(Line::new(v(0.05, 0.1), angle, side(left)).unwrap());
        check_segment(&wall, a, b, 2000);
    }

    #[test]
    fn polyline_segment_contact_beats_sampling(
        (vertices, left) in polyline_strategy(),
        (a, b) in segment_strategy(0.08),
    ) {
        let wall = WallShape::Polyline(Polyline::new(vertices, side(left)).unwrap());
        check_segment(&wall, a, b, 2000);
    }

    #[test]
    fn digitized_polyline_segment_contact_beats_sampling(
        (vertices, left) in dense_polyline_strategy(),
        (a, b) in segment_strategy(0.02),
    ) {
        let wall = WallShape::Polyline(Polyline::new(vertices, side(left)).unwrap());
        check_segment(&wall, a, b, 2000);
    }

    /// A contact solver's interior point of a segment that stays in free space is never
    /// deeper than the segment comes to the wall: a corner off to the side of the segment
    /// is not measured along the segment's normal.
    #[test]
    fn polyline_interior_contact_of_a_free_segment_is_no_deeper_than_it(
        (vertices, left) in polyline_strategy(),
        (a, b) in segment_strategy(0.08),
    ) {
        let wall = Polyline::new(vertices, side(left)).unwrap();
        let samples = 2000;
        let sampled = (0..=samples)
            .map(|i| wall.signed_distance(&(a + (b - a) * (i as f64 / samples as f64))).gap_m)
            .fold(f64::INFINITY, f64::min);
        let spacing = (b - a).norm() / samples as f64;
        let lowest = sampled - 0.5 * spacing - 1e-12;
        if let Some(c) = wall.segment_interior_contact(&a, &b) {
            prop_assert!(c.s > 0.0 && c.s < 1.0);
            prop_assert!((c.point_m - (a + (b - a) * c.s)).norm() < 1e-15);
            if lowest > 0.0 {
                prop_assert!(
                    c.wall.gap_m >= lowest,
                    "{} < {lowest} for {a:?} -> {b:?}",
                    c.wall.gap_m
                );
            }
        }
    }

    #[test]
    fn sinusoid_segment_contact_beats_sampling(
        (wall, amplitude, _, _) in sinusoid_strategy(),
        (a, b) in segment_strategy(0.08),
    ) {
        let _ = amplitude;
        let wall = Wall::smooth(wall);
        check_segment(&wall.shape, a, b, 1000);
    }
}

/// The broad phase spares a sinusoid's search where the antenna is not near it: a link 5 mm
/// clear of the thesis's 14.2 cycles/m, 10 mm sinusoid (steepest slope 0.89) inside its band is
/// bounded above zero, within the `1 / sqrt(1 + 0.89^2)` of its vertical gap the bound
/// promises; a link beyond the band by its height there; a link through the wall below zero.
#[test]
fn the_broad_phase_bounds_links_clear_of_a_sinusoid_above_zero() {
    let wall = WallShape::from(
        Sinusoid::new(v(0.0, 0.17), 0.0, 0.01, 14.2, 0.0, SolidSide::Left).unwrap(),
    );
    // Free side is below (solid on the left of +x): the crest seen from it is where
    // sin = -1, the curve at y = 0.16. A link across it, 5 mm below.
    let crest = 0.75 / 14.2;
    let (a, b) = (v(crest - 0.01, 0.155), v(crest + 0.01, 0.155));
    let gap = wall.segment_contact(&a, &b).wall.gap_m;
    let bound = wall.segment_gap_lower_bound_m(&a, &b);
    let slope = 0.01 * 2.0 * std::f64::consts::PI * 14.2;
    assert!(bound > 0.0 && bound <= gap, "bound {bound}, gap {gap}");
    assert!(bound >= 0.005 / (1.0 + slope * slope).sqrt() - 1e-12);
    // Beyond the band (y < 0.16) by 30 mm at its nearer end.
    let (a, b) = (v(0.0, 0.13), v(0.04, 0.125));
    assert!((wall.segment_gap_lower_bound_m(&a, &b) - 0.03).abs() < 1e-12);
    // Through the crest by 5 mm: a bound below zero, below the link's gap.
    let (a, b) = (v(crest - 0.01, 0.165), v(crest + 0.01, 0.165));
    let bound = wall.segment_gap_lower_bound_m(&a, &b);
    assert!(bound < 0.0 && bound <= wall.segment_contact(&a, &b).wall.gap_m);
    assert!(wall.gap_lower_bound_m(&v(f64::NAN, 0.0)).is_nan());
}
