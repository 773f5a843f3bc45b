#!/usr/bin/env python3
"""The tip states of a `[fracture]` run whose branch speed is above c_R (`crack_tips.csv`), each
with the secant speed over the same window as the reported least-squares one (the states whose
extension lies within `reach` of the state's, `reach` = the larger of two crack edges and half
of c_R tau, shifted inward at a branch's ends, as engine/src/fracture/tips.rs fits them, but
without whole-edge widening), and how far from its branch's origin and how long after the
branch began (`events.csv`) the state is. Speeds over c_R.

    python3 scripts/fast_states.py RUN_FOLDER EDGE_M [c_R in m/s, default 938.93] [c_R tau in m, default 9.4e-6]

EDGE_M: the length of the crack's edges (the legs at `adapt.min_edge`: 1.95e-6 at 1.5 um,
3.9e-6 at 3 um, 5.5e-6 at 5 um).
"""
import csv
import sys
from pathlib import Path

run = Path(sys.argv[1])
edge = float(sys.argv[2])
c_r = float(sys.argv[3]) if len(sys.argv) > 3 else 938.93
zone = float(sys.argv[4]) if len(sys.argv) > 4 else 9.4e-6
branches = {}
for r in csv.DictReader(open(run / "crack_tips.csv", newline="")):
    state = (float(r["t_s"]), float(r["extension_m"]), float(r["speed_m_s"]))
    branches.setdefault(r["branch"], []).append(state)
began = {}
for e in csv.DictReader(open(run / "events.csv", newline="")):
    if e["branch"]:
        began.setdefault(e["branch"], float(e["time_s"]))
reach = max(2.0 * edge, 0.5 * zone)
print("branch,t_s,reported_over_c_r,secant_over_c_r,states_in_window,from_origin_m,after_start_s")
for branch, states in branches.items():
    least, most = states[0][1], states[-1][1]
    for t, e, v in states:
        if not v > c_r:
            continue
        lo = max(min(e - reach, most - 2.0 * reach), least)
        window = [s for s in states if lo <= s[1] <= lo + 2.0 * reach]
        (t0, e0, _), (t1, e1, _) = window[0], window[-1]
        secant = (e1 - e0) / (t1 - t0) / c_r if t1 > t0 else float("nan")
        after = t - began.get(branch, float("nan"))
        print(f"{branch},{t:.6e},{v / c_r:.3f},{secant:.3f},{len(window)},{e:.3e},{after:.3e}")
