//! The preallocated state of one solve: the chain's data copied into flat arrays, the
//! current angles, the tip vectors `q_j = p_n - p_(j-1)`, and scratch for the Newton step.
//! Nothing inside the Newton loop allocates.

use nalgebra::Vector2;

use crate::Chain;

/// The function a Newton stage minimizes over the box of joint limits: the augmented
/// Lagrangian `U - F . p_n - mu . c + rho/2 |c|^2` with `c = p_n - P` (with no target: the
/// dead-load potential `U - F . p_n`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Merit {
    pub force: Vector2<f64>,
    pub mu: Vector2<f64>,
    pub rho: f64,
    pub target: Option<Vector2<f64>>,
}

impl Merit {
    pub fn dead_load(force: Vector2<f64>) -> Merit {
        Merit {
            force,
            mu: Vector2::zeros(),
            rho: 0.0,
            target: None,
        }
    }

    /// The pin gap `c = p_n - P` (zero without a target).
    pub fn gap(&self, tip: Vector2<f64>) -> Vector2<f64> {
        self.target.map_or_else(Vector2::zeros, |t| tip - t)
    }

    /// The force whose dead load has the same gradient: `F + mu - rho c`.
    pub fn effective_force(&self, tip: Vector2<f64>) -> Vector2<f64> {
        self.force + self.mu - self.rho * self.gap(tip)
    }
}

/// Flat copies of the chain and the scratch of a solve.
#[derive(Clone, Debug)]
pub(crate) struct Workspace {
    pub n: usize,
    /// The base angle `theta_0`.
    pub theta0: f64,
    /// `p_0`, the distal end of the base link (the first flexible joint).
    pub base_tip: Vector2<f64>,
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
    pub k: Vec<f64>,
    pub rest: Vec<f64>,
    pub len: Vec<f64>,
    pub l_flex: f64,
    pub k_max: f64,
    /// Current flexible angles `theta_1..theta_n`.
    pub x: Vec<f64>,
    /// Absolute link angles `phi_1..phi_n` at `x` (valid after [`Workspace::kinematics`]).
    pub phi: Vec<f64>,
    /// `q_j = p_n - p_(j-1)` at `x` (valid after [`Workspace::kinematics`]).
    pub qx: Vec<f64>,
    pub qy: Vec<f64>,
    /// The tip at `x` (valid after [`Workspace::kinematics`]).
    pub tip: Vector2<f64>,
    pub g: Vec<f64>,
    pub dir: Vec<f64>,
    pub trial: Vec<f64>,
    pub a: Vec<f64>,
    pub piv: Vec<f64>,
    pub cc: Vec<f64>,
    pub y1: Vec<f64>,
    pub y2: Vec<f64>,
    pub free: Vec<bool>,
    /// Scratch diagonal (shifted stiffness) for the saddle escape.
    pub dshift: Vec<f64>,
    /// The last Levenberg shift that made the Newton matrix positive definite.
    pub sigma: f64,
}

impl Workspace {
    pub fn new(chain: &Chain, x: Vec<f64>) -> Workspace {
        let n = chain.n();
        let lim = &chain.joint_limits()[1..];
        let len = chain.link_lengths_m()[1..].to_vec();
        let theta0 = chain.base_angle_rad();
        let l0 = chain.link_lengths_m()[0];
        let k = chain.stiffness_nm_per_rad()[1..].to_vec();
        Workspace {
            n,
            theta0,
            base_tip: Vector2::new(l0 * theta0.cos(), l0 * theta0.sin()),
            lo: lim.iter().map(|l| l.cw_rad).collect(),
            hi: lim.iter().map(|l| l.ccw_rad).collect(),
            k_max: k.iter().copied().fold(0.0, f64::max),
            k,
            rest: chain.rest_angles_rad()[1..].to_vec(),
            l_flex: len.iter().sum(),
            len,
            x,
            phi: vec![0.0; n],
            qx: vec![0.0; n],
            qy: vec![0.0; n],
            tip: Vector2::zeros(),
            g: vec![0.0; n],
            dir: vec![0.0; n],
            trial: vec![0.0; n],
            a: vec![0.0; n],
            piv: vec![0.0; n],
            cc: vec![0.0; n],
            y1: vec![0.0; n],
            y2: vec![0.0; n],
            free: vec![true; n],
            dshift: vec![0.0; n],
            sigma: 0.0,
        }
    }

    /// Fills `phi`, `qx`, `qy` and `tip` from `x` (suffix sums, `O(n)`).
    pub fn kinematics(&mut self) {
        let mut phi = self.theta0;
        for j in 0..self.n {
            phi += self.x[j];
            self.phi[j] = phi;
            let (s, c) = phi.sin_cos();
            self.qx[j] = self.len[j] * c;
            self.qy[j] = self.len[j] * s;
        }
        let (mut sx, mut sy) = (0.0_f64, 0.0_f64);
        for j in (0..self.n).rev() {
            sx += self.qx[j];
            sy += self.qy[j];
            self.qx[j] = sx;
            self.qy[j] = sy;
        }
        self.tip = self.base_tip + Vector2::new(sx, sy);
    }

    /// The gradient of the merit at `x` into `g`, for the force `f` of
    /// [`Merit::effective_force`]: `g_j = k_j (x_j - r_j) - f . R90 q_j`. Needs
    /// [`Workspace::kinematics`].
    pub fn gradient(&mut self, f: Vector2<f64>) {
        for j in 0..self.n {
            self.g[j] =
                self.k[j] * (self.x[j] - self.rest[j]) + f.x * self.qy[j] - f.y * self.qx[j];
        }
    }

    /// The torque scale `T = max k + |f| L` (N m/rad) of the KKT residual.
    pub fn torque_scale(&self, f: Vector2<f64>) -> f64 {
        (self.k_max + f.norm() * self.l_flex).max(f64::MIN_POSITIVE)
    }

    /// The projected-gradient residual `max_j |x_j - clamp(x_j - g_j / T)|` at `x`, `g`.
    pub fn stationarity(&self, scale: f64) -> f64 {
        let mut r = 0.0_f64;
        for j in 0..self.n {
            let x = self.x[j];
            let moved = (x - self.g[j] / scale).clamp(self.lo[j], self.hi[j]);
            let v = (x - moved).abs();
            r = if v.is_nan() { f64::NAN } else { r.max(v) };
            if r.is_nan() {
                return r;
            }
        }
        r
    }

    /// The spring energy `U(x)`.
    pub fn strain(&self, x: &[f64]) -> f64 {
        0.5 * x
            .iter()
            .zip(&self.rest)
            .zip(&self.k)
            .map(|((&t, &r), &k)| k * (t - r) * (t - r))
            .sum::<f64>()
    }

    /// The tip at angles `x`.
    pub fn tip_of(&self, x: &[f64]) -> Vector2<f64> {
        let mut phi = self.theta0;
        let (mut sx, mut sy) = (0.0_f64, 0.0_f64);
        for (&t, &l) in x.iter().zip(&self.len) {
            phi += t;
            let (s, c) = phi.sin_cos();
            sx += l * c;
            sy += l * s;
        }
        self.base_tip + Vector2::new(sx, sy)
    }

    /// The merit at angles `y`, evaluated directly.
    pub fn merit_value(&self, m: &Merit, y: &[f64]) -> f64 {
        let tip = self.tip_of(y);
        let c = m.gap(tip);
        self.strain(y) - m.force.dot(&tip) - m.mu.dot(&c) + 0.5 * m.rho * c.norm_squared()
    }

    /// The change of the merit from `x` to `trial`, as an accurate difference: `U` by
    /// `k (t - x)(t + x - 2 r) / 2`, the tip by `cos a - cos b = -2 sin((a+b)/2) sin((a-b)/2)`
    /// and the like, so a change far below the rounding error of the totals keeps its sign.
    /// Needs [`Workspace::kinematics`] at `x`.
    pub fn merit_change(&self, m: &Merit) -> f64 {
        let (mut du, mut dphi) = (0.0_f64, 0.0_f64);
        let (mut dx, mut dy) = (0.0_f64, 0.0_f64);
        for j in 0..self.n {
            let (t, x) = (self.trial[j], self.x[j]);
            let step = t - x;
            du += 0.5 * self.k[j] * step * (t + x - 2.0 * self.rest[j]);
            dphi += step;
            let h = 0.5 * dphi;
            let sh = h.sin();
            let (sm, cm) = (self.phi[j] + h).sin_cos();
            dx -= self.len[j] * 2.0 * sm * sh;
            dy += self.len[j] * 2.0 * cm * sh;
        }
        let dtip = Vector2::new(dx, dy);
        let c = m.gap(self.tip);
        let (dc, c_new) = if m.target.is_some() {
            (dtip, c + dtip)
        } else {
            (Vector2::zeros(), Vector2::zeros())
        };
        du - m.force.dot(&dtip) - m.mu.dot(&dc) + 0.5 * m.rho * dc.dot(&(c + c_new))
    }

    /// The full `theta` (`theta_0` first).
    pub fn theta(&self) -> Vec<f64> {
        let mut t = Vec::with_capacity(self.n + 1);
        t.push(self.theta0);
        t.extend_from_slice(&self.x);
        t
    }
}
