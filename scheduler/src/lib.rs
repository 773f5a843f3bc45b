//! Physics-agnostic concurrent scheduling of tent pitches on an advancing front.
//!
//! Worker threads advance one shared [`Front`] together. A worker claims a vertex that is a local
//! minimum of the front (exclusive on the vertex, shared on its neighbours, see [`claim`]),
//! pitches its tent and solves its patch through [`Work::tent`], records it, releases the claim
//! and offers the vertex and its neighbours as new candidates. Topology changes are events that
//! run with exclusive access to the state: exclusive ones ([`Action`]) with no tent in flight,
//! regional ones ([`RegionalAction`]) beside tents that solve without the state's lock
//! ([`Lease::unlocked`]) and hold none of their vertices. The design, its invariants and why it
//! cannot deadlock or race are in `scheduler/README.md`.
//!
//! Two modes:
//! - asynchronous (default): candidates flow through work-stealing deques; a vertex is taken
//!   only when it comes first in `(time, id)` among its neighbours, so without events the front
//!   and solution are the serial reference order's, bitwise, for any thread count; events
//!   (refinement, coarsening, cracks) run when a worker gets to them, so with events the
//!   spacetime mesh depends on timing (equally accurate);
//! - deterministic: rounds of every vertex first in `(time, id)` among its neighbours, solved in
//!   parallel, recorded in that order, with events between rounds, so results depend only on the
//!   inputs, never on the thread count or timing; without events the tents are the serial order's
//!   and the asynchronous mode's.

pub mod claim;
mod error;
mod pool;
mod rounds;
mod serial;
mod sync;

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

use parking_lot::Mutex;
use sdg_mesh::{Front, Mesh};

pub use claim::{ClaimTable, VertexId};
pub use error::RunError;
use error::panic_message;
pub use serial::run_serial;

/// How to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Options {
    /// Worker threads, at least 1.
    pub threads: usize,
    /// Rounds of the vertices first among their neighbours instead of asynchronous claiming.
    pub deterministic: bool,
}

/// The data tents share: a space mesh and its front, plus whatever the engine keeps with them
/// (the solution under the front). Tents see it shared; events get it exclusively and may change
/// the mesh, appending vertices with their front times or removing them (the last vertex then
/// takes the removed one's id).
pub trait State: Send + Sync {
    /// The space mesh.
    fn mesh(&self) -> &Mesh;
    /// The front over [`State::mesh`], one time per vertex.
    fn front(&self) -> &Front;
}

/// A mesh and front that no event changes.
#[derive(Clone, Copy, Debug)]
pub struct Fixed<'m> {
    /// The space mesh.
    pub mesh: &'m Mesh,
    /// Its front.
    pub front: &'m Front,
}

impl State for Fixed<'_> {
    fn mesh(&self) -> &Mesh {
        self.mesh
    }

    fn front(&self) -> &Front {
        self.front
    }
}

/// What the engine does for each tent; `'a` is the lifetime of the data its events borrow.
pub trait Work<'a>: Sync {
    /// The shared mesh, front and solution.
    type State: State;
    /// Per-worker scratch memory (the patch solver's buffers).
    type Scratch: Send;
    /// What a tent produces for [`Work::record`].
    type Outcome: Send;
    /// A failure that stops the run.
    type Error: Send;

    /// Pitches the tent at `v` and solves its patch; returns the vertex's new time (s; equal to
    /// the old one when the tent is rejected) and the outcome. Called with `v` claimed
    /// exclusively and its neighbours shared, and `v` a local minimum of the front below the end
    /// time. A tent that leaves `v` in place must make sure an event changes something first
    /// (otherwise it would be retried forever); in asynchronous mode its claim is held until
    /// the next batch of events, so the event sees `v`'s star as the tent left it if the batch
    /// runs it (a regional event it puts back must check). May queue events, but only events
    /// queued by [`Work::record`] run in a fixed order in deterministic mode.
    ///
    /// The tent reads the state through `lease`; it may let go of it while it solves
    /// ([`Lease::unlocked`]), and events may then change the state away from its claim.
    fn tent(
        &self,
        lease: &mut Lease<'_, Self::State>,
        scratch: &mut Self::Scratch,
        v: VertexId,
        events: &Events<'a, Self::State>,
    ) -> Result<(f64, Self::Outcome), Self::Error>;

    /// Completes a finished tent's `outcome` with what [`Work::record`] reads from the state
    /// around `v`, so that recording is left with what must go in order. Asynchronous mode:
    /// called by the worker just before [`Work::record`]. Deterministic mode: called once every
    /// tent of the round has run, on any worker, with the state as the round left it (which
    /// [`Work::record`] sees too).
    fn settle(&self, state: &Self::State, v: VertexId, outcome: &mut Self::Outcome) {
        let _ = (state, v, outcome);
    }

    /// Records a finished and settled tent (outputs, energy sums). Asynchronous mode: called by
    /// the worker while it still holds the claim. Deterministic mode: called on one thread
    /// after each round, in the round's order. May queue events.
    fn record(
        &'a self,
        state: &Self::State,
        v: VertexId,
        outcome: Self::Outcome,
        events: &Events<'a, Self::State>,
    ) -> Result<(), Self::Error>;

    /// True asks the run to pause: it returns at the next quiescent point (no tent in flight,
    /// every queued event run) with [`Stats::paused`] set, and a later [`run`] on the same state
    /// goes on from there. Deterministic mode pauses between rounds, so a paused and resumed
    /// run is bitwise the same as an uninterrupted one. Polled before every tent or round.
    fn pause(&self) -> bool {
        false
    }

    /// Deterministic mode: called by a worker after it settled a chunk of a round's tents and
    /// checked which of the vertices they took are ready for the next round, with the time that
    /// took, `busy`, for a trace of the rounds. The chunks are the same for any thread count.
    fn settled(&self, busy: Duration) {
        let _ = busy;
    }

    /// Deterministic mode: called after each round and its events with the time the calling
    /// thread spent on the round alone, `serial` (choosing its vertices and recording its
    /// settled tents in order; not the events), for a trace of the rounds.
    fn round(&self, serial: Duration) {
        let _ = serial;
    }

    /// Deterministic mode split over processes that each hold the whole state and run the same
    /// rounds: whether this process solves the round's `index`-th tent, at `v`. The others
    /// come from [`Work::exchange`]. All, by default.
    fn solves(&self, index: usize, v: VertexId) -> bool {
        let _ = (index, v);
        true
    }

    /// Deterministic mode split over processes ([`Work::solves`]): called on the calling thread
    /// once every tent of the round this process solves has run, before any is settled, with
    /// the round's vertices in order and per vertex what its tent gave (a panic as its
    /// message), `None` where another process solved it. Gives the others this process's
    /// results and fills in theirs, applying what their tents wrote to `state`. An error ends
    /// the run. Nothing, by default.
    fn exchange(
        &self,
        state: &Self::State,
        round: &[VertexId],
        results: &mut [Option<Tried<Self::Outcome, Self::Error>>],
    ) -> Result<(), Self::Error> {
        let _ = (state, round, results);
        Ok(())
    }

    /// True when the rounds are split over processes and [`Work::exchange`] must be called.
    fn exchanges(&self) -> bool {
        false
    }
}

/// What a tent gave: its outcome or error, or the message of its panic.
pub type Tried<O, E> = Result<Result<O, E>, String>;

/// An event: runs with exclusive access to the state (no tent in flight) and reports what it
/// changed.
pub type Action<'a, S> = Box<dyn FnOnce(&mut S) -> Changed + Send + 'a>;

/// A regional event: runs with the state held exclusively while tents in flight elsewhere go on
/// solving ([`Lease::unlocked`]), and must leave their claims alone: it changes the star of no
/// vertex that `region` says is held ([`Region::is_free`]), nor its time, nor its id.
pub type RegionalAction<'a, S> = Box<dyn FnOnce(&mut S, &Region<'_>) -> Changed + Send + 'a>;

/// What a regional event will change, asked with the state held exclusively just before it
/// would run: the vertices whose stars, times or ids it changes. The event runs only when all of
/// them are free, so that it runs whole or waits; it must still check [`Region::is_free`] for
/// anything the list may have missed.
pub type Probe<'a, S> = Box<dyn Fn(&S) -> Vec<VertexId> + Send + 'a>;

/// Which vertices tents in flight hold, for a regional event.
#[derive(Clone, Copy, Debug)]
pub struct Region<'r> {
    claims: Option<&'r ClaimTable>,
}

impl Region<'_> {
    /// No tent is in flight: every vertex is free.
    pub fn everything() -> Region<'static> {
        Region { claims: None }
    }

    /// True when no tent in flight holds `v`: a regional event may change its star, its time
    /// and its id.
    pub fn is_free(&self, v: VertexId) -> bool {
        self.claims.is_none_or(|claims| claims.is_free(v))
    }
}

/// A queued event.
enum Queued<'a, S> {
    /// Runs with no tent in flight.
    Exclusive(Action<'a, S>),
    /// Runs beside tents in flight when its probe's vertices are free.
    Regional(Probe<'a, S>, RegionalAction<'a, S>),
}

impl<S> Queued<'_, S> {
    /// Runs the event with no tent in flight, and counts it run in `events`.
    fn run_alone(self, state: &mut S, events: &Events<'_, S>) -> Changed {
        let (changed, exclusive) = match self {
            Queued::Exclusive(action) => (action(state), true),
            Queued::Regional(_, action) => (action(state, &Region::everything()), false),
        };
        events.ran(exclusive);
        changed
    }
}

/// A tent's hold on the state: shared with other tents, exclusive of events. In asynchronous
/// mode a tent may let go of it while it solves, so that events can run elsewhere meanwhile;
/// in deterministic mode it is kept for the whole round.
pub struct Lease<'l, S> {
    hold: Hold<'l, S>,
}

impl<S> std::fmt::Debug for Lease<'_, S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kind = match self.hold {
            Hold::Kept(_) => "kept",
            Hold::Lock(_) => "lock",
        };
        f.debug_struct("Lease").field("hold", &kind).finish()
    }
}

enum Hold<'l, S> {
    Kept(&'l S),
    Lock(&'l mut dyn Relock<S>),
}

/// A read lock on the state that can be let go of for a while.
trait Relock<S> {
    fn state(&self) -> &S;
    fn unlocked(&mut self, f: &mut dyn FnMut());
}

impl<'l, S> Lease<'l, S> {
    /// A lease that holds `state` throughout: [`Lease::unlocked`] just runs its closure.
    pub fn kept(state: &'l S) -> Self {
        Self {
            hold: Hold::Kept(state),
        }
    }

    fn lock(lock: &'l mut dyn Relock<S>) -> Self {
        Self {
            hold: Hold::Lock(lock),
        }
    }

    /// The state, shared.
    pub fn state(&self) -> &S {
        match &self.hold {
            Hold::Kept(state) => state,
            Hold::Lock(lock) => lock.state(),
        }
    }

    /// Runs `f` without holding the state (the borrow of `&mut self` keeps every reference into
    /// it out of `f`); the tent's claim stays held, so the events that may run meanwhile leave
    /// its vertex's star, its neighbours' times and their ids as they are.
    pub fn unlocked<T>(&mut self, f: impl FnOnce() -> T) -> T {
        match &mut self.hold {
            Hold::Kept(_) => f(),
            Hold::Lock(lock) => {
                let (mut f, mut out) = (Some(f), None);
                lock.unlocked(&mut || out = f.take().map(|f| f()));
                out.expect("the unlocked closure runs once")
            }
        }
    }
}

/// What an event changed.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Changed {
    /// Vertices whose readiness may have changed, appended ones included (ids as after the
    /// event).
    pub offer: Vec<VertexId>,
    /// Vertices below the end time appended minus those removed.
    pub below_end: isize,
}

/// The queue of pending events.
pub struct Events<'a, S> {
    queue: Mutex<Vec<Queued<'a, S>>>,
    /// Events pushed and not yet run.
    pending: AtomicUsize,
    /// Exclusive events pushed and not yet run: tents stop starting until they have.
    exclusive: AtomicUsize,
    /// An event pushed with [`Events::push_now`] is queued.
    urgent: AtomicBool,
}

impl<S> Default for Events<'_, S> {
    fn default() -> Self {
        Self {
            queue: Mutex::new(Vec::new()),
            pending: AtomicUsize::new(0),
            exclusive: AtomicUsize::new(0),
            urgent: AtomicBool::new(false),
        }
    }
}

impl<S> std::fmt::Debug for Events<'_, S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Events")
            .field("pending", &self.pending.load(Ordering::Relaxed))
            .finish_non_exhaustive()
    }
}

impl<'a, S> Events<'a, S> {
    /// Queues `action`, to run with no tent in flight. Deterministic mode runs queued events
    /// in the order they were pushed.
    pub fn push(&self, action: Action<'a, S>) {
        self.queue.lock().push(Queued::Exclusive(action));
        self.exclusive.fetch_add(1, Ordering::AcqRel);
        self.pending.fetch_add(1, Ordering::AcqRel);
    }

    /// Queues `action` to run before the next tent any worker starts, with no tent in flight,
    /// where the asynchronous mode would otherwise let events gather into a batch: for events
    /// whose result depends on when they run, such as a record of the whole front at a
    /// milestone time. Deterministic mode runs every event after its round either way.
    pub fn push_now(&self, action: Action<'a, S>) {
        let mut queue = self.queue.lock();
        queue.push(Queued::Exclusive(action));
        self.exclusive.fetch_add(1, Ordering::AcqRel);
        self.pending.fetch_add(1, Ordering::AcqRel);
        self.urgent.store(true, Ordering::Release);
    }

    /// Queues the regional event `action`, which changes the state only at the vertices
    /// `probe` lists (see [`Probe`] and [`RegionalAction`]): asynchronous mode runs it beside
    /// the tents in flight once they hold none of them. Deterministic mode runs it after its
    /// round, in push order with the others.
    pub fn push_regional(&self, probe: Probe<'a, S>, action: RegionalAction<'a, S>) {
        self.queue.lock().push(Queued::Regional(probe, action));
        self.pending.fetch_add(1, Ordering::AcqRel);
    }

    /// True when an event pushed with [`Events::push_now`] waits.
    fn is_urgent(&self) -> bool {
        self.urgent.load(Ordering::Acquire)
    }

    /// True when an event that needs every tent finished waits.
    fn has_exclusive(&self) -> bool {
        self.exclusive.load(Ordering::Acquire) > 0
    }

    /// Takes every queued event, in push order.
    fn take(&self) -> Vec<Queued<'a, S>> {
        let mut queue = self.queue.lock();
        self.urgent.store(false, Ordering::Release);
        std::mem::take(&mut *queue)
    }

    /// Puts back events taken by [`Events::take`] that could not run yet, ahead of those
    /// pushed since, in their order.
    fn put_back(&self, events: Vec<Queued<'a, S>>) {
        if events.is_empty() {
            return;
        }
        let mut queue = self.queue.lock();
        let later = std::mem::replace(&mut *queue, events);
        queue.extend(later);
    }

    /// Counts one event run.
    fn ran(&self, exclusive: bool) {
        if exclusive {
            self.exclusive.fetch_sub(1, Ordering::AcqRel);
        }
        self.pending.fetch_sub(1, Ordering::AcqRel);
    }
}

/// Counts of a completed run.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Tents pitched.
    pub tents: u64,
    /// Tents per worker thread.
    pub tents_per_thread: Vec<u64>,
    /// Deterministic rounds (zero in asynchronous mode).
    pub rounds: u64,
    /// Topology events run.
    pub events: u64,
    /// The run paused at [`Work::pause`]'s request before the front reached the end time.
    pub paused: bool,
    /// Time spent running events, with the state held exclusively.
    pub event_time: Duration,
    /// Time the workers spent without a tent, summed over workers: asleep with nothing ready,
    /// waiting for the state's lock (events) or, in deterministic mode, at the round's
    /// barriers while others solve, the calling thread records and events run.
    pub wait_time: Duration,
}

/// Nanoseconds summed from several threads.
#[derive(Debug, Default)]
struct Clock(std::sync::atomic::AtomicU64);

impl Clock {
    /// Adds the time since `start`.
    fn add_since(&self, start: std::time::Instant) {
        let ns = u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
        self.0.fetch_add(ns, Ordering::Relaxed);
    }

    fn total(&self) -> Duration {
        Duration::from_nanos(self.0.load(Ordering::Relaxed))
    }
}

/// True when `v` is below `t_end` and comes first in the order of `(time, id)` among its
/// neighbours: no neighbour is earlier, and none at exactly the same time has a smaller id. Two such vertices are never neighbours, and a
/// tent elsewhere changes neither whether `v` is one nor what its tent reads, so tents taken by
/// this rule in any order give the serial reference order's front and solution
/// ([`run_serial`]: always the earliest vertex, ties to the smaller id).
fn is_first_among_neighbours<S: State>(state: &S, t_end: f64, v: VertexId) -> bool {
    let front = state.front();
    (v as usize) < front.len() && front.time(v) < t_end && {
        let t = front.time(v);
        state.mesh().vertex_neighbors(v).iter().all(|&w| {
            let tw = front.time(w);
            tw > t || (tw == t && w > v)
        })
    }
}

/// Vertices of `state` below `t_end`.
fn below_end<S: State>(state: &S, t_end: f64) -> usize {
    (0..state.front().len() as VertexId)
        .filter(|&v| state.front().time(v) < t_end)
        .count()
}

/// Advances every vertex of the state's front to `t_end` with one worker per element of
/// `scratch`. Events may refine the mesh meanwhile; the run ends when every vertex, old or new,
/// has reached `t_end`.
pub fn run<'a, W: Work<'a>>(
    state: &mut W::State,
    t_end: f64,
    work: &'a W,
    scratch: Vec<W::Scratch>,
    options: &Options,
) -> Result<Stats, RunError<W::Error>> {
    assert!(!scratch.is_empty(), "at least one worker");
    if options.deterministic {
        rounds::run(state, t_end, work, scratch)
    } else {
        pool::run(state, t_end, work, scratch)
    }
}
