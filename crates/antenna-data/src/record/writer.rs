//! [`TrialRecorder`]: one trial to one MCAP file, flushed at least every 100 ms of trial time.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use mcap::records::{MessageHeader, Metadata};
use mcap::{WriteOptions, Writer};
use serde::Serialize;
use serde_json::Value;

use super::error::RecordError;
use super::messages::{LogMessage, SegmentsMessage, ServoMessage, StageMessage, TrialMetadata};
use super::schema::{
    LOG_TOPIC, MESSAGE_ENCODING, METADATA_TOPIC, SCHEMA_ENCODING, SEGMENTS_TOPIC, SERVO_TOPIC,
    STAGE_TOPIC, log_schema, metadata_schema, segments_schema, servo_schema, stage_schema,
};

/// The default and largest flush interval, s of trial time.
pub const FLUSH_INTERVAL_S: f64 = 0.1;

/// How many messages of each kind are recorded, and how many of them are flushed (readable
/// after a crash).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RecordCounts {
    /// `/antenna/segments` messages.
    pub segments: u64,
    /// `/antenna/stage` messages.
    pub stage: u64,
    /// `/antenna/servo` messages.
    pub servo: u64,
    /// `/trial/log` messages.
    pub log: u64,
}

#[derive(Debug, Clone, Copy)]
struct Channel {
    id: u16,
    sequence: u32,
}

/// Records one trial to an MCAP file.
///
/// The file holds the JSON schemas and one channel per topic (see [`super::schema`]); the
/// metadata is written first. Messages go into chunks (uncompressed); a flush closes the
/// current chunk, writes it and flushes the file to the OS, so everything written before a
/// flush survives the process being killed (`kill -9`): the file then lacks its summary and
/// footer, and [`super::TrialReader`] (or any reader that reads the data section linearly,
/// such as Python's `mcap` `make_reader` on a stream) gets every message up to the last flush.
/// The recorder flushes by itself whenever a message is at least [`FLUSH_INTERVAL_S`] of
/// trial time after the last flush; the daemon should also call [`Self::flush_if_due`] from
/// its timer so that a pause in messages does not hold one back. (Flushing reaches the OS,
/// not the disk: a power cut may lose what the OS has not written yet.)
///
/// [`Self::finish`] writes the summary and footer; dropping the recorder does the same,
/// ignoring errors.
pub struct TrialRecorder {
    path: PathBuf,
    writer: Writer<BufWriter<File>>,
    segments: Channel,
    stage: Channel,
    servo: Channel,
    /// Added with the first log line, so a trial with none has no `/trial/log` channel.
    log: Option<Channel>,
    flush_interval_s: f64,
    last_flush_t_s: f64,
    written: RecordCounts,
    flushed: RecordCounts,
    /// Messages written since the last flush.
    dirty: bool,
}

impl std::fmt::Debug for TrialRecorder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TrialRecorder")
            .field("path", &self.path)
            .field("written", &self.written)
            .field("flushed", &self.flushed)
            .finish_non_exhaustive()
    }
}

impl TrialRecorder {
    /// Creates (or truncates) `path`, writes the header, schemas, channels and `metadata`, and
    /// flushes, so that even a trial killed at once leaves a readable file.
    pub fn create(path: impl AsRef<Path>, metadata: &TrialMetadata) -> Result<Self, RecordError> {
        let path = path.as_ref().to_path_buf();
        let file = File::create(&path).map_err(|source| RecordError::Io {
            path: path.clone(),
            source,
        })?;
        let mcap_err = |p: &Path| {
            let p = p.to_path_buf();
            move |source| RecordError::Mcap { path: p, source }
        };
        let mut writer = WriteOptions::new()
            .compression(None)
            .profile("")
            .library(concat!("antennad ", env!("CARGO_PKG_VERSION")))
            .create(BufWriter::new(file))
            .map_err(mcap_err(&path))?;
        let channel = |writer: &mut Writer<BufWriter<File>>,
                       topic: &str,
                       name: &str,
                       schema: Value|
         -> Result<Channel, RecordError> {
            let data = serde_json::to_vec(&schema).map_err(|source| RecordError::Json {
                path: path.clone(),
                topic: topic.to_string(),
                source,
            })?;
            let schema_id = writer
                .add_schema(name, SCHEMA_ENCODING, &data)
                .map_err(mcap_err(&path))?;
            let id = writer
                .add_channel(schema_id, topic, MESSAGE_ENCODING, &BTreeMap::new())
                .map_err(mcap_err(&path))?;
            Ok(Channel { id, sequence: 0 })
        };
        let mut meta = channel(
            &mut writer,
            METADATA_TOPIC,
            "antenna.TrialMetadata",
            metadata_schema(),
        )?;
        let segments = channel(
            &mut writer,
            SEGMENTS_TOPIC,
            "antenna.Segments",
            segments_schema(),
        )?;
        let stage = channel(&mut writer, STAGE_TOPIC, "antenna.Stage", stage_schema())?;
        let servo = channel(&mut writer, SERVO_TOPIC, "antenna.Servo", servo_schema())?;
        let mut recorder = Self {
            path,
            writer,
            segments,
            stage,
            servo,
            log: None,
            flush_interval_s: FLUSH_INTERVAL_S,
            last_flush_t_s: 0.0,
            written: RecordCounts::default(),
            flushed: RecordCounts::default(),
            dirty: false,
        };
        recorder.write(METADATA_TOPIC, &mut meta, 0.0, metadata)?;
        recorder
            .writer
            .write_metadata(&Metadata {
                name: "trial".to_string(),
                metadata: metadata.to_key_values(),
            })
            .map_err(mcap_err(&recorder.path))?;
        recorder.flush()?;
        Ok(recorder)
    }

    /// Flushes more often than every [`FLUSH_INTERVAL_S`]: `interval_s` is clamped to
    /// `0..=FLUSH_INTERVAL_S` (0 flushes after every message).
    pub fn set_flush_interval_s(&mut self, interval_s: f64) {
        self.flush_interval_s = if interval_s.is_nan() {
            FLUSH_INTERVAL_S
        } else {
            interval_s.clamp(0.0, FLUSH_INTERVAL_S)
        };
    }

    /// The trial file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Messages written so far (flushed or not).
    pub fn written(&self) -> RecordCounts {
        self.written
    }

    /// Messages flushed so far: these survive a crash.
    pub fn flushed(&self) -> RecordCounts {
        self.flushed
    }

    /// Records one poll of the segments.
    pub fn record_segments(&mut self, message: &SegmentsMessage) -> Result<(), RecordError> {
        let mut channel = self.segments;
        self.write(SEGMENTS_TOPIC, &mut channel, message.t_s, message)?;
        self.segments = channel;
        self.written.segments += 1;
        self.flush_if_due(message.t_s)
    }

    /// Records a stage position.
    pub fn record_stage(&mut self, message: &StageMessage) -> Result<(), RecordError> {
        let mut channel = self.stage;
        self.write(STAGE_TOPIC, &mut channel, message.t_s, message)?;
        self.stage = channel;
        self.written.stage += 1;
        self.flush_if_due(message.t_s)
    }

    /// Records a base angle.
    pub fn record_servo(&mut self, message: &ServoMessage) -> Result<(), RecordError> {
        let mut channel = self.servo;
        self.write(SERVO_TOPIC, &mut channel, message.t_s, message)?;
        self.servo = channel;
        self.written.servo += 1;
        self.flush_if_due(message.t_s)
    }

    /// Records a log line.
    pub fn record_log(&mut self, message: &LogMessage) -> Result<(), RecordError> {
        let mut channel = match self.log {
            Some(channel) => channel,
            None => self.add_channel(LOG_TOPIC, "antenna.Log", &log_schema())?,
        };
        self.write(LOG_TOPIC, &mut channel, message.t_s, message)?;
        self.log = Some(channel);
        self.written.log += 1;
        self.flush_if_due(message.t_s)
    }

    /// Flushes if `now_t_s` (trial time, s) is at least the flush interval after the last
    /// flush. Call it from the daemon's timer too.
    pub fn flush_if_due(&mut self, now_t_s: f64) -> Result<(), RecordError> {
        if now_t_s - self.last_flush_t_s >= self.flush_interval_s {
            self.last_flush_t_s = now_t_s;
            self.flush()?;
        }
        Ok(())
    }

    /// Closes the current chunk and flushes the file to the OS: everything recorded so far
    /// survives a crash.
    pub fn flush(&mut self) -> Result<(), RecordError> {
        if !self.dirty {
            return Ok(());
        }
        self.writer.flush().map_err(|source| RecordError::Mcap {
            path: self.path.clone(),
            source,
        })?;
        self.flushed = self.written;
        self.dirty = false;
        Ok(())
    }

    /// Writes the summary and footer and closes the file; returns its path.
    pub fn finish(mut self) -> Result<PathBuf, RecordError> {
        self.writer.finish().map_err(|source| RecordError::Mcap {
            path: self.path.clone(),
            source,
        })?;
        self.flushed = self.written;
        Ok(self.path.clone())
    }

    fn add_channel(
        &mut self,
        topic: &str,
        name: &str,
        schema: &Value,
    ) -> Result<Channel, RecordError> {
        let data = serde_json::to_vec(schema).map_err(|source| RecordError::Json {
            path: self.path.clone(),
            topic: topic.to_string(),
            source,
        })?;
        let mcap_err = |source| RecordError::Mcap {
            path: self.path.clone(),
            source,
        };
        let schema_id = self
            .writer
            .add_schema(name, SCHEMA_ENCODING, &data)
            .map_err(mcap_err)?;
        let id = self
            .writer
            .add_channel(schema_id, topic, MESSAGE_ENCODING, &BTreeMap::new())
            .map_err(mcap_err)?;
        Ok(Channel { id, sequence: 0 })
    }

    fn write<T: Serialize>(
        &mut self,
        topic: &str,
        channel: &mut Channel,
        t_s: f64,
        message: &T,
    ) -> Result<(), RecordError> {
        if !(t_s.is_finite() && t_s >= 0.0) {
            return Err(RecordError::BadTime {
                path: self.path.clone(),
                t_s,
            });
        }
        let data = serde_json::to_vec(message).map_err(|source| RecordError::Json {
            path: self.path.clone(),
            topic: topic.to_string(),
            source,
        })?;
        // Whole nanoseconds; a trial would need 584 years to overflow.
        let log_time = (t_s * 1e9).round() as u64;
        let header = MessageHeader {
            channel_id: channel.id,
            sequence: channel.sequence,
            log_time,
            publish_time: log_time,
        };
        self.writer
            .write_to_known_channel(&header, &data)
            .map_err(|source| RecordError::Mcap {
                path: self.path.clone(),
                source,
            })?;
        channel.sequence = channel.sequence.wrapping_add(1);
        self.dirty = true;
        Ok(())
    }
}
