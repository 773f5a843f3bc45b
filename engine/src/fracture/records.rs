//! The crack records of a run: fracture events, crack edges, their files and pictures, and the
//! statistics of the crack network in `summary.json`.

use super::criteria::Fracture;
use super::network::{self, CrackLink, MacroFork};
use super::tips::{self, TipState};
use crate::config::TimeConfig;
use crate::frontier::Frontier;
use crate::output::table::Table;
use sdg_mesh::{EdgeId, Mesh, TagId};
use sdg_solver::crack::Crossing;
use sdg_solver::element::FrontSolution;
use sdg_solver::face::{FaceBasis, FaceState, STATE_COMPONENTS};
use serde::Serialize;
use std::borrow::Cow;
use std::collections::{BTreeMap, BTreeSet};

/// Scratch size for one element's basis values and fields at a point.
pub(crate) const SCRATCH: usize = 64;

/// One line of `events.csv`.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(crate) struct FractureEvent {
    /// Front time at the tip, s.
    pub(crate) time: f64,
    /// `nucleation`, `extension`, `branching`, `arrest`, `refused` or `coarsening`.
    pub(crate) kind: Cow<'static, str>,
    /// The crack branch; none for a coarsening of an initial crack's edges.
    pub(crate) branch: Option<u32>,
    /// Where it happened and, for an extension, the new edge's far end; for a refused edge,
    /// where it would have ended (the crossing of its direction with the edge opposite the tip,
    /// or the vertex it would have taken), m.
    pub(crate) from: [f64; 2],
    pub(crate) to: [f64; 2],
    /// Why a new edge was refused ([`Refusal::name`]); none for other events.
    #[serde(default)]
    pub(crate) reason: Option<Cow<'static, str>>,
}

/// Why the mesh could not make a new crack edge when its tip was tested.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Refusal {
    /// The direction leaves the domain at the tip (a boundary vertex).
    Outside,
    /// No split of the crossed edge may leave pieces that short (`fracture.min_piece`) and no
    /// end of it lies within `fracture.floor_angle` of the direction under the rules.
    Floor,
    /// The front over the crossed triangle is too steep for the split's thin child now
    /// ([`sdg_mesh::Pitcher::may_split_at`]); it changes as the triangle's corners are pitched.
    Front,
    /// A child of the split would be degenerate (a very flat triangle).
    Degenerate,
    /// The tip's two new edges would be closer than the shield angle.
    Shield,
    /// The closure of the tip's second split split its first new edge.
    Closure,
    /// The edge the mesh would make (to an end of the crossed edge, which may lie farther than
    /// the crossing the test bounded) is longer than `fracture.max_tip_speed` allows since the
    /// tip reached its vertex: the tip waits for its next tent.
    Speed,
}

impl Refusal {
    /// The name in `events.csv` and `summary.json`.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Refusal::Outside => "outside",
            Refusal::Floor => "floor",
            Refusal::Front => "front",
            Refusal::Degenerate => "degenerate",
            Refusal::Shield => "shield",
            Refusal::Closure => "closure",
            Refusal::Speed => "speed",
        }
    }
}

/// `fracture` in `summary.json`.
#[derive(Clone, Debug, Default, Serialize)]
pub struct FractureSummary {
    /// Cracks nucleated from defects.
    pub nucleations: u64,
    /// Crack edges added.
    pub extensions: u64,
    /// Tips that extended along two directions at once.
    pub branchings: u64,
    /// Tips that stopped on a crack or the boundary.
    pub arrests: u64,
    /// New crack edges the mesh could not make when their tip was tested; the tip tries again
    /// after its neighbours' tents.
    pub refused: u64,
    /// `refused` by reason (`events.csv` column `reason`), reasons that occurred only.
    pub refusals: BTreeMap<String, u64>,
    /// Merges of two fully debonded crack edges into one by coarsening (the crack's wake).
    pub wake_coarsenings: u64,
    /// Crack branches: the initial tips, every branching's new one and each half of every
    /// nucleated crack.
    pub branches: u32,
    /// Tips still active at the end.
    pub active_tips: usize,
    /// Length of the crack edges added, m.
    pub total_length: f64,
    /// Time of the first branching, s.
    pub first_branching_time: Option<f64>,
    /// Distance from the nearest tip of the initial cracks to the point of the first
    /// branching, m; none without an initial crack.
    pub first_branching_distance: Option<f64>,
    /// The first fork of the crack network with two arms reaching `fracture.macro_length`
    /// beyond the one the crack came in by (`network`); none without that setting or such a
    /// fork.
    pub macro_branching: Option<MacroFork>,
    /// The same for arms of `fracture.short_macro_length`.
    pub short_macro_branching: Option<MacroFork>,
}

/// `events.csv`: one line per fracture event in the order they happened, at its time on the
/// clock of `time`.
pub(crate) fn events_csv(events: &[FractureEvent], time: &TimeConfig) -> String {
    let mut csv = Table::new([
        "time_s", "event", "branch", "x_m", "y_m", "to_x_m", "to_y_m", "reason",
    ]);
    for e in events {
        csv.row([
            format!("{:e}", time.clock(e.time)),
            e.kind.to_string(),
            e.branch.map_or(String::new(), |b| b.to_string()),
            format!("{:e}", e.from[0]),
            format!("{:e}", e.from[1]),
            format!("{:e}", e.to[0]),
            format!("{:e}", e.to[1]),
            e.reason.as_deref().unwrap_or("").to_string(),
        ]);
    }
    csv.into_text()
}

/// A crack edge at the end of a run.
pub(crate) struct CrackEdge {
    pub(crate) edge: sdg_mesh::EdgeId,
    /// End points, m.
    pub(crate) ends: [[f64; 2]; 2],
    /// Damage on the front, in [0, 1]: the interface state at the top corner of the last face
    /// solved over the edge, or the tag's initial damage where none was.
    pub(crate) damage: f64,
}

/// Every crack edge of `mesh` with its damage on the front; `initial_damage(tag)` for edges no
/// face was solved over.
pub(crate) fn crack_edges(
    mesh: &Mesh,
    solution: &FrontSolution,
    fracture: &Fracture,
    order: usize,
    initial_damage: impl Fn(Option<sdg_mesh::TagId>) -> f64,
) -> Vec<CrackEdge> {
    let basis = FaceBasis::new(order);
    (0..mesh.edges().len())
        .filter(|&e| fracture.is_crack(mesh.edges()[e].tag))
        .map(|e| {
            let edge = &mesh.edges()[e];
            let damage = solution.face(e).map_or(initial_damage(edge.tag), |face| {
                let corners = face.geometry.corners();
                let top = (0..3)
                    .max_by(|&a, &b| corners[a][2].total_cmp(&corners[b][2]))
                    .expect("a face has corners");
                corner_damage(&face, &basis)[top]
            });
            // The face polynomial may overshoot where D saturates; D itself is in [0, 1].
            let damage = damage.clamp(0.0, 1.0);
            CrackEdge {
                edge: e as sdg_mesh::EdgeId,
                ends: edge.vertices.map(|w| mesh.vertex(w)),
                damage,
            }
        })
        .collect()
}

/// The damage `D` of `face` (an interface state) at each corner of its spacetime triangle.
fn corner_damage(face: &FaceState, basis: &FaceBasis) -> [f64; 3] {
    let mut psi = [0.0; SCRATCH];
    face.geometry
        .corners()
        .map(|x| face.evaluate(basis, x, &mut psi[..basis.len()])[STATE_COMPONENTS - 1])
}

/// The least damage `D` over edge `e` on the front: the smallest at the corners of the last
/// face solved over it (faces of order `order`), or `initial` where none was. `D` never
/// decreases in time, so this is the damage of the whole face up to the polynomial's wiggle.
pub(crate) fn least_damage(solution: &FrontSolution, e: EdgeId, order: usize, initial: f64) -> f64 {
    solution.face(e as usize).map_or(initial, |face| {
        corner_damage(&face, &FaceBasis::new(order))
            .into_iter()
            .fold(f64::INFINITY, f64::min)
    })
}

/// A merge of two crack edges into one by coarsening (the crack's wake, seed Fig. 4.6), at
/// front time `time` (s): the restored edge runs `from` `to` (m); its branch is the one whose
/// extension made the removed vertex `at` (m) a crack vertex, if any (none on initial cracks).
pub(crate) fn wake_coarsening(
    events: &[FractureEvent],
    time: f64,
    at: [f64; 2],
    from: [f64; 2],
    to: [f64; 2],
) -> FractureEvent {
    FractureEvent {
        time,
        kind: "coarsening".into(),
        branch: events
            .iter()
            .find(|e| e.kind == "extension" && on_segment(at, e.from, e.to))
            .and_then(|e| e.branch),
        from,
        to,
        reason: None,
    }
}

/// `cracks.csv`: the crack edges, their ends (m), tag, branch and damage. An edge's branch is
/// the one whose extension (in `events`) made the segment it lies on (bisections split an
/// extension's edge and coarsening merges the halves again, so every crack edge lies on one);
/// empty on initial cracks.
pub(crate) fn cracks_csv(mesh: &Mesh, cracks: &[CrackEdge], events: &[FractureEvent]) -> String {
    let extensions: Vec<&FractureEvent> = events.iter().filter(|e| e.kind == "extension").collect();
    let mut csv = Table::new(["x0_m", "y0_m", "x1_m", "y1_m", "tag", "branch", "damage"]);
    for c in cracks {
        let tag = mesh.edges()[c.edge as usize]
            .tag
            .map_or("", |t| mesh.tag_names()[t as usize].as_str());
        let [a, b] = c.ends;
        let middle = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
        let branch = extensions
            .iter()
            .find(|e| on_segment(middle, e.from, e.to))
            .and_then(|e| e.branch)
            .map_or(String::new(), |b| b.to_string());
        csv.row([
            format!("{:e}", a[0]),
            format!("{:e}", a[1]),
            format!("{:e}", b[0]),
            format!("{:e}", b[1]),
            tag.to_string(),
            branch,
            format!("{:e}", c.damage),
        ]);
    }
    csv.into_text()
}

/// The summary of the fracture events of a run on the final `state`, whose crack edges are
/// `cracks`; `initial_tips` are the positions of the initial cracks' tips, m; `macro_lengths`
/// the arms' reach of a macro fork and of a short one, m; its times are on the clock of `time`.
pub(crate) fn summary(
    events: &[FractureEvent],
    (state, cracks): (&Frontier, &[CrackEdge]),
    fracture: &Fracture,
    (initial_tips, macro_lengths): (&[[f64; 2]], [Option<f64>; 2]),
    time: &TimeConfig,
) -> FractureSummary {
    let count = |kind: &str| events.iter().filter(|e| e.kind == kind).count() as u64;
    let (first_branching_time, first_branching_distance) = first_branching(events, initial_tips);
    let [macro_branching, short_macro_branching] = macro_lengths.map(|length| {
        length
            .and_then(|l| macro_fork(&state.mesh, fracture, events, cracks, l, initial_tips))
            .map(|fork| MacroFork {
                time: time.clock(fork.time),
                ..fork
            })
    });
    FractureSummary {
        nucleations: count("nucleation"),
        extensions: count("extension"),
        branchings: count("branching"),
        arrests: count("arrest"),
        refused: count("refused"),
        refusals: events.iter().filter_map(|e| e.reason.as_deref()).fold(
            BTreeMap::new(),
            |mut by, reason| {
                *by.entry(reason.to_owned()).or_insert(0) += 1;
                by
            },
        ),
        wake_coarsenings: count("coarsening"),
        branches: state.next_branch,
        active_tips: state.tips.iter().flatten().count(),
        total_length: events
            .iter()
            .filter(|e| e.kind == "extension")
            .map(|e| (e.to[0] - e.from[0]).hypot(e.to[1] - e.from[1]))
            .fold(0.0, |a, b| a + b),
        first_branching_time: first_branching_time.map(|t| time.clock(t)),
        first_branching_distance,
        macro_branching,
        short_macro_branching,
    }
}

/// The first macro fork of the crack network on `mesh` whose arms reach `length` (m)
/// ([`network`]); `initial_tips` are the positions of the initial cracks' tips, m.
pub(crate) fn macro_fork(
    mesh: &Mesh,
    fracture: &Fracture,
    events: &[FractureEvent],
    cracks: &[CrackEdge],
    length: f64,
    initial_tips: &[[f64; 2]],
) -> Option<MacroFork> {
    let links = crack_links(mesh, fracture.tag, events, cracks);
    network::first_macro_fork(&links, length, initial_tips)
}

/// The crack edges `cracks` of `mesh` as links of the crack network with their damage, each
/// made when the extension whose segment it lies on was (see [`cracks_csv`]), initial cracks
/// (every tag but `grown`, the one of new crack edges) at 0.
fn crack_links(
    mesh: &Mesh,
    grown: TagId,
    events: &[FractureEvent],
    cracks: &[CrackEdge],
) -> Vec<CrackLink> {
    let extensions: Vec<&FractureEvent> = events.iter().filter(|e| e.kind == "extension").collect();
    cracks
        .iter()
        .map(|crack| {
            let edge = &mesh.edges()[crack.edge as usize];
            let points = edge.vertices.map(|w| mesh.vertex(w));
            let middle = [
                0.5 * (points[0][0] + points[1][0]),
                0.5 * (points[0][1] + points[1][1]),
            ];
            let time = extensions
                .iter()
                .find(|e| on_segment(middle, e.from, e.to))
                .map_or(0.0, |e| e.time);
            CrackLink {
                ends: edge.vertices,
                points,
                time,
                initial: edge.tag != Some(grown),
                damage: crack.damage,
            }
        })
        .collect()
}

/// The time (s) of the first branching and its distance (m) from the nearest of
/// `initial_tips` (m), as the seed measures it (none without initial tips).
fn first_branching(
    events: &[FractureEvent],
    initial_tips: &[[f64; 2]],
) -> (Option<f64>, Option<f64>) {
    let Some(b) = events
        .iter()
        .filter(|e| e.kind == "branching")
        .min_by(|a, b| a.time.total_cmp(&b.time))
    else {
        return (None, None);
    };
    let distance = initial_tips
        .iter()
        .map(|o| (b.from[0] - o[0]).hypot(b.from[1] - o[1]))
        .min_by(f64::total_cmp);
    (Some(b.time), distance)
}

/// The crack-tip states of every branch: the crossings of the damage levels on the crack edges
/// the branch added (found by where they lie: later splits keep them on the segment), tracked
/// per branch as a cohesive crack is per tag ([`tips::tip_states`], speeds fitted over at
/// least `length`, m: the damage law's process zone `c_R tau`): the tip is where
/// the damage reaches `OPEN_DAMAGE` (an open crack), behind the newest crack edge, whose insertion only marks where
/// damage may start. The edges a nucleation makes are left out: the traction that exceeded the
/// defect's strength loads them whole, so their points fail almost together (on the plate with
/// right diagonals, four points over 2.9 um within 0.39 ns), which is no tip running; a nucleated
/// branch's tip starts where they end. So are the edges that end a branch on another crack or
/// the boundary (an arrest at the edge's far end): the ligament ahead of the tip, which breaks
/// as a whole.
pub(crate) fn branch_tips(
    events: &[FractureEvent],
    crossings: &[Crossing],
    length: f64,
) -> BTreeMap<u32, Vec<TipState>> {
    let key = |e: &FractureEvent| (e.time.to_bits(), e.from.map(f64::to_bits));
    let nucleations: BTreeSet<_> = events
        .iter()
        .filter(|e| e.kind == "nucleation")
        .map(key)
        .collect();
    let edge = |e: &FractureEvent| (key(e), e.to.map(f64::to_bits));
    let ligaments: BTreeSet<_> = events
        .iter()
        .filter(|e| e.kind == "arrest" && e.to != e.from)
        .map(edge)
        .collect();
    let segments: Vec<(&FractureEvent, u32)> = events
        .iter()
        .filter(|e| {
            e.kind == "extension" && !nucleations.contains(&key(e)) && !ligaments.contains(&edge(e))
        })
        .filter_map(|e| Some((e, e.branch?)))
        .collect();
    let mut by_branch: BTreeMap<u32, Vec<Crossing>> = BTreeMap::new();
    for c in crossings {
        if let Some((_, branch)) = segments
            .iter()
            .find(|(e, _)| on_segment(c.point, e.from, e.to))
        {
            by_branch.entry(*branch).or_default().push(*c);
        }
    }
    by_branch
        .into_iter()
        .map(|(branch, list)| (branch, tips::tip_states(&list, length)))
        .filter(|(_, states)| !states.is_empty())
        .collect()
}

/// True when `p` lies on the segment from `a` to `b` (to a billionth of its length).
fn on_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let length2 = dx * dx + dy * dy;
    let along = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2;
    let across = ((p[0] - a[0]) * dy - (p[1] - a[1]) * dx).abs() / length2.sqrt();
    (0.0..=1.0).contains(&along) && across <= 1e-9 * length2.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use sdg_solver::crack::Level;
    use sdg_solver::crack::OPEN_DAMAGE;

    /// Times written as they are on the run's clock.
    const UNIT_TIME: TimeConfig = TimeConfig {
        start: 0.0,
        end: 1.0,
    };

    /// The least damage of an edge is the smallest of its face's corners (D = 0.9 + 0.1 xi on
    /// the reference face: 0.9, 1, 0.9), or the initial damage where no face was solved.
    #[test]
    fn the_least_damage_of_an_edge_is_that_of_its_face_s_lowest_corner() {
        let solution = FrontSolution::new(1, 3, 5).with_edges(2);
        let geometry = sdg_solver::face::FaceGeometry::new([
            [0.0, 0.0, 0.0],
            [1e-5, 0.0, 0.0],
            [0.0, 0.0, 2e-5],
        ]);
        let mut coefficients = [[0.0; sdg_solver::face::MAX_FACE_BASIS]; STATE_COMPONENTS];
        coefficients[STATE_COMPONENTS - 1][..2].copy_from_slice(&[0.9, 0.1]);
        solution.store_face(
            1,
            &FaceState {
                geometry,
                coefficients,
            },
        );
        assert_eq!(least_damage(&solution, 0, 1, 0.25), 0.25);
        assert!((least_damage(&solution, 1, 1, 0.25) - 0.9).abs() < 1e-15);
    }

    /// On the unit square's notch to its centre, cracks grown up and down from the notch's tip
    /// along the grid (quarter-length edges) make a macro fork there with two half-length arms;
    /// the lower arm's second edge is half damaged, so a quarter of that arm is open.
    #[test]
    fn a_macro_fork_s_arms_count_their_open_length() {
        let (mut mesh, fracture) = crate::fracture::criteria::tests::notched();
        let at = |mesh: &Mesh, x| crate::fracture::criteria::tests::vertex_at(mesh, x);
        let path = [[0.5, 1.0], [0.5, 0.75], [0.5, 0.5], [0.5, 0.25], [0.5, 0.0]];
        let mut events = Vec::new();
        for (i, pair) in path.windows(2).enumerate() {
            let e = mesh
                .edge_between(at(&mesh, pair[0]), at(&mesh, pair[1]))
                .unwrap();
            mesh.set_tag(e, Some(fracture.tag));
            events.push(extension(i as f64, i as u32, pair[0], pair[1]));
        }
        let cracks = |half_damaged: f64| -> Vec<CrackEdge> {
            (0..mesh.edges().len() as EdgeId)
                .filter(|&e| fracture.is_crack(mesh.edges()[e as usize].tag))
                .map(|e| {
                    let ends = mesh.edges()[e as usize].vertices.map(|v| mesh.vertex(v));
                    let lowest = ends[0][1].min(ends[1][1]) == 0.0;
                    CrackEdge {
                        edge: e,
                        ends,
                        damage: if lowest { half_damaged } else { 1.0 },
                    }
                })
                .collect()
        };
        let tips = [[0.5, 0.5]];
        let fork = macro_fork(&mesh, &fracture, &events, &cracks(0.5), 0.5, &tips).unwrap();
        assert_eq!((fork.point, fork.distance), ([0.5, 0.5], Some(0.0)));
        assert_eq!(
            (fork.arms, fork.open_arms),
            (vec![0.5, 0.5], vec![0.5, 0.25])
        );
        // An edge at the threshold is open; just below it, not.
        let fork = macro_fork(&mesh, &fracture, &events, &cracks(OPEN_DAMAGE), 0.5, &tips);
        assert_eq!(fork.unwrap().open_arms, vec![0.5, 0.5]);
        let below = OPEN_DAMAGE - 1e-9;
        let fork = macro_fork(&mesh, &fracture, &events, &cracks(below), 0.5, &tips);
        assert_eq!(fork.unwrap().open_arms, vec![0.5, 0.25]);
    }

    fn extension(time: f64, branch: u32, from: [f64; 2], to: [f64; 2]) -> FractureEvent {
        FractureEvent {
            time,
            kind: "extension".into(),
            branch: Some(branch),
            from,
            to,
            reason: None,
        }
    }

    /// The branching plate's clock: the span, `3.6e-6 + 2.392e-6`, plus the start is one
    /// rounding below `3.6e-6`; an event at the end is written at `time.end` itself.
    #[test]
    fn an_event_at_the_end_time_is_written_at_time_end() {
        let time = TimeConfig {
            start: -2.392e-6,
            end: 3.6e-6,
        };
        assert_ne!(time.span() + time.start, time.end);
        let events = [extension(0.0, 1, [0.0; 2], [1e-5, 0.0]), {
            let mut arrest = extension(time.span(), 1, [1e-5, 0.0], [1e-5, 0.0]);
            arrest.kind = "arrest".into();
            arrest
        }];
        let csv = events_csv(&events, &time);
        let times: Vec<f64> = (csv.lines().skip(1))
            .map(|line| line.split(',').next().unwrap().parse().unwrap())
            .collect();
        assert_eq!(times, [-2.392e-6, 3.6e-6]);
    }

    /// A defect nucleates at the origin and makes two 10 um edges at once, branches 2 (along
    /// +x) and 3 (along -x), whose four points each reach D = 1 within 0.4 ns (25 km/s if read
    /// as a tip); branch 2 then runs on at 400 m/s over ten more edges, branch 3 stops.
    #[test]
    fn a_nucleated_crack_s_first_edges_are_no_tip_run() {
        let h = 1e-5;
        let t0 = 1e-6;
        let mut events = vec![FractureEvent {
            time: t0,
            kind: "nucleation".into(),
            branch: Some(2),
            from: [0.0, 0.0],
            to: [0.0, 0.0],
            reason: None,
        }];
        let mut crossings = Vec::new();
        let mut tip = |x: f64, time: f64| {
            crossings.push(Crossing {
                edge: 0,
                point: [x, 0.0],
                time,
                level: Level::Tip,
                edge_length: h,
            })
        };
        for (branch, sign) in [(2, 1.0), (3, -1.0)] {
            events.push(extension(t0, branch, [0.0, 0.0], [sign * h, 0.0]));
            for j in 0..4 {
                tip(sign * h * (j as f64 + 0.5) / 4.0, t0 + 1e-10 * j as f64);
            }
        }
        let t1 = t0 + 1e-9;
        for k in 1..11 {
            let r = h * k as f64;
            events.push(extension(t1 + (r - h) / 400.0, 2, [r, 0.0], [r + h, 0.0]));
            for j in 0..4 {
                let r = r + h * (j as f64 + 0.5) / 4.0;
                tip(r, t1 + (r - h) / 400.0);
            }
        }
        let tips = branch_tips(&events, &crossings, 0.0);
        assert_eq!(tips.keys().copied().collect::<Vec<_>>(), [2]);
        assert_eq!(tips[&2].len(), 40);
        let (_, summary) = tips::tips_csv("branch", &tips, 1000.0, &UNIT_TIME);
        assert!(
            (summary.max_speed_over_c_r - 0.4).abs() < 0.004,
            "{summary:?}"
        );
    }

    /// Branch 0 runs along x in 10 um edges at 500 m/s and its last edge joins another crack
    /// (an arrest at the edge's far end): that ligament breaks at once, 0.1 ns after the edge
    /// before it, and is no tip running. Without its crossings the fastest state is the run's.
    #[test]
    fn the_ligament_to_a_crack_a_tip_joins_is_no_tip_run() {
        let h = 1e-5;
        let speed = 500.0;
        let mut events = Vec::new();
        let mut crossings = Vec::new();
        let n = 10;
        for k in 0..=n {
            let x = h * k as f64;
            let time = if k < n {
                x / speed
            } else {
                (x - h) / speed + 1e-10
            };
            events.push(extension(time, 0, [x, 0.0], [x + h, 0.0]));
            for j in 0..4 {
                let point = [x + h * (j as f64 + 0.5) / 4.0, 0.0];
                let at = if k < n { point[0] / speed } else { time };
                crossings.push(Crossing {
                    edge: k as EdgeId,
                    point,
                    time: at,
                    level: Level::Tip,
                    edge_length: h,
                });
            }
        }
        let mut arrest = events[n].clone();
        arrest.kind = "arrest".into();
        let tips = |events: &[FractureEvent]| {
            let tips = branch_tips(events, &crossings, 0.0);
            (
                tips[&0].len(),
                tips::tips_csv("branch", &tips, 1000.0, &UNIT_TIME).1,
            )
        };
        let (states, summary) = tips(&events);
        assert_eq!(states, 4 * (n + 1));
        assert!(summary.max_speed_over_c_r > 0.6, "{summary:?}");
        events.push(arrest);
        let (states, summary) = tips(&events);
        assert_eq!(states, 4 * n);
        assert!(
            (summary.max_speed_over_c_r - 0.5).abs() < 0.01,
            "{summary:?}"
        );
    }

    /// Branch 0 runs along x in 10 um edges and branches at x = 60 um into itself (on, 30
    /// degrees up) and branch 1 (30 degrees down). The damage reaches 1 at four points per edge,
    /// at 500 m/s on branch 0 and 400 m/s on branch 1; crossings elsewhere (the notch) belong to
    /// no branch. Events and crossings come out of time order, as workers record them.
    #[test]
    fn each_branch_has_its_own_tip() {
        let h = 1e-5;
        let mut events = Vec::new();
        let mut crossings = Vec::new();
        let mut branch = |id: u32, start: [f64; 2], t0: f64, angle: f64, speed: f64, n: usize| {
            let at = |r: f64| [start[0] + r * angle.cos(), start[1] + r * angle.sin()];
            for k in (0..n).rev() {
                let r = h * k as f64;
                events.push(extension(t0 + r / speed, id, at(r), at(r + h)));
                for j in 0..4 {
                    let r = r + h * (j as f64 + 0.5) / 4.0;
                    crossings.push(Crossing {
                        edge: 100 * id + k as EdgeId + if angle > 0.0 { 50 } else { 0 },
                        point: at(r),
                        time: t0 + r / speed,
                        level: Level::Tip,
                        edge_length: h,
                    });
                }
            }
        };
        let angle = 30f64.to_radians();
        branch(1, [6e-5, 0.0], 1.2e-7, -angle, 400.0, 20);
        branch(0, [0.0, 0.0], 0.0, 0.0, 500.0, 6);
        branch(0, [6e-5, 0.0], 1.2e-7, angle, 500.0, 20);
        crossings.push(Crossing {
            edge: 0,
            point: [-1e-5, 0.0],
            time: 0.0,
            level: Level::Tip,
            edge_length: h,
        });
        let tips = branch_tips(&events, &crossings, 0.0);
        assert_eq!(tips.keys().copied().collect::<Vec<_>>(), [0, 1]);
        assert_eq!((tips[&0].len(), tips[&1].len()), (104, 80));
        for (id, speed) in [(0, 500.0), (1, 400.0)] {
            let states = &tips[&id];
            assert!(states.windows(2).all(|w| w[0].time <= w[1].time));
            // Branch 0 turns by 30 degrees at the branching, and its extension is the straight
            // distance from its origin: it grows at 0.87 to 0.99 of the tip's speed there.
            let least = if id == 0 { 0.85 } else { 0.99 };
            for s in &states[10..states.len() - 10] {
                assert!(
                    (least..1.01).contains(&(s.speed / speed)),
                    "branch {id}: {s:?}"
                );
            }
        }
        let (csv, summary) = tips::tips_csv("branch", &tips, 1000.0, &UNIT_TIME);
        assert_eq!(csv.lines().count(), 185);
        assert!(csv.starts_with("t_s,branch,x_m,"));
        assert!(
            (summary.max_speed_over_c_r - 0.5).abs() < 0.01,
            "{summary:?}"
        );
        let mut branching = extension(1.2e-7, 0, [6e-5, 0.0], [6e-5, 0.0]);
        branching.kind = "branching".into();
        events.push(branching);
        // Measured from the nearer initial tip, not from where branch 0's edges start.
        let (time, distance) = first_branching(&events, &[[1e-5, 0.0], [-1e-3, 0.0]]);
        assert_eq!(time, Some(1.2e-7));
        assert!((distance.unwrap() - 5e-5).abs() < 1e-15, "{distance:?}");
        assert_eq!(first_branching(&events, &[]), (Some(1.2e-7), None));
    }
}
