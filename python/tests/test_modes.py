"""hsnc.modes returns what `hsnc modes` writes (the same doubles), as NumPy
arrays; the bilinear oscillator's backbone against its closed form; bad
input raises InputError naming the Python argument."""

import math

import numpy as np
import pytest

import hsnc
from conftest import SOURCE_DIR, read_csv


def example(name):
    return str(SOURCE_DIR / "examples" / "modes" / name)


def bilinear_period(A, k1=4.0, k2=12.0, d=0.1):
    """Two harmonic arcs joined at the gap: omega2 about c beyond it, omega1 about 0 below."""
    w1, w2 = math.sqrt(k1), math.sqrt(k1 + k2)
    if A <= d:
        return 2 * math.pi / w1
    c = k2 * d / (k1 + k2)
    t2 = math.acos((d - c) / (A - c)) / w2
    C = math.hypot(d, (A - c) * w2 * math.sin(w2 * t2) / w1)
    return 2 * t2 + (2 * math.pi - 2 * math.acos(d / C)) / w1


def test_bilinear_backbone_against_its_closed_form():
    r = hsnc.modes(hsnc.Model.from_file(example("bilinear-gap.toml")), 0.6, start=0.03, points=12)
    assert r["status"] == "ok" and r["dof"] == "m" and r["linear_omega"] == 2.0
    closed = np.array([bilinear_period(a) for a in r["amplitude"]])
    assert np.allclose(r["period"], closed, rtol=1e-11, atol=0)
    assert np.allclose(r["omega"], 2 * math.pi / closed, rtol=1e-11, atol=0)
    assert r["stable"].all() and r["x"].shape == (12, 1) and r["ratios"].shape == (12, 0)
    pen = np.maximum(r["amplitude"] - 0.1, 0.0)  # beyond the gap the peak is on the free side
    assert np.allclose(r["peak"][:, 0], np.sqrt(r["amplitude"] ** 2 + 3 * pen ** 2), rtol=1e-12, atol=0)


def test_matches_the_command_line(cli, tmp_path):
    path = example("chain-stops.toml")
    r = hsnc.modes(hsnc.Model.from_file(path), 0.51, start=0.06, points=10, mode=1, dof="m1")
    out = tmp_path / "b.csv"
    p = cli("modes", path, "--mode", 1, "--dof", "m1", "--from", 0.06, "--to", 0.51, "--points", 10, "--out", out,
            "--quiet")
    assert p.stdout.startswith("status=ok mode=1 dof=m1 ")
    header, rows = read_csv(out)
    col = {name: i for i, name in enumerate(header)}
    assert r["others"] == [2] and len(rows) == 10
    for i, row in enumerate(rows):
        assert float(row[col["omega"]]) == r["omega"][i]
        assert float(row[col["energy"]]) == r["energy"][i]
        assert float(row[col["x_m2"]]) == r["x"][i, 1]
        assert float(row[col["peak_m2"]]) == r["peak"][i, 1]
        assert float(row[col["ratio_mode2"]]) == r["ratios"][i, 0]
        assert row[col["resonance"]] == ";".join(r["resonances"][i])
        assert (row[col["stable"]] == "true") == bool(r["stable"][i])
    assert sum(len(x) for x in r["resonances"]) == 1 and "mode2 2:1" in sum(r["resonances"], [])
    assert r["multipliers"].shape == (10, 4) and r["multipliers"].dtype == complex


@pytest.mark.parametrize("kwargs, word", [
    (dict(stop=0.5, start=-0.1), "start"),
    (dict(stop=0.5, dof="zz"), "dof"),
    (dict(stop=0.5, mode=3), "mode"),
    (dict(stop=float("nan")), "stop"),
    (dict(stop=0.5, points=0), "points"),
])
def test_refuses_by_argument(kwargs, word):
    with pytest.raises(hsnc.InputError, match=word):
        hsnc.modes(hsnc.Model.from_file(example("chain-stops.toml")), **kwargs)


def test_a_damper_makes_the_mode_damped_with_xi_its_rate():
    """On one dof the EPMC term -xi m v cancels a damper c exactly: xi = c/m at every
    amplitude, and the orbits are the conservative closed form's."""
    text = open(example("bilinear-gap.toml")).read() + '\n[[damper]]\nbetween = ["m", "ground"]\nc = 0.1\n'
    r = hsnc.modes(hsnc.Model.from_string(text), 0.6, start=0.03, points=8)
    assert r["status"] == "ok" and r["damped"]
    assert r["linear_damping_ratio"] == pytest.approx(0.1 / (2 * 2.0), rel=1e-14)
    assert np.allclose(r["xi"], 0.1, rtol=1e-10, atol=0)
    closed = np.array([bilinear_period(a) for a in r["amplitude"]])
    assert np.allclose(r["period"], closed, rtol=1e-10, atol=0)


def test_friction_between_two_bodies_starts_from_them_moving_as_one():
    """Stuck, f rides on m: the linear limit of masses 1 + 0.05 on springs 1 + 3."""
    text = ('name = "pair"\n[[mass]]\nname = "m"\nm = 1.0\n[[mass]]\nname = "f"\nm = 0.05\n'
            '[[spring]]\nbetween = ["m", "ground"]\nk = 1.0\n[[spring]]\nbetween = ["f", "ground"]\nk = 3.0\n'
            '[[friction]]\nbetween = ["f", "m"]\nmu_k = 0.5\nnormal = 0.6\n')
    r = hsnc.modes(hsnc.Model.from_string(text), 0.5, start=0.05, points=3)
    assert r["status"] == "ok" and r["damped"]
    assert r["linear_omega"] == pytest.approx(math.sqrt(4 / 1.05), rel=1e-14)
    assert r["omega"][0] == pytest.approx(math.sqrt(4 / 1.05), rel=1e-12)
    assert np.all(r["xi"][1:] > 0)


def test_energy_backbone_in_equal_ratios():
    r = hsnc.modes(hsnc.Model.from_file(example("bilinear-gap.toml")), 100.0, start=1e-3, points=6,
                   parameter="energy", geometric=True)
    assert r["status"] == "ok"
    assert np.allclose(r["energy"], 1e-3 * 10.0 ** np.arange(6), rtol=1e-12, atol=0)
    closed = np.array([bilinear_period(a) for a in r["amplitude"]])
    assert np.allclose(r["period"], closed, rtol=1e-11, atol=0)
    with pytest.raises(hsnc.InputError, match="parameter"):
        hsnc.modes(hsnc.Model.from_file(example("bilinear-gap.toml")), 1.0, parameter="power")


def test_damped_mode_of_a_jenkins_joint_matches_the_command_line(cli, tmp_path):
    path = example("jenkins-joint.toml")
    r = hsnc.modes(hsnc.Model.from_file(path), 1.0, start=0.05, points=8)
    assert r["status"] == "ok" and r["damped"] and r["linear_damping_ratio"] == 0.0
    assert r["sliders"].shape == (8, 1) and r["multipliers"].shape == (8, 3)
    out = tmp_path / "m.csv"
    p = cli("modes", path, "--from", 0.05, "--to", 1.0, "--points", 8, "--out", out, "--quiet")
    assert p.stdout.startswith("status=ok mode=1 dof=m ") and "damping_ratio=" in p.stdout
    header, rows = read_csv(out)
    col = {name: i for i, name in enumerate(header)}
    for name in ("amplitude", "omega", "damping_ratio", "xi", "period", "energy"):
        assert [float(row[col[name]]) for row in rows] == list(r[name]), name
    assert [float(row[col["s_joint"]]) for row in rows] == list(r["sliders"][:, 0])
    # Stuck below F_s/k_t = 0.1: the linear mode, undamped; beyond, the frequency falls toward
    # the free 1 rad/s and the joint damps.
    stuck = r["amplitude"] < 0.1
    assert np.all(r["omega"][stuck] == 2.0) and np.all(r["xi"][stuck] == 0.0)
    assert np.all(np.diff(r["omega"][~stuck]) < 0) and np.all(r["omega"] > 1.0)
    assert np.all(r["damping_ratio"][~stuck] > 0)
    with pytest.raises(hsnc.InputError, match="energy"):
        hsnc.modes(hsnc.Model.from_file(path), 1.0, parameter="energy")
