//! Where a spacetime element meets a plane of constant time: the polygon it cuts (the slicing
//! rule of the snapshot module); the values on slices and on interface segments.

use sdg_solver::spacetime::cut;

/// Field values at a point of a slice, physical SI units.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PointValues {
    /// Velocity, m/s.
    pub velocity: [f64; 3],
    /// Stress, Pa, in VTK symmetric-tensor order XX, YY, ZZ, XY, YZ, XZ.
    pub stress: [f64; 6],
    /// Displacement, m.
    pub displacement: [f64; 3],
    /// Strain energy density, J/m^3.
    pub strain_energy_density: f64,
}

/// Values on a contact interface at a point of a slice, physical SI units.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InterfaceValues {
    /// Normal separation, m.
    pub delta: f64,
    /// Tangential slip, m.
    pub slip: f64,
    /// Damage `D` in effect (damage law; 0 with other laws).
    pub damage: f64,
    /// Target traction (normal, tangential), Pa.
    pub traction: [f64; 2],
    /// Contact area fraction.
    pub eta: f64,
    /// Mode with the largest area fraction: 0 stick, 1 slip, 2 separation, 3 bonded (damage
    /// law).
    pub mode: f64,
}

/// A slice segment of an interface: ends `(x, y)`, metres, and the values there.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct Segment {
    pub(super) xy: [[f64; 2]; 2],
    pub(super) values: [InterfaceValues; 2],
}

/// A slice triangle: corners `(x, y)` counter-clockwise, metres, and the fields there.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct Triangle {
    pub(super) xy: [[f64; 2]; 3],
    pub(super) values: [PointValues; 3],
}

impl Triangle {
    pub(super) fn area(&self) -> f64 {
        signed_area(self.xy[0], self.xy[1], self.xy[2])
    }
}

/// Which rule of the module docs a slice comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Rule {
    Crossing,
    BottomFace,
}

/// Corners of the slice of one element, counter-clockwise in `(x, y)`; `points[len..]` unused.
#[derive(Clone, Copy, Debug)]
pub(super) struct Corners {
    pub(super) points: [[f64; 3]; 4],
    pub(super) len: usize,
    pub(super) rule: Rule,
}

pub(super) fn slice(v: &[[f64; 3]; 4], tau_s: f64, tol: f64) -> Option<Corners> {
    let side = |p: &[f64; 3]| {
        if p[2] < tau_s - tol {
            -1
        } else if p[2] > tau_s + tol {
            1
        } else {
            0
        }
    };
    let sides = v.each_ref().map(side);
    let below = sides.iter().filter(|&&s| s < 0).count();
    let on = sides.iter().filter(|&&s| s == 0).count();
    let rule = match (below, on) {
        (0, 3) => Rule::BottomFace,
        (0, _) | (4, _) => return None,
        _ => Rule::Crossing,
    };
    let mut points = [[0.0; 3]; 4];
    let mut len = 0;
    let mut push = |p: [f64; 3]| {
        points[len] = p;
        len += 1;
    };
    if below == 2 && on == 0 {
        // Quadrilateral: cut edges in cyclic order b0a0, b0a1, b1a1, b1a0 (consecutive ones share
        // a face of the tetrahedron).
        let (mut b, mut a) = ([0; 2], [0; 2]);
        let (mut nb, mut na) = (0, 0);
        for (i, &s) in sides.iter().enumerate() {
            if s < 0 {
                b[nb] = i;
                nb += 1;
            } else {
                a[na] = i;
                na += 1;
            }
        }
        for (i, j) in [(b[0], a[0]), (b[0], a[1]), (b[1], a[1]), (b[1], a[0])] {
            push(cut(v[i], v[j], tau_s));
        }
    } else {
        for i in 0..4 {
            match sides[i] {
                0 => push(v[i]),
                s if s < 0 => {
                    for j in 0..4 {
                        if sides[j] > 0 {
                            push(cut(v[i], v[j], tau_s));
                        }
                    }
                }
                _ => {}
            }
        }
    }
    if len < 3 {
        return None;
    }
    let xy = |p: [f64; 3]| [p[0], p[1]];
    let twice_area: f64 = (1..len - 1)
        .map(|i| signed_area(xy(points[0]), xy(points[i]), xy(points[i + 1])))
        .sum();
    if twice_area < 0.0 {
        points[..len].reverse();
    }
    Some(Corners { points, len, rule })
}

/// Signed area of the triangle `a, b, c`: positive when counter-clockwise.
pub(super) fn signed_area(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
}
