//! A recorded trial (MCAP, written by antennad) as a [`History`] to scrub, read with
//! `antenna_data::record::TrialReader` (the one MCAP reader of the project).
//!
//! Every `/antenna/segments` poll becomes a [`Sample`], with the latest stage and servo
//! samples at or before it (they are recorded at their own, lower rates). The geometry comes
//! from the rig kept in the recording's metadata (what the daemon sends in its stream's
//! `hello`); a recording without one (written before antennad kept it) gets a stand-in and
//! says so in [`RecordedTrial::geometry_note`]. The daemon's wall estimates
//! (`/antenna/estimate`) are kept whole in [`RecordedTrial::estimates`], drawn and plotted
//! as live ones are.

use std::path::{Path, PathBuf};

use antenna_data::record::{LogMessage, SegmentSample, TrialMetadata, TrialReader};

use crate::error::MonitorError;
use crate::estimate::{Estimate, EstimateHistory};
use crate::history::{Health, History, Sample, SegmentReading};
use crate::rig::RigGeometry;

/// A trial read from its MCAP file.
#[derive(Debug, Clone)]
pub struct RecordedTrial {
    /// The file.
    pub path: PathBuf,
    /// The trial's name (from its metadata, else the file's stem).
    pub name: String,
    /// Every poll, in order.
    pub history: History,
    /// The rig's geometry.
    pub rig: RigGeometry,
    /// Why the geometry is a stand-in, if it is.
    pub geometry_note: Option<String>,
    /// The daemon's log during the trial.
    pub log: Vec<LogMessage>,
    /// Set if the file was cut short (a crash): where reading stopped.
    pub truncated: Option<String>,
    /// The segments' addresses, base to tip.
    pub segment_addresses: Vec<u8>,
    /// The daemon's wall estimates, all of them, in time order (empty from a recording
    /// without them).
    pub estimates: EstimateHistory,
}

/// Reads the trial at `path`.
pub fn open_trial(path: &Path) -> Result<RecordedTrial, MonitorError> {
    let trial = TrialReader::read(path).map_err(|source| MonitorError::Recording {
        path: path.to_path_buf(),
        source,
    })?;
    let first = trial
        .segments
        .first()
        .ok_or_else(|| MonitorError::EmptyRecording {
            path: path.to_path_buf(),
        })?;
    let segment_count = first.segments.len();
    let segment_addresses = first.segments.iter().map(|s| s.address).collect();
    let (rig, geometry_note) = geometry(trial.metadata.as_ref())
        .and_then(|rig| {
            if rig.segment_count() == segment_count {
                Ok((rig, None))
            } else {
                Err(format!(
                    "its configuration describes {} segments, the polls hold {segment_count}",
                    rig.segment_count()
                ))
            }
        })
        .or_else(|why| RigGeometry::fallback(segment_count).map(|rig| (rig, Some(why))))?;
    let mut history = History::new(segment_count, trial.segments.len());
    let (mut stage, mut servo) = (0, 0);
    for poll in &trial.segments {
        while stage < trial.stage.len() && trial.stage[stage].t_s <= poll.t_s {
            stage += 1;
        }
        while servo < trial.servo.len() && trial.servo[servo].t_s <= poll.t_s {
            servo += 1;
        }
        let sample = Sample {
            seq: poll.seq,
            t_s: poll.t_s,
            segments: poll.segments.iter().map(reading).collect(),
            stage_position_m: stage.checked_sub(1).map(|k| trial.stage[k].position_m),
            servo_angle_rad: servo.checked_sub(1).map(|k| trial.servo[k].base_angle_rad),
        };
        history.push(&sample).map_err(|e| {
            MonitorError::Geometry(format!("{}: poll at {} s: {e}", path.display(), poll.t_s))
        })?;
    }
    let name = trial.metadata.as_ref().map_or_else(
        || {
            path.file_stem()
                .map_or_else(String::new, |s| s.to_string_lossy().into_owned())
        },
        |m| m.trial.clone(),
    );
    Ok(RecordedTrial {
        path: path.to_path_buf(),
        name,
        history,
        rig,
        geometry_note,
        log: trial.log,
        truncated: trial.truncated,
        segment_addresses,
        estimates: EstimateHistory::whole(trial.estimate.into_iter().map(Estimate::from)),
    })
}

fn geometry(metadata: Option<&TrialMetadata>) -> Result<RigGeometry, String> {
    let metadata = metadata.ok_or("the recording has no metadata")?;
    let rig = metadata.rig.as_ref().ok_or(
        "the recording keeps no rig geometry (antennad added it to the trial metadata in 0.2)",
    )?;
    RigGeometry::from_rig_info(rig, "the recording's rig").map_err(|e| e.to_string())
}

fn reading(s: &SegmentSample) -> SegmentReading {
    let health = if s.ok {
        if s.stale { Health::Stale } else { Health::Ok }
    } else if s.nack {
        Health::Nack
    } else if s.pec_error {
        Health::Pec
    } else {
        Health::Bus
    };
    SegmentReading {
        angle_rad: s.angle_rad,
        touch_bits: s.touch,
        health,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use antenna_data::record::{
        EstimateMessage, StageMessage, TrialRecorder, synthetic_metadata, synthetic_segments,
    };

    #[test]
    fn reads_polls_stage_and_geometry_back() {
        let path =
            std::env::temp_dir().join(format!("monitor-recording-{}.mcap", std::process::id()));
        let mut metadata = synthetic_metadata("unit");
        let config = host_daemon::service::config::Config::default();
        metadata.rig = Some(host_daemon::service::daemon::rig_info(&config));
        let mut recorder = TrialRecorder::create(&path, &metadata).unwrap();
        for i in 0..300 {
            let segments = synthetic_segments(i, 8);
            if i % 10 == 0 {
                recorder
                    .record_stage(&StageMessage {
                        t_s: segments.t_s,
                        position_m: i as f64 * 1e-4,
                    })
                    .unwrap();
            }
            recorder.record_segments(&segments).unwrap();
            if i % 10 == 5 {
                let known = i >= 100;
                recorder
                    .record_estimate(&EstimateMessage {
                        t_s: segments.t_s,
                        seq: i,
                        estimator: "contact-line".to_owned(),
                        distance_m: known.then_some(0.2),
                        wall_angle_rad: known.then_some(-0.1),
                        preview_m: known.then_some(0.05),
                        reason: (!known).then(|| "no contact in the window".to_owned()),
                        true_distance_m: Some(0.21),
                        true_angle_rad: Some(-0.14),
                    })
                    .unwrap();
            }
        }
        recorder.finish().unwrap();
        let trial = open_trial(&path).unwrap();
        std::fs::remove_file(&path).ok();
        assert_eq!(trial.history.len(), 300);
        // The estimates, all of them, on the polls' clock.
        assert_eq!(trial.estimates.len(), 30);
        let at = trial.history.t_s(200).unwrap();
        let e = trial.estimates.current_at(at).unwrap().unwrap();
        assert_eq!(
            (e.seq, e.distance_m, e.angle_rad),
            (195, Some(0.2), Some(-0.1))
        );
        assert_eq!(e.true_distance_m, Some(0.21));
        let early = trial.estimates.at(trial.history.t_s(50).unwrap()).unwrap();
        assert_eq!(early.reason.as_deref(), Some("no contact in the window"));
        assert_eq!(trial.history.segment_count(), 8);
        assert_eq!(trial.rig.segment_count(), 8);
        // The rig kept in the metadata: the simulated rig with its scene's wall.
        assert!(!trial.rig.walls.is_empty(), "{:?}", trial.geometry_note);
        let last = trial.history.sample(299).unwrap();
        assert!((last.stage_position_m.unwrap() - 0.029).abs() < 1e-6);
        assert!(trial.truncated.is_none());
        // The recording keeps each segment's four touch bits: every poll's come back as
        // written (none for a failed read), and its frame lights one switch per bit set.
        for i in 0..300 {
            let written: Vec<Option<u8>> = synthetic_segments(i, 8)
                .segments
                .iter()
                .map(|s| s.touch)
                .collect();
            let read: Vec<Option<u8>> = trial
                .history
                .sample(i as usize)
                .unwrap()
                .segments
                .iter()
                .map(|s| s.touch_bits)
                .collect();
            assert_eq!(read, written, "poll {i}");
            let lit = trial.rig.frame_at(&trial.history, i as usize).unwrap();
            let lit: Vec<(usize, usize)> = lit
                .lit_switches()
                .iter()
                .map(|l| (l.segment, l.switch))
                .collect();
            let expected: Vec<(usize, usize)> = written
                .iter()
                .enumerate()
                .flat_map(|(k, bits)| {
                    let bits = bits.unwrap_or(0);
                    (0..4)
                        .filter(move |b| bits & (1 << b) != 0)
                        .map(move |b| (k, b))
                })
                .collect();
            assert_eq!(lit, expected, "poll {i}");
        }
    }

    #[test]
    fn names_the_file_that_is_not_mcap() {
        let path =
            std::env::temp_dir().join(format!("monitor-notmcap-{}.mcap", std::process::id()));
        std::fs::write(&path, b"hello").unwrap();
        let err = open_trial(&path).unwrap_err().to_string();
        std::fs::remove_file(&path).ok();
        assert!(err.contains("monitor-notmcap"), "{err}");
    }
}
