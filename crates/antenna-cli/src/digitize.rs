//! Digitized walls made up: a polyline sampled at evenly spaced points along its arclength,
//! each moved off the wall by Gaussian noise along the normal of the edge it lies on, as a
//! scan of the wall would give (issue #14). The result is a `points_file` for a `[[walls]]`
//! table ([`points_csv`]; the format is in [`antenna_scene::points_file`]).
//!
//! `examples/walls/trapezoid_10k.csv` is the thesis's 4.2.2 trapezoid (the wall of
//! `examples/wall_polyline.toml`) digitized with [`TRAPEZOID_10K`]; regenerate it with
//!
//! ```sh
//! cargo run -p antenna-cli --example digitize_trapezoid
//! ```
//!
//! The draw is reproducible: the noise comes from a SplitMix64 stream of the given seed
//! (no crate whose stream could change between versions), and the points are rounded to
//! the nanometre, so the same seed writes the same bytes.
//!
//! ```
//! use antenna_cli::digitize::{Digitizing, digitize, points_csv};
//! use nalgebra::Vector2;
//! use sim_core::SolidSide;
//!
//! let wall_m = [Vector2::new(0.0, 0.2), Vector2::new(1.0, 0.2)];
//! let spec = Digitizing { points: 101, noise_m: 1e-4, seed: 7 };
//! let points_m = digitize(&wall_m, SolidSide::Left, &spec).unwrap();
//! assert_eq!(points_m.len(), 101);
//! assert!(points_m.iter().all(|p| (p.y - 0.2).abs() < 1e-3));
//! let csv = points_csv(&points_m);
//! assert!(csv.starts_with("x_m,y_m\n0.000000000,0.200000000\n"));
//! ```

use nalgebra::Vector2;
use sim_core::{Polyline, SolidSide, WallError};

/// How to digitize a wall.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Digitizing {
    /// Number of points, evenly spaced along the arclength from the first vertex to the last
    /// (both included); at least 5.
    pub points: usize,
    /// Standard deviation of the Gaussian noise along the wall's normal, metres (>= 0).
    pub noise_m: f64,
    /// Seed of the noise.
    pub seed: u64,
}

/// `examples/walls/trapezoid_10k.csv`: 10,000 points, 0.1 mm of noise, seed 4221.
pub const TRAPEZOID_10K: Digitizing = Digitizing {
    points: 10_000,
    noise_m: 1e-4,
    seed: 4221,
};

/// Draws tried before [`digitize`] gives up on finding one sim-core accepts.
pub const MAX_DRAWS: usize = 100;

/// Points are rounded to the nanometre (this many steps per metre), so that a CSV written
/// with [`points_csv`] reads back as exactly the points drawn.
pub const STEPS_PER_METRE: f64 = 1e9;

/// Why a wall could not be digitized.
#[derive(Debug, thiserror::Error)]
pub enum DigitizeError {
    /// Fewer than 5 points asked for.
    #[error("{points} points asked for; digitizing takes at least 5")]
    TooFewPoints {
        /// The number asked for.
        points: usize,
    },
    /// No points per edge asked for ([`sample_edges`]).
    #[error("0 points per edge asked for; sampling an edge takes at least 1")]
    NoPointsPerEdge,
    /// A negative or non-finite noise.
    #[error("the noise must be a finite number of metres >= 0, got {noise_m}")]
    BadNoise {
        /// The noise asked for, metres.
        noise_m: f64,
    },
    /// The wall to digitize is not a valid polyline.
    #[error("the wall to digitize is not a polyline: {0}")]
    Wall(#[from] WallError),
    /// Every draw crossed itself (or doubled back).
    #[error("no draw of {MAX_DRAWS} is a valid polyline (the noise is too large for the spacing)")]
    NoValidDraw,
}

/// The polyline through `vertices_m` (from the first vertex to the last, its end rays left
/// out) sampled at `spec.points` points evenly spaced along its arclength, each moved by
/// Gaussian noise of `spec.noise_m` along the normal of the edge it lies on, rounded to
/// the nanometre. The two points at each end are left on the wall, so that the digitized
/// wall's end edges (which run on to infinity, as any polyline's) keep the wall's end
/// directions. A draw that sim-core refuses as a polyline with `solid` (noise that makes it
/// cross itself or double back) is followed by the next draw of the same stream, up to
/// [`MAX_DRAWS`].
///
/// # Errors
/// [`DigitizeError`] for fewer than 5 points, a bad noise, an invalid wall, or no valid
/// draw.
pub fn digitize(
    vertices_m: &[Vector2<f64>],
    solid: SolidSide,
    spec: &Digitizing,
) -> Result<Vec<Vector2<f64>>, DigitizeError> {
    if spec.points < 5 {
        return Err(DigitizeError::TooFewPoints {
            points: spec.points,
        });
    }
    if !(spec.noise_m.is_finite() && spec.noise_m >= 0.0) {
        return Err(DigitizeError::BadNoise {
            noise_m: spec.noise_m,
        });
    }
    // Checks the wall itself (at least 2 finite vertices, no zero-length edge).
    Polyline::new(vertices_m.to_vec(), solid)?;
    let samples = arclength_samples(vertices_m, spec.points);
    let mut noise = Gaussian::new(spec.seed);
    let last = spec.points - 1;
    for _ in 0..MAX_DRAWS {
        let points_m: Vec<Vector2<f64>> = samples
            .iter()
            .enumerate()
            .map(|(k, (on_wall_m, normal))| {
                let exact = k < 2 || k + 2 > last;
                let offset_m = if exact {
                    0.0
                } else {
                    spec.noise_m * noise.next()
                };
                round(on_wall_m + normal * offset_m)
            })
            .collect();
        if Polyline::new(points_m.clone(), solid).is_ok() {
            return Ok(points_m);
        }
    }
    Err(DigitizeError::NoValidDraw)
}

/// The wall through `vertices_m` sampled with no noise, `per_edge` points on each edge: edge
/// `i`'s points are `v_i + (v_{i+1} - v_i) k / per_edge` for `k` in `0..per_edge`, then the
/// last vertex; `edges * per_edge + 1` points in all, rounded to the nanometre like
/// [`digitize`]'s. The vertices themselves are among the points, every other point lies on
/// an edge to within the rounding (issue #49: a finely sampled wall must sweep as its
/// vertices do).
///
/// # Errors
/// [`DigitizeError::NoPointsPerEdge`] for `per_edge` of 0, [`DigitizeError::Wall`] for an
/// invalid wall.
pub fn sample_edges(
    vertices_m: &[Vector2<f64>],
    solid: SolidSide,
    per_edge: usize,
) -> Result<Vec<Vector2<f64>>, DigitizeError> {
    if per_edge == 0 {
        return Err(DigitizeError::NoPointsPerEdge);
    }
    Polyline::new(vertices_m.to_vec(), solid)?;
    let mut points_m = Vec::with_capacity((vertices_m.len() - 1) * per_edge + 1);
    for pair in vertices_m.windows(2) {
        for k in 0..per_edge {
            points_m.push(round(
                pair[0] + (pair[1] - pair[0]) * (k as f64 / per_edge as f64),
            ));
        }
    }
    points_m.push(round(vertices_m[vertices_m.len() - 1]));
    Polyline::new(points_m.clone(), solid)?;
    Ok(points_m)
}

/// The points as a `points_file`: a header line `x_m,y_m`, then one `x,y` line per point
/// with nine decimals (nanometres), each line ending in `\n`.
pub fn points_csv(points_m: &[Vector2<f64>]) -> String {
    let mut csv = csv::Writer::from_writer(Vec::with_capacity(24 * (points_m.len() + 1)));
    // Writing to a Vec cannot fail, and the fields are ASCII.
    let _ = csv.write_record(["x_m", "y_m"]);
    for p in points_m {
        let _ = csv.write_record([format!("{:.9}", p.x), format!("{:.9}", p.y)]);
    }
    let bytes = csv.into_inner().unwrap_or_default();
    String::from_utf8(bytes).unwrap_or_default()
}

/// `count` points evenly spaced along the arclength of the edges between `vertices_m`, each
/// with the unit normal of its edge; the first and last are the end vertices.
fn arclength_samples(
    vertices_m: &[Vector2<f64>],
    count: usize,
) -> Vec<(Vector2<f64>, Vector2<f64>)> {
    let lengths_m: Vec<f64> = vertices_m
        .windows(2)
        .map(|w| (w[1] - w[0]).norm())
        .collect();
    let total_m: f64 = lengths_m.iter().sum();
    let mut samples = Vec::with_capacity(count);
    let mut edge = 0;
    let mut edge_start_m = 0.0;
    for k in 0..count {
        let s_m = total_m * k as f64 / (count - 1) as f64;
        while edge + 1 < lengths_m.len() && s_m > edge_start_m + lengths_m[edge] {
            edge_start_m += lengths_m[edge];
            edge += 1;
        }
        let tangent = (vertices_m[edge + 1] - vertices_m[edge]) / lengths_m[edge];
        let normal = Vector2::new(-tangent.y, tangent.x);
        let along_m = (s_m - edge_start_m).clamp(0.0, lengths_m[edge]);
        let point_m = if k + 1 == count {
            vertices_m[vertices_m.len() - 1]
        } else {
            vertices_m[edge] + tangent * along_m
        };
        samples.push((point_m, normal));
    }
    samples
}

/// `p_m` rounded to the nanometre: `k / 1e9` (both exact doubles, the quotient correctly
/// rounded) is the double nearest the decimal `k * 1e-9`, which is what reading its nine
/// decimals back gives.
fn round(p_m: Vector2<f64>) -> Vector2<f64> {
    p_m.map(|x| (x * STEPS_PER_METRE).round() / STEPS_PER_METRE)
}

/// Standard normal draws: SplitMix64 uniforms through Marsaglia's polar method.
struct Gaussian {
    state: u64,
    spare: Option<f64>,
}

impl Gaussian {
    fn new(seed: u64) -> Gaussian {
        Gaussian {
            state: seed,
            spare: None,
        }
    }

    /// A uniform draw in [-1, 1).
    fn uniform(&mut self) -> f64 {
        // SplitMix64 (Steele, Lea and Flood 2014).
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        // The top 53 bits, exactly representable.
        let unit = (z >> 11) as f64 / (1u64 << 53) as f64;
        2.0 * unit - 1.0
    }

    fn next(&mut self) -> f64 {
        if let Some(spare) = self.spare.take() {
            return spare;
        }
        loop {
            let (u, v) = (self.uniform(), self.uniform());
            let s = u * u + v * v;
            if s > 0.0 && s < 1.0 {
                let factor = (-2.0 * s.ln() / s).sqrt();
                self.spare = Some(v * factor);
                return u * factor;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn the_noise_is_standard_normal() {
        let mut g = Gaussian::new(1);
        let draws: Vec<f64> = (0..100_000).map(|_| g.next()).collect();
        let mean = draws.iter().sum::<f64>() / draws.len() as f64;
        let var = draws.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / draws.len() as f64;
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.02, "{var}");
    }

    #[test]
    fn samples_are_evenly_spaced_along_the_wall() {
        let wall = [
            Vector2::new(0.0, 0.0),
            Vector2::new(1.0, 0.0),
            Vector2::new(1.0, 1.0),
        ];
        let samples = arclength_samples(&wall, 9);
        let expected = [
            (0.0, 0.0),
            (0.25, 0.0),
            (0.5, 0.0),
            (0.75, 0.0),
            (1.0, 0.0),
            (1.0, 0.25),
            (1.0, 0.5),
            (1.0, 0.75),
            (1.0, 1.0),
        ];
        for ((p, _), (x, y)) in samples.iter().zip(expected) {
            assert!((p - Vector2::new(x, y)).norm() < 1e-15, "{p:?}");
        }
        assert_eq!(samples[6].1, Vector2::new(-1.0, 0.0));
    }

    #[test]
    fn the_ends_stay_on_the_wall_and_bad_requests_are_refused() {
        let wall = [Vector2::new(0.0, 0.0), Vector2::new(1.0, 0.0)];
        let spec = Digitizing {
            points: 50,
            noise_m: 1e-3,
            seed: 3,
        };
        let p = digitize(&wall, SolidSide::Left, &spec).unwrap();
        for k in [0, 1, 48, 49] {
            assert_eq!(p[k].y, 0.0, "{k}");
        }
        assert!(p[2..48].iter().any(|q| q.y != 0.0));
        // The CSV reads back as exactly these points.
        let back = antenna_scene::points_file::parse_points(&points_csv(&p)).unwrap();
        assert_eq!(back.points_m, p);
        assert!(matches!(
            digitize(&wall, SolidSide::Left, &Digitizing { points: 4, ..spec }),
            Err(DigitizeError::TooFewPoints { points: 4 })
        ));
        assert!(matches!(
            digitize(
                &wall,
                SolidSide::Left,
                &Digitizing {
                    noise_m: -1.0,
                    ..spec
                }
            ),
            Err(DigitizeError::BadNoise { .. })
        ));
        assert!(matches!(
            digitize(&wall[..1], SolidSide::Left, &spec),
            Err(DigitizeError::Wall(_))
        ));
        // A straight wall never crosses itself (its points stay in order along it); a hairpin
        // 1 cm wide under 0.1 m of noise always does.
        let hairpin = [
            Vector2::new(0.0, 0.0),
            Vector2::new(1.0, 0.0),
            Vector2::new(0.0, 0.01),
        ];
        assert!(matches!(
            digitize(
                &hairpin,
                SolidSide::Left,
                &Digitizing {
                    noise_m: 0.1,
                    ..spec
                }
            ),
            Err(DigitizeError::NoValidDraw)
        ));
    }
}
