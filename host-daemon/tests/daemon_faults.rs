//! Faults at the daemon's level, in-process on the simulated rig: a NACK storm, PEC errors and
//! a stuck counter injected into three segments (`sim.faults`) while a stalled client and a
//! garbage-sending client are connected. The daemon keeps polling, streaming and recording;
//! each fault is marked on its segment only, in the stream and in the recording, and no
//! recorded poll is lost or corrupted.
#![allow(clippy::unwrap_used)]

mod net_support;

use antenna_data::record::TrialReader;
use antenna_data::stream::StreamMessage;
use host_daemon::service::config::{Config, SimFaultConfig, SimFaultKind};
use host_daemon::service::daemon::{Daemon, DaemonOptions};
use net_support::{Client, TOKEN};
use std::io::Write;
use std::net::TcpStream;
use std::time::Duration;

#[test]
fn nack_storms_pec_errors_and_a_stuck_counter_are_marked_and_nothing_is_lost() {
    let dir = std::env::temp_dir().join(format!("antennad-faults-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    let mut config = Config::default();
    config.server.listen = "127.0.0.1:0".to_owned();
    config.server.token = Some(host_daemon::net::ControlToken::new(TOKEN).unwrap());
    config.data_dir = dir.clone();
    config.bus.poll_hz = 500.0;
    config.bus.counter_check_every = 25;
    let fault = |address, kind, from_s, until_s| SimFaultConfig {
        address,
        kind,
        from_s,
        until_s,
    };
    config.sim.faults = vec![
        fault(0x22, SimFaultKind::Nack, 0.8, 1.3),
        fault(0x24, SimFaultKind::Pec, 1.0, 1.5),
        fault(0x26, SimFaultKind::Stuck, 0.8, 1.8),
    ];
    config.trials[0].duration_s = 2.5;
    let options = DaemonOptions {
        first_trial: Some(None),
        exit_after_trial: true,
        ..DaemonOptions::default()
    };
    let daemon = Daemon::start(config, options).unwrap();
    let addr = daemon.local_addr().unwrap();
    // A client that never reads, and one that sends garbage.
    let stalled = TcpStream::connect(addr).unwrap();
    let mut garbage = TcpStream::connect(addr).unwrap();
    let mut noise = Vec::new();
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    for _ in 0..200_000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        noise.push((x >> 24) as u8);
    }
    garbage.write_all(&noise).ok();
    // A client that reads everything: consecutive polls, the faults on their segments only.
    let mut client = Client::connect(addr);
    let (mut nacks, mut pecs, mut stale) = (0, 0, 0);
    let mut last_seq = None;
    let mut stream_gaps = 0;
    let mut samples = 0;
    while samples < 800 {
        match client.next_message() {
            StreamMessage::Samples { seq, segments, .. } => {
                if let Some(last) = last_seq {
                    // A jump is only ever a deadline the poller skipped (checked below).
                    assert!(seq > last);
                    stream_gaps += seq - last - 1;
                }
                last_seq = Some(seq);
                samples += 1;
                for s in &segments {
                    // A failed read has no touch bits; a read has all four, `contact` any.
                    match s.error {
                        Some(_) => assert_eq!((s.contact, s.touch_bits), (None, None)),
                        None => {
                            let bits = s.touch_bits.unwrap_or_else(|| panic!("no bits: {s:?}"));
                            assert_eq!(s.contact, Some(bits != 0), "{s:?}");
                        }
                    }
                    match (s.address, s.error.as_deref(), s.stale) {
                        (0x22, Some("nack"), false) => nacks += 1,
                        (0x24, Some("pec"), false) => pecs += 1,
                        (0x26, None, true) => stale += 1,
                        (_, None, false) => assert!(s.angle_rad.is_some()),
                        other => panic!("unexpected {other:?} at poll {seq}"),
                    }
                }
            }
            StreamMessage::Lagged { dropped, .. } => panic!("{dropped} dropped for a reader"),
            _ => {}
        }
    }
    assert!(
        nacks > 50 && pecs > 50 && stale > 50,
        "{nacks} {pecs} {stale}"
    );
    while !daemon.is_finished() {
        std::thread::sleep(Duration::from_millis(20));
    }
    let log = daemon.log_lines();
    let summary = daemon.wait().unwrap();
    drop((stalled, garbage));
    assert_eq!(summary.dropped, 0);
    assert!(
        stream_gaps <= summary.skipped,
        "{stream_gaps} > {}",
        summary.skipped
    );
    // 0.5 s at 500 Hz: 250 polls, less any deadline skipped on a loaded machine.
    let window = 250 - summary.skipped.min(250);
    let nacks = summary.health[2].nacks;
    let pecs = summary.health[4].pec_errors;
    assert!((window..=251).contains(&nacks), "{nacks}, {summary:?}");
    assert!((window..=251).contains(&pecs), "{pecs}, {summary:?}");
    assert!(summary.health[6].stale >= 3, "{:?}", summary.health[6]);
    for k in [0, 1, 3, 5, 7] {
        assert!(summary.health[k].all_ok(), "{k}: {:?}", summary.health[k]);
    }

    let trial = TrialReader::read(summary.trials[0].path.as_ref().unwrap()).unwrap();
    assert!(trial.truncated.is_none());
    let seqs: Vec<u64> = trial.segments.iter().map(|m| m.seq.unwrap()).collect();
    let gaps: u64 = seqs.windows(2).map(|w| w[1] - w[0] - 1).sum();
    assert!(
        gaps <= summary.skipped,
        "{gaps} gaps, {} skipped",
        summary.skipped
    );
    // Every fault is on its segment, for its whole window (250 polls at 500 Hz), once.
    let flagged = |k: usize, f: fn(&antenna_data::record::SegmentSample) -> bool| -> Vec<u64> {
        trial
            .segments
            .iter()
            .filter(|m| f(&m.segments[k]))
            .map(|m| m.seq.unwrap())
            .collect()
    };
    for (k, f) in [
        (
            2,
            (|s| s.nack) as fn(&antenna_data::record::SegmentSample) -> bool,
        ),
        (4, |s| s.pec_error),
    ] {
        let polls = flagged(k, f);
        assert!(
            (window as usize..=251).contains(&polls.len()),
            "segment {k}"
        );
        // Its first and last poll span the window, less the deadlines skipped (a skipped
        // deadline at either end shortens it).
        let (first, last) = (polls[0], polls[polls.len() - 1]);
        assert!(
            (248 - summary.skipped.min(248)..=251).contains(&(last - first)),
            "segment {k}: {first}..={last}, {} skipped",
            summary.skipped
        );
        // One unbroken window: every recorded poll inside it is flagged.
        let inside = seqs
            .iter()
            .filter(|&&q| (first..=last).contains(&q))
            .count();
        assert_eq!(inside, polls.len(), "segment {k}");
    }
    let stuck = flagged(6, |s| s.stale);
    // 1 s at 500 Hz, less the polls before the check found it and any deadline skipped.
    assert!(
        stuck.len() as u64 + summary.skipped > 300 && stuck.len() <= 525,
        "{}, {} skipped",
        stuck.len(),
        summary.skipped
    );
    for m in &trial.segments {
        for (k, s) in m.segments.iter().enumerate() {
            let faulty = (k == 2 && s.nack) || (k == 4 && s.pec_error);
            assert_eq!(s.ok, !faulty, "poll {:?} segment {k}", m.seq);
            assert_eq!(s.angle_counts.is_some(), s.ok);
            assert!(!s.bus_error);
        }
    }
    let log = log.join("\n");
    assert!(
        log.contains("segment 0x26: counter stopped (stale)"),
        "{log}"
    );
    assert!(log.contains("segment 0x26: counter moving again"), "{log}");
    std::fs::remove_dir_all(&dir).ok();
}
