//! The chain's points in the ground frame for one posture: link ends, points along links,
//! hair tips, and the Jacobian columns of any of them (`O(n)` per point).

use nalgebra::Vector2;

use crate::{Chain, Hair};

/// `R(phi) v`.
pub(crate) fn rotate(phi_rad: f64, v: Vector2<f64>) -> Vector2<f64> {
    let (sn, cs) = phi_rad.sin_cos();
    Vector2::new(cs * v.x - sn * v.y, sn * v.x + cs * v.y)
}

/// `R90 v`.
pub(crate) fn perp(v: Vector2<f64>) -> Vector2<f64> {
    Vector2::new(-v.y, v.x)
}

/// The z-component of `a x b`.
pub(crate) fn cross(a: Vector2<f64>, b: Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Where the base is: its pivot and the base link's angle `theta_0` (a step's goal, or the
/// committed state).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Pose {
    /// The base pivot, ground frame, metres.
    pub base_m: Vector2<f64>,
    /// The base link's angle `theta_0`, radians.
    pub angle_rad: f64,
}

impl Pose {
    /// The size of the move from `self` to `to`: `max(|d base|, reach |d angle|)`, metres
    /// (`reach_m` the farthest a point of the chain is from the base pivot: a turn moves it
    /// by that much per radian). Without a turn it is `|d base|` exactly.
    pub fn distance_m(&self, to: &Pose, reach_m: f64) -> f64 {
        (to.base_m - self.base_m)
            .norm()
            .max(reach_m * (to.angle_rad - self.angle_rad).abs())
    }

    /// Halfway from `self` to `to` (pivot and angle interpolated); without a turn the pivot
    /// is `base + (to - base) * 0.5` exactly, as a plain base step has always halved it.
    pub fn midway(&self, to: &Pose) -> Pose {
        Pose {
            base_m: self.base_m + (to.base_m - self.base_m) * 0.5,
            angle_rad: self.angle_rad + (to.angle_rad - self.angle_rad) * 0.5,
        }
    }

    /// `point_m`, fixed to the base at `self`, carried with the base to `to`: turned about
    /// the pivot by the change of angle and moved with it. Without a turn it is
    /// `point + (to - base)`, as a base that only moves has always carried it.
    pub fn carry(&self, to: &Pose, point_m: Vector2<f64>) -> Vector2<f64> {
        let turn_rad = to.angle_rad - self.angle_rad;
        if turn_rad == 0.0 {
            point_m + (to.base_m - self.base_m)
        } else {
            to.base_m + rotate(turn_rad, point_m - self.base_m)
        }
    }
}

/// Link angles and link ends of one posture, with the base pivot at `base_m`.
#[derive(Clone, Debug, Default)]
pub(crate) struct Posture {
    /// The base pivot `b` (ground frame).
    pub base_m: Vector2<f64>,
    /// Absolute link angles `phi_0..phi_n`.
    pub phi_rad: Vec<f64>,
    /// Distal ends `p_0..p_n` of the links (`p_n` the tip); joint `j` sits at `p_(j-1)`.
    pub end_m: Vec<Vector2<f64>>,
}

impl Posture {
    /// Recomputes everything for `theta` (`n + 1` entries) and the base at `base_m`.
    pub fn update(&mut self, chain: &Chain, base_m: Vector2<f64>, theta: &[f64]) {
        let angle_rad = theta.first().copied().unwrap_or(0.0);
        self.update_at(chain, Pose { base_m, angle_rad }, theta);
    }

    /// [`Self::update`] with the base at `pose`: its angle stands for `theta[0]` (the
    /// joint angles `theta[1..]` carried to a base that turns).
    pub fn update_at(&mut self, chain: &Chain, pose: Pose, theta: &[f64]) {
        let base_m = pose.base_m;
        let links = chain.link_lengths_m();
        self.base_m = base_m;
        self.phi_rad.resize(links.len(), 0.0);
        self.end_m.resize(links.len(), Vector2::zeros());
        let mut phi = 0.0;
        let mut at = base_m;
        for (i, (&l, &t)) in links.iter().zip(theta).enumerate() {
            phi += if i == 0 { pose.angle_rad } else { t };
            let (sn, cs) = phi.sin_cos();
            at += Vector2::new(cs, sn) * l;
            self.phi_rad[i] = phi;
            self.end_m[i] = at;
        }
    }

    /// The proximal end of link `link` (`b` for link 0).
    pub fn start_of(&self, link: usize) -> Vector2<f64> {
        if link == 0 {
            self.base_m
        } else {
            self.end_m[link - 1]
        }
    }

    /// The point at fraction `s` of link `link`.
    pub fn link_point(&self, link: usize, s: f64) -> Vector2<f64> {
        let a = self.start_of(link);
        a + (self.end_m[link] - a) * s
    }

    /// The tip of `hair` on link `link` at hair angle `beta_rad`.
    pub fn hair_tip(&self, hair: &Hair, link: usize, beta_rad: f64) -> Vector2<f64> {
        self.end_m[link] + rotate(self.phi_rad[link], hair.tip_in_link_m(beta_rad))
    }

    /// The pivot of `hair` on link `link`.
    pub fn hair_pivot(&self, hair: &Hair, link: usize) -> Vector2<f64> {
        self.end_m[link] + rotate(self.phi_rad[link], hair.pivot_in_link_m())
    }

    /// `d tip / d beta` of `hair` on link `link`, ground frame.
    pub fn hair_tip_rate(&self, hair: &Hair, link: usize, beta_rad: f64) -> Vector2<f64> {
        rotate(self.phi_rad[link], hair.tip_rate_in_link_m(beta_rad))
    }
}

/// `theta` with its flexible joints replaced by the first `n` coordinates of `x`.
pub(crate) fn theta_of(theta: &[f64], x: &[f64]) -> Vec<f64> {
    let mut out = theta.to_vec();
    let n = out.len() - 1;
    out[1..].copy_from_slice(&x[..n]);
    out
}
