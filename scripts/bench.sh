#!/usr/bin/env bash
# Runs the criterion benchmarks and prints each one's median time per iteration and median
# throughput, read from criterion's estimates. Usage: scripts/bench.sh [BENCH_FILTER]
set -euo pipefail
cd "$(dirname "$0")/.."
cargo bench --bench pitch -- "${1:-}" >target/bench.log 2>&1 || { cat target/bench.log; exit 1; }
python3 - <<'PY'
import json, pathlib
for est in sorted(pathlib.Path("target/criterion").glob("*/*/new/estimates.json")):
    bench = json.loads((est.parent / "benchmark.json").read_text())
    median_s = json.loads(est.read_text())["median"]["point_estimate"] * 1e-9
    thr = bench.get("throughput") or {}
    per_s = f", {thr['Elements'] / median_s:,.0f} elements/s" if "Elements" in thr else ""
    print(f"{bench['full_id']}: median {median_s * 1e3:.3f} ms{per_s}")
PY
