#!/usr/bin/env bash
# Regenerate the generated tables of docs/verification.md and docs/performance.md and the
# status table of README.md.
#
#   scripts/verify.sh                       # from the repository root, after cargo build --release
#   SDG=/path/to/sdg THREADS=2 scripts/verify.sh
#
# Runs the shipped configs that have a cheap check (and a plane-wave convergence sweep), all in
# deterministic mode, into $VERIFY_OUT (default target/verify), then rewrites every block
# between `<!-- verify:NAME begin -->` and `<!-- verify:NAME end -->` with
# scripts/verify_tables.py. A rerun with the same binary writes the same bytes, apart from the
# wall-time columns. About 10 minutes on 2 cores, half of it the main job; VERIFY_MAIN=0 skips
# the main job and keeps its tables as they are.
#
# The branching study's table (verify:branching_study) is read from results/branching_convergence,
# the --output folder of `sdg study configs/studies/branching_convergence.toml` kept in the
# repository (results/README.md; hours: run it apart); without its study.json the table is kept.
#
# Environment: SDG (the binary, default target/release/sdg), THREADS (default 2), VERIFY_OUT,
# VERIFY_MAIN (1 or 0). Needs python3 (standard library only).
set -euo pipefail

# All in one function, so that bash has read the whole script before it runs any of it.
main() {
    cd "$(dirname "$0")/.."

    SDG=${SDG:-target/release/sdg}
    THREADS=${THREADS:-2}
    OUT=${VERIFY_OUT:-target/verify}
    MAIN=${VERIFY_MAIN:-1}

    if [ ! -x "$SDG" ]; then
        echo "verify.sh: no sdg binary at $SDG (cargo build --release, or set SDG)" >&2
        exit 2
    fi
    mkdir -p "$OUT"
    start=$(date +%s)

    # run NAME sdg-arguments...: one run into $OUT/NAME, its command line kept in command.txt.
    run() {
        local name=$1
        shift
        rm -rf "${OUT:?}/$name"
        echo "[$(($(date +%s) - start)) s] $name: sdg $*" >&2
        "$SDG" "$@" --output "$OUT/$name" --quiet
        echo "sdg $*" >"$OUT/$name/command.txt"
    }

    # Convergence to the exact plane wave: P and S waves, p = 1 to 3, 8 to 32 cells a side.
    for wave in P S; do
        for p in 1 2 3; do
            for nx in 8 16 32; do
                run "conv_${wave}_p${p}_n${nx}" run configs/plane_wave.toml --deterministic \
                    --threads "$THREADS" --set "exact.wave=$wave" --set "solver.order=$p" \
                    --set "mesh.nx=$nx" --set "mesh.ny=$nx" --set 'output.snapshot_times=[]' \
                    --set output.png=false
            done
        done
    done

    # The shipped configs with a check of their own, as shipped (deterministic, no pictures).
    for config in plane_wave antiplane_pulse adaptive_pulse cohesive_wave decohesion \
        contact_separation damage_interface crack_growth stick_slip; do
        run "$config" run "configs/$config.toml" --deterministic --threads "$THREADS" \
            --set output.png=false
    done

    # Pitching only.
    for config in plate_mesh plate_with_hole; do
        run "mesh_$config" mesh "configs/$config.toml" --deterministic --threads "$THREADS"
    done

    # Thread-count invariance: the same runs on one thread.
    run det_crack_growth_t1 run configs/crack_growth.toml --deterministic --threads 1 \
        --set output.png=false
    for t in 1 "$THREADS"; do
        run "async_plane_wave_t$t" run configs/plane_wave.toml --threads "$t" --set output.png=false
    done

    # The main job (deterministic by its config).
    if [ "$MAIN" = 1 ]; then
        run crack_branching run configs/crack_branching.toml --threads "$THREADS" \
            --set output.png=false
    fi

    python3 scripts/verify_tables.py "$OUT" docs/verification.md docs/performance.md README.md
    echo "verify.sh: done in $(($(date +%s) - start)) s ($THREADS threads, $SDG)" >&2
}

main "$@"
