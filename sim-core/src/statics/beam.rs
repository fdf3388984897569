//! Chains as beams: a chain of rigid links with joint springs that approximates a clamped
//! inextensible Euler-Bernoulli beam (docs/model.md 5), and Richardson extrapolation over the number
//! of links, which turns chain answers into beam-accurate ones fastest.
//!
//! A [`Beam`] has length `L`, bending stiffness `EI(s)` along the arc length `s` and a clamp
//! angle; its reference answer is the elastica ([`crate::statics::elastica`]). A chain with `n`
//! flexible joints stands for it in one of two layouts ([`BeamLayout`]):
//!
//! - [`BeamLayout::EqualLinks`], docs/model.md 5 read literally: `n + 1` links of `l = L / (n + 1)`,
//!   joint `j` at `x_j = j l`, `k_j = EI(x_j) / l`. Link 0 is the rigid base link clamped at the
//!   base angle, so the beam's most loaded stretch `[0, l]` cannot bend: the tip deflection is
//!   first-order accurate, relative error about `-0.6 / n` (`alpha = 10`) to `-1.4 / n`
//!   (`alpha = 0.5`) for the cantilever with a perpendicular tip load, and its error expansion
//!   has every power of `1 / n` (measured, `sim-core/tests/integration/beam_convergence.rs`).
//! - [`BeamLayout::Hencky`] (the default): the beam is cut into `n` pieces of `h = L / n` and a
//!   spring sits at the middle of each, `s_j = (j - 1/2) h`, with `k_j = EI(s_j) / h`; so the
//!   base link and the last link are `h / 2` long and the others `h`. Each spring lumps the
//!   curvature of its piece at the piece's midpoint (the midpoint rule for `theta(s)`), which
//!   makes the error an expansion in even powers of `h`: `c_2 h^2 + c_4 h^4 + ...`. Measured
//!   order 2.00 for `alpha = F L^2 / EI` in 0.5..10, relative error about `-0.25 / n^2` to
//!   `-0.5 / n^2`.
//!
//! [`richardson_tip`] solves the Hencky chain at `n_0, 2 n_0, ..., 2^m n_0` links and eliminates
//! the `h^2, h^4, ..., h^(2m)` terms (a Romberg tableau), so `m` eliminations give order
//! `2m + 2` (measured: 4, 6, 8). Each finer solve starts from the coarser answer resampled
//! onto the finer joints (curvature interpolated along the arc), which cuts its Newton
//! iterations. With `n_0 = 8` and three solves (8, 16, 32 links) the tip deflection is within
//! `1e-7` of the elastica for `alpha` up to 10 at a few times the cost of the 32-link solve.
//!
//! Each chain is solved by [`solve_equilibrium`] with the dead load at the tip and no pin.
//!
//! # Example: a beam-accurate tip from three small chains
//! ```
//! use nalgebra::Vector2;
//! use sim_core::statics::beam::{Beam, RichardsonOptions, richardson_tip};
//! use sim_core::statics::elastica::perpendicular_load_closed_form;
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! // A 0.36 m cantilever, EI = 0.02 N m^2, clamped along x, loaded across at alpha = 5.
//! let (l, ei, alpha) = (0.36, 0.02, 5.0);
//! let beam = Beam::uniform(l, ei, 0.0);
//! let force = Vector2::new(0.0, alpha * ei / (l * l));
//! // Hencky chains of 8, 16 and 32 links, extrapolated to order 6.
//! let tip = richardson_tip(&beam, force, &RichardsonOptions::default())?;
//! let exact = perpendicular_load_closed_form(alpha)?.tip_transverse_over_length * l;
//! assert_eq!(tip.order, 6);
//! assert!((tip.tip_position_m.y / exact - 1.0).abs() < 1e-7);
//! # Ok(())
//! # }
//! ```

use nalgebra::Vector2;

use crate::statics::elastica::{BendingStiffness, ElasticaError, ElasticaProblem};
use crate::statics::equilibrium::{
    EquilibriumError, EquilibriumProblem, InitialGuess, LimitSide, SolveOptions, solve_equilibrium,
};
use crate::{Chain, ChainError, JointLimit, KinematicsError, tip_pose};

/// Largest number of flexible joints a beam chain may have.
pub const MAX_BEAM_LINKS: usize = 1 << 20;

/// Errors from building or solving a beam chain.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BeamError {
    /// The beam itself is invalid (length, clamp angle, breakpoints or `EI`).
    #[error("invalid beam: {0}")]
    Beam(#[from] ElasticaError),
    /// A number of flexible joints outside `1..=MAX_BEAM_LINKS`.
    #[error("links = {links} is out of range (1..={MAX_BEAM_LINKS})")]
    InvalidLinks {
        /// The number asked for.
        links: usize,
    },
    /// An option is out of its domain.
    #[error("option {field} = {value} is out of range ({expected})")]
    InvalidOption {
        /// Option name.
        field: &'static str,
        /// The offending value.
        value: f64,
        /// The domain, in words.
        expected: &'static str,
    },
    /// Building the chain failed.
    #[error("building the chain: {0}")]
    Chain(#[from] ChainError),
    /// Evaluating the chain failed.
    #[error("chain kinematics: {0}")]
    Kinematics(#[from] KinematicsError),
    /// The equilibrium solver rejected the problem.
    #[error("equilibrium solve: {0}")]
    Equilibrium(#[from] EquilibriumError),
    /// The equilibrium solver ran out of iterations.
    #[error(
        "the {links}-link chain did not converge in {iterations} iterations (KKT residual {kkt_residual:e})"
    )]
    NotConverged {
        /// Flexible joints of the chain.
        links: usize,
        /// Iterations spent.
        iterations: usize,
        /// KKT residual reached.
        kkt_residual: f64,
    },
    /// A joint bent to its `+-pi` limit: the chain is too coarse for this load.
    #[error("joint {joint} of the {links}-link chain reached its +-pi limit: use more links")]
    JointOnLimit {
        /// Flexible joints of the chain.
        links: usize,
        /// The joint on its limit.
        joint: usize,
    },
}

/// How a chain stands for a beam; see the module docs for the orders.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BeamLayout {
    /// `n + 1` equal links, springs `EI(x_j) / l` at their joints (first order).
    EqualLinks,
    /// Springs `EI(s_j) / h` at the midpoints of `n` equal pieces, half-length end links
    /// (second order, even-power error expansion).
    #[default]
    Hencky,
}

impl BeamLayout {
    /// The exponents of the error expansion in `h = L / n`: `1, 2, 3, ...` for equal links,
    /// `2, 4, 6, ...` for Hencky (the `k`-th, from 1).
    pub fn error_exponent(self, k: usize) -> usize {
        match self {
            BeamLayout::EqualLinks => k,
            BeamLayout::Hencky => 2 * k,
        }
    }
}

/// A clamped inextensible beam: the continuous object a chain approximates.
#[derive(Debug, Clone)]
pub struct Beam {
    /// Beam length `L`, m.
    pub length_m: f64,
    /// `EI(s)`, N m^2.
    pub bending_stiffness: BendingStiffness,
    /// Clamp direction, rad from the ground x-axis (the chain's base angle `theta_0`).
    pub clamp_angle_rad: f64,
}

impl Beam {
    /// A uniform beam.
    pub fn uniform(length_m: f64, ei_n_m2: f64, clamp_angle_rad: f64) -> Beam {
        Beam {
            length_m,
            bending_stiffness: BendingStiffness::Uniform { ei_n_m2 },
            clamp_angle_rad,
        }
    }

    /// The elastica problem for this beam under a dead tip force (ground frame, N).
    pub fn elastica_problem(&self, tip_force_n: Vector2<f64>) -> ElasticaProblem {
        ElasticaProblem {
            length_m: self.length_m,
            bending_stiffness: self.bending_stiffness.clone(),
            clamp_angle_rad: self.clamp_angle_rad,
            tip_force_n: [tip_force_n.x, tip_force_n.y],
        }
    }

    /// The arc length each spring stands for: `L / (n + 1)` or `L / n`.
    fn spacing_m(&self, links: usize, layout: BeamLayout) -> f64 {
        match layout {
            BeamLayout::EqualLinks => self.length_m / (links + 1) as f64,
            BeamLayout::Hencky => self.length_m / links as f64,
        }
    }

    fn check(&self, links: usize) -> Result<(), BeamError> {
        if links == 0 || links > MAX_BEAM_LINKS {
            return Err(BeamError::InvalidLinks { links });
        }
        let l = self.length_m;
        if !(l.is_finite() && l > 0.0) {
            return Err(ElasticaError::InvalidLength { value_m: l }.into());
        }
        if !self.clamp_angle_rad.is_finite() {
            return Err(ElasticaError::InvalidClampAngle {
                value_rad: self.clamp_angle_rad,
            }
            .into());
        }
        let mut previous = 0.0;
        for (index, &value_m) in self.bending_stiffness.breakpoints_m().iter().enumerate() {
            if !(value_m.is_finite() && value_m > previous && value_m < l) {
                return Err(ElasticaError::InvalidBreakpoint { index, value_m }.into());
            }
            previous = value_m;
        }
        if let BendingStiffness::PiecewiseConstant {
            breakpoints_m,
            ei_n_m2,
        } = &self.bending_stiffness
            && ei_n_m2.len() != breakpoints_m.len() + 1
        {
            return Err(ElasticaError::SectionCountMismatch {
                breakpoints: breakpoints_m.len(),
                values: ei_n_m2.len(),
            }
            .into());
        }
        Ok(())
    }

    /// Arc lengths of the `n = links` flexible joints, m (element `j - 1` is joint `j`).
    ///
    /// # Errors
    /// [`BeamError::InvalidLinks`] or an invalid beam.
    pub fn joint_arc_lengths_m(
        &self,
        links: usize,
        layout: BeamLayout,
    ) -> Result<Vec<f64>, BeamError> {
        self.check(links)?;
        let h = self.spacing_m(links, layout);
        let offset = match layout {
            BeamLayout::EqualLinks => 1.0,
            BeamLayout::Hencky => 0.5,
        };
        Ok((0..links).map(|j| (j as f64 + offset) * h).collect())
    }

    /// Link lengths `l_0..=l_n`, m, for `n = links` flexible joints; they sum to `L`.
    ///
    /// # Errors
    /// [`BeamError::InvalidLinks`] or an invalid beam.
    pub fn link_lengths_m(&self, links: usize, layout: BeamLayout) -> Result<Vec<f64>, BeamError> {
        self.check(links)?;
        let h = self.spacing_m(links, layout);
        let mut lengths = vec![h; links + 1];
        if layout == BeamLayout::Hencky {
            lengths[0] = 0.5 * h;
            lengths[links] = 0.5 * h;
        }
        Ok(lengths)
    }

    /// Joint stiffnesses `k_1..k_n`, N m/rad: `EI(s_j)` over the spacing (docs/model.md 5).
    ///
    /// # Errors
    /// [`BeamError::InvalidLinks`] or an invalid beam (an `EI` that is not finite and positive
    /// at a joint).
    pub fn joint_stiffnesses_nm_per_rad(
        &self,
        links: usize,
        layout: BeamLayout,
    ) -> Result<Vec<f64>, BeamError> {
        let h = self.spacing_m(links, layout);
        self.joint_arc_lengths_m(links, layout)?
            .into_iter()
            .map(|s| Ok(self.bending_stiffness.at_n_m2(s)? / h))
            .collect()
    }

    /// The chain with `n = links` flexible joints that stands for this beam: base angle the
    /// clamp angle, rest angles 0, joint limits `+-pi` (a beam chain never needs them; a joint
    /// that reaches one makes [`solve_beam_chain`] fail with [`BeamError::JointOnLimit`]).
    ///
    /// # Errors
    /// [`BeamError::InvalidLinks`], an invalid beam, or a [`ChainError`].
    pub fn chain(&self, links: usize, layout: BeamLayout) -> Result<Chain, BeamError> {
        let stiffness = self.joint_stiffnesses_nm_per_rad(links, layout)?;
        Ok(Chain::builder(links)
            .link_lengths_m(self.link_lengths_m(links, layout)?)
            .base_angle_rad(self.clamp_angle_rad)
            .joint_limit(JointLimit::new(-std::f64::consts::PI, std::f64::consts::PI))
            .stiffnesses_nm_per_rad(stiffness)
            .build()?)
    }

    /// Resamples the flexible joint angles of a `coarse_links` chain onto a `fine_links` chain
    /// of the same layout: the curvature `theta_j / spacing` is interpolated linearly along the
    /// arc (held constant beyond the end joints) and multiplied by the finer spacing. A warm
    /// start for the finer solve.
    ///
    /// # Errors
    /// [`BeamError::InvalidLinks`] when `coarse_theta_rad` does not have `coarse_links`
    /// entries, or an invalid beam.
    pub fn resample_joint_angles(
        &self,
        coarse_theta_rad: &[f64],
        fine_links: usize,
        layout: BeamLayout,
    ) -> Result<Vec<f64>, BeamError> {
        let coarse_links = coarse_theta_rad.len();
        let s_coarse = self.joint_arc_lengths_m(coarse_links, layout)?;
        let s_fine = self.joint_arc_lengths_m(fine_links, layout)?;
        let h_coarse = self.spacing_m(coarse_links, layout);
        let h_fine = self.spacing_m(fine_links, layout);
        let kappa = |j: usize| coarse_theta_rad[j] / h_coarse;
        let limit = std::f64::consts::PI * (1.0 - 1e-9);
        Ok(s_fine
            .iter()
            .map(|&s| {
                let upper = s_coarse.partition_point(|&c| c <= s);
                let k = if upper == 0 {
                    kappa(0)
                } else if upper == coarse_links {
                    kappa(coarse_links - 1)
                } else {
                    let (a, b) = (s_coarse[upper - 1], s_coarse[upper]);
                    let t = (s - a) / (b - a);
                    (1.0 - t) * kappa(upper - 1) + t * kappa(upper)
                };
                (k * h_fine).clamp(-limit, limit)
            })
            .collect())
    }
}

/// The tip of one solved beam chain.
#[derive(Debug, Clone, PartialEq)]
pub struct BeamTip {
    /// Flexible joints of the chain.
    pub links: usize,
    /// Tip position, ground frame, m.
    pub tip_position_m: Vector2<f64>,
    /// Tip angle (of the last link), rad from the ground x-axis.
    pub tip_angle_rad: f64,
    /// Flexible joint angles `theta_1..theta_n`, rad.
    pub joint_angles_rad: Vec<f64>,
    /// Newton iterations the solver spent.
    pub iterations: usize,
    /// KKT residual of the answer.
    pub kkt_residual: f64,
}

/// Builds the `links`-joint chain for `beam` and solves it under the dead tip load
/// `tip_force_n` (ground frame, N), no pin.
///
/// # Errors
/// [`BeamError`] for an invalid beam or link count, a solver error, a solve that did not
/// converge, or a joint on its `+-pi` limit.
pub fn solve_beam_chain(
    beam: &Beam,
    links: usize,
    layout: BeamLayout,
    tip_force_n: Vector2<f64>,
    initial: &InitialGuess,
    options: &SolveOptions,
) -> Result<BeamTip, BeamError> {
    let chain = beam.chain(links, layout)?;
    solve_chain(&chain, tip_force_n, initial, options)
}

fn solve_chain(
    chain: &Chain,
    tip_force_n: Vector2<f64>,
    initial: &InitialGuess,
    options: &SolveOptions,
) -> Result<BeamTip, BeamError> {
    let links = chain.n();
    let problem = EquilibriumProblem {
        chain,
        tip_force_n,
        tip_pin_m: None,
    };
    let eq = solve_equilibrium(&problem, initial, options)?;
    if !eq.converged {
        return Err(BeamError::NotConverged {
            links,
            iterations: eq.iterations,
            kkt_residual: eq.kkt_residual,
        });
    }
    if let Some(joint) = eq
        .limit_sides
        .iter()
        .skip(1)
        .position(|side| *side != LimitSide::Free)
    {
        return Err(BeamError::JointOnLimit {
            links,
            joint: joint + 1,
        });
    }
    let tip = tip_pose(chain, &eq.theta_rad)?;
    Ok(BeamTip {
        links,
        tip_position_m: tip.position_m,
        tip_angle_rad: tip.angle_rad,
        joint_angles_rad: eq.theta_rad[1..].to_vec(),
        iterations: eq.iterations,
        kkt_residual: eq.kkt_residual,
    })
}

/// Options for [`richardson_tip`].
#[derive(Debug, Clone, PartialEq)]
pub struct RichardsonOptions {
    /// Flexible joints of the coarsest chain, `n_0` (default 8).
    pub coarsest_links: usize,
    /// Chains solved: `n_0, 2 n_0, ..., 2^(solves - 1) n_0` (default 3; `solves - 1`
    /// eliminations).
    pub solves: usize,
    /// Layout of every chain (default [`BeamLayout::Hencky`]).
    pub layout: BeamLayout,
    /// Start each finer solve from the coarser answer resampled (default `true`); otherwise
    /// from straight.
    pub warm_start: bool,
    /// `n` times the KKT tolerance each `n`-link chain is solved to (default `1e-13`). The
    /// KKT residual bounds each joint's angle error, and the tip adds up `n` of them, so a
    /// fixed tolerance would let the tip error grow with `n`; at the solver's own default
    /// (`1e-10`) a warm-started 64-link solve may stop `1e-9` (relative) away from the chain's
    /// equilibrium, above the extrapolated error. The tolerance used is the smaller of this
    /// over `n` and `solve_options.tolerance`.
    pub tolerance_times_links: f64,
    /// Options of every chain solve (iteration budget, and an upper bound on the tolerance).
    pub solve_options: SolveOptions,
}

impl Default for RichardsonOptions {
    fn default() -> Self {
        RichardsonOptions {
            coarsest_links: 8,
            solves: 3,
            layout: BeamLayout::Hencky,
            warm_start: true,
            tolerance_times_links: 1e-13,
            solve_options: SolveOptions::default(),
        }
    }
}

impl RichardsonOptions {
    /// The order of the extrapolated answer: the first exponent of the error expansion not
    /// eliminated (`2 * solves` for Hencky, `solves` for equal links).
    pub fn order(&self) -> usize {
        self.layout.error_exponent(self.solves)
    }
}

/// The extrapolated tip, with the chain solves it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct RichardsonTip {
    /// Extrapolated tip position, ground frame, m.
    pub tip_position_m: Vector2<f64>,
    /// Extrapolated tip angle, rad.
    pub tip_angle_rad: f64,
    /// Expected order of the answer in `h = L / n_finest` ([`RichardsonOptions::order`]).
    pub order: usize,
    /// `|T_(m,m) - T_(m,m-1)|` on the tip position, m: the last correction, an estimate of
    /// the error of the one-lower-order answer (and a pessimistic bound on this one's). Zero
    /// with a single solve.
    pub error_estimate_m: f64,
    /// The chain solves, coarsest first.
    pub solves: Vec<BeamTip>,
}

/// Richardson extrapolation over the number of links of the chain tip under a dead tip load:
/// see the module docs.
///
/// # Errors
/// [`BeamError::InvalidOption`] for `solves` = 0 or a finest chain above
/// [`MAX_BEAM_LINKS`]; otherwise as [`solve_beam_chain`].
pub fn richardson_tip(
    beam: &Beam,
    tip_force_n: Vector2<f64>,
    options: &RichardsonOptions,
) -> Result<RichardsonTip, BeamError> {
    let t = options.tolerance_times_links;
    if !(t.is_finite() && t > 0.0) {
        return Err(BeamError::InvalidOption {
            field: "tolerance_times_links",
            value: t,
            expected: "finite and positive",
        });
    }
    if options.solves == 0 || options.solves > 20 {
        return Err(BeamError::InvalidOption {
            field: "solves",
            value: options.solves as f64,
            expected: "in 1..=20",
        });
    }
    let finest = options
        .coarsest_links
        .checked_mul(1 << (options.solves - 1))
        .filter(|&f| f <= MAX_BEAM_LINKS && options.coarsest_links > 0);
    if finest.is_none() {
        return Err(BeamError::InvalidOption {
            field: "coarsest_links",
            value: options.coarsest_links as f64,
            expected: "coarsest_links * 2^(solves - 1) in 1..=MAX_BEAM_LINKS",
        });
    }
    let mut solves: Vec<BeamTip> = Vec::with_capacity(options.solves);
    // Romberg tableau rows of (x, y, angle): row i holds T_(i,0..=i).
    let mut tableau: Vec<Vec<[f64; 3]>> = Vec::with_capacity(options.solves);
    for i in 0..options.solves {
        let links = options.coarsest_links << i;
        let initial = match solves.last() {
            Some(previous) if options.warm_start => InitialGuess::Angles(
                beam.resample_joint_angles(&previous.joint_angles_rad, links, options.layout)?,
            ),
            _ => InitialGuess::Straight,
        };
        let solve_options = SolveOptions {
            tolerance: options
                .solve_options
                .tolerance
                .min(options.tolerance_times_links / links as f64),
            ..options.solve_options
        };
        let tip = solve_beam_chain(
            beam,
            links,
            options.layout,
            tip_force_n,
            &initial,
            &solve_options,
        )?;
        let mut row = vec![[
            tip.tip_position_m.x,
            tip.tip_position_m.y,
            tip.tip_angle_rad,
        ]];
        for k in 1..=i {
            // Eliminate the h^p term, p the k-th exponent, between T_(i,k-1) and T_(i-1,k-1).
            let p = options.layout.error_exponent(k) as i32;
            let factor = 1.0 / (2f64.powi(p) - 1.0);
            let (fine, coarse) = (row[k - 1], tableau[i - 1][k - 1]);
            row.push(std::array::from_fn(|c| {
                fine[c] + (fine[c] - coarse[c]) * factor
            }));
        }
        tableau.push(row);
        solves.push(tip);
    }
    let last = &tableau[options.solves - 1];
    let best = last[options.solves - 1];
    let error_estimate_m = if options.solves > 1 {
        let previous = last[options.solves - 2];
        (best[0] - previous[0]).hypot(best[1] - previous[1])
    } else {
        0.0
    };
    Ok(RichardsonTip {
        tip_position_m: Vector2::new(best[0], best[1]),
        tip_angle_rad: best[2],
        order: options.order(),
        error_estimate_m,
        solves,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_sum_to_the_length_and_put_joints_where_documented() {
        let beam = Beam::uniform(0.36, 0.02, 0.3);
        for layout in [BeamLayout::EqualLinks, BeamLayout::Hencky] {
            for n in [1, 2, 7, 64] {
                let lengths = beam.link_lengths_m(n, layout).unwrap();
                assert_eq!(lengths.len(), n + 1);
                let total: f64 = lengths.iter().sum();
                assert!((total - 0.36).abs() < 1e-15);
                // Joint j sits at the distal end of link j - 1.
                let s = beam.joint_arc_lengths_m(n, layout).unwrap();
                let mut prefix = 0.0;
                for (j, s_j) in s.iter().enumerate() {
                    prefix += lengths[j];
                    assert!((prefix - s_j).abs() < 1e-15);
                }
            }
        }
        let s = beam.joint_arc_lengths_m(4, BeamLayout::Hencky).unwrap();
        for (got, want) in s.iter().zip([0.045, 0.135, 0.225, 0.315]) {
            assert!((got - want).abs() < 1e-15);
        }
        let k = beam
            .joint_stiffnesses_nm_per_rad(4, BeamLayout::Hencky)
            .unwrap();
        assert!(k.iter().all(|&k| (k - 0.02 / 0.09).abs() < 1e-12));
        let k = beam
            .joint_stiffnesses_nm_per_rad(3, BeamLayout::EqualLinks)
            .unwrap();
        assert!(k.iter().all(|&k| (k - 0.02 / 0.09).abs() < 1e-12));
    }

    #[test]
    fn stiffness_is_sampled_at_the_joints() {
        let beam = Beam {
            length_m: 1.0,
            bending_stiffness: BendingStiffness::PiecewiseConstant {
                breakpoints_m: vec![0.5],
                ei_n_m2: vec![2.0, 1.0],
            },
            clamp_angle_rad: 0.0,
        };
        let k = beam
            .joint_stiffnesses_nm_per_rad(4, BeamLayout::Hencky)
            .unwrap();
        assert_eq!(k, vec![8.0, 8.0, 4.0, 4.0]);
        let f = Beam {
            bending_stiffness: BendingStiffness::function(|s| 1.0 + s),
            ..beam.clone()
        };
        let k = f
            .joint_stiffnesses_nm_per_rad(2, BeamLayout::Hencky)
            .unwrap();
        assert!((k[0] - 1.25 / 0.5).abs() < 1e-15 && (k[1] - 1.75 / 0.5).abs() < 1e-15);
    }

    #[test]
    fn resampling_a_uniform_curvature_keeps_it() {
        let beam = Beam::uniform(2.0, 1.0, 0.0);
        for layout in [BeamLayout::EqualLinks, BeamLayout::Hencky] {
            let h = |n: usize| match layout {
                BeamLayout::EqualLinks => 2.0 / (n + 1) as f64,
                BeamLayout::Hencky => 2.0 / n as f64,
            };
            let coarse = vec![0.3 * h(5); 5];
            let fine = beam.resample_joint_angles(&coarse, 10, layout).unwrap();
            assert_eq!(fine.len(), 10);
            for t in fine {
                assert!((t - 0.3 * h(10)).abs() < 1e-15);
            }
        }
        // A linear curvature is reproduced between the end joints.
        let coarse: Vec<f64> = beam
            .joint_arc_lengths_m(4, BeamLayout::Hencky)
            .unwrap()
            .iter()
            .map(|s| (1.0 - 0.4 * s) * 0.5)
            .collect();
        let fine = beam
            .resample_joint_angles(&coarse, 8, BeamLayout::Hencky)
            .unwrap();
        let s_fine = beam.joint_arc_lengths_m(8, BeamLayout::Hencky).unwrap();
        for (t, s) in fine.iter().zip(&s_fine).skip(1).take(6) {
            assert!((t - (1.0 - 0.4 * s) * 0.25).abs() < 1e-15);
        }
    }

    #[test]
    fn bad_input_gives_typed_errors() {
        let beam = Beam::uniform(0.36, 0.02, 0.0);
        assert_eq!(
            beam.chain(0, BeamLayout::Hencky).unwrap_err(),
            BeamError::InvalidLinks { links: 0 }
        );
        assert!(matches!(
            Beam::uniform(-1.0, 0.02, 0.0).chain(4, BeamLayout::Hencky),
            Err(BeamError::Beam(ElasticaError::InvalidLength { .. }))
        ));
        assert!(matches!(
            Beam::uniform(1.0, 0.0, 0.0).chain(4, BeamLayout::Hencky),
            Err(BeamError::Beam(ElasticaError::InvalidStiffness { .. }))
        ));
        let options = RichardsonOptions {
            solves: 0,
            ..RichardsonOptions::default()
        };
        assert!(matches!(
            richardson_tip(&beam, Vector2::new(0.0, 0.1), &options),
            Err(BeamError::InvalidOption {
                field: "solves",
                ..
            })
        ));
        let options = RichardsonOptions {
            coarsest_links: MAX_BEAM_LINKS,
            solves: 2,
            ..RichardsonOptions::default()
        };
        assert!(matches!(
            richardson_tip(&beam, Vector2::new(0.0, 0.1), &options),
            Err(BeamError::InvalidOption {
                field: "coarsest_links",
                ..
            })
        ));
    }

    #[test]
    fn richardson_orders_are_the_uneliminated_exponents() {
        let o = RichardsonOptions::default();
        assert_eq!(o.order(), 6);
        let o = RichardsonOptions {
            layout: BeamLayout::EqualLinks,
            solves: 2,
            ..o
        };
        assert_eq!(o.order(), 2);
    }
}
