#!/usr/bin/env bash
# A run over MPI ranks (of one or two threads) measured against the same run on threads and
# against what `sdg scaling
# --ranks 2` predicts from a trace of the threaded run on 2 threads (whose tents cost what they
# cost with both cores busy, as on 2 ranks). REPEAT rounds (default 3), each running
# every variant once in turn, so that a noisy host weighs on all alike; prints a markdown row
# per variant with the median `wall_time_s` (the solve, from summary.json) and each round's.
# The case: configs/plane_wave.toml on CELLS x CELLS cells (default 48), p = 2, to 2 us.
# SDG: the binary without MPI (default: build this checkout's); SDG_MPI: one built with
# `--features mpi` (required); LATENCY_US: the prediction's update latency (default 100, the
# MPI transport's longest idle sleep). mpirun runs on loopback, as root if need be.
# Usage: SDG_MPI=path [SDG=path] [REPEAT=3] [LATENCY_US=100] scripts/rank_scaling.sh [CELLS]
set -euo pipefail
cd "$(dirname "$0")/.."
: "${SDG_MPI:?set SDG_MPI to an sdg built with --features mpi}"
sdg=${SDG:-}
if [ -z "$sdg" ]; then
  cargo build --release --quiet
  sdg=./target/release/sdg
fi
cells=${1:-48}
repeat=${REPEAT:-3}
latency=${LATENCY_US:-100}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_btl=self,vader OMPI_MCA_oob_tcp_if_include=lo
set_=(--set "mesh.nx=$cells" --set "mesh.ny=$cells" --set "output.snapshot_times=[]"
      --set output.png=false)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
wall() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['wall_time_s'])" "$1/summary.json"; }
for r in $(seq "$repeat"); do
  "$sdg" run configs/plane_wave.toml "${set_[@]}" --threads 1 --quiet --force --output "$out/t1"
  echo "threads_1 $(wall "$out/t1")" >> "$out/times"
  "$sdg" run configs/plane_wave.toml "${set_[@]}" --threads 2 --quiet --force \
    --output "$out/t2" --trace "$out/trace.csv"
  echo "threads_2_traced $(wall "$out/t2")" >> "$out/times"
  "$sdg" scaling "$out/trace.csv" --workers 1 --ranks 2 --config configs/plane_wave.toml \
    "${set_[@]}" --latency-us "$latency" | awk '$1 == "1" { print "predicted_2_ranks", $2 }' \
    >> "$out/times"
  for n in 1 2; do
    mpirun -n "$n" "$SDG_MPI" run configs/plane_wave.toml "${set_[@]}" --mpi --quiet --force \
      --output "$out/m$n"
    echo "mpirun_-n_$n $(wall "$out/m$n")" >> "$out/times"
  done
  # One rank of two threads, given both cores (mpirun binds a rank to one core otherwise).
  mpirun -n 1 --map-by slot:PE=2 "$SDG_MPI" run configs/plane_wave.toml "${set_[@]}" --mpi \
    --threads 2 --quiet --force --output "$out/m1t2"
  echo "mpirun_-n_1_--threads_2 $(wall "$out/m1t2")" >> "$out/times"
  echo "round $r of $repeat done" >&2
done
python3 - "$out/times" "$cells" "$latency" <<'PY'
import statistics, sys
times = {}
for line in open(sys.argv[1]):
    name, value = line.split()
    times.setdefault(name, []).append(float(value))
print(f"plane_wave {sys.argv[2]} x {sys.argv[2]}, p = 2, to 2 us; prediction with {sys.argv[3]} us")
print("| variant | median wall time (s) | rounds (s) |")
print("| --- | --- | --- |")
for name, values in times.items():
    rounds = " / ".join(f"{v:.2f}" for v in values)
    print(f"| {name.replace('_', ' ')} | {statistics.median(values):.2f} | {rounds} |")
PY
