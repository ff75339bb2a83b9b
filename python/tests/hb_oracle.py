"""Harmonic balance (HB) of hsnc's nonlinear modes, an independent oracle:
the Fourier coefficients of a periodic orbit solved from the balance of
harmonics, the nonlinear forces by alternating frequency-time (AFT) on N
samples of the period, SciPy's hybrid Powell method. Used by
test_modes_hb.py and bench/hb_compare.py.

- hb_gap: a 1-dof oscillator x'' + k1 x + k2 max(x - d, 0) = 0 (unit mass):
  x = a_0 + sum_h a_h cos(h w t) (time-reversible about the turning point
  x(0) = A), unknowns a_0..a_H and w.
- hb_jenkins: a spring k and a Jenkins element (kt, slip force fs) to the
  ground, damped mode by the extended periodic motion concept as hsnc modes
  (x'' - xi x' + k x + f_J = 0, damping ratio xi/(2 w)): cosine and sine
  terms, unknowns a_0, a_h, b_h, w, xi, the turning point at t = 0 (x(0) =
  A, x'(0) = 0); the Jenkins force over two periods, the second kept.
"""
import numpy as np
from scipy.optimize import root

N = 1 << 14  # AFT samples a period: far more than any H used, so the AFT's own error does not enter
THETA = 2 * np.pi * np.arange(N) / N


def projections(f, H):
    """Fourier coefficients of samples f over one period: mean, cos and sin of 1..H."""
    c = np.fft.rfft(f) / N
    return c[0].real, 2 * c[1:H + 1].real, -2 * c[1:H + 1].imag


def hb_gap(A, H, k1, k2, d, start):
    """The bilinear oscillator's orbit with turning point x(0) = A: (w, coefficients)."""
    h = np.arange(1, H + 1)
    cos = np.cos(np.outer(h, THETA))

    def residual(u):
        a0, a, w = u[0], u[1:H + 1], u[H + 1]
        x = a0 + a @ cos
        f0, fc, _ = projections(k1 * x + k2 * np.maximum(x - d, 0.0), H)
        return np.concatenate(([f0], -(h * w) ** 2 * a + fc, [a0 + a.sum() - A]))

    return solved(residual, start)


def solved(residual, start):
    """The root from `start` when its residual is at rounding level, else None."""
    sol = root(residual, start, method="hybr", options={"xtol": 1e-13})
    return sol.x if np.max(np.abs(residual(sol.x))) < 1e-10 else None


def jenkins_force(x, kt, fs):
    """The Jenkins element's force over one period of samples x (the second of two periods)."""
    s = x[0]
    f = np.empty_like(x)
    for sweep in range(2):
        for j, xj in enumerate(x):
            fj = kt * (xj - s)
            if fj > fs:
                s, fj = xj - fs / kt, fs
            elif fj < -fs:
                s, fj = xj + fs / kt, -fs
            f[j] = fj
    return f


def hb_jenkins(A, H, k, kt, fs, start):
    """The damped mode's orbit with turning point x(0) = A: unknowns a0, a (H), b (H), w, xi."""
    h = np.arange(1, H + 1)
    cos, sin = np.cos(np.outer(h, THETA)), np.sin(np.outer(h, THETA))

    def residual(u):
        a0, a, b, w, xi = u[0], u[1:H + 1], u[H + 1:2 * H + 1], u[2 * H + 1], u[2 * H + 2]
        x = a0 + a @ cos + b @ sin
        f0, fc, fsn = projections(jenkins_force(x, kt, fs), H)
        hw = h * w
        rc = -hw ** 2 * a - xi * hw * b + k * a + fc
        rs = -hw ** 2 * b + xi * hw * a + k * b + fsn
        return np.concatenate(([k * a0 + f0], rc, rs, [a0 + a.sum() - A, (h * b).sum()]))

    return solved(residual, start)


def grow(u, H_old, H, damped):
    """A solution of H_old harmonics as the start of H (the new harmonics 0)."""
    if not damped:
        return np.concatenate((u[:H_old + 1], np.zeros(H - H_old), u[H_old + 1:]))
    a0, a, b, tail = u[0], u[1:H_old + 1], u[H_old + 1:2 * H_old + 1], u[2 * H_old + 1:]
    pad = np.zeros(H - H_old)
    return np.concatenate(([a0], a, pad, b, pad, tail))
