#!/usr/bin/python3
"""Harmonic balance against hsnc's exact nonlinear modes: how many harmonics
H a harmonic-balance solution needs before its frequency (and, for a
friction joint, its damping ratio) is within 1e-3 of hsnc's exact backbone
on the same model.

Two models of examples/modes:
- bilinear-gap.toml (a 1-dof oscillator with a one-sided stop): the
  conservative backbone. HB: x = a_0 + sum_h a_h cos(h w t) (the orbit is
  time-reversible about its turning point, x(0) = A), unknowns a_0..a_H and
  w, the stop's force by alternating frequency-time (AFT) on N samples.
- jenkins-joint.toml (a spring with a Jenkins element to the ground): the
  damped mode by the extended periodic motion concept, as hsnc modes
  (x'' - xi x' + k x + f_J = 0, damping ratio xi/(2 w)). HB: cosine and sine
  terms, unknowns a_0, a_h, b_h, w, xi, the turning point at t = 0 (x(0) = A,
  x'(0) = 0), the Jenkins force by AFT over two periods (the second kept).

The HB solver is python/tests/hb_oracle.py (2^14 AFT samples a period, far
more than any H used). Each amplitude is solved for H = 1, 2, 3, ... from the
previous H's solution; the table gives each H's relative error and the
smallest H from which it stays below 1e-3.

    PYTHONPATH=build/python python3 bench/hb_compare.py
"""
import os
import sys

import numpy as np

import hsnc

SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, os.path.join(SOURCE, "python", "tests"))
from hb_oracle import grow, hb_gap, hb_jenkins  # noqa: E402 (the oracle of python/tests/test_modes_hb.py)

HARMONICS = (1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 40, 50, 60, 80)
TARGET = 1e-3


def first_within(errors):
    """The smallest H from which every error is below TARGET (None: never)."""
    best = None
    for H, e in reversed(errors):
        if e is None or e >= TARGET:
            break
        best = H
    return best


def table(title, rows, quantities):
    print(title)
    print("  %-10s %-24s %s" % ("amplitude", "hsnc (exact)", "relative error of HB with H harmonics"))
    for A, exact, errors, first in rows:
        for q, name in enumerate(quantities):
            shown = "  ".join("%d:%.1e" % (H, e[q]) for H, e in errors if H in (1, 3, 5, 10, 20, 40, 80) and e)
            print("  %-10s %-24s %s" % ("%g" % A if q == 0 else "", "%s %.12g" % (name, exact[q]), shown))
        print("  %-10s %s" % ("", "; ".join("%s within 1e-3 from H = %s" % (name, first[q])
                                             for q, name in enumerate(quantities))))


def compare(title, example, amplitudes, quantities, damped, first_guess, solve, errors_of):
    """HB of the mode of examples/modes/EXAMPLE at each amplitude, H growing, against hsnc's backbone."""
    model = hsnc.Model.from_file(os.path.join(SOURCE, "examples", "modes", example))
    backbone = hsnc.modes(model, 1.0, points=20)
    rows = []
    for A in amplitudes:
        i = int(np.argmin(np.abs(backbone["amplitude"] - A)))
        assert abs(backbone["amplitude"][i] - A) < 1e-12
        exact = tuple(backbone[q][i] for q in quantities)
        u, H_old, errors = first_guess(A, exact), 1, []
        for H in HARMONICS:
            u = solve(A, H, grow(u, H_old, H, damped))
            H_old = H
            if u is None:
                errors.append((H, None))
                break
            errors.append((H, errors_of(u, H, exact)))
        first = tuple(first_within([(H, e and e[q]) for H, e in errors]) for q in range(len(quantities)))
        rows.append((A, exact, errors, first))
    table("%s (examples/modes/%s)" % (title, example), rows, quantities)
    return rows


def compare_gap():
    return compare("bilinear gap: backbone frequency", "bilinear-gap.toml", (0.2, 0.5, 1.0), ("omega",), False,
                   lambda A, exact: np.array([0.0, A, 2.0]),
                   lambda A, H, start: hb_gap(A, H, 4.0, 12.0, 0.1, start),
                   lambda u, H, exact: (abs(u[H + 1] / exact[0] - 1),))


def compare_jenkins():
    def errors_of(u, H, exact):
        w, xi = u[2 * H + 1], u[2 * H + 2]
        return abs(w / exact[0] - 1), abs(xi / (2 * w) / exact[1] - 1)

    # H = 1 starts from hsnc's frequency and damping: the first HB solve then needs no search.
    return compare("Jenkins joint: damped mode", "jenkins-joint.toml", (0.15, 0.3, 1.0), ("omega", "damping_ratio"),
                   True, lambda A, exact: np.array([0.0, A, 0.0, exact[0], 2 * exact[0] * exact[1]]),
                   lambda A, H, start: hb_jenkins(A, H, 1.0, 3.0, 0.3, start), errors_of)


def main():
    compare_gap()
    print()
    compare_jenkins()
    return 0


if __name__ == "__main__":
    sys.exit(main())
