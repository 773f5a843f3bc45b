//! `[material]`: the bulk material and the 2D mode of elasticity.

use serde::{Deserialize, Serialize};

/// The 2D mode of elasticity.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum PlaneName {
    /// Plane strain.
    Strain,
    /// Plane stress.
    Stress,
    /// Anti-plane shear.
    Antiplane,
}

/// `[material]`: an isotropic linear elastic material.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialConfig {
    /// Young's modulus, Pa.
    pub young: f64,
    /// Poisson ratio, in (-1, 0.5).
    pub poisson: f64,
    /// Mass density, kg/m^3.
    pub density: f64,
    /// `"strain"`, `"stress"` or `"antiplane"`.
    pub plane: PlaneName,
}

#[cfg(test)]
mod tests {
    use crate::config::tests::{BASE, parse};

    /// Found by `tests/fuzz_inputs.rs`: valid values whose wave speed is infinite or zero
    /// reached tent pitching, which failed at run time (exit 1).
    #[test]
    fn wave_speeds_out_of_range_are_rejected() {
        for set in [
            ["material.density=5e-324", "material.young=3.24e9"],
            ["material.density=1190.0", "material.young=5e-324"],
            ["material.density=1e-10", "material.young=1e308"],
        ] {
            let e = parse(BASE, &set).unwrap_err();
            assert_eq!(e.key.as_deref(), Some("material"), "{set:?}: {e}");
            assert!(e.reason.contains("wave speeds"), "{set:?}: {e}");
        }
        assert!(parse(BASE, &["material.young=1e300", "material.density=1e300"]).is_ok());
    }
}
