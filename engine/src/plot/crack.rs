//! `crack_tips.png`: the extension and the speed of each crack tip over time, from
//! `crack_tips.csv`; under a `[loading]`, in the seed's normalized units against the LEFM tip
//! (as seed figures 2.6-2.8). `sdg plot` draws several runs' tips together. Runs with
//! `[fracture]` draw their branches' tips as `tip_speed.png`, against the Rayleigh speed.

use std::path::{Path, PathBuf};

use super::canvas::Image;
use super::line::{LineChart, LineStyle};
use crate::error::EngineError;
use crate::lefm;
use crate::output::table::{ReadTable, number};

/// Size of `crack_tips.png`, pixels: two charts stacked.
pub const CRACK_PNG_SIZE: (u32, u32) = (1000, 1200);

/// The units of the seed's mode-I problem: `t' = (t - arrival) / tau`, `a' = a / (tau c_r)`,
/// speeds over `c_r`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Normalization {
    /// `tau'`, s.
    pub tau: f64,
    /// Rayleigh speed, m/s.
    pub c_r: f64,
    /// Time at which the load reaches the crack plane, s.
    pub arrival: f64,
    /// End time of the run, s: the LEFM curve is drawn up to it.
    pub end: f64,
}

/// Branches that `tip_speed.png` draws in colour and names: the longest; the others are drawn
/// faint behind them.
const NAMED_BRANCHES: usize = 8;

/// `tip_speed.png`'s speed axis ends at this many `c_R` when some state is faster.
const SPEED_AXIS_C_R: f64 = 2.0;

/// The points of one interface's tip, in the chart's units.
pub(super) struct TipSeries {
    name: String,
    extension: Vec<(f64, f64)>,
    speed: Vec<(f64, f64)>,
    style: LineStyle,
}

/// The tip extension chart above the tip speed chart, for the texts of one or more runs'
/// `crack_tips.csv`, each with a label naming its series; the LEFM reference is drawn when
/// `normalization` is given.
pub fn crack_charts(
    runs: &[(&str, &str)],
    normalization: Option<Normalization>,
) -> Result<Image, EngineError> {
    // Per run and interface tag: the series' name, extension and speed.
    let mut tips: Vec<TipSeries> = Vec::new();
    for &(label, csv) in runs {
        tip_series((label, "crack_tips.csv"), csv, normalization, &mut tips)?;
    }
    render(&tips, normalization, None, None)
}

/// The extension chart above the speed chart of `tips`, with the LEFM reference under a
/// `normalization`, and the Rayleigh speed `c_r` (m/s) as a line when given (the speed axis
/// then cut as [`speed_axis`] says); over the time range `window` when given.
pub(super) fn render(
    tips: &[TipSeries],
    normalization: Option<Normalization>,
    c_r: Option<f64>,
    window: Option<(f64, f64)>,
) -> Result<Image, EngineError> {
    let (time, extension, speed) = match normalization {
        Some(_) => (
            "normalized time t' = (t - t0) / tau'",
            "normalized extension a' = a / (tau' c_R)",
            "tip speed / c_R",
        ),
        None => ("time (us)", "extension (mm)", "tip speed (m/s)"),
    };
    let (title, range) = speed_axis(tips, c_r);
    let mut position = LineChart::new("Crack tip extension", time, extension);
    let mut velocity = LineChart::new(&title, time, speed);
    if let Some((lo, hi)) = range {
        velocity = velocity.y_range(lo, hi);
    }
    if let Some((lo, hi)) = window {
        position = position.x_range(lo, hi);
        velocity = velocity.x_range(lo, hi);
    }
    for tip in tips {
        position = position.series(&tip.name, &tip.extension, tip.style);
        velocity = velocity.series(&tip.name, &tip.speed, tip.style);
    }
    if let Some(c_r) = c_r {
        let times = tips.iter().flat_map(|t| t.speed.iter().map(|p| p.0));
        let (first, last) = times.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
        if first < last {
            let line = [(first, c_r), (last, c_r)];
            velocity = velocity.series("Rayleigh speed c_R", &line, LineStyle::Dashed);
        }
    }
    if let Some(n) = normalization {
        let reference = lefm::tip_history((n.end - n.arrival) / n.tau, 400);
        let a: Vec<(f64, f64)> = reference.iter().map(|r| (r.0, r.1)).collect();
        let v: Vec<(f64, f64)> = reference.iter().map(|r| (r.0, r.2)).collect();
        position = position.series("LEFM (seed 2.61, 2.63)", &a, LineStyle::Dashed);
        velocity = velocity.series("LEFM (seed 2.61, 2.63)", &v, LineStyle::Dashed);
    }
    let half = (CRACK_PNG_SIZE.0, CRACK_PNG_SIZE.1 / 2);
    Ok(position.render(half)?.above(velocity.render(half)?))
}

/// Appends the series of the `crack_tips.csv` text `csv` to `tips`, one per interface tag (or
/// per branch, for runs with `[fracture]`), named `label, tag` (`label, branch N`); errors name
/// the `source` file.
pub(super) fn tip_series(
    (label, source): (&str, &str),
    csv: &str,
    normalization: Option<Normalization>,
    tips: &mut Vec<TipSeries>,
) -> Result<(), EngineError> {
    let first = tips.len();
    let table = ReadTable::parse(csv, source)?;
    let column = |name: &str| {
        (table.column(name))
            .ok_or_else(|| EngineError::Input(format!("{source}: no column {name}")))
    };
    let (tag, prefix) = match column("interface") {
        Ok(i) => (i, ""),
        Err(_) => (
            column("branch").map_err(|_| {
                EngineError::Input(format!("{source}: no column interface or branch"))
            })?,
            "branch ",
        ),
    };
    let (t, a, v) = (column("t_s")?, column("extension_m")?, column("speed_m_s")?);
    // x = (t - shift) * per_time, extension * per_length, speed * per_speed.
    let (shift, per_time, per_length, per_speed) = match normalization {
        Some(n) => (n.arrival, 1.0 / n.tau, 1.0 / (n.tau * n.c_r), 1.0 / n.c_r),
        None => (0.0, 1e6, 1e3, 1.0),
    };
    for row in table.rows() {
        let get = |i: usize| number(row.get(i));
        let name = format!("{label}, {prefix}{}", row.get(tag).unwrap_or(""));
        if tips[first..].last().is_none_or(|l| l.name != name) {
            tips.push(TipSeries {
                name,
                extension: Vec::new(),
                speed: Vec::new(),
                style: LineStyle::Solid,
            });
        }
        let entry = tips.last_mut().expect("pushed");
        let x = (get(t) - shift) * per_time;
        entry.extension.push((x, get(a) * per_length));
        // A crack shorter than one edge has no speed (NaN): nothing to draw.
        if get(v).is_finite() {
            entry.speed.push((x, get(v) * per_speed));
        }
    }
    Ok(())
}

/// Draws `crack_tips.csv`'s text `csv` as `dir/crack_tips.png`; a picture that cannot be drawn
/// is logged as a warning, never an error of the run.
pub fn write_crack_png(dir: &Path, csv: &str, normalization: Option<Normalization>) {
    let path = dir.join("crack_tips.png");
    let charts = crack_charts(&[("sdg", csv)], normalization);
    if let Err(e) = charts.and_then(|image| image.write_png(&path)) {
        tracing::warn!("{}: {e}", path.display());
    }
}

/// Draws the branch tips of a run with `[fracture]` (`crack_tips.csv`'s text `csv`) as
/// `dir/tip_speed.png`, the speed against the Rayleigh speed `c_r` (m/s); a picture that cannot
/// be drawn is logged as a warning.
pub fn write_tip_speed_png(dir: &Path, csv: &str, c_r: f64) {
    let path = dir.join("tip_speed.png");
    if let Err(e) = tip_speed_charts(csv, c_r).and_then(|image| image.write_png(&path)) {
        tracing::warn!("{}: {e}", path.display());
    }
}

/// The charts of `tip_speed.png` for `crack_tips.csv`'s text `csv` of a run with `[fracture]`.
fn tip_speed_charts(csv: &str, c_r: f64) -> Result<Image, EngineError> {
    let mut tips = Vec::new();
    tip_series(("sdg", "crack_tips.csv"), csv, None, &mut tips)?;
    render(&longest_named(tips), None, Some(c_r), None)
}

/// The speed chart's title and fixed y range: with the Rayleigh speed `c_r` (m/s) given and
/// states above [`SPEED_AXIS_C_R`] times it, the axis ends there and the title counts them;
/// otherwise the axis spans the points.
fn speed_axis(tips: &[TipSeries], c_r: Option<f64>) -> (String, Option<(f64, f64)>) {
    let speeds = || tips.iter().flat_map(|t| t.speed.iter().map(|p| p.1));
    let Some(c_r) = c_r else {
        return ("Crack tip speed".into(), None);
    };
    let top = SPEED_AXIS_C_R * c_r;
    let above = speeds().filter(|&v| v > top).count();
    if above == 0 {
        return ("Crack tip speed".into(), None);
    }
    let title = format!(
        "Crack tip speed ({above} states above {SPEED_AXIS_C_R} c_R, up to {:.2} c_R, run off the \
         top)",
        speeds().fold(top, f64::max) / c_r
    );
    (title, Some((speeds().fold(0.0, f64::min), top)))
}

/// `tips` with the [`NAMED_BRANCHES`] longest (by final extension; the earlier of equal ones)
/// kept, longest first, and the others faint, drawn first and named once in the legend.
fn longest_named(mut tips: Vec<TipSeries>) -> Vec<TipSeries> {
    let reach = |t: &TipSeries| t.extension.iter().map(|p| p.1).fold(0.0, f64::max);
    tips.sort_by(|a, b| reach(b).total_cmp(&reach(a)));
    let others = tips.split_off(NAMED_BRANCHES.min(tips.len()));
    let count = others.len();
    let mut all: Vec<TipSeries> = others
        .into_iter()
        .enumerate()
        .map(|(i, t)| TipSeries {
            name: if i == 0 {
                format!("{count} other branches")
            } else {
                String::new()
            },
            style: LineStyle::Faint,
            ..t
        })
        .collect();
    all.extend(tips);
    all
}

/// `sdg plot` of one or more runs' `crack_tips.csv` files: their tips drawn together, each run
/// named by its folder, into `out`. Errors name the file that cannot be read or lacks a column.
pub fn plot_tips(files: &[PathBuf], out: &Path) -> Result<(), EngineError> {
    let mut tips = Vec::new();
    for file in files {
        let source = file.display().to_string();
        let text = std::fs::read_to_string(file)
            .map_err(|e| EngineError::Input(format!("{source}: {e}")))?;
        let label = file
            .parent()
            .and_then(Path::file_name)
            .map_or_else(|| source.clone(), |n| n.to_string_lossy().into_owned());
        tip_series((&label, &source), &text, None, &mut tips)?;
    }
    super::canvas::make_folder(out)?;
    render(&tips, None, None, None)?.write_png(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tips_and_the_reference_are_drawn() {
        let mut csv =
            String::from("t_s,interface,x_m,y_m,extension_m,speed_m_s,process_zone_length_m\n");
        for i in 0..50 {
            let t = 1.6e-6 + 2e-8 * f64::from(i);
            csv += &format!("{t:e},path,0,0,{:e},{:e},0\n", 5e-6 * f64::from(i), 250.0);
        }
        let n = Normalization {
            tau: 6.5565e-7,
            c_r: 938.0,
            arrival: 5.74e-7,
            end: 2.87e-6,
        };
        for normalization in [None, Some(n)] {
            let image = crack_charts(&[("sdg", &csv)], normalization).unwrap();
            assert_eq!((image.width, image.height), CRACK_PNG_SIZE);
            let blue = image.rgb.chunks(3).filter(|p| p == &[31, 119, 180]).count();
            let orange = image.rgb.chunks(3).filter(|p| p == &[255, 127, 14]).count();
            assert!(blue > 500, "{blue}");
            assert_eq!(orange > 300, normalization.is_some(), "{orange}");
        }
        assert!(crack_charts(&[("sdg", "t_s,x\n")], None).is_err());
    }

    #[test]
    fn tip_speed_names_the_longest_branches_and_cuts_the_speed_axis() {
        const C_R: f64 = 938.0;
        let mut csv =
            String::from("t_s,branch,x_m,y_m,extension_m,speed_m_s,process_zone_length_m\n");
        // Branch b runs b + 1 states at 0.5 c_R; branch 3's last state bursts at 5 c_R.
        for b in 0..12 {
            for i in 0..=b {
                let speed = if (b, i) == (3, 3) { 5.0 } else { 0.5 } * C_R;
                let t = 1e-6 * (1.0 + 0.1 * f64::from(b) + 0.01 * f64::from(i));
                let a = 1e-5 * f64::from(i);
                csv += &format!("{t:e},{b},0,0,{a:e},{speed:e},0\n");
            }
        }
        let mut tips = Vec::new();
        tip_series(("sdg", "crack_tips.csv"), &csv, None, &mut tips).unwrap();
        let tips = longest_named(tips);
        let names: Vec<&str> = tips.iter().map(|t| t.name.as_str()).collect();
        assert_eq!(
            names[..5],
            ["4 other branches", "", "", "", "sdg, branch 11"]
        );
        assert_eq!(names[11], "sdg, branch 4");
        assert!(tips[..4].iter().all(|t| t.style == LineStyle::Faint));
        assert!(tips[4..].iter().all(|t| t.style == LineStyle::Solid));
        let image = tip_speed_charts(&csv, C_R).unwrap();
        let pixels = |c: [u8; 3]| image.rgb.chunks(3).filter(|p| *p == c).count();
        // Faint grey for branches 0 to 3; eight palette colours for branches 4 to 11 and the
        // ninth for the Rayleigh line; the tenth colour is unused.
        assert!(pixels([170, 170, 170]) > 100);
        assert!(pixels([188, 189, 34]) > 100, "the Rayleigh line");
        assert_eq!(pixels([23, 190, 207]), 0);
        let (title, range) = speed_axis(&tips, Some(C_R));
        assert_eq!(range, Some((0.0, 2.0 * C_R)));
        assert!(
            title.contains("1 states above 2 c_R, up to 5.00 c_R"),
            "{title}"
        );
        let (title, range) = speed_axis(&tips[4..], Some(C_R));
        assert_eq!((title.as_str(), range), ("Crack tip speed", None));
        assert_eq!(speed_axis(&tips, None).1, None);
    }
}
