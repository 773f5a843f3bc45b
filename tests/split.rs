//! Splitting a front edge at any point (crack alignment's building block) on a live run of
//! `configs/plane_wave.toml` (a plane wave through the whole square, so that every split cuts a
//! non-zero solution), with adaptivity on for the pitcher's refinement margin and the solvers'
//! star capacity but a tolerance no patch exceeds: mid-run, edges are split at 0.3 and near an
//! end (0.1) through the engine's own refinement path. Every split keeps the front causal under
//! the pitcher's criterion, moves no front time and changes neither the energy nor the momentum
//! on the front (the children restrict their parent's polynomial exactly); a split the pitcher
//! refuses changes nothing; and the run then continues to its end with a valid energy balance,
//! its off-midpoint vertices never coarsened.

use crate::common;

use std::sync::{Arc, Mutex};

use common::{shipped, solve};
use sdg_engine::{Live, RunOptions};
use sdg_mesh::{EdgeId, Mesh, TriangleId, VertexId};
use sdg_solver::element::evaluate;
use sdg_solver::quadrature;
use sdg_solver::system::{MAX_FIELDS, System};

/// End time, s: the wave moves about 2.3 mm, a quarter of the square.
const END: f64 = 1e-6;
/// The splits happen once the whole front has passed this time (s): every triangle then lies
/// on a solved element, and the front is as the tents left it, not flat.
const AFTER: f64 = 4e-7;

/// Relative change allowed in the energy and momentum on the front by a split. Both are
/// integrals of polynomials (the elements' restrictions to the front facets) computed with
/// rules exact for their degree, so a split changes them by round-off only: the sum over
/// ~500 triangles of ~1e-16 relative errors, well under 1e-12.
const ROUND_OFF: f64 = 1e-12;

/// Momentum crossing the front (scaled units, per component) and the sum of the absolute values
/// of its quadrature terms (the scale its round-off is relative to; the total may nearly
/// cancel). On the facet `tau = c t(x)` it is the velocity rows of `A_n q` with
/// `n = (-grad tau, 1)`: `int (v + sigma grad tau) dx dy`, as the patches balance it.
fn front_momentum(live: &Live, system: &System) -> ([f64; 2], f64) {
    let (mesh, front, solution, basis) = (live.mesh(), live.front(), live.solution(), live.basis());
    let rule = quadrature::triangle(2 * basis.degree() + 2);
    let width = solution.width();
    let mut phi = vec![0.0; basis.len()];
    let mut values = vec![0.0; width];
    let (mut total, mut scale) = ([0.0; 2], 0.0);
    for (t, corners) in mesh.triangles().iter().enumerate() {
        let p = corners.map(|v| mesh.vertex(v));
        let tau = corners.map(|v| system.c_ref() * front.time(v));
        let g = sdg_mesh::geometry::linear_gradient(p, tau);
        let a_n = system.a_n([-g[0], -g[1], 1.0]);
        let area2 = sdg_mesh::geometry::signed_area2(p[0], p[1], p[2]);
        solution.with_element(t, |element| {
            let (geometry, coefficients) = element.expect("every triangle is solved");
            for (xi, &w) in rule.points.iter().zip(&rule.weights) {
                let x = [0, 1]
                    .map(|i| p[0][i] + xi[0] * (p[1][i] - p[0][i]) + xi[1] * (p[2][i] - p[0][i]));
                let s = tau[0] + xi[0] * (tau[1] - tau[0]) + xi[1] * (tau[2] - tau[0]);
                evaluate(
                    basis,
                    geometry,
                    coefficients,
                    [x[0], x[1], s],
                    &mut phi,
                    &mut values,
                );
                let mut q = [0.0; MAX_FIELDS];
                q[..system.fields()].copy_from_slice(&values[..system.fields()]);
                let flux = system.apply(&a_n, &q);
                for (k, m) in total.iter_mut().enumerate() {
                    *m += w * area2 * flux[k];
                    scale += (w * area2 * flux[k]).abs();
                }
            }
        });
    }
    (total, scale)
}

/// The energy and momentum on the front.
#[derive(Clone, Copy, Debug)]
struct Balance {
    energy: f64,
    /// The energy's kinetic and strain parts: a split leaves each unchanged, the parent's as the
    /// patch recorded them and the children's as integrated anew.
    parts: [f64; 2],
    momentum: [f64; 2],
    momentum_scale: f64,
}

fn balance(live: &Live, system: &System) -> Balance {
    let (momentum, momentum_scale) = front_momentum(live, system);
    let energy = live.front_energy();
    Balance {
        energy: energy.total,
        parts: [energy.kinetic, energy.strain],
        momentum,
        momentum_scale,
    }
}

/// Largest relative change of the energy (and its kinetic and strain parts) and of the momentum
/// from `a` to `b`.
fn change(a: Balance, b: Balance) -> (f64, f64) {
    let energy = [
        (b.energy, a.energy),
        (b.parts[0], a.parts[0]),
        (b.parts[1], a.parts[1]),
    ]
    .iter()
    .map(|(b, a)| ((b - a) / a).abs())
    .fold(0.0, f64::max);
    let momentum = (0..2)
        .map(|k| (b.momentum[k] - a.momentum[k]).abs() / a.momentum_scale)
        .fold(0.0, f64::max);
    (energy, momentum)
}

/// The largest ratio over the front of a triangle's time spread to what the pitcher's criterion
/// allows (`causal_width_factor` times its smallest altitude): at most 1 on a causal front.
fn causality_ratio(live: &Live) -> f64 {
    let (mesh, front) = (live.mesh(), live.front());
    let factor = live.pitcher().causal_width_factor();
    (0..mesh.triangles().len() as TriangleId)
        .map(|t| {
            let times = mesh.triangles()[t as usize].map(|v| front.time(v));
            let spread = times.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
                - times.iter().cloned().fold(f64::INFINITY, f64::min);
            let width = mesh.altitudes(t).into_iter().fold(f64::INFINITY, f64::min);
            spread / (factor * width)
        })
        .fold(0.0, f64::max)
}

/// The refinement edge of `t` and the triangles on it.
fn refinement_edge(mesh: &Mesh, t: TriangleId) -> (EdgeId, Vec<TriangleId>) {
    let e = mesh.triangle_edges(t)[mesh.refinement_edge(t)];
    let on = mesh.edges()[e as usize].triangles.into_iter().flatten();
    (e, on.collect())
}

/// True when `t`'s refinement edge is interior and the refinement edge of the triangle across
/// too, so that a split needs no closure.
fn shared_interior(mesh: &Mesh, t: TriangleId) -> bool {
    let (e, on) = refinement_edge(mesh, t);
    on.len() == 2 && on.iter().all(|&u| refinement_edge(mesh, u).0 == e)
}

/// Whether the pitcher allows splitting `t`'s refinement edge at `fraction` on the current front,
/// for every triangle on the edge.
fn allowed(live: &Live, t: TriangleId, fraction: f64) -> bool {
    let (mesh, front) = (live.mesh(), live.front());
    let (_, on) = refinement_edge(mesh, t);
    on.iter().all(|&u| {
        live.pitcher()
            .may_split_at(mesh, |v| front.time(v), u, fraction)
    })
}

/// Whether both pieces of `t`'s refinement edge split at `fraction` are at least `min_edge`
/// (m) long, as adaptive refinement requires.
fn long_enough(live: &Live, t: TriangleId, fraction: f64, min_edge: f64) -> bool {
    let (e, _) = refinement_edge(live.mesh(), t);
    fraction.min(1.0 - fraction) * live.mesh().edge_length(e) >= min_edge
}

/// What the intervention saw: per split, its fraction, whether it was done and the energy and
/// momentum changes; the largest causality ratio before and after any split.
#[derive(Debug, Default)]
struct Seen {
    splits: Vec<(f64, bool, (f64, f64))>,
    causality: f64,
    /// Per split with closure: whether the last step was done, and the vertices added.
    closure: Vec<(bool, usize)>,
    /// Vertices added in all.
    added: usize,
    /// Triangles whose edge could be split at 0.1 but for causality, and how many the pitcher
    /// refuses.
    candidates_at_tenth: usize,
    refused_at_tenth: usize,
}

/// Splits `t` at `fraction` through the engine and checks what the split must keep; returns
/// whether it was done.
fn split_and_check(
    live: &mut Live,
    system: &System,
    t: TriangleId,
    fraction: f64,
    seen: &mut Seen,
) -> bool {
    let before = balance(live, system);
    let vertices = live.mesh().vertices().len();
    let times = live.front().snapshot();
    let (e, _) = refinement_edge(live.mesh(), t);
    let [p, q] = live.mesh().edges()[e as usize].vertices;
    let no_closure = shared_interior(live.mesh(), t);
    let done = live.split_at(t, fraction).expect("a valid split");
    let mesh = live.mesh();
    mesh.validate().unwrap();
    // No old vertex moved in time.
    assert!((0..vertices).all(|v| live.front().time(v as VertexId) == times[v]));
    if done {
        let v = (mesh.vertices().len() - 1) as VertexId;
        let [pp, pq] = [p, q].map(|w| mesh.vertex(w));
        let want = [0, 1].map(|i| (1.0 - fraction) * pp[i] + fraction * pq[i]);
        assert_eq!(mesh.vertex(v), want, "the new vertex is at the fraction");
        let [tp, tq] = [p, q].map(|w| times[w as usize]);
        assert_eq!(live.front().time(v), (1.0 - fraction) * tp + fraction * tq);
        assert!(mesh.vertex_neighbors(v).contains(&p) && mesh.vertex_neighbors(v).contains(&q));
        if no_closure {
            assert_eq!(mesh.vertices().len(), vertices + 1);
        }
    } else if no_closure {
        assert_eq!(
            mesh.vertices().len(),
            vertices,
            "a refused split changes nothing"
        );
    }
    let ratio = causality_ratio(live);
    assert!(ratio <= 1.0, "front not causal after a split: {ratio}");
    seen.causality = seen.causality.max(ratio);
    let changed = change(before, balance(live, system));
    assert!(
        changed.0 < ROUND_OFF && changed.1 < ROUND_OFF,
        "split at {fraction}: energy and momentum changed by {changed:?}"
    );
    seen.splits.push((fraction, done, changed));
    done
}

/// The splits of the test on the live front: 0.3 without and with closure, 0.1 where the
/// pitcher refuses it (a thin child under a steep front) and where it accepts it.
fn intervene(live: &mut Live, system: &System, min_edge: f64, seen: &mut Seen) {
    let count = live.mesh().triangles().len() as TriangleId;
    let vertices = live.mesh().vertices().len();
    // Candidates the engine's other limits (piece length) do not refuse.
    let fits = |live: &Live, t: TriangleId, fraction: f64| {
        shared_interior(live.mesh(), t) && long_enough(live, t, fraction, min_edge)
    };
    assert!((0..count).all(|t| live.solution().is_solved(t as usize)));
    seen.causality = causality_ratio(live);

    let t = (0..count)
        .find(|&t| {
            let mesh = live.mesh();
            let (_, on) = refinement_edge(mesh, t);
            let inside = |u: TriangleId| {
                let edges = mesh.triangle_edges(u);
                edges
                    .iter()
                    .all(|&e| !mesh.edges()[e as usize].is_boundary())
            };
            fits(live, t, 0.3) && on.into_iter().all(inside) && allowed(live, t, 0.3)
        })
        .expect("an interior edge the pitcher lets split at 0.3");
    assert!(split_and_check(live, system, t, 0.3, seen));

    // With closure (the children's refinement edges are the cells' sides, whose other
    // triangles have their diagonals as refinement edges): the neighbour is bisected first,
    // then the side is split at 0.3 if the pitcher allows it for `t` and for the neighbour's
    // child, whose apex (the new midpoint) may be far ahead of or behind the side's ends.
    let count = live.mesh().triangles().len() as TriangleId;
    let closure: Vec<TriangleId> = (0..count)
        .filter(|&t| {
            let (mesh, front) = (live.mesh(), live.front());
            let (_, on) = refinement_edge(mesh, t);
            on.len() == 2
                && !shared_interior(mesh, t)
                && live.pitcher().may_split_at(mesh, |v| front.time(v), t, 0.3)
        })
        .collect();
    assert!(!closure.is_empty());
    for t in closure {
        let vertices = live.mesh().vertices().len();
        let done = split_and_check(live, system, t, 0.3, seen);
        let added = live.mesh().vertices().len() - vertices;
        assert!(
            added >= 1,
            "the closure bisects the neighbour even when the split is refused"
        );
        seen.closure.push((done, added));
    }

    // Near an end: refused where the front is steep over the thin child.
    let count = live.mesh().triangles().len() as TriangleId;
    let refused =
        (0..count).find(|&t| fits(live, t, 0.1) && allowed(live, t, 0.5) && !allowed(live, t, 0.1));
    let t = refused.expect("a split the pitcher allows at the midpoint but not at 0.1");
    assert!(!split_and_check(live, system, t, 0.1, seen));
    let candidates = (0..count).filter(|&t| fits(live, t, 0.1));
    seen.refused_at_tenth = candidates
        .clone()
        .filter(|&t| !allowed(live, t, 0.1))
        .count();
    seen.candidates_at_tenth = candidates.count();
    // And done where the front is flat enough.
    let t = (0..count)
        .find(|&t| fits(live, t, 0.1) && allowed(live, t, 0.1))
        .expect("an interior edge the pitcher lets split at 0.1");
    assert!(split_and_check(live, system, t, 0.1, seen));
    seen.added = live.mesh().vertices().len() - vertices;
}

#[test]
fn splitting_front_edges_off_their_midpoints_keeps_causality_energy_and_momentum() {
    let problem = shipped(
        "plane_wave.toml",
        &[
            &format!("time.end={END:e}"),
            "output.snapshot_times=[]",
            "output.png=false",
            "adapt.enabled=true",
            "adapt.tol=1",
        ],
    );
    let (reference, _dir) = solve(&problem, 2, true);
    let dir = tempfile::tempdir().unwrap();
    let options = RunOptions {
        output_dir: Some(dir.path().to_path_buf()),
        threads: Some(2),
        deterministic: true,
        progress: false,
        force: false,
        ..RunOptions::default()
    };
    let seen = Arc::new(Mutex::new(None));
    let system = problem.system.clone();
    // The default: a thousandth of the shortest initial edge.
    let min_edge = 1e-3 * problem.mesh.edge_length_range().0;
    let out = Arc::clone(&seen);
    // A failed check inside the event ends the run with its message (RunError::Panic).
    let (s, _) = sdg_engine::solve_job_with(&problem, &options, AFTER, move |live| {
        let mut seen = Seen::default();
        intervene(live, &system, min_edge, &mut seen);
        *out.lock().unwrap() = Some(seen);
    })
    .unwrap();
    let seen = seen.lock().unwrap().take().expect("the intervention ran");
    eprintln!("{seen:#?}");
    eprintln!(
        "with splits: {} refinements, {} coarsenings, balance {:e}, momentum {:e}, error {:?}; \
         without: balance {:e}, error {:?}",
        s.refinements,
        s.coarsenings,
        s.energy.balance_residual_rel,
        s.max_momentum_residual,
        s.error,
        reference.energy.balance_residual_rel,
        reference.error
    );
    assert_eq!(s.final_time, END);
    assert_eq!((s.rejected_patches, reference.refinements), (0, 0));
    // Every vertex the intervention added is booked as a refinement; only the closure's
    // midpoints may be coarsened again, never a vertex split off its edge's midpoint.
    let off_midpoint = seen.splits.iter().filter(|s| s.1).count();
    assert_eq!(s.refinements as usize, seen.added);
    assert!(s.coarsenings as usize <= seen.added - off_midpoint, "{s:?}");
    // As for any adaptive run (tests/adaptivity.rs): the balance holds to the linear solves'
    // round-off, every element balances momentum.
    assert!(s.energy.balance_residual_rel.abs() < 1e-8, "{:?}", s.energy);
    assert!(s.max_momentum_residual < 1e-10);
    assert!(s.max_slope_ratio < 0.9);
    assert_ne!(
        s.state_hash, reference.state_hash,
        "the splits changed the run"
    );
    // A few splits leave the solution as accurate.
    let (a, r) = (s.error.unwrap(), reference.error.unwrap());
    assert!(
        a.velocity_l2_rel < 1.5 * r.velocity_l2_rel,
        "{a:?} vs {r:?}"
    );
}
