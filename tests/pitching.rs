//! Tent pitching on many kinds of triangulations: causality of every facet, progress to the end
//! time, linear tent counts, and a spacetime mesh that fills the slab exactly.

use sdg_engine::{SpacetimeMesh, pitch_to_end};
use sdg_mesh::{Diagonal, Front, Mesh, Pitcher, Rectangle};

const C: f64 = 2000.0;
const SAFETY: f64 = 0.9;

fn rectangle(nx: u32, diagonal: Diagonal, perturb: f64) -> Mesh {
    Rectangle {
        width: 1.0,
        height: 1.0,
        nx,
        ny: nx,
        diagonal,
        interfaces: Vec::new(),
        sides: Vec::new(),
        perturb,
        seed: 7,
    }
    .build()
    .unwrap()
}

/// A mesh of the unit square graded toward the origin by `p -> p r^(k-1)`, `r = max(x, y)`.
fn graded(nx: u32, k: f64) -> Mesh {
    rectangle(nx, Diagonal::Alternate, 0.0)
        .map_vertices(|p| {
            let r = p[0].max(p[1]);
            let s = if r > 0.0 { r.powf(k - 1.0) } else { 0.0 };
            [p[0] * s, p[1] * s]
        })
        .unwrap()
}

/// A sheared structured mesh whose triangles have angles up to about 153 degrees.
fn obtuse(nx: u32) -> Mesh {
    rectangle(nx, Diagonal::Right, 0.0)
        .map_vertices(|p| [p[0] + 2.0 * p[1], p[1]])
        .unwrap()
}

fn plate_with_hole() -> Mesh {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/plate_with_hole.msh"
    );
    sdg_mesh::gmsh::read_msh(std::path::Path::new(path)).unwrap()
}

struct Outcome {
    tents: u64,
    max_ratio: f64,
    spacetime: SpacetimeMesh,
}

/// Pitches `mesh` to `t_end`, checking every tent as it is built: the vertex was a local minimum,
/// the tent has positive height, and every new front facet satisfies the slope bound.
fn pitch_checked(mesh: &Mesh, t_end: f64) -> Outcome {
    let pitcher = Pitcher::new(mesh, C, SAFETY, t_end).unwrap();
    let front = Front::flat(mesh.vertices().len(), 0.0);
    let mut spacetime = SpacetimeMesh::new(mesh, &front);
    let mut max_ratio: f64 = 0.0;
    let tents = pitch_to_end(mesh, &pitcher, &front, |tent, front| {
        let v = tent.vertex;
        assert!(tent.t_new > tent.t_old, "tent {tent:?} has no height");
        for &w in mesh.vertex_neighbors(v) {
            assert!(
                front.time(w) >= tent.t_old,
                "vertex {v} was not a local minimum"
            );
        }
        for &t in mesh.vertex_triangles(v) {
            let ratio = C * front.slope(mesh, t);
            assert!(
                ratio < SAFETY,
                "facet {t} of tent {tent:?}: slope ratio {ratio}"
            );
            max_ratio = max_ratio.max(ratio);
        }
        spacetime.add_tent(mesh, tent);
    })
    .unwrap();
    assert!(
        front.snapshot().iter().all(|&t| t == t_end),
        "the front ends exactly flat at the end time"
    );
    Outcome {
        tents,
        max_ratio,
        spacetime,
    }
}

/// Checks causality and progress and that the tetrahedra tile the slab `domain x [0, t_end]`.
fn check_mesh(mesh: &Mesh, t_end: f64) -> Outcome {
    let out = pitch_checked(mesh, t_end);
    assert!(out.max_ratio < SAFETY && out.max_ratio > 0.5 * SAFETY);
    let area: f64 = (0..mesh.triangles().len() as u32)
        .map(|t| mesh.area(t))
        .sum();
    let mut volume = 0.0;
    for i in 0..out.spacetime.tetrahedra() {
        let v = out.spacetime.volume(i);
        assert!(v > 0.0, "tetrahedron {i} has volume {v}");
        volume += v;
    }
    let slab = area * t_end;
    assert!(
        (volume - slab).abs() < 1e-10 * slab,
        "volume {volume} vs slab {slab}"
    );
    out
}

#[test]
fn structured_meshes_of_every_diagonal_pattern() {
    for d in [Diagonal::Right, Diagonal::Left, Diagonal::Alternate] {
        let mesh = rectangle(12, d, 0.0);
        check_mesh(&mesh, 20.0 / 12.0 / C);
    }
}

#[test]
fn randomly_perturbed_mesh() {
    let mesh = rectangle(20, Diagonal::Alternate, 0.2);
    check_mesh(&mesh, 10.0 / 20.0 / C);
}

#[test]
fn obtuse_triangles() {
    let mesh = obtuse(10);
    let widest = (0..mesh.triangles().len() as u32)
        .flat_map(|t| mesh.angles(t))
        .fold(0.0, f64::max);
    assert!(
        widest.to_degrees() > 150.0,
        "widest angle {}",
        widest.to_degrees()
    );
    check_mesh(&mesh, 5.0 / 10.0 / C);
}

#[test]
fn strongly_graded_mesh() {
    let mesh = graded(16, 3.5);
    let (lo, hi) = mesh.edge_length_range();
    assert!(lo / hi <= 1e-3, "edge ratio {}", lo / hi);
    // Long enough that the largest elements take several tents.
    let out = check_mesh(&mesh, 3.0 * hi / C);
    assert!(out.tents > 10 * mesh.vertices().len() as u64);
}

#[test]
fn gmsh_plate_with_a_hole() {
    let mesh = plate_with_hole();
    let (_, hi) = mesh.edge_length_range();
    check_mesh(&mesh, 5.0 * hi / C);
}

/// The predicted number of tents: each vertex advances by about the time budget of its star,
/// so `sum_v t_end c / (s h_v)` with `h_v` the smallest altitude in the star.
fn predicted_tents(mesh: &Mesh, t_end: f64) -> f64 {
    (0..mesh.vertices().len() as u32)
        .map(|v| {
            let h = mesh
                .vertex_triangles(v)
                .iter()
                .flat_map(|&t| mesh.altitudes(t))
                .fold(f64::INFINITY, f64::min);
            t_end * C / (SAFETY * h)
        })
        .sum()
}

#[test]
fn tent_count_is_linear_in_vertices_times_end_time_over_edge_length() {
    let t_end = 4.0 / C;
    let ratios: Vec<f64> = [8, 16, 32]
        .into_iter()
        .map(|n| {
            let mesh = rectangle(n, Diagonal::Alternate, 0.15);
            pitch_checked(&mesh, t_end).tents as f64 / predicted_tents(&mesh, t_end)
        })
        .collect();
    eprintln!("tent-count ratios {ratios:?}");
    // Tents go as N_v * t_end / h = O(n^3) here; the constant stays put across sizes.
    for r in &ratios {
        assert!((0.6..=1.1).contains(r), "ratios {ratios:?}");
    }
    let spread = ratios.iter().cloned().fold(0.0, f64::max)
        / ratios.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(spread < 1.1, "ratios {ratios:?}");
}

/// Largest `c |grad tau|` over every front facet.
fn max_slope_ratio(mesh: &Mesh, front: &Front) -> f64 {
    (0..mesh.triangles().len() as u32)
        .map(|t| C * front.slope(mesh, t))
        .fold(0.0, f64::max)
}

#[test]
fn refinement_toward_a_corner_to_edge_ratio_1e_4_keeps_causality_and_progress() {
    let mut mesh = rectangle(4, Diagonal::Right, 0.0);
    // About ten coarse tents; the finest triangles need tens of thousands each.
    let t_end = 1.0 / C;
    let mut pitcher = Pitcher::new(&mesh, C, SAFETY, t_end)
        .unwrap()
        .for_refinement(&mesh);
    let mut front = Front::flat(mesh.vertices().len(), 0.0);
    let corner = (0..mesh.vertices().len() as u32)
        .find(|&v| mesh.vertex(v) == [0.0, 0.0])
        .unwrap();
    let ratio = |mesh: &Mesh| {
        let (lo, hi) = mesh.edge_length_range();
        lo / hi
    };
    let (mut tents, mut refused, mut reached) = (0u64, 0u64, None);
    loop {
        // Once the front has left t = 0 everywhere (it is no longer flat), bisect the smallest
        // triangle at the corner every third tent until the ratio is reached, whenever the
        // pitcher allows it.
        if front.min_time() > 0.3 * t_end && tents % 3 == 0 && ratio(&mesh) > 1e-4 {
            let t = *mesh
                .vertex_triangles(corner)
                .iter()
                .min_by(|&&a, &&b| mesh.area(a).total_cmp(&mesh.area(b)))
                .unwrap();
            let mut splits = Vec::new();
            let mut allow = |m: &Mesh, done: &[sdg_mesh::Split], u: u32| {
                pitcher.may_bisect(m, |w| front.time_after(done, w), u)
            };
            if !mesh.bisect(t, &mut allow, &mut splits) {
                refused += 1;
            }
            for split in &splits {
                let [a, b] = split.ends;
                front.push(0.5 * (front.time(a) + front.time(b)));
            }
            pitcher.update(
                &mesh,
                splits
                    .iter()
                    .flat_map(|s| s.halves.iter().flat_map(|&(k, n)| [k, n])),
            );
            let slope = max_slope_ratio(&mesh, &front);
            assert!(
                slope < SAFETY,
                "refinement made a facet non-causal: {slope}"
            );
            if ratio(&mesh) <= 1e-4 && reached.is_none() {
                reached = Some(tents);
            }
        }
        let Some(v) = (0..mesh.vertices().len() as u32)
            .filter(|&v| front.time(v) < t_end)
            .min_by(|&a, &b| front.time(a).total_cmp(&front.time(b)).then(a.cmp(&b)))
        else {
            break;
        };
        let tent = pitcher
            .pitch(&mesh, &front, v)
            .expect("the earliest vertex is pitchable");
        assert!(tent.t_new > tent.t_old);
        for &t in mesh.vertex_triangles(v) {
            let slope = C * front.slope(&mesh, t);
            assert!(slope < SAFETY, "tent {tents} at {v}: slope ratio {slope}");
        }
        tents += 1;
        assert!(tents < 20_000_000, "no progress");
    }
    mesh.validate().unwrap();
    let reached = reached.expect("edge-length ratio 1e-4 reached");
    eprintln!(
        "ratio {:e} after {reached} tents, {} vertices, {tents} tents in all, {refused} refused",
        ratio(&mesh),
        mesh.vertices().len()
    );
    assert!(ratio(&mesh) <= 1e-4);
    assert!(
        front.snapshot().iter().all(|&t| t == t_end),
        "front ends at t_end"
    );
}
