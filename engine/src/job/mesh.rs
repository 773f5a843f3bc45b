//! `sdg mesh`: tents pitched from the initial front to the end time without solving.

use std::path::PathBuf;
use std::time::Instant;

use parking_lot::Mutex;
use serde::Serialize;

use sdg_mesh::{Front, Mesh, Pitcher, Tent};
use sdg_scheduler::{Events, Fixed, Lease, VertexId, Work};

use crate::error::{EngineError, scheduler_error};
use crate::estimate::{self, Estimate};
use crate::job::options::RunOptions;
use crate::output::spacetime::SpacetimeMesh;
use crate::output::write_atomic;
use crate::problem::Problem;

/// Refuses (bad input, exit 2) to write `sdg mesh`'s summary into `dir` when it holds the
/// `summary.json` of `sdg run`: that run's results would lose their summary.
fn refuse_run_folder(dir: &std::path::Path) -> Result<(), EngineError> {
    let path = dir.join("summary.json");
    let command = std::fs::read_to_string(&path)
        .ok()
        .and_then(|text| serde_json::from_str::<serde_json::Value>(&text).ok())
        .and_then(|json| json.get("command")?.as_str().map(str::to_owned));
    if command.as_deref() == Some("run") {
        return Err(EngineError::Input(format!(
            "{}: the summary of `sdg run`; `sdg mesh` would replace it. Write elsewhere \
             (`--output`)",
            path.display()
        )));
    }
    Ok(())
}

/// Pitches tents on `front` until every vertex reaches the pitcher's end time, on the calling
/// thread in order of increasing time, calling `on_tent` after each tent with the advanced
/// front. Returns the number of tents.
pub fn pitch_to_end(
    mesh: &Mesh,
    pitcher: &Pitcher,
    front: &Front,
    mut on_tent: impl FnMut(&Tent, &Front),
) -> Result<u64, EngineError> {
    sdg_scheduler::run_serial(&front.snapshot(), pitcher.t_end(), |v| {
        let tent = pitcher.pitch(mesh, front, v).ok_or_else(|| {
            EngineError::Runtime(format!("vertex {v} was scheduled but cannot be pitched"))
        })?;
        on_tent(&tent, front);
        Ok(tent.t_new)
    })
    .map_err(scheduler_error)
}

/// Pitching without solving, for `sdg mesh`.
struct MeshWork<'a> {
    pitcher: &'a Pitcher,
    record: Mutex<MeshRecord>,
}

/// What `sdg mesh` accumulates.
struct MeshRecord {
    tetrahedra: u64,
    max_slope_ratio: f64,
    spacetime: Option<SpacetimeMesh>,
}

impl<'a> Work<'a> for MeshWork<'a> {
    type State = Fixed<'a>;
    type Scratch = ();
    type Outcome = Tent;
    type Error = EngineError;

    fn tent(
        &self,
        lease: &mut Lease<'_, Fixed<'a>>,
        _: &mut (),
        v: VertexId,
        _: &Events<'a, Fixed<'a>>,
    ) -> Result<(f64, Tent), EngineError> {
        let state = *lease.state();
        let tent = self
            .pitcher
            .pitch(state.mesh, state.front, v)
            .ok_or_else(|| {
                EngineError::Runtime(format!("vertex {v} was claimed but cannot be pitched"))
            })?;
        Ok((tent.t_new, tent))
    }

    fn record(
        &'a self,
        state: &Fixed<'a>,
        v: VertexId,
        tent: Tent,
        _: &Events<'a, Fixed<'a>>,
    ) -> Result<(), EngineError> {
        let Fixed { mesh, front } = *state;
        let star = mesh.vertex_triangles(v);
        let slope = star
            .iter()
            .map(|&t| self.pitcher.c_max() * front.slope(mesh, t))
            .fold(0.0, f64::max);
        let mut r = self.record.lock();
        r.tetrahedra += star.len() as u64;
        r.max_slope_ratio = r.max_slope_ratio.max(slope);
        if let Some(s) = r.spacetime.as_mut() {
            s.add_tent(mesh, &tent);
        }
        Ok(())
    }
}

/// `summary.json` of `sdg mesh`.
#[derive(Clone, Debug, Serialize)]
pub struct MeshSummary {
    /// `"mesh"`.
    pub command: &'static str,
    /// The config file.
    pub config_file: PathBuf,
    /// The `--set` overrides applied to it, in order.
    pub overrides: Vec<String>,
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
    /// Earliest front time at the end, s, on the config's clock: equals `time.end`.
    pub final_time: f64,
    /// Maximum over all front facets ever built of `c_max |grad tau|`; below `safety`.
    pub max_slope_ratio: f64,
    /// Wall-clock time of pitching, s.
    pub wall_time_s: f64,
    /// Worker threads used.
    pub threads: usize,
    /// The estimate made before pitching.
    pub estimate: Estimate,
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
    let pitcher = Pitcher::new(mesh, c_max, config.pitch.safety, config.time.span())
        .map_err(|e| EngineError::Runtime(e.to_string()))?;
    let scheduler = options.scheduler(problem);
    let estimate = estimate::mesh(mesh, &pitcher, scheduler.threads);
    tracing::info!(
        tents = estimate.tents,
        wall_time_s = estimate.wall_time_s,
        "estimate"
    );
    if !options.force {
        estimate.check(problem)?;
    }
    let dir = options.output_dir(problem)?;
    refuse_run_folder(&dir)?;

    let front = Front::flat(mesh.vertices().len(), 0.0);
    let work = MeshWork {
        pitcher: &pitcher,
        record: Mutex::new(MeshRecord {
            tetrahedra: 0,
            max_slope_ratio: 0.0,
            spacetime: config
                .output
                .spacetime_mesh
                .then(|| SpacetimeMesh::new(mesh, &front)),
        }),
    };
    let _span = tracing::info_span!("mesh", config = %problem.loaded.file.display()).entered();
    let start = Instant::now();
    let stats = sdg_scheduler::run(
        &mut Fixed {
            mesh,
            front: &front,
        },
        config.time.span(),
        &work,
        vec![(); scheduler.threads],
        &scheduler,
    )
    .map_err(scheduler_error)?;
    let wall_time_s = start.elapsed().as_secs_f64();
    tracing::info!(tents = stats.tents, wall_time_s, "pitching finished");
    let record = work.record.into_inner();
    let (min_edge, max_edge) = mesh.edge_length_range();
    let summary = MeshSummary {
        command: "mesh",
        config_file: problem.loaded.file.clone(),
        overrides: problem.loaded.overrides.clone(),
        vertices: mesh.vertices().len(),
        triangles: mesh.triangles().len(),
        min_edge,
        max_edge,
        c_max,
        safety: config.pitch.safety,
        tents: stats.tents,
        tetrahedra: record.tetrahedra,
        final_time: config.time.clock(front.min_time()),
        max_slope_ratio: record.max_slope_ratio,
        wall_time_s,
        threads: scheduler.threads,
        estimate,
    };
    if let Some(s) = record.spacetime {
        let vtu = s
            .to_grid(c_max, config.time.start)
            .to_vtu(config.output.vtu);
        write_atomic(&dir, "spacetime.vtu", vtu.as_bytes())?;
    }
    let json = serde_json::to_string_pretty(&summary).expect("summary serializes") + "\n";
    write_atomic(&dir, "summary.json", json.as_bytes())?;
    Ok((summary, dir))
}
