//! `[fracture]`: cracks that grow from the tips of existing cracks along the directions of
//! largest effective traction (seed 4.3.2), on mesh edges aligned with those directions.

use serde::{Deserialize, Serialize};

use sdg_solver::nucleation::DefectStrengths;

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
    /// Where no split may be made (a piece would be shorter than `min_piece`), the crack takes
    /// an existing edge of the tip's triangle within this angle of its direction, degrees in
    /// (0, 90]. Default half the shield angle; with 90, a tip takes the nearer end of the
    /// crossed edge that points forward and is shielded: it does not stand still while the
    /// mesh is at its floor.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor_angle: Option<f64>,
    /// A tip's forward half is taken about its crack's direction averaged over about this
    /// length, m (> 0): each new edge of length `l` weighs `1 - exp(-l / tangent_length)`
    /// against the direction before it. Default none: about the last edge alone, so that on the
    /// finest grid, whose edges are 45 degrees apart, a tip may turn 45 degrees at every edge
    /// and curl onto its own crack.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tangent_length: Option<f64>,
    /// A crack surface tip's criterion reads the stress averaged over a segment of this length
    /// from the tip, m (> 0), in each direction, instead of the stress at the tip: a point
    /// value in the tip's singular field grows without bound as the mesh is refined, a mean
    /// over a fixed length converges. The segment stops where it meets a crack or the
    /// boundary. Default none: the stress at the tip (the seed's radius `0+`). Nucleation
    /// stays a test of the stress at a point.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub criterion_length: Option<f64>,
    /// The fastest a crack surface tip may advance, as a fraction of the Rayleigh speed `c_R`
    /// (> 0, default 1; `inf`: the seed's rule, one edge at every tent of the tip). A tip
    /// extends only when its new edge's length over the time since the tip reached its vertex
    /// is at most this speed; until then it waits for its next tent. Without it, a tip in
    /// material loaded above `threshold` (around a nucleation) makes an edge at every tent, at
    /// the mesh's pace `h / dt` rather than any crack's.
    #[serde(default = "default_max_tip_speed")]
    pub max_tip_speed: f64,
    /// No split for a crack leaves a piece of an edge shorter than this, m (> 0). Default
    /// `adapt.min_edge`, or without `[adapt]` a quarter of the initial mesh's shortest edge.
    /// Below `adapt.min_edge` the crack may split triangles the indicator no longer refines,
    /// so that its direction, not the grid's, decides where it runs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_piece: Option<f64>,
    /// Nucleation from random defects (seed 4.3.1): defects per unit area, 1/m^2 (> 0). Without
    /// it no crack nucleates; with it `defect_mean`, `defect_std` and `defect_lower` are
    /// required.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub defect_density: Option<f64>,
    /// Mean defect strength, Pa.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub defect_mean: Option<f64>,
    /// Standard deviation of the defect strengths before truncation, Pa.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub defect_std: Option<f64>,
    /// Lower bound of the defect strengths (the truncation point), Pa.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub defect_lower: Option<f64>,
    /// Seed of the defect draws (default 0).
    #[serde(default)]
    pub seed: u64,
    /// Defects also nucleate cracks at vertices on the boundary and on cracks, running one way
    /// into the material (seed 4.3.2: anywhere in the closure of the domain). Default false:
    /// only at interior vertices on no crack.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub surface_nucleation: bool,
    /// Reach along crack edges that two arms of a fork (besides the one the crack came in by)
    /// must have for `summary.json` to report it as the first macro branching, m (> 0). Only
    /// the report uses it; without it none is reported.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub macro_length: Option<f64>,
    /// The same reach for a second, shorter report, `fracture.short_macro_branching`, m (> 0):
    /// a fork whose arms reach this and no further (one arm arrested) counts there and not in
    /// the macro one. Only the report uses it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub short_macro_length: Option<f64>,
}

impl FractureConfig {
    /// The defect strengths, when nucleation is on; `(key, reason)` for a missing or invalid
    /// defect setting.
    pub fn defects(&self) -> Result<Option<(f64, DefectStrengths)>, (String, String)> {
        let key = |k: &str| format!("fracture.{k}");
        let keys = [
            ("defect_mean", self.defect_mean),
            ("defect_std", self.defect_std),
            ("defect_lower", self.defect_lower),
        ];
        let Some(density) = self.defect_density else {
            return match keys.iter().find(|(_, v)| v.is_some()) {
                Some((k, _)) => Err((key(k), "needs fracture.defect_density".into())),
                None => Ok(None),
            };
        };
        if !(density.is_finite() && density > 0.0) {
            return Err((
                key("defect_density"),
                format!("must be a positive number of defects per m^2, got {density}"),
            ));
        }
        let [mean, std, lower] = keys.map(|(k, v)| {
            v.ok_or_else(|| {
                (
                    key(k),
                    "is required with fracture.defect_density".to_string(),
                )
            })
        });
        let strengths =
            DefectStrengths::new(mean?, std?, lower?).map_err(|e| (key(e.key), e.reason))?;
        Ok(Some((density, strengths)))
    }
}

fn default_snap() -> f64 {
    0.2
}

fn default_max_tip_speed() -> f64 {
    1.0
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
        assert_eq!(
            (f.snap, f.from.len(), f.surface_nucleation),
            (0.2, 1, false)
        );
        let c = parse(
            &format!("{BASE}{FRACTURE}"),
            &["fracture.surface_nucleation=true"],
        )
        .unwrap();
        assert!(c.fracture.unwrap().surface_nucleation);
        let length = |sets: &[&str]| {
            let c = parse(&format!("{BASE}{FRACTURE}"), sets).unwrap();
            c.fracture.unwrap().criterion_length
        };
        assert_eq!(length(&[]), None);
        assert_eq!(length(&["fracture.criterion_length=9.4e-6"]), Some(9.4e-6));
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
            (
                "fracture.macro_length=0.0",
                "fracture.macro_length",
                "positive length",
            ),
            ("fracture.snap=0.0", "fracture.snap", "(0, 0.5]"),
            (
                "fracture.floor_angle=90.5",
                "fracture.floor_angle",
                "(0, 90]",
            ),
            (
                "fracture.floor_angle=-5.0",
                "fracture.floor_angle",
                "(0, 90]",
            ),
            (
                "fracture.max_tip_speed=0.0",
                "fracture.max_tip_speed",
                "fraction of the Rayleigh speed",
            ),
            (
                "fracture.min_piece=-1e-6",
                "fracture.min_piece",
                "positive length",
            ),
            (
                "fracture.tangent_length=0.0",
                "fracture.tangent_length",
                "positive length",
            ),
            (
                "fracture.criterion_length=0.0",
                "fracture.criterion_length",
                "positive length",
            ),
            (
                "fracture.criterion_length=-1e-6",
                "fracture.criterion_length",
                "positive length",
            ),
            (
                "fracture.criterion_length=nan",
                "fracture.criterion_length",
                "positive length",
            ),
            (
                "fracture.criterion_length=inf",
                "fracture.criterion_length",
                "positive length",
            ),
            (
                "fracture.defect_mean=3e8",
                "fracture.defect_mean",
                "defect_density",
            ),
            (
                "fracture.defect_density=1e9",
                "fracture.defect_mean",
                "required",
            ),
            (
                "fracture.defect_density=-1.0",
                "fracture.defect_density",
                "positive",
            ),
        ] {
            let e = parse(&text, &[set]).unwrap_err();
            assert_eq!(e.key.as_deref(), Some(key), "{set}: {e}");
            assert!(e.reason.contains(words), "{set}: {e}");
        }
        let defects = [
            "fracture.defect_density=1e9",
            "fracture.defect_mean=3.1e8",
            "fracture.defect_std=6.2e7",
        ];
        for (set, key) in [
            ("fracture.defect_lower=4e8", "fracture.defect_lower"),
            ("fracture.defect_lower=2.5e7", ""),
        ] {
            let mut sets = defects.to_vec();
            sets.push(set);
            match parse(&text, &sets) {
                Ok(c) => assert!(key.is_empty() && c.fracture.unwrap().defect_density.is_some()),
                Err(e) => assert_eq!(e.key.as_deref(), Some(key), "{e}"),
            }
        }
        let cracked = text.replace("c0 = 0.8\n", "c0 = 0.8\ninitial_damage = 1.0\n");
        let e = parse(&cracked, &[]).unwrap_err();
        assert_eq!(e.key.as_deref(), Some("fracture.tag"), "{e}");
        assert!(e.reason.contains("initial_damage"), "{e}");
    }
}
