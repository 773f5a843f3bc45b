//! One tent's patch: the spacetime DG equations on its tetrahedra, assembled and solved at once
//! by a [`PatchSolver`].

mod assembly;
mod contact;
mod inflow;
mod iteration;
mod kron;
mod newton;
mod post;
mod report;
mod separation;
mod slot;
mod solver;
pub(crate) mod tables;

pub use inflow::Initial;
pub use newton::{Newton, NewtonFailure};
pub use report::{
    BLOW_UP, ENERGY_TERMS, ElementReport, FaceCut, InterfaceSample, MOMENTUM_TERMS, PatchReport,
};
pub use solver::PatchSolver;
