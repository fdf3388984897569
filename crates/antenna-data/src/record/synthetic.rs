//! Deterministic synthetic trial data, for tests, the `record-until-killed` test helper and
//! demos: sample `i` is a pure function of `i`, so a reader can check every sample it gets.

use std::collections::BTreeMap;

use antenna_protocol::Calibration;

use super::messages::{
    EstimateMessage, SegmentSample, SegmentsMessage, ServoMessage, StageMessage, TrialMetadata,
};
use crate::stream::RigInfo;

/// The poll period of the synthetic trial, s (1 kHz).
pub const SYNTHETIC_POLL_PERIOD_S: f64 = 0.001;

/// The `i`-th synthetic poll of `segments` segments (addresses 0x21 upwards): angles sweep,
/// touch bits cycle, and every 97th sample of segment 2 is a NACK, every 101st of segment 1
/// a PEC error, every 89th of segment 0 stale.
pub fn synthetic_segments(i: u64, segments: usize) -> SegmentsMessage {
    let calibration = Calibration::default();
    let samples = (0..segments)
        .map(|k| {
            let address = 0x21 + k as u8;
            let nack = k == 2 && i % 97 == 5;
            let pec_error = k == 1 && i % 101 == 7;
            let ok = !(nack || pec_error);
            let counts = ((i * 7 + k as u64 * 311) % 4096) as u16;
            SegmentSample {
                address,
                angle_counts: ok.then_some(counts),
                angle_rad: ok.then(|| calibration.angle_rad(counts)),
                touch: ok.then_some(((i / 50 + k as u64) % 16) as u8),
                ok,
                nack,
                pec_error,
                bus_error: false,
                stale: ok && k == 0 && i % 89 == 3,
            }
        })
        .collect();
    SegmentsMessage {
        seq: Some(i),
        t_s: i as f64 * SYNTHETIC_POLL_PERIOD_S,
        segments: samples,
    }
}

/// The `i`-th synthetic stage position (every 10th poll, 100 Hz): 2 mm/s.
pub fn synthetic_stage(i: u64) -> StageMessage {
    let t_s = i as f64 * 10.0 * SYNTHETIC_POLL_PERIOD_S;
    StageMessage {
        t_s,
        position_m: 0.002 * t_s,
    }
}

/// The `i`-th synthetic base angle (every 20th poll, 50 Hz).
pub fn synthetic_servo(i: u64) -> ServoMessage {
    let t_s = i as f64 * 20.0 * SYNTHETIC_POLL_PERIOD_S;
    ServoMessage {
        t_s,
        base_angle_rad: 0.1 * (t_s * 0.5).sin(),
    }
}

/// Metadata of a synthetic trial named `name`.
pub fn synthetic_metadata(name: &str) -> TrialMetadata {
    let mut notes = BTreeMap::new();
    notes.insert("wall".to_string(), "flat, 0.12 m from the base".to_string());
    notes.insert("hairs".to_string(), "4 per segment, 1.5 mm".to_string());
    TrialMetadata {
        trial: name.to_string(),
        started_unix_s: 1_795_000_000.25,
        started_unix_ns: Some(1_795_000_000_250_000_000),
        config: "[bus]\nkind = \"sim\"\n# synthetic\n".to_string(),
        notes,
        rig: None,
    }
}

/// The rig of a synthetic antenna of `segments` segments: links of 40 mm (the base link and
/// one per segment), mounted at 30 degrees, polled at 1 kHz; no scene.
pub fn synthetic_rig(segments: usize) -> RigInfo {
    RigInfo {
        poll_hz: 1.0 / SYNTHETIC_POLL_PERIOD_S,
        stage_min_m: 0.0,
        stage_max_m: 0.3,
        scene_toml: None,
        scene_source: None,
        link_lengths_m: vec![0.04; segments + 1],
        base_mount_angle_deg: 30.0,
        estimate_wall_side: None,
    }
}

/// The `i`-th synthetic wall estimate (every 10th poll, 100 Hz): the `contact-line`
/// estimator's, with no estimate (a reason instead) for every 7th.
pub fn synthetic_estimate(i: u64) -> EstimateMessage {
    let seq = i * 10;
    let t_s = seq as f64 * SYNTHETIC_POLL_PERIOD_S;
    let found = i % 7 != 3;
    EstimateMessage {
        t_s,
        seq,
        estimator: "contact-line".to_owned(),
        distance_m: found.then(|| 0.1 + 0.01 * (t_s * 0.7).sin()),
        wall_angle_rad: found.then(|| 0.05 * (t_s * 0.3).cos()),
        preview_m: found.then_some(0.08),
        reason: (!found).then(|| "no contact in the window".to_owned()),
        true_distance_m: Some(0.1),
        true_angle_rad: Some(0.0),
    }
}
