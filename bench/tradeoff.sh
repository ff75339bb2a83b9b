#!/bin/sh
# Work-precision of hsnc against the numerical baselines (ab4 over its step,
# rk45 -- and cvode when the build has it -- over their tolerances) on the
# paper's two scenarios and a chain, with `hsnc tradeoff`, and on the Coulomb
# oscillator against its exact closed form (bench/coulomb_exact.sh). For each model it
# writes OUTDIR/<model>.csv (one row per run: wall time, errors, time ratio to
# hsnc), OUTDIR/<model>.png (log-log error against wall time, one curve per
# method) and OUTDIR/<model>-summary.txt (per baseline: the cheapest run that
# reaches each accuracy, as a time ratio to hsnc measured in the same run).
#
# Usage: bench/tradeoff.sh [-o OUTDIR] [-r REFDIR] [-b BUILD_DIR] [-m MODELS] [-- MORE_TRADEOFF_FLAGS]
#   OUTDIR  default docs/tradeoff
#   MODELS  space-separated subset of the models below (default: all)
#   REFDIR  reference CSVs <model>.csv and <model>-events.csv (the contract's
#           format, sampled at t0 + k*(t_end-t0)/1000); default: the reference is
#           computed in process at 40 digits (hsnc::reference, the CLN engine).
#           Figures for the docs must come from a true reference: never commit
#           ones made against hsnc's own double-precision output.
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
#   coulomb-1dof     4 s   9 reversals, then stuck from t = pi on; its reference is
#                          always the closed form (exact, so also without REFDIR).
# Each run's setting is skipped when predicted to exceed --budget 10 s (ab4) or
# after an adaptive run took longer. The runs take about 20 s in all on 2 cores
# (measured with CSV references), plus the reference runs.
set -eu
here=$(cd "$(dirname "$0")/.." && pwd)
out="$here/docs/tradeoff"
refdir=""
build="$here/build"
only=""
while [ $# -gt 0 ]; do
    case "$1" in
        -o) out=$2; shift 2 ;;
        -r) refdir=$2; shift 2 ;;
        -b) build=$2; shift 2 ;;
        -m) only=$2; shift 2 ;;
        --) shift; break ;;
        *) echo "tradeoff.sh: unknown argument '$1' (usage: bench/tradeoff.sh [-o OUTDIR] [-r REFDIR] [-b BUILD_DIR] [-m MODELS] [-- FLAGS])" >&2; exit 2 ;;
    esac
done
hsnc="$build/hsnc"
[ -x "$hsnc" ] || { echo "tradeoff.sh: no hsnc at $hsnc (build first)" >&2; exit 2; }
mkdir -p "$out"
exact=$(mktemp -d)
trap 'rm -rf "$exact"' EXIT
"$here/bench/coulomb_exact.sh" 4 0.004 "$exact/coulomb-1dof-exact.csv" "$exact/coulomb-1dof-exact-events.csv"

for spec in seed-scenario-1:2 seed-scenario-2:20 chain-8:5 coulomb-1dof:4; do
    model=${spec%%:*}
    t_end=${spec##*:}
    case " ${only:-$model} " in *" $model "*) ;; *) continue ;; esac
    ref=""
    if [ "$model" = coulomb-1dof ]; then
        ref="--reference-out $exact/$model-exact.csv --reference-events $exact/$model-exact-events.csv"
    elif [ -n "$refdir" ]; then
        ref="--reference-out $refdir/$model.csv --reference-events $refdir/$model-events.csv"
    fi
    echo "== $model, t_end = $t_end s" >&2
    # shellcheck disable=SC2086  # $ref is a list of flags
    "$hsnc" tradeoff "$here/models/$model.toml" --t-end "$t_end" $ref --budget 10 \
        --csv "$out/$model.csv" --plot "$out/$model.png" "$@" > "$out/$model-summary.txt"
    cat "$out/$model-summary.txt"
done
