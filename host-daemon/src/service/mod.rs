//! The daemon: its configuration and where it comes from, the hub that records and streams
//! ([`daemon`]), the polling thread and its watchdog ([`acquisition`], [`watchdog`]), the one
//! motion loop and the trial script (`motion`, `trial_script`) on the rig of devices
//! ([`rig`]), and what makes it a system service (systemd notifications in [`systemd`],
//! stdout that can close in [`stdout_lines`]).

pub mod acquisition;
pub mod clock;
/// The configuration, now its own layer ([`crate::config`]); kept here under its old path.
pub use crate::config;
pub mod config_source;
pub mod daemon;
pub mod estimate;
pub mod free_space;
pub(crate) mod motion;
pub mod rig;
pub mod samples;
pub mod stdout_lines;
pub mod systemd;
pub(crate) mod trial_script;
pub mod watchdog;
