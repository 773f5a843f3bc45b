//! One-dimensional wave problems in a 2D mesh: a P-wave pulse between `roller` sides reflects
//! off a `free` side with the exact sign change and arrival time, and leaves through a
//! `transmitting` side without reflection.

use crate::common;

use sdg_mesh::{Diagonal, Rectangle};
use sdg_solver::boundary::{Boundary, Condition};
use sdg_solver::exact::{PlaneWave, Profile, Wave};
use sdg_solver::norms::{front_energy, slice_errors};
use sdg_solver::{Material, Plane};

const LENGTH: f64 = 1.0;
const WIDTH: f64 = 0.25;

fn material() -> Material {
    Material::new(3.24e9, 0.35, 1190.0, Plane::Strain).unwrap()
}

/// The 1 m x 0.25 m strip, 32 x 8 right-diagonal cells.
fn strip_mesh() -> sdg_mesh::Mesh {
    Rectangle {
        width: LENGTH,
        height: WIDTH,
        nx: 32,
        ny: 8,
        diagonal: Diagonal::Right,
        interfaces: Vec::new(),
        sides: Vec::new(),
        perturb: 0.0,
        seed: 0,
    }
    .build()
    .unwrap()
}

/// A pulse of width 0.25 m centred at x = 0.5 m travelling in +x, in a 1 m x 0.25 m strip with
/// rollers on the long sides, an absorbing left side and `right` on the right; solved at order
/// `order` to `t_end`.
fn strip(right: Condition, order: usize, t_end: f64) -> (common::Direct, PlaneWave) {
    let m = material();
    let pulse = PlaneWave::new(&m, Wave::P, 0.0, WIDTH, 1.0, Profile::Pulse, 0.5).unwrap();
    let mesh = strip_mesh();
    let absorbing = Condition::Transmitting {
        incoming: [0.0; 2],
        history: sdg_solver::history::History::Constant,
    };
    // Tags: left, right, bottom, top.
    let boundary = Boundary::new(
        vec![
            Some(absorbing),
            Some(right),
            Some(Condition::Roller),
            Some(Condition::Roller),
        ],
        None,
    );
    let run = common::solve_direct(mesh, &m, &boundary, Some(&pulse), order, t_end, |_| {});
    (run, pulse)
}

#[test]
fn free_side_reflects_with_a_sign_change_in_stress() {
    let m = material();
    let c = m.c_d();
    // Centre travels 0.5 m to the wall and 0.4 m back: the reflection is whole and clear of
    // both ends.
    let t_end = 0.9 / c;
    let (run, _) = strip(Condition::Free, 3, t_end);
    // Reflected: v = f(2L - x - c t) with the same velocity sign, stress sign flipped, i.e. a
    // left-going wave of velocity amplitude -1 (its polarization is -x) centred at 0.5 - 2L.
    let reflected = PlaneWave::new(
        &m,
        Wave::P,
        180.0,
        WIDTH,
        -1.0,
        Profile::Pulse,
        0.5 - 2.0 * LENGTH,
    )
    .unwrap();
    let e = slice_errors(
        &run.mesh,
        &run.solution,
        run.solver.basis(),
        &run.system,
        t_end,
        &reflected,
    );
    eprintln!("free reflection errors: {e:?}");
    assert!(e.velocity < 2e-3 && e.stress < 2e-3, "{e:?}");
    // The same pulse without the sign change, or a tenth of a width early or late, is far off.
    let wrong_sign = PlaneWave::new(
        &m,
        Wave::P,
        180.0,
        WIDTH,
        1.0,
        Profile::Pulse,
        0.5 - 2.0 * LENGTH,
    )
    .unwrap();
    let early = PlaneWave::new(
        &m,
        Wave::P,
        180.0,
        WIDTH,
        -1.0,
        Profile::Pulse,
        0.5 - 2.0 * LENGTH + 0.025,
    )
    .unwrap();
    for other in [wrong_sign, early] {
        let e = slice_errors(
            &run.mesh,
            &run.solution,
            run.solver.basis(),
            &run.system,
            t_end,
            &other,
        );
        assert!(e.velocity > 0.3 || e.stress > 0.3, "{e:?}");
    }
}

#[test]
fn transmitting_side_absorbs_the_pulse() {
    let m = material();
    // The pulse's trailing edge (x = 0.375 m) leaves the strip after 0.625 m of travel.
    let t_end = 0.7 / m.c_d();
    let absorbing = Condition::Transmitting {
        incoming: [0.0; 2],
        history: sdg_solver::history::History::Constant,
    };
    let (run, pulse) = strip(absorbing, 3, t_end);
    let energy = |run: &common::Direct, initial: bool| {
        let flat = sdg_mesh::Front::flat(run.front.len(), 0.0);
        let times = if initial { &flat } else { &run.front };
        let empty = sdg_solver::element::FrontSolution::new(
            run.mesh.triangles().len(),
            run.solver.basis().len(),
            run.solver.width(),
        );
        let solution = if initial { &empty } else { &run.solution };
        front_energy(
            &run.mesh,
            times,
            solution,
            run.solver.basis(),
            &run.system,
            2,
            |x| run.system.to_scaled(&pulse.state(x, 0.0)),
        )
        .total
    };
    let (incident, left) = (energy(&run, true), energy(&run, false));
    eprintln!("energy left / incident: {:e}", left / incident);
    assert!(left < 1e-6 * incident, "{left} of {incident}");
}

/// A velocity or traction history on the left end of the strip launches the wave
/// `v = v0 H(t - x / c_d)`, `s11 = -Z v` into a medium at rest (`H` the smooth ramp); the right
/// end absorbs it.
#[test]
fn velocity_and_traction_sides_launch_the_exact_wave() {
    use sdg_solver::element::evaluate;
    use sdg_solver::history::History;
    let m = material();
    let (c, z) = (m.c_d(), m.density() * m.c_d());
    let ramp = 0.2 / c;
    let t_end = 0.6 / c;
    let smooth = History::Smooth { ramp };
    let absorbing = Condition::Transmitting {
        incoming: [0.0; 2],
        history: History::Constant,
    };
    for left in [
        Condition::Velocity {
            value: [1.0, 0.0],
            history: smooth.clone(),
        },
        // Traction sigma n with n = -x: -s11 = Z v.
        Condition::Traction {
            value: [z, 0.0],
            history: smooth.clone(),
        },
    ] {
        let mesh = strip_mesh();
        let boundary = Boundary::new(
            vec![
                Some(left.clone()),
                Some(absorbing.clone()),
                Some(Condition::Roller),
                Some(Condition::Roller),
            ],
            None,
        );
        let run = common::solve_direct(mesh, &m, &boundary, None, 2, t_end, |_| {});
        let basis = run.solver.basis();
        let mut phi = vec![0.0; basis.len()];
        let mut values = vec![0.0; run.solver.width()];
        let mut worst: f64 = 0.0;
        for (t, corners) in run.mesh.triangles().iter().enumerate() {
            let mut geometry = sdg_solver::element::Geometry::default();
            let mut coefficients = vec![0.0; basis.len() * run.solver.width()];
            assert!(run.solution.load(t, &mut geometry, &mut coefficients));
            let p = corners.map(|v| run.mesh.vertex(v));
            let x = [
                (p[0][0] + p[1][0] + p[2][0]) / 3.0,
                (p[0][1] + p[1][1] + p[2][1]) / 3.0,
            ];
            evaluate(
                basis,
                &geometry,
                &coefficients,
                [x[0], x[1], c * t_end],
                &mut phi,
                &mut values,
            );
            let v = smooth.value(t_end - x[0] / c);
            let q = run
                .system
                .to_physical(&[values[0], values[1], values[2], values[3], values[4]]);
            worst = worst
                .max((q[0] - v).abs())
                .max(q[1].abs())
                .max((q[2] + z * v).abs() / z);
        }
        eprintln!("{left:?}: worst error {worst:.2e} (amplitude 1)");
        // The cubic ramp is only C1, which limits the pointwise accuracy; a wrong sign, speed or
        // amplitude errs by order one.
        assert!(worst < 1e-2, "{left:?}: {worst}");
    }
}
