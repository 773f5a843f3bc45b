//! Patches solved over ranks give the serial run's elements, bitwise, for every partition and
//! message timing; and the serial run is the engine's (`sdg run` of the same config).

use std::time::Duration;

use sdg_distributed::{
    Causality, LoopbackOptions, Options, Partition, Physics, PitchingError, RankSolution,
    solve_threads,
};
use sdg_engine::{LoadedConfig, Problem, RunOptions};
use sdg_mesh::{Front, Mesh, VertexId};
use sdg_solver::element::{FrontSolution, Geometry};
use sdg_solver::patch::Initial;

/// `configs/plane_wave.toml` (an oblique P wave through a PMMA square, the exact solution on
/// every side, order 2) on `cells` x `cells` cells to `end` s, writing into `dir`.
fn plane_wave(cells: u32, end: f64, dir: &std::path::Path) -> Problem {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/plane_wave.toml");
    let overrides = [
        format!("mesh.nx={cells}"),
        format!("mesh.ny={cells}"),
        format!("time.end={end:e}"),
        "output.png=false".to_string(),
        "output.snapshot_times=[]".to_string(),
        format!("output.dir=\"{}\"", dir.display()),
    ];
    Problem::setup(LoadedConfig::load(&path, &overrides).expect("a valid config"))
        .expect("a valid problem")
}

fn physics(problem: &Problem) -> Physics<'_> {
    Physics {
        system: &problem.system,
        order: problem.loaded.config.solver.order,
        boundary: &problem.boundary,
        initial: problem.exact.as_ref().map_or(Initial::Rest, Initial::Wave),
    }
}

fn causality(problem: &Problem) -> Causality {
    let config = &problem.loaded.config;
    Causality {
        c_max: problem.material.max_wave_speed(),
        safety: config.pitch.safety,
        t_end: config.time.span(),
    }
}

fn options(seed: u64) -> Options {
    Options {
        seed,
        idle_limit: Duration::from_secs(20),
    }
}

/// One element's bits: geometry values, top facet energy parts, coefficients.
type Bits = Vec<u64>;

fn element_bits(solution: &FrontSolution, t: usize) -> Option<Bits> {
    let energy = solution.energy(t).map(|e| e.map(f64::to_bits));
    solution.with_element(t, |element| {
        element.map(|(geometry, coefficients)| {
            let values = geometry.to_values();
            let energy = energy.expect("a solved element has its energy");
            values
                .iter()
                .map(|x| x.to_bits())
                .chain(energy)
                .chain(coefficients.iter().map(|x| x.to_bits()))
                .collect()
        })
    })
}

/// Per global triangle, its element's bits from the ranks' copies; asserts that all copies of
/// an element are bitwise the same and that every triangle has one, and that every rank's
/// front is at `t_end`.
fn gather(mesh: &Mesh, ranks: &[RankSolution], t_end: f64) -> Vec<Bits> {
    let mut elements: Vec<Option<Bits>> = vec![None; mesh.triangles().len()];
    for rank in ranks {
        let view = &rank.view;
        for t in 0..view.mesh().triangles().len() {
            let bits = element_bits(&rank.solution, t).expect("every element solved");
            let slot = &mut elements[view.global_triangle(t as u32) as usize];
            match slot {
                Some(other) => assert!(*other == bits, "copies of an element differ"),
                None => *slot = Some(bits),
            }
        }
        let front = &rank.front;
        assert!((0..front.len() as VertexId).all(|v| front.time(v) == t_end));
    }
    elements.into_iter().map(|e| e.expect("held")).collect()
}

/// The engine's state hash (`summary.json`): FNV-1a over the front times' bits and, per
/// element in triangle order, its vertices' and coefficients' bits.
fn state_hash(front: &[f64], elements: &[Bits], size: usize) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |x: u64| {
        for byte in x.to_le_bytes() {
            hash ^= u64::from(byte);
            hash = hash.wrapping_mul(0x0100_0000_01b3);
        }
    };
    front.iter().for_each(|t| feed(t.to_bits()));
    for bits in elements {
        let values: [f64; 22] = std::array::from_fn(|i| f64::from_bits(bits[i]));
        let geometry = Geometry::from_values(&values);
        geometry
            .vertices()
            .iter()
            .flatten()
            .for_each(|x| feed(x.to_bits()));
        bits[bits.len() - size..].iter().for_each(|&x| feed(x));
    }
    format!("{hash:016x}")
}

#[test]
fn elements_are_the_serial_runs_for_every_partition_and_timing() {
    let dir = tempfile::tempdir().unwrap();
    let problem = plane_wave(8, 5e-6, dir.path());
    let (mesh, causality, physics) = (&problem.mesh, causality(&problem), physics(&problem));
    let n = mesh.vertices().len();

    // The serial run: the engine on one thread.
    let engine = RunOptions {
        threads: Some(1),
        force: true,
        ..RunOptions::default()
    };
    let (summary, _) = sdg_engine::solve_job(&problem, &engine).unwrap();

    // One rank is the serial order (no messages), with the engine's elements.
    let fifo = LoopbackOptions {
        seed: 0,
        max_delay: Duration::ZERO,
        fifo: true,
    };
    let one = Partition::coordinate(mesh, 1).unwrap();
    let serial = solve_threads(mesh, &one, causality, physics, fifo, &options(0)).unwrap();
    let reference = gather(mesh, &serial, causality.t_end);
    let size = physics.initial_solution(&serial[0].view).width()
        * physics.initial_solution(&serial[0].view).basis_len();
    let tents = serial[0].report.tents.len();
    assert_eq!(tents as u64, summary.patches, "the engine's patch count");
    assert_eq!(
        state_hash(&vec![causality.t_end; n], &reference, size),
        summary.state_hash,
        "one rank gives the engine's state hash"
    );
    assert!(tents > 8 * n, "{tents} tents on {n} vertices");

    let mut messages = 0;
    for ranks in 2..=4 {
        let partitions = [
            Partition::coordinate(mesh, ranks).unwrap(),
            Partition::striped(mesh, ranks).unwrap(),
            Partition::random(mesh, ranks, 17 + ranks as u64).unwrap(),
        ];
        for (k, partition) in partitions.iter().enumerate() {
            for fifo in [true, false] {
                let seed = (ranks * 10 + k) as u64;
                let delays = LoopbackOptions {
                    seed,
                    max_delay: Duration::from_micros(200),
                    fifo,
                };
                let result =
                    solve_threads(mesh, partition, causality, physics, delays, &options(seed))
                        .unwrap();
                let got = gather(mesh, &result, causality.t_end);
                assert!(
                    got == reference,
                    "{ranks} ranks, partition {k}, fifo {fifo}: elements differ from the serial \
                     run's"
                );
                let tents: usize = result.iter().map(|r| r.report.tents.len()).sum();
                assert_eq!(tents, serial[0].report.tents.len());
                messages += result.iter().map(|r| r.report.updates_sent).sum::<u64>();
            }
        }
    }
    eprintln!("{tents} tents a run, {messages} updates sent in 18 runs");
    assert!(messages > 1000, "{messages} updates sent");
}

#[test]
fn a_front_solution_of_the_wrong_size_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let problem = plane_wave(4, 1e-7, dir.path());
    let (mesh, causality, physics) = (&problem.mesh, causality(&problem), physics(&problem));
    let partition = Partition::coordinate(mesh, 1).unwrap();
    let view = sdg_distributed::LocalView::new(mesh, &partition, 0).unwrap();
    let pitcher = sdg_mesh::Pitcher::new(
        view.mesh(),
        causality.c_max,
        causality.safety,
        causality.t_end,
    )
    .unwrap();
    let front = Front::flat(view.mesh().vertices().len(), 0.0);
    let good = physics.initial_solution(&view);
    let wrong = FrontSolution::new(good.len() - 1, good.basis_len(), good.width());
    let mut ends = sdg_distributed::Loopback::connect(
        1,
        LoopbackOptions {
            seed: 0,
            max_delay: Duration::ZERO,
            fifo: true,
        },
    );
    let err = sdg_distributed::solve_rank(
        &view,
        &pitcher,
        &front,
        &wrong,
        physics,
        &mut ends[0],
        &options(0),
    )
    .unwrap_err();
    let size = good.basis_len() * good.width();
    assert_eq!(
        err,
        PitchingError::Solution {
            rank: 0,
            got: [good.len() - 1, size],
            expected: [good.len(), size],
        }
    );
}
