//! The delayed-damage interface law (seed 4.2) on `configs/damage_interface.toml`: the damage
//! against the closed form of its rate law under a constant load, full debonding and the
//! reflection that follows, and the two limits of the law (undamaged: bonded; fully debonded:
//! contact).

use crate::common;

use std::path::Path;

use common::{csv_columns, solve};
use sdg_engine::{Config, LoadedConfig, Problem};

const CONFIG: &str = include_str!("../configs/damage_interface.toml");
/// The config's damage law: delay (s), rate exponent, damage_eps (the default).
const TAU: f64 = 1e-6;
const A: f64 = 10.0;
const EPS: f64 = 1e-4;
/// Where a damage face counts as an open crack, the tip of `crack_tips.csv`.
const OPEN_DAMAGE: f64 = sdg_solver::crack::OPEN_DAMAGE;
/// The config's load ramp (s).
const RAMP: f64 = 4e-7;
/// The config on a mesh twice as coarse, for the tests of the law's limits.
const COARSE: [&str; 2] = ["mesh.nx=2", "mesh.ny=32"];

fn problem(text: &str, overrides: &[&str]) -> Problem {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let config = Config::parse(text, "damage_interface.toml", &overrides).expect("valid config");
    Problem::setup(LoadedConfig {
        config,
        file: "damage_interface.toml".into(),
        overrides,
    })
    .expect("valid problem")
}

/// The config with its interface law replaced by `law` (TOML lines after `tags`).
fn with_law(law: &str) -> String {
    let start = CONFIG.find("law = \"damage\"").expect("damage law");
    let end = CONFIG[start..]
        .find("\n\n")
        .map_or(CONFIG.len(), |e| start + e);
    format!("{}{law}{}", &CONFIG[..start], &CONFIG[end..])
}

/// `interface.csv` rows: time, damage, normal traction, normal bonded traction.
fn damage_rows(dir: &Path) -> Vec<Vec<f64>> {
    csv_columns(
        &dir.join("interface.csv"),
        &["t_s", "damage", "s_n_pa", "sI_n_pa"],
    )
}

/// Under a constant `y >= 1`, `f(y) = 1`: from `(t2, d2)` the damage is
/// `1 - (1/a) ln[1 + (exp(a (1 - d2)) - 1) exp(-a (t - t2) / tau)]` (seed 4.2).
fn closed_form(t: f64, (t2, d2): (f64, f64)) -> f64 {
    1.0 - (1.0 + ((A * (1.0 - d2)).exp() - 1.0) * (-A * (t - t2) / TAU).exp()).ln() / A
}

/// When the closed form from `(t2, d2)` reaches `d` (s).
fn closed_form_time(d: f64, (t2, d2): (f64, f64)) -> f64 {
    t2 + TAU / A * (((A * (1.0 - d2)).exp() - 1.0) / ((A * (1.0 - d)).exp() - 1.0)).ln()
}

/// The samples of `interface.csv` once the load is constant (0.1 us after the ramp has passed
/// the interface; the config's wave arrives at `2 mm / c_d`), up to `D = 1 - 2 eps` where the
/// damage in effect leaves the state's `D`; and the largest relative error of the damage
/// against the closed form from the first of them. The bonded traction must stay within
/// `load_tol` of `1.2 sigma_c` over them (the closed form is for a constant load).
fn closed_form_error(rows: &[Vec<f64>], load_tol: f64) -> (usize, f64) {
    let (c_d, _) = common::pmma_p_wave();
    let start = rows
        .iter()
        .position(|r| r[0] > 2e-3 / c_d + RAMP + 0.1e-6)
        .expect("samples after the ramp");
    let origin = (rows[start][0], rows[start][1]);
    let mut worst: f64 = 0.0;
    for r in rows[start..].iter().take_while(|r| r[1] < 1.0 - 2.0 * EPS) {
        let want = closed_form(r[0], origin);
        worst = worst.max((r[1] - want).abs() / want);
        assert!((r[3] / 62.1e6 - 1.2).abs() < load_tol, "y stays 1.2: {r:?}");
    }
    (start, worst)
}

#[test]
fn damage_follows_its_rate_law_debonds_and_the_wave_reflects() {
    let (summary, dir) = solve(&problem(CONFIG, &[]), 2, true);
    let rows = damage_rows(dir.path());
    let (start, worst) = closed_form_error(&rows, 5e-3);
    eprintln!(
        "damage from D = {:.3}: largest relative error {worst:.2e}",
        rows[start][1]
    );
    // The seed's accuracy; measured 2.3e-8 (docs/verification.md).
    assert!(worst < 1e-6, "{worst}");
    // D stays in [0, 1] and never decreases; it reaches 1, after which the faces separate:
    // no traction, the wave is reflected.
    for pair in rows.windows(2) {
        assert!(pair[1][1] >= pair[0][1], "{:?} then {:?}", pair[0], pair[1]);
    }
    assert!(rows.iter().all(|r| (0.0..=1.0).contains(&r[1])));
    let debonded = rows
        .iter()
        .position(|r| r[1] == 1.0)
        .expect("full debonding");
    // Fully debonded from D = 1 - eps on, when the closed form says: between the last sample
    // before and the first after (an error of 1e-6 in D moves that time by 1 ps).
    let debond = closed_form_time(1.0 - EPS, (rows[start][0], rows[start][1]));
    assert!(
        (rows[debonded - 1][0]..=rows[debonded][0]).contains(&debond),
        "debonded at {debond} s, sampled {} and {}",
        rows[debonded - 1][0],
        rows[debonded][0]
    );
    assert!(rows[debonded..].iter().all(|r| r[2] == 0.0));
    // The crack tip is where D reaches OPEN_DAMAGE (open: 1% of the bonded traction), before
    // full debonding: all along the interface at once (a plane wave), between the samples
    // about it, when the closed form says.
    let tips = csv_columns(&dir.path().join("crack_tips.csv"), &["t_s", "x_m"]);
    let open = rows
        .iter()
        .position(|r| r[1] >= OPEN_DAMAGE)
        .expect("an open crack");
    assert!(open > start && open < debonded);
    let opened = closed_form_time(OPEN_DAMAGE, (rows[start][0], rows[start][1]));
    assert!((rows[open - 1][0]..=rows[open][0]).contains(&opened));
    assert!(!tips.is_empty());
    for tip in &tips {
        assert!(
            (rows[open - 1][0]..=rows[open][0]).contains(&tip[0]),
            "{tip:?}"
        );
        assert!(
            (tip[0] - opened).abs() < 1e-3 * opened,
            "{tip:?} against {opened}"
        );
    }
    assert_eq!(summary.crack.expect("crack tips").tip_states, tips.len());
    // Before: the bonded part carried the load.
    assert!(rows[start][2] > 0.5 * 74.52e6);
    assert!(summary.energy.balance_residual_rel.abs() < 1e-8);
    assert!(summary.energy.fracture_energy > 0.0);
}

#[test]
fn damage_error_falls_at_order_p_plus_1_as_the_tents_shrink() {
    // p = 2 on the config's mesh and on one twice as coarse (edges and tents twice as long).
    // The bonded traction carries the discretization error of the ramp's passage, most on the
    // coarse mesh (measured 0.60% there at most).
    let error = |nx: &str, ny: &str, load_tol: f64| {
        let p = problem(
            CONFIG,
            &["solver.order=2", nx, ny, "output.snapshot_times=[]"],
        );
        let (_, dir) = solve(&p, 2, true);
        closed_form_error(&damage_rows(dir.path()), load_tol).1
    };
    let coarse = error("mesh.nx=2", "mesh.ny=32", 1e-2);
    let fine = error("mesh.nx=4", "mesh.ny=64", 5e-3);
    let order = (coarse / fine).log2();
    eprintln!("p = 2: {coarse:.2e} then {fine:.2e}, order {order:.2}");
    // Measured 2.8e-5 then 7.9e-7 (order 5.2); at least p + 1 = 3, less half an order.
    assert!(order > 2.5, "{order}");
}

#[test]
fn an_undamaged_interface_is_bonded_and_a_debonded_one_is_contact() {
    // Below the threshold (y = 0.5 < c0) the damage stays 0 and the interface is the bonded
    // law: the bulk solution is the same as without an interface law.
    let below = ["boundary.1.incoming=[6.21e7, 0.0]", COARSE[0], COARSE[1]];
    let (damage, d) = solve(&problem(CONFIG, &below), 2, true);
    let (bonded, b) = solve(&problem(&with_law("law = \"bonded\""), &below), 2, true);
    assert!(damage_rows(d.path()).iter().all(|r| r[1] == 0.0));
    assert_eq!(damage.patches, bonded.patches);
    for name in ["snapshot_0001.vtu", "snapshot_0002.vtu"] {
        let (x, y) = (
            std::fs::read(d.path().join(name)).unwrap(),
            std::fs::read(b.path().join(name)).unwrap(),
        );
        assert!(x == y, "{name} differs from the bonded run");
    }
    // Fully debonded from the start: the contact law of its debonded part.
    let contact_law = "law = \"contact\"\nfriction = 0.0\nr_c = -1e-6\nr_s = 0.0\ns_c = 0.0\n\
                       s_s = 6e5";
    let (_, d) = solve(
        &problem(
            CONFIG,
            &["interface.0.initial_damage=1.0", COARSE[0], COARSE[1]],
        ),
        2,
        true,
    );
    let (_, c) = solve(&problem(&with_law(contact_law), &COARSE), 2, true);
    let columns = ["t_s", "s_n_pa", "delta_m", "jump_vn_m_s"];
    let (x, y) = (
        csv_columns(&d.path().join("interface.csv"), &columns),
        csv_columns(&c.path().join("interface.csv"), &columns),
    );
    assert_eq!(x.len(), y.len());
    for (p, q) in x.iter().zip(&y) {
        for (k, (u, v)) in p.iter().zip(q).enumerate() {
            assert!(
                (u - v).abs() <= 1e-12 * (u.abs() + v.abs()) + 1e-300,
                "{}: {u} vs {v}",
                columns[k]
            );
        }
    }
}

#[test]
fn damage_runs_are_bitwise_identical_for_1_and_2_threads() {
    let p = problem(
        CONFIG,
        &[
            "time.end=2.4e-6",
            "output.snapshot_times=[]",
            COARSE[0],
            COARSE[1],
        ],
    );
    let (one, _a) = solve(&p, 1, true);
    let (two, _b) = solve(&p, 2, true);
    assert_eq!(one.state_hash, two.state_hash);
}

#[test]
fn bad_damage_parameters_name_the_key() {
    for (set, key) in [
        ("interface.0.delay=0.0", "interface[0].delay"),
        ("interface.0.c0=1.0", "interface[0].c0"),
        (
            "interface.0.initial_damage=1.5",
            "interface[0].initial_damage",
        ),
        (
            "interface.0.critical_separation=1e-6",
            "interface[0].critical_separation",
        ),
    ] {
        let e = Config::parse(CONFIG, "damage_interface.toml", &[set.to_string()]).unwrap_err();
        assert_eq!(e.key.as_deref(), Some(key), "{set}: {e}");
        assert!(e.to_string().starts_with(&format!("--set {set}")), "{e}");
    }
}

/// Tip states of `crack_tips.csv`: time, x, y, extension, speed.
fn tip_rows(dir: &Path) -> Vec<Vec<f64>> {
    csv_columns(
        &dir.join("crack_tips.csv"),
        &["t_s", "x_m", "y_m", "extension_m", "speed_m_s"],
    )
}

/// Checks that a crack ran along `damage_mode1.toml`'s path (y = 1.2 mm, beyond the free crack
/// that ends at x = 2.5 mm) by at least `extension` (m), at every state with a speed slower than
/// `speed_limit` (m/s); returns the largest speed. A state whose fitting window spans less
/// than one edge has no speed (`NaN`, `crack_output::tip_states`): an asynchronous run may
/// leave the crack's first state alone in its window.
fn check_damage_crack(dir: &Path, extension: f64, speed_limit: f64) -> f64 {
    let tips = tip_rows(dir);
    assert!(!tips.is_empty(), "no crack tip");
    for t in &tips {
        assert!(t[2] == 1.2e-3 && t[1] > 2.5e-3, "tip off the path: {t:?}");
        assert!(t[4].is_nan() || t[4] < speed_limit, "{t:?}");
    }
    let last = tips.last().unwrap();
    assert!(last[3] >= extension, "{last:?}");
    let speeds: Vec<f64> = tips.iter().map(|t| t[4]).filter(|v| !v.is_nan()).collect();
    assert!(
        speeds.len() * 2 > tips.len(),
        "most states have a speed: {tips:?}"
    );
    speeds.into_iter().fold(0.0, f64::max)
}

/// `configs/damage_mode1.toml` on a coarser path (100 um edges instead of 25 um) to 0.63 us after
/// the waves meet: the damage crack starts ahead of the free crack's tip and runs along the path;
/// the energy balance holds with the fracture energy in it. The shipped resolution is
/// `damage_mode1_crack_runs_slower_than_c_r` below.
#[test]
fn a_damage_crack_runs_along_its_path() {
    let problem = common::shipped(
        "damage_mode1.toml",
        &["time.end=1.2e-6", "adapt.zone.1.max_edge=1e-4"],
    );
    let (summary, dir) = solve(&problem, 2, false);
    let fastest = check_damage_crack(dir.path(), 50e-6, 938.0);
    eprintln!(
        "fastest tip {fastest:.0} m/s, balance {:.2e}",
        summary.energy.balance_residual_rel
    );
    assert!(summary.energy.fracture_energy > 0.0);
    assert!(summary.energy.balance_residual_rel.abs() < 1e-7);
}

/// The acceptance on `configs/damage_mode1.toml` to its end time (seed 4.2 with 4.5's
/// parameters): the tip slower than c_R = 938 m/s at every state, the energy balance below 1e-8.
/// `cargo test --release --test suite damage::damage_mode1_crack_runs_slower_than_c_r -- --ignored
/// --nocapture` (long: see docs/verification.md).
#[test]
#[ignore = "long: run on demand"]
fn damage_mode1_crack_runs_slower_than_c_r() {
    let (summary, dir) = solve(&common::shipped("damage_mode1.toml", &[]), 2, false);
    let fastest = check_damage_crack(dir.path(), 0.5e-3, 938.0);
    eprintln!("fastest tip {fastest:.0} m/s");
    assert!(summary.energy.balance_residual_rel.abs() < 1e-8);
}

/// The seed's two delays (set 1: 1e-8 s, set 2: 1e-9 s) on `configs/damage_mode1.toml`'s
/// straight path at its load, to 1.5 us: the shorter delay debonds first, runs faster and
/// dissipates far less per metre of crack; a damage law without a length of its own takes its
/// toughness from the delay (docs/verification.md, "Delayed damage"; at the plate's lower load
/// the shorter delay does not debond).
/// Long (two runs of about 1M patches): `cargo test --release --test suite
/// damage::the_shorter_delay_debonds_sooner_runs_faster_and_dissipates_less -- --ignored`.
#[test]
#[ignore = "long: run on demand"]
fn the_shorter_delay_debonds_sooner_runs_faster_and_dissipates_less() {
    const C_R: f64 = 938.0;
    // Start (s), median tip speed (m/s) and fracture energy per metre of crack (J/m^2).
    let run = |delay: &str| {
        let delay = format!("interface.1.delay={delay}");
        let problem = common::shipped("damage_mode1.toml", &["time.end=1.5e-6", &delay]);
        let (summary, dir) = solve(&problem, 2, true);
        let tips = tip_rows(dir.path());
        assert!(!tips.is_empty(), "{delay}: no crack");
        let mut speeds: Vec<f64> = tips.iter().map(|t| t[4]).filter(|v| !v.is_nan()).collect();
        speeds.sort_by(f64::total_cmp);
        let length = tips.last().unwrap()[3];
        let result = (
            tips[0][0],
            speeds[speeds.len() / 2],
            summary.energy.fracture_energy / length,
        );
        eprintln!(
            "{delay}: start, median speed, energy per length {result:?}; largest speed {}",
            speeds[speeds.len() - 1]
        );
        result
    };
    let (start_1, speed_1, energy_1) = run("1e-8");
    let (start_2, speed_2, energy_2) = run("1e-9");
    // Sooner by more than the longer delay, the least time its damage needs to open the crack
    // (the rate is at most 1 / tau): measured 40 ns with the tip at OPEN_DAMAGE.
    assert!(start_2 < start_1 - 1e-8, "{start_2} against {start_1}");
    assert!(speed_2 > speed_1 + 0.1 * C_R, "{speed_2} against {speed_1}");
    assert!(energy_2 < 0.2 * energy_1, "{energy_2} against {energy_1}");
}
