#!/usr/bin/env python3
"""Write the generated tables of docs/verification.md (and the README's status table).

    python3 scripts/verify_tables.py OUT FILE.md...

OUT is the folder `scripts/verify.sh` ran into: one sub-folder per run, each with the run's
outputs and `command.txt` (the command that made it). Every block between
`<!-- verify:NAME begin -->` and `<!-- verify:NAME end -->` in the FILEs is replaced by table
NAME. A table whose runs are missing is left as it was (and said so on stderr). Numbers are
printed from bitwise-reproducible runs (deterministic mode), so a rerun with the same binary
writes the same bytes, the wall-time columns aside. Python 3 standard library only.
"""

import csv
import json
import math
import re
import sys
from pathlib import Path

# PMMA as in every shipped config (plane strain).
E, NU, RHO = 3.24e9, 0.35, 1190.0
LAM = E * NU / ((1 + NU) * (1 - 2 * NU))
MU = E / (2 * (1 + NU))
C_D = math.sqrt((LAM + 2 * MU) / RHO)
Z_D = RHO * C_D


class Missing(Exception):
    pass


class Runs:
    def __init__(self, out):
        self.out = Path(out)

    def dir(self, name):
        d = self.out / name
        if not (d / "summary.json").is_file():
            raise Missing(name)
        return d

    def summary(self, name):
        return json.loads((self.dir(name) / "summary.json").read_text())

    def command(self, name):
        """The run's command line, values with brackets quoted for the shell."""
        words = (self.dir(name) / "command.txt").read_text().split()
        return " ".join(f"'{w}'" if "[" in w else w for w in words)

    def rows(self, name, file):
        with open(self.dir(name) / file, newline="") as f:
            return list(csv.DictReader(f))


def e(x, digits=2):
    """A number in e-notation with `digits` after the point (1.23e-4)."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "n/a"
    s = f"{x:.{digits}e}"
    mant, exp = s.split("e")
    return f"{mant}e{int(exp)}"


def g(x, digits=3):
    """A number with `digits` significant digits, plain where it reads plainly."""
    if x is None:
        return "n/a"
    if x != 0 and (abs(x) < 1e-3 or abs(x) >= 1e6):
        return e(x, digits - 1)
    s = f"{x:.{digits}g}"
    return s


def n(x):
    return f"{x:,}"


def table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "| " + " | ".join("---" for _ in header) + " |"]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines)


def cmd(runs, name):
    return f"`{runs.command(name)}`"


def wall(s):
    return f"{s['wall_time_s']:.1f}"


# ---------------------------------------------------------------------------------------------
# convergence


def convergence(runs):
    out = []
    for wave in ("P", "S"):
        for p in (1, 2, 3):
            errs = []
            for nx in (8, 16, 32):
                err = runs.summary(f"conv_{wave}_p{p}_n{nx}")["error"]
                errs.append((err["velocity_l2_rel"], err["stress_l2_rel"]))
            orders = [
                " / ".join(f"{math.log2(a[i] / b[i]):.2f}" for i in range(2))
                for a, b in zip(errs, errs[1:])
            ]
            out.append(
                [wave, p]
                + [f"{e(v)} / {e(s)}" for v, s in errs]
                + orders
            )
    text = table(
        ["wave", "p", "nx = 8", "nx = 16", "nx = 32", "order 8-16", "order 16-32"], out
    )
    return text + "\n\nCommand of each cell: " + cmd(runs, "conv_P_p2_n16") + (
        ", with `exact.wave`, `solver.order` and `mesh.nx` = `mesh.ny` as in its row and column."
    )


# ---------------------------------------------------------------------------------------------
# conservation: every run's energy balance and element momentum balance

CONSERVATION = [
    ("plane_wave", "exact data on every side"),
    ("antiplane_pulse", "anti-plane shear, absorbing ends"),
    ("adaptive_pulse", "refinement and coarsening"),
    ("contact_separation", "contact and separation"),
    ("stick_slip", "friction"),
    ("cohesive_wave", "Xu-Needleman interface"),
    ("decohesion", "decohesion, refinement"),
    ("damage_interface", "delayed damage"),
    ("crack_growth", "crack propagation"),
    ("crack_branching", "the main job"),
]


def conservation(runs):
    out = []
    for name, what in CONSERVATION:
        try:
            s = runs.summary(name)
        except Missing:
            if name == "crack_branching":
                continue
            raise
        out.append(
            [
                f"`{name}`",
                what,
                n(s["patches"]),
                e(s["energy"]["balance_residual_rel"], 1),
                e(s["max_momentum_residual"], 1),
                f"{s['max_slope_ratio']:.10f}",
                wall(s),
            ]
        )
    return table(
        [
            "config",
            "what it exercises",
            "patches",
            "energy balance residual",
            "largest element momentum residual",
            "largest `c_max \\|grad tau\\|` (safety 0.9)",
            "wall time (s)",
        ],
        out,
    )


# ---------------------------------------------------------------------------------------------
# exact solutions


def exact(runs):
    out = []
    for name, test in [
        ("plane_wave", "`tests/configs.rs` `solver_configs_match_stored_results`"),
        ("antiplane_pulse", "`tests/configs.rs` `solver_configs_match_stored_results`"),
        (
            "adaptive_pulse",
            "`tests/efficiency.rs` `adaptive_pulse_beats_the_uniform_mesh_of_its_smallest_edge_with_five_times_fewer_patches`",
        ),
    ]:
        s = runs.summary(name)
        out.append(
            [
                f"`{name}`",
                e(s["error"]["velocity_l2_rel"]),
                e(s["error"]["stress_l2_rel"]),
                n(s["patches"]),
                f"{n(s['refinements'])} / {n(s['coarsenings'])}",
                test,
            ]
        )
    stored = Path(__file__).resolve().parent.parent / "tests/data/adaptive_pulse_uniform.json"
    u = json.loads(stored.read_text())
    out.append(
        [
            "`adaptive_pulse`, uniform 0.25 mm edges (stored in `tests/data/adaptive_pulse_uniform.json`)",
            e(u["velocity_l2_rel"]),
            e(u["stress_l2_rel"]),
            n(u["patches"]),
            "",
            "`tests/efficiency.rs` `the_stored_uniform_results_are_current` (ignored, 4 min)",
        ]
    )
    return table(
        [
            "config",
            "velocity error",
            "stress error",
            "patches",
            "bisections / coarsenings",
            "test",
        ],
        out,
    )


# ---------------------------------------------------------------------------------------------
# contact


def contact_changes(runs):
    """Times (s) the probe of contact_separation opens and closes after the waves arrive."""
    t0 = 0.002 / C_D
    opens, closes, prev = [], [], None
    for r in runs.rows("contact_separation", "interface.csv"):
        t, m = float(r["t_s"]), r["mode"]
        if t > t0 and prev is not None and m != prev:
            if m == "separation":
                opens.append(t)
            elif opens:  # closing after the first opening (not the waves' arrival)
                closes.append(t)
        prev = m
    return opens, closes


def contact(runs):
    opens, closes = contact_changes(runs)
    test = "`tests/contact.rs` `contact_separation_follows_the_1d_reference`"
    out = []
    for what, seed, t in [
        ("separation starts", 2.46, opens[0] if opens else None),
        ("faces close again", 3.46, closes[0] if closes else None),
        ("separation starts again", 4.46, opens[1] if len(opens) > 1 else None),
    ]:
        ours = f"{t * 1e6:.3f} us" if t is not None else "none"
        out.append(["`contact_separation`", what, f"{seed:.2f} us (dissertation, 3.4.1)", ours, test])
    s = runs.summary("stick_slip")
    en = s["energy"]
    it = s["interface"]
    out.append(
        [
            "`stick_slip`",
            "friction dissipation / boundary work",
            "30.6% (dissertation, 3.4.2; not reproduced, see below)",
            f"{100 * en['friction_dissipation'] / en['boundary_work']:.2f}%",
            "`tests/contact.rs` `stick_slip_balances_energy_and_slips_as_the_seed_describes`",
        ]
    )
    out.append(
        [
            "`stick_slip`",
            "numerical dissipation / boundary work",
            "0.02% (dissertation, 3.4.2)",
            f"{100 * en['dissipation'] / en['boundary_work']:.3f}%",
            "`tests/contact.rs` `stick_slip_balances_energy_and_slips_as_the_seed_describes`",
        ]
    )
    out.append(
        [
            "`stick_slip`",
            "Newton patches; linear solves each (mean, most)",
            "",
            f"{n(it['nonlinear_patches'])}; {it['newton_iterations_mean']:.2f}, {it['newton_iterations_max']}",
            "",
        ]
    )
    return table(["config", "quantity", "reference", "sdg", "test"], out)


# ---------------------------------------------------------------------------------------------
# cohesive: the 1D reference of tests/cohesive.rs


SIGMA_C, DELTA_C = 3.24e8, 4e-7
PHI = math.e * SIGMA_C * DELTA_C


def xn(delta):
    d = delta / DELTA_C
    return SIGMA_C * d * math.exp(1 - d)


def potential(delta):
    d = delta / DELTA_C
    return PHI * (1 - (1 + d) * math.exp(-d))


def reference_1d(w, t_end, dt=1e-11):
    """Opening of a cohesive line hit by two waves of level w (ramp 0.2 us): RK4 on
    d delta/dt = (2/Z)(w H(t - t0) - T(delta)), as tests/cohesive.rs (which steps 1e-12 s)."""
    t0, ramp = 0.002 / C_D, 0.2e-6

    def rate(t, d):
        r = min(max((t - t0) / ramp, 0.0), 1.0)
        return 2.0 / Z_D * (w * r * r * (3 - 2 * r) - xn(d))

    t, d, out = 0.0, 0.0, []
    while t < t_end:
        k1 = rate(t, d)
        k2 = rate(t + dt / 2, d + dt / 2 * k1)
        k3 = rate(t + dt / 2, d + dt / 2 * k2)
        k4 = rate(t + dt, d + dt * k3)
        d += dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        t += dt
        out.append((t, d))
    return out


def cohesive(runs):
    out = []
    # Below the strength: the opening holds where T(delta) = 0.8 sigma_c.
    w = 0.8 * SIGMA_C
    lo, hi = 0.0, DELTA_C
    for _ in range(100):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if xn(mid) < w else (lo, mid)
    hold = lo
    ref = reference_1d(w, 2e-6)
    rows = runs.rows("cohesive_wave", "interface.csv")
    worst = 0.0
    for r in rows:
        t, d = float(r["t_s"]), float(r["delta_m"])
        i = min(int(round(t / 1e-11)) - 1, len(ref) - 1)
        worst = max(worst, abs(d - ref[max(i, 0)][1]) / hold)
    s = runs.summary("cohesive_wave")
    last = float(rows[-1]["delta_m"])
    test = "`tests/cohesive.rs` `a_cohesive_interface_below_its_strength_is_a_nonlinear_spring`"
    out.append(
        [
            "`cohesive_wave`",
            "opening at the probe, largest difference over the run / hold opening",
            "1D reference (RK4)",
            e(worst),
            test,
        ]
    )
    out.append(
        [
            "`cohesive_wave`",
            "fracture energy (J/m)",
            f"{potential(last) * 0.004:.5f} (the law's potential at the final opening, 4 mm)",
            f"{s['energy']['fracture_energy']:.5f}",
            test,
        ]
    )
    # Decohesion: phi per unit area over the 1 mm line; the tips when the 1D reference opens to delta_c.
    s = runs.summary("decohesion")
    ref = reference_1d(1.25 * SIGMA_C, 1.2e-6)
    t_c = next(t for t, d in ref if d >= DELTA_C)
    tips = runs.rows("decohesion", "crack_tips.csv")
    tip_times = [float(r["t_s"]) for r in tips]
    test = "`tests/cohesive.rs` `decohesion_absorbs_the_work_of_separation_when_the_1d_reference_does`"
    out.append(
        [
            "`decohesion`",
            "fracture energy (J/m)",
            f"{PHI * 0.001:.5f} (`phi` = e `sigma_c` `delta_c` over 1 mm)",
            f"{s['energy']['fracture_energy']:.5f}",
            test,
        ]
    )
    out.append(
        [
            "`decohesion`",
            "tip states (the line opens at once)",
            f"{t_c * 1e6:.4f} us (1D reference reaches `delta_c`)",
            f"{min(tip_times) * 1e6:.4f} to {max(tip_times) * 1e6:.4f} us",
            test,
        ]
    )
    return table(["config", "quantity", "reference", "sdg", "test"], out)


# ---------------------------------------------------------------------------------------------
# delayed damage: the closed form of tests/damage.rs


def damage_numbers(runs):
    """The damage at the probe against the closed form, as tests/damage.rs measures it."""
    tau, a, eps, ramp = 1e-6, 10.0, 1e-4, 4e-7
    rows = [
        (float(r["t_s"]), float(r["damage"]))
        for r in runs.rows("damage_interface", "interface.csv")
    ]
    start = next(i for i, r in enumerate(rows) if r[0] > 2e-3 / C_D + ramp + 0.1e-6)
    t2, d2 = rows[start]

    def closed(t):
        return 1 - math.log(1 + (math.exp(a * (1 - d2)) - 1) * math.exp(-a * (t - t2) / tau)) / a

    worst = 0.0
    for t, d in rows[start:]:
        if d >= 1 - 2 * eps:
            break
        want = closed(t)
        worst = max(worst, abs(d - want) / want)
    t_debond = t2 + tau / a * math.log((math.exp(a * (1 - d2)) - 1) / (math.exp(a * eps) - 1))
    first = next(i for i, (t, d) in enumerate(rows) if d == 1.0)
    return {
        "from": d2,
        "worst": worst,
        "t_debond": t_debond,
        "bracket": (rows[first - 1][0], rows[first][0]),
    }


def damage(runs):
    x = damage_numbers(runs)
    s = runs.summary("damage_interface")
    test = "`tests/damage.rs` `damage_follows_its_rate_law_debonds_and_the_wave_reflects`"
    out = [
        [
            "`damage_interface`",
            f"damage `D(t)` from `D` = {x['from']:.3f}, largest relative error",
            "closed form of the rate law (4.8)",
            e(x["worst"]),
            test,
        ],
        [
            "`damage_interface`",
            "fully debonded (`D >= 1 - eps`)",
            f"{x['t_debond'] * 1e6:.4f} us (closed form)",
            "between the samples at {:.4f} and {:.4f} us".format(*(b * 1e6 for b in x["bracket"])),
            test,
        ],
        [
            "`damage_interface`",
            "fracture energy (J/m)",
            "positive",
            f"{s['energy']['fracture_energy']:.4g}",
            test,
        ],
    ]
    return table(["config", "quantity", "reference", "sdg", "test"], out)


# ---------------------------------------------------------------------------------------------
# pitching


def pitching(runs):
    stored = {"plate_mesh": (35212, 203162), "plate_with_hole": (590, 2844)}
    out = []
    for name in ("plate_mesh", "plate_with_hole"):
        s = runs.summary(f"mesh_{name}")
        tents, tets = stored[name]
        out.append(
            [
                f"`{name}`",
                n(s["vertices"]),
                f"{n(s['tents'])} ({n(tents)})",
                f"{n(s['tetrahedra'])} ({n(tets)})",
                f"{s['final_time']:g}",
                f"{s['max_slope_ratio']:.10f}",
            ]
        )
    return table(
        [
            "config (`sdg mesh --deterministic`)",
            "vertices",
            "tents (stored)",
            "tetrahedra (stored)",
            "final time (s)",
            "largest `c_max \\|grad tau\\|` (safety 0.9)",
        ],
        out,
    ) + "\n\nStored values: `tests/configs.rs` `pitching_configs_match_stored_results`."


# ---------------------------------------------------------------------------------------------
# determinism


def determinism(runs):
    async_many = sorted(
        d.name for d in runs.out.glob("async_plane_wave_t*") if d.name != "async_plane_wave_t1"
    )
    if not async_many:
        raise Missing("async_plane_wave_tN")
    out = []
    threads = None
    for label, names, test in [
        (
            "`crack_growth` (deterministic)",
            ["det_crack_growth_t1", "crack_growth"],
            "`tests/fracture.rs` `the_crack_pattern_is_bitwise_the_same_for_one_two_and_four_threads`",
        ),
        (
            "`plane_wave` (asynchronous, no events)",
            ["async_plane_wave_t1", async_many[0]],
            "`tests/parallel.rs` `asynchronous_mode_without_events_is_bitwise_identical_for_1_2_and_4_threads`",
        ),
    ]:
        s1, s2 = (runs.summary(x) for x in names)
        threads = s2["threads"]
        out.append(
            [
                label,
                f"`{s1['state_hash']}`",
                f"`{s2['state_hash']}`",
                "yes" if s1["state_hash"] == s2["state_hash"] else "**no**",
                test,
            ]
        )
    return table(
        ["run", "`state_hash`, 1 thread", f"{threads} threads", "equal", "test"], out
    )


# ---------------------------------------------------------------------------------------------
# fracture


def first_branching(runs, name):
    for r in runs.rows(name, "events.csv"):
        if r["event"] == "branching":
            return r
    return None


def fracture(runs):
    out = []
    s = runs.summary("crack_growth")
    b = first_branching(runs, "crack_growth")
    fr = s["fracture"]
    angles = [
        math.degrees(
            math.atan2(float(r["to_y_m"]) - float(r["y_m"]), float(r["to_x_m"]) - float(r["x_m"]))
        )
        for r in runs.rows("crack_growth", "events.csv")
        if r["event"] == "extension" and (r["time_s"], r["x_m"], r["y_m"]) == (b["time_s"], b["x_m"], b["y_m"])
    ]
    out.append(
        [
            "`crack_growth`",
            "first branching (time, place)",
            "the test: within two edges of the straight path's end, edges at least 35 degrees apart, their ends on both sides of the line (or on it)",
            f"{float(b['time_s']) * 1e6:.3f} us at ({float(b['x_m']) * 1e3:.3f}, {float(b['y_m']) * 1e3:.3f}) mm, edges at "
            + " and ".join(f"{a:+.1f}" for a in sorted(angles, reverse=True))
            + " degrees",
            "`tests/fracture.rs` `a_notch_under_mode_one_grows_straight_ahead_debonds_behind_its_tip_and_branches`",
        ]
    )
    out.append(
        [
            "`crack_growth`",
            "extensions, branchings, arrests; crack edges added",
            "",
            f"{fr['extensions']}, {fr['branchings']}, {fr['arrests']}; {fr['total_length'] * 1e3:.3f} mm",
            "",
        ]
    )
    return table(["config", "quantity", "reference", "sdg", "test"], out)


def branching(runs):
    s = runs.summary("crack_branching")
    fr, cr = s["fracture"], s["crack"]
    mb = fr["macro_branching"]
    out = []
    if mb:
        out.append(
            [
                "first macro fork (two arms past 1 mm): time",
                "2.26 us",
                f"{mb['time'] * 1e6:.3f} us",
            ]
        )
        out.append(
            [
                "distance of the fork from the notch's tip",
                "0.37 mm",
                f"{mb['distance'] * 1e3:.2f} mm",
            ]
        )
        out.append(
            [
                "arms at 3.6 us along crack edges (of them on open edges, `D >= 0.99`)",
                "",
                ", ".join(
                    f"{a * 1e3:.2f} ({o * 1e3:.2f}) mm"
                    for a, o in zip(mb["arms"], mb["open_arms"])
                ),
            ]
        )
    else:
        out.append(["first macro fork (two arms past 1 mm)", "2.26 us, 0.37 mm ahead", "none"])
    out.append(
        [
            "tip states above `c_R` (largest speed / `c_R`)",
            "none",
            f"{cr['states_over_c_r']} of {n(cr['tip_states'])} ({cr['max_speed_over_c_r']:.2f})",
        ]
    )
    out.append(
        [
            "nucleations, branchings, crack edges added",
            "",
            f"{fr['nucleations']}, {fr['branchings']}, {fr['total_length'] * 1e3:.2f} mm",
        ]
    )
    out.append(
        [
            "patches (accepted at the refinement floor)",
            "",
            f"{n(s['patches'])} ({100 * s['unresolved_patches'] / s['patches']:.1f}%)",
        ]
    )
    out.append(["`state_hash`", "", f"`{s['state_hash']}`"])
    return table(["`configs/crack_branching.toml` at 3.6 us", "dissertation (section 4.5)", "sdg"], out) + (
        "\n\nCommand: " + cmd(runs, "crack_branching") + f"; wall time {wall(s)} s."
    )


# ---------------------------------------------------------------------------------------------
# README status: one row per case


def status(runs):
    rows = []

    def add(case, ref, ours, test):
        rows.append([case, ref, ours, test])

    c = {}
    for p in (1, 2, 3):
        e8 = runs.summary(f"conv_P_p{p}_n16")["error"]["velocity_l2_rel"]
        e16 = runs.summary(f"conv_P_p{p}_n32")["error"]["velocity_l2_rel"]
        c[p] = math.log2(e8 / e16)
    add(
        "plane P wave, orders p = 1, 2, 3",
        "2, 3, 4",
        ", ".join(f"{c[p]:.2f}" for p in (1, 2, 3)),
        "`convergence`",
    )
    worst = max(
        abs(runs.summary(name)["energy"]["balance_residual_rel"])
        for name, _ in CONSERVATION
        if (runs.out / name / "summary.json").is_file()
    )
    add("energy balance of the shipped runs", "0", f"at most {e(worst, 0)}", "`elements`, `adaptivity`")
    opens, _ = contact_changes(runs)
    add("contact and separation: the faces open", "2.46 us (dissertation)", f"{opens[0] * 1e6:.2f} us", "`contact`")
    en = runs.summary("stick_slip")["energy"]
    add(
        "stick-slip: friction share of the inflow",
        "30.6% (dissertation)",
        f"{100 * en['friction_dissipation'] / en['boundary_work']:.1f}% (not reproduced: its loads' readings)",
        "`contact`",
    )
    s = runs.summary("decohesion")
    add(
        "decohesion: work of separation",
        f"{PHI * 0.001:.4f} J/m",
        f"{s['energy']['fracture_energy']:.4f} J/m",
        "`cohesive`",
    )
    add(
        "mode-I cohesive crack vs LEFM, `t' >= 3`",
        "LEFM (dissertation, 2.5)",
        "3.6% ahead (by hand, 10 min)",
        "`cohesive` (`--ignored`)",
    )
    add(
        "delayed damage under constant load",
        "closed form (dissertation, 4.2)",
        f"within {e(damage_numbers(runs)['worst'], 1)}",
        "`damage`",
    )
    try:
        s = runs.summary("crack_branching")
        mb = s["fracture"]["macro_branching"]
        ours = (
            f"{mb['time'] * 1e6:.2f} us, {mb['distance'] * 1e3:.2f} mm"
            if mb
            else "no fork with two arms past 1 mm"
        )
        add(
            "branching plate: first macro fork",
            "2.26 us, 0.37 mm ahead",
            ours + " (one draw)",
            "none: `scripts/verify.sh`",
        )
    except Missing:
        pass
    header = ["case", "reference", "sdg", "checked by `cargo test --release --test suite NAME::`"]
    return table(header, rows)


def secs(x):
    return f"{x:.3g} s" if x < 100 else f"{x:,.0f} s"


def estimate(runs):
    out = []
    for name, _ in CONSERVATION:
        try:
            s = runs.summary(name)
        except Missing:
            continue
        est = s["estimate"]
        mem = s.get("peak_memory_bytes")
        out.append(
            [
                f"`{name}`" + (" (lower bound)" if est["lower_bound"] else ""),
                n(int(est["tents"])),
                n(s["patches"]),
                f"{s['patches'] / est['tents']:.2f}",
                secs(est["wall_time_s"]),
                secs(s["wall_time_s"]),
                f"{s['wall_time_s'] / est['wall_time_s']:.2f}",
                f"{est['memory_bytes'] / 2**20:.0f} / {mem / 2**20:.0f}" if mem else "",
            ]
        )
    return table(
        [
            "config",
            "tents est.",
            "patches",
            "ratio",
            "wall est.",
            "wall",
            "ratio",
            "memory est. / peak (MiB)",
        ],
        out,
    )


# ---------------------------------------------------------------------------------------------
# branching_study: the branching plate over draws and resolutions (`sdg study`)


def study_json(name):
    """The study.json of results/NAME (a study's --output folder, kept in the repository) and
    its folder."""
    folder = Path(__file__).resolve().parent.parent / "results" / name
    path = folder / "study.json"
    if not path.is_file():
        raise Missing(name)
    return folder, json.loads(path.read_text())


def branching_rows(folder, study, label):
    """One row per group of a branching study with cases done: `label(group)`, then the fork,
    speed, balance and cost statistics of its study.json."""

    def interval(m, scale, unit, digits):
        if not m or m["mean"] is None:
            return "none"
        text = f"{m['mean'] * scale:.{digits}f}"
        if m["ci95"]:
            lo, hi = (x * scale for x in m["ci95"])
            text += f" [{lo:.{digits}f}, {hi:.{digits}f}]"
        return text + f" {unit}"

    out = []
    for g in study["groups"]:
        if not g["done"]:
            continue
        m = g["metrics"]
        fork_t = m.get("fracture.macro_branching.time")
        fork_d = m.get("fracture.macro_branching.distance")
        angle = m.get("fracture.macro_branching.angle")
        short_t = m.get("fracture.short_macro_branching.time")
        short_d = m.get("fracture.short_macro_branching.distance")
        speed = m.get("crack.max_branch_speed_over_c_r")
        balance = m.get("energy.balance_residual_rel")
        forked = round(fork_t["present"] * g["done"]) if fork_t else 0
        over = (
            f"{sum_of(folder, 'crack.states_over_c_r', g):,}"
            if "crack.states_over_c_r" in m
            else ""
        )
        out.append(
            [
                label(g),
                f"{g['done']} of {g['cases']}",
                f"{forked} of {g['done']}",
                interval(fork_t, 1e6, "us", 3),
                interval(fork_d, 1e3, "mm", 2),
                interval(angle, 1.0, "deg", 0),
                interval(short_t, 1e6, "us", 3),
                interval(short_d, 1e3, "mm", 2),
                f"{speed['mean']:.2f} ({speed['min']:.2f} to {speed['max']:.2f})" if speed else "",
                over,
                e(balance["max"], 1) if balance else "",
                f"{m['patches']['mean'] / 1e6:.1f}M" if "patches" in m else "",
                f"{m['wall_time_s']['mean']:.0f} s" if "wall_time_s" in m else "",
            ]
        )
    return out


BRANCHING_HEADER = [
    "draws done",
    "forked (two arms past 1 mm)",
    "fork time, mean [95% interval]",
    "fork distance from the notch",
    "angle between its arms (at 1 mm)",
    "first fork with 0.2 mm arms: time",
    "its distance",
    "largest branch speed / `c_R`: mean (least to largest) over draws",
    "tip states above `c_R`, all draws",
    "largest energy balance residual",
    "patches (mean)",
    "wall time (mean)",
]


def branching_study(runs):
    """Per resolution of configs/studies/branching_convergence.toml: the statistics of its
    study.json, from results/branching_convergence."""
    folder, study = study_json("branching_convergence")
    rows = branching_rows(
        folder, study, lambda g: f"{g['axes']['adapt.min_edge'] * 1e6:g} um"
    )
    return table(["`adapt.min_edge`"] + BRANCHING_HEADER, rows) + (
        f"\n\nCommand: `sdg study {study['study']} --output results/branching_convergence`, its "
        "cases one or two at a time beside other work (wall times measure that)."
    )


def branching_async(runs):
    """configs/studies/branching_async.toml (the shipped config's asynchronous tent order)
    beside the deterministic rounds of the same draws, branching_convergence's 5 um level."""
    folder, study = study_json("branching_async")
    det_folder, det = study_json("branching_convergence")
    det["groups"] = [g for g in det["groups"] if g["axes"]["adapt.min_edge"] == 5e-6]
    rows = branching_rows(det_folder, det, lambda g: "deterministic rounds")
    rows += branching_rows(folder, study, lambda g: "asynchronous, 2 threads")
    return table(["tent order (5 um)"] + BRANCHING_HEADER, rows) + (
        f"\n\nCommand: `sdg study {study['study']} --output results/branching_async --threads 2`, "
        "its cases one at a time beside other work (wall times measure that)."
    )


def lefm_sweep_high(runs):
    """configs/studies/lefm_sweep_high.toml (the seed's high load ratios, Figs. 2.8, 2.9b,
    2.10b): per case of results/lefm_sweep_high/study.csv, the metrics against the seed's
    statements."""
    folder, study = study_json("lefm_sweep_high")
    with open(folder / "study.csv", newline="") as f:
        rows = list(csv.DictReader(f))

    def cell(r, key, digits=3):
        return g(float(r[key]), digits) if r.get(key) else "not run"

    lines = []
    for r in rows:
        ratio = float(r["loading.load_ratio"])
        label = f"10^-1/{round(-1.0 / math.log10(ratio))}"
        if r["status"] != "done":
            lines.append([label, r["status"]] + [""] * 7)
            continue
        lines.append(
            [
                label,
                "done",
                cell(r, "lefm.onset_time"),
                cell(r, "crack.max_speed_over_c_r"),
                cell(r, "lefm.energy_release_over_phi"),
                cell(r, "lefm.process_zone_over_estimate.median"),
                e(float(r["energy.balance_residual_rel"])),
                n(int(r["patches"])),
                secs(float(r["wall_time_s"])),
            ]
        )
    header = [
        "`sigma'`",
        "case",
        "onset (first tip state), `t'`",
        "fastest tip state / `c_R` (seed: below 1)",
        "`G / phi` from `t'` = 40 (seed: below 1)",
        "process zone / (2.53), median (seed: above 1)",
        "energy balance residual",
        "patches",
        "wall time",
    ]
    return table(header, lines) + (
        f"\n\nCommand: `sdg study {study['study']} --output results/lefm_sweep_high --case K "
        "--threads 1` for each case, then `--collect`; one thread each, beside other work "
        "(wall times measure that)."
    )


def sum_of(folder, key, group):
    """The sum of `key` over the done cases of `group` in the study's study.csv."""
    with open(folder / "study.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["status"] == "done"]
    mine = [
        r
        for r in rows
        if all(float(r[k]) == float(v) for k, v in group["axes"].items())
    ]
    return sum(int(r[key]) for r in mine if r[key])


TABLES = {
    "estimate": estimate,
    "convergence": convergence,
    "conservation": conservation,
    "exact": exact,
    "contact": contact,
    "cohesive": cohesive,
    "damage": damage,
    "pitching": pitching,
    "determinism": determinism,
    "fracture": fracture,
    "branching": branching,
    "branching_study": branching_study,
    "branching_async": branching_async,
    "lefm_sweep_high": lefm_sweep_high,
    "status": status,
}


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    runs = Runs(sys.argv[1])
    made = {}
    for path in sys.argv[2:]:
        text = Path(path).read_text()
        names = re.findall(r"<!-- verify:([a-z_]+) begin -->", text)
        for name in names:
            if name not in TABLES:
                sys.exit(f"{path}: unknown table verify:{name}")
            if name not in made:
                try:
                    made[name] = TABLES[name](runs)
                except Missing as err:
                    print(f"{path}: verify:{name} kept (no run {err})", file=sys.stderr)
                    made[name] = None
            if made[name] is None:
                continue
            pattern = re.compile(
                rf"(<!-- verify:{name} begin -->\n).*?(<!-- verify:{name} end -->)", re.S
            )
            text, count = pattern.subn(lambda m: m.group(1) + made[name] + "\n" + m.group(2), text)
            if count != 1:
                sys.exit(f"{path}: verify:{name} markers not found once")
        Path(path).write_text(text)
        print(f"{path}: {len(names)} tables", file=sys.stderr)


if __name__ == "__main__":
    main()
