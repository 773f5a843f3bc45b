//! Crack nucleation and propagation criteria (seed 4.3.1-4.3.2, 4.4.2) as pure functions:
//! counter-based random draws ([`Draws`]), the strengths and number of defects
//! ([`DefectStrengths`], [`poisson`], [`weakest_defect`]), and the effective traction on a plane
//! with its maxima over orientations ([`effective_traction`], [`max_effective_traction`],
//! [`tensile_maxima`], [`crack_directions`]).
//!
//! Units are SI: stresses and strengths in Pa, densities in 1/m^2, areas in m^2, angles in
//! radians measured counterclockwise from the x axis.

mod defects;
mod draws;
#[cfg(test)]
mod testing;
mod traction;

pub use defects::{DefectStrengths, poisson, weakest_defect};
pub use draws::Draws;
pub use traction::{crack_directions, effective_traction, max_effective_traction, tensile_maxima};
