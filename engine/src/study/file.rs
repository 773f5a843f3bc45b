//! The study file: reading it and checking its keys.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;

use super::cases::{self, Axis, Case};
use super::error::StudyError;
use super::metrics::check_metric;
use crate::config::LoadedConfig;

/// The study file as written; tables keep their keys' places in the file (spans) so that axes
/// and overrides are taken in file order.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Raw {
    base: Option<String>,
    metrics: Option<Vec<String>>,
    #[serde(default)]
    axes: BTreeMap<Spanned<String>, toml::Value>,
    #[serde(default)]
    set: BTreeMap<Spanned<String>, toml::Value>,
}

/// A checked study file.
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    /// The study file.
    pub file: PathBuf,
    /// The base config, resolved against the study file's folder.
    pub base: PathBuf,
    /// The `summary.json` keys collected from every case (dotted).
    pub metrics: Vec<String>,
    /// The axes in file order: cases are their product, the first axis outermost.
    pub axes: Vec<Axis>,
    /// Overrides for every case (dotted config key, value), in file order.
    pub set: Vec<(String, toml::Value)>,
}

impl Study {
    /// Reads and checks the study `file`: its keys, axes and metrics (not yet the configs of
    /// its cases: [`Study::prepare`]).
    pub fn load(file: &Path) -> Result<Self, StudyError> {
        let name = file.display().to_string();
        let error = |key: Option<&str>, reason: String| StudyError {
            file: name.clone(),
            key: key.map(str::to_string),
            reason,
        };
        let text =
            std::fs::read_to_string(file).map_err(|e| error(None, format!("cannot read: {e}")))?;
        let raw: Raw = toml::from_str(&text).map_err(|e| {
            let line = e.span().map_or(String::new(), |s| {
                format!(
                    " (line {})",
                    text[..s.start.min(text.len())].matches('\n').count() + 1
                )
            });
            error(None, format!("{}{line}", e.message().trim_end()))
        })?;
        let base = raw.base.ok_or_else(|| {
            error(
                Some("base"),
                "missing: the config every case starts from".into(),
            )
        })?;
        let base = file.parent().unwrap_or(Path::new("")).join(base);
        let metrics = raw.metrics.ok_or_else(|| {
            error(
                Some("metrics"),
                "missing: the summary.json keys to collect".into(),
            )
        })?;
        if metrics.is_empty() {
            return Err(error(Some("metrics"), "an empty list".into()));
        }
        for (i, key) in metrics.iter().enumerate() {
            if metrics[..i].contains(key) {
                return Err(error(Some("metrics"), format!("`{key}` is listed twice")));
            }
            check_metric(key).map_err(|reason| error(Some("metrics"), reason))?;
        }
        let mut set = Vec::new();
        for (key, value) in in_file_order(raw.set) {
            flatten(key, value, &mut set);
        }
        let mut axes: Vec<Axis> = Vec::new();
        for (key, value) in in_file_order(raw.axes) {
            let name = format!("axes.\"{key}\"");
            let (values, draws, with) = axis_values(value).map_err(|r| error(Some(&name), r))?;
            let taken = |k: &str| {
                set.iter().any(|(s, _)| s == k)
                    || (axes.iter()).any(|a| a.key == k || a.with.iter().any(|(w, _)| w == k))
            };
            let places = std::iter::once((&key, name.clone()))
                .chain((with.iter()).map(|(k, _)| (k, format!("{name}.with.\"{k}\""))));
            for (i, (k, place)) in places.enumerate() {
                if taken(k) || (i > 0 && *k == key) {
                    return Err(error(
                        Some(&place),
                        format!("`{k}` is also set elsewhere in the study: give a key one place"),
                    ));
                }
            }
            axes.push(Axis {
                key,
                values,
                draws,
                with,
            });
        }
        Ok(Self {
            file: file.to_path_buf(),
            base,
            metrics,
            axes,
            set,
        })
    }

    /// The cases, each with its config loaded (and so checked) and hashed: a key that is not a
    /// config key, a value of the wrong type or a base config that does not load is an error
    /// naming the study key that set it.
    pub fn prepare(&self) -> Result<Vec<Case>, StudyError> {
        let mut out = Vec::new();
        for (index, values) in cases::product(&self.axes).into_iter().enumerate() {
            let (overrides, sources) = cases::overrides(&self.set, &self.axes, &values);
            let loaded = LoadedConfig::load(&self.base, &overrides).map_err(|e| {
                let key = (sources.iter().zip(&overrides))
                    .find(|(_, spec)| e.file == format!("--set {spec}"))
                    .map_or_else(|| "base".to_string(), |(key, _)| key.clone());
                let which = match self.axes.is_empty() {
                    true => String::new(),
                    false => format!("case {index} ({}): ", cases::label(&self.axes, &values)),
                };
                StudyError {
                    file: self.file.display().to_string(),
                    key: Some(key),
                    reason: format!("{which}{e}"),
                }
            })?;
            out.push(Case {
                index,
                values,
                overrides,
                sources,
                hash: cases::config_hash(&loaded.config),
            });
        }
        Ok(out)
    }

    /// The file's stem, e.g. `plate_draws`: the default output folder's name.
    pub fn stem(&self) -> String {
        self.file
            .file_stem()
            .map_or_else(|| "study".into(), |s| s.to_string_lossy().into_owned())
    }
}

/// The entries of a study table in the order the file gives them.
fn in_file_order(table: BTreeMap<Spanned<String>, toml::Value>) -> Vec<(String, toml::Value)> {
    let mut entries: Vec<_> = table.into_iter().collect();
    entries.sort_by_key(|(k, _)| k.span().start);
    entries
        .into_iter()
        .map(|(k, v)| (k.into_inner(), v))
        .collect()
}

/// `value` set at `key` as dotted keys: a table (`[set] output.png = false` without quotes)
/// is set key by key, never whole (which would drop the base's other keys of that table).
fn flatten(key: String, value: toml::Value, out: &mut Vec<(String, toml::Value)>) {
    match value {
        toml::Value::Table(table) => {
            for (k, v) in table {
                flatten(format!("{key}.{k}"), v, out);
            }
        }
        value => out.push((key, value)),
    }
}

/// An axis's values, whether it is a draws axis, and the keys that go with it (see
/// [`axis_values`]).
type AxisValues = (Vec<toml::Value>, bool, Vec<(String, Vec<toml::Value>)>);

/// The values of an axis (a non-empty list; `{ draws = N, first = F }`, `F` 1 by default; or
/// `{ values = [...], with = { "key" = [...], ... } }`, distinct values each with a value of
/// every key of `with`), whether it is a draws axis and the keys that go with it; or why it is
/// none of these.
fn axis_values(value: toml::Value) -> Result<AxisValues, String> {
    match value {
        toml::Value::Array(values) if values.is_empty() => {
            Err("an empty list: give at least one value".into())
        }
        toml::Value::Array(values) => Ok((values, false, Vec::new())),
        toml::Value::Table(mut table) if table.contains_key("values") => {
            if let Some(k) = table
                .keys()
                .find(|k| !["values", "with"].contains(&k.as_str()))
            {
                return Err(format!(
                    "unknown key `{k}` of an axis with keys that go with it (values, with)"
                ));
            }
            let (values, _, _) = axis_values(table.remove("values").expect("checked"))
                .map_err(|r| format!("values: {r}"))?;
            for (i, v) in values.iter().enumerate() {
                if values[..i].contains(v) {
                    return Err(format!("values: {v} is listed twice"));
                }
            }
            let with = match table.remove("with") {
                None => toml::map::Map::new(),
                Some(toml::Value::Table(with)) => with,
                Some(v) => return Err(format!("with must be a table of keys and lists, got {v}")),
            };
            let mut keys = Vec::new();
            for (k, v) in with {
                match v {
                    toml::Value::Array(vs) if vs.len() == values.len() => keys.push((k, vs)),
                    toml::Value::Array(vs) => {
                        return Err(format!(
                            "with.\"{k}\": {} values for the axis's {}: give one per value",
                            vs.len(),
                            values.len()
                        ));
                    }
                    v => return Err(format!("with.\"{k}\" must be a list, got {v}")),
                }
            }
            Ok((values, false, keys))
        }
        toml::Value::Table(table) if table.contains_key("draws") => {
            if let Some(k) = table
                .keys()
                .find(|k| !["draws", "first"].contains(&k.as_str()))
            {
                return Err(format!("unknown key `{k}` of a draws axis (draws, first)"));
            }
            let int = |k: &str, default: i64| match table.get(k) {
                None => Ok(default),
                Some(toml::Value::Integer(n)) => Ok(*n),
                Some(v) => Err(format!("{k} must be an integer, got {v}")),
            };
            let (draws, first) = (int("draws", 0)?, int("first", 1)?);
            if draws < 1 {
                return Err(format!("draws = {draws}: at least one draw"));
            }
            let last = first
                .checked_add(draws - 1)
                .ok_or_else(|| format!("first = {first}: the draws overflow"))?;
            Ok((
                (first..=last).map(toml::Value::Integer).collect(),
                true,
                Vec::new(),
            ))
        }
        v => Err(format!(
            "an axis is a list of values, {{ draws = N, first = F }} or {{ values = [...], with \
             = {{ ... }} }}, got {v} (quote a dotted key: \"adapt.min_edge\" = [...])"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Writes a study `text` beside a copy of `base` text; returns the folder and the file.
    fn study(text: &str) -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("base.toml"), crate::config::tests::BASE).unwrap();
        let file = dir.path().join("s.toml");
        std::fs::write(&file, text).unwrap();
        (dir, file)
    }

    #[test]
    fn axes_and_overrides_keep_file_order() {
        let (_dir, file) = study(
            "base = \"base.toml\"\nmetrics = [\"patches\"]\n[axes]\n\"time.end\" = [1e-6, 2e-6]\n\
             \"mesh.nx\" = { draws = 3, first = 4 }\n\"adapt.tol\" = [1.0]\n[set]\n\
             \"mesh.ny\" = 8\noutput.png = false\n",
        );
        let s = Study::load(&file).unwrap();
        let keys: Vec<&str> = s.axes.iter().map(|a| a.key.as_str()).collect();
        assert_eq!(keys, ["time.end", "mesh.nx", "adapt.tol"]);
        assert_eq!(
            s.axes[1].values,
            [4, 5, 6].map(toml::Value::Integer).to_vec()
        );
        assert!(s.axes[1].draws && !s.axes[0].draws);
        assert_eq!(
            s.set,
            [
                ("mesh.ny".to_string(), toml::Value::Integer(8)),
                ("output.png".to_string(), toml::Value::Boolean(false))
            ]
        );
        assert_eq!(s.base, file.parent().unwrap().join("base.toml"));
        assert_eq!(s.stem(), "s");
    }

    #[test]
    fn keys_that_go_with_an_axis_are_set_with_its_values() {
        let (_dir, file) = study(
            "base = \"base.toml\"\nmetrics = [\"patches\"]\n[axes]\n\"mesh.nx\" = { values = [4, \
             8], with = { \"mesh.ny\" = [6, 12], \"time.end\" = [1e-6, 2e-6] } }\n\
             \"adapt.tol\" = [1.0, 2.0]\n",
        );
        let s = Study::load(&file).unwrap();
        assert_eq!(s.axes[0].with.len(), 2);
        let cases = s.prepare().unwrap();
        assert_eq!(cases.len(), 4);
        assert_eq!(
            cases[2].overrides,
            ["mesh.nx=8", "mesh.ny=12", "time.end=2e-6", "adapt.tol=1.0"]
        );
        assert_eq!(cases[2].label(&s.axes), "mesh.nx=8, adapt.tol=1.0");
        assert_ne!(cases[0].hash, cases[2].hash);
    }

    #[test]
    fn bad_studies_name_the_key() {
        let head = "base = \"base.toml\"\nmetrics = [\"patches\"]\n";
        let cases = [
            ("metrics = [\"patches\"]\n", "base", "missing"),
            ("base = \"base.toml\"\n", "metrics", "missing"),
            (
                "base = \"base.toml\"\nmetrics = [\"crack.first_branching_tme\"]\n",
                "metrics",
                "crack.first_branching_tme",
            ),
            (
                &format!("{head}[axes]\n\"fracture.seed\" = {{ draws = 0 }}\n"),
                "axes.\"fracture.seed\"",
                "draws = 0",
            ),
            (
                &format!("{head}[axes]\n\"mesh.nx\" = []\n"),
                "axes.\"mesh.nx\"",
                "empty",
            ),
            (
                &format!("{head}[axes]\n\"mesh.nx\" = [4]\n[set]\n\"mesh.nx\" = 8\n"),
                "axes.\"mesh.nx\"",
                "one place",
            ),
            (
                &format!(
                    "{head}[axes]\n\"mesh.nx\" = {{ values = [4, 8], with = {{ \"mesh.ny\" = [4] }} }}\n"
                ),
                "axes.\"mesh.nx\"",
                "1 values for the axis's 2",
            ),
            (
                &format!("{head}[axes]\n\"mesh.nx\" = {{ values = [4, 4] }}\n"),
                "axes.\"mesh.nx\"",
                "listed twice",
            ),
            (
                &format!(
                    "{head}[axes]\n\"mesh.nx\" = {{ values = [4], with = {{ \"mesh.ny\" = [4] }} }}\n\
                     \"mesh.ny\" = [8]\n"
                ),
                "axes.\"mesh.ny\"",
                "one place",
            ),
            (
                &format!(
                    "{head}[axes]\n\"mesh.nx\" = {{ values = [4], with = {{ \"mesh.ny\" = [4] }} }}\n\
                     [set]\n\"mesh.ny\" = 8\n"
                ),
                "axes.\"mesh.nx\".with.\"mesh.ny\"",
                "one place",
            ),
        ];
        for (text, key, reason) in cases {
            let (_dir, file) = study(text);
            let e = Study::load(&file).unwrap_err();
            assert_eq!(e.key.as_deref(), Some(key), "{e}");
            assert!(e.reason.contains(reason), "{e}");
            assert_eq!(e.file, file.display().to_string());
        }
        let (_dir, file) = study(&format!("{head}colour = 1\n"));
        assert!(Study::load(&file).unwrap_err().reason.contains("colour"));
    }

    #[test]
    fn unknown_config_keys_and_bad_bases_are_refused_before_running() {
        let head = "base = \"base.toml\"\nmetrics = [\"patches\"]\n";
        let (_dir, file) = study(&format!("{head}[axes]\n\"adapt.min_edgee\" = [1e-3]\n"));
        let e = Study::load(&file).unwrap().prepare().unwrap_err();
        assert_eq!(e.key.as_deref(), Some("axes.\"adapt.min_edgee\""), "{e}");
        assert!(e.reason.contains("unknown field"), "{e}");
        let (_dir, file) = study(&format!("{head}[set]\n\"mesh.nx\" = \"many\"\n"));
        let e = Study::load(&file).unwrap().prepare().unwrap_err();
        assert_eq!(e.key.as_deref(), Some("set.\"mesh.nx\""), "{e}");
        let (_dir, file) = study(&head.replace("base.toml", "nowhere.toml"));
        let e = Study::load(&file).unwrap().prepare().unwrap_err();
        assert_eq!(e.key.as_deref(), Some("base"), "{e}");
        assert!(e.reason.contains("cannot read"), "{e}");
    }
}
