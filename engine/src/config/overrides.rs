//! `--set KEY=VALUE` overrides, applied to the TOML tree before the schema reads it.

use super::ConfigError;

/// Applies one `key.path=value` override to the config's `root` table. The value is read as a
/// TOML value (`3`, `1e-6`, `true`, `"text"`, `[0.0, 1.0]`), or as a string when it is not one;
/// the schema then checks its type like any other key. A number in the path selects an entry
/// of an array of tables that exists: `interface.0.r_c`. Returns the key path (as errors spell
/// it) of the outermost table the override added, if it added one: an error there is the
/// override's.
pub(super) fn apply_override(
    root: &mut toml::Value,
    spec: &str,
) -> Result<Option<String>, ConfigError> {
    let source = format!("--set {spec}");
    let err = |key: &[&str], reason: String| ConfigError {
        file: source.clone(),
        key: (!key.is_empty()).then(|| key.join(".")),
        reason,
    };
    let (path, raw) = spec
        .split_once('=')
        .ok_or_else(|| err(&[], "expected KEY=VALUE".into()))?;
    let path = path.trim();
    let keys: Vec<&str> = path.split('.').collect();
    if keys.iter().any(|k| k.is_empty()) {
        return Err(err(&[], "the key path has an empty segment".into()));
    }
    let value = toml::from_str::<toml::Table>(&format!("v = {raw}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(raw.to_string()));
    let mut node = root;
    let mut added = None;
    for (i, key) in keys.iter().enumerate() {
        let missing = matches!(&*node, toml::Value::Table(t) if !t.contains_key(*key));
        if missing && keys.get(i + 1).is_some_and(|k| k.parse::<usize>().is_ok()) {
            return Err(err(
                &keys[..=i],
                "is not in the config: an override sets keys of list entries the config has, \
                 it does not add entries"
                    .into(),
            ));
        }
        if missing && added.is_none() {
            added = Some(dotted(&keys[..=i].join(".")));
        }
        node = entry(node, key).map_err(|reason| err(&keys[..i], reason))?;
    }
    *node = value;
    Ok(added)
}

/// `error` blamed on the last override that added a table containing its key (`added`: each
/// override with the key path [`apply_override`] returned), unless it already names one.
pub(super) fn attribute_added(mut error: ConfigError, added: &[(&str, String)]) -> ConfigError {
    let Some(key) = error.key.clone() else {
        return error;
    };
    if error.file.starts_with("--set ") {
        return error;
    }
    let culprit = added.iter().rev().find(|(_, path)| is_within(&key, path));
    if let Some((spec, _)) = culprit {
        error.file = format!("--set {spec}");
    }
    error
}

/// `error` (from the file after the overrides were applied) blamed on the last override that set
/// its key, or a table or list containing it: its source becomes `--set KEY=VALUE`. Errors of
/// keys no override set keep naming the file.
pub fn attribute(mut error: ConfigError, overrides: &[String]) -> ConfigError {
    let Some(key) = error.key.clone() else {
        return error;
    };
    let culprit = overrides.iter().rev().find_map(|spec| {
        let path = dotted(spec.split_once('=')?.0.trim());
        is_within(&key, &path).then_some(spec)
    });
    if let Some(spec) = culprit {
        error.file = format!("--set {spec}");
    }
    error
}

/// True when error key `key` is `path` or a key inside it (`adapt.tol`, `interface[0].r_c`
/// inside `adapt`, `interface`).
fn is_within(key: &str, path: &str) -> bool {
    key.strip_prefix(path)
        .is_some_and(|rest| rest.is_empty() || rest.starts_with(['.', '[']))
}

/// An override's key path as error keys spell it: `interface.0.r_c` is `interface[0].r_c`.
fn dotted(path: &str) -> String {
    let mut out = String::new();
    for segment in path.split('.') {
        if segment.parse::<usize>().is_ok() {
            out.push_str(&format!("[{segment}]"));
        } else {
            if !out.is_empty() {
                out.push('.');
            }
            out.push_str(segment);
        }
    }
    out
}

/// The entry `key` of a table (a new empty table when missing) or of an array (`key` an index
/// below its length), or why `node` has none.
fn entry<'a>(node: &'a mut toml::Value, key: &str) -> Result<&'a mut toml::Value, String> {
    match node {
        toml::Value::Table(table) => Ok(table
            .entry(key.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))),
        toml::Value::Array(array) => {
            let len = array.len();
            key.parse::<usize>()
                .ok()
                .and_then(|k| array.get_mut(k))
                .ok_or_else(|| {
                    format!("is a list of {len} entries; `{key}` is not an index below {len}")
                })
        }
        _ => Err("is a value, not a table".into()),
    }
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use crate::config::DiagonalName;
    use crate::config::tests::{BASE, parse};

    #[test]
    fn errors_of_overridden_keys_name_the_override() {
        let e = parse(BASE, &["mesh.nx=0"]).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("--set mesh.nx=0: mesh.nx: must be at least 1"),
            "{e}"
        );
        let e = parse(BASE, &["pitch.safety=1.5", "mesh.ny=8"]).unwrap_err();
        assert_eq!(e.file, "--set pitch.safety=1.5");
        // A table set whole: the key inside it stays in the message.
        let e = parse(BASE, &["adapt={tol = -1.0}"]).unwrap_err();
        assert_eq!(
            (e.file.as_str(), e.key.as_deref()),
            ("--set adapt={tol = -1.0}", Some("adapt.tol"))
        );
        // A type error of an overridden key.
        let e = parse(BASE, &["mesh.nx=many"]).unwrap_err();
        assert_eq!(e.file, "--set mesh.nx=many");
        // An error in a key no override set names the file.
        let e = parse(&BASE.replace("nx = 16", "nx = 0"), &["mesh.ny=8"]).unwrap_err();
        assert_eq!(e.key.as_deref(), Some("mesh.nx"));
        assert!(!e.file.starts_with("--set"), "{e}");
        assert_eq!(super::dotted("interface.0.r_c"), "interface[0].r_c");
        // A table the override added: an unknown one is the override's, not the file's.
        let e = parse(BASE, &["foo.bar=1"]).unwrap_err();
        assert_eq!(
            (e.file.as_str(), e.key.as_deref()),
            ("--set foo.bar=1", Some("foo"))
        );
        // An entry of a list the config does not have.
        let e = parse(BASE, &["adapt.zone.0.radius=-1"]).unwrap_err();
        assert_eq!(e.file, "--set adapt.zone.0.radius=-1");
        assert_eq!(e.key.as_deref(), Some("adapt.zone"));
        assert!(e.reason.contains("does not add entries"), "{e}");
    }

    #[test]
    fn defaults_and_overrides() {
        let c = parse(BASE, &[]).unwrap();
        assert_eq!(c.pitch.safety, 0.9);
        assert_eq!(c.output.dir, PathBuf::from("out"));
        let c = parse(
            BASE,
            &[
                "mesh.nx=32",
                "pitch.safety=0.5",
                "output.dir=runs/a",
                "mesh.diagonal=right",
            ],
        )
        .unwrap();
        assert_eq!(c.mesh.nx, Some(32));
        assert_eq!(c.pitch.safety, 0.5);
        assert_eq!(c.output.dir, PathBuf::from("runs/a"));
        assert_eq!(c.mesh.diagonal, Some(DiagonalName::Right));
        let c = parse(
            BASE,
            &[
                "mesh.interface.from=[0.0, 0.005]",
                "mesh.interface.to=[0.002, 0.005]",
            ],
        )
        .unwrap();
        assert_eq!(c.mesh.interface.len(), 1);
        assert_eq!(c.mesh.interface[0].tag, "interface");
        assert_eq!(c.solver.newton_tol, 1e-10);
        assert_eq!(c.solver.newton_max_iter, 30);
        assert!(c.interface.is_empty() && c.output.interface_probes.is_empty());
    }
}
