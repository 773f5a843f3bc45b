#!/usr/bin/env python3
"""The readings of the dissertation's stick-slip example (section 3.4.2) and their energy shares.

    python3 scripts/stick_slip_readings.py                 # run what is missing, print the table
    python3 scripts/stick_slip_readings.py --write         # and rewrite docs/verification.md's
                                                           # <!-- readings:stick_slip --> block
    python3 scripts/stick_slip_readings.py --cells 16 --jobs 2 --sdg target/release/sdg

The dissertation's figure 3.12 (the geometry and loads) is missing from its text, so how the
lateral loads pi(t) = 100 t / 12 MPa are applied, and whether the bottom edge reflects, is not
stated. Each reading here is configs/stick_slip.toml (p = 3, the dissertation's regularization
and friction) with its `[[boundary]]` entries replaced; each runs at 16 and 32 cells a side,
deterministic, into --out (default target/readings/stick_slip). A run whose summary.json exists
for the same command is not run again, so an interrupted sweep resumes. Standard library only.
"""

import argparse
import concurrent.futures
import json
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BASE = ROOT / "configs" / "stick_slip.toml"

# The compressive wave through the top, as shipped.
TOP = """[[boundary]]
sides = ["top"]
kind = "transmitting"
incoming = [-2e8, 0.0]
history = { kind = "smooth", ramp = 0.2e-6 }
"""

BOTTOM = {
    "fixed": '[[boundary]]\nsides = ["bottom"]\nkind = "velocity"\nvalue = [0.0, 0.0]\n',
    "transmitting": '[[boundary]]\nsides = ["bottom"]\nkind = "transmitting"\n',
}

# The halves of the vertical sides above and below the interface (y = 2 mm).
HALVES = """[[mesh.side]]
from = [0.0, 0.002]
to = [0.0, 0.004]
tag = "left_upper"

[[mesh.side]]
from = [0.004, 0.0]
to = [0.004, 0.002]
tag = "right_lower"
"""


def traction(side, value):
    """A `[[boundary]]` traction `value` (Pa, x and y) on `side` growing as pi(t)."""
    return (
        f'[[boundary]]\nsides = ["{side}"]\nkind = "traction"\nvalue = [{value[0]:e}, '
        f'{value[1]:e}]\nhistory = {{ kind = "linear", ramp = 12e-6 }}\n'
    )


PI = 1e8
# name: (what the reading is, the lateral tractions (x, y), Pa, on the halves of the vertical
# sides: left above and below the interface, right above and below). The halves are tagged
# `left_upper`, `left` (what is left of it), `right` and `right_lower` by HALVES.
READINGS = {
    "shear_whole": (
        "shear on the whole vertical sides, down on the left and up on the right "
        "(the traction of a shear stress sigma_xy = pi)",
        [(0, -PI), (0, -PI), (0, PI), (0, PI)],
    ),
    "shear_halves": (
        "shear on the halves in opposite senses: above the interface down on the left and up "
        "on the right, below it the reverse",
        [(0, -PI), (0, PI), (0, PI), (0, -PI)],
    ),
    "normal_halves": (
        "normal pressure on opposite halves: the upper block pushed to the right on its left "
        "side, the lower block to the left on its right side; the other halves free",
        [(PI, 0), (0, 0), (0, 0), (-PI, 0)],
    ),
    "normal_blocks": (
        "normal traction on every half: the upper block pushed on its left and pulled on its "
        "right side to the right, the lower block the reverse",
        [(PI, 0), (-PI, 0), (PI, 0), (-PI, 0)],
    ),
}
SIDES = ["left_upper", "left", "right", "right_lower"]

# The dissertation's numbers (section 3.4.2): friction 2.04e-2 J, 30.6% of the inflow;
# numerical dissipation 0.02% of it.
SEED_FRICTION_SHARE = 30.6
SEED_NUMERICAL_SHARE = 0.02


def config_text(reading, bottom):
    _, tractions = READINGS[reading]
    loads = "".join(traction(side, value) for side, value in zip(SIDES, tractions))
    return (
        f"# stick_slip reading `{reading}`, bottom {bottom} (scripts/stick_slip_readings.py)\n"
        f'extends = "{BASE}"\n\n{HALVES}\n{TOP}\n{BOTTOM[bottom]}\n{loads}'
    )


def run(sdg, out, reading, bottom, cells, threads):
    """Runs one case unless its summary exists for the same command; returns its folder."""
    name = f"{reading}_{bottom}_n{cells}"
    folder = out / name
    config = out / f"{reading}_{bottom}.toml"
    config.write_text(config_text(reading, bottom))
    command = [
        str(sdg), "run", str(config), "--deterministic", "--threads", str(threads), "--quiet",
        "--force", "--set", f"mesh.nx={cells}", "--set", f"mesh.ny={cells}",
        "--set", "output.png=false", "--set", "output.snapshot_times=[]",
        "--output", str(folder),
    ]
    # The command and the config it ran: a reading changed here runs again.
    record = " ".join(command[1:]) + "\n" + config.read_text()
    stamp = folder / "command.txt"
    done = (folder / "summary.json").exists() and stamp.exists()
    if done and stamp.read_text() == record:
        return folder
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"{name}: exit {result.returncode}: {result.stderr[-2000:]}")
    stamp.write_text(record)
    return folder


def shares(folder):
    s = json.loads((folder / "summary.json").read_text())
    e = s["energy"]
    return {
        "inflow": e["boundary_work"],
        "friction": 100 * e["friction_dissipation"] / e["boundary_work"],
        "numerical": 100 * e["dissipation"] / e["boundary_work"],
        "balance": e["balance_residual_rel"],
        "patches": s["patches"],
    }


def table(results, cells):
    head = (
        ["reading", "bottom"]
        + [f"friction, {n} cells" for n in cells]
        + [f"numerical, {n} cells" for n in cells]
        + [f"inflow, {cells[-1]} cells (J/m)", f"patches, {cells[-1]} cells"]
    )
    rows = []
    for reading in READINGS:
        for bottom in BOTTOM:
            r = [results[(reading, bottom, n)] for n in cells]
            rows.append(
                [f"`{reading}`", bottom]
                + [f"{x['friction']:.2f}%" for x in r]
                + [f"{x['numerical']:.3f}%" for x in r]
                + [f"{r[-1]['inflow']:.1f}", f"{r[-1]['patches']:,}"]
            )
    seed = ["the dissertation", ""] + [""] * (2 * len(cells) + 2)
    seed[2] = f"{SEED_FRICTION_SHARE}%"
    seed[2 + len(cells)] = f"{SEED_NUMERICAL_SHARE}%"
    rows.append(seed)
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sdg", default=str(ROOT / "target" / "release" / "sdg"))
    parser.add_argument("--out", default=str(ROOT / "target" / "readings" / "stick_slip"))
    parser.add_argument("--cells", default="16,32", help="cells a side, comma-separated")
    parser.add_argument("--jobs", type=int, default=2, help="runs at once")
    parser.add_argument("--threads", type=int, default=1, help="threads per run")
    parser.add_argument("--write", action="store_true", help="rewrite docs/verification.md")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cells = [int(c) for c in args.cells.split(",")]
    cases = [(r, b, n) for n in cells for r in READINGS for b in BOTTOM]
    results = {}
    with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
        futures = {
            pool.submit(run, args.sdg, out, r, b, n, args.threads): (r, b, n) for r, b, n in cases
        }
        for f in concurrent.futures.as_completed(futures):
            case = futures[f]
            results[case] = shares(f.result())
            print(f"{case}: {results[case]}", file=sys.stderr)
    text = table(results, cells)
    print(text)
    if args.write:
        doc = ROOT / "docs" / "verification.md"
        pattern = re.compile(
            r"(<!-- readings:stick_slip begin -->\n).*?(<!-- readings:stick_slip end -->)", re.S
        )
        new, count = pattern.subn(lambda m: m.group(1) + text + "\n" + m.group(2), doc.read_text())
        if count != 1:
            sys.exit(f"{doc}: readings:stick_slip markers not found once")
        doc.write_text(new)


if __name__ == "__main__":
    main()
