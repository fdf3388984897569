//! `antenna export`: a trial recorded by `antennad` (MCAP, see `antenna_data::record`) to a
//! MAT-file (v5 format, as `scipy.io.loadmat` and MATLAB read it) or a CSV file.
//!
//! # MAT-file variables
//!
//! N polls, S segments, M stage positions, K base angles; missing samples (a failed poll) are
//! NaN; flags are 0/1. Whole numbers may be stored as integer classes: load with
//! `scipy.io.loadmat(path, mat_dtype=True)` to get doubles everywhere.
//!
//! | variable | size | meaning |
//! |---|---|---|
//! | `t_s` | N x 1 | poll times, s since the trial started |
//! | `seq` | N x 1 | the polls' numbers on the daemon's clock (+1 per poll deadline: a gap is a skipped deadline); NaN in files written before antennad recorded it |
//! | `address` | 1 x S | segment I2C addresses, polling order |
//! | `angle_rad` | N x S | joint angles, rad |
//! | `angle_counts` | N x S | raw angles, counts of 4096 per turn |
//! | `touch` | N x S | touch bits (bit i: hair i) |
//! | `ok`, `nack`, `pec_error`, `bus_error`, `stale` | N x S | per-sample health flags |
//! | `stage_t_s`, `stage_position_m` | M x 1 | stage positions, m, and their times |
//! | `servo_t_s`, `base_angle_rad` | K x 1 | base angles, rad, and their times |
//! | `trial`, `config` | char | trial name; the configuration in force, without the control token (a `token = ...` line of a file written before antennad left it out is blanked here) |
//! | `started_unix_s` | 1 x 1 | wall-clock start, Unix s |
//! | `notes` | P x 2 cell | free-text notes: key, value |
//! | `truncated` | char | empty, or why the file ended early (a crash) |
//!
//! # CSV columns
//!
//! Comment lines (`#`) first: `# trial: ...`, `# started_unix_s: ...`, `# started_unix_ns:
//! ...` (every poll's wall-clock time is this plus its `t_s`), `# notes.KEY: ...`, `# config:
//! LINE` per configuration line (no token, as in the MAT-file), and `# truncated: ...` for a
//! cut file. Then the header and one row per segment per poll:
//! `poll,seq,t_s,address,angle_counts,angle_rad,touch,ok,nack,pec_error,bus_error,stale,stage_position_m,base_angle_rad`.
//! `poll` numbers the polls from 0 in the file, `seq` is the daemon's poll number (empty in
//! files written before antennad recorded it); a missing sample leaves its cells empty; flags
//! are 0/1;
//! `stage_position_m` and `base_angle_rad` are the latest values at or before `t_s` (empty
//! before the first).

use std::fmt::Write as _;
use std::path::Path;

use antenna_data::record::{SegmentSample, Trial};
use matrw::{CellArray, MatFile, MatVariable, MatlabType, NumericArray};

/// Why a trial could not be exported.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The polls do not all have the same segments.
    #[error("poll {poll} has {found} segments, the first poll {expected}")]
    RaggedPolls {
        /// The poll index.
        poll: usize,
        /// Segments in the first poll.
        expected: usize,
        /// Segments in this poll.
        found: usize,
    },
    /// matrw refused an array.
    #[error("building the MAT-file: {0}")]
    Mat(String),
    /// The csv writer failed (in memory: not expected).
    #[error("writing the CSV: {0}")]
    Csv(String),
}

fn segment_count(trial: &Trial) -> Result<usize, ExportError> {
    let expected = trial.segments.first().map_or(0, |m| m.segments.len());
    for (poll, m) in trial.segments.iter().enumerate() {
        if m.segments.len() != expected {
            return Err(ExportError::RaggedPolls {
                poll,
                expected,
                found: m.segments.len(),
            });
        }
    }
    Ok(expected)
}

fn numeric(rows: usize, cols: usize, column_major: Vec<f64>) -> Result<MatVariable, ExportError> {
    NumericArray::new(vec![rows, cols], MatlabType::F64(column_major), None)
        .map(MatVariable::NumericArray)
        .map_err(|e| ExportError::Mat(format!("{e:?}")))
}

fn text(s: &str) -> MatVariable {
    MatVariable::from(s)
}

/// The MAT-file of a trial (variables in the module docs).
pub fn trial_to_mat(trial: &Trial) -> Result<MatFile, ExportError> {
    let s = segment_count(trial)?;
    let n = trial.segments.len();
    let mut mat = MatFile::new();
    let t: Vec<f64> = trial.segments.iter().map(|m| m.t_s).collect();
    mat.insert("t_s", numeric(n, 1, t)?);
    let seq: Vec<f64> = trial
        .segments
        .iter()
        .map(|m| m.seq.map_or(f64::NAN, |s| s as f64))
        .collect();
    mat.insert("seq", numeric(n, 1, seq)?);
    let addresses = trial
        .segments
        .first()
        .map(|m| m.segments.iter().map(|x| f64::from(x.address)).collect())
        .unwrap_or_default();
    mat.insert("address", numeric(1, s, addresses)?);
    let matrix = |f: &dyn Fn(&SegmentSample) -> f64| {
        let mut data = Vec::with_capacity(n * s);
        for k in 0..s {
            data.extend(trial.segments.iter().map(|m| f(&m.segments[k])));
        }
        numeric(n, s, data)
    };
    let flag = |b: bool| if b { 1.0 } else { 0.0 };
    mat.insert("angle_rad", matrix(&|x| x.angle_rad.unwrap_or(f64::NAN))?);
    mat.insert(
        "angle_counts",
        matrix(&|x| x.angle_counts.map_or(f64::NAN, f64::from))?,
    );
    mat.insert("touch", matrix(&|x| x.touch.map_or(f64::NAN, f64::from))?);
    mat.insert("ok", matrix(&|x| flag(x.ok))?);
    mat.insert("nack", matrix(&|x| flag(x.nack))?);
    mat.insert("pec_error", matrix(&|x| flag(x.pec_error))?);
    mat.insert("bus_error", matrix(&|x| flag(x.bus_error))?);
    mat.insert("stale", matrix(&|x| flag(x.stale))?);
    let m = trial.stage.len();
    mat.insert(
        "stage_t_s",
        numeric(m, 1, trial.stage.iter().map(|x| x.t_s).collect())?,
    );
    mat.insert(
        "stage_position_m",
        numeric(m, 1, trial.stage.iter().map(|x| x.position_m).collect())?,
    );
    let k = trial.servo.len();
    mat.insert(
        "servo_t_s",
        numeric(k, 1, trial.servo.iter().map(|x| x.t_s).collect())?,
    );
    mat.insert(
        "base_angle_rad",
        numeric(k, 1, trial.servo.iter().map(|x| x.base_angle_rad).collect())?,
    );
    let metadata = trial.metadata.clone().unwrap_or_default();
    mat.insert("trial", text(&metadata.trial));
    mat.insert("config", text(&without_token(&metadata.config)));
    mat.insert(
        "started_unix_s",
        numeric(1, 1, vec![metadata.started_unix_s])?,
    );
    let p = metadata.notes.len();
    // Column-major P x 2: every key, then every value.
    let cells: Vec<MatVariable> = metadata
        .notes
        .keys()
        .map(|key| text(key))
        .chain(metadata.notes.values().map(|value| text(value)))
        .collect();
    let notes =
        CellArray::new(vec![p, 2], cells).map_err(|e| ExportError::Mat(format!("{e:?}")))?;
    mat.insert("notes", MatVariable::CellArray(notes));
    mat.insert("truncated", text(trial.truncated.as_deref().unwrap_or("")));
    Ok(mat)
}

/// Writes the MAT-file of a trial to `path` (uncompressed).
pub fn write_mat(trial: &Trial, path: &Path) -> anyhow::Result<()> {
    let mat = trial_to_mat(trial)?;
    let name = path
        .to_str()
        .ok_or_else(|| anyhow::anyhow!("{}: the path is not UTF-8", path.display()))?;
    matrw::save_matfile_v7(name, mat, false)
        .map_err(|e| anyhow::anyhow!("{}: writing the MAT-file: {e:?}", path.display()))
}

/// A recorded configuration without its control token: antennad has left the token out of
/// recordings since 0.2; a `token = ...` line of an older file is blanked here, so an export
/// never carries it.
pub fn without_token(config: &str) -> String {
    config
        .split_inclusive('\n')
        .map(|line| {
            let key = line.split('=').next().unwrap_or_default().trim();
            if line.contains('=') && key.trim_matches('"') == "token" {
                let end = if line.ends_with('\n') { "\n" } else { "" };
                format!("token = \"<redacted>\"{end}")
            } else {
                line.to_owned()
            }
        })
        .collect()
}

fn cell<T: std::fmt::Display>(value: Option<T>) -> String {
    value.map(|v| v.to_string()).unwrap_or_default()
}

/// The CSV columns (module docs).
const CSV_COLUMNS: [&str; 14] = [
    "poll",
    "seq",
    "t_s",
    "address",
    "angle_counts",
    "angle_rad",
    "touch",
    "ok",
    "nack",
    "pec_error",
    "bus_error",
    "stale",
    "stage_position_m",
    "base_angle_rad",
];

/// The CSV text of a trial (columns in the module docs).
pub fn trial_to_csv(trial: &Trial) -> Result<String, ExportError> {
    segment_count(trial)?;
    let mut comments = String::new();
    if let Some(metadata) = &trial.metadata {
        let _ = writeln!(comments, "# trial: {}", metadata.trial);
        let _ = writeln!(comments, "# started_unix_s: {}", metadata.started_unix_s);
        if let Some(ns) = metadata.started_unix_ns {
            let _ = writeln!(comments, "# started_unix_ns: {ns}");
        }
        for (key, value) in &metadata.notes {
            let _ = writeln!(comments, "# notes.{key}: {}", value.replace('\n', " "));
        }
        for line in without_token(&metadata.config).lines() {
            let _ = writeln!(comments, "# config: {line}");
        }
    }
    if let Some(why) = &trial.truncated {
        let _ = writeln!(comments, "# truncated: {}", why.replace('\n', " "));
    }
    let mut out = csv::Writer::from_writer(comments.into_bytes());
    let csv_error = |e: csv::Error| ExportError::Csv(e.to_string());
    out.write_record(CSV_COLUMNS).map_err(csv_error)?;
    let flag = |b: bool| if b { "1" } else { "0" };
    let (mut stage, mut servo) = (0, 0);
    for (poll, m) in trial.segments.iter().enumerate() {
        while stage < trial.stage.len() && trial.stage[stage].t_s <= m.t_s {
            stage += 1;
        }
        while servo < trial.servo.len() && trial.servo[servo].t_s <= m.t_s {
            servo += 1;
        }
        let position = cell(stage.checked_sub(1).map(|i| trial.stage[i].position_m));
        let base = cell(servo.checked_sub(1).map(|i| trial.servo[i].base_angle_rad));
        let (poll, seq, t_s) = (poll.to_string(), cell(m.seq), m.t_s.to_string());
        for x in &m.segments {
            out.write_record([
                poll.as_str(),
                &seq,
                &t_s,
                &x.address.to_string(),
                &cell(x.angle_counts),
                &cell(x.angle_rad),
                &cell(x.touch),
                flag(x.ok),
                flag(x.nack),
                flag(x.pec_error),
                flag(x.bus_error),
                flag(x.stale),
                &position,
                &base,
            ])
            .map_err(csv_error)?;
        }
    }
    let bytes = out
        .into_inner()
        .map_err(|e| ExportError::Csv(e.error().to_string()))?;
    String::from_utf8(bytes).map_err(|e| ExportError::Csv(e.to_string()))
}
