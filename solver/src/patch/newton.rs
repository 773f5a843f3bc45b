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
#[error("{}", self.describe())]
pub struct NewtonFailure {
    /// Iterations done.
    pub iterations: usize,
    /// Relative residual of the last iterate; NaN when the iterate is not finite, or when
    /// [`Self::face`] failed at the first.
    pub residual: f64,
    /// An interface face's own separation (its inner Newton solve for the iterate's traces)
    /// did not converge: the patch is not converged, and a finer face may be.
    pub face: bool,
}

impl NewtonFailure {
    fn describe(&self) -> String {
        if self.face {
            let before = if self.residual.is_nan() {
                String::new()
            } else {
                format!(" (relative residual before it {:.3e})", self.residual)
            };
            format!(
                "the separation of an interface face did not converge at Newton iteration \
                 {}{before}",
                self.iterations
            )
        } else {
            format!(
                "Newton iterations did not converge: relative residual {:.3e} after {} \
                 iterations",
                self.residual, self.iterations
            )
        }
    }

    /// A failure for want of finite values (inflow or iterate): no refinement helps it.
    pub fn is_non_finite(&self) -> bool {
        !self.face && !self.residual.is_finite()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A face whose separation did not converge is a patch not converged (refinement may help
    /// it), whatever residual it carries; a non-finite residual otherwise is non-finite input.
    #[test]
    fn a_face_that_did_not_converge_is_not_a_non_finite_failure() {
        let face = NewtonFailure {
            iterations: 3,
            residual: f64::NAN,
            face: true,
        };
        assert!(!face.is_non_finite());
        assert!(face.to_string().contains("separation of an interface face"));
        let nan = NewtonFailure {
            face: false,
            ..face
        };
        assert!(nan.is_non_finite());
        assert!(nan.to_string().contains("relative residual NaN"));
        let slow = NewtonFailure {
            residual: 1e-3,
            ..nan
        };
        assert!(!slow.is_non_finite());
    }
}
