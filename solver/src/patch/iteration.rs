//! The outer Newton iterations of a patch with nonlinear faces: the faces' term `N(Q)`, its
//! Jacobian, and the iteration loop.

use faer::Accum;

use super::contact::ContactFaces;
use super::kron::kron_sum;
use super::newton::NewtonFailure;
use super::solver::PatchSolver;
use crate::face::solve_dense;
use crate::interface::Targets;
use crate::ring::BlockSystem;
use crate::system::{FrameTrace, MAX_FIELDS, Matrix, System};

impl PatchSolver {
    /// Solves the assembled patch with contact faces (assembled bonded) by Newton iterations
    /// from the bonded solution; leaves the solution where [`BlockSystem::rhs`] has it. Returns
    /// the number of linear solves.
    pub(super) fn solve_newton(&mut self) -> Result<usize, NewtonFailure> {
        let d = self.used;
        let size = d * self.basis.len() * self.system.fields();
        let norm = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>().sqrt();
        let b_norm = norm(self.blocks.rhs());
        self.blocks.save();
        self.blocks.solve(&self.order[..d]);
        let (q, nl, r) = (
            &mut self.iterate[..size],
            &mut self.nonlinear[..size],
            &mut self.residual[..size],
        );
        q.copy_from_slice(self.blocks.rhs());
        let failure = |iterations, residual| NewtonFailure {
            iterations,
            residual,
            face: false,
        };
        let mut iterations = 1;
        let mut relative = f64::NAN;
        loop {
            nl.fill(0.0);
            if !self.contact.evaluate(&self.system, q, nl) {
                // A face whose separation did not converge for a finite iterate is a patch not
                // converged; a non-finite iterate comes from non-finite inflow.
                let face = q.iter().all(|x| x.is_finite());
                let residual = if face { relative } else { f64::NAN };
                return Err(NewtonFailure {
                    face,
                    ..failure(iterations, residual)
                });
            }
            self.blocks.residual(q, r);
            for (ri, ni) in r.iter_mut().zip(nl.iter()) {
                *ri -= ni;
            }
            let scale = b_norm + norm(nl);
            relative = if scale > 0.0 { norm(r) / scale } else { 0.0 };
            if !relative.is_finite() {
                return Err(failure(iterations, relative));
            }
            if relative <= self.newton.tol {
                break;
            }
            if iterations == self.newton.max_iter {
                return Err(failure(iterations, relative));
            }
            self.blocks.restore();
            self.contact.add_jacobians(&self.system, &mut self.blocks);
            let m = size / d;
            for i in 0..d {
                self.blocks
                    .rhs_mut(i)
                    .copy_from_slice(&r[i * m..(i + 1) * m]);
            }
            self.blocks.solve(&self.order[..d]);
            for (qi, dq) in q.iter_mut().zip(self.blocks.rhs()) {
                *qi += dq;
            }
            iterations += 1;
        }
        let m = size / d;
        for i in 0..d {
            self.blocks
                .rhs_mut(i)
                .copy_from_slice(&q[i * m..(i + 1) * m]);
        }
        Ok(iterations)
    }
}

/// Linear maps of one side's state to a face frame: rows `v[0], v[1], s[0], s[1]`.
type FrameRows = [[f64; MAX_FIELDS]; 4];

fn frame_rows(system: &System, m: [f64; 2]) -> FrameRows {
    let mut rows = [[0.0; MAX_FIELDS]; 4];
    for j in 0..system.fields() {
        let mut e = [0.0; MAX_FIELDS];
        e[j] = 1.0;
        let f = system.frame(&e, m);
        for (row, value) in rows.iter_mut().zip([f.v[0], f.v[1], f.s[0], f.s[1]]) {
            row[j] = value;
        }
    }
    rows
}

/// `d w / d q` of the characteristic arriving from side a (`sign = -1`: `s - Z v`) or side b
/// (`sign = 1`: `s + Z v`), rows normal and tangential.
fn characteristic_rows(rows: &FrameRows, z: [f64; 2], sign: f64) -> [[f64; MAX_FIELDS]; 2] {
    [0, 1].map(|k| std::array::from_fn(|j| rows[2 + k][j] + sign * z[k] * rows[k][j]))
}

/// The flux `A_m q*` as a linear map of the frame values `(v[0], v[1], s[0], s[1])`: columns.
fn flux_columns(system: &System, m: [f64; 2]) -> [[f64; MAX_FIELDS]; 4] {
    std::array::from_fn(|c| {
        let mut star = FrameTrace::default();
        if c < 2 {
            star.v[c] = 1.0;
        } else {
            star.s[c - 2] = 1.0;
        }
        system.flux(&star, m)
    })
}

/// `d flux / d w` (fields x 2) for targets with `d star / d w = dstar` and `d w / d q = dw`:
/// returns the `fields x fields` Jacobian `F dstar dw`.
fn chain(
    flux: &[[f64; MAX_FIELDS]; 4],
    dstar: &[[f64; 2]; 4],
    dw: &[[f64; MAX_FIELDS]; 2],
) -> Matrix {
    let mut out = [[0.0; MAX_FIELDS]; MAX_FIELDS];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..4)
                .map(|c| flux[c][i] * (dstar[c][0] * dw[0][j] + dstar[c][1] * dw[1][j]))
                .sum();
        }
    }
    out
}

/// Side a's targets minus the bonded ones, from the arriving characteristics.
fn departure(t: &Targets, z: [f64; 2], w_a: [f64; 2], w_b: [f64; 2]) -> FrameTrace {
    let mut star = t.star;
    for k in 0..2 {
        star.v[k] -= (w_b[k] - w_a[k]) / (2.0 * z[k]);
        star.s[k] -= 0.5 * (w_a[k] + w_b[k]);
    }
    star
}

/// `t` with the bonded targets' derivatives taken off `d_wa` and `d_wb` (see [`departure`]).
fn departure_derivatives(t: &Targets, z: [f64; 2]) -> Targets {
    let mut out = *t;
    for (k, zk) in z.iter().enumerate() {
        out.d_wa[k][k] += 0.5 / zk;
        out.d_wb[k][k] -= 0.5 / zk;
        out.d_wa[2 + k][k] -= 0.5;
        out.d_wb[2 + k][k] -= 0.5;
    }
    out
}

impl ContactFaces {
    /// Evaluates every face at the patch solution `q` (block rows of `m` unknowns): solves each
    /// face's separation and its targets and adds `N(q)` to `nl`. Returns false when a face's
    /// separation cannot be solved.
    pub(super) fn evaluate(&mut self, system: &System, q: &[f64], nl: &mut [f64]) -> bool {
        for f in 0..self.count {
            if !self.solve_face(system, f, q) {
                return false;
            }
            self.add_flux(system, f, nl);
        }
        true
    }

    /// Adds the Jacobian of `N` at the last evaluated solution to the block system.
    pub(super) fn add_jacobians(&mut self, system: &System, blocks: &mut BlockSystem) {
        for f in 0..self.count {
            self.add_jacobian(system, f, blocks);
        }
    }

    /// Adds `int phi (F* - F_bonded)` of face `f` for both sides to `nl`.
    fn add_flux(&self, system: &System, f: usize, nl: &mut [f64]) {
        let fields = system.fields();
        let face = &self.faces[f];
        let n = face.phi_a.len() / face.weights.len();
        let m = n * fields;
        let minus = face.normal.map(|x| -x);
        for p in 0..face.weights.len() {
            let w = face.weights[p];
            let (z, w_a, w_b) = (face.law.z, face.w_a[p], face.w_b[p]);
            let fa = system.flux(&departure(&face.targets_a[p], z, w_a, w_b), face.normal);
            let fb = system.flux(&departure(&face.targets_b[p], z, w_b, w_a), minus);
            for (side, flux, phi) in [
                (face.a, fa, &face.phi_a[p * n..(p + 1) * n]),
                (face.b, fb, &face.phi_b[p * n..(p + 1) * n]),
            ] {
                let rows = &mut nl[side * m..(side + 1) * m];
                for (k, &ph) in phi.iter().enumerate() {
                    for (r, fl) in rows[k * fields..(k + 1) * fields].iter_mut().zip(&flux) {
                        *r += w * ph * fl;
                    }
                }
            }
        }
    }

    /// Adds the Jacobian of face `f`'s `int phi F*` with respect to both sides' coefficients,
    /// through the traces directly and through the face's interface state.
    fn add_jacobian(&mut self, system: &System, f: usize, blocks: &mut BlockSystem) {
        let fields = system.fields();
        let c = system.c_ref();
        let nf = self.basis.len();
        let face = &self.faces[f];
        let ns = face.law.components();
        let n2 = ns * nf;
        let n = face.phi_a.len() / face.weights.len();
        let m = n * fields;
        let z = face.law.z;
        let minus = face.normal.map(|x| -x);
        let rows = frame_rows(system, face.normal);
        let (dwa, dwb) = (
            characteristic_rows(&rows, z, -1.0),
            characteristic_rows(&rows, z, 1.0),
        );
        let (flux_a, flux_b) = (
            flux_columns(system, face.normal),
            flux_columns(system, minus),
        );
        let (a, b) = (face.a, face.b);
        let projects = face.projects();
        let [coupling_a, coupling_b] = &mut self.coupling;
        coupling_a.fill(0.0);
        coupling_b.fill(0.0);
        let columns = &mut self.columns[..n2 * 2 * m];
        columns.fill(0.0);
        let jac = &mut self.jacobian[..n2 * n2];
        jac.fill(0.0);
        for comp in 0..ns {
            for k in 0..nf {
                jac[(comp * nf + k) * n2 + comp * nf..][..nf]
                    .copy_from_slice(&face.m0[k * nf..(k + 1) * nf]);
            }
        }
        for p in 0..face.weights.len() {
            let w = face.weights[p];
            let (ta, tb) = (
                &departure_derivatives(&face.targets_a[p], z),
                &departure_derivatives(&face.targets_b[p], z),
            );
            let phi_a = &face.phi_a[p * n..(p + 1) * n];
            let phi_b = &face.phi_b[p * n..(p + 1) * n];
            let psi = &face.psi[p * nf..(p + 1) * nf];
            // Direct dependence on the traces: four blocks.
            for (row, col, phi_r, phi_c, j) in [
                (a, a, phi_a, phi_a, chain(&flux_a, &ta.d_wa, &dwa)),
                (a, b, phi_a, phi_b, chain(&flux_a, &ta.d_wb, &dwb)),
                (b, b, phi_b, phi_b, chain(&flux_b, &tb.d_wa, &dwb)),
                (b, a, phi_b, phi_a, chain(&flux_b, &tb.d_wb, &dwa)),
            ] {
                for (k, &pr) in phi_r.iter().enumerate() {
                    for (l, &pc) in phi_c.iter().enumerate() {
                        self.outer[k * n + l] = w * pr * pc;
                    }
                }
                kron_sum(
                    blocks.block_mut(row, col),
                    Accum::Add,
                    m,
                    n,
                    fields,
                    &[(&self.outer[..n * n], j)],
                );
            }
            // Dependence through the separation: d flux / d sep per side, and the face
            // system's derivative with respect to the traces.
            for (coupling, flux, t, phi) in [
                (&mut *coupling_a, &flux_a, ta, phi_a),
                (&mut *coupling_b, &flux_b, tb, phi_b),
            ] {
                for e in 0..ns {
                    let df: [f64; MAX_FIELDS] =
                        std::array::from_fn(|i| (0..4).map(|c| flux[c][i] * t.d_sep[c][e]).sum());
                    for (k, &ph) in phi.iter().enumerate() {
                        for (i, &d) in df[..fields].iter().enumerate() {
                            let row = &mut coupling[(k * fields + i) * n2 + e * nf..][..nf];
                            for (r, &ps) in row.iter_mut().zip(psi) {
                                *r += w * ph * d * ps;
                            }
                        }
                    }
                }
                if projects {
                    // Through the projected traction: d star / d T_k is (1 - eta) / Z_k for
                    // the velocity, 1 - eta for the traction.
                    for e in 0..2 {
                        for l in 0..nf {
                            let slope = |k: usize| face.slopes[((p * 2 + k) * 2 + e) * nf + l];
                            let dstar = [
                                (1.0 - t.eta) / z[0] * slope(0),
                                (1.0 - t.eta) / z[1] * slope(1),
                                (1.0 - t.eta) * slope(0),
                                (1.0 - t.eta) * slope(1),
                            ];
                            for (k, &ph) in phi.iter().enumerate() {
                                for i in 0..fields {
                                    let d: f64 = (0..4).map(|c| flux[c][i] * dstar[c]).sum();
                                    coupling[(k * fields + i) * n2 + e * nf + l] += w * ph * d;
                                }
                            }
                        }
                    }
                }
            }
            for comp in 0..ns {
                let drate: [[f64; MAX_FIELDS]; 2] =
                    [(&ta.rate_wa[comp], &dwa), (&ta.rate_wb[comp], &dwb)]
                        .map(|(r, dw)| std::array::from_fn(|j| r[0] * dw[0][j] + r[1] * dw[1][j]));
                for (side, phi) in [phi_a, phi_b].into_iter().enumerate() {
                    for (k, &ps) in psi.iter().enumerate() {
                        for (l, &ph) in phi.iter().enumerate() {
                            for (i, &dr) in drate[side][..fields].iter().enumerate() {
                                columns[(side * m + l * fields + i) * n2 + comp * nf + k] +=
                                    w / c * ps * ph * dr;
                            }
                        }
                    }
                }
                for e in 0..ns {
                    let r = w / c * ta.rate_sep[comp][e];
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
            }
            if projects {
                face.add_projected_slopes(p, w / c, ta, jac, n2);
            }
        }
        // d sep / d q = J^-1 (int psi (d rate / d q) / c), one column per side unknown.
        if !solve_dense(jac, n2, columns, 2 * m) {
            return;
        }
        for (row_side, coupling) in [(a, &*coupling_a), (b, &*coupling_b)] {
            for (col_side, offset) in [(a, 0), (b, m)] {
                let block = &mut self.block[..m * m];
                for col in 0..m {
                    let dd = &columns[(offset + col) * n2..][..n2];
                    for row in 0..m {
                        block[col * m + row] = coupling[row * n2..(row + 1) * n2]
                            .iter()
                            .zip(dd)
                            .map(|(x, y)| x * y)
                            .sum();
                    }
                }
                for (t, s) in blocks
                    .block_mut(row_side, col_side)
                    .iter_mut()
                    .zip(block.iter())
                {
                    *t += s;
                }
            }
        }
    }
}
