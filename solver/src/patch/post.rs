//! Post-processing of a solved patch: per element energies, work, dissipation and momentum
//! balance, and the displacement.

use faer::dyn_stack::MemStack;
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::{MatMut, MatRef, Par};

use super::inflow::other_values;
use super::report::ElementReport;
use super::slot::{Face, TOP, face_geometry, face_points};
use super::solver::PatchSolver;
use super::tables::FaceTables;
use crate::boundary::Boundary;
use crate::interface::Law;
use crate::riemann::{self, Side};
use crate::system::{MAX_FIELDS, State};

impl PatchSolver {
    /// Energy terms and diagnostics of element `i` after the solve; also copies its field
    /// coefficients into the output buffer.
    pub(super) fn element_post(&mut self, i: usize, boundary: &Boundary) -> ElementReport {
        let n = self.basis.len();
        let fields = self.system.fields();
        let nv = self.system.displacement_components();
        let m = n * fields;
        let width = self.width();
        let c = self.system.c_ref();
        let slot = self.slots[i];
        let solution = self.blocks.rhs();
        for k in 0..n {
            let out = &mut self.output[i * n * width + k * width..][..fields];
            out.copy_from_slice(&solution[i * m + k * fields..][..fields]);
        }
        let system = &self.system;
        // The element's state at point q of the rule of `tables` on its face `face`.
        let own = |tables: &FaceTables, face: Face, q: usize| {
            let phi = tables.at(FaceTables::triple(face.0), q);
            combine(&solution[i * m..(i + 1) * m], phi, fields)
        };
        let mut r = ElementReport::default();
        let mut momentum = [0.0; 2];
        let mut scale = 0.0;
        let mut add_momentum = |face: [f64; 2]| {
            for (a, b) in momentum.iter_mut().zip(face) {
                *a += b;
            }
            scale += face[0].hypot(face[1]);
        };
        let (exact, data) = (&self.exact, &self.data);
        let mut face_momentum = [0.0; 2];
        let mut point = 0..;
        face_points(&exact.rule, &slot.vertices, TOP, |_, w, nrm| {
            let q = own(&exact.tables, TOP, point.next().expect("unbounded"));
            let aq = system.apply(&system.a_n(nrm), &q);
            let out = 0.5 * w * system.dot(&q, &aq);
            let kinetic = w * nrm[2] * system.kinetic_density(&q);
            let strain = w * nrm[2] * system.energy_density(&q) - kinetic;
            r.energy_out += out;
            r.energy_out_parts[0] += kinetic;
            r.energy_out_parts[1] += strain;
            r.energy_out_parts[2] += out - kinetic - strain;
            for (f, a) in face_momentum.iter_mut().zip(&aq[..nv]) {
                *f += w * a;
            }
        });
        add_momentum(face_momentum);
        let stride = data.tables.points();
        for (f, &(face, source)) in slot.inflows().iter().enumerate() {
            // The rule and the states below of the assembly.
            let quadrature = if self.inflow.solved[source] {
                exact
            } else {
                data
            };
            let (rule, tables) = (&quadrature.rule, &quadrature.tables);
            let kept = &self.below_states[(2 * i + f) * stride..][..stride];
            face_momentum = [0.0; 2];
            let mut point = 0..;
            face_points(rule, &slot.vertices, face, |_, w, nrm| {
                let p = point.next().expect("unbounded");
                let an = system.a_n(nrm);
                let q_prev = kept[p].0;
                let q = own(tables, face, p);
                let aq_prev = system.apply(&an, &q_prev);
                r.energy_in -= 0.5 * w * system.dot(&q_prev, &aq_prev);
                let jump = std::array::from_fn(|k| q[k] - q_prev[k]);
                r.dissipation -= 0.5 * w * system.dot(&jump, &system.apply(&an, &jump));
                for (f, a) in face_momentum.iter_mut().zip(&aq_prev[..nv]) {
                    *f += w * a;
                }
            });
            add_momentum(face_momentum);
        }
        for side in slot.sides() {
            let condition = boundary.condition(side.tag);
            let law = side.neighbour.map(|_| self.interfaces.law(side.tag));
            let contact = side.contact.map(|f| {
                let face = &self.contact.faces()[f];
                if face.a == i {
                    &face.targets_a
                } else {
                    &face.targets_b
                }
            });
            // Polynomial integrands between linear elements; boundary data and nonlinear faces
            // (whose states the contact faces hold at the data rule's points) take the other.
            let polynomial = law.is_some_and(|law| !law.is_nonlinear());
            let quadrature = if polynomial { exact } else { data };
            let (rule, tables) = (&quadrature.rule, &quadrature.tables);
            let across = side.neighbour.map(|j| {
                let other = &self.slots[j];
                let (scratch, basis) = (&mut self.other_values, &self.basis);
                let at = (&slot, side.face);
                other_values(
                    tables,
                    basis,
                    scratch,
                    rule,
                    at,
                    &other.geometry,
                    &other.vertices,
                )
            });
            face_momentum = [0.0; 2];
            let mut point = 0;
            face_points(rule, &slot.vertices, side.face, |x, w, nrm| {
                let normal = [nrm[0], nrm[1]];
                let a = system.frame(&own(tables, side.face, point), normal);
                let star_trace = match (side.neighbour, law) {
                    (Some(_), Some(law)) if law.is_nonlinear() => {
                        contact.expect("contact faces are registered")[point].star
                    }
                    (Some(_), Some(Law::Free)) => {
                        riemann::solve(system, &a, &[Side::Traction(0.0); 2])
                    }
                    (Some(j), _) => {
                        let phi_j = &across.expect("a neighbour")[point * n..][..n];
                        let q_b = combine(&solution[j * m..(j + 1) * m], phi_j, fields);
                        riemann::bonded(system, &a, &system.frame(&q_b, normal))
                    }
                    (None, _) => {
                        let sides = boundary.sides(
                            system,
                            condition,
                            [x[0], x[1]],
                            x[2] / c,
                            normal,
                            false,
                        );
                        riemann::solve(system, &a, &sides)
                    }
                };
                let power = w
                    * (0..system.directions())
                        .map(|k| star_trace.v[k] * star_trace.s[k])
                        .sum::<f64>();
                point += 1;
                r.vertical_work += power;
                match law {
                    None => r.boundary_work += power,
                    Some(Law::Bonded) => {}
                    Some(law) => {
                        r.interface_work -= power;
                        if law.is_cohesive() {
                            r.fracture_work -= power;
                        } else {
                            r.friction_dissipation -= w * star_trace.v[1] * star_trace.s[1];
                        }
                    }
                }
                r.dissipation += w * riemann::dissipation(system, &a, &star_trace);
                let f = system.flux(&star_trace, normal);
                for (fm, a) in face_momentum.iter_mut().zip(&f[..nv]) {
                    *fm += w * a;
                }
            });
            add_momentum(face_momentum);
        }
        r.dissipation_balance = r.energy_in - r.energy_out + r.vertical_work;
        r.momentum_imbalance = momentum[0].hypot(momentum[1]);
        r.momentum_flux = scale;
        r.momentum_residual = r.momentum_imbalance / scale.max(f64::MIN_POSITIVE);
        r
    }

    /// Solves `du/dtau = v / c_ref` on element `i` (upwind in time from the element below) and
    /// stores the displacement coefficients in the output buffer.
    pub(super) fn displacement(&mut self, i: usize) {
        let n = self.basis.len();
        let fields = self.system.fields();
        let nv = self.system.displacement_components();
        let width = self.width();
        let c = self.system.c_ref();
        let slot = self.slots[i];
        let det = slot.geometry.det();
        let inv_tau = [0, 1, 2].map(|r| slot.geometry.inverse()[r][2]);
        let small = &mut self.small[..n * n];
        let rhs = &mut self.small_rhs[..n * nv];
        for k in 0..n {
            for l in 0..n {
                small[l * n + k] = det
                    * (0..3)
                        .map(|r| self.h_ref[r][k * n + l] * inv_tau[r])
                        .sum::<f64>();
            }
            for d in 0..nv {
                rhs[d * n + k] = det * self.output[i * n * width + k * width + d] / c;
            }
        }
        let stride = self.data.tables.points();
        for (f, &(face, source)) in slot.inflows().iter().enumerate() {
            // The rule and the displacements below of the assembly.
            let quadrature = if self.inflow.solved[source] {
                &self.exact
            } else {
                &self.data
            };
            let (rule, tables) = (&quadrature.rule, &quadrature.tables);
            let kept = &self.below_states[(2 * i + f) * stride..][..stride];
            let (_, _, _, nrm, area2) = face_geometry(&slot.vertices, face);
            let own = FaceTables::triple(face.0);
            for (s, mass) in small.iter_mut().zip(tables.mass(own)) {
                // The mass is symmetric: row-major or column-major alike.
                *s -= area2 * nrm[2] * mass;
            }
            let mut points = tables.values(own).chunks_exact(n).enumerate();
            face_points(rule, &slot.vertices, face, |_, w, nrm| {
                let (q, phi) = points.next().expect("one per rule point");
                let u_prev = kept[q].1;
                for (k, p) in phi.iter().enumerate() {
                    for d in 0..nv {
                        rhs[d * n + k] -= w * nrm[2] * p * u_prev[d];
                    }
                }
            });
        }
        let stack = MemStack::new(&mut self.stack);
        let lu = MatMut::from_column_major_slice_mut(small, n, n);
        let (_, perm) = factor::lu_in_place(
            lu,
            &mut self.perm[..n],
            &mut self.perm_inv[..n],
            Par::Seq,
            stack,
            Default::default(),
        );
        let lu = MatRef::from_column_major_slice(&self.small[..n * n], n, n);
        let x = MatMut::from_column_major_slice_mut(&mut self.small_rhs[..n * nv], n, nv);
        solve::solve_in_place(lu, lu, perm, x, Par::Seq, stack);
        for k in 0..n {
            for d in 0..nv {
                self.output[i * n * width + k * width + fields + d] = self.small_rhs[d * n + k];
            }
        }
    }
}

/// The state `sum_k phi_k q_k` of coefficients stored `fields` per basis function.
fn combine(coefficients: &[f64], phi: &[f64], fields: usize) -> State {
    let mut q = [0.0; MAX_FIELDS];
    for (k, p) in phi.iter().enumerate() {
        for (qc, c) in q
            .iter_mut()
            .zip(&coefficients[k * fields..(k + 1) * fields])
        {
            *qc += p * c;
        }
    }
    q
}
