//! Patches solved over MPI, checked against the serial run on every rank.
//!
//! ```text
//! cargo build --release -p sdg-distributed --features mpi --example mpi_solve
//! mpirun -n 4 target/release/examples/mpi_solve [CELLS] [PARTITION]
//! ```
//!
//! Every rank sets up `configs/plane_wave.toml` (an oblique P wave through a PMMA square, the
//! exact solution on every side, order 2, to 2 us) on `CELLS` x `CELLS` cells (default 16),
//! partitions it over the world size (`coordinate`, the default, `striped` or `random`),
//! solves its owned vertices' patches with [`MpiTransport`], and compares every element of its
//! view bitwise with a serial run of the whole mesh that it runs itself (one rank, the serial
//! order). Each rank prints one line, rank 0 the totals with the update messages and bytes per
//! tent. Exit code 0 when every rank's elements are the serial ones, 1 when any differ or the
//! run failed, 2 for bad arguments.

mod common;

use std::process::ExitCode;
use std::time::{Duration, Instant};

use sdg_distributed::{
    Causality, LocalView, LoopbackOptions, MpiTransport, Options, Partition, Physics, RankReport,
    RankSolution, Transport, solve_rank, solve_threads,
};
use sdg_engine::{LoadedConfig, Problem, causality, physics};
use sdg_mesh::{Front, Pitcher};
use sdg_solver::element::FrontSolution;

/// The shipped plane-wave config on `cells` x `cells` cells.
fn plane_wave(cells: u32) -> Result<Problem, String> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../configs/plane_wave.toml");
    let overrides = [format!("mesh.nx={cells}"), format!("mesh.ny={cells}")];
    let loaded = LoadedConfig::load(path.as_ref(), &overrides).map_err(|e| e.to_string())?;
    Problem::setup(loaded).map_err(|e| e.to_string())
}

fn setup(problem: &Problem) -> (Causality, Physics<'_>) {
    (causality(problem), physics(problem, &[]))
}

/// Solves this rank's share; returns its view, report, elements and the wall time.
fn solve(
    problem: &Problem,
    partition: &Partition,
    transport: &mut MpiTransport,
) -> Result<(LocalView, RankReport, FrontSolution, Duration), String> {
    let (causality, physics) = setup(problem);
    let view =
        LocalView::new(&problem.mesh, partition, transport.rank()).map_err(|e| e.to_string())?;
    let pitcher = Pitcher::new(
        view.mesh(),
        causality.c_max,
        causality.safety,
        causality.t_end,
    )
    .map_err(|e| e.to_string())?;
    let front = Front::flat(view.mesh().vertices().len(), 0.0);
    let solution = physics.initial_solution(&view);
    let options = Options::new(1, Duration::from_secs(60));
    // Start together, so that the wait below is for updates, not for slower process starts.
    transport.sum(&[0]).map_err(|e| e.to_string())?;
    let start = Instant::now();
    let report = solve_rank(
        &view, &pitcher, &front, &solution, physics, transport, &options,
    )
    .map_err(|e| e.to_string())?;
    Ok((view, report, solution, start.elapsed()))
}

/// The serial run of the whole mesh: one rank, no messages.
fn serial(problem: &Problem) -> Result<RankSolution, String> {
    let (causality, physics) = setup(problem);
    let one = Partition::coordinate(&problem.mesh, 1).map_err(|e| e.to_string())?;
    let fifo = LoopbackOptions {
        seed: 0,
        max_delay: Duration::ZERO,
        fifo: true,
    };
    let options = Options::new(0, Duration::from_secs(60));
    let mut ranks = solve_threads(&problem.mesh, &one, causality, physics, fifo, &options)
        .map_err(|e| e.to_string())?;
    ranks.pop().ok_or("no rank".to_string())
}

/// One element's bits: top facet energy parts and coefficients, with the geometry's values.
fn bits(solution: &FrontSolution, t: usize) -> Option<Vec<u64>> {
    let energy = solution.energy(t).unwrap_or([f64::NAN; 3]);
    solution.with_element(t, |element| {
        element.map(|(geometry, coefficients)| {
            let values = geometry.to_values();
            values
                .iter()
                .chain(&energy)
                .chain(coefficients)
                .map(|x| x.to_bits())
                .collect()
        })
    })
}

/// Elements of `view` (local ids in `solution`) that are not bitwise the serial run's.
fn differing(view: &LocalView, solution: &FrontSolution, reference: &RankSolution) -> usize {
    (0..view.mesh().triangles().len())
        .filter(|&t| {
            let global = view.global_triangle(t as u32) as usize;
            bits(solution, t) != bits(&reference.solution, global)
        })
        .count()
}

fn main() -> ExitCode {
    let (args, mut transport) = match common::start("mpi_solve", 16, 2..=512) {
        Ok(started) => started,
        Err(code) => return code,
    };
    let rank = transport.rank();
    let ranks = transport.ranks();
    let outcome = plane_wave(args.cells).and_then(|problem| {
        let mesh = &problem.mesh;
        let partition = common::partition(mesh, &args, &transport)?;
        let (view, report, solution, elapsed) = solve(&problem, &partition, &mut transport)?;
        let reference = serial(&problem)?;
        let differ = differing(&view, &solution, &reference);
        let serial_tents = reference.report.tents.len();
        Ok((report, elapsed, differ, serial_tents))
    });
    let (report, elapsed, differ, serial_tents) = match outcome {
        Ok(outcome) => outcome,
        Err(e) => {
            eprintln!("mpi_solve: rank {rank}: {e}");
            transport.abort(1);
        }
    };
    let tents = report.tents.len() as u64;
    println!(
        "rank {rank}/{ranks}: {tents} patches, {} updates sent ({} applied, {} stale), {} \
         boundary vertices, waited {:.1} ms of {:.1} ms, {differ} elements differ from the \
         serial run's",
        report.updates_sent,
        report.updates_applied,
        report.updates_stale,
        report.boundary_vertices,
        report.waited.as_secs_f64() * 1e3,
        elapsed.as_secs_f64() * 1e3,
    );
    let totals = [
        tents,
        report.updates_sent,
        report.update_bytes,
        differ as u64,
    ];
    let sums = match transport.sum(&totals) {
        Ok(sums) => sums,
        Err(e) => {
            eprintln!("mpi_solve: rank {rank}: {e}");
            return ExitCode::from(1);
        }
    };
    drop(transport);
    let [tents, updates, bytes, differ] = sums[..] else {
        unreachable!("as many sums as values")
    };
    let same = differ == 0 && tents == serial_tents as u64;
    if rank == 0 {
        println!(
            "{ranks} ranks, {} partition: {tents} patches (serial {serial_tents}), {updates} \
             update messages ({:.4} per tent, {:.1} bytes per tent); {}",
            args.partition,
            updates as f64 / tents.max(1) as f64,
            bytes as f64 / tents.max(1) as f64,
            if same {
                "elements bitwise the serial run's".to_string()
            } else {
                format!("{differ} elements differ from the serial run's")
            }
        );
    }
    if same {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}
