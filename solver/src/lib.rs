//! Physics of the spacetime DG method: materials and wave speeds (the patch solver follows).
//!
//! Units are SI throughout: Pa, kg/m^3, m/s.

pub mod material;

pub use material::{Material, MaterialError, Plane};
