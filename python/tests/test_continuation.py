"""hsnc.sweep(continuation=True): the hardening stop's branch with its two
folds, the same numbers as `hsnc sweep --continuation`; a failing point;
and Ctrl-C (SIGINT) interrupting a long sweep promptly."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np

import hsnc
from conftest import SOURCE_DIR, read_csv, run_cli

HARDENING = str(SOURCE_DIR / "examples" / "hardening-stop.toml")


def assert_refused(call, name, bads):
    """call(bad) raises ValueError or TypeError naming `name`, for every bad value."""
    for bad in bads:
        try:
            call(bad)
        except (ValueError, TypeError) as e:
            assert name in str(e), e
        else:
            raise AssertionError("%s=%r accepted" % (name, bad))


def test_continuation_through_two_folds_same_as_the_command_line(tmp_path):
    model = hsnc.Model.from_file(HARDENING)
    r = hsnc.sweep(model, "omega", 0.8, 2.0, 25, continuation=True)
    n = len(r["value"])
    assert n >= 25 and r["value"][0] == 0.8 and r["value"][-1] == 2.0
    folds = [i for i, b in enumerate(r["bifurcation"]) if b.startswith("fold")]
    assert len(folds) == 2
    # The lower branch reaches the stop (a grazing row of its own), and leaves
    # it at the second fold (crossed in the same step).
    assert [b for b in r["bifurcation"] if b] == ["grazing", "fold", "fold+grazing"]
    # Stable before the first fold and from the second on, unstable between.
    expected = np.array([i < folds[0] or i >= folds[1] for i in range(n)])
    assert (r["stable"] == expected).all()
    assert ((r["max_multiplier"] < 1) == expected).all()
    assert all(s == "" for s in r["stop"]) and all(f == "" for f in r["failure"])
    out = tmp_path / "c.csv"
    run_cli("sweep", HARDENING, "--param", "omega", "--from", 0.8, "--to", 2.0, "--points", 25, "--continuation",
            "--quiet", "--out", out)
    header, rows = read_csv(out)
    assert header[-3:] == ["stable", "max_multiplier", "bifurcation"]
    assert len(rows) == n
    for i, row in enumerate(rows):
        assert float(row[0]) == r["value"][i] and float(row[5]) == r["xmax"][i, 0]
        assert row[8] == ("true" if r["stable"][i] else "false") and float(row[9]) == r["max_multiplier"][i]
        assert row[10] == r["bifurcation"][i]


CASCADE = textwrap.dedent('''
    name = "bilinear-cascade"
    [parameters]
    omega = 2.4
    [[mass]]
    name = "m"
    m = 1.0
    [[spring]]
    between = ["ground", "m"]
    k = 1.0
    [damping]
    alpha = 0.1
    [[contact]]
    between = ["m", "ground"]
    gap = 0.0
    k = 50.0
    [[forcing]]
    omega = "omega"
    amplitude = { m = 1.0 }
''')


def test_branch_switching_follows_the_period_two_branch_as_the_command_line(tmp_path):
    # A bilinear oscillator's period-1 orbit doubles at omega = 2.4964: with
    # branch_switch=1 the period-2 branch born there is followed too (its
    # own doubling at 2.6119 is marked, not followed).
    path = tmp_path / "cascade.toml"
    path.write_text(CASCADE)
    r = hsnc.sweep(hsnc.Model.from_file(str(path)), "omega", 2.4, 2.66, 14, continuation=True, branch_switch=1)
    branch, multiple = np.asarray(r["branch"]), np.asarray(r["multiple"])
    assert sorted(set(branch.tolist())) == [0, 1]
    assert (multiple == np.where(branch == 0, 1, 2)).all()
    doublings = [i for i, b in enumerate(r["bifurcation"]) if b == "period_doubling"]
    assert len(doublings) == 2 and branch[doublings[0]] == 0 and branch[doublings[1]] == 1
    first = int(np.argmax(branch == 1))
    assert r["value"][first] == r["value"][doublings[0]] and abs(r["value"][first] - 2.4964) < 1e-4
    out = tmp_path / "c.csv"
    run_cli("sweep", path, "--param", "omega", "--from", 2.4, "--to", 2.66, "--points", 14, "--continuation",
            "--branch-switch", 1, "--quiet", "--out", out)
    header, rows = read_csv(out)
    assert header[-4:] == ["stable", "max_multiplier", "bifurcation", "branch"]
    assert [int(row[-1]) for row in rows] == branch.tolist()
    assert [float(row[0]) for row in rows] == list(r["value"])
    model = hsnc.Model.from_file(str(path))
    assert_refused(lambda bad: hsnc.sweep(model, "omega", 2.4, 2.66, 14, continuation=True, branch_switch=bad),
                   "branch_switch", (7, -1, 1.5))


def test_a_grazing_curve_over_two_parameters_is_the_closed_form():
    # The hardening stop's lower branch reaches the stop where F |H(omega)| = 0.5.
    model = hsnc.Model.from_file(HARDENING)
    r = hsnc.sweep(model, "omega", 0.6, 2.0, 29, continuation=True, track="grazing", param2="F", values2=[0.1, 0.05])
    w, F = np.asarray(r["value"]), np.asarray(r["value2"])
    assert len(w) >= 10 and F[0] == 0.1 and F[-1] < 0.055
    H = np.abs(1 / (1 - w ** 2 + 0.04j * w))
    assert np.abs(F * H - 0.5).max() < 1e-10
    assert all(b == "grazing" for b in r["bifurcation"])
    assert_refused(lambda bad: hsnc.sweep(model, "omega", 0.6, 2.0, 29, continuation=True, param2="F",
                                          values2=[0.1, 0.05], track=bad), "track", ("cusp", 3))


def test_basins_of_the_bistable_oscillator_as_the_command_line(tmp_path):
    model = hsnc.Model.from_file(HARDENING, set={"omega": 1.3})
    values = list(np.linspace(-3, 3, 9))
    r = hsnc.sweep(model, "x0.m", -3, 3, 9, param2="v0.m", values2=values, restart_each=True, max_periods=3000)
    assert len(r["attractors"]) == 2 and set(np.asarray(r["attractor"]).tolist()) == {1, 2}
    out = tmp_path / "b.csv"
    run_cli("sweep", HARDENING, "--set", "omega=1.3", "--param", "x0.m", "--from", -3, "--to", 3, "--points", 9,
            "--param2", "v0.m", "--values2=-3:3:9", "--restart-each", "--max-periods", 3000, "--quiet", "--out", out)
    header, rows = read_csv(out)
    assert header[-1] == "attractor"
    assert [int(row[-1]) for row in rows] == np.asarray(r["attractor"]).tolist()


def test_basins_chaotic_set_and_escape():
    # The bilinear cascade at 2.7 rad/s: every initial state in one chaotic set (multiple 0).
    model = hsnc.Model.from_string(CASCADE, set={"omega": 2.7})
    r = hsnc.sweep(model, "x0.m", -3, 3, 5, param2="v0.m", values2=[-1, 1], restart_each=True, max_periods=300,
                   record_periods=64)
    assert [a["multiple"] for a in r["attractors"]] == [0]
    assert np.asarray(r["attractor"]).tolist() == [1] * 10
    assert not np.asarray(r["escaped"]).any()
    # An undamped resonance escapes |x| > 30 after 10 periods from rest (x(2 pi k) = -pi k).
    resonance = hsnc.Model.from_string(textwrap.dedent('''
        name = "resonance"
        [[mass]]
        name = "m"
        m = 1.0
        [[spring]]
        between = ["ground", "m"]
        k = 1.0
        [[forcing]]
        omega = 1.0
        amplitude = { m = 1.0 }
        '''))
    e = hsnc.sweep(resonance, "x0.m", 0, 0, 1, param2="v0.m", values2=[0], restart_each=True, escape=30)
    assert np.asarray(e["escaped"]).tolist() == [True] and int(e["periods"][0]) == 10
    assert np.asarray(e["attractor"]).tolist() == [-2] and e["attractors"] == []
    assert_refused(lambda bad: hsnc.sweep(resonance, "x0.m", 0, 0, 1, param2="v0.m", values2=[0], restart_each=True,
                                          escape=bad), "escape", (-1, float("nan"), "30"))


def test_continuation_from_a_row_of_an_earlier_run():
    # The period-2 branch born at the cascade's first doubling, then a branch
    # started from one of its rows (state at t0, multiple 2) with no transient.
    model = hsnc.Model.from_string(CASCADE)
    r = hsnc.sweep(model, "omega", 2.4, 2.66, 14, continuation=True, branch_switch=1)
    branch = np.asarray(r["branch"])
    rows = [i for i in range(len(branch)) if branch[i] == 1 and r["value"][i] > 2.55]
    assert rows
    i = rows[0]
    first = sum(int(m) for m in r["multiple"][:i])
    x, v = r["diagram"]["x"][first + 1, 0], r["diagram"]["v"][first + 1, 0]
    again = hsnc.sweep(hsnc.Model.from_string(CASCADE, x0={"m": x}, v0={"m": v}), "omega", r["value"][i], 2.6, 5,
                       continuation=True, start_periods=2)
    assert again["value"][0] == r["value"][i] and int(again["multiple"][0]) == 2 and int(again["periods"][0]) == 0
    assert abs(again["diagram"]["x"][1, 0] - x) < 1e-10 and abs(again["diagram"]["v"][1, 0] - v) < 1e-10
    assert set(np.asarray(again["multiple"]).tolist()) == {2}
    assert_refused(lambda bad: hsnc.sweep(model, "omega", 2.4, 2.66, 14, continuation=True, start_periods=bad),
                   "start_periods", (-1, 1025, 2.5))


def test_a_failing_point_is_a_row_and_the_sweep_goes_on():
    # k = 1e300 at p = 2 only: that point's run fails at once.
    text = textwrap.dedent('''
        name = "fails-in-the-middle"
        [parameters]
        p = 1.0
        [[mass]]
        name = "m"
        m = 1.0
        [[spring]]
        between = ["m", "ground"]
        k = "pow(10, 300*exp(-100*(p - 2)^2))"
        [[contact]]
        between = ["m", "ground"]
        gap = 0
        k = 12
        [damping]
        alpha = 0.1
        [[forcing]]
        omega = 1.0
        amplitude = { m = 1.0 }
        ''')
    r = hsnc.sweep(hsnc.Model.from_string(text), "p", 1, 3, 3, max_periods=400, record_periods=2)
    assert list(r["settled"]) == [True, False, True]
    assert r["failure"][0] == "" and r["failure"][2] == ""
    assert "the run stopped" in r["failure"][1]
    assert np.isnan(r["xmax"][1, 0]) and np.isfinite(r["xmax"][[0, 2], 0]).all()


def test_ctrl_c_interrupts_a_long_sweep_promptly():
    # An undamped oscillator at irrational frequency ratios never settles: with max_periods
    # = 1e8 the sweep would run for a long time.
    script = textwrap.dedent('''
        import sys, time
        import hsnc
        m = hsnc.Model.from_string(\'\'\'
        name = "undamped"
        [parameters]
        omega = 0.7
        [[mass]]
        name = "m"
        m = 1.0
        [[spring]]
        between = ["ground", "m"]
        k = 1.0
        [[forcing]]
        omega = "omega"
        amplitude = { m = 1.0 }
        \'\'\')
        print("running", flush=True)
        try:
            hsnc.sweep(m, "omega", 0.6180339887498949, 0.7071067811865476, 3, max_periods=100000000, threads=2,
                       restart_each=True)
            print("finished", flush=True)
        except KeyboardInterrupt:
            print("interrupted", time.monotonic(), flush=True)
        ''')
    p = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env=dict(os.environ))
    try:
        assert p.stdout.readline().strip() == "running"
        time.sleep(1.0)  # inside the native run
        assert p.poll() is None
        sent = time.monotonic()
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=30)
    finally:
        if p.poll() is None:
            p.kill()
    words = out.split()
    assert words[:1] == ["interrupted"], out + err
    # Prompt: well within a second of the signal (a forcing period is microseconds here).
    assert float(words[1]) - sent < 1.0, (float(words[1]) - sent)
    assert p.returncode == 0
