//! Snapshots: the solution on planes `t = const`, cut from the spacetime elements as they are
//! solved and written as VTK triangle grids (`snapshot_NNNN.vtu`) with a ParaView collection
//! (`snapshots.pvd`). Crack surfaces (contact, cohesive and damage interfaces) are cut the same
//! way: their vertical faces give segments on the plane, written as `cracks_NNNN.vtu` (lines)
//! beside the triangles and listed in the collection as its part 1. In a run over ranks each
//! rank cuts the elements it solved and writes them as its piece of each snapshot
//! (`snapshot_NNNN_R.vtu`), and rank 0 the `snapshot_NNNN.pvtu` that joins them ([`Piece`]).
//!
//! # Slicing rule
//! A snapshot at `t_s` is the plane `tau = tau_s = c_ref t_s`. Each element vertex is classified
//! as below, on or above the plane, "on" meaning within `8 eps |tau_s|` of it (so that a front
//! time equal to `t_s` up to rounding counts as exactly on the plane). The plane is covered
//! exactly once by the slices of
//!
//! 1. the elements with a vertex below and a vertex on or above the plane, i.e.
//!    `min tau < tau_s <= max tau` ("taken from below"). An element whose top face lies in the
//!    plane contributes that face; one that touches the plane with a vertex or an edge
//!    contributes a degenerate polygon, which is dropped. This covers every `t_s` in
//!    `(t_start, t_end]`, including a flat front at `t_s` and the end time itself.
//! 2. Only when no element satisfies rule 1 — the plane is the initial front, `t_s = t_start` —
//!    the elements whose bottom face lies in the plane (three vertices on it, one above). Such
//!    faces are held as a fallback while rule 1 has produced nothing yet and dropped as soon as
//!    it does, whatever the order in which elements arrive.
//!
//! # Completeness
//! Every later element has all its vertices on or above the current front, so once the front's
//! minimum time reaches `t_s` no element can satisfy rule 1 any more: the snapshot is written
//! when `front_min_time >= t_s`. The start-time snapshot (rule 2) is complete only when the front
//! has left `t_s` everywhere, `front_min_time > t_s`. A snapshot later than the end time is never
//! written.

mod files;
mod slicing;
mod snapshots;

pub(crate) use files::{draw_pieces_png, remove_earlier};
pub use slicing::{InterfaceValues, PointValues};
pub use snapshots::{Piece, Snapshots};
