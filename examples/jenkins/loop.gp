# The friction damper's hysteresis loop from a trajectory CSV of
# friction_damper.toml: the element's force k*(x_platform - s_damper) against
# the platform's displacement, and both against time, after the transient.
#   hsnc simulate examples/jenkins/friction_damper.toml --dt 0.001 --out damper.csv
#   gnuplot -e "in='damper.csv'; out='jenkins-loop.png'" examples/jenkins/loop.gp
if (!exists("in")) in = 'damper.csv'
if (!exists("out")) out = 'jenkins-loop.png'
k = 400.0          # [[jenkins]] k
Fs = 5.0           # [[jenkins]] slip_force
t_from = 35.0      # the steady state
set datafile separator ','
set terminal pngcairo size 1200,520 font ',11' noenhanced
set output out
set multiplot layout 1,2 title "jenkins-friction-damper: the friction damper at the platform, forced at 10 rad/s, t = 35-40 s"
set grid
set key top left opaque box
set xlabel 'x_platform [m]' noenhanced
set ylabel 'damper force k (x_platform - s) [N]'
set yrange [-1.2 * Fs : 1.7 * Fs]
plot in every ::1 using ($1 >= t_from ? column('x_platform') : 1/0):(k * (column('x_platform') - column('s_damper'))) \
         with lines lw 2 title 'loop (stick: slope k; slip: +-slip_force)', \
     Fs with lines dt 2 lc rgb 'gray' title '+-slip_force', -Fs with lines dt 2 lc rgb 'gray' notitle
set xlabel 't [s]'
set ylabel 'damper force [N]'
set y2label '[m]'
set y2tics
set ytics nomirror
set key top left opaque box
set yrange [-1.6 * Fs : 1.6 * Fs]
plot in every ::1 using ($1 >= t_from ? $1 : 1/0):(k * (column('x_platform') - column('s_damper'))) \
         with lines lw 2 title 'damper force', \
     in every ::1 using ($1 >= t_from ? $1 : 1/0):(column('x_platform')) axes x1y2 with lines lw 2 title 'x_platform', \
     in every ::1 using ($1 >= t_from ? $1 : 1/0):(column('s_damper')) axes x1y2 with lines lw 2 title 's_damper (slider)'
unset multiplot
