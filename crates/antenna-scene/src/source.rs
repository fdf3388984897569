//! The scene text and its name, for turning spans into located errors; the checks every
//! table's values share (finite numbers, positive numbers, lists of a given length, points,
//! names from a list). Public so that the toolkit's other input files (a study, an
//! optimization) give their errors the way scenes do.

use std::ops::Range;

use nalgebra::Vector2;
use toml::Spanned;

use super::keys::{REQUIRED_KEYS, TABLES};
use crate::error::{Location, SceneError, SceneErrorKind};

/// Reads an input file (a scene, a study, an optimization): its text, its name as given
/// (for errors) and its folder (what its relative paths are relative to).
///
/// # Errors
/// [`SceneErrorKind::Io`] naming the file.
pub fn read_input(
    path: &std::path::Path,
) -> Result<(String, String, &std::path::Path), SceneError> {
    let label = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| SceneError {
        path: label.clone(),
        location: None,
        kind: Box::new(SceneErrorKind::Io(e)),
    })?;
    let folder = path.parent().unwrap_or_else(|| std::path::Path::new(""));
    Ok((text, label, folder))
}

/// The scene text and its name, for turning spans into located errors.
pub struct Source<'a> {
    /// The whole text of the file.
    pub text: &'a str,
    /// The file's name as given (what errors start with).
    pub path: &'a str,
}

impl Source<'_> {
    /// The line and column where `span` starts.
    pub fn at(&self, span: Range<usize>) -> Option<Location> {
        Some(Location::of_offset(self.text, span.start))
    }

    /// An error of `kind` at `span` (without a location when `span` is `None`).
    pub fn error(&self, span: Option<Range<usize>>, kind: SceneErrorKind) -> SceneError {
        SceneError {
            path: self.path.to_string(),
            location: span.and_then(|s| self.at(s)),
            kind: Box::new(kind),
        }
    }

    /// [`SceneErrorKind::Invalid`]: `key` in `table` (at `span`) has a value out of its domain.
    pub fn invalid(
        &self,
        span: Range<usize>,
        table: &str,
        key: &str,
        reason: impl Into<String>,
    ) -> SceneError {
        self.error(
            Some(span),
            SceneErrorKind::Invalid {
                key: key.to_string(),
                table: table.to_string(),
                reason: reason.into(),
            },
        )
    }

    /// [`SceneErrorKind::MissingKey`]: `table` (at `span`) lacks the required `key`.
    pub fn missing(&self, span: Range<usize>, table: &str, key: &str) -> SceneError {
        self.error(
            Some(span),
            SceneErrorKind::MissingKey {
                key: key.to_string(),
                table: table.to_string(),
            },
        )
    }

    /// Turns a TOML/serde error into a located scene error naming the key (where the text
    /// is TOML, its tables and keys are found with toml_edit's spans).
    pub fn toml_error(&self, e: &toml::de::Error) -> SceneError {
        let span = e.span();
        let offset = span.as_ref().map_or(0, |s| s.start);
        let message = e.message().trim().to_string();
        let layout = Layout::of(self.text, offset);
        if let Some(rest) = message.strip_prefix("unknown field `") {
            let names = backticked(rest);
            let key = rest.split('`').next().unwrap_or_default().to_string();
            let allowed: Vec<String> = names.into_iter().collect();
            let table = table_with_keys(&allowed).map_or_else(
                || layout.table_at(self.text, offset),
                |t| layout.array_table(t, offset),
            );
            return self.error(
                span,
                SceneErrorKind::UnknownKey {
                    key,
                    table,
                    allowed,
                },
            );
        }
        if let Some(rest) = message.strip_prefix("missing field `") {
            let key = rest.split('`').next().unwrap_or_default().to_string();
            let owners: Vec<&str> = REQUIRED_KEYS
                .iter()
                .filter(|(_, k)| *k == key)
                .map(|(t, _)| *t)
                .collect();
            let table = match owners.as_slice() {
                [only] => layout.array_table(only, offset),
                _ => layout.table_at(self.text, offset),
            };
            return self.error(span, SceneErrorKind::MissingKey { key, table });
        }
        let message = match layout.key_at(offset) {
            Some(key) => format!(
                "`{key}` in {}: {message}",
                layout.table_at(self.text, offset)
            ),
            None => message,
        };
        self.error(span, SceneErrorKind::Syntax { message })
    }
}

/// The label of the `index`-th (0-based) `[[walls]]` table in errors.
pub fn wall_table(index: usize) -> String {
    format!("[[walls]] (wall {index})")
}

/// The label of zone `zone` (0-based) of wall `wall` in errors.
pub fn zone_table(wall: usize, zone: usize) -> String {
    format!("[[walls.zones]] (wall {wall}, zone {zone})")
}

/// The names between backticks in `text` after its first backticked name.
fn backticked(text: &str) -> Vec<String> {
    // `text` starts just after the first opening backtick: "foo`, expected one of `a`, `b`".
    text.split('`')
        .skip(1)
        .enumerate()
        .filter(|(i, _)| i % 2 == 1)
        .map(|(_, s)| s.to_string())
        .collect()
}

/// The table whose allowed keys are exactly `keys`, if exactly one is.
fn table_with_keys(keys: &[String]) -> Option<&'static str> {
    let mut found = TABLES.iter().filter(|(_, allowed)| {
        allowed.len() == keys.len() && allowed.iter().all(|a| keys.iter().any(|k| k == a))
    });
    match (found.next(), found.next()) {
        (Some((table, _)), None) => Some(table),
        _ => None,
    }
}

/// Where the tables and values of a TOML text are, from toml_edit's spans: each table
/// header's offset with its label in errors, and each value's span with its key.
#[derive(Default)]
struct Layout {
    /// Table headers, in file order.
    headers: Vec<Header>,
    /// The values of `key = value` lines (a dotted key joined with `.`), at any depth of
    /// tables but not inside a value (an inline table is one value).
    values: Vec<(Range<usize>, String)>,
}

/// A `[name]` or `[[name]]` header.
struct Header {
    /// Its byte offset.
    start: usize,
    /// The table's dotted name.
    name: String,
    /// How errors name it: `[name]`, `[[walls]] (wall 1)`, ...
    label: String,
}

impl Layout {
    /// The layout of `text`; for a syntax error at byte `offset`, the tables of the lines
    /// before it and the key written before it on its line (`key = ` then the bad value).
    fn of(text: &str, offset: usize) -> Layout {
        let mut layout = Layout::default();
        if let Ok(document) = toml_edit::Document::parse(text) {
            layout.walk(document.as_table(), "", None);
        } else {
            let offset = offset.min(text.len());
            let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
            if let Ok(document) = toml_edit::Document::parse(&text[..line_start]) {
                layout.walk(document.as_table(), "", None);
            }
            let key = text[line_start..offset]
                .split_once('=')
                .and_then(|(key, _)| toml_edit::Key::parse(key.trim()).ok());
            if let Some(key) = key {
                let key: Vec<&str> = key.iter().map(toml_edit::Key::get).collect();
                layout.values.push((offset..offset + 1, key.join(".")));
            }
        }
        layout.headers.sort_by_key(|h| h.start);
        layout
    }

    /// Adds `table`'s values and its sub-tables (`path` its name, `wall` the index of the
    /// `[[walls]]` table it is in).
    fn walk(&mut self, table: &toml_edit::Table, path: &str, wall: Option<usize>) {
        for (keys, value) in table.get_values() {
            if let Some(span) = value.span() {
                let key: Vec<&str> = keys.iter().map(|k| k.get()).collect();
                self.values.push((span, key.join(".")));
            }
        }
        for (key, item) in table.iter() {
            let name = if path.is_empty() {
                key.to_string()
            } else {
                format!("{path}.{key}")
            };
            match item {
                toml_edit::Item::Table(t) if !t.is_dotted() => {
                    if let (false, Some(span)) = (t.is_implicit(), t.span()) {
                        let label = format!("[{name}]");
                        self.header(span.start, &name, label);
                    }
                    self.walk(t, &name, wall);
                }
                toml_edit::Item::ArrayOfTables(array) => {
                    for (index, t) in array.iter().enumerate() {
                        let (label, wall) = match (name.as_str(), wall) {
                            ("walls", _) => (wall_table(index), Some(index)),
                            ("walls.zones", Some(w)) => (zone_table(w, index), wall),
                            _ => (format!("[[{name}]]"), wall),
                        };
                        if let Some(span) = t.span() {
                            self.header(span.start, &name, label);
                        }
                        self.walk(t, &name, wall);
                    }
                }
                _ => {}
            }
        }
    }

    fn header(&mut self, start: usize, name: &str, label: String) {
        self.headers.push(Header {
            start,
            name: name.to_string(),
            label,
        });
    }

    /// The table header in force at byte `offset` of `text` (written on a line before it),
    /// or `the top level`.
    fn table_at(&self, text: &str, offset: usize) -> String {
        let offset = offset.min(text.len());
        let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
        self.headers
            .iter()
            .rfind(|h| h.start < line_start)
            .map_or_else(|| "the top level".to_string(), |h| h.label.clone())
    }

    /// `table` with its index added when it is an array of tables (`[[walls]]`,
    /// `[[walls.zones]]`): the last such header before byte `offset`.
    fn array_table(&self, table: &str, offset: usize) -> String {
        let before = || self.headers.iter().filter(|h| h.start < offset);
        let found = match table {
            "[[walls]]" => before().rfind(|h| h.name == "walls"),
            "[[walls.zones]]" => before()
                .rfind(|h| h.name == "walls" || h.name == "walls.zones")
                .filter(|h| h.name == "walls.zones"),
            _ => None,
        };
        found.map_or_else(|| table.to_string(), |h| h.label.clone())
    }

    /// The key whose value holds byte `offset`.
    fn key_at(&self, offset: usize) -> Option<String> {
        self.values
            .iter()
            .find(|(span, _)| span.contains(&offset))
            .map(|(_, key)| key.clone())
    }
}

/// `"a", "b", "c"`.
pub fn quoted_list(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The index of `value` in `names`, or an error listing the names.
pub fn one_of(
    source: &Source<'_>,
    table: &str,
    key: &str,
    value: &Spanned<String>,
    names: &[&str],
) -> Result<usize, SceneError> {
    let v = value.get_ref().as_str();
    names.iter().position(|n| *n == v).ok_or_else(|| {
        source.invalid(
            value.span(),
            table,
            key,
            format!("\"{v}\" is not one of {}", quoted_list(names)),
        )
    })
}

/// Checks that every value of a list is finite; returns the list.
pub fn finite_list(
    source: &Source<'_>,
    table: &str,
    key: &str,
    list: &Spanned<Vec<f64>>,
) -> Result<Vec<f64>, SceneError> {
    if let Some((i, v)) = list
        .get_ref()
        .iter()
        .enumerate()
        .find(|(_, v)| !v.is_finite())
    {
        return Err(source.invalid(
            list.span(),
            table,
            key,
            format!(
                "value #{} is {v}; every value must be a finite number",
                i + 1
            ),
        ));
    }
    Ok(list.get_ref().clone())
}

/// A finite list of exactly `len` values, `what` saying what each value is for.
pub fn list_of_len(
    source: &Source<'_>,
    table: &str,
    key: &str,
    list: &Spanned<Vec<f64>>,
    len: usize,
    what: &str,
) -> Result<Vec<f64>, SceneError> {
    let found = list.get_ref().len();
    if found != len {
        return Err(source.invalid(
            list.span(),
            table,
            key,
            format!("has {found} value(s); expected {len} ({what})"),
        ));
    }
    finite_list(source, table, key, list)
}

/// A point or vector `[x, y]`.
pub fn point(
    source: &Source<'_>,
    table: &str,
    key: &str,
    list: &Spanned<Vec<f64>>,
) -> Result<Vector2<f64>, SceneError> {
    let v = list_of_len(source, table, key, list, 2, "[x, y]")?;
    Ok(Vector2::new(v[0], v[1]))
}

/// A finite number.
pub fn finite(
    source: &Source<'_>,
    table: &str,
    key: &str,
    value: &Spanned<f64>,
) -> Result<f64, SceneError> {
    let v = *value.get_ref();
    if v.is_finite() {
        Ok(v)
    } else {
        Err(source.invalid(
            value.span(),
            table,
            key,
            format!("{v} is not a finite number"),
        ))
    }
}

/// A finite number > 0.
pub fn positive(
    source: &Source<'_>,
    table: &str,
    key: &str,
    value: &Spanned<f64>,
) -> Result<f64, SceneError> {
    let v = finite(source, table, key, value)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(source.invalid(value.span(), table, key, format!("{v} must be > 0")))
    }
}

/// A finite number >= 0.
pub fn non_negative(
    source: &Source<'_>,
    table: &str,
    key: &str,
    value: &Spanned<f64>,
) -> Result<f64, SceneError> {
    let v = finite(source, table, key, value)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(source.invalid(value.span(), table, key, format!("{v} must be >= 0")))
    }
}

/// An integer in `min..=max`.
pub fn count(
    source: &Source<'_>,
    table: &str,
    key: &str,
    value: &Spanned<i64>,
    min: usize,
    max: usize,
) -> Result<usize, SceneError> {
    let v = *value.get_ref();
    usize::try_from(v)
        .ok()
        .filter(|c| (min..=max).contains(c))
        .ok_or_else(|| {
            source.invalid(
                value.span(),
                table,
                key,
                format!("{v} is out of range {min}..={max}"),
            )
        })
}

/// An error for a key that the table's chosen variant does not take (`what` names the
/// variant, `takes` its keys).
pub fn not_for(
    source: &Source<'_>,
    span: Range<usize>,
    table: &str,
    key: &str,
    what: &str,
    takes: &[&str],
) -> SceneError {
    let takes = if takes.is_empty() {
        "no other keys".to_string()
    } else {
        takes.join(", ")
    };
    source.invalid(
        span,
        table,
        key,
        format!("not a key of {what} (it takes {takes})"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "a = 1\n[sweep]\nstep_s = [\n  0.1,\n  \"x\",\n]\n[[walls]]\nmu = 1\n\
                        [[walls]]\n[[walls.zones]]\nfrom_m = { b = 2 }\n[[walls.zones]]\n";

    #[test]
    fn tables_and_keys_are_found_by_their_spans() {
        let layout = Layout::of(TEXT, 0);
        let at = |needle: &str| TEXT.find(needle).unwrap_or_default();
        assert_eq!(layout.table_at(TEXT, at("1\n")), "the top level");
        assert_eq!(layout.key_at(at("1\n")).as_deref(), Some("a"));
        assert_eq!(layout.table_at(TEXT, at("\"x\"")), "[sweep]");
        assert_eq!(layout.key_at(at("\"x\"")).as_deref(), Some("step_s"));
        assert_eq!(layout.table_at(TEXT, at("mu")), "[[walls]] (wall 0)");
        assert_eq!(layout.key_at(at("mu")), None);
        let b = at("b = 2");
        assert_eq!(layout.table_at(TEXT, b), "[[walls.zones]] (wall 1, zone 0)");
        assert_eq!(layout.key_at(b).as_deref(), Some("from_m"));
        assert_eq!(layout.array_table("[[walls]]", b), "[[walls]] (wall 1)");
        assert_eq!(
            layout.array_table("[[walls.zones]]", TEXT.len()),
            "[[walls.zones]] (wall 1, zone 1)"
        );
        assert_eq!(
            layout.array_table("[[walls.zones]]", at("mu")),
            "[[walls.zones]]"
        );
        // Not TOML: the tables before the bad line, the key written on it.
        let broken = "[sweep]\nstep_s = 1\n[base]\n\"x\".y = 1 1\n";
        let at = broken.rfind('1').unwrap_or_default();
        let layout = Layout::of(broken, at);
        assert_eq!(layout.key_at(at).as_deref(), Some("x.y"));
        assert_eq!(layout.table_at(broken, at), "[base]");
    }
}
