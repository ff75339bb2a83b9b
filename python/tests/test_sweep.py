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
