#!/usr/bin/env python3
"""Writes the LEFM sweep studies of seed 2.5.3 (Figs. 2.6-2.10):

    configs/studies/lefm_sweep_low.toml    sigma' = 10^-3/2 ... 10^-1/2, from mode1_lefm.toml
    configs/studies/lefm_sweep_high.toml   sigma' = 10^-1/4 ... 10^-1/128, from mode1_lefm_high.toml
    configs/studies/lefm_sweep_ci.toml     two low loads and one high, shortened (CI runs one)

    python3 scripts/lefm_sweep.py          # from the repository root

Every length and time of the mode-I problem scales with tau' c_R and tau', and tau' with
sigma'^-2 (2.67), so each load ratio's domain, refinement zones, end time and reference energy
are its base config's times s = (sigma'_base / sigma')^2 (the seed's sizing rule 2.5.2 with the
base's alpha). Only the process zone keeps its size (11 um at rest), so the smallest edge does
not scale: `adapt.min_edge` is chosen per load so that the tip's legs are 3.5 to 5 um, 2 to 3
per process zone, as the base configs' (min_edge = 3 um); the lowest load keeps
mode1_lefm_low.toml's 4.8 um (4.9 um legs), which costs five hours already.
"""
import math
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# (key, base value) of the keys that scale with s; lists scale entry by entry.
LOW_BASE = {
    "mesh.width": 5.5e-3,
    "mesh.height": 2.4e-3,
    "mesh.interface.0.from": [0.0, 1.2e-3],
    "mesh.interface.0.to": [2.5e-3, 1.2e-3],
    "mesh.interface.1.from": [2.5e-3, 1.2e-3],
    "mesh.interface.1.to": [5.5e-3, 1.2e-3],
    "time.end": 2.87e-6,
    "adapt.reference_energy": 0.5,
    "adapt.zone.0.from": [2.4e-3, 1.2e-3],
    "adapt.zone.0.to": [4.0e-3, 1.2e-3],
    "adapt.zone.0.radius": 0.4e-3,
    "adapt.zone.0.max_edge": 0.2e-3,
    "adapt.zone.1.from": [2.5e-3, 1.2e-3],
    "adapt.zone.1.to": [3.8e-3, 1.2e-3],
    "adapt.zone.1.radius": 0.1e-3,
    "adapt.zone.1.max_edge": 50e-6,
}
HIGH_BASE = {
    "mesh.width": 1.8e-3,
    "mesh.height": 1.0e-3,
    "mesh.interface.0.from": [0.0, 0.5e-3],
    "mesh.interface.0.to": [0.5e-3, 0.5e-3],
    "mesh.interface.1.from": [0.5e-3, 0.5e-3],
    "mesh.interface.1.to": [1.8e-3, 0.5e-3],
    "time.end": 6.47e-7,
    "adapt.reference_energy": 6.0,
    "adapt.zone.0.from": [0.45e-3, 0.5e-3],
    "adapt.zone.0.to": [1.8e-3, 0.5e-3],
    "adapt.zone.0.radius": 0.1e-3,
    "adapt.zone.0.max_edge": 25e-6,
    "adapt.zone.1.from": [0.5e-3, 0.5e-3],
    "adapt.zone.1.to": [1.0e-3, 0.5e-3],
    "adapt.zone.1.radius": 0.04e-3,
    "adapt.zone.1.max_edge": 12.5e-6,
}
# The base configs' PMMA (plane strain) and Xu-Needleman law, for the time scales of the CI study.
YOUNG, POISSON, DENSITY = 3.24e9, 0.35, 1190.0
STRENGTH, CRITICAL_SEPARATION = 3.24e8, 4e-7
# Distance from the loaded sides to the crack plane in each base config, m.
LOW_HALF_HEIGHT, HIGH_HALF_HEIGHT = 1.2e-3, 0.5e-3
LOW_GRID, HIGH_GRID = (22, 12), (18, 10)

METRICS = [
    "lefm.onset_time",
    "lefm.tip_error_max",
    "lefm.energy_release_over_phi",
    "lefm.process_zone_over_estimate.median",
    "crack.max_speed_over_c_r",
    "crack.final_length",
    "energy.balance_residual_rel",
    "patches",
    "wall_time_s",
]


def number(x):
    return repr(x)


def scaled(value, s):
    if isinstance(value, list):
        return "[" + ", ".join(number(v * s) for v in value) + "]"
    return number(value * s)


def write(name, base, ratio_base, exponents, base_values, min_edge, compare_from, head):
    ratios = [10.0**e for e in exponents]
    scales = [(ratio_base / r) ** 2 for r in ratios]
    lines = [f"# {line}" if line else "#" for line in head.strip().split("\n")]
    lines += [
        "# Written by scripts/lefm_sweep.py: edit that, not this file.",
        "#",
        f"#   sdg study configs/studies/{name}.toml --output results/{name}",
        f'base = "../{base}"',
        "metrics = [" + ", ".join(f'"{m}"' for m in METRICS) + "]",
        "",
        "[axes]",
        '"loading.load_ratio" = { values = ['
        + ", ".join(repr(r) for r in ratios)
        + "], with = {",
    ]
    with_lines = [f'    "adapt.min_edge" = [{", ".join(number(m) for m in min_edge)}],']
    for key, value in base_values.items():
        with_lines.append(f'    "{key}" = [{", ".join(scaled(value, s) for s in scales)}],')
    # No comma after the last entry: TOML 1.0 inline tables allow none (Python's tomllib
    # refuses one).
    with_lines[-1] = with_lines[-1].rstrip(",")
    lines += with_lines
    lines += ["} }", "", "[set]", '"output.png" = false', f'"loading.compare_from" = {compare_from}', ""]
    # TOML inline tables are one line: join the with-table's lines.
    text = "\n".join(lines)
    start = text.index('"loading.load_ratio"')
    end = text.index("} }", start) + 3
    text = text[:start] + " ".join(x.strip() for x in text[start:end].split("\n")) + text[end:]
    (ROOT / "configs" / "studies" / f"{name}.toml").write_text(text)



def wave_speeds():
    """`(mu, c_d, c_s)` of the PMMA in plane strain: Pa, m/s, m/s."""
    mu = YOUNG / (2.0 * (1.0 + POISSON))
    lam = YOUNG * POISSON / ((1.0 + POISSON) * (1.0 - 2.0 * POISSON))
    return mu, math.sqrt((lam + 2.0 * mu) / DENSITY), math.sqrt(mu / DENSITY)


def tau_prime(ratio):
    """`tau' = pi mu phi c_d / (4 (c_s sigma' sigma_c)^2)` (2.67), s."""
    mu, c_d, c_s = wave_speeds()
    phi = math.e * STRENGTH * CRITICAL_SEPARATION
    return math.pi * mu * phi * c_d / (4.0 * (c_s * ratio * STRENGTH) ** 2)


def write_ci(cases, head):
    """The CI study on mode1_lefm.toml: `cases` are `(exponent, base values, base ratio,
    min_edge, grid, half height, end t', compare_from t')`; each case's keys are its base's
    scaled, its grid, and the end time `t0 + t' tau'`."""
    keys = ["adapt.min_edge", "mesh.nx", "mesh.ny", *LOW_BASE, "loading.compare_from"]
    columns = {key: [] for key in keys}
    ratios = []
    for exponent, base, ratio_base, min_edge, grid, half, end, compare_from in cases:
        ratio = 10.0**exponent
        s = (ratio_base / ratio) ** 2
        ratios.append(ratio)
        values = {key: scaled(value, s) for key, value in base.items()}
        arrival = s * half / wave_speeds()[1]
        values["time.end"] = number(arrival + end * tau_prime(ratio))
        values.update({"adapt.min_edge": number(min_edge), "mesh.nx": str(grid[0])})
        values.update({"mesh.ny": str(grid[1]), "loading.compare_from": number(compare_from)})
        for key in keys:
            columns[key].append(values[key])
    lines = [f"# {line}" if line else "#" for line in head.strip().split("\n")]
    lines += [
        "# Written by scripts/lefm_sweep.py: edit that, not this file.",
        "#",
        "#   sdg study configs/studies/lefm_sweep_ci.toml --output out/lefm_sweep_ci",
        'base = "../mode1_lefm.toml"',
        "metrics = [" + ", ".join(f'"{m}"' for m in METRICS) + "]",
        "",
        "[axes]",
        '"loading.load_ratio" = { values = ['
        + ", ".join(repr(r) for r in ratios)
        + "], with = { "
        + ", ".join(f'"{key}" = [{", ".join(columns[key])}]' for key in keys)
        + " } }",
        "",
        "[set]",
        '"output.png" = false',
        '"scheduler.deterministic" = true',
        "",
    ]
    (ROOT / "configs" / "studies" / "lefm_sweep_ci.toml").write_text("\n".join(lines))

write(
    "lefm_sweep_low",
    "mode1_lefm.toml",
    0.1,
    [-1.5, -1.25, -1.0, -0.75, -0.5],
    LOW_BASE,
    [4.8e-6, 3e-6, 3e-6, 2.5e-6, 2e-6],
    3.0,
    """
The seed's low load ratios (2.5.3, Figs. 2.6, 2.7, 2.9a, 2.10a): sigma' = 10^-3/2 to 10^-1/2,
each on mode1_lefm.toml scaled by s = (0.1 / sigma')^2 (scripts/lefm_sweep.py says why), run
to t' = 3.5. summary.json's `lefm` compares the tip with LEFM from t' = 3 and the energy
released per unit extension from there. The lowest load alone takes about five hours on 2 cores.
""",
)
write(
    "lefm_sweep_high",
    "mode1_lefm_high.toml",
    10.0 ** (-1.0 / 128.0),
    [-1 / 4, -1 / 8, -1 / 16, -1 / 32, -1 / 64, -1 / 128],
    HIGH_BASE,
    [3e-6] * 6,
    40.0,
    """
The seed's high load ratios (2.5.3, Figs. 2.8, 2.9b): sigma' = 10^-1/4 to 10^-1/128, each on
mode1_lefm_high.toml scaled by s = (10^-1/128 / sigma')^2 (scripts/lefm_sweep.py), run to
t' = 60. The seed's points: the speed stays below c_R, and the energy released per unit
extension stays below phi once the crack runs (compared from t' = 40).
""",
)
write_ci(
    [
        # (exponent, base, base ratio, min_edge, grid, half height, end t', compare_from t')
        (-0.75, LOW_BASE, 0.1, 2.5e-6, LOW_GRID, LOW_HALF_HEIGHT, 3.0, 2.5),
        (-0.5, LOW_BASE, 0.1, 2e-6, LOW_GRID, LOW_HALF_HEIGHT, 3.0, 2.5),
        (-1 / 128, HIGH_BASE, 10.0 ** (-1.0 / 128.0), 3e-6, HIGH_GRID, HIGH_HALF_HEIGHT, 6.0, 40.0),
    ],
    """
The reduced LEFM sweep (issue 70; tests/lefm_sweep.rs runs it, CI its case 1, and says what
each checks): two low loads, 10^-3/4 and 10^-1/2, and the highest, 10^-1/128, each as in
lefm_sweep_low.toml / lefm_sweep_high.toml but shortened. The low loads run to t' = 3: their
cracks start near t' = 1 and pass 0.5 c_R at t' = 2.4, where the seed finds G ~ phi (Fig. 2.9a,
t' >= 2-4, speeds above 0.4-0.8 c_R), so G is compared from t' = 2.5. The high load runs to
t' = 6, five tau' past its onset at the end of the ramp (t' = 1): most of its cost is the waves'
35 tau' to the crack plane; its G is compared from t' = 40, as the full sweep's (none here).
Deterministic, so that the tests check the same run on every machine.
""",
)
