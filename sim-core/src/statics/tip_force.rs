//! The force at the tip that holds a chain in static equilibrium at a given posture (thesis
//! 3.2.2, docs/model.md 4): the least-squares solution of `J_Gn^T F = -tau` (thesis 3.2.2.11), and
//! the free-body system (thesis 3.2.2.9) with an unknown stop torque at every joint resting on
//! a limit, with the base reaction and the servo torque.
//!
//! # Sign conventions
//! - `F` ([`TipForce::force_n`]) is the force the **environment exerts on the tip**, ground
//!   frame, newtons: the wall reaction, the thesis's `F_E`. The force the antenna exerts on the
//!   environment, the thesis's `F_(n,E)`, is `-F` ([`TipForce::force_on_environment_n`]).
//! - `tau_j = -k_j (theta_j - rest_j)` is the torque of spring `j` on link `j`
//!   ([`crate::statics::energy::joint_torques_nm`], thesis 3.2.2.1). A stop torque `s_j` is the torque a joint's
//!   stop exerts on link `j`: `>= 0` from a clockwise stop, `<= 0` from a counter-clockwise
//!   one, as in the equilibrium solver.
//! - Equilibrium of the links distal to joint `j` (moments about joint `j`, at `p_(j-1)`):
//!   `tau_j + s_j + (p_n - p_(j-1)) x F = 0`, that is
//!   `k_j (theta_j - rest_j) = (J_Gn^T F)_j + s_j` with `(J_Gn^T F)_j = F . R90 (p_n - p_(j-1))`,
//!   the translational rows of the hybrid tip Jacobian ([`crate::kinematics::jacobian::tip_jacobian`]). This is
//!   the stationarity of `U - F . p_n` (what the solver minimizes), and the thesis's
//!   `tau = J_Gn^T F_(n,E)` (3.2.2.10) with `F_(n,E) = -F`.
//! - The base joint (`j = 0`) is held by the servo, which is always an unknown: it never
//!   enters the fit. The base mount (servo plus base spring) exerts on link 0 the force
//!   `R = -F` and the moment `M = -(p_n - b) x F` about the base point `b`; the servo supplies
//!   `tau_servo = M + k_0 (theta_0 - rest_0)` (`k_0 = 0` for every [`Chain`], so the two are
//!   equal unless that changes). `tau_servo = dP/dtheta_0` with `P = U - F . p_n`: the
//!   virtual work of turning the whole chain about the base.
//!
//! # Which to use
//! Both fit `F` to the flexible joints' equations in least squares (a pin is free to rotate,
//! so there is no tip moment; [`tip_wrench_least_squares`] adds one, as the thesis's 3.2.2.11
//! literally does). [`tip_force_least_squares`] uses every flexible joint; it is wrong when a
//! joint rests on a limit, because the stop's torque is then read as if the tip force had
//! caused it. [`tip_force_free_body`] gives each joint on a limit its own unknown stop torque,
//! which absorbs that joint's equation exactly, so `F` is fitted to the free joints only.
//! With no joint on a limit the two are the same computation and agree exactly.
//!
//! # How the free-body system is solved
//! The thesis's system 3.2.2.9 has, per link, two force and one moment equation, and unknowns
//! the intersegmental forces, `F`, the servo torque (and here the stop torques). Nothing acts
//! between base and tip, so the force equations give every intersegmental force exactly:
//! link `i - 1` pushes link `i` with `-F`, and the ground pushes link 0 with `R = -F`. Summing
//! the moment equations of links `j..=n` (a triangular, invertible recombination) turns them
//! into the joint equations above; joint 0's equation gives the servo torque, each joint on a
//! limit's gives its stop torque, and the free joints' equations (overdetermined beyond two
//! free joints, the thesis's 3.2.2.7-8 count) give `F` in least squares. When the torques are consistent (a true
//! equilibrium) this is the exact solution of 3.2.2.9; when not, the residuals are measured as
//! moments about the joints (newton-metres) rather than mixing the thesis's force and moment
//! equations in one norm. Everything is `O(n)` (a Jacobi SVD of an `n x 2` matrix).
//!
//! A straight chain cannot tell an axial force: every joint's lever arm is parallel to it.
//! The fit then has rank 1 and returns the minimum-norm force (no axial component);
//! [`TipForce::rank`] and [`TipForce::condition_number`] say how well `F` is determined.

use nalgebra::{DMatrix, DVector, Vector2};

use crate::{Chain, KinematicsError};

/// Singular values below this fraction of the largest one count as zero in the fits.
pub const TIP_FORCE_RANK_TOLERANCE: f64 = 1e-10;

/// An argument that does not fit the chain or the computation asked for.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum TipForceError {
    /// A vector argument has the wrong length (`"theta"`, `"on_limit"`).
    #[error(transparent)]
    Kinematics(#[from] KinematicsError),
    /// An argument entry is NaN or infinite.
    #[error("{argument}[{index}] is not finite ({value})")]
    NotFinite {
        /// Which argument (`"theta"`, `"tip_force_n"`, `"tip_moment_nm"`).
        argument: &'static str,
        /// The entry's index.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// `on_limit[0]` is set: the base joint is held by the servo, whose torque is always
    /// solved for ([`FreeBodyForces::servo_torque_nm`]), never a stop torque.
    #[error("on_limit[0] is true: the base joint is held by the servo, not by a stop")]
    BaseOnLimit,
    /// A joint has zero stiffness where a deflection `tau / k` is asked for.
    #[error("stiffness_nm_per_rad[{joint}] is 0: the deflection tau / k is undefined")]
    ZeroStiffness {
        /// The joint (`1..=n`).
        joint: usize,
    },
}

/// A tip force fitted to the joint torques.
#[derive(Clone, Debug, PartialEq)]
pub struct TipForce {
    /// `F`: the force the environment exerts on the tip, ground frame, newtons.
    pub force_n: Vector2<f64>,
    /// The moment the environment exerts on the tip, N m (counter-clockwise positive). Zero
    /// except from [`tip_wrench_least_squares`]: a pin is free to rotate.
    pub moment_nm: f64,
    /// `n + 1` entries: `residual_nm[j] = k_j (theta_j - rest_j) - (J_Gn^T (F, M))_j - s_j`,
    /// the part of joint `j`'s spring torque the fitted load (and stop) does not explain.
    /// Zero for the base (entry 0, taken by the servo) and for joints on a limit (taken by
    /// their stop torque).
    pub residual_nm: Vec<f64>,
    /// The Euclidean norm of [`Self::residual_nm`], N m: zero at a true equilibrium.
    pub residual_norm_nm: f64,
    /// The numerical rank of the fit: 2 (3 with a tip moment) when the load is determined,
    /// less for a straight chain or fewer than two free joints (the minimum-norm load is
    /// returned).
    pub rank: usize,
    /// Largest over smallest singular value of the fit (with a tip moment, its column is
    /// scaled by the chain's total length first); infinite when rank-deficient.
    pub condition_number: f64,
}

impl TipForce {
    /// `-F`: the force the antenna exerts on the environment, the thesis's `F_(n,E)`.
    pub fn force_on_environment_n(&self) -> Vector2<f64> {
        -self.force_n
    }
}

/// The free-body answer (thesis 3.2.2.9 with stop torques): tip force, stop torques, base
/// reaction and servo torque.
#[derive(Clone, Debug, PartialEq)]
pub struct FreeBodyForces {
    /// The tip force fitted to the free joints (residuals at joints on a limit are zero).
    pub tip: TipForce,
    /// `n + 1` entries: the torque the stop exerts on link `j` (zero for free joints and the
    /// base): `>= 0` from a clockwise stop, `<= 0` from a counter-clockwise stop when the
    /// posture is a true equilibrium.
    pub stop_torques_nm: Vec<f64>,
    /// `n + 1` entries: the total torque joint `j` exerts on link `j`, spring plus stop,
    /// `-k_j (theta_j - rest_j) + s_j`; entry 0 is the base mount's moment
    /// ([`Self::base_reaction_moment_nm`]). At equilibrium it equals `-(J_Gn^T F)_j`, the
    /// thesis's "correct joint torques" `J_Gn^T F_(n,E)`.
    pub joint_torques_nm: Vec<f64>,
    /// The force the base mount exerts on link 0, ground frame, newtons: `-F`.
    pub base_reaction_force_n: Vector2<f64>,
    /// The moment the base mount (servo and base spring together) exerts on link 0 about the
    /// base point, N m: `-(p_n - b) x F`.
    pub base_reaction_moment_nm: f64,
    /// The torque the base servo supplies to hold `theta_0`, N m:
    /// `base_reaction_moment_nm + k_0 (theta_0 - rest_0)`, equal to `dP/dtheta_0` with
    /// `P = U - F . p_n`.
    pub servo_torque_nm: f64,
}

/// The tip force that best explains the spring torques at `theta`: least squares over the
/// flexible joints `1..=n` of `k_j (theta_j - rest_j) = (J_Gn^T F)_j` (thesis 3.2.2.11 with the
/// translational rows; the tip is a pin). `O(n)`.
///
/// Right at a true equilibrium with no joint on a limit; with joints on a limit use
/// [`tip_force_free_body`]. Signs are in the [module docs](self).
///
/// # Errors
/// [`TipForceError::Kinematics`] if `theta` does not have `n + 1` entries,
/// [`TipForceError::NotFinite`] for a NaN or infinite angle.
///
/// # Example
/// ```
/// use nalgebra::Vector2;
/// use sim_core::kinematics::jacobian::tip_jacobian;
/// use sim_core::statics::tip_force::tip_force_least_squares;
/// use sim_core::Chain;
///
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// // A posture and a wall force; rest angles chosen so that the springs balance it exactly:
/// // k (theta_j - rest_j) = (J^T F)_j.
/// let theta = [0.5, 0.3, -0.2, 0.4, 0.1];
/// let force_n = Vector2::new(-0.2, 0.5);
/// let k = 0.01;
/// let probe = Chain::builder(4).link_length_m(0.04).base_angle_rad(0.5).build()?;
/// let jt_f = tip_jacobian(&probe, &theta)?.fixed_rows::<2>(0).transpose() * force_n;
/// let rest: Vec<f64> = (1..=4).map(|j| theta[j] - jt_f[j] / k).collect();
/// let chain = Chain::builder(4)
///     .link_length_m(0.04)
///     .base_angle_rad(0.5)
///     .stiffness_nm_per_rad(k)
///     .rest_angles_rad(rest)
///     .build()?;
///
/// let fit = tip_force_least_squares(&chain, &theta)?;
/// assert!((fit.force_n - force_n).norm() < 1e-12);
/// assert!(fit.residual_norm_nm < 1e-15);
/// assert_eq!(fit.rank, 2);
/// # Ok(())
/// # }
/// ```
pub fn tip_force_least_squares(chain: &Chain, theta: &[f64]) -> Result<TipForce, TipForceError> {
    check_theta(chain, theta)?;
    let arms = lever_arms_m(chain, theta);
    let free = vec![false; chain.dof()];
    Ok(fit(chain, theta, &arms, &free, false))
}

/// [`tip_force_least_squares`] with an unknown tip moment as well: the thesis's 3.2.2.11
/// literally, `(F, M) = (J_Gn^T)^+ (K (theta - rest))` with all three rows of the hybrid
/// Jacobian. For a tip that cannot rotate freely (clamped, or gripped by the environment);
/// needs three free joints to be determined.
///
/// # Errors
/// As [`tip_force_least_squares`].
///
/// # Example
/// ```
/// use sim_core::statics::tip_force::tip_wrench_least_squares;
/// use sim_core::Chain;
///
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// // A pure moment M at the tip bends every joint by M / k.
/// let chain = Chain::builder(5).link_length_m(0.04).stiffness_nm_per_rad(0.02).build()?;
/// let mut theta = vec![0.05; 6];
/// theta[0] = 0.0;
/// let fit = tip_wrench_least_squares(&chain, &theta)?;
/// assert!((fit.moment_nm - 0.02 * 0.05).abs() < 1e-15);
/// assert!(fit.force_n.norm() < 1e-12);
/// # Ok(())
/// # }
/// ```
pub fn tip_wrench_least_squares(chain: &Chain, theta: &[f64]) -> Result<TipForce, TipForceError> {
    check_theta(chain, theta)?;
    let arms = lever_arms_m(chain, theta);
    let free = vec![false; chain.dof()];
    Ok(fit(chain, theta, &arms, &free, true))
}

/// The free-body system of thesis 3.2.2.9 with an unknown stop torque at every joint resting on
/// a limit: the tip force fitted to the free joints, the stop torques, the base reaction and
/// the servo torque. `on_limit` has `n + 1` entries (entry 0, the base, must be `false`);
/// [`joints_on_limit`] builds it from the angles, or map the solver's limit sides. With no
/// joint on a limit the tip force equals [`tip_force_least_squares`]'s exactly. `O(n)`.
///
/// Signs and the reduction of 3.2.2.9 are in the [module docs](self).
///
/// # Errors
/// [`TipForceError::Kinematics`] if `theta` or `on_limit` does not have `n + 1` entries,
/// [`TipForceError::NotFinite`] for a NaN or infinite angle, [`TipForceError::BaseOnLimit`]
/// if `on_limit[0]` is set.
///
/// # Example
/// ```
/// use nalgebra::Vector2;
/// use sim_core::kinematics::jacobian::tip_jacobian;
/// use sim_core::statics::tip_force::{tip_force_free_body, tip_force_least_squares};
/// use sim_core::{Chain, JointLimit};
///
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// // Joint 2 rests on its clockwise stop at -0.3 rad, which pushes it with 0.004 N m on top
/// // of what the wall force F explains.
/// let theta = [0.0, 0.4, -0.3, 0.5, 0.2, 0.3];
/// let force_n = Vector2::new(0.1, -0.3);
/// let (k, stop) = (0.01, 0.004);
/// let probe = Chain::builder(5).link_length_m(0.04).build()?;
/// let jt_f = tip_jacobian(&probe, &theta)?.fixed_rows::<2>(0).transpose() * force_n;
/// let rest: Vec<f64> = (1..=5)
///     .map(|j| theta[j] - (jt_f[j] + if j == 2 { stop } else { 0.0 }) / k)
///     .collect();
/// let chain = Chain::builder(5)
///     .link_length_m(0.04)
///     .joint_limit(JointLimit::new(-0.3, 1.0))
///     .stiffness_nm_per_rad(k)
///     .rest_angles_rad(rest)
///     .build()?;
///
/// let on_limit = [false, false, true, false, false, false];
/// let fb = tip_force_free_body(&chain, &theta, &on_limit)?;
/// assert!((fb.tip.force_n - force_n).norm() < 1e-12);
/// assert!((fb.stop_torques_nm[2] - stop).abs() < 1e-15);
/// assert_eq!(fb.base_reaction_force_n, -fb.tip.force_n); // what the base mount exerts
///
/// // Least squares blames the stop's torque on the tip force: wrong.
/// let ls = tip_force_least_squares(&chain, &theta)?;
/// assert!((ls.force_n - force_n).norm() > 1e-3);
/// # Ok(())
/// # }
/// ```
pub fn tip_force_free_body(
    chain: &Chain,
    theta: &[f64],
    on_limit: &[bool],
) -> Result<FreeBodyForces, TipForceError> {
    check_theta(chain, theta)?;
    chain.check_len("on_limit", on_limit.len())?;
    if on_limit[0] {
        return Err(TipForceError::BaseOnLimit);
    }
    let arms = lever_arms_m(chain, theta);
    let tip = fit(chain, theta, &arms, on_limit, false);
    let f = tip.force_n;
    let k = chain.stiffness_nm_per_rad();
    let rest = chain.rest_angles_rad();
    let mut stop_torques_nm = vec![0.0; chain.dof()];
    let mut joint_torques_nm = vec![0.0; chain.dof()];
    for j in 1..chain.dof() {
        let spring = k[j] * (theta[j] - rest[j]);
        if on_limit[j] {
            stop_torques_nm[j] = spring - cross(arms[j], f);
        }
        joint_torques_nm[j] = -spring + stop_torques_nm[j];
    }
    // Moments on the whole chain about the base point: M + (p_n - b) x F = 0.
    let base_reaction_moment_nm = -cross(arms[0], f);
    joint_torques_nm[0] = base_reaction_moment_nm;
    Ok(FreeBodyForces {
        tip,
        stop_torques_nm,
        joint_torques_nm,
        base_reaction_force_n: -f,
        base_reaction_moment_nm,
        servo_torque_nm: base_reaction_moment_nm + k[0] * (theta[0] - rest[0]),
    })
}

/// Which joints rest on a limit: `n + 1` flags, entry `j` set when `theta_j` is within
/// `tolerance_rad` of joint `j`'s clockwise or counter-clockwise limit; entry 0 (the base,
/// held by the servo) is always `false`. The input [`tip_force_free_body`] expects.
///
/// # Errors
/// [`TipForceError::Kinematics`] if `theta` does not have `n + 1` entries,
/// [`TipForceError::NotFinite`] for a NaN or infinite angle or tolerance.
pub fn joints_on_limit(
    chain: &Chain,
    theta: &[f64],
    tolerance_rad: f64,
) -> Result<Vec<bool>, TipForceError> {
    check_theta(chain, theta)?;
    if !tolerance_rad.is_finite() {
        return Err(TipForceError::NotFinite {
            argument: "tolerance_rad",
            index: 0,
            value: tolerance_rad,
        });
    }
    Ok(theta
        .iter()
        .zip(chain.joint_limits())
        .enumerate()
        .map(|(j, (&t, lim))| {
            j > 0
                && ((t - lim.cw_rad).abs() <= tolerance_rad
                    || (t - lim.ccw_rad).abs() <= tolerance_rad)
        })
        .collect())
}

/// `theta` has `n + 1` finite entries.
pub(crate) fn check_theta(chain: &Chain, theta: &[f64]) -> Result<(), TipForceError> {
    chain.check_len("theta", theta.len())?;
    check_finite("theta", theta)
}

pub(crate) fn check_finite(argument: &'static str, values: &[f64]) -> Result<(), TipForceError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(TipForceError::NotFinite {
            argument,
            index,
            value: values[index],
        }),
        None => Ok(()),
    }
}

/// `d_j = p_n - p_(j-1)` for `j = 0..=n` (`p_(-1) = 0`, the base point): the lever arm of a
/// tip force about joint `j`. Backward suffix sums, `O(n)`.
pub(crate) fn lever_arms_m(chain: &Chain, theta: &[f64]) -> Vec<Vector2<f64>> {
    let mut phi = 0.0;
    let mut arms: Vec<Vector2<f64>> = theta
        .iter()
        .map(|&t| {
            phi += t;
            Vector2::new(phi, 0.0)
        })
        .collect();
    let mut sum = Vector2::zeros();
    for (a, &l) in arms.iter_mut().zip(chain.link_lengths_m()).rev() {
        let (s, c) = a.x.sin_cos();
        sum += Vector2::new(l * c, l * s);
        *a = sum;
    }
    arms
}

/// `a x f` (the z-component); with `a = d_j`, `(J_Gn^T F)_j = F . R90 d_j = d_j x F`.
pub(crate) fn cross(a: Vector2<f64>, f: Vector2<f64>) -> f64 {
    a.x * f.y - a.y * f.x
}

/// Least squares of `k_j (theta_j - rest_j) = d_j x F (+ M)` over the flexible joints not in
/// `skip`.
fn fit(
    chain: &Chain,
    theta: &[f64],
    arms: &[Vector2<f64>],
    skip: &[bool],
    with_moment: bool,
) -> TipForce {
    let k = chain.stiffness_nm_per_rad();
    let rest = chain.rest_angles_rad();
    let rows: Vec<usize> = (1..chain.dof()).filter(|&j| !skip[j]).collect();
    let cols = if with_moment { 3 } else { 2 };
    // The moment column is scaled by the total length so that all columns are in metres.
    let length_m = chain.total_length_m();
    let mut a = DMatrix::zeros(rows.len(), cols);
    let mut b = DVector::zeros(rows.len());
    for (r, &j) in rows.iter().enumerate() {
        a[(r, 0)] = -arms[j].y;
        a[(r, 1)] = arms[j].x;
        if with_moment {
            a[(r, 2)] = length_m;
        }
        b[r] = k[j] * (theta[j] - rest[j]);
    }
    let (x, rank, condition_number) = solve_least_squares(a, b);
    let force_n = Vector2::new(x[0], x[1]);
    let moment_nm = if with_moment { x[2] * length_m } else { 0.0 };
    let mut residual_nm = vec![0.0; chain.dof()];
    for &j in &rows {
        residual_nm[j] = k[j] * (theta[j] - rest[j]) - cross(arms[j], force_n) - moment_nm;
    }
    let residual_norm_nm = residual_nm.iter().map(|r| r * r).sum::<f64>().sqrt();
    TipForce {
        force_n,
        moment_nm,
        residual_nm,
        residual_norm_nm,
        rank,
        condition_number,
    }
}

/// Minimum-norm least squares of a thin `a x = b` (`k <= 3` columns) by one-sided Jacobi
/// (Hestenes): plane rotations `V` make the columns of `W = a V` orthogonal, so
/// `a = U diag(sigma) V^T` with `sigma_i = |w_i|`, and `x = sum_i v_i (w_i . b) / sigma_i^2`
/// over the `sigma_i` above [`TIP_FORCE_RANK_TOLERANCE`] times the largest. `O(n k^2)` per
/// sweep, a few sweeps (one rotation settles two columns). Backward stable and accurate on
/// ill-conditioned postures; we do not use nalgebra's SVD here because its `svd(true, true)`
/// returns wrong singular values for some small rank-deficient matrices (nalgebra issues
/// 983 and 1172; reproduced on 0.34.2 with the `R` factor of a straight chain's fit).
/// Returns the solution, the numerical rank and the condition number.
fn solve_least_squares(mut w: DMatrix<f64>, b: DVector<f64>) -> (DVector<f64>, usize, f64) {
    const MAX_SWEEPS: usize = 60;
    let cols = w.ncols();
    let mut v = DMatrix::<f64>::identity(cols, cols);
    for _ in 0..MAX_SWEEPS {
        let mut rotated = false;
        for p in 0..cols {
            for q in p + 1..cols {
                let alpha = w.column(p).norm_squared();
                let beta = w.column(q).norm_squared();
                let gamma = w.column(p).dot(&w.column(q));
                if gamma.abs() <= f64::EPSILON * (alpha * beta).sqrt() {
                    continue;
                }
                rotated = true;
                let zeta = (beta - alpha) / (2.0 * gamma);
                let t = zeta.signum() / (zeta.abs() + zeta.hypot(1.0));
                let c = 1.0 / t.hypot(1.0);
                let s = c * t;
                rotate(&mut w, p, q, c, s);
                rotate(&mut v, p, q, c, s);
            }
        }
        if !rotated {
            break;
        }
    }
    let sigma: Vec<f64> = (0..cols).map(|i| w.column(i).norm()).collect();
    let largest = sigma.iter().copied().fold(0.0, f64::max);
    let tol = TIP_FORCE_RANK_TOLERANCE * largest;
    let mut x = DVector::zeros(cols);
    let mut rank = 0;
    for (i, &s) in sigma.iter().enumerate() {
        if s > tol && s > 0.0 {
            rank += 1;
            x += v.column(i) * (w.column(i).dot(&b) / (s * s));
        }
    }
    let condition_number = if rank == cols {
        largest / sigma.iter().copied().fold(f64::INFINITY, f64::min)
    } else {
        f64::INFINITY
    };
    (x, rank, condition_number)
}

/// Columns `p, q` of `m` to `(c m_p - s m_q, s m_p + c m_q)`.
fn rotate(m: &mut DMatrix<f64>, p: usize, q: usize, c: f64, s: f64) {
    for i in 0..m.nrows() {
        let (x, y) = (m[(i, p)], m[(i, q)]);
        m[(i, p)] = c * x - s * y;
        m[(i, q)] = s * x + c * y;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::jacobian::tip_jacobian;

    #[test]
    fn lever_arms_match_the_jacobian() {
        let chain = Chain::builder(3)
            .link_lengths_m(vec![0.01, 0.02, 0.03, 0.04])
            .build()
            .unwrap();
        let theta = [0.3, -0.4, 0.7, 0.2];
        let j = tip_jacobian(&chain, &theta).unwrap();
        let arms = lever_arms_m(&chain, &theta);
        for (c, d) in arms.iter().enumerate() {
            assert!((j[(0, c)] + d.y).abs() < 1e-15);
            assert!((j[(1, c)] - d.x).abs() < 1e-15);
        }
    }

    #[test]
    fn jacobi_least_squares_on_matrices_nalgebra_svd_gets_wrong() {
        // The R factor of a straight chain's fit (rank 1): nalgebra 0.34.2's
        // svd(true, true) recomposes it wrongly; the minimum-norm solution is r1 c1 / |r1|^2.
        let a = DMatrix::from_row_slice(
            2,
            2,
            &[
                0.111_444_426_743_707_44,
                -0.263_590_856_722_623_17,
                0.0,
                6.177e-17,
            ],
        );
        let b = DVector::from_row_slice(&[-0.085_854_528_127_525_14, 2.3e-17]);
        let (x, rank, cond) = solve_least_squares(a.clone(), b.clone());
        assert_eq!(rank, 1);
        assert!(cond.is_infinite());
        let r1 = a.row(0).transpose();
        let want = &r1 * (b[0] / r1.norm_squared());
        assert!((x - want).norm() < 1e-15);

        // A well-posed 3-column problem: the exact solution.
        let a = DMatrix::from_fn(7, 3, |r, c| {
            ((r * 3 + c) as f64 * 0.7).sin() + if r == c { 1.0 } else { 0.0 }
        });
        let want = DVector::from_row_slice(&[0.3, -1.2, 0.5]);
        let (x, rank, _) = solve_least_squares(a.clone(), &a * &want);
        assert_eq!(rank, 3);
        assert!((x - want).norm() < 1e-14);
    }

    #[test]
    fn one_horizontal_link_held_by_the_servo() {
        // n = 0: only the base link, horizontal, 0.1 m; a 2 N downward tip load needs a
        // counter-clockwise 0.2 N m from the mount.
        let chain = Chain::builder(0).link_length_m(0.1).build().unwrap();
        let fb = tip_force_free_body(&chain, &[0.0], &[false]).unwrap();
        assert_eq!(fb.tip.rank, 0);
        assert_eq!(fb.tip.force_n, Vector2::zeros());
        let f = Vector2::new(0.0, -2.0);
        let arms = lever_arms_m(&chain, &[0.0]);
        assert!((-cross(arms[0], f) - 0.2).abs() < 1e-15);
    }
}
