//! The spacetime mesh of pitched tents, recorded for output.

use sdg_mesh::{Front, Mesh, Tent};

use crate::output::{CellType, Field, UnstructuredGrid};

/// Tetrahedra in `(x, y, t)` of all tents pitched so far. Each tent adds one point (its pole
/// top) and one tetrahedron per triangle of its vertex star.
#[derive(Clone, Debug)]
pub struct SpacetimeMesh {
    /// `(x, y, t)` per point: metres, metres, seconds.
    points: Vec<[f64; 3]>,
    /// Point indices per tetrahedron: pole base, the two other corners, pole top.
    tets: Vec<[u32; 4]>,
    /// Index of the tent that made each tetrahedron.
    tent_of_tet: Vec<u32>,
    /// The point at each vertex's current front time.
    current: Vec<u32>,
    tents: u32,
}

impl SpacetimeMesh {
    /// The initial front as points, no tetrahedra yet.
    pub fn new(mesh: &Mesh, front: &Front) -> Self {
        let points = mesh
            .vertices()
            .iter()
            .zip(front.snapshot())
            .map(|(p, t)| [p[0], p[1], t])
            .collect();
        Self {
            points,
            tets: Vec::new(),
            tent_of_tet: Vec::new(),
            current: (0..mesh.vertices().len() as u32).collect(),
            tents: 0,
        }
    }

    /// Records a tent just pitched on `mesh`. Every tetrahedron has positive volume in
    /// `(x, y, t)`: corners `(v, t_old), a, b, (v, t_new)` with `(v, a, b)` counter-clockwise.
    pub fn add_tent(&mut self, mesh: &Mesh, tent: &Tent) {
        let v = tent.vertex;
        let p = mesh.vertex(v);
        let top = self.points.len() as u32;
        self.points.push([p[0], p[1], tent.t_new]);
        let base = self.current[v as usize];
        for &t in mesh.vertex_triangles(v) {
            let tri = mesh.triangles()[t as usize];
            let i = tri
                .iter()
                .position(|&w| w == v)
                .expect("star triangle contains v");
            let a = self.current[tri[(i + 1) % 3] as usize];
            let b = self.current[tri[(i + 2) % 3] as usize];
            self.tets.push([base, a, b, top]);
            self.tent_of_tet.push(self.tents);
        }
        self.current[v as usize] = top;
        self.tents += 1;
    }

    /// Number of tetrahedra.
    pub fn tetrahedra(&self) -> usize {
        self.tets.len()
    }

    /// The mesh as a VTK grid with points `(x, y, start + t)` (metres, metres, seconds): the
    /// run's times on the clock of a run that starts at `start` (s). Point fields: `time` (s)
    /// and `ct`, `c * time` in metres, which a ParaView "Warp By Scalar" turns into a view where
    /// causal cones look like cones; cell field `tent`, the tent index.
    pub fn to_grid(&self, c: f64, start: f64) -> UnstructuredGrid {
        let points: Vec<[f64; 3]> = (self.points.iter())
            .map(|&[x, y, t]| [x, y, start + t])
            .collect();
        UnstructuredGrid {
            cell_type: CellType::Tetra,
            connectivity: self.tets.iter().flatten().copied().collect(),
            point_data: vec![
                Field::scalar("time", points.iter().map(|p| p[2]).collect()),
                Field::scalar("ct", points.iter().map(|p| c * p[2]).collect()),
            ],
            points,
            cell_data: vec![Field::scalar(
                "tent",
                self.tent_of_tet.iter().map(|&t| t as f64).collect(),
            )],
        }
    }

    /// Signed volume of tetrahedron `i` in `(x, y, t)`, m^2 s.
    pub fn volume(&self, i: usize) -> f64 {
        let [p0, p1, p2, p3] = self.tets[i].map(|k| self.points[k as usize]);
        let d = |q: [f64; 3]| [q[0] - p0[0], q[1] - p0[1], q[2] - p0[2]];
        let (a, b, c) = (d(p1), d(p2), d(p3));
        (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0]))
            / 6.0
    }
}
