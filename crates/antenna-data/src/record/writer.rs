//! [`TrialRecorder`]: one trial to one MCAP file, in compressed chunks, flushed at least every
//! 100 ms of trial time, synced to the disk at an interval and at the end.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use mcap::records::{MessageHeader, Metadata};
use mcap::{Compression, WriteOptions, Writer};
use serde::Serialize;
use serde_json::Value;

use foxglove::messages::{FrameTransforms, SceneUpdate};

use super::error::RecordError;
use super::messages::{
    EstimateMessage, LogMessage, PhysicsStepMessage, SegmentsMessage, ServoMessage, StageMessage,
    TrialMetadata,
};
use super::schema::{
    ESTIMATE_TOPIC, LOG_TOPIC, MESSAGE_ENCODING, METADATA_TOPIC, PHYSICS_TOPIC, SCENE_TOPIC,
    SCHEMA_ENCODING, SEGMENTS_TOPIC, SERVO_TOPIC, STAGE_TOPIC, TRANSFORMS_TOPIC, estimate_schema,
    log_schema, metadata_schema, physics_schema, segments_schema, servo_schema, stage_schema,
};
use super::sealed_file::SealedFile;
use crate::foxglove::{
    ChainModel, ChainPose, ChannelSchema, EstimatedWall, chain_scene_update, encode_into,
    frame_transforms, scene_update,
};

/// The default and largest flush interval, s of trial time.
pub const FLUSH_INTERVAL_S: f64 = 0.1;

/// How the chunks of a trial file are compressed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ChunkCompression {
    /// Zstandard (MCAP's `zstd`, level 3): about 25 times smaller on the default trial.
    #[default]
    Zstd,
    /// Uncompressed.
    None,
}

impl ChunkCompression {
    /// The name MCAP files use (`zstd`, or empty for none).
    pub fn mcap_name(self) -> &'static str {
        match self {
            Self::Zstd => "zstd",
            Self::None => "",
        }
    }
}

/// How a [`TrialRecorder`] writes; `Default` gives the documented values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecorderOptions {
    /// Chunk compression (default zstd).
    pub compression: ChunkCompression,
    /// How often the file is synced to the disk (`fdatasync`), s of trial time, on top of the
    /// sync at [`TrialRecorder::finish`]; 0 syncs only there (default 1 s).
    pub sync_interval_s: f64,
}

impl Default for RecorderOptions {
    fn default() -> Self {
        Self {
            compression: ChunkCompression::Zstd,
            sync_interval_s: 1.0,
        }
    }
}

/// The default rate of the Foxglove channels (`/antenna/transforms`, `/antenna/scene`), Hz.
pub const DEFAULT_SCENE_HZ: f64 = 50.0;

/// How often the walls are drawn again in `/antenna/scene`, s of trial time (they do not
/// move; a viewer keeps them between updates).
pub const WALLS_INTERVAL_S: f64 = 1.0;

/// What a [`TrialRecorder`] draws in Foxglove's standard schemas (`/antenna/transforms`,
/// `/antenna/scene`: [`crate::foxglove`]); `Default` gives the documented values.
#[derive(Debug, Clone, PartialEq)]
pub struct FoxgloveOptions {
    /// The chain, where it sits and the walls; `None` (the default) takes the links and base
    /// mount angle from the metadata's rig ([`ChainModel::from_rig`]: the base pivot at the
    /// origin, the stage travelling along `x`, no walls). With neither, the file has no
    /// Foxglove channels.
    pub chain: Option<ChainModel>,
    /// How often the frames and the scene are recorded, Hz of trial time (default
    /// [`DEFAULT_SCENE_HZ`]); 0 (or not finite) records none.
    pub scene_hz: f64,
    /// The estimated wall is on the left of the stage's travel (default `true`), for drawing
    /// the estimates of [`TrialRecorder::record_estimate`].
    pub wall_on_left: bool,
}

impl Default for FoxgloveOptions {
    fn default() -> Self {
        Self {
            chain: None,
            scene_hz: DEFAULT_SCENE_HZ,
            wall_on_left: true,
        }
    }
}

/// How many messages of each kind are recorded, flushed (readable after a crash) or synced
/// (on the disk).
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
    /// `/sim/physics` messages.
    pub physics: u64,
    /// `/antenna/estimate` messages.
    pub estimate: u64,
    /// `/antenna/transforms` messages (Foxglove's frames).
    pub transforms: u64,
    /// `/antenna/scene` messages (Foxglove's 3D scene).
    pub scene: u64,
}

#[derive(Debug, Clone, Copy)]
struct Channel {
    id: u16,
    sequence: u32,
}

/// The Foxglove channels' state: the newest readings, drawn at the scene rate.
#[derive(Debug)]
struct SceneRecorder {
    model: ChainModel,
    transforms: Channel,
    scene: Channel,
    period_s: f64,
    /// Trial time of the next frames and scene.
    next_t_s: f64,
    /// Trial time of the next scene with the walls.
    next_walls_t_s: f64,
    wall_on_left: bool,
    /// The newest stage position (0 until the first: a rig without a stage stays there).
    stage_m: f64,
    /// The newest servo angle (0 until the first: a rig without a servo stays there).
    servo_rad: f64,
    joint_angles_rad: Vec<Option<f64>>,
    touch_bits: Vec<Option<u8>>,
    estimate: Option<EstimatedWall>,
    buf: Vec<u8>,
}

impl SceneRecorder {
    /// Whether a poll at `t_s` is due for the frames and the scene; if so, the next is set.
    fn due(&mut self, t_s: f64) -> bool {
        if t_s < self.next_t_s {
            return false;
        }
        self.next_t_s += self.period_s;
        if self.next_t_s <= t_s {
            self.next_t_s = t_s + self.period_s;
        }
        true
    }

    /// Whether the scene at `t_s` draws the walls too; if so, the next is set.
    fn walls_due(&mut self, t_s: f64) -> bool {
        if t_s < self.next_walls_t_s {
            return false;
        }
        self.next_walls_t_s = t_s + WALLS_INTERVAL_S;
        true
    }
}

/// Records one trial to an MCAP file.
///
/// The file holds the JSON schemas and one channel per topic (see [`super::schema`]); the
/// metadata is written first. Messages go into zstd-compressed chunks (MCAP's own
/// compression, which every MCAP reader undoes). A flush closes the current chunk and writes
/// it with a provisional end of file ([`super::sealed_file`]), so after every flush the file
/// is a complete MCAP file that standard readers open without recovery: a process killed
/// with `kill -9` loses only what came after its last flush. The recorder flushes by itself
/// whenever a message is at least [`FLUSH_INTERVAL_S`] of trial time after the last flush;
/// the daemon should also call [`Self::flush_if_due`] from its timer so that a pause in
/// messages does not hold one back.
///
/// A flush reaches the operating system; the file is synced to the disk every
/// [`RecorderOptions::sync_interval_s`] and at [`Self::finish`], which also writes the
/// summary and footer. Dropping the recorder finishes it too, ignoring errors.
///
/// Message log times are Unix-epoch nanoseconds: the metadata's start plus each message's
/// `t_s`, so a trial lines up with video and other logs.
pub struct TrialRecorder {
    path: PathBuf,
    writer: Option<Writer<SealedFile>>,
    /// The same file, for syncing (the writer hands out its file only when finished).
    sync_handle: std::fs::File,
    /// Unix-epoch nanoseconds of `t_s = 0`.
    epoch_ns: u64,
    segments: Channel,
    stage: Channel,
    servo: Channel,
    /// Added with the first log line, so a trial with none has no `/trial/log` channel.
    log: Option<Channel>,
    /// Added with the first physics step (the simulated rig's).
    physics: Option<Channel>,
    /// Added with the first estimate.
    estimate: Option<Channel>,
    /// The Foxglove channels (none without a chain model).
    scene: Option<SceneRecorder>,
    flush_interval_s: f64,
    sync_interval_s: f64,
    last_flush_t_s: f64,
    last_sync_t_s: f64,
    written: RecordCounts,
    flushed: RecordCounts,
    synced: RecordCounts,
    /// Messages written since the last flush.
    dirty: bool,
}

impl std::fmt::Debug for TrialRecorder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TrialRecorder")
            .field("path", &self.path)
            .field("written", &self.written)
            .field("flushed", &self.flushed)
            .field("synced", &self.synced)
            .finish_non_exhaustive()
    }
}

impl TrialRecorder {
    /// [`Self::create_with`] with [`RecorderOptions::default`] (and
    /// [`FoxgloveOptions::default`]).
    ///
    /// # Errors
    /// See [`Self::create_with`].
    pub fn create(path: impl AsRef<Path>, metadata: &TrialMetadata) -> Result<Self, RecordError> {
        Self::create_with(path, metadata, RecorderOptions::default())
    }

    /// [`Self::create_with_foxglove`] with [`FoxgloveOptions::default`]: the Foxglove
    /// channels at [`DEFAULT_SCENE_HZ`], the chain from the metadata's rig.
    ///
    /// # Errors
    /// See [`Self::create_with_foxglove`].
    pub fn create_with(
        path: impl AsRef<Path>,
        metadata: &TrialMetadata,
        options: RecorderOptions,
    ) -> Result<Self, RecordError> {
        Self::create_with_foxglove(path, metadata, options, FoxgloveOptions::default())
    }

    /// Creates `path` (which must not exist: an existing file or a planted link is never
    /// overwritten), writes the header, schemas, channels and `metadata`, and flushes, so
    /// that even a trial killed at once leaves a readable file. With a chain model
    /// ([`FoxgloveOptions::chain`], or the metadata's rig), the file also has the channels
    /// `/antenna/transforms` (`foxglove.FrameTransforms`) and `/antenna/scene`
    /// (`foxglove.SceneUpdate`), protobuf, which the recorder fills itself from the polls,
    /// stage positions, servo angles and estimates it records, at
    /// [`FoxgloveOptions::scene_hz`].
    ///
    /// # Errors
    /// [`RecordError::Io`] if the file exists or cannot be written, [`RecordError::BadTime`]
    /// for a start time that is not a Unix time.
    pub fn create_with_foxglove(
        path: impl AsRef<Path>,
        metadata: &TrialMetadata,
        options: RecorderOptions,
        foxglove: FoxgloveOptions,
    ) -> Result<Self, RecordError> {
        let path = path.as_ref().to_path_buf();
        let epoch_ns = metadata
            .start_unix_ns()
            .ok_or_else(|| RecordError::BadTime {
                path: path.clone(),
                t_s: metadata.started_unix_s,
            })?;
        let file = SealedFile::create_new(&path).map_err(|source| RecordError::Io {
            path: path.clone(),
            source,
        })?;
        let sync_handle = file.sync_handle().map_err(|source| RecordError::Io {
            path: path.clone(),
            source,
        })?;
        let mcap_err = |p: &Path| {
            let p = p.to_path_buf();
            move |source| RecordError::Mcap { path: p, source }
        };
        let compression = match options.compression {
            ChunkCompression::Zstd => Some(Compression::Zstd),
            ChunkCompression::None => None,
        };
        let mut writer = WriteOptions::new()
            .compression(compression)
            // One thread: a chunk is 100 ms of data, compressed on the recording thread.
            .compression_threads(0)
            // Chunks are written whole, never through a placeholder header (see SealedFile).
            .disable_seeking(true)
            // Per-message indexes would be a third of the file (16 bytes for each ~30-byte
            // compressed message); the chunk indexes are enough for 100 ms chunks, and the
            // MCAP specification makes message indexes optional.
            .emit_message_indexes(false)
            .profile("")
            .library(concat!("antennad ", env!("CARGO_PKG_VERSION")))
            .create(file)
            .map_err(mcap_err(&path))?;
        let channel = |writer: &mut Writer<SealedFile>, topic: &str, name: &str, schema: Value| {
            add_channel(writer, &path, topic, name, &schema)
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
        let model = foxglove
            .chain
            .clone()
            .or_else(|| metadata.rig.as_ref().and_then(ChainModel::from_rig));
        let scene = match model {
            Some(model) if foxglove.scene_hz.is_finite() && foxglove.scene_hz > 0.0 => {
                let transforms =
                    add_foxglove_channel::<FrameTransforms>(&mut writer, &path, TRANSFORMS_TOPIC)?;
                let scene = add_foxglove_channel::<SceneUpdate>(&mut writer, &path, SCENE_TOPIC)?;
                let segments = model.segments();
                Some(SceneRecorder {
                    model,
                    transforms,
                    scene,
                    period_s: 1.0 / foxglove.scene_hz,
                    next_t_s: 0.0,
                    next_walls_t_s: 0.0,
                    wall_on_left: foxglove.wall_on_left,
                    stage_m: 0.0,
                    servo_rad: 0.0,
                    joint_angles_rad: vec![None; segments],
                    touch_bits: vec![None; segments],
                    estimate: None,
                    buf: Vec::new(),
                })
            }
            _ => None,
        };
        let sync_interval_s = if options.sync_interval_s.is_finite() {
            options.sync_interval_s.max(0.0)
        } else {
            0.0
        };
        let mut recorder = Self {
            path,
            writer: Some(writer),
            sync_handle,
            epoch_ns,
            segments,
            stage,
            servo,
            log: None,
            physics: None,
            estimate: None,
            scene,
            flush_interval_s: FLUSH_INTERVAL_S,
            sync_interval_s,
            last_flush_t_s: 0.0,
            last_sync_t_s: 0.0,
            written: RecordCounts::default(),
            flushed: RecordCounts::default(),
            synced: RecordCounts::default(),
            dirty: false,
        };
        recorder.write(METADATA_TOPIC, &mut meta, 0.0, metadata)?;
        let record = Metadata {
            name: "trial".to_string(),
            metadata: metadata.to_key_values(),
        };
        let path = recorder.path.clone();
        recorder
            .writer()?
            .write_metadata(&record)
            .map_err(mcap_err(&path))?;
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

    /// Unix-epoch nanoseconds of trial time 0: every message's log time is this plus its
    /// `t_s`.
    pub fn epoch_ns(&self) -> u64 {
        self.epoch_ns
    }

    /// Messages written so far (flushed or not).
    pub fn written(&self) -> RecordCounts {
        self.written
    }

    /// Messages flushed so far: these survive the process being killed.
    pub fn flushed(&self) -> RecordCounts {
        self.flushed
    }

    /// Messages synced to the disk so far: these survive a power cut.
    pub fn synced(&self) -> RecordCounts {
        self.synced
    }

    /// Records one poll of the segments.
    pub fn record_segments(&mut self, message: &SegmentsMessage) -> Result<(), RecordError> {
        let mut channel = self.segments;
        self.write(SEGMENTS_TOPIC, &mut channel, message.t_s, message)?;
        self.segments = channel;
        self.written.segments += 1;
        if let Some(mut scene) = self.scene.take() {
            scene.joint_angles_rad.clear();
            scene.touch_bits.clear();
            for sample in &message.segments {
                scene.joint_angles_rad.push(sample.angle_rad);
                scene.touch_bits.push(sample.touch);
            }
            let drawn = if scene.due(message.t_s) {
                self.draw(&mut scene, message.t_s)
            } else {
                Ok(())
            };
            self.scene = Some(scene);
            drawn?;
        }
        self.flush_if_due(message.t_s)
    }

    /// Records a stage position.
    pub fn record_stage(&mut self, message: &StageMessage) -> Result<(), RecordError> {
        let mut channel = self.stage;
        self.write(STAGE_TOPIC, &mut channel, message.t_s, message)?;
        self.stage = channel;
        self.written.stage += 1;
        if let Some(scene) = &mut self.scene {
            scene.stage_m = message.position_m;
        }
        self.flush_if_due(message.t_s)
    }

    /// Records a base angle.
    pub fn record_servo(&mut self, message: &ServoMessage) -> Result<(), RecordError> {
        let mut channel = self.servo;
        self.write(SERVO_TOPIC, &mut channel, message.t_s, message)?;
        self.servo = channel;
        self.written.servo += 1;
        if let Some(scene) = &mut self.scene {
            scene.servo_rad = message.base_angle_rad;
        }
        self.flush_if_due(message.t_s)
    }

    /// Records a log line.
    pub fn record_log(&mut self, message: &LogMessage) -> Result<(), RecordError> {
        let log = self.log;
        self.log = Some(self.write_lazy(
            log,
            (LOG_TOPIC, "antenna.Log", log_schema),
            message.t_s,
            message,
        )?);
        self.written.log += 1;
        self.flush_if_due(message.t_s)
    }

    /// Records a wall estimate; the scene draws the newest one (one without a distance or a
    /// preview point removes it).
    pub fn record_estimate(&mut self, message: &EstimateMessage) -> Result<(), RecordError> {
        let estimate = self.estimate;
        self.estimate = Some(self.write_lazy(
            estimate,
            (ESTIMATE_TOPIC, "antenna.Estimate", estimate_schema),
            message.t_s,
            message,
        )?);
        self.written.estimate += 1;
        if let Some(scene) = &mut self.scene {
            scene.estimate = match (message.distance_m, message.preview_m) {
                (Some(distance_m), Some(preview_m)) => Some(EstimatedWall {
                    distance_m,
                    wall_angle_rad: message.wall_angle_rad,
                    preview_m,
                    wall_on_left: scene.wall_on_left,
                }),
                _ => None,
            };
        }
        self.flush_if_due(message.t_s)
    }

    /// Records the chain's frames and the scene at trial time `t_s`, from the newest readings.
    fn draw(&mut self, scene: &mut SceneRecorder, t_s: f64) -> Result<(), RecordError> {
        let log_time = self.log_time(t_s)?;
        let walls = scene.walls_due(t_s);
        let pose = ChainPose {
            t_ns: log_time,
            stage_m: Some(scene.stage_m),
            servo_rad: Some(scene.servo_rad),
            joint_angles_rad: &scene.joint_angles_rad,
            touch_bits: &scene.touch_bits,
        };
        let transforms = frame_transforms(&scene.model, &pose);
        let update = if walls {
            scene_update(&scene.model, &pose, scene.estimate.as_ref())
        } else {
            chain_scene_update(&scene.model, &pose, scene.estimate.as_ref())
        };
        let mut buf = std::mem::take(&mut scene.buf);
        let result = self
            .encode_and_write(
                &mut buf,
                TRANSFORMS_TOPIC,
                &mut scene.transforms,
                log_time,
                &transforms,
            )
            .and_then(|()| {
                self.encode_and_write(&mut buf, SCENE_TOPIC, &mut scene.scene, log_time, &update)
            });
        scene.buf = buf;
        result?;
        self.written.transforms += 1;
        self.written.scene += 1;
        Ok(())
    }

    fn encode_and_write<M: foxglove::Encode>(
        &mut self,
        buf: &mut Vec<u8>,
        topic: &str,
        channel: &mut Channel,
        log_time: u64,
        message: &M,
    ) -> Result<(), RecordError> {
        buf.clear();
        encode_into(message, buf).map_err(|source| RecordError::Foxglove {
            path: self.path.clone(),
            topic: topic.to_owned(),
            source,
        })?;
        self.write_bytes(channel, log_time, buf)
    }

    /// Records one step of the simulated rig's physics.
    pub fn record_physics(&mut self, message: &PhysicsStepMessage) -> Result<(), RecordError> {
        let physics = self.physics;
        self.physics = Some(self.write_lazy(
            physics,
            (PHYSICS_TOPIC, "antenna.PhysicsStep", physics_schema),
            message.t_s,
            message,
        )?);
        self.written.physics += 1;
        self.flush_if_due(message.t_s)
    }

    /// Writes `message` on `channel`, or on a new channel `(topic, schema name, schema)` when
    /// this is the topic's first message (channels a trial may never use are added only when
    /// used); returns the channel to keep.
    fn write_lazy<T: Serialize>(
        &mut self,
        channel: Option<Channel>,
        (topic, name, schema): (&str, &str, fn() -> Value),
        t_s: f64,
        message: &T,
    ) -> Result<Channel, RecordError> {
        let mut channel = match channel {
            Some(channel) => channel,
            None => {
                let path = self.path.clone();
                add_channel(self.writer()?, &path, topic, name, &schema())?
            }
        };
        self.write(topic, &mut channel, t_s, message)?;
        Ok(channel)
    }

    /// Flushes if `now_t_s` (trial time, s) is at least the flush interval after the last
    /// flush, and syncs if it is the sync interval after the last sync. Call it from the
    /// daemon's timer too.
    pub fn flush_if_due(&mut self, now_t_s: f64) -> Result<(), RecordError> {
        if now_t_s - self.last_flush_t_s >= self.flush_interval_s {
            self.last_flush_t_s = now_t_s;
            self.flush()?;
        }
        if self.sync_interval_s > 0.0 && now_t_s - self.last_sync_t_s >= self.sync_interval_s {
            self.last_sync_t_s = now_t_s;
            self.sync()?;
        }
        Ok(())
    }

    /// Closes the current chunk and writes it out, the file sealed as a complete MCAP file:
    /// everything recorded so far survives the process being killed.
    pub fn flush(&mut self) -> Result<(), RecordError> {
        if !self.dirty {
            return Ok(());
        }
        let path = self.path.clone();
        self.writer()?
            .flush()
            .map_err(|source| RecordError::Mcap { path, source })?;
        self.flushed = self.written;
        self.dirty = false;
        Ok(())
    }

    /// Flushes, then syncs the file to the disk (`fdatasync`): everything recorded so far
    /// survives a power cut.
    pub fn sync(&mut self) -> Result<(), RecordError> {
        self.flush()?;
        if self.synced == self.flushed {
            return Ok(());
        }
        self.sync_handle
            .sync_data()
            .map_err(|source| RecordError::Io {
                path: self.path.clone(),
                source,
            })?;
        self.synced = self.flushed;
        Ok(())
    }

    /// Writes the summary and footer, syncs the file to the disk and closes it; returns its
    /// path.
    pub fn finish(mut self) -> Result<PathBuf, RecordError> {
        self.finish_in_place()?;
        Ok(self.path.clone())
    }

    fn finish_in_place(&mut self) -> Result<(), RecordError> {
        let Some(mut writer) = self.writer.take() else {
            return Ok(());
        };
        writer.finish().map_err(|source| RecordError::Mcap {
            path: self.path.clone(),
            source,
        })?;
        writer
            .into_inner()
            .close()
            .map_err(|source| RecordError::Io {
                path: self.path.clone(),
                source,
            })?;
        self.flushed = self.written;
        self.synced = self.written;
        Ok(())
    }

    fn writer(&mut self) -> Result<&mut Writer<SealedFile>, RecordError> {
        self.writer.as_mut().ok_or_else(|| RecordError::Finished {
            path: self.path.clone(),
        })
    }

    fn write<T: Serialize>(
        &mut self,
        topic: &str,
        channel: &mut Channel,
        t_s: f64,
        message: &T,
    ) -> Result<(), RecordError> {
        let log_time = self.log_time(t_s)?;
        let data = serde_json::to_vec(message).map_err(|source| RecordError::Json {
            path: self.path.clone(),
            topic: topic.to_string(),
            source,
        })?;
        self.write_bytes(channel, log_time, &data)
    }

    /// The log time of trial time `t_s`: Unix-epoch nanoseconds.
    fn log_time(&self, t_s: f64) -> Result<u64, RecordError> {
        (t_s.is_finite() && t_s >= 0.0)
            .then(|| (t_s * 1e9).round())
            .filter(|ns| *ns < u64::MAX as f64)
            .and_then(|ns| self.epoch_ns.checked_add(ns as u64))
            .ok_or_else(|| RecordError::BadTime {
                path: self.path.clone(),
                t_s,
            })
    }

    /// Writes a message's bytes on `channel`.
    fn write_bytes(
        &mut self,
        channel: &mut Channel,
        log_time: u64,
        data: &[u8],
    ) -> Result<(), RecordError> {
        let header = MessageHeader {
            channel_id: channel.id,
            sequence: channel.sequence,
            log_time,
            publish_time: log_time,
        };
        let path = self.path.clone();
        self.writer()?
            .write_to_known_channel(&header, data)
            .map_err(|source| RecordError::Mcap { path, source })?;
        channel.sequence = channel.sequence.wrapping_add(1);
        self.dirty = true;
        Ok(())
    }
}

impl Drop for TrialRecorder {
    fn drop(&mut self) {
        let _ = self.finish_in_place();
    }
}

fn add_channel(
    writer: &mut Writer<SealedFile>,
    path: &Path,
    topic: &str,
    name: &str,
    schema: &Value,
) -> Result<Channel, RecordError> {
    let data = serde_json::to_vec(schema).map_err(|source| RecordError::Json {
        path: path.to_path_buf(),
        topic: topic.to_string(),
        source,
    })?;
    let mcap_err = |source| RecordError::Mcap {
        path: path.to_path_buf(),
        source,
    };
    let schema_id = writer
        .add_schema(name, SCHEMA_ENCODING, &data)
        .map_err(mcap_err)?;
    let id = writer
        .add_channel(schema_id, topic, MESSAGE_ENCODING, &BTreeMap::new())
        .map_err(mcap_err)?;
    Ok(Channel { id, sequence: 0 })
}

/// Adds a channel of Foxglove's standard schema for `M` (protobuf), through the same writer
/// (and so the same sealed file) as the JSON channels.
fn add_foxglove_channel<M: foxglove::Encode>(
    writer: &mut Writer<SealedFile>,
    path: &Path,
    topic: &str,
) -> Result<Channel, RecordError> {
    let schema = ChannelSchema::of::<M>().map_err(|source| RecordError::Foxglove {
        path: path.to_path_buf(),
        topic: topic.to_string(),
        source,
    })?;
    add_raw_channel(writer, path, topic, &schema)
}

/// Adds a channel with a given schema (name, encoding, data) and message encoding; its
/// messages are written as raw bytes.
fn add_raw_channel(
    writer: &mut Writer<SealedFile>,
    path: &Path,
    topic: &str,
    schema: &ChannelSchema,
) -> Result<Channel, RecordError> {
    let mcap_err = |source| RecordError::Mcap {
        path: path.to_path_buf(),
        source,
    };
    let schema_id = writer
        .add_schema(&schema.name, &schema.encoding, &schema.data)
        .map_err(mcap_err)?;
    let id = writer
        .add_channel(schema_id, topic, &schema.message_encoding, &BTreeMap::new())
        .map_err(mcap_err)?;
    Ok(Channel { id, sequence: 0 })
}
