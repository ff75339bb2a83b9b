#!/usr/bin/python3
"""Writes M.mtx, K.mtx and C.mtx of the cracked cantilever (beam-crack.toml).

A cantilever of length L = 1 m, bending stiffness EI = 100 N m^2 and mass
2 kg/m, discretised at five equally spaced nodes (translational dofs w1..w5,
w5 at the tip). The open crack at the root is a rotational spring k_r = 200
N m/rad at the clamp. K is the inverse of the flexibility matrix
F_ij = a^2 (3 b - a) / (6 EI) + x_i x_j / k_r  (a = min(x_i, x_j), b = max),
a dense matrix with positive off-diagonal entries (no spring network). M is the
lumped mass (0.4 kg per node, 0.2 kg at the tip). C = 0.2 M + 5e-4 K.
Deterministic: run it again and the files are byte-identical.
"""
import numpy as np

L, EI, rho, k_r, n = 1.0, 100.0, 2.0, 200.0, 5
x = np.array([L * (i + 1) / n for i in range(n)])
F = np.empty((n, n))
for i in range(n):
    for j in range(n):
        a, b = min(x[i], x[j]), max(x[i], x[j])
        F[i, j] = a * a * (3 * b - a) / (6 * EI) + x[i] * x[j] / k_r
K = np.linalg.inv(F)
K = 0.5 * (K + K.T)
m = np.full(n, rho * L / n)
m[-1] *= 0.5
M = np.diag(m)
C = 0.2 * M + 5e-4 * K


def write(name, A, comment):
    with open(name, "w") as f:
        f.write("%%MatrixMarket matrix coordinate real symmetric\n")
        f.write("% " + comment + "\n")
        entries = [(i, j, A[i, j]) for j in range(n) for i in range(j, n) if A[i, j] != 0.0]
        f.write("%d %d %d\n" % (n, n, len(entries)))
        for i, j, v in entries:
            f.write("%d %d %s\n" % (i + 1, j + 1, repr(float(v))))


write("M.mtx", M, "lumped mass of the cracked cantilever [kg] (make_matrices.py)")
write("K.mtx", K, "stiffness of the cracked cantilever, crack open [N/m] (make_matrices.py)")
write("C.mtx", C, "Rayleigh damping C = 0.2 M + 5e-4 K [N s/m] (make_matrices.py)")
