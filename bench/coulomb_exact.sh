#!/bin/sh
# The exact response of models/coulomb-1dof.toml in the contract's CSV format:
# a true reference for `hsnc tradeoff` (closed form, evaluated in double).
#
# Usage: bench/coulomb_exact.sh T_END DT TRAJECTORY_CSV EVENTS_CSV
# The model: m = 1, k = 100 (omega = 10), mu_s = mu_k = 0.1, g = 9.81, x0 = 0.2
# at rest (the values are those of the model file; a change there must be made
# here too). Half-cycle n runs from t_n = n*pi/omega about the centre
# c_n = sign(X_n)*a, a = mu*g/omega^2: x = c_n + (X_n - c_n) cos(omega (t - t_n)),
# and the next extreme is X_{n+1} = 2 c_n - X_n; a reversal at each t_n while
# |X_n| > a, then the mass sticks for good (at t = pi, x = 0.0038). Samples at
# t = k*DT (and T_END), as the runs sample.
set -eu
[ $# -eq 4 ] || { echo "usage: bench/coulomb_exact.sh T_END DT TRAJECTORY_CSV EVENTS_CSV" >&2; exit 2; }
awk -v t_end="$1" -v dt="$2" -v traj="$3" -v events="$4" 'BEGIN {
    pi = atan2(0, -1); w = 10.0; a = 0.1 * 9.81 / (w * w)
    n = 0; T[0] = 0.0; X[0] = 0.2
    while ((X[n] > 0 ? X[n] : -X[n]) > a) { c = X[n] > 0 ? a : -a; X[n + 1] = 2 * c - X[n]; n++; T[n] = n * pi / w }
    print "t,x_m1,v_m1" > traj
    for (k = 0; ; k++) {
        t = k * dt; last = !(t < t_end - 1e-9 * dt); if (last) t = t_end
        j = 0; while (j < n && t >= T[j + 1]) j++
        x = X[j]; v = 0.0
        if (j < n) { c = X[j] > 0 ? a : -a; x = c + (X[j] - c) * cos(w * (t - T[j])); v = -(X[j] - c) * w * sin(w * (t - T[j])) }
        if (v == 0) v = 0.0  # not -0
        printf "%.17g,%.17g,%.17g\n", t, x, v > traj
        if (last) break
    }
    print "t,kind,element,x_m1,v_m1" > events
    for (j = 1; j <= n; j++) if (T[j] <= t_end) printf "%.17g,%s,m1,%.17g,0\n", T[j], (j == n ? "stick" : "reversal"), X[j] > events
}'
