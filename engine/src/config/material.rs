//! `[material]`: the bulk material and the 2D mode of elasticity.

use serde::{Deserialize, Serialize};

use sdg_solver::{Material, Plane};

use super::{Config, ConfigError};

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

impl Config {
    /// The material, validated.
    pub fn material(&self) -> Result<Material, ConfigError> {
        let m = &self.material;
        let plane = match m.plane {
            PlaneName::Strain => Plane::Strain,
            PlaneName::Stress => Plane::Stress,
            PlaneName::Antiplane => Plane::Antiplane,
        };
        Material::new(m.young, m.poisson, m.density, plane).map_err(|e| ConfigError {
            file: String::new(),
            key: Some(format!("material.{}", e.field())),
            reason: e
                .to_string()
                .split_once(": ")
                .map_or(e.to_string(), |(_, r)| r.to_string()),
        })
    }
}
