"""hsnc's exact nonlinear modes against harmonic balance (hb_oracle.py), an
independent method on the same models: as the harmonics grow, HB's frequency
and damping ratio converge to hsnc's (bench/hb_compare.py tabulates how
fast)."""

import numpy as np

import hsnc
from conftest import SOURCE_DIR
from hb_oracle import grow, hb_gap, hb_jenkins


def backbone_at(name, amplitudes, stop=1.0, points=20):
    model = hsnc.Model.from_file(str(SOURCE_DIR / "examples" / "modes" / name))
    b = hsnc.modes(model, stop, points=points)
    assert b["status"] == "ok"
    rows = [int(np.argmin(np.abs(b["amplitude"] - a))) for a in amplitudes]
    assert all(abs(b["amplitude"][i] - a) < 1e-12 for i, a in zip(rows, amplitudes))
    return b, rows


def test_a_gap_backbone_is_the_limit_of_harmonic_balance():
    """bilinear-gap.toml (k1 = 4, k2 = 12, d = 0.1): with 40 harmonics HB's frequency is within 1e-6 of
    hsnc's at amplitudes 0.2, 0.5 and 1 (measured 1.0e-7, 2.4e-8, 8.2e-10), and closer than with 10."""
    b, rows = backbone_at("bilinear-gap.toml", (0.2, 0.5, 1.0))
    for A, i in zip((0.2, 0.5, 1.0), rows):
        u, errors = np.array([0.0, A, 2.0]), {}
        for H_old, H in ((1, 1), (1, 10), (10, 40)):
            u = hb_gap(A, H, 4.0, 12.0, 0.1, grow(u, H_old, H, False))
            assert u is not None, (A, H)
            errors[H] = abs(u[H + 1] / b["omega"][i] - 1)
        assert errors[40] < 1e-6, (A, errors)
        assert errors[40] < errors[10], (A, errors)


def test_a_friction_joints_damped_mode_is_the_limit_of_harmonic_balance():
    """jenkins-joint.toml (k = 1, kt = 3, slip force 0.3; slip from amplitude 0.1): with 20 harmonics HB's
    frequency is within 1e-5 and its damping ratio within 1e-4 of hsnc's (measured at 0.3: 5.2e-7, 7.1e-6),
    both closer than with 5."""
    b, rows = backbone_at("jenkins-joint.toml", (0.3,))
    i = rows[0]
    omega, zeta = b["omega"][i], b["damping_ratio"][i]
    assert 1.0 < omega < 2.0 and zeta > 0.1
    u, errors = np.array([0.0, 0.3, 0.0, omega, 2 * omega * zeta]), {}
    for H_old, H in ((1, 1), (1, 5), (5, 20)):
        u = hb_jenkins(0.3, H, 1.0, 3.0, 0.3, grow(u, H_old, H, True))
        assert u is not None, H
        w, xi = u[2 * H + 1], u[2 * H + 2]
        errors[H] = (abs(w / omega - 1), abs(xi / (2 * w) / zeta - 1))
    assert errors[20][0] < 1e-5 and errors[20][1] < 1e-4, errors
    assert errors[20][0] < errors[5][0] and errors[20][1] < errors[5][1], errors
