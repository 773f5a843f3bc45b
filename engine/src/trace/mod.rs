//! Tracing a run for scaling studies (`sdg run --trace FILE`) and replaying the trace on any
//! number of simulated workers (`sdg scaling FILE --workers 1,2,4,...`).
//!
//! A trace lists every tent with its vertex, its kind, when it ran, how long it took and the
//! earlier tents it depends on: the last tents at its vertex and at the vertex's neighbours
//! (their front times and the elements it reads), or the regional event that last changed
//! them. Events that change the mesh only around some vertices (refinement, coarsening, crack
//! extension: `region` rows) list as dependencies the last tents and events at the vertices
//! they changed and at those vertices' neighbours; the other events (`event` rows: history
//! rows, interventions) hold the whole state.
//!
//! The replay models the asynchronous scheduler: a tent is ready once its dependencies are done,
//! and each free worker takes the ready tent that came first in the trace, paying a fixed claim
//! overhead per tent; a `region` event, like a tent, waits only for its dependencies and takes
//! one worker while the others go on solving, as the scheduler runs regional events; an `event`
//! waits for every tent before it and runs alone. A trace of a deterministic run also lists the
//! chunks of each round's tents that the workers settled once they had all run (`settle`: what
//! recording reads from the state, and which vertices are ready next) and marks the end of each
//! round (`round`, with the time the scheduler spent on it alone: choosing its vertices and
//! recording its settled tents in order), and is replayed as those rounds, which are the same
//! for any thread count: a round's tents go to the first free worker in trace order, then its
//! settling chunks the same way, then its events and the scheduler's own time run alone.
//! Over ranks (`sdg scaling --ranks`, module `ranks`) the tents go to the ranks owning their
//! vertices and a dependency between ranks waits for an update message's latency.
//! Either way the replay predicts the wall time, the critical path (the time with unlimited
//! workers) and the mean number of ready tents. The costs are those measured in the traced run,
//! so the model leaves out what more threads do to each tent (shared caches and memory
//! bandwidth) and the barriers' cost.

mod entry;
mod ranks;
mod record;
mod replay;
mod scaling;
#[cfg(test)]
mod tests;

pub use entry::{Entry, Kind, read};
pub use ranks::RankModel;
pub(crate) use record::{Tracer, check_path};
pub use replay::{
    CriticalPath, Prediction, critical_path, critical_path_parts, regions, replay, rounds,
};
pub use scaling::{Scaling, scaling_job};
