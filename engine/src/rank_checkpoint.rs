//! Checkpoints of a run over ranks, in the threaded run's format, so that `sdg run --restart`
//! goes on from one on any number of ranks or on threads, and a run over ranks from a threaded
//! run's checkpoint.
//!
//! # When
//! The ranks pause together ([`sdg_distributed::Pause`]): at each multiple of
//! `checkpoint.every_sim_s` every rank pitches the vertices below it and stops once all its
//! vertices have reached it (exactly the tents with `t_old` below it, whatever the partition
//! and timing; no tent is capped, so the tents are the uninterrupted run's); on SIGTERM,
//! SIGINT, SIGHUP, SIGUSR1, `checkpoint.every_wall_s` or the wall-time limit each rank stops
//! where it is and tells its neighbour ranks. Once every rank has stopped no update is in
//! flight, and the ranks' fronts and elements are a state of the uninterrupted run.
//!
//! # What
//! Rank 0 gathers the front, the elements and interface faces, each rank's tally of its tents
//! since the run (re)started, its history sums and its slices of the snapshots not written yet,
//! and writes one `checkpoint_NNNNNN.sdgc` ([`crate::solve::checkpoint`]): the front, the
//! elements and the pitcher, and a bookkeeping with the totals, the history rows of the times
//! the whole front has passed, the snapshots (files written, slices pending) and the
//! milestones still ahead. One file, written last of all (temporary file, sync, rename), is
//! the manifest and the state at once: a reader sees a whole checkpoint or none.
//!
//! # A restart over ranks
//! Every rank reads the checkpoint and takes its part of the front and elements; rank 0 takes
//! the pending snapshot slices. Rows of `history.csv` before the checkpoint are its rows; the
//! rows of times between the checkpoint front's earliest and latest times are left out (their
//! tents were split by the checkpoint, and the front of such a time was never whole); rows
//! after it are as in an uninterrupted run.

use std::path::PathBuf;
use std::time::Instant;

use sdg_distributed::Gathered;
use sdg_mesh::{Front, Pitcher};
use sdg_solver::element::{FrontSolution, Geometry};
use sdg_solver::norms::FrontEnergy;

use crate::error::EngineError;
use crate::exact_sum::ExactSum;
use crate::frontier::Frontier;
use crate::output::snapshot::Snapshots;
use crate::problem::Problem;
use crate::progress::Progress;
use crate::rank_outputs::{PARTS, history_csv};
use crate::rank_prior::Prior;
use crate::rank_tally::Tally;
use crate::solve::book::{Book, Milestones, Records};
use crate::solve::checkpoint::{Counts, Folder};

/// What rank 0 writes a checkpoint from: the gathered state, the merged tally of the tents
/// since the (re)start, the merged history sums and the snapshots with every rank's pending
/// slices.
pub(crate) struct Pausing<'a> {
    pub(crate) gathered: &'a Gathered,
    pub(crate) tally: &'a Tally,
    pub(crate) sums: &'a [[ExactSum; PARTS]],
    pub(crate) snapshots: Snapshots,
    /// The ranks' crack-tracking crossings and probe samples since the (re)start.
    pub(crate) records: Records,
    /// Energy of the initial front, scaled units.
    pub(crate) energy0: &'a FrontEnergy,
    /// Wall time of the solve since the (re)start, s.
    pub(crate) wall_time_s: f64,
}

/// Writes checkpoint number `number` of the state `at` of a run over ranks of `problem` after
/// `prior` into `folder`. Returns its path and the seconds it took.
pub(crate) fn write(
    problem: &Problem,
    folder: &Folder,
    prior: &Prior,
    at: Pausing<'_>,
    number: u64,
) -> Result<(PathBuf, f64), EngineError> {
    let started = Instant::now();
    let config = &problem.loaded.config;
    let mesh = &problem.mesh;
    let t_end = config.time.span();
    let (front, solution) = (&at.gathered.front, &at.gathered.solution);
    let history = history_csv(problem, prior, at.tally, at.sums, (at.energy0, front, None))?;
    let mut book = book(problem, prior, at.tally, at.energy0.total);
    book.history = history;
    let mut records = prior.records.clone();
    records.append(at.records);
    (book.crossings, book.samples) = (records.crossings, records.samples);
    book.snapshots = at.snapshots.with_png(config.output.png);
    let snapshot_times: Vec<f64> = (config.output.snapshot_times.iter())
        .map(|&t| config.time.elapsed(t))
        .collect();
    book.milestones = Milestones::resumed(
        &front.snapshot(),
        t_end,
        &snapshot_times,
        config.checkpoint.every_sim_s,
    );
    let pitcher = Pitcher::new(
        mesh,
        problem.material.max_wave_speed(),
        config.pitch.safety,
        t_end,
    )
    .map_err(|e| EngineError::Runtime(e.to_string()))?;
    let copy = FrontSolution::new(solution.len(), solution.basis_len(), solution.width())
        .with_edges(solution.edges());
    let mut element = (
        Geometry::default(),
        vec![0.0; solution.basis_len() * solution.width()],
    );
    for t in 0..solution.len() {
        if solution.load(t, &mut element.0, &mut element.1) {
            copy.store(t, &element.0, &element.1, solution.energy(t));
        }
    }
    for e in 0..solution.edges() {
        if let Some(face) = solution.face(e) {
            copy.store_face(e, &face);
        }
    }
    let times = Front::flat(front.len(), 0.0);
    for (v, t) in front.snapshot().into_iter().enumerate() {
        times.set_time(v as u32, t);
    }
    let frontier = Frontier::new(mesh.clone(), times, copy, pitcher);
    let counts = Counts {
        tents: book.patches,
        wall_time_s: prior.wall_time_s + at.wall_time_s,
        written: number,
        ..Counts::default()
    };
    let path = folder.write(config, counts, &frontier, &book)?;
    let seconds = started.elapsed().as_secs_f64();
    tracing::info!(
        checkpoint = %path.display(),
        time = config.time.clock(front.min_time()),
        seconds,
        "checkpoint written"
    );
    Ok((path, seconds))
}

/// The bookkeeping of a run over ranks of `problem` after `prior` and the tents of `tally`,
/// from an initial front of energy `energy0` (scaled units); history, snapshots and milestones
/// are the caller's to fill in.
fn book(problem: &Problem, prior: &Prior, tally: &Tally, energy0: f64) -> Book {
    let config = &problem.loaded.config;
    let totals = tally.totals(&prior.totals);
    let (elements, dofs) = tally.elements_and_dofs();
    let (elements, dofs) = (prior.elements + elements, prior.dofs + dofs);
    let (nonlinear, newton, newton_max) = tally.newton();
    let (nonlinear, newton) = (prior.nonlinear + nonlinear, prior.newton + newton);
    let newton_max = prior.newton_max.max(newton_max);
    let c_max = problem.material.max_wave_speed();
    let slope_ratio = prior.max_slope_ratio.max(c_max * tally.slope());
    Book {
        totals,
        patches: prior.patches + tally.tents(),
        rejected: 0,
        refinements: 0,
        coarsenings: 0,
        unresolved: 0,
        unresolved_max: 0.0,
        samples: Vec::new(),
        crossings: Vec::new(),
        fracture_events: Vec::new(),
        nonlinear_patches: nonlinear,
        newton_iterations: newton,
        newton_max,
        initial_energy: energy0,
        energy_max: energy0.max(energy0 + totals.boundary_work),
        elements,
        dofs,
        max_slope_ratio: slope_ratio,
        timings: Default::default(),
        snapshots: Snapshots::on_clock(&[], config.time.start, c_max, PathBuf::new()),
        milestones: Milestones::new(0, 0.0, &[], None, None),
        passed: Vec::new(),
        history: String::new(),
        progress: Progress::new(false, 0.0),
        phi: Vec::new(),
        values: Vec::new(),
        geometry: Geometry::default(),
        coefficients: Vec::new(),
    }
}
