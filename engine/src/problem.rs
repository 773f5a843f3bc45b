//! Problem setup: the space mesh and material a configuration describes.

use sdg_mesh::Mesh;
use sdg_solver::Material;

use crate::config::{ConfigError, LoadedConfig, MeshKind};
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
}

impl Problem {
    /// Builds the mesh (generating it or reading the Gmsh file) and the material.
    pub fn setup(loaded: LoadedConfig) -> Result<Self, EngineError> {
        let config = &loaded.config;
        let file = loaded.file.display().to_string();
        let material = config.material().map_err(|e| ConfigError {
            file: file.clone(),
            ..e
        })?;
        let mesh = match config.mesh.kind {
            MeshKind::Rectangle => config.rectangle().build().map_err(|e| ConfigError {
                file,
                key: Some(format!("mesh.{}", e.field)),
                reason: e.reason,
            })?,
            MeshKind::Gmsh => {
                let path = config
                    .mesh
                    .path
                    .as_deref()
                    .expect("validated: gmsh has a path");
                sdg_mesh::gmsh::read_msh(&loaded.resolve(path))
                    .map_err(|e| EngineError::Mesh(e.to_string()))?
            }
        };
        Ok(Self {
            loaded,
            mesh,
            material,
        })
    }
}
