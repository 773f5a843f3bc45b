//! The run loop: pitching tents from the initial front to the end time, and the commands built
//! on it.

use std::path::PathBuf;
use std::time::Instant;

use serde::Serialize;

use sdg_mesh::{Front, Mesh, Pitcher, Tent};

use crate::error::EngineError;
use crate::output::write_atomic;
use crate::problem::Problem;
use crate::spacetime::SpacetimeMesh;

/// Command-line choices that are not part of the configuration.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Output folder; overrides `output.dir`.
    pub output_dir: Option<PathBuf>,
}

/// Pitches tents on `front` until every vertex reaches the pitcher's end time, calling
/// `on_tent` after each tent with the advanced front. Returns the number of tents.
pub fn pitch_to_end(
    mesh: &Mesh,
    pitcher: &Pitcher,
    front: &mut Front,
    mut on_tent: impl FnMut(&Tent, &Front),
) -> Result<u64, EngineError> {
    let initial = front.times().to_vec();
    let stats = sdg_scheduler::run_serial(&initial, pitcher.t_end(), |v| {
        let tent = pitcher.pitch(mesh, front, v).ok_or_else(|| {
            EngineError::Runtime(format!("vertex {v} was scheduled but cannot be pitched"))
        })?;
        on_tent(&tent, front);
        Ok(tent.t_new)
    })
    .map_err(|e| match e {
        sdg_scheduler::RunError::Pitch(e) => e,
        stalled => EngineError::Runtime(stalled.to_string()),
    })?;
    Ok(stats.tents)
}

/// `summary.json` of `sdg mesh`.
#[derive(Clone, Debug, Serialize)]
pub struct MeshSummary {
    /// `"mesh"`.
    pub command: &'static str,
    /// The config file.
    pub config_file: PathBuf,
    /// Space mesh vertices.
    pub vertices: usize,
    /// Space mesh triangles.
    pub triangles: usize,
    /// Shortest space edge, m.
    pub min_edge: f64,
    /// Longest space edge, m.
    pub max_edge: f64,
    /// Fastest wave speed the front is causal for, m/s.
    pub c_max: f64,
    /// The configured safety factor.
    pub safety: f64,
    /// Tents pitched.
    pub tents: u64,
    /// Spacetime tetrahedra built (one per triangle of each tent's star).
    pub tetrahedra: u64,
    /// Earliest front time at the end, s: equals `time.end`.
    pub final_time: f64,
    /// Maximum over all front facets ever built of `c_max |grad tau|`; below `safety`.
    pub max_slope_ratio: f64,
    /// Wall-clock time of pitching, s.
    pub wall_time_s: f64,
    /// Worker threads used.
    pub threads: usize,
}

/// `sdg mesh`: pitches tents to the end time without solving, writes `summary.json` and, when
/// `output.spacetime_mesh` is set, `spacetime.vtu`. Returns the summary and the output folder.
pub fn mesh_job(
    problem: &Problem,
    options: &RunOptions,
) -> Result<(MeshSummary, PathBuf), EngineError> {
    let config = &problem.loaded.config;
    let mesh = &problem.mesh;
    let c_max = problem.material.max_wave_speed();
    let pitcher = Pitcher::new(mesh, c_max, config.pitch.safety, config.time.end)
        .map_err(|e| EngineError::Runtime(e.to_string()))?;
    let dir = options
        .output_dir
        .clone()
        .unwrap_or_else(|| config.output.dir.clone());
    std::fs::create_dir_all(&dir).map_err(|e| EngineError::io(&dir, e))?;

    let mut front = Front::flat(mesh.vertices().len(), 0.0);
    let mut spacetime = config
        .output
        .spacetime_mesh
        .then(|| SpacetimeMesh::new(mesh, &front));
    let mut tetrahedra = 0u64;
    let mut max_slope_ratio: f64 = 0.0;
    let start = Instant::now();
    let tents = pitch_to_end(mesh, &pitcher, &mut front, |tent, front| {
        let star = mesh.vertex_triangles(tent.vertex);
        tetrahedra += star.len() as u64;
        for &t in star {
            max_slope_ratio = max_slope_ratio.max(c_max * front.slope(mesh, t));
        }
        if let Some(s) = spacetime.as_mut() {
            s.add_tent(mesh, tent);
        }
    })?;
    let wall_time_s = start.elapsed().as_secs_f64();
    let (min_edge, max_edge) = mesh.edge_length_range();
    let summary = MeshSummary {
        command: "mesh",
        config_file: problem.loaded.file.clone(),
        vertices: mesh.vertices().len(),
        triangles: mesh.triangles().len(),
        min_edge,
        max_edge,
        c_max,
        safety: config.pitch.safety,
        tents,
        tetrahedra,
        final_time: front.min_time(),
        max_slope_ratio,
        wall_time_s,
        threads: 1,
    };
    if let Some(s) = spacetime {
        write_atomic(&dir, "spacetime.vtu", s.to_grid(c_max).to_vtu().as_bytes())?;
    }
    let json = serde_json::to_string_pretty(&summary).expect("summary serializes") + "\n";
    write_atomic(&dir, "summary.json", json.as_bytes())?;
    Ok((summary, dir))
}
