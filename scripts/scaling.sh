#!/usr/bin/env bash
# Strong scaling of `sdg run`, run REPEAT times (default 3) per thread count and mode; prints the
# median wall time (the solve, from summary.json) and the speedup over one thread.
# CASE=plane_wave (default): the p = 2 plane wave on a 64 x 64 mesh.
# CASE=adaptive: configs/adaptive_pulse.toml to 2e-6 s, refining as it goes.
# Usage: [CASE=...] scripts/scaling.sh [THREADS...]   (default: 1 2)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
repeat=${REPEAT:-3}
threads=("${@:-1 2}")
case "${CASE:-plane_wave}" in
  plane_wave) run=(configs/plane_wave.toml --set mesh.nx=64 --set mesh.ny=64 --set solver.order=2
                   --set time.end=5e-7) ;;
  adaptive) run=(configs/adaptive_pulse.toml --set time.end=2e-6) ;;
  *) echo "unknown CASE ${CASE}" >&2; exit 2 ;;
esac
out=$(mktemp -d)
for mode in asynchronous deterministic; do
  flag=""; [ "$mode" = deterministic ] && flag="--deterministic"
  base=""
  for n in ${threads[@]}; do
    times=()
    for _ in $(seq "$repeat"); do
      ./target/release/sdg run "${run[@]}" --quiet $flag --threads "$n" --output "$out" \
        --set 'output.snapshot_times=[]'
      times+=("$(python3 -c "import json;print(json.load(open('$out/summary.json'))['wall_time_s'])")")
    done
    median=$(printf '%s\n' "${times[@]}" | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}')
    [ -z "$base" ] && base=$median
    printf '%-13s threads %2d: median %.3f s of [%s], speedup %.2f\n' "$mode" "$n" "$median" \
      "$(echo "${times[@]}" | sed 's/ /, /g')" "$(python3 -c "print($base/$median)")"
  done
done
rm -rf "$out"
