//! Cases: the product of a study's axes, each a list of `--set` overrides of the base config,
//! its folder, and the hash of the config it runs.

use std::path::{Path, PathBuf};

use crate::config::Config;

/// One axis of a study: a config key and its values, and keys that go with it.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// The dotted config key, as `--set` takes it.
    pub key: String,
    /// Its values, in order (distinct when `with` is not empty).
    pub values: Vec<toml::Value>,
    /// True for a `{ draws = N, first = F }` axis (the integers `F`, ..., `F + N - 1`): the
    /// statistics are taken over it.
    pub draws: bool,
    /// Further config keys that vary with this one (`{ values = [...], with = { ... } }`):
    /// each with one value per value of `values`, the `i`-th set with the `i`-th (a load and
    /// the domain sized for it, say).
    pub with: Vec<(String, Vec<toml::Value>)>,
}

impl Axis {
    /// The keys and values of `with` that go with `value` of this axis.
    pub(super) fn companions<'a>(
        &'a self,
        value: &toml::Value,
    ) -> impl Iterator<Item = (&'a String, &'a toml::Value)> {
        let i = self.values.iter().position(|v| v == value);
        (self.with.iter()).filter_map(move |(k, vs)| Some((k, &vs[i?])))
    }
}

/// One case of a study: a value of every axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// The case number, from 0 (`--case K`, the Slurm array task id).
    pub index: usize,
    /// Its value of each axis, in the order of the axes.
    pub values: Vec<toml::Value>,
    /// `KEY=VALUE` overrides of the base config, as `sdg run --set` takes them: the study's
    /// `[set]`, then the axes' values.
    pub overrides: Vec<String>,
    /// The study key behind each override (`set."output.png"`, `axes."fracture.seed"`).
    pub sources: Vec<String>,
    /// [`config_hash`] of the case's config: a finished case of another hash is run again.
    pub hash: String,
}

impl Case {
    /// `key=value` of each of the study's `axes`, comma-separated (`adapt.min_edge=5e-6,
    /// fracture.seed=3`).
    pub fn label(&self, axes: &[Axis]) -> String {
        label(axes, &self.values)
    }
}

/// `key=value` of each axis with its value in `values`, comma-separated.
pub(super) fn label(axes: &[Axis], values: &[toml::Value]) -> String {
    let parts: Vec<String> = (axes.iter().zip(values))
        .map(|(a, v)| format!("{}={}", a.key, value_text(v)))
        .collect();
    parts.join(", ")
}

/// A group of cases: those with the same values of the axes other than the draws.
#[derive(Debug)]
pub(super) struct Group {
    /// The non-draws axes' values (in the order of the axes; the draws' places skipped).
    pub values: Vec<toml::Value>,
    /// The cases in the group.
    pub cases: Vec<usize>,
}

/// The groups of `cases` of a study with `axes` by their non-draws axis values, in the order they first appear.
pub(super) fn groups(axes: &[Axis], cases: &[Case]) -> Vec<Group> {
    let mut groups: Vec<Group> = Vec::new();
    for case in cases {
        let values: Vec<toml::Value> = (axes.iter().zip(&case.values))
            .filter(|(a, _)| !a.draws)
            .map(|(_, v)| v.clone())
            .collect();
        match groups.iter_mut().find(|g| g.values == values) {
            Some(g) => g.cases.push(case.index),
            None => groups.push(Group {
                values,
                cases: vec![case.index],
            }),
        }
    }
    groups
}

/// The value combinations of the product of `axes`, in case order: the first axis outermost,
/// the last innermost (so a draws axis given last varies fastest). One empty combination
/// without axes.
pub(super) fn product(axes: &[Axis]) -> Vec<Vec<toml::Value>> {
    let mut combos = vec![Vec::new()];
    for axis in axes {
        combos = combos
            .into_iter()
            .flat_map(|c| {
                axis.values.iter().map(move |v| {
                    let mut next = c.clone();
                    next.push(v.clone());
                    next
                })
            })
            .collect();
    }
    combos
}

/// The overrides of a case of a study with overrides `set` and `axes` whose axis values are
/// `values`, and the study key behind each.
pub(super) fn overrides(
    set: &[(String, toml::Value)],
    axes: &[Axis],
    values: &[toml::Value],
) -> (Vec<String>, Vec<String>) {
    let set = set.iter().map(|(k, v)| (k, v, format!("set.\"{k}\"")));
    let axes = (axes.iter().zip(values)).flat_map(|(a, v)| {
        let main = (&a.key, v, format!("axes.\"{}\"", a.key));
        let with =
            (a.companions(v)).map(|(k, w)| (k, w, format!("axes.\"{}\".with.\"{k}\"", a.key)));
        std::iter::once(main).chain(with)
    });
    set.chain(axes)
        .map(|(key, value, source)| (format!("{key}={}", toml_text(value)), source))
        .unzip()
}

/// A value as a table cell or label: a string's text, any other value as [`toml_text`].
pub(super) fn value_text(value: &toml::Value) -> String {
    match value {
        toml::Value::String(s) => s.clone(),
        v => toml_text(v),
    }
}

/// A value in TOML syntax, read back exactly: floats below 1e-3 or from 1e5 up in exponent
/// notation (`8e-7`, not `0.0000008`), also inside lists.
fn toml_text(value: &toml::Value) -> String {
    match value {
        toml::Value::Float(x) if x.is_finite() && *x != 0.0 && !(1e-3..1e5).contains(&x.abs()) => {
            format!("{x:e}")
        }
        toml::Value::Array(items) => {
            let items: Vec<String> = items.iter().map(toml_text).collect();
            format!("[{}]", items.join(", "))
        }
        v => v.to_string(),
    }
}

/// The folder of case `index` of `count` in the study output `out`: `out/cases/NNN`, numbered
/// from 0 with at least three digits.
pub fn case_dir(out: &Path, index: usize, count: usize) -> PathBuf {
    let width = count.saturating_sub(1).to_string().len().max(3);
    out.join("cases").join(format!("{index:0width$}"))
}

/// 16 hex digits: FNV-1a of the configuration as JSON (every key, defaults included, after the
/// overrides). Equal hashes mean the same configuration; the mesh file a config names is not
/// read, only its path.
pub fn config_hash(config: &Config) -> String {
    let json = serde_json::to_string(config).expect("the configuration serializes");
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for byte in json.bytes() {
        hash ^= u64::from(byte);
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{hash:016x}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn axis(key: &str, values: &[toml::Value]) -> Axis {
        Axis {
            key: key.into(),
            values: values.to_vec(),
            draws: false,
            with: Vec::new(),
        }
    }

    #[test]
    fn cases_are_the_product_with_the_last_axis_innermost() {
        use toml::Value::{Boolean, Float, Integer, String as Text};
        let axes = [
            axis("adapt.min_edge", &[Float(5e-6), Float(3e-6)]),
            axis("fracture.seed", &[Integer(1), Integer(2), Integer(3)]),
        ];
        let combos = product(&axes);
        assert_eq!(combos.len(), 6);
        assert_eq!(combos[1], [Float(5e-6), Integer(2)]);
        assert_eq!(combos[3], [Float(3e-6), Integer(1)]);
        assert_eq!(product(&[]), [Vec::<toml::Value>::new()]);
        assert_eq!(
            label(&axes, &combos[4]),
            "adapt.min_edge=3e-6, fracture.seed=2"
        );
        let list = toml::Value::Array(vec![
            Float(4e7),
            Float(0.0),
            Float(0.25),
            Float(f64::INFINITY),
        ]);
        assert_eq!(toml_text(&list), "[4e7, 0.0, 0.25, inf]");
        // Overrides in TOML syntax: strings quoted, floats exact.
        let axes = [
            axis("mesh.diagonal", &[Text("right".into())]),
            axis("x", &[Float(0.1)]),
        ];
        let set = [("output.png".to_string(), Boolean(false))];
        let (specs, sources) = overrides(&set, &axes, &[Text("right".into()), Float(0.1)]);
        assert_eq!(
            specs,
            ["output.png=false", "mesh.diagonal=\"right\"", "x=0.1"]
        );
        assert_eq!(sources[1], "axes.\"mesh.diagonal\"");
        // Keys that go with an axis take the value at its value's place.
        let mut load = axis("loading.load_ratio", &[Float(0.1), Float(0.5)]);
        load.with = vec![("mesh.width".into(), vec![Float(4e-3), Float(2e-3)])];
        let (specs, sources) = overrides(&[], &[load], &[Float(0.5)]);
        assert_eq!(specs, ["loading.load_ratio=0.5", "mesh.width=0.002"]);
        assert_eq!(
            sources[1],
            "axes.\"loading.load_ratio\".with.\"mesh.width\""
        );
        assert_eq!(case_dir(Path::new("o"), 7, 16), Path::new("o/cases/007"));
        assert_eq!(case_dir(Path::new("o"), 7, 1001), Path::new("o/cases/0007"));
    }
}
