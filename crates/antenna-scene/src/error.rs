//! Errors in a scene file, each naming the file, the key and, where the parser knows it, the
//! line and column.

use std::fmt;

/// A 1-based line and column in a scene file (columns count characters, not bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Location {
    /// Line, from 1.
    pub line: usize,
    /// Column, from 1.
    pub column: usize,
}

impl Location {
    /// The line and column of byte `offset` in `text` (clamped to the text).
    pub fn of_offset(text: &str, offset: usize) -> Location {
        let mut offset = offset.min(text.len());
        while !text.is_char_boundary(offset) {
            offset -= 1;
        }
        let before = &text[..offset];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = text[line_start..offset].chars().count() + 1;
        Location { line, column }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.column)
    }
}

/// What is wrong with a scene file.
#[derive(Debug, thiserror::Error)]
pub enum SceneErrorKind {
    /// The file could not be read.
    #[error("cannot read the scene file: {0}")]
    Io(std::io::Error),
    /// The text is not valid TOML, or a value has the wrong type (the TOML parser's message,
    /// with the key added when it can be found).
    #[error("{message}")]
    Syntax {
        /// What the parser said.
        message: String,
    },
    /// A key that is not part of the scene format.
    #[error("unknown key `{key}` in {table}; allowed: {}", allowed.join(", "))]
    UnknownKey {
        /// The key as written.
        key: String,
        /// The table it is in, e.g. `[antenna]` or `the top level`.
        table: String,
        /// The keys allowed in that table.
        allowed: Vec<String>,
    },
    /// A required key is absent.
    #[error("missing key `{key}` in {table}")]
    MissingKey {
        /// The key that is required.
        key: String,
        /// The table it belongs in.
        table: String,
    },
    /// Two keys that exclude each other are both given.
    #[error("`{key}` and `{other}` in {table} exclude each other; give one of them")]
    Conflict {
        /// The key reported (the later one in the file).
        key: String,
        /// The key it conflicts with.
        other: String,
        /// The table both are in.
        table: String,
    },
    /// A key naming a file whose contents are wrong (a wall's `points_file`): the file's own
    /// error names the file and its line.
    #[error("`{key}` in {table}: {error}")]
    PointsFile {
        /// The key.
        key: String,
        /// The table it is in.
        table: String,
        /// What is wrong in the file, and where.
        error: crate::points_file::PointsFileError,
    },
    /// A key with a value out of its domain (a NaN, a list of the wrong length, min > max, an
    /// unknown profile name, ...).
    #[error("`{key}` in {table}: {reason}")]
    Invalid {
        /// The key.
        key: String,
        /// The table it is in.
        table: String,
        /// What is wrong, in words.
        reason: String,
    },
    /// A run of the scene (a follow scene's closed loop) could not start or go on for a
    /// reason no one key is to blame for (a step the antenna's solver refused, ...).
    #[error("{message}")]
    Run {
        /// What went wrong, in words.
        message: String,
    },
}

/// An error in a scene file: the file, where in it (when known) and what.
///
/// Displays as `path:line:column: message` (or `path: message` without a location), e.g.
/// ``scene.toml:7:1: unknown key `foo` in [antenna]; allowed: links, link_length_m, ...``.
#[derive(Debug)]
pub struct SceneError {
    /// The file name as given on the command line.
    pub path: String,
    /// Where in the file, when the parser knows.
    pub location: Option<Location>,
    /// What is wrong (boxed: errors travel in `Result`s and should stay small).
    pub kind: Box<SceneErrorKind>,
}

/// The message already includes the cause (an I/O error's text), so there is no `source`:
/// printing the chain does not repeat it.
impl std::error::Error for SceneError {}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.location {
            Some(at) => write!(f, "{}:{}: {}", self.path, at, self.kind),
            None => write!(f, "{}: {}", self.path, self.kind),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_map_to_one_based_lines_and_columns() {
        let text = "a = 1\nbé = 2\n";
        assert_eq!(
            Location::of_offset(text, 0),
            Location { line: 1, column: 1 }
        );
        assert_eq!(
            Location::of_offset(text, 6),
            Location { line: 2, column: 1 }
        );
        // 'é' is two bytes: the '=' after "bé " is at byte 10, column 4.
        assert_eq!(
            Location::of_offset(text, 10),
            Location { line: 2, column: 4 }
        );
        assert_eq!(
            Location::of_offset(text, 999),
            Location { line: 3, column: 1 }
        );
    }
}
