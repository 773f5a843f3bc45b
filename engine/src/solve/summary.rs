//! `summary.json` of `sdg run` and the state hash in it.

use std::path::PathBuf;

use serde::Serialize;

use sdg_mesh::Front;
use sdg_solver::element::{FrontSolution, Geometry};
use sdg_solver::norms::FrontEnergy;
use sdg_solver::patch::PatchReport;

/// Energy totals of a run, J per metre of thickness.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct EnergySummary {
    /// Kinetic plus strain energy at t = 0.
    pub initial: f64,
    /// Kinetic energy on the final (flat) front.
    pub final_kinetic: f64,
    /// Strain energy on the final front.
    pub final_strain: f64,
    /// Total energy on the final front.
    pub r#final: f64,
    /// Work done on the body through the domain boundary.
    pub boundary_work: f64,
    /// Numerical dissipation of all elements (each non-negative).
    pub dissipation: f64,
    /// Work absorbed by interfaces (contact, free): the power their targets take out of the
    /// elements on both sides, integrated.
    pub interface_work: f64,
    /// Part of `interface_work` done by tangential tractions on tangential velocity jumps of
    /// contact interfaces.
    pub friction_dissipation: f64,
    /// Part of `interface_work` done on cohesive interfaces: the work of the cohesive
    /// tractions, fracture energy.
    pub fracture_energy: f64,
    /// `(initial + boundary_work - final - dissipation - interface_work) /
    /// (initial + |boundary_work|)`.
    pub balance_residual_rel: f64,
}

impl EnergySummary {
    /// The totals of a run of density `rho` (kg/m^3) from its energies per unit density: the
    /// initial energy `initial`, the final front's `end` and the patches' summed `totals`.
    pub(crate) fn new(rho: f64, initial: f64, end: &FrontEnergy, totals: &PatchReport) -> Self {
        let (initial, r#final) = (rho * initial, rho * end.total);
        let boundary_work = rho * totals.boundary_work;
        let (dissipation, interface_work) = (rho * totals.dissipation, rho * totals.interface_work);
        let residual = initial + boundary_work - r#final - dissipation - interface_work;
        Self {
            initial,
            final_kinetic: rho * end.kinetic,
            final_strain: rho * end.strain,
            r#final,
            boundary_work,
            dissipation,
            interface_work,
            friction_dissipation: rho * totals.friction_dissipation,
            fracture_energy: rho * totals.fracture_work,
            balance_residual_rel: residual / (initial + boundary_work.abs()).max(f64::MIN_POSITIVE),
        }
    }
}

/// Nonlinear interface patches of a run.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct InterfaceSummary {
    /// Patches solved by Newton iterations (with a contact face).
    pub nonlinear_patches: u64,
    /// Mean linear solves per nonlinear patch (the first from the bonded solution).
    pub newton_iterations_mean: f64,
    /// Most linear solves of one nonlinear patch.
    pub newton_iterations_max: usize,
}

/// Relative L2 errors at the end time against the exact solution.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ErrorSummary {
    /// `||v - v_exact|| / ||v_exact||` on the final slice.
    pub velocity_l2_rel: f64,
    /// `||sigma - sigma_exact|| / ||sigma_exact||` on the final slice.
    pub stress_l2_rel: f64,
}

/// `summary.json` of `sdg run`. In deterministic mode every field but `wall_time_s`,
/// `patches_per_second`, `threads`, `peak_memory_bytes` and `estimate` is the same for any
/// thread count.
#[derive(Clone, Debug, Serialize)]
pub struct RunSummary {
    /// `"run"`.
    pub command: &'static str,
    /// The config file.
    pub config_file: PathBuf,
    /// The `--set` overrides applied to it, in order.
    pub overrides: Vec<String>,
    /// Space mesh vertices.
    pub vertices: usize,
    /// Space mesh triangles.
    pub triangles: usize,
    /// Polynomial order.
    pub order: usize,
    /// Tents pitched and patches solved.
    pub patches: u64,
    /// Spacetime elements solved.
    pub elements: u64,
    /// Mean unknowns per patch linear system.
    pub dofs_per_patch: f64,
    /// End time reached, s.
    pub final_time: f64,
    /// Maximum `c_max |grad tau|` over all front facets.
    pub max_slope_ratio: f64,
    /// Largest momentum imbalance of an element (the sum of its faces' momentum fluxes),
    /// relative to the largest momentum flux through the faces of any element: zero to
    /// round-off, as every element balances linear momentum.
    pub max_momentum_residual: f64,
    /// `"deterministic"` or `"asynchronous"`.
    pub mode: &'static str,
    /// FNV-1a hash of the final front: vertex times, then every element's geometry and
    /// coefficients, then every interface face's corners and coefficients, as hexadecimal.
    /// Equal hashes mean bitwise equal final states.
    pub state_hash: String,
    /// Wall-clock time of the solve, s.
    pub wall_time_s: f64,
    /// Patches per second of wall-clock time.
    pub patches_per_second: f64,
    /// Worker threads used (with `--ranks`, one per rank).
    pub threads: usize,
    /// Ranks the front was split over (`sdg run --ranks`); 1 for a run in one process.
    pub ranks: usize,
    /// How the ranks shared the work (`sdg run --ranks`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub distributed: Option<DistributedSummary>,
    /// Peak resident memory of the process, bytes (Linux; absent elsewhere).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_memory_bytes: Option<f64>,
    /// The estimate made before the run, to compare with `patches`, `wall_time_s` and
    /// `peak_memory_bytes`.
    pub estimate: crate::estimate::Estimate,
    /// Energy accounting.
    pub energy: EnergySummary,
    /// Newton statistics of patches with contact faces.
    pub interface: InterfaceSummary,
    /// The scales of `[loading]`, when configured.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub loading: Option<crate::problem::Loading>,
    /// With `[loading]`: the tip of its interface against LEFM.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lefm: Option<crate::lefm::LefmComparison>,
    /// Crack tips of cohesive interfaces (runs with a cohesive law).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub crack: Option<crate::fracture::tips::CrackSummary>,
    /// Crack propagation (runs with `[fracture]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fracture: Option<crate::fracture::records::FractureSummary>,
    /// Errors against `[exact]`, when configured.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<ErrorSummary>,
    /// Snapshot files written: `[time s, file]`.
    pub snapshots: Vec<(f64, String)>,
    /// Edge bisections (new vertices) made by adaptive refinement.
    pub refinements: u64,
    /// Patches (tents or coarsenings) solved and rejected by the error indicator (included in
    /// `patches`).
    pub rejected_patches: u64,
    /// Patches accepted with the error indicator above `adapt.tol` because none of their star
    /// triangles could be bisected (halves shorter than `adapt.min_edge`, or than
    /// `adapt.far_edge` away from cracks, a star at the solvers' capacity, or the front's
    /// causality): where the run is less resolved than the tolerance asks. Lower those floors
    /// when this is a large share of `patches`.
    pub unresolved_patches: u64,
    /// The largest indicator of those patches over `adapt.tol` (0 when there are none).
    pub unresolved_max: f64,
    /// Bisection vertices removed again by coarsening patches (included in `patches`).
    pub coarsenings: u64,
    /// Scheduler events run (refinement, coarsening, history rows): each holds the whole
    /// front, so the other workers wait for it.
    pub events: u64,
    /// Deterministic mode: rounds of independent tents (`patches / rounds` tents per round on
    /// average, each round ending at a barrier); 0 in asynchronous mode.
    pub rounds: u64,
    /// Shortest edge of the final space mesh, m.
    pub min_edge: f64,
    /// Longest edge of the final space mesh, m.
    pub max_edge: f64,
    /// Checkpoints of this process and the one it restarted from.
    pub checkpoint: CheckpointSummary,
    /// Where the wall time went.
    pub timings: Timings,
}

/// `distributed` in `summary.json`: the partition and the messages between ranks.
#[derive(Clone, Debug, Serialize)]
pub struct DistributedSummary {
    /// `"coordinate"`, `"stripes"` or `"random"`.
    pub partition: &'static str,
    /// Vertices whose owner rank is not that of every neighbour, summed over ranks.
    pub boundary_vertices: usize,
    /// Update messages sent per tent.
    pub updates_per_tent: f64,
    /// Bytes of those updates per tent.
    pub bytes_per_tent: f64,
    /// Time the ranks waited for updates with nothing to pitch, summed over ranks, s.
    pub waited_s: f64,
    /// The same per rank, in rank order, since the run (re)started.
    pub per_rank: Vec<RankSummary>,
}

/// `distributed.per_rank[]` in `summary.json`: what one rank did since the run (re)started.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct RankSummary {
    /// Tents it pitched and solved.
    pub tents: u64,
    /// Its owned vertices that another rank holds as a ghost.
    pub boundary_vertices: usize,
    /// Update messages it sent, and their bytes.
    pub updates_sent: u64,
    pub update_bytes: u64,
    /// Time it waited for updates with nothing to pitch, s.
    pub waited_s: f64,
}

/// `timings` in `summary.json`: where the wall time went, s, summed over the worker threads
/// (and the main thread's bookkeeping), measured, so not the same from run to run.
#[derive(Clone, Copy, Debug, Default, Serialize, serde::Deserialize)]
pub struct Timings {
    /// Computing tent heights.
    pub pitching_s: f64,
    /// Assembling patch systems.
    pub assembly_s: f64,
    /// Solving them: ring eliminations and Newton iterations.
    pub solve_s: f64,
    /// Evaluating solved patches: energies, displacements, interface states.
    pub evaluation_s: f64,
    /// Scheduler events (refinement, coarsening, crack growth, history rows), with the state
    /// held exclusively.
    pub events_s: f64,
    /// Workers without a tent: asleep with nothing ready, waiting for the state's lock, or at
    /// the deterministic rounds' barriers.
    pub waiting_s: f64,
    /// Snapshot slices, probes and the files written at the end (snapshot files are written
    /// by a thread of their own, not counted).
    pub output_s: f64,
}

/// `checkpoint` in `summary.json`.
#[derive(Clone, Debug, Default, Serialize)]
pub struct CheckpointSummary {
    /// Checkpoints this process wrote.
    pub written: u64,
    /// The checkpoint file this run restarted from, if any.
    pub restarted_from: Option<PathBuf>,
    /// The front's least time in that checkpoint, s.
    pub restart_time: Option<f64>,
    /// Wall time spent writing checkpoints, s (not part of `wall_time_s`).
    pub write_seconds: f64,
}

/// FNV-1a over the bits of the front times, of every element under the front and of every
/// interface face on it.
pub(crate) fn state_hash(front: &Front, solution: &FrontSolution, size: usize) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |x: f64| {
        for byte in x.to_bits().to_le_bytes() {
            hash ^= u64::from(byte);
            hash = hash.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for t in front.snapshot() {
        feed(t);
    }
    let mut geometry = Geometry::default();
    let mut coefficients = vec![0.0; size];
    for t in 0..solution.len() {
        if solution.load(t, &mut geometry, &mut coefficients) {
            geometry.vertices().iter().flatten().for_each(|&x| feed(x));
            coefficients.iter().for_each(|&x| feed(x));
        }
    }
    for e in 0..solution.edges() {
        if let Some(face) = solution.face(e) {
            face.geometry
                .corners()
                .iter()
                .flatten()
                .for_each(|&x| feed(x));
            face.coefficients.iter().flatten().for_each(|&x| feed(x));
        }
    }
    format!("{hash:016x}")
}
