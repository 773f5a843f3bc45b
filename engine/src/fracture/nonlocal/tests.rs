use super::*;
use crate::fracture::criteria::crossing;
use crate::fracture::criteria::tests::{notched, vertex_at};
use sdg_mesh::{Diagonal, GridSegment, Rectangle};

/// The forward candidates (within the half-plane about +x), one per direction (the point
/// rule may find a maximum on a star edge from both of its sectors), by direction.
fn forward(mut found: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    found.retain(|&(d, _)| d.cos() > 1e-9);
    found.sort_by(|p, q| p.0.total_cmp(&q.0));
    found.dedup_by(|q, p| angle_between(p.0, q.0) < 1e-3);
    found
}

#[test]
fn a_uniform_stress_gives_the_point_rule_s_candidates_for_any_length() {
    let (mesh, mut fracture) = notched();
    let v = vertex_at(&mesh, [0.5, 0.5]);
    let tilted = {
        let (s, c) = (2.0 * 20f64.to_radians()).sin_cos();
        let (p, q) = (15.5, 5.5);
        [p + q * c, p - q * c, q * s]
    };
    let mut compared = 0;
    for (beta, stress) in [
        (1.0, [0.0, 10.0, 0.0]),
        (1.0, tilted),
        (2.0, [4.0, 10.0, 0.0]),
        (0.5, [3.0, 10.0, -4.0]),
    ] {
        fracture.beta = beta;
        let point = forward(fracture.candidates(&mesh, v, |_| stress));
        assert!(!point.is_empty(), "{stress:?}");
        for length in [0.1, 0.3] {
            let averaged =
                forward(fracture.averaged_candidates(&mesh, v, 0.0, length, 2, |_, _| stress));
            assert_eq!(point.len(), averaged.len(), "{point:?} {averaged:?}");
            for (p, a) in point.iter().zip(&averaged) {
                assert!(angle_between(p.0, a.0) < 1e-4, "{point:?} {averaged:?}");
                assert!((p.1 - a.1).abs() < 1e-9 * p.1, "{point:?} {averaged:?}");
                compared += 1;
            }
        }
    }
    // Two maxima for beta = 2.
    assert_eq!(compared, 10);
}

#[test]
fn a_segment_stops_where_it_meets_a_crack_or_the_boundary() {
    let (mut mesh, fracture) = notched();
    let v = vertex_at(&mesh, [0.5, 0.5]);
    // A crack edge ahead, on x = 0.75 from y = 0.5 to 0.75.
    let [a, b] = [[0.75, 0.5], [0.75, 0.75]].map(|x| vertex_at(&mesh, x));
    let e = mesh.edge_between(a, b).unwrap();
    mesh.set_tag(e, Some(fracture.tag));
    // A linear field: the mean over a segment is its value at the segment's middle.
    let field = |x: [f64; 2]| [1.0 + 2.0 * x[0], 3.0 - 5.0 * x[1], 0.5 + x[0] * 7.0 - x[1]];
    let rule = gauss_legendre(1);
    let mean = |d: f64, length| fracture.mean_stress(&mesh, v, d, length, rule, |_, x| field(x));
    let at = |d: f64, r: f64| field([0.5 + r * d.cos(), 0.5 + r * d.sin()]);
    let close = |p: [f64; 3], q: [f64; 3]| (0..3).all(|i| (p[i] - q[i]).abs() < 1e-12);
    for (degrees, length, cut) in [
        // Into the crack edge at (0.75, 0.5 + 0.25 tan 30): cut at 0.25 / cos 30.
        (30.0, 0.5, 0.25 / 30f64.to_radians().cos()),
        // Short of it: the whole length.
        (30.0, 0.2, 0.2),
        // Along the grid line through the crack edge's end (0.75, 0.5): cut there.
        (0.0, 1.0, 0.25),
        (0.0, 0.2, 0.2),
        // Along the diagonal through (0.75, 0.25) to the boundary's corner (1, 0).
        (-45.0, 1.0, 0.5 * 2f64.sqrt()),
        // Into the boundary edge between (1, 0.25) and (1, 0.5).
        (-20.0, 1.0, 0.5 / 20f64.to_radians().cos()),
        // Past the crack edge's end (0.75, 0.75) into the triangles beyond.
        (50.0, 0.5, 0.5),
    ] {
        let d = f64::to_radians(degrees);
        let found = mean(d, length).unwrap();
        assert!(close(found, at(d, 0.5 * cut)), "{degrees}: {found:?}");
    }
    // Along the notch, and out of the domain from a boundary vertex: no segment.
    assert!(mean(PI, 0.3).is_none());
    let corner = vertex_at(&mesh, [1.0, 0.5]);
    assert!(
        fracture
            .mean_stress(&mesh, corner, 0.0, 0.3, rule, |_, x| field(x))
            .is_none()
    );
}

/// Mode I crack-tip field (Williams) with `K` in Pa sqrt(m), the tip at `tip` and the crack
/// along -x: `[sxx, syy, sxy]` (Pa) at `x` (m).
fn williams(k: f64, tip: [f64; 2], x: [f64; 2]) -> [f64; 3] {
    let (dx, dy) = (x[0] - tip[0], x[1] - tip[1]);
    let (r, th) = ((dx * dx + dy * dy).sqrt(), dy.atan2(dx));
    let a = k / (2.0 * PI * r).sqrt();
    let (s, c) = (0.5 * th).sin_cos();
    let (s3, c3) = (1.5 * th).sin_cos();
    [
        a * c * (1.0 - s * s3),
        a * c * (1.0 + s * s3),
        a * c * s * c3,
    ]
}

/// Per triangle of `mesh`, the L2 projection of `field` onto linear functions, as the values
/// of the linear function at the triangle's corners. The quadrature is a product
/// Gauss-Legendre rule on the square collapsed onto the triangle at its corner nearest `tip`,
/// `a = s^2` from that corner: with the singularity `r^-1/2` at that corner the integrand is
/// smooth in `(s, b)`.
fn projected(
    mesh: &Mesh,
    tip: [f64; 2],
    field: impl Fn([f64; 2]) -> [f64; 3],
) -> Vec<[[f64; 3]; 3]> {
    let rule = sdg_solver::quadrature::gauss_legendre(10);
    (0..mesh.triangles().len() as TriangleId)
        .map(|t| {
            let corners = mesh.triangle_points(t);
            let near = (0..3)
                .min_by(|&i, &j| {
                    let d = |k: usize| geometry::distance(corners[k], tip);
                    d(i).total_cmp(&d(j))
                })
                .unwrap();
            // The corners from the nearest one on; the values go back in the mesh's order.
            let p = [0, 1, 2].map(|i| corners[(near + i) % 3]);
            let area = mesh.area(t);
            // b_i = integral of field * lambda_i.
            let mut moments = [[0.0; 3]; 3];
            for (&[s], &ws) in rule.points.iter().zip(&rule.weights) {
                for (&[b], &wb) in rule.points.iter().zip(&rule.weights) {
                    let a = s * s;
                    let lambda = [1.0 - a, a * (1.0 - b), a * b];
                    let x = [0, 1].map(|k| (0..3).map(|i| lambda[i] * p[i][k]).sum());
                    let weight = ws * wb * 4.0 * area * s * s * s;
                    let f = field(x);
                    for i in 0..3 {
                        for c in 0..3 {
                            moments[i][c] += weight * lambda[i] * f[c];
                        }
                    }
                }
            }
            // The inverse of the P1 mass matrix area / 12 [[2, 1, 1], [1, 2, 1], [1, 1, 2]].
            let values = [0, 1, 2].map(|i| {
                [0, 1, 2].map(|c| {
                    (0..3)
                        .map(|j| if i == j { 3.0 } else { -1.0 } * moments[j][c])
                        .sum::<f64>()
                        * 3.0
                        / area
                })
            });
            [0, 1, 2].map(|k| values[(k + 3 - near) % 3])
        })
        .collect()
}

/// The point of the criterion over a length: on a straight crack under the mode I field
/// (K = 1e6 Pa sqrt(m)), with the field L2-projected onto linear stresses per triangle (as a
/// DG solution approximates it; the projection is exact for the triangle's mean, and its value
/// at the tip is finite), the point rule's traction straight ahead grows like h^-1/2 as the
/// elements shrink from L / 2 to L / 16, while the mean over L converges to the exact
/// 2 K / sqrt(2 pi L).
#[test]
fn over_a_length_the_traction_ahead_of_a_crack_tip_converges_as_the_point_value_does_not() {
    let (k, length) = (1e6, 1e-3);
    let width = 4.0 * length;
    let tip = [0.5 * width, 0.5 * width];
    let exact = 2.0 * k / (2.0 * PI * length).sqrt();
    let mut point = Vec::new();
    let mut averaged = Vec::new();
    for n in [8, 16, 32, 64, 128] {
        let mut mesh = Rectangle {
            width,
            height: width,
            nx: n,
            ny: n,
            diagonal: Diagonal::Right,
            interfaces: vec![GridSegment {
                from: [0.0, tip[1]],
                to: tip,
                tag: "notch".into(),
            }],
            sides: Vec::new(),
            perturb: 0.0,
            seed: 1,
        }
        .build()
        .unwrap();
        let (_, template) = notched();
        let notch = mesh.tag_id("notch").unwrap();
        let tag = mesh.add_tag("crack");
        let fracture = Fracture {
            tag,
            cracks: vec![tag, notch],
            ..template
        };
        let v = vertex_at(&mesh, tip);
        let tri = mesh.triangles().to_vec();
        let linear = projected(&mesh, tip, |x| williams(k, tip, x));
        let stress_at = |t: TriangleId, x: [f64; 2]| {
            let lambda = barycentric(&mesh, t, x);
            let c = &linear[t as usize];
            [0, 1, 2].map(|j| (0..3).map(|i| lambda[i] * c[i][j]).sum())
        };
        let ahead = |stress| effective_traction(stress, fracture.beta, 0.5 * PI).0;
        // The point rule: the stress at the tip in the star triangle straight ahead.
        let t = crossing(&mesh, v, 0.0).unwrap().triangle;
        let corner = tri[t as usize].iter().position(|&w| w == v).unwrap();
        point.push(ahead(linear[t as usize][corner]));
        let mean = fracture.mean_stress(&mesh, v, 0.0, length, gauss_legendre(1), stress_at);
        averaged.push(ahead(mean.unwrap()));
        // The strongest averaged maximum is straight ahead with that traction.
        let found = fracture.averaged_candidates(&mesh, v, 0.0, length, 1, stress_at);
        let best = found.iter().max_by(|p, q| p.1.total_cmp(&q.1)).unwrap();
        assert!(best.0.abs() < 1e-3, "{n}: {found:?}");
        assert!(best.1 >= averaged[averaged.len() - 1], "{n}: {found:?}");
    }
    eprintln!("point {point:?}\naveraged {averaged:?}\nexact {exact}");
    // The point value grows like h^-1/2: by sqrt(2) a level.
    for i in 1..point.len() {
        let ratio = point[i] / point[i - 1];
        assert!((1.3..1.55).contains(&ratio), "point {point:?}");
    }
    // The mean converges to the exact one: its error falls at every level (like sqrt(h / L)
    // once h <= L / 8), and its changes are small beside the point value's.
    let error: Vec<f64> = averaged.iter().map(|a| (a / exact - 1.0).abs()).collect();
    for i in 1..error.len() {
        assert!(
            error[i] < error[i - 1],
            "averaged {averaged:?}, exact {exact}"
        );
        let change = (averaged[i] - averaged[i - 1]).abs();
        assert!(change < 3e-3 * exact, "averaged {averaged:?}");
    }
    for i in 3..averaged.len() {
        let (before, after) = (
            averaged[i - 1] - averaged[i - 2],
            averaged[i] - averaged[i - 1],
        );
        assert!(after.abs() < before.abs(), "averaged {averaged:?}");
    }
    assert!(
        error[0] < 0.015 && error[3] < 0.01,
        "averaged {averaged:?}, exact {exact}"
    );
}
