//! The Foxglove channels of a recording: a synthetic trial with a rig is recorded, read back
//! by the Rust `mcap` crate (frames decoded and composed against the recorded angles) and by
//! Python's `mcap` reader with `mcap-protobuf-support` (`tests/python/read_foxglove.py`),
//! as Foxglove reads it. Needs python3 with mcap and mcap-protobuf-support: `scripts/setup`
//! installs them.
#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::process::Command;

use antenna_data::foxglove::{ChainModel, link_frame_id};
use antenna_data::record::{
    DEFAULT_SCENE_HZ, FoxgloveOptions, RecorderOptions, TrialReader, TrialRecorder,
    synthetic_estimate, synthetic_metadata, synthetic_rig, synthetic_segments, synthetic_servo,
    synthetic_stage,
};
use foxglove::Decode;
use foxglove::messages::{FrameTransforms, SceneUpdate};

const SEGMENTS: usize = 9;

fn record(path: &Path, polls: u64, foxglove: FoxgloveOptions) {
    let mut metadata = synthetic_metadata("foxglove");
    metadata.rig = Some(synthetic_rig(SEGMENTS));
    let mut recorder =
        TrialRecorder::create_with_foxglove(path, &metadata, RecorderOptions::default(), foxglove)
            .unwrap();
    for i in 0..polls {
        recorder
            .record_segments(&synthetic_segments(i, SEGMENTS))
            .unwrap();
        if i % 10 == 0 {
            recorder.record_stage(&synthetic_stage(i / 10)).unwrap();
            recorder
                .record_estimate(&synthetic_estimate(i / 10))
                .unwrap();
        }
        if i % 20 == 0 {
            recorder.record_servo(&synthetic_servo(i / 20)).unwrap();
        }
    }
    let written = recorder.written();
    assert_eq!(written.transforms, written.scene);
    recorder.finish().unwrap();
}

fn temp(name: &str) -> PathBuf {
    let path = std::env::temp_dir().join(format!(
        "record-foxglove-{name}-{}.mcap",
        std::process::id()
    ));
    std::fs::remove_file(&path).ok();
    path
}

/// Runs `tests/python/read_foxglove.py` on `path`; its JSON summary.
pub fn read_in_python(path: &Path) -> serde_json::Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/python/read_foxglove.py");
    let out = Command::new("python3")
        .arg(&script)
        .arg(path)
        .output()
        .expect("python3 (scripts/setup installs it with mcap and mcap-protobuf-support)");
    assert!(
        out.status.success(),
        "read_foxglove.py failed ({}; scripts/setup installs mcap and mcap-protobuf-support):\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn python_decodes_frame_transforms_that_match_the_recorded_angles() {
    let path = temp("python");
    let polls = 2000;
    record(&path, polls, FoxgloveOptions::default());

    // Today's channels read back as before, the estimates too.
    let trial = TrialReader::read(&path).unwrap();
    assert!(trial.truncated.is_none(), "{:?}", trial.truncated);
    assert_eq!(trial.segments.len() as u64, polls);
    let estimates: Vec<_> = (0..polls / 10).map(synthetic_estimate).collect();
    assert_eq!(trial.estimate, estimates);
    // 50 Hz of 2 s of polls: one every 20 polls.
    let scenes = polls.div_ceil(1000 / DEFAULT_SCENE_HZ as u64);
    assert_eq!(trial.foxglove_messages, 2 * scenes);

    let python = read_in_python(&path);
    assert_eq!(python["transforms"].as_u64(), Some(scenes), "{python}");
    assert_eq!(python["scenes"].as_u64(), Some(scenes), "{python}");
    // Every segment's link checked but for the failed reads.
    assert!(
        python["links_checked"].as_u64().unwrap() > (scenes - 5) * SEGMENTS as u64,
        "{python}"
    );
    assert_eq!(
        python["switches_checked"].as_u64(),
        Some(scenes * 4 * SEGMENTS as u64),
        "{python}"
    );
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn rust_decodes_the_same_frames_and_the_estimated_wall() {
    let path = temp("rust");
    let chain = ChainModel {
        walls_m: vec![vec![[0.0, 0.2], [1.0, 0.2]]],
        ..ChainModel::from_rig(&synthetic_rig(SEGMENTS)).unwrap()
    };
    record(
        &path,
        300,
        FoxgloveOptions {
            chain: Some(chain),
            scene_hz: 10.0,
            wall_on_left: false,
        },
    );
    let bytes = std::fs::read(&path).unwrap();
    let mut transforms = Vec::new();
    let mut scenes = Vec::new();
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        let message = message.unwrap();
        let schema = message.channel.schema.as_ref().unwrap();
        match message.channel.topic.as_str() {
            "/antenna/transforms" => {
                assert_eq!(schema.name, "foxglove.FrameTransforms");
                assert_eq!(schema.encoding, "protobuf");
                assert_eq!(message.channel.message_encoding, "protobuf");
                let decoded = FrameTransforms::decode(&message.data[..]).unwrap();
                transforms.push((message.log_time, decoded));
            }
            "/antenna/scene" => {
                assert_eq!(schema.name, "foxglove.SceneUpdate");
                scenes.push((
                    message.log_time,
                    SceneUpdate::decode(&message.data[..]).unwrap(),
                ));
            }
            _ => {}
        }
    }
    // 10 Hz over 0.3 s of polls: at 0, 0.1 and 0.2 s.
    assert_eq!(transforms.len(), 3);
    assert_eq!(scenes.len(), 3);
    let start_ns = synthetic_metadata("x").started_unix_ns.unwrap();
    for (n, (log_time, message)) in transforms.iter().enumerate() {
        let i = n as u64 * 100;
        assert_eq!(*log_time, start_ns + i * 1_000_000);
        let poll = synthetic_segments(i, SEGMENTS);
        for (k, sample) in poll.segments.iter().enumerate() {
            let t = message
                .transforms
                .iter()
                .find(|t| t.child_frame_id == link_frame_id(k + 1));
            match (sample.angle_rad, t) {
                (Some(angle_rad), Some(t)) => {
                    let q = t.rotation.unwrap();
                    let got = 2.0 * q.z.atan2(q.w);
                    assert!((got - angle_rad).abs() < 1e-12, "poll {i} link {}", k + 1);
                }
                (None, None) => {}
                (a, t) => panic!("poll {i} segment {k}: {a:?} and {t:?}"),
            }
        }
    }
    // The walls in the first scene (then every second), the estimate on the right.
    let ids = |s: &SceneUpdate| s.entities.iter().map(|e| e.id.clone()).collect::<Vec<_>>();
    assert!(ids(&scenes[0].1).contains(&"wall_0".to_owned()));
    assert!(!ids(&scenes[1].1).contains(&"wall_0".to_owned()));
    // At 0.1 s the newest estimate is the 9th (the 10th is recorded after the poll, and has
    // no distance anyway).
    let estimate = synthetic_estimate(9);
    let wall = scenes[1]
        .1
        .entities
        .iter()
        .find(|e| e.id == "estimated_wall")
        .unwrap();
    assert_eq!(wall.frame_id, "carriage");
    for p in &wall.lines[0].points {
        let toward = estimate.distance_m.unwrap()
            + (p.x - estimate.preview_m.unwrap()) * estimate.wall_angle_rad.unwrap().tan();
        assert!((p.y + toward).abs() < 1e-12, "{p:?}");
    }
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn without_a_rig_or_a_chain_there_are_no_foxglove_channels() {
    let path = temp("none");
    let mut recorder = TrialRecorder::create(&path, &synthetic_metadata("none")).unwrap();
    for i in 0..100 {
        recorder.record_segments(&synthetic_segments(i, 3)).unwrap();
    }
    assert_eq!(recorder.written().transforms, 0);
    recorder.finish().unwrap();
    assert_eq!(TrialReader::read(&path).unwrap().foxglove_messages, 0);
    std::fs::remove_file(&path).unwrap();
}
