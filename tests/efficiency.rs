//! The efficiency of adaptivity on the shipped `configs/adaptive_pulse.toml`: the adaptive run
//! is at least as accurate as the uniform run whose edges are the adaptive run's smallest edge,
//! with at least five times fewer patches.

mod common;

use common::{shipped, solve};

#[test]
fn adaptive_pulse_beats_the_uniform_mesh_of_its_smallest_edge_with_five_times_fewer_patches() {
    let (a, _d) = solve(
        &shipped("adaptive_pulse.toml", &["output.snapshot_times=[]"]),
        2,
        true,
    );
    // The coarse 2 mm grid divided by 8: legs of 0.25 mm, the adaptive run's smallest edge.
    let uniform = shipped(
        "adaptive_pulse.toml",
        &[
            "output.snapshot_times=[]",
            "adapt.enabled=false",
            "mesh.nx=160",
            "mesh.ny=40",
        ],
    );
    let (u, _e) = solve(&uniform, 2, true);
    let (ea, eu) = (a.error.unwrap(), u.error.unwrap());
    eprintln!(
        "adaptive: {} patches, edges {:e} to {:e}, {} refinements, {} coarsenings, error {ea:?}; \
         uniform: {} patches, edges {:e} to {:e}, error {eu:?}",
        a.patches,
        a.min_edge,
        a.max_edge,
        a.refinements,
        a.coarsenings,
        u.patches,
        u.min_edge,
        u.max_edge
    );
    assert!((u.min_edge - a.min_edge).abs() < 1e-9 * a.min_edge);
    assert!(ea.velocity_l2_rel <= eu.velocity_l2_rel, "{ea:?} vs {eu:?}");
    assert!(ea.stress_l2_rel <= eu.stress_l2_rel, "{ea:?} vs {eu:?}");
    assert!(u.patches >= 5 * a.patches, "{} vs {}", a.patches, u.patches);
    assert!(a.energy.balance_residual_rel.abs() < 1e-8);
}
