"""hsnc.sweep: the response curve of a linear oscillator against |H(omega)|,
the same numbers as `hsnc sweep --out --diagram` bit for bit, and bad input."""

import math

import numpy as np
import pytest

import hsnc
from conftest import read_csv, run_cli

LINEAR = """
name = "linear"
[parameters]
omega = 1.0
zeta = 0.05
[[mass]]
name = "m"
m = 1.0
[[spring]]
between = ["ground", "m"]
k = 1.0
[damping]
alpha = "2*zeta"
[[forcing]]
omega = "omega"
amplitude = { m = 1.0 }
"""


def test_linear_response_curve_against_closed_form():
    model = hsnc.Model.from_string(LINEAR)
    r = hsnc.sweep(model, "omega", 0.6, 1.4, 5, direction="both", max_periods=2000, record_periods=8)
    assert r["param"] == "omega" and r["param2"] is None and r["masses"] == ["m"]
    assert list(r["direction"]) == ["up"] * 5 + ["down"] * 5
    assert r["xmax"].shape == (10, 1) and r["diagram"]["x"].shape == (80, 1)
    assert r["settled"].all() and (r["multiple"] == 1).all()
    w = r["value"]
    h = 1 / np.sqrt((1 - w**2) ** 2 + (0.1 * w) ** 2)
    np.testing.assert_allclose(r["xmax"][:, 0], h, rtol=1e-8)
    np.testing.assert_allclose(r["a1"][:, 0], h, rtol=1e-8)
    np.testing.assert_allclose(r["xrms"][:, 0], h / math.sqrt(2), rtol=1e-8)
    assert np.isnan(r["value2"]).all()


def test_same_numbers_as_the_command_line(tmp_path):
    path = tmp_path / "linear.toml"
    path.write_text(LINEAR)
    model = hsnc.Model.from_file(path)
    r = hsnc.sweep(model, "omega", 0.8, 1.2, 3, direction="down", param2="zeta", values2=[0.1, 0.2],
                   threads=2, max_periods=300, record_periods=4)
    out, diagram = tmp_path / "curve.csv", tmp_path / "diagram.csv"
    run_cli("sweep", path, "--param", "omega", "--from", 0.8, "--to", 1.2, "--points", 3, "--direction", "down",
            "--param2", "zeta", "--values2", "0.1,0.2", "--max-periods", 300, "--record-periods", 4, "--quiet",
            "--out", out, "--diagram", diagram)
    header, rows = read_csv(out)
    assert header == ["omega", "direction", "settled", "periods", "multiple", "xmax_m", "xrms_m", "a1_m", "zeta"]
    assert len(rows) == 6
    for i, row in enumerate(rows):
        assert float(row[0]) == r["value"][i] and row[1] == r["direction"][i]
        assert row[2] == ("true" if r["settled"][i] else "false") and int(row[3]) == r["periods"][i]
        assert float(row[5]) == r["xmax"][i, 0] and float(row[6]) == r["xrms"][i, 0] and float(row[7]) == r["a1"][i, 0]
        assert float(row[8]) == r["value2"][i]
    header, rows = read_csv(diagram)
    assert header == ["omega", "direction", "t", "x_m", "v_m", "zeta"]
    d = r["diagram"]
    assert len(rows) == len(d["t"]) == 24
    for i, row in enumerate(rows):
        assert float(row[2]) == d["t"][i] and float(row[3]) == d["x"][i, 0] and float(row[4]) == d["v"][i, 0]


def test_bad_input_raises_input_error():
    model = hsnc.Model.from_string(LINEAR)
    with pytest.raises(hsnc.InputError, match="no parameter named 'nope'"):
        hsnc.sweep(model, "nope", 1, 2, 3)
    with pytest.raises(hsnc.InputError, match="direction"):
        hsnc.sweep(model, "omega", 1, 2, 3, direction="sideways")
    with pytest.raises(hsnc.InputError, match="sweep at omega = 0: "):
        hsnc.sweep(model, "omega", 1, -1, 3)
    with pytest.raises(ValueError):
        hsnc.sweep(model, "omega", 1, 2, 0)


def test_harmonics_amplitude_and_phase_against_h_and_the_command_line(tmp_path):
    """harmonics=K: amp and phase (points x masses x K); a linear
    oscillator's first harmonic is |H| and arg H (x = sum amp sin(k w t +
    phase)), the others vanish; the CLI's columns are the same numbers."""
    path = tmp_path / "linear.toml"
    path.write_text(LINEAR)
    model = hsnc.Model.from_file(path)
    r = hsnc.sweep(model, "omega", 0.6, 1.4, 3, max_periods=2000, record_periods=4, harmonics=2)
    assert r["amp"].shape == (3, 1, 2) and r["phase"].shape == (3, 1, 2)
    w = r["value"]
    H = 1 / (1 - w**2 + 0.1j * w)
    np.testing.assert_allclose(r["amp"][:, 0, 0], np.abs(H), rtol=1e-8)
    np.testing.assert_allclose(r["phase"][:, 0, 0], np.angle(H), atol=1e-8)
    assert (r["amp"][:, 0, 0] == r["a1"][:, 0]).all()
    assert (r["amp"][:, 0, 1] < 1e-8 * r["amp"][:, 0, 0]).all()
    assert "amp" not in hsnc.sweep(model, "omega", 0.6, 1.4, 2, max_periods=50)
    out = tmp_path / "curve.csv"
    run_cli("sweep", path, "--param", "omega", "--from", 0.6, "--to", 1.4, "--points", 3, "--max-periods", 2000,
            "--record-periods", 4, "--harmonics", 2, "--quiet", "--out", out)
    header, rows = read_csv(out)
    assert header[-4:] == ["amp1_m", "phase1_m", "amp2_m", "phase2_m"]
    for i, row in enumerate(rows):
        assert [float(c) for c in row[-4:]] == [r["amp"][i, 0, 0], r["phase"][i, 0, 0], r["amp"][i, 0, 1],
                                                r["phase"][i, 0, 1]]
    with pytest.raises(hsnc.InputError, match="harmonics"):
        hsnc.sweep(model, "omega", 0.6, 1.4, 3, harmonics=-1)
