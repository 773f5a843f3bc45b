//! `sdg plot --lefm RUN...`: the seed's figures 2.6 to 2.10 from runs of the mode-I problem
//! (configs with `[loading]`), one curve per run (per load ratio) in the seed's normalized
//! units: time `t' = (t - t0) / tau'`, extension `a' = a / (tau' c_R)`, speed over `c_R`.
//!
//! Each run folder gives its `summary.json` (`loading`: `tau'`, `c_R`, `t0`, `phi`, the load
//! ratio; `lefm.zone_estimate`: the process zone's steady-state estimate), `crack_tips.csv` and
//! `history.csv`. Written into the output folder:
//! - `lefm_tips.png` (Figs. 2.6 and 2.8): extension and speed against `t'` with the LEFM tip;
//! - `lefm_tips_early.png` (Fig. 2.7): the same up to `t' = 4`;
//! - `lefm_energy_release.png` (Fig. 2.9): `G / phi` against `t'`, `G` the growth of
//!   `history.csv`'s `fracture_energy_j` over the growth of the extension in windows of
//!   [`G_WINDOW`] `tau'` (the latest tip state at or before each row);
//! - `lefm_process_zone.png` (Fig. 2.10): the process zone over its steady-state estimate
//!   `Lambda / Lambda(v)` against the speed over `c_R`, at the tip states below `c_R` whose
//!   zone has a trailing edge (`lefm.process_zone_over_estimate` counts the same from 0.5 `c_R`).

use std::path::{Path, PathBuf};

use super::crack::{Normalization, render, tip_series};
use super::line::{LineChart, LineStyle};
use crate::error::EngineError;
use crate::lefm::ZoneEstimate;
use crate::output::table::{ReadTable, number};

/// Width of the windows over which `lefm_energy_release.png` measures `G`, in `tau'`.
pub const G_WINDOW: f64 = 0.5;

/// `lefm_tips_early.png` ends at this `t'` (the seed's Fig. 2.7 shows the early stages).
const EARLY_END: f64 = 4.0;

/// Size of the single-chart pictures, pixels.
const CHART_SIZE: (u32, u32) = (1000, 650);

/// What one run folder gives.
struct Run {
    /// `sigma' = 10^x`, for the legend.
    label: String,
    /// The load ratio `sigma'`, by which the runs are ordered.
    ratio: f64,
    normalization: Normalization,
    /// `phi`, J/m^2.
    phi: f64,
    zone: ZoneEstimate,
    tips: String,
    history: String,
    /// The folder, for messages.
    dir: PathBuf,
}

/// Draws the figures of the runs in `dirs` into the folder `out` (made if missing); returns
/// the pictures written. Errors name the file that is missing or lacks a key or column.
pub fn plot_lefm(dirs: &[PathBuf], out: &Path) -> Result<Vec<PathBuf>, EngineError> {
    let mut runs = dirs
        .iter()
        .map(|d| read_run(d))
        .collect::<Result<Vec<_>, _>>()?;
    runs.sort_by(|a, b| a.ratio.total_cmp(&b.ratio));
    std::fs::create_dir_all(out).map_err(|e| EngineError::io(out, e))?;
    let mut tips = Vec::new();
    for run in &runs {
        let source = run.dir.join("crack_tips.csv").display().to_string();
        tip_series(
            (&run.label, &source),
            &run.tips,
            Some(run.normalization),
            &mut tips,
        )?;
    }
    // The LEFM tip up to the latest end.
    let latest = (runs.iter().map(|r| r.normalization))
        .max_by(|a, b| {
            let end = |n: &Normalization| (n.end - n.arrival) / n.tau;
            end(a).total_cmp(&end(b))
        })
        .ok_or_else(|| {
            EngineError::Input("sdg plot --lefm: give at least one run folder".into())
        })?;
    let mut written = Vec::new();
    let mut write = |name: &str, image: super::canvas::Image| {
        let path = out.join(name);
        image.write_png(&path)?;
        written.push(path);
        Ok::<(), EngineError>(())
    };
    write("lefm_tips.png", render(&tips, Some(latest), None, None)?)?;
    let early = Some((0.0, EARLY_END));
    write(
        "lefm_tips_early.png",
        render(&tips, Some(latest), None, early)?,
    )?;
    let mut release = LineChart::new(
        &format!("Energy release rate (over windows of {G_WINDOW} tau')"),
        "normalized time t' = (t - t0) / tau'",
        "G / phi",
    );
    let mut zone = LineChart::new(
        "Process zone over its steady-state estimate (zeta = 9/16)",
        "tip speed / c_R",
        "Lambda / Lambda(v)",
    )
    .x_range(0.0, 1.0);
    for run in &runs {
        release = release.series(&run.label, &energy_release(run)?, LineStyle::Solid);
        zone = zone.series(&run.label, &zone_ratio(run)?, LineStyle::Solid);
    }
    let t_end = (latest.end - latest.arrival) / latest.tau;
    let phi_line = [(0.0, 1.0), (t_end, 1.0)];
    release = release.series("phi", &phi_line, LineStyle::Dashed);
    zone = zone.series("estimate", &[(0.0, 1.0), (1.0, 1.0)], LineStyle::Dashed);
    write("lefm_energy_release.png", release.render(CHART_SIZE)?)?;
    write("lefm_process_zone.png", zone.render(CHART_SIZE)?)?;
    Ok(written)
}

/// The run in folder `dir`.
fn read_run(dir: &Path) -> Result<Run, EngineError> {
    let read = |name: &str| {
        let path = dir.join(name);
        std::fs::read_to_string(&path).map_err(|e| EngineError::io(&path, e))
    };
    let summary_path = dir.join("summary.json").display().to_string();
    let summary: serde_json::Value = serde_json::from_str(&read("summary.json")?)
        .map_err(|e| EngineError::Input(format!("{summary_path}: {e}")))?;
    let key = |path: &str| {
        let mut value = &summary;
        for part in path.split('.') {
            value = &value[part];
        }
        value.as_f64().ok_or_else(|| {
            EngineError::Input(format!(
                "{summary_path}: no number at {path} (a run with [loading] writes it)"
            ))
        })
    };
    let ratio = key("loading.load_ratio")?;
    Ok(Run {
        label: format!("sigma' = 10^{:.3}", ratio.log10()),
        ratio,
        normalization: Normalization {
            tau: key("loading.tau_prime")?,
            c_r: key("loading.c_r")?,
            arrival: key("loading.arrival_time")?,
            end: key("final_time")?,
        },
        phi: key("loading.work_of_separation")?,
        zone: ZoneEstimate {
            quasi_static: key("lefm.zone_estimate.quasi_static")?,
            c_d: key("lefm.zone_estimate.c_d")?,
            c_s: key("lefm.zone_estimate.c_s")?,
        },
        tips: read("crack_tips.csv")?,
        history: read("history.csv")?,
        dir: dir.to_path_buf(),
    })
}

/// The columns `names` of the CSV text `text` read from `source`, row by row.
fn columns(text: &str, source: &Path, names: &[&str]) -> Result<Vec<Vec<f64>>, EngineError> {
    let source = source.display().to_string();
    let table = ReadTable::parse(text, &source)?;
    let index = (names.iter())
        .map(|n| {
            (table.column(n)).ok_or_else(|| EngineError::Input(format!("{source}: no column {n}")))
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok((table.rows())
        .map(|row| index.iter().map(|&i| number(row.get(i))).collect())
        .collect())
}

/// `(t', G / phi)` of `run`: per window of [`G_WINDOW`] `tau'` between history rows, the growth
/// of the fracture energy over the growth of the extension, at the window's middle; windows
/// over which the tip did not move are left out.
fn energy_release(run: &Run) -> Result<Vec<(f64, f64)>, EngineError> {
    let n = run.normalization;
    let t = |s: f64| (s - n.arrival) / n.tau;
    let tips = columns(
        &run.tips,
        &run.dir.join("crack_tips.csv"),
        &["t_s", "extension_m"],
    )?;
    let work = columns(
        &run.history,
        &run.dir.join("history.csv"),
        &["time_s", "fracture_energy_j"],
    )?;
    let extension = |time: f64| {
        (tips.iter())
            .take_while(|r| r[0] <= time)
            .map(|r| r[1])
            .fold(0.0, f64::max)
    };
    let mut out = Vec::new();
    let mut start = 0;
    for end in 1..work.len() {
        let (a, b) = (&work[start], &work[end]);
        if t(b[0]) - t(a[0]) < G_WINDOW {
            continue;
        }
        let grown = extension(b[0]) - extension(a[0]);
        if grown > 0.0 {
            let g = (b[1] - a[1]) / grown / run.phi;
            out.push((0.5 * (t(a[0]) + t(b[0])), g));
        }
        start = end;
    }
    Ok(out)
}

/// `(v / c_R, Lambda / Lambda(v))` at the tip states of `run` below `c_R` with a fitted speed
/// and a zone shorter than the extension, in time order.
fn zone_ratio(run: &Run) -> Result<Vec<(f64, f64)>, EngineError> {
    let c_r = run.normalization.c_r;
    let tips = columns(
        &run.tips,
        &run.dir.join("crack_tips.csv"),
        &["extension_m", "speed_m_s", "process_zone_length_m"],
    )?;
    Ok((tips.iter())
        .filter(|r| r[1].is_finite() && r[1] > 0.0 && r[1] < c_r)
        .filter(|r| r[2] < r[0] * (1.0 - 1e-9))
        .map(|r| (r[1] / c_r, r[2] / run.zone.at(r[1])))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run folder whose tip starts at `t' = 1`, runs at `0.5 c_R`, with a process zone of
    /// twice the estimate, and releases `phi` per unit extension.
    fn fake_run(dir: &Path, ratio: f64) {
        let (tau, c_r, phi) = (1e-7, 1000.0, 2.0);
        let zone = ZoneEstimate::new(1e9, 2000.0, 1100.0, phi, 1e7);
        let summary = serde_json::json!({
            "final_time": 10.0 * tau,
            "loading": {"load_ratio": ratio, "tau_prime": tau, "c_r": c_r,
                        "arrival_time": 0.0, "work_of_separation": phi},
            "lefm": {"zone_estimate": zone},
        });
        std::fs::create_dir_all(dir).unwrap();
        std::fs::write(dir.join("summary.json"), summary.to_string()).unwrap();
        let mut tips =
            String::from("t_s,interface,x_m,y_m,extension_m,speed_m_s,process_zone_length_m\n");
        let mut history = String::from("time_s,fracture_energy_j\n");
        for k in 0..=100 {
            let t = k as f64 * 0.1 * tau;
            let a = (0.5 * c_r * (t - tau)).max(0.0);
            if t > tau {
                let lambda = 2.0 * zone.at(0.5 * c_r);
                tips += &format!("{t:e},crack,{a:e},0,{a:e},{:e},{lambda:e}\n", 0.5 * c_r);
            }
            history += &format!("{t:e},{:e}\n", phi * a);
        }
        std::fs::write(dir.join("crack_tips.csv"), tips).unwrap();
        std::fs::write(dir.join("history.csv"), history).unwrap();
    }

    #[test]
    fn the_figures_read_back_what_the_runs_hold() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a"), dir.path().join("b"));
        fake_run(&a, 0.1);
        fake_run(&b, 10f64.powf(-0.5));
        let run = read_run(&a).unwrap();
        assert_eq!(run.label, "sigma' = 10^-1.000");
        let g = energy_release(&run).unwrap();
        assert!(!g.is_empty());
        for (t, g) in g.iter().filter(|p| p.0 > 2.0) {
            assert!((g - 1.0).abs() < 1e-9, "G / phi = {g} at t' = {t}");
        }
        let zone = zone_ratio(&run).unwrap();
        assert!(!zone.is_empty());
        for (v, r) in zone {
            assert!((v - 0.5).abs() < 1e-12 && (r - 2.0).abs() < 1e-9, "{v} {r}");
        }
        let out = dir.path().join("figures");
        let written = plot_lefm(&[a, b], &out).unwrap();
        assert_eq!(written.len(), 4);
        for path in written {
            assert!(std::fs::metadata(&path).unwrap().len() > 1000, "{path:?}");
        }
    }

    #[test]
    fn a_run_without_loading_is_refused_naming_the_file_and_key() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("summary.json"), "{\"final_time\": 1.0}").unwrap();
        let Err(e) = plot_lefm(&[dir.path().to_path_buf()], &dir.path().join("out")) else {
            panic!("accepted");
        };
        let message = e.to_string();
        assert!(message.contains("summary.json"), "{message}");
        assert!(message.contains("loading.load_ratio"), "{message}");
    }
}
