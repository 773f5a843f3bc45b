//! Points of scaled spacetime, shared by elements and interface faces.

/// A point `(x, y, tau)` in scaled spacetime, metres.
pub type SpacePoint = [f64; 3];
