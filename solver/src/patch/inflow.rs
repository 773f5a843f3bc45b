//! What flows into a patch from below: the initial data, or copies of the elements under the
//! front, with their values at the inflow faces' quadrature points.

use sdg_mesh::TriangleId;

use super::slot::{Face, FaceQuadrature, Slot, face_points};
use super::tables::FaceTables;
use crate::basis::Basis;
use crate::element::{FrontSolution, Geometry};
use crate::exact::PlaneWave;
use crate::quadrature::Rule;
use crate::spacetime::SpacePoint;
use crate::system::{MAX_FIELDS, State, System};

/// Initial data: the state at `t = 0`, a plane wave or rest.
#[derive(Clone, Copy, Debug)]
pub enum Initial<'a> {
    /// Zero velocity, stress and displacement.
    Rest,
    /// The exact solution at `t = 0`.
    Wave(&'a PlaneWave),
}

/// Copies of the elements below a patch's elements, taken when the patch starts.
#[derive(Debug)]
pub(super) struct Inflow {
    pub(super) solved: Vec<bool>,
    pub(super) geometry: Vec<Geometry>,
    pub(super) coefficients: Vec<f64>,
    /// Values per element.
    pub(super) size: usize,
}

impl Inflow {
    /// Copies the elements under `triangles` from `solution`: source `i` is `triangles[i]`.
    pub(super) fn gather(&mut self, triangles: &[TriangleId], solution: &FrontSolution) {
        for (i, &t) in triangles.iter().enumerate() {
            let size = self.size;
            self.solved[i] = solution.load(
                t as usize,
                &mut self.geometry[i],
                &mut self.coefficients[i * size..(i + 1) * size],
            );
        }
    }

    /// The element of source `i`, or `None` for initial data.
    pub(super) fn below(&self, i: usize) -> Option<(&Geometry, &[f64])> {
        let size = self.size;
        self.solved[i].then(|| {
            (
                &self.geometry[i],
                &self.coefficients[i * size..(i + 1) * size],
            )
        })
    }
}

/// The element below an inflow face: its basis values at the face's rule points (`n` per
/// point) and its coefficients.
type Below<'a> = (&'a [f64], &'a [f64]);

/// The quadrature of an inflow face (`exact` below a solved element, whose trace is a
/// polynomial, `data` on initial data) and, below a solved element, its basis values at the
/// rule's points of `face` (`points x n`, from the tables, or evaluated into `scratch` if its
/// vertices do not match) with its coefficients.
pub(super) fn inflow_values<'a, 'q: 'a>(
    [exact, data]: [&'q FaceQuadrature; 2],
    basis: &Basis,
    scratch: &'a mut [f64],
    slot: &Slot,
    face: Face,
    below: Option<(&Geometry, &'a [f64])>,
) -> (&'q FaceQuadrature, Option<Below<'a>>) {
    let Some((geometry, coefficients)) = below else {
        return (data, None);
    };
    let vertices = geometry.vertices();
    let values = other_values(
        &exact.tables,
        basis,
        scratch,
        &exact.rule,
        (slot, face),
        geometry,
        &vertices,
    );
    (exact, Some((values, coefficients)))
}

/// The basis values at the rule points of `slot`'s `face` of the element with `geometry` and
/// `vertices` that shares the face: a table if the face's corners are among `vertices`, else
/// evaluated into `scratch`.
pub(super) fn other_values<'a>(
    tables: &'a FaceTables,
    basis: &Basis,
    scratch: &'a mut [f64],
    rule: &Rule<2>,
    (slot, face): (&Slot, Face),
    geometry: &Geometry,
    vertices: &[SpacePoint; 4],
) -> &'a [f64] {
    match FaceTables::corners_in(face.0.map(|c| slot.vertices[c]), vertices) {
        Some(t) => tables.values(t),
        None => {
            let n = basis.len();
            let mut q = 0;
            face_points(rule, &slot.vertices, face, |x, _, _| {
                basis.eval(geometry.to_reference(x), &mut scratch[q * n..(q + 1) * n]);
                q += 1;
            });
            scratch
        }
    }
}

/// `sum_k phi_k c_k` for coefficients of `width` values per basis function: value `index`.
fn value_at(phi: &[f64], coefficients: &[f64], index: usize) -> f64 {
    let width = coefficients.len() / phi.len();
    phi.iter()
        .zip(coefficients.chunks_exact(width))
        .map(|(p, c)| p * c[index])
        .sum()
}

/// The state below the front at `x`: from the element below (its basis values at `x` and
/// coefficients), or the initial data.
pub(super) fn inflow_state(
    system: &System,
    under: Option<(&[f64], &[f64])>,
    initial: Initial,
    x: SpacePoint,
) -> State {
    match (under, initial) {
        (Some((phi, coefficients)), _) => std::array::from_fn(|k| {
            if k < system.fields() {
                value_at(phi, coefficients, k)
            } else {
                0.0
            }
        }),
        (None, Initial::Rest) => [0.0; MAX_FIELDS],
        (None, Initial::Wave(w)) => system.to_scaled(&w.state([x[0], x[1]], 0.0)),
    }
}

/// The displacement (m) below the front at `x`, like [`inflow_state`].
pub(super) fn inflow_displacement(
    system: &System,
    under: Option<(&[f64], &[f64])>,
    initial: Initial,
    x: SpacePoint,
) -> [f64; 2] {
    match (under, initial) {
        (Some((phi, coefficients)), _) => {
            let f = system.fields();
            std::array::from_fn(|d| {
                if d < system.displacement_components() {
                    value_at(phi, coefficients, f + d)
                } else {
                    0.0
                }
            })
        }
        (None, Initial::Rest) => [0.0; 2],
        (None, Initial::Wave(w)) => w.displacement([x[0], x[1]], 0.0),
    }
}
