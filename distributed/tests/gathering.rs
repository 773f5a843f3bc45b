//! The ranks' results gathered on rank 0 through a transport are those gathered in one
//! process, and every element and face is the serial run's.

use std::time::Duration;

use sdg_distributed::{
    Causality, Gathered, Loopback, LoopbackOptions, Options, Partition, Physics, gather,
    gather_threads, solve_threads,
};
use sdg_engine::{LoadedConfig, Problem, causality, physics};
use sdg_solver::element::FrontSolution;

/// `configs/stick_slip.toml` on 6 x 6 cells to 3 us: friction faces that slip.
fn stick_slip(dir: &std::path::Path) -> Problem {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../configs/stick_slip.toml");
    let overrides = [
        "mesh.nx=6".to_string(),
        "mesh.ny=6".to_string(),
        "time.end=3e-6".to_string(),
        "output.snapshot_times=[]".to_string(),
        "output.interface_probes=[]".to_string(),
        format!("output.dir=\"{}\"", dir.display()),
    ];
    Problem::setup(LoadedConfig::load(path.as_ref(), &overrides).unwrap()).unwrap()
}

fn setup(problem: &Problem) -> (Causality, Physics<'_>) {
    (causality(problem), physics(problem, &[]))
}

/// Every element's and face's bits, by global id.
fn bits(solution: &FrontSolution) -> Vec<Vec<u64>> {
    let elements = (0..solution.len()).map(|t| {
        let energy = solution.energy(t).unwrap_or([f64::NAN; 3]);
        solution.with_element(t, |element| {
            let (geometry, coefficients) = element.expect("every element solved");
            (geometry
                .to_values()
                .iter()
                .chain(&energy)
                .chain(coefficients))
            .map(|x| x.to_bits())
            .collect()
        })
    });
    let faces = (0..solution.edges()).map(|e| {
        solution.face(e).map_or(Vec::new(), |face| {
            (face.geometry.to_values().iter())
                .chain(face.coefficients.iter().flatten())
                .map(|x| x.to_bits())
                .collect()
        })
    });
    elements.chain(faces).collect()
}

fn times(gathered: &Gathered) -> Vec<u64> {
    gathered
        .front
        .snapshot()
        .iter()
        .map(|t| t.to_bits())
        .collect()
}

#[test]
fn gathering_through_a_transport_gives_the_serial_runs_elements_and_tents() {
    let dir = tempfile::tempdir().unwrap();
    let problem = stick_slip(dir.path());
    let mesh = &problem.mesh;
    let (causality, physics) = setup(&problem);
    let fifo = LoopbackOptions {
        seed: 0,
        max_delay: Duration::ZERO,
        fifo: true,
    };
    let options = Options::new(3, Duration::from_secs(20));
    let one = Partition::coordinate(mesh, 1).unwrap();
    let serial = solve_threads(mesh, &one, causality, physics, fifo, &options).unwrap();
    let serial = gather_threads(mesh, &serial).unwrap();

    let partition = Partition::random(mesh, 3, 5).unwrap();
    let ranks = solve_threads(mesh, &partition, causality, physics, fifo, &options).unwrap();
    let in_process = gather_threads(mesh, &ranks).unwrap();
    let delays = LoopbackOptions {
        seed: 9,
        max_delay: Duration::from_micros(200),
        fifo: false,
    };
    let ends = Loopback::connect(3, delays);
    let sent: Vec<Option<Gathered>> = std::thread::scope(|s| {
        let handles: Vec<_> = (ends.into_iter().zip(&ranks))
            .map(|(mut end, rank)| {
                s.spawn(move || {
                    let parts = (&rank.front, &rank.solution, &rank.report);
                    gather(mesh, &rank.view, parts, &mut end, Duration::from_secs(20)).unwrap()
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert!(
        sent[1].is_none() && sent[2].is_none(),
        "only rank 0 gathers"
    );
    let sent = sent.into_iter().next().flatten().expect("rank 0 gathers");

    let reference = bits(&serial.solution);
    assert!(
        bits(&in_process.solution) == reference,
        "gathered in one process"
    );
    assert!(
        bits(&sent.solution) == reference,
        "gathered through the transport"
    );
    assert_eq!(times(&sent), times(&serial));
    assert!(
        times(&sent)
            .iter()
            .all(|&t| f64::from_bits(t) == causality.t_end)
    );
    let slipped = (0..sent.solution.edges())
        .filter_map(|e| sent.solution.face(e))
        .filter(|f| f.coefficients.iter().flatten().any(|&x| x != 0.0))
        .count();
    assert!(slipped > 0, "some interface faces moved");
    // The same tents with the same patches, in the serial order.
    let order = |g: &Gathered| {
        (g.in_serial_order().into_iter())
            .map(|(tent, patch)| (tent.vertex, tent.t_old.to_bits(), patch.report))
            .collect::<Vec<_>>()
    };
    let strip = |mut v: Vec<(u32, u64, sdg_solver::patch::PatchReport)>| {
        // Wall times differ from run to run.
        for (_, _, r) in &mut v {
            (r.assembly_s, r.solve_s, r.evaluation_s) = (0.0, 0.0, 0.0);
        }
        v
    };
    assert_eq!(strip(order(&sent)), strip(order(&serial)));
    assert_eq!(sent.reports.len(), 3);
    let updates: u64 = sent.reports.iter().map(|r| r.updates_sent).sum();
    let expected: u64 = ranks.iter().map(|r| r.report.updates_sent).sum();
    assert_eq!(updates, expected);
    assert!(updates > 0);
}

/// Ranks that keep no tents (`Options::keep_tents`, what `sdg run` over ranks does: its
/// observer tallies them) gather the same elements and count the same tents, and hold none.
#[test]
fn ranks_that_keep_no_tents_count_them_and_gather_the_same_state() {
    let dir = tempfile::tempdir().unwrap();
    let problem = stick_slip(dir.path());
    let mesh = &problem.mesh;
    let (causality, physics) = setup(&problem);
    let delays = LoopbackOptions {
        seed: 4,
        max_delay: Duration::from_micros(100),
        fifo: false,
    };
    let partition = Partition::random(mesh, 3, 5).unwrap();
    let kept = Options::new(3, Duration::from_secs(20));
    let kept = solve_threads(mesh, &partition, causality, physics, delays, &kept).unwrap();
    let kept = gather_threads(mesh, &kept).unwrap();
    let none = Options {
        keep_tents: false,
        ..Options::new(3, Duration::from_secs(20))
    };
    let ranks = solve_threads(mesh, &partition, causality, physics, delays, &none).unwrap();
    for rank in &ranks {
        assert!(rank.report.tents.is_empty() && rank.report.patches.is_empty());
        assert!(rank.report.pitched > 0);
    }
    let gathered = gather_threads(mesh, &ranks).unwrap();
    assert!(gathered.tents.is_empty());
    assert_eq!(gathered.tents_by_rank, kept.tents_by_rank);
    let total: u64 = gathered.tents_by_rank.iter().sum();
    assert_eq!(total, kept.tents.len() as u64);
    assert!(bits(&gathered.solution) == bits(&kept.solution));
    assert_eq!(times(&gathered), times(&kept));
}
