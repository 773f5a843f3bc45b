//! Reading a configuration: the file and the files it extends, the command line's overrides,
//! and validation.
//!
//! A config file may build on another with `extends = "base.toml"` (relative to its own folder):
//! the base is read first (itself extending others, if it says so), then every key of the file
//! replaces the base's, tables merging key by key and any other value (arrays of tables
//! included) replacing whole. A chain that comes back to a file, or names a file that cannot be
//! read, is refused naming the chain.

use std::path::{Path, PathBuf};

use super::error::ConfigError;
use super::interface::take_interfaces;
use super::overrides::{apply_override, attribute, attribute_added};
use super::schema::Config;

/// A loaded, validated configuration and where it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedConfig {
    /// The validated configuration with overrides applied.
    pub config: Config,
    /// The config file.
    pub file: PathBuf,
    /// The overrides applied, in order (`key.path=value`, as `--set` gives them).
    pub overrides: Vec<String>,
}

impl LoadedConfig {
    /// Reads `file` with the files it extends, applies `overrides` (`key.path=value`, in order)
    /// and validates.
    pub fn load(file: &Path, overrides: &[String]) -> Result<Self, ConfigError> {
        let source = file.display().to_string();
        let table = read_extended(file, &mut Vec::new())?;
        let config = Config::from_table(table, &source, overrides)?;
        Ok(Self {
            config,
            file: file.to_path_buf(),
            overrides: overrides.to_vec(),
        })
    }

    /// Resolves a path given in the config relative to the config file's folder.
    pub fn resolve(&self, path: &Path) -> PathBuf {
        match self.file.parent() {
            Some(dir) if path.is_relative() => dir.join(path),
            _ => path.to_path_buf(),
        }
    }
}

impl Config {
    /// Parses TOML `text` (named `source` in errors), applies `overrides` and validates. Text
    /// has no folder: a config that extends another is loaded from its file
    /// ([`LoadedConfig::load`]).
    pub fn parse(text: &str, source: &str, overrides: &[String]) -> Result<Self, ConfigError> {
        let table = parse_table(text, source)?;
        if table.contains_key(EXTENDS) {
            return Err(ConfigError {
                file: source.to_string(),
                key: Some(EXTENDS.into()),
                reason: "a config given as text cannot extend another: load it from its file"
                    .into(),
            });
        }
        Self::from_table(table, source, overrides)
    }

    /// The configuration of the TOML `table` (named `source` in errors) with `overrides`
    /// applied, validated.
    fn from_table(
        table: toml::Table,
        source: &str,
        overrides: &[String],
    ) -> Result<Self, ConfigError> {
        let mut root = toml::Value::Table(table);
        let mut added = Vec::new();
        for spec in overrides {
            if let Some(path) = apply_override(&mut root, spec)? {
                added.push((spec.as_str(), path));
            }
        }
        let error = |key: Option<String>, reason: String| {
            let error = ConfigError {
                file: source.to_string(),
                key,
                reason,
            };
            attribute_added(attribute(error, overrides), &added)
        };
        let interface = take_interfaces(&mut root).map_err(|(key, r)| error(Some(key), r))?;
        let mut config: Config = serde_path_to_error::deserialize(root).map_err(|e| {
            let path = e.path().to_string();
            error(
                (path != ".").then_some(path),
                e.into_inner().message().to_string(),
            )
        })?;
        config.interface = interface;
        config
            .validate()
            .map_err(|(key, reason)| error(Some(key), reason))?;
        Ok(config)
    }
}

/// ` (line N)` for a TOML error span, or nothing.
fn line_of(text: &str, span: Option<std::ops::Range<usize>>) -> String {
    span.map(|s| {
        let line = text[..s.start.min(text.len())].matches('\n').count() + 1;
        format!(" (line {line})")
    })
    .unwrap_or_default()
}

/// The key by which a config file builds on another.
const EXTENDS: &str = "extends";

/// The TOML table of `text` (named `source` in errors).
fn parse_table(text: &str, source: &str) -> Result<toml::Table, ConfigError> {
    toml::from_str(text).map_err(|e| ConfigError {
        file: source.to_string(),
        key: None,
        reason: format!("invalid TOML: {}", e.message())
            .trim_end()
            .to_string()
            + &line_of(text, e.span()),
    })
}

/// The table of `file` on top of the tables it extends; `chain` holds the files that led to it,
/// the first one given first, and names them in errors (about the first).
fn read_extended(file: &Path, chain: &mut Vec<PathBuf>) -> Result<toml::Table, ConfigError> {
    let first = chain
        .first()
        .map_or(file, PathBuf::as_path)
        .display()
        .to_string();
    let path_of = |chain: &[PathBuf], last: &Path| {
        (chain.iter().map(|f| f.as_path()))
            .chain(std::iter::once(last))
            .map(|f| f.display().to_string())
            .collect::<Vec<_>>()
            .join(" -> ")
    };
    let text = std::fs::read_to_string(file).map_err(|e| match chain.is_empty() {
        true => ConfigError {
            file: first.clone(),
            key: None,
            reason: format!("cannot read: {e}"),
        },
        false => ConfigError {
            file: first.clone(),
            key: Some(EXTENDS.into()),
            reason: format!(
                "{}: cannot read {}: {e}",
                path_of(chain, file),
                file.display()
            ),
        },
    })?;
    let mut table = parse_table(&text, &file.display().to_string())?;
    let Some(base) = table.remove(EXTENDS) else {
        return Ok(table);
    };
    let Some(base) = base.as_str() else {
        return Err(ConfigError {
            file: file.display().to_string(),
            key: Some(EXTENDS.into()),
            reason: "must be the name of a config file (a string)".into(),
        });
    };
    let base = file.parent().unwrap_or(Path::new("")).join(base);
    chain.push(file.to_path_buf());
    let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    };
    if chain.iter().any(|f| same(f, &base)) {
        return Err(ConfigError {
            file: first,
            key: Some(EXTENDS.into()),
            reason: format!("{}: a cycle", path_of(chain, &base)),
        });
    }
    let mut merged = read_extended(&base, chain)?;
    merge(&mut merged, table);
    Ok(merged)
}

/// `over`'s keys into `base`: tables merge key by key, any other value replaces.
fn merge(base: &mut toml::Table, over: toml::Table) {
    for (key, value) in over {
        match (base.get_mut(&key), value) {
            (Some(toml::Value::Table(inner)), toml::Value::Table(value)) => merge(inner, value),
            (_, value) => {
                base.insert(key, value);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::tests::BASE;

    /// Writes `files` (name, text) into a fresh folder.
    fn folder(files: &[(&str, &str)]) -> tempfile::TempDir {
        let dir = tempfile::tempdir().expect("temporary folder");
        for (name, text) in files {
            std::fs::write(dir.path().join(name), text).expect("write");
        }
        dir
    }

    #[test]
    fn a_config_overrides_what_it_extends_key_by_key() {
        let dir = folder(&[
            ("base.toml", BASE),
            ("mid.toml", "extends = \"base.toml\"\n[time]\nend = 2e-6\n"),
            ("top.toml", "extends = \"mid.toml\"\n[mesh]\nnx = 8\n"),
        ]);
        let base = LoadedConfig::load(&dir.path().join("base.toml"), &[]).unwrap();
        let top = LoadedConfig::load(&dir.path().join("top.toml"), &[]).unwrap();
        // Nested: the middle file's end time, the top file's nx, the rest from the base.
        assert_eq!(top.config.time.end, 2e-6);
        assert_eq!(top.config.mesh.nx, Some(8));
        assert_eq!(top.config.mesh.ny, base.config.mesh.ny);
        assert_eq!(top.config.material, base.config.material);
        // The command line still has the last word.
        let set = ["mesh.nx=4".to_string()];
        let top = LoadedConfig::load(&dir.path().join("top.toml"), &set).unwrap();
        assert_eq!(top.config.mesh.nx, Some(4));
    }

    #[test]
    fn interface_entries_come_from_the_base_or_replace_it_whole() {
        let crack =
            "[[mesh.interface]]\nfrom = [0.0, 0.005]\nto = [0.004, 0.005]\ntag = \"crack\"\n";
        let cohesive = "[[interface]]\ntags = [\"crack\"]\nlaw = \"xu_needleman\"\n\
                        strength = 1e6\ncritical_separation = 1e-6\n";
        let base = format!("{BASE}{crack}{cohesive}");
        let dir = folder(&[
            ("base.toml", &base),
            ("same.toml", "extends = \"base.toml\"\n[time]\nend = 2e-6\n"),
            (
                "free.toml",
                "extends = \"base.toml\"\n[[interface]]\ntags = [\"crack\"]\nlaw = \"free\"\n",
            ),
            (
                "mixed.toml",
                "extends = \"base.toml\"\n[[interface]]\ntags = [\"crack\"]\nlaw = \"free\"\n\
                 strength = 1e6\n",
            ),
        ]);
        let load = |name: &str| LoadedConfig::load(&dir.path().join(name), &[]);
        let base = load("base.toml").unwrap().config;
        let same = load("same.toml").unwrap().config;
        assert_eq!(same.interface, base.interface);
        assert_eq!(same.law_of("crack").map(|l| l.is_cohesive()), Some(true));
        let free = load("free.toml").unwrap().config;
        assert_eq!(free.law_of("crack"), Some(sdg_solver::interface::Law::Free));
        // The entry replaces the base's whole: the base's strength is not carried over.
        let e = load("mixed.toml").unwrap_err();
        assert!(e.file.ends_with("mixed.toml"), "{e}");
        assert_eq!(e.key.as_deref(), Some("interface[0].strength"));
    }

    #[test]
    fn a_cycle_or_a_missing_base_is_refused_naming_the_chain() {
        let dir = folder(&[
            ("a.toml", "extends = \"b.toml\"\n"),
            ("b.toml", "extends = \"a.toml\"\n"),
            ("c.toml", "extends = \"nowhere.toml\"\n"),
            ("d.toml", "extends = 3\n"),
        ]);
        let e = LoadedConfig::load(&dir.path().join("a.toml"), &[]).unwrap_err();
        assert_eq!(e.key.as_deref(), Some("extends"));
        assert!(e.reason.contains("a.toml -> ") && e.reason.contains("b.toml -> "));
        assert!(e.reason.ends_with("a.toml: a cycle"), "{e}");
        let e = LoadedConfig::load(&dir.path().join("c.toml"), &[]).unwrap_err();
        assert!(e.file.ends_with("c.toml"), "{e}");
        assert!(
            e.reason.contains("c.toml -> ") && e.reason.contains("cannot read"),
            "{e}"
        );
        let e = LoadedConfig::load(&dir.path().join("d.toml"), &[]).unwrap_err();
        assert!(e.reason.contains("a string"), "{e}");
        // Text has no folder to resolve a base in.
        let e = Config::parse("extends = \"a.toml\"\n", "text", &[]).unwrap_err();
        assert_eq!(e.key.as_deref(), Some("extends"));
    }
}
