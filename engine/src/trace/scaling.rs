//! `sdg scaling`: a trace replayed on each number of workers asked for, on threads or over
//! ranks, and the picture of the predicted speedups.

use std::path::Path;

use super::entry::read;
use super::ranks::{
    RankModel, critical_path_over_ranks, cross_rank_fraction, replay_over_ranks, tents_on_ranks,
};
use super::replay::{Prediction, critical_path, replay};
use crate::error::EngineError;
use crate::plot::{LineChart, LineStyle};

/// What `sdg scaling` predicts for a trace.
#[derive(Clone, Debug, PartialEq)]
pub struct Scaling {
    /// One per number of workers asked for (per rank with ranks), as the scheduler runs
    /// ([`replay`]) or as the ranks run (module `ranks`).
    pub predictions: Vec<Prediction>,
    /// Its critical path, s.
    pub critical_s: f64,
    /// The wall time on one worker, s (without ranks).
    pub one_s: f64,
    /// With ranks, the fraction of the tents' dependencies that cross ranks.
    pub cross_rank: Option<f64>,
}

/// `sdg scaling`: replays the trace at `path` on each of `workers`, over the ranks of `ranks`
/// when given (each with that many workers); with `png`, draws the predicted speedups against
/// all the workers. Errors: a trace that cannot be read or has no tent, and one that `ranks`
/// cannot replay (a run that changed its mesh, another mesh), as bad input.
pub fn scaling_job(
    path: &Path,
    workers: &[usize],
    overhead_s: f64,
    ranks: Option<&RankModel>,
    png: Option<&Path>,
) -> Result<Scaling, EngineError> {
    let entries = read(path)?;
    if entries.is_empty() {
        return Err(EngineError::Input(format!(
            "{}: the trace has no tent",
            path.display()
        )));
    }
    let one_s = replay(&entries, 1, overhead_s).wall_time_s;
    let scaling = match ranks {
        None => Scaling {
            predictions: (workers.iter())
                .map(|&w| replay(&entries, w, overhead_s))
                .collect(),
            critical_s: critical_path(&entries, overhead_s),
            one_s,
            cross_rank: None,
        },
        Some(model) => {
            let tents = tents_on_ranks(&entries, model)?;
            Scaling {
                predictions: (workers.iter())
                    .map(|&w| replay_over_ranks(&tents, model, w, overhead_s))
                    .collect(),
                critical_s: critical_path_over_ranks(&tents, model, overhead_s),
                one_s,
                cross_rank: Some(cross_rank_fraction(&tents)),
            }
        }
    };
    if let Some(png) = png {
        let ranks = ranks.map_or(1, |m| m.ranks) as f64;
        let all = |p: &Prediction| ranks * p.workers as f64;
        let speedups: Vec<(f64, f64)> = (scaling.predictions.iter())
            .map(|p| (all(p), one_s / p.wall_time_s))
            .collect();
        let at = |y: f64| -> Vec<(f64, f64)> {
            (scaling.predictions.iter()).map(|p| (all(p), y)).collect()
        };
        let ideal: Vec<(f64, f64)> = (scaling.predictions.iter())
            .map(|p| (all(p), all(p)))
            .collect();
        let label = if ranks > 1.0 {
            "replayed trace over ranks"
        } else {
            "replayed trace"
        };
        LineChart::new("predicted speedup", "workers", "speedup over 1 worker")
            .series(label, &speedups, LineStyle::Solid)
            .series("ideal", &ideal, LineStyle::Dashed)
            .series(
                "critical path bound",
                &at(one_s / scaling.critical_s),
                LineStyle::Dashed,
            )
            .write_png(png, (900, 600))?;
    }
    Ok(scaling)
}
