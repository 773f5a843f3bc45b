//! `[fracture]`: cracks that grow from the tips of existing cracks along the directions of
//! largest effective traction (seed 4.3.2), on mesh edges aligned with those directions.

use serde::{Deserialize, Serialize};

use sdg_solver::interface::Law;

use super::Config;

/// `[fracture]`: crack propagation.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FractureConfig {
    /// Tag that new crack edges take: an `[[interface]]` tag with `law = "damage"` and no
    /// initial damage. It need not be on any edge at t = 0.
    pub tag: String,
    /// Interface tags whose crack ends are tips at t = 0 (besides `tag`): an interior vertex on
    /// exactly one edge of these tags is a tip, travelling along that edge.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub from: Vec<String>,
    /// Propagation threshold `sigma0_d`, Pa (> 0): a tip extends along a direction whose
    /// effective traction is a tensile local maximum above it.
    pub threshold: f64,
    /// Shield angle `theta_S`, degrees in (0, 90): two crack edges meeting at a vertex are at
    /// least this far apart in angle.
    pub shield_angle: f64,
    /// Where a direction crosses the opposite edge of the tip's triangle closer than this
    /// fraction of that edge to one of its ends, the crack takes the existing edge to that end
    /// instead of splitting (default 0.2, in (0, 0.5]).
    #[serde(default = "default_snap")]
    pub snap: f64,
}

fn default_snap() -> f64 {
    0.2
}

impl Config {
    /// Checks `[fracture]`: `(key, reason)`.
    pub(super) fn validate_fracture(&self) -> Result<(), (String, String)> {
        let Some(f) = &self.fracture else {
            return Ok(());
        };
        let fail = |key: &str, reason: String| Err((format!("fracture.{key}"), reason));
        let law_of = |tag: &str| {
            self.interface
                .iter()
                .find(|i| i.tags.iter().any(|t| t == tag))
                .and_then(|i| i.to_law().ok())
        };
        match law_of(&f.tag) {
            Some(Law::Damage(d)) if d.initial == 0.0 => {}
            _ => {
                return fail(
                    "tag",
                    format!(
                        "`{}` must be the tag of an [[interface]] with law = \"damage\" and no \
                         initial_damage: new crack edges start bonded",
                        f.tag
                    ),
                );
            }
        }
        for (i, tag) in f.from.iter().enumerate() {
            if !matches!(law_of(tag), Some(Law::Damage(_) | Law::Free)) {
                return fail(
                    &format!("from[{i}]"),
                    format!(
                        "`{tag}` must be the tag of an [[interface]] with law = \"damage\" or \
                         \"free\": a crack"
                    ),
                );
            }
        }
        if !(f.threshold.is_finite() && f.threshold > 0.0) {
            return fail(
                "threshold",
                format!("must be a positive stress in Pa, got {}", f.threshold),
            );
        }
        if !(f.shield_angle > 0.0 && f.shield_angle < 90.0) {
            return fail(
                "shield_angle",
                format!("must be in (0, 90) degrees, got {}", f.shield_angle),
            );
        }
        if !(f.snap > 0.0 && f.snap <= 0.5) {
            return fail(
                "snap",
                format!("must be a fraction of an edge in (0, 0.5], got {}", f.snap),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::config::tests::{BASE, parse};

    /// A notch (free) and the damage law of new crack edges.
    const FRACTURE: &str = r#"
[[mesh.interface]]
from = [0.0, 0.005]
to = [0.004, 0.005]
tag = "notch"

[[interface]]
tags = ["notch"]
law = "free"

[[interface]]
tags = ["crack"]
law = "damage"
strength = 62.1e6
delay = 1e-8
a = 10.0
c0 = 0.8
friction = 0.0
r_c = -1e-6
r_s = 0.0
s_c = 0.0
s_s = 6e5

[fracture]
tag = "crack"
from = ["notch"]
threshold = 4.47e7
shield_angle = 35.0
"#;

    #[test]
    fn a_valid_section_loads() {
        let c = parse(&format!("{BASE}{FRACTURE}"), &[]).unwrap();
        let f = c.fracture.unwrap();
        assert_eq!((f.snap, f.from.len()), (0.2, 1));
    }

    #[test]
    fn bad_settings_name_the_key() {
        let text = format!("{BASE}{FRACTURE}");
        for (set, key, words) in [
            ("fracture.tag=\"notch\"", "fracture.tag", "law = \"damage\""),
            ("fracture.tag=\"nowhere\"", "fracture.tag", "`nowhere`"),
            (
                "fracture.from=[\"crack\", \"x\"]",
                "fracture.from[1]",
                "`x`",
            ),
            ("fracture.threshold=0.0", "fracture.threshold", "positive"),
            ("fracture.threshold=nan", "fracture.threshold", "positive"),
            (
                "fracture.shield_angle=90.0",
                "fracture.shield_angle",
                "(0, 90)",
            ),
            (
                "fracture.shield_angle=-5.0",
                "fracture.shield_angle",
                "(0, 90)",
            ),
            ("fracture.snap=0.6", "fracture.snap", "(0, 0.5]"),
            ("fracture.snap=0.0", "fracture.snap", "(0, 0.5]"),
        ] {
            let e = parse(&text, &[set]).unwrap_err();
            assert_eq!(e.key.as_deref(), Some(key), "{set}: {e}");
            assert!(e.reason.contains(words), "{set}: {e}");
        }
        let cracked = text.replace("c0 = 0.8\n", "c0 = 0.8\ninitial_damage = 1.0\n");
        let e = parse(&cracked, &[]).unwrap_err();
        assert_eq!(e.key.as_deref(), Some("fracture.tag"), "{e}");
        assert!(e.reason.contains("initial_damage"), "{e}");
    }
}
