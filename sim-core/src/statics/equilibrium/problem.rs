//! What acts on the chain ([`EquilibriumProblem`]) and where the search starts
//! ([`InitialGuess`]).

use nalgebra::Vector2;

use super::EquilibriumError;
use crate::Chain;

/// What acts on the chain: a dead load at the tip and, optionally, a pin holding the tip at a
/// point (free to rotate). The springs, rest angles and limits come from the chain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EquilibriumProblem<'c> {
    /// The chain (stiffness, rest angles, limits, base angle).
    pub chain: &'c Chain,
    /// Dead load at the tip, ground frame, newtons (zero for none).
    pub tip_force_n: Vector2<f64>,
    /// Tip pinned at this ground-frame point (free to rotate), or `None`.
    pub tip_pin_m: Option<Vector2<f64>>,
}

impl<'c> EquilibriumProblem<'c> {
    /// The chain alone: no load, no pin.
    pub fn new(chain: &'c Chain) -> EquilibriumProblem<'c> {
        EquilibriumProblem {
            chain,
            tip_force_n: Vector2::zeros(),
            tip_pin_m: None,
        }
    }

    /// With a dead load at the tip (newtons, ground frame).
    pub fn with_tip_force_n(mut self, tip_force_n: Vector2<f64>) -> Self {
        self.tip_force_n = tip_force_n;
        self
    }

    /// With the tip pinned at a ground-frame point (metres).
    pub fn with_tip_pin_m(mut self, tip_pin_m: Vector2<f64>) -> Self {
        self.tip_pin_m = Some(tip_pin_m);
        self
    }

    pub(crate) fn check(&self) -> Result<(), EquilibriumError> {
        for (index, &value) in self.tip_force_n.iter().enumerate() {
            if !value.is_finite() {
                return Err(EquilibriumError::NotFinite {
                    argument: "tip_force_n",
                    index,
                    value,
                });
            }
        }
        if let Some(pin) = self.tip_pin_m {
            for (index, &value) in pin.iter().enumerate() {
                if !value.is_finite() {
                    return Err(EquilibriumError::NotFinite {
                        argument: "tip_pin_m",
                        index,
                        value,
                    });
                }
            }
        }
        Ok(())
    }
}

/// Where the search starts. Generated postures are clamped into the joint limits; explicit
/// [`InitialGuess::Angles`] must lie inside them.
///
/// The generated bends:
/// - **Without a pin**, the C turns a total of `pi/2` evenly over the flexible joints; the S
///   turns `+pi/2` over the first half of the joints and `-pi/2` over the rest (twice the
///   per-joint angle of the C, opposite signs).
/// - **With a pin**, the C is the uniform-curvature arc whose tip lies on the target: joints
///   `2..=n` share one angle `beta` chosen (by bisection) so that the end-to-end distance of
///   the arc equals the distance from the first flexible joint to the target, and joint 1
///   aims the arc at the target. The S is built the same way from two arcs of opposite sense
///   (first half `+beta`, the rest `-beta`). Both bend counter-clockwise first.
///   [`InitialGuess::Mirror`] of a generated pinned C or S is the same construction with the
///   opposite sense of bending (still aimed at the target); without a pin, or when the
///   target lies on the base axis, that is exactly the C or S with every sign flipped.
#[derive(Clone, Debug, PartialEq)]
pub enum InitialGuess {
    /// Every flexible joint at its rest angle (clamped into the limits).
    Straight,
    /// Every flexible joint bent the same way (counter-clockwise).
    C,
    /// The first half of the joints bent one way (counter-clockwise), the rest the other.
    S,
    /// The same posture with every flexible joint's sign flipped (for a pinned C or S: the
    /// opposite sense of bending, aimed at the target).
    Mirror(Box<InitialGuess>),
    /// `n` flexible joint angles `theta_1..theta_n`, radians.
    Angles(Vec<f64>),
}

impl InitialGuess {
    /// The mirror image of this start.
    pub fn mirrored(self) -> InitialGuess {
        InitialGuess::Mirror(Box::new(self))
    }

    /// The flexible joint angles `theta_1..theta_n` this start stands for (before clamping).
    fn raw(
        &self,
        chain: &Chain,
        target: Option<Vector2<f64>>,
        sense: f64,
    ) -> Result<Vec<f64>, EquilibriumError> {
        let n = chain.n();
        Ok(match self {
            InitialGuess::Straight => chain.rest_angles_rad()[1..]
                .iter()
                .map(|r| sense * r)
                .collect(),
            InitialGuess::C | InitialGuess::S => {
                let s_shape = matches!(self, InitialGuess::S);
                match target {
                    Some(p) => aimed_arc(chain, p, s_shape, sense),
                    None => {
                        let beta = if n == 0 {
                            0.0
                        } else {
                            core::f64::consts::FRAC_PI_2 / n as f64
                        };
                        (0..n)
                            .map(|j| {
                                let b = if s_shape {
                                    2.0 * beta * half_sign(j, n)
                                } else {
                                    beta
                                };
                                sense * b
                            })
                            .collect()
                    }
                }
            }
            InitialGuess::Mirror(inner) => inner.raw(chain, target, -sense)?,
            InitialGuess::Angles(v) => {
                if v.len() != n {
                    return Err(EquilibriumError::WrongLength {
                        argument: "initial angles",
                        expected: n,
                        actual: v.len(),
                    });
                }
                v.iter().map(|t| sense * t).collect()
            }
        })
    }

    /// The start `theta_1..theta_n`, inside the limits.
    pub(crate) fn resolve(
        &self,
        chain: &Chain,
        target: Option<Vector2<f64>>,
    ) -> Result<Vec<f64>, EquilibriumError> {
        let mut v = self.raw(chain, target, 1.0)?;
        let explicit = matches!(self, InitialGuess::Angles(_));
        for (i, (t, lim)) in v.iter_mut().zip(&chain.joint_limits()[1..]).enumerate() {
            if !t.is_finite() {
                return Err(EquilibriumError::NotFinite {
                    argument: "initial angles",
                    index: i + 1,
                    value: *t,
                });
            }
            if explicit && !lim.contains(*t) {
                return Err(EquilibriumError::StartOutsideLimits {
                    index: i + 1,
                    value_rad: *t,
                    cw_rad: lim.cw_rad,
                    ccw_rad: lim.ccw_rad,
                });
            }
            *t = t.clamp(lim.cw_rad, lim.ccw_rad);
        }
        Ok(v)
    }
}

/// `+1` on the first half of `0..n`, `-1` on the rest.
fn half_sign(j: usize, n: usize) -> f64 {
    if 2 * j < n { 1.0 } else { -1.0 }
}

/// The tip of the flexible links relative to `C_0`, in the base link's frame, with joint 1 at
/// 0 and joint `j >= 2` at `pattern(j) beta`.
fn arc_tip(lengths: &[f64], beta: f64, s_shape: bool) -> Vector2<f64> {
    let n = lengths.len();
    let mut phi = 0.0;
    let mut z = Vector2::zeros();
    for (j, &l) in lengths.iter().enumerate() {
        if j > 0 {
            phi += if s_shape {
                beta * half_sign(j, n)
            } else {
                beta
            };
        }
        z += l * Vector2::new(phi.cos(), phi.sin());
    }
    z
}

/// The C or S arc whose tip lies on `target` (see [`InitialGuess`]).
fn aimed_arc(chain: &Chain, target: Vector2<f64>, s_shape: bool, sense: f64) -> Vec<f64> {
    let n = chain.n();
    if n == 0 {
        return Vec::new();
    }
    let lengths = &chain.link_lengths_m()[1..];
    let (l0, t0) = (chain.link_lengths_m()[0], chain.base_angle_rad());
    let rel = target - Vector2::new(l0 * t0.cos(), l0 * t0.sin());
    let d = rel.norm();
    // |arc_tip| falls from L at beta = 0 towards 0 as the arc closes: bisect.
    let turns = if s_shape {
        (n as f64 / 2.0).max(1.0)
    } else {
        n as f64
    };
    let (mut lo, mut hi) = (0.0_f64, 2.0 * core::f64::consts::PI / turns);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if arc_tip(lengths, mid, s_shape).norm() > d {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let beta = sense * 0.5 * (lo + hi);
    let z = arc_tip(lengths, beta, s_shape);
    // Joint 1 turns the whole arc so that its tip points at the target.
    let psi = rel.y.atan2(rel.x) - t0;
    let gamma = wrap(psi - z.y.atan2(z.x));
    (0..n)
        .map(|j| {
            if j == 0 {
                gamma
            } else if s_shape {
                beta * half_sign(j, n)
            } else {
                beta
            }
        })
        .collect()
}

/// An angle wrapped into `(-pi, pi]`.
fn wrap(a: f64) -> f64 {
    let tau = 2.0 * core::f64::consts::PI;
    let w = a.rem_euclid(tau);
    if w > core::f64::consts::PI {
        w - tau
    } else {
        w
    }
}
