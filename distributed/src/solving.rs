//! Patches solved over ranks: each rank solves the patch of every tent it pitches on its own
//! view, with the real patch solver, and its updates carry what neighbours read as inflow: the
//! elements under the star and the interface states over its spokes.
//!
//! # What a patch reads, and why it is the serial run's
//! The patch of a tent at `v` reads the front times of `v`'s neighbours, the elements under
//! `v`'s star triangles (its inflow) and, with interface laws, the interface faces over `v`'s
//! spokes (the state below its contact faces). The pitching rule makes those times current
//! ([`crate::pitching`]). Each element was left by the last tent at one of its triangle's
//! corners, each face by the last tent at one of its edge's ends; that tent's owner sends it,
//! with the tent's update, to every rank that holds the triangle or edge, tagged with its
//! generation (tents at the triangle's corners or the edge's ends so far), and a receiver
//! stores it only if that is newer than its copy. When `v` passes the rule, its rank sees
//! every corner `w` of its star at `w`'s current time, so the update of `w`'s last tent has
//! arrived (or `w` is its own), and with it every element and face that tent left on this
//! rank: nothing newer exists, so the copies the patch reads are current. The star's
//! triangles are in the whole mesh's order with their corner order (local ids increase with
//! global ids), so the patch solver gets the serial run's inputs in the serial run's order and
//! returns its elements and faces bitwise, for any partition and message timing. At the end
//! every copy, on every rank that holds it, is the serial run's.
//!
//! # Scope
//! Elastodynamics with the interface laws of the solver (contact, friction, cohesion, damage),
//! without mesh-changing events and without fracture, from initial data at time 0. An element
//! travels as its geometry's values ([`Geometry::to_values`]), its top facet's energy parts and
//! its coefficients, a face as its geometry's values ([`FaceGeometry::to_values`]) and its
//! coefficients, all `f64` bits; only tents at vertices that another rank holds as a ghost send
//! any, and solving an interior patch allocates nothing.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender, channel};
use std::sync::{Mutex, TryLockError};
use std::time::Duration;

use sdg_mesh::{EdgeId, Front, Mesh, Tent, VertexId};
use sdg_solver::boundary::Boundary;
use sdg_solver::crack::Crossing;
use sdg_solver::element::{FrontSolution, GEOMETRY_VALUES, Geometry};
use sdg_solver::face::{
    FACE_GEOMETRY_VALUES, FaceGeometry, FaceState, MAX_FACE_BASIS, STATE_COMPONENTS,
};
use sdg_solver::interface::Interfaces;
use sdg_solver::patch::{FaceCut, Initial, InterfaceSample, Newton, PatchReport, PatchSolver};
use sdg_solver::system::System;

use crate::held::Held;
use crate::partition::{Partition, Rank};
use crate::pitching::{
    Causality, CellKind, Options, PitchingError, RankReport, SolvedPatch, Work, on_threads,
    panic_message, rank_start, run_rank,
};
use crate::transport::loopback::LoopbackOptions;
use crate::transport::{Transport, Update};
use crate::view::LocalView;

/// Values of a top facet's energy parts `[kinetic, strain, flux]` in an element's values.
const ENERGY_VALUES: usize = 3;

/// What every rank solves its patches with.
#[derive(Clone, Copy, Debug)]
pub struct Physics<'a> {
    /// The first-order system of the material.
    pub system: &'a System,
    /// Polynomial order of the elements, 1 to 4.
    pub order: usize,
    /// Boundary conditions by tag (on the local views, boundary edges keep their tags).
    pub boundary: &'a Boundary,
    /// The state at time 0.
    pub initial: Initial<'a>,
    /// Interface laws by tag (interior edges without one are bonded).
    pub interfaces: &'a Interfaces,
    /// Newton settings of the patches with nonlinear faces.
    pub newton: Newton,
    /// Points (m) where interface probes sample each patch ([`PatchSolver::probe_samples`]).
    pub probes: &'a [[f64; 2]],
    /// Times (s, on the run's clock from 0) of the planes that cut each patch's contact faces
    /// ([`PatchSolver::snapshot_cuts`]): the snapshots'.
    pub cut_times: &'a [f64],
}

impl Physics<'_> {
    /// A patch solver for stars of up to `max_star` triangles.
    fn solver(&self, max_star: usize) -> PatchSolver {
        PatchSolver::new(self.system.clone(), self.order, max_star)
            .with_interfaces(self.interfaces.clone(), self.newton)
    }

    /// Initial data under every triangle of `view`: the front solution a rank starts from.
    pub fn initial_solution(&self, view: &LocalView) -> FrontSolution {
        // Only for the element sizes: no interfaces, no patch.
        let solver = PatchSolver::new(self.system.clone(), self.order, 0);
        FrontSolution::new(
            view.mesh().triangles().len(),
            solver.basis().len(),
            solver.width(),
        )
        .with_edges(view.mesh().edges().len())
    }
}

/// The pitcher, local front and local solution of the rank whose view is `view`, from the whole
/// mesh's `front` (s, by global vertex) and `solution` (elements by global triangle, faces by
/// global edge): a run that goes on from a paused or checkpointed state.
pub fn rank_state(
    view: &LocalView,
    causality: Causality,
    physics: Physics<'_>,
    (front, solution): (&Front, &FrontSolution),
) -> Result<(sdg_mesh::Pitcher, Front, FrontSolution), PitchingError> {
    let (pitcher, local_front) = rank_start(view, causality, &front.snapshot())?;
    let local = physics.initial_solution(view);
    for t in 0..local.len() {
        let global = view.global_triangle(t as u32) as usize;
        let energy = solution.energy(global);
        solution.with_element(global, |element| {
            if let Some((geometry, coefficients)) = element {
                local.store(t, geometry, coefficients, energy);
            }
        });
    }
    for e in 0..local.edges() {
        if let Some(face) = solution.face(view.global_edge(e as u32) as usize) {
            local.store_face(e, &face);
        }
    }
    Ok((pitcher, local_front, local))
}

/// A rank's result: its report, view, front, and the elements and interface faces on it.
#[derive(Debug)]
pub struct RankSolution {
    /// What the rank did.
    pub report: RankReport,
    /// Its view of the mesh.
    pub view: LocalView,
    /// Its front (local vertex ids), at the end time.
    pub front: Front,
    /// The elements under its view's triangles and the interface faces over its edges (local
    /// ids).
    pub solution: FrontSolution,
}

/// What a rank's caller records of each of the rank's tents as it is solved (outputs such as
/// snapshot slices, history sums and crack-tracking crossings), through
/// [`solve_rank_observed`].
pub trait Observer {
    /// Called right after the patch of `solved.tent` (at an owned local vertex of `view`) is
    /// stored in `solved.solution` (local ids), with `front` at the tent's new time. By the
    /// pitching rule the times of the tent's neighbours in `front` are their current ones.
    fn solved(&mut self, view: &LocalView, front: &Front, solved: Observed<'_>);
}

/// A patch as an [`Observer`] sees it.
#[derive(Clone, Copy, Debug)]
pub struct Observed<'a> {
    /// Its tent.
    pub tent: &'a Tent,
    /// Its report and the largest slope of the front's triangles it left.
    pub patch: &'a SolvedPatch,
    /// The rank's elements and faces, the patch's stored.
    pub solution: &'a FrontSolution,
    /// Where its cohesive faces crossed the crack-tracking levels
    /// ([`PatchSolver::crack_crossings`], local edge ids).
    pub crossings: &'a [Crossing],
    /// Its samples at [`Physics::probes`]: `(probe index, sample)`.
    pub samples: &'a [(usize, InterfaceSample)],
    /// Its contact faces' cuts by the planes of [`Physics::cut_times`].
    pub cuts: &'a [FaceCut],
}

/// Observes nothing.
impl Observer for () {
    fn solved(&mut self, _: &LocalView, _: &Front, _: Observed<'_>) {}
}

/// A solved patch: its report, its crack-tracking crossings (local edge ids), its probes'
/// samples and its contact faces' snapshot cuts (all empty, and not allocated, for most
/// patches).
#[derive(Debug)]
struct Solved {
    report: PatchReport,
    crossings: Vec<Crossing>,
    samples: Vec<(usize, InterfaceSample)>,
    cuts: Vec<FaceCut>,
}

/// A rank's patch solves: the [`Work`] of [`solve_rank`].
struct Patches<'a, O> {
    solving: Solving<'a>,
    observer: &'a mut O,
    physics: Physics<'a>,
    solution: &'a FrontSolution,
    /// Per local triangle, tents at its corners so far, as far as this rank has heard.
    generation: Vec<u32>,
    /// Per local edge, tents at its ends so far, as far as this rank has heard; empty without
    /// nonlinear interface laws (no faces are stored then).
    edge_generation: Vec<u32>,
    /// Values per element.
    stride: usize,
    /// Per tent so far, its patch's report and slope ([`Options::keep_tents`]; empty otherwise).
    patches: Vec<SolvedPatch>,
    keep_tents: bool,
    /// What the rank knows of the energy held ([`Options::held`]), and per rank the entries of
    /// its `known` last sent there (empty without the guard).
    held: Option<Held>,
    sent_work: Vec<Vec<f64>>,
}

/// The blow-up guard of a tent: the energy the body can have held before it and the energy
/// scale of the messages ([`Held::bound`], [`Held::scale`]); none without the guard.
type Guard = Option<(f64, f64)>;

/// Values per interface face: its geometry's, then the coefficients of each component.
const FACE_VALUES: usize = FACE_GEOMETRY_VALUES + STATE_COMPONENTS * MAX_FACE_BASIS;

/// The edges from `v` to its neighbours on `mesh`.
fn spokes(mesh: &Mesh, v: VertexId) -> impl Iterator<Item = EdgeId> + '_ {
    mesh.vertex_neighbors(v)
        .iter()
        .filter_map(move |&w| mesh.edge_between(v, w))
}

/// Solves the patch of `tent` with `solver` and stores it in `solution`; a patch with a
/// non-finite value, or that blows up by `guard`, is not stored (the engine's guards).
fn solve_tent(
    solver: &mut PatchSolver,
    physics: &Physics<'_>,
    (view, front, solution): (&LocalView, &Front, &FrontSolution),
    (tent, guard): (&Tent, Guard),
) -> Result<Solved, PitchingError> {
    let report = solver
        .solve(
            view.mesh(),
            front,
            tent,
            physics.boundary,
            physics.initial,
            solution,
        )
        .map_err(|source| PitchingError::Patch {
            rank: view.rank(),
            vertex: view.global(tent.vertex),
            time: tent.t_old,
            source,
        })?;
    if let Some((name, value)) = report.first_non_finite() {
        return Err(PitchingError::NonFinite {
            rank: view.rank(),
            vertex: view.global(tent.vertex),
            time: tent.t_old,
            name,
            value,
        });
    }
    if let Some((held, scale)) = guard.filter(|&(held, _)| report.blows_up(held)) {
        return Err(PitchingError::BlowUp {
            rank: view.rank(),
            vertex: view.global(tent.vertex),
            time: tent.t_old,
            out: scale * report.energy_out,
            held: scale * (held + report.boundary_work.max(0.0)),
        });
    }
    solver.commit(solution);
    let mut samples = Vec::new();
    if !physics.probes.is_empty() {
        solver.probe_samples(view.mesh(), physics.probes.iter().copied(), &mut samples);
    }
    let mut cuts = Vec::new();
    solver.snapshot_cuts(physics.cut_times, &mut cuts);
    Ok(Solved {
        report,
        crossings: solver.crack_crossings().to_vec(),
        samples,
        cuts,
    })
}

/// Where a rank's patches are solved: on the rank's thread with `solver`, and with
/// [`Options::threads`] above 1 on solving threads too.
struct Solving<'c> {
    solver: PatchSolver,
    crew: Option<Crew<'c>>,
}

/// The channels to a rank's solving threads: tents go in on `tents` and are taken from
/// `taken` (by the rank's thread too, when it has nothing else to do); what [`solve_tent`]
/// returned comes back on `solved`.
struct Crew<'c> {
    tents: Sender<(Tent, Guard)>,
    taken: &'c Mutex<Receiver<(Tent, Guard)>>,
    solved: Receiver<(Tent, Result<Solved, PitchingError>)>,
}

/// A solving thread: solves the tents it takes from `tents` with `solver` until the channel
/// closes, and gives back each result (a panic as [`PitchingError::Panic`]).
fn solving_thread(
    mut solver: PatchSolver,
    physics: &Physics<'_>,
    rank: (&LocalView, &Front, &FrontSolution),
    tents: &Mutex<Receiver<(Tent, Guard)>>,
    solved: &Sender<(Tent, Result<Solved, PitchingError>)>,
) {
    loop {
        // One thread at a time waits on the channel; the lock is let go before solving.
        let next = tents.lock().unwrap_or_else(|e| e.into_inner()).recv();
        let Ok((tent, guard)) = next else { return };
        let result = catch_unwind(AssertUnwindSafe(|| {
            solve_tent(&mut solver, physics, rank, (&tent, guard))
        }))
        .unwrap_or_else(|payload| {
            Err(PitchingError::Panic {
                rank: rank.0.rank(),
                message: panic_message(payload),
            })
        });
        if solved.send((tent, result)).is_err() {
            return;
        }
    }
}

impl<O: Observer> Patches<'_, O> {
    /// Solves `tent` on the rank's thread with `guard`, and what follows ([`Patches::solved`]).
    fn solve(
        &mut self,
        view: &LocalView,
        front: &Front,
        tent: (&Tent, Guard),
    ) -> Result<(), PitchingError> {
        let solver = &mut self.solving.solver;
        let solved = solve_tent(solver, &self.physics, (view, front, self.solution), tent)?;
        self.solved(view, front, tent.0, solved);
        Ok(())
    }

    /// What follows a stored patch, in the order of the tents: generations, the slope, the
    /// report and the observer.
    fn solved(&mut self, view: &LocalView, front: &Front, tent: &Tent, solved: Solved) {
        let Solved {
            report,
            crossings,
            samples,
            cuts,
        } = solved;
        if let Some(held) = &mut self.held {
            held.add(view.rank(), &report);
        }
        let mut slope = 0.0_f64;
        for &t in view.mesh().vertex_triangles(tent.vertex) {
            self.generation[t as usize] += 1;
            slope = slope.max(front.slope(view.mesh(), t));
        }
        let patch = SolvedPatch { report, slope };
        if self.keep_tents {
            self.patches.push(patch);
        }
        if !self.edge_generation.is_empty() {
            for e in spokes(view.mesh(), tent.vertex) {
                self.edge_generation[e as usize] += 1;
            }
        }
        let observed = Observed {
            tent,
            patch: &patch,
            solution: self.solution,
            crossings: &crossings,
            samples: &samples,
            cuts: &cuts,
        };
        self.observer.solved(view, front, observed);
    }
}

impl<O> Patches<'_, O> {
    /// The guard of a tent pitched now.
    fn guard(&self) -> Guard {
        self.held.as_ref().map(|h| (h.bound(), h.scale))
    }
}

impl<O: Observer> Work for Patches<'_, O> {
    fn tent(&mut self, view: &LocalView, front: &Front, tent: &Tent) -> Result<(), PitchingError> {
        self.solve(view, front, (tent, self.guard()))
    }

    fn start(&mut self, tent: &Tent) -> bool {
        let guard = self.guard();
        // Solving threads gone show as a disconnected channel in `finish`.
        (self.solving.crew.as_ref()).is_some_and(|crew| {
            let _ = crew.tents.send((*tent, guard));
            true
        })
    }

    fn help(&mut self, view: &LocalView, front: &Front) -> Result<Option<Tent>, PitchingError> {
        let Some(crew) = &self.solving.crew else {
            return Ok(None);
        };
        // A solving thread holding the lock waits on an empty channel or is taking the tent.
        let next = match crew.taken.try_lock() {
            Ok(taken) => taken.try_recv().ok(),
            Err(TryLockError::Poisoned(taken)) => taken.into_inner().try_recv().ok(),
            Err(TryLockError::WouldBlock) => None,
        };
        let Some((tent, guard)) = next else {
            return Ok(None);
        };
        self.solve(view, front, (&tent, guard))?;
        Ok(Some(tent))
    }

    fn finish(
        &mut self,
        view: &LocalView,
        front: &Front,
        wait: Duration,
    ) -> Result<Option<Tent>, PitchingError> {
        let Some(crew) = &self.solving.crew else {
            return Ok(None);
        };
        let (tent, solved) = match crew.solved.recv_timeout(wait) {
            Ok(done) => done,
            Err(RecvTimeoutError::Timeout) => return Ok(None),
            Err(RecvTimeoutError::Disconnected) => {
                return Err(PitchingError::Panic {
                    rank: view.rank(),
                    message: "the solving threads are gone".into(),
                });
            }
        };
        self.solved(view, front, &tent, solved?);
        Ok(Some(tent))
    }

    fn cells_for(&mut self, view: &LocalView, v: VertexId, to: Rank, update: &mut Update) {
        if let Some(held) = &self.held {
            held.changes(&mut self.sent_work[to as usize], &mut update.work);
        }
        let elements = &mut update.elements;
        for &t in view.mesh().vertex_triangles(v) {
            if !view.held_by(t, to) {
                continue;
            }
            elements
                .ids
                .push((view.global_triangle(t), self.generation[t as usize]));
            let energy = self
                .solution
                .energy(t as usize)
                .unwrap_or([f64::NAN; ENERGY_VALUES]);
            self.solution.with_element(t as usize, |element| {
                let (geometry, coefficients) = element.expect("the tent's star is solved");
                elements.values.extend(geometry.to_values());
                elements.values.extend(energy);
                elements.values.extend_from_slice(coefficients);
            });
        }
        if self.edge_generation.is_empty() {
            return;
        }
        for e in spokes(view.mesh(), v) {
            let face = self.solution.face(e as usize);
            if let Some(face) = face.filter(|_| view.edge_held_by(e, to)) {
                let faces = &mut update.faces;
                faces
                    .ids
                    .push((view.global_edge(e), self.edge_generation[e as usize]));
                faces.values.extend(face.geometry.to_values());
                faces.values.extend(face.coefficients.iter().flatten());
            }
        }
    }

    fn apply(
        &mut self,
        view: &LocalView,
        from: Rank,
        update: &Update,
    ) -> Result<(), PitchingError> {
        let rank = view.rank();
        let (elements, faces) = (&update.elements, &update.faces);
        let sizes = [
            (CellKind::Element, elements, self.stride),
            (CellKind::Face, faces, FACE_VALUES),
        ];
        for (kind, cells, expected) in sizes {
            if cells.values.len() != cells.len() * expected {
                return Err(PitchingError::CellSize {
                    rank,
                    from,
                    kind,
                    got: cells.stride(),
                    expected,
                });
            }
        }
        if let Some(held) = &mut self.held {
            held.merge(update.work.iter().copied());
        }
        let stray = |kind, id| PitchingError::StrayCell {
            rank,
            from,
            kind,
            id,
        };
        for i in 0..elements.len() {
            let (global, generation, values) = elements.get(i);
            let t = view
                .local_triangle(global)
                .filter(|&t| view.held_by(t, from))
                .ok_or(stray(CellKind::Element, global))?;
            if generation <= self.generation[t as usize] {
                continue;
            }
            self.generation[t as usize] = generation;
            let (geometry, rest) = values.split_at(GEOMETRY_VALUES);
            let (energy, coefficients) = rest.split_at(ENERGY_VALUES);
            let geometry = Geometry::from_values(geometry.try_into().expect("split there"));
            let energy: [f64; ENERGY_VALUES] = energy.try_into().expect("split there");
            let energy = energy.iter().all(|x| !x.is_nan()).then_some(energy);
            self.solution
                .store(t as usize, &geometry, coefficients, energy);
        }
        for i in 0..faces.len() {
            let (global, generation, values) = faces.get(i);
            // A face comes with the tent at one of its edge's ends.
            let e = view
                .local_edge(global)
                .filter(|&e| {
                    let ends = view.mesh().edges()[e as usize].vertices;
                    ends.iter().any(|&v| view.owner(v) == from)
                })
                .filter(|_| !self.edge_generation.is_empty())
                .ok_or(stray(CellKind::Face, global))?;
            if generation <= self.edge_generation[e as usize] {
                continue;
            }
            self.edge_generation[e as usize] = generation;
            let (geometry, coefficients) = values.split_at(FACE_GEOMETRY_VALUES);
            let face = FaceState {
                geometry: FaceGeometry::from_values(geometry.try_into().expect("split there")),
                coefficients: std::array::from_fn(|k| {
                    std::array::from_fn(|j| coefficients[k * MAX_FACE_BASIS + j])
                }),
            };
            self.solution.store_face(e as usize, &face);
        }
        Ok(())
    }

    fn into_report(self, report: &mut RankReport) {
        report.patches = self.patches;
        report.held = self.held;
    }
}

/// [`crate::pitch_rank`] that also solves each tent's patch with `physics` on `solution`, the
/// elements under the view's triangles (local ids; [`Physics::initial_solution`] at the start,
/// with `front` flat at time 0), and sends other ranks the elements they read with the updates.
/// At the end every element of `solution` is the serial run's, bitwise.
pub fn solve_rank<T: Transport>(
    view: &LocalView,
    pitcher: &sdg_mesh::Pitcher,
    front: &Front,
    solution: &FrontSolution,
    physics: Physics<'_>,
    transport: &mut T,
    options: &Options,
) -> Result<RankReport, PitchingError> {
    let (rank, observer) = ((view, pitcher, front, solution), &mut ());
    solve_rank_observed(rank, physics, transport, observer, options)
}

/// [`solve_rank`] on `(view, pitcher, front, solution)` telling `observer` of each tent
/// solved.
pub fn solve_rank_observed<T: Transport, O: Observer>(
    (view, pitcher, front, solution): (&LocalView, &sdg_mesh::Pitcher, &Front, &FrontSolution),
    physics: Physics<'_>,
    transport: &mut T,
    observer: &mut O,
    options: &Options,
) -> Result<RankReport, PitchingError> {
    let max_star = view
        .owned()
        .map(|v| view.mesh().vertex_triangles(v).len())
        .max()
        .unwrap_or(0);
    let solver = physics.solver(max_star);
    let size = solver.basis().len() * solver.width();
    let (triangles, edges) = (view.mesh().triangles().len(), view.mesh().edges().len());
    let faces = physics.interfaces.any_nonlinear();
    let sizes = [
        ("triangles", solution.len(), triangles),
        (
            "values per element",
            solution.basis_len() * solution.width(),
            size,
        ),
        (
            "edges",
            solution.edges(),
            if faces { edges } else { solution.edges() },
        ),
    ];
    for (what, got, expected) in sizes {
        if got != expected {
            return Err(PitchingError::Solution {
                rank: view.rank(),
                what,
                got,
                expected,
            });
        }
    }
    let threads = options.threads.max(1);
    let ranks = transport.ranks();
    let held = options.held.clone().map(|mut held| {
        held.known.resize(ranks, 0.0);
        held
    });
    let sent_work = match held {
        Some(_) => vec![vec![0.0; ranks]; ranks],
        None => Vec::new(),
    };
    let (tents, taken) = channel::<(Tent, Guard)>();
    let (solved, done) = channel();
    let taken = Mutex::new(taken);
    let crew = (threads > 1).then(|| Crew {
        tents,
        taken: &taken,
        solved: done,
    });
    let work = Patches {
        solving: Solving { solver, crew },
        observer,
        physics,
        solution,
        generation: vec![0; triangles],
        edge_generation: if faces { vec![0; edges] } else { Vec::new() },
        stride: GEOMETRY_VALUES + ENERGY_VALUES + size,
        patches: Vec::new(),
        keep_tents: options.keep_tents,
        held,
        sent_work,
    };
    if threads == 1 {
        return run_rank(view, pitcher, front, transport, work, options);
    }
    std::thread::scope(|s| {
        let rank = (view, front, solution);
        for _ in 1..threads {
            let (physics, taken, solved) = (&physics, &taken, solved.clone());
            let solver = physics.solver(max_star);
            s.spawn(move || solving_thread(solver, physics, rank, taken, &solved));
        }
        drop(solved);
        // Returning drops `work` and its end of `tents`: the solving threads end.
        run_rank(view, pitcher, front, transport, work, options)
    })
}

/// Runs [`solve_rank`] for every rank of `partition` on threads of this process, connected by
/// [`crate::Loopback`] with `delays`, from initial data at time 0. Returns the ranks' results
/// by rank, or the first error by rank that is not an [`PitchingError::Aborted`].
pub fn solve_threads(
    mesh: &Mesh,
    partition: &Partition,
    causality: Causality,
    physics: Physics<'_>,
    delays: LoopbackOptions,
    options: &Options,
) -> Result<Vec<RankSolution>, PitchingError> {
    let mut observers = vec![(); partition.ranks()];
    let run = (causality, physics, delays);
    solve_threads_observed(mesh, partition, run, &mut observers, options)
}

/// [`solve_threads`] with `(causality, physics, delays)`, rank `r` telling `observers[r]` of
/// each tent it solved.
pub fn solve_threads_observed<O: Observer + Send>(
    mesh: &Mesh,
    partition: &Partition,
    (causality, physics, delays): (Causality, Physics<'_>, LoopbackOptions),
    observers: &mut [O],
    options: &Options,
) -> Result<Vec<RankSolution>, PitchingError> {
    let views = LocalView::all(mesh, partition)?;
    let start = vec![0.0; mesh.vertices().len()];
    let ranks = views
        .iter()
        .map(|view| {
            let (pitcher, front) = rank_start(view, causality, &start)?;
            Ok((pitcher, front, physics.initial_solution(view)))
        })
        .collect::<Result<Vec<_>, PitchingError>>()?;
    let observers: Vec<std::sync::Mutex<&mut O>> =
        observers.iter_mut().map(std::sync::Mutex::new).collect();
    let reports = on_threads(&views, delays, |rank, end| {
        let (pitcher, front, solution) = &ranks[rank];
        let mut observer = observers[rank].lock().unwrap_or_else(|e| e.into_inner());
        solve_rank_observed(
            (&views[rank], pitcher, front, solution),
            physics,
            end,
            &mut **observer,
            options,
        )
    })?;
    Ok(reports
        .into_iter()
        .zip(views)
        .zip(ranks)
        .map(|((report, view), (_, front, solution))| RankSolution {
            report,
            view,
            front,
            solution,
        })
        .collect())
}
