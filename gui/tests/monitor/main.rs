//! The monitor's interaction tests, one binary (each test binary links the whole GUI stack):
//! against a real antennad on the simulated rig ([`live`]), against a fake newer one that
//! sends wall estimates and a message type not known here, and a real one's estimates
//! ([`estimate`]), on a recorded trial
//! ([`recorded_trial`]) and on a scene file's simulated sweep ([`scene_sweep`]) with its wall
//! map ([`mapping`]) and on a closed-loop follow run, a follow scene's and a `--jsonl`
//! file's ([`follow_run`]), driven through egui_kittest.
#![allow(clippy::unwrap_used)]

mod estimate;
mod follow_run;
mod live;
mod mapping;
mod recorded_trial;
mod scene_sweep;
mod support;
