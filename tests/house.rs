//! House rules of the source tree: no file of `engine/src` or `solver/src` over 800 lines, and no
//! circle of imports between the files of any crate.
//!
//! A file depends on another when it names one of the other's items by a path (`use` or inline):
//! `crate::a::b::Item` depends on the file of the deepest module `a::b` that exists, `super::x`
//! and `self::x` the same relative to the file's own module. A parent that declares a child
//! (`mod child;`) does not depend on it by that; a parent that re-exports from it does. A path
//! through a re-export depends on the file that defines the item. Unit tests (`mod tests`) do
//! not count.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Longest file allowed in the crates that hold most of the code, lines.
const MAX_LINES: usize = 800;

/// The crates' source folders, relative to the workspace root.
const CRATES: [&str; 6] = [
    "mesh/src",
    "solver/src",
    "scheduler/src",
    "engine/src",
    "distributed/src",
    "src",
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every `.rs` file under `dir`, sorted.
fn sources(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("source folder") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// The module path of `file` within its crate rooted at `src` (`[]` for the crate root).
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let relative = file.strip_prefix(src).expect("under src");
    let mut parts: Vec<String> = relative
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().expect("a file name");
    let stem = last.trim_end_matches(".rs");
    if !matches!(stem, "mod" | "lib" | "main") {
        parts.push(stem.to_string());
    }
    parts
}

/// `text` without comments and string literals (so that paths in docs do not count).
fn code_only(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
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
                let mut last = ' ';
                for c in chars.by_ref() {
                    if last == '*' && c == '/' {
                        break;
                    }
                    last = c;
                }
            }
            '"' => {
                let mut escaped = false;
                for c in chars.by_ref() {
                    if c == '"' && !escaped {
                        break;
                    }
                    escaped = c == '\\' && !escaped;
                }
                out.push_str("\"\"");
            }
            // A char literal such as '"' or '{' (lifetimes are left alone: no closing quote).
            '\'' => {
                let rest: String = chars.clone().take(3).collect();
                let literal = rest.starts_with('\\') || rest.chars().nth(1) == Some('\'');
                if literal {
                    for c in chars.by_ref() {
                        if c == '\'' {
                            break;
                        }
                    }
                    out.push_str("' '");
                } else {
                    out.push(c);
                }
            }
            _ => out.push(c),
        }
    }
    out
}

/// A path named in a file: its segments as written (`crate`, `super`, `self` or a first name),
/// and for a `use` leaf the name it brings into scope.
#[derive(Debug)]
struct Named {
    segments: Vec<String>,
    alias: Option<String>,
    /// The inline modules (`mod tests { .. }`) it is written in, outermost first.
    inner: Vec<String>,
}

/// The paths named in `code`: those that start at `crate`, `super` or `self` anywhere, and every
/// `use` path (brace groups expanded, `as` renames kept).
fn paths(code: &str) -> Vec<Named> {
    let mut found = Vec::new();
    let bytes = code.as_bytes();
    let is_ident = |b: u8| b.is_ascii_alphanumeric() || b == b'_';
    // Open braces, each with the inline module it opens (if it does).
    let mut braces: Vec<Option<String>> = Vec::new();
    let mut module: Option<String> = None;
    let mut i = 0;
    while i < bytes.len() {
        let at_word = i == 0 || !is_ident(bytes[i - 1]) && bytes[i - 1] != b':';
        let inner: Vec<String> = braces.iter().flatten().cloned().collect();
        let start = found.len();
        if at_word && code[i..].starts_with("use ") {
            let end = path_end(code, i + 4);
            expand(code[i + 4..end].trim(), true, &mut found);
            i = end.max(i + 4);
        } else if at_word
            && ["crate::", "super::", "self::"]
                .iter()
                .any(|p| code[i..].starts_with(p))
        {
            let end = path_end(code, i);
            expand(&code[i..end], false, &mut found);
            i = end;
        } else if at_word && code[i..].starts_with("mod ") {
            let name: String = code[i + 4..]
                .trim_start()
                .chars()
                .take_while(|&c| is_ident(c as u8))
                .collect();
            module = Some(name);
            i += 4;
        } else {
            match bytes[i] {
                b'{' => braces.push(module.take()),
                b'}' => {
                    braces.pop();
                }
                b';' => module = None,
                _ => {}
            }
            i += 1;
        }
        for named in &mut found[start..] {
            named.inner.clone_from(&inner);
        }
    }
    found
}

/// Where the path starting at `from` ends: its brace groups included.
fn path_end(code: &str, from: usize) -> usize {
    let bytes = code.as_bytes();
    let mut depth = 0usize;
    let mut i = from;
    while i < bytes.len() {
        match bytes[i] {
            b'{' => depth += 1,
            b'}' if depth > 0 => depth -= 1,
            b'}' => return i,
            b';' => return i,
            // Inside braces and for `as` renames anything goes but `;`.
            _ if depth > 0 => {}
            b' ' if code[i..].starts_with(" as ") => i += 3,
            // Leading spaces of `use  x` are part of it.
            b' ' if i == from => {}
            c if !(c.is_ascii_alphanumeric() || c == b'_' || c == b':' || c == b'*') => return i,
            _ => {}
        }
        i += 1;
    }
    i
}

/// Expands `a::{b, c::{d as e}}` into `a::b` and `a::c::d` (named `e`), pushing each.
fn expand(path: &str, is_use: bool, out: &mut Vec<Named>) {
    let path = path.replace(" as ", "@");
    let path: String = path.chars().filter(|c| !c.is_whitespace()).collect();
    match path.find('{') {
        None => {
            let (path, alias) = match path.split_once('@') {
                Some((p, a)) => (p.to_string(), Some(a.to_string())),
                None => (path.clone(), None),
            };
            let segments: Vec<String> = path
                .split("::")
                .filter(|s| !s.is_empty())
                .map(str::to_string)
                .collect();
            let alias = is_use.then(|| {
                alias.unwrap_or_else(|| match segments.last().map(String::as_str) {
                    // `use a::b::{self}` names `b`.
                    Some("self") if segments.len() > 1 => segments[segments.len() - 2].clone(),
                    last => last.unwrap_or("").to_string(),
                })
            });
            let alias = alias.filter(|a| a != "*");
            out.push(Named {
                segments,
                alias,
                inner: Vec::new(),
            });
        }
        Some(open) => {
            let prefix = &path[..open];
            let inner = &path[open + 1..path.rfind('}').unwrap_or(path.len())];
            let mut depth = 0;
            let mut piece = String::new();
            for c in inner.chars().chain(std::iter::once(',')) {
                match c {
                    '{' => {
                        depth += 1;
                        piece.push(c);
                    }
                    '}' => {
                        depth -= 1;
                        piece.push(c);
                    }
                    ',' if depth == 0 => {
                        if !piece.is_empty() {
                            expand(&format!("{prefix}{piece}"), is_use, out);
                        }
                        piece.clear();
                    }
                    _ => piece.push(c),
                }
            }
        }
    }
}

/// A module's file, and the names its `use` items bring into scope with the absolute paths
/// they stand for (`None` for another crate's).
struct Module {
    file: PathBuf,
    uses: BTreeMap<String, Option<Vec<String>>>,
    named: Vec<Vec<String>>,
}

/// `path` as written in module `module` made absolute within the crate (`None` for a path into
/// another crate or the standard library).
fn absolute(
    module: &[String],
    named: &Named,
    modules: &BTreeMap<Vec<String>, Module>,
) -> Option<Vec<String>> {
    let path = named.segments.as_slice();
    let mut base: Vec<String> = module.iter().chain(&named.inner).cloned().collect();
    let rest = match path.first().map(String::as_str) {
        Some("crate") => {
            base.clear();
            &path[1..]
        }
        Some("self") => &path[1..],
        Some("super") => {
            let mut rest = path;
            while rest.first().map(String::as_str) == Some("super") {
                base.pop();
                rest = &rest[1..];
            }
            rest
        }
        // A relative path: a child module of this one, or a name this module imports.
        Some(first) => {
            let mut child = module.to_vec();
            child.push(first.to_string());
            if !modules.contains_key(&child) {
                return match modules.get(module).and_then(|m| m.uses.get(first)) {
                    Some(Some(target)) => Some(target.iter().chain(&path[1..]).cloned().collect()),
                    _ => None,
                };
            }
            path
        }
        None => return None,
    };
    base.extend(rest.iter().filter(|s| *s != "self").cloned());
    Some(base)
}

/// The file that defines what the absolute `path` names: the deepest module it goes through,
/// or, when the next name is one that module imports, where that import leads.
fn defining_file(
    path: &[String],
    modules: &BTreeMap<Vec<String>, Module>,
    hops: usize,
) -> Option<PathBuf> {
    let mut deepest = Vec::new();
    for (i, segment) in path.iter().enumerate() {
        let mut longer = deepest.clone();
        longer.push(segment.clone());
        if modules.contains_key(&longer) {
            deepest = longer;
            continue;
        }
        let module = modules.get(&deepest)?;
        if hops < 8
            && let Some(target) = module.uses.get(segment)
        {
            // Re-exported or imported here: the item lives where the import leads.
            let target: Vec<String> = target
                .as_ref()?
                .iter()
                .chain(&path[i + 1..])
                .cloned()
                .collect();
            return defining_file(&target, modules, hops + 1);
        }
        return Some(module.file.clone());
    }
    modules.get(&deepest).map(|m| m.file.clone())
}

/// The import circles among the files of the crate in `src`, each as its files in order.
fn circles(src: &Path) -> Vec<Vec<PathBuf>> {
    let mut modules: BTreeMap<Vec<String>, Module> = sources(src)
        .into_iter()
        .map(|file| {
            let module = module_of(src, &file);
            let named = Module {
                file,
                uses: BTreeMap::new(),
                named: Vec::new(),
            };
            (module, named)
        })
        .collect();
    // Each file's paths; its imports resolved once every module is known.
    let mut written = BTreeMap::new();
    for (module, m) in &modules {
        let code = code_only(&std::fs::read_to_string(&m.file).expect("source"));
        written.insert(module.clone(), paths(&code));
    }
    for _ in 0..3 {
        for (module, named) in &written {
            let uses: BTreeMap<String, Option<Vec<String>>> = named
                .iter()
                .filter_map(|n| {
                    let alias = n.alias.clone()?;
                    Some((alias, absolute(module, n, &modules)))
                })
                .collect();
            modules.get_mut(module).expect("module").uses = uses;
        }
    }
    for (module, named) in &written {
        // Unit tests may use test helpers that use the module under test.
        let resolved: Vec<Vec<String>> = named
            .iter()
            .filter(|n| !n.inner.iter().any(|m| m == "tests"))
            .filter_map(|n| absolute(module, n, &modules))
            .collect();
        modules.get_mut(module).expect("module").named = resolved;
    }
    let graph: BTreeMap<PathBuf, BTreeSet<PathBuf>> = modules
        .values()
        .map(|m| {
            let deps = m
                .named
                .iter()
                .filter_map(|path| defining_file(path, &modules, 0))
                .filter(|f| *f != m.file)
                .collect();
            (m.file.clone(), deps)
        })
        .collect();
    // A circle is a path back to its start; each is reported once, from its smallest file.
    let mut found = Vec::new();
    for start in graph.keys() {
        let mut stack = vec![(start.clone(), vec![start.clone()])];
        let mut seen = BTreeSet::new();
        while let Some((at, trail)) = stack.pop() {
            for next in &graph[&at] {
                if next == start {
                    found.push(trail.clone());
                } else if next > start && seen.insert(next.clone()) {
                    let mut longer = trail.clone();
                    longer.push(next.clone());
                    stack.push((next.clone(), longer));
                }
            }
        }
    }
    found
}

#[test]
fn no_import_circles() {
    let root = root();
    let mut all = Vec::new();
    for krate in CRATES {
        for circle in circles(&root.join(krate)) {
            let names: Vec<String> = circle
                .iter()
                .map(|f| f.strip_prefix(&root).unwrap_or(f).display().to_string())
                .collect();
            all.push(names.join(" -> "));
        }
    }
    assert!(all.is_empty(), "import circles:\n{}", all.join("\n"));
}

#[test]
fn no_long_files() {
    let root = root();
    let long: Vec<String> = ["engine/src", "solver/src"]
        .iter()
        .flat_map(|krate| sources(&root.join(krate)))
        .filter_map(|file| {
            let lines = std::fs::read_to_string(&file)
                .expect("source")
                .lines()
                .count();
            (lines > MAX_LINES).then(|| format!("{} ({lines} lines)", file.display()))
        })
        .collect();
    assert!(long.is_empty(), "files over {MAX_LINES} lines: {long:?}");
}

#[test]
fn the_checker_sees_a_circle() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let src = dir.path();
    std::fs::create_dir(src.join("a")).expect("folder");
    std::fs::write(src.join("lib.rs"), "mod a;\nmod b;\n").expect("write");
    std::fs::write(src.join("a/mod.rs"), "mod c;\npub use c::X;\n").expect("write");
    std::fs::write(src.join("a/c.rs"), "use super::super::b::{Y, z::W};\n").expect("write");
    std::fs::write(
        src.join("b.rs"),
        "// crate::a::X\nfn f() { crate::a::X; }\n",
    )
    .expect("write");
    let found = circles(src);
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].len(), 2, "{found:?}");
    // An item defined in a parent that re-exports from its child closes a circle.
    std::fs::write(src.join("b.rs"), "use crate::a::D;\n").expect("write");
    std::fs::write(
        src.join("a/mod.rs"),
        "mod c;\npub use c::X;\npub struct D;\n",
    )
    .expect("write");
    let found = circles(src);
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].len(), 3, "{found:?}");
    // Through a re-export the dependency is on the file that defines the item: none here.
    std::fs::write(src.join("a/d.rs"), "pub struct D;\n").expect("write");
    std::fs::write(
        src.join("a/mod.rs"),
        "mod c;\nmod d;\npub use c::X;\npub use d::D;\n",
    )
    .expect("write");
    assert!(circles(src).is_empty());
    // Without the inline path in b.rs there is none (its comment does not count).
    std::fs::write(src.join("b.rs"), "// crate::a::X\nfn f() {}\n").expect("write");
    assert!(circles(src).is_empty());
}
