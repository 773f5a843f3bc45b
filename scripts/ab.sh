#!/usr/bin/env bash
# A/B timing of two sdg binaries on the same run, interleaved (the one that goes first
# alternates), so that machine noise hits both alike. Prints each run's patches and
# `wall_time_s` from summary.json, the medians, and the ratio A / B of the medians.
#
# Usage: scripts/ab.sh OLD_BINARY NEW_BINARY REPS CONFIG [sdg run arguments...]
# Example (kernel of issue 16, old commit built in a worktree):
#   scripts/ab.sh /tmp/wt-old/target/release/sdg target/release/sdg 3 configs/plane_wave.toml \
#     --set mesh.nx=32 --set mesh.ny=32 --set solver.order=3 --threads 1 --deterministic
set -euo pipefail
a=$1 b=$2 reps=$3 config=$4
shift 4
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
extra=("$@")
for rep in $(seq 1 "$reps"); do
  if ((rep % 2)); then order="a b"; else order="b a"; fi
  for which in $order; do
    bin=$a; [[ $which == b ]] && bin=$b
    "$bin" run "$config" "${extra[@]}" --set "output.dir=\"$out/$which$rep\"" \
      --set "output.snapshot_times=[]" --set output.png=false >/dev/null 2>&1
  done
done
python3 - "$out" "$reps" <<'PY'
import json, statistics, sys, pathlib
out, reps = pathlib.Path(sys.argv[1]), int(sys.argv[2])
med = {}
for which in "ab":
    runs = [json.loads((out / f"{which}{r}" / "summary.json").read_text()) for r in range(1, reps + 1)]
    walls = [s["wall_time_s"] for s in runs]
    med[which] = statistics.median(walls)
    print(f"{which}: patches {runs[0]['patches']}, wall_time_s " + " / ".join(f"{w:.3f}" for w in walls)
          + f", median {med[which]:.3f} s, {runs[0]['patches'] / med[which]:,.0f} patches/s")
print(f"ratio a / b of the medians: {med['a'] / med['b']:.2f}")
PY
