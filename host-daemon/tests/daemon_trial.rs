//! Short simulated trials end to end: the stage carries the antenna along the wall and the
//! segments' angles and touch bits change; a move beyond the soft limits is refused.
#![allow(clippy::unwrap_used)]

use host_daemon::service::acquisition::AcquisitionEvent;
use host_daemon::service::config::{Config, MoveConfig};
use host_daemon::service::daemon::{Daemon, DaemonOptions, DaemonSummary, EventTap};
use std::sync::{Arc, Mutex};
use std::time::Duration;

fn run(config: &Config) -> (DaemonSummary, Vec<AcquisitionEvent>) {
    let events = Arc::new(Mutex::new(Vec::new()));
    let tap = {
        let events = Arc::clone(&events);
        EventTap::new(move |e| events.lock().unwrap().push(e.clone()))
    };
    let options = DaemonOptions::tapped_trial(Duration::ZERO, tap); // until the moves are done
    let summary = Daemon::start(config.clone(), options)
        .unwrap()
        .wait()
        .unwrap();
    let events = std::mem::take(&mut *events.lock().unwrap());
    (summary, events)
}

#[test]
fn the_stage_carries_the_antenna_to_the_wall_and_the_segments_feel_it() {
    let mut config = Config::default();
    config.bus.poll_hz = 500.0;
    config.trials[0].moves = vec![MoveConfig {
        distance_mm: 100.0,
        speed_mm_per_s: 50.0,
        pause_s: 0.2,
    }];
    let calibrations = config.bus.calibrations();
    let (summary, events) = run(&config);
    assert_eq!((summary.moves_started, summary.moves_refused), (1, 0));
    assert_eq!(summary.dropped, 0);
    assert!(
        summary.health.iter().all(|h| h.all_ok()),
        "{:?}",
        summary.health
    );

    let stage: Vec<f64> = events
        .iter()
        .filter_map(|e| match e {
            AcquisitionEvent::Stage { position_mm, .. } => Some(*position_mm),
            _ => None,
        })
        .collect();
    assert!(
        stage.windows(2).all(|w| w[1] >= w[0]),
        "the stage only moves forward"
    );
    assert_eq!(stage.last().copied(), Some(100.0));
    // Two seconds at 50 mm/s, sampled at 50 Hz: positions in between were seen.
    assert!(stage.iter().filter(|&&mm| mm > 0.0 && mm < 100.0).count() > 20);

    let polls: Vec<_> = events
        .iter()
        .filter_map(|e| match e {
            AcquisitionEvent::Poll(p) => Some(p),
            _ => None,
        })
        .collect();
    assert_eq!(polls.len() as u64, summary.polls);
    let angles = |p: &host_daemon::service::acquisition::PollRecord| -> Vec<f64> {
        p.readings
            .iter()
            .zip(&calibrations)
            .map(|(r, c)| c.angle_rad(r.result.unwrap().angle_counts()))
            .collect()
    };
    // The trial places the antenna once the stage is homed: the first poll after that.
    let placed_ns = events
        .iter()
        .find_map(|e| match e {
            AcquisitionEvent::Physics { t_ns, step }
                if step.kind == host_daemon::sim::rig::StepKind::Place =>
            {
                Some(*t_ns)
            }
            _ => None,
        })
        .unwrap();
    let first = angles(polls.iter().find(|p| p.t_ns > placed_ns).unwrap());
    let last = angles(polls[polls.len() - 1]);
    // The built-in scene (the thesis's 4.2.1): placed with its tip on the wall, bent back
    // along it, every joint the same way; 100 mm on, the wall has closed in by 14 mm and the
    // bend has changed, the tip segment's switches closed throughout (once debounced).
    let max = |a: &[f64]| a.iter().fold(0f64, |m, x| m.max(x.abs()));
    assert!(max(&first).to_degrees() > 20.0, "{first:?}");
    assert!(first.iter().all(|&a| a > -0.002), "{first:?}");
    let moved = first
        .iter()
        .zip(&last)
        .fold(0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(moved.to_degrees() > 2.0, "{first:?} {last:?}");
    assert!(
        polls[polls.len() - 1]
            .readings
            .iter()
            .any(|r| r.result.unwrap().touch().any())
    );
    // Time stamps share one clock: the stage samples fall between the polls.
    let last_stage_t = events
        .iter()
        .filter_map(|e| match e {
            AcquisitionEvent::Stage { t_ns, .. } => Some(*t_ns),
            _ => None,
        })
        .max()
        .unwrap();
    assert!(last_stage_t <= polls[polls.len() - 1].t_ns + 50_000_000);
}

#[test]
fn a_move_beyond_the_soft_limits_is_refused_and_the_trial_goes_on() {
    let mut config = Config::default();
    config.bus.poll_hz = 200.0;
    config.stage.max_mm = 50.0;
    config.trials[0].moves = vec![
        MoveConfig {
            distance_mm: 80.0,
            speed_mm_per_s: 50.0,
            pause_s: 0.0,
        },
        MoveConfig {
            distance_mm: 20.0,
            speed_mm_per_s: 50.0,
            pause_s: 0.0,
        },
    ];
    let (summary, events) = run(&config);
    assert_eq!((summary.moves_started, summary.moves_refused), (1, 1));
    let notes: Vec<&str> = events
        .iter()
        .filter_map(|e| match e {
            AcquisitionEvent::Note { text, .. } => Some(text.as_str()),
            _ => None,
        })
        .collect();
    // The first note about the moves (a note on the polling thread's scheduling may come
    // before it).
    let first_move_note = notes.iter().find(|n| n.contains("move ")).copied();
    assert!(
        first_move_note.is_some_and(|n| n.contains("move 1 refused") && n.contains("soft limits")),
        "{notes:?}"
    );
    let stage_max = events
        .iter()
        .filter_map(|e| match e {
            AcquisitionEvent::Stage { position_mm, .. } => Some(*position_mm),
            _ => None,
        })
        .fold(f64::MIN, f64::max);
    assert_eq!(stage_max, 20.0);
}
