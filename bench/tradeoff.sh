#!/bin/sh
# Work-precision of hsnc against the numerical baselines (ab4 over its step,
# rk45 -- and cvode when the build has it -- over their tolerances) on the
# paper's two scenarios and a chain, with `hsnc tradeoff`. For each model it
# writes OUTDIR/<model>.csv (one row per run: wall time, errors, time ratio to
# hsnc), OUTDIR/<model>.png (log-log error against wall time, one curve per
# method) and OUTDIR/<model>-summary.txt (per baseline: the cheapest run that
# reaches each accuracy, as a time ratio to hsnc measured in the same run).
#
# Usage: bench/tradeoff.sh [-o OUTDIR] [-r REFDIR] [-b BUILD_DIR] [-- MORE_TRADEOFF_FLAGS]
#   OUTDIR  default docs/tradeoff
#   REFDIR  reference CSVs <model>.csv and <model>-events.csv (the contract's
#           format, sampled at t0 + k*(t_end-t0)/1000); default: the reference is
#           computed in process at 40 digits (hsnc::reference; needs that engine in
#           the build). Figures for the docs must come from a true reference:
#           never commit ones made against hsnc's own double-precision output.
#
# Horizons:
#   seed-scenario-1  2 s   the paper's horizon (Figs. 5-6).
#   seed-scenario-2  20 s  not the paper's 300 s: the motion is chaotic (the
#                          divergence of nearby trajectories grows like
#                          exp(0.09 t), docs/paper.md), so over 300 s any error
#                          is amplified by ~1e11 and every baseline ends at the
#                          size of the attractor -- the plot would show chaos,
#                          not the methods. Over 20 s the amplification is ~6.
#   chain-8          5 s   202 switches and 20 configurations already; keeps
#                          the slowest ab4 runs (8 DOF) within the budget.
# Each run's setting is skipped when predicted to exceed --budget 10 s (ab4) or
# after an adaptive run took longer; the whole script takes a few minutes on 2 cores.
set -eu
here=$(cd "$(dirname "$0")/.." && pwd)
out="$here/docs/tradeoff"
refdir=""
build="$here/build"
while [ $# -gt 0 ]; do
    case "$1" in
        -o) out=$2; shift 2 ;;
        -r) refdir=$2; shift 2 ;;
        -b) build=$2; shift 2 ;;
        --) shift; break ;;
        *) echo "tradeoff.sh: unknown argument '$1' (usage: bench/tradeoff.sh [-o OUTDIR] [-r REFDIR] [-b BUILD_DIR] [-- FLAGS])" >&2; exit 2 ;;
    esac
done
hsnc="$build/hsnc"
[ -x "$hsnc" ] || { echo "tradeoff.sh: no hsnc at $hsnc (build first)" >&2; exit 2; }
mkdir -p "$out"

for spec in seed-scenario-1:2 seed-scenario-2:20 chain-8:5; do
    model=${spec%%:*}
    t_end=${spec##*:}
    ref=""
    if [ -n "$refdir" ]; then
        ref="--reference-out $refdir/$model.csv --reference-events $refdir/$model-events.csv"
    fi
    echo "== $model, t_end = $t_end s" >&2
    # shellcheck disable=SC2086  # $ref is a list of flags
    "$hsnc" tradeoff "$here/models/$model.toml" --t-end "$t_end" $ref --budget 10 \
        --csv "$out/$model.csv" --plot "$out/$model.png" "$@" > "$out/$model-summary.txt"
    cat "$out/$model-summary.txt"
done
