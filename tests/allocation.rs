//! The patch solve allocates nothing: all scratch memory lives in the `PatchSolver`.
//!
//! The counting allocator counts per thread: the test harness's own threads allocate while the
//! test runs (at any moment, depending on scheduling), and the patch solve runs on the test's
//! thread alone.

// A counting global allocator is the standard way to observe heap allocations; it forwards to the
// system allocator unchanged.
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use sdg_mesh::{Diagonal, Front, Pitcher, Rectangle};
use sdg_solver::boundary::{Boundary, Condition};
use sdg_solver::element::FrontSolution;
use sdg_solver::exact::{PlaneWave, Profile, Wave};
use sdg_solver::history::History;
use sdg_solver::patch::{Initial, PatchSolver};
use sdg_solver::system::System as Elastodynamics;
use sdg_solver::{Material, Plane};

struct Counting;

thread_local! {
    /// Allocations made by this thread (a const-initialized `Cell`: reading it never allocates).
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

/// Allocations made by the calling thread so far.
fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

// SAFETY: every call forwards to `System` with the caller's arguments.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // A thread being torn down has no counter left; its allocations are not the test's.
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        // SAFETY: same contract as ours.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as ours.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn patch_solves_do_not_allocate() {
    let mesh = Rectangle {
        width: 1.0,
        height: 1.0,
        nx: 8,
        ny: 8,
        diagonal: Diagonal::Alternate,
        interfaces: Vec::new(),
        sides: Vec::new(),
        perturb: 0.1,
        seed: 5,
    }
    .build()
    .unwrap();
    let material = Material::new(3.24e9, 0.35, 1190.0, Plane::Strain).unwrap();
    let wave = PlaneWave::new(&material, Wave::S, 30.0, 1.0, 1.0, Profile::Sine, 0.0).unwrap();
    let boundary = Boundary::new(
        vec![
            Some(Condition::Exact),
            Some(Condition::Traction {
                value: [1e6, 0.0],
                history: History::Smooth { ramp: 1e-5 },
            }),
            Some(Condition::Transmitting {
                incoming: [1e6, 0.0],
                history: History::Constant,
            }),
            Some(Condition::Roller),
        ],
        Some(wave.clone()),
    );
    let system = Elastodynamics::new(&material);
    let mut solver = PatchSolver::new(system.clone(), 3, 8);
    let solution = FrontSolution::new(mesh.triangles().len(), solver.basis().len(), solver.width());
    let pitcher = Pitcher::new(&mesh, system.c_ref(), 0.9, 1.0).unwrap();
    let front = Front::flat(mesh.vertices().len(), 0.0);
    let mut counts = Vec::with_capacity(200);
    for _ in 0..200 {
        let v = (0..mesh.vertices().len() as u32)
            .min_by(|&a, &b| front.time(a).total_cmp(&front.time(b)))
            .unwrap();
        let before = allocations();
        let tent = pitcher.pitch(&mesh, &front, v).unwrap();
        solver
            .solve(
                &mesh,
                &front,
                &tent,
                &boundary,
                Initial::Wave(&wave),
                &solution,
            )
            .unwrap();
        solver.commit(&solution);
        counts.push(allocations() - before);
    }
    // The very first solve of the process may allocate once inside the linear algebra library
    // (lazy initialisation of its kernel dispatch); every later patch must allocate nothing.
    assert!(counts[0] <= 1, "first patch: {} allocations", counts[0]);
    assert!(
        counts[1..].iter().all(|&c| c == 0),
        "allocations per patch: {counts:?}"
    );
}
