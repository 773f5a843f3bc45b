//! Patch solves per second on one core for p = 1..4, the patch kinds of the branching problem,
//! and a dense LU of the same size.
//!
//! Run: `cargo bench --bench patch`; `PATCH_TABLE=1 cargo bench --bench patch` prints instead the
//! table of time per stage against the arithmetic of the branching patch kinds
//! (`scripts/patch_table.sh`). The mesh is a 12 x 12 right-diagonal mesh, plane strain,
//! with a plane wave as initial data. One iteration pitches and solves 25 interior tents from a
//! flat front at pairwise non-adjacent vertices: each patch has 6 tetrahedra and
//! `N = 6 x 5 x (p+1)(p+2)(p+3)/6` unknowns (120, 300, 600, 1050 for p = 1..4); criterion reports
//! patches per second. `lu/N` factors and solves a random diagonally dominant `N x N` system
//! with faer's in-place partial-pivoting LU, for comparison at the same size.
//!
//! `branching/KIND` solves one p = 1 patch of each kind the branching problem solves, on a
//! 12 x 12 mesh with damage interfaces along `y = 1/2` (see [`Branching`]): `bulk4` and `bulk8`
//! (no interface face, 4 and 8 elements), `damage1` and `damage2` (one and two intact damage faces loaded past the threshold, so
//! the damage grows inside the tent: Newton), `tip` (the end of a debonded crack: one contact
//! face opening).

use criterion::{BatchSize, Criterion, Throughput, criterion_group};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::{MatMut, MatRef, Par};

use sdg_mesh::{Diagonal, Front, Mesh, Pitcher, Rectangle};
use sdg_solver::boundary::{Boundary, Condition};
use sdg_solver::element::FrontSolution;
use sdg_solver::exact::{PlaneWave, Profile, Wave};
use sdg_solver::patch::{Initial, PatchSolver};
use sdg_solver::system::System;
use sdg_solver::{Material, Plane};

/// Interior vertices `(i, j)` with even `i, j` in 2..=10: 25 pairwise non-adjacent tents.
const PATCHES: u64 = 25;

fn mesh() -> Mesh {
    Rectangle {
        width: 1.0,
        height: 1.0,
        nx: 12,
        ny: 12,
        diagonal: Diagonal::Right,
        interfaces: Vec::new(),
        sides: Vec::new(),
        perturb: 0.0,
        seed: 0,
    }
    .build()
    .expect("valid rectangle")
}

fn patches(c: &mut Criterion) {
    let mesh = mesh();
    let material = Material::new(3.24e9, 0.35, 1190.0, Plane::Strain).expect("PMMA");
    let wave =
        PlaneWave::new(&material, Wave::P, 30.0, 1.0, 1.0, Profile::Sine, 0.0).expect("wave");
    let boundary = Boundary::new(vec![Some(Condition::Exact); 4], Some(wave.clone()));
    let system = System::new(&material);
    let pitcher = Pitcher::new(&mesh, system.c_ref(), 0.9, 1.0).expect("pitcher");
    let mut group = c.benchmark_group("patch");
    group.throughput(Throughput::Elements(PATCHES));
    group.sample_size(10);
    for order in 1..=4 {
        let mut solver = PatchSolver::new(system.clone(), order, 6);
        let empty =
            FrontSolution::new(mesh.triangles().len(), solver.basis().len(), solver.width());
        group.bench_function(format!("p{order}"), |b| {
            b.iter_batched_ref(
                || (Front::flat(mesh.vertices().len(), 0.0), empty.clone()),
                |(front, solution)| {
                    for (i, j) in (1..=5).flat_map(|i| (1..=5).map(move |j| (2 * i, 2 * j))) {
                        let v = j * 13 + i;
                        let tent = pitcher.pitch(&mesh, front, v).expect("local minimum");
                        solver
                            .solve(
                                &mesh,
                                front,
                                &tent,
                                &boundary,
                                Initial::Wave(&wave),
                                solution,
                            )
                            .expect("a linear patch");
                        solver.commit(solution);
                    }
                },
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

fn dense_lu(c: &mut Criterion) {
    let mut group = c.benchmark_group("lu");
    group.sample_size(10);
    for n in [120usize, 300, 600, 1050] {
        let mut a = vec![0.0; n * n];
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for (i, x) in a.iter_mut().enumerate() {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            *x = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
                + if i % (n + 1) == 0 { n as f64 } else { 0.0 };
        }
        let mut work = a.clone();
        let mut rhs = vec![1.0; n];
        let (mut perm, mut perm_inv) = (vec![0usize; n], vec![0usize; n]);
        let mut buffer = MemBuffer::new(StackReq::any_of(&[
            factor::lu_in_place_scratch::<usize, f64>(n, n, Par::Seq, Default::default()),
            solve::solve_in_place_scratch::<usize, f64>(n, 1, Par::Seq),
        ]));
        group.throughput(Throughput::Elements(1));
        group.bench_function(format!("{n}"), |b| {
            b.iter(|| {
                work.copy_from_slice(&a);
                rhs.fill(1.0);
                let stack = MemStack::new(&mut buffer);
                let (_, p) = factor::lu_in_place(
                    MatMut::from_column_major_slice_mut(&mut work, n, n),
                    &mut perm,
                    &mut perm_inv,
                    Par::Seq,
                    stack,
                    Default::default(),
                );
                let lu = MatRef::from_column_major_slice(&work, n, n);
                solve::solve_in_place(
                    lu,
                    lu,
                    p,
                    MatMut::from_column_major_slice_mut(&mut rhs, n, 1),
                    Par::Seq,
                    stack,
                );
            })
        });
    }
    group.finish();
}

#[path = "patch/branching.rs"]
mod branching;

use branching::Branching;

fn branching_kinds(c: &mut Criterion) {
    let mut setup = Branching::new();
    let mut group = c.benchmark_group("branching");
    group.sample_size(20);
    group.measurement_time(std::time::Duration::from_secs(2));
    group.warm_up_time(std::time::Duration::from_millis(500));
    group.throughput(Throughput::Elements(1));
    for kind in &branching::KINDS {
        group.bench_function(kind.name, |b| b.iter(|| setup.solve(kind)));
    }
    group.finish();
}

criterion_group!(benches, patches, branching_kinds, dense_lu);

fn main() {
    if std::env::var_os("PATCH_TABLE").is_some() {
        branching::table();
    } else {
        benches();
        Criterion::default().configure_from_args().final_summary();
    }
}
