//! Interfaces with their own law on a P-wave pulse in a strip: a free interface reflects like a
//! free boundary at the expected convergence rate, bonded interfaces change nothing, and a contact
//! interface that stays in compressive stick gives the bonded solution.

use crate::common;

use sdg_mesh::{Diagonal, Mesh, Rectangle};
use sdg_solver::boundary::{Boundary, Condition};
use sdg_solver::exact::{PlaneWave, Profile, Wave};
use sdg_solver::history::History;
use sdg_solver::interface::{ContactParams, Interfaces, Law};
use sdg_solver::norms::slice_errors;
use sdg_solver::{Material, Plane};

const LENGTH: f64 = 1.0;
const WIDTH: f64 = 0.25;
/// The interface line `x = WALL` across the strip.
const WALL: f64 = 0.75;

fn material() -> Material {
    Material::new(3.24e9, 0.35, 1190.0, Plane::Strain).unwrap()
}

/// The strip with `4 n x n` right-diagonal cells; the edges on `x = WALL` get the tag `wall`
/// (the last tag), or with `every_edge` every interior edge does.
fn strip(n: u32, every_edge: bool) -> Mesh {
    let base = Rectangle {
        width: LENGTH,
        height: WIDTH,
        nx: 4 * n,
        ny: n,
        diagonal: Diagonal::Right,
        interfaces: Vec::new(),
        sides: Vec::new(),
        perturb: 0.0,
        seed: 0,
    }
    .build()
    .unwrap();
    let mut names = base.tag_names().to_vec();
    names.push("wall".into());
    let wall = (names.len() - 1) as u16;
    let tagged: Vec<_> = base
        .edges()
        .iter()
        .filter_map(|e| {
            let [p, q] = e.vertices.map(|v| base.vertex(v));
            let on_wall = (p[0] - WALL).abs() < 1e-12 && (q[0] - WALL).abs() < 1e-12;
            match e.tag {
                Some(t) => Some((e.vertices, t)),
                None if on_wall || (every_edge && !e.is_boundary()) => Some((e.vertices, wall)),
                None => None,
            }
        })
        .collect();
    Mesh::new(
        base.vertices().to_vec(),
        base.triangles().to_vec(),
        names,
        &tagged,
    )
    .unwrap()
}

/// Rollers on the long sides, absorbing ends; tags: left, right, bottom, top.
fn boundary() -> Boundary {
    let absorbing = Condition::Transmitting {
        incoming: [0.0; 2],
        history: History::Constant,
    };
    Boundary::new(
        vec![
            Some(absorbing.clone()),
            Some(absorbing),
            Some(Condition::Roller),
            Some(Condition::Roller),
        ],
        None,
    )
}

/// Laws with `law` on the `wall` tag (index 4).
fn laws(law: Law) -> Interfaces {
    Interfaces::new(vec![None, None, None, None, Some(law)])
}

/// A compressive P pulse (velocity +1 m/s along +x) of width `WIDTH` centred at x = 0.5 m.
fn pulse(m: &Material) -> PlaneWave {
    PlaneWave::new(m, Wave::P, 0.0, WIDTH, 1.0, Profile::Pulse, 0.5).unwrap()
}

#[test]
fn free_interface_reflects_like_a_free_side_at_the_expected_rate() {
    let m = material();
    // The centre travels 0.25 m to the interface and 0.25 m back.
    let t_end = 0.5 / m.c_d();
    let reflected = PlaneWave::new(
        &m,
        Wave::P,
        180.0,
        WIDTH,
        -1.0,
        Profile::Pulse,
        0.5 - 2.0 * WALL,
    )
    .unwrap();
    let order = 2;
    let mut errors = Vec::new();
    for n in [4, 8] {
        let run = common::solve_direct_with(
            strip(n, false),
            &m,
            &boundary(),
            &laws(Law::Free),
            Some(&pulse(&m)),
            order,
            t_end,
            |r| assert!(r.momentum_residual < 1e-12 && r.dissipation >= -1e-15),
        );
        let e = slice_errors(
            &run.mesh,
            &run.solution,
            run.solver.basis(),
            &run.system,
            t_end,
            &reflected,
        );
        assert_eq!(run.newton_iterations, 0, "free interfaces are linear");
        errors.push(e);
    }
    let rate = |a: f64, b: f64| (a / b).log2();
    let (v, s) = (
        rate(errors[0].velocity, errors[1].velocity),
        rate(errors[0].stress, errors[1].stress),
    );
    eprintln!("free interface: errors {errors:?}, rates {v:.2} {s:.2}");
    assert!(errors[1].velocity < 2e-2 && errors[1].stress < 2e-2);
    assert!(v > order as f64 + 0.5 && s > order as f64 + 0.5, "{v} {s}");
}

/// Every coefficient of two runs' final fronts, and the largest difference relative to the
/// largest coefficient.
fn difference(a: &common::Direct, b: &common::Direct) -> f64 {
    let size = a.solver.basis().len() * a.solver.width();
    let (mut ga, mut gb) = (Default::default(), Default::default());
    let (mut ca, mut cb) = (vec![0.0; size], vec![0.0; size]);
    let (mut worst, mut largest) = (0.0f64, 0.0f64);
    for t in 0..a.solution.len() {
        assert!(a.solution.load(t, &mut ga, &mut ca) && b.solution.load(t, &mut gb, &mut cb));
        assert_eq!(ga, gb);
        for (x, y) in ca.iter().zip(&cb) {
            worst = worst.max((x - y).abs());
            largest = largest.max(x.abs());
        }
    }
    worst / largest
}

#[test]
fn bonded_interfaces_everywhere_change_nothing() {
    let m = material();
    let t_end = 0.4 / m.c_d();
    let run = |mesh: Mesh, interfaces: &Interfaces| {
        common::solve_direct_with(
            mesh,
            &m,
            &boundary(),
            interfaces,
            Some(&pulse(&m)),
            2,
            t_end,
            |_| {},
        )
    };
    let plain = run(strip(4, false), &Interfaces::default());
    let bonded = run(strip(4, true), &laws(Law::Bonded));
    assert_eq!(difference(&plain, &bonded), 0.0, "bitwise equal");
}

#[test]
fn contact_in_compressive_stick_is_the_bonded_solution() {
    let m = material();
    let t_end = 0.6 / m.c_d();
    // A long P wave running in -x, compressive at the interface for the whole run (phase
    // between -0.34 and -0.19 wavelengths there), imposed on every side.
    let wave = PlaneWave::new(&m, Wave::P, 180.0, 4.0, -1.0, Profile::Sine, 0.0).unwrap();
    let exact = Boundary::new(vec![Some(Condition::Exact); 4], Some(wave.clone()));
    let contact = Law::Contact(ContactParams {
        friction: 0.5,
        r_c: 0.0,
        r_s: 1e-6,
        s_c: 0.0,
        s_s: 1e3,
    });
    let mut worst = 0.0f64;
    let mut run = |interfaces: &Interfaces| {
        common::solve_direct_with(
            strip(4, false),
            &m,
            &exact,
            interfaces,
            Some(&wave),
            2,
            t_end,
            |r| worst = worst.max(r.momentum_residual),
        )
    };
    let bonded = run(&laws(Law::Bonded));
    let stick = run(&laws(contact));
    let diff = difference(&bonded, &stick);
    eprintln!(
        "contact in stick against bonded: {diff:.2e}, {} linear solves, momentum {worst:.1e}",
        stick.newton_iterations
    );
    assert!(stick.newton_iterations > 0);
    assert!(diff < 1e-12, "{diff}");
    assert!(worst < 1e-12, "{worst}");
    // The same wave in tension opens the interface: far from bonded.
    let tension = PlaneWave::new(&m, Wave::P, 180.0, 4.0, 1.0, Profile::Sine, 0.0).unwrap();
    let exact = Boundary::new(vec![Some(Condition::Exact); 4], Some(tension.clone()));
    let run = |interfaces: &Interfaces| {
        common::solve_direct_with(
            strip(4, false),
            &m,
            &exact,
            interfaces,
            Some(&tension),
            2,
            t_end,
            |_| {},
        )
    };
    let open = difference(&run(&laws(Law::Bonded)), &run(&laws(contact)));
    assert!(open > 1e-2, "{open}");
}
