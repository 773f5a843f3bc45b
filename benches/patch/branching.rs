//! The p = 1 patch kinds of the branching problem, and the table of their time per stage against
//! the arithmetic each stage must do.
//!
//! The mesh is the unit square in 12 x 12 cells (alternate diagonals, PMMA, plane strain) with two
//! damage interfaces on `y = 1/2`: a debonded crack (`initial = 1`) from `x = 0` to `4/12` and an
//! intact segment from `8/12` to `1`, loaded by a P wave of 5 MPa tension across them (strength
//! 1 MPa, delay 20 us, about half a tent's height: the damage grows inside the tent). The vertices
//! of this mesh have stars of 4 or 8 triangles, as on the branching problem's. Every vertex
//! but the kinds' own is pitched once from a flat front, so each kind's patch takes its inflow
//! from solved elements and interface faces, as in a run; its tent is then solved again and
//! again, never committed.

use std::time::Instant;

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};
use sdg_mesh::{Diagonal, Front, GridSegment, Mesh, Pitcher, Rectangle, Tent};
use sdg_solver::boundary::{Boundary, Condition};
use sdg_solver::element::FrontSolution;
use sdg_solver::exact::{PlaneWave, Profile, Wave};
use sdg_solver::interface::{ContactParams, DamageParams, Interfaces, Law};
use sdg_solver::patch::{Initial, Newton, PatchReport, PatchSolver};
use sdg_solver::quadrature;
use sdg_solver::system::System;
use sdg_solver::{Material, Plane};

/// A patch kind: its name and the grid vertex `(i, j)` at `(i / 12, j / 12)` of its tent.
#[derive(Debug)]
pub struct Kind {
    pub name: &'static str,
    vertex: (u32, u32),
    /// Interface faces in its patch.
    faces: usize,
}

/// Bulk only (stars of 4 and of 8 triangles); one and two intact damage faces; the debonded
/// crack's tip (stars of 8).
pub const KINDS: [Kind; 5] = [
    Kind {
        name: "bulk4",
        vertex: (3, 2),
        faces: 0,
    },
    Kind {
        name: "bulk8",
        vertex: (6, 2),
        faces: 0,
    },
    Kind {
        name: "damage1",
        vertex: (8, 6),
        faces: 1,
    },
    Kind {
        name: "damage2",
        vertex: (10, 6),
        faces: 2,
    },
    Kind {
        name: "tip",
        vertex: (4, 6),
        faces: 1,
    },
];

const CELLS: u32 = 12;

fn index((i, j): (u32, u32)) -> u32 {
    j * (CELLS + 1) + i
}

/// The mesh, solver and front of the kinds' patches.
pub struct Branching {
    mesh: Mesh,
    solver: PatchSolver,
    boundary: Boundary,
    wave: PlaneWave,
    solution: FrontSolution,
    front: Front,
    tents: Vec<Tent>,
}

impl Branching {
    /// Pitches and solves every vertex but the kinds' once, then the kinds' tents.
    pub fn new() -> Self {
        let segment = |from: f64, to: f64, tag: &str| GridSegment {
            from: [from, 0.5],
            to: [to, 0.5],
            tag: tag.into(),
        };
        let mesh = Rectangle {
            width: 1.0,
            height: 1.0,
            nx: CELLS,
            ny: CELLS,
            diagonal: Diagonal::Alternate,
            interfaces: vec![
                segment(0.0, 4.0 / 12.0, "crack"),
                segment(8.0 / 12.0, 1.0, "intact"),
            ],
            sides: Vec::new(),
            perturb: 0.0,
            seed: 0,
        }
        .build()
        .expect("valid rectangle");
        let material = Material::new(3.24e9, 0.35, 1190.0, Plane::Strain).expect("PMMA");
        // Upward P wave, 5 MPa tension on y = 1/2 at t = 0.
        let wave =
            PlaneWave::new(&material, Wave::P, 90.0, 2.0, -2.0, Profile::Sine, 0.0).expect("wave");
        let boundary = Boundary::new(vec![Some(Condition::Exact); 4], Some(wave.clone()));
        let system = System::new(&material);
        let damage = |initial| {
            Law::Damage(DamageParams {
                strength: 1e6,
                delay: 2e-5,
                a: 10.0,
                c0: 0.8,
                beta: DamageParams::DEFAULT_BETA,
                eps: DamageParams::DEFAULT_EPS,
                initial,
                contact: ContactParams {
                    friction: 0.0,
                    r_c: -1e-6,
                    r_s: 0.0,
                    s_c: 0.0,
                    s_s: 6e5,
                },
            })
        };
        let mut laws = vec![None; mesh.tag_names().len()];
        for (tag, initial) in [("crack", 1.0), ("intact", 0.0)] {
            laws[mesh.tag_id(tag).expect("tagged") as usize] = Some(damage(initial));
        }
        let max_star = (0..mesh.vertices().len() as u32)
            .map(|v| mesh.vertex_triangles(v).len())
            .max()
            .expect("vertices");
        let mut solver = PatchSolver::new(system.clone(), 1, max_star)
            .with_interfaces(Interfaces::new(laws), Newton::default());
        let solution =
            FrontSolution::new(mesh.triangles().len(), solver.basis().len(), solver.width())
                .with_edges(mesh.edges().len());
        let pitcher = Pitcher::new(&mesh, system.c_ref(), 0.9, 1.0).expect("pitcher");
        let front = Front::flat(mesh.vertices().len(), 0.0);
        let own: Vec<u32> = KINDS.iter().map(|k| index(k.vertex)).collect();
        for v in (0..mesh.vertices().len() as u32).filter(|v| !own.contains(v)) {
            // From a flat front every vertex not yet pitched is a local minimum.
            let tent = pitcher.pitch(&mesh, &front, v).expect("local minimum");
            solver
                .solve(
                    &mesh,
                    &front,
                    &tent,
                    &boundary,
                    Initial::Wave(&wave),
                    &solution,
                )
                .expect("the first layer converges");
            solver.commit(&solution);
        }
        let tents = own
            .iter()
            .map(|&v| pitcher.pitch(&mesh, &front, v).expect("local minimum"))
            .collect();
        Self {
            mesh,
            solver,
            boundary,
            wave,
            solution,
            front,
            tents,
        }
    }

    /// Solves the patch of `kind` (not committed).
    pub fn solve(&mut self, kind: &Kind) -> PatchReport {
        let k = KINDS
            .iter()
            .position(|x| x.name == kind.name)
            .expect("a kind");
        self.solver
            .solve(
                &self.mesh,
                &self.front,
                &self.tents[k],
                &self.boundary,
                Initial::Wave(&self.wave),
                &self.solution,
            )
            .expect("the kind's patch converges")
    }
}

/// The arithmetic of one stage: floating-point operations and bytes moved, per patch.
#[derive(Clone, Copy, Debug)]
struct Work {
    flops: f64,
    bytes: f64,
}

/// The arithmetic model of the stages of a p = 1 patch of `d` elements, `m = n fields`
/// unknowns each, couplings of rank `r` between ring neighbours, `faces` Newton faces of
/// `points` rule points and `ns` interface components. Lower bounds: the dense work a direct
/// implementation cannot avoid (the block elimination counts its LUs, the triangular solves of
/// the coupling factors and right-hand side, and one rank-`r` Schur update per element).
struct Model {
    d: f64,
    m: f64,
    r: f64,
    faces: f64,
    points: f64,
    ns_nf: f64,
    width_n: f64,
}

impl Model {
    /// Diagonal blocks as 6 Kronecker terms, two coupling factors per element.
    fn assembly(&self) -> Work {
        let (d, m, r) = (self.d, self.m, self.r);
        Work {
            flops: d * (12.0 * m * m + 8.0 * m * r),
            bytes: 8.0 * d * (m * m + 4.0 * m * r),
        }
    }

    /// One ring elimination and back substitution.
    fn ring_solve(&self) -> Work {
        let (d, m, r) = (self.d, self.m, self.r);
        Work {
            flops: d * (2.0 / 3.0 * m * m * m + 4.0 * m * m * r + 2.0 * m * m + 4.0 * m * r * r),
            bytes: 8.0 * d * (m * m + 2.0 * m * r),
        }
    }

    /// What a Newton iteration adds to its ring solve: the faces' Jacobian blocks (four
    /// Kronecker products per point and the coupling through the interface state), the
    /// residual `b - K q`, and restoring the assembled blocks.
    fn newton_extra(&self) -> Work {
        let (d, m, r) = (self.d, self.m, self.r);
        let face = self.points * 8.0 * m * m + 8.0 * m * m * self.ns_nf;
        Work {
            flops: self.faces * face + d * (2.0 * m * m + 8.0 * m * r),
            bytes: 8.0 * (2.0 * d * (m * m + 4.0 * m * r) + self.faces * 4.0 * m * m),
        }
    }

    /// Evaluating the solution on each element's 5 faces at `points` points (state and
    /// displacement), and writing the coefficients.
    fn evaluation(&self) -> Work {
        let d = self.d;
        Work {
            flops: d * 5.0 * self.points * 2.0 * self.width_n,
            bytes: 8.0 * d * self.width_n,
        }
    }
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Sustained flop rate of one core on a dense `128 x 128` product (faer, sequential): the
/// bound's machine rate, in flop/s.
fn peak_flops() -> f64 {
    let n = 128;
    let a = Mat::<f64>::from_fn(n, n, |i, j| (i + 2 * j) as f64 * 1e-3);
    let mut c = Mat::<f64>::zeros(n, n);
    let mut rates: Vec<f64> = (0..31)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..10 {
                matmul(
                    c.as_mut(),
                    Accum::Add,
                    a.as_ref(),
                    a.as_ref(),
                    1.0,
                    Par::Seq,
                );
            }
            10.0 * 2.0 * (n * n * n) as f64 / t.elapsed().as_secs_f64()
        })
        .collect();
    median(&mut rates)
}

/// Prints the markdown table of each kind's stages: median measured time, the model's flops and
/// bytes, the time the flops take at the measured peak rate, and measured over that bound.
pub fn table() {
    let peak = peak_flops();
    let mut setup = Branching::new();
    let (n, fields) = (setup.solver.basis().len(), setup.solver.system().fields());
    let width = setup.solver.width();
    let points = quadrature::triangle(4).points.len() as f64;
    println!(
        "Peak: {:.1} GFlop/s (dense 128 x 128 product, one core). Times are medians of 1,000 \
         solves of the same patch, in us.\n",
        peak * 1e-9
    );
    println!(
        "| kind | N | linear solves | stage | measured (us) | flops | bytes | flop bound (us) | \
         measured / bound |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for kind in &KINDS {
        for _ in 0..100 {
            setup.solve(kind);
        }
        let samples: Vec<(PatchReport, f64)> = (0..1000)
            .map(|_| {
                let t = Instant::now();
                let r = setup.solve(kind);
                (r, t.elapsed().as_secs_f64())
            })
            .collect();
        let first = &samples[0].0;
        let solves = first.newton_iterations.max(1);
        let pick = |f: &dyn Fn(&(PatchReport, f64)) -> f64| {
            let mut v: Vec<f64> = samples.iter().map(f).collect();
            median(&mut v) * 1e6
        };
        let model = Model {
            d: first.elements as f64,
            m: (n * fields) as f64,
            r: 6.0,
            faces: kind.faces as f64,
            points,
            ns_nf: 2.0 * 3.0,
            width_n: (n * width) as f64,
        };
        let ring = model.ring_solve();
        let extra = model.newton_extra();
        let newton = (solves > 1).then_some(Work {
            flops: ring.flops + extra.flops,
            bytes: ring.bytes + extra.bytes,
        });
        let per_solve = pick(&|(r, _)| r.solve_s) / solves as f64;
        let whole = pick(&|(_, t)| *t);
        let total_work = Work {
            flops: model.assembly().flops
                + ring.flops
                + (solves - 1) as f64 * newton.map_or(0.0, |w| w.flops)
                + model.evaluation().flops,
            bytes: 0.0,
        };
        let rows: [(&str, f64, Option<Work>); 5] = [
            (
                "assembly",
                pick(&|(r, _)| r.assembly_s),
                Some(model.assembly()),
            ),
            (
                if solves > 1 {
                    "solve, per Newton iteration"
                } else {
                    "ring solve"
                },
                per_solve,
                newton.or(Some(ring)),
            ),
            (
                "evaluation",
                pick(&|(r, _)| r.evaluation_s),
                Some(model.evaluation()),
            ),
            (
                "preparation",
                whole
                    - pick(&|(r, _)| r.assembly_s)
                    - pick(&|(r, _)| r.solve_s)
                    - pick(&|(r, _)| r.evaluation_s),
                None,
            ),
            ("whole patch", whole, Some(total_work)),
        ];
        for (stage, us, work) in rows {
            let (flops, bytes, bound, ratio) = match work {
                Some(w) => {
                    let bound = w.flops / peak * 1e6;
                    (
                        format!("{:.0}", w.flops),
                        if w.bytes > 0.0 {
                            format!("{:.0}", w.bytes)
                        } else {
                            String::new()
                        },
                        format!("{bound:.2}"),
                        format!("{:.0}", us / bound),
                    )
                }
                None => Default::default(),
            };
            println!(
                "| {} | {} | {solves} | {stage} | {us:.2} | {flops} | {bytes} | {bound} | {ratio} |",
                kind.name, first.dofs
            );
        }
    }
}
