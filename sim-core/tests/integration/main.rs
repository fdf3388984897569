//! sim-core's integration tests, one test binary (`cargo test -p sim-core --test integration`;
//! a module's tests alone: `cargo test -p sim-core --test integration kinematics_golden::`).
//! Each module was a test file of its own; one binary links once instead of once per file.
//!
//! proptest keeps the failures it has found (`FileFailurePersistence::SourceParallel`, its
//! default) in `tests/proptest-regressions/<module>.txt`: the directory beside the one that
//! holds this `main.rs`, a file per module, replayed before any new case.

mod common_kinematics;
mod equilibrium_common;
mod tip_force_common;

mod beam_convergence;
mod contact_broad_phase;
mod contact_friction;
mod contact_jumps_many_links;
mod coverage;
mod equilibrium_dead_load;
mod equilibrium_limits;
mod equilibrium_pinned;
mod equilibrium_pinned_regressions;
mod equilibrium_structured;
mod follow_loop;
mod follow_theory;
mod identify_table_6_4;
mod kinematics_errors;
mod kinematics_fast_vs_seed;
mod kinematics_finite_differences;
mod kinematics_golden;
mod kinematics_identities;
mod mapping_estimate;
mod metrics_postures;
mod sensor;
mod stress_equilibrium;
mod tip_force;
mod tip_force_castigliano;
mod tip_force_errors;
mod wall_brute_force;
mod wall_shapes;
