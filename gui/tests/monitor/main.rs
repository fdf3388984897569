//! The monitor's interaction tests, one binary (each test binary links the whole GUI stack):
//! against a real antennad on the simulated rig ([`live`]) and on a recorded trial
//! ([`recorded_trial`]), driven through egui_kittest.
#![allow(clippy::unwrap_used)]

mod live;
mod recorded_trial;
mod support;
