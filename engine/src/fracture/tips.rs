//! Crack tips of cohesive and damage interfaces over time (`crack_tips.csv`, `summary.json`
//! `crack`).
//!
//! Patches report where their faces crossed the crack-tip level (Xu-Needleman: the separation
//! `delta_c`; damage: `D = OPEN_DAMAGE`, an open crack) and the level of the process zone's other end (the
//! trailing edge `delta_T` behind the tip; the damage front `D = eps` ahead of it)
//! ([`sdg_solver::crack`]). Per interface tag, each probe point keeps its first crossing of
//! each level. The crack opens progressively, so in time order each first tip crossing is the
//! tip at that time; the crack's origin is the first such crossing. At each tip state:
//! - `extension`: the distance from the origin to the farthest tip so far, m;
//! - `speed`: the least-squares slope of the extension against time over the tip states whose
//!   extension lies within half a window of this state's, m/s. The window is [`SPEED_EDGES`]
//!   lengths of the edge the tip crossed on each side, and at least the crack's own length
//!   scale where it has one (a crack branch: the damage law's process zone `c_R tau`, see
//!   [`tip_states`]); near the origin and the last state it is the window of that width that
//!   stays inside the states; it is widened to the whole of the edges at its ends. The crack advances face by
//!   face, so over a window of less than a few edges the slope measures those steps, not its
//!   speed (on `configs/damage_mode1.toml`, fits over nine successive states, about 10 ns,
//!   scattered up to 1.13 c_R about a mean of 0.9 c_R); over two edges on each side it still
//!   measured a tip that crosses each edge at once and then waits 8% off when the window cut
//!   the crossings of an edge; over whole edges, within 1%. A crack whose
//!   states span less than its length scale (a branch shorter than `c_R tau`) has no speed
//!   (NaN): it fails within about `tau` as one stretch. Nor does a window spanning less than
//!   one edge: its
//!   crossings are the points of one face reaching the level, as the face's polynomial has it
//!   (two points 1 um apart 3 ps apart on a nucleated branch of the branching plate), not a
//!   tip running;
//! - `process_zone_length`: the distance from the tip to the latest zone-end crossing at or
//!   before that time (to the origin while a cohesive zone has no trailing edge yet), m.
//!
//! One tip per interface tag: a tag whose crack grows at two ends mixes them.

use crate::output::table::Table;
use std::collections::BTreeMap;

use serde::Serialize;

use sdg_solver::crack::{Crossing, Level};

use crate::config::TimeConfig;

/// Edge lengths on each side of a tip state that its speed is fitted over.
pub const SPEED_EDGES: f64 = 2.0;

/// One state of a crack tip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TipState {
    /// Time, s.
    pub time: f64,
    /// Position, m.
    pub point: [f64; 2],
    /// Distance from the origin to the farthest tip so far, m.
    pub extension: f64,
    /// Tip speed, m/s; NaN where the crack spans less than its length scale or the window one edge.
    pub speed: f64,
    /// Length of the process zone, m.
    pub process_zone_length: f64,
}

/// Crack totals of a run for `summary.json`, over every cohesive and damage interface.
#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct CrackSummary {
    /// Tip states recorded.
    pub tip_states: usize,
    /// Largest extension of a crack at the end, m.
    pub final_length: f64,
    /// Largest tip speed, m/s.
    pub max_speed: f64,
    /// `max_speed / c_R`.
    pub max_speed_over_c_r: f64,
    /// Tip states whose speed is above `c_R`.
    pub states_over_c_r: usize,
    /// With `[fracture]`, the crack network's totals under the names the crack-branching
    /// problem gives them (`crack.branches`, ...).
    #[serde(flatten)]
    pub network: Option<CrackNetwork>,
}

/// The crack network's totals of a run with `[fracture]`: the values of `fracture.branches`,
/// `fracture.total_length`, `fracture.first_branching_time` and
/// `fracture.first_branching_distance`, repeated in `crack` where the crack-branching problem
/// (issue 14, "Outputs") names them.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct CrackNetwork {
    /// Crack branches.
    pub branches: u32,
    /// Total length of the crack edges added, m.
    pub total_length: f64,
    /// Time of the first branching on the config's clock, s; `null` if none.
    pub first_branching_time: Option<f64>,
    /// Distance from the nearest initial tip to the first branching, m; `null` if none.
    pub first_branching_distance: Option<f64>,
    /// Largest speed of a branch's debonded front over `c_R`: `max_speed_over_c_r`, whose
    /// speeds are fitted per branch over at least the process zone `c_R tau` (`crack_tips.csv`).
    pub max_branch_speed_over_c_r: f64,
}

/// Per point, the first crossing of one level.
fn first_crossings(crossings: &[Crossing], level: Level) -> Vec<Crossing> {
    let mut first: BTreeMap<(u64, u64), Crossing> = BTreeMap::new();
    for c in crossings.iter().filter(|c| c.level == level) {
        let key = (c.point[0].to_bits(), c.point[1].to_bits());
        first
            .entry(key)
            .and_modify(|old| {
                if c.time < old.time {
                    *old = *c;
                }
            })
            .or_insert(*c);
    }
    let mut out: Vec<Crossing> = first.into_values().collect();
    out.sort_by(|a, b| {
        a.time
            .total_cmp(&b.time)
            .then(a.point[0].total_cmp(&b.point[0]))
            .then(a.point[1].total_cmp(&b.point[1]))
    });
    out
}

fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// The tip states of one crack from its crossings (any order); `length` (m, >= 0) is the
/// least window of extension a speed is fitted over.
///
/// A crack branch passes the damage law's process zone `c_R tau`: a debonded front is the
/// edge of a zone about that long, so its advance over less measures the zone's inner
/// structure and the probe points, not the crack (a whole overloaded stretch shorter than it
/// fails within `tau`). On meshes whose edges are longer than a quarter of it, the
/// [`SPEED_EDGES`] edges decide, and the window is the same as with `length` = 0. A crack
/// whose states span less than `length` has no speed (NaN at every state): all of it lies
/// within one process zone, and its first states are a stretch failing at once, not a front
/// running (a 6.8 um branch of the branching plate read 1.32 `c_R`).
pub fn tip_states(crossings: &[Crossing], length: f64) -> Vec<TipState> {
    let tips = first_crossings(crossings, Level::Tip);
    let zone_ends = first_crossings(crossings, Level::ZoneEnd);
    let Some(origin) = tips.first().map(|c| c.point) else {
        return Vec::new();
    };
    let mut states = Vec::with_capacity(tips.len());
    let mut extension = 0.0f64;
    let mut behind = 0;
    for tip in &tips {
        extension = extension.max(distance(tip.point, origin));
        while behind < zone_ends.len() && zone_ends[behind].time <= tip.time {
            behind += 1;
        }
        let tail = if behind > 0 {
            zone_ends[behind - 1].point
        } else {
            origin
        };
        states.push(TipState {
            time: tip.time,
            point: tip.point,
            extension,
            speed: 0.0,
            process_zone_length: distance(tip.point, tail),
        });
    }
    // The extension never decreases along the states: each window is a contiguous range. Near
    // the crack's origin and its last state the window keeps its width and shifts inward: a
    // half window would fit one or two face-by-face steps, not the speed.
    let (least, most) = (states[0].extension, extension);
    if most - least < length {
        for state in &mut states {
            state.speed = f64::NAN;
        }
        return states;
    }
    for (i, tip) in tips.iter().enumerate() {
        let reach = (SPEED_EDGES * tip.edge_length).max(0.5 * length);
        let lo = (states[i].extension - reach)
            .min(most - 2.0 * reach)
            .max(least);
        let hi = lo + 2.0 * reach;
        let mut first = states.partition_point(|s| s.extension < lo);
        let mut last = states.partition_point(|s| s.extension <= hi);
        // Whole edges: a window that cuts an edge's crossings fits part of a step of the
        // face-by-face staircase, which tilts the slope (by up to 8%).
        while first > 0 && first < last && tips[first - 1].edge == tips[first].edge {
            first -= 1;
        }
        while last > first && last < tips.len() && tips[last].edge == tips[last - 1].edge {
            last += 1;
        }
        let window = &states[first..last];
        let span = window.last().map_or(0.0, |s| s.extension) - window[0].extension;
        states[i].speed = if span >= tip.edge_length {
            slope(window.iter().map(|s| (s.time, s.extension)))
        } else {
            f64::NAN
        };
    }
    states
}

/// Least-squares slope of `y` against `x`; zero for fewer than two distinct `x`.
fn slope(points: impl Iterator<Item = (f64, f64)> + Clone) -> f64 {
    let n = points.clone().count() as f64;
    let (mx, my) = points
        .clone()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let (sxy, sxx) = points.fold((0.0, 0.0), |(a, b), (x, y)| {
        (a + (x - mx) * (y - my), b + (x - mx) * (x - mx))
    });
    if sxx > 0.0 { sxy / sxx } else { 0.0 }
}

/// `crack_tips.csv` and the summary from the crossings of every cracking interface, with the
/// tag name of each crossing; `c_r` is the Rayleigh speed, m/s; times are written on the
/// clock of `time`.
pub fn write(
    crossings: &[(String, Crossing)],
    c_r: f64,
    time: &TimeConfig,
) -> (String, CrackSummary) {
    let mut by_tag: BTreeMap<&str, Vec<Crossing>> = BTreeMap::new();
    for (tag, c) in crossings {
        by_tag.entry(tag.as_str()).or_default().push(*c);
    }
    tips_csv(
        "interface",
        by_tag
            .into_iter()
            .map(|(tag, list)| (tag, tip_states(&list, 0.0))),
        c_r,
        time,
    )
}

/// `crack_tips.csv` (one row per tip state, keyed by its crack in the column `key`) and its
/// totals; `c_r` is the Rayleigh speed, m/s; each state's time is written on the clock of
/// `time`.
pub(crate) fn tips_csv<K: std::fmt::Display, S: AsRef<[TipState]>>(
    key: &str,
    cracks: impl IntoIterator<Item = (K, S)>,
    c_r: f64,
    time: &TimeConfig,
) -> (String, CrackSummary) {
    let mut csv = Table::new([
        "t_s",
        key,
        "x_m",
        "y_m",
        "extension_m",
        "speed_m_s",
        "process_zone_length_m",
    ]);
    let mut summary = CrackSummary::default();
    for (crack, states) in cracks {
        let states = states.as_ref();
        for s in states {
            csv.row([
                format!("{:e}", time.clock(s.time)),
                crack.to_string(),
                format!("{:e}", s.point[0]),
                format!("{:e}", s.point[1]),
                format!("{:e}", s.extension),
                format!("{:e}", s.speed),
                format!("{:e}", s.process_zone_length),
            ]);
            summary.max_speed = summary.max_speed.max(s.speed);
            summary.states_over_c_r += usize::from(s.speed > c_r);
        }
        summary.tip_states += states.len();
        if let Some(last) = states.last() {
            summary.final_length = summary.final_length.max(last.extension);
        }
    }
    summary.max_speed_over_c_r = summary.max_speed / c_r;
    (csv.into_text(), summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn crossing(x: f64, time: f64, level: Level) -> Crossing {
        Crossing {
            edge: 0,
            point: [x, 0.0],
            time,
            level,
            edge_length: 4e-5,
        }
    }

    #[test]
    fn a_crack_at_constant_speed() {
        // Tip at x = 1 + 300 (t - 1e-6) m, the trailing edge 0.205 mm behind; a point crossing
        // twice keeps its first crossing; the crossings come in any order.
        let mut list = Vec::new();
        for i in (0..40).rev() {
            let x = 1.0 + 1e-5 * i as f64;
            let t = 1e-6 + (x - 1.0) / 300.0;
            list.push(crossing(x, t, Level::Tip));
            list.push(crossing(x, t + 0.3e-6, Level::Tip));
            list.push(crossing(x, t + 2.05e-4 / 300.0, Level::ZoneEnd));
        }
        let states = tip_states(&list, 0.0);
        assert_eq!(states.len(), 40);
        for (i, s) in states.iter().enumerate() {
            assert!((s.extension - 1e-5 * i as f64).abs() < 1e-12);
            assert!((s.speed - 300.0).abs() < 1e-6 * 300.0, "{s:?}");
            // Until the trailing edge forms the zone reaches back to the origin; then it ends
            // at the last probe point the trailing edge passed (21 points behind).
            let want = if i <= 20 { s.extension } else { 21e-5 };
            assert!((s.process_zone_length - want).abs() < 1e-12, "{i}: {s:?}");
        }
        let (csv, summary) = write(
            &list
                .iter()
                .map(|c| ("crack".to_string(), *c))
                .collect::<Vec<_>>(),
            600.0,
            &TimeConfig {
                start: -1e-6,
                end: 1e-5,
            },
        );
        assert_eq!(csv.lines().count(), 41);
        // The times written count from `time.start` = -1 us: the first tip at 1 us is at 0.
        let first: f64 = csv
            .lines()
            .nth(1)
            .unwrap()
            .split(',')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert_eq!(first, 1e-6 - 1e-6);
        assert!((summary.final_length - 39e-5).abs() < 1e-12);
        assert!((summary.max_speed_over_c_r - 0.5).abs() < 1e-6);
        assert_eq!(summary.states_over_c_r, 0);
        // At a Rayleigh speed below the crack's, every state is above it.
        let crossings: Vec<_> = list.iter().map(|c| ("crack".to_string(), *c)).collect();
        let time = TimeConfig {
            start: 0.0,
            end: 1e-5,
        };
        assert_eq!(write(&crossings, 299.0, &time).1.states_over_c_r, 40);
    }

    #[test]
    fn the_speed_is_fitted_over_an_edge_length() {
        // A tip advancing at 300 m/s on average, but edge by edge: the four probe points of each
        // 40 um edge debond within 3 ns of each other, then the next edge waits.
        let mut list = Vec::new();
        for k in 0..30 {
            for j in 0..4 {
                let x = 4e-5 * f64::from(k) + 1e-5 * f64::from(j);
                let t = 4e-5 * f64::from(k) / 300.0 + 1e-9 * f64::from(j);
                list.push(Crossing {
                    edge: k,
                    ..crossing(x, t, Level::Tip)
                });
            }
        }
        let states = tip_states(&list, 0.0);
        // Windows of whole edges: each step of the staircase weighs the same, and the slope is
        // the mean speed up to the 3 ns within a step, up to the first and the last state
        // (windows of full width there). Windows that cut the steps read 276 to 291 m/s.
        for s in &states {
            assert!((s.speed - 300.0).abs() < 3.0, "{s:?}");
        }
    }

    #[test]
    fn a_stretch_that_fails_at_once_is_fitted_over_the_process_zone() {
        // A tip at 300 m/s on 1 um edges, except that a 4 um stretch fails at once. Over
        // two edges on each side the jump reads as a burst far above the mean; over a
        // process zone of 40 um it is averaged over ten times its length.
        let mut list = Vec::new();
        let mut t = 0.0;
        for k in 0..100u32 {
            let x = 1e-6 * f64::from(k);
            if !(50..54).contains(&k) {
                t += 1e-6 / 300.0;
            }
            list.push(Crossing {
                edge: k,
                edge_length: 1e-6,
                ..crossing(x, t, Level::Tip)
            });
        }
        let fastest = |length: f64| {
            tip_states(&list, length)
                .iter()
                .map(|s| s.speed)
                .fold(0.0, f64::max)
        };
        assert!(fastest(0.0) > 2.0 * 300.0, "{}", fastest(0.0));
        let zone = fastest(40e-6);
        assert!(zone > 300.0 && zone < 300.0 * 1.2, "{zone}");
    }

    #[test]
    fn a_crack_shorter_than_its_length_scale_has_no_speed() {
        // A branch of 10 edges of 1 um whose first half fails within a nanosecond: over a
        // length scale of 9 um it has a speed, over one of 11 um (longer than the branch:
        // 9 um from its first state to its last) none, at any state.
        let list: Vec<Crossing> = (0..10u32)
            .map(|k| {
                let t = if k < 5 { 1e-10 } else { 1e-9 } * f64::from(k);
                Crossing {
                    edge: k,
                    edge_length: 1e-6,
                    ..crossing(1e-6 * f64::from(k), t, Level::Tip)
                }
            })
            .collect();
        assert!(tip_states(&list, 9e-6).iter().all(|s| s.speed > 0.0));
        let states = tip_states(&list, 11e-6);
        assert_eq!(states.len(), 10);
        assert!(states.iter().all(|s| s.speed.is_nan()), "{states:?}");
        assert!((states[9].extension - 9e-6).abs() < 1e-18);
    }

    #[test]
    fn the_process_zone_ends_at_the_latest_trailing_crossing() {
        let list = [
            crossing(0.0, 0.0, Level::Tip),
            crossing(1.0, 1.0, Level::Tip),
            crossing(0.0, 1.5, Level::ZoneEnd),
            crossing(2.0, 2.0, Level::Tip),
            crossing(0.5, 2.5, Level::ZoneEnd),
            crossing(3.0, 3.0, Level::Tip),
        ];
        let pz: Vec<f64> = tip_states(&list, 0.0)
            .iter()
            .map(|s| s.process_zone_length)
            .collect();
        assert_eq!(pz, [0.0, 1.0, 2.0, 2.5]);
    }
}
