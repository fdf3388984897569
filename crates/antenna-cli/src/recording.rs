//! Free-oscillation recordings for `antenna identify`: a small CSV format.
//!
//! - Blank lines and lines starting with `#` are ignored. Fields are separated by commas (read
//!   with the csv crate, without quoting), or by whitespace when a line has no comma.
//! - An optional header line names the columns: `t_s` (time, seconds) and either `angle_rad`
//!   or `angle_deg` (the joint angle). Other columns are ignored.
//! - Without a header, one column is `angle_rad` and two columns are `t_s, angle_rad`.
//! - With a time column the sample rate is `(samples - 1) / (t_last - t_first)`; the steps
//!   must be uniform (each within 1 % of the mean step). Without one the caller supplies the
//!   rate (`--sample-rate-hz`).
//!
//! ```
//! use antenna_cli::recording::Recording;
//!
//! let csv = "# ring-down of joint 3\nt_s,angle_deg\n0.00,10\n0.01,8\n0.02,5\n";
//! let r = Recording::parse(csv).unwrap();
//! assert_eq!(r.angle_rad.len(), 3);
//! assert!((r.sample_rate_hz.unwrap() - 100.0).abs() < 1e-9);
//! assert!((r.angle_rad[0] - 10f64.to_radians()).abs() < 1e-15);
//! ```

/// Errors reading a recording; lines are 1-based.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RecordingError {
    /// No data rows.
    #[error("no samples (every line is blank, a comment or the header)")]
    Empty,
    /// A header without an angle column.
    #[error(
        "line {line}: the header has no angle column; name one `angle_rad` or `angle_deg` \
         (columns found: {found})"
    )]
    NoAngleColumn {
        /// The header's line.
        line: usize,
        /// The columns it names.
        found: String,
    },
    /// A headerless file with more than two columns.
    #[error(
        "line {line}: {columns} columns without a header; give one column (angle_rad), two \
         (t_s, angle_rad), or a header line naming t_s and angle_rad/angle_deg"
    )]
    TooManyColumns {
        /// The first data line.
        line: usize,
        /// Columns on it.
        columns: usize,
    },
    /// A row with a different number of fields than the first one.
    #[error("line {line}: {found} field(s), expected {expected}")]
    RaggedRow {
        /// The line.
        line: usize,
        /// Fields expected (from the header or first row).
        expected: usize,
        /// Fields found.
        found: usize,
    },
    /// A field that is not a finite number.
    #[error("line {line}, column `{column}`: {text:?} is not a finite number")]
    BadNumber {
        /// The line.
        line: usize,
        /// The column's name.
        column: String,
        /// The field as written.
        text: String,
    },
    /// The csv reader could not read a line (not expected of text).
    #[error("line {line}: cannot read the line: {why}")]
    Unreadable {
        /// The line.
        line: usize,
        /// The reader's error.
        why: String,
    },
    /// Times that do not step uniformly forward.
    #[error(
        "line {line}: time step {step_s} s differs from the mean step {mean_step_s} s by more \
         than 1 % (the samples must be uniform)"
    )]
    NonUniformTime {
        /// The line of the later sample of the bad step.
        line: usize,
        /// The step, seconds.
        step_s: f64,
        /// The mean step, seconds.
        mean_step_s: f64,
    },
}

/// A recording: uniformly sampled joint angles and, when the file has a time column, the
/// sample rate it implies.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// The joint angle, radians, one per sample.
    pub angle_rad: Vec<f64>,
    /// The sample rate from the time column, Hz (`None` without one).
    pub sample_rate_hz: Option<f64>,
}

/// The data lines of `text` with their 1-based line numbers and fields: read with the csv
/// crate ([`crate::csv_lines`]), a line without a comma split at whitespace;
/// blank lines and lines starting with `#` left out.
fn data_rows(text: &str) -> Result<Vec<(usize, Vec<String>)>, RecordingError> {
    let mut rows = Vec::new();
    for record in antenna_scene::csv_lines::Records::new(text) {
        let (line, record) =
            record.map_err(|(line, why)| RecordingError::Unreadable { line, why })?;
        let fields: Vec<String> = match record.iter().collect::<Vec<_>>().as_slice() {
            [] | [""] => continue,
            [first, ..] if first.starts_with('#') => continue,
            [only] => only.split_whitespace().map(str::to_string).collect(),
            fields => fields.iter().map(|f| f.to_string()).collect(),
        };
        rows.push((line, fields));
    }
    Ok(rows)
}

impl Recording {
    /// Parses the CSV format described in the module docs.
    ///
    /// # Errors
    /// [`RecordingError`] naming the line (and column) that is wrong.
    pub fn parse(text: &str) -> Result<Recording, RecordingError> {
        let mut rows = data_rows(text)?.into_iter().peekable();
        let Some((first_line, first_fields)) = rows.peek().cloned() else {
            return Err(RecordingError::Empty);
        };
        let is_header = first_fields.iter().any(|f| f.parse::<f64>().is_err());
        let columns: Vec<String>;
        let (time_col, angle_col, angle_in_deg) = if is_header {
            rows.next();
            columns = first_fields;
            let find = |name: &str| columns.iter().position(|c| c == name);
            let time = find("t_s");
            let (angle, deg) = match (find("angle_rad"), find("angle_deg")) {
                (Some(a), _) => (a, false),
                (None, Some(a)) => (a, true),
                (None, None) => {
                    return Err(RecordingError::NoAngleColumn {
                        line: first_line,
                        found: columns.join(", "),
                    });
                }
            };
            (time, angle, deg)
        } else {
            match first_fields.len() {
                1 => {
                    columns = vec!["angle_rad".to_string()];
                    (None, 0, false)
                }
                2 => {
                    columns = vec!["t_s".to_string(), "angle_rad".to_string()];
                    (Some(0), 1, false)
                }
                n => {
                    return Err(RecordingError::TooManyColumns {
                        line: first_line,
                        columns: n,
                    });
                }
            }
        };

        let mut times = Vec::new();
        let mut lines = Vec::new();
        let mut angle_rad = Vec::new();
        for (line, f) in rows {
            if f.len() != columns.len() {
                return Err(RecordingError::RaggedRow {
                    line,
                    expected: columns.len(),
                    found: f.len(),
                });
            }
            let number = |col: usize| {
                f[col]
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| RecordingError::BadNumber {
                        line,
                        column: columns[col].clone(),
                        text: f[col].clone(),
                    })
            };
            let a = number(angle_col)?;
            angle_rad.push(if angle_in_deg { a.to_radians() } else { a });
            if let Some(t) = time_col {
                times.push(number(t)?);
                lines.push(line);
            }
        }
        if angle_rad.is_empty() {
            return Err(RecordingError::Empty);
        }
        let sample_rate_hz = match time_col {
            Some(_) if times.len() >= 2 => Some(uniform_rate_hz(&times, &lines)?),
            _ => None,
        };
        Ok(Recording {
            angle_rad,
            sample_rate_hz,
        })
    }
}

/// `(samples - 1) / (t_last - t_first)` after checking every step against the mean.
fn uniform_rate_hz(times: &[f64], lines: &[usize]) -> Result<f64, RecordingError> {
    let span_s = times[times.len() - 1] - times[0];
    let mean_step_s = span_s / (times.len() - 1) as f64;
    for (k, w) in times.windows(2).enumerate() {
        let step_s = w[1] - w[0];
        if !(mean_step_s > 0.0 && (step_s - mean_step_s).abs() <= 0.01 * mean_step_s) {
            return Err(RecordingError::NonUniformTime {
                line: lines[k + 1],
                step_s,
                mean_step_s,
            });
        }
    }
    Ok(1.0 / mean_step_s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headerless_one_and_two_columns() {
        let r = Recording::parse("0.1\n0.2\n0.3\n").unwrap();
        assert_eq!(r.angle_rad, vec![0.1, 0.2, 0.3]);
        assert_eq!(r.sample_rate_hz, None);
        let r = Recording::parse("0 0.1\n0.5 0.2\n1.0 0.3\n").unwrap();
        assert_eq!(r.sample_rate_hz, Some(2.0));
    }

    #[test]
    fn errors_name_the_line() {
        assert_eq!(Recording::parse("# only\n"), Err(RecordingError::Empty));
        let e = Recording::parse("t_s,angle_rad\n0,1\n0.1,x\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "line 3, column `angle_rad`: \"x\" is not a finite number"
        );
        let e = Recording::parse("t_s,angle_rad\n0,1\n0.1,1\n0.3,1\n").unwrap_err();
        assert!(
            matches!(e, RecordingError::NonUniformTime { line: 3, .. }),
            "{e}"
        );
        let e = Recording::parse("t,theta\n0,1\n").unwrap_err();
        assert!(e.to_string().contains("no angle column"), "{e}");
        let e = Recording::parse("1,2,3\n").unwrap_err();
        assert!(matches!(
            e,
            RecordingError::TooManyColumns {
                line: 1,
                columns: 3
            }
        ));
        let e = Recording::parse("1,2\n1\n").unwrap_err();
        assert!(matches!(e, RecordingError::RaggedRow { line: 2, .. }));
    }
}
