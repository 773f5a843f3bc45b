#!/usr/bin/env python3
"""How far the crack edges of `[fracture]` runs are debonded at the end: per run folder, the
crack edges (`cracks.csv`, tag `crack`) by their damage on the front, in the bands 0, (0, 0.9),
[0.9, 0.99), [0.99, 1 - eps) and [1 - eps, 1], with eps the damage law's `damage_eps` (default
1e-4). The tip states of `crack_tips.csv`, and the branch speeds fitted to them, are the
crossings of `D = 1 - eps`: an edge whose damage stalls below it (its overstress gone) has
none, and the debonded front measured across it jumps (docs/verification.md, "Fracture and
branching").

    python3 scripts/crack_damage.py RUN_FOLDER... [--eps 1e-4]
"""
import csv
import sys
from pathlib import Path

args = sys.argv[1:]
eps = 1e-4
if "--eps" in args:
    i = args.index("--eps")
    eps = float(args[i + 1])
    del args[i : i + 2]
if not args:
    sys.exit(__doc__)
bands = [("0", 0.0), ("(0, 0.9)", 0.9), ("[0.9, 0.99)", 0.99), ("[0.99, 1 - eps)", 1.0 - eps)]
print("run,crack_edges," + ",".join(name for name, _ in bands) + ",[1 - eps, 1]")
for run in args:
    if not (Path(run) / "summary.json").is_file():
        print(f"{run}: not finished (no summary.json), left out", file=sys.stderr)
        continue
    damage = [
        float(row["damage"])
        for row in csv.DictReader(open(Path(run) / "cracks.csv", newline=""))
        if row["tag"] == "crack"
    ]
    counts = [0] * (len(bands) + 1)
    for d in damage:
        if d <= 0.0:
            counts[0] += 1
            continue
        k = next((k for k, (_, top) in enumerate(bands) if k > 0 and d < top), len(bands))
        counts[k] += 1
    print(f"{run},{len(damage)}," + ",".join(str(c) for c in counts))
