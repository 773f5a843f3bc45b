#!/usr/bin/env bash
# The table of time per stage against the arithmetic of the p = 1 patch kinds of the branching
# problem (benches/patch/branching.rs), as markdown on standard output; docs/performance.md has
# its output. Runs in about ten seconds after the build:
#   scripts/patch_table.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo bench --bench patch --no-run --quiet 2>/dev/null
PATCH_TABLE=1 cargo bench --bench patch --quiet 2>/dev/null
