//! The files a run writes: atomic writes and the VTU grid writer (`files`), faults injected into
//! them for the tests (`fault`), snapshots of the
//! solution on planes of constant time (`snapshot`), the interface probes and crack surfaces cut
//! by snapshot planes (`interface`), the spacetime mesh of `sdg mesh` (`spacetime`), and the
//! writer and reader of every CSV table (`table`).

pub(crate) mod fault;
pub(crate) mod files;
pub(crate) mod interface;
pub(crate) mod snapshot;
pub mod spacetime;
pub(crate) mod table;

pub use files::{CellType, Field, UnstructuredGrid, check_writable, write_atomic};
pub(crate) use files::{write_output, write_synced};
