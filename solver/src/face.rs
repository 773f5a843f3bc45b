//! Interface faces: the vertical spacetime triangles above an interface edge, and the interface
//! state they carry.
//!
//! The tent at vertex `v` builds one vertical face over each of its star edges `(v, w)`: corners
//! `P0 = (v, tau_old)`, `P1 = (w, tau_w)` and `P2 = (v, tau_new)` in scaled coordinates. Its
//! bottom edge `P0 P1` lies on the front (it is the top edge of the previous face over the same
//! edge), its top edge `P2 P1` becomes the front. On an interface edge the face carries the
//! normal separation `delta` (m), the tangential slip (m) and, with the damage law, the damage
//! `D`, each a polynomial of total degree `p` on the face, advanced in time by its own upwind DG
//! (seed 4.21-4.22): `d delta / d tau = [[v*_n]] / c_ref` (3.40), `d D / d tau = (dD/dt) / c_ref`
//! (4.8), no flux along the edge, the previous face's trace as inflow on the bottom edge. A bisected edge hands each half the parent's face, whose
//! polynomial restricts exactly: nothing is projected.

use crate::spacetime::SpacePoint;

/// Largest number of face basis functions (degree 4).
pub const MAX_FACE_BASIS: usize = 15;

/// Monomials `xi^i eta^j`, `i + j <= p`, on the reference triangle `{xi, eta >= 0, xi + eta <= 1}`.
#[derive(Clone, Debug)]
pub struct FaceBasis {
    powers: Vec<(i32, i32)>,
}

impl FaceBasis {
    /// The basis of total degree `degree` (at most 4).
    pub fn new(degree: usize) -> Self {
        assert!(degree <= 4, "face bases go up to degree 4");
        let d = degree as i32;
        let powers = (0..=d)
            .flat_map(|total| (0..=total).map(move |j| (total - j, j)))
            .collect();
        Self { powers }
    }

    /// Number of basis functions.
    pub fn len(&self) -> usize {
        self.powers.len()
    }

    /// The total degree `p`; the first `p (p + 1) / 2` functions span degree `p - 1`.
    pub fn degree(&self) -> usize {
        self.powers.last().map_or(0, |&(i, j)| (i + j) as usize)
    }

    /// True for no basis functions (never).
    pub fn is_empty(&self) -> bool {
        self.powers.is_empty()
    }

    /// Values at reference point `xi` into `out` (length [`Self::len`]).
    pub fn eval(&self, xi: [f64; 2], out: &mut [f64]) {
        for (o, &(i, j)) in out.iter_mut().zip(&self.powers) {
            *o = xi[0].powi(i) * xi[1].powi(j);
        }
    }

    /// Values and reference gradients at `xi`.
    pub fn eval_with_gradient(&self, xi: [f64; 2], out: &mut [f64], grad: &mut [[f64; 2]]) {
        for ((o, g), &(i, j)) in out.iter_mut().zip(grad.iter_mut()).zip(&self.powers) {
            let (a, b) = (xi[0].powi(i), xi[1].powi(j));
            *o = a * b;
            let da = if i > 0 {
                f64::from(i) * xi[0].powi(i - 1)
            } else {
                0.0
            };
            let db = if j > 0 {
                f64::from(j) * xi[1].powi(j - 1)
            } else {
                0.0
            };
            *g = [da * b, a * db];
        }
    }
}

/// The affine map of a vertical face from the reference triangle: corner `k` of the reference
/// (`0`, `e1`, `e2`) goes to corner `k` of the face (`P0`, `P1`, `P2`). Points are located on the
/// face by their distance `s` from `P0` along the edge direction and their height `tau`.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FaceGeometry {
    corners: [SpacePoint; 3],
    /// Unit direction of the edge from `P0` to `P1` in space.
    direction: [f64; 2],
    /// `d (xi, eta) / d (s, tau)` as rows `[d xi / ds, d xi / dtau]`, `[d eta / ds, d eta / dtau]`.
    inverse: [[f64; 2]; 2],
    /// Length of the edge, m.
    length: f64,
}

impl FaceGeometry {
    /// The face with corners `P0` (pole bottom), `P1` (far end of the edge) and `P2` (pole top).
    pub fn new(corners: [SpacePoint; 3]) -> Self {
        let [p0, p1, p2] = corners;
        let d = [p1[0] - p0[0], p1[1] - p0[1]];
        let length = d[0].hypot(d[1]);
        let direction = [d[0] / length, d[1] / length];
        // Columns of the map in (s, tau): P1 - P0 = (L, dtau1), P2 - P0 = (s2, dtau2).
        let s2 = (p2[0] - p0[0]) * direction[0] + (p2[1] - p0[1]) * direction[1];
        let j = [[length, s2], [p1[2] - p0[2], p2[2] - p0[2]]];
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        let inverse = [
            [j[1][1] / det, -j[0][1] / det],
            [-j[1][0] / det, j[0][0] / det],
        ];
        Self {
            corners,
            direction,
            inverse,
            length,
        }
    }

    /// The corners `P0`, `P1`, `P2`.
    pub fn corners(&self) -> [SpacePoint; 3] {
        self.corners
    }

    /// Length of the edge, m.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// Reference coordinates of a point `x` of the face's plane.
    pub fn to_reference(&self, x: SpacePoint) -> [f64; 2] {
        let p0 = self.corners[0];
        let s = (x[0] - p0[0]) * self.direction[0] + (x[1] - p0[1]) * self.direction[1];
        let tau = x[2] - p0[2];
        self.inverse.map(|row| row[0] * s + row[1] * tau)
    }

    /// `d (xi, eta) / d tau`.
    pub fn d_tau(&self) -> [f64; 2] {
        [self.inverse[0][1], self.inverse[1][1]]
    }

    /// The map's stored values (corners, edge direction, inverse by rows, length), for sending
    /// it to another process bit for bit; [`Self::from_values`] reads them back.
    pub fn to_values(&self) -> [f64; FACE_GEOMETRY_VALUES] {
        let mut out = [0.0; FACE_GEOMETRY_VALUES];
        let stored = (self.corners.iter().flatten())
            .chain(&self.direction)
            .chain(self.inverse.iter().flatten())
            .chain([&self.length]);
        for (o, &x) in out.iter_mut().zip(stored) {
            *o = x;
        }
        out
    }

    /// The map whose [`Self::to_values`] are `values`, bitwise.
    pub fn from_values(values: &[f64; FACE_GEOMETRY_VALUES]) -> Self {
        Self {
            corners: std::array::from_fn(|k| std::array::from_fn(|i| values[3 * k + i])),
            direction: [values[9], values[10]],
            inverse: [[values[11], values[12]], [values[13], values[14]]],
            length: values[15],
        }
    }
}

/// Values in [`FaceGeometry::to_values`].
pub const FACE_GEOMETRY_VALUES: usize = 16;

/// Components of the interface state: the normal separation `delta` (m), the tangential slip
/// (m) and the damage `D` (dimensionless, seed 4.2; zero for laws without damage).
pub const STATE_COMPONENTS: usize = 3;

/// The interface state on one face: coefficients of each of its [`STATE_COMPONENTS`] in the
/// face's [`FaceBasis`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FaceState {
    /// Where the face lies.
    pub geometry: FaceGeometry,
    /// Coefficients of `delta`, slip and `D`; only the first `FaceBasis::len` of each are used.
    pub coefficients: [[f64; MAX_FACE_BASIS]; STATE_COMPONENTS],
}

impl FaceState {
    /// `[delta (m), slip (m), D]` at the point `x` of the face; `psi` is scratch of the basis
    /// length.
    pub fn evaluate(
        &self,
        basis: &FaceBasis,
        x: SpacePoint,
        psi: &mut [f64],
    ) -> [f64; STATE_COMPONENTS] {
        basis.eval(self.geometry.to_reference(x), psi);
        self.coefficients
            .map(|c| psi.iter().zip(&c).map(|(p, c)| p * c).sum::<f64>())
    }
}

/// Solves the dense `n x n` system `a x = b` (row-major `a`, overwritten by its LU factors) for
/// `columns` right-hand sides stored one after another in `b`, by Gaussian elimination with
/// partial pivoting. Returns false for a singular matrix.
pub(crate) fn solve_dense(a: &mut [f64], n: usize, b: &mut [f64], columns: usize) -> bool {
    for k in 0..n {
        let pivot = (k..n)
            .max_by(|&i, &j| a[i * n + k].abs().total_cmp(&a[j * n + k].abs()))
            .expect("k < n");
        if a[pivot * n + k] == 0.0 || !a[pivot * n + k].is_finite() {
            return false;
        }
        if pivot != k {
            for c in 0..n {
                a.swap(k * n + c, pivot * n + c);
            }
            for col in 0..columns {
                b.swap(col * n + k, col * n + pivot);
            }
        }
        for i in k + 1..n {
            let f = a[i * n + k] / a[k * n + k];
            if f == 0.0 {
                continue;
            }
            for c in k..n {
                a[i * n + c] -= f * a[k * n + c];
            }
            for col in 0..columns {
                b[col * n + i] -= f * b[col * n + k];
            }
        }
    }
    for col in 0..columns {
        let x = &mut b[col * n..(col + 1) * n];
        for k in (0..n).rev() {
            let s: f64 = (k + 1..n).map(|c| a[k * n + c] * x[c]).sum();
            x[k] = (x[k] - s) / a[k * n + k];
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geometry_maps_corners_to_the_reference() {
        let g = FaceGeometry::new([[0.1, 0.2, 0.5], [0.4, 0.6, 0.7], [0.1, 0.2, 0.9]]);
        let refs = g.corners().map(|c| g.to_reference(c));
        let want = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        for (r, w) in refs.iter().zip(want) {
            assert!((r[0] - w[0]).abs() < 1e-14 && (r[1] - w[1]).abs() < 1e-14);
        }
        assert!((g.length() - 0.5).abs() < 1e-15);
        let values = g.to_values();
        assert_eq!(values[..3], [0.1, 0.2, 0.5]);
        assert_eq!(values[15], g.length());
        assert_eq!(FaceGeometry::from_values(&values), g);
        // Along the pole, tau alone changes eta.
        let dt = g.d_tau();
        assert!(dt[0].abs() < 1e-14 && (dt[1] - 2.5).abs() < 1e-12);
    }

    #[test]
    fn gradients_match_finite_differences() {
        let b = FaceBasis::new(4);
        assert_eq!(b.len(), 15);
        let (mut v, mut g) = (vec![0.0; 15], vec![[0.0; 2]; 15]);
        let (mut p, mut m) = (vec![0.0; 15], vec![0.0; 15]);
        let x = [0.3, 0.2];
        b.eval_with_gradient(x, &mut v, &mut g);
        for d in 0..2 {
            let mut xp = x;
            let mut xm = x;
            xp[d] += 1e-6;
            xm[d] -= 1e-6;
            b.eval(xp, &mut p);
            b.eval(xm, &mut m);
            for k in 0..15 {
                assert!((g[k][d] - (p[k] - m[k]) / 2e-6).abs() < 1e-8);
            }
        }
    }

    #[test]
    fn dense_solve_with_pivoting() {
        let mut a = vec![0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 2.0, 0.0, 3.0];
        let orig = a.clone();
        let x = [1.0, -2.0, 0.5];
        let mut b: Vec<f64> = (0..3)
            .map(|i| (0..3).map(|j| orig[i * 3 + j] * x[j]).sum())
            .collect();
        assert!(solve_dense(&mut a, 3, &mut b, 1));
        for i in 0..3 {
            assert!((b[i] - x[i]).abs() < 1e-14);
        }
        let mut singular = vec![1.0, 2.0, 2.0, 4.0];
        assert!(!solve_dense(&mut singular, 2, &mut [1.0, 1.0], 1));
    }
}
