//! Potential energy (thesis 2.2.4.7-8, docs/model.md 4): the joint springs
//! `U(theta) = 1/2 sum_{j>=1} k_j (theta_j - rest_j)^2` plus an optional dead load `F` at the
//! tip, `-F . p_Gn(theta)`; with gradient and Hessian in `theta` and in the limit coordinates
//! `q` (`theta = g(q)`, [`crate::kinematics::joint_limits`]).
//!
//! The load term has gradient `-J_Gn^T F`, column `j` being `-F . R90 (p_n - p_(j-1))`, and
//! Hessian `d2/dtheta_i dtheta_j = F . (p_n - p_(m-1))` with `m = max(i, j)`. In `q`, by the
//! chain rule with the diagonal `g`: `grad_q = g' o grad_theta`,
//! `H_q = diag(g') H_theta diag(g') + diag(grad_theta o g'')`.

use nalgebra::{DMatrix, DVector, Vector2};

use crate::kinematics::joint_limits::theta_from_q;
use crate::kinematics::positions::tip_pose;
use crate::{Chain, KinematicsError};

/// Joint torques from the springs, `tau_j = -k_j (theta_j - rest_j)` (thesis 3.2.2.1), N m.
///
/// # Errors
/// [`KinematicsError::WrongLength`] if `theta` does not have `n + 1` entries.
pub fn joint_torques_nm(chain: &Chain, theta: &[f64]) -> Result<DVector<f64>, KinematicsError> {
    chain.check_len("theta", theta.len())?;
    Ok(DVector::from_fn(theta.len(), |j, _| {
        -chain.stiffness_nm_per_rad()[j] * (theta[j] - chain.rest_angles_rad()[j])
    }))
}

/// The strain energy of the joint springs in joules, `1/2 sum k_j (theta_j - rest_j)^2`.
///
/// # Errors
/// [`KinematicsError::WrongLength`] if `theta` does not have `n + 1` entries.
pub fn strain_energy_j(chain: &Chain, theta: &[f64]) -> Result<f64, KinematicsError> {
    chain.check_len("theta", theta.len())?;
    Ok(strain(chain, theta))
}

fn strain(chain: &Chain, theta: &[f64]) -> f64 {
    let k = chain.stiffness_nm_per_rad();
    let r = chain.rest_angles_rad();
    0.5 * theta
        .iter()
        .zip(k)
        .zip(r)
        .map(|((&t, &k), &r)| k * (t - r) * (t - r))
        .sum::<f64>()
}

/// The total potential of a chain with a dead load at the tip: springs plus `-F . p_Gn`.
/// The cost of an equilibrium problem; gradient and Hessian in `theta` and in `q`.
#[derive(Clone, Copy, Debug)]
pub struct Potential<'c> {
    chain: &'c Chain,
    tip_force_n: Vector2<f64>,
}

impl<'c> Potential<'c> {
    /// The springs alone (no tip load).
    pub fn new(chain: &'c Chain) -> Potential<'c> {
        Potential {
            chain,
            tip_force_n: Vector2::zeros(),
        }
    }

    /// With a constant force `F` (newtons, ground frame) acting on the tip.
    pub fn with_tip_force_n(mut self, tip_force_n: Vector2<f64>) -> Potential<'c> {
        self.tip_force_n = tip_force_n;
        self
    }

    /// The chain.
    pub fn chain(&self) -> &'c Chain {
        self.chain
    }

    /// The tip force in newtons.
    pub fn tip_force_n(&self) -> Vector2<f64> {
        self.tip_force_n
    }

    /// `U(theta) - F . p_Gn(theta)` in joules. `O(n)`.
    ///
    /// # Errors
    /// [`KinematicsError::WrongLength`] if `theta` does not have `n + 1` entries.
    pub fn value_theta(&self, theta: &[f64]) -> Result<f64, KinematicsError> {
        let tip = tip_pose(self.chain, theta)?;
        Ok(strain(self.chain, theta) - self.tip_force_n.dot(&tip.position_m))
    }

    /// The gradient in `theta` (J/rad). `O(n)`.
    ///
    /// # Errors
    /// [`KinematicsError::WrongLength`] if `theta` does not have `n + 1` entries.
    pub fn gradient_theta(&self, theta: &[f64]) -> Result<DVector<f64>, KinematicsError> {
        let mut g = DVector::zeros(self.chain.dof());
        self.gradient_theta_into(theta, g.as_mut_slice())?;
        Ok(g)
    }

    /// [`Self::gradient_theta`] into a caller-supplied slice of `n + 1` entries; no allocation.
    ///
    /// # Errors
    /// [`KinematicsError::WrongLength`] if `theta` or `out` does not have `n + 1` entries.
    pub fn gradient_theta_into(
        &self,
        theta: &[f64],
        out: &mut [f64],
    ) -> Result<(), KinematicsError> {
        let chain = self.chain;
        chain.check_len("theta", theta.len())?;
        chain.check_len("gradient", out.len())?;
        // Forward: absolute angles phi_i into `out`. Backward: suffix sums p_n - p_(i-1).
        let mut phi = 0.0;
        for (o, &t) in out.iter_mut().zip(theta) {
            phi += t;
            *o = phi;
        }
        let (fx, fy) = (self.tip_force_n.x, self.tip_force_n.y);
        let (mut sx, mut sy) = (0.0_f64, 0.0_f64);
        let k = chain.stiffness_nm_per_rad();
        let r = chain.rest_angles_rad();
        for (j, o) in out.iter_mut().enumerate().rev() {
            let (sn, cs) = o.sin_cos();
            let l = chain.link_lengths_m()[j];
            sx += l * cs;
            sy += l * sn;
            // -F . R90 S, R90 S = (-sy, sx)
            *o = k[j] * (theta[j] - r[j]) - (-fx * sy + fy * sx);
        }
        Ok(())
    }

    /// The Hessian in `theta`, `(n+1) x (n+1)`: `diag(k) + [F . (p_n - p_(max(i,j)-1))]`.
    /// `O(n^2)` to fill (the load part is dense).
    ///
    /// # Errors
    /// [`KinematicsError::WrongLength`] if `theta` does not have `n + 1` entries.
    pub fn hessian_theta(&self, theta: &[f64]) -> Result<DMatrix<f64>, KinematicsError> {
        let chain = self.chain;
        chain.check_len("theta", theta.len())?;
        let m = chain.dof();
        // d_j = F . (p_n - p_(j-1)) by a suffix sum.
        let mut d = vec![0.0; m];
        let mut phi = 0.0;
        for (dj, &t) in d.iter_mut().zip(theta) {
            phi += t;
            *dj = phi;
        }
        let (mut sx, mut sy) = (0.0_f64, 0.0_f64);
        for (j, dj) in d.iter_mut().enumerate().rev() {
            let (sn, cs) = dj.sin_cos();
            let l = chain.link_lengths_m()[j];
            sx += l * cs;
            sy += l * sn;
            *dj = self.tip_force_n.x * sx + self.tip_force_n.y * sy;
        }
        let k = chain.stiffness_nm_per_rad();
        Ok(DMatrix::from_fn(m, m, |i, j| {
            d[i.max(j)] + if i == j { k[i] } else { 0.0 }
        }))
    }

    /// `U(g(q)) - F . p_Gn(g(q))`.
    ///
    /// # Errors
    /// [`KinematicsError::WrongLength`] if `q` does not have `n + 1` entries.
    pub fn value_q(&self, q: &[f64]) -> Result<f64, KinematicsError> {
        let theta = theta_from_q(self.chain, q)?;
        self.value_theta(theta.as_slice())
    }

    /// The gradient in `q`: `g'(q) o grad_theta(g(q))`.
    ///
    /// # Errors
    /// [`KinematicsError::WrongLength`] if `q` does not have `n + 1` entries.
    pub fn gradient_q(&self, q: &[f64]) -> Result<DVector<f64>, KinematicsError> {
        let theta = theta_from_q(self.chain, q)?;
        let mut g = self.gradient_theta(theta.as_slice())?;
        for ((gj, lim), &qj) in g.iter_mut().zip(self.chain.joint_limits()).zip(q) {
            *gj *= lim.dtheta_dq(qj);
        }
        Ok(g)
    }

    /// The Hessian in `q`: `diag(g') H_theta diag(g') + diag(grad_theta o g'')`.
    ///
    /// # Errors
    /// [`KinematicsError::WrongLength`] if `q` does not have `n + 1` entries.
    pub fn hessian_q(&self, q: &[f64]) -> Result<DMatrix<f64>, KinematicsError> {
        let theta = theta_from_q(self.chain, q)?;
        let grad = self.gradient_theta(theta.as_slice())?;
        let mut h = self.hessian_theta(theta.as_slice())?;
        let limits = self.chain.joint_limits();
        let d1: Vec<f64> = limits
            .iter()
            .zip(q)
            .map(|(lim, &qj)| lim.dtheta_dq(qj))
            .collect();
        for j in 0..h.ncols() {
            for i in 0..h.nrows() {
                h[(i, j)] *= d1[i] * d1[j];
            }
            h[(j, j)] += grad[j] * limits[j].d2theta_dq2(q[j]);
        }
        Ok(h)
    }
}
