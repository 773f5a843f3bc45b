#!/usr/bin/env bash
# The state hash, patch count and output-file digests of every shipped solver config, each run
# to a shortened end time (or to its own end with FULL=1), so that a change meant to leave
# behaviour alone can be checked against the run before it:
#   scripts/state_hashes.sh BINARY > before.txt; ...; scripts/state_hashes.sh BINARY > after.txt
#   diff before.txt after.txt
# Prints one line per config: file, patches, state_hash, then the md5 of each CSV, VTU and PVD
# file the run wrote.
set -euo pipefail
bin=${1:?usage: scripts/state_hashes.sh BINARY [CONFIG...]}
shift
cd "$(dirname "$0")/.."
configs=("$@")
if ((${#configs[@]} == 0)); then
  configs=(configs/*.toml)
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for config in "${configs[@]}"; do
  name=$(basename "$config" .toml)
  case $name in plate_mesh | plate_with_hole) continue ;; esac
  # Deterministic: asynchronous runs with events (adaptivity, cracks) depend on timing.
  args=(--threads 2 --deterministic --force --quiet --set "output.dir=\"$out/$name\"" --set output.png=false)
  if [[ ${FULL:-0} != 1 ]]; then
    # A tenth of the span past the start.
    end=$(python3 - "$config" <<'PY'
import pathlib, sys, tomllib
def load(path):
    c = tomllib.load(open(path, "rb"))
    base = c.pop("extends", None)
    if base is None:
        return c
    merged = load(pathlib.Path(path).parent / base)
    def merge(b, o):
        for k, v in o.items():
            if isinstance(b.get(k), dict) and isinstance(v, dict):
                merge(b[k], v)
            else:
                b[k] = v
    merge(merged, c)
    return merged
t = load(sys.argv[1]).get("time", {})
start, end = t.get("start", 0.0), t["end"]
span = end - start
print(repr(start + 0.1 * span))
PY
)
    # One snapshot, at the shortened end.
    args+=(--set "time.end=$end" --set "output.snapshot_times=[$end]")
  fi
  if ! "$bin" run "$config" "${args[@]}" >/dev/null 2>"$out/$name.err"; then
    echo "$name FAILED: $(tail -1 "$out/$name.err")"
    continue
  fi
  python3 - "$out/$name" "$name" <<'PY'
import hashlib, json, pathlib, sys
d = pathlib.Path(sys.argv[1])
s = json.loads((d / "summary.json").read_text())
files = sorted(p for p in d.rglob("*") if p.suffix in (".csv", ".vtu", ".pvd"))
digests = " ".join(f"{p.relative_to(d)}:{hashlib.md5(p.read_bytes()).hexdigest()[:12]}" for p in files)
print(sys.argv[2], s["patches"], s["state_hash"], digests)
PY
done
