//! The polling thread polls on absolute deadlines; NACK storms, PEC errors and a stuck
//! counter are recorded per segment while the others keep polling, and no sample that is
//! delivered is lost or corrupted.
#![allow(clippy::unwrap_used)]

use antenna_protocol::{Calibration, Direction};
use host_daemon::service::acquisition::{
    AcquisitionEvent, FIRMWARE_READ_INTERVAL, FirmwareReading, HealthChange, PollSettings,
    event_channel, spawn_poller,
};
use host_daemon::service::clock::TrialClock;
use host_daemon::{PollError, Poller, SegmentFault, SimBus, SimBusError, SimSegment};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

const SEGMENTS: usize = 9;

/// How long a wait for the poller may take before the test fails: only a hang takes this
/// long, however loaded the machine.
const PATIENCE: Duration = Duration::from_secs(60);

fn wait_until(what: &str, mut ok: impl FnMut() -> bool) {
    let deadline = std::time::Instant::now() + PATIENCE;
    while !ok() {
        assert!(
            std::time::Instant::now() < deadline,
            "timed out waiting for {what}"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn calibration(k: usize) -> Calibration {
    Calibration::new(1000 + 200 * k as u16, Direction::CounterClockwise)
}

fn angle(k: usize, poll: u64) -> f64 {
    // Every segment moves, each along its own ramp.
    -0.8 + 0.1 * k as f64 + 0.0005 * poll as f64
}

#[test]
fn faults_are_marked_per_segment_while_the_others_keep_polling_on_deadlines() {
    let addresses: Vec<u8> = (0..SEGMENTS as u8).map(|k| 0x30 + k).collect();
    let bus = SimBus::new(
        (0..SEGMENTS)
            .map(|k| SimSegment::new(addresses[k], calibration(k)))
            .collect(),
    );
    let period = Duration::from_millis(1);
    let (events, receiver) = event_channel(100_000);
    let stop = Arc::new(AtomicBool::new(false));
    let mut poll = 0u64;
    // Faults by poll number: a NACK storm on segment 2 (polls 50..150), corrupted transfers
    // on segment 4 (100..200), segment 6's main loop stuck from poll 100 on.
    let hook = move |bus: &mut SimBus, _t: Duration| {
        let fault = |k: usize| match k {
            2 if (50..150).contains(&poll) => SegmentFault::Nack,
            4 if (100..200).contains(&poll) => SegmentFault::CorruptPec,
            6 if poll >= 100 => SegmentFault::StuckCounter,
            _ => SegmentFault::None,
        };
        for k in 0..SEGMENTS {
            let segment = bus.segment_mut(k).unwrap();
            segment.set_fault(fault(k));
            segment.set_angle_rad(angle(k, poll));
        }
        bus.sample_all();
        poll += 1;
    };
    let clock = TrialClock::start();
    let handle = spawn_poller(
        Poller::new(bus, &addresses),
        clock,
        PollSettings {
            period,
            counter_check_every: 10,
            spin: Duration::from_micros(100),
            realtime_priority: 0,
        },
        hook,
        events,
        Arc::clone(&stop),
    )
    .unwrap();
    // Run until 300 polls have arrived and 20 more after the stuck counter was found (the
    // check comes round on deadlines, which a loaded machine skips), however long that takes;
    // counted in polls, so a check that never comes ends the test.
    let mut events: Vec<AcquisitionEvent> = Vec::new();
    let mut seen = 0;
    let mut stale_found_at = None;
    while (seen < 300 || stale_found_at.is_none_or(|at| seen < at + 20)) && seen < 100_000 {
        let event = receiver.recv_timeout(PATIENCE).unwrap();
        seen += usize::from(matches!(event, AcquisitionEvent::Poll(_)));
        if matches!(event, AcquisitionEvent::Health { .. }) {
            stale_found_at.get_or_insert(seen);
        }
        events.push(event);
    }
    stop.store(true, Ordering::Relaxed);
    let report = handle.join().unwrap();
    events.extend(receiver.try_iter());
    let polls: Vec<_> = events
        .iter()
        .filter_map(|e| match e {
            AcquisitionEvent::Poll(p) => Some(p),
            _ => None,
        })
        .collect();
    // Every poll made was delivered.
    assert_eq!(polls.len() as u64, report.polls);
    // Absolute deadlines: deadline = seq * period exactly, woken at or after it, and the
    // sequence only skips deadlines the thread reports as skipped.
    let mut expected_seq = 0;
    for p in &polls {
        assert_eq!(p.deadline_ns, p.seq * 1_000_000);
        assert!(p.t_ns >= p.deadline_ns);
        assert!(p.seq >= expected_seq);
        expected_seq = p.seq + 1;
    }
    // Every deadline up to the last poll was either polled or counted as skipped, the first
    // ones too: a loaded machine can skip deadline 0 (seen once in a flake hunt under load:
    // 7 gaps between polls, 8 skipped).
    let last_seq = polls.last().map_or(0, |p| p.seq + 1);
    assert_eq!(last_seq - polls.len() as u64, report.skipped);

    // Each delivered word is the angle the segment was given at that poll (the hook's poll
    // counter counts the polls made, so poll index i saw angle(k, i)).
    for (i, p) in polls.iter().enumerate() {
        for (k, reading) in p.readings.iter().enumerate() {
            let i = i as u64;
            match (k, &reading.result) {
                (2, Err(PollError::Nack { address })) => {
                    assert!((50..150).contains(&i));
                    assert_eq!(*address, addresses[2]);
                }
                (4, Err(PollError::Corrupted { .. })) => assert!((100..200).contains(&i)),
                (_, Ok(word)) => {
                    let got = calibration(k).angle_rad(word.angle_counts());
                    // A stuck segment keeps serving its last word.
                    let want = if k == 6 && i >= 100 {
                        angle(6, 99)
                    } else {
                        angle(k, i)
                    };
                    assert!(
                        (got - want).abs() < 0.002,
                        "segment {k} poll {i}: {got} vs {want}"
                    );
                }
                (k, Err(e)) => panic!("segment {k} poll {i}: unexpected {e}"),
            }
        }
    }
    let health = &report.health;
    assert_eq!(health[2].nacks, 100);
    assert_eq!(health[4].pec_errors, 100);
    for k in [0, 1, 3, 5, 7, 8] {
        assert!(health[k].all_ok(), "segment {k}: {:?}", health[k]);
        assert_eq!(health[k].ok, report.polls);
    }
    // The stuck counter is reported once as a change, and marked in every later poll.
    let stale_events: Vec<_> = events
        .iter()
        .filter_map(|e| match e {
            AcquisitionEvent::Health {
                address, change, ..
            } => Some((*address, *change)),
            _ => None,
        })
        .collect();
    assert_eq!(stale_events, vec![(addresses[6], HealthChange::Stale)]);
    // Unmarked before it stuck, marked in every poll from the one that found it on.
    let found = polls
        .iter()
        .position(|p| p.stale_mask != 0)
        .expect("a poll marked stale");
    assert!(found >= 100, "marked stale at poll {found}");
    assert!(polls[found..].iter().all(|p| p.stale_mask == 1 << 6));
    // Counted stale at every check from then on: segment 6's slot of each 10-deadline cycle
    // (9 counter checks and one poll left for the firmware registers).
    let checks: Vec<u64> = polls[found..]
        .iter()
        .filter(|p| p.seq % 10 == 6)
        .map(|p| p.seq)
        .collect();
    assert_eq!(checks.first(), Some(&polls[found].seq));
    assert_eq!(report.health[6].stale, checks.len() as u64);
}

#[test]
fn a_full_queue_drops_and_counts_without_delaying_polls() {
    let bus = SimBus::new(vec![SimSegment::new(0x21, Calibration::default())]);
    let (events, receiver) = event_channel(5);
    let counter = events.clone();
    let stop = Arc::new(AtomicBool::new(false));
    let handle = spawn_poller(
        Poller::new(bus, &[0x21]),
        TrialClock::start(),
        PollSettings {
            period: Duration::from_millis(2),
            counter_check_every: 5,
            spin: Duration::ZERO,
            realtime_priority: 0,
        },
        |bus: &mut SimBus, _| bus.sample_all(),
        events,
        Arc::clone(&stop),
    )
    .unwrap();
    // Nobody reads the queue: the poller keeps polling, its events dropped and counted.
    wait_until("100 events dropped", || counter.dropped() >= 100);
    stop.store(true, Ordering::Relaxed);
    let report = handle.join().unwrap();
    // 5 events fit, the rest were dropped and counted.
    assert_eq!(receiver.try_iter().count(), 5);
    // Besides the polls, a firmware register read is sent every FIRMWARE_READ_INTERVAL
    // (250 ms of the poller's clock): the first at once, then at most one for each interval
    // its deadlines (made or skipped, 2 ms apart) spanned.
    let dropped = counter.dropped();
    let firmware_reads = (dropped + 5).checked_sub(report.polls);
    let deadlines = report.polls + report.skipped;
    let most = 2 + deadlines * 2 / FIRMWARE_READ_INTERVAL.as_millis() as u64;
    assert!(
        firmware_reads.is_some_and(|n| (1..=most).contains(&n)),
        "{dropped} dropped of {} polls ({} skipped)",
        report.polls,
        report.skipped
    );
}

/// A simulated bus that counts its transfers.
struct CountingBus {
    bus: SimBus,
    transfers: Arc<AtomicU64>,
}

impl embedded_hal::i2c::ErrorType for CountingBus {
    type Error = SimBusError;
}

impl embedded_hal::i2c::I2c for CountingBus {
    fn transaction(
        &mut self,
        address: u8,
        operations: &mut [embedded_hal::i2c::Operation<'_>],
    ) -> Result<(), SimBusError> {
        self.transfers.fetch_add(1, Ordering::Relaxed);
        self.bus.transaction(address, operations)
    }
}

#[test]
fn housekeeping_is_one_register_read_per_poll_at_most_and_reads_the_firmware() {
    let addresses: Vec<u8> = (0..SEGMENTS as u8).map(|k| 0x30 + k).collect();
    let transfers = Arc::new(AtomicU64::new(0));
    let bus = CountingBus {
        bus: SimBus::new(
            (0..SEGMENTS)
                .map(|k| SimSegment::new(addresses[k], calibration(k)))
                .collect(),
        ),
        transfers: Arc::clone(&transfers),
    };
    // Transfers made by each poll, as the next poll's hook finds them.
    let per_poll = Arc::new(Mutex::new(Vec::new()));
    let seen = Arc::clone(&per_poll);
    let hook = move |bus: &mut CountingBus, _: Duration| {
        let made = bus.transfers.swap(0, Ordering::Relaxed);
        seen.lock().unwrap().push(made);
        // Segment 3's main loop stops after a while: its counter is still checked.
        if seen.lock().unwrap().len() == 200 {
            bus.bus
                .segment_mut(3)
                .unwrap()
                .set_fault(SegmentFault::StuckCounter);
        }
        bus.bus.sample_all();
    };
    let (events, receiver) = event_channel(100_000);
    let stop = Arc::new(AtomicBool::new(false));
    let handle = spawn_poller(
        Poller::new(bus, &addresses),
        TrialClock::start(),
        PollSettings {
            period: Duration::from_millis(1),
            // Shorter than the segments: the cycle is stretched to 10 polls.
            counter_check_every: 4,
            spin: Duration::ZERO,
            realtime_priority: 0,
        },
        hook,
        events,
        Arc::clone(&stop),
    )
    .unwrap();
    // Three firmware reads (about 0.5 s), and the stuck counter found (polls are counted, so
    // a broken check ends the test rather than hanging it).
    let mut firmware = Vec::new();
    let mut stale = Vec::new();
    let mut polls_seen = 0u64;
    while (firmware.len() < 3 || stale.is_empty()) && polls_seen < 100_000 {
        match receiver.recv_timeout(PATIENCE).unwrap() {
            AcquisitionEvent::Poll(_) => polls_seen += 1,
            AcquisitionEvent::Firmware {
                address, reading, ..
            } => firmware.push((address, reading)),
            AcquisitionEvent::Health {
                address, change, ..
            } => stale.push((address, change)),
            _ => {}
        }
    }
    stop.store(true, Ordering::Relaxed);
    let report = handle.join().unwrap();
    // Each segment's status, then its version, then the next segment's; healthy flags.
    assert_eq!(
        firmware[..3],
        vec![
            (addresses[0], FirmwareReading::Status(Default::default())),
            (addresses[0], FirmwareReading::Version(1, 0)),
            (addresses[1], FirmwareReading::Status(Default::default())),
        ]
    );
    // Two intervals passed between the first read and the third: 500 deadlines of 1 ms,
    // polled or skipped (half of them asserted, as before).
    assert!(
        report.polls + report.skipped >= 2 * FIRMWARE_READ_INTERVAL.as_millis() as u64 / 2,
        "{} polls, {} skipped",
        report.polls,
        report.skipped
    );
    // Every poll: nine sample reads and at most one register read.
    let per_poll = per_poll.lock().unwrap();
    assert!(per_poll.len() > 200, "{}", per_poll.len());
    assert!(
        per_poll[1..]
            .iter()
            .all(|&n| n == SEGMENTS as u64 || n == SEGMENTS as u64 + 1),
        "{per_poll:?}"
    );
    // The counters are still checked, one segment at a time: the stuck one is found.
    assert_eq!(stale, vec![(addresses[3], HealthChange::Stale)]);
    assert!(report.health[3].stale >= 1);
}
