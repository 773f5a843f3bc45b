//! Problem setup: the space mesh, material, boundary conditions and exact solution a
//! configuration describes.

use sdg_mesh::Mesh;
use sdg_solver::Material;
use sdg_solver::boundary::{Boundary, Condition};
use sdg_solver::exact::{PlaneWave, Profile, Wave};
use sdg_solver::history::History;
use sdg_solver::system::System;

use crate::config::{
    BoundaryConfig, BoundaryKind, ConfigError, LoadedConfig, MeshKind, ProfileName, WaveName,
};
use crate::error::EngineError;

/// Everything a run needs that is derived from the configuration.
#[derive(Clone, Debug)]
pub struct Problem {
    /// The validated configuration and its file.
    pub loaded: LoadedConfig,
    /// The space mesh at the initial time.
    pub mesh: Mesh,
    /// The bulk material.
    pub material: Material,
    /// The scaled first-order system of the material.
    pub system: System,
    /// Boundary conditions per tag.
    pub boundary: Boundary,
    /// The exact solution, if configured.
    pub exact: Option<PlaneWave>,
}

impl Problem {
    /// Builds the mesh (generating it or reading the Gmsh file), the material, the boundary
    /// conditions and the exact solution; checks that every `[[boundary]]` side is a boundary
    /// tag of the mesh.
    pub fn setup(loaded: LoadedConfig) -> Result<Self, EngineError> {
        let config = &loaded.config;
        let file = loaded.file.display().to_string();
        let invalid = |key: String, reason: String| ConfigError {
            file: file.clone(),
            key: Some(key),
            reason,
        };
        let material = config.material().map_err(|e| ConfigError {
            file: file.clone(),
            ..e
        })?;
        let mesh = match config.mesh.kind {
            MeshKind::Rectangle => config
                .rectangle()
                .build()
                .map_err(|e| invalid(format!("mesh.{}", e.field), e.reason))?,
            MeshKind::Gmsh => {
                let path = config
                    .mesh
                    .path
                    .as_deref()
                    .expect("validated: gmsh has a path");
                sdg_mesh::read_msh(&loaded.resolve(path))
                    .map_err(|e| EngineError::Mesh(e.to_string()))?
            }
        };
        let exact = config
            .exact
            .as_ref()
            .map(|e| {
                let wave = match e.wave {
                    WaveName::P => Wave::P,
                    WaveName::S => Wave::S,
                };
                let profile = match e.profile {
                    ProfileName::Sine => Profile::Sine,
                    ProfileName::Pulse => Profile::Pulse,
                };
                PlaneWave::new(
                    &material,
                    wave,
                    e.angle_deg,
                    e.wavelength,
                    e.amplitude,
                    profile,
                    e.center,
                )
                .map_err(|err| invalid("exact".into(), err.to_string()))
            })
            .transpose()?;
        let mut by_tag = vec![None; mesh.tag_names().len()];
        for (i, b) in config.boundary.iter().enumerate() {
            for side in &b.sides {
                let tag = mesh
                    .tag_id(side)
                    .filter(|&t| {
                        mesh.edges()
                            .iter()
                            .any(|e| e.is_boundary() && e.tag == Some(t))
                    })
                    .ok_or_else(|| {
                        let known: Vec<&str> = boundary_tags(&mesh);
                        invalid(
                            format!("boundary[{i}].sides"),
                            format!("no boundary side is tagged `{side}`; the mesh has {known:?}"),
                        )
                    })?;
                by_tag[tag as usize] = Some(condition(b));
            }
        }
        Ok(Self {
            system: System::new(&material),
            boundary: Boundary::new(by_tag, exact.clone()),
            exact,
            loaded,
            mesh,
            material,
        })
    }
}

/// Tag names that occur on boundary edges.
fn boundary_tags(mesh: &Mesh) -> Vec<&str> {
    mesh.tag_names()
        .iter()
        .enumerate()
        .filter(|&(t, _)| {
            mesh.edges()
                .iter()
                .any(|e| e.is_boundary() && e.tag == Some(t as u16))
        })
        .map(|(_, n)| n.as_str())
        .collect()
}

/// The solver's condition for a validated `[[boundary]]` entry.
fn condition(b: &BoundaryConfig) -> Condition {
    let pair = |v: &Option<Vec<f64>>| {
        let v = v.as_deref().unwrap_or(&[]);
        [
            v.first().copied().unwrap_or(0.0),
            v.get(1).copied().unwrap_or(0.0),
        ]
    };
    let history = || {
        b.history.as_ref().map_or(History::Constant, |h| {
            h.to_history().expect("validated history")
        })
    };
    match b.kind {
        BoundaryKind::Free => Condition::Free,
        BoundaryKind::Roller => Condition::Roller,
        BoundaryKind::Exact => Condition::Exact,
        BoundaryKind::Traction => Condition::Traction {
            value: pair(&b.value),
            history: history(),
        },
        BoundaryKind::Velocity => Condition::Velocity {
            value: pair(&b.value),
            history: history(),
        },
        BoundaryKind::Transmitting => Condition::Transmitting {
            incoming: pair(&b.incoming),
            history: history(),
        },
    }
}
