//! antennad's layers, as `src/lib.rs` states them: `config` (imports no other layer), then
//! `hardware`, `sim`, `net`, `service`; a module may import its own layer and the ones below
//! it, never one above, so no circle of imports can close between them.
//!
//! The check reads every `use` (groups expanded) and every `crate::` path in the library's
//! sources (`src/`, the binary aside: it sits on top of everything), resolves `super::` and
//! the names `lib.rs` re-exports (`crate::FakeStage` is `sim`'s), and names the file and
//! line of each import against the order. Comments and `#[cfg(test)]` modules are left out:
//! a unit test may use a fake from a layer above.
#![allow(clippy::unwrap_used)]

use std::collections::BTreeMap;
use std::path::Path;

/// The layers, lowest first.
const LAYERS: [&str; 5] = ["config", "hardware", "sim", "net", "service"];

/// A source file: its path under `src/` (`sim/rig.rs`) and its text.
struct Source {
    path: String,
    text: String,
}

/// `text` without comments, string and character literals (each replaced by spaces, so
/// lines keep their numbers and columns) and without `#[cfg(test)]` modules.
fn code_only(text: &str) -> Vec<String> {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    let mut block_depth = 0usize;
    while let Some(c) = chars.next() {
        if block_depth > 0 {
            if c == '*' && chars.peek() == Some(&'/') {
                chars.next();
                block_depth -= 1;
                out.push_str("  ");
            } else if c == '/' && chars.peek() == Some(&'*') {
                chars.next();
                block_depth += 1;
                out.push_str("  ");
            } else {
                out.push(if c == '\n' { '\n' } else { ' ' });
            }
            continue;
        }
        match c {
            '/' if chars.peek() == Some(&'/') => {
                for c in chars.by_ref() {
                    if c == '\n' {
                        out.push('\n');
                        break;
                    }
                }
            }
            '/' if chars.peek() == Some(&'*') => {
                chars.next();
                block_depth = 1;
                out.push_str("  ");
            }
            // A raw string (`r"..."`, `r#"..."#`), not an identifier ending in `r`.
            'r' if matches!(chars.peek(), Some('#' | '"'))
                && !out
                    .chars()
                    .next_back()
                    .is_some_and(|p| p.is_alphanumeric() || p == '_') =>
            {
                let mut hashes = 0;
                while chars.peek() == Some(&'#') {
                    chars.next();
                    hashes += 1;
                }
                if chars.peek() != Some(&'"') {
                    out.push('r');
                    out.push_str(&"#".repeat(hashes));
                    continue;
                }
                chars.next();
                out.push_str(&" ".repeat(hashes + 2));
                let closing = format!("\"{}", "#".repeat(hashes));
                let mut body = String::new();
                for c in chars.by_ref() {
                    body.push(c);
                    out.push(if c == '\n' { '\n' } else { ' ' });
                    if body.ends_with(&closing) {
                        break;
                    }
                }
            }
            '"' => {
                out.push(' ');
                while let Some(c) = chars.next() {
                    match c {
                        '\\' => {
                            chars.next();
                            out.push_str("  ");
                        }
                        '"' => break,
                        '\n' => out.push('\n'),
                        _ => out.push(' '),
                    }
                }
                out.push(' ');
            }
            // A character literal ('{', '\n'), not a lifetime ('a).
            '\'' => {
                let rest: String = chars.clone().take(3).collect();
                let close = if rest.starts_with('\\') {
                    rest.chars().nth(2) == Some('\'')
                } else {
                    rest.chars().nth(1) == Some('\'')
                };
                if close {
                    let n = if rest.starts_with('\\') { 3 } else { 2 };
                    for _ in 0..n {
                        chars.next();
                    }
                    out.push_str(&" ".repeat(n + 1));
                } else {
                    out.push(c);
                }
            }
            c => out.push(c),
        }
    }
    // `#[cfg(test)]` modules: blanked to their closing brace.
    let mut lines: Vec<String> = out.lines().map(str::to_owned).collect();
    let mut i = 0;
    while i < lines.len() {
        if lines[i].trim() == "#[cfg(test)]"
            && lines
                .get(i + 1)
                .is_some_and(|l| l.trim_start().starts_with("mod ") && l.contains('{'))
        {
            let mut depth = 0i64;
            let mut j = i + 1;
            while j < lines.len() {
                depth += lines[j].matches('{').count() as i64;
                depth -= lines[j].matches('}').count() as i64;
                lines[j].clear();
                if depth <= 0 {
                    break;
                }
                j += 1;
            }
            lines[i].clear();
            i = j;
        }
        i += 1;
    }
    lines
}

/// The paths a `use` tree (aliases already dropped by [`use_statements`]) stands for:
/// `crate::{a::b, c::{d, e}}` is `crate::a::b`, `crate::c::d` and `crate::c::e`.
fn expand(tree: &str) -> Vec<String> {
    let tree: String = tree.split_whitespace().collect();
    let Some(open) = tree.find('{') else {
        return vec![tree];
    };
    let prefix = &tree[..open];
    let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0usize, 0usize);
    for (k, c) in inner.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&inner[start..k]);
                start = k + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[start..]);
    parts
        .into_iter()
        .filter(|p| !p.is_empty())
        .flat_map(|p| expand(p).into_iter().map(|leaf| format!("{prefix}{leaf}")))
        .collect()
}

/// Every `use` statement of `lines`: its first line (1-based) and its tree.
fn use_statements(lines: &[String]) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (n, line) in lines.iter().enumerate() {
        let trimmed = line.trim();
        if current.is_none() {
            let rest = ["use ", "pub use ", "pub(crate) use ", "pub(super) use "]
                .iter()
                .find_map(|p| trimmed.strip_prefix(p));
            if let Some(rest) = rest {
                current = Some((n + 1, String::new()));
                if let Some((_, text)) = &mut current {
                    text.push_str(rest);
                }
            }
        } else if let Some((_, text)) = &mut current {
            text.push(' ');
            text.push_str(trimmed);
        }
        if let Some((line, text)) = current.take_if(|(_, t)| t.contains(';')) {
            let tree = text.split(';').next().unwrap_or_default();
            // Aliases are written `path as name`: the path is what is imported.
            let tree = tree
                .split(',')
                .map(|part| {
                    let mut words = part.split(" as ");
                    let path = words.next().unwrap_or_default().to_owned();
                    // Keep a closing brace that followed the alias.
                    let closing: String = words
                        .next()
                        .map(|alias| alias.chars().filter(|&c| c == '}').collect())
                        .unwrap_or_default();
                    path + &closing
                })
                .collect::<Vec<_>>()
                .join(",");
            found.push((line, tree));
        }
    }
    found
}

/// Every `crate::` path written outside `use` statements: its line and the path.
fn inline_paths(lines: &[String]) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    let mut in_use = false;
    for (n, line) in lines.iter().enumerate() {
        let trimmed = line.trim();
        if !in_use
            && ["use ", "pub use ", "pub(crate) use ", "pub(super) use "]
                .iter()
                .any(|p| trimmed.starts_with(p))
        {
            in_use = true;
        }
        if in_use {
            in_use = !trimmed.contains(';');
            continue;
        }
        let mut rest = line.as_str();
        while let Some(at) = rest.find("crate::") {
            let before = rest[..at].chars().next_back();
            let tail = &rest[at..];
            let end = tail
                .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                .unwrap_or(tail.len());
            if !before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                found.push((n + 1, tail[..end].trim_end_matches(':').to_owned()));
            }
            rest = &tail[end.max(1)..];
        }
    }
    found
}

/// The module path of a file under `src/`: `sim/emulator/vxm.rs` is `sim::emulator::vxm`,
/// `sim/mod.rs` is `sim`, `lib.rs` the crate root.
fn module_of(path: &str) -> Vec<String> {
    let path = path.trim_end_matches(".rs");
    let mut parts: Vec<String> = path.split('/').map(str::to_owned).collect();
    if parts.last().is_some_and(|p| p == "mod" || p == "lib") {
        parts.pop();
    }
    parts
}

/// What `lib.rs` re-exports at the crate root: each name and the module it comes from.
fn reexports(lib_rs: &str) -> BTreeMap<String, String> {
    let lines = code_only(lib_rs);
    let mut names = BTreeMap::new();
    for (_, tree) in use_statements(&lines) {
        for path in expand(&tree) {
            let segments: Vec<&str> = path.split("::").collect();
            let first = segments.first().copied().unwrap_or_default();
            let first = if first == "crate" || first == "self" {
                segments.get(1).copied().unwrap_or_default()
            } else {
                first
            };
            if let Some(last) = segments.last() {
                names.insert((*last).to_owned(), first.to_owned());
            }
        }
    }
    names
}

/// The layer an absolute path (`crate::` dropped) lands in, or why it cannot be told.
fn layer_of(
    segments: &[&str],
    reexports: &BTreeMap<String, String>,
) -> Result<Option<usize>, String> {
    let Some(first) = segments.first() else {
        return Ok(None);
    };
    if let Some(rank) = LAYERS.iter().position(|l| l == first) {
        return Ok(Some(rank));
    }
    match reexports.get(*first) {
        Some(module) => Ok(LAYERS.iter().position(|l| l == module)),
        None => Err(format!(
            "`crate::{first}` is neither a layer nor a name lib.rs re-exports"
        )),
    }
}

/// Every import of `sources` against the layer order (`file:line: what`), and how many
/// imports of this crate's modules were checked.
fn violations(sources: &[Source]) -> (Vec<String>, usize) {
    let reexports = sources
        .iter()
        .find(|s| s.path == "lib.rs")
        .map(|s| reexports(&s.text))
        .unwrap_or_default();
    let mut found = Vec::new();
    let mut checked = 0;
    for source in sources {
        let module = module_of(&source.path);
        let Some(own) = module
            .first()
            .and_then(|m| LAYERS.iter().position(|l| l == m))
        else {
            continue; // the crate root and the binary sit on top
        };
        let lines = code_only(&source.text);
        let mut paths: Vec<(usize, String)> = use_statements(&lines)
            .into_iter()
            .flat_map(|(line, tree)| expand(&tree).into_iter().map(move |p| (line, p)))
            .collect();
        paths.extend(inline_paths(&lines));
        for (line, path) in paths {
            let mut segments: Vec<&str> = path.split("::").collect();
            // Relative paths to absolute ones; other crates are not this check's business.
            let absolute: Vec<&str> = match segments.first().copied() {
                Some("crate") => segments.split_off(1),
                Some("super") => {
                    let mut base: Vec<&str> = module.iter().map(String::as_str).collect();
                    while segments.first() == Some(&"super") {
                        base.pop();
                        segments.remove(0);
                    }
                    base.extend(segments);
                    base
                }
                _ => continue,
            };
            checked += 1;
            match layer_of(&absolute, &reexports) {
                Ok(Some(rank)) if rank > own => found.push(format!(
                    "src/{}:{line}: `{path}`: {} may not import {} (layers, lowest first: {})",
                    source.path,
                    LAYERS[own],
                    LAYERS[rank],
                    LAYERS.join(", ")
                )),
                Ok(_) => {}
                Err(why) => found.push(format!("src/{}:{line}: {why}", source.path)),
            }
        }
    }
    (found, checked)
}

/// The library's sources under `src/` (the binary's aside).
fn library_sources() -> Vec<Source> {
    fn walk(dir: &Path, root: &Path, out: &mut Vec<Source>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                if path.file_name().is_some_and(|n| n != "bin") {
                    walk(&path, root, out);
                }
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(Source {
                    path: path
                        .strip_prefix(root)
                        .unwrap()
                        .to_string_lossy()
                        .replace('\\', "/"),
                    text: std::fs::read_to_string(&path).unwrap(),
                });
            }
        }
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut sources = Vec::new();
    walk(&root, &root, &mut sources);
    sources.sort_by(|a, b| a.path.cmp(&b.path));
    sources
}

#[test]
fn no_module_imports_a_layer_above_its_own() {
    let sources = library_sources();
    assert!(sources.iter().any(|s| s.path == "lib.rs"));
    assert!(sources.len() > 40, "{} sources", sources.len());
    let (found, checked) = violations(&sources);
    // The layers' modules import one another a few hundred times.
    assert!(checked > 200, "only {checked} imports found");
    assert!(
        found.is_empty(),
        "imports against the layers:\n{}",
        found.join("\n")
    );
}

#[test]
fn every_module_of_the_crate_root_is_a_layer() {
    let sources = library_sources();
    let lib = sources.iter().find(|s| s.path == "lib.rs").unwrap();
    let modules: Vec<String> = code_only(&lib.text)
        .iter()
        .filter_map(|l| {
            l.trim()
                .strip_prefix("pub mod ")
                .map(|m| m.trim_end_matches(';').to_owned())
        })
        .collect();
    let mut sorted_layers = LAYERS.map(str::to_owned).to_vec();
    sorted_layers.sort();
    let mut sorted = modules.clone();
    sorted.sort();
    assert_eq!(sorted, sorted_layers, "lib.rs declares {modules:?}");
}

fn fake(files: &[(&str, &str)]) -> Vec<Source> {
    files
        .iter()
        .map(|(path, text)| Source {
            path: (*path).to_owned(),
            text: (*text).to_owned(),
        })
        .collect()
}

#[test]
fn the_check_catches_an_import_against_the_layers() {
    let lib = "//! docs: crate::service is fine here\npub mod config;\npub mod sim;\npub mod service;\n\
               pub use sim::fake::{FakeStage, FakeServo};\npub use service::rig::Rig;\n";
    let sources = fake(&[
        ("lib.rs", lib),
        (
            "config/mod.rs",
            "//! See [`crate::service`].\nuse std::fmt;\nuse crate::FakeStage;\n",
        ),
        (
            "sim/rig.rs",
            "use crate::config::Config;\nuse crate::{\n    config::X,\n    service::motion::{A, B},\n};\n\
             fn f() {\n    let s = \"crate::service::x\";\n    crate::service::clock::now();\n}\n",
        ),
        (
            "sim/emulator/vxm.rs",
            "use super::super::super::service::Thing;\nuse super::Runner;\n",
        ),
        (
            "service/rig.rs",
            "use crate::sim::rig::SimState;\nuse crate::{Rig, FakeServo};\nuse crate::nowhere::X;\n",
        ),
        (
            "hardware/stage.rs",
            "fn f() {}\n#[cfg(test)]\nmod tests {\n    fn g() { let c = '{'; let j = r#\"a\"b}\"#; }\n    use crate::sim::fake::FakeStage;\n}\n",
        ),
    ]);
    let (found, checked) = violations(&sources);
    assert_eq!(checked, 12);
    let expected = [
        "src/config/mod.rs:3: `crate::FakeStage`: config may not import sim",
        "src/sim/rig.rs:2: `crate::service::motion::A`: sim may not import service",
        "src/sim/rig.rs:2: `crate::service::motion::B`: sim may not import service",
        "src/sim/rig.rs:8: `crate::service::clock::now`: sim may not import service",
        "src/sim/emulator/vxm.rs:1: `super::super::super::service::Thing`: sim may not import service",
        "src/service/rig.rs:3: `crate::nowhere` is neither a layer nor a name lib.rs re-exports",
    ];
    for e in expected {
        assert!(
            found.iter().any(|f| f.starts_with(e)),
            "missing {e:?} in:\n{}",
            found.join("\n")
        );
    }
    assert_eq!(found.len(), expected.len(), "{}", found.join("\n"));
    // Importing downward, aliases included, is allowed; the message names the order.
    assert!(found[0].ends_with("(layers, lowest first: config, hardware, sim, net, service)"));
}

#[test]
fn use_trees_are_expanded_and_aliases_dropped() {
    assert_eq!(
        expand("crate::{a::b, c::{d, e}}"),
        ["crate::a::b", "crate::c::d", "crate::c::e"]
    );
    let lines = code_only("use crate::x::{Y as Z, W};\npub(crate) use crate::q as r;\n");
    let statements = use_statements(&lines);
    assert_eq!(
        statements,
        [
            (1, "crate::x::{Y, W}".to_owned()),
            (2, "crate::q".to_owned())
        ]
    );
}
