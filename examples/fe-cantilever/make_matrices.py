#!/usr/bin/python3
"""Writes M.mtx and K.mtx of the consistent-mass cantilever (fe-cantilever.toml).

A cantilever of length L = 1 m, bending stiffness EI = 100 N m^2 and mass
2 kg/m in N Euler-Bernoulli elements (8 unless given), each with its cubic
(Hermite) stiffness and consistent mass matrix; two dofs per node, the
deflection w and the rotation t (w1, t1, ..., wN, tN; node N at the tip), the
root clamped. M is coupled (consistent mass), K banded. Deterministic: run it
again and the files are byte-identical.

    make_matrices.py [N [DIR]]   (into DIR, default the current directory;
                                  examples/beam-40: make_matrices.py 20 ../beam-40)
"""
import os
import sys

import numpy as np

L, EI, rho = 1.0, 100.0, 2.0
N = int(sys.argv[1]) if len(sys.argv) > 1 else 8
out = sys.argv[2] if len(sys.argv) > 2 else "."
h = L / N
ke = EI / h**3 * np.array([[12, 6 * h, -12, 6 * h], [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                           [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h * h, -6 * h, 4 * h * h]])
me = rho * h / 420 * np.array([[156, 22 * h, 54, -13 * h], [22 * h, 4 * h * h, 13 * h, -3 * h * h],
                               [54, 13 * h, 156, -22 * h], [-13 * h, -3 * h * h, -22 * h, 4 * h * h]])
n = 2 * (N + 1)
K = np.zeros((n, n))
M = np.zeros((n, n))
for e in range(N):
    idx = [2 * e, 2 * e + 1, 2 * e + 2, 2 * e + 3]
    K[np.ix_(idx, idx)] += ke
    M[np.ix_(idx, idx)] += me
K, M = K[2:, 2:], M[2:, 2:]  # the clamped root: w0 = t0 = 0


def write(name, A, comment):
    size = A.shape[0]
    with open(os.path.join(out, name), "w") as f:
        f.write("%%MatrixMarket matrix coordinate real symmetric\n")
        f.write("% " + comment + "\n")
        entries = [(i, j, A[i, j]) for j in range(size) for i in range(j, size) if A[i, j] != 0.0]
        f.write("%d %d %d\n" % (size, size, len(entries)))
        for i, j, v in entries:
            f.write("%d %d %s\n" % (i + 1, j + 1, repr(float(v))))


write("M.mtx", M, "consistent mass of the cantilever [kg, kg m, kg m^2] (make_matrices.py)")
write("K.mtx", K, "stiffness of the cantilever [N/m, N, N m] (make_matrices.py)")
