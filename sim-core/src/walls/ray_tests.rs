//! The ray query ([`Wall::ray_hit_m`], [`first_ray_hit`]) against closed forms and
//! brute-force sampling, and the mirror image ([`Wall::mirrored_about_x_axis`]) against the
//! signed distance and the surfaces of the original.
#![allow(clippy::unwrap_used)]

use core::f64::consts::{FRAC_PI_2, PI, TAU};

use nalgebra::{Matrix2, Vector2};
use proptest::prelude::*;

use super::*;

fn v(x: f64, y: f64) -> Vector2<f64> {
    Vector2::new(x, y)
}

fn unit(angle_rad: f64) -> Vector2<f64> {
    Vector2::new(angle_rad.cos(), angle_rad.sin())
}

/// The thesis's trapezoid (as in the integration tests): a bump hanging from a wall at
/// y = 0.10 m, solid above, down to y = 0.07 between x = 0.10 and 0.16.
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

/// Where the ray `o + t d` crosses the line `p + s w`, solved as a 2x2 system: `(t, s)`.
fn crossing(o: Vector2<f64>, d: Vector2<f64>, p: Vector2<f64>, w: Vector2<f64>) -> (f64, f64) {
    let m = Matrix2::new(d.x, -w.x, d.y, -w.y);
    let ts = m.try_inverse().unwrap() * (p - o);
    (ts.x, ts.y)
}

#[test]
fn a_line_is_hit_where_the_closed_form_says() {
    let angle = 8f64.to_radians();
    let point = v(0.0, 0.2);
    let line = Line::new(point, angle, SolidSide::Left).unwrap();
    for (origin, ray_angle) in [
        (v(0.0, 0.0), FRAC_PI_2),
        (v(0.1, 0.05), 1.2),
        (v(-0.3, 0.1), 0.3),
        (v(0.2, 0.5), -1.9),
    ] {
        let d = unit(ray_angle);
        let (t, _) = crossing(origin, d, point, unit(angle));
        let hit = line.ray_hit_m(&origin, &d, 10.0).unwrap();
        assert!((hit - t).abs() < 1e-13, "{hit} vs {t}");
        assert!(line.signed_distance(&(origin + d * hit)).gap_m.abs() < 1e-14);
        // Too short a ray, and the ray pointing the other way, miss.
        assert_eq!(line.ray_hit_m(&origin, &d, 0.99 * t), None);
        assert_eq!(line.ray_hit_m(&origin, &(-d), 10.0), None);
    }
    // Parallel: no hit, from either side.
    assert_eq!(line.ray_hit_m(&v(0.0, 0.0), &unit(angle), 1e9), None);
    assert_eq!(line.ray_hit_m(&v(0.0, 0.5), &unit(angle + PI), 1e9), None);
    // On the line: at once.
    assert_eq!(line.ray_hit_m(&point, &unit(1.0), 1.0), Some(0.0));
    // Not a ray.
    let o = v(0.0, 0.0);
    assert_eq!(line.ray_hit_m(&o, &v(0.0, 2.0), 10.0), None);
    assert_eq!(line.ray_hit_m(&o, &v(f64::NAN, 1.0), 10.0), None);
    assert_eq!(
        line.ray_hit_m(&v(f64::INFINITY, 0.0), &v(0.0, 1.0), 10.0),
        None
    );
    assert_eq!(line.ray_hit_m(&o, &v(0.0, 1.0), f64::NAN), None);
    assert_eq!(line.ray_hit_m(&o, &v(0.0, 1.0), -1.0), None);
    assert!(line.ray_hit_m(&o, &v(0.0, 1.0), f64::INFINITY).is_some());
}

#[test]
fn a_trapezoid_is_hit_on_each_edge_and_each_end_ray() {
    let wall = trapezoid();
    let vertices = wall.vertices_m().to_vec();
    let edges = vertices.len() - 1;
    for edge in 0..edges {
        let (a, b) = (vertices[edge], vertices[edge + 1]);
        let t = (b - a).normalize();
        let n = SolidSide::Left.free_normal(&t);
        // A point along the edge, and on the end rays well beyond the end vertices.
        let targets = match edge {
            0 => vec![a + (b - a) * 0.3, a - t * 0.5],
            e if e == edges - 1 => vec![a + (b - a) * 0.3, b + t * 0.5],
            _ => vec![a + (b - a) * 0.3, a + (b - a) * 0.8],
        };
        for target in targets {
            // From 2 cm off the wall in free space, straight at it and at a slant.
            for tilt in [0.0, 0.3, -0.3] {
                let d = {
                    let base = -n;
                    let (s, c) = f64::sin_cos(tilt);
                    v(c * base.x - s * base.y, s * base.x + c * base.y)
                };
                let origin = target - d * 0.02;
                let hit = wall.ray_hit_m(&origin, &d, 1.0).unwrap();
                assert!(
                    (hit - 0.02).abs() < 1e-12,
                    "edge {edge} tilt {tilt}: {hit} (target {target:?})"
                );
            }
        }
    }
    // Up the middle of the bump's floor; across the bump sideways, entering its left slope.
    assert!((wall.ray_hit_m(&v(0.13, 0.0), &v(0.0, 1.0), 1.0).unwrap() - 0.07).abs() < 1e-14);
    let hit = wall.ray_hit_m(&v(-0.1, 0.085), &v(1.0, 0.0), 1.0).unwrap();
    assert!((hit - 0.185).abs() < 1e-12, "{hit}");
    // Through a vertex exactly, and pointing away.
    let hit = wall.ray_hit_m(&v(0.10, 0.0), &v(0.0, 1.0), 1.0).unwrap();
    assert!((hit - 0.07).abs() < 1e-14, "{hit}");
    assert_eq!(wall.ray_hit_m(&v(0.13, 0.0), &v(0.0, -1.0), 1.0), None);
    // On the floor, along it: at once.
    let hit = wall.ray_hit_m(&v(0.12, 0.07), &v(1.0, 0.0), 1.0).unwrap();
    assert_eq!(hit, 0.0);
    let along =
        Polyline::new(vec![v(0.0, 0.0), v(1.0, 0.0), v(2.0, 1.0)], SolidSide::Left).unwrap();
    let hit = along.ray_hit_m(&v(-1.0, 0.0), &v(1.0, 0.0), 5.0).unwrap();
    assert_eq!(hit, 0.0, "the first edge's backward ray runs along the ray");
    let hit = along.ray_hit_m(&v(3.0, 1.0), &v(-1.0, 0.0), 5.0).unwrap();
    assert!((hit - 1.0).abs() < 1e-14, "{hit}");
}

/// The sign of the wall's signed distance at `n` points of `o + t d`, `t` in `[0, t_max)`,
/// changes nowhere, and is that of `o`.
fn no_crossing_before(wall: &Wall, o: Vector2<f64>, d: Vector2<f64>, t_max: f64, n: usize) -> bool {
    let sign = wall.signed_distance(&o).gap_m.signum();
    (1..n).all(|i| {
        let t = t_max * i as f64 / n as f64;
        wall.signed_distance(&(o + d * t)).gap_m.signum() == sign
    })
}

/// The vertical offset `y - g(x)` of a point from a sinusoid, in its baseline frame, from its
/// description (not from its code).
fn vertical_offset(w: &Sinusoid, p: Vector2<f64>) -> f64 {
    let (s, c) = w.direction_rad().sin_cos();
    let r = p - w.baseline_point_m();
    let (x, y) = (c * r.x + s * r.y, -s * r.x + c * r.y);
    y - w.amplitude_m() * (TAU * w.frequency_per_m() * x + w.phase_rad()).sin()
}

#[test]
fn a_vertical_ray_hits_a_sinusoid_at_its_value() {
    let angle = 0.4;
    let w = Sinusoid::new(v(0.1, 0.2), angle, 0.02, 6.3, 0.7, SolidSide::Left).unwrap();
    let (u, n) = (unit(angle), unit(angle + FRAC_PI_2));
    for x in [-0.3, -0.01, 0.0, 0.05, 0.123, 0.4] {
        let g = 0.02 * (TAU * 6.3 * x + 0.7).sin();
        // From below the band, up along the baseline's normal, and from above, down.
        let below = w.baseline_point_m() + u * x - n * 0.05;
        let hit = w.ray_hit_m(&below, &n, 1.0).unwrap();
        assert!(
            (hit - (0.05 + g)).abs() < 1e-12,
            "x {x}: {hit} vs {}",
            0.05 + g
        );
        let above = w.baseline_point_m() + u * x + n * 0.03;
        let hit = w.ray_hit_m(&above, &(-n), 1.0).unwrap();
        assert!((hit - (0.03 - g)).abs() < 1e-12, "x {x}: {hit}");
        assert_eq!(w.ray_hit_m(&above, &n, 1.0), None);
    }
    // Along the baseline from outside the band: none; inside it: within a wavelength.
    assert_eq!(
        w.ray_hit_m(&(n * 0.0201 + w.baseline_point_m()), &u, 1e6),
        None
    );
    let hit = w
        .ray_hit_m(&(n * 0.0199 + w.baseline_point_m()), &u, f64::INFINITY)
        .unwrap();
    assert!(hit < w.wavelength_m());
    // Tangent to a crest (g = A at k x + phase = pi/2): it touches there.
    let x_crest = (FRAC_PI_2 - 0.7) / (TAU * 6.3);
    let origin = w.baseline_point_m() + u * (x_crest - 0.05) + n * 0.02;
    let hit = w.ray_hit_m(&origin, &u, 1.0).unwrap();
    assert!((hit - 0.05).abs() < 1e-6, "{hit}");
    // A flat sinusoid is a line.
    let flat = Sinusoid::new(v(0.0, 0.1), 0.0, 0.0, 5.0, 0.0, SolidSide::Left).unwrap();
    let hit = flat.ray_hit_m(&v(0.3, 0.0), &unit(1.0), 1.0).unwrap();
    assert!((hit - 0.1 / 1f64.sin()).abs() < 1e-12, "{hit}");
}

#[test]
fn a_ray_grazing_between_two_close_crossings_finds_the_first() {
    // A horizontal ray just under a crest crosses twice, 2 * sqrt(2 h / (A k^2)) apart.
    let w = Sinusoid::new(v(0.0, 0.0), 0.0, 0.02, 10.0, 0.0, SolidSide::Left).unwrap();
    let k = TAU * 10.0;
    for h in [1e-6, 1e-9, 1e-11] {
        let y = 0.02 - h;
        let half = (2.0 * h / (0.02 * k * k)).sqrt();
        let x_crest = FRAC_PI_2 / k;
        let origin = v(x_crest - 0.01, y);
        let hit = w.ray_hit_m(&origin, &v(1.0, 0.0), 1.0).unwrap();
        let expected = 0.01 - half;
        assert!(
            (hit - expected).abs() < 1e-3 * half + 1e-11,
            "h {h}: {hit} vs {expected}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// A random ray against a random sinusoid: the hit lies on the curve within 1e-9 m and
    /// no crossing comes before it at a fine sampling of the offset; no hit, no crossing.
    #[test]
    fn a_sinusoid_is_hit_at_its_first_crossing(
        angle in -PI..PI,
        amplitude in 0.0f64..0.05,
        frequency in 1.0f64..20.0,
        phase in -PI..PI,
        ox in -0.3f64..0.3,
        oy in -0.15f64..0.15,
        ray_angle in -PI..PI,
        max_m in 0.01f64..0.6,
        solid_left in any::<bool>(),
    ) {
        let solid = if solid_left { SolidSide::Left } else { SolidSide::Right };
        let w = Sinusoid::new(v(0.02, -0.01), angle, amplitude, frequency, phase, solid).unwrap();
        let o = v(ox, oy);
        let d = unit(ray_angle);
        let n = 20_000;
        let offset = |t: f64| vertical_offset(&w, o + d * t);
        let sign0 = offset(0.0).signum();
        match w.ray_hit_m(&o, &d, max_m) {
            Some(t) => {
                prop_assert!((0.0..=max_m).contains(&t));
                let gap = w.signed_distance(&(o + d * t)).gap_m;
                prop_assert!(gap.abs() < 1e-9, "hit {t} is {gap} off the curve");
                let before = (t - 1e-9).max(0.0);
                for i in 0..n {
                    let s = before * i as f64 / n as f64;
                    prop_assert!(offset(s).signum() == sign0, "a crossing at {s} before {t}");
                }
            }
            None => {
                for i in 0..=n {
                    let s = max_m * i as f64 / n as f64;
                    prop_assert!(offset(s).signum() == sign0, "a crossing at {s} missed");
                }
            }
        }
    }

    /// A random ray against the trapezoid, rotated and moved: the hit matches the smallest
    /// crossing of the edges solved as 2x2 systems, lies on the wall, and nothing is
    /// crossed before it.
    #[test]
    fn a_polyline_is_hit_at_its_first_crossing(
        turn in -PI..PI,
        ox in -0.2f64..0.5,
        oy in -0.1f64..0.3,
        ray_angle in -PI..PI,
        max_m in 0.01f64..1.0,
    ) {
        let (s, c) = turn.sin_cos();
        let rotate = |p: Vector2<f64>| v(c * p.x - s * p.y, s * p.x + c * p.y);
        let base = trapezoid();
        let vertices: Vec<_> = base.vertices_m().iter().map(|p| rotate(*p)).collect();
        let wall = Wall::smooth(Polyline::new(vertices.clone(), SolidSide::Left).unwrap());
        let o = v(ox, oy);
        let d = unit(ray_angle);
        let edges = vertices.len() - 1;
        let mut oracle: Option<f64> = None;
        for e in 0..edges {
            let (a, b) = (vertices[e], vertices[e + 1]);
            let (t, s) = crossing(o, d, a, b - a);
            let lo = if e == 0 { f64::NEG_INFINITY } else { 0.0 };
            let hi = if e == edges - 1 { f64::INFINITY } else { 1.0 };
            if s >= lo && s <= hi && t >= 0.0 && t <= max_m && oracle.is_none_or(|b| t < b) {
                oracle = Some(t);
            }
        }
        let hit = wall.ray_hit_m(&o, &d, max_m);
        match (hit, oracle) {
            (Some(t), Some(expected)) => {
                prop_assert!((t - expected).abs() < 1e-12, "{t} vs {expected}");
                prop_assert!(wall.signed_distance(&(o + d * t)).gap_m.abs() < 1e-12);
                prop_assert!(no_crossing_before(&wall, o, d, (t - 1e-9).max(0.0), 2000));
            }
            (None, None) => {
                prop_assert!(no_crossing_before(&wall, o, d, max_m, 2000));
            }
            other => prop_assert!(false, "{other:?}"),
        }
    }

    /// A point's mirror image is as far from the mirrored wall, on the same side, and on
    /// the same surface, for every shape; the mirrored wall answers a ray's mirror image
    /// at the same distance.
    #[test]
    fn a_mirrored_wall_keeps_every_distance_and_surface(
        px in -0.4f64..0.6,
        py in -0.3f64..0.3,
        angle in -PI..PI,
        amplitude in 0.0f64..0.04,
        frequency in 1.0f64..15.0,
        phase in -PI..PI,
        ray_angle in -PI..PI,
        solid_left in any::<bool>(),
    ) {
        let solid = if solid_left { SolidSide::Left } else { SolidSide::Right };
        let felt = Surface::Rough { mu: 0.8, hold_shear_n: 0.01, hold_tension_n: 0.005 };
        let zones = [
            SurfaceMap::zoned(ZoneAxis::Arclength, Surface::default(), vec![(0.05, felt)])
                .unwrap(),
            SurfaceMap::zoned(ZoneAxis::WorldX, Surface::default(), vec![(0.12, felt)])
                .unwrap(),
        ];
        let shapes: [WallShape; 3] = [
            Line::new(v(0.05, 0.1), angle, solid).unwrap().into(),
            Polyline::new(
                trapezoid().vertices_m().iter().map(|p| p + v(0.0, -0.05)).collect(),
                solid,
            )
            .unwrap()
            .into(),
            Sinusoid::new(v(-0.02, 0.03), angle, amplitude, frequency, phase, solid)
                .unwrap()
                .into(),
        ];
        let p = v(px, py);
        let mirror = |q: Vector2<f64>| v(q.x, -q.y);
        for shape in shapes {
            for surfaces in &zones {
                let wall = Wall::new(shape.clone(), surfaces.clone());
                let mirrored = wall.mirrored_about_x_axis();
                let a = wall.signed_distance(&p);
                let b = mirrored.signed_distance(&mirror(p));
                prop_assert!((a.gap_m - b.gap_m).abs() < 1e-12, "{} vs {}", a.gap_m, b.gap_m);
                prop_assert!((mirror(a.closest_m) - b.closest_m).norm() < 1e-9);
                prop_assert!((a.arclength_m - b.arclength_m).abs() < 1e-9);
                prop_assert!((mirror(a.normal) - b.normal).norm() < 1e-6);
                if (a.arclength_m - 0.05).abs() > 1e-6 && (a.closest_m.x - 0.12).abs() > 1e-6 {
                    prop_assert_eq!(wall.surface_at(&a), mirrored.surface_at(&b));
                }
                let d = unit(ray_angle);
                let hit = wall.ray_hit_m(&p, &d, 1.0);
                let mirrored_hit = mirrored.ray_hit_m(&mirror(p), &mirror(d), 1.0);
                match (hit, mirrored_hit) {
                    (Some(s), Some(t)) => prop_assert!((s - t).abs() < 1e-9, "{s} vs {t}"),
                    (None, None) => {}
                    other => prop_assert!(false, "{other:?}"),
                }
            }
        }
    }
}

#[test]
fn the_first_wall_along_a_ray_is_the_nearest() {
    let near = Wall::smooth(Line::new(v(0.0, 0.1), 0.0, SolidSide::Left).unwrap());
    let far = Wall::smooth(Line::new(v(0.0, 0.3), 0.0, SolidSide::Left).unwrap());
    let up = v(0.0, 1.0);
    let walls = [far.clone(), near.clone()];
    assert_eq!(
        first_ray_hit(&walls, &v(0.0, 0.0), &up, 1.0),
        Some((1, 0.1))
    );
    assert_eq!(first_ray_hit(&walls, &v(0.0, 0.0), &up, 0.05), None);
    assert_eq!(
        first_ray_hit(&walls, &v(0.0, 0.2), &up, 1.0).map(|h| h.0),
        Some(0)
    );
    assert_eq!(first_ray_hit(&walls, &v(0.0, 0.0), &(-up), 1.0), None);
    assert_eq!(first_ray_hit(&[], &v(0.0, 0.0), &up, 1.0), None);
    // A tie goes to the lower index.
    let twins = [near.clone(), near];
    assert_eq!(
        first_ray_hit(&twins, &v(0.0, 0.0), &up, 1.0),
        Some((0, 0.1))
    );
    assert_eq!(first_ray_hit(&twins, &v(0.0, 0.0), &v(0.0, 3.0), 1.0), None);
}
