//! `[loading]`: the mode-I load of seed 2.5 given by its load ratio.
//!
//! Equal tensile plane waves enter through the transmitting sides `sides` and meet on the
//! crack plane. The load ratio `sigma' = sigma_bar / sigma_c` (2.59), with `sigma_bar = 2 s_inf`
//! the stress the two waves carry together and `sigma_c` the strength of the cohesive interface
//! `interface`, fixes the incoming characteristic `w = 2 s_inf = sigma_bar` of each wave and the
//! ramp time `tau' = pi mu phi c_d / (4 (c_s sigma_bar)^2)` (2.67), over which the waves are
//! ramped by `3 t'^2 - 2 t'^3` (2.71); `phi = e sigma_c delta_c` is the work of separation.

use serde::{Deserialize, Serialize};

/// `[loading]`: a mode-I load from its load ratio.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LoadingConfig {
    /// Load ratio `sigma' = sigma_bar / sigma_c`, in (0, 1].
    pub load_ratio: f64,
    /// Tag of the Xu-Needleman interface whose strength and work of separation scale the load
    /// (an in-plane law: the material is in plane strain or stress).
    pub interface: String,
    /// The sides the waves enter through (transmitting; not named by a `[[boundary]]`).
    pub sides: Vec<String>,
    /// Normalized time `t'` (> 0) from which `summary.json`'s `lefm` compares the tip with
    /// LEFM and measures the energy released per unit extension. Only the report uses it.
    #[serde(default = "default_compare_from")]
    pub compare_from: f64,
}

/// `compare_from`'s default: from `t' = 3`, where the seed compares its tips with LEFM
/// (Fig. 2.6).
fn default_compare_from() -> f64 {
    3.0
}

/// The scales of a `[loading]`: SI units.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct LoadScales {
    /// `sigma'`.
    pub load_ratio: f64,
    /// `sigma_bar = sigma' sigma_c`, Pa: the incoming characteristic of each wave.
    pub sigma_bar: f64,
    /// `tau'`, s: the ramp time and the unit of normalized time.
    #[serde(rename = "tau_prime")]
    pub tau: f64,
    /// Work of separation `phi = e sigma_c delta_c`, J/m^2.
    pub work_of_separation: f64,
    /// Rayleigh wave speed `c_R`, m/s: with `tau'`, the unit `tau' c_R` of normalized length.
    pub c_r: f64,
}

#[cfg(test)]
mod tests {
    use super::super::tests::{BASE, parse};

    const LOADED: &str = r#"
[[mesh.interface]]
from = [0.0, 0.005]
to = [0.016, 0.005]
tag = "path"

[[interface]]
tags = ["path"]
law = "xu_needleman"
strength = 3.24e8
critical_separation = 4e-7

[[boundary]]
sides = ["left", "right"]
kind = "roller"

[loading]
load_ratio = 0.1
interface = "path"
sides = ["bottom", "top"]
"#;

    #[test]
    fn the_load_ratio_gives_the_seed_s_amplitude_and_ramp() {
        let config = parse(&format!("{BASE}{LOADED}"), &[]).unwrap();
        let s = config.load_scales().unwrap().unwrap();
        // PMMA, sigma_c = 0.1 E, delta_c = 4e-4 mm (seed 2.5.3): sigma_bar = 32.4 MPa and
        // tau' = 0.6557 us.
        assert!((s.sigma_bar - 3.24e7).abs() < 1e-6);
        assert!((s.tau / 6.5565e-7 - 1.0).abs() < 2e-4, "{}", s.tau);
        assert!((s.work_of_separation - 352.3).abs() < 0.1);
        let (key, b) = config.boundaries().pop().unwrap();
        assert_eq!(key, "loading");
        assert_eq!(b.sides, ["bottom", "top"]);
        assert_eq!(b.incoming, Some(vec![3.24e7, 0.0]));
        assert_eq!(b.history.unwrap().ramp, Some(s.tau));
    }

    #[test]
    fn bad_loading_is_rejected_with_its_key() {
        let text = format!("{BASE}{LOADED}");
        for (set, key, reason) in [
            ("loading.load_ratio=0", "loading.load_ratio", "(0, 1]"),
            ("loading.load_ratio=1.5", "loading.load_ratio", "(0, 1]"),
            ("loading.compare_from=0", "loading.compare_from", "positive"),
            (
                "loading.interface=\"crack\"",
                "loading.interface",
                "xu_needleman",
            ),
            ("loading.sides=[\"left\"]", "loading.sides", "already"),
            ("loading.sides=[]", "loading.sides", "no side"),
        ] {
            let e = parse(&text, &[set]).unwrap_err();
            assert_eq!(e.key.as_deref(), Some(key), "{set}: {e}");
            assert!(e.reason.contains(reason), "{set}: {e}");
        }
    }
}
