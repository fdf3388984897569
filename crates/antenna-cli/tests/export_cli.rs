//! `antenna export` from the command line: bad input exits 2 with a message naming the file,
//! and a trial cut short by a crash exports up to its last flush with a warning.
#![allow(clippy::unwrap_used)]

use std::path::PathBuf;
use std::process::{Command, Output};

use antenna_data::record::{TrialRecorder, synthetic_metadata, synthetic_segments};

fn dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("antenna-export-{name}-{}", std::process::id()));
    // Trial files are never overwritten: start from an empty directory.
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn antenna(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_antenna"))
        .arg("export")
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn a_missing_or_foreign_file_exits_2_naming_it() {
    let dir = dir("bad");
    let out_mat = dir.join("out.mat");
    let missing = dir.join("no-such-trial.mcap");
    let out = antenna(&[missing.as_os_str(), "--mat".as_ref(), out_mat.as_os_str()]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("no-such-trial.mcap"), "{stderr}");

    let foreign = dir.join("ringdown.csv");
    std::fs::write(&foreign, "t_s,angle_rad\n0,0.1\n").unwrap();
    let out = antenna(&[
        foreign.as_os_str(),
        "--csv".as_ref(),
        dir.join("o.csv").as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("ringdown.csv") && stderr.contains("not an MCAP"),
        "{stderr}"
    );
    assert!(!out_mat.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_trial_cut_by_a_crash_exports_up_to_its_last_flush() {
    let dir = dir("cut");
    let live = dir.join("live.mcap");
    let mut recorder = TrialRecorder::create(&live, &synthetic_metadata("cut")).unwrap();
    for i in 0..150 {
        recorder.record_segments(&synthetic_segments(i, 3)).unwrap();
    }
    let flushed = recorder.flushed().segments;
    let cut = dir.join("cut.mcap");
    std::fs::copy(&live, &cut).unwrap();
    drop(recorder);

    let csv = dir.join("cut.csv");
    let out = antenna(&[cut.as_os_str(), "--csv".as_ref(), csv.as_os_str()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("warning") && stderr.contains("cut.mcap"),
        "{stderr}"
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let rows = text.lines().filter(|l| !l.starts_with('#')).count();
    assert_eq!(rows as u64, 1 + 3 * flushed);
    assert!(text.contains("# truncated: "));
    assert!(text.contains("# notes.wall: flat"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_trial_killed_before_its_first_poll_exports_empty_arrays() {
    let dir = dir("empty");
    let trial = dir.join("empty.mcap");
    let recorder = TrialRecorder::create(&trial, &synthetic_metadata("empty")).unwrap();
    let cut = dir.join("cut.mcap");
    std::fs::copy(&trial, &cut).unwrap();
    drop(recorder);
    let (mat, csv) = (dir.join("empty.mat"), dir.join("empty.csv"));
    for source in [&trial, &cut] {
        let out = antenna(&[
            source.as_os_str(),
            "--mat".as_ref(),
            mat.as_os_str(),
            "--csv".as_ref(),
            csv.as_os_str(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(std::fs::metadata(&mat).unwrap().len() > 128);
        let text = std::fs::read_to_string(&csv).unwrap();
        assert_eq!(text.lines().filter(|l| !l.starts_with('#')).count(), 1);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
