# The scaling plot of docs/results.md "How it scales": time per switch against the
# number of masses, hsnc's Eigen solver, generic (the interpreter) and CVODE, from
# build/hsnc_scaling_bench --csv scaling.csv.
#   gnuplot -e "in='scaling.csv'; out='docs/scaling.png'" bench/scaling.gp
if (!exists("in")) in = 'scaling.csv'
if (!exists("out")) out = 'scaling.png'
set terminal pngcairo size 800,520 font ",11"
set output out
set datafile separator ","
set key top left
set logscale xy
set xlabel "masses in the chain"
set ylabel "CPU time per switch [us]"
set xtics (2, 8, 32, 64, 128)
set xrange [1.6:160]
set grid
plot in skip 1 using 1:4 with linespoints lw 2 title "hsnc, --kernels eigen", \
     in skip 1 using 1:(1e3*$6/$2) with linespoints lw 2 title "hsnc, --kernels generic (a derivation per configuration)", \
     in skip 1 using 1:(1e3*$9/$2) with linespoints lw 2 title "CVODE, rtol 1e-12"
