//! Quadrature rules on reference simplices.
//!
//! The triangle and tetrahedron rules are collapsed-coordinate (Duffy, conical product) rules:
//! the simplex is the image of the unit cube under
//! `(u, v, w) -> (u (1 - v) (1 - w), v (1 - w), w)`, whose Jacobian `(1 - v) (1 - w)^2` is
//! absorbed into Gauss–Jacobi weights in `v` and `w`. A rule exact for total degree `d` uses
//! `d / 2 + 1` points per direction, the fewest a product of Gauss rules allows. Nodes are
//! computed by Newton iteration on the three-term recurrence of the Jacobi polynomials.

/// A quadrature rule on a D-dimensional reference simplex: points and positive weights.
#[derive(Clone, Debug)]
pub struct Rule<const D: usize> {
    pub points: Vec<[f64; D]>,
    pub weights: Vec<f64>,
}

/// Gauss–Legendre rule with `n >= 1` points on [0, 1] (weights sum to 1), exact for degree
/// `2n - 1`. Points are strictly inside (0, 1) and increasing.
///
/// # Panics
/// If `n == 0`.
pub fn gauss_legendre(n: usize) -> Rule<1> {
    let (points, weights) = gauss_jacobi(n, 0);
    Rule {
        points: points.into_iter().map(|t| [t]).collect(),
        weights,
    }
}

/// Rule on the reference triangle {x >= 0, y >= 0, x + y <= 1} (weights sum to 1/2),
/// exact for every polynomial of total degree <= `degree`; `(degree / 2 + 1)^2` points.
pub fn triangle(degree: usize) -> Rule<2> {
    let n = points_per_direction(degree);
    let (us, wus) = gauss_jacobi(n, 0);
    let (vs, wvs) = gauss_jacobi(n, 1);
    let mut rule = Rule {
        points: Vec::with_capacity(n * n),
        weights: Vec::with_capacity(n * n),
    };
    for (&v, &wv) in vs.iter().zip(&wvs) {
        for (&u, &wu) in us.iter().zip(&wus) {
            rule.points.push([u * (1.0 - v), v]);
            rule.weights.push(wu * wv);
        }
    }
    rule
}

/// Values at `rule`'s points of an orthonormal basis of the polynomials of total degree <=
/// `degree` on the reference triangle, orthonormal in `rule`'s discrete inner product (exact
/// for `rule` of degree >= `2 degree`): `values[q * dim + f]`, `dim = (degree+1)(degree+2)/2`.
/// Built by Gram-Schmidt (twice, for round-off) from the monomials.
pub fn triangle_orthonormal(rule: &Rule<2>, degree: usize) -> Vec<f64> {
    let points = rule.points.len();
    let mut columns: Vec<Vec<f64>> = Vec::new();
    for total in 0..=degree {
        for b in 0..=total {
            let mut column: Vec<f64> = rule
                .points
                .iter()
                .map(|p| p[0].powi((total - b) as i32) * p[1].powi(b as i32))
                .collect();
            for _ in 0..2 {
                for done in &columns {
                    let dot: f64 = (0..points)
                        .map(|q| rule.weights[q] * column[q] * done[q])
                        .sum();
                    for (c, d) in column.iter_mut().zip(done) {
                        *c -= dot * d;
                    }
                }
            }
            let norm = (0..points)
                .map(|q| rule.weights[q] * column[q] * column[q])
                .sum::<f64>()
                .sqrt();
            column.iter_mut().for_each(|c| *c /= norm);
            columns.push(column);
        }
    }
    let dim = columns.len();
    let mut values = vec![0.0; points * dim];
    for (f, column) in columns.iter().enumerate() {
        for (q, &v) in column.iter().enumerate() {
            values[q * dim + f] = v;
        }
    }
    values
}

/// Rule on the reference tetrahedron {x, y, z >= 0, x + y + z <= 1} (weights sum to 1/6),
/// exact for every polynomial of total degree <= `degree`; `(degree / 2 + 1)^3` points.
pub fn tetrahedron(degree: usize) -> Rule<3> {
    let n = points_per_direction(degree);
    let (us, wus) = gauss_jacobi(n, 0);
    let (vs, wvs) = gauss_jacobi(n, 1);
    let (ws, wws) = gauss_jacobi(n, 2);
    let mut rule = Rule {
        points: Vec::with_capacity(n * n * n),
        weights: Vec::with_capacity(n * n * n),
    };
    for (&w, &ww) in ws.iter().zip(&wws) {
        for (&v, &wv) in vs.iter().zip(&wvs) {
            for (&u, &wu) in us.iter().zip(&wus) {
                rule.points
                    .push([u * (1.0 - v) * (1.0 - w), v * (1.0 - w), w]);
                rule.weights.push(wu * wv * ww);
            }
        }
    }
    rule
}

/// Gauss points per direction for a collapsed rule exact to total degree `degree`: each 1D
/// factor (with its Jacobi weight) is a polynomial of degree <= `degree`.
fn points_per_direction(degree: usize) -> usize {
    degree / 2 + 1
}

/// Gauss–Jacobi rule with `n >= 1` points on [0, 1] for the weight `(1 - t)^alpha`: increasing
/// points in (0, 1) and positive weights, exact for degree `2n - 1`.
fn gauss_jacobi(n: usize, alpha: u32) -> (Vec<f64>, Vec<f64>) {
    assert!(n >= 1, "a Gauss rule needs at least one point");
    let a = f64::from(alpha);
    // Roots of P_n^(alpha, 0) on [-1, 1], by Newton's method with deflation of the roots
    // already found. The deflated function is a polynomial with only real roots, so Newton
    // converges from any start; Chebyshev nodes are close starts.
    let mut roots: Vec<f64> = Vec::with_capacity(n);
    for k in 0..n {
        let mut x = -(std::f64::consts::PI * (2 * k + 1) as f64 / (2 * n) as f64).cos();
        for _ in 0..100 {
            let (p, dp) = jacobi(n, a, x);
            let deflation: f64 = roots.iter().map(|r| 1.0 / (x - r)).sum();
            let dx = p / (dp - p * deflation);
            x -= dx;
            if dx.abs() <= 4.0 * f64::EPSILON {
                break;
            }
        }
        // One plain Newton step to polish to full precision.
        let (p, dp) = jacobi(n, a, x);
        x -= p / dp;
        roots.push(x);
    }
    roots.sort_by(f64::total_cmp);
    // On [-1, 1] with weight (1 - x)^alpha the weights are 2^(alpha+1) / ((1 - x^2) P_n'(x)^2);
    // mapping to [0, 1] divides them by 2^(alpha+1).
    let weights = roots
        .iter()
        .map(|&x| {
            let (_, dp) = jacobi(n, a, x);
            1.0 / ((1.0 - x) * (1.0 + x) * dp * dp)
        })
        .collect();
    let points = roots.iter().map(|&x| 0.5 * (1.0 + x)).collect();
    (points, weights)
}

/// Jacobi polynomial `P_n^(alpha, 0)(x)` and its derivative, by the three-term recurrence.
fn jacobi(n: usize, alpha: f64, x: f64) -> (f64, f64) {
    let (mut p0, mut d0) = (1.0, 0.0);
    if n == 0 {
        return (p0, d0);
    }
    let (mut p1, mut d1) = (0.5 * ((alpha + 2.0) * x + alpha), 0.5 * (alpha + 2.0));
    for m in 2..=n {
        let m = m as f64;
        let s = 2.0 * m + alpha;
        let denominator = 2.0 * m * (m + alpha) * (s - 2.0);
        let b = (s - 1.0) * s * (s - 2.0);
        let c = (s - 1.0) * alpha * alpha;
        let e = 2.0 * (m + alpha - 1.0) * (m - 1.0) * s;
        let p2 = ((b * x + c) * p1 - e * p0) / denominator;
        let d2 = ((b * x + c) * d1 + b * p1 - e * d0) / denominator;
        (p0, d0, p1, d1) = (p1, d1, p2, d2);
    }
    (p1, d1)
}

#[cfg(test)]
mod tests {

    #[test]
    fn triangle_orthonormal_basis_is_orthonormal_and_spans_the_polynomials() {
        for degree in 0..=4 {
            let rule = triangle(2 * degree + 2);
            let dim = (degree + 1) * (degree + 2) / 2;
            let psi = triangle_orthonormal(&rule, degree);
            let inner = |f: &dyn Fn(usize) -> f64, g: &dyn Fn(usize) -> f64| -> f64 {
                (0..rule.points.len())
                    .map(|q| rule.weights[q] * f(q) * g(q))
                    .sum()
            };
            for a in 0..dim {
                for b in 0..dim {
                    let dot = inner(&|q| psi[q * dim + a], &|q| psi[q * dim + b]);
                    let want = if a == b { 1.0 } else { 0.0 };
                    assert!(
                        (dot - want).abs() < 1e-12,
                        "degree {degree}: ({a}, {b}) {dot}"
                    );
                }
            }
            // x^degree + y^degree is reproduced by its projection.
            let f = |q: usize| {
                rule.points[q][0].powi(degree as i32) + rule.points[q][1].powi(degree as i32)
            };
            let coefficients: Vec<f64> =
                (0..dim).map(|a| inner(&f, &|q| psi[q * dim + a])).collect();
            for q in 0..rule.points.len() {
                let projected: f64 = (0..dim).map(|a| coefficients[a] * psi[q * dim + a]).sum();
                assert!((projected - f(q)).abs() < 1e-12, "degree {degree}");
            }
        }
    }

    use super::*;

    fn factorial(n: usize) -> f64 {
        (1..=n).map(|k| k as f64).product()
    }

    fn assert_close(got: f64, want: f64, tol: f64, what: &str) {
        assert!(
            (got - want).abs() <= tol * want.abs(),
            "{what}: got {got:e}, want {want:e}, relative error {:e}",
            (got - want).abs() / want.abs()
        );
    }

    #[test]
    fn gauss_legendre_is_exact_to_degree_2n_minus_1() {
        for n in 1..=20 {
            let rule = gauss_legendre(n);
            assert_eq!(rule.points.len(), n);
            assert!(rule.weights.iter().all(|&w| w > 0.0));
            assert!(rule.points.iter().all(|&[t]| t > 0.0 && t < 1.0));
            assert!(rule.points.windows(2).all(|p| p[0][0] < p[1][0]));
            for k in 0..2 * n {
                let sum: f64 = rule
                    .points
                    .iter()
                    .zip(&rule.weights)
                    .map(|(&[t], w)| w * t.powi(k as i32))
                    .sum();
                assert_close(sum, 1.0 / (k + 1) as f64, 1e-14, &format!("n={n} t^{k}"));
            }
        }
    }

    #[test]
    fn gauss_jacobi_weights_sum_to_weight_integral() {
        for alpha in 0..=2 {
            for n in 1..=20 {
                let (_, weights) = gauss_jacobi(n, alpha);
                let sum: f64 = weights.iter().sum();
                assert_close(sum, 1.0 / f64::from(alpha + 1), 1e-14, "weight sum");
            }
        }
    }

    #[test]
    fn triangle_is_exact_for_monomials() {
        for degree in 0..=14 {
            let rule = triangle(degree);
            let n = degree / 2 + 1;
            assert_eq!(rule.points.len(), n * n);
            assert!(rule.weights.iter().all(|&w| w > 0.0));
            assert!(
                rule.points
                    .iter()
                    .all(|&[x, y]| x > 0.0 && y > 0.0 && x + y < 1.0)
            );
            let sum: f64 = rule.weights.iter().sum();
            assert_close(sum, 0.5, 1e-14, "triangle weight sum");
            for a in 0..=degree {
                for b in 0..=degree - a {
                    let got: f64 = rule
                        .points
                        .iter()
                        .zip(&rule.weights)
                        .map(|(&[x, y], w)| w * x.powi(a as i32) * y.powi(b as i32))
                        .sum();
                    let want = factorial(a) * factorial(b) / factorial(a + b + 2);
                    assert_close(got, want, 1e-14, &format!("degree {degree}: x^{a} y^{b}"));
                }
            }
        }
    }

    #[test]
    fn tetrahedron_is_exact_for_monomials() {
        for degree in 0..=14 {
            let rule = tetrahedron(degree);
            let n = degree / 2 + 1;
            assert_eq!(rule.points.len(), n * n * n);
            assert_eq!(rule.weights.len(), n * n * n);
            assert!(rule.weights.iter().all(|&w| w > 0.0));
            assert!(
                rule.points
                    .iter()
                    .all(|&[x, y, z]| x > 0.0 && y > 0.0 && z > 0.0 && x + y + z < 1.0)
            );
            let sum: f64 = rule.weights.iter().sum();
            assert_close(sum, 1.0 / 6.0, 1e-14, "tetrahedron weight sum");
            for a in 0..=degree {
                for b in 0..=degree - a {
                    for c in 0..=degree - a - b {
                        let got: f64 = rule
                            .points
                            .iter()
                            .zip(&rule.weights)
                            .map(|(&[x, y, z], w)| {
                                w * x.powi(a as i32) * y.powi(b as i32) * z.powi(c as i32)
                            })
                            .sum();
                        let want =
                            factorial(a) * factorial(b) * factorial(c) / factorial(a + b + c + 3);
                        assert_close(
                            got,
                            want,
                            1e-14,
                            &format!("degree {degree}: x^{a} y^{b} z^{c}"),
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn tetrahedron_is_not_exact_one_degree_above() {
        // Degree 3 uses two points per direction; z^4 needs three.
        let rule = tetrahedron(3);
        let got: f64 = rule
            .points
            .iter()
            .zip(&rule.weights)
            .map(|(p, w)| w * p[2].powi(4))
            .sum();
        let want = factorial(4) / factorial(7);
        assert!((got - want).abs() > 1e-6 * want);
    }
}
