//! `points_file` of a polyline `[[walls]]` table: a digitized wall, read from a CSV file of
//! points instead of `vertices_m` (issue #14).
//!
//! The file has one `x_m,y_m` point per line (metres, ground frame), in the order of the
//! polyline's vertices, and may start with a header line (a first line with no number in it,
//! e.g. `x_m,y_m`). Whitespace around lines and fields, CRLF line ends, a byte-order mark and
//! empty lines after the last point are accepted. Every error names the file and, where it
//! is about one, its 1-based line: a field that is not a number, a NaN or an infinity, a
//! line without exactly two fields, an empty line between points, fewer than 2 points, and
//! a polyline sim-core refuses (two consecutive points the same, a point where it doubles
//! back, two edges that cross), told by the lines of the points involved.
//!
//! ```
//! use antenna_scene::points_file::parse_points;
//!
//! let points = parse_points("x_m,y_m\r\n0.0, 0.2\r\n0.5,0.15\r\n1.0,0.2\r\n").unwrap();
//! assert_eq!(points.points_m.len(), 3);
//! assert_eq!(points.lines, [2, 3, 4]);
//! let (line, error) = parse_points("x_m,y_m\n0.0,0.2\n0.5,abc\n").unwrap_err();
//! assert_eq!(line, 3);
//! assert_eq!(error.to_string(), "`y_m` is \"abc\", not a number");
//! ```

use std::path::{Path, PathBuf};

use nalgebra::Vector2;
use sim_core::{Polyline, SolidSide, WallError};

/// The names of a line's two fields, in errors.
const FIELD_NAMES: [&str; 2] = ["x_m", "y_m"];

/// An error in a points file: the file (as resolved against the scene's folder), the line
/// (1-based) where the error is about one, and what is wrong.
///
/// Displays as `path:line: message`, or `path: message` without a line.
#[derive(Debug, thiserror::Error)]
#[error("{}: {kind}", place(.path, .line))]
pub struct PointsFileError {
    /// The file, as resolved (the scene's folder joined with `points_file`).
    pub path: PathBuf,
    /// The 1-based line the error is about (`None`: the file could not be read).
    pub line: Option<usize>,
    /// What is wrong.
    pub kind: PointsFileErrorKind,
}

/// What is wrong with a points file.
#[derive(Debug, thiserror::Error)]
pub enum PointsFileErrorKind {
    /// The file could not be read (missing, unreadable, not UTF-8).
    #[error("cannot read the points file: {0}")]
    Read(std::io::Error),
    /// The csv reader could not read a line (not expected of text).
    #[error("cannot read the line: {0}")]
    Unreadable(String),
    /// No line holds anything.
    #[error("the file is empty; a points file has one `x_m,y_m` point per line")]
    Empty,
    /// Fewer than 2 points (after the header).
    #[error("{count} point(s) in the file; a polyline needs at least 2")]
    TooFewPoints {
        /// The points found.
        count: usize,
    },
    /// An empty line with points after it.
    #[error("an empty line between points; a points file has one `x_m,y_m` point per line")]
    EmptyLine,
    /// A line without exactly two fields.
    #[error("{found} field(s); expected 2 (`x_m,y_m`)")]
    FieldCount {
        /// The comma-separated fields found.
        found: usize,
    },
    /// A field that does not parse as a number.
    #[error("`{field}` is \"{text}\", not a number")]
    NotANumber {
        /// `x_m` or `y_m`.
        field: &'static str,
        /// The field as written (trimmed).
        text: String,
    },
    /// A NaN or an infinity (`nan`, `inf`, or a number beyond `f64`'s range).
    #[error("`{field}` is {value}; every coordinate is a finite number of metres")]
    NotFinite {
        /// `x_m` or `y_m`.
        field: &'static str,
        /// The value read.
        value: f64,
    },
    /// A point equal to the one before it (a zero-length edge).
    #[error("the same point as line {previous_line}; consecutive points must differ")]
    RepeatedPoint {
        /// The line of the point before.
        previous_line: usize,
    },
    /// The polyline turns back by 180 degrees at this line's point.
    #[error(
        "the polyline doubles back on itself at this point (lines {previous_line} and \
         {next_line} lie in the same direction from it)"
    )]
    DoublesBack {
        /// The line of the point before.
        previous_line: usize,
        /// The line of the point after.
        next_line: usize,
    },
    /// Two non-adjacent edges meet.
    #[error("the polyline crosses itself: {first} meets {second}")]
    EdgesCross {
        /// The first edge, in words with its lines (`the edge from line 5 to line 6`).
        first: String,
        /// The second edge, in words with its lines.
        second: String,
    },
    /// Any other polyline error from sim-core.
    #[error("{0}")]
    Polyline(WallError),
}

/// The points of a file, with the line each came from.
#[derive(Clone, Debug, PartialEq)]
pub struct Points {
    /// The points, metres, in file order.
    pub points_m: Vec<Vector2<f64>>,
    /// The 1-based line of each point.
    pub lines: Vec<usize>,
}

/// `path:line`, or `path` without a line.
fn place(path: &Path, line: &Option<usize>) -> String {
    match *line {
        Some(line) => format!("{}:{line}", path.display()),
        None => path.display().to_string(),
    }
}

/// Reads the points file at `path` (already resolved against the scene's folder) and builds
/// the polyline through its points, solid on `solid`.
///
/// # Errors
/// [`PointsFileError`] naming `path` and, except when it cannot be read, the line.
pub fn read_polyline(path: &Path, solid: SolidSide) -> Result<Polyline, PointsFileError> {
    let error = |line: Option<usize>, kind: PointsFileErrorKind| PointsFileError {
        path: path.to_path_buf(),
        line,
        kind,
    };
    let text =
        std::fs::read_to_string(path).map_err(|e| error(None, PointsFileErrorKind::Read(e)))?;
    let points = parse_points(&text).map_err(|(line, kind)| error(Some(line), kind))?;
    let Points { points_m, lines } = points;
    Polyline::new(points_m, solid).map_err(|e| {
        let (line, kind) = polyline_error(&lines, e);
        error(Some(line), kind)
    })
}

/// The points of a points file's text, with their lines.
///
/// # Errors
/// The 1-based line and what is wrong there (for an empty file, line 1; for too few points,
/// the last line that holds anything).
pub fn parse_points(text: &str) -> Result<Points, (usize, PointsFileErrorKind)> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut points_m = Vec::new();
    let mut lines = Vec::new();
    let mut last_content_line: usize = 0;
    // The reader skips empty lines; a line of spaces is one empty field.
    for record in crate::csv_lines::Records::new(text) {
        let (line, record) =
            record.map_err(|(line, why)| (line, PointsFileErrorKind::Unreadable(why)))?;
        if record.iter().all(str::is_empty) {
            continue;
        }
        if last_content_line > 0 && line > last_content_line + 1 {
            // Every line between two that hold something is blank.
            return Err((last_content_line + 1, PointsFileErrorKind::EmptyLine));
        }
        let first_content = last_content_line == 0;
        last_content_line = line;
        if first_content && record.iter().all(|f| f.parse::<f64>().is_err()) {
            // A header.
            continue;
        }
        let [x, y] = [0, 1].map(|k| record.get(k).unwrap_or_default());
        if record.len() != 2 {
            return Err((
                line,
                PointsFileErrorKind::FieldCount {
                    found: record.len(),
                },
            ));
        }
        let x_m = coordinate(x, FIELD_NAMES[0]).map_err(|k| (line, k))?;
        let y_m = coordinate(y, FIELD_NAMES[1]).map_err(|k| (line, k))?;
        points_m.push(Vector2::new(x_m, y_m));
        lines.push(line);
    }
    if last_content_line == 0 {
        return Err((1, PointsFileErrorKind::Empty));
    }
    if points_m.len() < 2 {
        return Err((
            last_content_line,
            PointsFileErrorKind::TooFewPoints {
                count: points_m.len(),
            },
        ));
    }
    Ok(Points { points_m, lines })
}

/// A field as a finite number.
fn coordinate(text: &str, field: &'static str) -> Result<f64, PointsFileErrorKind> {
    let value: f64 = text.parse().map_err(|_| PointsFileErrorKind::NotANumber {
        field,
        text: text.to_string(),
    })?;
    if value.is_finite() {
        Ok(value)
    } else {
        Err(PointsFileErrorKind::NotFinite { field, value })
    }
}

/// sim-core's refusal of the polyline through the points on `lines`, told by those lines:
/// the line to report and what is wrong.
fn polyline_error(lines: &[usize], e: WallError) -> (usize, PointsFileErrorKind) {
    let line = |vertex: usize| lines.get(vertex).copied().unwrap_or(0);
    let edges = lines.len().saturating_sub(1);
    match e {
        WallError::ZeroLengthEdge { index } => (
            line(index + 1),
            PointsFileErrorKind::RepeatedPoint {
                previous_line: line(index),
            },
        ),
        WallError::EdgeDoublesBack { vertex } => (
            line(vertex),
            PointsFileErrorKind::DoublesBack {
                previous_line: line(vertex.saturating_sub(1)),
                next_line: line(vertex + 1),
            },
        ),
        WallError::EdgesCross { first, second } => {
            let words = |edge: usize| {
                let (from, to) = (line(edge), line(edge + 1));
                if edge == 0 {
                    format!(
                        "the edge from line {from} to line {to} (run on backward past line {from})"
                    )
                } else if edge + 1 == edges {
                    format!("the edge from line {from} to line {to} (run on past line {to})")
                } else {
                    format!("the edge from line {from} to line {to}")
                }
            };
            (
                line(first),
                PointsFileErrorKind::EdgesCross {
                    first: words(first),
                    second: words(second),
                },
            )
        }
        other => (line(0), PointsFileErrorKind::Polyline(other)),
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn fails(text: &str) -> (usize, String) {
        let (line, kind) = parse_points(text).unwrap_err();
        (line, kind.to_string())
    }

    #[test]
    fn headers_whitespace_and_line_ends() {
        let plain = parse_points("0,0.2\n1,0.2\n").unwrap();
        assert_eq!(
            plain.points_m,
            [Vector2::new(0.0, 0.2), Vector2::new(1.0, 0.2)]
        );
        assert_eq!(plain.lines, [1, 2]);
        let header = parse_points("\u{feff} x_m , y_m \r\n 0 , 0.2 \r\n1,0.2\r\n\r\n  \n").unwrap();
        assert_eq!(header.points_m, plain.points_m);
        assert_eq!(header.lines, [2, 3]);
        // No final line end.
        assert_eq!(
            parse_points("0,0.2\n1,0.2").unwrap().points_m,
            plain.points_m
        );
        // Blank lines before the first line that holds anything count in the line numbers.
        assert_eq!(parse_points("\n\nx,y\n0,0.2\n1,0.2").unwrap().lines, [4, 5]);
    }

    #[test]
    fn bad_lines_are_named() {
        assert_eq!(
            fails(""),
            (
                1,
                "the file is empty; a points file has one `x_m,y_m` point per line".into()
            )
        );
        assert_eq!(fails(" \r\n\n").0, 1);
        assert_eq!(
            fails("x_m,y_m\n").1,
            "0 point(s) in the file; a polyline needs at least 2"
        );
        assert_eq!(fails("x_m,y_m\n0,0\n\n").0, 2);
        assert_eq!(
            fails("0,0\n1,0,2\n"),
            (2, "3 field(s); expected 2 (`x_m,y_m`)".into())
        );
        assert_eq!(fails("0,0\n1\n").1, "1 field(s); expected 2 (`x_m,y_m`)");
        assert_eq!(
            fails("0,0\n\n1,0\n"),
            (
                2,
                "an empty line between points; a points file has one `x_m,y_m` point per line"
                    .into()
            )
        );
        assert_eq!(
            fails("0,0\nabc,1\n"),
            (2, "`x_m` is \"abc\", not a number".into())
        );
        // A first line with one number is a point, not a header.
        assert_eq!(
            fails("1,y\n0,0\n1,0\n"),
            (1, "`y_m` is \"y\", not a number".into())
        );
        assert_eq!(
            fails("0,0\n1,NaN\n"),
            (
                2,
                "`y_m` is NaN; every coordinate is a finite number of metres".into()
            )
        );
        assert_eq!(
            fails("0,0\n-inf,1\n").1,
            "`x_m` is -inf; every coordinate is a finite number of metres"
        );
        assert_eq!(
            fails("0,0\n1e400,1\n").1,
            "`x_m` is inf; every coordinate is a finite number of metres"
        );
    }

    #[test]
    fn polyline_errors_name_the_lines_of_their_points() {
        let lines = [2, 3, 4, 5, 6, 7];
        let (line, kind) = polyline_error(&lines, WallError::ZeroLengthEdge { index: 2 });
        assert_eq!(
            (line, kind.to_string()),
            (
                5,
                "the same point as line 4; consecutive points must differ".into()
            )
        );
        let (line, kind) = polyline_error(&lines, WallError::EdgeDoublesBack { vertex: 1 });
        assert_eq!(line, 3);
        assert!(
            kind.to_string()
                .contains("(lines 2 and 4 lie in the same direction"),
            "{kind}"
        );
        let (line, kind) = polyline_error(
            &lines,
            WallError::EdgesCross {
                first: 0,
                second: 4,
            },
        );
        assert_eq!(
            (line, kind.to_string()),
            (2, "the polyline crosses itself: the edge from line 2 to line 3 (run on backward past \
                 line 2) meets the edge from line 6 to line 7 (run on past line 7)".into())
        );
        let (line, kind) = polyline_error(
            &lines,
            WallError::EdgesCross {
                first: 1,
                second: 3,
            },
        );
        assert_eq!(
            (line, kind.to_string()),
            (
                3,
                "the polyline crosses itself: the edge from line 3 to line 4 meets the edge from \
                 line 5 to line 6"
                    .into()
            )
        );
    }
}
