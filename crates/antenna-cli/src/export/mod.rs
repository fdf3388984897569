//! `antenna export`: a trial recorded by `antennad` (MCAP, see `antenna_data::record`) to a
//! MAT-file (v5 format, as `scipy.io.loadmat` and MATLAB read it) or a CSV file.
//!
//! # MAT-file variables
//!
//! N polls, S segments, M stage positions, K base angles, E wall estimates (`/antenna/estimate`:
//! antennad's live estimate, in the carriage frame: origin at the base pivot, x along the
//! stage's travel, y toward the wall; none in files from before it or without it). Every variable loads as its class
//! with MATLAB's `load` and with scipy's default `scipy.io.loadmat(path)` (no options; the
//! writer is [`mat`], which never stores a double as an integer type): measurements and times
//! are double (float64 in scipy) even when every value is whole; counters, addresses, raw
//! counts and touch bits are the integer class of the recording's field; flags are logical
//! (uint8 0/1 in scipy, logical in MATLAB). Missing samples (a failed poll: `ok` false) are NaN
//! in doubles and 0 in `angle_counts` and `touch`.
//!
//! | variable | class (numpy dtype) | size | meaning |
//! |---|---|---|---|
//! | `t_s` | double (float64) | N x 1 | poll times, s since the trial started |
//! | `seq` | uint64 | N x 1 | the polls' numbers on the daemon's clock (+1 per poll deadline: a gap is a skipped deadline); 0 x 1 in files written before antennad recorded it |
//! | `address` | uint8 | 1 x S | segment I2C addresses, polling order |
//! | `angle_rad` | double (float64) | N x S | joint angles, rad (NaN: missing) |
//! | `angle_counts` | uint16 | N x S | raw angles, counts of 4096 per turn (0 where missing) |
//! | `touch` | uint8 | N x S | touch bits, bit i: hair i (0 where missing) |
//! | `ok`, `nack`, `pec_error`, `bus_error`, `stale` | logical (uint8) | N x S | per-sample health flags |
//! | `stage_t_s`, `stage_position_m` | double (float64) | M x 1 | stage positions, m, and their times |
//! | `servo_t_s`, `base_angle_rad` | double (float64) | K x 1 | base angles, rad, and their times |
//! | `trial`, `config` | char | 1 x L | trial name; the configuration in force, without the control token (a `token = ...` line of a file written before antennad left it out is blanked here) |
//! | `started_unix_s` | double (float64) | 1 x 1 | wall-clock start, Unix s |
//! | `started_unix_ns` | uint64 | 1 x 1 | the same instant exactly, Unix ns (0 x 0 in files written before antennad recorded it) |
//! | `notes` | cell of char | P x 2 | free-text notes: key, value |
//! | `truncated` | char | 1 x L | empty (0 x 0), or why the file ended early (a crash) |
//! | `estimate_t_s` | double (float64) | E x 1 | the wall estimates' times (their newest poll's `t_s`), s |
//! | `estimate_seq` | uint64 | E x 1 | the newest poll's `seq` of each estimate |
//! | `estimator` | cell of char | E x 1 | the estimator (`contact-line`, `bend`, `ideal-preview`) |
//! | `estimate_distance_m` | double (float64) | E x 1 | the wall's distance from the travel at `x = preview_m`, m (NaN: no estimate) |
//! | `estimate_angle_rad` | double (float64) | E x 1 | the wall's angle to the travel, rad (NaN: no estimate, or `bend`, which gives none) |
//! | `estimate_preview_m` | double (float64) | E x 1 | where along the travel the distance is estimated, m from the base pivot (NaN: no estimate) |
//! | `estimate_reason` | cell of char | E x 1 | why there is no estimate (empty when there is one) |
//! | `estimate_true_distance_m`, `estimate_true_angle_rad` | double (float64) | E x 1 | the true wall at the same place and instant, m and rad (the simulated rig; NaN otherwise) |
//!
//! A write that fails (a full disk) is an error naming the file; the MAT-file and the CSV
//! file are written to a temporary file beside the destination and renamed over it only when
//! complete and synced, so a failed export leaves no partial file (and an older file of that
//! name as it was).
//!
//! # CSV columns
//!
//! Comment lines (`#`) first: `# trial: ...`, `# started_unix_s: ...`, `# started_unix_ns:
//! ...` (every poll's wall-clock time is this plus its `t_s`), `# notes.KEY: ...`, `# config:
//! LINE` per configuration line (no token, as in the MAT-file), and `# truncated: ...` for a
//! cut file. Then the header and one row per segment per poll:
//! `poll,seq,t_s,address,angle_counts,angle_rad,touch,ok,nack,pec_error,bus_error,stale,stage_position_m,base_angle_rad,estimate_seq,estimator,estimate_distance_m,estimate_angle_rad,estimate_preview_m,estimate_reason,estimate_true_distance_m,estimate_true_angle_rad`.
//! `poll` numbers the polls from 0 in the file, `seq` is the daemon's poll number (empty in
//! files written before antennad recorded it); a missing sample leaves its cells empty; flags
//! are 0/1;
//! `stage_position_m`, `base_angle_rad` and the `estimate_` columns are the latest values at
//! or before `t_s` (empty before the first, and where the estimate has none); the estimate's
//! own poll is `estimate_seq`.

pub mod mat;

use std::fmt::Write as _;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use antenna_data::record::{EstimateMessage, SegmentSample, Trial};

use mat::{Array, Data, MatError, MatFile};

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
    /// A variable the MAT-file cannot hold.
    #[error("building the MAT-file: {0}")]
    Mat(#[from] MatError),
    /// The csv writer failed (in memory: not expected).
    #[error("writing the CSV: {0}")]
    Csv(String),
    /// Writing the output file failed (nothing was left under its name).
    #[error("{}: cannot write: {source}", path.display())]
    Write {
        /// The output file.
        path: PathBuf,
        /// The operating system's error.
        source: io::Error,
    },
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

/// The MAT-file of a trial (variables and classes in the module docs).
pub fn trial_to_mat(trial: &Trial) -> Result<MatFile, ExportError> {
    let s = segment_count(trial)?;
    let n = trial.segments.len();
    let mut mat = MatFile::new();
    let column = |values: Vec<f64>| Array::column(Data::Double(values));
    mat.insert(
        "t_s",
        column(trial.segments.iter().map(|m| m.t_s).collect()),
    )?;
    // Every poll has its seq since antennad recorded it; a file from before has none.
    let seq: Option<Vec<u64>> = trial.segments.iter().map(|m| m.seq).collect();
    mat.insert("seq", Array::column(Data::Uint64(seq.unwrap_or_default())))?;
    let addresses = trial
        .segments
        .first()
        .map(|m| m.segments.iter().map(|x| x.address).collect())
        .unwrap_or_default();
    mat.insert("address", Array::new(1, s, Data::Uint8(addresses)))?;
    // N x S, column-major: segment by segment.
    fn matrix<T>(trial: &Trial, s: usize, f: impl Fn(&SegmentSample) -> T) -> Vec<T> {
        (0..s)
            .flat_map(|k| trial.segments.iter().map(move |m| &m.segments[k]))
            .map(f)
            .collect()
    }
    let mut insert = |name: &str, data: Data| mat.insert(name, Array::new(n, s, data));
    insert(
        "angle_rad",
        Data::Double(matrix(trial, s, |x| x.angle_rad.unwrap_or(f64::NAN))),
    )?;
    insert(
        "angle_counts",
        Data::Uint16(matrix(trial, s, |x| x.angle_counts.unwrap_or(0))),
    )?;
    insert(
        "touch",
        Data::Uint8(matrix(trial, s, |x| x.touch.unwrap_or(0))),
    )?;
    insert("ok", Data::Logical(matrix(trial, s, |x| x.ok)))?;
    insert("nack", Data::Logical(matrix(trial, s, |x| x.nack)))?;
    insert(
        "pec_error",
        Data::Logical(matrix(trial, s, |x| x.pec_error)),
    )?;
    insert(
        "bus_error",
        Data::Logical(matrix(trial, s, |x| x.bus_error)),
    )?;
    insert("stale", Data::Logical(matrix(trial, s, |x| x.stale)))?;
    mat.insert(
        "stage_t_s",
        column(trial.stage.iter().map(|x| x.t_s).collect()),
    )?;
    mat.insert(
        "stage_position_m",
        column(trial.stage.iter().map(|x| x.position_m).collect()),
    )?;
    mat.insert(
        "servo_t_s",
        column(trial.servo.iter().map(|x| x.t_s).collect()),
    )?;
    mat.insert(
        "base_angle_rad",
        column(trial.servo.iter().map(|x| x.base_angle_rad).collect()),
    )?;
    let metadata = trial.metadata.clone().unwrap_or_default();
    mat.insert("trial", Array::text(&metadata.trial))?;
    mat.insert("config", Array::text(&without_token(&metadata.config)))?;
    mat.insert(
        "started_unix_s",
        Array::new(1, 1, Data::Double(vec![metadata.started_unix_s])),
    )?;
    let ns: Vec<u64> = metadata.started_unix_ns.into_iter().collect();
    mat.insert(
        "started_unix_ns",
        Array::new(ns.len(), ns.len(), Data::Uint64(ns)),
    )?;
    let p = metadata.notes.len();
    // Column-major P x 2: every key, then every value.
    let cells: Vec<Array> = metadata
        .notes
        .keys()
        .map(|key| Array::text(key))
        .chain(metadata.notes.values().map(|value| Array::text(value)))
        .collect();
    mat.insert("notes", Array::new(p, 2, Data::Cell(cells)))?;
    mat.insert(
        "truncated",
        Array::text(trial.truncated.as_deref().unwrap_or("")),
    )?;
    insert_estimates(&mut mat, trial)?;
    Ok(mat)
}

/// The wall estimates' variables (module docs).
fn insert_estimates(mat: &mut MatFile, trial: &Trial) -> Result<(), MatError> {
    let estimates = &trial.estimate;
    let double = |f: &dyn Fn(&EstimateMessage) -> Option<f64>| {
        Array::column(Data::Double(
            estimates.iter().map(|e| f(e).unwrap_or(f64::NAN)).collect(),
        ))
    };
    let texts = |f: &dyn Fn(&EstimateMessage) -> &str| {
        Array::column(Data::Cell(
            estimates.iter().map(|e| Array::text(f(e))).collect(),
        ))
    };
    mat.insert("estimate_t_s", double(&|e| Some(e.t_s)))?;
    mat.insert(
        "estimate_seq",
        Array::column(Data::Uint64(estimates.iter().map(|e| e.seq).collect())),
    )?;
    mat.insert("estimator", texts(&|e| &e.estimator))?;
    mat.insert("estimate_distance_m", double(&|e| e.distance_m))?;
    mat.insert("estimate_angle_rad", double(&|e| e.wall_angle_rad))?;
    mat.insert("estimate_preview_m", double(&|e| e.preview_m))?;
    mat.insert(
        "estimate_reason",
        texts(&|e| e.reason.as_deref().unwrap_or("")),
    )?;
    mat.insert("estimate_true_distance_m", double(&|e| e.true_distance_m))?;
    mat.insert("estimate_true_angle_rad", double(&|e| e.true_angle_rad))?;
    Ok(())
}

/// Writes the MAT-file of a trial to `path` (uncompressed, as before). A failed write is an
/// error and leaves nothing under `path` (see [`write_file`]).
pub fn write_mat(trial: &Trial, path: &Path) -> Result<(), ExportError> {
    let mat = trial_to_mat(trial)?;
    write_file(path, |w| mat.write_to(w))
}

/// Writes the CSV file of a trial to `path`, as [`write_mat`] does.
pub fn write_csv(trial: &Trial, path: &Path) -> Result<(), ExportError> {
    let text = trial_to_csv(trial)?;
    write_file(path, |w| w.write_all(text.as_bytes()))
}

/// Writes a file so that it exists under `path` only complete: the bytes go to a new
/// temporary file beside it (`.NAME.PID-K.part`), which is flushed, synced (so an error the
/// file system reports late, as NFS or a quota does, is seen) and then renamed over `path`; on
/// any error it is removed and the error names `path`. A path that exists and is not a
/// regular file (a device such as `/dev/stdout`, a pipe) is written directly, as there is
/// nothing to rename over; a symbolic link is followed.
pub fn write_file(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> Result<(), ExportError> {
    let error = |source: io::Error| ExportError::Write {
        path: path.to_owned(),
        source,
    };
    let target = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_owned());
    let special = std::fs::metadata(&target).is_ok_and(|m| !m.is_file());
    if special {
        let mut w = BufWriter::new(File::create(&target).map_err(error)?);
        write(&mut w).map_err(error)?;
        return w.into_inner().map(drop).map_err(|e| error(e.into_error()));
    }
    let (temp, file) = create_temp(&target).map_err(error)?;
    let mut w = BufWriter::new(file);
    let written = write(&mut w)
        .and_then(|()| w.into_inner().map_err(io::IntoInnerError::into_error))
        .and_then(|file| file.sync_all())
        .and_then(|()| std::fs::rename(&temp, &target));
    if let Err(e) = written {
        // Best effort: the write's error is the one to report.
        let _ignored = std::fs::remove_file(&temp);
        return Err(error(e));
    }
    Ok(())
}

/// A new temporary file beside `path`.
fn create_temp(path: &Path) -> io::Result<(PathBuf, File)> {
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "not a file name"))?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut k = 0u32;
    loop {
        let mut temp_name = std::ffi::OsString::from(".");
        temp_name.push(name);
        temp_name.push(format!(".{}-{k}.part", std::process::id()));
        let temp = dir.join(temp_name);
        match File::create_new(&temp) {
            Ok(file) => return Ok((temp, file)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists && k < 100 => k += 1,
            Err(e) => return Err(e),
        }
    }
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
const CSV_COLUMNS: [&str; 22] = [
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
    "estimate_seq",
    "estimator",
    "estimate_distance_m",
    "estimate_angle_rad",
    "estimate_preview_m",
    "estimate_reason",
    "estimate_true_distance_m",
    "estimate_true_angle_rad",
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
    let (mut stage, mut servo, mut estimate) = (0, 0, 0);
    for (poll, m) in trial.segments.iter().enumerate() {
        while stage < trial.stage.len() && trial.stage[stage].t_s <= m.t_s {
            stage += 1;
        }
        while servo < trial.servo.len() && trial.servo[servo].t_s <= m.t_s {
            servo += 1;
        }
        while estimate < trial.estimate.len() && trial.estimate[estimate].t_s <= m.t_s {
            estimate += 1;
        }
        let position = cell(stage.checked_sub(1).map(|i| trial.stage[i].position_m));
        let base = cell(servo.checked_sub(1).map(|i| trial.servo[i].base_angle_rad));
        let e = estimate.checked_sub(1).map(|i| &trial.estimate[i]);
        let estimate_cells = [
            cell(e.map(|e| e.seq)),
            cell(e.map(|e| &e.estimator)),
            cell(e.and_then(|e| e.distance_m)),
            cell(e.and_then(|e| e.wall_angle_rad)),
            cell(e.and_then(|e| e.preview_m)),
            cell(e.and_then(|e| e.reason.as_ref())),
            cell(e.and_then(|e| e.true_distance_m)),
            cell(e.and_then(|e| e.true_angle_rad)),
        ];
        let (poll, seq, t_s) = (poll.to_string(), cell(m.seq), m.t_s.to_string());
        for x in &m.segments {
            let row = [
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
            ];
            out.write_record(
                row.into_iter()
                    .chain(estimate_cells.iter().map(String::as_str)),
            )
            .map_err(csv_error)?;
        }
    }
    let bytes = out
        .into_inner()
        .map_err(|e| ExportError::Csv(e.error().to_string()))?;
    String::from_utf8(bytes).map_err(|e| ExportError::Csv(e.to_string()))
}
