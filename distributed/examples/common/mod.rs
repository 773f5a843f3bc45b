//! What the MPI examples share: their command line, MPI's start and the partition they name.

use std::ops::RangeInclusive;
use std::process::ExitCode;

use sdg_distributed::{MpiOptions, MpiTransport, Partition, Transport};
use sdg_mesh::Mesh;

/// The command line: cells along x and the partition's name.
pub struct Args {
    pub cells: u32,
    pub partition: String,
}

/// `[CELLS] [PARTITION]`, cells `default` when not given and within `range`.
fn parse_args(default: u32, range: RangeInclusive<u32>) -> Result<Args, String> {
    let mut args = std::env::args().skip(1);
    let cells = match args.next() {
        None => default,
        Some(s) => s
            .parse::<u32>()
            .ok()
            .filter(|n| range.contains(n))
            .ok_or(format!(
                "CELLS: `{s}` is not a whole number in {}..={}",
                range.start(),
                range.end()
            ))?,
    };
    let partition = args.next().unwrap_or_else(|| "coordinate".to_string());
    if !["coordinate", "striped", "random"].contains(&partition.as_str()) {
        return Err(format!(
            "PARTITION: `{partition}` is not one of coordinate, striped, random"
        ));
    }
    if let Some(extra) = args.next() {
        return Err(format!("unexpected argument `{extra}`"));
    }
    Ok(Args { cells, partition })
}

/// The command line of example `name` (cells `default` and within `range`) and MPI started;
/// the exit code when either fails (2 for bad arguments, with the usage; 1 when MPI does not
/// start).
pub fn start(
    name: &str,
    default: u32,
    range: RangeInclusive<u32>,
) -> Result<(Args, MpiTransport), ExitCode> {
    let args = parse_args(default, range).map_err(|e| {
        eprintln!("{name}: {e}\nusage: mpirun -n RANKS {name} [CELLS] [PARTITION]");
        ExitCode::from(2)
    })?;
    let transport = MpiTransport::start(MpiOptions::default()).map_err(|e| {
        eprintln!("{name}: {e}");
        ExitCode::from(1)
    })?;
    Ok((args, transport))
}

/// The partition of `mesh` that `args` names over the world size of `transport`.
pub fn partition(mesh: &Mesh, args: &Args, transport: &MpiTransport) -> Result<Partition, String> {
    let ranks = transport.ranks();
    match args.partition.as_str() {
        "striped" => Partition::striped(mesh, ranks),
        "random" => Partition::random(mesh, ranks, 17),
        _ => Partition::coordinate(mesh, ranks),
    }
    .map_err(|e| e.to_string())
}
