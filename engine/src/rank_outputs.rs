//! The outputs of a run over ranks as it goes: each rank cuts the elements it solves by the
//! snapshot planes and writes its piece of every snapshot once its own vertices have passed the
//! plane, sums the front's energy at each history time and tallies its tents (module
//! `rank_tally`); rank 0 writes `history.csv` from the merged sums and tallies at the end.
//!
//! # Snapshots: one piece per rank
//! Every element is left by exactly one tent, solved on one rank: the ranks' slices together are
//! the threaded run's, each once. A rank writes `snapshot_NNNN_R.vtu` when all the vertices it
//! owns are at or past the plane (no later tent of its can cross it); rank 0 writes the
//! `snapshot_NNNN.pvtu` that joins the pieces and `snapshots.pvd`. Pieces rather than one file
//! from rank 0: no slice travels, memory stays per rank, and the threaded run's own file is not
//! the same from run to run (its cells come in the order the threads solved them), so one file
//! would be no closer to it. The cuts of interface faces go the same way, as `cracks_NNNN_R.vtu`
//! and `cracks_NNNN.pvtu` (every rank writes its piece, empty where its patches cut no face).
//! With `output.png`, rank 0 draws the snapshots from the pieces when the run ends
//! (`rank_finish`).
//!
//! # History rows: those of the serial reference order
//! On threads a row is taken when the front's earliest time has passed `t_k = k t_end / 100`,
//! from the front as it is when the row's event runs, which depends on the threads' timing. Over
//! ranks the row of `t_k` is the serial reference order's (tents by `(t_old, id)`), the same for
//! every partition and timing: the front right after the last tent with `t_old < t_k`, where
//! every vertex is at the end of its tent crossing `t_k` (`t_old < t_k <= t_new`). Its columns:
//! - `patches`: the tents with `t_old < t_k`; the accounts: their reports summed exactly
//!   (the ranks' tallies, merged on rank 0);
//! - `time_s`: the smallest `t_new` of the crossing tents;
//! - the front's energy: per triangle, the top-facet energy of the element left by the last of
//!   its corners' crossing tents. Tents at neighbours run in `(t_old, id)` order, so that tent is
//!   the one whose triangle's other corners are at or past `t_k` already when it is solved
//!   (current on its rank by the pitching rule). Each rank adds those energies into exact sums
//!   ([`ExactSum`]) that rank 0 merges: the total is the correctly rounded sum, whatever the
//!   partition.
//!
//! The first row is the initial front's, the last the end front's (energy summed in triangle
//! order, as on threads): those two are the threaded run's but for the accounts' rounding
//! (summed exactly here, in the order of recording there). Rows that would repeat the last
//! row's time and patches are left out.
//!
//! # Memory
//! Per rank: the slices of its elements for the snapshots not yet written, and three exact sums
//! (a few values each) and a bin of the tally per history time; no element is kept beyond the
//! run's own, and no tent.

use sdg_distributed::{LocalView, Observed, Observer, Partition};
use sdg_mesh::Front;
use sdg_solver::basis::Basis;
use sdg_solver::crack::Crossing;
use sdg_solver::element::{FrontSolution, Geometry};
use sdg_solver::norms::FrontEnergy;
use sdg_solver::patch::{PatchReport, PatchSolver};

use crate::error::EngineError;
use crate::exact_sum::ExactSum;
use crate::output::snapshot::{Piece, Snapshots};
use crate::problem::Problem;
use crate::rank_prior::Prior;
use crate::rank_tally::Tally;
use crate::solve::book::{Milestone, Milestones, Records, history_times};
use crate::solve::history::{history_header, history_line, point_values, repeats_last_row};

/// Snapshot files written: (time in s, file name).
type Written = Vec<(f64, String)>;

/// Parts of a front facet's energy: kinetic, strain, flux (scaled units).
pub(crate) const PARTS: usize = 3;

/// The energy parts of the front at one history time, summed exactly.
pub(crate) type HistorySums = [ExactSum; PARTS];

/// What one rank records of its tents for the outputs: the [`Observer`] of a run over ranks.
pub(crate) struct RankOutputs<'p> {
    problem: &'p Problem,
    basis: Basis,
    snapshots: Snapshots,
    /// The snapshot times with the rank's owned vertices below each.
    milestones: Milestones,
    passed: Vec<(f64, Milestone)>,
    /// The history times `t_k` (s) and the energy parts of the front at each, summed over the
    /// triangles whose last crossing tent this rank solved.
    times: Vec<f64>,
    sums: Vec<[ExactSum; PARTS]>,
    geometry: Geometry,
    coefficients: Vec<f64>,
    phi: Vec<f64>,
    values: Vec<f64>,
    /// The rank's tents summed for the accounts.
    tally: Tally,
    /// The crack-tracking crossings and probe samples of the rank's patches.
    records: Records,
    /// The first failure (a snapshot not written, an element without its energy).
    error: Option<EngineError>,
}

impl<'p> RankOutputs<'p> {
    /// The outputs of rank `rank` of `partition` for `problem`, written into `dir`, from the
    /// whole front `start` (s by global vertex; `None`: the initial front) with the snapshots
    /// `resumed` of a checkpoint (rank 0 keeps their slices and files written, the others only
    /// which are still to come). Errors: a snapshot folder that cannot be set.
    pub(crate) fn new(
        problem: &'p Problem,
        partition: &Partition,
        rank: u32,
        dir: &std::path::Path,
        (start, resumed): (Option<&[f64]>, Option<Snapshots>),
    ) -> Result<Self, EngineError> {
        let config = &problem.loaded.config;
        let t_end = config.time.span();
        let solver = PatchSolver::new(problem.system.clone(), config.solver.order, 0);
        let (basis, width) = (solver.basis().clone(), solver.width());
        let snapshot_times: Vec<f64> = (config.output.snapshot_times.iter())
            .map(|&t| config.time.elapsed(t))
            .collect();
        let owned = partition.owners().iter().filter(|&&r| r == rank).count();
        let absolute = std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf());
        let piece = Piece {
            rank,
            ranks: partition.ranks() as u32,
            cuts: problem.interfaces.any_nonlinear(),
        };
        let times = history_times(t_end);
        let snapshots = match resumed {
            Some(mut snapshots) => {
                snapshots.set_output(&absolute, config.output.vtu)?;
                if rank != 0 {
                    snapshots.forget_collected();
                }
                snapshots.with_piece(piece)
            }
            None => Snapshots::on_clock(
                &config.output.snapshot_times,
                config.time.start,
                problem.material.max_wave_speed(),
                absolute,
            )
            .with_vtu(config.output.vtu)
            .with_piece(piece),
        };
        let milestones = match start {
            Some(start) => {
                let owned: Vec<f64> = (partition.owners().iter().zip(start))
                    .filter(|&(&r, _)| r == rank)
                    .map(|(_, &t)| t)
                    .collect();
                Milestones::resumed(&owned, t_end, &snapshot_times, None)
            }
            None => Milestones::new(owned, t_end, &snapshot_times, None, None),
        };
        Ok(Self {
            problem,
            snapshots,
            milestones,
            passed: Vec::new(),
            sums: vec![Default::default(); times.len()],
            tally: Tally::new(&times),
            times,
            geometry: Geometry::default(),
            coefficients: vec![0.0; basis.len() * width],
            phi: vec![0.0; basis.len()],
            values: vec![0.0; width],
            basis,
            records: Records::default(),
            error: None,
        })
    }

    /// What a checkpoint gathers from this rank, once every file handed to the writer is on disk:
    /// the values [`Self::finish`] returns, then the number of snapshots it has written and the
    /// slices of [`Snapshots::pending_cbor`] as bytes ([`push_bytes`]).
    pub(crate) fn checkpoint_values(&mut self) -> Result<Vec<f64>, EngineError> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        self.snapshots.finish()?;
        let mut values = self.values();
        let (next, bytes) = self.snapshots.pending_cbor();
        values.push(next as f64);
        push_bytes(&mut values, &bytes);
        Ok(values)
    }

    /// A copy of this rank's snapshots as a checkpoint stores them when every rank has
    /// written the first `next` ([`Snapshots::rewound`]).
    pub(crate) fn stored_snapshots(&self, next: usize) -> Snapshots {
        self.snapshots.rewound(next)
    }

    /// Forgets what the snapshots keep for checkpoints of the first `next`, which every rank
    /// has written.
    pub(crate) fn checkpointed(&mut self, next: usize) {
        self.snapshots.forget_kept(next);
    }

    /// The history sums, the tally and the records as values: per history time and part, the
    /// number of partials, then the partials; then the [`Tally`]; then the [`Records`] as CBOR
    /// bytes ([`push_bytes`]).
    fn values(&self) -> Vec<f64> {
        let mut values = Vec::new();
        for sum in self.sums.iter().flatten() {
            values.push(sum.partials().len() as f64);
            values.extend_from_slice(sum.partials());
        }
        self.tally.push_values(&mut values);
        let mut cbor = Vec::new();
        ciborium::into_writer(&self.records, &mut cbor).expect("records encode in memory");
        push_bytes(&mut values, &cbor);
        values
    }

    /// Writes the snapshots left (those at the end time), waits for every file, and returns
    /// the history sums and the records as values for [`sdg_distributed::RankReport::outputs`]
    /// ([`Self::values`]) with the snapshot files this rank wrote (time in s, file name).
    pub(crate) fn finish(mut self) -> Result<(Vec<f64>, Written), EngineError> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        let t_end = self.problem.loaded.config.time.span();
        self.snapshots.flush(t_end)?;
        self.snapshots.finish()?;
        Ok((self.values(), self.snapshots.written().to_vec()))
    }

    /// Cuts the elements of `triangles` (local ids) by the pending snapshot planes.
    fn slice(&mut self, solution: &FrontSolution, triangles: &[u32]) {
        let problem = self.problem;
        for &t in triangles {
            if !solution.load(t as usize, &mut self.geometry, &mut self.coefficients) {
                continue;
            }
            let (geometry, coefficients) = (&self.geometry, &self.coefficients);
            let (phi, values, basis) = (&mut self.phi, &mut self.values, &self.basis);
            self.snapshots.add_element(&geometry.vertices(), |x| {
                point_values(
                    &problem.material,
                    (&problem.system, basis),
                    geometry,
                    coefficients,
                    x,
                    phi,
                    values,
                )
            });
        }
    }
}

impl Observer for RankOutputs<'_> {
    fn solved(&mut self, view: &LocalView, front: &Front, solved: Observed<'_>) {
        let (tent, solution) = (solved.tent, solved.solution);
        self.tally.add(tent, solved.patch);
        let edges = self.problem.mesh.edges();
        let records = &mut self.records;
        records.crossings.extend(solved.crossings.iter().map(|c| {
            let edge = view.global_edge(c.edge);
            (edges[edge as usize].tag, Crossing { edge, ..*c })
        }));
        records.samples.extend_from_slice(solved.samples);
        for cut in solved.cuts {
            let (time, xy, values) = crate::output::interface::cut(cut);
            self.snapshots.add_interface_segment(time, xy, values);
        }
        let mesh = view.mesh();
        let v = tent.vertex;
        let star = mesh.vertex_triangles(v);
        let (lo, hi) = (mesh.vertex_neighbors(v).iter())
            .map(|&w| front.time(w))
            .fold((tent.t_old, tent.t_new), |(lo, hi), t| {
                (lo.min(t), hi.max(t))
            });
        if self.snapshots.pending_within(lo, hi) {
            self.slice(solution, star);
        }
        // The history times this tent crosses: for each triangle of its star whose other
        // corners have crossed already, the element just stored is the one at that time.
        let first = self.times.partition_point(|&t| t <= tent.t_old);
        let last = self.times.partition_point(|&t| t <= tent.t_new);
        for k in first..last {
            let t_k = self.times[k];
            for &t in star {
                let corners = mesh.triangles()[t as usize];
                if corners.iter().any(|&w| w != v && front.time(w) < t_k) {
                    continue;
                }
                match solution.energy(t as usize) {
                    Some(parts) => {
                        for (sum, part) in self.sums[k].iter_mut().zip(parts) {
                            sum.add(part);
                        }
                    }
                    None => {
                        self.error.get_or_insert_with(|| {
                            EngineError::Runtime(format!(
                                "rank {}: the element of triangle {} has no energy",
                                view.rank(),
                                view.global_triangle(t)
                            ))
                        });
                    }
                }
            }
        }
        self.milestones
            .advance(tent.t_old, tent.t_new, &mut self.passed);
        for (t, kind) in std::mem::take(&mut self.passed) {
            if kind == Milestone::Snapshot
                && let Err(e) = self.snapshots.flush(t)
            {
                self.error.get_or_insert(e);
            }
        }
    }
}

/// `history.csv` of a run over ranks on rank 0 after `prior`: its rows (or, for a new run,
/// the row of the initial front with energy `energy0`), a row per history time after the
/// prior's front from the ranks' merged `tally` of the tents since and their merged history
/// `sums`, and the row of the end `front` with its `energy` (all scaled units). Without
/// `energy` (a checkpoint) the rows stop at the last history time the whole `front` has
/// passed, with no end row. Errors: sums of the wrong form, as a runtime error.
pub(crate) fn history_csv(
    problem: &Problem,
    prior: &Prior,
    tally: &Tally,
    sums: &[[ExactSum; PARTS]],
    (energy0, front, energy): (&FrontEnergy, &Front, Option<&FrontEnergy>),
) -> Result<String, EngineError> {
    let config = &problem.loaded.config;
    let rho = problem.material.density();
    let initial = energy0.total;
    let times = history_times(config.time.span());
    if sums.len() != times.len() {
        return Err(EngineError::Runtime(
            "history sums of the wrong form".into(),
        ));
    }
    let zero = PatchReport::default();
    let mut history = prior.history.clone();
    if history.is_empty() {
        history = history_header();
        history.push_str(&history_line(
            config.time.clock(0.0),
            0,
            energy0,
            &zero,
            initial,
            rho,
        ));
    }
    let all = tally.tents();
    let mut running = tally.running(&prior.totals);
    let min_time = front.min_time();
    for (k, &t_k) in times.iter().enumerate() {
        if energy.is_none() && t_k > min_time {
            break;
        }
        // The tents with `t_old < t_k`: those of the bins up to k.
        running.through(k);
        let patches = prior.patches + running.tents();
        // After every tent, the front is the end front: its row is the last.
        let time = config.time.clock(tally.earliest(k));
        let at_end = energy.is_some() && running.tents() == all;
        if t_k <= prior.reached || at_end || repeats_last_row(&history, time, patches) {
            continue;
        }
        let [kinetic, strain, flux] = sums[k].each_ref().map(ExactSum::value);
        let e = FrontEnergy {
            kinetic,
            strain,
            flux,
            total: kinetic + strain + flux,
        };
        let totals = running.report();
        history.push_str(&history_line(time, patches, &e, &totals, initial, rho));
    }
    let Some(energy) = energy else {
        return Ok(history);
    };
    let totals = tally.totals(&prior.totals);
    let time = config.time.clock(front.min_time());
    let patches = prior.patches + all;
    if !repeats_last_row(&history, time, patches) {
        let row = history_line(time, patches, energy, &totals, initial, rho);
        history.push_str(&row);
    }
    Ok(history)
}

/// The ranks' outputs merged ([`merged`]): per history time the sums of the energy parts, the
/// tally of every rank's tents, and each rank's values after its tally.
pub(crate) type Merged<'a> = (Vec<HistorySums>, Tally, Vec<&'a [f64]>);

/// The ranks' `outputs` merged, for the history times `times` (s): per history time, the sums
/// of the energy parts, and the tally of every rank's tents; with each rank's values after its
/// tally (its records, then what [`RankOutputs::checkpoint_values`] adds).
pub(crate) fn merged<'a>(outputs: &[&'a [f64]], times: &[f64]) -> Result<Merged<'a>, EngineError> {
    let mut sums: Vec<[ExactSum; PARTS]> = vec![Default::default(); times.len()];
    let mut tally = Tally::new(times);
    let mut rests = Vec::new();
    for (rank, values) in outputs.iter().enumerate() {
        let bad = || EngineError::Runtime(format!("rank {rank}: history sums of the wrong form"));
        let mut at = 0;
        for sum in sums.iter_mut().flatten() {
            let n = *values.get(at).ok_or_else(bad)? as usize;
            let partials = values.get(at + 1..at + 1 + n).ok_or_else(bad)?;
            sum.merge(&ExactSum::from_partials(partials));
            at += 1 + n;
        }
        let (theirs, rest) = Tally::take(&values[at..], times).ok_or_else(|| {
            EngineError::Runtime(format!("rank {rank}: a tally of the wrong form"))
        })?;
        tally.merge(&theirs);
        rests.push(rest);
    }
    Ok((sums, tally, rests))
}

/// Appends `bytes` to `values`: their length, then the bytes, 8 to a value's bits.
fn push_bytes(values: &mut Vec<f64>, bytes: &[u8]) {
    values.push(bytes.len() as f64);
    values.extend(bytes.chunks(8).map(|chunk| {
        let mut word = [0_u8; 8];
        word[..chunk.len()].copy_from_slice(chunk);
        f64::from_bits(u64::from_le_bytes(word))
    }));
}

/// The bytes [`push_bytes`] put at the start of `rest`, and the values after them; `None` for
/// values of the wrong form.
fn take_bytes(rest: &[f64]) -> Option<(Vec<u8>, &[f64])> {
    let (&len, rest) = rest.split_first()?;
    let len = len as usize;
    let (words, rest) = rest.split_at_checked(len.div_ceil(8))?;
    let mut bytes: Vec<u8> = words
        .iter()
        .flat_map(|w| w.to_bits().to_le_bytes())
        .collect();
    bytes.truncate(len);
    Some((bytes, rest))
}

/// The [`Records`] a rank's values hold after its sums (`rest`), and the values after them.
/// Errors: values of the wrong form.
pub(crate) fn records(rest: &[f64]) -> Result<(Records, &[f64]), EngineError> {
    let bad = |why: String| EngineError::Runtime(format!("the records of a rank: {why}"));
    let (bytes, rest) = take_bytes(rest).ok_or_else(|| bad("of the wrong length".into()))?;
    let records = ciborium::from_reader(&bytes[..]).map_err(|e| bad(e.to_string()))?;
    Ok((records, rest))
}

/// The number of snapshots a rank has written, and its snapshot slices as CBOR, from the
/// values [`RankOutputs::checkpoint_values`] put after its records (`rest`). Errors: values of
/// the wrong form.
pub(crate) fn pending(rest: &[f64]) -> Result<(usize, Vec<u8>), EngineError> {
    let bad = |why: &str| EngineError::Runtime(format!("snapshot slices of a rank: {why}"));
    let (next, rest) = rest.split_first().ok_or_else(|| bad("none"))?;
    match take_bytes(rest) {
        Some((bytes, [])) => Ok((*next as usize, bytes)),
        _ => Err(bad("of the wrong length")),
    }
}
