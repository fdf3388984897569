//! Where a key is written: the spans of the toml crate's own parser ([`DeTable`], every key
//! and value a [`toml::Spanned`]), as 1-based lines and columns.

use super::ConfigError;
use std::ops::Range;
use toml::de::{DeTable, DeValue};

/// One key of the text: its dotted path (list entries indexed: `trials[0].moves[1].name`),
/// where its key and its value are written.
#[derive(Debug)]
struct Entry {
    path: String,
    key: Range<usize>,
    value: Range<usize>,
}

impl Entry {
    /// Where the entry starts: the key, or the `[` of a table's header.
    fn start(&self) -> usize {
        self.key.start.min(self.value.start)
    }

    fn contains(&self, offset: usize) -> bool {
        self.key.contains(&offset) || self.value.contains(&offset)
    }
}

/// Every key of a TOML text and where it is written, as the parser saw it (what parses
/// of a text with syntax errors).
#[derive(Debug)]
pub(super) struct Spans<'t> {
    text: &'t str,
    entries: Vec<Entry>,
}

impl<'t> Spans<'t> {
    /// The keys of `text`.
    pub(super) fn parse(text: &'t str) -> Self {
        let (root, _errors) = DeTable::parse_recoverable(text);
        let mut entries = Vec::new();
        walk_table("", root.get_ref(), &mut entries);
        Self { text, entries }
    }

    /// Line and column of the dotted `key` (`trials[0].moves[1].speed_mm_per_s`), or of the
    /// nearest table holding it when the key is not written (a default in force).
    pub(super) fn locate(&self, key: &str) -> Option<(usize, usize)> {
        let mut path = key;
        loop {
            if let Some(entry) = self.entries.iter().find(|e| e.path == path) {
                return Some(line_column(self.text, entry.start()));
            }
            path = &path[..path.rfind(['.', '['])?];
        }
    }

    /// The innermost entry written at byte `offset`.
    fn entry_at(&self, offset: usize) -> Option<&Entry> {
        self.entries
            .iter()
            .filter(|e| e.contains(offset))
            .max_by_key(|e| (e.path.len(), std::cmp::Reverse(e.start())))
    }
}

fn join(table: &str, key: &str) -> String {
    if table.is_empty() {
        key.to_owned()
    } else {
        format!("{table}.{key}")
    }
}

fn walk_table(prefix: &str, table: &DeTable<'_>, entries: &mut Vec<Entry>) {
    for (key, value) in table {
        let path = join(prefix, key.get_ref());
        entries.push(Entry {
            path: path.clone(),
            key: key.span(),
            value: value.span(),
        });
        walk_value(&path, value.get_ref(), entries);
    }
}

fn walk_value(path: &str, value: &DeValue<'_>, entries: &mut Vec<Entry>) {
    match value {
        DeValue::Table(table) => walk_table(path, table, entries),
        DeValue::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                let path = format!("{path}[{i}]");
                entries.push(Entry {
                    path: path.clone(),
                    key: item.span(),
                    value: item.span(),
                });
                walk_value(&path, item.get_ref(), entries);
            }
        }
        _ => {}
    }
}

/// `path` without its list indices (`bus.segments[0]` is `bus.segments`), as a file's
/// headers name the table.
fn without_indices(path: &str) -> String {
    let mut out = String::with_capacity(path.len());
    let mut depth = 0usize;
    for c in path.chars() {
        match c {
            '[' => depth += 1,
            ']' => depth = depth.saturating_sub(1),
            c if depth == 0 => out.push(c),
            _ => {}
        }
    }
    out
}

/// Line and column (1-based) of byte `offset` in `text`.
pub(super) fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = text.get(..offset).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

/// A TOML or serde error as a [`ConfigError`] naming the key (as the file's headers name its
/// table: `bus.segments.zero_counts`), line and column.
pub(super) fn toml_error(text: &str, path: &str, e: &toml::de::Error) -> ConfigError {
    let offset = e.span().map_or(0, |s| s.start);
    let (line, column) = line_column(text, offset);
    let message = e.message().trim().to_owned();
    let spans = Spans::parse(text);
    let at = spans
        .entry_at(offset)
        .map(|entry| without_indices(&entry.path));
    let field = ["unknown field `", "missing field `"]
        .iter()
        .find_map(|prefix| message.strip_prefix(prefix))
        .map(|rest| rest.split('`').next().unwrap_or_default());
    let key = match (field, at) {
        // The unknown key itself, or the table missing one.
        (Some(field), Some(at)) if at == field || at.ends_with(&format!(".{field}")) => at,
        (Some(field), Some(at)) => join(&at, field),
        (Some(field), None) => field.to_owned(),
        (None, Some(at)) => at,
        (None, None) => "(top level)".to_owned(),
    };
    ConfigError {
        path: path.to_owned(),
        key,
        line: Some(line),
        column: Some(column),
        message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_lines_are_located() {
        let text = "[stage]\nmin_mm = 0\n  max_mm = -1\n";
        let spans = Spans::parse(text);
        assert_eq!(spans.locate("stage.max_mm"), Some((3, 3)));
        // A key left out is placed at its table's header; no table, no place.
        assert_eq!(spans.locate("stage.steps_per_mm"), Some((1, 1)));
        assert_eq!(spans.locate("bus.poll_hz"), None);
        assert_eq!(line_column("ab\ncd", 4), (2, 2));
    }

    #[test]
    fn list_entries_are_located_by_index() {
        let text = "[[trials]]\nname = \"a\"\n[[trials]]\nname = \"b\"\n\
                    moves = [{ distance_mm = 1.0 }, { distance_mm = 2.0 }]\n";
        let spans = Spans::parse(text);
        assert_eq!(spans.locate("trials[1].name"), Some((4, 1)));
        assert_eq!(
            spans.locate("trials[1].moves[1].distance_mm"),
            Some((5, 35))
        );
        // An entry's key left out: the entry itself.
        assert_eq!(
            spans.locate("trials[1].moves[1].speed_mm_per_s"),
            Some((5, 33))
        );
        assert_eq!(spans.locate("trials[0].base_angle_deg"), Some((1, 1)));
    }

    #[test]
    fn indices_are_dropped_as_headers_name_tables() {
        assert_eq!(
            without_indices("bus.segments[10].address"),
            "bus.segments.address"
        );
        assert_eq!(without_indices("stage"), "stage");
    }
}
