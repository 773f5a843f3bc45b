#!/usr/bin/env python3
"""Per crack branch of a `[fracture]` run, how fast its crack surface tip made edges: from
`events.csv`, the length and time between consecutive `extension` events of the branch.
Prints, per branch, how it started (nucleated, or from the notch or a fork), its edges, the
median speed between consecutive extensions and the mean speed over its first five edges after
the first, both over c_R. The debonded front's speed is `crack_tips.csv`'s; this is the tip that
runs ahead of it (docs/theory/method.md#cracks-that-grow-fracture-sections-43-44).

    python3 scripts/tip_advance.py RUN_FOLDER [c_R in m/s, default 938 (the plate's PMMA)]
"""
import csv
import math
import statistics
import sys
from pathlib import Path

run = Path(sys.argv[1])
c_r = float(sys.argv[2]) if len(sys.argv) > 2 else 938.0
events = list(csv.DictReader(open(run / "events.csv", newline="")))
nucleated = {e["branch"] for e in events if e["event"] == "nucleation"}
edges = {}
for e in events:
    if e["event"] == "extension" and e["branch"]:
        length = math.hypot(float(e["to_x_m"]) - float(e["x_m"]), float(e["to_y_m"]) - float(e["y_m"]))
        edges.setdefault(e["branch"], []).append((float(e["time_s"]), length))
print("branch,start,edges,median_speed_over_c_r,first_five_over_c_r")
for branch in sorted(edges, key=int):
    made = edges[branch]
    speeds = [b[1] / (b[0] - a[0]) for a, b in zip(made, made[1:]) if b[0] > a[0]]
    median = statistics.median(speeds) / c_r if speeds else math.nan
    first = math.nan
    if len(made) >= 6 and made[5][0] > made[0][0]:
        first = sum(l for _, l in made[1:6]) / (made[5][0] - made[0][0]) / c_r
    start = "nucleated" if branch in nucleated else "notch_or_fork"
    print(f"{branch},{start},{len(made)},{median:.3f},{first:.3f}")
