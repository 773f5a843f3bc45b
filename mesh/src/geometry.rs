//! Planar geometry of points and triangles. Lengths in metres.

/// A point of the plane, `[x, y]` in metres.
pub type Point = [f64; 2];

/// Twice the signed area of triangle `(a, b, c)`: positive when counter-clockwise.
pub fn signed_area2(a: Point, b: Point, c: Point) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// True when a triangle is too flat for a mesh: twice its area is at most `1e-14` times its
/// longest edge squared (its corners are collinear to round-off). [`crate::Mesh::new`] rejects
/// such triangles.
pub fn is_degenerate(p: [Point; 3]) -> bool {
    let scale = (0..3)
        .map(|i| distance(p[i], p[(i + 1) % 3]))
        .fold(0.0, f64::max);
    signed_area2(p[0], p[1], p[2]).abs() <= 1e-14 * scale * scale
}

/// Euclidean distance between two points.
pub fn distance(a: Point, b: Point) -> f64 {
    (b[0] - a[0]).hypot(b[1] - a[1])
}

/// Altitudes of a triangle: entry `i` is the distance from corner `i` to the line through the
/// other two corners.
pub fn altitudes(p: [Point; 3]) -> [f64; 3] {
    let area2 = signed_area2(p[0], p[1], p[2]).abs();
    std::array::from_fn(|i| area2 / distance(p[(i + 1) % 3], p[(i + 2) % 3]))
}

/// Interior angles of a triangle in radians: entry `i` is the angle at corner `i`.
pub fn angles(p: [Point; 3]) -> [f64; 3] {
    std::array::from_fn(|i| {
        let a = p[i];
        let b = p[(i + 1) % 3];
        let c = p[(i + 2) % 3];
        let u = [b[0] - a[0], b[1] - a[1]];
        let w = [c[0] - a[0], c[1] - a[1]];
        let cross = u[0] * w[1] - u[1] * w[0];
        let dot = u[0] * w[0] + u[1] * w[1];
        cross.abs().atan2(dot)
    })
}

/// Gradient of the linear function that takes values `f` at the corners `p` of a
/// non-degenerate triangle. Units: `[f]` per metre.
pub fn linear_gradient(p: [Point; 3], f: [f64; 3]) -> [f64; 2] {
    let e1 = [p[1][0] - p[0][0], p[1][1] - p[0][1]];
    let e2 = [p[2][0] - p[0][0], p[2][1] - p[0][1]];
    let d1 = f[1] - f[0];
    let d2 = f[2] - f[0];
    let det = e1[0] * e2[1] - e1[1] * e2[0];
    [
        (d1 * e2[1] - d2 * e1[1]) / det,
        (e1[0] * d2 - e2[0] * d1) / det,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    const RIGHT: [Point; 3] = [[0.0, 0.0], [2.0, 0.0], [0.0, 1.0]];

    #[test]
    fn area_sign_follows_orientation() {
        assert_eq!(signed_area2(RIGHT[0], RIGHT[1], RIGHT[2]), 2.0);
        assert_eq!(signed_area2(RIGHT[0], RIGHT[2], RIGHT[1]), -2.0);
    }

    #[test]
    fn altitudes_of_right_triangle() {
        let h = altitudes(RIGHT);
        assert!((h[0] - 2.0 / 5f64.sqrt()).abs() < 1e-15);
        assert!((h[1] - 2.0).abs() < 1e-15);
        assert!((h[2] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn angles_sum_to_pi() {
        let a = angles(RIGHT);
        assert!((a[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!((a.iter().sum::<f64>() - std::f64::consts::PI).abs() < 1e-14);
    }

    #[test]
    fn gradient_reproduces_linear_function() {
        let g = [0.3, -1.7];
        let f = RIGHT.map(|q| 4.0 + g[0] * q[0] + g[1] * q[1]);
        let got = linear_gradient(RIGHT, f);
        assert!((got[0] - g[0]).abs() < 1e-14 && (got[1] - g[1]).abs() < 1e-14);
    }
}
