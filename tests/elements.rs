//! Per-element properties of the SDG solution: linear momentum balance against the target
//! fluxes, non-negative numerical dissipation equal to the element's energy balance, and
//! dissipation that falls under refinement.

mod common;

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
        interface: None,
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
