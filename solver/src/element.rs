//! Spacetime elements: affine tetrahedra in scaled coordinates `(x, y, tau)`, and the solution on
//! the elements whose top faces form the current front.

use parking_lot::Mutex;

use crate::basis::Basis;
use crate::face::FaceState;
pub use crate::spacetime::SpacePoint;

/// Values in [`Geometry::to_values`].
pub const GEOMETRY_VALUES: usize = 22;

/// The affine map `X = P0 + J xi` of a tetrahedron from the reference tetrahedron.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Geometry {
    origin: SpacePoint,
    jacobian: [[f64; 3]; 3],
    inverse: [[f64; 3]; 3],
    det: f64,
}

impl Geometry {
    /// The map sending reference vertices `0, e1, e2, e3` to `vertices`. The tetrahedron must
    /// be non-degenerate.
    pub fn new(vertices: &[SpacePoint; 4]) -> Self {
        let p0 = vertices[0];
        let mut j = [[0.0; 3]; 3];
        for (col, v) in vertices[1..].iter().enumerate() {
            for row in 0..3 {
                j[row][col] = v[row] - p0[row];
            }
        }
        let cof = |r: usize, c: usize| {
            let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
            let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
            j[r1][c1] * j[r2][c2] - j[r1][c2] * j[r2][c1]
        };
        let det = j[0][0] * cof(0, 0) + j[0][1] * cof(0, 1) + j[0][2] * cof(0, 2);
        let mut inverse = [[0.0; 3]; 3];
        for (r, row) in inverse.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                *x = cof(c, r) / det;
            }
        }
        Self {
            origin: p0,
            jacobian: j,
            inverse,
            det,
        }
    }

    /// Reference coordinates of the point `x`.
    pub fn to_reference(&self, x: SpacePoint) -> [f64; 3] {
        let d = [0, 1, 2].map(|i| x[i] - self.origin[i]);
        self.inverse
            .map(|row| row[0] * d[0] + row[1] * d[1] + row[2] * d[2])
    }

    /// The point with reference coordinates `xi`.
    pub fn from_reference(&self, xi: [f64; 3]) -> SpacePoint {
        let mut x = self.origin;
        for (i, xi_i) in x.iter_mut().enumerate() {
            *xi_i += (0..3).map(|c| self.jacobian[i][c] * xi[c]).sum::<f64>();
        }
        x
    }

    /// The four vertices: images of `0, e1, e2, e3`.
    pub fn vertices(&self) -> [SpacePoint; 4] {
        [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
            .map(|xi| self.from_reference(xi))
    }

    /// `d xi_r / d X_mu` as `inverse[r][mu]`.
    pub fn inverse(&self) -> &[[f64; 3]; 3] {
        &self.inverse
    }

    /// Determinant of `J`: six times the signed volume.
    pub fn det(&self) -> f64 {
        self.det
    }

    /// The map's stored values (origin, Jacobian and inverse by rows, determinant), for sending
    /// it to another process bit for bit; [`Self::from_values`] reads them back.
    pub fn to_values(&self) -> [f64; GEOMETRY_VALUES] {
        let mut out = [0.0; GEOMETRY_VALUES];
        let rows = self.jacobian.iter().chain(&self.inverse).flatten();
        for (o, &x) in out.iter_mut().zip(self.origin.iter().chain(rows)) {
            *o = x;
        }
        out[GEOMETRY_VALUES - 1] = self.det;
        out
    }

    /// The map whose [`Self::to_values`] are `values`, bitwise.
    pub fn from_values(values: &[f64; GEOMETRY_VALUES]) -> Self {
        let matrix =
            |at: usize| std::array::from_fn(|r| std::array::from_fn(|c| values[at + 3 * r + c]));
        Self {
            origin: [values[0], values[1], values[2]],
            jacobian: matrix(3),
            inverse: matrix(12),
            det: values[21],
        }
    }
}

/// The solution on the elements under the front: per front triangle, the element whose top face
/// it is, or nothing while the triangle still carries initial data.
///
/// Coefficients are stored per basis function, `width` values each (the scaled fields, then the
/// displacement components), in the orthonormal basis of the element's reference tetrahedron.
/// Each triangle's entry has its own lock, so threads whose tents own disjoint triangles work on
/// one `FrontSolution` without waiting for each other.
///
/// It also holds the interface state on the front: per mesh edge, the last interface face solved
/// over it (see [`crate::face`]), or nothing while the edge carries the initial state (zero
/// separation and slip). Only the tent at one of an edge's ends touches its entry.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub struct FrontSolution {
    basis_len: usize,
    width: usize,
    cells: Vec<Mutex<Cell>>,
    faces: Vec<Mutex<Option<Box<FaceState>>>>,
}

/// The element under one front triangle.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
struct Cell {
    solved: bool,
    geometry: Geometry,
    coefficients: Box<[f64]>,
    /// The energy on the triangle's facet split as `[kinetic, strain, flux]` (see
    /// `norms::FrontEnergy`), once computed; `None` after the facet or its element changed
    /// without it.
    energy: Option<[f64; 3]>,
}

impl Clone for FrontSolution {
    fn clone(&self) -> Self {
        Self {
            basis_len: self.basis_len,
            width: self.width,
            cells: self
                .cells
                .iter()
                .map(|c| Mutex::new(c.lock().clone()))
                .collect(),
            faces: self
                .faces
                .iter()
                .map(|f| Mutex::new(f.lock().clone()))
                .collect(),
        }
    }
}

impl FrontSolution {
    /// Initial data everywhere on a front of `triangles` triangles.
    pub fn new(triangles: usize, basis_len: usize, width: usize) -> Self {
        let cell = Cell {
            solved: false,
            geometry: Geometry::default(),
            coefficients: vec![0.0; basis_len * width].into_boxed_slice(),
            energy: None,
        };
        Self {
            basis_len,
            width,
            cells: (0..triangles).map(|_| Mutex::new(cell.clone())).collect(),
            faces: Vec::new(),
        }
    }

    /// Adds room for the interface state of `edges` mesh edges, all in the initial state. Needed
    /// before solving patches with nonlinear interface faces.
    pub fn with_edges(mut self, edges: usize) -> Self {
        self.faces = (0..edges).map(|_| Mutex::new(None)).collect();
        self
    }

    /// Number of edges with room for interface state.
    pub fn edges(&self) -> usize {
        self.faces.len()
    }

    /// The interface face over edge `e`, or `None` in the initial state.
    pub fn face(&self, e: usize) -> Option<FaceState> {
        self.faces[e].lock().as_deref().copied()
    }

    /// Replaces the interface face over edge `e`.
    pub fn store_face(&self, e: usize, face: &FaceState) {
        let mut slot = self.faces[e].lock();
        match slot.as_deref_mut() {
            Some(old) => *old = *face,
            None => *slot = Some(Box::new(*face)),
        }
    }

    /// Follows a refinement of the mesh, now of `edges` edges: each split edge's appended half
    /// lies on the same face as the half that kept its id (exact restriction, no projection).
    pub fn follow_splits(&mut self, edges: usize, splits: &[sdg_mesh::Split]) {
        if self.faces.is_empty() {
            return;
        }
        self.faces.resize_with(edges, || Mutex::new(None));
        for split in splits {
            let [kept, new] = split.edges.map(|e| e as usize);
            let face = self.faces[kept].get_mut().clone();
            *self.faces[new].get_mut() = face;
        }
    }

    /// Values per basis function.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Number of front triangles.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// True for a front of no triangles.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// Appends a front triangle that lies on the top face of the element under triangle `from`
    /// (a child of a bisection; `from` is now the other child): it gets the same element, no
    /// projection. Returns its index. The energies on both facets are no longer known.
    pub fn push_copy(&mut self, from: usize) -> usize {
        let cell = self.cells[from].get_mut();
        cell.energy = None;
        let cell = cell.clone();
        self.cells.push(Mutex::new(cell));
        self.cells.len() - 1
    }

    /// Follows a coarsening of the mesh: drops the removed children's and edges' entries,
    /// renumbering like the mesh. The parents keep their entries until the coarsening patch is committed.
    pub fn remove(&mut self, merge: &sdg_mesh::Merge) {
        merge.apply_to_triangles(&mut self.cells);
        if !self.faces.is_empty() {
            merge.apply_to_edges(&mut self.faces);
        }
    }

    /// True once an element lies under triangle `t` (false while it carries initial data).
    pub fn is_solved(&self, t: usize) -> bool {
        self.cells[t].lock().solved
    }

    /// Copies the element under triangle `t` into `geometry` and `coefficients` (basis length
    /// times width values); returns false, copying nothing, while `t` carries initial data.
    pub fn load(&self, t: usize, geometry: &mut Geometry, coefficients: &mut [f64]) -> bool {
        let cell = self.cells[t].lock();
        if cell.solved {
            *geometry = cell.geometry;
            coefficients.copy_from_slice(&cell.coefficients);
        }
        cell.solved
    }

    /// Replaces the element under triangle `t`, whose top face is the triangle's facet, with
    /// the energy on that facet as `[kinetic, strain, flux]` if known.
    pub fn store(
        &self,
        t: usize,
        geometry: &Geometry,
        coefficients: &[f64],
        energy: Option<[f64; 3]>,
    ) {
        let mut cell = self.cells[t].lock();
        cell.solved = true;
        cell.geometry = *geometry;
        cell.coefficients.copy_from_slice(coefficients);
        cell.energy = energy;
    }

    /// The energy on triangle `t`'s facet as `[kinetic, strain, flux]`, if known.
    pub fn energy(&self, t: usize) -> Option<[f64; 3]> {
        self.cells[t].lock().energy
    }

    /// Records the energy on triangle `t`'s facet, computed for its current element and facet.
    pub fn set_energy(&self, t: usize, energy: [f64; 3]) {
        self.cells[t].lock().energy = Some(energy);
    }

    /// Calls `f` with the element under triangle `t`, or `None` while it carries initial data.
    pub fn with_element<R>(&self, t: usize, f: impl FnOnce(Option<(&Geometry, &[f64])>) -> R) -> R {
        let cell = self.cells[t].lock();
        f(cell
            .solved
            .then_some((&cell.geometry, &cell.coefficients[..])))
    }

    /// Number of basis functions per element.
    pub fn basis_len(&self) -> usize {
        self.basis_len
    }
}

/// Evaluates an element's `width` values at the point `x` into `out`; `phi` is scratch of the
/// basis length.
pub fn evaluate(
    basis: &Basis,
    geometry: &Geometry,
    coefficients: &[f64],
    x: SpacePoint,
    phi: &mut [f64],
    out: &mut [f64],
) {
    basis.eval(geometry.to_reference(x), phi);
    combine(phi, coefficients, out);
}

/// The `width = out.len()` values `sum_k phi[k] coefficients[k * width..]` of an element whose
/// basis functions take the values `phi` at a point, into `out`.
pub fn combine(phi: &[f64], coefficients: &[f64], out: &mut [f64]) {
    let width = out.len();
    out.fill(0.0);
    for (k, &p) in phi.iter().enumerate() {
        for (o, c) in out
            .iter_mut()
            .zip(&coefficients[k * width..(k + 1) * width])
        {
            *o += p * c;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_round_trip() {
        let g = Geometry::new(&[
            [0.1, 0.2, 0.0],
            [1.0, 0.3, 0.1],
            [0.2, 1.1, 0.2],
            [0.1, 0.2, 0.7],
        ]);
        let xi = [0.2, 0.3, 0.1];
        let back = g.to_reference(g.from_reference(xi));
        assert!((0..3).all(|i| (back[i] - xi[i]).abs() < 1e-14));
        assert!(g.det() > 0.0);
        let values = g.to_values();
        assert_eq!(values[21], g.det());
        assert_eq!(values[..3], [0.1, 0.2, 0.0]);
        assert_eq!(Geometry::from_values(&values), g);
    }
}
