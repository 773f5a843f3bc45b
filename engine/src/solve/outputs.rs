//! The files a run writes at its end, or as far as it got when it stops early.

use std::path::Path;

use sdg_mesh::Mesh;
use sdg_solver::crack::Crossing;
use sdg_solver::patch::InterfaceSample;

use crate::error::EngineError;
use crate::frontier::Frontier;
use crate::job::RunOptions;
use crate::output::write_output;
use crate::plot;
use crate::problem::Problem;

use super::book::TaggedCrossing;
use super::context::Solve;
use crate::fracture::picture;
use crate::fracture::records;
use crate::fracture::tips;
use crate::fracture::tips::CrackSummary;
use crate::lefm::{self, LefmComparison};
use crate::output::interface;
use crate::output::table::{ReadTable, number};

impl Solve<'_> {
    /// Writes what a run that stops before the end has produced so far: the history up to now
    /// (a row for the front as it is), the probes, the crack tips crossed so far and the
    /// fracture outputs of the front as it is; complete snapshots are already written. Each
    /// is tried whatever became of the others (the run is failing or stopping already: a
    /// full disk may still take the small files); failures are logged. Nothing when the run
    /// writes no files ([`Solve::writes`]).
    pub(crate) fn write_partial_outputs(&self, state: &Frontier, dir: &Path) {
        let config = &self.problem.loaded.config;
        let mut book = self.book.lock();
        book.progress.finish();
        if !self.writes() {
            return;
        }
        let warn = |what: &str, result: Result<(), EngineError>| {
            if let Err(e) = result {
                tracing::error!("{what} of the stopped run not written: {e}");
            }
        };
        warn("a snapshot", book.snapshots.finish());
        self.history_row(state, &mut book);
        warn(
            "history.csv",
            write_output(dir, "history.csv", book.history.as_bytes()).map(drop),
        );
        if config.output.png {
            plot::write_history_png(dir, &book.history);
        }
        let tips = crack_tips(
            self.problem,
            &state.mesh,
            &book.crossings,
            &book.fracture_events,
        );
        if let Some((csv, _)) = tips {
            warn("crack_tips.csv", write_crack_tips(self.problem, dir, &csv));
        }
        warn(
            "the crack files",
            self.write_fracture(state, &book.fracture_events, dir),
        );
        warn(
            "interface.csv",
            write_probes(self.problem, dir, &mut book.samples),
        );
    }

    /// With `[fracture]`: `events.csv` (`events`), `cracks.csv` and, with `output.png`,
    /// `crack_path.png` and `crack_zoom.png` of the crack edges on the front of `state`.
    pub(crate) fn write_fracture(
        &self,
        state: &Frontier,
        events: &[records::FractureEvent],
        dir: &Path,
    ) -> Result<(), EngineError> {
        let Some(fracture) = &self.problem.fracture else {
            return Ok(());
        };
        let config = &self.problem.loaded.config;
        write_output(
            dir,
            "events.csv",
            records::events_csv(events, &config.time).as_bytes(),
        )?;
        let cracks = front_cracks(self.problem, fracture, state);
        if config.output.png {
            let time = config.time.clock(state.front.min_time());
            let fork = (config.fracture.as_ref())
                .and_then(|f| f.macro_length)
                .and_then(|length| {
                    let tips = initial_tip_points(fracture, &self.problem.mesh);
                    records::macro_fork(&state.mesh, fracture, events, &cracks, length, &tips)
                });
            picture::write_crack_path_png(
                dir,
                &state.mesh,
                &cracks,
                fracture.tag,
                time,
                fork.map(|f| f.point),
            );
        }
        let csv = records::cracks_csv(&state.mesh, &cracks, events);
        write_output(dir, "cracks.csv", csv.as_bytes())?;
        Ok(())
    }

    /// Writes the trace of `--trace`.
    pub(crate) fn write_trace(&self, options: &RunOptions) -> Result<(), EngineError> {
        match (&self.tracer, &options.trace) {
            (Some(tracer), Some(path)) => tracer.write(path),
            _ => Ok(()),
        }
    }
}

/// With `[loading]`: its interface's tip states in `crack_tips` (the text of
/// `crack_tips.csv`: time, extension, speed and process zone) and the work of the cohesive
/// tractions in `history` (of `history.csv`) against LEFM; `None` without `[loading]` or
/// either table.
pub(crate) fn lefm(
    problem: &Problem,
    crack_tips: Option<&str>,
    history: &str,
) -> Option<LefmComparison> {
    let loading = problem.loading?;
    let config = &problem.loaded.config;
    let from = config.loading.as_ref()?.compare_from;
    let (t0, tau) = (config.time.clock(loading.arrival_time), loading.scales.tau);
    let columns = |text: &str, names: &[&str]| -> Option<Vec<Vec<f64>>> {
        let table = ReadTable::parse(text, "").ok()?;
        let at: Vec<usize> = names
            .iter()
            .map(|n| table.column(n))
            .collect::<Option<_>>()?;
        let tag = table.column("interface");
        let name = &config.loading.as_ref()?.interface;
        let rows = table
            .rows()
            .filter(|r| tag.is_none_or(|c| r.get(c) == Some(name)));
        let row = |r: &csv::StringRecord| at.iter().map(|&c| number(r.get(c))).collect();
        Some(rows.map(row).collect())
    };
    let normalized = |t: f64| (t - t0) / tau;
    let tips = columns(
        crack_tips?,
        &["t_s", "extension_m", "speed_m_s", "process_zone_length_m"],
    )?;
    let tips: Vec<lefm::TipPoint> = (tips.iter())
        .map(|r| lefm::TipPoint {
            time: normalized(r[0]),
            extension: r[1],
            speed: r[2],
            process_zone: r[3],
        })
        .collect();
    let work = columns(history, &["time_s", "fracture_energy_j"])?;
    let work: Vec<(f64, f64)> = work.iter().map(|r| (normalized(r[0]), r[1])).collect();
    let (scales, material) = (loading.scales, &problem.material);
    let units = lefm::Units {
        length: tau * scales.c_r,
        phi: scales.work_of_separation,
        c_r: scales.c_r,
        zone: lefm::ZoneEstimate::new(
            material.mu(),
            material.c_d(),
            material.c_s(),
            scales.work_of_separation,
            scales.sigma_bar / scales.load_ratio,
        ),
    };
    Some(lefm::compare(&tips, &work, from, &units))
}

/// `crack_tips.csv` and its summary from the tip `crossings` recorded so far (with their
/// edges' tags on `mesh`) and the fracture `events`: per crack branch with `[fracture]` (the
/// crossings of one tag would mix the tips of its branches), else per cohesive or damage
/// interface tag; `None` when the run tracks no crack tips.
pub(crate) fn crack_tips(
    problem: &Problem,
    mesh: &Mesh,
    crossings: &[TaggedCrossing],
    events: &[records::FractureEvent],
) -> Option<(String, CrackSummary)> {
    let c_r = problem.material.c_r();
    let time = &problem.loaded.config.time;
    if let Some(fracture) = &problem.fracture {
        let crossings: Vec<Crossing> = crossings.iter().map(|&(_, c)| c).collect();
        let zone = c_r * fracture.delay;
        let branches = records::branch_tips(events, &crossings, zone);
        Some(tips::tips_csv("branch", &branches, c_r, time))
    } else if problem.interfaces.any_cohesive() {
        let names = mesh.tag_names();
        let crossings: Vec<_> = crossings
            .iter()
            .map(|(tag, c)| {
                let name = tag.map_or("untagged", |t| names[t as usize].as_str());
                (name.to_string(), *c)
            })
            .collect();
        Some(tips::write(&crossings, c_r, time))
    } else {
        None
    }
}

/// Writes `crack_tips.csv` (its text `csv`) and, with `output.png`, its picture: the branch
/// tips' speeds with `[fracture]`, else the tips against LEFM in the normalized units of
/// `[loading]` up to the end time.
pub(crate) fn write_crack_tips(
    problem: &Problem,
    dir: &Path,
    csv: &str,
) -> Result<(), EngineError> {
    let time = &problem.loaded.config.time;
    write_output(dir, "crack_tips.csv", csv.as_bytes())?;
    if problem.loaded.config.output.png && problem.fracture.is_some() {
        plot::write_tip_speed_png(dir, csv, problem.material.c_r());
    } else if problem.loaded.config.output.png {
        let normalization = problem.loading.map(|l| plot::Normalization {
            tau: l.scales.tau,
            c_r: l.scales.c_r,
            arrival: time.clock(l.arrival_time),
            end: time.end,
        });
        plot::write_crack_png(dir, csv, normalization);
    }
    Ok(())
}

/// Writes `interface.csv` of `problem`'s probes from their `samples` when probes are
/// configured.
pub(crate) fn write_probes(
    problem: &Problem,
    dir: &Path,
    samples: &mut [(usize, InterfaceSample)],
) -> Result<(), EngineError> {
    let probes = &problem.probes;
    if !probes.is_empty() {
        let time = &problem.loaded.config.time;
        let text = interface::csv(probes, samples, time);
        write_output(dir, "interface.csv", text.as_bytes())?;
    }
    Ok(())
}

/// The crack edges of `state` with their damage on the front (initial cracks without a face
/// solved at their law's initial damage, 1 for other laws).
pub(crate) fn front_cracks(
    problem: &Problem,
    fracture: &crate::fracture::criteria::Fracture,
    state: &Frontier,
) -> Vec<records::CrackEdge> {
    records::crack_edges(
        &state.mesh,
        &state.solution,
        fracture,
        problem.loaded.config.solver.order,
        |tag| match problem.interfaces.law(tag) {
            sdg_solver::interface::Law::Damage(d) => d.initial,
            _ => 1.0,
        },
    )
}

/// The positions (m) of the tips of the initial cracks on the initial `mesh`.
pub(crate) fn initial_tip_points(
    fracture: &crate::fracture::criteria::Fracture,
    mesh: &Mesh,
) -> Vec<[f64; 2]> {
    (fracture.initial_tips(mesh).iter())
        .zip(mesh.vertices())
        .filter_map(|(tip, &p)| tip.as_ref().map(|_| p))
        .collect()
}
