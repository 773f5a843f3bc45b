//! Adaptivity on `configs/adaptive_pulse.toml`: rejected patches, bisections and coarsening
//! patches keep every element's momentum balance and the global energy balance, make the run
//! more accurate than the unrefined mesh, and give bitwise identical results for any thread
//! count in deterministic mode.

use crate::common;

use common::{assert_same_outputs, outputs, shipped, solve};

/// The shipped adaptive pulse, stopped once the pulse has moved about 3 mm.
const SHORT: [&str; 2] = ["time.end=1.5e-6", "output.snapshot_times=[1.5e-6]"];

#[test]
fn refinement_and_coarsening_conserve_momentum_and_energy_and_beat_the_unrefined_mesh() {
    let adaptive = shipped("adaptive_pulse.toml", &SHORT);
    let (s, _dir) = solve(&adaptive, 2, true);
    eprintln!(
        "adaptive: {} patches, {} rejected, {} refinements, {} coarsenings, edges {:e} to {:e}, \
         error {:?}, balance {:e}, momentum {:e}",
        s.patches,
        s.rejected_patches,
        s.refinements,
        s.coarsenings,
        s.min_edge,
        s.max_edge,
        s.error,
        s.energy.balance_residual_rel,
        s.max_momentum_residual
    );
    assert!(s.refinements > 100 && s.rejected_patches > 10, "{s:?}");
    assert!(s.coarsenings > 100, "{s:?}");
    assert!(s.energy.balance_residual_rel.abs() < 1e-8, "{:?}", s.energy);
    assert!(s.max_momentum_residual < 1e-10);
    assert!(s.max_slope_ratio < 0.9);
    let min_edge = adaptive.loaded.config.adapt.min_edge.unwrap();
    assert!(s.min_edge >= min_edge * (1.0 - 1e-12) && s.min_edge < 2.0 * min_edge);
    assert_eq!(s.final_time, 1.5e-6);

    let mut off = SHORT.to_vec();
    off.push("adapt.enabled=false");
    let (coarse, _dir) = solve(&shipped("adaptive_pulse.toml", &off), 2, true);
    let (a, c) = (s.error.unwrap(), coarse.error.unwrap());
    eprintln!("unrefined: {} patches, error {c:?}", coarse.patches);
    assert!(
        a.velocity_l2_rel < 0.25 * c.velocity_l2_rel,
        "{a:?} vs {c:?}"
    );
    assert!(a.stress_l2_rel < 0.25 * c.stress_l2_rel, "{a:?} vs {c:?}");
}

/// With `min_edge` above half the initial edges (2 mm) nothing can be bisected: every patch over
/// the tolerance is accepted anyway, and the summary counts them instead of staying silent; with
/// a tolerance above the largest of them, none is counted.
#[test]
fn patches_over_the_tolerance_at_the_refinement_floor_are_counted() {
    let mut overrides = SHORT.to_vec();
    overrides.push("adapt.min_edge=1.5e-3");
    let (floor, _dir) = solve(&shipped("adaptive_pulse.toml", &overrides), 2, true);
    eprintln!(
        "floor: {} of {} patches over the tolerance, largest {:.1} x tol",
        floor.unresolved_patches, floor.patches, floor.unresolved_max
    );
    assert_eq!((floor.refinements, floor.rejected_patches), (0, 0));
    assert!(floor.unresolved_patches > 20, "{floor:?}");
    assert!(floor.unresolved_max > 10.0, "{floor:?}");

    let tol = format!("adapt.tol={:e}", 2.0 * floor.unresolved_max * 1e-2);
    overrides.push(&tol);
    let (loose, _dir) = solve(&shipped("adaptive_pulse.toml", &overrides), 2, true);
    assert_eq!((loose.unresolved_patches, loose.unresolved_max), (0, 0.0));
    assert_eq!(loose.state_hash, floor.state_hash);
}

/// Without interfaces or cracks every element is far from them: `adapt.far_edge` is then the
/// indicator's floor, the same run as `adapt.min_edge` at that length.
#[test]
fn without_cracks_the_far_edge_is_the_refinement_floor() {
    let run = |set: &str| {
        let mut overrides = SHORT.to_vec();
        overrides.push(set);
        solve(&shipped("adaptive_pulse.toml", &overrides), 2, true).0
    };
    let floor = run("adapt.min_edge=5e-4");
    let far = run("adapt.far_edge=5e-4");
    assert!(floor.refinements > 10, "{floor:?}");
    assert!(far.min_edge >= 5e-4 * (1.0 - 1e-12), "{far:?}");
    assert_eq!(
        (far.state_hash, far.refinements, far.unresolved_patches),
        (
            floor.state_hash,
            floor.refinements,
            floor.unresolved_patches
        )
    );
}

#[test]
fn adaptive_deterministic_runs_are_bitwise_identical_for_1_2_and_4_threads() {
    let problem = shipped(
        "adaptive_pulse.toml",
        &["time.end=8e-7", "output.snapshot_times=[4e-7, 8e-7]"],
    );
    let (reference, dir) = solve(&problem, 1, true);
    assert!(reference.refinements > 0 && reference.coarsenings > 0);
    let expected = outputs(dir.path());
    for threads in [2, 4] {
        let (summary, dir) = solve(&problem, threads, true);
        assert_eq!(
            summary.state_hash, reference.state_hash,
            "{threads} threads"
        );
        assert_eq!(summary.refinements, reference.refinements);
        assert_eq!(summary.coarsenings, reference.coarsenings);
        let context = format!("{threads} threads");
        assert_same_outputs(&expected, &outputs(dir.path()), &context);
    }
}

#[test]
fn asynchronous_adaptive_run_conserves_energy() {
    let (s, _dir) = solve(
        &shipped(
            "adaptive_pulse.toml",
            &["time.end=8e-7", "output.snapshot_times=[]"],
        ),
        2,
        false,
    );
    assert!(s.refinements > 0 && s.coarsenings > 0);
    assert!(s.energy.balance_residual_rel.abs() < 1e-8, "{:?}", s.energy);
    assert!(s.max_momentum_residual < 1e-10);
}
