#!/usr/bin/env python3
"""A Markdown table of finished `[fracture]` runs, one row per run folder, from their
`summary.json` (the folder's name first: the summary does not record `--set` overrides such as
the draw, `fracture.seed`, so name folders after them): patches, wall time, state hash,
the first fork with both arms past 1 mm (time, distance from the notch tip, angle), branches and
nucleations, the largest branch speed over c_R, tip states above c_R of all tip states,
extensions the speed bound refused, and the energy balance residual.

    python3 scripts/fork_table.py RUN_FOLDER...

A run without such a fork shows "none" there.
"""
import json
import sys
from pathlib import Path

HEADER = [
    "run",
    "patches",
    "wall (s)",
    "state hash",
    "1 mm fork (us)",
    "at (mm)",
    "angle (deg)",
    "branches",
    "nucleations",
    "largest branch speed / c_R",
    "states above c_R",
    "speed refusals",
    "balance residual",
]


def row(folder):
    s = json.loads((Path(folder) / "summary.json").read_text())
    crack, fracture = s["crack"], s["fracture"]
    fork = fracture.get("macro_branching")
    if fork:
        at = [f"{fork['time'] * 1e6:.3f}", f"{fork['distance'] * 1e3:.2f}", f"{fork['angle']:.0f}"]
    else:
        at = ["none", "", ""]
    return [
        Path(folder).name,
        f"{s['patches']:,}",
        f"{s['wall_time_s']:,.0f}",
        s["state_hash"],
        *at,
        str(fracture["branches"]),
        str(fracture["nucleations"]),
        f"{crack['max_branch_speed_over_c_r']:.2f}",
        f"{crack['states_over_c_r']} / {crack['tip_states']:,}",
        f"{fracture['refusals'].get('speed', 0):,}",
        f"{s['energy']['balance_residual_rel']:.1e}",
    ]


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    print("| " + " | ".join(HEADER) + " |")
    print("|" + " --- |" * len(HEADER))
    for folder in sys.argv[1:]:
        print("| " + " | ".join(row(folder)) + " |")


main()
