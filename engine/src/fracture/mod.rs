//! Fracture: where cracks nucleate and which way their tips extend (`criteria`; over a length,
//! `nonlocal`), the event that extends them on the running front (`propagation`), and what a
//! run records of them: fracture events and crack edges (`records`), tip speeds (`tips`), the
//! crack network's forks (`network`) and the crack pictures (`picture`).

pub mod criteria;
pub(crate) mod network;
pub mod nonlocal;
pub(crate) mod picture;
pub(crate) mod propagation;
pub(crate) mod records;
pub(crate) mod tips;

pub use criteria::{Fracture, Tip};
pub use records::FractureSummary;
pub use tips::{CrackNetwork, CrackSummary};
