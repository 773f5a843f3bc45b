//! Patches solved over ranks give the serial run's elements, bitwise, for every partition and
//! message timing; and the serial run is the engine's (`sdg run` of the same config).

use std::time::Duration;

use sdg_distributed::{
    Held, LoopbackOptions, Options, Partition, PitchingError, RankReport, RankSolution,
    solve_threads,
};
use sdg_engine::{LoadedConfig, Problem, RunOptions, causality, physics};
use sdg_mesh::{Front, Mesh, VertexId};
use sdg_solver::element::{FrontSolution, Geometry};

/// The shipped config `name` with `overrides`, to `end` s, writing into `dir`.
fn shipped(name: &str, overrides: &[&str], end: f64, dir: &std::path::Path) -> Problem {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../configs")
        .join(name);
    let mut overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    overrides.extend([
        format!("time.end={end:e}"),
        "output.png=false".to_string(),
        "output.snapshot_times=[]".to_string(),
        "output.interface_probes=[]".to_string(),
        format!("output.dir=\"{}\"", dir.display()),
    ]);
    Problem::setup(LoadedConfig::load(&path, &overrides).expect("a valid config"))
        .expect("a valid problem")
}

/// `configs/plane_wave.toml` (an oblique P wave through a PMMA square, the exact solution on
/// every side, order 2) on `cells` x `cells` cells to `end` s, writing into `dir`.
fn plane_wave(cells: u32, end: f64, dir: &std::path::Path) -> Problem {
    let (nx, ny) = (format!("mesh.nx={cells}"), format!("mesh.ny={cells}"));
    shipped("plane_wave.toml", &[&nx, &ny], end, dir)
}

fn options(seed: u64) -> Options {
    Options::new(seed, Duration::from_secs(20))
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

fn face_bits(solution: &FrontSolution, e: usize) -> Option<Bits> {
    solution.face(e).map(|face| {
        let geometry = face.geometry.to_values();
        (geometry.iter().chain(face.coefficients.iter().flatten()))
            .map(|x| x.to_bits())
            .collect()
    })
}

/// What the ranks hold, by global id: per triangle its element's bits, per edge its interface
/// face's bits (if any).
#[derive(Debug, PartialEq)]
struct Gathered {
    elements: Vec<Bits>,
    faces: Vec<Option<Bits>>,
}

/// The ranks' copies by global id; asserts that all copies of an element or a face are bitwise
/// the same, that every triangle has an element, and that every rank's front is at `t_end`.
fn gather(mesh: &Mesh, ranks: &[RankSolution], t_end: f64) -> Gathered {
    let mut elements: Vec<Option<Bits>> = vec![None; mesh.triangles().len()];
    let mut faces: Vec<Option<Option<Bits>>> = vec![None; mesh.edges().len()];
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
        for e in 0..view.mesh().edges().len() {
            let bits = face_bits(&rank.solution, e);
            let slot = &mut faces[view.global_edge(e as u32) as usize];
            match slot {
                Some(other) => assert!(*other == bits, "copies of an interface face differ"),
                None => *slot = Some(bits),
            }
        }
        let front = &rank.front;
        assert!((0..front.len() as VertexId).all(|v| front.time(v) == t_end));
    }
    Gathered {
        elements: elements.into_iter().map(|e| e.expect("held")).collect(),
        faces: faces.into_iter().map(|f| f.expect("held")).collect(),
    }
}

/// The engine's state hash (`summary.json`): FNV-1a over the front times' bits, per element in
/// triangle order its vertices' and coefficients' bits, and per interface face in edge order
/// its corners' and coefficients' bits.
fn state_hash(front: &[f64], gathered: &Gathered, size: usize) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |x: u64| {
        for byte in x.to_le_bytes() {
            hash ^= u64::from(byte);
            hash = hash.wrapping_mul(0x0100_0000_01b3);
        }
    };
    front.iter().for_each(|t| feed(t.to_bits()));
    for bits in &gathered.elements {
        let values: [f64; 22] = std::array::from_fn(|i| f64::from_bits(bits[i]));
        let geometry = Geometry::from_values(&values);
        geometry
            .vertices()
            .iter()
            .flatten()
            .for_each(|x| feed(x.to_bits()));
        bits[bits.len() - size..].iter().for_each(|&x| feed(x));
    }
    for bits in gathered.faces.iter().flatten() {
        // The corners are the first 9 of the face geometry's values.
        bits[..9].iter().chain(&bits[16..]).for_each(|&x| feed(x));
    }
    format!("{hash:016x}")
}

/// Solves `problem` on one rank (the serial order) and checks its state hash and patch count
/// against the engine's run on one thread; returns the gathered elements and faces, the tents
/// and the values per element.
fn serial(problem: &Problem) -> (Gathered, usize) {
    let (mesh, causality, physics) = (&problem.mesh, causality(problem), physics(problem, &[]));
    let engine = RunOptions {
        threads: Some(1),
        force: true,
        ..RunOptions::default()
    };
    let (summary, _) = sdg_engine::solve_job(problem, &engine).unwrap();
    let one = Partition::coordinate(mesh, 1).unwrap();
    let serial = solve_threads(mesh, &one, causality, physics, FIFO, &options(0)).unwrap();
    let gathered = gather(mesh, &serial, causality.t_end);
    let solution = physics.initial_solution(&serial[0].view);
    let size = solution.width() * solution.basis_len();
    let tents = serial[0].report.tents.len();
    assert_eq!(tents as u64, summary.patches, "the engine's patch count");
    assert_eq!(
        state_hash(
            &vec![causality.t_end; mesh.vertices().len()],
            &gathered,
            size
        ),
        summary.state_hash,
        "one rank gives the engine's state hash"
    );
    (gathered, tents)
}

/// Interface faces with a state other than zero (separation, slip or damage).
fn opened(gathered: &Gathered) -> usize {
    let state = |bits: &&Bits| bits[16..].iter().any(|&x| f64::from_bits(x) != 0.0);
    gathered.faces.iter().flatten().filter(state).count()
}

const FIFO: LoopbackOptions = LoopbackOptions {
    seed: 0,
    max_delay: Duration::ZERO,
    fifo: true,
};

/// Solves `problem` on `ranks` ranks of `partition` with seeded delays, `threads` solving
/// threads each; asserts that the elements and faces are `reference`'s and the tents `tents`;
/// returns the updates sent.
fn check(
    problem: &Problem,
    (partition, threads): (&Partition, usize),
    seed: u64,
    fifo: bool,
    reference: &Gathered,
    tents: usize,
) -> u64 {
    let (mesh, causality, physics) = (&problem.mesh, causality(problem), physics(problem, &[]));
    let delays = LoopbackOptions {
        seed,
        max_delay: Duration::from_micros(200),
        fifo,
    };
    let options = Options {
        threads,
        ..options(seed)
    };
    let result = solve_threads(mesh, partition, causality, physics, delays, &options).unwrap();
    let got = gather(mesh, &result, causality.t_end);
    assert!(
        got == *reference,
        "{} ranks of {threads} threads, seed {seed}, fifo {fifo}: elements or faces differ \
         from the serial run's",
        partition.ranks()
    );
    assert_eq!(
        result.iter().map(|r| r.report.tents.len()).sum::<usize>(),
        tents
    );
    result.iter().map(|r| r.report.updates_sent).sum()
}

#[test]
fn elements_are_the_serial_runs_for_every_partition_and_timing() {
    let dir = tempfile::tempdir().unwrap();
    let problem = plane_wave(8, 5e-6, dir.path());
    let mesh = &problem.mesh;
    let n = mesh.vertices().len();
    let (reference, tents) = serial(&problem);
    assert!(tents > 8 * n, "{tents} tents on {n} vertices");
    // One rank solving with three threads.
    let one = Partition::coordinate(mesh, 1).unwrap();
    check(&problem, (&one, 3), 1, true, &reference, tents);
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
                // 1 to 3 solving threads per rank.
                let threads = if fifo { 1 } else { ranks - 1 };
                let run = (partition, threads);
                messages += check(&problem, run, seed, fifo, &reference, tents);
            }
        }
    }
    eprintln!("{tents} tents a run, {messages} updates sent in 18 runs");
    assert!(messages > 1000, "{messages} updates sent");
}

#[test]
fn interface_states_are_the_serial_runs_over_ranks() {
    // Contact and separation across a debonded mid-line (order 3), to past the wave's arrival
    // at the interface; the mid-line lies on a coordinate bisection's cut.
    let dir = tempfile::tempdir().unwrap();
    let problem = shipped(
        "contact_separation.toml",
        &["mesh.ny=16"],
        1.6e-6,
        dir.path(),
    );
    let mesh = &problem.mesh;
    let (reference, tents) = serial(&problem);
    let faces = reference.faces.iter().flatten().count();
    assert!(
        faces >= 4 && opened(&reference) > 0,
        "{faces} interface faces"
    );
    let mut messages = 0;
    for ranks in [2, 3] {
        let partitions = [
            Partition::coordinate(mesh, ranks).unwrap(),
            Partition::random(mesh, ranks, 5 + ranks as u64).unwrap(),
        ];
        for (k, partition) in partitions.iter().enumerate() {
            let seed = (ranks * 10 + k) as u64;
            let run = (partition, 1 + k);
            messages += check(&problem, run, seed, k == 0, &reference, tents);
        }
    }
    eprintln!("{tents} tents a run, {faces} interface faces, {messages} updates sent");
}

#[test]
fn friction_cohesion_and_damage_states_are_the_serial_runs_over_ranks() {
    let cases: [(&str, &[&str], f64); 3] = [
        ("stick_slip.toml", &["mesh.nx=8", "mesh.ny=8"], 4e-6),
        ("cohesive_wave.toml", &["mesh.ny=16"], 2e-6),
        (
            "damage_interface.toml",
            &["mesh.nx=2", "mesh.ny=16"],
            1.6e-6,
        ),
    ];
    for (name, overrides, end) in cases {
        let dir = tempfile::tempdir().unwrap();
        let problem = shipped(name, overrides, end, dir.path());
        let (reference, tents) = serial(&problem);
        let faces = reference.faces.iter().flatten().count();
        let partition = Partition::random(&problem.mesh, 3, 7).unwrap();
        let messages = check(&problem, (&partition, 2), 3, false, &reference, tents);
        eprintln!("{name}: {tents} tents, {faces} interface faces, {messages} updates sent");
        assert!(
            faces >= 2 && opened(&reference) > 0,
            "{name}: {faces} faces"
        );
    }
}

#[test]
fn a_front_solution_of_the_wrong_size_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let problem = plane_wave(4, 1e-7, dir.path());
    let (mesh, causality, physics) = (&problem.mesh, causality(&problem), physics(&problem, &[]));
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
    let wrong =
        FrontSolution::new(good.len() - 1, good.basis_len(), good.width()).with_edges(good.edges());
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
    assert_eq!(
        err,
        PitchingError::Solution {
            rank: 0,
            what: "triangles",
            got: good.len() - 1,
            expected: good.len(),
        }
    );
}

/// The engine's guard over ranks: a patch with a non-finite value (here from a bad element
/// written between two runs of the rank) is not stored, and the rank stops naming the vertex,
/// the time and the value.
/// One rank holding the whole mesh of `problem`, solved from the initial front to a time and
/// then on to a later one (its solution kept between), so that a test can spoil an element
/// between the two runs ([`WholeRank::spoil`]).
struct WholeRank<'p> {
    view: sdg_distributed::LocalView,
    causality: sdg_distributed::Causality,
    physics: sdg_distributed::Physics<'p>,
    front: Front,
    solution: FrontSolution,
    ends: Vec<sdg_distributed::Loopback>,
}

impl<'p> WholeRank<'p> {
    fn new(problem: &'p Problem, delays: LoopbackOptions) -> Self {
        let mesh = &problem.mesh;
        let partition = Partition::coordinate(mesh, 1).unwrap();
        let view = sdg_distributed::LocalView::new(mesh, &partition, 0).unwrap();
        let physics = physics(problem, &[]);
        Self {
            front: Front::flat(view.mesh().vertices().len(), 0.0),
            solution: physics.initial_solution(&view),
            causality: causality(problem),
            physics,
            view,
            ends: sdg_distributed::Loopback::connect(1, delays),
        }
    }

    /// Solves the rank's tents to `t_end` s, on from where the last call stopped.
    fn solve(&mut self, t_end: f64, options: &Options) -> Result<RankReport, PitchingError> {
        let c = &self.causality;
        let pitcher = sdg_mesh::Pitcher::new(self.view.mesh(), c.c_max, c.safety, t_end).unwrap();
        sdg_distributed::solve_rank(
            &self.view,
            &pitcher,
            &self.front,
            &self.solution,
            self.physics,
            &mut self.ends[0],
            options,
        )
    }

    /// Element 0's coefficients now.
    fn coefficients(&self) -> Vec<f64> {
        let solution = &self.solution;
        let mut geometry = Geometry::default();
        let mut coefficients = vec![0.0; solution.basis_len() * solution.width()];
        assert!(solution.load(0, &mut geometry, &mut coefficients));
        coefficients
    }

    /// Sets the first coefficient of element 0 to `value`; returns the element's coefficients.
    fn spoil(&self, value: f64) -> Vec<f64> {
        let solution = &self.solution;
        let mut geometry = Geometry::default();
        let mut coefficients = vec![0.0; solution.basis_len() * solution.width()];
        assert!(solution.load(0, &mut geometry, &mut coefficients));
        coefficients[0] = value;
        solution.store(0, &geometry, &coefficients, None);
        coefficients
    }
}

#[test]
fn a_patch_with_a_non_finite_value_stops_the_rank() {
    let dir = tempfile::tempdir().unwrap();
    let problem = plane_wave(4, 1e-7, dir.path());
    let fifo = LoopbackOptions {
        seed: 0,
        max_delay: Duration::ZERO,
        fifo: true,
    };
    let mut rank = WholeRank::new(&problem, fifo);
    let t_end = rank.causality.t_end;
    let half = 0.5 * t_end;
    rank.solve(half, &options(0)).unwrap();
    rank.spoil(f64::NAN);
    let err = rank.solve(t_end, &options(0)).unwrap_err();
    assert!(
        matches!(err, PitchingError::NonFinite { rank: 0, time, value, .. }
            if value.is_nan() && time >= half),
        "{err}"
    );
    assert!(err.to_string().contains("a non-finite value"), "{err}");
}

/// The energy blow-up guard over ranks. `cohesive_wave`'s waves enter through the top and the
/// bottom only, here owned by ranks 0 and 2 of three horizontal bands: the middle rank's
/// patches carry energy it knows of only from the work entries of the updates, and no patch
/// trips the guard (the elements are the unguarded run's, bitwise). A bad element between two
/// runs of one rank then makes the next patch on it blow up: nothing of it is stored, and the
/// rank stops naming the vertex and the time.
#[test]
fn the_energy_guard_knows_the_work_of_other_ranks_and_stops_a_blow_up() {
    let dir = tempfile::tempdir().unwrap();
    let problem = shipped("cohesive_wave.toml", &["mesh.ny=24"], 2e-6, dir.path());
    let (mesh, causality, physics) = (&problem.mesh, causality(&problem), physics(&problem, &[]));
    let rho = problem.material.density();
    let ys = mesh.vertices().iter().map(|v| v[1]);
    let (low, high) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
        (a.min(y), b.max(y))
    });
    let bands = mesh
        .vertices()
        .iter()
        .map(|v| (3.0 * (v[1] - low) / (high - low)).min(2.0) as u32)
        .collect();
    let partition = Partition::from_owners(mesh, bands, 3).unwrap();
    let delays = LoopbackOptions {
        seed: 3,
        max_delay: Duration::from_micros(50),
        fifo: false,
    };
    let run = |held: Option<Held>| {
        let options = Options { held, ..options(1) };
        let run = (causality, physics, delays);
        let mut observers = vec![(); 3];
        sdg_distributed::solve_threads_observed(mesh, &partition, run, &mut observers, &options)
            .unwrap()
    };
    let free = run(None);
    let guarded = run(Some(Held::new(0.0, rho, 3)));
    for (a, b) in free.iter().zip(&guarded) {
        for t in 0..a.solution.len() {
            assert_eq!(element_bits(&a.solution, t), element_bits(&b.solution, t));
        }
    }
    let middle = guarded[1].report.held.as_ref().unwrap();
    let loaded = |r: usize| guarded[r].report.held.as_ref().unwrap().known[r];
    assert!(loaded(0) > 0.0 && loaded(2) > 0.0, "{middle:?}");
    assert!(
        middle.known[0] > 0.5 * loaded(0) && middle.known[2] > 0.5 * loaded(2),
        "the middle rank heard of the loaded ranks' work: {middle:?}"
    );
    assert!(middle.bound() > 0.0 && guarded[1].report.patches.len() > 100);

    let mut rank = WholeRank::new(&problem, delays);
    let held = |held| Options {
        held: Some(held),
        ..options(0)
    };
    let half = 0.5 * causality.t_end;
    let report = rank.solve(half, &held(Held::new(0.0, rho, 1))).unwrap();
    let known = report.held.unwrap();
    assert!(known.bound() > 0.0, "{known:?}");
    let coefficients = rank.spoil(1e6);
    let err = rank.solve(causality.t_end, &held(known)).unwrap_err();
    assert!(
        matches!(err, PitchingError::BlowUp { rank: 0, time, out, held, .. }
            if time >= half && out > 10.0 * held),
        "{err}"
    );
    assert!(err.to_string().contains("energy blow-up"), "{err}");
    assert_eq!(
        rank.coefficients(),
        coefficients,
        "nothing of the patch stored"
    );
}
