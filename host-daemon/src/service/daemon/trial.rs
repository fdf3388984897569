//! Trials on the hub: started by a client or at start (a recording opened, the script
//! handed to the motion thread), ended by a command, their duration, their script, a lost
//! stage or a disk filling up (the file finalized with the reason).

use super::TrialOutcome;
use super::control::HubRequest;
use super::hub::Hub;
use super::recording::{Recorded, RecordingThread};
use super::rig_info::rig_info;
use super::start::trial_names;
use crate::config::WallSideName;
use crate::net::ControlToken;
use crate::net::foxglove::chain_model;
use crate::service::motion::MotionCommand;
use antenna_data::record::{
    FoxgloveOptions, LogMessage, RecordCounts, TrialMetadata, TrialRecorder,
};
use anyhow::Result;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// `text` with every occurrence of the token replaced: what a client asks to record never
/// carries it into a file.
fn scrub(text: &str, token: &ControlToken) -> String {
    text.replace(token.expose(), "<redacted>")
}

/// How often the free space under the data directory is looked at during a trial.
const FREE_SPACE_CHECK: Duration = Duration::from_secs(1);

/// `<dir>/<name>.mcap`, or `<dir>/<name>-2.mcap` and so on if it exists.
fn free_path(dir: &Path, name: &str) -> PathBuf {
    let first = dir.join(format!("{name}.mcap"));
    if !first.exists() {
        return first;
    }
    (2u32..)
        .map(|k| dir.join(format!("{name}-{k}.mcap")))
        .find(|p| !p.exists())
        .unwrap_or(first)
}

/// A trial being recorded.
pub(super) struct ActiveTrial {
    pub(super) id: u64,
    pub(super) name: String,
    pub(super) start_ns: u64,
    /// Zero: until the script is done.
    pub(super) duration: Duration,
    /// The recording, on its own thread.
    pub(super) recorder: Option<RecordingThread>,
    pub(super) print_every: u64,
}

impl Hub {
    pub(super) fn on_request(&mut self, request: HubRequest) {
        match request {
            HubRequest::Start {
                name,
                metadata,
                reply,
            } => {
                let _ = reply.send(self.start_trial(&name, metadata, None));
            }
            HubRequest::Stop { why, reply } => {
                let answer = if self.trial.is_some() {
                    Ok(self.end_trial(why))
                } else {
                    Err("no trial is running".to_owned())
                };
                let _ = reply.send(answer);
            }
        }
    }

    pub(super) fn start_trial(
        &mut self,
        name: &str,
        metadata: BTreeMap<String, String>,
        duration: Option<Duration>,
    ) -> Result<String, String> {
        if let Some(trial) = &self.trial {
            return Err(format!(
                "trial {:?} is already running; send stop_trial first",
                trial.name
            ));
        }
        let Some(config) = self.config.trial(Some(name)).cloned() else {
            return Err(format!(
                "no trial {name:?} in the configuration (trials: {})",
                trial_names(&self.config)
            ));
        };
        let mut notes = config.metadata.clone();
        notes.extend(metadata);
        let notes = notes
            .into_iter()
            .map(|(k, v)| (scrub(&k, &self.token), scrub(&v, &self.token)))
            .collect();
        let start_ns = self.clock.elapsed_ns();
        let recorder = if self.options.record {
            let dir = &self.config.data_dir;
            std::fs::create_dir_all(dir)
                .map_err(|e| format!("creating the data directory {}: {e}", dir.display()))?;
            if let Some(short) = self.free_space_short() {
                return Err(format!("trial {:?} refused: {short}", config.name));
            }
            let path = free_path(dir, &config.name);
            let started_unix_ns = self.unix_origin_ns.saturating_add(start_ns);
            let metadata = TrialMetadata {
                trial: config.name.clone(),
                started_unix_s: started_unix_ns as f64 * 1e-9,
                started_unix_ns: Some(started_unix_ns),
                config: scrub(&self.config.to_recorded_toml(), &self.token),
                notes,
                rig: Some(rig_info(&self.config)),
            };
            let options = self.config.recording.recorder_options();
            // The recording's Foxglove channels draw the chain Foxglove live draws.
            let foxglove = FoxgloveOptions {
                chain: Some(chain_model(&self.config)),
                scene_hz: self.config.foxglove.scene_hz,
                wall_on_left: self.config.estimate.wall_side == WallSideName::Left,
            };
            let recorder = TrialRecorder::create_with_foxglove(&path, &metadata, options, foxglove)
                .map_err(|e| format!("creating the recording {}: {e}", path.display()))?;
            Some(
                RecordingThread::start(recorder)
                    .map_err(|e| format!("starting the recording's thread: {e}"))?,
            )
        } else {
            None
        };
        self.free_check_due = Instant::now() + FREE_SPACE_CHECK;
        let id = self.next_trial_id;
        self.next_trial_id += 1;
        let duration = duration.unwrap_or(Duration::from_secs_f64(config.duration_s));
        let moves = config
            .moves
            .iter()
            .map(|m| format!("{:+} mm at {} mm/s", m.distance_mm, m.speed_mm_per_s))
            .collect::<Vec<_>>()
            .join(", then ");
        let mut message = format!(
            "trial {:?} started: base angle {} deg, stage moves {}, {}",
            config.name,
            config.base_angle_deg,
            if moves.is_empty() { "none" } else { &moves },
            if duration.is_zero() {
                "until its moves are done".to_owned()
            } else {
                format!("for {} s", duration.as_secs_f64())
            }
        );
        if let Some(recorder) = &recorder {
            message.push_str(&format!("; recording to {}", recorder.path().display()));
        }
        self.log.line(format!("antennad: {message}"));
        if self.options.echo {
            self.log.sample(format!(
                "{:>7} {:>8}  joint angles, deg (base to tip)                      touch",
                "t_s", "stage_mm"
            ));
        }
        let print_every = ((self.config.bus.poll_hz / self.options.print_hz).round() as u64).max(1);
        self.trial = Some(ActiveTrial {
            id,
            name: config.name.clone(),
            start_ns,
            duration,
            recorder,
            print_every,
        });
        if let Ok(mut state) = self.trial_state.lock() {
            *state = Some(config.name.clone());
        }
        let _ = self.motion.send(MotionCommand::RunScript {
            id,
            trial: Box::new(config),
        });
        self.note = Some(message.clone());
        self.publish_status();
        Ok(message)
    }

    /// Ends the running trial (there must be one): stops its script and the stage, finalizes
    /// the file. Returns what happened.
    pub(super) fn end_trial(&mut self, why: &str) -> String {
        let Some(trial) = self.trial.take() else {
            return "no trial was running".to_owned();
        };
        if let Ok(mut state) = self.trial_state.lock() {
            *state = None;
        }
        let _ = self.motion.send(MotionCommand::EndScript);
        let (path, recorded, result) = match trial.recorder {
            Some(recording) => {
                // The reason is the file's last word (a full disk may refuse even that).
                let t_s = self.clock.elapsed_ns().saturating_sub(trial.start_ns) as f64 * 1e-9;
                let path = recording.path().to_path_buf();
                let (written, result) = recording.finish(Recorded::Log(LogMessage {
                    t_s,
                    text: format!("trial ended: {why}"),
                }));
                (Some(path), written, result)
            }
            None => (None, RecordCounts::default(), Ok(())),
        };
        let mut message = format!("trial {:?} ended ({why})", trial.name);
        if let Some(path) = &path {
            match result {
                Ok(()) => message.push_str(&format!(
                    "; recorded {} polls, {} stage and {} servo samples to {}",
                    recorded.segments,
                    recorded.stage,
                    recorded.servo,
                    path.display()
                )),
                Err(e) => message.push_str(&format!("; closing {} failed: {e}", path.display())),
            }
        }
        self.log.line(format!("antennad: {message}"));
        self.outcomes.push(TrialOutcome {
            name: trial.name,
            path,
            recorded,
            ended: why.to_owned(),
        });
        if self.options.exit_after_trial {
            self.finished = true;
        }
        self.note = Some(message.clone());
        self.publish_status();
        message
    }

    /// Why the data directory has too little room for a recording, if it has.
    fn free_space_short(&self) -> Option<String> {
        let dir = &self.config.data_dir;
        let min_bytes = self.config.recording.min_free_bytes();
        match self.options.free_space.free_bytes(dir) {
            Ok(free) if free < min_bytes => Some(format!(
                "the disk holding {} is nearly full: {:.1} MB free, below recording.min_free_mb \
                 = {} MB",
                dir.display(),
                free as f64 * 1e-6,
                self.config.recording.min_free_mb
            )),
            Ok(_) => None,
            Err(e) => Some(format!(
                "the free space under {} cannot be read: {e}",
                dir.display()
            )),
        }
    }

    pub(super) fn check_trial_end(&mut self) {
        if self.trial.as_ref().is_some_and(|t| t.recorder.is_some())
            && Instant::now() >= self.free_check_due
        {
            self.free_check_due = Instant::now() + FREE_SPACE_CHECK;
            if let Some(short) = self.free_space_short() {
                self.log
                    .warn(format!("antennad: {short}; ending the trial"));
                let why: &'static str = "the disk is nearly full";
                self.record_log(self.clock.elapsed_ns(), &short);
                self.end_trial(why);
                return;
            }
        }
        let Some(trial) = &self.trial else { return };
        if let Some(why) = self.script_ends.failure(trial.id) {
            self.end_trial(&why);
            return;
        }
        let elapsed_ns = self.clock.elapsed_ns().saturating_sub(trial.start_ns);
        let why = if trial.duration.is_zero() {
            self.script_ends
                .is_done(trial.id)
                .then_some("its moves are done")
        } else {
            (u128::from(elapsed_ns) >= trial.duration.as_nanos()).then_some("its duration passed")
        };
        if let Some(why) = why {
            self.end_trial(why);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_token_never_reaches_a_recording() {
        let token = ControlToken::new("s3cret-s3cret-s3cret").unwrap();
        assert_eq!(
            scrub(
                "operator=s3cret-s3cret-s3cret; again s3cret-s3cret-s3cret",
                &token
            ),
            "operator=<redacted>; again <redacted>"
        );
    }

    #[test]
    fn a_recording_never_overwrites_another() {
        let dir = std::env::temp_dir().join(format!("antennad-free-path-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        assert_eq!(free_path(&dir, "t"), dir.join("t.mcap"));
        std::fs::write(dir.join("t.mcap"), b"").unwrap();
        std::fs::write(dir.join("t-2.mcap"), b"").unwrap();
        assert_eq!(free_path(&dir, "t"), dir.join("t-3.mcap"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
