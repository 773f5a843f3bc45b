//! Distributed asynchronous pitching over MPI, checked against the serial order on every rank.
//!
//! ```text
//! cargo build --release -p sdg-distributed --features mpi --example mpi_pitch
//! mpirun -n 4 target/release/examples/mpi_pitch [CELLS] [PARTITION]
//! ```
//!
//! Every rank builds the same perturbed rectangle of `CELLS` x `4 CELLS / 5` cells (default
//! 48), partitions it over the world size (`coordinate`, the default, `striped` or `random`),
//! pitches its owned vertices with [`MpiTransport`] to t = 0.3 s (c = 1 m/s, safety 0.5), and
//! compares its owned vertices' tent sequences `(t_old, t_new)` bitwise with a serial pitching
//! of the whole mesh that it runs itself. Each rank prints one line, rank 0 the totals with
//! the update messages per tent. Exit code 0 when every rank's tents are the serial ones, 1
//! when any differ or the run failed, 2 for bad arguments.

mod common;

use std::process::ExitCode;
use std::time::{Duration, Instant};

use sdg_distributed::{
    Causality, LocalView, MpiTransport, Options, Partition, RankReport, Transport, pitch_rank,
};
use sdg_mesh::{Diagonal, Front, Mesh, Pitcher, Rectangle, VertexId};
use sdg_scheduler::run_serial;

const CAUSALITY: Causality = Causality {
    c_max: 1.0,
    safety: 0.5,
    t_end: 0.3,
};

/// Per vertex, the bit patterns of `(t_old, t_new)` of its tents in order.
type Sequences = Vec<Vec<(u64, u64)>>;

fn rectangle(cells: u32) -> Result<Mesh, String> {
    Rectangle {
        width: 1.0,
        height: 0.8,
        nx: cells,
        ny: cells * 4 / 5,
        diagonal: Diagonal::Alternate,
        interfaces: Vec::new(),
        sides: Vec::new(),
        perturb: 0.2,
        seed: 4,
    }
    .build()
    .map_err(|e| e.to_string())
}

/// The serial reference order on the whole mesh from a flat front at 0: always the earliest
/// vertex, ties to the smaller id.
fn serial(mesh: &Mesh) -> Result<Sequences, String> {
    let Causality {
        c_max,
        safety,
        t_end,
    } = CAUSALITY;
    let pitcher = Pitcher::new(mesh, c_max, safety, t_end).map_err(|e| e.to_string())?;
    let n = mesh.vertices().len();
    let front = Front::flat(n, 0.0);
    let mut sequences = vec![Vec::new(); n];
    run_serial(&vec![0.0; n], t_end, |v| {
        let tent = pitcher.pitch(mesh, &front, v).ok_or(v)?;
        sequences[v as usize].push((tent.t_old.to_bits(), tent.t_new.to_bits()));
        Ok::<f64, VertexId>(tent.t_new)
    })
    .map_err(|e| format!("serial pitching failed: {e:?}"))?;
    Ok(sequences)
}

/// Pitches this rank's share; returns its report and the wall time.
fn pitch(
    mesh: &Mesh,
    partition: &Partition,
    transport: &mut MpiTransport,
) -> Result<(RankReport, Duration), String> {
    let view = LocalView::new(mesh, partition, transport.rank()).map_err(|e| e.to_string())?;
    let Causality {
        c_max,
        safety,
        t_end,
    } = CAUSALITY;
    let pitcher = Pitcher::new(view.mesh(), c_max, safety, t_end).map_err(|e| e.to_string())?;
    let front = Front::flat(view.mesh().vertices().len(), 0.0);
    let options = Options::new(1, Duration::from_secs(20));
    // Start together, so that the wait below is for updates, not for slower process starts.
    transport.sum(&[0]).map_err(|e| e.to_string())?;
    let start = Instant::now();
    let report =
        pitch_rank(&view, &pitcher, &front, transport, &options).map_err(|e| e.to_string())?;
    Ok((report, start.elapsed()))
}

/// Owned vertices (global ids) whose tent sequence differs from the reference.
fn differing(report: &RankReport, partition: &Partition, reference: &Sequences) -> usize {
    let mut got: Sequences = vec![Vec::new(); reference.len()];
    for tent in &report.tents {
        got[tent.vertex as usize].push((tent.t_old.to_bits(), tent.t_new.to_bits()));
    }
    (0..reference.len())
        .filter(|&v| partition.owner(v as VertexId) == report.rank)
        .filter(|&v| got[v] != reference[v])
        .count()
}

fn main() -> ExitCode {
    let (args, mut transport) = match common::start("mpi_pitch", 48, 5..=2000) {
        Ok(started) => started,
        Err(code) => return code,
    };
    let rank = transport.rank();
    let ranks = transport.ranks();
    let outcome = rectangle(args.cells).and_then(|mesh| {
        let partition = common::partition(&mesh, &args, &transport)?;
        let (report, elapsed) = pitch(&mesh, &partition, &mut transport)?;
        let reference = serial(&mesh)?;
        let differ = differing(&report, &partition, &reference);
        let serial_tents: usize = reference.iter().map(Vec::len).sum();
        Ok((report, elapsed, differ, serial_tents))
    });
    let (report, elapsed, differ, serial_tents) = match outcome {
        Ok(outcome) => outcome,
        Err(e) => {
            eprintln!("mpi_pitch: rank {rank}: {e}");
            transport.abort(1);
        }
    };
    let tents = report.tents.len() as u64;
    println!(
        "rank {rank}/{ranks}: {tents} tents, {} updates sent ({} applied, {} stale), {} boundary \
         vertices, waited {:.1} ms of {:.1} ms, {differ} owned vertices differ from the serial order",
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
        report.boundary_vertices as u64,
        differ as u64,
    ];
    let sums = match transport.sum(&totals) {
        Ok(sums) => sums,
        Err(e) => {
            eprintln!("mpi_pitch: rank {rank}: {e}");
            return ExitCode::from(1);
        }
    };
    drop(transport);
    let [tents, updates, bytes, boundary, differ] = sums[..] else {
        unreachable!("as many sums as values")
    };
    let same = differ == 0 && tents == serial_tents as u64;
    if rank == 0 {
        println!(
            "{ranks} ranks, {} partition: {tents} tents (serial {serial_tents}), {updates} \
             update messages ({:.4} per tent, {:.3} bytes per tent), {boundary} boundary \
             vertices; {}",
            args.partition,
            updates as f64 / tents.max(1) as f64,
            bytes as f64 / tents.max(1) as f64,
            if same {
                "tents bitwise the serial order's".to_string()
            } else {
                format!("{differ} vertices differ from the serial order")
            }
        );
    }
    if same {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}
