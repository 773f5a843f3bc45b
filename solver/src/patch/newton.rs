//! Settings of the Newton iterations of patches with nonlinear faces, and their failure.

/// Settings of the Newton iterations of patches with nonlinear faces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Newton {
    /// Converged when `|b - K Q - N(Q)| <= tol (|b| + |N(Q)|)` (Euclidean norms over the patch).
    pub tol: f64,
    /// Iterations allowed before the patch counts as not converged.
    pub max_iter: usize,
}

impl Default for Newton {
    fn default() -> Self {
        Self {
            tol: 1e-10,
            max_iter: 30,
        }
    }
}

/// A patch whose Newton iterations did not converge.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error(
    "Newton iterations did not converge: relative residual {residual:.3e} after {iterations} \
     iterations"
)]
pub struct NewtonFailure {
    /// Iterations done.
    pub iterations: usize,
    /// Relative residual of the last iterate.
    pub residual: f64,
}
