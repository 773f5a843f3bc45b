#!/usr/bin/env bash
# The error at the end time against the end time's phase in the tent pattern (docs/performance.md,
# "What decides the rates"). Runs the peer problem of ../shared/peers/compare_ngstents.sh (anti-plane
# plane wave at 23 degrees on the unit square, n x n "left" diagonals, exact data on the sides) at
# COUNT end times evenly spread over [0.45, 0.545] (more than a layer of tents on every level from
# n = 6 up) and prints per level the error at T = 0.5, the geometric mean, least and largest error
# over the end times, and the observed rates between levels from T = 0.5 alone and from the means.
# The error is the comparison script's: sqrt((e_v^2 + e_s^2) / 2) of the relative L2 errors.
# ORDER=2 (default) or 3; LEVELS="8 16 32 64" (default); COUNT=14 (default);
# PERTURB=x moves interior vertices by up to x cells (mesh.perturb), e.g. 1e-9 to break exact ties;
# SDG=path: the binary (default: build and run this checkout's release binary). One thread.
# Usage: [ORDER=..] [LEVELS=..] [COUNT=..] [PERTURB=..] [SDG=..] scripts/end_phase.sh
set -euo pipefail
cd "$(dirname "$0")/.."
[ -n "${SDG:-}" ] || cargo build --release --quiet
sdg=${SDG:-./target/release/sdg}
order=${ORDER:-2}
levels=${LEVELS:-8 16 32 64}
count=${COUNT:-14}
extra=()
[ -n "${PERTURB:-}" ] && extra=(--set "mesh.perturb=${PERTURB}")
out=$(mktemp -d)
rows="$out/rows"
for n in $levels; do
  for k in $(seq 0 "$count"); do
    # k = count is T = 0.5 itself; the others spread over [0.45, 0.545].
    t=$(python3 -c "k, c = $k, $count; print(0.5 if k == c else round(0.45 + k * 0.095 / (c - 1), 6))")
    dir="$out/run"
    "$sdg" run configs/plane_wave.toml --quiet --force --threads 1 --output "$dir" \
      --set 'material.plane="antiplane"' --set material.young=2.5 --set material.poisson=0.25 \
      --set material.density=1.0 --set mesh.width=1 --set mesh.height=1 --set "mesh.nx=$n" \
      --set "mesh.ny=$n" --set 'mesh.diagonal="left"' --set 'exact.wave="S"' \
      --set exact.angle_deg=23 --set exact.wavelength=1 --set exact.amplitude=1 \
      --set 'exact.profile="sine"' --set "time.end=$t" --set "solver.order=$order" \
      --set 'output.snapshot_times=[]' --set output.png=false "${extra[@]}" >/dev/null
    python3 - "$dir/summary.json" "$n" "$t" "$k" "$count" >>"$rows" <<'EOF'
import json, math, sys
s = json.load(open(sys.argv[1]))
e = s["error"]
err = math.sqrt((e["velocity_l2_rel"] ** 2 + e["stress_l2_rel"] ** 2) / 2)
print(sys.argv[2], sys.argv[3], int(sys.argv[4]) == int(sys.argv[5]), s["patches"], err)
EOF
  done
done
python3 - "$rows" "$order" <<'EOF'
import math, sys
rows = [line.split() for line in open(sys.argv[1])]
levels = sorted({int(r[0]) for r in rows})
at_half, spread = {}, {}
for n, t, half, tents, err in rows:
    if half == "True":
        at_half[int(n)] = (int(tents), float(err))
    else:
        spread.setdefault(int(n), []).append(float(err))
print(f"p = {sys.argv[2]}: error at the end time T")
print("| n | tents at T = 0.5 | error at T = 0.5 | geometric mean | least | largest | end times |")
print("| --- | --- | --- | --- | --- | --- | --- |")
geo = {}
for n in levels:
    e = spread[n]
    geo[n] = math.exp(sum(map(math.log, e)) / len(e))
    tents, half = at_half[n]
    print(f"| {n} | {tents} | {half:.3e} | {geo[n]:.3e} | {min(e):.3e} | {max(e):.3e} | {len(e)} |")
print()
for a, b in zip(levels, levels[1:]):
    r = math.log(b / a)
    print(f"rate {a} -> {b}: at T = 0.5 {math.log(at_half[a][1] / at_half[b][1]) / r:.2f}, "
          f"from the means {math.log(geo[a] / geo[b]) / r:.2f}")
EOF
rm -rf "$out"
