//! The polling thread's watchdog: the thread beats a [`PollHeartbeat`] after every poll, and
//! whoever watches (the daemon's hub) asks a [`PollWatchdog`] whether the polls have stopped.
//!
//! A poll that hangs in the I2C driver (a segment holding the clock low, a controller
//! without a timeout) blocks the polling thread inside the ioctl: nothing it could do itself
//! would tell anyone. The heartbeat is read from another thread, so a stall is seen however
//! the thread is stuck: no poll finished for longer than the bound
//! ([`stall_bound`]: ten poll periods, at least 100 ms) is a stall, reported once when it
//! starts and once when polls resume, with the deadlines missed meanwhile.
//!
//! ```
//! use host_daemon::service::watchdog::{PollHeartbeat, PollWatchdog, WatchdogEvent};
//! use std::sync::Arc;
//! use std::time::Duration;
//!
//! let heartbeat = Arc::new(PollHeartbeat::new(0));
//! let mut watchdog = PollWatchdog::new(Arc::clone(&heartbeat), Duration::from_millis(100));
//! heartbeat.beat(1_000_000, 0);
//! assert_eq!(watchdog.check(50_000_000), None);
//! assert!(matches!(watchdog.check(200_000_000), Some(WatchdogEvent::Stalled { .. })));
//! assert!(watchdog.status(200_000_000).stalled);
//! heartbeat.beat(210_000_000, 208);
//! assert!(matches!(
//!     watchdog.check(210_000_000),
//!     Some(WatchdogEvent::Resumed { missed_deadlines: 208, .. })
//! ));
//! ```

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

/// The bound past which a polling thread that has not finished a poll is stalled: ten poll
/// periods, and at least 100 ms (so a loaded machine's scheduling hiccups are not stalls).
pub fn stall_bound(period: Duration) -> Duration {
    (period * 10).max(Duration::from_millis(100))
}

/// What the polling thread publishes after every poll, readable from any thread.
#[derive(Debug)]
pub struct PollHeartbeat {
    last_poll_ns: AtomicU64,
    polls: AtomicU64,
    missed: AtomicU64,
}

impl PollHeartbeat {
    /// A heartbeat whose polling thread starts at `start_ns` (its clock's nanoseconds): the
    /// wait for the first poll counts from there.
    pub fn new(start_ns: u64) -> Self {
        Self {
            last_poll_ns: AtomicU64::new(start_ns),
            polls: AtomicU64::new(0),
            missed: AtomicU64::new(0),
        }
    }

    /// A poll finished at `now_ns`, after `skipped` deadlines missed since the previous one.
    pub fn beat(&self, now_ns: u64, skipped: u64) {
        self.missed.fetch_add(skipped, Ordering::Relaxed);
        self.polls.fetch_add(1, Ordering::Relaxed);
        self.last_poll_ns.store(now_ns, Ordering::Release);
    }

    /// When the last poll finished (or the thread started), clock nanoseconds.
    pub fn last_poll_ns(&self) -> u64 {
        self.last_poll_ns.load(Ordering::Acquire)
    }

    /// Polls finished.
    pub fn polls(&self) -> u64 {
        self.polls.load(Ordering::Relaxed)
    }

    /// Deadlines missed (skipped because the thread was a whole period late), as counted when
    /// the polls resumed.
    pub fn missed_deadlines(&self) -> u64 {
        self.missed.load(Ordering::Relaxed)
    }
}

/// A change the watchdog saw.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WatchdogEvent {
    /// No poll has finished for longer than the bound.
    Stalled {
        /// When the last poll finished, clock nanoseconds.
        last_poll_ns: u64,
        /// How long ago, when the stall was seen.
        silent: Duration,
    },
    /// Polls finish again.
    Resumed {
        /// How long no poll finished.
        stalled_for: Duration,
        /// Deadlines missed over the stall.
        missed_deadlines: u64,
    },
}

/// What the watchdog says now, for the daemon's `status`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WatchdogStatus {
    /// No poll has finished for longer than the bound.
    pub stalled: bool,
    /// Since the last poll finished.
    pub since_last_poll: Duration,
    /// The bound.
    pub bound: Duration,
    /// Polls finished.
    pub polls: u64,
    /// Deadlines missed in all (not counting those of a stall still going on).
    pub missed_deadlines: u64,
    /// Stalls seen, the one going on included.
    pub stalls: u64,
}

/// Judges a [`PollHeartbeat`] against a bound (see the module documentation).
#[derive(Debug)]
pub struct PollWatchdog {
    heartbeat: Arc<PollHeartbeat>,
    bound: Duration,
    stalled_since_ns: Option<u64>,
    missed_at_stall: u64,
    stalls: u64,
}

impl PollWatchdog {
    /// Watches `heartbeat`: a stall is no poll for longer than `bound`.
    pub fn new(heartbeat: Arc<PollHeartbeat>, bound: Duration) -> Self {
        Self {
            heartbeat,
            bound,
            stalled_since_ns: None,
            missed_at_stall: 0,
            stalls: 0,
        }
    }

    /// The heartbeat watched.
    pub fn heartbeat(&self) -> &Arc<PollHeartbeat> {
        &self.heartbeat
    }

    /// Whether a stall is going on (as of the last [`PollWatchdog::check`]).
    pub fn is_stalled(&self) -> bool {
        self.stalled_since_ns.is_some()
    }

    /// Looks at the heartbeat at `now_ns`: a stall starting or ending.
    pub fn check(&mut self, now_ns: u64) -> Option<WatchdogEvent> {
        let last = self.heartbeat.last_poll_ns();
        let silent = Duration::from_nanos(now_ns.saturating_sub(last));
        match self.stalled_since_ns {
            None if silent > self.bound => {
                self.stalled_since_ns = Some(last);
                self.missed_at_stall = self.heartbeat.missed_deadlines();
                self.stalls += 1;
                Some(WatchdogEvent::Stalled {
                    last_poll_ns: last,
                    silent,
                })
            }
            Some(since) if last > since => {
                self.stalled_since_ns = None;
                Some(WatchdogEvent::Resumed {
                    stalled_for: Duration::from_nanos(last - since),
                    missed_deadlines: self
                        .heartbeat
                        .missed_deadlines()
                        .saturating_sub(self.missed_at_stall),
                })
            }
            _ => None,
        }
    }

    /// The watchdog's view at `now_ns` (as of the last [`PollWatchdog::check`] for `stalled`).
    pub fn status(&self, now_ns: u64) -> WatchdogStatus {
        WatchdogStatus {
            stalled: self.is_stalled(),
            since_last_poll: Duration::from_nanos(
                now_ns.saturating_sub(self.heartbeat.last_poll_ns()),
            ),
            bound: self.bound,
            polls: self.heartbeat.polls(),
            missed_deadlines: self.heartbeat.missed_deadlines(),
            stalls: self.stalls,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stall_is_reported_once_and_its_end_once() {
        let heartbeat = Arc::new(PollHeartbeat::new(0));
        let mut watchdog = PollWatchdog::new(Arc::clone(&heartbeat), Duration::from_millis(100));
        // Before the first poll the wait counts from the start.
        assert_eq!(watchdog.check(99_000_000), None);
        assert!(matches!(
            watchdog.check(101_000_000),
            Some(WatchdogEvent::Stalled {
                last_poll_ns: 0,
                ..
            })
        ));
        assert_eq!(watchdog.check(500_000_000), None);
        let status = watchdog.status(500_000_000);
        assert!(status.stalled);
        assert_eq!(status.since_last_poll, Duration::from_millis(500));
        assert_eq!(status.stalls, 1);
        heartbeat.beat(600_000_000, 599);
        assert_eq!(
            watchdog.check(600_000_000),
            Some(WatchdogEvent::Resumed {
                stalled_for: Duration::from_millis(600),
                missed_deadlines: 599,
            })
        );
        assert_eq!(watchdog.check(650_000_000), None);
        assert!(!watchdog.status(650_000_000).stalled);
        assert_eq!(watchdog.status(650_000_000).missed_deadlines, 599);
    }

    #[test]
    fn the_bound_is_ten_periods_and_at_least_100_ms() {
        assert_eq!(
            stall_bound(Duration::from_millis(1)),
            Duration::from_millis(100)
        );
        assert_eq!(
            stall_bound(Duration::from_millis(50)),
            Duration::from_millis(500)
        );
    }
}
