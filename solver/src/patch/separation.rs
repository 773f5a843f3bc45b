//! The interface state on a nonlinear face: its upwind DG in time (see [`crate::face`]), solved
//! exactly for the current traces by an inner Newton iteration, and the cohesive traction
//! projected onto the face's polynomials.

use super::contact::{ContactFace, ContactFaces};
use crate::face::{FaceBasis, MAX_FACE_BASIS, STATE_COMPONENTS, solve_dense};
use crate::interface::{Targets, characteristics};
use crate::system::{MAX_FIELDS, System};

impl ContactFace {
    /// The interface state (normal separation, slip: m; damage) at quadrature point `p` for
    /// coefficients `d`.
    pub(super) fn separation_at(&self, nf: usize, p: usize, d: &[f64]) -> [f64; STATE_COMPONENTS] {
        state_from(&self.psi[p * nf..(p + 1) * nf], d)
    }

    /// `-G(d) = inflow - M0 d + int psi rate(state) / c` of the face's state system (the law's
    /// components) at the coefficients `d` into `g` (length `ns nf`), and with `jacobian` its
    /// derivative `M0 - int psi psi (d rate / d state) / c` (row-major, `ns nf` square);
    /// returns `|G|`.
    fn separation_residual(
        &mut self,
        c: f64,
        d: &[f64; STATE_COMPONENTS * MAX_FACE_BASIS],
        g: &mut [f64],
        mut jacobian: Option<&mut [f64]>,
    ) -> f64 {
        let n2 = g.len();
        let ns = self.law.components();
        let nf = n2 / ns;
        let projected = self.project_traction(nf, d, jacobian.is_some());
        for (row, gk) in g.iter_mut().enumerate() {
            let (comp, k) = (row / nf, row % nf);
            let md: f64 = (0..nf)
                .map(|l| self.m0[k * nf + l] * d[comp * nf + l])
                .sum();
            *gk = self.inflow[row] - md;
        }
        if let Some(jac) = jacobian.as_deref_mut() {
            jac.fill(0.0);
            for comp in 0..ns {
                for k in 0..nf {
                    let row = &mut jac[(comp * nf + k) * n2 + comp * nf..][..nf];
                    row.copy_from_slice(&self.m0[k * nf..(k + 1) * nf]);
                }
            }
        }
        for p in 0..self.weights.len() {
            let psi = &self.psi[p * nf..(p + 1) * nf];
            let t = self.targets_at(p, projected, self.separation_at(nf, p, d), false);
            let w = self.weights[p] / c;
            for comp in 0..ns {
                for k in 0..nf {
                    g[comp * nf + k] += w * psi[k] * t.rate[comp];
                }
            }
            if let Some(jac) = jacobian.as_deref_mut() {
                for (comp, e) in (0..ns).flat_map(|comp| (0..ns).map(move |e| (comp, e))) {
                    let r = w * t.rate_sep[comp][e];
                    if r == 0.0 {
                        continue;
                    }
                    for k in 0..nf {
                        let row = &mut jac[(comp * nf + k) * n2 + e * nf..][..nf];
                        for (x, &pl) in row.iter_mut().zip(psi) {
                            *x -= r * psi[k] * pl;
                        }
                    }
                }
                if projected {
                    self.add_projected_slopes(p, w, &t, jac, n2);
                }
            }
        }
        g.iter().map(|x| x * x).sum::<f64>().sqrt()
    }

    /// True for a cohesive face without damage: its target traction is the law's traction
    /// projected onto the face's polynomials (see [`Self::project_traction`]).
    pub(super) fn projects(&self) -> bool {
        self.law.cohesive.is_some() && self.law.damage.is_none()
    }

    /// Side a's (or with `swap` side b's) targets at point `p` for the interface `state` there,
    /// with the projected traction when `projected`.
    fn targets_at(
        &self,
        p: usize,
        projected: bool,
        state: [f64; STATE_COMPONENTS],
        swap: bool,
    ) -> Targets {
        let (w_a, w_b) = if swap {
            (self.w_b[p], self.w_a[p])
        } else {
            (self.w_a[p], self.w_b[p])
        };
        if projected {
            self.law
                .targets_with_traction(w_a, w_b, state, self.traction[p])
        } else {
            self.law.targets(w_a, w_b, state)
        }
    }

    /// For a cohesive face, the law's traction at the state coefficients `d` projected onto
    /// the face's polynomials ([`Self::project_matrix`]), at every point (and with `slopes`
    /// its derivatives with respect to `d`). Testing the face's DG equation with the target
    /// traction gives its work as the law's potential gained over the face plus terms that
    /// vanish for `Pi T` (docs/theory/method.md): with the pointwise `T`, `-(2 / Z) |T - Pi T|^2`
    /// (an L2 projection removes it), and `-int_bottom (T - Pi T) (delta+ - delta-)` on the
    /// bottom's jump (the bottom moments remove it). Returns whether the face projects.
    fn project_traction(&mut self, nf: usize, d: &[f64], slopes: bool) -> bool {
        if !self.projects() {
            return false;
        }
        let law = self.law.cohesive.expect("a cohesive face");
        let points = self.weights.len();
        if slopes {
            self.slopes[..points * 4 * nf].fill(0.0);
        }
        for p in 0..points {
            self.traction[p] = [0.0; 2];
        }
        let sources = points + self.bottom_weights.len();
        for q in 0..sources {
            let psi_q = if q < points {
                &self.psi[q * nf..(q + 1) * nf]
            } else {
                &self.bottom_psi[(q - points) * nf..(q - points + 1) * nf]
            };
            let state = state_from(psi_q, d);
            let (t, dt) = law.traction([state[0], state[1]]);
            for p in 0..points {
                let w = self.projection[p * sources + q];
                if w == 0.0 {
                    continue;
                }
                for (x, tk) in self.traction[p].iter_mut().zip(t) {
                    *x += w * tk;
                }
                if slopes {
                    for (k, e) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                        let f = w * dt[k][e];
                        let row = &mut self.slopes[((p * 2 + k) * 2 + e) * nf..][..nf];
                        for (x, &ps) in row.iter_mut().zip(psi_q) {
                            *x += f * ps;
                        }
                    }
                }
            }
        }
        true
    }

    /// Subtracts from the face system's Jacobian `jac` (`n2` square) the dependence of the
    /// rate at point `p` (weight `w`, scaled by `1 / c`; targets `t`) on the state through the
    /// projected traction: `d r_k / d T_k = -2 (1 - eta) / Z_k`.
    pub(super) fn add_projected_slopes(
        &self,
        p: usize,
        w: f64,
        t: &Targets,
        jac: &mut [f64],
        n2: usize,
    ) {
        let nf = n2 / 2;
        let psi = &self.psi[p * nf..(p + 1) * nf];
        for comp in 0..2 {
            let r = w * -2.0 * (1.0 - t.eta) / self.law.z[comp];
            for e in 0..2 {
                let slope = &self.slopes[((p * 2 + comp) * 2 + e) * nf..][..nf];
                for k in 0..nf {
                    let row = &mut jac[(comp * nf + k) * n2 + e * nf..][..nf];
                    for (x, &sl) in row.iter_mut().zip(slope) {
                        *x -= r * psi[k] * sl;
                    }
                }
            }
        }
    }

    /// The projection of a cohesive face's traction (see [`Self::project_traction`]): the
    /// polynomial `Pi T` of the face's degree `p` whose moments against the polynomials of
    /// degree `p - 1` on the face (face rule) and against those of degree `p` along the bottom
    /// edge (bottom rule) are the traction's. The first makes `int Pi T d delta / d tau` the
    /// law's potential gained over the face; the second makes the work on the bottom's jump
    /// of the separation that of `T` itself. Fills `projection` (points x sources); `g`
    /// (`nf^2` for the face basis' `nf` functions) and `x` (`nf` per source) are scratch. Falls back to the pointwise traction
    /// if the moments do not determine `Pi T`.
    pub(super) fn project_matrix(&mut self, basis: &FaceBasis, g: &mut [f64], x: &mut [f64]) {
        let (nf, degree) = (basis.len(), basis.degree());
        let points = self.weights.len();
        let bottom = self.bottom_weights.len();
        let sources = points + bottom;
        // The face basis is ordered by degree: its first `interior` functions span degree p - 1.
        let interior = nf - (degree + 1);
        let (g, x) = (&mut g[..nf * nf], &mut x[..nf * sources]);
        g.fill(0.0);
        x.fill(0.0);
        for q in 0..points {
            let psi = &self.psi[q * nf..(q + 1) * nf];
            let w = self.weights[q];
            for j in 0..interior {
                for k in 0..nf {
                    g[j * nf + k] += w * psi[j] * psi[k];
                }
                x[q * nf + j] = w * psi[j];
            }
        }
        for b in 0..bottom {
            let psi = &self.bottom_psi[b * nf..(b + 1) * nf];
            let (w, s) = (self.bottom_weights[b], self.bottom_along[b]);
            for i in 0..=degree {
                let row = interior + i;
                let moment = w * s.powi(i as i32);
                for k in 0..nf {
                    g[row * nf + k] += moment * psi[k];
                }
                x[(points + b) * nf + row] = moment;
            }
        }
        let projection = &mut self.projection[..points * sources];
        if solve_dense(g, nf, x, sources) {
            for p in 0..points {
                let psi = &self.psi[p * nf..(p + 1) * nf];
                for q in 0..sources {
                    let xq = &x[q * nf..(q + 1) * nf];
                    projection[p * sources + q] = psi.iter().zip(xq).map(|(a, b)| a * b).sum();
                }
            }
        } else {
            projection.fill(0.0);
            for p in 0..points {
                projection[p * sources + p] = 1.0;
            }
        }
    }
}

/// The interface state (normal separation, slip: m; damage) at a point with face basis values
/// `psi`, for coefficients `d` (`psi.len()` per component).
fn state_from(psi: &[f64], d: &[f64]) -> [f64; STATE_COMPONENTS] {
    let nf = psi.len();
    std::array::from_fn(|c| psi.iter().zip(&d[c * nf..]).map(|(a, b)| a * b).sum())
}

impl ContactFaces {
    /// Traces, separation (face DG, inner Newton) and targets of face `f` at the solution `q`.
    pub(super) fn solve_face(&mut self, system: &System, f: usize, q: &[f64]) -> bool {
        let fields = system.fields();
        let c = system.c_ref();
        let nf = self.basis.len();
        let face = &mut self.faces[f];
        let n = face.phi_a.len() / face.weights.len();
        let m = n * fields;
        let points = face.weights.len();
        let z = face.law.z;
        let (qa, qb) = (
            &q[face.a * m..(face.a + 1) * m],
            &q[face.b * m..(face.b + 1) * m],
        );
        for p in 0..points {
            let trace = |coefficients: &[f64], phi: &[f64]| {
                let mut s = [0.0; MAX_FIELDS];
                for (k, &ph) in phi.iter().enumerate() {
                    for (si, c) in s
                        .iter_mut()
                        .zip(&coefficients[k * fields..(k + 1) * fields])
                    {
                        *si += ph * c;
                    }
                }
                s
            };
            let ta = trace(qa, &face.phi_a[p * n..(p + 1) * n]);
            let tb = trace(qb, &face.phi_b[p * n..(p + 1) * n]);
            let (w_a, w_b) = characteristics(
                z,
                &system.frame(&ta, face.normal),
                &system.frame(&tb, face.normal),
            );
            face.w_a[p] = w_a;
            face.w_b[p] = w_b;
        }
        // Inner Newton on the face, G(d) = M0 d - inflow - int psi rate(state) / c = 0, with a
        // backtracking line search on |G|: the area fractions saturate (flat rate beyond r_c and
        // r_s), where plain Newton steps can cycle.
        let ns = face.law.components();
        // Per component, a size of the values: the separation's (both components, at least
        // the law's scale) and the damage's (at least 1).
        let scale = face.law.separation_scale();
        let sizes = |d: &[f64]| -> [f64; STATE_COMPONENTS] {
            let largest = |range: std::ops::Range<usize>, floor: f64| {
                d[range].iter().fold(floor, |m: f64, x| m.max(x.abs()))
            };
            let separation = largest(0..2 * nf, scale);
            [separation, separation, largest(2 * nf..3 * nf, 1.0)]
        };
        // The largest step of any component relative to its size.
        let relative = |step: &[f64], size: &[f64; STATE_COMPONENTS]| {
            (0..ns).fold(0.0f64, |m, comp| {
                step[comp * nf..(comp + 1) * nf]
                    .iter()
                    .fold(m, |m, s| m.max(s.abs() / size[comp]))
            })
        };
        let n2 = ns * nf;
        let (g, rest) = self.columns.split_at_mut(n2);
        let trial_g = &mut rest[..n2];
        let jac = &mut self.jacobian[..n2 * n2];
        let sep = face.sep;
        let mut norm = face.separation_residual(c, &sep, g, Some(jac));
        let mut converged = false;
        let mut previous = f64::INFINITY;
        for _ in 0..60 {
            if !solve_dense(jac, n2, g, 1) {
                return false;
            }
            // Trust region: steps of at most half the law's scale or of the state so far, per
            // component (the cohesive traction is not monotone; a long first step can land
            // beyond its peak, in another basin of |G|).
            let size = sizes(&face.sep);
            let largest = relative(g, &size);
            if largest > 0.5 {
                g.iter_mut().for_each(|s| *s *= 0.5 / largest);
            }
            let mut alpha = 1.0;
            let mut trial = face.sep;
            loop {
                for ((t, d), s) in trial.iter_mut().zip(&face.sep).zip(g.iter()) {
                    *t = d + alpha * s;
                }
                let trial_norm = face.separation_residual(c, &trial, trial_g, None);
                if trial_norm <= (1.0 - 1e-4 * alpha) * norm || alpha < 1e-6 {
                    break;
                }
                alpha *= 0.5;
            }
            face.sep = trial;
            let step = alpha * relative(g, &sizes(&face.sep));
            if !step.is_finite() {
                return false;
            }
            let sep = face.sep;
            norm = face.separation_residual(c, &sep, g, Some(jac));
            // Converged, or stalled at round-off (the step no longer halves).
            if step <= 1e-12 || (step <= 1e-9 && step >= 0.5 * previous) {
                converged = true;
                break;
            }
            previous = step;
        }
        let sep = face.sep;
        let projected = face.project_traction(nf, &sep, true);
        for p in 0..points {
            let state = face.separation_at(nf, p, &sep);
            face.targets_a[p] = face.targets_at(p, projected, state, false);
            face.targets_b[p] = face.targets_at(p, projected, state, true);
        }
        converged
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature;

    /// A cohesive face's projection keeps the traction's moments against degree `p - 1` on the
    /// face and against degree `p` along the bottom edge, and reproduces polynomials of degree
    /// `p`: what makes the face's work the law's potential plus the work of `T` itself on the
    /// bottom's jump.
    #[test]
    fn the_projected_traction_keeps_the_face_and_bottom_moments() {
        for p in 1..=4 {
            let rule = quadrature::triangle(2 * p + 2);
            let bottom_rule = quadrature::gauss_legendre(p + 2);
            let points = rule.points.len();
            let mut faces = ContactFaces::new(1, p, points, 1, 1);
            let nf = faces.basis.len();
            let basis = FaceBasis::new(p);
            let face = &mut faces.faces[0];
            // The reference triangle, its bottom the edge eta = 0 (twice as long as in `rule`).
            let mut psi = vec![0.0; nf];
            for (q, (x, &w)) in rule.points.iter().zip(&rule.weights).enumerate() {
                face.weights[q] = w;
                basis.eval(*x, &mut psi);
                face.psi[q * nf..(q + 1) * nf].copy_from_slice(&psi);
            }
            face.bottom_weights.clear();
            face.bottom_along.clear();
            for (b, (t, &w)) in bottom_rule
                .points
                .iter()
                .zip(&bottom_rule.weights)
                .enumerate()
            {
                basis.eval([t[0], 0.0], &mut psi);
                face.bottom_psi[b * nf..(b + 1) * nf].copy_from_slice(&psi);
                face.bottom_weights.push(2.0 * w);
                face.bottom_along.push(t[0]);
            }
            face.project_matrix(&faces.basis, &mut faces.jacobian, &mut faces.moments);
            let sources: Vec<[f64; 2]> = rule
                .points
                .iter()
                .copied()
                .chain(bottom_rule.points.iter().map(|t| [t[0], 0.0]))
                .collect();
            let projected = |f: &dyn Fn([f64; 2]) -> f64| -> Vec<f64> {
                (0..points)
                    .map(|q| {
                        let row = &face.projection[q * sources.len()..][..sources.len()];
                        row.iter().zip(&sources).map(|(w, &x)| w * f(x)).sum()
                    })
                    .collect()
            };
            // Degree p is reproduced.
            let poly =
                |x: [f64; 2]| 0.3 + x[0].powi(p as i32) - 2.0 * x[0] * x[1].powi(p as i32 - 1);
            for (q, value) in projected(&poly).into_iter().enumerate() {
                assert!((value - poly(rule.points[q])).abs() < 1e-11, "p = {p}");
            }
            // A smooth traction: the projection's polynomial, from its values at the face's
            // points, against the traction's moments.
            let traction =
                |x: [f64; 2]| (0.7 * x[0] - 1.3 * x[1]).exp() + (3.0 * x[0] * x[1]).sin();
            let values = projected(&traction);
            let (mut mass, mut c) = (vec![0.0; nf * nf], vec![0.0; nf]);
            for ((psi_q, &w), value) in face.psi.chunks_exact(nf).zip(&face.weights).zip(&values) {
                for k in 0..nf {
                    for l in 0..nf {
                        mass[k * nf + l] += w * psi_q[k] * psi_q[l];
                    }
                    c[k] += w * psi_q[k] * value;
                }
            }
            assert!(solve_dense(&mut mass, nf, &mut c, 1));
            let pi = |x: [f64; 2]| {
                let mut psi = vec![0.0; nf];
                basis.eval(x, &mut psi);
                psi.iter().zip(&c).map(|(a, b)| a * b).sum::<f64>()
            };
            let interior = p * (p + 1) / 2;
            for j in 0..interior {
                let moment: f64 = (0..points)
                    .map(|q| {
                        let x = rule.points[q];
                        face.weights[q] * face.psi[q * nf + j] * (pi(x) - traction(x))
                    })
                    .sum();
                assert!(moment.abs() < 1e-12, "p = {p}, face moment {j}: {moment:e}");
            }
            for i in 0..=p {
                let moment: f64 = bottom_rule
                    .points
                    .iter()
                    .zip(&bottom_rule.weights)
                    .map(|(t, w)| {
                        w * t[0].powi(i as i32) * (pi([t[0], 0.0]) - traction([t[0], 0.0]))
                    })
                    .sum();
                assert!(
                    moment.abs() < 1e-12,
                    "p = {p}, bottom moment {i}: {moment:e}"
                );
            }
        }
    }
}
