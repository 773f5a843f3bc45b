#!/usr/bin/env bash
# Strong scaling of `sdg run`, REPEAT rounds (default 3); each round runs every mode and thread
# count once, in turn, so that a noisy host weighs on all of them alike. Prints per mode and
# thread count the median wall time (the solve, from summary.json) and the speedup over the
# first thread count (ratio of medians, and per round).
# CASE=plane_wave (default): the p = 2 plane wave on a 64 x 64 mesh.
# CASE=adaptive: configs/adaptive_pulse.toml to 2e-6 s, refining as it goes.
# SDG=path: the binary to run (default: build and run this checkout's release binary).
# Usage: [CASE=...] [REPEAT=...] [SDG=...] scripts/scaling.sh [THREADS...]   (default: 1 2)
set -euo pipefail
cd "$(dirname "$0")/.."
sdg=${SDG:-}
if [ -z "$sdg" ]; then
  cargo build --release --quiet
  sdg=./target/release/sdg
fi
repeat=${REPEAT:-3}
threads=("${@:-1 2}")
case "${CASE:-plane_wave}" in
  plane_wave) run=(configs/plane_wave.toml --set mesh.nx=64 --set mesh.ny=64 --set solver.order=2
                   --set time.end=5e-7) ;;
  adaptive) run=(configs/adaptive_pulse.toml --set time.end=2e-6) ;;
  *) echo "unknown CASE ${CASE}" >&2; exit 2 ;;
esac
out=$(mktemp -d)
log="$out/times"
for _ in $(seq "$repeat"); do
  for mode in asynchronous deterministic; do
    flag=""; [ "$mode" = deterministic ] && flag="--deterministic"
    for n in ${threads[@]}; do
      "$sdg" run "${run[@]}" --quiet $flag --threads "$n" --output "$out/run" \
        --set 'output.snapshot_times=[]' 2>/dev/null
      echo "$mode $n $(python3 -c "import json;print(json.load(open('$out/run/summary.json'))['wall_time_s'])")" >>"$log"
    done
  done
done
python3 - "$log" <<'PY'
import collections, statistics, sys
times = collections.defaultdict(list)
order = []
for line in open(sys.argv[1]):
    mode, n, t = line.split()
    if (mode, n) not in times:
        order.append((mode, n))
    times[(mode, n)].append(float(t))
base = {}
for mode, n in order:
    ts = times[(mode, n)]
    base.setdefault(mode, n)
    b = times[(mode, base[mode])]
    median = statistics.median(ts)
    per_round = ", ".join(f"{x / y:.2f}" for x, y in zip(b, ts))
    print(f"{mode:<13} threads {int(n):2d}: median {median:.3f} s of "
          f"[{', '.join(f'{t:.3f}' for t in ts)}], speedup {statistics.median(b) / median:.2f} "
          f"(per round {per_round})")
PY
rm -rf "$out"
