//! Structured triangulations of a rectangle `[0, width] x [0, height]`.

use std::collections::HashMap;

use crate::geometry::{self, Point};
use crate::mesh::{Mesh, MeshError, TagId, VertexId};

/// How each grid cell is split into two triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Diagonal {
    /// Every cell split along `/` (lower-left to upper-right).
    Right,
    /// Every cell split along `\` (upper-left to lower-right).
    Left,
    /// `/` and `\` alternating like a checkerboard (vertex degrees 4 and 8).
    Alternate,
}

/// A straight segment on grid lines to tag as an interior interface (later a crack or a
/// contact line). Both ends must be grid nodes and the segment horizontal or vertical.
#[derive(Clone, Debug, PartialEq)]
pub struct GridSegment {
    /// One end, metres.
    pub from: Point,
    /// The other end, metres.
    pub to: Point,
    /// Tag name of the interface edges.
    pub tag: String,
}

/// Parameters of a rectangle mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Rectangle {
    /// Extent in x, metres.
    pub width: f64,
    /// Extent in y, metres.
    pub height: f64,
    /// Cells along x.
    pub nx: u32,
    /// Cells along y.
    pub ny: u32,
    /// Cell split pattern.
    pub diagonal: Diagonal,
    /// Interface segments on grid lines; segments may share a tag, and may overlap only where
    /// they share it.
    pub interfaces: Vec<GridSegment>,
    /// Boundary segments on the rectangle's sides that get a tag of their own instead of their
    /// side's (a load on part of a side); they may not overlap.
    pub sides: Vec<GridSegment>,
    /// Random displacement of interior vertices as a fraction of the cell size in each
    /// direction, in `[0, 0.25)`. Vertices on the boundary or an interface do not move.
    pub perturb: f64,
    /// Seed of the perturbation; each vertex's draw depends only on the seed and its id.
    pub seed: u64,
}

/// Why a rectangle cannot be generated; `field` names the offending parameter.
#[derive(Debug, thiserror::Error)]
#[error("{field}: {reason}")]
pub struct RectangleError {
    /// Parameter name (`width`, `nx`, `interfaces[k]` or `sides[k]` for the k-th segment, ...).
    pub field: String,
    /// What is wrong with it.
    pub reason: String,
}

fn invalid(field: impl Into<String>, reason: impl Into<String>) -> RectangleError {
    RectangleError {
        field: field.into(),
        reason: reason.into(),
    }
}

/// The boundary side tags, in tag-id order.
pub const SIDES: [&str; 4] = ["left", "right", "bottom", "top"];

impl Rectangle {
    /// Generates the triangulation. Boundary edges are tagged `left`, `right`, `bottom`, `top`
    /// (tag ids 0 to 3); interface edges get their segment's tag, with ids from 4 in order of
    /// first appearance, and then boundary edges on a side segment get its tag.
    pub fn build(&self) -> Result<Mesh, RectangleError> {
        for (field, value) in [("width", self.width), ("height", self.height)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(invalid(
                    field,
                    format!("must be a positive length, got {value}"),
                ));
            }
        }
        for (field, n) in [("nx", self.nx), ("ny", self.ny)] {
            if n == 0 {
                return Err(invalid(field, "must be at least 1"));
            }
        }
        // Saturating: (2^32)^2 wraps u64 to 0.
        let nodes = (self.nx as u64 + 1).saturating_mul(self.ny as u64 + 1);
        if nodes > u32::MAX as u64 / 8 {
            return Err(invalid("nx", "too many cells for 32-bit indices"));
        }
        if !(0.0..0.25).contains(&self.perturb) {
            return Err(invalid(
                "perturb",
                format!("must be in [0, 0.25), got {}", self.perturb),
            ));
        }
        let (nx, ny) = (self.nx, self.ny);
        let dx = self.width / nx as f64;
        let dy = self.height / ny as f64;
        let id = |i: u32, j: u32| j * (nx + 1) + i;
        let mut vertices = Vec::with_capacity(nodes as usize);
        for j in 0..=ny {
            for i in 0..=nx {
                vertices.push([i as f64 * dx, j as f64 * dy]);
            }
        }
        let mut triangles = Vec::with_capacity(2 * (nx * ny) as usize);
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                let slash = match self.diagonal {
                    Diagonal::Right => true,
                    Diagonal::Left => false,
                    Diagonal::Alternate => (i + j) % 2 == 0,
                };
                if slash {
                    triangles.extend([[a, b, c], [a, c, d]]);
                } else {
                    triangles.extend([[a, b, d], [b, c, d]]);
                }
            }
        }

        let mut tagged: Vec<([VertexId; 2], TagId)> = Vec::new();
        for i in 0..nx {
            tagged.push(([id(i, 0), id(i + 1, 0)], 2));
            tagged.push(([id(i, ny), id(i + 1, ny)], 3));
        }
        for j in 0..ny {
            tagged.push(([id(0, j), id(0, j + 1)], 0));
            tagged.push(([id(nx, j), id(nx, j + 1)], 1));
        }
        let mut tag_names: Vec<String> = SIDES.iter().map(|s| s.to_string()).collect();
        let mut pinned = vec![false; vertices.len()];
        // The tag of each interface edge so far, by its end vertices in increasing order.
        let mut segment_edges: HashMap<[VertexId; 2], TagId> = HashMap::new();
        for (k, seg) in self.interfaces.iter().enumerate() {
            let field = format!("interfaces[{k}]");
            if SIDES.contains(&seg.tag.as_str()) {
                return Err(invalid(field, format!("tag `{}` is a side name", seg.tag)));
            }
            let node = |p: Point| self.grid_node(p, &field);
            let (a, b) = (node(seg.from)?, node(seg.to)?);
            let steps: Vec<(u32, u32)> = if a == b {
                return Err(invalid(field, "the segment has zero length"));
            } else if a.1 == b.1 {
                if a.1 == 0 || a.1 == ny {
                    return Err(invalid(field, "the segment lies on the boundary"));
                }
                (a.0.min(b.0)..=a.0.max(b.0)).map(|i| (i, a.1)).collect()
            } else if a.0 == b.0 {
                if a.0 == 0 || a.0 == nx {
                    return Err(invalid(field, "the segment lies on the boundary"));
                }
                (a.1.min(b.1)..=a.1.max(b.1)).map(|j| (a.0, j)).collect()
            } else {
                return Err(invalid(field, "the segment must be horizontal or vertical"));
            };
            let tag = tag_id(&mut tag_names, &seg.tag);
            for w in steps.windows(2) {
                let ends = [id(w[0].0, w[0].1), id(w[1].0, w[1].1)];
                match segment_edges.get(&ends) {
                    Some(&other) if other != tag => {
                        return Err(invalid(
                            field,
                            format!(
                                "overlaps an earlier segment tagged `{}`",
                                tag_names[other as usize]
                            ),
                        ));
                    }
                    Some(_) => {}
                    None => {
                        segment_edges.insert(ends, tag);
                        tagged.push((ends, tag));
                    }
                }
            }
            for &(i, j) in &steps {
                pinned[id(i, j) as usize] = true;
            }
        }

        self.tag_sides(&mut tagged, &mut tag_names, &id)?;

        if self.perturb > 0.0 {
            for j in 1..ny {
                for i in 1..nx {
                    let v = id(i, j);
                    if !pinned[v as usize] {
                        let p = &mut vertices[v as usize];
                        p[0] += self.perturb * dx * (2.0 * unit_draw(self.seed, v, 0) - 1.0);
                        p[1] += self.perturb * dy * (2.0 * unit_draw(self.seed, v, 1) - 1.0);
                    }
                }
            }
            if let Some(t) = triangles.iter().position(|tri| {
                let p = tri.map(|v| vertices[v as usize]);
                geometry::signed_area2(p[0], p[1], p[2]) <= 0.0
            }) {
                return Err(invalid(
                    "perturb",
                    format!("the perturbation inverts triangle {t}; use a smaller value"),
                ));
            }
        }
        Mesh::new(vertices, triangles, tag_names, &tagged).map_err(|e: MeshError| {
            invalid("mesh", format!("generated an invalid triangulation: {e}"))
        })
    }
}

impl Rectangle {
    /// The grid node `(i, j)` at `p`, m; `field` names the segment in the error.
    fn grid_node(&self, p: Point, field: &str) -> Result<(u32, u32), RectangleError> {
        let (fi, fj) = (
            p[0] * self.nx as f64 / self.width,
            p[1] * self.ny as f64 / self.height,
        );
        let (i, j) = (fi.round(), fj.round());
        let on_grid = (fi - i).abs() < 1e-9 && (fj - j).abs() < 1e-9;
        if !on_grid || i < 0.0 || j < 0.0 || i > self.nx as f64 || j > self.ny as f64 {
            return Err(invalid(
                field,
                format!("end point {p:?} is not a grid node of the rectangle"),
            ));
        }
        Ok((i as u32, j as u32))
    }

    /// Gives the boundary edges of each of [`Self::sides`] its tag (new names get the next
    /// ids). A side segment must lie on one side, and its tag must not be a side's or an
    /// interface's.
    fn tag_sides(
        &self,
        tagged: &mut [([VertexId; 2], TagId)],
        tag_names: &mut Vec<String>,
        id: &impl Fn(u32, u32) -> VertexId,
    ) -> Result<(), RectangleError> {
        let (nx, ny) = (self.nx, self.ny);
        let interface_tags = tag_names.len();
        let mut claimed: HashMap<[VertexId; 2], usize> = HashMap::new();
        for (k, seg) in self.sides.iter().enumerate() {
            let field = format!("sides[{k}]");
            if tag_names[..interface_tags].contains(&seg.tag) {
                return Err(invalid(
                    field,
                    format!("tag `{}` already names a side or an interface", seg.tag),
                ));
            }
            let (a, b) = (
                self.grid_node(seg.from, &field)?,
                self.grid_node(seg.to, &field)?,
            );
            let steps: Vec<(u32, u32)> = if a == b {
                return Err(invalid(field, "the segment has zero length"));
            } else if a.1 == b.1 && (a.1 == 0 || a.1 == ny) {
                (a.0.min(b.0)..=a.0.max(b.0)).map(|i| (i, a.1)).collect()
            } else if a.0 == b.0 && (a.0 == 0 || a.0 == nx) {
                (a.1.min(b.1)..=a.1.max(b.1)).map(|j| (a.0, j)).collect()
            } else {
                return Err(invalid(
                    field,
                    "the segment must lie on one side of the rectangle",
                ));
            };
            let tag = tag_id(tag_names, &seg.tag);
            for w in steps.windows(2) {
                let ends = [id(w[0].0, w[0].1), id(w[1].0, w[1].1)];
                if let Some(other) = claimed.insert(ends, k) {
                    return Err(invalid(field, format!("overlaps sides[{other}]")));
                }
                if let Some(edge) = tagged.iter_mut().find(|(e, _)| *e == ends) {
                    edge.1 = tag;
                }
            }
        }
        Ok(())
    }
}

/// The id of tag `name` in `tag_names`, appended if new.
fn tag_id(tag_names: &mut Vec<String>, name: &str) -> TagId {
    match tag_names.iter().position(|n| n == name) {
        Some(t) => t as TagId,
        None => {
            tag_names.push(name.to_string());
            (tag_names.len() - 1) as TagId
        }
    }
}

/// A uniform draw in `[0, 1)` that depends only on `(seed, vertex, axis)` (SplitMix64).
fn unit_draw(seed: u64, vertex: VertexId, axis: u64) -> f64 {
    fn mix(mut z: u64) -> u64 {
        z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    let bits = mix(seed ^ mix(2 * vertex as u64 + axis));
    (bits >> 11) as f64 / (1u64 << 53) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Found by `tests/fuzz_inputs.rs`: `nx = ny = u32::MAX` wrapped the node count to 0 and
    /// went on to build 2^64 nodes.
    #[test]
    fn the_largest_counts_are_rejected() {
        let r = Rectangle {
            nx: u32::MAX,
            ny: u32::MAX,
            ..rect(Diagonal::Right)
        };
        let e = r.build().unwrap_err();
        assert_eq!(e.field, "nx");
        assert!(e.reason.contains("too many cells"), "{}", e.reason);
    }

    fn rect(diagonal: Diagonal) -> Rectangle {
        Rectangle {
            width: 2.0,
            height: 1.0,
            nx: 4,
            ny: 3,
            diagonal,
            interfaces: Vec::new(),
            sides: Vec::new(),
            perturb: 0.0,
            seed: 1,
        }
    }

    #[test]
    fn counts_and_side_tags() {
        for d in [Diagonal::Right, Diagonal::Left, Diagonal::Alternate] {
            let m = rect(d).build().unwrap();
            assert_eq!(m.vertices().len(), 20);
            assert_eq!(m.triangles().len(), 24);
            let area: f64 = (0..24).map(|t| m.area(t)).sum();
            assert!((area - 2.0).abs() < 1e-12);
            for (tag, count) in [(0, 3), (1, 3), (2, 4), (3, 4)] {
                let n = m.edges().iter().filter(|e| e.tag == Some(tag)).count();
                assert_eq!(n, count, "{d:?} side {}", SIDES[tag as usize]);
                assert!(
                    m.edges()
                        .iter()
                        .filter(|e| e.tag == Some(tag))
                        .all(|e| e.is_boundary())
                );
            }
            assert_eq!(m.edges().iter().filter(|e| e.is_boundary()).count(), 14);
        }
    }

    #[test]
    fn interface_segment_tags_interior_edges() {
        let mut r = rect(Diagonal::Alternate);
        r.interfaces = vec![GridSegment {
            from: [0.0, 2.0 / 3.0],
            to: [1.0, 2.0 / 3.0],
            tag: "crack".into(),
        }];
        r.perturb = 0.2;
        let m = r.build().unwrap();
        let crack = m.tag_id("crack").unwrap();
        let edges: Vec<_> = m.edges().iter().filter(|e| e.tag == Some(crack)).collect();
        assert_eq!(edges.len(), 2);
        assert!(edges.iter().all(|e| e.is_interface()));
        for e in edges {
            for v in e.vertices {
                assert!((m.vertex(v)[1] - 2.0 / 3.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn side_segments_retag_parts_of_sides() {
        let seg = |from, to, tag: &str| GridSegment {
            from,
            to,
            tag: tag.into(),
        };
        let mut r = rect(Diagonal::Alternate);
        r.interfaces = vec![seg([0.0, 1.0 / 3.0], [2.0, 1.0 / 3.0], "crack")];
        // The upper two thirds of the left side and the lower third of the right side.
        r.sides = vec![
            seg([0.0, 1.0 / 3.0], [0.0, 1.0], "push"),
            seg([2.0, 0.0], [2.0, 1.0 / 3.0], "pull"),
        ];
        let m = r.build().unwrap();
        assert_eq!(
            m.tag_names(),
            ["left", "right", "bottom", "top", "crack", "push", "pull"]
        );
        let on = |tag: TagId| -> Vec<[f64; 2]> {
            m.edges()
                .iter()
                .filter(|e| e.tag == Some(tag))
                .map(|e| {
                    let [a, b] = e.vertices.map(|v| m.vertex(v));
                    [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])]
                })
                .collect()
        };
        assert_eq!(on(0), [[0.0, 1.0 / 6.0]]);
        assert_eq!(on(1).len(), 2);
        assert!(on(1).iter().all(|p| p[1] > 1.0 / 3.0));
        assert_eq!(on(5).len(), 2);
        assert!(on(5).iter().all(|p| p[0] == 0.0 && p[1] > 1.0 / 3.0));
        assert_eq!(on(6), [[2.0, 1.0 / 6.0]]);
        assert!(
            m.edges()
                .iter()
                .filter(|e| e.tag >= Some(5))
                .all(|e| e.is_boundary())
        );

        let fails = |sides: Vec<GridSegment>| {
            let e = Rectangle { sides, ..r.clone() }.build().unwrap_err();
            (e.field, e.reason)
        };
        let (field, reason) = fails(vec![seg([0.5, 0.0], [0.5, 1.0], "x")]);
        assert_eq!(field, "sides[0]");
        assert!(reason.contains("one side"), "{reason}");
        let (field, reason) = fails(vec![seg([0.0, 0.0], [0.0, 1.0], "crack")]);
        assert_eq!(field, "sides[0]");
        assert!(reason.contains("`crack`"), "{reason}");
        let (field, reason) = fails(vec![
            seg([0.0, 0.0], [0.0, 2.0 / 3.0], "a"),
            seg([0.0, 1.0 / 3.0], [0.0, 1.0], "b"),
        ]);
        assert_eq!(field, "sides[1]");
        assert!(reason.contains("overlaps sides[0]"), "{reason}");
    }

    #[test]
    fn several_segments_share_or_add_tags() {
        let seg = |from, to, tag: &str| GridSegment {
            from,
            to,
            tag: tag.into(),
        };
        let mut r = rect(Diagonal::Alternate);
        r.interfaces = vec![
            seg([0.0, 1.0 / 3.0], [1.0, 1.0 / 3.0], "crack"),
            seg([1.5, 0.0], [1.5, 1.0], "joint"),
            // Shares its tag and one edge with the first segment.
            seg([0.5, 1.0 / 3.0], [2.0, 1.0 / 3.0], "crack"),
        ];
        let m = r.build().unwrap();
        assert_eq!(
            m.tag_names(),
            ["left", "right", "bottom", "top", "crack", "joint"]
        );
        let count = |tag: TagId| m.edges().iter().filter(|e| e.tag == Some(tag)).count();
        assert_eq!(
            count(4),
            4,
            "the union of both crack segments: one grid line"
        );
        assert_eq!(count(5), 3);
        assert!(
            m.edges()
                .iter()
                .all(|e| e.tag.unwrap_or(0) < 4 || e.is_interface())
        );

        r.interfaces[2].tag = "other".into();
        let e = r.build().unwrap_err();
        assert_eq!(e.field, "interfaces[2]");
        assert!(e.reason.contains("`crack`"), "{e}");
    }

    #[test]
    fn rejects_bad_parameters() {
        let field = |r: Rectangle| r.build().unwrap_err().field;
        assert_eq!(
            field(Rectangle {
                nx: 0,
                ..rect(Diagonal::Right)
            }),
            "nx"
        );
        assert_eq!(
            field(Rectangle {
                width: -1.0,
                ..rect(Diagonal::Right)
            }),
            "width"
        );
        assert_eq!(
            field(Rectangle {
                perturb: 0.3,
                ..rect(Diagonal::Right)
            }),
            "perturb"
        );
        let seg = |from, to| Rectangle {
            interfaces: vec![
                GridSegment {
                    from: [0.0, 1.0 / 3.0],
                    to: [0.5, 1.0 / 3.0],
                    tag: "c".into(),
                },
                GridSegment {
                    from,
                    to,
                    tag: "c".into(),
                },
            ],
            ..rect(Diagonal::Right)
        };
        assert_eq!(field(seg([0.0, 0.1], [1.0, 0.1])), "interfaces[1]");
        assert_eq!(field(seg([0.0, 0.0], [1.0, 0.0])), "interfaces[1]");
        assert_eq!(
            field(seg([0.0, 1.0 / 3.0], [1.0, 2.0 / 3.0])),
            "interfaces[1]"
        );
        assert_eq!(field(seg([0.5, 0.0], [0.5, 0.0])), "interfaces[1]");
        let mut side = seg([1.0, 0.0], [1.0, 1.0]);
        side.interfaces[1].tag = "top".into();
        assert_eq!(field(side), "interfaces[1]");
    }

    #[test]
    fn perturbation_is_deterministic_and_keeps_sides_straight() {
        let mut r = rect(Diagonal::Right);
        r.perturb = 0.2;
        let a = r.build().unwrap();
        let b = r.build().unwrap();
        assert_eq!(a.vertices(), b.vertices());
        let moved = a
            .vertices()
            .iter()
            .zip(rect(Diagonal::Right).build().unwrap().vertices())
            .filter(|(p, q)| p != q)
            .count();
        assert_eq!(moved, 3 * 2);
    }
}
