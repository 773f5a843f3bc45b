#!/usr/bin/env python3
"""What came just before each tip state faster than c_R, over the crack records of runs.

For every tip state of `crack_tips.csv` whose fitted speed exceeds c_R, the events of
`events.csv` on its branch within WINDOW before it, in this order of precedence: the branch's
arrest (its path stopped on a crack or the boundary), a `speed` refusal (the path held by
`max_tip_speed`), a `shield` refusal, its start (the branching or nucleation that made it);
else "other". Prints a line per run folder and one for all, with the share of all tip states
with a speed that follow a `speed` refusal within WINDOW, for comparison.

    python3 scripts/fast_causes.py RUN_FOLDER... [--c-r 938.93] [--window 1e-8]
"""
import bisect
import csv
import sys
from pathlib import Path

args = sys.argv[1:]


def option(name, default):
    if name in args:
        i = args.index(name)
        value = float(args[i + 1])
        del args[i : i + 2]
        return value
    return default


c_r = option("--c-r", 938.93)
window = option("--window", 1e-8)
CAUSES = ("arrest", "speed", "shield", "start", "other")


def causes(run):
    """Counts of the causes of the states above c_R in `run`, and (states with a speed, those
    of them within `window` after a speed refusal)."""
    marks, first_edge = {}, {}
    for e in csv.DictReader(open(run / "events.csv", newline="")):
        if not e["branch"]:
            continue
        t = float(e["time_s"])
        if e["event"] in ("extension", "branching", "nucleation"):
            first_edge[e["branch"]] = min(first_edge.get(e["branch"], t), t)
        kind = e["reason"] if e["event"] == "refused" else e["event"]
        if kind in ("branching", "nucleation"):
            # A branching names its parent branch; the new branch starts with its first edge.
            kind = "start"
        if kind in CAUSES:
            marks.setdefault(e["branch"], {}).setdefault(kind, []).append(t)
    for times in marks.values():
        for kind in times:
            times[kind].sort()

    def within(branch, kind, t):
        times = marks.get(branch, {}).get(kind, [])
        if kind == "start" and branch in first_edge:
            times = sorted(times + [first_edge[branch]])
        k = bisect.bisect_right(times, t)
        return k > 0 and t - times[k - 1] <= window

    counts = dict.fromkeys(CAUSES, 0)
    with_speed = after_refusal = 0
    for r in csv.DictReader(open(run / "crack_tips.csv", newline="")):
        speed = float(r["speed_m_s"]) if r["speed_m_s"] else float("nan")
        if speed != speed:
            continue
        t, branch = float(r["t_s"]), r["branch"]
        with_speed += 1
        after_refusal += within(branch, "speed", t)
        if speed > c_r:
            cause = next((k for k in CAUSES[:-1] if within(branch, k, t)), "other")
            counts[cause] += 1
    return counts, with_speed, after_refusal


total = dict.fromkeys(CAUSES, 0)
all_speed = all_after = 0
print("run, states above c_R, after: " + ", ".join(CAUSES) + ", share of all states after a speed refusal")
for folder in args:
    counts, with_speed, after = causes(Path(folder))
    for k in CAUSES:
        total[k] += counts[k]
    all_speed += with_speed
    all_after += after
    share = after / with_speed if with_speed else float("nan")
    print(f"{folder}, {sum(counts.values())}, " + ", ".join(str(counts[k]) for k in CAUSES) + f", {share:.2f}")
share = all_after / all_speed if all_speed else float("nan")
print(f"all, {sum(total.values())}, " + ", ".join(str(total[k]) for k in CAUSES) + f", {share:.2f}")
