#!/usr/bin/env bash
# A deterministic run with events (adaptivity) over 2 ranks, each holding the whole state and
# solving every other tent of each round, measured against the same run on 1 and 2 threads.
# REPEAT rounds (default 3), each running every variant once in turn, so that a noisy host
# weighs on all alike; prints a markdown row per variant with the median `wall_time_s` (the
# solve, from summary.json) and each round's, and checks that every run has the same
# state_hash. The case: configs/adaptive_pulse.toml to 4 us, deterministic.
# SDG: the binary without MPI (default: build this checkout's); SDG_MPI: one built with
# `--features mpi` (optional: without it, no mpirun row). mpirun runs on loopback, as root if
# need be.
# Usage: [SDG=path] [SDG_MPI=path] [REPEAT=3] scripts/rank_events_scaling.sh
set -euo pipefail
cd "$(dirname "$0")/.."
sdg=${SDG:-}
if [ -z "$sdg" ]; then
  cargo build --release --quiet
  sdg=./target/release/sdg
fi
repeat=${REPEAT:-3}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_btl=self,vader OMPI_MCA_oob_tcp_if_include=lo
set_=(--set time.end=4e-6 --set "output.snapshot_times=[]" --set output.png=false
      --deterministic --quiet --force)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
record() {
  python3 -c "import json,sys; d = json.load(open(sys.argv[1])); print(sys.argv[2], d['wall_time_s'], d['state_hash'])" \
    "$out/$1/summary.json" "$1" >> "$out/times"
}
for r in $(seq "$repeat"); do
  for threads in 1 2; do
    "$sdg" run configs/adaptive_pulse.toml "${set_[@]}" --threads "$threads" --output "$out/threads_$threads"
    record "threads_$threads"
  done
  "$sdg" run configs/adaptive_pulse.toml "${set_[@]}" --ranks 2 --output "$out/ranks_2"
  record ranks_2
  if [ -n "${SDG_MPI:-}" ]; then
    mpirun -n 2 "$SDG_MPI" run configs/adaptive_pulse.toml "${set_[@]}" --mpi --output "$out/mpirun_-n_2"
    record mpirun_-n_2
  fi
  echo "round $r of $repeat done" >&2
done
python3 - "$out/times" <<'PY'
import statistics, sys
times, hashes = {}, set()
for line in open(sys.argv[1]):
    name, value, state_hash = line.split()
    times.setdefault(name, []).append(float(value))
    hashes.add(state_hash)
if len(hashes) != 1:
    sys.exit(f"the runs differ: state hashes {sorted(hashes)}")
print(f"adaptive_pulse to 4 us, deterministic; every run's state_hash {hashes.pop()}")
print("| variant | median wall time (s) | rounds (s) |")
print("| --- | --- | --- |")
for name, values in times.items():
    rounds = " / ".join(f"{v:.2f}" for v in values)
    print(f"| {name.replace('_', ' ')} | {statistics.median(values):.2f} | {rounds} |")
PY
