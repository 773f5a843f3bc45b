//! Asynchronous tent pitching over ranks: each rank pitches its owned vertices on its own view
//! and tells the ranks that hold them as ghosts.
//!
//! # Rule
//! A rank pitches an owned vertex `v` when `v` is below the end time and comes first in the
//! order of `(time, global id)` among its neighbours, as the rank sees them: owned neighbours
//! exactly, ghosts as the last [`Update`] received. After the tent it sends `v`'s new time and
//! generation (tents so far at `v`) to every rank holding `v` as a ghost; a receiver applies an
//! update only if its generation is newer than its copy's.
//!
//! # Why this is the serial order's front, for any partition and timing
//! Front times only grow and a ghost copy is some earlier time of its vertex, so a copy is
//! never ahead. Suppose `v` passes the rule with ghost `w` seen at `t'_w` but `w` has already
//! been pitched from `t'_w`. That tent needed `(t'_w, w)` first among `w`'s neighbours as `w`'s
//! owner saw them, and its copy of `v` was at most `v`'s time then, at most `t_v` now: so
//! `(t'_w, w) < (t_v, v)`, against the rule `v` passed. Hence a vertex that passes reads
//! exactly the current times of its whole star, and tents at neighbouring vertices happen in
//! the order of their `(t_old, id)`, as in the serial reference order (always the earliest
//! vertex, ties to the smaller id, `sdg_scheduler::run_serial`). Each tent's inputs are thus
//! the serial run's, bitwise: the per-vertex tent sequences are the same for every partition
//! and message timing. A rank whose candidate waits behind a stale ghost is woken by the
//! update that ghost's owner sends, so no wake-up is lost.
//!
//! # Termination
//! A rank with no owned vertex below the end time sends [`Message::Done`] with the number of
//! messages it sent each neighbour rank; it stops when every neighbour rank has said done and
//! it received as many messages from each as announced. No global poll; messages may arrive in
//! any order (FIFO per pair is not needed). An error on a rank sends [`Message::Abort`] to
//! every other rank, which stop with [`PitchingError::Aborted`].
//!
//! # Pauses (checkpoints)
//! A run may end before the end time, every message delivered, so that the caller can gather
//! the front and go on (or restart) from it ([`Pause`]). With [`Pause::at`] a rank pitches
//! only vertices below that time and is done when every owned vertex has reached it: the
//! ranks stop after exactly the tents with `t_old` below it, the same cut for every
//! partition and timing, with no tent capped (a tent is the uninterrupted run's). On a
//! [`Pause::requested`] request (a signal, a wall-time limit) a rank stops pitching at once
//! and sends [`Message::Pause`] to its neighbour ranks (counted in its done count), which stop
//! too and pass it on unless they said done already; the ranks then stop wherever they are.
//! Either way the front and the elements on every rank are a state of the uninterrupted run
//! (no update is in flight once every rank has finished), and the tents that follow from it
//! are that run's: per-vertex tent sequences depend on the front and the elements only, and a
//! new run from the paused state starts its generations afresh, which is safe because no
//! message of the old run is left.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;
use std::time::{Duration, Instant};

use sdg_mesh::{Front, Mesh, PitchError, Pitcher, Tent, VertexId};
use sdg_solver::patch::{BLOW_UP, NewtonFailure, PatchReport};

use crate::held::Held;
use crate::partition::{Partition, Rank};
use crate::rng::SplitMix64;
use crate::transport::loopback::{Loopback, LoopbackOptions};
use crate::transport::{Message, Transport, TransportError, Update};
use crate::view::{LocalView, ViewError};

/// How a rank runs.
#[derive(Clone, Debug)]
pub struct Options {
    /// Seed of the order in which a rank tries its candidates (any order gives the same front).
    pub seed: u64,
    /// Longest wait for a message while something is left to do; then the rank reports a stall.
    pub idle_limit: Duration,
    /// When to stop before the end time.
    pub pause: Pause,
    /// Threads that solve a rank's tents ([`crate::solve_rank`]), at least 1, the rank's own
    /// included. With more than one, the rank's thread pitches and talks to the other ranks
    /// while the others solve, keeping up to [`IN_FLIGHT_PER_THREAD`] tents per thread in
    /// flight, and solves one of them itself when it has nothing else to do; the tents are
    /// the same for any count.
    pub threads: usize,
    /// With patches solved ([`crate::solve_rank`]): what this rank knows of the energy the
    /// body has held, for the blow-up guard ([`PitchingError::BlowUp`]); none: no guard.
    pub held: Option<Held>,
    /// Keep every tent and its patch in the [`RankReport`] (`tents`, `patches`), as the tests
    /// that compare them with the serial order need. A caller that sums what it needs of each
    /// patch as it is solved (an [`crate::Observer`]) sets it false, so that a rank's memory
    /// does not grow with its tents; [`RankReport::pitched`] counts them either way.
    pub keep_tents: bool,
}

/// Tents a rank keeps in flight per solving thread ([`Options::threads`]): enough that a thread
/// that finishes finds the next while the rank's thread is busy.
pub const IN_FLIGHT_PER_THREAD: usize = 4;

/// Longest a rank with tents in flight and nothing to pitch waits for one to land before it
/// looks for updates again.
const LANDING_WAIT: Duration = Duration::from_micros(200);

impl Options {
    /// A rank seeded `seed` that reports a stall after `idle_limit`, running to the end time.
    pub fn new(seed: u64, idle_limit: Duration) -> Self {
        Self {
            seed,
            idle_limit,
            pause: Pause::default(),
            threads: 1,
            held: None,
            keep_tents: true,
        }
    }
}

/// A request to pause, asked between tents; true stops the rank.
pub type PauseRequest = Arc<dyn Fn() -> bool + Send + Sync>;

/// When a rank stops before the end time (see the module docs): at a time, or when asked.
#[derive(Clone, Default)]
pub struct Pause {
    /// Pitch only vertices below this time, s; none: to the end time.
    pub at: Option<f64>,
    /// Asked between tents: true stops pitching now and tells the other ranks.
    pub requested: Option<PauseRequest>,
}

impl std::fmt::Debug for Pause {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Pause")
            .field("at", &self.at)
            .field("requested", &self.requested.is_some())
            .finish()
    }
}

/// The causality parameters every rank builds its [`Pitcher`] from, on its own view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Causality {
    /// Fastest wave speed, m/s.
    pub c_max: f64,
    /// Safety factor in (0, 1).
    pub safety: f64,
    /// End time, s.
    pub t_end: f64,
}

/// Why distributed pitching failed.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PitchingError {
    #[error("rank {rank}: {source}")]
    Transport { rank: Rank, source: TransportError },
    #[error(transparent)]
    View(#[from] ViewError),
    #[error(transparent)]
    Pitch(#[from] PitchError),
    #[error("the start front has {front} vertices, but the mesh has {mesh}")]
    FrontLength { front: usize, mesh: usize },
    #[error(
        "rank {rank}: no progress for {waited:?}: {remaining} owned vertices are below the end \
         time and no message came"
    )]
    Stalled {
        rank: Rank,
        remaining: usize,
        waited: Duration,
    },
    #[error("rank {rank}: an update of vertex {vertex} from rank {from}, which does not own it")]
    Stray {
        rank: Rank,
        from: Rank,
        vertex: VertexId,
    },
    #[error("rank {rank}: the tent at vertex {vertex} (time {time} s) did not advance it")]
    NoAdvance {
        rank: Rank,
        vertex: VertexId,
        time: f64,
    },
    #[error("rank {rank} stopped because rank {by} failed")]
    Aborted { rank: Rank, by: Rank },
    #[error("gathering the results on rank 0: rank {rank}: {reason}")]
    Gather { rank: Rank, reason: String },
    #[error("rank {rank}: internal error (a bug, please report it): {message}")]
    Panic { rank: Rank, message: String },
    #[error(
        "rank {rank}: the patch of vertex {vertex} at t = {time} s: {name} is {value} (a \
         non-finite value); nothing of it was stored"
    )]
    NonFinite {
        rank: Rank,
        vertex: VertexId,
        time: f64,
        name: &'static str,
        value: f64,
    },
    #[error(
        "rank {rank}: the patch of vertex {vertex} at t = {time} s: energy blow-up: it carries \
         {out:e} J/m out, more than {BLOW_UP} times the {held:e} J/m the body has held as far as \
         this rank knows; nothing of it was stored"
    )]
    BlowUp {
        rank: Rank,
        vertex: VertexId,
        time: f64,
        out: f64,
        held: f64,
    },
    #[error("rank {rank}: the patch of vertex {vertex} at t = {time} s: {source}")]
    Patch {
        rank: Rank,
        vertex: VertexId,
        time: f64,
        source: NewtonFailure,
    },
    #[error(
        "rank {rank}: the {kind} of global id {id} from rank {from}, which one of them does not \
         hold"
    )]
    StrayCell {
        rank: Rank,
        from: Rank,
        kind: CellKind,
        id: u32,
    },
    #[error(
        "rank {rank}: the front solution has {got} {what}, but the view and the solver need \
         {expected}"
    )]
    Solution {
        rank: Rank,
        what: &'static str,
        got: usize,
        expected: usize,
    },
    #[error(
        "rank {rank}: {kind}s of {got} values from rank {from}, but this rank's have {expected}"
    )]
    CellSize {
        rank: Rank,
        from: Rank,
        kind: CellKind,
        got: usize,
        expected: usize,
    },
}

/// What a cell of an update is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellKind {
    /// An element under a front triangle.
    Element,
    /// An interface face over a front edge.
    Face,
}

impl std::fmt::Display for CellKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            CellKind::Element => "element",
            CellKind::Face => "interface face",
        })
    }
}

/// What a rank does besides pitching: with each of its tents, and with the elements that
/// updates carry. Nothing for pitching alone (`()`); [`crate::solving`] solves the patches.
pub(crate) trait Work {
    /// Called right after the tent at owned local vertex `tent.vertex` was pitched (`front`
    /// has its new time already).
    fn tent(&mut self, view: &LocalView, front: &Front, tent: &Tent) -> Result<(), PitchingError>;

    /// Starts what [`Work::tent`] does for `tent` on a thread of the work's own and returns
    /// true; false when the work has no threads ([`Work::tent`] is called then). Until
    /// [`Work::finish`] returns it, no neighbour of the tent's vertex is pitched.
    fn start(&mut self, tent: &Tent) -> bool {
        let _ = tent;
        false
    }

    /// Does the work of a tent [`Work::start`]ed before that no thread of the work has taken
    /// yet, on the caller's thread, completed as [`Work::tent`] would; `None` if there is none.
    fn help(&mut self, view: &LocalView, front: &Front) -> Result<Option<Tent>, PitchingError> {
        let _ = (view, front);
        Ok(None)
    }

    /// A tent [`Work::start`]ed before whose work is done, completed as [`Work::tent`] would,
    /// waiting up to `wait` for one; `None` if none is done by then.
    fn finish(
        &mut self,
        view: &LocalView,
        front: &Front,
        wait: Duration,
    ) -> Result<Option<Tent>, PitchingError> {
        let _ = (view, front, wait);
        Ok(None)
    }

    /// Writes into `update`'s (empty) cells what rank `to` reads of the last tent at owned
    /// local vertex `v`.
    fn cells_for(&mut self, view: &LocalView, v: VertexId, to: Rank, update: &mut Update);

    /// Stores the cells of `update` from rank `from` that are newer than this rank's copies.
    fn apply(&mut self, view: &LocalView, from: Rank, update: &Update)
    -> Result<(), PitchingError>;

    /// Adds what the work recorded to the rank's `report`, at the end of a run.
    fn into_report(self, _report: &mut RankReport)
    where
        Self: Sized,
    {
    }
}

impl Work for () {
    fn tent(&mut self, _: &LocalView, _: &Front, _: &Tent) -> Result<(), PitchingError> {
        Ok(())
    }

    fn cells_for(&mut self, _: &LocalView, _: VertexId, _: Rank, _: &mut Update) {}

    fn apply(&mut self, _: &LocalView, _: Rank, _: &Update) -> Result<(), PitchingError> {
        Ok(())
    }
}

/// What a rank did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RankReport {
    /// The rank.
    pub rank: Rank,
    /// Its tents in the order it pitched them, with global vertex ids ([`Options::keep_tents`];
    /// empty otherwise).
    pub tents: Vec<Tent>,
    /// How many tents it pitched.
    pub pitched: u64,
    /// Update messages sent (one per tent and ghost-holding rank).
    pub updates_sent: u64,
    /// Bytes of the updates sent, as [`Message::encode`] writes them.
    pub update_bytes: u64,
    /// Updates applied to ghost copies.
    pub updates_applied: u64,
    /// Updates ignored because the copy was as new already.
    pub updates_stale: u64,
    /// Owned vertices that another rank holds as a ghost.
    pub boundary_vertices: usize,
    /// Time spent waiting for messages with nothing to pitch.
    pub waited: Duration,
    /// With patches solved ([`crate::solve_rank`]) and [`Options::keep_tents`], one per tent in
    /// the order of `tents`; empty for pitching alone.
    pub patches: Vec<SolvedPatch>,
    /// Values the caller sets after the run (its observer's results, see
    /// [`crate::solving::Observer`]), which [`crate::gather`] carries to rank 0 as they are.
    pub outputs: Vec<f64>,
    /// Owned vertices left below the end time: more than 0 after a [`Pause`].
    pub below_end: usize,
    /// The rank stopped on a [`Pause::requested`] request or a neighbour's [`Message::Pause`].
    pub paused: bool,
    /// [`Options::held`] at the end, with what the rank learned and did.
    pub held: Option<Held>,
}

/// What a solved patch adds to a run's totals.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolvedPatch {
    /// The patch solver's report (scaled units).
    pub report: PatchReport,
    /// The steepest front facet of the tent's star after the tent, `|grad t|`, s/m.
    pub slope: f64,
}

/// A rank's running state.
struct Runner<'v, T, W> {
    view: &'v LocalView,
    pitcher: &'v Pitcher,
    front: &'v Front,
    transport: &'v mut T,
    work: W,
    /// Per local vertex, tents pitched at it (owned) or as last heard (ghost).
    generation: Vec<u32>,
    /// Per local vertex, whether its tent is in flight ([`Work::start`]), and how many are.
    in_flight: Vec<bool>,
    flying: usize,
    /// Candidates to try: those that other ranks hold as ghosts (whose tents the neighbour
    /// ranks wait for), tried first, and the others; and whether each local vertex is one.
    shared: Vec<VertexId>,
    candidates: Vec<VertexId>,
    queued: Vec<bool>,
    order: SplitMix64,
    /// Pitch only vertices below this time, s: the end time or the pause's.
    limit: f64,
    /// Owned vertices below `limit`.
    below: usize,
    /// Asked between tents whether to stop.
    requested: Option<PauseRequest>,
    /// Stopped on a request or a neighbour's pause; and whether the neighbours were told.
    paused: bool,
    told: bool,
    /// Per rank, messages sent to it and received from it, and its done count if it said so.
    sent: Vec<u64>,
    received: Vec<u64>,
    done: Vec<Option<u64>>,
    report: RankReport,
    keep_tents: bool,
}

impl<T: Transport, W: Work> Runner<'_, T, W> {
    fn rank(&self) -> Rank {
        self.view.rank()
    }

    fn offer(&mut self, v: VertexId) {
        if self.view.is_owned(v) && !self.queued[v as usize] && self.front.time(v) < self.limit {
            self.queued[v as usize] = true;
            match self.view.sharers(v).is_empty() {
                true => self.candidates.push(v),
                false => self.shared.push(v),
            }
        }
    }

    fn offer_neighbours(&mut self, v: VertexId) {
        for &w in self.view.mesh().vertex_neighbors(v) {
            self.offer(w);
        }
    }

    /// True when owned `v` is below the limit and first in `(time, global id)` among its
    /// neighbours on this rank's view, and neither it nor a neighbour has a tent in flight.
    fn is_first(&self, v: VertexId) -> bool {
        let (t, g) = (self.front.time(v), self.view.global(v));
        t < self.limit
            && !self.in_flight[v as usize]
            && self.view.mesh().vertex_neighbors(v).iter().all(|&w| {
                let tw = self.front.time(w);
                !self.in_flight[w as usize] && (tw > t || (tw == t && self.view.global(w) > g))
            })
    }

    /// A candidate that passes the rule, one that other ranks hold first, each in seeded random
    /// order; drops those that do not pass (what blocks them offers them again when it moves).
    fn next_ready(&mut self) -> Option<VertexId> {
        loop {
            let pool = match (self.shared.is_empty(), self.candidates.is_empty()) {
                (false, _) => &mut self.shared,
                (true, false) => &mut self.candidates,
                (true, true) => return None,
            };
            let v = pool.swap_remove(self.order.below(pool.len()));
            self.queued[v as usize] = false;
            if self.is_first(v) {
                return Some(v);
            }
        }
    }

    fn send(&mut self, to: Rank, message: Message) -> Result<(), PitchingError> {
        self.sent[to as usize] += 1;
        let rank = self.rank();
        self.transport
            .send(to, message)
            .map_err(|source| PitchingError::Transport { rank, source })
    }

    /// Pitches `v`, which passed the rule, and has the work do its tent: here, then its
    /// updates and candidates; or on the work's threads, and those when it is done.
    fn pitch(&mut self, v: VertexId) -> Result<(), PitchingError> {
        let t_old = self.front.time(v);
        let tent = self
            .pitcher
            .pitch(self.view.mesh(), self.front, v)
            .filter(|tent| tent.t_new > t_old);
        let Some(tent) = tent else {
            return Err(PitchingError::NoAdvance {
                rank: self.rank(),
                vertex: self.view.global(v),
                time: t_old,
            });
        };
        if self.work.start(&tent) {
            self.in_flight[v as usize] = true;
            self.flying += 1;
            return Ok(());
        }
        self.work.tent(self.view, self.front, &tent)?;
        self.after_tent(&tent)
    }

    /// Takes the tents in flight whose work is done, waiting up to `wait` for the first;
    /// returns how many.
    fn land(&mut self, wait: Duration) -> Result<usize, PitchingError> {
        let mut landed = 0;
        let mut wait = wait;
        while self.flying > 0 {
            let Some(tent) = self.work.finish(self.view, self.front, wait)? else {
                break;
            };
            self.landed(&tent)?;
            landed += 1;
            wait = Duration::ZERO;
        }
        Ok(landed)
    }

    /// A tent in flight whose work is done: [`Runner::after_tent`].
    fn landed(&mut self, tent: &Tent) -> Result<(), PitchingError> {
        self.in_flight[tent.vertex as usize] = false;
        self.flying -= 1;
        self.after_tent(tent)
    }

    /// After the work did `tent` at an owned vertex: its generation, its updates to the ranks
    /// holding it as a ghost, and the candidates it makes.
    fn after_tent(&mut self, tent: &Tent) -> Result<(), PitchingError> {
        let v = tent.vertex;
        self.generation[v as usize] += 1;
        if tent.t_new >= self.limit {
            self.below -= 1;
        }
        for i in 0..self.view.sharers(v).len() {
            let to = self.view.sharers(v)[i];
            let mut update = Update {
                vertex: self.view.global(v),
                time: tent.t_new,
                generation: self.generation[v as usize],
                ..Update::default()
            };
            self.work.cells_for(self.view, v, to, &mut update);
            self.report.updates_sent += 1;
            self.report.update_bytes += update.encoded_len() as u64;
            self.send(to, Message::Update(update))?;
        }
        self.report.pitched += 1;
        if self.keep_tents {
            self.report.tents.push(Tent {
                vertex: self.view.global(v),
                ..*tent
            });
        }
        self.offer(v);
        self.offer_neighbours(v);
        Ok(())
    }

    fn handle(&mut self, from: Rank, message: Message) -> Result<(), PitchingError> {
        let rank = self.rank();
        match message {
            Message::Update(u) => {
                self.received[from as usize] += 1;
                let w = self
                    .view
                    .local(u.vertex)
                    .filter(|&w| self.view.owner(w) == from)
                    .ok_or(PitchingError::Stray {
                        rank,
                        from,
                        vertex: u.vertex,
                    })?;
                self.work.apply(self.view, from, &u)?;
                if u.generation > self.generation[w as usize] {
                    self.generation[w as usize] = u.generation;
                    self.front.set_time(w, u.time);
                    self.report.updates_applied += 1;
                    self.offer_neighbours(w);
                } else {
                    self.report.updates_stale += 1;
                }
            }
            Message::Done { sent } => self.done[from as usize] = Some(sent),
            Message::Abort => return Err(PitchingError::Aborted { rank, by: from }),
            Message::Pause => {
                self.received[from as usize] += 1;
                self.paused = true;
            }
        }
        Ok(())
    }

    /// True when this rank pitches no more: paused, or every owned vertex at the limit; and
    /// no tent in flight.
    fn stopped(&self) -> bool {
        (self.paused || self.below == 0) && self.flying == 0
    }

    /// True when this rank is done and has heard all its neighbour ranks say so, with every
    /// message they announced received.
    fn finished(&self) -> bool {
        self.stopped()
            && self
                .view
                .neighbour_ranks()
                .iter()
                .all(|&r| self.done[r as usize] == Some(self.received[r as usize]))
    }

    fn run(&mut self, idle_limit: Duration, threads: usize) -> Result<(), PitchingError> {
        let rank = self.rank();
        let most = IN_FLIGHT_PER_THREAD * threads;
        let transport_error = |source| PitchingError::Transport { rank, source };
        let mut said_done = false;
        loop {
            while let Some((from, message)) = self
                .transport
                .receive(Duration::ZERO)
                .map_err(transport_error)?
            {
                self.handle(from, message)?;
            }
            if !self.paused && self.requested.as_ref().is_some_and(|r| r()) {
                self.paused = true;
            }
            if self.paused && !self.told && !said_done {
                self.told = true;
                for i in 0..self.view.neighbour_ranks().len() {
                    self.send(self.view.neighbour_ranks()[i], Message::Pause)?;
                }
            }
            self.land(Duration::ZERO)?;
            if !self.paused
                && self.flying < most
                && let Some(v) = self.next_ready()
            {
                self.pitch(v)?;
                continue;
            }
            if self.stopped() && !said_done {
                said_done = true;
                for i in 0..self.view.neighbour_ranks().len() {
                    let r = self.view.neighbour_ranks()[i];
                    let sent = self.sent[r as usize];
                    self.send(r, Message::Done { sent })?;
                }
            }
            if self.finished() {
                return Ok(());
            }
            if self.flying > 0 {
                // Nothing to pitch until a tent lands or an update arrives: solve a tent no
                // solving thread has taken, or wait for one to land briefly, then look for
                // updates (not counted as waiting for other ranks).
                match self.work.help(self.view, self.front)? {
                    Some(tent) => self.landed(&tent)?,
                    None => {
                        self.land(LANDING_WAIT)?;
                    }
                }
                continue;
            }
            let start = Instant::now();
            let message = self
                .transport
                .receive(idle_limit)
                .map_err(transport_error)?;
            self.report.waited += start.elapsed();
            match message {
                Some((from, message)) => self.handle(from, message)?,
                None => {
                    return Err(PitchingError::Stalled {
                        rank,
                        remaining: self.below,
                        waited: idle_limit,
                    });
                }
            }
        }
    }
}

/// Pitches the owned vertices of `view` to `pitcher`'s end time on `front` (the view's local
/// front, ghosts included), exchanging updates through `transport`, until this rank and its
/// neighbour ranks are done. On an error, tells every other rank to stop ([`Message::Abort`]).
///
/// `pitcher` is [`Pitcher::new`] on `view.mesh()`: its budgets are then bitwise the whole
/// mesh's. Not [`Pitcher::for_refinement`] on the view, whose margin is a minimum over the mesh
/// it is given (it must be the same on every rank).
pub fn pitch_rank<T: Transport>(
    view: &LocalView,
    pitcher: &Pitcher,
    front: &Front,
    transport: &mut T,
    options: &Options,
) -> Result<RankReport, PitchingError> {
    run_rank(view, pitcher, front, transport, (), options)
}

/// [`pitch_rank`] doing `work` besides.
pub(crate) fn run_rank<T: Transport, W: Work>(
    view: &LocalView,
    pitcher: &Pitcher,
    front: &Front,
    transport: &mut T,
    work: W,
    options: &Options,
) -> Result<RankReport, PitchingError> {
    let n = view.mesh().vertices().len();
    let ranks = transport.ranks();
    let t_end = pitcher.t_end();
    let limit = options.pause.at.map_or(t_end, |at| at.min(t_end));
    let mut state = Runner {
        view,
        pitcher,
        front,
        transport,
        work,
        generation: vec![0; n],
        in_flight: vec![false; n],
        flying: 0,
        shared: Vec::new(),
        candidates: Vec::new(),
        queued: vec![false; n],
        order: SplitMix64::new(options.seed ^ u64::from(view.rank())),
        limit,
        below: view.owned().filter(|&v| front.time(v) < limit).count(),
        requested: options.pause.requested.clone(),
        paused: false,
        told: false,
        sent: vec![0; ranks],
        received: vec![0; ranks],
        done: vec![None; ranks],
        report: RankReport {
            rank: view.rank(),
            boundary_vertices: view.boundary_vertices(),
            ..RankReport::default()
        },
        keep_tents: options.keep_tents,
    };
    for v in view.owned() {
        state.offer(v);
    }
    match state.run(options.idle_limit, options.threads.max(1)) {
        Ok(()) => {
            let mut report = state.report;
            report.below_end = view.owned().filter(|&v| front.time(v) < t_end).count();
            report.paused = state.paused;
            state.work.into_report(&mut report);
            Ok(report)
        }
        Err(e) => {
            abort_others(state.transport);
            Err(e)
        }
    }
}

/// Runs [`pitch_rank`] for every rank of `partition` on threads of this process, connected by
/// [`Loopback`] with `delays`, from the global front `start` (s, one time per vertex). Returns
/// the reports by rank, or the first error by rank that is not an [`PitchingError::Aborted`]
/// (a rank stopped by another's failure).
pub fn run_threads(
    mesh: &Mesh,
    partition: &Partition,
    start: &[f64],
    causality: Causality,
    delays: LoopbackOptions,
    options: &Options,
) -> Result<Vec<RankReport>, PitchingError> {
    if start.len() != mesh.vertices().len() {
        return Err(PitchingError::FrontLength {
            front: start.len(),
            mesh: mesh.vertices().len(),
        });
    }
    let views = LocalView::all(mesh, partition)?;
    let ranks = views
        .iter()
        .map(|view| rank_start(view, causality, start))
        .collect::<Result<Vec<_>, _>>()?;
    on_threads(&views, delays, |rank, end| {
        let (pitcher, front) = &ranks[rank];
        pitch_rank(&views[rank], pitcher, front, end, options)
    })
}

/// The pitcher and the local front at `start` (global, s) of the rank whose view is `view`.
pub(crate) fn rank_start(
    view: &LocalView,
    causality: Causality,
    start: &[f64],
) -> Result<(Pitcher, Front), PitchingError> {
    let pitcher = Pitcher::new(
        view.mesh(),
        causality.c_max,
        causality.safety,
        causality.t_end,
    )?;
    let front = Front::flat(view.mesh().vertices().len(), 0.0);
    for v in 0..front.len() as VertexId {
        front.set_time(v, start[view.global(v) as usize]);
    }
    Ok((pitcher, front))
}

/// Runs `rank(r, transport)` for every rank `r` of `views` on its own thread, connected by
/// [`Loopback`] with `delays`. Returns the results by rank, or the first error by rank that is
/// not an [`PitchingError::Aborted`] (a rank stopped by another's failure). A panic on a rank
/// aborts the others and is reported as [`PitchingError::Panic`].
pub(crate) fn on_threads<R: Send + std::fmt::Debug>(
    views: &[LocalView],
    delays: LoopbackOptions,
    rank: impl Fn(usize, &mut Loopback) -> Result<R, PitchingError> + Sync,
) -> Result<Vec<R>, PitchingError> {
    let ends = Loopback::connect(views.len(), delays);
    let rank = &rank;
    let results: Vec<Result<R, PitchingError>> = std::thread::scope(|s| {
        let handles: Vec<_> = ends
            .into_iter()
            .enumerate()
            .map(|(r, mut end)| {
                s.spawn(move || {
                    catch_unwind(AssertUnwindSafe(|| rank(r, &mut end))).unwrap_or_else(|payload| {
                        abort_others(&mut end);
                        Err(PitchingError::Panic {
                            rank: r as Rank,
                            message: panic_message(payload),
                        })
                    })
                })
            })
            .collect();
        handles
            .into_iter()
            .enumerate()
            .map(|(r, handle)| {
                handle.join().unwrap_or_else(|payload| {
                    Err(PitchingError::Panic {
                        rank: r as Rank,
                        message: panic_message(payload),
                    })
                })
            })
            .collect()
    });
    let failure = results
        .iter()
        .position(|r| matches!(r, Err(e) if !matches!(e, PitchingError::Aborted { .. })))
        .or_else(|| results.iter().position(Result::is_err));
    match failure {
        Some(i) => Err(results.into_iter().nth(i).expect("found").unwrap_err()),
        None => Ok(results.into_iter().map(|r| r.expect("no error")).collect()),
    }
}

/// Tells every other rank to stop, as far as the transport still can: the error at hand is
/// what the caller needs to see.
fn abort_others<T: Transport>(transport: &mut T) {
    let rank = transport.rank();
    for r in (0..transport.ranks() as Rank).filter(|&r| r != rank) {
        let _ = transport.send(r, Message::Abort);
    }
}

pub(crate) fn panic_message(payload: Box<dyn std::any::Any + Send>) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".to_string())
}
