//! The reduced LEFM sweep (issue 70; seed 2.5.3, Figs. 2.7-2.10): the study
//! `configs/studies/lefm_sweep_ci.toml` runs two of the seed's low load ratios, 10^-3/4 and
//! 10^-1/2, to t' = 3, and its highest, 10^-1/128, to t' = 6, and their outputs are held to the
//! seed's findings (docs/verification.md says why each tolerance). CI runs its cheapest case,
//! 10^-1/2, held to the findings on a low load; the whole sweep (8 minutes on 2 cores) runs
//! with `-- --ignored`.

use crate::common;

use std::path::{Path, PathBuf};

use serde_json::Value;

/// The study's load ratios, in case order.
const NAMES: [&str; 3] = ["10^-3/4", "10^-1/2", "10^-1/128"];

/// The folders and `summary.json`s of the study's cases `cases` run into `out` (each as
/// `sdg study --case K`), in case order.
fn run_cases(out: &Path, cases: &[usize]) -> Vec<(PathBuf, Value)> {
    let study = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/studies/lefm_sweep_ci.toml");
    cases
        .iter()
        .map(|k| {
            let case = k.to_string();
            let args = [
                "--output",
                out.to_str().unwrap(),
                "--case",
                &case,
                "--quiet",
            ];
            let run = common::sdg(&[&["study", study.to_str().unwrap()], &args[..]].concat());
            assert!(run.status.success(), "{}", common::stderr(&run));
            let dir = out.join(format!("cases/{k:03}"));
            let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
            let summary: Value = serde_json::from_str(&text).unwrap();
            eprintln!(
                "{}: onset t' = {:.3}, G / phi from t' = {}: {}, fastest {:.3} c_R, process \
                 zone over the estimate {}, {} patches",
                NAMES[*k],
                number(&summary, "lefm.onset_time"),
                number(&summary, "lefm.compare_from"),
                summary["lefm"]["energy_release_over_phi"],
                number(&summary, "crack.max_speed_over_c_r"),
                summary["lefm"]["process_zone_over_estimate"],
                summary["patches"],
            );
            (dir, summary)
        })
        .collect()
}

fn number(summary: &Value, path: &str) -> f64 {
    let value = path.split('.').fold(summary, |v, key| &v[key]);
    value.as_f64().unwrap_or_else(|| panic!("{path}: {value}"))
}

/// The seed's findings on every case: no tip state at or above `c_R` (2.6), the energy
/// balanced, and the work of the cohesive tractions never negative.
fn assert_every_case((dir, s): &(PathBuf, Value)) {
    // 2.6: below c_R at every tip state.
    assert_eq!(s["crack"]["states_over_c_r"], 0, "{}", s["crack"]);
    assert!(number(s, "crack.max_speed_over_c_r") < 1.0);
    assert!(number(s, "energy.balance_residual_rel").abs() < 1e-6);
    // The work of the cohesive tractions is the law's potential plus what the faces
    // dissipate: never negative.
    let work = common::csv_columns(&dir.join("history.csv"), &["fracture_energy_j"]);
    let lowest = work.iter().map(|r| r[0]).fold(f64::INFINITY, f64::min);
    let largest = work.iter().map(|r| r[0]).fold(0.0, f64::max);
    assert!(lowest >= -1e-9 * largest, "{lowest} (largest {largest})");
}

/// The seed's findings on a low load once its crack runs: `G` within 5% of `phi` (Fig. 2.9a)
/// and the process zone within 15% of the steady-state estimate (Fig. 2.10a).
fn assert_low_load(s: &Value) {
    // Fig. 2.9a: G ~ phi once the crack runs faster than about 0.4 c_R; from t' = 2.5 here
    // (0.5 c_R). Measured: 0.995 (10^-3/4) and 1.023 (10^-1/2).
    let g = number(s, "lefm.energy_release_over_phi");
    assert!((g - 1.0).abs() < 0.05, "{g}");
    // Fig. 2.10a, the 15%: measured 0.99 to 1.14 and 0.96 to 1.07 over 51 and 26
    // states; the zone's ends are crossings of probe points a fraction of an edge apart,
    // 1.6 to 3.7 um against zones of 8 to 10 um.
    let zone = &s["lefm"]["process_zone_over_estimate"];
    assert!(number(zone, "states") >= 10.0, "{zone}");
    assert!(
        number(zone, "min") > 0.85 && number(zone, "max") < 1.15,
        "{zone}"
    );
}

/// CI's part of the sweep: its cheapest case, 10^-1/2 (210k patches), meets the findings on
/// every case and on a low load, and the seed's figures are drawn from it.
#[test]
fn the_low_load_10_to_the_minus_half_releases_phi_over_the_estimated_process_zone() {
    let out = tempfile::tempdir().unwrap();
    let cases = run_cases(out.path(), &[1]);
    assert_every_case(&cases[0]);
    assert_low_load(&cases[0].1);
    assert_figures(out.path(), &cases);
}

/// The seed's findings on the reduced sweep: the onsets in the order of its Fig. 2.7 and the
/// high load's at the end of its ramp (Fig. 2.8), and the findings on every case and on the
/// low loads; then the seed's figures from the three runs.
/// `cargo test --release --test suite lefm_sweep:: -- --ignored`.
#[test]
#[ignore = "8 minutes on 2 cores: run on demand"]
fn the_reduced_lefm_sweep_meets_the_seed_s_findings() {
    let out = tempfile::tempdir().unwrap();
    let cases = run_cases(out.path(), &[0, 1, 2]);
    let [low, mid, high] = [&cases[0].1, &cases[1].1, &cases[2].1];
    // Fig. 2.7: the higher the low load, the earlier the onset, both before LEFM's (1.51),
    // the limit sigma' -> 0. Measured: 1.040 and 0.967.
    let onset = |s: &Value| number(s, "lefm.onset_time");
    let lefm_onset = number(low, "lefm.lefm_onset_time");
    assert!(onset(mid) < onset(low) && onset(low) < lefm_onset);
    cases.iter().for_each(assert_every_case);
    [low, mid].into_iter().for_each(assert_low_load);
    // Fig. 2.8: at 10^-1/128 the crack starts as soon as the load reaches its sustained value
    // (t' = 1), already fast, at the initial tip (x = 0.5 mm, within the 3 um of the refined
    // path). Deterministic, so the same on every machine: the start is sensitive to the order
    // of refinements near the tip (the interface there sits at 0.81 delta_c under the load
    // alone); asynchronous 2-thread runs started between t' = 1.05 and 1.36 over eleven runs,
    // and once just before t' = 1. Measured: t' = 1.119 (LEFM: 1.51), at most 0.80 c_R by t' = 6.
    assert!((1.0..1.2).contains(&onset(high)), "{}", onset(high));
    let tips = common::csv_columns(&cases[2].0.join("crack_tips.csv"), &["x_m", "speed_m_s"]);
    assert!((tips[0][0] - 0.5e-3).abs() < 3e-6, "{}", tips[0][0]);
    let early = tips[tips.len() / 4][1] / number(high, "loading.c_r");
    assert!(early > 0.5, "{early}");
    assert_figures(out.path(), &cases);
}

/// `sdg plot --lefm` draws the seed's figures from the runs `cases`.
fn assert_figures(out: &Path, cases: &[(PathBuf, Value)]) {
    let figures = out.join("figures");
    let dirs: Vec<&str> = cases.iter().map(|(d, _)| d.to_str().unwrap()).collect();
    let args = [
        &["plot", "--lefm"][..],
        &dirs,
        &["--out", figures.to_str().unwrap()],
    ]
    .concat();
    let plot = common::sdg(&args);
    assert!(plot.status.success(), "{}", common::stderr(&plot));
    for name in [
        "lefm_tips",
        "lefm_tips_early",
        "lefm_energy_release",
        "lefm_process_zone",
    ] {
        let png = figures.join(format!("{name}.png"));
        assert!(
            std::fs::metadata(&png).is_ok_and(|m| m.len() > 1000),
            "{png:?}"
        );
    }
}
