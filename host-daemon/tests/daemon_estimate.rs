//! The live wall estimate end to end on the simulated rig: antennad streams an `estimate`
//! line after the samples of the poll it was made from, at `[estimate] rate_hz`, on the
//! daemon's clock, with the true wall of that poll beside it; the contact-line estimate is
//! within its bound of the truth, the ideal preview is the truth; bad `[estimate]` and
//! `[foxglove]` keys are refused with the file, line and key named.
#![allow(clippy::unwrap_used)]

mod net_support;

use antenna_data::stream::{EstimateMessage, StreamMessage};
use host_daemon::service::config::{Config, EstimatorName, MoveConfig};
use host_daemon::service::daemon::{Daemon, DaemonOptions};
use net_support::Client;
use std::collections::HashMap;
use std::time::Duration;

/// What a client saw of one trial.
struct Seen {
    /// `seq -> t_ns` of every samples line.
    samples: HashMap<u64, u64>,
    /// Each estimate, with the daemon clock's reading when its line arrived.
    estimates: Vec<(EstimateMessage, u64)>,
    /// Estimates whose samples line had not arrived before them.
    before_their_samples: usize,
    /// `lagged` lines (none expected: the client reads all the time).
    lagged: u64,
}

/// Runs the configuration's first trial (`moves`, then `hold_s` more) with a TCP client
/// reading every line until the daemon stops.
fn watch(mut config: Config) -> Seen {
    config.server.listen = "127.0.0.1:0".to_owned();
    config.server.token = Some(host_daemon::net::ControlToken::new(net_support::TOKEN).unwrap());
    let options = DaemonOptions {
        first_trial: Some(None),
        first_trial_duration: Some(Duration::ZERO),
        exit_after_trial: true,
        record: false,
        ..DaemonOptions::default()
    };
    let daemon = Daemon::start(config, options).unwrap();
    let clock = daemon.clock();
    let mut client = Client::connect(daemon.local_addr().unwrap());
    let mut seen = Seen {
        samples: HashMap::new(),
        estimates: Vec::new(),
        before_their_samples: 0,
        lagged: 0,
    };
    while let Some(line) = client.next_line() {
        let arrived_ns = clock.elapsed_ns();
        match serde_json::from_str::<StreamMessage>(&line).unwrap() {
            StreamMessage::Samples { seq, t_ns, .. } => {
                seen.samples.insert(seq, t_ns);
            }
            StreamMessage::Estimate(estimate) => {
                if seen.samples.get(&estimate.seq) != Some(&estimate.t_ns) {
                    seen.before_their_samples += 1;
                }
                seen.estimates.push((estimate, arrived_ns));
            }
            StreamMessage::Lagged { dropped, .. } => seen.lagged += dropped,
            _ => {}
        }
    }
    daemon.wait().unwrap();
    seen
}

/// The default rig (the thesis's 4.2.1 scene, the tip placed on the wall at the trial's
/// start) moving 60 mm along the wall at 30 mm/s.
fn along_the_wall(estimator: EstimatorName) -> Config {
    let mut config = Config::default();
    config.estimate.estimator = estimator;
    config.trials[0].moves = vec![MoveConfig {
        distance_mm: 60.0,
        speed_mm_per_s: 30.0,
        pause_s: 0.3,
    }];
    config
}

fn percentile(values: &mut [u64], p: f64) -> u64 {
    values.sort_unstable();
    values[((values.len() - 1) as f64 * p).round() as usize]
}

#[test]
fn the_contact_line_estimate_follows_its_poll_and_finds_the_wall() {
    let seen = watch(along_the_wall(EstimatorName::ContactLine));
    assert_eq!(seen.lagged, 0);
    assert!(!seen.estimates.is_empty(), "no estimate was streamed");
    assert_eq!(
        seen.before_their_samples, 0,
        "an estimate came before its samples"
    );
    let period_ns = 10_000_000; // the default rate_hz = 100
    let mut latencies = Vec::new();
    for pair in seen.estimates.windows(2) {
        // One estimate per period at most: the next is due a period after the last.
        assert!(
            pair[1].0.t_ns >= pair[0].0.t_ns + period_ns / 2,
            "{:?}",
            (&pair[0].0, &pair[1].0)
        );
    }
    let mut truth_known = false;
    for (e, arrived_ns) in &seen.estimates {
        assert_eq!(e.estimator, "contact-line");
        assert!(e.t_ns <= e.estimated_ns && e.estimated_ns <= *arrived_ns);
        latencies.push(arrived_ns - e.t_ns);
        // The simulated rig knows the truth from its first solve on (the polls before the
        // world is built sense its default state).
        truth_known |= e.true_distance_m.is_some();
        assert!(!truth_known || e.true_distance_m.is_some(), "{e:?}");
        assert_eq!(e.distance_m.is_some(), e.reason.is_none(), "{e:?}");
    }
    assert!(truth_known);
    // Against the truth: the wall at 8 degrees, the tip's points along it.
    let errors_mm: Vec<f64> = seen
        .estimates
        .iter()
        .filter_map(|(e, _)| Some((e.distance_m? - e.true_distance_m?) * 1e3))
        .collect();
    let angles_deg: Vec<f64> = seen
        .estimates
        .iter()
        .filter_map(|(e, _)| Some((e.angle_rad? - e.true_angle_rad?).to_degrees()))
        .collect();
    assert!(
        errors_mm.len() * 2 >= seen.estimates.len(),
        "{} estimates of {}",
        errors_mm.len(),
        seen.estimates.len()
    );
    let worst_mm = errors_mm.iter().fold(0.0f64, |m, e| m.max(e.abs()));
    let mean_mm = errors_mm.iter().sum::<f64>() / errors_mm.len() as f64;
    let worst_deg = angles_deg.iter().fold(0.0f64, |m, e| m.max(e.abs()));
    eprintln!(
        "contact-line: {} estimates, {} with a distance; error mean {mean_mm:.2} mm, worst \
         {worst_mm:.2} mm; angle worst {worst_deg:.2} deg; latency p50 {} us, p99 {} us",
        seen.estimates.len(),
        errors_mm.len(),
        percentile(&mut latencies, 0.5) / 1000,
        percentile(&mut latencies, 0.99) / 1000
    );
    assert!(worst_mm < 3.0, "worst distance error {worst_mm} mm");
    assert!(worst_deg < 5.0, "worst angle error {worst_deg} deg");
}

#[test]
fn the_ideal_preview_is_the_truth_and_the_bend_gives_no_angle() {
    let seen = watch(along_the_wall(EstimatorName::IdealPreview));
    assert!(!seen.estimates.is_empty());
    let mut truths = 0;
    for (e, _) in &seen.estimates {
        // Before the world's first solve there is no truth, and so no ideal preview.
        assert_eq!(e.distance_m, e.true_distance_m, "{e:?}");
        assert_eq!(e.angle_rad, None);
        if e.true_distance_m.is_some() {
            assert_eq!(e.preview_m, Some(0.0));
            truths += 1;
        }
    }
    assert!(
        truths * 2 > seen.estimates.len(),
        "{truths} of {}",
        seen.estimates.len()
    );
    let seen = watch(along_the_wall(EstimatorName::Bend));
    assert!(!seen.estimates.is_empty());
    assert!(seen.estimates.iter().all(|(e, _)| e.angle_rad.is_none()));
    let errors_mm: Vec<f64> = seen
        .estimates
        .iter()
        .filter_map(|(e, _)| Some((e.distance_m? - e.true_distance_m?) * 1e3))
        .collect();
    assert!(
        !errors_mm.is_empty(),
        "the bend estimator never estimated: {:?}",
        seen.estimates
            .iter()
            .map(|(e, _)| e.reason.clone())
            .collect::<std::collections::BTreeSet<_>>()
    );
    let worst_mm = errors_mm.iter().fold(0.0f64, |m, e| m.max(e.abs()));
    eprintln!(
        "bend: {} estimates, worst error {worst_mm:.1} mm",
        errors_mm.len()
    );
}

#[test]
fn no_estimate_when_none_is_asked_for() {
    let seen = watch(along_the_wall(EstimatorName::None));
    assert!(!seen.samples.is_empty());
    assert!(seen.estimates.is_empty());
}

#[test]
fn bad_estimate_and_foxglove_keys_are_refused_with_the_key_named() {
    for (text, key) in [
        ("[estimate]\nwindow_s = 0.0\n", "estimate.window_s"),
        ("[estimate]\nrate_hz = 5000.0\n", "estimate.rate_hz"),
        ("[estimate]\nestimator = \"kalman\"\n", "estimator"),
        ("[estimate]\nwall_side = \"up\"\n", "wall_side"),
        ("[estimate]\nwindow = 1.0\n", "window"),
        (
            "[estimate]\nestimator = \"ideal-preview\"\n[servo]\nport = \"/dev/ttyACM0\"\n",
            "estimate.estimator",
        ),
        ("[foxglove]\nscene_hz = 0.0\n", "foxglove.scene_hz"),
        ("[foxglove]\nscene_hz = 2000.0\n", "foxglove.scene_hz"),
        ("[foxglove]\nlisten = \"everywhere\"\n", "foxglove.listen"),
        ("[foxglove]\nrequired = \"yes\"\n", "required"),
        ("[foxglove]\nport = 8765\n", "port"),
    ] {
        let error = Config::from_toml_str(text, "estimate.toml")
            .unwrap_err()
            .to_string();
        assert!(error.contains(key), "{text:?}: {error}");
        let located = error
            .strip_prefix("estimate.toml:")
            .is_some_and(|rest| rest.starts_with(|c: char| c.is_ascii_digit()));
        assert!(located, "{text:?}: not located: {error}");
    }
}
