//! Whether a state is a strict local minimum of its step's potential.

use super::QuasiStatic;
use crate::contact::pair::Pair;
use crate::contact::step_solver::StepProblem;

impl QuasiStatic {
    /// Whether the current state is a strict local minimum of the step's potential: the
    /// Hessian of the Lagrangian (springs, the contact forces' and the tip load's curvature,
    /// the walls' curvature) is positive definite on the tangent space of the active
    /// constraints (joints on a limit held, contacts carrying a force kept touching, stuck
    /// ones kept in place).
    pub fn is_stable(&mut self) -> bool {
        self.stability_margin() > 0.0
    }

    /// The smallest eigenvalue of that reduced Hessian divided by the largest joint
    /// stiffness (dimensionless; `> 0` stable). `+inf` when nothing can move.
    pub fn stability_margin(&mut self) -> f64 {
        let n = self.world.chain().n();
        let mut hair_links: Vec<usize> = self
            .committed
            .pairs()
            .iter()
            .filter_map(|c| c.key.hair_link())
            .collect();
        hair_links.sort_unstable();
        hair_links.dedup();
        let mut x: Vec<f64> = self.committed.theta()[1..].to_vec();
        x.extend(hair_links.iter().map(|&l| self.committed.beta()[l]));
        // The contacts as they are, each its own start (no slip).
        let mut pairs: Vec<Pair> = self
            .committed
            .pairs()
            .iter()
            .map(|c| Pair {
                start_m: c.material_m,
                ..*c
            })
            .collect();
        let problem = StepProblem {
            chain: self.world.chain(),
            pieces: &self.world.pieces().walls,
            tip_force_n: self.world.tip_force_n(),
            base_m: self.committed.base_m(),
            base_angle_rad: self.committed.theta()[0],
            hair_links: &hair_links,
            hair_beta_rad: self.committed.beta(),
            proximal: None,
            hand_m: self.world.hand_target(self.committed.pose()),
            tolerance_m: self.world.settings().tolerance_m,
            acceptable_m: self.world.settings().acceptable_m,
            max_departure_rad: f64::INFINITY,
            max_iterations: 1,
            stall_after: None,
        };
        let reduced = self.step_solver.tangent_hessian(&problem, &x, &mut pairs);
        if reduced.nrows() == 0 {
            return f64::INFINITY;
        }
        let k_max = self.world.chain().stiffness_nm_per_rad()[1..=n]
            .iter()
            .copied()
            .fold(f64::MIN_POSITIVE, f64::max);
        let min = reduced
            .symmetric_eigen()
            .eigenvalues
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        min / k_max
    }
}
