#!/usr/bin/env python3
"""The two fronts of each crack branch of a `[fracture]` run: the edge front (the far end of the
branch's newest crack edge, `events.csv` extensions and branchings: where the extension rule has
put the crack path, bonded at first) and the debonded front (the tip states, `crack_tips.csv`:
where `D` reached 0.99). Distances are along the branch's path, the polyline of its edges.

Per branch with a fitted speed: its edges, the extensions `max_tip_speed` refused for now, the
edge front's speed over windows of at least `c_R tau` (median and largest over c_R), the lead of
the edge front over the debonded front at each tip state (least, median, largest, in um), and
the debonded front's largest fitted speed over c_R (`speed_m_s` of crack_tips.csv). A line
gives the largest of each over all branches, and the last lines the debonded front's largest
least-squares speed over windows of 1, 1.5, 2 and 3 `c_R tau` of its extension (each window
the states whose extension lies within it, from a tip state's on), to show how much of a
speed above c_R is the front's moving within its process zone.

    python3 scripts/crack_fronts.py RUN_FOLDER [c_R in m/s, default 938.93] [c_R tau in m, default 9.4e-6]

With `--branch B` after the folder, the tip states of branch B instead: time, both fronts, the
lead and the fitted speed.
"""
import csv
import math
import statistics
import sys
from pathlib import Path

args = [a for a in sys.argv[1:] if a != "--branch"]
show = None
if "--branch" in sys.argv:
    show = sys.argv[sys.argv.index("--branch") + 1]
    args.remove(show)
run = Path(args[0])
c_r = float(args[1]) if len(args) > 1 else 938.93
zone = float(args[2]) if len(args) > 2 else 9.4e-6

edges, refused = {}, {}
for e in csv.DictReader(open(run / "events.csv", newline="")):
    branch = e["branch"]
    if not branch:
        continue
    if e["event"] in ("extension", "branching"):
        xy = tuple(float(e[k]) for k in ("x_m", "y_m", "to_x_m", "to_y_m"))
        edges.setdefault(branch, []).append((float(e["time_s"]), xy))
    elif e["event"] == "refused" and e["reason"] == "speed":
        refused[branch] = refused.get(branch, 0) + 1
states = {}
for r in csv.DictReader(open(run / "crack_tips.csv", newline="")):
    state = (float(r["t_s"]), float(r["x_m"]), float(r["y_m"]), float(r["speed_m_s"]))
    states.setdefault(r["branch"], []).append(state)


def path(made):
    """The branch's polyline: its vertices and their distances along it, by edge in time order."""
    points, along = [made[0][1][:2]], [0.0]
    for _, (_, _, x1, y1) in made:
        x0, y0 = points[-1]
        along.append(along[-1] + math.hypot(x1 - x0, y1 - y0))
        points.append((x1, y1))
    return points, along


def project(points, along, x, y):
    """The distance along the polyline of its point nearest to (x, y)."""
    best = (math.inf, 0.0)
    for (p, q), s in zip(zip(points, points[1:]), along):
        dx, dy = q[0] - p[0], q[1] - p[1]
        length2 = dx * dx + dy * dy
        u = 0.0 if length2 == 0 else max(0.0, min(1.0, ((x - p[0]) * dx + (y - p[1]) * dy) / length2))
        d = math.hypot(p[0] + u * dx - x, p[1] + u * dy - y)
        best = min(best, (d, s + u * math.sqrt(length2)))
    return best[1]


def window_speeds(made, along):
    """The edge front's speed over each window from one edge's end to the first at least `zone`
    further, over c_R."""
    ends = [(t, s) for (t, _), s in zip(made, along[1:])]
    speeds = []
    for i, (t0, s0) in enumerate(ends):
        later = [(t, s) for t, s in ends[i + 1:] if s - s0 >= zone]
        if later and later[0][0] > t0:
            t1, s1 = later[0]
            speeds.append((s1 - s0) / (t1 - t0) / c_r)
    return speeds


totals = {"edge": 0.0, "lead": 0.0, "debonded": 0.0}
if show is None:
    print("branch,edges,refused_speed,edge_front_speed_median,edge_front_speed_max,"
          "lead_min_um,lead_median_um,lead_max_um,debonded_speed_max")
for branch, tips in states.items():
    made = edges.get(branch)
    fitted = [v / c_r for *_, v in tips if not math.isnan(v)]
    if not made or not fitted:
        continue
    points, along = path(made)
    leads = []
    for t, x, y, v in tips:
        front = max((s for (te, _), s in zip(made, along[1:]) if te <= t), default=0.0)
        debonded = project(points, along, x, y)
        leads.append(front - debonded)
        if show == branch:
            print(f"{t * 1e6:.4f} us  debonded {debonded * 1e6:7.2f} um  edge {front * 1e6:7.2f} um"
                  f"  lead {(front - debonded) * 1e6:6.2f} um  speed {v / c_r:.3f} c_R")
    speeds = window_speeds(made, along)
    if show is None and speeds:
        print(f"{branch},{len(made)},{refused.get(branch, 0)},{statistics.median(speeds):.3f},"
              f"{max(speeds):.3f},{min(leads) * 1e6:.1f},{statistics.median(leads) * 1e6:.1f},"
              f"{max(leads) * 1e6:.1f},{max(fitted):.3f}")
        totals["edge"] = max(totals["edge"], max(speeds))
        totals["lead"] = max(totals["lead"], max(leads))
        totals["debonded"] = max(totals["debonded"], max(fitted))


def largest_fit(width):
    """The largest least-squares speed of the debonded front over windows of extension `width`
    (the states whose extension lies from a state's to `width` beyond it, spanning at least 90%
    of it), over c_R, and its branch."""
    best = (0.0, "")
    for branch, tips in extensions.items():
        for _, e0 in tips:
            window = [(t, e) for t, e in tips if e0 <= e <= e0 + width]
            if max(e for _, e in window) - e0 < 0.9 * width:
                continue
            n = len(window)
            mean_t = sum(t for t, _ in window) / n
            mean_e = sum(e for _, e in window) / n
            stt = sum((t - mean_t) ** 2 for t, _ in window)
            if stt > 0:
                v = sum((t - mean_t) * (e - mean_e) for t, e in window) / stt / c_r
                best = max(best, (v, branch))
    return best


extensions = {}
for r in csv.DictReader(open(run / "crack_tips.csv", newline="")):
    extensions.setdefault(r["branch"], []).append((float(r["t_s"]), float(r["extension_m"])))
for tips in extensions.values():
    tips.sort()
if show is None:
    print(f"largest: edge front {totals['edge']:.3f} c_R over c_R tau windows, lead "
          f"{totals['lead'] * 1e6:.1f} um, debonded front {totals['debonded']:.3f} c_R")
    for k in (1.0, 1.5, 2.0, 3.0):
        v, branch = largest_fit(k * zone)
        found = f"largest {v:.3f} c_R (branch {branch})" if branch else "no window spans it"
        print(f"debonded front over {k:g} c_R tau: {found}")
