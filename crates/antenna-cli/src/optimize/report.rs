//! What `antenna optimize` reports: the best stiffnesses and their objective, the named
//! profiles', every failed evaluation, and the best value after each evaluation.

use std::fmt::Write as _;

use serde::Serialize;

use super::{Evaluation, Objective, OptimizeSpec, Wires};

/// A named profile's evaluation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NamedResult {
    /// The profile's name (docs/model.md 5).
    pub name: String,
    /// Its objective, metres (`null`: infeasible).
    pub objective_value: Option<f64>,
    /// Its joint stiffnesses as swept, N m/rad (made by wires with `wires = "available"`).
    pub values_n_m_per_rad: Vec<f64>,
}

/// An infeasible evaluation and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FailedEvaluation {
    /// The evaluation's index.
    pub evaluation: usize,
    /// Its stiffnesses, N m/rad.
    pub values_n_m_per_rad: Vec<f64>,
    /// `scene file: outcome: why`, one per infeasible sweep.
    pub why: Vec<String>,
}

/// The result of `antenna optimize` (`--json` prints it).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OptimizeReport {
    /// The optimization file.
    pub file: String,
    /// The scene files.
    pub scenes: Vec<String>,
    /// The objective's name.
    pub objective: String,
    /// The family searched.
    pub parameters: String,
    /// `"any"` or `"available"`.
    pub wires: String,
    /// The method.
    pub method: String,
    /// The stiffness bounds, N m/rad.
    pub stiffness_bounds_n_m_per_rad: [f64; 2],
    /// The budget, sweeps.
    pub budget: usize,
    /// The seed.
    pub seed: u64,
    /// The best joint stiffnesses found, N m/rad, joint 1 first (a scene with these as
    /// `values_n_m_per_rad` sweeps to `objective_value`).
    pub values_n_m_per_rad: Vec<f64>,
    /// Their objective, metres, averaged over the scenes (`null`: no evaluation was
    /// feasible).
    pub objective_value: Option<f64>,
    /// `"search"`, or `"named profile NAME"` when no point of the search beat it.
    pub found_by: String,
    /// The best evaluation's index.
    pub best_evaluation: Option<usize>,
    /// With `wires = "available"`: the wire per joint, inch.
    pub wire_diameters_in: Option<Vec<f64>>,
    /// The best of the seven named profiles of Table 4.1.
    pub best_named_profile: Option<NamedResult>,
    /// All seven, in Table 4.1's order.
    pub named_profiles: Vec<NamedResult>,
    /// Evaluations (distinct stiffness sets, each swept on every scene).
    pub evaluations: usize,
    /// Sweeps run (with `--resume`, the logged ones the run took from the log included).
    pub sweeps: usize,
    /// Evaluations taken from the log of a resumed run (`--resume`) instead of swept.
    pub replayed_evaluations: usize,
    /// Evaluations some sweep made infeasible.
    pub failed_evaluations: usize,
    /// Those evaluations and why.
    pub failures: Vec<FailedEvaluation>,
    /// The best objective after each evaluation, metres (`null` while none was feasible).
    pub history: Vec<Option<f64>>,
    /// Each evaluation's own objective, metres (`null`: infeasible).
    pub objective_values: Vec<Option<f64>>,
    /// Why the search stopped: `"budget"`, `"converged"` (Nelder-Mead's simplex agreed to
    /// 1e-9 m), `"stalled"` (200 calls in a row asked only for stiffness sets swept before),
    /// `"interrupted"` (Ctrl-C), `"log failed: ..."` or `"max iterations"`.
    pub stopped_by: String,
    /// Wall-clock time, seconds.
    pub elapsed_s: f64,
}

impl OptimizeReport {
    /// The report of `records`, the evaluations of `spec` in order, the first ones those of
    /// the `named_profiles` (two named profiles that wires make alike are one evaluation).
    pub fn new(
        spec: &OptimizeSpec,
        named_profiles: Vec<NamedResult>,
        records: &[Evaluation],
        sweeps: usize,
        stopped_by: String,
        elapsed_s: f64,
    ) -> OptimizeReport {
        let scene_label = |i: usize| {
            spec.scenes
                .get(i)
                .map_or_else(|| format!("scene {i}"), |(p, _)| p.display().to_string())
        };
        let mut best: Option<&Evaluation> = None;
        let mut history = Vec::with_capacity(records.len());
        for r in records {
            if let Some(v) = r.objective_value
                && best.is_none_or(|b| b.objective_value.is_none_or(|bv| v > bv))
            {
                best = Some(r);
            }
            history.push(best.and_then(|b| b.objective_value));
        }
        let best_named_profile = named_profiles
            .iter()
            .filter(|n| n.objective_value.is_some())
            .fold(None::<&NamedResult>, |b, n| match b {
                Some(b) if b.objective_value >= n.objective_value => Some(b),
                _ => Some(n),
            })
            .cloned();
        let failures: Vec<FailedEvaluation> = records
            .iter()
            .filter(|r| r.failed())
            .map(|r| FailedEvaluation {
                evaluation: r.index,
                values_n_m_per_rad: r.values_n_m_per_rad.clone(),
                why: r
                    .scenes
                    .iter()
                    .filter(|s| s.objective_value.is_none())
                    .map(|s| {
                        format!(
                            "{}: {}: {}",
                            scene_label(s.scene),
                            s.outcome,
                            s.why.as_deref().unwrap_or("no objective")
                        )
                    })
                    .collect(),
            })
            .collect();
        let values = best
            .or(records.first())
            .map(|b| b.values_n_m_per_rad.clone())
            .unwrap_or_default();
        let wire_diameters_in = (spec.space.wires == Wires::Available).then(|| {
            values
                .iter()
                .map(|&k| {
                    spec.space
                        .nearest_wire(k)
                        .map_or(f64::NAN, |(w, _)| w.diameter_in())
                })
                .collect()
        });
        OptimizeReport {
            file: spec.path.display().to_string(),
            scenes: (0..spec.scenes.len()).map(scene_label).collect(),
            objective: spec.objective.name().to_string(),
            parameters: spec.space.family.name().to_string(),
            wires: spec.space.wires.name().to_string(),
            method: spec.method.name().to_string(),
            stiffness_bounds_n_m_per_rad: [
                spec.space.bounds_n_m_per_rad.0,
                spec.space.bounds_n_m_per_rad.1,
            ],
            budget: spec.budget,
            seed: spec.seed,
            values_n_m_per_rad: values,
            objective_value: best.and_then(|b| b.objective_value),
            found_by: match best.and_then(|b| b.profile.as_ref()) {
                Some(name) => format!("named profile {name}"),
                None => "search".to_string(),
            },
            best_evaluation: best.map(|b| b.index),
            wire_diameters_in,
            best_named_profile,
            named_profiles,
            evaluations: records.len(),
            sweeps,
            replayed_evaluations: 0,
            failed_evaluations: failures.len(),
            failures,
            history,
            objective_values: records.iter().map(|r| r.objective_value).collect(),
            stopped_by,
            elapsed_s,
        }
    }

    /// A short table: the named profiles, the profile found, what it beats them by.
    pub fn table(&self) -> String {
        let objective = Objective::by_name(&self.objective).unwrap_or(Objective::PreviewMean);
        let mm = |v: Option<f64>| v.map_or("infeasible".to_string(), |v| objective.show(v));
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{}: maximize {} over {} scene(s); {} ({} coordinate(s)), wires {}, {}, budget {} sweeps",
            self.file,
            self.objective,
            self.scenes.len(),
            self.parameters,
            match self.parameters.as_str() {
                "per-joint" => self.values_n_m_per_rad.len(),
                _ => 2,
            },
            self.wires,
            self.method,
            self.budget
        );
        let _ = writeln!(out, "named profiles (thesis Table 4.1):");
        for n in &self.named_profiles {
            let _ = writeln!(out, "  {:<18} {}", n.name, mm(n.objective_value));
        }
        let _ = writeln!(
            out,
            "best: {} (found by {}{})",
            mm(self.objective_value),
            self.found_by,
            self.best_evaluation
                .map_or(String::new(), |i| format!(", evaluation {i}"))
        );
        if let (Some(best), Some(named)) = (self.objective_value, &self.best_named_profile)
            && let Some(nv) = named.objective_value
        {
            let _ = writeln!(
                out,
                "  {:+.4} {} over the best named profile, {} ({})",
                (best - nv) * objective.display_unit().1,
                objective.display_unit().0,
                named.name,
                mm(Some(nv))
            );
        }
        let _ = writeln!(
            out,
            "  joint  k (N m/rad){}",
            match &self.wire_diameters_in {
                Some(_) => "  wire (in)",
                None => "",
            }
        );
        for (j, k) in self.values_n_m_per_rad.iter().enumerate() {
            let wire = self
                .wire_diameters_in
                .as_ref()
                .and_then(|w| w.get(j))
                .map_or(String::new(), |d| format!("  {d:.3}"));
            let _ = writeln!(out, "  {:>5}  {k:.6}{wire}", j + 1);
        }
        let _ = writeln!(
            out,
            "{} evaluation(s), {} sweep(s), {} failed; stopped by {}; {:.1} s",
            self.evaluations, self.sweeps, self.failed_evaluations, self.stopped_by, self.elapsed_s
        );
        for f in &self.failures {
            let _ = writeln!(
                out,
                "  failed evaluation {}: {}",
                f.evaluation,
                f.why.join("; ")
            );
        }
        out
    }
}
