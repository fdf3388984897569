//! Trial recording round trips: every sample written is read back equal, and a file cut
//! anywhere after its last flush (what `kill -9` leaves) reads back exactly the samples up to
//! that flush, none corrupted.
#![allow(clippy::unwrap_used)]

use std::path::PathBuf;

use antenna_data::record::{
    RecordError, TrialReader, TrialRecorder, synthetic_metadata, synthetic_segments,
    synthetic_servo, synthetic_stage,
};

fn temp_path(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("record-{name}-{}.mcap", std::process::id()))
}

/// Records polls `range` (with stage every 10th and servo every 20th poll).
fn record(recorder: &mut TrialRecorder, range: std::ops::Range<u64>) {
    for i in range {
        recorder.record_segments(&synthetic_segments(i, 9)).unwrap();
        if i % 10 == 0 {
            recorder.record_stage(&synthetic_stage(i / 10)).unwrap();
        }
        if i % 20 == 0 {
            recorder.record_servo(&synthetic_servo(i / 20)).unwrap();
        }
    }
}

#[test]
fn a_finished_trial_reads_back_every_sample_exactly() {
    let path = temp_path("roundtrip");
    let mut recorder = TrialRecorder::create(&path, &synthetic_metadata("roundtrip")).unwrap();
    record(&mut recorder, 0..2500);
    assert_eq!(recorder.written().segments, 2500);
    recorder.finish().unwrap();

    let trial = TrialReader::read(&path).unwrap();
    assert_eq!(trial.truncated, None);
    assert_eq!(trial.metadata, Some(synthetic_metadata("roundtrip")));
    let expected: Vec<_> = (0..2500).map(|i| synthetic_segments(i, 9)).collect();
    assert_eq!(trial.segments, expected);
    let stage: Vec<_> = (0..250).map(synthetic_stage).collect();
    assert_eq!(trial.stage, stage);
    let servo: Vec<_> = (0..125).map(synthetic_servo).collect();
    assert_eq!(trial.servo, servo);
    // The synthetic data does exercise the failure flags.
    assert!(trial.segments.iter().flatten_segments().any(|s| s.nack));
    assert!(
        trial
            .segments
            .iter()
            .flatten_segments()
            .any(|s| s.pec_error)
    );
    assert!(trial.segments.iter().flatten_segments().any(|s| s.stale));
    std::fs::remove_file(&path).unwrap();
}

trait FlattenSegments<'a> {
    fn flatten_segments(self) -> impl Iterator<Item = &'a antenna_data::record::SegmentSample>;
}

impl<'a, I: Iterator<Item = &'a antenna_data::record::SegmentsMessage>> FlattenSegments<'a> for I {
    fn flatten_segments(self) -> impl Iterator<Item = &'a antenna_data::record::SegmentSample> {
        self.flat_map(|m| m.segments.iter())
    }
}

#[test]
fn the_recorder_flushes_at_least_every_100_ms_of_trial_time() {
    let path = temp_path("interval");
    let mut recorder = TrialRecorder::create(&path, &synthetic_metadata("interval")).unwrap();
    for i in 0..1000 {
        recorder.record_segments(&synthetic_segments(i, 2)).unwrap();
        let unflushed = recorder.written().segments - recorder.flushed().segments;
        // 1 kHz polls: never more than 100 ms of them unflushed.
        assert!(unflushed <= 100, "{unflushed} polls unflushed at poll {i}");
    }
    drop(recorder);
    std::fs::remove_file(&path).unwrap();
}

/// A small deterministic generator for the cut points.
fn lcg(state: &mut u64) -> u64 {
    *state = state
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    *state >> 33
}

#[test]
fn a_file_cut_after_its_last_flush_reads_back_exactly_the_flushed_samples() {
    let path = temp_path("truncated");
    let mut recorder = TrialRecorder::create(&path, &synthetic_metadata("truncated")).unwrap();
    record(&mut recorder, 0..60);
    recorder.flush().unwrap();
    let flushed = recorder.flushed();
    assert_eq!(flushed.segments, 60);
    let flushed_len = std::fs::metadata(&path).unwrap().len() as usize;
    // More, unflushed: beyond the writer's buffer, so a partial chunk reaches the file.
    record(&mut recorder, 60..95);
    assert_eq!(recorder.flushed(), flushed);
    let bytes = std::fs::read(&path).unwrap();
    assert!(
        bytes.len() > flushed_len,
        "the unflushed chunk should have partly reached the file"
    );

    let expected: Vec<_> = (0..60).map(|i| synthetic_segments(i, 9)).collect();
    let mut state = 42;
    let mut cuts: Vec<usize> = (0..200)
        .map(|_| flushed_len + (lcg(&mut state) as usize) % (bytes.len() - flushed_len + 1))
        .collect();
    cuts.extend([flushed_len, flushed_len + 1, bytes.len()]);
    for cut in cuts {
        let trial = TrialReader::read_bytes(&path, &bytes[..cut]).unwrap();
        assert_eq!(trial.segments, expected, "cut at byte {cut}");
        assert_eq!(trial.stage.len() as u64, flushed.stage, "cut at byte {cut}");
        assert_eq!(trial.servo.len() as u64, flushed.servo, "cut at byte {cut}");
        assert_eq!(trial.metadata, Some(synthetic_metadata("truncated")));
        assert!(trial.truncated.is_some(), "cut at byte {cut}");
    }
    // A cut anywhere at all (even before the last flush, which kill -9 cannot do) gives an
    // exact prefix of the polls, never a corrupted one, and never a panic.
    let all: Vec<_> = (0..95).map(|i| synthetic_segments(i, 9)).collect();
    // (Every byte of the first 1000, then every 13th.)
    for cut in (0..1000).chain((1000..bytes.len()).step_by(13)) {
        let trial = TrialReader::read_bytes(&path, &bytes[..cut]).unwrap();
        let n = trial.segments.len();
        assert_eq!(trial.segments, all[..n], "cut at byte {cut}");
        assert!(trial.truncated.is_some(), "cut at byte {cut}");
    }
    drop(recorder);
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn a_file_cut_before_its_first_flush_is_an_empty_trial_and_garbage_is_an_error() {
    let path = temp_path("garbage");
    let trial = TrialReader::read_bytes(&path, b"\x89MCA").unwrap();
    assert!(trial.segments.is_empty() && trial.truncated.is_some());
    let err = TrialReader::read_bytes(&path, b"t_s,angle_rad\n0,1\n").unwrap_err();
    assert!(matches!(err, RecordError::NotMcap { .. }), "{err}");
    assert!(err.to_string().contains("record-garbage"), "{err}");
}

#[test]
fn times_that_are_not_trial_times_are_refused() {
    let path = temp_path("badtime");
    let mut recorder = TrialRecorder::create(&path, &synthetic_metadata("badtime")).unwrap();
    let mut message = synthetic_segments(0, 1);
    message.t_s = -1.0;
    assert!(matches!(
        recorder.record_segments(&message),
        Err(RecordError::BadTime { .. })
    ));
    message.t_s = f64::NAN;
    assert!(recorder.record_segments(&message).is_err());
    recorder.finish().unwrap();
    std::fs::remove_file(&path).unwrap();
}
