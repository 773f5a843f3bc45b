//! Adaptivity: the error indicator of a patch and its tolerance (`indicator`), and the policy of a
//! solve built on it (`policy`): which patches are rejected and refined around, which bisection
//! vertices are coarsened, and the refinement before the first tent.

pub(crate) mod indicator;
pub(crate) mod policy;
