//! Space triangulations for tent-pitched spacetime meshes: the mesh and its adjacency, structured
//! and Gmsh-read meshes, newest-vertex bisection and coarsening, the advancing front and the tent
//! pitcher.
//!
//! Units are SI: metres for lengths, seconds for times.

pub mod coarsen;
pub mod front;
pub mod geometry;
pub mod gmsh;
pub mod mesh;
pub mod rectangle;
pub mod refine;
pub mod tent;
#[cfg(test)]
mod testing;

pub use coarsen::Merge;
pub use front::Front;
pub use geometry::Point;
pub use gmsh::{GmshError, read_msh};
pub use mesh::{Edge, EdgeId, Mesh, MeshError, TagId, TriangleId, VertexId};
pub use rectangle::{Diagonal, GridSegment, Rectangle, RectangleError};
pub use refine::{AllowSplit, Split, SplitError};
pub use tent::{PitchError, Pitcher, Tent};
