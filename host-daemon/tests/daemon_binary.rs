//! The `antennad` binary end to end: a short trial on the simulated rig prints sample lines
//! and its summary, records every poll to MCAP, and a bad configuration is a clear error.
#![allow(clippy::unwrap_used)]

use host_daemon::record::TrialReader;
use std::process::Command;

#[test]
fn a_short_trial_is_printed_recorded_and_streamed() {
    let dir = std::env::temp_dir().join(format!("antennad-bin-{}", std::process::id()));
    let output = Command::new(env!("CARGO_BIN_EXE_antennad"))
        .args([
            "--duration-s",
            "1.5",
            "--listen",
            "127.0.0.1:0",
            "--data-dir",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(stdout.contains("watch it with: nc 127.0.0.1 "), "{stdout}");
    assert!(
        stdout.contains("-- move 1: +150.0 mm at 30 mm/s"),
        "{stdout}"
    );
    // "antennad: N polls in ..." and the recording's own count agree.
    let polls: u64 = stdout
        .lines()
        .find_map(|l| {
            l.strip_prefix("antennad: ")?
                .split_once(" polls in ")?
                .0
                .parse()
                .ok()
        })
        .unwrap();
    let trial = TrialReader::read(dir.join("wall-sweep.mcap")).unwrap();
    assert!(trial.truncated.is_none());
    assert_eq!(trial.segments.len() as u64, polls);
    assert!(polls > 500);
    assert!(
        trial
            .segments
            .iter()
            .all(|m| m.segments.len() == 9 && m.segments.iter().all(|s| s.ok))
    );
    assert!(trial.stage.last().unwrap().position_m > 0.02);
    assert_eq!(trial.metadata.unwrap().notes["wall"], "simulated flat wall");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_bad_configuration_names_the_key_and_exits_with_failure() {
    let path = std::env::temp_dir().join(format!("antennad-bad-{}.toml", std::process::id()));
    std::fs::write(&path, "[bus]\npoll_hz = 0.0\n").unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_antennad"))
        .arg("--config")
        .arg(&path)
        .output()
        .unwrap();
    std::fs::remove_file(&path).ok();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(
        stderr.contains(":2:1: `bus.poll_hz`: must be in (0, 10000]"),
        "{stderr}"
    );
}
