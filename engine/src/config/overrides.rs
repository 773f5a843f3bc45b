//! `--set KEY=VALUE` overrides, applied to the TOML tree before the schema reads it.

use super::ConfigError;

/// Applies one `key.path=value` override to the config's `root` table. The value is read as a
/// TOML value (`3`, `1e-6`, `true`, `"text"`, `[0.0, 1.0]`), or as a string when it is not one;
/// the schema then checks its type like any other key. A number in the path selects an entry
/// of an array of tables: `interface.0.r_c`.
pub(super) fn apply_override(root: &mut toml::Value, spec: &str) -> Result<(), ConfigError> {
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
    for (i, key) in keys.iter().enumerate() {
        node = entry(node, key).map_err(|reason| err(&keys[..i], reason))?;
    }
    *node = value;
    Ok(())
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
