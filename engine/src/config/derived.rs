//! What a configuration implies beyond its keys: the material, the rectangle, the load scales
//! and the boundary conditions of `[loading]`.

use sdg_solver::interface::Law;
use sdg_solver::{Material, Plane};

use super::conditions::{BoundaryConfig, BoundaryKind, HistoryConfig, HistoryKind};
use super::error::ConfigError;
use super::loading::LoadScales;
use super::material::PlaneName;
use super::mesh::DiagonalName;
use super::schema::Config;

impl Config {
    /// The material, validated.
    pub fn material(&self) -> Result<Material, ConfigError> {
        let m = &self.material;
        let plane = match m.plane {
            PlaneName::Strain => Plane::Strain,
            PlaneName::Stress => Plane::Stress,
            PlaneName::Antiplane => Plane::Antiplane,
        };
        let material =
            Material::new(m.young, m.poisson, m.density, plane).map_err(|e| ConfigError {
                file: String::new(),
                key: Some(format!("material.{}", e.field())),
                reason: e
                    .to_string()
                    .split_once(": ")
                    .map_or(e.to_string(), |(_, r)| r.to_string()),
            })?;
        // Each value in range, the wave speeds and impedances may still over- or underflow.
        let (c_d, c_s) = (material.c_d(), material.c_s());
        let speeds = [c_d, c_s, m.density * c_d, m.density * c_s];
        if !speeds.iter().all(|x| x.is_finite() && *x > 0.0) {
            return Err(ConfigError {
                file: String::new(),
                key: Some("material".into()),
                reason: format!(
                    "young = {:e} Pa over density = {:e} kg/m^3 gives wave speeds c_d = {c_d:e} \
                     m/s, c_s = {c_s:e} m/s: they and the impedances must be positive and finite",
                    m.young, m.density
                ),
            });
        }
        Ok(material)
    }
}

impl Config {
    /// The rectangle generator's parameters; missing keys read as zero (validation rejects them).
    pub fn rectangle(&self) -> sdg_mesh::Rectangle {
        let m = &self.mesh;
        sdg_mesh::Rectangle {
            width: m.width.unwrap_or(0.0),
            height: m.height.unwrap_or(0.0),
            nx: m.nx.unwrap_or(0),
            ny: m.ny.unwrap_or(0),
            diagonal: match m.diagonal.unwrap_or_default() {
                DiagonalName::Right => sdg_mesh::Diagonal::Right,
                DiagonalName::Left => sdg_mesh::Diagonal::Left,
                DiagonalName::Alternate => sdg_mesh::Diagonal::Alternate,
            },
            interfaces: m
                .interface
                .iter()
                .map(|i| sdg_mesh::GridSegment {
                    from: i.from,
                    to: i.to,
                    tag: i.tag.clone(),
                })
                .collect(),
            sides: m
                .side
                .iter()
                .map(|s| sdg_mesh::GridSegment {
                    from: s.from,
                    to: s.to,
                    tag: s.tag.clone(),
                })
                .collect(),
            perturb: m.perturb.unwrap_or(0.0),
            seed: m.seed.unwrap_or(0),
        }
    }
}

impl Config {
    /// The law of the `[[interface]]` entry that names `tag`, if one does.
    pub fn law_of(&self, tag: &str) -> Option<Law> {
        (self.interface.iter())
            .find(|i| i.tags.iter().any(|t| t == tag))
            .map(|i| i.law.law())
    }

    /// The scales of `[loading]`, if any; `(key, reason)` when the section is invalid.
    pub fn load_scales(&self) -> Result<Option<LoadScales>, (String, String)> {
        let Some(l) = &self.loading else {
            return Ok(None);
        };
        let fail = |key: &str, reason: String| Err((format!("loading.{key}"), reason));
        if !(l.load_ratio > 0.0 && l.load_ratio <= 1.0) {
            return fail(
                "load_ratio",
                format!(
                    "must be in (0, 1]: above 1 the bulk load exceeds the strength, got {}",
                    l.load_ratio
                ),
            );
        }
        if !(l.compare_from.is_finite() && l.compare_from > 0.0) {
            return fail(
                "compare_from",
                format!(
                    "must be a positive normalized time t', got {}",
                    l.compare_from
                ),
            );
        }
        let Some(Law::XuNeedleman(cohesive)) = self.law_of(&l.interface) else {
            return fail(
                "interface",
                format!(
                    "`{}` must be the tag of an [[interface]] with law = \"xu_needleman\"",
                    l.interface
                ),
            );
        };
        if l.sides.is_empty() {
            return fail("sides", "lists no side".into());
        }
        if let Some(side) = l
            .sides
            .iter()
            .find(|s| self.boundary.iter().any(|b| b.sides.contains(s)))
        {
            return fail(
                "sides",
                format!("side `{side}` has a [[boundary]] condition already"),
            );
        }
        let material = self
            .material()
            .map_err(|e| (e.key.unwrap_or_default(), e.reason))?;
        let sigma_bar = l.load_ratio * cohesive.strength;
        let phi = std::f64::consts::E * cohesive.strength * cohesive.critical_separation;
        let tau = std::f64::consts::PI * material.mu() * phi * material.c_d()
            / (4.0 * (material.c_s() * sigma_bar).powi(2));
        Ok(Some(LoadScales {
            load_ratio: l.load_ratio,
            sigma_bar,
            tau,
            work_of_separation: phi,
            c_r: material.c_r(),
        }))
    }

    /// The boundary conditions: each `[[boundary]]` entry with its key prefix, then the
    /// transmitting sides of `[loading]` (prefix `loading`), whose scales must be valid.
    pub fn boundaries(&self) -> Vec<(String, BoundaryConfig)> {
        let mut all: Vec<(String, BoundaryConfig)> = self
            .boundary
            .iter()
            .enumerate()
            .map(|(i, b)| (format!("boundary[{i}]"), b.clone()))
            .collect();
        if let (Some(l), Ok(Some(scales))) = (&self.loading, self.load_scales()) {
            all.push((
                "loading".into(),
                BoundaryConfig {
                    sides: l.sides.clone(),
                    kind: BoundaryKind::Transmitting,
                    value: None,
                    incoming: Some(vec![scales.sigma_bar, 0.0]),
                    history: Some(HistoryConfig {
                        kind: HistoryKind::Smooth,
                        ramp: Some(scales.tau),
                        points: None,
                    }),
                },
            ));
        }
        all
    }
}
