//! How much of the wall a mapping run captured (thesis 4.2.2, Figure 4.16): the wall section the
//! antenna passed, sampled evenly along its arclength, each sample scored by its distance to
//! the nearest estimated contact point.
//!
//! The point error of [`crate::sensing::mapping`] asks "is each estimated point on the wall?"; a map
//! can pass it and still miss the wall's shape: troughs the antenna bridges are never
//! touched. The coverage asks the converse, "is each wall point near an estimated point?",
//! which is what the thesis's "mean spatial error from the ground truth" grows with.
//!
//! - **Section**: per wall, the part whose projection on the motion direction lies between
//!   two bounds (a sweep takes the first and last contact with that wall, [`Section`]).
//! - **Coverage error**: per sample, the distance to the nearest estimated point, millimetres;
//!   summarized by its mean and 90th percentile (nearest rank).
//! - **Completeness**: the fraction of the samples within
//!   [`CoverageSettings::complete_within_m`] of an estimated point.
//!
//! ```
//! use nalgebra::Vector2;
//! use sim_core::{CoverageSettings, Line, Section, SolidSide, Wall, wall_coverage};
//! let wall = Wall::smooth(Line::new(Vector2::new(0.0, 0.1), 0.0, SolidSide::Left)?);
//! // Points every 2 cm along the first 10 cm of the wall y = 0.1 m.
//! let points: Vec<_> = (0..=5).map(|i| Vector2::new(0.02 * i as f64, 0.1)).collect();
//! let section = Section { wall: 0, from_m: 0.0, to_m: 0.1 };
//! let c = wall_coverage(&[wall], &Vector2::x(), &[section], &points, &CoverageSettings::default())?;
//! // The farthest wall point is 1 cm from a point; on average 5 mm.
//! assert!((c.p90_error_mm.unwrap() - 9.0).abs() < 0.6);
//! assert!((c.mean_error_mm.unwrap() - 5.0).abs() < 0.1);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use nalgebra::Vector2;

use crate::contact::Contact;
use crate::walls::{Wall, WallShape};

/// How the wall is sampled and what counts as captured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoverageSettings {
    /// Arclength between wall samples, metres (`> 0`).
    pub spacing_m: f64,
    /// A wall sample this close to an estimated point counts as captured, metres (`>= 0`).
    pub complete_within_m: f64,
}

impl Default for CoverageSettings {
    /// Samples every 0.5 mm; captured within 5 mm (about a segment's width, and below the
    /// thesis's smallest mean error, 2.7 mm at 2.8 1/m, doubled).
    fn default() -> Self {
        Self {
            spacing_m: 5e-4,
            complete_within_m: 5e-3,
        }
    }
}

/// The part of one wall a run passed: the wall's points whose projection on the motion
/// direction lies in `[from_m, to_m]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Section {
    /// The wall (index into the walls given).
    pub wall: usize,
    /// The lower bound of the projection, metres.
    pub from_m: f64,
    /// The upper bound of the projection, metres.
    pub to_m: f64,
}

/// One wall sample and how well it was captured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallSample {
    /// The wall.
    pub wall: usize,
    /// The sample on the wall, ground frame, metres.
    pub point_m: Vector2<f64>,
    /// Its distance to the nearest estimated point, millimetres (`None` without points).
    pub error_mm: Option<f64>,
}

/// The coverage of a run (see the module docs).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Coverage {
    /// Every wall sample, wall by wall, in order along each wall.
    pub samples: Vec<WallSample>,
    /// The mean distance of a wall sample to the nearest estimated point, millimetres
    /// (`None` without samples or points).
    pub mean_error_mm: Option<f64>,
    /// The 90th percentile of that distance (nearest rank), millimetres.
    pub p90_error_mm: Option<f64>,
    /// The fraction of the samples captured, `0..=1` (`None` without samples; `0` without
    /// points).
    pub completeness: Option<f64>,
}

/// Arguments of [`wall_coverage`] that do not fit.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum CoverageError {
    /// A section names a wall not given.
    #[error("section of wall {wall}, but {walls} walls are given")]
    NoSuchWall {
        /// The wall named.
        wall: usize,
        /// The walls given.
        walls: usize,
    },
    /// A setting, bound, direction or point is not finite or out of its range.
    #[error("{argument} = {value} is not finite or out of range")]
    OutOfRange {
        /// Which argument.
        argument: &'static str,
        /// Its value.
        value: f64,
    },
    /// The wall would take more samples than [`MAX_SAMPLES`] at the spacing given.
    #[error("the sections take more than {MAX_SAMPLES} samples at a spacing of {spacing_m} m")]
    TooManySamples {
        /// The spacing given.
        spacing_m: f64,
    },
}

/// The most wall samples [`wall_coverage`] takes (a bound on its work and memory).
pub const MAX_SAMPLES: usize = 4_000_000;

/// Scores `points_m` (estimated contact points, ground frame) against the `sections` of
/// `walls` passed along the unit `direction` (see the module docs).
///
/// # Errors
/// [`CoverageError::NoSuchWall`]; [`CoverageError::OutOfRange`] for a spacing that is not
/// positive, a negative threshold, a direction that is not a unit vector, a non-finite bound
/// or point; [`CoverageError::TooManySamples`].
pub fn wall_coverage(
    walls: &[Wall],
    direction: &Vector2<f64>,
    sections: &[Section],
    points_m: &[Vector2<f64>],
    settings: &CoverageSettings,
) -> Result<Coverage, CoverageError> {
    let bad = |argument, value| Err(CoverageError::OutOfRange { argument, value });
    if !(settings.spacing_m.is_finite() && settings.spacing_m > 0.0) {
        return bad("spacing_m", settings.spacing_m);
    }
    if !(settings.complete_within_m.is_finite() && settings.complete_within_m >= 0.0) {
        return bad("complete_within_m", settings.complete_within_m);
    }
    let norm = direction.norm();
    if norm.is_nan() || (norm - 1.0).abs() >= 1e-9 {
        return bad("direction", norm);
    }
    for section in sections {
        if section.wall >= walls.len() {
            return Err(CoverageError::NoSuchWall {
                wall: section.wall,
                walls: walls.len(),
            });
        }
        for value in [section.from_m, section.to_m] {
            if !value.is_finite() {
                return bad("section", value);
            }
        }
    }
    if let Some(p) = points_m
        .iter()
        .find(|p| !(p.x.is_finite() && p.y.is_finite()))
    {
        return bad("points_m", if p.x.is_finite() { p.y } else { p.x });
    }

    let mut samples = Vec::new();
    for section in sections {
        let (from_m, to_m) = if section.from_m <= section.to_m {
            (section.from_m, section.to_m)
        } else {
            (section.to_m, section.from_m)
        };
        let dense = dense_curve(
            &walls[section.wall].shape,
            direction,
            from_m,
            to_m,
            settings,
        )?;
        resample(
            &dense,
            direction,
            from_m,
            to_m,
            settings.spacing_m,
            |point_m| {
                samples.push(WallSample {
                    wall: section.wall,
                    point_m,
                    error_mm: None,
                });
            },
        );
        if samples.len() > MAX_SAMPLES {
            return Err(CoverageError::TooManySamples {
                spacing_m: settings.spacing_m,
            });
        }
    }

    // Nearest estimated point by a sorted sweep along the direction: scan outwards from the
    // sample's projection until the projection gap alone exceeds the best distance.
    let mut sorted: Vec<(f64, Vector2<f64>)> =
        points_m.iter().map(|p| (p.dot(direction), *p)).collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    for sample in &mut samples {
        sample.error_mm = nearest_m(&sorted, &sample.point_m, direction).map(|d| d * 1e3);
    }

    let mut errors: Vec<f64> = samples.iter().filter_map(|s| s.error_mm).collect();
    let within_mm = settings.complete_within_m * 1e3;
    let completeness = if samples.is_empty() {
        None
    } else {
        let captured = errors.iter().filter(|&&e| e <= within_mm).count();
        Some(captured as f64 / samples.len() as f64)
    };
    let mean_error_mm = if errors.is_empty() {
        None
    } else {
        Some(errors.iter().sum::<f64>() / errors.len() as f64)
    };
    errors.sort_by(f64::total_cmp);
    let p90_error_mm = if errors.is_empty() {
        None
    } else {
        // Nearest rank: the smallest value with at least 90 % of the samples at or below it.
        let rank = ((0.9 * errors.len() as f64).ceil() as usize).clamp(1, errors.len());
        Some(errors[rank - 1])
    };
    Ok(Coverage {
        samples,
        mean_error_mm,
        p90_error_mm,
        completeness,
    })
}

/// A run's coverage, gathered step by step: the extent of the true contacts on each wall
/// along the motion direction (the [`Section`]s passed) and the estimated points.
///
/// ```
/// use nalgebra::Vector2;
/// use sim_core::{CoverageAccumulator, CoverageSettings, Line, SolidSide, Wall};
/// let wall = Wall::smooth(Line::new(Vector2::zeros(), 0.0, SolidSide::Right)?);
/// let mut run = CoverageAccumulator::new(0.0, 1);
/// run.pass_points(0, [Vector2::new(0.0, 0.0), Vector2::new(0.1, 0.0)]);
/// run.estimate([Vector2::new(0.05, 0.0)]);
/// let c = run.coverage(&[wall], &CoverageSettings::default())?;
/// assert!((c.mean_error_mm.unwrap() - 25.0).abs() < 0.2);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct CoverageAccumulator {
    direction: Vector2<f64>,
    /// Per wall: the least and greatest projection of a true contact.
    extents_m: Vec<Option<(f64, f64)>>,
    points_m: Vec<Vector2<f64>>,
}

impl CoverageAccumulator {
    /// An empty run moving along `direction_rad` (from the ground x-axis) past `walls` walls.
    pub fn new(direction_rad: f64, walls: usize) -> Self {
        let (sin, cos) = direction_rad.sin_cos();
        Self {
            direction: Vector2::new(cos, sin),
            extents_m: vec![None; walls],
            points_m: Vec::new(),
        }
    }

    /// A step's true contacts: each widens its wall's section to include it (a contact on a
    /// wall beyond those counted, or not finite, is skipped).
    pub fn pass(&mut self, contacts: &[Contact]) {
        for c in contacts {
            self.pass_points(c.wall, [c.point_m]);
        }
    }

    /// Widens wall `wall`'s section to include `points_m` (non-finite points are skipped).
    pub fn pass_points(&mut self, wall: usize, points_m: impl IntoIterator<Item = Vector2<f64>>) {
        let Some(extent) = self.extents_m.get_mut(wall) else {
            return;
        };
        for p in points_m {
            let s = p.dot(&self.direction);
            if !s.is_finite() {
                continue;
            }
            *extent = Some(match *extent {
                Some((lo, hi)) => (lo.min(s), hi.max(s)),
                None => (s, s),
            });
        }
    }

    /// Adds estimated contact points.
    pub fn estimate(&mut self, points_m: impl IntoIterator<Item = Vector2<f64>>) {
        self.points_m.extend(points_m);
    }

    /// The estimated points so far.
    pub fn points_m(&self) -> &[Vector2<f64>] {
        &self.points_m
    }

    /// The sections passed so far: one per wall touched.
    pub fn sections(&self) -> Vec<Section> {
        self.extents_m
            .iter()
            .enumerate()
            .filter_map(|(wall, e)| e.map(|(from_m, to_m)| Section { wall, from_m, to_m }))
            .collect()
    }

    /// The coverage of the run so far ([`wall_coverage`]).
    ///
    /// # Errors
    /// As [`wall_coverage`].
    pub fn coverage(
        &self,
        walls: &[Wall],
        settings: &CoverageSettings,
    ) -> Result<Coverage, CoverageError> {
        wall_coverage(
            walls,
            &self.direction,
            &self.sections(),
            &self.points_m,
            settings,
        )
    }
}

/// The distance from `p` to the nearest of `sorted` (sorted by projection on `direction`).
fn nearest_m(
    sorted: &[(f64, Vector2<f64>)],
    p: &Vector2<f64>,
    direction: &Vector2<f64>,
) -> Option<f64> {
    if sorted.is_empty() {
        return None;
    }
    let s = p.dot(direction);
    let start = sorted.partition_point(|q| q.0 < s);
    let mut best = f64::INFINITY;
    for q in sorted[start..].iter() {
        if q.0 - s > best {
            break;
        }
        best = best.min((q.1 - p).norm());
    }
    for q in sorted[..start].iter().rev() {
        if s - q.0 > best {
            break;
        }
        best = best.min((q.1 - p).norm());
    }
    Some(best)
}

/// The wall curve, densely (at most an eighth of the spacing apart), over at least the part
/// whose projection on `direction` lies in `[from_m, to_m]`; empty for a wall that runs
/// across the direction (a line or baseline within 1e-9 rad of perpendicular).
fn dense_curve(
    shape: &WallShape,
    direction: &Vector2<f64>,
    from_m: f64,
    to_m: f64,
    settings: &CoverageSettings,
) -> Result<Vec<Vector2<f64>>, CoverageError> {
    let fine_m = settings.spacing_m / 8.0;
    let too_many = || CoverageError::TooManySamples {
        spacing_m: settings.spacing_m,
    };
    // Points `a + t u` for `t` in `[t0, t1]` every `step_m` (and `t1`).
    let mut dense = Vec::new();
    let along = |dense: &mut Vec<Vector2<f64>>,
                 t0: f64,
                 t1: f64,
                 step_m: f64,
                 at: &dyn Fn(f64) -> Vector2<f64>|
     -> Result<(), CoverageError> {
        let count = ((t1 - t0) / step_m).ceil();
        if !(count.is_finite() && count <= (8 * MAX_SAMPLES) as f64) {
            return Err(too_many());
        }
        let count = count.max(1.0) as usize;
        for i in 0..=count {
            dense.push(at(t0 + (t1 - t0) * i as f64 / count as f64));
        }
        Ok(())
    };
    // The parameter range of a straight piece `a + t u` whose projection (give or take
    // `slack_m`) covers the section, or `None` if it runs across the direction.
    let range = |a: &Vector2<f64>, u: &Vector2<f64>, slack_m: f64| -> Option<(f64, f64)> {
        let ud = u.dot(direction);
        if ud.abs() < 1e-9 {
            return None;
        }
        let ta = (from_m - slack_m - a.dot(direction)) / ud;
        let tb = (to_m + slack_m - a.dot(direction)) / ud;
        Some((ta.min(tb), ta.max(tb)))
    };
    match shape {
        WallShape::Line(line) => {
            let (sin, cos) = line.angle_rad().sin_cos();
            let u = Vector2::new(cos, sin);
            let a = line.point_m();
            if let Some((t0, t1)) = range(&a, &u, 0.0) {
                along(&mut dense, t0, t1, fine_m, &|t| a + u * t)?;
            }
        }
        WallShape::Sinusoid(wave) => {
            let (sin, cos) = wave.direction_rad().sin_cos();
            let u = Vector2::new(cos, sin);
            let a = wave.baseline_point_m();
            let slope = core::f64::consts::TAU * wave.frequency_per_m() * wave.amplitude_m();
            if let Some((t0, t1)) = range(&a, &u, wave.amplitude_m()) {
                along(&mut dense, t0, t1, fine_m / (1.0 + slope), &|t| {
                    wave.point_at_m(t)
                })?;
            }
        }
        WallShape::Polyline(polyline) => {
            let v = polyline.vertices_m();
            let (Some(&first), Some(&last)) = (v.first(), v.last()) else {
                return Ok(dense);
            };
            // The end rays, long enough to leave the section.
            let reach_m = v
                .iter()
                .map(|p| {
                    (p.dot(direction) - from_m)
                        .abs()
                        .max((p.dot(direction) - to_m).abs())
                })
                .fold(0.0, f64::max)
                + (to_m - from_m)
                + 1.0;
            let ray = |from: Vector2<f64>, toward: Vector2<f64>| {
                let d = from - toward;
                from + d / d.norm() * reach_m
            };
            let mut corners = Vec::with_capacity(v.len() + 2);
            if v.len() >= 2 {
                corners.push(ray(first, v[1]));
            }
            corners.extend_from_slice(v);
            if v.len() >= 2 {
                corners.push(ray(last, v[v.len() - 2]));
            }
            for pair in corners.windows(2) {
                let (a, b) = (pair[0], pair[1]);
                let length_m = (b - a).norm();
                if length_m == 0.0 {
                    continue;
                }
                let u = (b - a) / length_m;
                // Clip the edge to the section where it crosses it.
                let (t0, t1) = match range(&a, &u, 0.0) {
                    Some((t0, t1)) => (t0.max(0.0), t1.min(length_m)),
                    None => {
                        let s = a.dot(direction);
                        if s < from_m || s > to_m {
                            continue;
                        }
                        (0.0, length_m)
                    }
                };
                if t0 <= t1 {
                    along(&mut dense, t0, t1, fine_m, &|t| a + u * t)?;
                }
            }
        }
    }
    Ok(dense)
}

/// Walks `dense` and emits a point every `spacing_m` of arclength inside the section (the
/// first at its start), restarting the count where the curve re-enters the section.
fn resample(
    dense: &[Vector2<f64>],
    direction: &Vector2<f64>,
    from_m: f64,
    to_m: f64,
    spacing_m: f64,
    mut emit: impl FnMut(Vector2<f64>),
) {
    let inside = |p: &Vector2<f64>| {
        let s = p.dot(direction);
        s >= from_m - 1e-12 && s <= to_m + 1e-12
    };
    let mut to_next_m: Option<f64> = None;
    let mut previous: Option<Vector2<f64>> = None;
    for p in dense {
        if !inside(p) {
            to_next_m = None;
            previous = None;
            continue;
        }
        match (previous, to_next_m) {
            (Some(q), Some(mut left_m)) => {
                let step_m = (p - q).norm();
                let mut walked_m = 0.0;
                while step_m - walked_m >= left_m {
                    walked_m += left_m;
                    emit(q + (p - q) * (walked_m / step_m));
                    left_m = spacing_m;
                }
                to_next_m = Some(left_m - (step_m - walked_m));
            }
            _ => {
                emit(*p);
                to_next_m = Some(spacing_m);
            }
        }
        previous = Some(*p);
    }
}
