//! The scene text and its name, for turning spans into located errors; the checks every
//! table's values share (finite numbers, positive numbers, lists of a given length, points,
//! names from a list).

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
pub(crate) fn read_input(
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
pub(crate) struct Source<'a> {
    pub(crate) text: &'a str,
    pub(crate) path: &'a str,
}

impl Source<'_> {
    pub(crate) fn at(&self, span: Range<usize>) -> Option<Location> {
        Some(Location::of_offset(self.text, span.start))
    }

    pub(crate) fn error(&self, span: Option<Range<usize>>, kind: SceneErrorKind) -> SceneError {
        SceneError {
            path: self.path.to_string(),
            location: span.and_then(|s| self.at(s)),
            kind: Box::new(kind),
        }
    }

    pub(crate) fn invalid(
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

    pub(crate) fn missing(&self, span: Range<usize>, table: &str, key: &str) -> SceneError {
        self.error(
            Some(span),
            SceneErrorKind::MissingKey {
                key: key.to_string(),
                table: table.to_string(),
            },
        )
    }

    /// Turns a TOML/serde error into a located scene error naming the key.
    pub(crate) fn toml_error(&self, e: &toml::de::Error) -> SceneError {
        let span = e.span();
        let offset = span.as_ref().map_or(0, |s| s.start);
        let message = e.message().trim().to_string();
        if let Some(rest) = message.strip_prefix("unknown field `") {
            let names = backticked(rest);
            let key = rest.split('`').next().unwrap_or_default().to_string();
            let allowed: Vec<String> = names.into_iter().collect();
            let table = table_with_keys(&allowed).map_or_else(
                || table_at(self.text, offset),
                |t| label_array_table(t, self.text, offset),
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
                [only] => label_array_table(only, self.text, offset),
                _ => table_at(self.text, offset),
            };
            return self.error(span, SceneErrorKind::MissingKey { key, table });
        }
        let message = match key_at(self.text, offset) {
            Some(key) => format!("`{key}` in {}: {message}", table_at(self.text, offset)),
            None => message,
        };
        self.error(span, SceneErrorKind::Syntax { message })
    }
}

/// The label of the `index`-th (0-based) `[[walls]]` table in errors.
pub(crate) fn wall_table(index: usize) -> String {
    format!("[[walls]] (wall {index})")
}

/// The label of zone `zone` (0-based) of wall `wall` in errors.
pub(crate) fn zone_table(wall: usize, zone: usize) -> String {
    format!("[[walls.zones]] (wall {wall}, zone {zone})")
}

/// `table` with its index added when it is an array of tables (`[[walls]]`,
/// `[[walls.zones]]`), counted from the headers before byte `offset`.
fn label_array_table(table: &str, text: &str, offset: usize) -> String {
    let offset = offset.min(text.len());
    let headers = text[..offset]
        .lines()
        .map(str::trim)
        .filter(|l| l.starts_with("[["));
    let mut wall: Option<usize> = None;
    let mut zone: Option<usize> = None;
    for header in headers {
        let name: String = header.chars().filter(|c| !c.is_whitespace()).collect();
        if name.starts_with("[[walls]]") {
            wall = Some(wall.map_or(0, |w| w + 1));
            zone = None;
        } else if name.starts_with("[[walls.zones]]") {
            zone = Some(zone.map_or(0, |z| z + 1));
        }
    }
    match (table, wall, zone) {
        ("[[walls]]", Some(w), _) => wall_table(w),
        ("[[walls.zones]]", Some(w), Some(z)) => zone_table(w, z),
        _ => table.to_string(),
    }
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

/// The table header in force at byte `offset` (`[name]`, or `[[name]]` with its index), or
/// `the top level`.
fn table_at(text: &str, offset: usize) -> String {
    let offset = offset.min(text.len());
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    text[..line_start]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .and_then(|l| {
            let array = l.starts_with("[[");
            let inner = l.trim_start_matches('[');
            inner.find(']').map(|end| {
                let name = inner[..end].trim();
                if array {
                    label_array_table(&format!("[[{name}]]"), text, offset)
                } else {
                    format!("[{name}]")
                }
            })
        })
        .unwrap_or_else(|| "the top level".to_string())
}

/// The key of the `key = value` line holding byte `offset`, when `offset` is in the value.
fn key_at(text: &str, offset: usize) -> Option<String> {
    let offset = offset.min(text.len());
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let before = &text[line_start..offset];
    let (key, _) = before.split_once('=')?;
    let key = key.trim().trim_matches('"');
    let plain = !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'));
    plain.then(|| key.to_string())
}

/// `"a", "b", "c"`.
pub(crate) fn quoted_list(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The index of `value` in `names`, or an error listing the names.
pub(crate) fn one_of(
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
pub(crate) fn finite_list(
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
pub(crate) fn list_of_len(
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
pub(crate) fn point(
    source: &Source<'_>,
    table: &str,
    key: &str,
    list: &Spanned<Vec<f64>>,
) -> Result<Vector2<f64>, SceneError> {
    let v = list_of_len(source, table, key, list, 2, "[x, y]")?;
    Ok(Vector2::new(v[0], v[1]))
}

/// A finite number.
pub(crate) fn finite(
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
pub(crate) fn positive(
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
pub(crate) fn non_negative(
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
pub(crate) fn count(
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
pub(crate) fn not_for(
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
