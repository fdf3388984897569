//! `antenna export` from the command line: bad input exits 2 with a message naming the file,
//! a trial cut short by a crash exports up to its last flush with a warning, and a write that
//! fails (a full disk) is an error that leaves no partial file.
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

/// A trial of `polls` synthetic polls of 9 segments in `dir`.
fn trial(dir: &std::path::Path, polls: u64) -> PathBuf {
    let trial = dir.join("trial.mcap");
    let mut recorder = TrialRecorder::create(&trial, &synthetic_metadata("full")).unwrap();
    for i in 0..polls {
        recorder.record_segments(&synthetic_segments(i, 9)).unwrap();
    }
    recorder.finish().unwrap();
    trial
}

/// A full disk: `/dev/full` fails every write with ENOSPC, as a full file system does. The
/// export exits non-zero naming the file and the operating system's error (matrw, used
/// before, dropped write errors and exited 0).
#[cfg(target_os = "linux")]
#[test]
fn a_full_disk_is_an_error_naming_the_file() {
    let dir = dir("full");
    let trial = trial(&dir, 200);
    let out = antenna(&[trial.as_os_str(), "--mat".as_ref(), "/dev/full".as_ref()]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("/dev/full") && stderr.contains("No space left on device"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A write that fails half way into a regular file (the file size limit, `ulimit -f`, fails it
/// with EFBIG as a full disk fails it with ENOSPC; SIGXFSZ ignored so the write returns the
/// error): an error naming the file, and neither a partial file nor a temporary one is left;
/// an older export of that name stays as it was.
#[cfg(unix)]
#[test]
fn a_write_that_fails_half_way_leaves_no_partial_file() {
    let dir = dir("limit");
    let trial = trial(&dir, 2000);
    let mat = dir.join("trial.mat");
    std::fs::write(&mat, "an older export").unwrap();
    let out = Command::new("sh")
        .arg("-c")
        .arg("trap '' XFSZ; ulimit -f 16; exec \"$0\" export \"$1\" --mat \"$2\"")
        .arg(env!("CARGO_BIN_EXE_antenna"))
        .arg(&trial)
        .arg(&mat)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("trial.mat") && stderr.contains("File too large"),
        "{stderr}"
    );
    assert_eq!(std::fs::read_to_string(&mat).unwrap(), "an older export");
    let mut left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["trial.mat", "trial.mcap"]);

    // Without the limit the same export succeeds and replaces the older file.
    let out = antenna(&[trial.as_os_str(), "--mat".as_ref(), mat.as_os_str()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(std::fs::metadata(&mat).unwrap().len() > 16 * 1024);
    std::fs::remove_dir_all(&dir).unwrap();
}
