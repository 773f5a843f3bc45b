use super::*;
use sdg_mesh::{Diagonal, GridSegment, Rectangle};

/// A unit square in 4 x 4 cells with a notch from the left side to its centre.
pub(crate) fn notched() -> (Mesh, Fracture) {
    let mut mesh = Rectangle {
        width: 1.0,
        height: 1.0,
        nx: 4,
        ny: 4,
        diagonal: Diagonal::Alternate,
        interfaces: vec![GridSegment {
            from: [0.0, 0.5],
            to: [0.5, 0.5],
            tag: "notch".into(),
        }],
        sides: Vec::new(),
        perturb: 0.0,
        seed: 1,
    }
    .build()
    .unwrap();
    let tag = mesh.add_tag("crack");
    let notch = mesh.tag_id("notch").unwrap();
    let fracture = Fracture {
        tag,
        cracks: vec![tag, notch],
        threshold: 1.0,
        shield: 35f64.to_radians(),
        snap: 0.2,
        floor_angle: 17.5f64.to_radians(),
        max_tip_speed: 1000.0,
        tangent_length: None,
        criterion_length: None,
        beta: 1.0,
        delay: 1e-8,
        nucleation: None,
    };
    (mesh, fracture)
}

pub(crate) fn vertex_at(mesh: &Mesh, x: [f64; 2]) -> VertexId {
    (0..mesh.vertices().len() as VertexId)
        .find(|&v| geometry::distance(mesh.vertex(v), x) < 1e-12)
        .unwrap()
}

#[test]
fn the_notch_end_is_the_only_tip_and_travels_along_the_notch() {
    let (mesh, fracture) = notched();
    let tips = fracture.initial_tips(&mesh);
    let centre = vertex_at(&mesh, [0.5, 0.5]);
    let found: Vec<_> = (0..tips.len()).filter(|&v| tips[v].is_some()).collect();
    assert_eq!(found, [centre as usize]);
    let tip = tips[centre as usize].unwrap();
    assert!(tip.direction.abs() < 1e-12 && tip.branch == 0, "{tip:?}");
}

#[test]
fn mode_one_tension_extends_straight_ahead_and_compression_not_at_all() {
    let (mesh, fracture) = notched();
    let v = vertex_at(&mesh, [0.5, 0.5]);
    let tip = fracture.initial_tips(&mesh)[v as usize].unwrap();
    let d = fracture.directions(&mesh, v, tip, |_| [0.0, 10.0, 0.0]);
    assert!(d[0].abs() < 1e-12 && d[1].is_nan(), "{d:?}");
    let d = fracture.directions(&mesh, v, tip, |_| [0.0, -10.0, 0.0]);
    assert!(d.iter().all(|x| x.is_nan()), "{d:?}");
    // Below the threshold: nothing.
    let d = fracture.directions(&mesh, v, tip, |_| [0.0, 0.5, 0.0]);
    assert!(d.iter().all(|x| x.is_nan()), "{d:?}");
}

/// Ahead of a crack running at 0.8 c_R (PMMA, plane strain) Yoffe's field has
/// `sxx = 2.1 syy` on the crack line: the effective traction peaks across the path, at
/// +-90 degrees, just outside the forward half, and is least straight ahead.
#[test]
fn a_tip_whose_stress_runs_along_the_path_finds_its_maxima_across_it_and_none_forward() {
    let (mesh, fracture) = notched();
    let v = vertex_at(&mesh, [0.5, 0.5]);
    let tip = fracture.initial_tips(&mesh)[v as usize].unwrap();
    let stress = |_| [21.0, 10.0, 0.0];
    let found = fracture.candidates(&mesh, v, stress);
    assert!(!found.is_empty());
    for (d, s) in &found {
        assert!(
            (d.cos().abs() < 1e-9) && (s - 21.0).abs() < 1e-9,
            "{found:?}"
        );
    }
    let d = fracture.select(&mesh, v, tip, &found);
    assert!(d.iter().all(|x| x.is_nan()), "{d:?}");
    // With its principal axes turned 15 degrees (clockwise above the path, counterclockwise
    // below), the maxima enter the forward half, 75 degrees up and down: a branching.
    let tilted = |t: TriangleId| {
        let y = mesh.triangles()[t as usize].map(|w| mesh.vertex(w)[1]);
        let above = y.iter().sum::<f64>() / 3.0 > 0.5;
        let turn = if above { -15f64 } else { 15.0 }.to_radians();
        let (s, c) = (2.0 * turn).sin_cos();
        let (p, q) = (15.5, 5.5);
        [p + q * c, p - q * c, q * s]
    };
    let mut d = fracture
        .directions(&mesh, v, tip, tilted)
        .map(f64::to_degrees);
    d.sort_by(f64::total_cmp);
    assert!(
        (d[0] + 75.0).abs() < 1e-9 && (d[1] - 75.0).abs() < 1e-9,
        "{d:?}"
    );
}

#[test]
fn two_maxima_branch_when_the_shield_angle_allows_and_the_stronger_wins_otherwise() {
    let (mesh, mut fracture) = notched();
    let v = vertex_at(&mesh, [0.5, 0.5]);
    let tip = fracture.initial_tips(&mesh)[v as usize].unwrap();
    // Equal biaxial tension with beta = 2: the stationary point c* = p / (q (beta^2 - 1))
    // gives two planes symmetric about the principal one.
    fracture.beta = 2.0;
    let stress = [4.0, 10.0, 0.0];
    let d = fracture.directions(&mesh, v, tip, |_| stress);
    assert!(d.iter().all(|x| x.is_finite()), "{d:?}");
    assert!(
        (d[0] + d[1]).abs() < 1e-12,
        "symmetric about the x axis: {d:?}"
    );
    let spread = angle_between(d[0], d[1]);
    fracture.shield = spread + 0.01;
    let d = fracture.directions(&mesh, v, tip, |_| stress);
    assert!(d[0].is_finite() && d[1].is_nan(), "{d:?}");
}

#[test]
fn a_crack_nucleates_across_tension_where_weak_defects_are_and_nowhere_else() {
    let (mesh, mut fracture) = notched();
    let strengths = DefectStrengths::new(50.0, 10.0, 5.0).unwrap();
    fracture.nucleation = Some(Nucleation {
        density: 1e6,
        strengths,
        seed: 3,
        on_surfaces: false,
    });
    let inside = vertex_at(&mesh, [0.5, 0.25]);
    let tension = |_| [0.0, 1e4, 0.0];
    let d = fracture.nucleates(&mesh, inside, 1e-6, tension).unwrap();
    let mut d = d.map(|x| x.rem_euclid(2.0 * PI));
    d.sort_by(f64::total_cmp);
    assert!(d[0].abs() < 1e-12 && (d[1] - PI).abs() < 1e-12, "{d:?}");
    // Equal compression (no shear either), a stress below the weakest possible defect.
    assert_eq!(
        fracture.nucleates(&mesh, inside, 1e-6, |_| [-1e4, -1e4, 0.0]),
        None
    );
    assert_eq!(
        fracture.nucleates(&mesh, inside, 1e-6, |_| [0.0, 4.0, 0.0]),
        None
    );
    // On the boundary and on the notch: nothing without `on_surfaces`; with it, a crack
    // along the surface is shielded by it,
    let across = |_| [1e4, 0.0, 0.0];
    for at in [[0.25, 0.0], [0.25, 0.5]] {
        let v = vertex_at(&mesh, at);
        assert_eq!(fracture.nucleates(&mesh, v, 1e-6, across), None);
        fracture.nucleation.as_mut().unwrap().on_surfaces = true;
        assert_eq!(fracture.nucleates(&mesh, v, 1e-6, tension), None);
        fracture.nucleation.as_mut().unwrap().on_surfaces = false;
    }
    fracture.nucleation.as_mut().unwrap().on_surfaces = true;
    // and a crack across it runs one way: into the plate from its bottom side, and from
    // the notch into the side whose elements carry the larger traction.
    let d = fracture.nucleates(&mesh, vertex_at(&mesh, [0.25, 0.0]), 1e-6, across);
    let d = d.unwrap();
    assert!((d[0] - 0.5 * PI).abs() < 1e-12 && d[1].is_nan(), "{d:?}");
    let on_notch = vertex_at(&mesh, [0.25, 0.5]);
    for (side, sign) in [(0.75, 1.0), (0.25, -1.0)] {
        let stronger = |t: TriangleId| {
            let y = mesh.triangles()[t as usize].map(|w| mesh.vertex(w)[1]);
            let above = y.iter().sum::<f64>() / 3.0;
            let s = if (above - side).abs() < 0.25 {
                2e4
            } else {
                1e4
            };
            [s, 0.0, 0.0]
        };
        let d = fracture.nucleates(&mesh, on_notch, 1e-6, stronger).unwrap();
        assert!(
            (d[0] - sign * 0.5 * PI).abs() < 1e-12 && d[1].is_nan(),
            "{d:?}"
        );
    }
    // Few defects: whether one is weak enough depends on the draw, keyed by the time.
    fracture.nucleation.as_mut().unwrap().density = 1.0;
    let stress = |_| [0.0, 45.0, 0.0];
    let hits = (0..200)
        .filter(|&k| {
            fracture
                .nucleates(&mesh, inside, k as f64, stress)
                .is_some()
        })
        .count();
    // P = 1 - exp(-density area F(45)) with the area the star's and
    // F(45) = P(s < 45) for N(50, 10) truncated at 5.
    let area: f64 = mesh
        .vertex_triangles(inside)
        .iter()
        .map(|&t| mesh.area(t))
        .sum();
    let p = 1.0 - (-area * strengths.cdf(45.0)).exp();
    let expected = 200.0 * p;
    assert!(
        (hits as f64 - expected).abs() < 4.0 * (expected * (1.0 - p)).sqrt() + 1.0,
        "{hits} vs {expected}"
    );
}

/// A tip that reached its vertex at `since` extends along a direction only once the new edge
/// (to the crossing with the opposite edge, here the grid's 0.25 m diagonal) over the time
/// since is at most the speed limit; the initial cracks' tips and the seed's rule never wait.
#[test]
fn a_tip_waits_until_its_new_edge_is_within_the_speed_limit() {
    let (mesh, mut fracture) = notched();
    let v = vertex_at(&mesh, [0.5, 0.5]);
    let mut tip = fracture.initial_tips(&mesh)[v as usize].unwrap();
    let ahead = [0.0, f64::NAN];
    let length = 0.25;
    let time = length / fracture.max_tip_speed;
    assert!(fracture.in_time(&mesh, v, tip, ahead, 0.0));
    tip.since = 1.0;
    for (t, allowed) in [
        (1.0, false),
        (1.0 + 0.99 * time, false),
        (1.0 + 1.01 * time, true),
    ] {
        assert_eq!(
            fracture.in_time(&mesh, v, tip, ahead, t),
            allowed,
            "t = {t}"
        );
    }
    // Both directions of a branching must be in time: the diagonal one is longer.
    let fork = [0.0, 45f64.to_radians()];
    assert!(!fracture.in_time(&mesh, v, tip, fork, 1.0 + 1.01 * time));
    assert!(fracture.in_time(&mesh, v, tip, fork, 1.0 + 1.42 * time));
    fracture.max_tip_speed = f64::INFINITY;
    assert!(fracture.in_time(&mesh, v, tip, fork, 1.0));
}

#[test]
fn a_direction_crosses_the_opposite_edge_where_the_geometry_says() {
    let (mesh, _) = notched();
    let v = vertex_at(&mesh, [0.5, 0.5]);
    for k in 0..64 {
        let d = -PI + (k as f64 + 0.5) * PI / 32.0;
        let c = crossing(&mesh, v, d).unwrap();
        let [p, q] = mesh.edges()[c.edge as usize]
            .vertices
            .map(|w| mesh.vertex(w));
        let x = [0, 1].map(|i| p[i] + c.fraction * (q[i] - p[i]));
        let o = mesh.vertex(v);
        let along = (x[1] - o[1]).atan2(x[0] - o[0]);
        assert!(angle_between(along, d) < 1e-12, "{d} {along}");
        assert_eq!(mesh.triangles()[c.triangle as usize][c.corner], v);
    }
}

/// A tip may take an edge only within half the shield angle of its wanted direction, but
/// may join a crack it runs into along any forward edge that keeps the shield angle from
/// the crack edges at the tip: here the edge 45 degrees up from the notch's tip.
#[test]
fn a_tip_joins_a_crack_along_any_shielded_forward_edge() {
    let (mut mesh, fracture) = notched();
    let v = vertex_at(&mesh, [0.5, 0.5]);
    let tip = fracture.initial_tips(&mesh)[v as usize].unwrap();
    let [ahead, up, back] = [[0.75, 0.5], [0.75, 0.75], [0.25, 0.5]].map(|x| vertex_at(&mesh, x));
    for w in [ahead, up, back] {
        assert!(mesh.edge_between(v, w).is_some());
    }
    let half = 0.5 * fracture.shield;
    assert!(fracture.may_take(&mesh, (v, tip), 0.0, ahead, half));
    assert!(!fracture.may_take(&mesh, (v, tip), 0.0, up, half));
    // A direction 22 degrees up, between the two edges 45 degrees apart, is more than half
    // the shield angle from both and within the whole of it from both.
    let d = 22f64.to_radians();
    for w in [ahead, up] {
        assert!(!fracture.may_take(&mesh, (v, tip), d, w, half));
        assert!(fracture.may_take(&mesh, (v, tip), d, w, fracture.shield));
    }
    assert!(fracture.may_join(&mesh, v, tip, up));
    assert!(!fracture.may_join(&mesh, v, tip, back));
    // Once the edge ahead is a crack, the edge 45 degrees from it still keeps the shield
    // angle (35 degrees) and the crack edge itself is taken.
    let e = mesh.edge_between(v, ahead).unwrap();
    mesh.set_tag(e, Some(fracture.tag));
    assert!(fracture.may_join(&mesh, v, tip, up));
    assert!(!fracture.may_join(&mesh, v, tip, ahead));
    let shielded = Fracture {
        shield: 50f64.to_radians(),
        ..fracture.clone()
    };
    assert!(!shielded.may_join(&mesh, v, tip, up));
}

/// The crack tangent: the last edge's direction by default; averaged over
/// `tangent_length`, it keeps a tip that turned 45 degrees at each of four 5.5 um edges
/// (the finest grid's) from turning a fifth time the same way, back towards its own crack.
#[test]
fn the_tangent_averaged_over_a_length_stops_a_curl() {
    let (_, mut fracture) = notched();
    let l = 5.5e-6;
    let edge = |from: [f64; 2], degrees: f64| {
        let a = degrees.to_radians();
        [from[0] + l * a.cos(), from[1] + l * a.sin()]
    };
    let up = std::f64::consts::FRAC_PI_2;
    assert_eq!(fracture.tangent(Some(1.0), [0.0, 0.0], [0.0, 1.0]), up);
    fracture.tangent_length = Some(9.4e-6);
    assert_eq!(fracture.tangent(None, [0.0, 0.0], [0.0, 1.0]), up);
    assert_eq!(fracture.tangent(Some(0.0), [0.0, 0.0], [l, 0.0]), 0.0);
    let w = (-l / 9.4e-6f64).exp();
    let half = fracture.tangent(Some(0.0), [0.0, 0.0], [0.0, l]);
    assert!((half - (1.0 - w).atan2(w)).abs() < 1e-15, "{half}");
    let forward = |tangent: f64, degrees: f64| (degrees.to_radians() - tangent).cos() > 0.0;
    let (mut at, mut averaged, mut last) = ([0.0, 0.0], 0.0, 0.0);
    for degrees in [45.0, 90.0, 135.0, 180.0] {
        let to = edge(at, degrees);
        averaged = fracture.tangent(Some(averaged), at, to);
        last = (to[1] - at[1]).atan2(to[0] - at[0]);
        at = to;
    }
    assert!(
        forward(last, 225.0) && !forward(averaged, 225.0),
        "{averaged}"
    );
    assert!(forward(averaged, 180.0));
}

/// Checkpoints carry a tip's pending directions (CBOR, as `checkpoint_NNNNNN.sdgc`), NaN
/// entries included, and read a tip written before they existed as one with none.
#[test]
fn a_tip_s_pending_directions_survive_a_checkpoint() {
    let tip = Tip {
        direction: 0.25,
        branch: 3,
        since: 2.5e-7,
        pending: Some(Pending {
            directions: [-0.5, f64::NAN],
            time: 1.25e-6,
        }),
    };
    let mut bytes = Vec::new();
    ciborium::into_writer(&tip, &mut bytes).unwrap();
    let read: Tip = ciborium::from_reader(bytes.as_slice()).unwrap();
    let pending = read.pending.unwrap();
    assert_eq!((read.direction, read.branch), (0.25, 3));
    assert_eq!(pending.directions[0], -0.5);
    assert!(pending.directions[1].is_nan());
    assert_eq!(pending.time, 1.25e-6);
    #[derive(serde::Serialize)]
    struct Before {
        direction: f64,
        branch: u32,
    }
    let mut bytes = Vec::new();
    let before = Before {
        direction: 0.25,
        branch: 3,
    };
    ciborium::into_writer(&before, &mut bytes).unwrap();
    let read: Tip = ciborium::from_reader(bytes.as_slice()).unwrap();
    assert_eq!(read.pending, None);
}
