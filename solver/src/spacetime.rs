//! Points of scaled spacetime, shared by elements and interface faces, and where edges and
//! faces meet a plane of constant time.

/// A point `(x, y, tau)` in scaled spacetime, metres.
pub type SpacePoint = [f64; 3];

/// The point of the edge from `below` to `above` at `tau = tau_s`. Always interpolated from the
/// lower end, so the elements sharing an edge get the same point to the last bit.
pub fn cut(below: SpacePoint, above: SpacePoint, tau_s: f64) -> SpacePoint {
    let w = (tau_s - below[2]) / (above[2] - below[2]);
    [
        below[0] + w * (above[0] - below[0]),
        below[1] + w * (above[1] - below[1]),
        tau_s,
    ]
}

/// The cut of the triangle `corners` (a vertical interface face) by the plane `tau = tau_s`:
/// its two ends, or `None` when the plane misses the triangle or touches it in a point.
pub fn cut_face(corners: [SpacePoint; 3], tau_s: f64) -> Option<[SpacePoint; 2]> {
    let mut ends = [[0.0; 3]; 2];
    let mut count = 0;
    for i in 0..3 {
        let (p, q) = (corners[i], corners[(i + 1) % 3]);
        let on = p[2] == tau_s;
        let crosses = (p[2] - tau_s) * (q[2] - tau_s) < 0.0;
        for point in [on.then_some(p), crosses.then(|| cut(p, q, tau_s))]
            .into_iter()
            .flatten()
        {
            if count < 2 {
                ends[count] = point;
                count += 1;
            }
        }
    }
    let length = (ends[1][0] - ends[0][0]).hypot(ends[1][1] - ends[0][1]);
    (count == 2 && length > 0.0).then_some(ends)
}
