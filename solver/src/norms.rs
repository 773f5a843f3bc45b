//! Norms of the solution on a flat front, against an exact solution.

use sdg_mesh::{Front, Mesh};

use crate::basis::Basis;
use crate::element::{FrontSolution, Geometry, combine, evaluate};
use crate::exact::PlaneWave;
use crate::patch::tables::FaceTables;
use crate::quadrature;
use crate::system::System;

/// Relative L2 errors on a flat front at time `t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceErrors {
    /// `||v - v_exact|| / ||v_exact||`.
    pub velocity: f64,
    /// `||sigma - sigma_exact|| / ||sigma_exact||` (Frobenius norm of the stored components).
    pub stress: f64,
}

/// Relative L2 errors of velocity and stress over the domain on the flat front at time `t` (s):
/// every front triangle is the top face of its element, evaluated there with a rule exact to
/// degree `2 p + 4`. Triangles that still carry initial data are skipped (none at the end time).
pub fn slice_errors(
    mesh: &Mesh,
    front: &FrontSolution,
    basis: &Basis,
    system: &System,
    t: f64,
    exact: &PlaneWave,
) -> SliceErrors {
    let rule = quadrature::triangle(2 * basis.degree() + 4);
    let mut phi = vec![0.0; basis.len()];
    let mut values = vec![0.0; front.width()];
    let nv = system.displacement_components();
    let fields = system.fields();
    let (mut ev, mut nvel, mut es, mut ns) = (0.0, 0.0, 0.0, 0.0);
    let mut geometry = Geometry::default();
    let mut coefficients = vec![0.0; basis.len() * front.width()];
    for (tri, corners) in mesh.triangles().iter().enumerate() {
        if !front.load(tri, &mut geometry, &mut coefficients) {
            continue;
        }
        let p = corners.map(|v| mesh.vertex(v));
        let area2 =
            (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
        for (xi, &w) in rule.points.iter().zip(&rule.weights) {
            let x =
                [0, 1].map(|i| p[0][i] + xi[0] * (p[1][i] - p[0][i]) + xi[1] * (p[2][i] - p[0][i]));
            let wa = w * area2.abs();
            evaluate(
                basis,
                &geometry,
                &coefficients,
                [x[0], x[1], system.c_ref() * t],
                &mut phi,
                &mut values,
            );
            let mut q = [0.0; crate::system::MAX_FIELDS];
            q[..fields].copy_from_slice(&values[..fields]);
            let q = system.to_physical(&q);
            let e = exact.state(x, t);
            for c in 0..fields {
                let (d, r) = ((q[c] - e[c]).powi(2), e[c].powi(2));
                if c < nv {
                    ev += wa * d;
                    nvel += wa * r;
                } else {
                    es += wa * d;
                    ns += wa * r;
                }
            }
        }
    }
    SliceErrors {
        velocity: (ev / nvel).sqrt(),
        stress: (es / ns).sqrt(),
    }
}

/// Energy on the front (scaled units: physical = density times these), split as
/// `total = kinetic + strain + flux`: on a front facet `t = tau(x)` the energy crossing it is
/// `int (e - grad tau . (energy flux)) dx dy`; `flux` is the second part, zero on a flat front.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrontEnergy {
    /// `int |v|^2 / 2`.
    pub kinetic: f64,
    /// `int sigma : S sigma / 2`.
    pub strain: f64,
    /// The energy-flux part of a non-flat front.
    pub flux: f64,
    /// The sum.
    pub total: f64,
}

/// Energy on `front` (vertex times): every triangle's facet carries the solution
/// of the element under it, or the initial state `initial(x)` (scaled) if none. A facet's
/// energy is the one the patch solver recorded for it (the top face of its element, see
/// [`FrontSolution::store`]) or, where none is recorded (initial data, bisection children,
/// coarsened parents), computed here with the patch solver's face rule (degree `2 p + 2`, so
/// that energies of initial data match the solver's inflow energies exactly; where the facet is
/// a face of its element, the basis values come from the solver's tables on the reference
/// faces) and recorded. The facets missing an energy are computed on `threads` threads; the
/// facets' energies are summed in triangle order on one: the result is the same for any
/// `threads`.
pub fn front_energy(
    mesh: &Mesh,
    times: &Front,
    front: &FrontSolution,
    basis: &Basis,
    system: &System,
    threads: usize,
    initial: impl Fn([f64; 2]) -> crate::system::State + Sync,
) -> FrontEnergy {
    let triangles = mesh.triangles().len();
    let missing: Vec<usize> = (0..triangles)
        .filter(|&t| front.energy(t).is_none())
        .collect();
    if !missing.is_empty() {
        let rule = quadrature::triangle(2 * basis.degree() + 2);
        let tables = FaceTables::new(basis, &rule);
        let chunk = missing.len().div_ceil(threads.max(1)).max(1);
        let facets = Facets {
            mesh,
            times,
            front,
            basis,
            system,
            rule: &rule,
            tables: &tables,
        };
        let fill = |part: &[usize]| {
            let mut scratch = Scratch {
                geometry: Geometry::default(),
                coefficients: vec![0.0; basis.len() * front.width()],
                phi: vec![0.0; basis.len()],
                values: vec![0.0; front.width()],
            };
            for &tri in part {
                front.set_energy(tri, facets.energy(tri, &mut scratch, &initial));
            }
        };
        if threads <= 1 || missing.len() <= chunk {
            fill(&missing);
        } else {
            std::thread::scope(|s| {
                for part in missing.chunks(chunk) {
                    let fill = &fill;
                    s.spawn(move || fill(part));
                }
            });
        }
    }
    let mut e = FrontEnergy::default();
    for t in 0..triangles {
        let [kinetic, strain, flux] = front.energy(t).expect("every facet's energy is known");
        e.kinetic += kinetic;
        e.strain += strain;
        e.flux += flux;
    }
    e.total = e.kinetic + e.strain + e.flux;
    e
}

/// What [`front_energy`] integrates over the front's facets.
struct Facets<'a> {
    mesh: &'a Mesh,
    times: &'a Front,
    front: &'a FrontSolution,
    basis: &'a Basis,
    system: &'a System,
    rule: &'a quadrature::Rule<2>,
    tables: &'a FaceTables,
}

/// Element and basis scratch of [`Facets::energy`].
struct Scratch {
    geometry: Geometry,
    coefficients: Vec<f64>,
    phi: Vec<f64>,
    values: Vec<f64>,
}

impl Facets<'_> {
    /// Energy on the facet of triangle `tri` as `[kinetic, strain, flux]` by quadrature, with
    /// `initial(x)` (scaled) on a facet without an element.
    fn energy(
        &self,
        tri: usize,
        scratch: &mut Scratch,
        initial: &impl Fn([f64; 2]) -> crate::system::State,
    ) -> [f64; 3] {
        let Self {
            mesh,
            times,
            front,
            basis,
            system,
            rule,
            tables,
        } = *self;
        let Scratch {
            geometry,
            coefficients,
            phi,
            values,
        } = scratch;
        let fields = system.fields();
        let ax = system.a_n([1.0, 0.0, 0.0]);
        let ay = system.a_n([0.0, 1.0, 0.0]);
        let corners = mesh.triangles()[tri];
        let solved = front.load(tri, geometry, coefficients);
        let p = corners.map(|v| mesh.vertex(v));
        let tau = corners.map(|v| system.c_ref() * times.time(v));
        let grad = sdg_mesh::geometry::linear_gradient(p, tau);
        let area2 =
            (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
        // The facet is a face of its element (tabulated basis values), unless the triangle is a
        // split child still lying on its parent's element.
        let face = solved
            .then(|| {
                let facet = [0, 1, 2].map(|i| [p[i][0], p[i][1], tau[i]]);
                FaceTables::corners_in(facet, &geometry.vertices())
            })
            .flatten();
        let mut energy = [0.0; 3];
        for (point, (xi, &w)) in rule.points.iter().zip(&rule.weights).enumerate() {
            let x =
                [0, 1].map(|i| p[0][i] + xi[0] * (p[1][i] - p[0][i]) + xi[1] * (p[2][i] - p[0][i]));
            let t = tau[0] + xi[0] * (tau[1] - tau[0]) + xi[1] * (tau[2] - tau[0]);
            let q = if solved {
                match face {
                    Some(face) => combine(tables.at(face, point), coefficients, values),
                    None => evaluate(basis, geometry, coefficients, [x[0], x[1], t], phi, values),
                }
                let mut q = [0.0; crate::system::MAX_FIELDS];
                q[..fields].copy_from_slice(&values[..fields]);
                q
            } else {
                initial(x)
            };
            let wa = w * area2.abs();
            let kinetic = system.kinetic_density(&q);
            let total = system.energy_density(&q);
            let flux = -0.5
                * (grad[0] * system.dot(&q, &system.apply(&ax, &q))
                    + grad[1] * system.dot(&q, &system.apply(&ay, &q)));
            energy[0] += wa * kinetic;
            energy[1] += wa * (total - kinetic);
            energy[2] += wa * flux;
        }
        energy
    }
}

/// Energy (scaled units) of the initial state `initial(x)` on the flat facet of the triangle
/// with `corners` (m), with the patch solver's face rule for order `degree`: what the solver
/// takes in as inflow there.
pub fn initial_energy(
    system: &System,
    degree: usize,
    corners: [[f64; 2]; 3],
    initial: impl Fn([f64; 2]) -> crate::system::State,
) -> f64 {
    let rule = quadrature::triangle(2 * degree + 2);
    let p = corners;
    let area2 =
        (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
    rule.points
        .iter()
        .zip(&rule.weights)
        .map(|(xi, &w)| {
            let x =
                [0, 1].map(|i| p[0][i] + xi[0] * (p[1][i] - p[0][i]) + xi[1] * (p[2][i] - p[0][i]));
            w * area2.abs() * system.energy_density(&initial(x))
        })
        .sum()
}
