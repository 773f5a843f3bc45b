//! The efficiency of adaptivity on the shipped `configs/adaptive_pulse.toml`: the adaptive run
//! is at least as accurate as the uniform run whose edges are the adaptive run's smallest edge,
//! with at least five times fewer patches.
//!
//! The uniform run takes four minutes on two cores, so CI compares with its results stored in
//! `tests/data/adaptive_pulse_uniform.json`; the ignored test below reruns it and checks the
//! stored values (`cargo test --release --test suite efficiency:: -- --ignored`).

use crate::common;

use std::path::Path;

use common::{shipped, solve};
use sdg_engine::RunSummary;

/// The uniform run: the coarse 2 mm grid divided by 8, legs of 0.25 mm, the adaptive run's
/// smallest edge.
fn uniform() -> RunSummary {
    let problem = shipped(
        "adaptive_pulse.toml",
        &[
            "output.snapshot_times=[]",
            "adapt.enabled=false",
            "mesh.nx=160",
            "mesh.ny=40",
        ],
    );
    solve(&problem, 2, true).0
}

/// The stored uniform results: patches, shortest edge, velocity and stress errors.
fn stored() -> serde_json::Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/adaptive_pulse_uniform.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn adaptive_pulse_beats_the_uniform_mesh_of_its_smallest_edge_with_five_times_fewer_patches() {
    let (a, _d) = solve(
        &shipped("adaptive_pulse.toml", &["output.snapshot_times=[]"]),
        2,
        true,
    );
    let u = stored();
    let number = |key: &str| u[key].as_f64().unwrap();
    let ea = a.error.unwrap();
    eprintln!(
        "adaptive: {} patches, edges {:e} to {:e}, {} refinements, {} coarsenings, error {ea:?}; \
         uniform (stored): {u}",
        a.patches, a.min_edge, a.max_edge, a.refinements, a.coarsenings,
    );
    assert!((number("min_edge") - a.min_edge).abs() < 1e-9 * a.min_edge);
    assert!(
        ea.velocity_l2_rel <= number("velocity_l2_rel"),
        "{ea:?} vs {u}"
    );
    assert!(ea.stress_l2_rel <= number("stress_l2_rel"), "{ea:?} vs {u}");
    assert!(
        number("patches") >= 5.0 * a.patches as f64,
        "{} vs {u}",
        a.patches
    );
    assert!(a.energy.balance_residual_rel.abs() < 1e-8);
}

#[test]
#[ignore = "long: four minutes on two cores"]
fn the_stored_uniform_results_are_current() {
    let u = uniform();
    let e = u.error.unwrap();
    eprintln!(
        "{{\"patches\": {}, \"min_edge\": {:e}, \"velocity_l2_rel\": {:e}, \"stress_l2_rel\": {:e}}}",
        u.patches, u.min_edge, e.velocity_l2_rel, e.stress_l2_rel
    );
    let s = stored();
    let number = |key: &str| s[key].as_f64().unwrap();
    assert_eq!(u.patches as f64, number("patches"));
    assert!((u.min_edge / number("min_edge") - 1.0).abs() < 1e-9);
    for (value, key) in [
        (e.velocity_l2_rel, "velocity_l2_rel"),
        (e.stress_l2_rel, "stress_l2_rel"),
    ] {
        assert!(
            (value / number(key) - 1.0).abs() < 1e-6,
            "{key}: {value:e} vs {s}"
        );
    }
}
