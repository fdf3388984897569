//! The documentation holds together inside the repository:
//! - every citation of a page under `docs/` in a tracked `.rs`, `.md`, `.toml` or `.sh` file (or
//!   a script) names a page that exists, and a section number after it (`docs/model.md 6`,
//!   `docs/model.md section 5`, `docs/model.md 6-7`, `docs/model.md 1, 3, 4, 7`) names a
//!   numbered heading of that page;
//! - every relative Markdown link of `README.md`, `BENCHMARKS.md`, `docs/**/*.md` and the other
//!   Markdown files resolves to a file of the repository, and its anchor to a heading of the
//!   target (GitHub's slugs);
//! - no file points outside the repository to the design documents it was built from (the
//!   thesis is cited by title and author, the contracts as the pages under `docs/`);
//! - the thesis is cited as "thesis N.N": no "seed N.N" citation is left.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Component, Path, PathBuf};
use std::process::Command;

/// The repository's root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .canonicalize()
        .expect("the workspace root")
}

/// The repository's files, relative to the root: git's tracked and untracked-but-not-ignored
/// files, or without git every file outside `target/` and `.git/`. Files listed but absent
/// (deleted in the work tree) are left out.
fn repository_files(root: &Path) -> Vec<PathBuf> {
    let listed = Command::new("git")
        .arg("-C")
        .arg(root)
        .args([
            "ls-files",
            "-z",
            "--cached",
            "--others",
            "--exclude-standard",
        ])
        .output()
        .ok()
        .filter(|o| o.status.success() && !o.stdout.is_empty());
    let mut files: Vec<PathBuf> = match listed {
        Some(out) => out
            .stdout
            .split(|&b| b == 0)
            .filter(|p| !p.is_empty())
            .map(|p| PathBuf::from(String::from_utf8_lossy(p).into_owned()))
            .collect(),
        None => {
            let mut found = Vec::new();
            walk(root, root, &mut found);
            found
        }
    };
    files.retain(|f| root.join(f).is_file());
    files.sort();
    files.dedup();
    files
}

fn walk(root: &Path, dir: &Path, found: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name();
        if name == "target" || name == ".git" {
            continue;
        }
        if path.is_dir() {
            walk(root, &path, found);
        } else if let Ok(relative) = path.strip_prefix(root) {
            found.push(relative.to_path_buf());
        }
    }
}

/// Files whose text is scanned for citations: sources, docs, manifests and scripts.
fn is_scanned(path: &Path) -> bool {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    matches!(ext, "rs" | "md" | "toml" | "sh")
        || path.starts_with("scripts")
        || path.starts_with(".ci")
}

fn text_files(root: &Path, files: &[PathBuf]) -> Vec<(PathBuf, String)> {
    files
        .iter()
        .filter(|f| is_scanned(f))
        .filter_map(|f| {
            let text = std::fs::read_to_string(root.join(f)).ok()?;
            Some((f.clone(), text))
        })
        .collect()
}

/// The headings of a Markdown text, outside fenced code blocks, without their `#`s.
fn headings(markdown: &str) -> Vec<String> {
    let mut fenced = false;
    let mut out = Vec::new();
    for line in markdown.lines() {
        let trimmed = line.trim_start();
        if trimmed.starts_with("```") || trimmed.starts_with("~~~") {
            fenced = !fenced;
            continue;
        }
        if fenced || !line.starts_with('#') {
            continue;
        }
        let level = line.chars().take_while(|&c| c == '#').count();
        let rest = &line[level..];
        if level <= 6 && (rest.is_empty() || rest.starts_with(' ')) {
            out.push(rest.trim().trim_end_matches('#').trim().to_string());
        }
    }
    out
}

/// The section number a heading starts with ("6" for "6. Constraints and contact").
fn heading_number(heading: &str) -> Option<String> {
    let digits: String = heading
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == '.')
        .collect();
    let number = digits.trim_end_matches('.');
    (!number.is_empty()).then(|| number.to_string())
}

/// GitHub's anchor of a heading: the rendered text (code spans, links and emphasis reduced to
/// their text), lower-cased, every character but letters, digits, `-`, `_` and spaces dropped,
/// spaces turned into `-`.
fn slug(heading: &str) -> String {
    let mut text = String::new();
    let mut rest = heading;
    // Links: keep the text between the brackets, drop the target.
    while let Some(open) = rest.find('[') {
        let Some(close) = rest[open..].find("](").map(|c| open + c) else {
            break;
        };
        let Some(end) = rest[close..].find(')').map(|e| close + e) else {
            break;
        };
        text.push_str(&rest[..open]);
        text.push_str(&rest[open + 1..close]);
        rest = &rest[end + 1..];
    }
    text.push_str(rest);
    text.chars()
        .flat_map(char::to_lowercase)
        .filter(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | ' '))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// Every anchor of a Markdown text: its headings' slugs, repeated ones numbered `-1`, `-2`.
fn anchors(markdown: &str) -> BTreeSet<String> {
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut out = BTreeSet::new();
    for heading in headings(markdown) {
        let base = slug(&heading);
        let count = seen.entry(base.clone()).or_insert(0);
        out.insert(if *count == 0 {
            base.clone()
        } else {
            format!("{base}-{count}")
        });
        *count += 1;
    }
    out
}

/// A citation of a page under `docs/`: the page and the section numbers after it.
#[derive(Debug)]
struct Citation {
    line: usize,
    page: String,
    sections: Vec<String>,
}

fn is_path_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '/' | '.')
}

/// Reads `N` or `N-M` (both ends) at the start of `s`; returns the numbers and the rest.
fn number_or_range(s: &str) -> Option<(Vec<String>, &str)> {
    let digits = |t: &str| t.chars().take_while(char::is_ascii_digit).count();
    let n = digits(s);
    if n == 0 {
        return None;
    }
    let mut numbers = vec![s[..n].to_string()];
    let mut rest = &s[n..];
    if let Some(after) = rest.strip_prefix('-') {
        let m = digits(after);
        if m > 0 {
            let (from, to) = (s[..n].parse::<u32>().ok()?, after[..m].parse::<u32>().ok()?);
            numbers = (from..=to.max(from)).map(|k| k.to_string()).collect();
            rest = &after[m..];
        }
    }
    // A number followed by a letter or a dot and a digit is not a section ("8051", "2.5 mm").
    let mut next = rest.chars();
    match (next.next(), next.next()) {
        (Some(c), _) if c.is_ascii_alphabetic() => None,
        (Some('.'), Some(d)) if d.is_ascii_digit() => None,
        _ => Some((numbers, rest)),
    }
}

/// The citations of pages under `docs/` in a text: `docs/`, a page name and `.md`, not part of
/// a longer path, optionally followed by ` N`, ` section N`, ` sections N`, with ranges `N-M`
/// and lists `N, M`.
fn citations(text: &str) -> Vec<Citation> {
    let mut out = Vec::new();
    let lines: Vec<&str> = text.lines().collect();
    for (index, line) in lines.iter().enumerate() {
        // A citation may wrap after the page: its section is then read from the start of the
        // next line, comment markers left out.
        let wrapped = lines.get(index + 1).map(|n| {
            format!(
                " {}",
                n.trim_start()
                    .trim_start_matches(['/', '!', '#', '*'])
                    .trim_start()
            )
        });
        let mut from = 0;
        while let Some(found) = line[from..].find("docs/") {
            let start = from + found;
            from = start + "docs/".len();
            if line[..start].chars().next_back().is_some_and(is_path_char) {
                continue;
            }
            let tail = &line[start..];
            let len = tail
                .chars()
                .take_while(|&c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '/'))
                .count();
            let Some(after) = tail[len..].strip_prefix(".md") else {
                continue;
            };
            if after
                .chars()
                .next()
                .is_some_and(|c| c.is_ascii_alphanumeric())
            {
                continue;
            }
            let page = format!("{}.md", &tail[..len]);
            let after = match (after.is_empty(), &wrapped) {
                (true, Some(next)) => next.as_str(),
                _ => after,
            };
            let mut sections = Vec::new();
            let mut rest = after
                .strip_prefix(" section ")
                .or_else(|| after.strip_prefix(" sections "))
                .or_else(|| after.strip_prefix(' '));
            if let Some(mut r) = rest.take() {
                while let Some((numbers, next)) = number_or_range(r) {
                    sections.extend(numbers);
                    match next.strip_prefix(", ") {
                        Some(more) if more.starts_with(|c: char| c.is_ascii_digit()) => r = more,
                        _ => break,
                    }
                }
            }
            out.push(Citation {
                line: index + 1,
                page,
                sections,
            });
        }
    }
    out
}

#[test]
fn the_citation_parser_reads_numbers_ranges_and_lists() {
    let page = concat!("docs/", "model.md");
    let parsed = |s: &str| {
        citations(s)
            .into_iter()
            .map(|c| (c.page, c.sections))
            .collect::<Vec<_>>()
    };
    let model = || page.to_string();
    let strings = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert_eq!(
        parsed(&format!("(thesis 2.2, {page} 1, 3, 4, 7)")),
        [(model(), strings(&["1", "3", "4", "7"]))]
    );
    assert_eq!(
        parsed(&format!("{page} section 5; {page} 6-8).")),
        [
            (model(), strings(&["5"])),
            (model(), strings(&["6", "7", "8"]))
        ]
    );
    assert_eq!(
        parsed(&format!("`{page}`: the 8051, a/{page} 3, {page} 2.5 mm")),
        [(model(), vec![]), (model(), vec![])]
    );
    assert_eq!(
        parsed(&format!("/// the law of {page}\n/// 5 (`k = ...`)")),
        [(model(), strings(&["5"]))]
    );
    assert_eq!(
        slug("Monitor (`antenna-monitor`)"),
        "monitor-antenna-monitor"
    );
    assert_eq!(
        slug("6. Constraints and contact"),
        "6-constraints-and-contact"
    );
    assert_eq!(
        slug("The [scene format](scene-format.md): `[[walls]]`"),
        "the-scene-format-walls"
    );
    assert_eq!(
        heading_number("10. Sensors (thesis 2.3.1)").as_deref(),
        Some("10")
    );
}

#[test]
fn every_citation_of_a_docs_page_resolves() {
    let root = root();
    let files = repository_files(&root);
    let texts = text_files(&root, &files);
    let mut numbered: BTreeMap<String, Option<BTreeSet<String>>> = BTreeMap::new();
    let mut problems = Vec::new();
    let mut count = 0;
    for (file, text) in &texts {
        for citation in citations(text) {
            count += 1;
            let sections = numbered.entry(citation.page.clone()).or_insert_with(|| {
                std::fs::read_to_string(root.join(&citation.page))
                    .ok()
                    .map(|page| {
                        headings(&page)
                            .iter()
                            .filter_map(|h| heading_number(h))
                            .collect()
                    })
            });
            let place = format!("{}:{}", file.display(), citation.line);
            match sections {
                None => problems.push(format!("{place}: {} does not exist", citation.page)),
                Some(numbers) => {
                    for section in &citation.sections {
                        if !numbers.contains(section) {
                            problems.push(format!(
                                "{place}: {} has no heading numbered {section} (it has {numbers:?})",
                                citation.page
                            ));
                        }
                    }
                }
            }
        }
    }
    assert!(
        count > 100,
        "only {count} citations found: is the scan reading the repository?"
    );
    assert!(
        problems.is_empty(),
        "citations that do not resolve:\n{}",
        problems.join("\n")
    );
}

/// The Markdown files whose links are checked: the README, BENCHMARKS, the guide under
/// `docs/` and every other Markdown file of the repository (the crates' READMEs, the examples').
fn guide_pages(files: &[PathBuf]) -> Vec<&PathBuf> {
    files
        .iter()
        .filter(|f| f.extension().is_some_and(|e| e == "md"))
        .collect()
}

/// A line with its code spans removed (what is inside backticks is not a link).
fn without_code_spans(line: &str) -> String {
    let mut out = String::new();
    let mut rest = line;
    while let Some(open) = rest.find('`') {
        let ticks = rest[open..].chars().take_while(|&c| c == '`').count();
        let fence = "`".repeat(ticks);
        out.push_str(&rest[..open]);
        match rest[open + ticks..].find(&fence) {
            Some(close) => rest = &rest[open + ticks + close + ticks..],
            None => {
                rest = &rest[open + ticks..];
            }
        }
    }
    out.push_str(rest);
    out
}

/// The link targets of a Markdown text (inline `[..](target)` and reference definitions
/// `[label]: target`), with their lines, outside code blocks and code spans.
fn link_targets(markdown: &str) -> Vec<(usize, String)> {
    let mut fenced = false;
    let mut out = Vec::new();
    for (index, raw) in markdown.lines().enumerate() {
        let trimmed = raw.trim_start();
        if trimmed.starts_with("```") || trimmed.starts_with("~~~") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        let line = without_code_spans(raw);
        let t = line.trim_start();
        if t.starts_with('[')
            && let Some(close) = t.find("]: ")
        {
            let target = t[close + 3..].split_whitespace().next().unwrap_or("");
            out.push((index + 1, target.to_string()));
        }
        let mut from = 0;
        while let Some(found) = line[from..].find("](") {
            let start = from + found + 2;
            let mut depth = 0usize;
            let mut end = line.len();
            for (i, c) in line[start..].char_indices() {
                match c {
                    '(' => depth += 1,
                    ')' if depth == 0 => {
                        end = start + i;
                        break;
                    }
                    ')' => depth -= 1,
                    _ => {}
                }
            }
            let target = line[start..end].split_whitespace().next().unwrap_or("");
            out.push((index + 1, target.trim_matches(['<', '>']).to_string()));
            from = end.min(line.len());
        }
    }
    out
}

/// `base/relative` with `.` and `..` resolved; `None` when it leaves the repository.
fn resolve(base: &Path, relative: &str) -> Option<PathBuf> {
    let mut out = PathBuf::new();
    for component in base.join(relative).components() {
        match component {
            Component::CurDir => {}
            Component::ParentDir => {
                if !out.pop() {
                    return None;
                }
            }
            Component::Normal(part) => out.push(part),
            Component::RootDir | Component::Prefix(_) => return None,
        }
    }
    Some(out)
}

#[test]
fn every_link_of_the_readme_the_benchmarks_and_the_guide_resolves() {
    let root = root();
    let files = repository_files(&root);
    let pages = guide_pages(&files);
    assert!(
        pages.iter().any(|p| p.starts_with("docs")),
        "no page under docs/ found"
    );
    let mut problems = Vec::new();
    let mut checked = 0;
    for page in pages {
        let text = std::fs::read_to_string(root.join(page)).unwrap();
        let dir = page.parent().unwrap_or(Path::new(""));
        for (line, target) in link_targets(&text) {
            if target.is_empty() || target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            checked += 1;
            let place = format!("{}:{line}: `{target}`", page.display());
            let (path, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let file = if path.is_empty() {
                Some(page.clone())
            } else {
                resolve(dir, path)
            };
            let Some(file) = file else {
                problems.push(format!("{place}: leaves the repository"));
                continue;
            };
            let full = root.join(&file);
            if !full.exists() {
                problems.push(format!("{place}: {} does not exist", file.display()));
                continue;
            }
            if let Some(anchor) = anchor
                && file.extension().is_some_and(|e| e == "md")
            {
                let target_text = std::fs::read_to_string(&full).unwrap();
                if !anchors(&target_text).contains(anchor) {
                    problems.push(format!(
                        "{place}: {} has no heading with the anchor #{anchor}",
                        file.display()
                    ));
                }
            }
        }
    }
    assert!(checked > 20, "only {checked} links checked");
    assert!(
        problems.is_empty(),
        "links that do not resolve:\n{}",
        problems.join("\n")
    );
}

#[test]
fn no_file_points_outside_the_repository_to_the_design_documents() {
    let root = root();
    let files = repository_files(&root);
    // Built at run time, so that this file does not match itself.
    let needle = format!("{}/", "shared");
    let mut problems = Vec::new();
    for (file, text) in text_files(&root, &files) {
        for (index, line) in text.lines().enumerate() {
            if line.contains(&needle) {
                problems.push(format!("{}:{}: {}", file.display(), index + 1, line.trim()));
            }
        }
    }
    assert!(
        problems.is_empty(),
        "the thesis is cited by title and author, the contracts as pages under docs/:\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_thesis_is_cited_as_the_thesis() {
    let root = root();
    let files = repository_files(&root);
    let mut problems = Vec::new();
    for (file, text) in text_files(&root, &files) {
        let lines: Vec<&str> = text.lines().collect();
        for (index, line) in lines.iter().enumerate() {
            // A citation may wrap: the line is read with the start of the next one, its
            // comment markers left out.
            let next = lines.get(index + 1).map_or("", |n| {
                n.trim_start()
                    .trim_start_matches(['/', '!', '#', '*', '-'])
                    .trim_start()
            });
            let own = line.to_lowercase();
            let lower = format!("{own} {}", next.to_lowercase());
            let mut from = 0;
            while let Some(found) = lower[from..].find("seed ") {
                let at = from + found;
                from = at + 5;
                if at >= own.len() {
                    break;
                }
                if lower[..at]
                    .chars()
                    .next_back()
                    .is_some_and(char::is_alphanumeric)
                {
                    continue;
                }
                let after = &lower[at + 5..];
                let digits = after.chars().take_while(char::is_ascii_digit).count();
                let cites = (digits > 0
                    && after[digits..].starts_with('.')
                    && after[digits + 1..].starts_with(|c: char| c.is_ascii_digit()))
                    || after.starts_with("table ")
                    || after.starts_with("figure ");
                if cites {
                    problems.push(format!("{}:{}: {}", file.display(), index + 1, line.trim()));
                }
            }
        }
    }
    assert!(
        problems.is_empty(),
        "\"seed N.N\" citations of the thesis (write \"thesis N.N\"):\n{}",
        problems.join("\n")
    );
}
