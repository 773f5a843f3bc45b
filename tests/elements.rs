//! Per-element properties of the SDG solution: linear momentum balance against the target
//! fluxes, non-negative numerical dissipation equal to the element's energy balance, and
//! dissipation that falls under refinement.

use crate::common;

use sdg_mesh::{Diagonal, Rectangle};
use sdg_solver::boundary::{Boundary, Condition};
use sdg_solver::exact::{PlaneWave, Profile, Wave};
use sdg_solver::history::History;
use sdg_solver::{Material, Plane};

fn pmma(plane: Plane) -> Material {
    Material::new(3.24e9, 0.35, 1190.0, plane).unwrap()
}

fn square(nx: u32, perturb: f64) -> sdg_mesh::Mesh {
    Rectangle {
        width: 1.0,
        height: 1.0,
        nx,
        ny: nx,
        diagonal: Diagonal::Alternate,
        interfaces: Vec::new(),
        sides: Vec::new(),
        perturb,
        seed: 3,
    }
    .build()
    .unwrap()
}

/// Every boundary kind at once on a perturbed mesh, with a wave in the initial data.
#[test]
fn every_element_balances_momentum_and_dissipates() {
    for plane in [Plane::Strain, Plane::Stress, Plane::Antiplane] {
        let material = pmma(plane);
        let wave = PlaneWave::new(&material, Wave::S, 20.0, 0.5, 1.0, Profile::Sine, 0.0).unwrap();
        let smooth = History::Smooth { ramp: 2e-5 };
        // Tags: left, right, bottom, top.
        let boundary = Boundary::new(
            vec![
                Some(Condition::Traction {
                    value: [1e6, -2e6],
                    history: smooth.clone(),
                }),
                Some(Condition::Velocity {
                    value: [0.5, 0.2],
                    history: History::Linear { ramp: 1e-5 },
                }),
                Some(Condition::Transmitting {
                    incoming: [3e6, 1e6],
                    history: smooth,
                }),
                Some(Condition::Roller),
            ],
            Some(wave.clone()),
        );
        let mut checked = 0;
        let mut worst_momentum: f64 = 0.0;
        common::solve_direct(
            square(6, 0.2),
            &material,
            &boundary,
            Some(&wave),
            2,
            0.16 / material.max_wave_speed(),
            |e| {
                let scale = e.energy_in.abs() + e.energy_out.abs() + e.vertical_work.abs();
                assert!(e.dissipation >= -1e-13 * scale, "{plane:?}: {e:?}");
                assert!(
                    (e.dissipation - e.dissipation_balance).abs() <= 1e-9 * scale,
                    "{plane:?}: {e:?}"
                );
                worst_momentum = worst_momentum.max(e.momentum_residual);
                checked += 1;
            },
        );
        assert!(checked > 400, "{plane:?}: {checked} elements");
        eprintln!("{plane:?}: {checked} elements, worst momentum residual {worst_momentum:.1e}");
        assert!(
            worst_momentum < 1e-10,
            "{plane:?}: momentum residual {worst_momentum}"
        );
    }
}

#[test]
fn dissipation_decreases_under_refinement() {
    let material = pmma(Plane::Strain);
    let wave = PlaneWave::new(&material, Wave::P, 30.0, 1.0, 1.0, Profile::Sine, 0.0).unwrap();
    let boundary = Boundary::new(vec![Some(Condition::Exact); 4], Some(wave.clone()));
    let end = 0.2 / material.c_d();
    let totals: Vec<f64> = [4, 8, 16]
        .into_iter()
        .map(|n| {
            common::solve_direct(
                square(n, 0.0),
                &material,
                &boundary,
                Some(&wave),
                2,
                end,
                |_| {},
            )
            .dissipation
        })
        .collect();
    eprintln!("dissipation for nx = 4, 8, 16: {totals:?}");
    // The dissipation is a squared jump measure: it falls like h^(2p + 1) for smooth solutions.
    assert!(
        totals[0] > 8.0 * totals[1] && totals[1] > 8.0 * totals[2],
        "{totals:?}"
    );
}

/// The coarsening patch that removes a bisection vertex: its two elements balance momentum,
/// dissipate as their energy balance says, and carry the wave as accurately as the tents around.
#[test]
fn coarsening_patch_balances_momentum_and_energy() {
    use sdg_mesh::{Front, Pitcher};
    use sdg_solver::element::{FrontSolution, evaluate};
    use sdg_solver::patch::{Initial, PatchSolver};
    use sdg_solver::system::{MAX_FIELDS, System};

    let material = pmma(Plane::Strain);
    let wave = PlaneWave::new(&material, Wave::P, 30.0, 1.0, 1.0, Profile::Sine, 0.0).unwrap();
    let boundary = Boundary::new(vec![Some(Condition::Exact); 4], Some(wave.clone()));
    let system = System::new(&material);
    let mut mesh = square(6, 0.0);
    // Bisect an interior triangle: its refinement edge is interior, so four children.
    let t = (0..mesh.triangles().len() as u32)
        .find(|&t| {
            let e = mesh.triangle_edges(t)[mesh.refinement_edge(t)];
            !mesh.edges()[e as usize].is_boundary()
        })
        .unwrap();
    let mut splits = Vec::new();
    assert!(mesh.bisect(t, &mut |_, _, _| true, &mut splits));
    assert_eq!(splits.len(), 1, "a compatible pair");
    let m = splits[0].vertex;
    let [a, b] = mesh.coarsenable(m).unwrap();

    let c = system.c_ref();
    // Many tent layers: m is pitched again long before the end.
    let t_end = 1e-3;
    let pitcher = Pitcher::new(&mesh, c, 0.9, t_end)
        .unwrap()
        .for_refinement(&mesh);
    let mut solver = PatchSolver::new(system.clone(), 2, 12);
    let solution = FrontSolution::new(mesh.triangles().len(), solver.basis().len(), solver.width());
    let front = Front::flat(mesh.vertices().len(), 0.0);
    let init = Initial::Wave(&wave);
    let mut tents_at_m = 0;
    let report = loop {
        let v = (0..mesh.vertices().len() as u32)
            .min_by(|&x, &y| front.time(x).total_cmp(&front.time(y)).then(x.cmp(&y)))
            .unwrap();
        if v == m && tents_at_m > 0 {
            // m is the earliest vertex again, below edge ab, and its children are solved.
            assert!(front.time(m) < 0.5 * (front.time(a) + front.time(b)));
            break solver
                .solve_coarsening(&mesh, &front, m, &boundary, init, &solution)
                .unwrap();
        }
        tents_at_m += usize::from(v == m);
        let tent = pitcher.pitch(&mesh, &front, v).unwrap();
        solver
            .solve(&mesh, &front, &tent, &boundary, init, &solution)
            .unwrap();
        solver.commit(&solution);
    };
    assert_eq!(report.elements, 2);
    for r in solver.element_reports() {
        assert!(r.momentum_residual < 1e-12, "{r:?}");
        assert!(r.dissipation >= 0.0);
        let scale = r.energy_in.abs() + r.vertical_work.abs();
        assert!(
            (r.dissipation_balance - r.dissipation).abs() < 1e-10 * scale,
            "{r:?}"
        );
        assert!(r.energy_in > 0.0);
    }

    // The parents' facets carry the wave: compare with the exact state at their centroids, and
    // with the error of the tent elements under the other triangles of the same stars.
    let velocity_error =
        |solution: &FrontSolution, mesh: &sdg_mesh::Mesh, t: usize, time: &dyn Fn(u32) -> f64| {
            let corners = mesh.triangles()[t];
            let x = [0, 1].map(|i| corners.iter().map(|&w| mesh.vertex(w)[i]).sum::<f64>() / 3.0);
            let tau = corners.iter().map(|&w| time(w)).sum::<f64>() / 3.0;
            let mut phi = vec![0.0; solver.basis().len()];
            let mut values = vec![0.0; solver.width()];
            solution.with_element(t, |e| {
                let (geometry, coefficients) = e.expect("solved");
                evaluate(
                    solver.basis(),
                    geometry,
                    coefficients,
                    [x[0], x[1], c * tau],
                    &mut phi,
                    &mut values,
                );
            });
            let mut q = [0.0; MAX_FIELDS];
            q[..system.fields()].copy_from_slice(&values[..system.fields()]);
            let got = system.to_physical(&q);
            let exact = wave.state(x, tau);
            (got[0] - exact[0]).abs().max((got[1] - exact[1]).abs())
        };
    let tents_worst = (0..mesh.triangles().len())
        .map(|t| velocity_error(&solution, &mesh, t, &|w| front.time(w)))
        .fold(0.0, f64::max);
    let merge = mesh.coarsen(m).unwrap();
    let mut cells: Vec<usize> = (0..solution.len()).collect();
    merge.apply_to_triangles(&mut cells);
    let moved = |t: u32| {
        cells
            .iter()
            .position(|&c| c == t as usize)
            .map_or(t, |i| i as u32)
    };
    let coarse = FrontSolution::new(mesh.triangles().len(), solver.basis().len(), solver.width());
    solver.commit_to(&coarse, moved);
    let times = |w: u32| {
        // Vertex ids after the merge: m's id holds the former last vertex.
        let w = match merge.moved_vertex {
            Some((from, to)) if w == to => from,
            _ => w,
        };
        front.time(w)
    };
    let worst = merge
        .halves
        .iter()
        .map(|&(parent, _)| velocity_error(&coarse, &mesh, moved(parent) as usize, &times))
        .fold(0.0, f64::max);
    eprintln!("velocity error at parent centroids {worst:e}, tent elements up to {tents_worst:e}");
    assert!(worst <= tents_worst, "{worst} against {tents_worst}");
}
