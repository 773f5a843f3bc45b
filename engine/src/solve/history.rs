//! What each accepted patch adds to the bookkeeping: energy sums, snapshot slices, and the
//! history rows that integrate over the whole front.

use std::sync::atomic::Ordering;

use sdg_mesh::TriangleId;
use sdg_solver::basis::Basis;
use sdg_solver::element::{FrontSolution, Geometry, evaluate};
use sdg_solver::norms::{FrontEnergy, front_energy};
use sdg_solver::patch::PatchReport;
use sdg_solver::system::{MAX_FIELDS, System};
use sdg_solver::{Material, Plane};

use super::book::Book;
use super::context::{Solve, initial_state};
use crate::frontier::Frontier;
use crate::output::snapshot::PointValues;
use crate::output::table;

impl Solve<'_> {
    /// Adds a solved patch to the totals.
    pub(crate) fn add_patch(&self, book: &mut Book, report: &PatchReport) {
        book.patches += 1;
        book.timings.assembly_s += report.assembly_s;
        book.timings.solve_s += report.solve_s;
        book.timings.evaluation_s += report.evaluation_s;
        book.elements += report.elements as u64;
        book.dofs += report.dofs as u64;
        book.totals.accumulate(report);
        if report.newton_iterations > 0 {
            book.nonlinear_patches += 1;
            book.newton_iterations += report.newton_iterations as u64;
            book.newton_max = book.newton_max.max(report.newton_iterations);
        }
        book.energy_max = book
            .energy_max
            .max(book.initial_energy + book.totals.boundary_work);
        self.energy_reference
            .store(book.energy_max.to_bits(), Ordering::Relaxed);
    }

    /// Cuts the elements under `triangles`, just solved, by the snapshot planes (not in a run
    /// that writes no files, [`Solve::writes`]).
    pub(crate) fn add_to_snapshots(
        &self,
        book: &mut Book,
        solution: &FrontSolution,
        triangles: &[TriangleId],
    ) {
        if !self.writes() {
            return;
        }
        for &t in triangles {
            if solution.load(t as usize, &mut book.geometry, &mut book.coefficients) {
                let (phi, values, geometry, coefficients) = (
                    &mut book.phi,
                    &mut book.values,
                    &book.geometry,
                    &book.coefficients,
                );
                book.snapshots.add_element(&geometry.vertices(), |x| {
                    point_values(
                        &self.problem.material,
                        (&self.problem.system, &self.basis),
                        geometry,
                        coefficients,
                        x,
                        phi,
                        values,
                    )
                });
            }
        }
    }

    /// Appends a `history.csv` row for the current front, unless the last row is of the same
    /// front time and patch count: the front must not move meanwhile.
    pub(crate) fn history_row(&self, state: &Frontier, book: &mut Book) {
        let time = self
            .problem
            .loaded
            .config
            .time
            .clock(state.front.min_time());
        // The same front and books as the last row (the end's milestone and the final row):
        // the row would repeat it.
        if repeats_last_row(&book.history, time, book.patches) {
            return;
        }
        let system = &self.problem.system;
        let e = front_energy(
            &state.mesh,
            &state.front,
            &state.solution,
            &self.basis,
            system,
            self.threads,
            |x| initial_state(self.problem, self.initial, x),
        );
        let rho = self.problem.material.density();
        let row = history_line(
            time,
            book.patches,
            &e,
            &book.totals,
            book.initial_energy,
            rho,
        );
        book.history.push_str(&row);
        // Progress for batch jobs, which have no progress bar: one line per history row.
        tracing::info!(
            front_min_time_s = time,
            patches = book.patches,
            rejected = book.rejected,
            vertices = state.mesh.vertices().len(),
            crack_crossings = book.crossings.len(),
            "progress"
        );
    }
}

/// The header row of `history.csv`.
pub(crate) fn history_header() -> String {
    table::line([
        "time_s",
        "patches",
        "front_energy_j",
        "kinetic_j",
        "strain_j",
        "boundary_work_j",
        "dissipation_j",
        "interface_work_j",
        "friction_dissipation_j",
        "fracture_energy_j",
        "balance_residual_j",
    ])
}

/// True when a `history.csv` row at `time` (s) after `patches` patches would repeat the last
/// row of `history`: the same front and books.
pub(crate) fn repeats_last_row(history: &str, time: f64, patches: u64) -> bool {
    let key = format!("{time:e},{patches},");
    let last = history.trim_end().lines().next_back().unwrap_or("");
    last.starts_with(&key)
}

/// The `history.csv` row at `time` (s, the config's clock) after `patches` patches, with the
/// energy `e` on the front, the accounts `totals` so far and the `initial` energy (scaled
/// units, made J/m by the density `rho`, kg/m^3).
pub(crate) fn history_line(
    time: f64,
    patches: u64,
    e: &FrontEnergy,
    totals: &PatchReport,
    initial: f64,
    rho: f64,
) -> String {
    let balance =
        initial + totals.boundary_work - e.total - totals.dissipation - totals.interface_work;
    let j = |v: f64| format!("{:e}", rho * v);
    table::line([
        format!("{time:e}"),
        patches.to_string(),
        j(e.total),
        j(e.kinetic),
        j(e.strain),
        j(totals.boundary_work),
        j(totals.dissipation),
        j(totals.interface_work),
        j(totals.friction_dissipation),
        j(totals.fracture_work),
        j(balance),
    ])
}

/// Physical field values at the scaled point `x` of an element of `system` on `basis`, for
/// snapshots; `phi` and `values` are scratch of the basis length and the element width.
pub(crate) fn point_values(
    material: &Material,
    (system, basis): (&System, &Basis),
    geometry: &Geometry,
    coefficients: &[f64],
    x: [f64; 3],
    phi: &mut [f64],
    values: &mut [f64],
) -> PointValues {
    evaluate(basis, geometry, coefficients, x, phi, values);
    let fields = system.fields();
    let mut q = [0.0; MAX_FIELDS];
    q[..fields].copy_from_slice(&values[..fields]);
    let strain_energy_density =
        material.density() * (system.energy_density(&q) - system.kinetic_density(&q));
    let p = system.to_physical(&q);
    let u = &values[fields..];
    match material.plane() {
        Plane::Antiplane => PointValues {
            velocity: [0.0, 0.0, p[0]],
            stress: [0.0, 0.0, 0.0, 0.0, p[2], p[1]],
            displacement: [0.0, 0.0, u[0]],
            strain_energy_density,
        },
        plane => {
            let szz = if plane == Plane::Strain {
                material.poisson() * (p[2] + p[3])
            } else {
                0.0
            };
            PointValues {
                velocity: [p[0], p[1], 0.0],
                stress: [p[2], p[3], szz, p[4], 0.0, 0.0],
                displacement: [u[0], u[1], 0.0],
                strain_energy_density,
            }
        }
    }
}
