//! `kill -9` during a trial: the `record-until-killed` helper records the synthetic trial
//! with its 100 ms flushes and is killed with SIGKILL; the file reads back at least every
//! sample it reported flushed, each one intact.
#![allow(clippy::unwrap_used)]

use std::io::{BufRead as _, BufReader};
use std::process::{Command, Stdio};

use antenna_data::record::{
    TrialReader, synthetic_metadata, synthetic_segments, synthetic_servo, synthetic_stage,
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
    assert_eq!(trial.metadata, Some(synthetic_metadata("killed")));
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
    assert_eq!(trial.stage.len() as u64, n.div_ceil(10));
    assert_eq!(trial.servo.len() as u64, n.div_ceil(20));
    std::fs::remove_file(&path).unwrap();
}
