//! `study.png`: each metric against the first axis other than the draws, one chart per metric
//! stacked top to bottom. Each chart has every finished case's value (dots), the mean of each
//! group (dots) and its 95% interval (a vertical bar); groups that differ in further axes are
//! series of their own. A study whose only axes are draws has the cases against the first
//! axis, with the mean and the interval as horizontal lines.

use std::path::Path;

use super::cases::{Case, Group, value_text};
use super::file::Study;
use super::record::{CaseStatus, Collected};
use super::stats::Stats;
use crate::error::EngineError;
use crate::plot::{LineChart, LineStyle};

/// Pixels of one metric's chart.
const CHART_SIZE: (u32, u32) = (900, 420);

/// Draws the charts of `study`'s metrics over its `groups` into the PNG file `path`.
pub(super) fn write_png(
    study: &Study,
    cases: &[Case],
    groups: &[Group],
    collected: &Collected,
    path: &Path,
) -> Result<(), EngineError> {
    let mut image = None;
    for m in 0..study.metrics.len() {
        let chart = chart(study, cases, groups, collected, m).render(CHART_SIZE)?;
        image = Some(match image {
            None => chart,
            Some(above) => crate::plot::Image::above(above, chart),
        });
    }
    match image {
        Some(image) => image.write_png(path),
        None => Ok(()),
    }
}

/// The position of `value` on `axis` for the x axis: a number itself, any other value its
/// index among the axis's values.
fn position(study: &Study, axis: usize, value: &toml::Value) -> f64 {
    match value {
        toml::Value::Integer(n) => *n as f64,
        toml::Value::Float(x) => *x,
        v => study.axes[axis]
            .values
            .iter()
            .position(|a| a == v)
            .unwrap_or(0) as f64,
    }
}

/// The chart of metric `m`.
fn chart(
    study: &Study,
    all: &[Case],
    groups: &[Group],
    collected: &Collected,
    m: usize,
) -> LineChart {
    let key = &study.metrics[m];
    let done = |c: &usize| collected.statuses[*c] == CaseStatus::Done;
    let value = |c: usize| collected.values[c][m].unwrap_or(f64::NAN);
    let non_draws: Vec<usize> = (0..study.axes.len())
        .filter(|&a| !study.axes[a].draws)
        .collect();
    let finished = groups
        .iter()
        .flat_map(|g| &g.cases)
        .filter(|c| done(c))
        .count();
    let present = (groups.iter().flat_map(|g| &g.cases))
        .filter(|&&c| done(&c) && collected.values[c][m].is_some())
        .count();
    let title = format!("{key}: in {present} of {finished} finished cases");
    let Some(&x_axis) = non_draws.first() else {
        // Draws only (or no axis): the cases against the first axis (or their number).
        let x = |c: usize| match study.axes.first() {
            Some(_) => position(study, 0, &all[c].values[0]),
            None => c as f64,
        };
        let cases: Vec<usize> = groups.iter().flat_map(|g| &g.cases).copied().collect();
        let points: Vec<(f64, f64)> = cases
            .iter()
            .filter(|c| done(c))
            .map(|&c| (x(c), value(c)))
            .collect();
        let values: Vec<Option<f64>> = cases
            .iter()
            .filter(|c| done(c))
            .map(|&c| collected.values[c][m])
            .collect();
        let stats = Stats::of(&values);
        let (x0, x1) = points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.0), b.max(p.0))
            });
        let level = |y: Option<f64>| y.map_or_else(Vec::new, |y| vec![(x0, y), (x1, y)]);
        let [lo, hi] = stats
            .ci95
            .map_or([None, None], |[lo, hi]| [Some(lo), Some(hi)]);
        let x_label = study.axes.first().map_or("case", |a| a.key.as_str());
        return with_margin(LineChart::new(&title, x_label, key), study, 0)
            .series("cases", &points, LineStyle::Markers)
            .series("mean", &level(stats.mean), LineStyle::Solid)
            .series("95% interval", &level(lo), LineStyle::Dashed)
            .series("", &level(hi), LineStyle::Dashed);
    };
    let axis = &study.axes[x_axis];
    let numeric = axis.values.iter().all(|v| v.is_integer() || v.is_float());
    let x_label = match numeric {
        true => axis.key.clone(),
        false => {
            let named: Vec<String> = (axis.values.iter().enumerate())
                .map(|(i, v)| format!("{i}: {}", value_text(v)))
                .collect();
            format!("{} ({})", axis.key, named.join("; "))
        }
    };
    let mut chart = with_margin(LineChart::new(&title, &x_label, key), study, x_axis);
    // Groups that differ in the further non-draws axes: a series each.
    let mut lines: Vec<(String, Vec<&Group>)> = Vec::new();
    for g in groups {
        let name: Vec<String> = (non_draws.iter().zip(&g.values))
            .skip(1)
            .map(|(&a, v)| format!("{}={}", study.axes[a].key, value_text(v)))
            .collect();
        let name = name.join(", ");
        match lines.iter_mut().find(|(n, _)| *n == name) {
            Some((_, gs)) => gs.push(g),
            None => lines.push((name, vec![g])),
        }
    }
    for (name, gs) in lines {
        let suffix = if name.is_empty() {
            String::new()
        } else {
            format!(" ({name})")
        };
        let (mut cases, mut means, mut bars) = (Vec::new(), Vec::new(), Vec::new());
        for g in gs {
            let x = position(study, x_axis, &g.values[0]);
            let finished: Vec<usize> = g.cases.iter().filter(|c| done(c)).copied().collect();
            cases.extend(finished.iter().map(|&c| (x, value(c))));
            let stats = Stats::of(
                &finished
                    .iter()
                    .map(|&c| collected.values[c][m])
                    .collect::<Vec<_>>(),
            );
            means.extend(stats.mean.map(|y| (x, y)));
            if let Some([lo, hi]) = stats.ci95 {
                bars.extend([(x, lo), (x, hi), (f64::NAN, f64::NAN)]);
            }
        }
        chart = chart
            .series(&format!("cases{suffix}"), &cases, LineStyle::Markers)
            .series(&format!("mean{suffix}"), &means, LineStyle::Markers)
            .series(&format!("95% interval{suffix}"), &bars, LineStyle::Solid);
    }
    chart
}

/// `chart` with an x range a tenth wider on each side than the positions of axis `a`'s values.
fn with_margin(chart: LineChart, study: &Study, a: usize) -> LineChart {
    let Some(axis) = study.axes.get(a) else {
        return chart;
    };
    let xs = axis.values.iter().map(|v| position(study, a, v));
    let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
        (lo.min(x), hi.max(x))
    });
    let margin = if hi > lo {
        0.1 * (hi - lo)
    } else {
        0.5 * lo.abs().max(1.0)
    };
    chart.x_range(lo - margin, hi + margin)
}
