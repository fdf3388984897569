//! Acquisition: the polling thread and the motion thread, on one [`TrialClock`], feeding one
//! bounded channel of [`AcquisitionEvent`]s.
//!
//! - **Polling** ([`spawn_poller`]): a dedicated thread wakes on absolute deadlines
//!   (`start + k * period`, [`Schedule`]), reads every segment through the [`Poller`]
//!   (PEC-checked 3-byte reads), stamps the poll with the time since the trial started and
//!   sends it. Every `counter_check_every` polls it also reads each segment's sample counter:
//!   a counter that has not moved marks the segment stale ([`PollRecord::stale_mask`]). A
//!   NACK, a PEC error or a stale counter is recorded in the segment's health and the poll
//!   goes on.
//! - **Motion**: the motion thread (`crate::motion`, the daemon's one motion loop) samples
//!   the stage position and the base angle at their own rates under the same clock and sends
//!   them into the same stream.
//! - **The stream** ([`EventSender`]): a bounded channel written with `try_send`. A full
//!   consumer queue never delays polling: the event is dropped and counted
//!   ([`EventSender::dropped`]); size the queue so that never happens (the main loop
//!   forwards events to the recorder and the TCP server, which have their own queues).

use crate::clock::{Schedule, TrialClock};
use crate::poll::{CounterCheck, Poller, SegmentHealth, SegmentReading};
use embedded_hal::i2c::I2c;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// One poll of every segment.
#[derive(Debug, Clone, PartialEq)]
pub struct PollRecord {
    /// The poll's number since the trial started (gaps are skipped deadlines).
    pub seq: u64,
    /// When the poll started, nanoseconds since the trial started.
    pub t_ns: u64,
    /// When it was due, nanoseconds since the trial started.
    pub deadline_ns: u64,
    /// Each segment's word or why there is none, base to tip.
    pub readings: Vec<SegmentReading>,
    /// Bit `k` set: segment `k`'s sample counter did not move at its last check (its word is
    /// old news even if it reads well).
    pub stale_mask: u64,
}

impl PollRecord {
    /// Whether segment `index` was found stale at its last counter check.
    pub fn is_stale(&self, index: usize) -> bool {
        index < 64 && self.stale_mask & (1 << index) != 0
    }
}

/// A health change of one segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HealthChange {
    /// Its counter stopped moving.
    Stale,
    /// Its counter moves again.
    Recovered,
}

/// What the acquisition threads send.
#[derive(Debug, Clone, PartialEq)]
pub enum AcquisitionEvent {
    /// A poll of every segment.
    Poll(PollRecord),
    /// The stage position.
    Stage {
        /// Nanoseconds since the trial started.
        t_ns: u64,
        /// Millimetres from home.
        position_mm: f64,
    },
    /// The base (servo) angle.
    Base {
        /// Nanoseconds since the trial started.
        t_ns: u64,
        /// Radians.
        angle_rad: f64,
    },
    /// A segment's counter stopped or started moving.
    Health {
        /// Nanoseconds since the trial started.
        t_ns: u64,
        /// The segment.
        address: u8,
        /// What changed.
        change: HealthChange,
    },
    /// Something the trial did or refused (a move started, a move beyond the soft limits).
    Note {
        /// Nanoseconds since the trial started.
        t_ns: u64,
        /// What happened.
        text: String,
    },
}

/// The sending end of the event stream: never blocks; counts what a full queue refused.
#[derive(Debug, Clone)]
pub struct EventSender {
    sender: SyncSender<AcquisitionEvent>,
    dropped: Arc<AtomicU64>,
}

impl EventSender {
    /// Sends `event` if there is room; otherwise drops and counts it.
    pub fn send(&self, event: AcquisitionEvent) {
        if let Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) =
            self.sender.try_send(event)
        {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// Events dropped so far (queue full or the receiver gone), over every clone.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }
}

/// A bounded event stream of `capacity` events.
pub fn event_channel(capacity: usize) -> (EventSender, Receiver<AcquisitionEvent>) {
    let (sender, receiver) = sync_channel(capacity.max(1));
    (
        EventSender {
            sender,
            dropped: Arc::new(AtomicU64::new(0)),
        },
        receiver,
    )
}

/// How the polling thread runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PollSettings {
    /// Poll period.
    pub period: Duration,
    /// Read the sample counters every this many polls (at least 1).
    pub counter_check_every: u32,
    /// Busy-wait this long before each deadline (zero: sleep only).
    pub spin: Duration,
    /// Ask for `SCHED_FIFO` at this priority (1..=99) for the polling thread; 0: normal
    /// scheduling. The outcome is sent as an [`AcquisitionEvent::Note`]; a refusal leaves
    /// the thread on normal scheduling.
    pub realtime_priority: u8,
}

/// What the polling thread hands back when it stops.
#[derive(Debug)]
pub struct PollReport<I> {
    /// The bus.
    pub bus: I,
    /// Health per segment.
    pub health: Vec<SegmentHealth>,
    /// Polls made.
    pub polls: u64,
    /// Deadlines skipped because the thread was a whole period late.
    pub skipped: u64,
    /// The latest wake-up, after its deadline.
    pub max_lateness: Duration,
}

/// Starts the polling thread: polls `poller` every `settings.period` until `stop` is set.
/// `before_poll(bus, t)` runs at each deadline before the reads (the simulated rig uses it to
/// let its segments sample; give `|_, _| {}` for hardware, whose segments sample on their
/// own).
pub fn spawn_poller<I, H>(
    mut poller: Poller<I>,
    clock: TrialClock,
    settings: PollSettings,
    mut before_poll: H,
    events: EventSender,
    stop: Arc<AtomicBool>,
) -> std::io::Result<JoinHandle<PollReport<I>>>
where
    I: I2c + Send + 'static,
    H: FnMut(&mut I, Duration) + Send + 'static,
{
    std::thread::Builder::new()
        .name("antennad-poll".to_owned())
        .spawn(move || {
            crate::realtime::minimize_timer_slack();
            if settings.realtime_priority > 0 {
                let text = match crate::realtime::request_fifo(settings.realtime_priority) {
                    Ok(()) => format!(
                        "polling thread on SCHED_FIFO priority {}",
                        settings.realtime_priority
                    ),
                    Err(why) => format!(
                        "SCHED_FIFO priority {} refused ({why}); polling on normal scheduling",
                        settings.realtime_priority
                    ),
                };
                events.send(AcquisitionEvent::Note {
                    t_ns: clock.elapsed_ns(),
                    text,
                });
            }
            let mut schedule = Schedule::new(clock, settings.period).with_spin(settings.spin);
            let check_every = u64::from(settings.counter_check_every.max(1));
            let addresses = poller.addresses().to_vec();
            let mut stale_mask = 0u64;
            let mut skipped = 0;
            let mut max_lateness = Duration::ZERO;
            while !stop.load(Ordering::Relaxed) {
                let tick = schedule.wait_next();
                skipped += tick.skipped;
                max_lateness = max_lateness.max(tick.lateness());
                before_poll(poller.bus_mut(), tick.woke);
                let readings = poller.poll_all();
                if tick.index % check_every == check_every - 1 {
                    let t_ns = clock.elapsed_ns();
                    for (k, check) in poller.check_counters().into_iter().enumerate() {
                        let bit = if k < 64 { 1u64 << k } else { 0 };
                        let was = stale_mask & bit != 0;
                        let change = match check {
                            CounterCheck::Stale if !was => Some(HealthChange::Stale),
                            CounterCheck::Moving if was => Some(HealthChange::Recovered),
                            _ => None,
                        };
                        match check {
                            CounterCheck::Stale => stale_mask |= bit,
                            CounterCheck::Moving => stale_mask &= !bit,
                            CounterCheck::Unread => {}
                        }
                        if let Some(change) = change {
                            events.send(AcquisitionEvent::Health {
                                t_ns,
                                address: addresses[k],
                                change,
                            });
                        }
                    }
                }
                events.send(AcquisitionEvent::Poll(PollRecord {
                    seq: tick.index,
                    t_ns: nanos(tick.woke),
                    deadline_ns: nanos(tick.deadline),
                    readings,
                    stale_mask,
                }));
            }
            PollReport {
                health: poller.health().to_vec(),
                polls: schedule.ticks(),
                skipped,
                max_lateness,
                bus: poller.destroy(),
            }
        })
}

fn nanos(d: Duration) -> u64 {
    u64::try_from(d.as_nanos()).unwrap_or(u64::MAX)
}

/// A value shared between a writer thread and the polling thread (the simulated rig's
/// physical state): a mutex held only to copy.
pub type Shared<T> = Arc<Mutex<T>>;
