//! Physics-agnostic concurrent scheduling of tent pitches on an advancing front.
//!
//! Worker threads advance one shared [`Front`] together. A worker claims a vertex that is a local
//! minimum of the front (exclusive on the vertex, shared on its neighbours, see [`claim`]),
//! pitches its tent and solves its patch through [`Work::tent`], records it, releases the claim
//! and offers the vertex and its neighbours as new candidates. Topology changes are [`Event`]s
//! that claim a whole region the same way. The design, its invariants and why it cannot deadlock
//! or race are in `scheduler/README.md`.
//!
//! Two modes:
//! - asynchronous (default): candidates flow through work-stealing deques; results are equally
//!   accurate but the order of tents, hence the spacetime mesh, depends on timing;
//! - deterministic: rounds of a deterministically chosen independent set of ready vertices, solved
//!   in parallel and recorded in a fixed order, so results depend only on the inputs, never on the
//!   thread count or timing.

pub mod claim;
mod pool;
mod rounds;
mod serial;
mod sync;

use std::sync::atomic::{AtomicUsize, Ordering};

use parking_lot::Mutex;
use sdg_mesh::{Front, Mesh};

pub use claim::{ClaimTable, VertexId};
pub use serial::run_serial;

/// How to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Options {
    /// Worker threads, at least 1.
    pub threads: usize,
    /// Rounds of independent sets instead of asynchronous claiming.
    pub deterministic: bool,
}

/// What the engine does for each tent; `'a` is the lifetime of the data its events borrow.
pub trait Work<'a>: Sync {
    /// Per-worker scratch memory (the patch solver's buffers).
    type Scratch: Send;
    /// What a tent produces for [`Work::record`].
    type Outcome: Send;
    /// A failure that stops the run.
    type Error: Send;

    /// Pitches the tent at `v` and solves its patch; returns the vertex's new time (s) and the
    /// outcome. Called with `v` claimed exclusively and its neighbours shared, and `v` a local
    /// minimum of the front below the end time. May queue topology events.
    fn tent(
        &self,
        scratch: &mut Self::Scratch,
        v: VertexId,
        events: &Events<'a>,
    ) -> Result<(f64, Self::Outcome), Self::Error>;

    /// Records a finished tent (outputs, energy sums). Asynchronous mode: called by the worker
    /// while it still holds the claim. Deterministic mode: called on one thread after each round,
    /// in the round's order. May queue topology events.
    fn record(
        &'a self,
        v: VertexId,
        outcome: Self::Outcome,
        events: &Events<'a>,
    ) -> Result<(), Self::Error>;
}

/// A topology change: runs once no tent overlaps `region` (the vertices it modifies; their
/// neighbours are claimed shared), with no tent starting in the region meanwhile.
pub struct Event<'a> {
    /// Vertices whose star the event may change.
    pub region: Vec<VertexId>,
    /// The change.
    pub action: Box<dyn FnOnce() + Send + 'a>,
}

impl std::fmt::Debug for Event<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Event")
            .field("region", &self.region)
            .finish_non_exhaustive()
    }
}

/// The queue of pending topology events.
#[derive(Debug, Default)]
pub struct Events<'a> {
    queue: Mutex<Vec<Event<'a>>>,
    /// Events pushed and not yet run.
    pending: AtomicUsize,
}

impl<'a> Events<'a> {
    /// Queues `action` to run exclusively on `region`.
    pub fn push(&self, region: Vec<VertexId>, action: Box<dyn FnOnce() + Send + 'a>) {
        self.queue.lock().push(Event { region, action });
        self.pending.fetch_add(1, Ordering::AcqRel);
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
}

/// What stopped a run before the front reached the end time.
#[derive(Debug, thiserror::Error)]
pub enum RunError<E> {
    /// No vertex below the end time can be pitched: the pitching rule lost progress.
    #[error("no progress: {remaining} vertices are below the end time but none can be pitched")]
    Stalled {
        /// Vertices not yet at the end time.
        remaining: usize,
    },
    /// A tent or a record failed.
    #[error(transparent)]
    Work(E),
}

/// True when `v` is below `t_end` and no neighbour is earlier.
fn is_ready(mesh: &Mesh, front: &Front, t_end: f64, v: VertexId) -> bool {
    front.time(v) < t_end && front.is_local_minimum(mesh, v)
}

/// The vertices of `region` and, separately, their neighbours outside it, sorted.
fn region_and_halo(mesh: &Mesh, region: &[VertexId]) -> (Vec<VertexId>, Vec<VertexId>) {
    let mut owned = region.to_vec();
    owned.sort_unstable();
    owned.dedup();
    let mut halo: Vec<VertexId> = owned
        .iter()
        .flat_map(|&v| mesh.vertex_neighbors(v).iter().copied())
        .filter(|w| owned.binary_search(w).is_err())
        .collect();
    halo.sort_unstable();
    halo.dedup();
    (owned, halo)
}

/// Advances every vertex of `front` to `t_end` with one worker per element of `scratch`.
pub fn run<'a, W: Work<'a>>(
    mesh: &Mesh,
    front: &Front,
    t_end: f64,
    work: &'a W,
    scratch: Vec<W::Scratch>,
    options: &Options,
) -> Result<Stats, RunError<W::Error>> {
    assert!(!scratch.is_empty(), "at least one worker");
    if options.deterministic {
        rounds::run(mesh, front, t_end, work, scratch)
    } else {
        pool::run(mesh, front, t_end, work, scratch)
    }
}
