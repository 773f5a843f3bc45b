//! The elements of a patch and their faces: corners, inflow and vertical faces, face quadrature.

use sdg_mesh::{EdgeId, Mesh, TagId, TriangleId};

use super::tables::FaceTables;
use crate::element::Geometry;
use crate::quadrature::Rule;
use crate::spacetime::SpacePoint;

/// Per element of the patch being solved.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Slot {
    /// The front triangle the element's top face (`TOP`) becomes.
    pub(super) triangle: TriangleId,
    pub(super) vertices: [SpacePoint; 4],
    pub(super) geometry: Geometry,
    /// Inflow faces, each with the index of the element below it in `Inflow`: one for a tent
    /// element.
    pub(super) inflow: [(Face, usize); 2],
    pub(super) inflow_count: usize,
    /// Vertical faces.
    pub(super) sides: [Vertical; 2],
    pub(super) side_count: usize,
}

/// A vertical face of a patch element.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Vertical {
    pub(super) face: Face,
    /// The patch element across it (none on the domain boundary).
    pub(super) neighbour: Option<usize>,
    /// Tag and id of its space edge.
    pub(super) tag: Option<TagId>,
    pub(super) edge: EdgeId,
    /// On a coarsening patch's face over the restored edge `ab` (then `edge` is the half `ma`):
    /// the other half `mb`.
    pub(super) split: Option<EdgeId>,
    /// Its index among the patch's contact faces.
    pub(super) contact: Option<usize>,
}

/// A face of a tetrahedron: its corners (indices into the element's vertices) and the opposite one.
pub(super) type Face = ([usize; 3], usize);
pub(super) const TOP: Face = ([1, 2, 3], 0);
/// Vertical face over the edge from the tent vertex to corner `a` (vertex 1), then to `b`.
pub(super) const SIDE_A: Face = ([0, 1, 3], 2);
pub(super) const SIDE_B: Face = ([0, 2, 3], 1);

impl Slot {
    pub(super) fn inflows(&self) -> &[(Face, usize)] {
        &self.inflow[..self.inflow_count]
    }

    pub(super) fn sides(&self) -> &[Vertical] {
        &self.sides[..self.side_count]
    }
}

/// A face quadrature rule and the reference tables at its points.
#[derive(Clone, Debug)]
pub(super) struct FaceQuadrature {
    pub(super) rule: Rule<2>,
    pub(super) tables: FaceTables,
}

/// The inflow face of a tent element whose tent vertex is corner `corner` of its triangle, its
/// corners in the triangle's own vertex order: quadrature points on a front triangle are then the
/// same whichever vertex pitches it, so integrals of initial data match
/// [`crate::norms::front_energy`] exactly.
pub(super) fn tent_bottom(corner: usize) -> Face {
    // Tetrahedron vertex k (k < 3) is triangle corner (corner + k) mod 3.
    ([0, 1, 2].map(|k| (k + 3 - corner) % 3), 3)
}

/// A face's first corner, its two edge vectors from there, its outward unit normal and twice
/// its area.
pub(super) fn face_geometry(
    vertices: &[SpacePoint; 4],
    (corners, opposite): Face,
) -> (SpacePoint, [f64; 3], [f64; 3], [f64; 3], f64) {
    let [q0, q1, q2] = corners.map(|i| vertices[i]);
    let e1 = [0, 1, 2].map(|i| q1[i] - q0[i]);
    let e2 = [0, 1, 2].map(|i| q2[i] - q0[i]);
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let away = [0, 1, 2].map(|i| q0[i] - vertices[opposite][i]);
    let sign = if n[0] * away[0] + n[1] * away[1] + n[2] * away[2] < 0.0 {
        -1.0
    } else {
        1.0
    };
    (q0, e1, e2, n.map(|c| sign * c / norm), norm)
}

/// Visits the quadrature points of a face in physical coordinates with physical weights and the
/// outward unit normal.
pub(super) fn face_points(
    rule: &Rule<2>,
    vertices: &[SpacePoint; 4],
    face: Face,
    mut visit: impl FnMut(SpacePoint, f64, [f64; 3]),
) {
    let (q0, e1, e2, n, area2) = face_geometry(vertices, face);
    for (p, &w) in rule.points.iter().zip(&rule.weights) {
        let x = [0, 1, 2].map(|i| q0[i] + p[0] * e1[i] + p[1] * e2[i]);
        visit(x, w * area2, n);
    }
}

/// The two vertical faces of the tent element over triangle `t`, whose tent vertex is its corner
/// `corner`, with the element across each (an index in the star; none on the domain boundary)
/// and its space edge.
pub(super) fn vertical_faces(
    mesh: &Mesh,
    star: &[TriangleId],
    t: TriangleId,
    corner: usize,
) -> [Vertical; 2] {
    [(SIDE_A, 2), (SIDE_B, 1)].map(|(face, opposite_corner)| {
        let e = mesh.triangle_edges(t)[(corner + opposite_corner) % 3];
        let edge = mesh.edges()[e as usize];
        let neighbour = edge
            .triangles
            .iter()
            .flatten()
            .find(|&&u| u != t)
            .map(|&u| {
                star.iter()
                    .position(|&s| s == u)
                    .expect("edge neighbour is in the star")
            });
        Vertical {
            face,
            neighbour,
            tag: edge.tag,
            edge: e,
            split: None,
            contact: None,
        }
    })
}
