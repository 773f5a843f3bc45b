"""When each crack tip state's edge was laid, and how fast propagation laid the edges.

For a run with [fracture], reads OUTPUT/events.csv and OUTPUT/crack_tips.csv (both on the
run's clock) and prints:
- per tip state, the lag from the extension that laid the crack edge it lies on to the state
  (the time its point debonded), in units of the delay TAU: quantiles for the states above
  c_R and for the others. Under full overload (f(y) = 1 from D = 0) the damage law reaches
  1 - eps after -ln((exp(a eps) - 1) / (exp(a) - 1)) / a delays: 1.69 tau for a = 10 and
  eps = 1e-4, the shipped law's;
- per state above c_R, how its branch began (a nucleation, a branching off another branch, or
  an initial crack's tip) and the state's distance and time from that start;
- per branch with states above c_R, its extensions in time order with the gap to the previous
  one, the speed that gap lays the edge at, over c_R, and the tests the mesh refused at the
  tip in that gap by reason (the `reason` column of events.csv, docs/reference/config.md).

Usage: python3 scripts/crack_lag.py OUTPUT [TAU_S [C_R_M_S]]   (defaults 1e-8 s, 938 m/s: the
main job's delay and PMMA's Rayleigh speed). Python 3 standard library only.
"""

import csv
import math
import sys


def on_segment(p, a, b):
    """True when p lies on the segment a-b (to a billionth of its length)."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    length = math.hypot(dx, dy)
    if length == 0.0:
        return False
    along = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length**2
    across = abs((p[0] - a[0]) * dy - (p[1] - a[1]) * dx) / length
    return -1e-9 <= along <= 1.0 + 1e-9 and across <= 1e-9 * length


def quantiles(values):
    values = sorted(values)
    if not values:
        return "none"
    pick = lambda f: values[round(f * (len(values) - 1))]
    return "min %.2f, 10%% %.2f, median %.2f, 90%% %.2f, max %.2f" % tuple(
        pick(f) for f in (0.0, 0.1, 0.5, 0.9, 1.0)
    )


def main():
    out = sys.argv[1]
    tau = float(sys.argv[2]) if len(sys.argv) > 2 else 1e-8
    c_r = float(sys.argv[3]) if len(sys.argv) > 3 else 938.0
    with open(out + "/events.csv") as f:
        events = list(csv.DictReader(f))
    laid = [
        (
            float(e["time_s"]),
            e["branch"],
            (float(e["x_m"]), float(e["y_m"])),
            (float(e["to_x_m"]), float(e["to_y_m"])),
        )
        for e in events
        if e["event"] == "extension"
    ]
    refused = [
        (float(e["time_s"]), e["branch"], (float(e["x_m"]), float(e["y_m"])), e.get("reason", ""))
        for e in events
        if e["event"] == "refused"
    ]
    # A branch begins at its first extension; a nucleation or branching event at the same time
    # and point says how (a nucleation's second branch has no event of its own).
    starts = {(e["time_s"], e["x_m"], e["y_m"]): e["event"] for e in events
              if e["event"] in ("nucleation", "branching")}
    origins = {}
    for e in events:
        if e["event"] == "extension" and e["branch"] not in origins:
            kind = starts.get((e["time_s"], e["x_m"], e["y_m"]), "initial crack")
            origins[e["branch"]] = (kind, float(e["time_s"]), (float(e["x_m"]), float(e["y_m"])))
    above, below, fast, states = [], [], set(), []
    with open(out + "/crack_tips.csv") as f:
        for row in csv.DictReader(f):
            t, point = float(row["t_s"]), (float(row["x_m"]), float(row["y_m"]))
            edges = [e[0] for e in laid if on_segment(point, e[2], e[3])]
            if not edges:
                continue
            lag = (t - min(edges)) / tau
            if float(row["speed_m_s"]) > c_r:
                above.append(lag)
                fast.add(row["branch"])
                states.append((row["branch"], t, point, float(row["speed_m_s"]) / c_r))
            else:
                below.append(lag)
    print("lag from laying to debonding, in tau:")
    print("  %4d states above c_R: %s" % (len(above), quantiles(above)))
    print("  %4d other states:     %s" % (len(below), quantiles(below)))
    print("states above c_R (branch, time, speed, how the branch began, distance and time since):")
    for branch, t, point, speed in states:
        kind, start, at = origins[branch]
        print("  %4s  %.4f us  %.2f c_R  %-13s  %6.1f um, %6.1f ns" % (
            branch, t * 1e6, speed, kind, math.dist(point, at) * 1e6, (t - start) * 1e9))
    for branch in sorted(fast, key=int):
        print("branch %s, extensions (time, gap, laid at, refused tests since):" % branch)
        previous = None
        for t, b, a, z in sorted(e for e in laid if e[1] == branch):
            line = "  %.4f us" % (t * 1e6)
            if previous is not None and t > previous:
                gap = t - previous
                line += "  %6.2f ns  %6.2f c_R" % (gap * 1e9, math.dist(a, z) / gap / c_r)
                reasons = {}
                for rt, rb, at, reason in refused:
                    if rb == branch and at == a and previous < rt <= t:
                        reasons[reason] = reasons.get(reason, 0) + 1
                line += "  " + ", ".join("%d %s" % (n, r) for r, n in sorted(reasons.items()))
            print(line.rstrip())
            previous = t


if __name__ == "__main__":
    main()
