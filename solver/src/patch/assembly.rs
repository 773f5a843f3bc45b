//! Assembly of a patch's linear system and its solve.
//!
//! Weak form (see `docs/theory/method.md`): on every element `K` of the patch, for every test function
//! `phi` in the complete polynomials of degree `p`,
//!
//! `int_K phi . (A0 q_tau + Ax q_x + Ay q_y) + sum over faces F of int_F phi . (F* - A_n q) = 0`
//!
//! with the target flux `F*`: the earlier side's flux `A_n q_prev` on the inflow (bottom) face,
//! the element's own `A_n q` on the outflow (top) face, and the Riemann flux `A_m q*` on the
//! vertical faces, which couple the ring of elements around the tent pole, or carry the boundary
//! data. The patch system is solved by block elimination around the ring of elements
//! ([`crate::ring`]).
//!
//! Above an interface edge the vertical faces take their targets from the interface's law
//! ([`crate::interface`]): bonded faces keep the linear path, free faces are traction-free on
//! both sides (still linear), and contact faces make the patch a Newton solve (`contact`).

use std::time::Instant;

use faer::Accum;

use super::inflow::{Initial, inflow_displacement, inflow_state, inflow_values, other_values};
use super::kron::kron_sum;
use super::newton::NewtonFailure;
use super::report::PatchReport;
use super::slot::{Face, Slot, face_geometry, face_points};
use super::solver::PatchSolver;
use super::tables::FaceTables;
use crate::basis::Basis;
use crate::boundary::{Boundary, Condition};
use crate::interface::Law;
use crate::quadrature::Rule;
use crate::riemann;
use crate::system::{FrameTrace, MAX_FIELDS, Matrix, State, System};

impl PatchSolver {
    /// Assembles and solves the patch of the first `self.used` slots, whose inflow sources and
    /// contact faces are gathered, and computes the element reports.
    pub(super) fn solve_slots(
        &mut self,
        boundary: &Boundary,
        initial: Initial,
    ) -> Result<PatchReport, NewtonFailure> {
        let started = Instant::now();
        let c = self.system.c_ref();
        let d = self.used;
        let n = self.basis.len();
        let fields = self.system.fields();
        let m = n * fields;
        self.blocks.reset(d, m);
        let a_mu = [
            self.system.a_n([1.0, 0.0, 0.0]),
            self.system.a_n([0.0, 1.0, 0.0]),
            self.system.a_n([0.0, 0.0, 1.0]),
        ];
        for i in 0..d {
            let slot = self.slots[i];
            // The diagonal block is a sum of Kronecker products, added at the end: 3 volume
            // terms, one per inflow face, one per vertical face.
            let mut diagonal: [(&[f64], Matrix); 7] = [(&[], [[0.0; MAX_FIELDS]; MAX_FIELDS]); 7];
            let mut terms = 0;
            // Volume: det * sum_r H_r (x) B_r with B_r = sum_mu inverse[r][mu] A_mu.
            let inv = slot.geometry.inverse();
            let det = slot.geometry.det();
            for (h, inv_r) in self.h_ref.iter().zip(inv) {
                let mut b = [[0.0; MAX_FIELDS]; MAX_FIELDS];
                for (a, &factor) in a_mu.iter().zip(inv_r) {
                    for (brow, arow) in b.iter_mut().zip(a) {
                        for (x, y) in brow.iter_mut().zip(arow) {
                            *x += det * factor * y;
                        }
                    }
                }
                diagonal[terms] = (h, b);
                terms += 1;
            }
            // Inflow faces: the target is the earlier side's trace.
            let stride = self.data.tables.points();
            for (f, &(face, source)) in slot.inflows().iter().enumerate() {
                let own = FaceTables::triple(face.0);
                let (_, _, _, nrm, area2) = face_geometry(&slot.vertices, face);
                let an = self.system.a_n(nrm);
                let kept = &mut self.below_states[(2 * i + f) * stride..][..stride];
                let (quadrature, under) = inflow_values(
                    [&self.exact, &self.data],
                    &self.basis,
                    &mut self.other_values,
                    &slot,
                    face,
                    self.inflow.below(source),
                );
                let (rule, tables) = (&quadrature.rule, &quadrature.tables);
                let system = &self.system;
                let mut points = tables.values(own).chunks_exact(n).enumerate();
                let rhs = self.blocks.rhs_mut(i);
                face_points(rule, &slot.vertices, face, |x, w, _| {
                    let (q, phi) = points.next().expect("one per rule point");
                    let under = under.map(|(v, c)| (&v[q * n..][..n], c));
                    let q_prev = inflow_state(system, under, initial, x);
                    kept[q] = (q_prev, inflow_displacement(system, under, initial, x));
                    let aq = system.apply(&an, &q_prev);
                    for (k, p) in phi.iter().enumerate() {
                        for (r, a) in rhs[k * fields..][..fields].iter_mut().zip(&aq) {
                            *r -= w * p * a;
                        }
                    }
                });
                diagonal[terms] = (tables.mass(own), an.map(|row| row.map(|x| -area2 * x)));
                terms += 1;
            }
            let system = &self.system;
            // Vertical faces: Riemann fluxes with the ring neighbour or the boundary data; free
            // interfaces are traction-free on each side. Contact faces are assembled bonded: the
            // Newton iterations add the difference of their targets from the bonded ones.
            for side in slot.sides() {
                let (face, tag) = (side.face, side.tag);
                let law = side.neighbour.map(|_| self.interfaces.law(tag));
                let (neighbour, condition) = match law {
                    Some(Law::Free) => (None, &Condition::Free),
                    _ => (side.neighbour, boundary.condition(tag)),
                };
                let own = FaceTables::triple(face.0);
                let (_, _, _, nrm, area2) = face_geometry(&slot.vertices, face);
                let normal = [nrm[0], nrm[1]];
                let a_m = system.a_n([normal[0], normal[1], 0.0]);
                let (m_a, m_b) =
                    face_matrices(system, boundary, condition, neighbour.is_some(), normal);
                let self_block: Matrix = std::array::from_fn(|r| {
                    std::array::from_fn(|c| area2 * (m_a[r][c] - a_m[r][c]))
                });
                diagonal[terms] = (self.exact.tables.mass(own), self_block);
                terms += 1;
                let Some(j) = neighbour else {
                    let mut points = self.data.tables.values(own).chunks_exact(n);
                    let rhs = self.blocks.rhs_mut(i);
                    face_points(&self.data.rule, &slot.vertices, face, |x, w, _| {
                        let phi = points.next().expect("one per rule point");
                        let sides = boundary.sides(
                            system,
                            condition,
                            [x[0], x[1]],
                            x[2] / c,
                            normal,
                            false,
                        );
                        let g = system.flux(
                            &riemann::solve(system, &FrameTrace::default(), &sides),
                            normal,
                        );
                        for (k, p) in phi.iter().enumerate() {
                            for (r, gc) in rhs[k * fields..][..fields].iter_mut().zip(&g) {
                                *r -= w * p * gc;
                            }
                        }
                    });
                    continue;
                };
                // Face mass (T_i T_j^T area2) (x) (L R^T): rank face_dim x rank(m_b).
                let trace_j = neighbour_trace(
                    &self.exact.tables,
                    &self.basis,
                    &mut self.other_values,
                    &mut self.trace,
                    &self.exact.rule,
                    (&slot, face),
                    &self.slots[j],
                );
                let (trace_i, nf) = (self.exact.tables.trace(own), self.exact.tables.face_dim());
                let (rank, l, r) = low_rank(&m_b, fields);
                let (u, v) = self.blocks.term_mut(nf * rank);
                for (k, (ti, tj)) in trace_i
                    .chunks_exact(nf)
                    .zip(trace_j.chunks_exact(nf))
                    .enumerate()
                {
                    for f in 0..nf {
                        for s in 0..rank {
                            let column = (f * rank + s) * m + k * fields;
                            for a in 0..fields {
                                u[column + a] = area2 * ti[f] * l[a][s];
                                v[column + a] = tj[f] * r[a][s];
                            }
                        }
                    }
                }
                self.blocks.add_term(i, j, nf * rank, 1.0);
            }
            kron_sum(
                self.blocks.new_block_mut(i, i),
                Accum::Replace,
                m,
                n,
                fields,
                &diagonal[..terms],
            );
        }

        ring_order(&self.slots[..d], &mut self.order);
        let assembled = Instant::now();
        let newton_iterations = if self.contact.faces().is_empty() {
            self.blocks.solve(&self.order[..d]);
            0
        } else {
            self.solve_newton()?
        };
        let solved = Instant::now();

        let mut report = PatchReport {
            elements: d,
            dofs: d * m,
            newton_iterations,
            assembly_s: (assembled - started).as_secs_f64(),
            solve_s: (solved - assembled).as_secs_f64(),
            ..Default::default()
        };
        for i in 0..d {
            let r = self.element_post(i, boundary);
            report.accumulate(&PatchReport::from(&r));
            self.reports[i] = r;
            self.displacement(i);
        }
        self.faces.clear();
        self.faces.extend(self.contact.finish());
        self.contact.find_crossings(c);
        let (fields, width, output) = (self.system.fields(), self.width(), &self.output);
        report.cohesive_mismatch = self.contact.cohesive_mismatch(|i, phi| {
            let mut u = [0.0; 2];
            for (k, ph) in phi.iter().enumerate() {
                let at = &output[(i * n + k) * width + fields..];
                u[0] += ph * at[0];
                u[1] += ph * at[1];
            }
            u
        });
        report.evaluation_s = solved.elapsed().as_secs_f64();
        Ok(report)
    }
}

/// Orders the star's elements along the ring around the pole: each chain from its element
/// without a neighbour across its first side (`SIDE_A`, boundary tents), then closed rings,
/// walking across the second (`SIDE_B`, counter-clockwise). Elimination in this order fills only
/// blocks that couple to a ring's last element.
fn ring_order(slots: &[Slot], order: &mut Vec<usize>) {
    order.clear();
    let d = slots.len();
    let next = |i: usize| slots[i].sides[1].neighbour;
    let starts_chain = |i: usize| slots[i].sides[0].neighbour.is_none();
    for pass in [true, false] {
        for first in 0..d {
            if order.contains(&first) || (pass && !starts_chain(first)) {
                continue;
            }
            let mut i = first;
            loop {
                order.push(i);
                match next(i) {
                    Some(j) if !order.contains(&j) => i = j,
                    _ => break,
                }
            }
        }
    }
}

/// `matrix = L R^T` with `L`, `R` of `rank` columns (`l[a][s]`: row `a`, column `s`) on its
/// leading `fields x fields` part, by Gaussian elimination with full pivoting; pivots below
/// `1e-12` of the largest entry count as zero.
fn low_rank(matrix: &Matrix, fields: usize) -> (usize, Matrix, Matrix) {
    let mut rest = *matrix;
    let (mut l, mut r) = (
        [[0.0; MAX_FIELDS]; MAX_FIELDS],
        [[0.0; MAX_FIELDS]; MAX_FIELDS],
    );
    let largest = |m: &Matrix| {
        let mut best = (0, 0, 0.0f64);
        for (a, row) in m[..fields].iter().enumerate() {
            for (b, &x) in row[..fields].iter().enumerate() {
                if x.abs() > best.2 {
                    best = (a, b, x.abs());
                }
            }
        }
        best
    };
    let scale = largest(matrix).2;
    for s in 0..fields {
        let (p, q, size) = largest(&rest);
        if size <= 1e-12 * scale || size == 0.0 {
            return (s, l, r);
        }
        let pivot = rest[p][q];
        for a in 0..fields {
            l[a][s] = rest[a][q] / pivot;
            r[a][s] = rest[p][a];
        }
        for a in 0..fields {
            for b in 0..fields {
                rest[a][b] -= l[a][s] * r[b][s];
            }
        }
    }
    (fields, l, r)
}

/// The traces on `slot`'s `face` of the patch element `other` across it ([`FaceTables::trace`]).
fn neighbour_trace<'a>(
    tables: &'a FaceTables,
    basis: &Basis,
    values: &mut [f64],
    trace: &'a mut [f64],
    rule: &Rule<2>,
    (slot, face): (&Slot, Face),
    other: &Slot,
) -> &'a [f64] {
    match FaceTables::corners_in(face.0.map(|c| slot.vertices[c]), &other.vertices) {
        Some(t) => tables.trace(t),
        None => {
            let values = other_values(
                tables,
                basis,
                values,
                rule,
                (slot, face),
                &other.geometry,
                &other.vertices,
            );
            tables.trace_of(values, trace);
            trace
        }
    }
}

/// The flux matrices of a vertical face with outward normal `m`: `F* = M_a q_a + M_b q_b + g`,
/// with `g` the boundary data's part (zero between elements).
fn face_matrices(
    system: &System,
    boundary: &Boundary,
    condition: &Condition,
    interior: bool,
    m: [f64; 2],
) -> (Matrix, Matrix) {
    let homogeneous = boundary.sides(system, condition, [0.0; 2], 0.0, m, true);
    let flux = |qa: &State, qb: &State| -> State {
        let a = system.frame(qa, m);
        let star = if interior {
            riemann::bonded(system, &a, &system.frame(qb, m))
        } else {
            riemann::solve(system, &a, &homogeneous)
        };
        system.flux(&star, m)
    };
    let mut m_a = [[0.0; MAX_FIELDS]; MAX_FIELDS];
    let mut m_b = [[0.0; MAX_FIELDS]; MAX_FIELDS];
    let zero = [0.0; MAX_FIELDS];
    for j in 0..system.fields() {
        let mut e = zero;
        e[j] = 1.0;
        let fa = flux(&e, &zero);
        let fb = if interior { flux(&zero, &e) } else { zero };
        for i in 0..system.fields() {
            m_a[i][j] = fa[i];
            m_b[i][j] = fb[i];
        }
    }
    (m_a, m_b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Material, Plane};

    #[test]
    fn the_coupling_through_a_face_passes_only_the_incoming_waves() {
        // The bonded flux's dependence on the other side has rank 2 in plane strain (P and S
        // waves) and 1 in anti-plane shear; L R^T gives it back.
        for (plane, waves) in [(Plane::Strain, 2), (Plane::Antiplane, 1)] {
            let system = System::new(&Material::new(3.24e9, 0.35, 1190.0, plane).expect("PMMA"));
            let boundary = Boundary::new(vec![None; 1], None);
            let normal = [0.6, -0.8];
            let (_, m_b) = face_matrices(&system, &boundary, &Condition::Free, true, normal);
            let fields = system.fields();
            let (rank, l, r) = low_rank(&m_b, fields);
            assert_eq!(rank, waves, "{plane:?}");
            let largest = m_b.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
            for a in 0..fields {
                for b in 0..fields {
                    let product: f64 = (0..rank).map(|s| l[a][s] * r[b][s]).sum();
                    assert!((product - m_b[a][b]).abs() <= 1e-14 * largest, "{plane:?}");
                }
            }
        }
    }
}
