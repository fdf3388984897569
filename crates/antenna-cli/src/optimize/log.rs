//! `antenna optimize --log FILE.jsonl [--resume]`: every evaluation written as it completes
//! (one JSON line each, flushed, after a header line that names the optimization), so that a
//! run that is stopped (killed, the machine restarted) loses nothing, and `--resume` goes on
//! from the file. The search is deterministic for its file and seed: a resumed run asks for
//! the same stiffness sets in the same order, finds the logged ones in the file instead of
//! sweeping them (they still count towards the budget), and sweeps on from where the log ends.
//! A larger budget continues a finished run. A header that does not match the optimization
//! (another objective, method, seed, bounds, scene, or an edited scene file) is refused.
//!
//! A last line cut short by the stop is dropped (and cut from the file before it grows).

use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write as _};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{Evaluation, OptimizeSpec};

/// Why a log cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// The file exists and `--resume` was not given.
    #[error(
        "{}: the log exists: --resume continues the run it records; remove it to start afresh",
        path.display()
    )]
    Exists {
        /// The log.
        path: PathBuf,
    },
    /// The file cannot be read, created or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The log.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A line is not a header or an evaluation.
    #[error("{}:{line}: not a line of an optimization log: {why}", path.display())]
    Line {
        /// The log.
        path: PathBuf,
        /// The line, 1-based.
        line: usize,
        /// The parser's message.
        why: String,
    },
    /// The log records another optimization.
    #[error(
        "{}: the log records another optimization: its {key} is {logged}, this one's is {now}",
        path.display()
    )]
    Mismatch {
        /// The log.
        path: PathBuf,
        /// What differs.
        key: &'static str,
        /// The log's value.
        logged: String,
        /// This optimization's.
        now: String,
    },
}

/// The first line: what the evaluations that follow belong to.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LogHeader {
    /// `"optimize"`.
    #[serde(rename = "type")]
    pub kind: String,
    /// The objective's name.
    pub objective: String,
    /// The family's name.
    pub parameters: String,
    /// The wires' name.
    pub wires: String,
    /// The method's name.
    pub method: String,
    /// The stiffness bounds, N m/rad.
    pub stiffness_bounds_n_m_per_rad: [f64; 2],
    /// The seed.
    pub seed: u64,
    /// The scene files as resolved.
    pub scenes: Vec<String>,
    /// FNV-1a (64 bit, hex) of the scene files' texts and the sweep duration: an edited
    /// scene is another optimization.
    pub scene_digest: String,
}

impl LogHeader {
    /// The header of `spec`.
    ///
    /// # Errors
    /// [`LogError::Io`] when a scene file cannot be read again.
    pub fn of(spec: &OptimizeSpec) -> Result<LogHeader, LogError> {
        let mut digest = Fnv1a::default();
        for (path, scene) in &spec.scenes {
            let text = std::fs::read(path).map_err(|source| LogError::Io {
                path: path.clone(),
                source,
            })?;
            digest.write(&text);
            digest.write(&scene.motion.duration_s.to_le_bytes());
        }
        Ok(LogHeader {
            kind: "optimize".to_string(),
            objective: spec.objective.name().to_string(),
            parameters: spec.space.family.name().to_string(),
            wires: spec.space.wires.name().to_string(),
            method: spec.method.name().to_string(),
            stiffness_bounds_n_m_per_rad: [
                spec.space.bounds_n_m_per_rad.0,
                spec.space.bounds_n_m_per_rad.1,
            ],
            seed: spec.seed,
            scenes: spec
                .scenes
                .iter()
                .map(|(p, _)| p.display().to_string())
                .collect(),
            scene_digest: format!("{:016x}", digest.0),
        })
    }

    /// The first field in which `self` (the log's) and `now` differ.
    fn mismatch(&self, now: &LogHeader) -> Option<(&'static str, String, String)> {
        let pairs: [(&'static str, String, String); 8] = [
            ("objective", self.objective.clone(), now.objective.clone()),
            (
                "parameters",
                self.parameters.clone(),
                now.parameters.clone(),
            ),
            ("wires", self.wires.clone(), now.wires.clone()),
            ("method", self.method.clone(), now.method.clone()),
            (
                "stiffness_bounds_n_m_per_rad",
                format!("{:?}", self.stiffness_bounds_n_m_per_rad),
                format!("{:?}", now.stiffness_bounds_n_m_per_rad),
            ),
            ("seed", self.seed.to_string(), now.seed.to_string()),
            ("scenes", self.scenes.join(", "), now.scenes.join(", ")),
            (
                "scene files' digest (a scene was edited, or duration_s changed)",
                self.scene_digest.clone(),
                now.scene_digest.clone(),
            ),
        ];
        pairs.into_iter().find(|(_, a, b)| a != b)
    }
}

/// FNV-1a, 64 bit: a stable digest (std's hasher may change between Rust releases).
struct Fnv1a(u64);

impl Default for Fnv1a {
    fn default() -> Self {
        Fnv1a(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv1a {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

/// An evaluation line.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct LogLine {
    #[serde(rename = "type")]
    kind: String,
    #[serde(flatten)]
    evaluation: Evaluation,
}

/// The log being written.
#[derive(Debug)]
pub struct LogWriter {
    path: PathBuf,
    out: BufWriter<File>,
}

impl LogWriter {
    /// Appends `evaluation` as one line and flushes it.
    ///
    /// # Errors
    /// The I/O error's message (a full disk, a removed file system).
    pub fn write(&mut self, evaluation: &Evaluation) -> Result<(), String> {
        let line = LogLine {
            kind: "evaluation".to_string(),
            evaluation: evaluation.clone(),
        };
        let json = serde_json::to_string(&line).map_err(|e| e.to_string())?;
        writeln!(self.out, "{json}")
            .and_then(|()| self.out.flush())
            .map_err(|e| format!("{}: {e}", self.path.display()))
    }
}

/// Opens the log at `path` for `spec`: a new file with its header, or with `resume` the
/// existing one (checked against `spec`, a cut last line removed), and the evaluations it
/// holds.
///
/// # Errors
/// [`LogError`]: the file exists without `resume`, cannot be read or written, has a bad
/// line, or records another optimization.
pub fn open_log(
    path: &Path,
    spec: &OptimizeSpec,
    resume: bool,
) -> Result<(LogWriter, Vec<Evaluation>), LogError> {
    let io = |source| LogError::Io {
        path: path.to_path_buf(),
        source,
    };
    let header = LogHeader::of(spec)?;
    let exists = path.exists();
    if exists && !resume {
        return Err(LogError::Exists {
            path: path.to_path_buf(),
        });
    }
    let mut logged = Vec::new();
    if exists {
        let text = std::fs::read_to_string(path).map_err(io)?;
        let complete = text.rfind('\n').map_or(0, |i| i + 1);
        for (i, line) in text[..complete].lines().enumerate() {
            let bad = |why: String| LogError::Line {
                path: path.to_path_buf(),
                line: i + 1,
                why,
            };
            if i == 0 {
                let theirs: LogHeader =
                    serde_json::from_str(line).map_err(|e| bad(e.to_string()))?;
                if let Some((key, logged, now)) = theirs.mismatch(&header) {
                    return Err(LogError::Mismatch {
                        path: path.to_path_buf(),
                        key,
                        logged,
                        now,
                    });
                }
            } else {
                let entry: LogLine = serde_json::from_str(line).map_err(|e| bad(e.to_string()))?;
                logged.push(entry.evaluation);
            }
        }
        if complete < text.len() {
            // The last line was cut by the stop: drop it before appending.
            let file = OpenOptions::new().write(true).open(path).map_err(io)?;
            file.set_len(complete as u64).map_err(io)?;
        }
    }
    let file = OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .map_err(io)?;
    let mut writer = LogWriter {
        path: path.to_path_buf(),
        out: BufWriter::new(file),
    };
    if !exists || std::fs::metadata(path).map_err(io)?.len() == 0 {
        let json = serde_json::to_string(&header).map_err(|e| io(std::io::Error::other(e)))?;
        writeln!(writer.out, "{json}")
            .and_then(|()| writer.out.flush())
            .map_err(io)?;
    }
    Ok((writer, logged))
}
