//! Basis values and face matrices tabulated once per order on the faces of the reference
//! tetrahedron.
//!
//! An element is an affine image of the reference tetrahedron, so the quadrature points of one
//! of its faces, mapped back, are the face rule's points on a face of the reference element: the
//! basis values there, the face mass matrix and the traces in an orthonormal face basis are the
//! same for every element up to the face's area. A face is named by its corners in order (the
//! rule's first point direction runs from the first corner to the second), so the same physical
//! points seen from the element across the face, or from the element below, are a table of that
//! element too: [`FaceTables::corners_in`] finds which.

use crate::basis::Basis;
use crate::quadrature::{self, Rule};
use crate::spacetime::SpacePoint;

/// Ordered corner triples `(a, b, c)` of a tetrahedron, at `16 a + 4 b + c`.
const TRIPLES: usize = 64;

/// Per-order tables on the 24 ordered faces of the reference tetrahedron.
#[derive(Clone, Debug)]
pub struct FaceTables {
    n: usize,
    points: usize,
    face_dim: usize,
    /// `values[t][q * n + k]`: basis function `k` at rule point `q` of face triple `t`.
    values: Vec<Vec<f64>>,
    /// `masses[t][k * n + l]`: `sum_q w_q phi_k phi_l` with the reference rule's weights.
    masses: Vec<Vec<f64>>,
    /// `traces[t][k * face_dim + f]`: `sum_q w_q phi_k psi_f`, with `psi` orthonormal in the
    /// reference rule's inner product ([`quadrature::triangle_orthonormal`]).
    traces: Vec<Vec<f64>>,
    /// The orthonormal face basis at the rule's points and the rule's weights.
    psi: Vec<f64>,
    weights: Vec<f64>,
}

impl FaceTables {
    /// The tables of `basis` at the points of `rule`, exact for degree `2 p` or more.
    pub fn new(basis: &Basis, rule: &Rule<2>) -> Self {
        let n = basis.len();
        let points = rule.points.len();
        let p = basis.degree();
        let face_dim = (p + 1) * (p + 2) / 2;
        let psi = quadrature::triangle_orthonormal(rule, p);
        let reference: [[f64; 3]; 4] =
            [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let mut tables = Self {
            n,
            points,
            face_dim,
            values: vec![Vec::new(); TRIPLES],
            masses: vec![Vec::new(); TRIPLES],
            traces: vec![Vec::new(); TRIPLES],
            psi,
            weights: rule.weights.clone(),
        };
        for t in 0..TRIPLES {
            let [a, b, c] = [t / 16, t / 4 % 4, t % 4];
            if a == b || b == c || a == c {
                continue;
            }
            let (r0, r1, r2) = (reference[a], reference[b], reference[c]);
            let mut values = vec![0.0; points * n];
            for (q, xi) in rule.points.iter().enumerate() {
                let x =
                    [0, 1, 2].map(|i| r0[i] + xi[0] * (r1[i] - r0[i]) + xi[1] * (r2[i] - r0[i]));
                basis.eval(x, &mut values[q * n..(q + 1) * n]);
            }
            let mut mass = vec![0.0; n * n];
            let mut trace = vec![0.0; n * face_dim];
            for (q, &w) in rule.weights.iter().enumerate() {
                let phi = &values[q * n..(q + 1) * n];
                for (k, &pk) in phi.iter().enumerate() {
                    for (m, &pl) in mass[k * n..(k + 1) * n].iter_mut().zip(phi) {
                        *m += w * pk * pl;
                    }
                }
            }
            tables.trace_of(&values, &mut trace);
            tables.values[t] = values;
            tables.masses[t] = mass;
            tables.traces[t] = trace;
        }
        tables
    }

    /// The index of face `corners` (distinct corners 0..4, in order).
    pub fn triple(corners: [usize; 3]) -> usize {
        16 * corners[0] + 4 * corners[1] + corners[2]
    }

    /// The corners of `vertices` at the three `points` in their order, as a triple index; none
    /// if a point is not a vertex (within `1e-10` of the element's extent).
    pub fn corners_in(points: [SpacePoint; 3], vertices: &[SpacePoint; 4]) -> Option<usize> {
        let extent = vertices
            .iter()
            .flat_map(|v| (0..3).map(move |i| (v[i] - vertices[0][i]).abs()))
            .fold(0.0f64, f64::max);
        let tolerance = 1e-10 * extent;
        let mut corners = [0; 3];
        for (corner, p) in corners.iter_mut().zip(points) {
            *corner = vertices
                .iter()
                .position(|v| (0..3).all(|i| (v[i] - p[i]).abs() <= tolerance))?;
        }
        (corners[0] != corners[1] && corners[1] != corners[2] && corners[0] != corners[2])
            .then(|| Self::triple(corners))
    }

    /// Basis values at the rule's points of face triple `t`: `n` per point.
    pub fn values(&self, t: usize) -> &[f64] {
        &self.values[t]
    }

    /// The values of rule point `q` of face triple `t`.
    pub fn at(&self, t: usize, q: usize) -> &[f64] {
        &self.values[t][q * self.n..(q + 1) * self.n]
    }

    /// The reference face mass matrix of triple `t` (`n x n`); times twice the face's area it
    /// is the physical one.
    pub fn mass(&self, t: usize) -> &[f64] {
        &self.masses[t]
    }

    /// The traces of triple `t` (`n x face_dim` row-major); times the square root of twice the
    /// face's area they give the physical face mass between two elements as `T_a T_b^T`.
    pub fn trace(&self, t: usize) -> &[f64] {
        &self.traces[t]
    }

    /// The traces (as [`Self::trace`]) of functions with `values` at the rule's points (`n`
    /// per point), into `out`.
    pub fn trace_of(&self, values: &[f64], out: &mut [f64]) {
        let (n, f) = (self.n, self.face_dim);
        out[..n * f].fill(0.0);
        for (q, &w) in self.weights.iter().enumerate() {
            let psi = &self.psi[q * f..(q + 1) * f];
            for (k, &pk) in values[q * n..(q + 1) * n].iter().enumerate() {
                for (o, &s) in out[k * f..(k + 1) * f].iter_mut().zip(psi) {
                    *o += w * pk * s;
                }
            }
        }
    }

    /// Dimension of the face polynomials.
    pub fn face_dim(&self) -> usize {
        self.face_dim
    }

    /// Number of rule points per face.
    pub fn points(&self) -> usize {
        self.points
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::Geometry;

    #[test]
    fn tabulated_values_are_the_basis_at_the_mapped_points() {
        for p in 1..=4 {
            let basis = Basis::new(p);
            let rule = quadrature::triangle(2 * p + 2);
            let tables = FaceTables::new(&basis, &rule);
            let vertices = [
                [0.1, 0.2, 0.0],
                [1.3, 0.1, 0.2],
                [0.4, 1.1, 0.1],
                [0.3, 0.4, 0.9],
            ];
            let geometry = Geometry::new(&vertices);
            let mut phi = vec![0.0; basis.len()];
            for corners in [[1, 2, 3], [0, 1, 3], [3, 0, 2], [2, 1, 0]] {
                let points = corners.map(|c| vertices[c]);
                let t = FaceTables::corners_in(points, &vertices).expect("a face");
                assert_eq!(t, FaceTables::triple(corners));
                for (q, xi) in rule.points.iter().enumerate() {
                    let x = [0, 1, 2].map(|i| {
                        points[0][i]
                            + xi[0] * (points[1][i] - points[0][i])
                            + xi[1] * (points[2][i] - points[0][i])
                    });
                    basis.eval(geometry.to_reference(x), &mut phi);
                    for (a, b) in phi.iter().zip(tables.at(t, q)) {
                        assert!((a - b).abs() < 1e-12, "p = {p}, {corners:?}: {a} vs {b}");
                    }
                }
                let mut trace = vec![0.0; basis.len() * tables.face_dim()];
                tables.trace_of(tables.values(t), &mut trace);
                assert_eq!(trace, tables.trace(t));
                // The traces give the mass: T T^T.
                let (n, f) = (basis.len(), tables.face_dim());
                let (mass, trace) = (tables.mass(t), tables.trace(t));
                for k in 0..n {
                    for l in 0..n {
                        let product: f64 =
                            (0..f).map(|a| trace[k * f + a] * trace[l * f + a]).sum();
                        assert!((product - mass[k * n + l]).abs() < 1e-12, "p = {p}");
                    }
                }
            }
            let elsewhere = [[5.0, 5.0, 5.0], vertices[1], vertices[2]];
            assert_eq!(FaceTables::corners_in(elsewhere, &vertices), None);
        }
    }
}
