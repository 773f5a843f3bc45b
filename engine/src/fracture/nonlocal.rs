//! The propagation criterion over a length (`fracture.criterion_length`, `L`, m).
//!
//! A crack tip sits in a singular field: the stress at the tip vertex that the point rule
//! ([`Fracture::candidates`]) reads grows like `h^-1/2` with the element size `h`, so where and
//! whether a crack extends depends on the mesh. Here the traction along a direction `theta`
//! from the tip vertex `x0` is instead the effective traction ([`effective_traction`], plane
//! normal `theta + pi/2`, tensile normal only, else 0) of the mean stress along the segment
//! from `x0` to `x0 + L (cos theta, sin theta)`:
//! `sigma_bar(theta) = (1 / l) * integral of sigma over the segment`. The segment stops (length
//! `l <= L`) where it first meets a crack edge ([`Fracture::is_crack`]) or the boundary, at an
//! edge or at a vertex on one; `l = 0` (a direction along a crack edge at the tip, or out of the
//! domain) gives no traction. The mean converges as `h -> 0`; the point rule is its limit
//! `L -> 0`.
//!
//! The integral is exact for the element polynomials: the segment is cut at the triangle edges
//! it crosses (walking from the tip's star through edge- and vertex-adjacent triangles; a
//! segment running along an edge takes the triangle of the smaller id), and each piece takes a
//! Gauss-Legendre rule of `p / 2 + 1` points for stresses of degree `p`.
//!
//! The maxima: the averaged traction is continuous in `theta` (but where the segment's cut
//! length jumps). It is sampled every [`GRID_STEP`] (2.5 degrees) over the forward half-plane
//! of the tip's travel direction and [`MARGIN`] (10 degrees) beyond on either side (only
//! forward directions are ever selected); every sample above the threshold that is at least its
//! left neighbour and above its right one is refined by golden-section search between its two
//! neighbours to [`TOLERANCE`] (1e-5 rad), keeping the sample if the search found less.
//!
//! Nucleation ([`Fracture::nucleates`]) stays a test of the stress at a point: defects are
//! points.

use std::f64::consts::PI;

use sdg_mesh::{Mesh, TriangleId, VertexId, geometry};
use sdg_solver::nucleation::effective_traction;

use super::criteria::Fracture;

/// Spacing of the sampled directions, radians (2.5 degrees).
pub const GRID_STEP: f64 = 2.5 * PI / 180.0;
/// The sampled directions reach this far beyond the forward half-plane on either side, radians
/// (10 degrees).
pub const MARGIN: f64 = 10.0 * PI / 180.0;
/// Width of the bracket at which a maximum's golden-section search stops, radians.
pub const TOLERANCE: f64 = 1e-5;

/// Barycentric coordinates closer than this to 0 put a point on a triangle's edge.
const ON_EDGE: f64 = 1e-9;

impl Fracture {
    /// The local maxima of the traction averaged over `length` (m, > 0) around the tip at
    /// vertex `v` travelling in `travel` (radians), above the threshold, in the forward
    /// half-plane and [`MARGIN`] beyond: `(direction, traction)` in radians and Pa, as
    /// [`Fracture::candidates`] gives them for [`Fracture::select`]. `stress_at(t, x)` is the
    /// in-plane stress `[sxx, syy, sxy]` (Pa) at the point `x` (m) of triangle `t`, a
    /// polynomial of degree `order` (1 to 4) on each triangle. See the module documentation.
    pub fn averaged_candidates(
        &self,
        mesh: &Mesh,
        v: VertexId,
        travel: f64,
        length: f64,
        order: usize,
        stress_at: impl Fn(TriangleId, [f64; 2]) -> [f64; 3],
    ) -> Vec<(f64, f64)> {
        let rule = gauss_legendre(order);
        let traction = |d: f64| {
            self.mean_stress(mesh, v, d, length, rule, &stress_at)
                .map_or(0.0, |stress| {
                    let (eff, normal) = effective_traction(stress, self.beta, d + 0.5 * PI);
                    if normal > 0.0 { eff } else { 0.0 }
                })
        };
        let first = travel - 0.5 * PI - MARGIN;
        let n = ((PI + 2.0 * MARGIN) / GRID_STEP).ceil() as usize;
        let mut samples = [0.0; 128];
        let samples = &mut samples[..=n];
        for (k, s) in samples.iter_mut().enumerate() {
            *s = traction(first + k as f64 * GRID_STEP);
        }
        let mut found = Vec::with_capacity(4);
        for k in 1..n {
            let here = samples[k];
            if !(here > self.threshold && here >= samples[k - 1] && here > samples[k + 1]) {
                continue;
            }
            let at = first + k as f64 * GRID_STEP;
            let (d, s) = golden_section(&traction, at - GRID_STEP, at + GRID_STEP);
            let (d, s) = if s >= here { (d, s) } else { (at, here) };
            found.push((d, s));
        }
        found
    }

    /// The mean in-plane stress (Pa) along the segment from vertex `v` in `direction`
    /// (radians) of length `length` (m), cut where it meets a crack or the boundary; `None`
    /// when the cut segment has no length. `rule` is `(points, weights)` on [0, 1] with its
    /// number of points; `stress_at` as in [`Fracture::averaged_candidates`].
    pub fn mean_stress(
        &self,
        mesh: &Mesh,
        v: VertexId,
        direction: f64,
        length: f64,
        rule: Rule,
        stress_at: impl Fn(TriangleId, [f64; 2]) -> [f64; 3],
    ) -> Option<[f64; 3]> {
        let x0 = mesh.vertex(v);
        let u = [direction.cos(), direction.sin()];
        let along_crack = self.surface_edges(mesh, v, false).any(|w| {
            let p = mesh.vertex(w);
            let angle = (p[1] - x0[1]).atan2(p[0] - x0[0]);
            angle_between(angle, direction) < 1e-9
        });
        if along_crack {
            return None;
        }
        let tol = 1e-9 * length;
        let ray = Ray { x0, u, tol };
        let (points, weights, used) = rule;
        let mut sum = [0.0; 3];
        let mut s = 0.0;
        let mut current = ray.next(mesh, mesh.vertex_triangles(v).iter().copied(), s);
        // Each step crosses a triangle: the walk ends within the mesh's triangles.
        for _ in 0..mesh.triangles().len() {
            let Some((t, s_out)) = current else { break };
            let end = s_out.min(length);
            for (&xi, &w) in points[..used].iter().zip(&weights[..used]) {
                let r = s + xi * (end - s);
                let sigma = stress_at(t, [x0[0] + r * u[0], x0[1] + r * u[1]]);
                for (a, b) in sum.iter_mut().zip(sigma) {
                    *a += w * (end - s) * b;
                }
            }
            s = end;
            if s_out >= length {
                break;
            }
            // Where the segment leaves `t`: across an edge or through a corner.
            let lambda = barycentric(mesh, t, ray.at(s_out));
            let tri = mesh.triangles()[t as usize];
            let on: usize = lambda.iter().filter(|&&l| l < ON_EDGE).count();
            current = if on >= 2 {
                let k = (0..3).max_by(|&i, &j| lambda[i].total_cmp(&lambda[j]))?;
                let w = tri[k];
                if self.surface_edges(mesh, w, true).next().is_some() {
                    break;
                }
                let star = mesh.vertex_triangles(w).iter().copied();
                ray.next(mesh, star.filter(|&o| o != t), s)
            } else {
                let i = (0..3).min_by(|&i, &j| lambda[i].total_cmp(&lambda[j]))?;
                let edge = &mesh.edges()[mesh.triangle_edges(t)[i] as usize];
                if edge.is_boundary() || self.is_crack(edge.tag) {
                    break;
                }
                let across = edge.triangles.into_iter().flatten();
                ray.next(mesh, across.filter(|&o| o != t), s)
            };
        }
        (s > 0.0).then(|| sum.map(|x| x / s))
    }

    /// The far ends of the crack edges at vertex `v`, with `boundary` also of its boundary
    /// edges (an interior edge's end may come twice).
    fn surface_edges<'a>(
        &'a self,
        mesh: &'a Mesh,
        v: VertexId,
        boundary: bool,
    ) -> impl Iterator<Item = VertexId> + 'a {
        mesh.vertex_triangles(v).iter().flat_map(move |&t| {
            mesh.triangle_edges(t).into_iter().filter_map(move |e| {
                let edge = &mesh.edges()[e as usize];
                let [p, q] = edge.vertices;
                let surface = self.is_crack(edge.tag) || (boundary && edge.is_boundary());
                (surface && (p == v || q == v)).then_some(if p == v { q } else { p })
            })
        })
    }
}

/// A Gauss-Legendre rule on [0, 1]: points, weights (summing to 1), and how many are used.
pub type Rule = ([f64; 3], [f64; 3], usize);

/// The Gauss-Legendre rule on [0, 1] exact for polynomials of degree `order` (1 to 4):
/// `order / 2 + 1` points.
pub fn gauss_legendre(order: usize) -> Rule {
    debug_assert!((1..=4).contains(&order), "order {order}");
    match order / 2 + 1 {
        1 => ([0.5, 0.0, 0.0], [1.0, 0.0, 0.0], 1),
        2 => {
            let d = 0.5 / 3f64.sqrt();
            ([0.5 - d, 0.5 + d, 0.0], [0.5, 0.5, 0.0], 2)
        }
        _ => {
            let d = 0.5 * 0.6f64.sqrt();
            let (a, b) = (5.0 / 18.0, 8.0 / 18.0);
            ([0.5 - d, 0.5, 0.5 + d], [a, b, a], 3)
        }
    }
}

/// A ray from `x0` (m) along the unit vector `u`; parameters are distances from `x0`, m.
struct Ray {
    x0: [f64; 2],
    u: [f64; 2],
    /// Parameter differences below this are no progress, m.
    tol: f64,
}

impl Ray {
    fn at(&self, s: f64) -> [f64; 2] {
        [self.x0[0] + s * self.u[0], self.x0[1] + s * self.u[1]]
    }

    /// Of the triangles `candidates`, the one the ray runs through furthest beyond `s` (the
    /// first of equals) with where it leaves it; `None` when the ray enters none beyond `s`.
    fn next(
        &self,
        mesh: &Mesh,
        candidates: impl Iterator<Item = TriangleId>,
        s: f64,
    ) -> Option<(TriangleId, f64)> {
        let mut best: Option<(TriangleId, f64)> = None;
        for t in candidates {
            let Some((s_in, s_out)) = self.interval(mesh, t) else {
                continue;
            };
            if s_in <= s + self.tol
                && s_out > s + self.tol
                && best.is_none_or(|(_, b)| s_out > b + self.tol)
            {
                best = Some((t, s_out));
            }
        }
        best
    }

    /// The parameters between which the ray's line lies in triangle `t`, if it meets it.
    fn interval(&self, mesh: &Mesh, t: TriangleId) -> Option<(f64, f64)> {
        let p = mesh.triangle_points(t);
        let area2 = geometry::signed_area2(p[0], p[1], p[2]);
        let size = (0..3)
            .map(|i| geometry::distance(p[i], p[(i + 1) % 3]))
            .fold(0.0, f64::max);
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for i in 0..3 {
            let (a, b) = (p[(i + 1) % 3], p[(i + 2) % 3]);
            // lambda_i along the ray: l0 + s g.
            let l0 = geometry::signed_area2(self.x0, a, b) / area2;
            let g = cross(self.u, [a[0] - b[0], a[1] - b[1]]) / area2;
            if (g * size).abs() < 1e-12 {
                // Parallel to edge i: inside when on its inner side.
                if l0 < -ON_EDGE {
                    return None;
                }
            } else if g > 0.0 {
                lo = lo.max(-l0 / g);
            } else {
                hi = hi.min(-l0 / g);
            }
        }
        (lo < hi).then_some((lo, hi))
    }
}

/// The barycentric coordinates of the point `x` (m) in triangle `t`.
fn barycentric(mesh: &Mesh, t: TriangleId, x: [f64; 2]) -> [f64; 3] {
    let p = mesh.triangle_points(t);
    let area2 = geometry::signed_area2(p[0], p[1], p[2]);
    [0, 1, 2].map(|i| geometry::signed_area2(x, p[(i + 1) % 3], p[(i + 2) % 3]) / area2)
}

/// The time (s) of the plane through the triangle's corners at times `times` (s), at the point
/// `x` (m) of triangle `t`.
pub fn facet_time(mesh: &Mesh, t: TriangleId, times: [f64; 3], x: [f64; 2]) -> f64 {
    let lambda = barycentric(mesh, t, x);
    (0..3).map(|i| lambda[i] * times[i]).sum()
}

/// The maximum of `f` between `a` and `b` (radians) by golden-section search, to
/// [`TOLERANCE`]: the direction and the value there.
fn golden_section(f: &impl Fn(f64) -> f64, mut a: f64, mut b: f64) -> (f64, f64) {
    let ratio = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = b - ratio * (b - a);
    let mut d = a + ratio * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    while b - a > TOLERANCE {
        if fc >= fd {
            b = d;
            (d, fd) = (c, fc);
            c = b - ratio * (b - a);
            fc = f(c);
        } else {
            a = c;
            (c, fc) = (d, fd);
            d = a + ratio * (b - a);
            fd = f(d);
        }
    }
    let x = 0.5 * (a + b);
    (x, f(x))
}

/// The angle between two directions, in [0, pi].
fn angle_between(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(2.0 * PI);
    if d > PI { 2.0 * PI - d } else { d }
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

#[cfg(test)]
mod tests;
