#!/usr/bin/env bash
# Reproduce the Results section of the HSNC paper (Shahhosseini, Tien, D'Souza,
# DETC2021-69430): Figs. 5-8 and the runtime ratio of HSNC to fixed-step
# Adams-Bashforth 4 (the paper: 900 s vs 6.31 s, 142x).
#
#   ./build.sh && bench/reproduce_paper.sh [OUTDIR]      (default OUTDIR: paper-out)
#
# Uses build/hsnc (or $HSNC) and gnuplot (pngcairo). Writes to OUTDIR:
#   fig5.png ... fig8.png   the figures
#   numbers.txt             every number printed below (also on stdout)
#   csv/                    the trajectories the figures are drawn from
# docs/paper.md shows the figures and discusses the numbers.
#
# The ab4 runs dominate the cost (ab4 at h = 1e-6 over 300 s is 3e8 steps); the
# whole script takes a few minutes on 2 cores. Timings are wall times of whole
# `hsnc simulate` processes (start-up, model reading and CSV writing included).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
hsnc=${HSNC:-$root/build/hsnc}
out=${1:-paper-out}
[ -x "$hsnc" ] || { echo "reproduce_paper.sh: $hsnc not found; run ./build.sh first" >&2; exit 2; }
command -v gnuplot >/dev/null || { echo "reproduce_paper.sh: gnuplot not found (./build.sh installs it)" >&2; exit 2; }
mkdir -p "$out/csv"
csv=$out/csv
s1=$root/models/seed-scenario-1.toml
s2=$root/models/seed-scenario-2.toml
numbers=$out/numbers.txt
: >"$numbers"
say() { echo "$*" | tee -a "$numbers"; }
script_start=$EPOCHREALTIME

# timed OUTVAR cmd...: run cmd (stdout to /dev/null), store its wall time in seconds.
timed() {
    local __var=$1; shift
    local a=$EPOCHREALTIME
    "$@" >/dev/null
    local b=$EPOCHREALTIME
    printf -v "$__var" '%s' "$(awk -v a="$a" -v b="$b" 'BEGIN { printf "%.4f", b - a }')"
}
# median of the arguments
median() { printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

# Columns of a trajectory CSV: t,x_m1,x_m2,v_m1,v_m2.
# maxdiff A B: max over the common grid of max(|dx1|,|dx2|).
maxdiff() {
    paste -d, "$1" "$2" | awk -F, 'NR > 1 { if ($1 != $6) { print "grid mismatch at row " NR > "/dev/stderr"; exit 1 }
        d = $2 - $7; if (d < 0) d = -d; e = $3 - $8; if (e < 0) e = -e; if (e > d) d = e; if (d > m) m = d }
        END { printf "%.3g", m }'
}
# parting A B TOL: first grid time where max(|dx1|,|dx2|) > TOL ("none" if never).
parting() {
    paste -d, "$1" "$2" | awk -F, -v tol="$3" 'NR > 1 { d = $2 - $7; if (d < 0) d = -d; e = $3 - $8; if (e < 0) e = -e
        if (!found && (d > tol || e > tol)) { t = $1; found = 1 } }
        END { if (found) printf "%.2f", t; else printf "never" }'
}

say "# hsnc: reproduction of the HSNC paper's Results ($(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores, $(uname -m))"

# ---------------------------------------------------------------- Fig. 5
# Scenario 1 over the paper's 2 s: hsnc against ab4 with h = 1e-3 and 1e-6.
say ""
say "## Fig. 5: scenario 1, 0..2 s, hsnc vs ab4 (h = 1e-3, 1e-6); samples every 1e-4 s"
timed t5h "$hsnc" simulate "$s1" --t-end 2 --dt 1e-4 --quiet --out "$csv/s1_hsnc.csv"
timed t5a3 "$hsnc" simulate "$s1" --t-end 2 --dt 1e-4 --quiet --method ab4 --h 1e-3 --out "$csv/s1_ab4_1e-3.csv"
timed t5a6 "$hsnc" simulate "$s1" --t-end 2 --dt 1e-4 --quiet --method ab4 --h 1e-6 --out "$csv/s1_ab4_1e-6.csv"
say "wall time: hsnc $t5h s, ab4 h=1e-3 $t5a3 s, ab4 h=1e-6 $t5a6 s"
say "max |x_ab4 - x_hsnc| over 0..2 s: h=1e-3: $(maxdiff "$csv/s1_ab4_1e-3.csv" "$csv/s1_hsnc.csv") m, h=1e-6: $(maxdiff "$csv/s1_ab4_1e-6.csv" "$csv/s1_hsnc.csv") m"
say "first time max(|dx1|,|dx2|) > 1e-2 (s): h=1e-3: $(parting "$csv/s1_ab4_1e-3.csv" "$csv/s1_hsnc.csv" 1e-2), h=1e-6: $(parting "$csv/s1_ab4_1e-6.csv" "$csv/s1_hsnc.csv" 1e-2)"

# |x_ab4 - x_hsnc| (Euclidean, positions) on the common grid: errdiff A B > OUT
errdiff() {
    paste -d, "$1" "$2" | awk -F, 'NR > 1 { d1 = $2 - $7; d2 = $3 - $8; d = sqrt(d1 * d1 + d2 * d2); if (d > 0) print $1 "," d }'
}
for h in 1e-3 1e-6; do errdiff "$csv/s1_hsnc.csv" "$csv/s1_ab4_$h.csv" >"$csv/s1_err_ab4_$h.csv"; done
gnuplot <<EOF
set terminal pngcairo size 1000,900 noenhanced font ',10'
set output '$out/fig5.png'
set datafile separator ','
set multiplot layout 3,1 title 'Fig. 5: scenario 1, HSNC vs Adams-Bashforth 4 (fixed step h)'
set grid
set key outside right
set xrange [0:2]
set ylabel 'x1 [m]'
plot '$csv/s1_hsnc.csv' u 1:2 w l lw 4 lc rgb '#b0b0b0' t 'hsnc', \
     '$csv/s1_ab4_1e-3.csv' u 1:2 w l lw 1 lc rgb '#d62728' t 'ab4 h=1e-3', \
     '$csv/s1_ab4_1e-6.csv' u 1:2 w l lw 1 dt 2 lc rgb '#1f77b4' t 'ab4 h=1e-6'
set ylabel 'x2 [m]'
plot '$csv/s1_hsnc.csv' u 1:3 w l lw 4 lc rgb '#b0b0b0' t 'hsnc', \
     '$csv/s1_ab4_1e-3.csv' u 1:3 w l lw 1 lc rgb '#d62728' t 'ab4 h=1e-3', \
     '$csv/s1_ab4_1e-6.csv' u 1:3 w l lw 1 dt 2 lc rgb '#1f77b4' t 'ab4 h=1e-6'
set xlabel 't [s]'
set ylabel '|x_ab4 - x_hsnc| [m]'
set logscale y
set format y '1e%T'
set yrange [1e-8:1]
plot '$csv/s1_err_ab4_1e-3.csv' u 1:2 w l lw 1 lc rgb '#d62728' t 'ab4 h=1e-3', \
     '$csv/s1_err_ab4_1e-6.csv' u 1:2 w l lw 1 lc rgb '#1f77b4' t 'ab4 h=1e-6'
unset multiplot
EOF

# ---------------------------------------------------------------- Fig. 6 + runtime
# Scenario 2 over 300 s: hsnc against ab4 with h = 1e-4 and 1e-6, on a common
# 0.01 s sample grid; these are also the runs whose wall times are compared.
say ""
say "## Fig. 6: scenario 2, 0..300 s, hsnc vs ab4 (h = 1e-4, 1e-6); samples every 0.01 s"
th=()
for r in 1 2 3 4 5; do
    timed t "$hsnc" simulate "$s2" --t-end 300 --dt 0.01 --quiet --out "$csv/s2_hsnc.csv"
    th+=("$t")
done
t6h=$(median "${th[@]}")
"$hsnc" simulate "$s2" --t-end 300 --quiet >"$csv/s2_hsnc_summary.txt"
timed t6a4 "$hsnc" simulate "$s2" --t-end 300 --dt 0.01 --quiet --method ab4 --h 1e-4 --out "$csv/s2_ab4_1e-4.csv"
timed t6a6 "$hsnc" simulate "$s2" --t-end 300 --dt 0.01 --quiet --method ab4 --h 1e-6 --out "$csv/s2_ab4_1e-6.csv"
p4=$(parting "$csv/s2_ab4_1e-4.csv" "$csv/s2_hsnc.csv" 1e-2)
p6=$(parting "$csv/s2_ab4_1e-6.csv" "$csv/s2_hsnc.csv" 1e-2)
say "hsnc summary: $(cat "$csv/s2_hsnc_summary.txt")"
say "where they part, first time max(|x1_hsnc - x1_ab4|, |x2_hsnc - x2_ab4|) > 1e-2 (s): h=1e-4: $p4, h=1e-6: $p6"
# The true trajectory: the reference engine at 50 digits (docs/guide/reference.md "High-precision
# reference"; it agrees with 100 digits to ~1e-45 over these 300 s). Which run
# stays closer to it, and for how long?
timed t6ref "$hsnc" simulate "$s2" --t-end 300 --dt 0.01 --quiet --precision mp:50 --out "$csv/s2_ref.csv"
"$hsnc" simulate "$s2" --t-end 300 --quiet --precision mp:50 >"$csv/s2_ref_summary.txt"
say "reference (mp:50, $t6ref s): $(cat "$csv/s2_ref_summary.txt")"
for run in hsnc ab4_1e-4 ab4_1e-6; do
    say "  $run against the reference: max |dx| over 0..20 s $(maxdiff <(awk -F, 'NR == 1 || $1 <= 20' "$csv/s2_$run.csv") <(awk -F, 'NR == 1 || $1 <= 20' "$csv/s2_ref.csv")) m; first |dx| > 1e-6 at $(parting "$csv/s2_$run.csv" "$csv/s2_ref.csv" 1e-6) s, > 1e-2 at $(parting "$csv/s2_$run.csv" "$csv/s2_ref.csv" 1e-2) s"
done
say ""
say "## Runtime, the Fig. 6 run (300 s of scenario 2, trajectory CSV every 0.01 s written)"
say "hsnc: $t6h s (median of ${#th[@]} runs: ${th[*]})"
say "ab4 h=1e-4: $t6a4 s  -> ab4/hsnc = $(awk -v a="$t6a4" -v b="$t6h" 'BEGIN { printf "%.0f", a / b }')x"
say "ab4 h=1e-6: $t6a6 s  -> ab4/hsnc = $(awk -v a="$t6a6" -v b="$t6h" 'BEGIN { printf "%.0f", a / b }')x"
say "(paper: NI 900 s vs HSNC 6.31 s, 142x)"

# |dx|(t) of ab4 against hsnc, for the third panel.
# envelope FILE: maximum of column 2 in each 1 s window (keeps the plots readable and small)
envelope() {
    awk -F, '{ w = int($1); if (!(w in m) || $2 > m[w]) m[w] = $2; if (w > last) last = w }
        END { for (w = 0; w <= last; ++w) if (w in m) print w + 0.5 "," m[w] }' "$1"
}
for h in 1e-4 1e-6; do
    errdiff "$csv/s2_hsnc.csv" "$csv/s2_ab4_$h.csv" >"$csv/s2_err_ab4_$h.csv"
    envelope "$csv/s2_err_ab4_$h.csv" >"$csv/s2_err_ab4_${h}_env.csv"
done
errdiff "$csv/s2_ref.csv" "$csv/s2_hsnc.csv" >"$csv/s2_err_hsnc_ref.csv"
envelope "$csv/s2_err_hsnc_ref.csv" >"$csv/s2_err_hsnc_ref_env.csv"
pa=$p4; [ "$pa" = never ] && pa=300
pb=$p6; [ "$pb" = never ] && pb=300
gnuplot <<EOF
set terminal pngcairo size 920,800 noenhanced font ',10'
set output '$out/fig6.png'
set datafile separator ','
set multiplot layout 3,1 title 'Fig. 6: scenario 2, HSNC vs Adams-Bashforth 4 (h = 1e-4, 1e-6) and the 50-digit reference; top two panels: 120..130 s'
set grid
set key outside right
set xrange [120:130]
set ylabel 'x1 [m]'
plot '$csv/s2_hsnc.csv' u 1:2 w l lw 3 lc rgb 'black' t 'hsnc', \
     '$csv/s2_ab4_1e-4.csv' u 1:2 w l lw 1.5 lc rgb '#d62728' t 'ab4 h=1e-4', \
     '$csv/s2_ab4_1e-6.csv' u 1:2 w l lw 1.5 lc rgb '#1f77b4' t 'ab4 h=1e-6'
set ylabel 'x2 [m]'
plot '$csv/s2_hsnc.csv' u 1:3 w l lw 3 lc rgb 'black' t 'hsnc', \
     '$csv/s2_ab4_1e-4.csv' u 1:3 w l lw 1.5 lc rgb '#d62728' t 'ab4 h=1e-4', \
     '$csv/s2_ab4_1e-6.csv' u 1:3 w l lw 1.5 lc rgb '#1f77b4' t 'ab4 h=1e-6'
set xrange [0:300]
set logscale y
set format y '1e%T'
set yrange [1e-16:10]
set xlabel 't [s]'
set ylabel 'max |dx| per 1 s [m]'
set key inside bottom right
set arrow 1 from $pa, graph 0 to $pa, graph 1 nohead front lc rgb '#d62728' dt 2
set arrow 2 from $pb, graph 0 to $pb, graph 1 nohead front lc rgb '#1f77b4' dt 2
plot '$csv/s2_err_ab4_1e-4_env.csv' u 1:2 w l lw 1.5 lc rgb '#d62728' t sprintf('ab4 1e-4 vs hsnc, parts %s', '$p4'), \
     '$csv/s2_err_ab4_1e-6_env.csv' u 1:2 w l lw 1.5 lc rgb '#1f77b4' t sprintf('ab4 1e-6 vs hsnc, parts %s', '$p6'), \
     '$csv/s2_err_hsnc_ref_env.csv' u 1:2 w l lw 2 lc rgb 'black' t 'hsnc (double) vs 50-digit reference', \
     1e-2 w l lc rgb 'gray40' dt 2 t '1e-2'
unset multiplot
EOF

# ---------------------------------------------------------------- Fig. 7
say ""
say "## Fig. 7: phase portrait of scenario 2 from hsnc, 0..300 s, samples every 2e-3 s"
"$hsnc" simulate "$s2" --t-end 300 --dt 2e-3 --quiet --out "$csv/s2_hsnc_fine.csv" >/dev/null
gnuplot <<EOF
set terminal pngcairo size 900,430 noenhanced font ',10'
set output '$out/fig7.png'
set datafile separator ','
set multiplot layout 1,2 title 'Fig. 7: phase portrait of scenario 2 (hsnc, 0..300 s)'
set grid
unset key
set xlabel 'x1 [m]'
set ylabel 'v1 [m/s]'
plot '$csv/s2_hsnc_fine.csv' u 2:4 w l lw 0.7 lc rgb '#1f77b4'
set xlabel 'x2 [m]'
set ylabel 'v2 [m/s]'
plot '$csv/s2_hsnc_fine.csv' u 3:5 w l lw 0.7 lc rgb '#d62728'
unset multiplot
EOF
say "written: $out/fig7.png"

# ---------------------------------------------------------------- Fig. 8
# Two hsnc runs of scenario 2 with x1(0) = 0.2 and 0.200001. |dx| is the
# Euclidean norm of (x1, x2) differences on the 0.01 s grid. It oscillates with
# the motion, so the fits use its envelope: the maximum of |dx| in each 1 s
# window. Growth phase: from t = 1 s until the envelope first exceeds 1e-2
# (saturation, the size of the motion is ~1 m). Both fits have two parameters
# and are least squares on log10(envelope): exponential: log10|dx| = a + b t;
# power law: log10|dx| = a + p log10 t. Their RMS residuals are compared.
say ""
say "## Fig. 8: scenario 2, hsnc from x1(0) = 0.2 and 0.200001 (delta = 1e-6)"
"$hsnc" simulate "$s2" --t-end 300 --dt 0.01 --quiet --x0 m1=0.200001 --out "$csv/s2_hsnc_pert.csv" >/dev/null
errdiff "$csv/s2_hsnc.csv" "$csv/s2_hsnc_pert.csv" >"$csv/s2_div.csv"
envelope "$csv/s2_div.csv" >"$csv/s2_div_env.csv"
# t_sat: first window centre with envelope > 1e-2
tsat=$(awk -F, '$2 > 1e-2 { print $1; found = 1; exit } END { if (!found) print 300 }' "$csv/s2_div_env.csv")
# fitwin T1 T2: "ae be re ap bp rp n" for envelope windows with T1 <= t < T2
fitwin() {
    awk -F, -v t1="$1" -v t2="$2" '
    $1 >= t1 && $1 < t2 { n++; X[n] = $1; L[n] = log($1) / log(10); Y[n] = log($2) / log(10) }
    function lsq(U, n,   i, su, sy, suu, suy, b, a, r, ss) {
        for (i = 1; i <= n; i++) { su += U[i]; sy += Y[i]; suu += U[i] * U[i]; suy += U[i] * Y[i] }
        b = (n * suy - su * sy) / (n * suu - su * su); a = (sy - b * su) / n
        for (i = 1; i <= n; i++) { r = Y[i] - a - b * U[i]; ss += r * r }
        A = a; B = b; return sqrt(ss / n) }
    END { if (n < 3) { print "0 0 nan 0 0 nan " n; exit }
        re = lsq(X, n); ae = A; be = B
        rp = lsq(L, n); ap = A; bp = B
        printf "%.6g %.6g %.4g %.6g %.6g %.4g %d\n", ae, be, re, ap, bp, rp, n }' "$csv/s2_div_env.csv"
}
d1=$(awk -F, '$1 >= 1 { print $2; exit }' "$csv/s2_div_env.csv")
say "envelope of |dx| (max per 1 s window): at t~1 s $d1 m; first exceeds 1e-2 at t = $tsat s; final $(tail -1 "$csv/s2_div_env.csv" | cut -d, -f2) m"
for t1 in 20 1; do   # the last one (from 1 s) is the one drawn
    read -r ae be re ap bp rp nfit <<<"$(fitwin "$t1" "$tsat")"
    say "fit window $t1 s <= t < $tsat s ($nfit windows):"
    say "  exponential: log10|dx| = $ae + $be*t  -> lambda = $(awk -v b="$be" 'BEGIN { printf "%.4g", b * log(10) }') 1/s, e-folding time $(awk -v b="$be" 'BEGIN { printf "%.3g", 1 / (b * log(10)) }') s; RMS residual $re decades"
    say "  power law:   log10|dx| = $ap + $bp*log10(t)  -> |dx| ~ t^$bp; RMS residual $rp decades"
    better=$(awk -v e="$re" -v p="$rp" 'BEGIN { if (e + 0 < p + 0) print "exponential"; else print "power law" }')
    say "  better fit (smaller RMS residual): $better (RMS exp/power = $(awk -v e="$re" -v p="$rp" 'BEGIN { printf "%.3g", e / p }'))"
done

gnuplot <<EOF
set terminal pngcairo size 1000,560 noenhanced font ',10'
set output '$out/fig8.png'
set datafile separator ','
set title 'Fig. 8: divergence of two hsnc trajectories of scenario 2, x1(0) = 0.2 and 0.200001'
set grid
set key bottom right
set samples 1000
set logscale y
set format y '1e%T'
set xrange [0:300]
set yrange [1e-9:10]
set xlabel 't [s]'
set ylabel '|dx| = |(x1,x2) - (x1,x2)_perturbed| [m]'
set arrow 1 from $tsat, graph 0 to $tsat, graph 1 nohead lc rgb 'gray40' dt 2
plot '$csv/s2_div.csv' u 1:2 w l lw 0.5 lc rgb '#a0a0a0' t '|dx| (0.01 s samples)', \
     '$csv/s2_div_env.csv' u 1:2 w p pt 7 ps 0.4 lc rgb 'black' t 'envelope (max per 1 s)', \
     (x >= 1 && x <= $tsat) ? 10**($ae + $be*x) : 1/0 w l lw 2 lc rgb '#d62728' t sprintf('exp fit, lambda = %.3g 1/s, rms %.3g', $be*log(10), $re), \
     (x >= 1 && x <= $tsat) ? 10**($ap + $bp*log10(x)) : 1/0 w l lw 2 lc rgb '#1f77b4' t sprintf('power fit, t^%.2f, rms %.3g', $bp, $rp)
EOF

say ""
say "total script wall time: $(awk -v a="$script_start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.1f", b - a }') s"
say "figures: $out/fig5.png $out/fig6.png $out/fig7.png $out/fig8.png; numbers: $numbers"
