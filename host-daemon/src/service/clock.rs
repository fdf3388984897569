//! The trial clock: one monotonic origin for every thread, and periodic schedules on
//! absolute deadlines (`deadline_k = start + k * period`), so no drift accumulates however
//! late one wake-up is.
//!
//! ```
//! use host_daemon::service::clock::{Schedule, TrialClock};
//! use std::time::Duration;
//!
//! let clock = TrialClock::start();
//! let mut schedule = Schedule::new(clock, Duration::from_millis(1));
//! for _ in 0..5 {
//!     let tick = schedule.wait_next();
//!     assert!(clock.elapsed() >= tick.deadline);
//! }
//! assert_eq!(schedule.ticks(), 5);
//! ```

use std::time::{Duration, Instant};

/// The origin all time stamps of a trial are measured from (monotonic, `Instant`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TrialClock {
    origin: Instant,
}

impl TrialClock {
    /// A clock starting now.
    pub fn start() -> Self {
        Self {
            origin: Instant::now(),
        }
    }

    /// A clock starting at `origin`.
    pub fn from_origin(origin: Instant) -> Self {
        Self { origin }
    }

    /// The origin.
    pub fn origin(&self) -> Instant {
        self.origin
    }

    /// Time since the origin.
    pub fn elapsed(&self) -> Duration {
        self.origin.elapsed()
    }

    /// Time since the origin in nanoseconds (saturating; 584 years fit).
    pub fn elapsed_ns(&self) -> u64 {
        u64::try_from(self.elapsed().as_nanos()).unwrap_or(u64::MAX)
    }

    /// Sleeps until `deadline` after the origin: a plain sleep to within `spin` of it, then a
    /// busy wait for the rest (a sleep alone wakes tens of microseconds late).
    pub fn sleep_until(&self, deadline: Duration, spin: Duration) {
        let target = self.origin + deadline;
        loop {
            let now = Instant::now();
            if now >= target {
                return;
            }
            let left = target - now;
            if left > spin {
                std::thread::sleep(left - spin);
            } else {
                std::hint::spin_loop();
            }
        }
    }
}

/// One wake-up of a [`Schedule`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tick {
    /// The tick's number, from 0.
    pub index: u64,
    /// When it was due, since the clock's origin.
    pub deadline: Duration,
    /// When the thread actually woke, since the clock's origin.
    pub woke: Duration,
    /// Deadlines skipped because the thread was more than a whole period late.
    pub skipped: u64,
}

impl Tick {
    /// How late the wake-up was.
    pub fn lateness(&self) -> Duration {
        self.woke.saturating_sub(self.deadline)
    }
}

/// A periodic schedule on absolute deadlines: tick `k` is due at `k * period` after the
/// clock's origin. A thread that falls more than a period behind skips the deadlines it
/// missed (counted in [`Tick::skipped`]) instead of running a burst to catch up.
#[derive(Debug, Clone)]
pub struct Schedule {
    clock: TrialClock,
    period: Duration,
    spin: Duration,
    next: u64,
    ticks: u64,
}

impl Schedule {
    /// Ticks every `period` (at least 1 us) from the clock's origin, with no busy wait.
    pub fn new(clock: TrialClock, period: Duration) -> Self {
        Self {
            clock,
            period: period.max(Duration::from_micros(1)),
            spin: Duration::ZERO,
            next: 0,
            ticks: 0,
        }
    }

    /// The same, spinning for the last `spin` before each deadline.
    pub fn with_spin(mut self, spin: Duration) -> Self {
        self.spin = spin;
        self
    }

    /// The period.
    pub fn period(&self) -> Duration {
        self.period
    }

    /// Ticks returned so far.
    pub fn ticks(&self) -> u64 {
        self.ticks
    }

    /// The deadline of tick `index`.
    pub fn deadline(&self, index: u64) -> Duration {
        let nanos = self.period.as_nanos().saturating_mul(u128::from(index));
        Duration::from_nanos(u64::try_from(nanos).unwrap_or(u64::MAX))
    }

    /// The deadline of the next tick.
    pub fn next_deadline(&self) -> Duration {
        self.deadline(self.next)
    }

    /// Sleeps until the next deadline and returns the tick.
    pub fn wait_next(&mut self) -> Tick {
        let deadline = self.next_deadline();
        self.clock.sleep_until(deadline, self.spin);
        let woke = self.clock.elapsed();
        let index = self.next;
        // Skip the deadlines already missed entirely.
        let behind = woke.saturating_sub(deadline).as_nanos() / self.period.as_nanos().max(1);
        let skipped = u64::try_from(behind).unwrap_or(u64::MAX);
        self.next = index.saturating_add(1).saturating_add(skipped);
        self.ticks += 1;
        Tick {
            index,
            deadline,
            woke,
            skipped,
        }
    }
}
