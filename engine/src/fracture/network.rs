//! The crack network at the end of a run and its first macroscopic fork (`summary.json`
//! `fracture.macro_branching`).
//!
//! The crack edges form a graph on the mesh's vertices (cracks that arrest on one another share
//! a vertex, so a chain of nucleated cracks that link up is one path). At a vertex with three or
//! more crack edges, the fork's *core* is every crack vertex closer to it along crack edges than
//! a tenth of `length` ([`CORE`]), and its *arms* are the parts of the rest of the network that
//! hang on the core (two paths that meet again beyond the core are one arm; a microcrack that
//! links them within the core is not). An arm's *reach* is the longest distance along crack
//! edges from the vertex to a point of the arm; its *start* is when the earliest of its edges to
//! the core was made (an extension's time, 0 for initial cracks). The crack came in by the arm
//! that holds an initial crack, or without one by the arm that started first; the vertex is a
//! *macro fork* when at least two of the other arms reach `length`, and it forked when the
//! second of those started. Microbranches, side cracks and the steps of a wavy crack leave arms
//! shorter than `length` and are no macro fork; the seed's "the crack branches at 0.37 mm ahead
//! of the initial crack tip at 2.26 us" is the first macro fork. Times are those of the crack
//! edges, made ahead of the damage that debonds them. The reach counts crack edges whatever
//! their damage; each arm's *open* length is how much of the path of its reach lies on edges
//! at [`OPEN_DAMAGE`] or more, the part that is an open crack.

use std::cmp::Ordering;
use std::collections::{BTreeMap, BinaryHeap};

use serde::Serialize;

use sdg_mesh::VertexId;
use sdg_solver::crack::OPEN_DAMAGE;

/// One crack edge of the network.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CrackLink {
    /// Its end vertices.
    pub(crate) ends: [VertexId; 2],
    /// Its end points, m.
    pub(crate) points: [[f64; 2]; 2],
    /// When it was made, s (0 for initial cracks).
    pub(crate) time: f64,
    /// It belongs to an initial crack.
    pub(crate) initial: bool,
    /// Its damage on the front, in [0, 1].
    pub(crate) damage: f64,
}

/// The first macroscopic fork of the crack network.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MacroFork {
    /// When its second long arm started, s.
    pub time: f64,
    /// Where, m.
    pub point: [f64; 2],
    /// Distance from the nearest tip of the initial cracks, m; none without initial cracks.
    pub distance: Option<f64>,
    /// Reach of each arm other than the incoming one that reaches the macro length, longest
    /// first, m.
    pub arms: Vec<f64>,
    /// Per arm of `arms`, the length of the path of its reach (the shortest along crack edges
    /// from the fork to the arm's farthest point) that lies on open edges (damage at least
    /// [`OPEN_DAMAGE`]), m.
    pub open_arms: Vec<f64>,
    /// Angle between the two longest of `arms`, degrees in [0, 180]: each arm's direction is
    /// from the fork to the point where the path of its reach is `length` long along crack
    /// edges, so that it measures the fork at the scale it is defined on.
    pub angle: f64,
}

/// A vertex's neighbour along a crack edge, with the edge's length (m), time (s) and damage.
type Neighbour = (VertexId, f64, f64, f64);

/// Per vertex of the network: its neighbours, its position (m) and whether an initial crack's
/// edge ends there.
type Graph = BTreeMap<VertexId, (Vec<Neighbour>, [f64; 2], bool)>;

/// The first macro fork of the network of `links` whose forward arms reach `length` (m): the
/// earliest to fork, the nearest to `initial_tips` (m) among those of equal time.
pub(crate) fn first_macro_fork(
    links: &[CrackLink],
    length: f64,
    initial_tips: &[[f64; 2]],
) -> Option<MacroFork> {
    let mut graph = Graph::new();
    for link in links {
        let length = distance(link.points[0], link.points[1]);
        for (i, &v) in link.ends.iter().enumerate() {
            let entry = graph
                .entry(v)
                .or_insert_with(|| (Vec::new(), link.points[i], false));
            entry
                .0
                .push((link.ends[1 - i], length, link.time, link.damage));
            entry.2 |= link.initial;
        }
    }
    let mut best: Option<MacroFork> = None;
    for (&v, (neighbours, point, _)) in &graph {
        if neighbours.len() < 3 {
            continue;
        }
        let Some((time, arms, open_arms, angle)) = fork_at(&graph, v, length) else {
            continue;
        };
        let candidate = MacroFork {
            time,
            point: *point,
            distance: initial_tips
                .iter()
                .map(|&tip| distance(tip, *point))
                .min_by(f64::total_cmp),
            arms,
            open_arms,
            angle,
        };
        let earlier = |a: &MacroFork, b: &MacroFork| {
            a.time.total_cmp(&b.time).then(
                a.distance
                    .unwrap_or(0.0)
                    .total_cmp(&b.distance.unwrap_or(0.0)),
            ) == Ordering::Less
        };
        if best.as_ref().is_none_or(|b| earlier(&candidate, b)) {
            best = Some(candidate);
        }
    }
    best
}

/// The radius of a fork's core as a fraction of the macro length: crack vertices closer to the
/// fork than this along crack edges belong to it, so that a small loop there (a microcrack
/// that links two cracks just past the fork) does not merge the arms it joins.
const CORE: f64 = 0.1;

/// A fork's time (s), the reaches of its long forward arms (m), longest first, their open
/// lengths (m) and the angle between the two longest (degrees).
type ForkArms = (f64, Vec<f64>, Vec<f64>, f64);

/// When `v` is a macro fork for `length` (m), its [`ForkArms`]. The arms are the parts of the
/// network outside the fork's core that hang on it; an arm starts with the earliest of its
/// edges to the core.
fn fork_at(graph: &Graph, v: VertexId, length: f64) -> Option<ForkArms> {
    let (distances, previous) = distances_from(graph, v);
    let in_core = |u: VertexId| distances[&u] < CORE * length;
    let core: Vec<VertexId> = distances.keys().copied().filter(|&u| in_core(u)).collect();
    let mut arm_of: BTreeMap<VertexId, usize> = BTreeMap::new();
    // (holds an initial crack, start, reach, farthest vertex) of each arm.
    let mut arms: Vec<(bool, f64, f64, VertexId)> = Vec::new();
    for &c in &core {
        for &(first, _, time, _) in &graph[&c].0 {
            if in_core(first) {
                continue;
            }
            if !arm_of.contains_key(&first) {
                let arm = arms.len();
                let (mut reach, mut farthest, mut initial) = (0.0f64, first, false);
                let mut stack = vec![first];
                arm_of.insert(first, arm);
                while let Some(u) = stack.pop() {
                    let d = distances[&u];
                    if d > reach || (d == reach && u < farthest) {
                        (reach, farthest) = (d, u);
                    }
                    initial |= graph[&u].2;
                    for &(w, _, _, _) in &graph[&u].0 {
                        if !in_core(w) && !arm_of.contains_key(&w) {
                            arm_of.insert(w, arm);
                            stack.push(w);
                        }
                    }
                }
                arms.push((initial, f64::INFINITY, reach, farthest));
            }
            let start = &mut arms[arm_of[&first]].1;
            *start = start.min(time);
        }
    }
    // The incoming arm first: one that holds an initial crack, else the first to start.
    arms.sort_by(|a, b| {
        b.0.cmp(&a.0)
            .then(a.1.total_cmp(&b.1))
            .then(b.2.total_cmp(&a.2))
    });
    // (start, reach, open length, direction) of the long forward arms.
    let origin = graph[&v].1;
    let mut long: Vec<(f64, f64, f64, [f64; 2])> = arms
        .into_iter()
        .skip(1)
        .filter(|a| a.2 >= length)
        .map(|a| {
            let at = point_at(graph, &previous, &distances, a.3, length);
            (
                a.1,
                a.2,
                open_length(&previous, a.3),
                [at[0] - origin[0], at[1] - origin[1]],
            )
        })
        .collect();
    long.sort_by(|a, b| a.0.total_cmp(&b.0));
    if long.len() < 2 {
        return None;
    }
    let time = long[1].0;
    long.sort_by(|a, b| b.1.total_cmp(&a.1));
    let [a, b] = [long[0].3, long[1].3];
    let angle = (a[0] * b[1] - a[1] * b[0])
        .abs()
        .atan2(a[0] * b[0] + a[1] * b[1])
        .to_degrees();
    Some((
        time,
        long.iter().map(|a| a.1).collect(),
        long.iter().map(|a| a.2).collect(),
        angle,
    ))
}

/// The point (m) at `length` (m) along the shortest path that `previous` records from the fork
/// to `end`, whose distance from the fork is at least `length`; linear along the edge it lies on.
fn point_at(
    graph: &Graph,
    previous: &Previous,
    distances: &BTreeMap<VertexId, f64>,
    mut end: VertexId,
    length: f64,
) -> [f64; 2] {
    while let Some(&(from, edge, _)) = previous.get(&end) {
        let near = distances[&from];
        if near <= length {
            let s = if edge > 0.0 {
                (length - near) / edge
            } else {
                0.0
            };
            let [p, q] = [graph[&from].1, graph[&end].1];
            return [p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1])];
        }
        end = from;
    }
    graph[&end].1
}

/// Per vertex reached, the previous vertex on its shortest path and the length (m) and damage
/// of the edge from there.
type Previous = BTreeMap<VertexId, (VertexId, f64, f64)>;

/// Distances (m) along crack edges from `v` to every vertex of its part of the network, and the
/// shortest paths' [`Previous`].
fn distances_from(graph: &Graph, v: VertexId) -> (BTreeMap<VertexId, f64>, Previous) {
    let mut best: BTreeMap<VertexId, f64> = BTreeMap::from([(v, 0.0)]);
    let mut previous = Previous::new();
    let mut queue = BinaryHeap::from([Nearest(0.0, v)]);
    while let Some(Nearest(d, u)) = queue.pop() {
        if d > best[&u] {
            continue;
        }
        for &(w, edge, _, damage) in &graph[&u].0 {
            let next = d + edge;
            if best.get(&w).is_none_or(|&old| next < old) {
                best.insert(w, next);
                previous.insert(w, (u, edge, damage));
                queue.push(Nearest(next, w));
            }
        }
    }
    (best, previous)
}

/// The length (m) of the open edges on the shortest path to `u` that `previous` records.
fn open_length(previous: &Previous, mut u: VertexId) -> f64 {
    let mut open = 0.0;
    while let Some(&(from, edge, damage)) = previous.get(&u) {
        if damage >= OPEN_DAMAGE {
            open += edge;
        }
        u = from;
    }
    open
}

/// A queue entry of Dijkstra's search, nearest first.
#[derive(PartialEq)]
struct Nearest(f64, VertexId);

impl Eq for Nearest {}

impl Ord for Nearest {
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
    }
}

impl PartialOrd for Nearest {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Links along the points `path` (vertex ids from `first`), each made at `time`.
    fn path(first: VertexId, points: &[[f64; 2]], times: &[f64]) -> Vec<CrackLink> {
        points
            .windows(2)
            .enumerate()
            .map(|(i, w)| CrackLink {
                ends: [first + i as VertexId, first + i as VertexId + 1],
                points: [w[0], w[1]],
                time: times[i],
                initial: times[i] == 0.0,
                damage: 1.0,
            })
            .collect()
    }

    /// A notch from (0, 0) to the fork at (1, 0) made at t = 0, and two arms from the fork
    /// (vertex 1): up to (2, 1) in two edges from t = 1, down to (1.5, -0.5) from t = 2.
    fn y_network() -> Vec<CrackLink> {
        let mut links = path(0, &[[0.0, 0.0], [1.0, 0.0]], &[0.0]);
        links.push(CrackLink {
            ends: [1, 2],
            points: [[1.0, 0.0], [1.5, 0.5]],
            time: 1.0,
            initial: false,
            damage: 1.0,
        });
        links.push(CrackLink {
            ends: [2, 3],
            points: [[1.5, 0.5], [2.0, 1.0]],
            time: 1.5,
            initial: false,
            damage: 1.0,
        });
        links.push(CrackLink {
            ends: [1, 4],
            points: [[1.0, 0.0], [1.5, -0.5]],
            time: 2.0,
            initial: false,
            damage: 1.0,
        });
        links
    }

    #[test]
    fn a_fork_with_two_long_arms_is_a_macro_fork_from_its_second_arm_s_start() {
        let (up, down) = (2f64.sqrt(), 0.5 * 2f64.sqrt());
        let fork = first_macro_fork(&y_network(), 0.7, &[[0.5, 0.0]]).unwrap();
        assert_eq!(fork.time, 2.0);
        assert_eq!(fork.point, [1.0, 0.0]);
        assert_eq!(fork.distance, Some(0.5));
        assert_eq!(fork.arms.len(), 2);
        assert!((fork.arms[0] - up).abs() < 1e-15 && (fork.arms[1] - down).abs() < 1e-15);
        assert!((fork.angle - 90.0).abs() < 1e-12, "{}", fork.angle);
        // An arm shorter than the length is a side branch: no macro fork.
        assert_eq!(first_macro_fork(&y_network(), 0.8, &[]), None);
    }

    #[test]
    fn an_arm_s_direction_is_that_of_its_point_at_the_length() {
        // The notch into (1, 0); one arm up to (1, 1) and on right to (3, 1), one down to
        // (1, -3). At length 2 the upper arm's point is (2, 1): 45 degrees up, 135 from the
        // lower arm.
        let mut links = path(0, &[[0.0, 0.0], [1.0, 0.0]], &[0.0]);
        for (ends, points) in [
            ([1, 2], [[1.0, 0.0], [1.0, 1.0]]),
            ([2, 3], [[1.0, 1.0], [3.0, 1.0]]),
            ([1, 4], [[1.0, 0.0], [1.0, -3.0]]),
        ] {
            links.push(CrackLink {
                ends,
                points,
                time: 1.0,
                initial: false,
                damage: 1.0,
            });
        }
        let fork = first_macro_fork(&links, 2.0, &[]).unwrap();
        assert!((fork.angle - 135.0).abs() < 1e-12, "{}", fork.angle);
        // At length 1 the upper arm's point is (1, 1): straight up, opposite the lower arm.
        let fork = first_macro_fork(&links, 1.0, &[]).unwrap();
        assert!((fork.angle - 180.0).abs() < 1e-12, "{}", fork.angle);
    }

    #[test]
    fn without_an_initial_crack_the_arm_that_started_first_is_the_incoming_one() {
        // The same network without a notch: the crack came in from the upper arm (t = 1), and
        // the fork's other arms are the lower one (0.71) and the former notch (1.0), made last.
        let mut links = y_network();
        links[0].time = 3.0;
        links[0].initial = false;
        let fork = first_macro_fork(&links, 0.7, &[]).unwrap();
        assert_eq!((fork.time, fork.distance), (3.0, None));
        assert_eq!(fork.arms, vec![1.0, 0.5 * 2f64.sqrt()]);
        // Back along the notch, and down at 45 degrees.
        assert!((fork.angle - 135.0).abs() < 1e-12, "{}", fork.angle);
        // With the notch an initial crack again, it is the incoming arm whenever its edge at
        // the fork was made (here a crack that ran into it later): the fork is as before.
        links[0].initial = true;
        let fork = first_macro_fork(&links, 0.7, &[]).unwrap();
        assert_eq!(fork.time, 2.0);
        assert_eq!(fork.arms.len(), 2);
    }

    #[test]
    fn a_small_loop_at_the_fork_does_not_merge_its_arms() {
        // The notch into (1, 0); two short edges to A = (1.01, 0.01) and B = (1.01, -0.01),
        // linked by a microcrack; long arms from A up to (2, 1) (t = 1) and from B down to
        // (2, -1) (t = 2). A and B lie within the core (a tenth of 0.5) of the fork at (1, 0).
        let mut links = path(0, &[[0.0, 0.0], [1.0, 0.0]], &[0.0]);
        let (a, b) = ([1.01, 0.01], [1.01, -0.01]);
        for (ends, points, time) in [
            ([1, 2], [[1.0, 0.0], a], 1.0),
            ([1, 3], [[1.0, 0.0], b], 2.0),
            ([2, 3], [a, b], 3.0),
            ([2, 4], [a, [2.0, 1.0]], 1.0),
            ([3, 5], [b, [2.0, -1.0]], 2.0),
        ] {
            links.push(CrackLink {
                ends,
                points,
                time,
                initial: false,
                damage: 1.0,
            });
        }
        let fork = first_macro_fork(&links, 0.5, &[[1.0, 0.0]]).unwrap();
        assert_eq!((fork.point, fork.time), ([1.0, 0.0], 2.0));
        assert_eq!(fork.arms.len(), 2);
        assert!(fork.arms.iter().all(|&r| r > 1.4 && r < 1.43), "{fork:?}");
    }

    #[test]
    fn two_edges_of_one_loop_are_one_arm() {
        // A notch into vertex 1 at (1, 0); from there a loop through (2, 1) and (2, -1) that
        // closes at (3, 0), and a long tail on from (3, 0): vertex 1 has three crack edges but
        // only two arms, and (3, 0) has one arm forward.
        let mut links = path(0, &[[0.0, 0.0], [1.0, 0.0]], &[0.0]);
        let loop_points = [[1.0, 0.0], [2.0, 1.0], [3.0, 0.0], [2.0, -1.0], [1.0, 0.0]];
        let ids = [1, 2, 3, 4, 1];
        for (i, w) in loop_points.windows(2).enumerate() {
            links.push(CrackLink {
                ends: [ids[i], ids[i + 1]],
                points: [w[0], w[1]],
                time: 1.0 + i as f64,
                initial: false,
                damage: 1.0,
            });
        }
        links.push(CrackLink {
            ends: [3, 5],
            points: [[3.0, 0.0], [9.0, 0.0]],
            time: 9.0,
            initial: false,
            damage: 1.0,
        });
        assert_eq!(first_macro_fork(&links, 0.5, &[]), None);
    }
}
