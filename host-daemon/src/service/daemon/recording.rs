//! A trial's recorder on a thread of its own: the hub hands it each message ([`Recorded`])
//! and goes on, so the recorder's chunk compression, its flushes (every 100 ms) and its syncs
//! (every `recording.sync_interval_s`) never delay what the hub does with the next poll (the
//! stream, the live estimate, Foxglove).
//!
//! A write that fails, or a queue that fills because the disk stalls, is a failure the hub
//! reads ([`RecordingThread::failure`]) and ends the trial with; the messages after it are
//! dropped, and the file is still finalized (as far as the disk allows) when the trial ends.

use antenna_data::record::{
    EstimateMessage, LogMessage, PhysicsStepMessage, RecordCounts, RecordError, SegmentsMessage,
    ServoMessage, StageMessage, TrialRecorder,
};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Batches queued for the recorder at most: a minute of polls at 1 kHz with the stage, the
/// servo and the estimate. A disk that falls that far behind ends the trial.
pub(super) const QUEUE_CAPACITY: usize = 1 << 12;

/// Messages gathered into one batch at most: the thread wakes once per batch, not once per
/// message (at 1 kHz, a wake-up per message cost about a percent of a core).
pub(super) const BATCH_MESSAGES: usize = 64;

/// A batch is handed over at the latest this long after its first message.
pub(super) const BATCH_WAIT: Duration = Duration::from_millis(10);

/// One message for the recording, its time already set.
#[derive(Debug)]
pub(super) enum Recorded {
    Segments(SegmentsMessage),
    Stage(StageMessage),
    Servo(ServoMessage),
    Physics(PhysicsStepMessage),
    Log(LogMessage),
    Estimate(EstimateMessage),
}

impl Recorded {
    fn t_s(&self) -> f64 {
        match self {
            Recorded::Segments(m) => m.t_s,
            Recorded::Stage(m) => m.t_s,
            Recorded::Servo(m) => m.t_s,
            Recorded::Physics(m) => m.t_s,
            Recorded::Log(m) => m.t_s,
            Recorded::Estimate(m) => m.t_s,
        }
    }

    fn write(&self, recorder: &mut TrialRecorder) -> Result<(), RecordError> {
        match self {
            Recorded::Segments(m) => recorder.record_segments(m),
            Recorded::Stage(m) => recorder.record_stage(m),
            Recorded::Servo(m) => recorder.record_servo(m),
            Recorded::Physics(m) => recorder.record_physics(m),
            Recorded::Log(m) => recorder.record_log(m),
            Recorded::Estimate(m) => recorder.record_estimate(m),
        }?;
        recorder.flush_if_due(self.t_s())
    }
}

/// What the thread leaves when it ends: the counts written and how the file was closed.
type Finished = (RecordCounts, Result<(), String>);

/// The recorder's thread (see the [module documentation](self)).
pub(super) struct RecordingThread {
    path: PathBuf,
    queue: Option<SyncSender<Vec<Recorded>>>,
    /// Messages not handed over yet, and when the first of them came.
    batch: Vec<Recorded>,
    batch_since: Option<Instant>,
    failure: Arc<Mutex<Option<String>>>,
    thread: Option<JoinHandle<Finished>>,
}

impl RecordingThread {
    /// Starts the thread that owns `recorder`.
    ///
    /// # Errors
    /// When no thread can be started.
    pub(super) fn start(recorder: TrialRecorder) -> std::io::Result<Self> {
        let path = recorder.path().to_path_buf();
        let (queue, jobs) = sync_channel(QUEUE_CAPACITY);
        let failure = Arc::new(Mutex::new(None));
        let thread = {
            let failure = Arc::clone(&failure);
            std::thread::Builder::new()
                .name("antennad-record".to_owned())
                .spawn(move || write_all(recorder, &jobs, &failure))?
        };
        Ok(Self {
            path,
            queue: Some(queue),
            batch: Vec::with_capacity(BATCH_MESSAGES),
            batch_since: None,
            failure,
            thread: Some(thread),
        })
    }

    /// The file being written.
    pub(super) fn path(&self) -> &Path {
        &self.path
    }

    /// Gathers `message` into the batch, handed over when it is full (never blocks).
    pub(super) fn record(&mut self, message: Recorded) {
        self.batch_since.get_or_insert_with(Instant::now);
        self.batch.push(message);
        if self.batch.len() >= BATCH_MESSAGES {
            self.hand_over();
        }
    }

    /// Hands the batch over if its first message has waited [`BATCH_WAIT`] (the hub calls it
    /// on every turn of its loop).
    pub(super) fn hand_over_if_due(&mut self) {
        if self.batch_since.is_some_and(|t| t.elapsed() >= BATCH_WAIT) {
            self.hand_over();
        }
    }

    /// Queues the batch (never blocks). A full queue (the disk has stalled) is a failure.
    fn hand_over(&mut self) {
        self.batch_since = None;
        if self.batch.is_empty() {
            return;
        }
        let batch = std::mem::replace(&mut self.batch, Vec::with_capacity(BATCH_MESSAGES));
        let Some(queue) = &self.queue else { return };
        if let Err(TrySendError::Full(_)) = queue.try_send(batch) {
            self.fail(format!(
                "the recording fell {QUEUE_CAPACITY} batches of up to {BATCH_MESSAGES} messages \
                 behind (the disk has stalled)"
            ));
        }
    }

    /// Why the recording failed, once it has.
    pub(super) fn failure(&self) -> Option<String> {
        self.failure.lock().ok().and_then(|f| f.clone())
    }

    fn fail(&self, why: String) {
        if let Ok(mut failure) = self.failure.lock() {
            failure.get_or_insert(why);
        }
    }

    /// Writes `last` after everything queued, closes the file and ends the thread: the counts
    /// written and whether the file was closed cleanly.
    pub(super) fn finish(mut self, last: Recorded) -> Finished {
        self.batch.push(last);
        let batch = std::mem::take(&mut self.batch);
        if let Some(queue) = self.queue.take() {
            // Blocks only while the thread drains what is queued (the trial is ending).
            let _ = queue.send(batch);
        }
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(finished)) => finished,
            Some(Err(_)) => (
                RecordCounts::default(),
                Err("the recording thread panicked".to_owned()),
            ),
            None => (
                RecordCounts::default(),
                Err("no recording thread".to_owned()),
            ),
        }
    }
}

impl Drop for RecordingThread {
    /// A thread still running (the hub unwinding) is told to finish and left to do it.
    fn drop(&mut self) {
        self.queue.take();
    }
}

/// The thread: every message in order until the queue closes; after a failure the rest are
/// dropped; then the file is finalized.
fn write_all(
    mut recorder: TrialRecorder,
    jobs: &Receiver<Vec<Recorded>>,
    failure: &Mutex<Option<String>>,
) -> Finished {
    let mut failed = false;
    for message in jobs.iter().flatten() {
        if failed {
            continue;
        }
        if let Err(e) = message.write(&mut recorder) {
            failed = true;
            if let Ok(mut failure) = failure.lock() {
                failure.get_or_insert(e.to_string());
            }
        }
    }
    let written = recorder.written();
    let closed = recorder.finish().map(|_| ()).map_err(|e| e.to_string());
    (written, closed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use antenna_data::record::{TrialMetadata, TrialReader};
    use std::collections::BTreeMap;

    #[test]
    fn every_message_queued_is_in_the_file_after_finish_in_order() {
        let dir = std::env::temp_dir().join(format!("recording-thread-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("trial.mcap");
        let _ = std::fs::remove_file(&path);
        let metadata = TrialMetadata {
            trial: "thread".to_owned(),
            started_unix_s: 0.0,
            started_unix_ns: None,
            config: String::new(),
            notes: BTreeMap::new(),
            rig: None,
        };
        let mut thread =
            RecordingThread::start(TrialRecorder::create(&path, &metadata).unwrap()).unwrap();
        assert_eq!(thread.path(), path);
        for k in 0..2_000u32 {
            let t_s = f64::from(k) * 1e-3;
            thread.record(Recorded::Segments(SegmentsMessage {
                seq: Some(u64::from(k)),
                t_s,
                segments: Vec::new(),
            }));
            if k % 20 == 0 {
                thread.record(Recorded::Stage(StageMessage {
                    t_s,
                    position_m: f64::from(k) * 1e-5,
                }));
            }
        }
        let (written, closed) = thread.finish(Recorded::Log(LogMessage {
            t_s: 2.0,
            text: "trial ended: the test".to_owned(),
        }));
        assert_eq!(closed, Ok(()));
        assert_eq!(
            (written.segments, written.stage, written.log),
            (2_000, 100, 1)
        );
        let trial = TrialReader::read(&path).unwrap();
        let seqs: Vec<u64> = trial.segments.iter().filter_map(|s| s.seq).collect();
        assert_eq!(seqs, (0..2_000).collect::<Vec<u64>>());
        assert_eq!(
            trial.log.last().map(|l| l.text.as_str()),
            Some("trial ended: the test")
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
