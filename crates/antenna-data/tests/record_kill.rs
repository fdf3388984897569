//! `kill -9` during a trial: the `record-until-killed` helper records the synthetic trial
//! with its 100 ms flushes and is killed with SIGKILL; the file reads back at least every
//! sample it reported flushed, each one intact, and opens as it is in Python's `mcap` reader,
//! its Foxglove channels decoded by `mcap-protobuf-support` (`tests/python/read_foxglove.py`;
//! `scripts/setup` installs both).
#![allow(clippy::unwrap_used)]

use std::io::{BufRead as _, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};

use antenna_data::record::{
    TrialReader, synthetic_estimate, synthetic_metadata, synthetic_rig, synthetic_segments,
    synthetic_servo, synthetic_stage,
};

#[test]
fn a_trial_killed_with_sigkill_reads_back_up_to_its_last_flush() {
    let path = std::env::temp_dir().join(format!("record-kill-{}.mcap", std::process::id()));
    let mut child = Command::new(env!("CARGO_BIN_EXE_record-until-killed"))
        .arg(&path)
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let mut flushed = 0u64;
    for line in BufReader::new(stdout).lines() {
        let line = line.unwrap();
        flushed = line.strip_prefix("flushed ").unwrap().parse().unwrap();
        if flushed >= 500 {
            break;
        }
    }
    // Child::kill sends SIGKILL on Unix: no destructor, no footer.
    child.kill().unwrap();
    let status = child.wait().unwrap();
    assert!(!status.success());

    let trial = TrialReader::read(&path).unwrap();
    assert!(
        trial.truncated.is_some(),
        "a killed recorder leaves no footer"
    );
    let mut metadata = synthetic_metadata("killed");
    metadata.rig = Some(synthetic_rig(9));
    assert_eq!(trial.metadata, Some(metadata));
    let n = trial.segments.len() as u64;
    assert!(n >= flushed, "{n} polls read back, {flushed} were flushed");
    for (i, message) in trial.segments.iter().enumerate() {
        assert_eq!(*message, synthetic_segments(i as u64, 9), "poll {i}");
    }
    for (i, message) in trial.stage.iter().enumerate() {
        assert_eq!(*message, synthetic_stage(i as u64), "stage {i}");
    }
    for (i, message) in trial.servo.iter().enumerate() {
        assert_eq!(*message, synthetic_servo(i as u64), "servo {i}");
    }
    for (i, message) in trial.estimate.iter().enumerate() {
        assert_eq!(*message, synthetic_estimate(i as u64), "estimate {i}");
    }
    assert_eq!(trial.stage.len() as u64, n.div_ceil(10));
    assert_eq!(trial.estimate.len() as u64, n.div_ceil(10));
    assert_eq!(trial.servo.len() as u64, n.div_ceil(20));
    assert!(trial.foxglove_messages > 0);

    // Python's standard reader opens the file as it is and decodes its Foxglove channels.
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/python/read_foxglove.py");
    let out = Command::new("python3")
        .arg(&script)
        .arg(&path)
        .output()
        .expect("python3 (scripts/setup installs it with mcap and mcap-protobuf-support)");
    assert!(
        out.status.success(),
        "read_foxglove.py failed on the killed file ({}):\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let python: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        python["transforms"].as_u64(),
        Some(trial.foxglove_messages / 2),
        "{python}"
    );
    std::fs::remove_file(&path).unwrap();
}
