#!/usr/bin/env python3
"""Collect the summary.json of a sweep's runs into one CSV (standard library only).

    python3 examples/slurm/collect.py out/sweep_load > sweep_load.csv
    python3 examples/slurm/collect.py out/sweep_load/task_* --keys final_time,fracture.branchings

Each argument is a run's output dir (with summary.json) or a dir whose subdirs are. One row
per run: `dir`, `status`, the task's overrides (one column per key of its
overrides.txt, written by sweep.sbatch), then the keys (dotted paths, docs/reference/summary.md). Only
documented keys are read; an optional key a run lacks (`crack`, `fracture`, `error`,
`loading`, `peak_memory_bytes`) and a `null` give an empty cell. Keys a newer sdg adds are ignored.

`status`: `finished` (summary.json, and the last exit code in jobs.log, if any, is 0);
`exit N` (the job scripts' jobs.log ends with sdg exit code N != 0: 3 checkpointed, to be
resumed; 1 failed; 2 refused; a summary.json there is from an earlier run and is not read);
`checkpointed` (no summary, a checkpoint to resume from); `missing` (neither).
"""

import argparse
import csv
import json
import sys
from pathlib import Path

# Documented keys of summary.json (docs/reference/summary.md) worth a column in a sweep.
DEFAULT_KEYS = [
    "final_time",
    "patches",
    "elements",
    "wall_time_s",
    "threads",
    "peak_memory_bytes",
    "mode",
    "state_hash",
    "vertices",
    "triangles",
    "refinements",
    "energy.initial",
    "energy.final",
    "energy.boundary_work",
    "energy.dissipation",
    "energy.interface_work",
    "energy.fracture_energy",
    "energy.balance_residual_rel",
    "interface.nonlinear_patches",
    "loading.load_ratio",
    "crack.final_length",
    "crack.max_speed",
    "crack.max_speed_over_c_r",
    "fracture.nucleations",
    "fracture.extensions",
    "fracture.branchings",
    "fracture.branches",
    "fracture.total_length",
    "fracture.first_branching_time",
    "fracture.first_branching_distance",
    "error.velocity_l2_rel",
    "error.stress_l2_rel",
]


def run_dirs(paths):
    """The run dirs among `paths` and their subdirs, in order."""
    dirs = []
    for p in map(Path, paths):
        if not p.is_dir():
            sys.exit(f"collect.py: {p}: not a directory")
        if (p / "summary.json").exists() or (p / "overrides.txt").exists():
            dirs.append(p)
        else:
            dirs.extend(sorted(d for d in p.iterdir() if d.is_dir() and d.name != "checkpoints"))
    return dirs


def lookup(summary, key):
    """The value at dotted `key`, or None when a part is absent."""
    value = summary
    for part in key.split("."):
        if not isinstance(value, dict) or part not in value:
            return None
        value = value[part]
    return value


def last_exit_code(run):
    """sdg's exit code on the last line of the run's jobs.log (job scripts), or None."""
    path = run / "jobs.log"
    lines = path.read_text().split("\n") if path.exists() else []
    words = [line.split() for line in lines if "sdg exited" in line]
    return int(words[-1][-1]) if words else None


def overrides(run):
    """KEY=VALUE lines of the run's overrides.txt, as a dict."""
    path = run / "overrides.txt"
    if not path.exists():
        return {}
    pairs = (line.split("=", 1) for line in path.read_text().splitlines() if "=" in line)
    return {k.strip(): v.strip() for k, v in pairs}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dirs", nargs="+", help="run dirs, or dirs of run dirs")
    parser.add_argument("--keys", help="comma-separated dotted keys (default: a selection)")
    parser.add_argument("--output", "-o", help="CSV file (default: standard output)")
    args = parser.parse_args()
    keys = args.keys.split(",") if args.keys else DEFAULT_KEYS

    rows = []
    for run in run_dirs(args.dirs):
        summary_path = run / "summary.json"
        code = last_exit_code(run)
        if code not in (None, 0):
            summary, status = {}, f"exit {code}"
        elif summary_path.exists():
            summary, status = json.loads(summary_path.read_text()), "finished"
        else:
            checkpoints = list((run / "checkpoints").glob("checkpoint_*.sdgc"))
            summary, status = {}, "checkpointed" if checkpoints else "missing"
        row = {"dir": str(run), "status": status, **overrides(run)}
        for key in keys:
            value = lookup(summary, key)
            if value is None or isinstance(value, (dict, list)):
                value = ""
            elif isinstance(value, bool):
                value = str(value).lower()
            row[key] = value
        rows.append(row)

    override_keys = sorted({k for r in rows for k in r} - {"dir", "status", *keys})
    columns = ["dir", "status", *override_keys, *keys]
    out = open(args.output, "w", newline="") if args.output else sys.stdout
    writer = csv.DictWriter(out, fieldnames=columns, restval="", lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    finished = sum(r["status"] == "finished" for r in rows)
    print(f"collect.py: {len(rows)} runs, {finished} finished", file=sys.stderr)


if __name__ == "__main__":
    main()
