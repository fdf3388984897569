//! [`TrialReader`]: reads a trial file back, including one cut short by a crash.

use std::path::{Path, PathBuf};

use mcap::MessageStream;
use mcap::read::Options;
use serde::de::DeserializeOwned;

use super::error::RecordError;
use super::messages::{
    EstimateMessage, LogMessage, PhysicsStepMessage, SegmentsMessage, ServoMessage, StageMessage,
    TrialMetadata,
};
use super::schema::{
    ESTIMATE_TOPIC, LOG_TOPIC, METADATA_TOPIC, PHYSICS_TOPIC, SCENE_TOPIC, SEGMENTS_TOPIC,
    SERVO_TOPIC, STAGE_TOPIC, TRANSFORMS_TOPIC,
};

/// A trial read back from its MCAP file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trial {
    /// The metadata (`None` only if the file was cut before its first flush).
    pub metadata: Option<TrialMetadata>,
    /// Every `/antenna/segments` message, in recording order.
    pub segments: Vec<SegmentsMessage>,
    /// Every `/antenna/stage` message, in recording order.
    pub stage: Vec<StageMessage>,
    /// Every `/antenna/servo` message, in recording order.
    pub servo: Vec<ServoMessage>,
    /// Every `/trial/log` message, in recording order (none in files from before it existed).
    pub log: Vec<LogMessage>,
    /// Every `/sim/physics` message, in recording order (the simulated rig's; none in files
    /// from hardware or from before it existed).
    pub physics: Vec<PhysicsStepMessage>,
    /// Every `/antenna/estimate` message, in recording order (none in files without
    /// estimates or from before they existed).
    pub estimate: Vec<EstimateMessage>,
    /// How many `/antenna/transforms` and `/antenna/scene` messages (Foxglove's, protobuf:
    /// drawn from the other channels, so not decoded here) the file holds.
    pub foxglove_messages: u64,
    /// `None` for a complete file; otherwise why reading stopped early (a file cut by a crash
    /// ends in a partial record after its last flush). Everything before that point is
    /// returned, CRC-checked.
    pub truncated: Option<String>,
}

/// Reads trial files written by [`super::TrialRecorder`]: closed ones, ones that were not
/// closed (ending at their last flush), and older ones cut inside a chunk.
#[derive(Debug, Clone, Copy, Default)]
pub struct TrialReader;

const MAGIC: &[u8] = b"\x89MCAP0\r\n";

impl TrialReader {
    /// Reads the trial at `path`. A file without its footer (the recorder was killed) reads
    /// back up to its last flush, with [`Trial::truncated`] saying where it stopped; a file
    /// that is not MCAP or holds a message that does not decode is an error.
    pub fn read(path: impl AsRef<Path>) -> Result<Trial, RecordError> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|source| RecordError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::read_bytes(path, &bytes)
    }

    /// Reads a trial from the bytes of its file; `path` names it in errors.
    pub fn read_bytes(path: &Path, bytes: &[u8]) -> Result<Trial, RecordError> {
        let mut trial = Trial::default();
        let prefix = &MAGIC[..bytes.len().min(MAGIC.len())];
        if !bytes.starts_with(prefix) {
            return Err(RecordError::NotMcap {
                path: path.to_path_buf(),
            });
        }
        if bytes.len() < MAGIC.len() {
            trial.truncated = Some(format!("the file ends after {} bytes", bytes.len()));
            return Ok(trial);
        }
        // Read only whole top-level records: a crash cuts the file inside a record (often a
        // chunk whose header still holds placeholder lengths), and the tail is dropped here
        // rather than handed to the MCAP reader.
        let whole = whole_records_len(bytes);
        if whole < bytes.len() {
            trial.truncated = Some(format!(
                "the file ends inside a record: {} of {} bytes are whole records",
                whole,
                bytes.len()
            ));
        }
        let stream = MessageStream::new_with_options(
            &bytes[..whole],
            Options::IgnoreEndMagic | Options::ValidateChunkCrcs,
        )
        .map_err(|source| RecordError::Mcap {
            path: path.to_path_buf(),
            source,
        })?;
        for message in stream {
            let message = match message {
                Ok(m) => m,
                Err(e) => {
                    trial.truncated = Some(e.to_string());
                    break;
                }
            };
            let topic = message.channel.topic.as_str();
            let data = &message.data;
            match topic {
                SEGMENTS_TOPIC => trial.segments.push(decode(path, topic, data)?),
                STAGE_TOPIC => trial.stage.push(decode(path, topic, data)?),
                SERVO_TOPIC => trial.servo.push(decode(path, topic, data)?),
                LOG_TOPIC => trial.log.push(decode(path, topic, data)?),
                PHYSICS_TOPIC => trial.physics.push(decode(path, topic, data)?),
                ESTIMATE_TOPIC => trial.estimate.push(decode(path, topic, data)?),
                TRANSFORMS_TOPIC | SCENE_TOPIC => trial.foxglove_messages += 1,
                METADATA_TOPIC => trial.metadata = Some(decode(path, topic, data)?),
                _ => {}
            }
        }
        if trial.truncated.is_none() {
            if !(bytes.len() >= 2 * MAGIC.len() && bytes.ends_with(MAGIC)) {
                trial.truncated = Some(format!(
                    "the file ends after {} bytes without its footer",
                    bytes.len()
                ));
            } else if mcap::read::footer(bytes).is_ok_and(|f| f.summary_start == 0) {
                // The recorder seals the file after every flush with a footer without a
                // summary; a closed file has its summary.
                trial.truncated = Some(
                    "the recording was not closed (the recorder was killed or the disk cut it \
                     short): it ends at its last flush"
                        .to_owned(),
                );
            }
        }
        Ok(trial)
    }
}

/// The length of the longest prefix of an MCAP file (magic included) made of whole
/// top-level records, each an opcode byte, a little-endian u64 length and that many bytes.
fn whole_records_len(bytes: &[u8]) -> usize {
    let mut end = MAGIC.len();
    while let Some(length) = bytes
        .get(end + 1..end + 9)
        .and_then(|b| <[u8; 8]>::try_from(b).ok())
    {
        let record_end = usize::try_from(u64::from_le_bytes(length))
            .ok()
            .and_then(|len| len.checked_add(end + 9));
        match record_end {
            Some(record_end) if record_end <= bytes.len() => end = record_end,
            _ => break,
        }
    }
    // A complete file ends with the magic again, after its footer record.
    if bytes.len() >= end + MAGIC.len() && bytes[end..].starts_with(MAGIC) {
        end += MAGIC.len();
    }
    end
}

fn decode<T: DeserializeOwned>(path: &Path, topic: &str, data: &[u8]) -> Result<T, RecordError> {
    serde_json::from_slice(data).map_err(|source| RecordError::Json {
        path: PathBuf::from(path),
        topic: topic.to_string(),
        source,
    })
}
