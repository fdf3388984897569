//! `antenna export` checked by Python: a synthetic trial is recorded, exported to MAT and
//! CSV, and `tests/python/check_export.py` reads the MCAP file with the Python `mcap` reader's
//! `make_reader` (complete, and as `kill -9` leaves it), the MAT-file with scipy's default
//! `scipy.io.loadmat(path)` (no options: every variable's dtype is checked, float64 for doubles
//! even when all whole, as in a trial whose base angle is all zero, and an empty trial's) and the
//! CSV with `csv`, comparing every value with what was recorded. Needs python3 with scipy and
//! mcap: `scripts/setup` installs them.
#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::process::Command;

use antenna_data::record::{
    ServoMessage, StageMessage, TrialRecorder, synthetic_estimate, synthetic_metadata,
    synthetic_segments, synthetic_servo, synthetic_stage,
};
use serde_json::json;

fn record(recorder: &mut TrialRecorder, range: std::ops::Range<u64>) {
    for i in range {
        recorder.record_segments(&synthetic_segments(i, 9)).unwrap();
        if i % 10 == 0 {
            recorder.record_stage(&synthetic_stage(i / 10)).unwrap();
        }
        if i % 20 == 0 {
            recorder.record_servo(&synthetic_servo(i / 20)).unwrap();
        }
        if i % 10 == 0 {
            recorder
                .record_estimate(&synthetic_estimate(i / 10))
                .unwrap();
        }
    }
}

fn require_python() {
    let found = Command::new("python3")
        .args(["-c", "import scipy.io, numpy, mcap"])
        .output();
    match found {
        Ok(out) if out.status.success() => {}
        Ok(out) => panic!(
            "python3 lacks scipy or mcap ({}): run scripts/setup (it runs \
             `python3 -m pip install scipy mcap`)",
            String::from_utf8_lossy(&out.stderr).trim()
        ),
        Err(e) => panic!("python3 not found ({e}): install Python 3 and run scripts/setup"),
    }
}

fn export(trial: &Path, flag: &str, out: &Path) {
    let result = Command::new(env!("CARGO_BIN_EXE_antenna"))
        .arg("export")
        .arg(trial)
        .arg(flag)
        .arg(out)
        .output()
        .unwrap();
    assert!(
        result.status.success(),
        "antenna export {flag} failed: {}",
        String::from_utf8_lossy(&result.stderr)
    );
}

#[test]
fn python_reads_the_mcap_the_mat_file_and_the_csv_back_exactly() {
    require_python();
    let dir: PathBuf =
        std::env::temp_dir().join(format!("antenna-export-python-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).unwrap();
    let polls = 1234;
    let metadata = synthetic_metadata("export-python");

    let trial = dir.join("trial.mcap");
    let mut recorder = TrialRecorder::create(&trial, &metadata).unwrap();
    record(&mut recorder, 0..polls);
    recorder.finish().unwrap();

    // What kill -9 leaves: the bytes on disk while unflushed polls are in flight.
    let cut = dir.join("killed.mcap");
    let mut recorder = TrialRecorder::create(dir.join("live.mcap"), &metadata).unwrap();
    record(&mut recorder, 0..330);
    let flushed = recorder.flushed().segments;
    assert!((300..330).contains(&flushed), "{flushed}");
    std::fs::copy(recorder.path(), &cut).unwrap();
    drop(recorder);

    let mat = dir.join("trial.mat");
    let csv = dir.join("trial.csv");
    export(&trial, "--mat", &mat);
    export(&trial, "--csv", &csv);

    // Whole numbers in every double: whole seconds, whole metres, a base angle of zero.
    let whole_trial = dir.join("whole.mcap");
    let (whole_polls, whole_servo) = (50, 5);
    let mut recorder = TrialRecorder::create(&whole_trial, &metadata).unwrap();
    for i in 0..whole_polls {
        let mut poll = synthetic_segments(i, 3);
        poll.t_s = i as f64;
        recorder.record_segments(&poll).unwrap();
        let t_s = i as f64;
        recorder
            .record_stage(&StageMessage {
                t_s,
                position_m: t_s,
            })
            .unwrap();
        if i < whole_servo {
            recorder
                .record_servo(&ServoMessage {
                    t_s,
                    base_angle_rad: 0.0,
                })
                .unwrap();
        }
    }
    recorder.finish().unwrap();
    let whole_mat = dir.join("whole.mat");
    export(&whole_trial, "--mat", &whole_mat);

    let empty_trial = dir.join("empty.mcap");
    TrialRecorder::create(&empty_trial, &metadata)
        .unwrap()
        .finish()
        .unwrap();
    let empty_mat = dir.join("empty.mat");
    export(&empty_trial, "--mat", &empty_mat);

    let messages: Vec<_> = (0..polls).map(|i| synthetic_segments(i, 9)).collect();
    let per_sample = |f: &dyn Fn(&antenna_data::record::SegmentSample) -> serde_json::Value| {
        messages
            .iter()
            .map(|m| m.segments.iter().map(f).collect::<Vec<_>>())
            .collect::<Vec<_>>()
    };
    let stage: Vec<_> = (0..polls.div_ceil(10)).map(synthetic_stage).collect();
    let servo: Vec<_> = (0..polls.div_ceil(20)).map(synthetic_servo).collect();
    let expected = json!({
        "mcap": trial,
        "mat": mat,
        "csv": csv,
        "truncated_mcap": cut,
        "truncated_polls": flushed,
        "t_s": messages.iter().map(|m| m.t_s).collect::<Vec<_>>(),
        "seq": messages.iter().map(|m| m.seq).collect::<Vec<_>>(),
        "started_unix_ns": metadata.started_unix_ns,
        "address": messages[0].segments.iter().map(|s| s.address).collect::<Vec<_>>(),
        "angle_rad": messages.iter()
            .map(|m| m.segments.iter().map(|s| s.angle_rad).collect::<Vec<_>>())
            .collect::<Vec<_>>(),
        "touch": messages.iter()
            .map(|m| m.segments.iter().map(|s| s.touch).collect::<Vec<_>>())
            .collect::<Vec<_>>(),
        "angle_counts": per_sample(&|s| json!(s.angle_counts)),
        "ok": per_sample(&|s| json!(s.ok)),
        "nack": per_sample(&|s| json!(s.nack)),
        "pec_error": per_sample(&|s| json!(s.pec_error)),
        "bus_error": per_sample(&|s| json!(s.bus_error)),
        "stale": per_sample(&|s| json!(s.stale)),
        "stage_t_s": stage.iter().map(|s| s.t_s).collect::<Vec<_>>(),
        "stage_position_m": stage.iter().map(|s| s.position_m).collect::<Vec<_>>(),
        "servo_t_s": servo.iter().map(|s| s.t_s).collect::<Vec<_>>(),
        "base_angle_rad": servo.iter().map(|s| s.base_angle_rad).collect::<Vec<_>>(),
        "estimate": (0..polls.div_ceil(10)).map(synthetic_estimate).collect::<Vec<_>>(),
        "trial": metadata.trial,
        "config": metadata.config,
        "notes": metadata.notes,
        "whole": {
            "mat": whole_mat,
            "servo": whole_servo,
            "t_s": (0..whole_polls).map(|i| i as f64).collect::<Vec<_>>(),
            "stage_position_m": (0..whole_polls).map(|i| i as f64).collect::<Vec<_>>(),
        },
        "empty_mat": empty_mat,
    });
    let sidecar = dir.join("expected.json");
    std::fs::write(&sidecar, serde_json::to_string(&expected).unwrap()).unwrap();

    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/python/check_export.py");
    let out = Command::new("python3")
        .arg(&script)
        .arg(&sidecar)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "check_export.py failed:\n{stdout}\n{stderr}"
    );
    assert!(stdout.contains("check_export: all ok"), "{stdout}");
    std::fs::remove_dir_all(&dir).unwrap();
}
