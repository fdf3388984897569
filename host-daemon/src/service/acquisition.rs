//! Acquisition: the polling thread and the motion thread, on one [`TrialClock`], feeding one
//! bounded channel of [`AcquisitionEvent`]s.
//!
//! - **Polling** ([`spawn_poller`]): a dedicated thread wakes on absolute deadlines
//!   (`start + k * period`, [`Schedule`]), reads every segment through the [`Poller`]
//!   (PEC-checked 3-byte reads), stamps the poll with the time since the trial started and
//!   sends it. After the reads it makes at most one housekeeping register read, round-robin,
//!   so every poll costs the bus the same (`crate::hardware::bus_budget`): in each cycle of
//!   `counter_check_every` polls (at least one more than there are segments) the first polls
//!   read one segment's sample counter each, and a counter that has not moved marks the
//!   segment stale ([`PollRecord::stale_mask`]); in the others, every
//!   [`FIRMWARE_READ_INTERVAL`], the next segment's status register or firmware version
//!   ([`AcquisitionEvent::Firmware`]: each segment's status every few seconds). A NACK, a PEC
//!   error, a bus error or a stale counter is recorded in the segment's health and the poll
//!   goes on. After every poll the thread beats its [`PollHeartbeat`], which the daemon's
//!   watchdog reads ([`crate::service::watchdog`]): a poll stuck in the I2C driver is seen from
//!   outside.
//! - **Motion**: the motion thread (`crate::service::motion`, the daemon's one motion loop) samples
//!   the stage position and the base angle at their own rates under the same clock and sends
//!   them into the same stream.
//! - **The stream** ([`EventSender`]): a bounded channel written with `try_send`. A full
//!   consumer queue never delays polling: the event is dropped and counted
//!   ([`EventSender::dropped`]); size the queue so that never happens (the main loop
//!   forwards events to the recorder and the TCP server, which have their own queues).

use crate::hardware::poll::{CounterCheck, PollError, Poller, SegmentHealth, SegmentReading};
use crate::service::clock::{Schedule, TrialClock};
use crate::service::watchdog::PollHeartbeat;
use antenna_protocol::StatusFlags;
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

/// How often the polling thread reads a firmware register (status or version, one segment
/// at a time, round-robin): with 9 segments each one's status every 4.5 s.
pub const FIRMWARE_READ_INTERVAL: Duration = Duration::from_millis(250);

/// What a read of a segment's firmware registers found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FirmwareReading {
    /// The status register (0x02): the firmware's own fault flags.
    Status(StatusFlags),
    /// The firmware version register (0x01): (major, minor).
    Version(u8, u8),
    /// The read failed (it is not counted in the segment's health, which counts polls).
    Unread(PollError),
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
    /// A segment's firmware register, read at a low rate.
    Firmware {
        /// Nanoseconds since the trial started.
        t_ns: u64,
        /// The segment.
        address: u8,
        /// What the read found.
        reading: FirmwareReading,
    },
    /// One placement or step of the simulated rig's physics (recorded on `/sim/physics`).
    Physics {
        /// Nanoseconds since the trial started: when the step was made.
        t_ns: u64,
        /// The step: its base pose and the joint angles it gave.
        step: Box<crate::sim::rig::PhysicsStep>,
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
    /// Read each segment's sample counter every this many polls (one segment per poll, so
    /// at least one poll more than there are segments).
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
    poller: Poller<I>,
    clock: TrialClock,
    settings: PollSettings,
    before_poll: H,
    events: EventSender,
    stop: Arc<AtomicBool>,
) -> std::io::Result<JoinHandle<PollReport<I>>>
where
    I: I2c + Send + 'static,
    H: FnMut(&mut I, Duration) + Send + 'static,
{
    let heartbeat = Arc::new(PollHeartbeat::new(clock.elapsed_ns()));
    spawn_watched_poller(
        poller,
        clock,
        settings,
        before_poll,
        events,
        stop,
        heartbeat,
    )
}

/// [`spawn_poller`], beating `heartbeat` after every poll for a watchdog to read.
pub fn spawn_watched_poller<I, H>(
    mut poller: Poller<I>,
    clock: TrialClock,
    settings: PollSettings,
    mut before_poll: H,
    events: EventSender,
    stop: Arc<AtomicBool>,
    heartbeat: Arc<PollHeartbeat>,
) -> std::io::Result<JoinHandle<PollReport<I>>>
where
    I: I2c + Send + 'static,
    H: FnMut(&mut I, Duration) + Send + 'static,
{
    std::thread::Builder::new()
        .name("antennad-poll".to_owned())
        .spawn(move || {
            crate::hardware::realtime::minimize_timer_slack();
            if settings.realtime_priority > 0 {
                let text = match crate::hardware::realtime::request_fifo(settings.realtime_priority)
                {
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
            let addresses = poller.addresses().to_vec();
            let segments = addresses.len() as u64;
            // One counter read per poll for the first `segments` polls of each cycle; at
            // least one poll per cycle is left for the firmware registers.
            let cycle = u64::from(settings.counter_check_every.max(1)).max(segments + 1);
            let mut firmware_due = Duration::ZERO;
            let mut firmware_next = 0usize;
            let mut stale_mask = 0u64;
            let mut skipped = 0;
            let mut max_lateness = Duration::ZERO;
            while !stop.load(Ordering::Relaxed) {
                let tick = schedule.wait_next();
                skipped += tick.skipped;
                max_lateness = max_lateness.max(tick.lateness());
                before_poll(poller.bus_mut(), tick.woke);
                let readings = poller.poll_all();
                let slot = tick.index % cycle;
                if slot < segments {
                    let k = slot as usize;
                    let check = poller.check_counter(k);
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
                            t_ns: clock.elapsed_ns(),
                            address: addresses[k],
                            change,
                        });
                    }
                } else if tick.woke >= firmware_due && !addresses.is_empty() {
                    firmware_due = tick.woke + FIRMWARE_READ_INTERVAL;
                    // Each segment's status, then its version, then the next segment's.
                    let k = (firmware_next / 2) % addresses.len();
                    let reading = if firmware_next.is_multiple_of(2) {
                        poller
                            .read_status(k)
                            .map_or_else(FirmwareReading::Unread, FirmwareReading::Status)
                    } else {
                        poller
                            .read_version(k)
                            .map_or_else(FirmwareReading::Unread, |v| {
                                FirmwareReading::Version(v.0, v.1)
                            })
                    };
                    firmware_next = (firmware_next + 1) % (2 * addresses.len());
                    events.send(AcquisitionEvent::Firmware {
                        t_ns: clock.elapsed_ns(),
                        address: addresses[k],
                        reading,
                    });
                }
                heartbeat.beat(clock.elapsed_ns(), tick.skipped);
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
