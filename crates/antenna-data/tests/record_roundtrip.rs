//! Trial recording round trips: every sample written is read back equal, and a file cut
//! anywhere after its last flush (what `kill -9` leaves) reads back exactly the samples up to
//! that flush, none corrupted.
#![allow(clippy::unwrap_used)]

use std::path::PathBuf;

use antenna_data::record::sealed_file::PROVISIONAL_TAIL_BYTES;
use antenna_data::record::{
    ChunkCompression, RecordError, RecorderOptions, TrialReader, TrialRecorder, synthetic_metadata,
    synthetic_segments, synthetic_servo, synthetic_stage,
};

fn temp_path(name: &str) -> PathBuf {
    let path = std::env::temp_dir().join(format!("record-{name}-{}.mcap", std::process::id()));
    // A leftover of an earlier run would be refused (trial files are never overwritten).
    let _ = std::fs::remove_file(&path);
    path
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
fn nothing_reaches_the_file_between_flushes_and_a_torn_flush_loses_only_itself() {
    let path = temp_path("truncated");
    let mut recorder = TrialRecorder::create(&path, &synthetic_metadata("truncated")).unwrap();
    record(&mut recorder, 0..60);
    recorder.flush().unwrap();
    let flushed = recorder.flushed();
    assert_eq!(flushed.segments, 60);
    let first = std::fs::read(&path).unwrap();
    // More, unflushed: held in memory, the file on disk stays the sealed one.
    record(&mut recorder, 60..95);
    assert_eq!(recorder.flushed(), flushed);
    assert_eq!(std::fs::read(&path).unwrap(), first);
    recorder.flush().unwrap();
    let second = std::fs::read(&path).unwrap();
    // The second flush's one write starts where the first flush's provisional end began.
    let start = first.len() - PROVISIONAL_TAIL_BYTES;
    assert_eq!(second[..start], first[..start]);

    // A kill inside that write leaves its first k bytes over the old file: the reader gets
    // exactly the first flush's samples (or all of them once the write is whole).
    let expected_len = 60;
    let all: Vec<_> = (0..95).map(|i| synthetic_segments(i, 9)).collect();
    let mut state = 42;
    let written = second.len() - start;
    let mut ks: Vec<usize> = (0..300)
        .map(|_| (lcg(&mut state) as usize) % (written + 1))
        .collect();
    ks.extend([0, 1, 8, 9, PROVISIONAL_TAIL_BYTES, written - 1, written]);
    for k in ks {
        let mut torn = second[..start + k].to_vec();
        if start + k < first.len() {
            torn.extend_from_slice(&first[start + k..]);
        }
        let trial = TrialReader::read_bytes(&path, &torn).unwrap();
        // The first flush's polls, and the second's once its chunk is whole.
        let n = trial.segments.len();
        assert!(
            n == expected_len || n == all.len(),
            "torn after {k}: {n} polls"
        );
        assert_eq!(trial.segments, all[..n], "torn after {k} bytes");
        if k == written {
            assert_eq!(n, all.len());
        }
        assert_eq!(trial.metadata, Some(synthetic_metadata("truncated")));
        assert!(trial.truncated.is_some(), "torn after {k} bytes");
    }
    // A cut anywhere at all gives an exact prefix of the polls, never a corrupted one, and
    // never a panic. (Every byte of the first 1000, then every 13th.)
    for cut in (0..1000).chain((1000..second.len()).step_by(13)) {
        let trial = TrialReader::read_bytes(&path, &second[..cut]).unwrap();
        let n = trial.segments.len();
        assert_eq!(trial.segments, all[..n], "cut at byte {cut}");
        assert!(trial.truncated.is_some(), "cut at byte {cut}");
    }
    drop(recorder);
    std::fs::remove_file(&path).unwrap();
}

/// The Rust `mcap` crate, with none of this project's code, reads a file that was never
/// closed (what `kill -9` leaves) as a complete file: every flushed message, log times in
/// Unix-epoch nanoseconds, chunks compressed with zstd.
#[test]
fn an_unclosed_file_is_a_whole_mcap_file_for_the_mcap_crate() {
    let path = temp_path("unclosed");
    let metadata = synthetic_metadata("unclosed");
    let mut recorder = TrialRecorder::create(&path, &metadata).unwrap();
    record(&mut recorder, 0..250);
    let flushed = recorder.flushed();
    assert!((200..250).contains(&flushed.segments), "{flushed:?}");
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(mcap::Summary::read(&bytes).unwrap(), None, "no summary yet");
    let mut polls = 0;
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        let message = message.unwrap();
        if message.channel.topic == "/antenna/segments" {
            let poll: antenna_data::record::SegmentsMessage =
                serde_json::from_slice(&message.data).unwrap();
            let epoch_ns = metadata.started_unix_ns.unwrap();
            assert_eq!(message.log_time, epoch_ns + (poll.t_s * 1e9).round() as u64);
            assert_eq!(poll, synthetic_segments(polls, 9));
            polls += 1;
        }
    }
    assert_eq!(polls, flushed.segments);
    drop(recorder);
    // Closed, the file has its summary and its chunks are zstd-compressed.
    let bytes = std::fs::read(&path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    assert!(!summary.chunk_indexes.is_empty());
    for chunk in &summary.chunk_indexes {
        assert_eq!(chunk.compression, "zstd");
        assert!(chunk.compressed_size < chunk.uncompressed_size);
    }
    assert_eq!(TrialReader::read(&path).unwrap().truncated, None);
    std::fs::remove_file(&path).unwrap();
}

/// Compression: the same polls take a fifth of the bytes or less with zstd, although every
/// synthetic angle changes at every poll (the default trial, in `host-daemon`'s
/// `daemon_recording`, is held to ten times smaller).
#[test]
fn zstd_chunks_are_at_least_five_times_smaller() {
    let size = |compression| {
        let path = temp_path(&format!("size-{compression:?}"));
        let options = RecorderOptions {
            compression,
            ..RecorderOptions::default()
        };
        let mut recorder =
            TrialRecorder::create_with(&path, &synthetic_metadata("size"), options).unwrap();
        record(&mut recorder, 0..3000);
        recorder.finish().unwrap();
        let bytes = std::fs::metadata(&path).unwrap().len();
        assert_eq!(TrialReader::read(&path).unwrap().segments.len(), 3000);
        std::fs::remove_file(&path).unwrap();
        bytes
    };
    let plain = size(ChunkCompression::None);
    let zstd = size(ChunkCompression::Zstd);
    assert!(5 * zstd <= plain, "zstd {zstd} B, uncompressed {plain} B");
}

/// An existing file is never overwritten: a trial file cannot clobber another one, nor
/// follow a planted link.
#[test]
fn an_existing_file_is_never_overwritten() {
    let path = temp_path("exists");
    std::fs::write(&path, b"precious").unwrap();
    let err = TrialRecorder::create(&path, &synthetic_metadata("exists")).unwrap_err();
    assert!(matches!(err, RecordError::Io { .. }), "{err}");
    assert_eq!(std::fs::read(&path).unwrap(), b"precious");
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

/// The file is synced to the disk every `sync_interval_s` of trial time (after the flush it
/// needs), and only at the end with an interval of 0.
#[test]
fn the_file_is_synced_at_its_interval_and_at_the_end() {
    for (sync_interval_s, synced_before_end) in [(1.0, 2001), (0.0, 0)] {
        let path = temp_path(&format!("sync-{sync_interval_s}"));
        let options = RecorderOptions {
            sync_interval_s,
            ..RecorderOptions::default()
        };
        let mut recorder =
            TrialRecorder::create_with(&path, &synthetic_metadata("sync"), options).unwrap();
        record(&mut recorder, 0..2500);
        // Synced at t = 1.0 s and 2.0 s: polls 0..=1000 and 0..=2000.
        assert_eq!(recorder.synced().segments, synced_before_end);
        assert!(recorder.flushed().segments >= 2400);
        recorder.finish().unwrap();
        assert_eq!(TrialReader::read(&path).unwrap().segments.len(), 2500);
        std::fs::remove_file(&path).unwrap();
    }
}

/// The simulated rig's physics steps (`/sim/physics`, issue #46) read back exactly, and a
/// trial without them (hardware, or recorded before) reads back with none.
#[test]
fn physics_steps_read_back_exactly_and_older_files_have_none() {
    use antenna_data::record::{PhysicsStepKind, PhysicsStepMessage};
    let path = temp_path("physics");
    let mut recorder = TrialRecorder::create(&path, &synthetic_metadata("physics")).unwrap();
    let steps: Vec<PhysicsStepMessage> = (0..300)
        .map(|i| PhysicsStepMessage {
            t_s: f64::from(i) * 0.02,
            kind: if i == 0 {
                PhysicsStepKind::Place
            } else {
                PhysicsStepKind::Step
            },
            stage_m: f64::from(i) * 1e-3 / 3.0,
            base_x_m: f64::from(i) * 1e-3 / 3.0,
            base_y_m: -0.1 / 7.0,
            base_angle_rad: 30f64.to_radians(),
            joint_angles_rad: vec![0.1 / f64::from(i + 1); 8],
        })
        .collect();
    for step in &steps {
        recorder.record_physics(step).unwrap();
    }
    assert_eq!(recorder.written().physics, 300);
    recorder.finish().unwrap();
    let trial = TrialReader::read(&path).unwrap();
    assert_eq!(trial.physics, steps);
    std::fs::remove_file(&path).unwrap();

    let path = temp_path("no-physics");
    let mut recorder = TrialRecorder::create(&path, &synthetic_metadata("none")).unwrap();
    record(&mut recorder, 0..20);
    recorder.finish().unwrap();
    assert!(TrialReader::read(&path).unwrap().physics.is_empty());
    std::fs::remove_file(&path).unwrap();
}
