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
        let links = chain.link_lengths_m();
        self.base_m = base_m;
        self.phi_rad.resize(links.len(), 0.0);
        self.end_m.resize(links.len(), Vector2::zeros());
        let mut phi = 0.0;
        let mut at = base_m;
        for (i, (&l, &t)) in links.iter().zip(theta).enumerate() {
            phi += t;
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
