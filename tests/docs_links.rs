//! The documentation's links hold: every relative link and image in `README.md`, `CHANGELOG.md`
//! and `docs/**/*.md` names an existing file or folder, every `#anchor` names a heading of the
//! file it points into (GitHub's slugs), and no heading under `docs/` carries a date (history
//! belongs in `CHANGELOG.md`).

use std::collections::HashSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `README.md`, `CHANGELOG.md` and every `.md` file under `docs/`.
fn documents() -> Vec<PathBuf> {
    let root = root();
    let mut files = vec![root.join("README.md"), root.join("CHANGELOG.md")];
    let mut dirs = vec![root.join("docs")];
    while let Some(dir) = dirs.pop() {
        let entries = std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        for entry in entries {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// The text with fenced code blocks and inline code spans blanked out (newlines kept, so that
/// byte offsets still give line numbers).
fn without_code(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut fenced = false;
    for line in text.split_inclusive('\n') {
        let fence = line.trim_start().starts_with("```");
        if fenced || fence {
            out.extend(line.chars().map(|c| if c == '\n' { '\n' } else { ' ' }));
            if fence {
                fenced = !fenced;
            }
        } else {
            out.push_str(line);
        }
    }
    // Inline code: a run of n backticks up to the next run of exactly n.
    let bytes = out.as_bytes().to_vec();
    let mut blank = vec![false; bytes.len()];
    let run_at = |i: usize| bytes[i..].iter().take_while(|&&b| b == b'`').count();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] != b'`' {
            i += 1;
            continue;
        }
        let n = run_at(i);
        let mut j = i + n;
        let mut end = None;
        while j < bytes.len() {
            if bytes[j] == b'`' {
                let m = run_at(j);
                if m == n {
                    end = Some(j + m);
                    break;
                }
                j += m;
            } else {
                j += 1;
            }
        }
        match end {
            Some(e) => {
                blank[i..e].iter_mut().for_each(|b| *b = true);
                i = e;
            }
            None => i += n,
        }
    }
    out.char_indices()
        .map(|(k, c)| if blank[k] && c != '\n' { ' ' } else { c })
        .collect()
}

/// The heading lines of a Markdown text, outside code blocks: their text without the `#`s.
fn headings(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if (1..=6).contains(&hashes) && line[hashes..].starts_with(' ') {
            out.push(
                line[hashes..]
                    .trim()
                    .trim_end_matches('#')
                    .trim()
                    .to_string(),
            );
        }
    }
    out
}

/// GitHub's anchor of a heading: the text as rendered (code spans' backticks, links' targets
/// and emphasis marks dropped), lower case, every character but letters, digits, `_`, `-` and
/// spaces removed, spaces turned into hyphens.
fn slug(heading: &str) -> String {
    let mut rendered = String::new();
    let mut chars = heading.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            // [text](target): keep the text, drop the target.
            ']' if chars.peek() == Some(&'(') => {
                let mut depth = 0;
                for d in chars.by_ref() {
                    match d {
                        '(' => depth += 1,
                        ')' => {
                            depth -= 1;
                            if depth == 0 {
                                break;
                            }
                        }
                        _ => {}
                    }
                }
            }
            '`' | '*' | '[' | ']' => {}
            _ => rendered.push(c),
        }
    }
    rendered
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, '_' | '-' | ' '))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// Every anchor of a Markdown file: its headings' slugs, repeated ones numbered `-1`, `-2`...
fn anchors(text: &str) -> HashSet<String> {
    let mut seen = HashSet::new();
    for heading in headings(text) {
        let base = slug(&heading);
        let mut anchor = base.clone();
        let mut k = 0;
        while seen.contains(&anchor) {
            k += 1;
            anchor = format!("{base}-{k}");
        }
        seen.insert(anchor);
    }
    seen
}

/// The targets of the inline links and images of a text (code blanked out), with their lines.
fn links(text: &str) -> Vec<(usize, String)> {
    let clean = without_code(text);
    let bytes = clean.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(k) = clean[i..].find("](") {
        let start = i + k + 2;
        let mut depth = 1;
        let mut end = start;
        while end < bytes.len() && depth > 0 {
            match bytes[end] {
                b'(' => depth += 1,
                b')' => depth -= 1,
                b'\n' => break,
                _ => {}
            }
            end += 1;
        }
        if depth == 0 {
            let target = clean[start..end - 1]
                .split_whitespace()
                .next()
                .unwrap_or("");
            let line = clean[..start].matches('\n').count() + 1;
            out.push((
                line,
                target.trim_matches(|c| c == '<' || c == '>').to_string(),
            ));
        }
        i = start;
    }
    out
}

/// Problems with the links of `file`: targets that do not exist, anchors that name no heading.
fn check_links(file: &Path, text: &str) -> Vec<String> {
    let root = root();
    let name = file
        .strip_prefix(&root)
        .unwrap_or(file)
        .display()
        .to_string();
    let mut problems = Vec::new();
    for (line, target) in links(text) {
        if target.is_empty() {
            problems.push(format!("{name}:{line}: empty link"));
            continue;
        }
        if target.contains("://") || target.starts_with("mailto:") {
            continue;
        }
        let (path, anchor) = match target.split_once('#') {
            Some((p, a)) => (p, Some(a)),
            None => (target.as_str(), None),
        };
        let resolved = if path.is_empty() {
            file.to_path_buf()
        } else if let Some(from_root) = path.strip_prefix('/') {
            root.join(from_root)
        } else {
            file.parent().unwrap().join(path)
        };
        if !resolved.exists() {
            problems.push(format!("{name}:{line}: {target}: no such file"));
            continue;
        }
        let Some(anchor) = anchor else { continue };
        if resolved.extension().is_none_or(|e| e != "md") {
            continue;
        }
        let linked = std::fs::read_to_string(&resolved).unwrap();
        if !anchors(&linked).contains(anchor) {
            problems.push(format!(
                "{name}:{line}: {target}: no heading with the anchor #{anchor} in {}",
                resolved.strip_prefix(&root).unwrap_or(&resolved).display()
            ));
        }
    }
    problems
}

/// Whether `text` holds a date `20YY-MM-DD`.
fn has_date(text: &str) -> bool {
    let b = text.as_bytes();
    let digit = |i: usize| b[i].is_ascii_digit();
    (0..b.len().saturating_sub(9)).any(|i| {
        b[i] == b'2'
            && b[i + 1] == b'0'
            && digit(i + 2)
            && digit(i + 3)
            && b[i + 4] == b'-'
            && digit(i + 5)
            && digit(i + 6)
            && b[i + 7] == b'-'
            && digit(i + 8)
            && digit(i + 9)
    })
}

#[test]
fn every_relative_link_and_anchor_in_the_docs_resolves() {
    let files = documents();
    assert!(files.len() >= 10, "too few documents found: {files:?}");
    let mut problems = Vec::new();
    let mut count = 0;
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        count += links(&text).len();
        problems.extend(check_links(file, &text));
    }
    assert!(
        count > 50,
        "only {count} links found: is the parser broken?"
    );
    assert!(
        problems.is_empty(),
        "broken links:\n{}",
        problems.join("\n")
    );
}

#[test]
fn no_heading_under_docs_carries_a_date() {
    let docs = root().join("docs");
    let mut dated = Vec::new();
    for file in documents().iter().filter(|f| f.starts_with(&docs)) {
        let text = std::fs::read_to_string(file).unwrap();
        for heading in headings(&text) {
            if has_date(&heading) {
                dated.push(format!("{}: {heading}", file.display()));
            }
        }
    }
    assert!(dated.is_empty(), "dated headings:\n{}", dated.join("\n"));
}

#[test]
fn the_checker_finds_what_it_should() {
    let text = "# A `code` heading: (x) [link](y.md)\n## A code heading x\n\
                See [here](#a-code-heading-x) and `[not](a link)` and\n\
                ```\n[nor](this)\n```\n![pic](p.png \"title\")\n";
    assert_eq!(
        links(text),
        vec![
            (1, "y.md".to_string()),
            (3, "#a-code-heading-x".to_string()),
            (7, "p.png".to_string())
        ]
    );
    let a = anchors(text);
    assert!(a.contains("a-code-heading-x-link"), "{a:?}");
    assert!(a.contains("a-code-heading-x"), "{a:?}");
    assert_eq!(
        slug("`[mesh]`: the space triangulation at t = 0"),
        "mesh-the-space-triangulation-at-t--0"
    );
    assert_eq!(slug("`crack_tips.csv`"), "crack_tipscsv");
    assert!(has_date("## The run of 2026-11-29") && !has_date("## The run of 2026-11"));
    // A link to a missing file and to a missing anchor are both reported.
    let readme = root().join("README.md");
    let problems = check_links(
        &readme,
        "[a](docs/no_such_page.md) [b](CHANGELOG.md#no-such-heading)\n",
    );
    assert_eq!(problems.len(), 2, "{problems:?}");
}
