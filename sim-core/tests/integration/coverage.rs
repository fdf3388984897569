//! The wall coverage (`sim_core::wall_coverage`) against analytic results, a brute-force
//! nearest point, and the walls' own arclengths.

use nalgebra::Vector2;
use proptest::prelude::*;
use sim_core::{
    CoverageError, CoverageSettings, Line, Polyline, Section, Sinusoid, SolidSide, Wall,
    wall_coverage,
};

fn line_y(y_m: f64) -> Wall {
    Wall::smooth(Line::new(Vector2::new(0.0, y_m), 0.0, SolidSide::Left).expect("line"))
}

fn settings(spacing_m: f64, within_m: f64) -> CoverageSettings {
    CoverageSettings {
        spacing_m,
        complete_within_m: within_m,
    }
}

#[test]
fn points_every_two_centimetres_leave_a_triangle_of_errors() {
    // Wall samples every 0.1 mm over [0, 0.1] m; points every 20 mm on the wall: a sample's
    // error is its distance to the nearest multiple of 20 mm, uniform on [0, 10] mm.
    let points: Vec<_> = (0..=5)
        .map(|i| Vector2::new(0.02 * i as f64, 0.1))
        .collect();
    let section = Section {
        wall: 0,
        from_m: 0.0,
        to_m: 0.1,
    };
    let c = wall_coverage(
        &[line_y(0.1)],
        &Vector2::x(),
        &[section],
        &points,
        &settings(1e-4, 5e-3),
    )
    .expect("coverage");
    assert_eq!(c.samples.len(), 1001);
    assert!((c.mean_error_mm.expect("mean") - 5.0).abs() < 0.01);
    assert!((c.p90_error_mm.expect("p90") - 9.0).abs() < 0.11);
    assert!((c.completeness.expect("completeness") - 0.5).abs() < 0.002);
    // Everything within 10 mm.
    let all = wall_coverage(
        &[line_y(0.1)],
        &Vector2::x(),
        &[section],
        &points,
        &settings(1e-4, 10e-3),
    )
    .expect("coverage");
    assert_eq!(all.completeness, Some(1.0));
}

#[test]
fn points_off_the_wall_add_their_offset() {
    // One point 3 mm off the wall, over a 0-width band around it: the error is 3 mm.
    let c = wall_coverage(
        &[line_y(0.0)],
        &Vector2::x(),
        &[Section {
            wall: 0,
            from_m: 0.05,
            to_m: 0.05,
        }],
        &[Vector2::new(0.05, 0.003)],
        &CoverageSettings::default(),
    )
    .expect("coverage");
    assert!(!c.samples.is_empty());
    for s in &c.samples {
        assert!((s.error_mm.expect("error") - 3.0).abs() < 1e-9);
    }
}

#[test]
fn no_points_no_errors_and_nothing_complete() {
    let c = wall_coverage(
        &[line_y(0.0)],
        &Vector2::x(),
        &[Section {
            wall: 0,
            from_m: 0.0,
            to_m: 0.01,
        }],
        &[],
        &CoverageSettings::default(),
    )
    .expect("coverage");
    assert_eq!(c.samples.len(), 21);
    assert_eq!(c.mean_error_mm, None);
    assert_eq!(c.p90_error_mm, None);
    assert_eq!(c.completeness, Some(0.0));
    let none = wall_coverage(
        &[line_y(0.0)],
        &Vector2::x(),
        &[],
        &[Vector2::zeros()],
        &CoverageSettings::default(),
    )
    .expect("coverage");
    assert!(none.samples.is_empty());
    assert_eq!(none.completeness, None);
}

#[test]
fn sinusoid_samples_are_even_in_arclength() {
    // 1 cm amplitude, 14.2 1/m (the thesis's finest wall): its arclength per metre of baseline
    // is well above 1; the samples must follow the curve, not the baseline.
    let wave = Sinusoid::new(
        Vector2::new(0.0, 0.1),
        0.0,
        0.01,
        14.2,
        0.0,
        SolidSide::Left,
    )
    .expect("wave");
    let (t0, t1) = (0.0, 0.3);
    let arclength_m = wave.arclength_at_m(t1) - wave.arclength_at_m(t0);
    let spacing_m = 5e-4;
    let c = wall_coverage(
        &[Wall::smooth(wave.clone())],
        &Vector2::x(),
        &[Section {
            wall: 0,
            from_m: t0,
            to_m: t1,
        }],
        &[],
        &settings(spacing_m, 5e-3),
    )
    .expect("coverage");
    let expected = arclength_m / spacing_m;
    let got = c.samples.len() as f64;
    assert!(
        (got - expected).abs() <= 0.01 * expected + 2.0,
        "{got} samples for an arclength of {arclength_m} m"
    );
    for pair in c.samples.windows(2) {
        let gap = (pair[1].point_m - pair[0].point_m).norm();
        assert!(
            gap <= spacing_m * (1.0 + 1e-9) && gap > 0.9 * spacing_m,
            "gap {gap}"
        );
    }
    // Every sample lies on the wall.
    let wall = Wall::smooth(wave);
    for s in &c.samples {
        assert!(wall.signed_distance(&s.point_m).gap_m.abs() < 1e-7);
    }
}

#[test]
fn trapezoid_samples_cover_its_edges() {
    // The thesis's trapezoid shape: up, across, down; the section spans all of it.
    let vertices = vec![
        Vector2::new(0.0, 0.0),
        Vector2::new(0.1, 0.0),
        Vector2::new(0.13, 0.03),
        Vector2::new(0.23, 0.03),
        Vector2::new(0.26, 0.0),
        Vector2::new(0.4, 0.0),
    ];
    let wall = Wall::smooth(Polyline::new(vertices, SolidSide::Left).expect("polyline"));
    let spacing_m = 1e-3;
    let c = wall_coverage(
        std::slice::from_ref(&wall),
        &Vector2::x(),
        &[Section {
            wall: 0,
            from_m: 0.0,
            to_m: 0.4,
        }],
        &[],
        &settings(spacing_m, 5e-3),
    )
    .expect("coverage");
    let length_m = 0.1 + 2.0 * 0.03 * 2f64.sqrt() + 0.1 + 0.14;
    let got = c.samples.len() as f64;
    assert!((got - length_m / spacing_m).abs() <= 3.0, "{got} samples");
    for s in &c.samples {
        assert!(wall.signed_distance(&s.point_m).gap_m.abs() < 1e-9);
        assert!((-1e-12..=0.4 + 1e-12).contains(&s.point_m.x));
    }
}

#[test]
fn bad_arguments_are_errors() {
    let walls = [line_y(0.0)];
    let section = Section {
        wall: 0,
        from_m: 0.0,
        to_m: 0.1,
    };
    let ok = CoverageSettings::default();
    let run = |d: Vector2<f64>, sections: &[Section], points: &[Vector2<f64>], s| {
        wall_coverage(&walls, &d, sections, points, &s)
    };
    assert!(matches!(
        run(Vector2::x(), &[Section { wall: 1, ..section }], &[], ok),
        Err(CoverageError::NoSuchWall { wall: 1, walls: 1 })
    ));
    assert!(run(Vector2::new(2.0, 0.0), &[section], &[], ok).is_err());
    assert!(run(Vector2::new(f64::NAN, 0.0), &[section], &[], ok).is_err());
    assert!(run(Vector2::x(), &[section], &[Vector2::new(f64::NAN, 0.0)], ok).is_err());
    assert!(run(Vector2::x(), &[section], &[], settings(0.0, 1e-3)).is_err());
    assert!(run(Vector2::x(), &[section], &[], settings(1e-3, -1e-3)).is_err());
    assert!(
        run(
            Vector2::x(),
            &[Section {
                to_m: f64::INFINITY,
                ..section
            }],
            &[],
            ok
        )
        .is_err()
    );
    assert!(matches!(
        run(
            Vector2::x(),
            &[Section {
                to_m: 1e6,
                ..section
            }],
            &[],
            ok
        ),
        Err(CoverageError::TooManySamples { .. })
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Each sample's error is the brute-force nearest distance; the summary follows.
    #[test]
    fn nearest_points_match_brute_force(
        raw in prop::collection::vec((0.0..0.3f64, -0.05..0.15f64), 0..60),
        angle in -1.2..1.2f64,
        within_mm in 0.0..20.0f64,
    ) {
        let wave = Sinusoid::new(Vector2::new(0.0, 0.1), 0.0, 0.01, 6.3, 0.3, SolidSide::Left)
            .expect("wave");
        let walls = [Wall::smooth(wave)];
        let d = Vector2::new(angle.cos(), angle.sin());
        let points: Vec<_> = raw.iter().map(|&(x, y)| Vector2::new(x, y)).collect();
        let c = wall_coverage(
            &walls,
            &d,
            &[Section { wall: 0, from_m: 0.02, to_m: 0.2 }],
            &points,
            &settings(2e-3, within_mm * 1e-3),
        ).expect("coverage");
        let mut captured = 0;
        for s in &c.samples {
            let s_m = s.point_m.dot(&d);
            prop_assert!((0.02 - 1e-9..=0.2 + 1e-9).contains(&s_m));
            let brute = points.iter().map(|p| (p - s.point_m).norm() * 1e3).fold(f64::INFINITY, f64::min);
            match s.error_mm {
                Some(e) => prop_assert!((e - brute).abs() < 1e-9, "{e} vs {brute}"),
                None => prop_assert!(points.is_empty()),
            }
            if brute <= within_mm {
                captured += 1;
            }
        }
        if !c.samples.is_empty() {
            let fraction = captured as f64 / c.samples.len() as f64;
            prop_assert!((c.completeness.expect("completeness") - fraction).abs() < 1e-12);
            if let Some(mean) = c.mean_error_mm {
                let errors: Vec<f64> = c.samples.iter().filter_map(|s| s.error_mm).collect();
                let p90 = c.p90_error_mm.expect("p90");
                let mean_brute = errors.iter().sum::<f64>() / errors.len() as f64;
                prop_assert!((mean - mean_brute).abs() < 1e-9);
                // Nearest rank: at least 90 % at or below it, fewer than 90 % below it.
                let at_or_below = errors.iter().filter(|&&e| e <= p90).count();
                let below = errors.iter().filter(|&&e| e < p90).count();
                prop_assert!(at_or_below as f64 >= 0.9 * errors.len() as f64);
                prop_assert!((below as f64) < 0.9 * errors.len() as f64);
            }
        }
    }
}
