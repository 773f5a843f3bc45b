"""How much of a crack path is open: the damage along the shortest path of crack edges.

Reads OUTPUT/cracks.csv (every crack edge at the end of a run with [fracture]: ends, tag,
branch, damage on the front) and follows the shortest path along crack edges (of any tag and
damage) from the crack vertex nearest (X0, Y0) to the one nearest (X1, Y1), metres. Prints the
path's length, how much of it lies on edges with damage at least 0.99 and 0.9, the least
damage on it, and, with --edges, the damage of each of its edges in order. The arms that
`summary.json`'s `fracture.macro_branching` measures follow crack edges whatever their
damage, and its `open_arms` sum the edges at 0.99 or more on each arm's path from the fork to
its farthest point; this script follows any path and tells where it has not debonded.

Usage: python3 scripts/crack_path_damage.py OUTPUT X0 Y0 X1 Y1 [--edges]
Python 3 standard library only.
"""

import collections
import csv
import heapq
import math
import sys


def main():
    out, x0, y0, x1, y1 = sys.argv[1], *map(float, sys.argv[2:6])
    # Vertices keyed by their coordinates in nanometres (cracks.csv repeats shared ends exactly).
    key = lambda x, y: (round(x * 1e9), round(y * 1e9))
    graph = collections.defaultdict(list)
    with open(out + "/cracks.csv") as f:
        for row in csv.DictReader(f):
            a = key(float(row["x0_m"]), float(row["y0_m"]))
            b = key(float(row["x1_m"]), float(row["y1_m"]))
            length = math.dist(a, b) * 1e-9
            damage = float(row["damage"])
            graph[a].append((b, length, damage))
            graph[b].append((a, length, damage))
    nearest = lambda x, y: min(graph, key=lambda v: math.hypot(v[0] * 1e-9 - x, v[1] * 1e-9 - y))
    start, goal = nearest(x0, y0), nearest(x1, y1)
    distance, previous, heap = {start: 0.0}, {}, [(0.0, start)]
    while heap:
        d, v = heapq.heappop(heap)
        if d > distance[v]:
            continue
        for w, length, damage in graph[v]:
            if d + length < distance.get(w, math.inf):
                distance[w] = d + length
                previous[w] = (v, length, damage)
                heapq.heappush(heap, (d + length, w))
    if goal not in distance:
        sys.exit("no path of crack edges joins the two points")
    path, v = [], goal
    while v != start:
        v, length, damage = previous[v][0], previous[v][1], previous[v][2]
        path.append((length, damage))
    path.reverse()
    total = sum(length for length, _ in path)
    over = lambda level: sum(length for length, damage in path if damage >= level)
    print("path from (%.4f, %.4f) mm to (%.4f, %.4f) mm along %d crack edges: %.3f mm"
          % (start[0] * 1e-6, start[1] * 1e-6, goal[0] * 1e-6, goal[1] * 1e-6, len(path),
             total * 1e3))
    print("  on edges with D >= 0.99: %.3f mm; D >= 0.9: %.3f mm; least D %.3f"
          % (over(0.99) * 1e3, over(0.9) * 1e3, min((d for _, d in path), default=math.nan)))
    if "--edges" in sys.argv[6:]:
        print("  D along the path:", " ".join("%.2f" % d for _, d in path))


if __name__ == "__main__":
    main()
