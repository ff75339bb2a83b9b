"""hsnc.periodic and hsnc.lyapunov return what `hsnc periodic` and
`hsnc lyapunov` print (the same doubles), as NumPy arrays and dicts; bad
input raises InputError."""

import math

import numpy as np
import pytest

import hsnc
from conftest import model_path, read_csv


def fields(line):
    return dict(item.split("=", 1) for item in line.split())


def test_periodic_matches_the_command_line(cli, tmp_path):
    model = hsnc.Model.from_file(model_path("seed-scenario-1.toml"))
    r = hsnc.periodic(model, dt=0.001)
    mult = tmp_path / "mu.csv"
    p = cli("periodic", model_path("seed-scenario-1.toml"), "--multipliers", mult, "--quiet")
    line = fields(p.stdout.strip())
    assert r["status"] == line["status"] == "ok"
    assert r["period"] == float(line["period"])
    assert r["x"][0] == float(line["x_m1"]) and r["v"][1] == float(line["v_m2"])
    assert r["max_multiplier"] == float(line["max_multiplier"])
    assert r["stable"] == (line["stable"] == "true")
    assert r["grazing"] == int(line["grazing"]) == 0
    header, rows = read_csv(mult)
    assert header == ["index", "re", "im", "abs"]
    assert r["multipliers"].dtype == np.complex128 and r["multipliers"].shape == (4,)
    assert np.array_equal(r["multipliers"].real, [float(row[1]) for row in rows])
    assert np.array_equal(r["multipliers"].imag, [float(row[2]) for row in rows])
    assert r["monodromy"].shape == (4, 4)
    # The multipliers are the monodromy's eigenvalues.
    assert np.allclose(np.sort_complex(np.linalg.eigvals(r["monodromy"])), np.sort_complex(r["multipliers"]),
                       rtol=1e-12, atol=1e-12)
    orbit = r["orbit"]
    assert orbit["x"].shape == (len(orbit["t"]), 2) and orbit["t"][0] == r["t"]
    assert math.isclose(orbit["t"][-1], r["t"] + r["period"], rel_tol=1e-15)
    assert np.allclose(orbit["x"][-1], orbit["x"][0], rtol=0, atol=1e-9)


def test_periodic_and_lyapunov_carry_a_jenkins_slider(cli):
    """The friction damper's orbit: the slider is state (s), one multiplier
    and one exponent more; the command line prints the same orbit."""
    path = model_path("../examples/jenkins/friction_damper.toml")
    model = hsnc.Model.from_file(path)
    r = hsnc.periodic(model, transient=30.0, kernels="generic")
    assert r["status"] == "ok" and r["stable"]
    assert r["s"].shape == (1,) and r["multipliers"].shape == (5,) and r["monodromy"].shape == (5, 5)
    line = fields(cli("periodic", path, "--transient", "30", "--kernels", "generic", "--quiet").stdout.strip())
    assert r["s"][0] == float(line["s_damper"]) and r["x"][1] == float(line["x_platform"])
    ly = hsnc.lyapunov(model, t_end=20.0, transient=30.0, kernels="generic")
    assert ly["exponents"].shape == (5,) and ly["exponents"][-1] == -math.inf
    assert ly["rows"].shape[1] == 5


def test_periodic_not_converged_is_a_status_not_an_orbit():
    model = hsnc.Model.from_file(model_path("seed-scenario-2.toml"))
    r = hsnc.periodic(model, max_iterations=1)
    assert r["status"] == "not_converged" and r["message"]
    assert not r["stable"] and math.isnan(r["max_multiplier"])
    assert r["multipliers"].shape == (0,) and r["orbit"]["t"].shape == (0,)


def test_lyapunov_matches_the_command_line(cli, tmp_path):
    model = hsnc.Model.from_file(model_path("seed-scenario-2.toml"))
    r = hsnc.lyapunov(model, t_end=30)
    out = tmp_path / "lyap.csv"
    p = cli("lyapunov", model_path("seed-scenario-2.toml"), "--t-end", "30", "--out", out, "--quiet")
    line = fields(p.stdout.strip())
    assert r["exponents"].shape == (4,)
    assert list(r["exponents"]) == [float(line["lambda_%d" % k]) for k in range(1, 5)]
    assert r["sum"] == float(line["sum"]) == -math.inf
    assert r["collapsed"] == 1
    assert r["grazing"] == int(line["grazing"]) == 0 and r["singular"] == 0
    header, rows = read_csv(out)
    assert header == ["t", "lambda_1", "lambda_2", "lambda_3", "lambda_4"]
    assert r["rows"].shape == (len(rows), 4)
    assert np.array_equal(r["rows_t"], [float(row[0]) for row in rows])
    assert np.array_equal(r["rows"], [[float(c) for c in row[1:]] for row in rows])


def test_bad_input_raises_input_error():
    model = hsnc.Model.from_file(model_path("coulomb-1dof.toml"))
    with pytest.raises(hsnc.InputError, match="no harmonic forcing"):
        hsnc.periodic(model)
    with pytest.raises(hsnc.InputError, match="harmonic"):
        hsnc.periodic(hsnc.Model.from_file(model_path("seed-scenario-1.toml")), harmonic=0)
    with pytest.raises(hsnc.InputError, match="t_end"):
        hsnc.lyapunov(model, t_end=-1)
    with pytest.raises(hsnc.InputError, match="t_end"):
        hsnc.lyapunov(model, t_end="soon")


TWO_TONE = """name = "two_tone"
[[mass]]
name = "m"
m = 1.0
[[spring]]
between = ["m", "ground"]
k = 1.0
[damping]
alpha = 1.0
[[forcing]]
omega = 1.0
amplitude = { m = 1.0 }
[[forcing]]
omega = 1.4142135623730951
amplitude = { m = 0.5 }
"""


def test_rotation_number_of_a_stroboscopic_section_matches_the_command_line(cli, tmp_path):
    # Under 1 and sqrt(2) rad/s the section at 2 pi turns by sqrt(2) - 1 of a turn per period.
    path = tmp_path / "two_tone.toml"
    path.write_text(TWO_TONE)
    T = 2 * math.pi
    r = hsnc.simulate(hsnc.Model.from_file(path), t_end=1273 * T, dt=T)
    value, error = hsnc.rotation_number(r.x[:, 0], r.v[:, 0])
    assert abs(value - (math.sqrt(2) - 1)) < 1e-13 and error < 1e-11
    line = fields(cli("simulate", path, "--t-end", repr(1273 * T), "--section", "period:1", "--section-out",
                      tmp_path / "s.csv", "--quiet").stdout.strip())
    assert float(line["rotation"]) == value and float(line["rotation_error"]) == error
    assert all(math.isnan(z) for z in hsnc.rotation_number([1.0] * 10, np.arange(10.0)))  # x does not move
    for bad in ([[1.0, 2.0]], [1.0, math.nan], "x"):
        with pytest.raises(hsnc.InputError, match=r"hsnc.rotation_number\(\): x = .*: expected a 1-D sequence"):
            hsnc.rotation_number(bad, [1.0, 2.0])
    with pytest.raises(hsnc.InputError, match="x and v must have the same length"):
        hsnc.rotation_number([1.0, 2.0], [1.0])
