//! Physics of the spacetime DG method for 2D linear elastodynamics: materials, the scaled
//! first-order system, Riemann solutions, boundary data histories, exact solutions, the
//! nucleation criteria, and the patch solver.
//!
//! Units are SI throughout: Pa, kg/m^3, m/s, m, s.

pub mod basis;
pub mod boundary;
pub mod crack;
pub mod element;
pub mod exact;
pub mod face;
pub mod history;
pub mod interface;
pub mod material;
pub mod norms;
pub mod nucleation;
pub mod patch;
pub mod quadrature;
pub mod riemann;
pub mod ring;
pub mod spacetime;
pub mod system;

pub use material::{Material, MaterialError, Plane};
