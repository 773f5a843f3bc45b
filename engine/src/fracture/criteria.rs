//! Crack propagation (seed 4.3.2) on the space mesh: which vertices are crack tips, which
//! directions a tip extends along under a given stress, and where such a direction meets the
//! opposite edge of the tip's star (the point a crack-aligned split puts a vertex at).
//!
//! A tip extends along the directions where the effective traction (seed 4.10, mixity factor
//! `beta` of the crack's damage law) is a tensile local maximum above the threshold `sigma0_d`,
//! in the forward half of its direction of travel, and at least the shield angle `theta_S` from
//! every crack edge at the tip and from each other (the stronger of two close directions wins).
//! Angles are in radians, counterclockwise from the x axis; stresses in Pa.

use std::f64::consts::PI;

use sdg_mesh::{EdgeId, Mesh, TagId, TriangleId, VertexId, geometry};
use sdg_solver::interface::Law;
use sdg_solver::nucleation::{
    DefectStrengths, Draws, crack_directions, effective_traction, max_effective_traction,
    tensile_maxima, weakest_defect,
};

use crate::config::FractureConfig;

/// The propagation settings of `[fracture]` on the mesh's tags.
#[derive(Clone, Debug, PartialEq)]
pub struct Fracture {
    /// The tag new crack edges take (a damage law starting bonded).
    pub tag: TagId,
    /// Tags of crack edges: `tag` and `[fracture] from`.
    pub cracks: Vec<TagId>,
    /// `sigma0_d`, Pa.
    pub threshold: f64,
    /// `theta_S`, radians.
    pub shield: f64,
    /// Crossings nearer than this fraction of an edge to its end take the edge to that end.
    pub snap: f64,
    /// Where no split may be made, the crack takes an edge within this angle of its
    /// direction, radians.
    pub floor_angle: f64,
    /// The fastest a crack surface tip advances, m/s (infinite: one edge per tent).
    pub max_tip_speed: f64,
    /// Length over which a tip's crack tangent is averaged, m; none: its last edge.
    pub tangent_length: Option<f64>,
    /// Length over which a crack surface tip's criterion averages the stress ahead of it, m
    /// ([`Fracture::averaged_candidates`]); none: the stress at the tip
    /// ([`Fracture::candidates`]).
    pub criterion_length: Option<f64>,
    /// Mixity factor `beta` of the damage law of `tag`.
    pub beta: f64,
    /// Delay `tau` of the damage law of `tag`, s.
    pub delay: f64,
    /// Nucleation from random defects, if configured.
    pub nucleation: Option<Nucleation>,
}

/// Nucleation from random defects (seed 4.3.1, (4.15)-(4.18)).
#[derive(Clone, Debug, PartialEq)]
pub struct Nucleation {
    /// Defects per unit area, 1/m^2.
    pub density: f64,
    pub strengths: DefectStrengths,
    /// Seed of the draws.
    pub seed: u64,
    /// Cracks nucleate on the boundary and on cracks too.
    pub on_surfaces: bool,
}

/// A crack tip: the crack arrives at its vertex travelling in `direction` (radians); `branch`
/// names the crack branch it ends.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Tip {
    pub direction: f64,
    pub branch: u32,
    /// When the crack reached the vertex, s (the front time of the extension that made the
    /// tip; minus infinity for the tips of the initial cracks).
    #[serde(default = "f64_neg_infinity")]
    pub since: f64,
    /// The directions of the tip's last propagation test that the mesh could not take then.
    #[serde(default)]
    pub pending: Option<Pending>,
}

fn f64_neg_infinity() -> f64 {
    f64::NEG_INFINITY
}

/// Directions (radians, unused entries NaN) a tip's propagation test chose when no extension
/// could be made: a split the crack needed was refused, as the front over the crossed triangle
/// was too steep for its thin child ([`sdg_mesh::Pitcher::may_split_at`]). The front's time
/// over that triangle changes as its corners are pitched in turn, so the extension is tried
/// again after each tent of a neighbour of the tip, while the tip stays at `time` (s, its front
/// time at the test); the tip's next tent makes a new test instead.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Pending {
    pub directions: [f64; 2],
    pub time: f64,
}

/// Where a direction from a vertex leaves its star: across the edge `edge` of triangle
/// `triangle` opposite the vertex (its corner `corner`), at `fraction` of the edge from its
/// smaller-id end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    pub triangle: TriangleId,
    pub corner: usize,
    pub edge: EdgeId,
    pub fraction: f64,
}

impl Fracture {
    /// The settings of `config` on `mesh`, whose tag list gains `config.tag` if no edge has it
    /// yet; `law` gives the law of a tag name (validated: `config.tag`'s is a damage law);
    /// `c_r` is the material's Rayleigh speed, m/s.
    pub fn new(
        config: &FractureConfig,
        mesh: &mut Mesh,
        c_r: f64,
        law: impl Fn(&str) -> Law,
    ) -> Self {
        let tag = mesh.add_tag(&config.tag);
        let Law::Damage(damage) = law(&config.tag) else {
            unreachable!("validated: fracture.tag has a damage law")
        };
        let mut cracks = vec![tag];
        cracks.extend(config.from.iter().filter_map(|name| mesh.tag_id(name)));
        Self {
            tag,
            cracks,
            threshold: config.threshold,
            shield: config.shield_angle.to_radians(),
            snap: config.snap,
            floor_angle: config
                .floor_angle
                .map_or(0.5 * config.shield_angle.to_radians(), f64::to_radians),
            max_tip_speed: config.max_tip_speed * c_r,
            tangent_length: config.tangent_length,
            criterion_length: config.criterion_length,
            beta: damage.beta,
            delay: damage.delay,
            nucleation: config
                .defects()
                .expect("validated defects")
                .map(|(density, strengths)| Nucleation {
                    density,
                    strengths,
                    seed: config.seed,
                    on_surfaces: config.surface_nucleation,
                }),
        }
    }

    /// The crack tangent (radians) of the tip a new crack edge from `from` to `to` (m) makes,
    /// when the crack came to `from` with tangent `before` (none at a nucleation): the edge's
    /// direction, or with [`Fracture::tangent_length`] `L` the unit vectors of `before` and of
    /// the edge (length `l`) weighted `exp(-l / L)` and `1 - exp(-l / L)`.
    pub fn tangent(&self, before: Option<f64>, from: [f64; 2], to: [f64; 2]) -> f64 {
        let edge = (to[1] - from[1]).atan2(to[0] - from[0]);
        let (Some(length), Some(before)) = (self.tangent_length, before) else {
            return edge;
        };
        let l = ((to[0] - from[0]).powi(2) + (to[1] - from[1]).powi(2)).sqrt();
        let w = (-l / length).exp();
        let x = w * before.cos() + (1.0 - w) * edge.cos();
        let y = w * before.sin() + (1.0 - w) * edge.sin();
        y.atan2(x)
    }

    /// True when `tip` at vertex `v` may make its edges along `directions` (radians, NaN
    /// entries unused) at time `t` (s): each edge, from `v` to where its direction crosses the
    /// opposite edge, is at most [`Fracture::max_tip_speed`] times the time since the tip
    /// reached `v`.
    pub fn in_time(
        &self,
        mesh: &Mesh,
        v: VertexId,
        tip: Tip,
        directions: [f64; 2],
        t: f64,
    ) -> bool {
        directions.iter().filter(|d| d.is_finite()).all(|&d| {
            crossing(mesh, v, d).is_none_or(|c| {
                let [p, q] = mesh.edges()[c.edge as usize]
                    .vertices
                    .map(|w| mesh.vertex(w));
                let at = [0, 1].map(|k| p[k] + c.fraction * (q[k] - p[k]));
                self.within_reach(tip, t, geometry::distance(mesh.vertex(v), at))
            })
        })
    }

    /// True when `tip` may make an edge of `length` (m) at time `t` (s): at most
    /// [`Fracture::max_tip_speed`] times the time since the tip reached its vertex (always for
    /// the seed's rule and for the initial cracks' tips).
    pub fn within_reach(&self, tip: Tip, t: f64, length: f64) -> bool {
        self.max_tip_speed == f64::INFINITY
            || tip.since == f64::NEG_INFINITY
            || length <= self.max_tip_speed * (t - tip.since)
    }

    /// True when an edge with `tag` is a crack edge.
    pub fn is_crack(&self, tag: Option<TagId>) -> bool {
        tag.is_some_and(|t| self.cracks.contains(&t))
    }

    /// The crack edges at vertex `v`.
    pub fn crack_edges(&self, mesh: &Mesh, v: VertexId) -> Vec<EdgeId> {
        let mut edges: Vec<EdgeId> = vertex_edges(mesh, v)
            .filter(|&e| self.is_crack(mesh.edges()[e as usize].tag))
            .collect();
        edges.sort_unstable();
        edges.dedup();
        edges
    }

    /// The tips of the cracks on `mesh`, per vertex: an interior vertex on exactly one crack
    /// edge, travelling along it; branches numbered in vertex order from 0.
    pub fn initial_tips(&self, mesh: &Mesh) -> Vec<Option<Tip>> {
        let mut branch = 0;
        (0..mesh.vertices().len() as VertexId)
            .map(|v| {
                let edges = self.crack_edges(mesh, v);
                if edges.len() != 1 || on_boundary(mesh, v) {
                    return None;
                }
                let tip = Tip {
                    direction: angle_of(mesh, other_end(mesh, edges[0], v), v),
                    branch,
                    since: f64::NEG_INFINITY,
                    pending: None,
                };
                branch += 1;
                Some(tip)
            })
            .collect()
    }

    /// The directions (radians) `tip` at vertex `v` extends along, unused entries NaN:
    /// [`Fracture::select`] of the [`Fracture::candidates`] of `stress` (runs call the two
    /// apart, to log the candidates).
    #[cfg(test)]
    fn directions(
        &self,
        mesh: &Mesh,
        v: VertexId,
        tip: Tip,
        stress: impl Fn(TriangleId) -> [f64; 3],
    ) -> [f64; 2] {
        self.select(mesh, v, tip, &self.candidates(mesh, v, stress))
    }

    /// The local maxima of the effective traction around vertex `v` above the threshold, with
    /// tensile normal traction, in every direction: `(direction, traction)` in radians and Pa.
    /// `stress(t)` is the in-plane stress `[sxx, syy, sxy]` (Pa) at `v` in star triangle `t`.
    ///
    /// The effective traction along a direction is taken with the stress of the star triangle
    /// that contains it, so that elements beside the crack faces (whose normal stress
    /// vanishes) do not blur the field ahead of the tip: around the tip it is smooth in each
    /// triangle's sector, with jumps at the star's edges. Its local maxima are the tensile
    /// maxima inside a sector ([`tensile_maxima`] on the sector's stress) and the star edges
    /// towards which the traction grows on both sides; a jump alone makes no maximum.
    pub fn candidates(
        &self,
        mesh: &Mesh,
        v: VertexId,
        stress: impl Fn(TriangleId) -> [f64; 3],
    ) -> Vec<(f64, f64)> {
        let sectors = sectors(mesh, v, stress);
        let traction = |sector: &Sector, d: f64| {
            let (eff, normal) = effective_traction(sector.stress, self.beta, d + 0.5 * PI);
            if normal > 0.0 { eff } else { 0.0 }
        };
        let mut found: Vec<(f64, f64)> = Vec::with_capacity(4);
        for sector in &sectors {
            let centre = sector.start + 0.5 * sector.width;
            let window = Some((centre + 0.5 * PI, 0.5 * sector.width));
            let (planes, n) = tensile_maxima(sector.stress, self.beta, window, self.threshold);
            for &th in &planes[..n] {
                let d = th - 0.5 * PI;
                found.push((d, traction(sector, d)));
            }
            // The sector's first edge, with the sector that ends there.
            let edge = sector.start;
            let Some(before) = sectors
                .iter()
                .find(|s| angle_between(s.start + s.width, edge) < 1e-12)
            else {
                continue;
            };
            let (here, back) = (traction(before, edge), traction(sector, edge));
            if here > traction(before, edge - EDGE_STEP)
                && back > traction(sector, edge + EDGE_STEP)
                && here.min(back) > self.threshold
            {
                found.push((edge, here.min(back)));
            }
        }
        found
    }

    /// The directions (radians, unused entries NaN) `tip` at vertex `v` extends along, of the
    /// local maxima `candidates` (`(direction, traction)`, radians and Pa): those in the forward
    /// half of its direction of travel and at least the shield angle from every crack edge at
    /// `v`, the strongest first; a weaker one within the shield angle of a kept one goes.
    pub fn select(
        &self,
        mesh: &Mesh,
        v: VertexId,
        tip: Tip,
        candidates: &[(f64, f64)],
    ) -> [f64; 2] {
        let crack_edges: Vec<f64> = vertex_edges(mesh, v)
            .filter(|&e| self.is_crack(mesh.edges()[e as usize].tag))
            .map(|e| angle_of(mesh, v, other_end(mesh, e, v)))
            .collect();
        let mut found: Vec<(f64, f64)> = candidates
            .iter()
            .copied()
            .filter(|&(d, _)| {
                (d - tip.direction).cos() > 1e-9
                    && crack_edges
                        .iter()
                        .all(|&c| angle_between(d, c) >= self.shield)
            })
            .collect();
        found.sort_by(|p, q| q.1.total_cmp(&p.1).then(p.0.total_cmp(&q.0)));
        let mut out = [f64::NAN; 2];
        let mut kept = 0;
        for (d, _) in found {
            if kept < 2
                && out[..kept]
                    .iter()
                    .all(|&o| angle_between(o, d) >= self.shield)
            {
                out[kept] = d;
                kept += 1;
            }
        }
        out
    }
}

impl Fracture {
    /// True when the crack wanting direction `d` (radians) at `tip` (vertex `v`) may take the
    /// existing edge from `v` to its neighbour `w` instead: it may join `w` ([`Fracture::may_join`])
    /// and the edge lies within `within` (radians) of `d`: half the shield angle where a split
    /// could be made instead, [`Fracture::floor_angle`] where none may.
    pub fn may_take(
        &self,
        mesh: &Mesh,
        (v, tip): (VertexId, Tip),
        d: f64,
        w: VertexId,
        within: f64,
    ) -> bool {
        self.may_join(mesh, v, tip, w) && angle_between(angle_of(mesh, v, w), d) <= within
    }

    /// True when the crack at `tip` (vertex `v`) may run along the existing edge from `v` to
    /// its neighbour `w`: the edge points forward and lies at least the shield angle from every
    /// crack edge at `v`. This is how a tip whose direction runs into another crack joins it
    /// (at an end of the crack edge it meets).
    pub fn may_join(&self, mesh: &Mesh, v: VertexId, tip: Tip, w: VertexId) -> bool {
        let along = angle_of(mesh, v, w);
        (along - tip.direction).cos() > 0.0
            && vertex_edges(mesh, v)
                .filter(|&e| self.is_crack(mesh.edges()[e as usize].tag))
                .all(|e| {
                    angle_between(along, angle_of(mesh, v, other_end(mesh, e, v))) >= self.shield
                })
    }
}

impl Fracture {
    /// True when the edges from `v` to its neighbours `a` and `b` are distinct and at least the
    /// shield angle apart.
    pub fn apart(&self, mesh: &Mesh, v: VertexId, a: VertexId, b: VertexId) -> bool {
        a != b && angle_between(angle_of(mesh, v, a), angle_of(mesh, v, b)) >= self.shield
    }

    /// The directions (radians, unused entries NaN) of a crack nucleating at the top of the
    /// tent pole of vertex `v` that reached `t_new` (s), if one does: the largest effective
    /// traction over orientations and over the star's elements (`stress(t)`, Pa, at the middle
    /// of the pole) reaches the weakest defect in the patch's outflow area (the star's area, seed
    /// 4.4.2, approximation 1): a Poisson number of defects of mean `density * area` with
    /// truncated-normal strengths. The draws are keyed by the run seed, the vertex position and
    /// `t_new` (bits), so they do not depend on vertex numbering or thread scheduling.
    ///
    /// Inside, the crack runs both ways along the plane of that traction. Only with
    /// `on_surfaces` do cracks nucleate anywhere in the closure of the domain, the boundary and
    /// the surfaces of existing cracks included (seed 4.3.2); there a crack runs one way, into
    /// the material where the traction peaked (the direction of the pair closer to the
    /// strongest element's centroid), and only at least the shield angle from every crack and
    /// boundary edge at `v` (a free surface shields as a crack does).
    pub fn nucleates(
        &self,
        mesh: &Mesh,
        v: VertexId,
        t_new: f64,
        stress: impl Fn(TriangleId) -> [f64; 3],
    ) -> Option<[f64; 2]> {
        let n = self.nucleation.as_ref()?;
        // The free surfaces at `v`: its crack and boundary edges (checked before the stresses).
        let surface = |e: &EdgeId| {
            let edge = &mesh.edges()[*e as usize];
            edge.is_boundary() || self.is_crack(edge.tag)
        };
        let on_surface = vertex_edges(mesh, v).any(|e| surface(&e));
        if !n.on_surfaces && on_surface {
            return None;
        }
        let star = mesh.vertex_triangles(v);
        let (strongest_triangle, th, strongest) = star
            .iter()
            .map(|&t| {
                let (th, s) = max_effective_traction(stress(t), self.beta);
                (t, th, s)
            })
            .max_by(|a, b| a.2.total_cmp(&b.2).then(b.1.total_cmp(&a.1)))?;
        // No defect is weaker than the truncation point.
        if strongest <= n.strengths.lower {
            return None;
        }
        let area = star.iter().map(|&t| mesh.area(t)).sum::<f64>();
        let [x, y] = mesh.vertex(v);
        let mut draws = Draws::new(n.seed, [x.to_bits(), y.to_bits(), t_new.to_bits()]);
        let weakest = weakest_defect(n.density, area, &n.strengths, &mut draws)?;
        if strongest < weakest {
            return None;
        }
        let both = crack_directions(th);
        let directions = if on_surface {
            let corners = mesh.triangles()[strongest_triangle as usize].map(|w| mesh.vertex(w));
            let [cx, cy] = [0, 1].map(|i| corners.iter().map(|p| p[i]).sum::<f64>() / 3.0);
            let towards = (cy - y).atan2(cx - x);
            let d = if angle_between(both[0], towards) <= angle_between(both[1], towards) {
                both[0]
            } else {
                both[1]
            };
            let clear = vertex_edges(mesh, v)
                .filter(surface)
                .all(|e| angle_between(d, angle_of(mesh, v, other_end(mesh, e, v))) >= self.shield);
            if !clear || crossing(mesh, v, d).is_none() {
                return None;
            }
            [d, f64::NAN]
        } else {
            both
        };
        tracing::debug!(
            vertex = v,
            x,
            y,
            t = t_new,
            traction = strongest * 1e-6,
            defect = weakest * 1e-6,
            "nucleation test (MPa)"
        );
        Some(directions)
    }
}

/// Angle (radians) by which the traction beside a star edge is compared with its value on the
/// edge, to tell whether it grows towards the edge.
const EDGE_STEP: f64 = 1e-6;

/// The angular sector of a star triangle at its vertex, with the stress in it.
struct Sector {
    /// Direction of the sector's first edge (radians) and its counterclockwise width.
    start: f64,
    width: f64,
    stress: [f64; 3],
}

/// The sectors of the star triangles of `v`.
fn sectors(mesh: &Mesh, v: VertexId, stress: impl Fn(TriangleId) -> [f64; 3]) -> Vec<Sector> {
    let x = mesh.vertex(v);
    mesh.vertex_triangles(v)
        .iter()
        .map(|&t| {
            let tri = mesh.triangles()[t as usize];
            let corner = tri.iter().position(|&w| w == v).expect("star triangle");
            let [a, b] = [1, 2].map(|k| {
                let p = mesh.vertex(tri[(corner + k) % 3]);
                (p[1] - x[1]).atan2(p[0] - x[0])
            });
            Sector {
                start: a,
                width: (b - a).rem_euclid(2.0 * PI),
                stress: stress(t),
            }
        })
        .collect()
}

/// The triangle of `v`'s star that the ray from `v` in `direction` (radians) enters, and where
/// it crosses that triangle's edge opposite `v`; `None` when no triangle of the star contains
/// the direction (a boundary vertex pointing out of the domain).
pub fn crossing(mesh: &Mesh, v: VertexId, direction: f64) -> Option<Crossing> {
    let x = mesh.vertex(v);
    let u = [direction.cos(), direction.sin()];
    mesh.vertex_triangles(v).iter().find_map(|&t| {
        let tri = mesh.triangles()[t as usize];
        let corner = tri.iter().position(|&w| w == v)?;
        let (a, b) = (tri[(corner + 1) % 3], tri[(corner + 2) % 3]);
        let [pa, pb] = [a, b].map(|w| mesh.vertex(w));
        let to_a = [pa[0] - x[0], pa[1] - x[1]];
        let to_b = [pb[0] - x[0], pb[1] - x[1]];
        if cross(to_a, u) < 0.0 || cross(u, to_b) < 0.0 {
            return None;
        }
        let w = [pb[0] - pa[0], pb[1] - pa[1]];
        let r = (cross(to_a, u) / cross(u, w)).clamp(0.0, 1.0);
        let edge = mesh.triangle_edges(t)[corner];
        let fraction = if mesh.edges()[edge as usize].vertices[0] == a {
            r
        } else {
            1.0 - r
        };
        Some(Crossing {
            triangle: t,
            corner,
            edge,
            fraction,
        })
    })
}

/// True when vertex `v` is on the boundary of the domain.
pub fn on_boundary(mesh: &Mesh, v: VertexId) -> bool {
    vertex_edges(mesh, v).any(|e| mesh.edges()[e as usize].is_boundary())
}

/// The edges at vertex `v`, an interior one twice.
fn vertex_edges(mesh: &Mesh, v: VertexId) -> impl Iterator<Item = EdgeId> + '_ {
    mesh.vertex_triangles(v).iter().flat_map(move |&t| {
        mesh.triangle_edges(t)
            .into_iter()
            .filter(move |&e| mesh.edges()[e as usize].vertices.contains(&v))
    })
}

/// The end of edge `e` that is not `v`.
fn other_end(mesh: &Mesh, e: EdgeId, v: VertexId) -> VertexId {
    let [p, q] = mesh.edges()[e as usize].vertices;
    if p == v { q } else { p }
}

/// The angle (radians) of the direction from vertex `from` to vertex `to`.
fn angle_of(mesh: &Mesh, from: VertexId, to: VertexId) -> f64 {
    let [a, b] = [from, to].map(|w| mesh.vertex(w));
    (b[1] - a[1]).atan2(b[0] - a[0])
}

/// The angle between two directions, in [0, pi].
fn angle_between(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(2.0 * PI);
    if d > PI { 2.0 * PI - d } else { d }
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// Length (m) of the segment from vertex `a` to vertex `b`.
pub fn distance(mesh: &Mesh, a: VertexId, b: VertexId) -> f64 {
    geometry::distance(mesh.vertex(a), mesh.vertex(b))
}

#[cfg(test)]
pub(crate) mod tests;
