//! antennad under systemd (`Type=notify`, `host-daemon/packaging/antennad.service`): the
//! service manager's notifications through the `sd-notify` crate.
//!
//! - `READY=1` once the daemon polls ([`notify_ready`]), `STATUS=...` lines as it goes
//!   ([`notify_status`]), `STOPPING=1` when it shuts down ([`notify_stopping`]);
//! - `WATCHDOG=1` every half of `WATCHDOG_USEC` ([`Watchdog`]), sent by the hub thread (the
//!   one that handles every poll), so a wedged hub stops the pings and systemd restarts the
//!   service.
//!
//! Outside systemd (`NOTIFY_SOCKET` unset) every notification is a no-op that succeeds.

use std::time::Duration;

/// The service manager's watchdog: how often to ping it, from `WATCHDOG_USEC` (and
/// `WATCHDOG_PID`, which must be this process when set).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Watchdog {
    ping_every: Duration,
}

impl Watchdog {
    /// The watchdog systemd asked for (`WatchdogSec=`), if any: pings at half its timeout.
    pub fn from_env() -> Option<Self> {
        watchdog_timeout().map(Self::for_timeout)
    }

    /// A watchdog whose timeout is `timeout`: pings at half of it (`sd_watchdog_enabled(3)`).
    pub fn for_timeout(timeout: Duration) -> Self {
        Self {
            ping_every: (timeout / 2).max(Duration::from_millis(1)),
        }
    }

    /// How often [`Watchdog::ping`] must be called.
    pub fn ping_every(&self) -> Duration {
        self.ping_every
    }

    /// Sends `WATCHDOG=1`.
    pub fn ping(&self) -> std::io::Result<()> {
        notify(&[Notification::Watchdog])
    }
}

/// Sends `READY=1` with a status line.
pub fn notify_ready(status: &str) -> std::io::Result<()> {
    notify(&[Notification::Ready, Notification::Status(status)])
}

/// Sends `STATUS=<status>` (what `systemctl status` shows).
pub fn notify_status(status: &str) -> std::io::Result<()> {
    notify(&[Notification::Status(status)])
}

/// Sends `STOPPING=1` with a status line.
pub fn notify_stopping(status: &str) -> std::io::Result<()> {
    notify(&[Notification::Stopping, Notification::Status(status)])
}

/// Whether a service manager listens (`NOTIFY_SOCKET` is set).
pub fn notify_socket_set() -> bool {
    std::env::var_os("NOTIFY_SOCKET").is_some()
}

enum Notification<'a> {
    Ready,
    Stopping,
    Watchdog,
    Status(&'a str),
}

#[cfg(target_os = "linux")]
fn notify(states: &[Notification<'_>]) -> std::io::Result<()> {
    use sd_notify::NotifyState;
    let states: Vec<NotifyState<'_>> = states
        .iter()
        .map(|s| match s {
            Notification::Ready => NotifyState::Ready,
            Notification::Stopping => NotifyState::Stopping,
            Notification::Watchdog => NotifyState::Watchdog,
            Notification::Status(text) => NotifyState::Status(text),
        })
        .collect();
    sd_notify::notify(&states)
}

#[cfg(target_os = "linux")]
fn watchdog_timeout() -> Option<Duration> {
    sd_notify::watchdog_enabled().filter(|t| !t.is_zero())
}

/// No service manager to notify off Linux.
#[cfg(not(target_os = "linux"))]
fn notify(_: &[Notification<'_>]) -> std::io::Result<()> {
    Ok(())
}

#[cfg(not(target_os = "linux"))]
fn watchdog_timeout() -> Option<Duration> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_watchdog_is_pinged_at_half_its_timeout() {
        let watchdog = Watchdog::for_timeout(Duration::from_secs(20));
        assert_eq!(watchdog.ping_every(), Duration::from_secs(10));
        let tiny = Watchdog::for_timeout(Duration::from_micros(1));
        assert_eq!(tiny.ping_every(), Duration::from_millis(1));
    }
}
