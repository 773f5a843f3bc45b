//! Distributed runs of the advancing front: one front over many ranks (processes), with the
//! same tents as one process.
//!
//! What exists:
//! - [`partition`]: owner ranks of the vertices, by recursive coordinate bisection, METIS or
//!   stripes along x, weighted by star size or by the caller's weights, or seeded random owners;
//! - [`view`]: each rank's local view (owned vertices, every triangle with an owned corner, the
//!   one-vertex-deep ghost layer) as an ordinary mesh numbered in global id order, with the
//!   global ids kept;
//! - [`transport`]: the messages between ranks and the [`Transport`] trait that carries them,
//!   with an in-process implementation ([`Loopback`]: threads as ranks, seeded random delays,
//!   optional per-pair FIFO), and with the cargo feature `mpi` the MPI one (`MpiTransport`:
//!   one communication thread per process makes the MPI calls);
//! - [`pitching`]: asynchronous tent pitching over ranks under the `(time, id)`-first rule, with
//!   termination by done messages (no global poll), whose tents are bitwise the serial
//!   reference order's for every partition and message timing (the argument is in the module
//!   docs; the tests check it);
//! - [`solving`]: the same pitching with each tent's patch solved on its rank by the patch
//!   solver, the updates carrying the elements and interface faces the receiver reads as
//!   inflow, each with its generation, whose elements and faces are bitwise the serial run's
//!   (with interface laws, without mesh-changing events or fracture), telling an [`Observer`] of
//!   each tent solved (the engine writes its outputs from it), and with [`Held`] the threaded
//!   run's energy blow-up guard over what each rank knows of the boundary work;
//! - [`gathering`]: the ranks' results gathered on rank 0, each element and face once (from
//!   the owner of its triangle's first corner or its edge's first end), with every tent's
//!   patch report and the values the caller reports, through messages of the same transport.
//!
//! The ranks take the vertices first in `(time, id)` among their neighbours, the threaded
//! scheduler's rule in both its modes, so without events a run over ranks is the threaded run
//! of either mode. Not built yet: mesh-changing events and fracture across ranks. `sdg run
//! --ranks` uses [`Loopback`], `sdg run --mpi` the MPI transport. See `distributed/README.md`.

pub mod gathering;
pub mod held;
pub mod partition;
pub mod pitching;
mod rng;
pub mod solving;
#[cfg(test)]
mod testing;
pub mod transport;
pub mod view;

pub use gathering::{Gathered, gather, gather_threads};
pub use held::Held;
pub use partition::{Partition, PartitionError, Rank, star_weights};
pub use pitching::{
    Causality, CellKind, Options, Pause, PauseRequest, PitchingError, RankReport, SolvedPatch,
    pitch_rank, run_threads,
};
pub use solving::{
    Observed, Observer, Physics, RankSolution, rank_state, solve_rank, solve_rank_observed,
    solve_threads, solve_threads_observed,
};
pub use transport::loopback::{Loopback, LoopbackOptions};
#[cfg(feature = "mpi")]
pub use transport::mpi::{MpiError, MpiOptions, MpiTransport};
pub use transport::{Cells, Message, Transport, TransportError, Update};
pub use view::{LocalView, ViewError};
