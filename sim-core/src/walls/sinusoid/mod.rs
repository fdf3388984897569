//! A sinusoidal wall (thesis 4.2.2): `c(t) = o + t u + A sin(2 pi f t + phase) v` about a
//! straight baseline through `o` with direction `u = (cos a, sin a)`, `v = (-sin a, cos a)`.
//!
//! **Frequency unit.** `frequency_per_m` counts **cycles per metre** (wavelength `1 / f`).
//! The thesis writes only "1/m" for its walls (2.8 to 14.2 1/m); cycles per metre puts the
//! finest at a 70 mm wavelength, under two 40 mm segments, which fits its mapping errors
//! growing to 25 mm there; radians per metre would make even the finest wall 0.44 m per cycle.
//!
//!
//! One concept a file, each an `impl Sinusoid` block: this one holds the shape (its
//! construction, accessors, the curve and its arclength, mirror and translate);
//! `distance.rs` the nearest point and signed distance; `segment_contact.rs` the deepest
//! point of a segment; `features.rs` the crests that can press on a link; `bounds.rs` the
//! gap lower bounds without a nearest-point search (the broad phase); `ray.rs` the ray
//! query.

mod bounds;
mod distance;
mod features;
mod ray;
mod segment_contact;

use core::f64::consts::{PI, TAU};

use nalgebra::Vector2;

use super::SolidSide;
use super::error::{WallError, finite};

/// Sub-intervals per wavelength in the arclength table.
const ARCLENGTH_TABLE_INTERVALS: usize = 256;

/// The most samples (or candidate wavelengths) a query visits each way: 2048 wavelengths of
/// scan, reached only by points tens of kilometres from a centimetre-amplitude wall; beyond it
/// the answer is the best point visited (its distance still an upper bound).
const MAX_SCAN_STEPS: u32 = 1 << 16;

/// Three-point Gauss-Legendre nodes and weights on `[-1, 1]`.
const GAUSS_3: [(f64, f64); 3] = [
    (0.0, 0.888_888_888_888_889),
    (-0.774_596_669_241_483_4, 0.555_555_555_555_556),
    (0.774_596_669_241_483_4, 0.555_555_555_555_556),
];

/// Five-point Gauss-Legendre nodes and weights on `[-1, 1]`.
const GAUSS_5: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_888_9),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
    (0.906_179_845_938_664, 0.236_926_885_056_189_1),
];

/// A sinusoidal wall; arclength is measured along the curve from the parameter `t = 0` (the
/// baseline point), negative for `t < 0`. Tangent in the direction of increasing `t`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sinusoid {
    baseline_point_m: Vector2<f64>,
    direction_rad: f64,
    u: Vector2<f64>,
    v: Vector2<f64>,
    amplitude_m: f64,
    frequency_per_m: f64,
    phase_rad: f64,
    solid: SolidSide,
    /// `k = 2 pi f`, radians per metre.
    wavenumber_rad_per_m: f64,
    /// Arclength at `t = j / (f N)`, `j = 0..=N`.
    arclength_table_m: Vec<f64>,
}

impl Sinusoid {
    /// The sinusoid through `baseline_point_m` (at `t = 0`) along `direction_rad`, with
    /// `amplitude_m` (>= 0), `frequency_per_m` (cycles per metre, > 0) and `phase_rad`, solid
    /// on `solid`'s side of the baseline direction (`Left`: the `+v` side).
    ///
    /// # Errors
    /// [`WallError::NotFinite`], [`WallError::NegativeAmplitude`],
    /// [`WallError::NonPositiveFrequency`].
    pub fn new(
        baseline_point_m: Vector2<f64>,
        direction_rad: f64,
        amplitude_m: f64,
        frequency_per_m: f64,
        phase_rad: f64,
        solid: SolidSide,
    ) -> Result<Sinusoid, WallError> {
        finite("baseline_point_m.x", 0, baseline_point_m.x)?;
        finite("baseline_point_m.y", 0, baseline_point_m.y)?;
        finite("direction_rad", 0, direction_rad)?;
        finite("amplitude_m", 0, amplitude_m)?;
        finite("frequency_per_m", 0, frequency_per_m)?;
        finite("phase_rad", 0, phase_rad)?;
        if amplitude_m < 0.0 {
            return Err(WallError::NegativeAmplitude { amplitude_m });
        }
        if frequency_per_m <= 0.0 {
            return Err(WallError::NonPositiveFrequency { frequency_per_m });
        }
        let (sin, cos) = direction_rad.sin_cos();
        let mut wall = Sinusoid {
            baseline_point_m,
            direction_rad,
            u: Vector2::new(cos, sin),
            v: Vector2::new(-sin, cos),
            amplitude_m,
            frequency_per_m,
            phase_rad,
            solid,
            wavenumber_rad_per_m: TAU * frequency_per_m,
            arclength_table_m: Vec::with_capacity(ARCLENGTH_TABLE_INTERVALS + 1),
        };
        let step = wall.wavelength_m() / ARCLENGTH_TABLE_INTERVALS as f64;
        let mut total_m = 0.0;
        wall.arclength_table_m.push(0.0);
        for j in 0..ARCLENGTH_TABLE_INTERVALS {
            let t0 = j as f64 * step;
            total_m += wall.arclength_between(&GAUSS_5, t0, t0 + step);
            wall.arclength_table_m.push(total_m);
        }
        Ok(wall)
    }

    /// The baseline point (curve parameter `t = 0`), metres.
    pub fn baseline_point_m(&self) -> Vector2<f64> {
        self.baseline_point_m
    }

    /// The baseline direction from the ground x-axis, radians.
    pub fn direction_rad(&self) -> f64 {
        self.direction_rad
    }

    /// The amplitude, metres.
    pub fn amplitude_m(&self) -> f64 {
        self.amplitude_m
    }

    /// The spatial frequency, cycles per metre.
    pub fn frequency_per_m(&self) -> f64 {
        self.frequency_per_m
    }

    /// The wavelength `1 / f`, metres.
    pub fn wavelength_m(&self) -> f64 {
        1.0 / self.frequency_per_m
    }

    /// The phase, radians.
    pub fn phase_rad(&self) -> f64 {
        self.phase_rad
    }

    /// Which side is solid.
    pub fn solid_side(&self) -> SolidSide {
        self.solid
    }

    /// The curve point at parameter `t_m` (ground frame).
    pub fn point_at_m(&self, t_m: f64) -> Vector2<f64> {
        self.baseline_point_m + self.u * t_m + self.v * self.g(t_m)
    }

    /// The arclength from `t = 0` to `t = t_m` (negative for `t_m < 0`), metres.
    pub fn arclength_at_m(&self, t_m: f64) -> f64 {
        let wavelength_m = self.wavelength_m();
        let periods = (t_m / wavelength_m).floor();
        let rest_m = (t_m - periods * wavelength_m).clamp(0.0, wavelength_m);
        let step = wavelength_m / ARCLENGTH_TABLE_INTERVALS as f64;
        let j = ((rest_m / step) as usize).min(ARCLENGTH_TABLE_INTERVALS - 1);
        let period_m = self.arclength_table_m[ARCLENGTH_TABLE_INTERVALS];
        periods * period_m
            + self.arclength_table_m[j]
            + self.arclength_between(&GAUSS_3, j as f64 * step, rest_m)
    }

    /// `g(t) = A sin(k t + phase)`.
    fn g(&self, t: f64) -> f64 {
        self.amplitude_m * (self.wavenumber_rad_per_m * t + self.phase_rad).sin()
    }

    /// `(g, g', g'')` at `t`.
    fn g_derivatives(&self, t: f64) -> (f64, f64, f64) {
        let k = self.wavenumber_rad_per_m;
        let (sin, cos) = (k * t + self.phase_rad).sin_cos();
        let a = self.amplitude_m;
        (a * sin, a * k * cos, -a * k * k * sin)
    }

    /// `int_t0^t1 sqrt(1 + g'^2) dt` by the Gauss-Legendre rule `rule` (for short
    /// intervals: [`GAUSS_5`] for the table's, [`GAUSS_3`] within one of them, whose
    /// `1 / 256` of a period leaves it an error of order `1e-20` m).
    fn arclength_between(&self, rule: &[(f64, f64)], t0: f64, t1: f64) -> f64 {
        let (mid, half) = (0.5 * (t0 + t1), 0.5 * (t1 - t0));
        rule.iter()
            .map(|&(x, w)| {
                // g' alone: a cos, not a sin_cos.
                let k = self.wavenumber_rad_per_m;
                let slope = self.amplitude_m * k * (k * (mid + half * x) + self.phase_rad).cos();
                w * (1.0 + slope * slope).sqrt()
            })
            .sum::<f64>()
            * half
    }

    /// `+1` if free space is at larger baseline-frame `y` (above the curve), else `-1`.
    fn free_sign(&self) -> f64 {
        match self.solid {
            SolidSide::Left => -1.0,
            SolidSide::Right => 1.0,
        }
    }

    /// The query point in the baseline frame `(x, y)`.
    fn local(&self, p_m: &Vector2<f64>) -> (f64, f64) {
        let r = p_m - self.baseline_point_m;
        (self.u.dot(&r), self.v.dot(&r))
    }

    /// The curvature of the curve where `g' = slope` and `g'' = curve`, signed positive where
    /// it bulges into free space.
    fn signed_curvature(&self, slope: f64, curve: f64) -> f64 {
        -self.free_sign() * curve / (1.0 + slope * slope).powf(1.5)
    }

    /// Calls `f` with every parameter `t` in `[lo, hi]` where `k t + phase = base + 2 pi j`
    /// (at most [`MAX_SCAN_STEPS`] of them).
    fn each_phase(&self, lo: f64, hi: f64, base: f64, f: &mut dyn FnMut(f64)) {
        let (k, phase) = (self.wavenumber_rad_per_m, self.phase_rad);
        let j0 = ((k * lo + phase - base) / TAU).ceil();
        let j1 = ((k * hi + phase - base) / TAU).floor();
        let mut j = j0;
        while j <= j1 && j - j0 < f64::from(MAX_SCAN_STEPS) {
            f((base + TAU * j - phase) / k);
            j += 1.0;
        }
    }

    /// The sinusoid reflected `y -> -y` (ground frame): baseline point and direction
    /// reflected, the phase moved by half a period (the reflected `v` is minus the new
    /// baseline's), solid on the other side so that the reflected points of the solid are
    /// solid (a reflection flips the orientation); arclength is kept: a point's mirror image
    /// has its arclength (the speed `sqrt(1 + g'^2)` is unchanged by the half period).
    pub fn mirrored_about_x_axis(&self) -> Sinusoid {
        let mut mirrored = self.clone();
        mirrored.baseline_point_m = Vector2::new(self.baseline_point_m.x, -self.baseline_point_m.y);
        mirrored.direction_rad = -self.direction_rad;
        mirrored.u = Vector2::new(self.u.x, -self.u.y);
        mirrored.v = Vector2::new(-self.v.x, self.v.y);
        mirrored.phase_rad = if self.phase_rad > 0.0 {
            self.phase_rad - PI
        } else {
            self.phase_rad + PI
        };
        mirrored.solid = self.solid.swapped();
        mirrored
    }

    /// Moves the sinusoid by `offset_m` (arclength stays measured from the moved baseline
    /// point).
    pub fn translate(&mut self, offset_m: Vector2<f64>) {
        self.baseline_point_m += offset_m;
    }

    /// A copy moved by `offset_m`.
    pub fn translated(&self, offset_m: Vector2<f64>) -> Sinusoid {
        let mut moved = self.clone();
        moved.translate(offset_m);
        moved
    }
}
