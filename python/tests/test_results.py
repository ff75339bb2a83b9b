"""hsnc.simulate returns the numbers `hsnc simulate` writes: the same sample
grid and the same doubles (bit for bit: the CSV's 17 digits round-trip), the
same events and the same summary line."""

import numpy as np
import pytest

import hsnc
from conftest import model_path, numbers, read_csv


def cli_run(cli, tmp_path, model, *flags):
    out, events = tmp_path / "out.csv", tmp_path / "events.csv"
    p = cli("simulate", model, "--out", out, "--events", events, "--quiet", *flags)
    return read_csv(out), read_csv(events), p.stdout.strip()


def assert_same_run(r, model, traj, events, line):
    n = len(model.masses)
    header, rows = traj
    assert header == ["t"] + ["x_" + m for m in model.masses] + ["v_" + m for m in model.masses]
    assert r.t.shape == (len(rows),) and r.x.shape == (len(rows), n) and r.v.shape == (len(rows), n)
    assert r.t.dtype == np.float64
    # Exact equality, element by element (NaN would fail too: there is none here).
    assert np.array_equal(r.t, numbers(rows, [0])[:, 0])
    assert np.array_equal(r.x, numbers(rows, range(1, 1 + n)))
    assert np.array_equal(r.v, numbers(rows, range(1 + n, 1 + 2 * n)))

    eheader, erows = events
    assert eheader == ["t", "kind", "element"] + ["x_" + m for m in model.masses] + ["v_" + m for m in model.masses]
    assert len(r.events) == len(erows) > 0
    assert np.array_equal(r.events.t, numbers(erows, [0])[:, 0])
    assert list(r.events.kind) == [row[1] for row in erows]
    assert list(r.events.element) == [row[2] for row in erows]
    assert r.events.x.shape == (len(erows), n)
    assert np.array_equal(r.events.x, numbers(erows, range(3, 3 + n)))
    assert np.array_equal(r.events.v, numbers(erows, range(3 + n, 3 + 2 * n)))

    # The summary line: "status=ok method=hsnc t=... events=N contact_close=... x_m1=... v_m1=..."
    fields = dict(item.split("=", 1) for item in line.split())
    s = r.summary
    assert s["status"] == fields["status"] and s["method"] == fields["method"]
    assert s["t"] == float(fields["t"]) and s["events"] == int(fields["events"]) == len(erows)
    for kind, count in s["counts"].items():
        assert count == int(fields[kind]) == sum(1 for row in erows if row[1] == kind)
    for name in model.masses:
        assert s["x"][name] == float(fields["x_" + name]) and s["v"][name] == float(fields["v_" + name])
    if s["status"] == "ok":  # the end state is the last sample
        assert np.array_equal(r.x[-1], [s["x"][m] for m in model.masses])


@pytest.mark.parametrize("flags", [
    ("--t-end", "60", "--dt", "0.01"),   # a grid of its own
    ("--t-end", "7.3",),                  # the default grid (t_end - t0) / 1000
    ("--t-end", "5", "--dt", "0.3"),     # t_end off the grid: a last row at t_end
])
def test_scenario2_equals_cli_csv(cli, tmp_path, flags):
    model = hsnc.Model.from_file(model_path("seed-scenario-2.toml"))
    traj, events, line = cli_run(cli, tmp_path, model_path("seed-scenario-2.toml"), *flags)
    t_end = float(flags[1])
    dt = float(flags[3]) if len(flags) > 2 else None
    r = hsnc.simulate(model, t_end=t_end, dt=dt)
    assert r.summary["status"] == "ok" and r.t[0] == model.t0 and r.t[-1] == t_end
    assert_same_run(r, model, traj, events, line)


def test_overrides_and_baseline_equal_cli_csv(cli, tmp_path):
    # --set/--x0/--v0 and a numerical baseline (rk45 with its tolerances).
    path = model_path("seed-scenario-1.toml")
    model = hsnc.Model.from_file(path, set={"F1": 2.5}, x0={"m1": 0.1}, v0={"m2": -0.5})
    traj, events, line = cli_run(cli, tmp_path, path, "--set", "F1=2.5", "--x0", "m1=0.1", "--v0", "m2=-0.5",
                                 "--t-end", "20", "--dt", "0.05", "--method", "rk45", "--rtol", "1e-9")
    r = hsnc.simulate(model, t_end=20, dt=0.05, method="rk45", rtol=1e-9)
    assert_same_run(r, model, traj, events, line)
    assert r.summary["solver"] == "integrator"


def test_x0_v0_at_simulate_equal_model_overrides():
    path = model_path("seed-scenario-1.toml")
    a = hsnc.simulate(hsnc.Model.from_file(path, set={"F1": 2.5}), t_end=5, x0={"m1": 0.1}, v0={"m2": -0.5})
    b = hsnc.simulate(hsnc.Model.from_file(path, set={"F1": 2.5}, x0={"m1": 0.1}, v0={"m2": -0.5}), t_end=5)
    c = hsnc.simulate(hsnc.Model.from_file(path, set={"F1": 2.5}), t_end=5)
    assert a.x[0, 0] == 0.1 and a.v[0, 1] == -0.5
    assert np.array_equal(a.x, b.x) and np.array_equal(a.events.t, b.events.t)
    assert not np.array_equal(a.x, c.x)


def test_max_events_stops_with_that_status(cli, tmp_path):
    model = hsnc.Model.from_file(model_path("seed-scenario-2.toml"))
    traj, events, line = cli_run(cli, tmp_path, model_path("seed-scenario-2.toml"), "--t-end", "60",
                                 "--max-events", "25")
    r = hsnc.simulate(model, t_end=60, max_events=25)
    assert r.summary["status"] == "max_events" and len(r.events) == 25
    assert r.t[-1] <= r.summary["t"] < 60 and r.summary["t"] == r.events.t[-1]
    assert_same_run(r, model, traj, events, line)


def test_generic_kernels_and_reference_precision_run():
    model = hsnc.Model.from_file(model_path("bilinear-1dof.toml"))
    aot = hsnc.simulate(model, t_end=3)
    generic = hsnc.simulate(model, t_end=3, kernels="generic")
    ref = hsnc.simulate(model, t_end=3, precision="mp:30")
    assert (aot.summary["solver"], generic.summary["solver"], ref.summary["solver"]) == ("aot", "generic", "reference")
    # Model header: period 3*pi/4; the contact closes and opens once per period.
    assert list(aot.events.kind[:2]) == ["contact_open", "contact_close"]
    assert abs(aot.events.t[1] - 3 * np.pi / 4) < 1e-12
    assert np.allclose(generic.x, aot.x, rtol=0, atol=1e-12)
    assert np.allclose(ref.x, aot.x, rtol=0, atol=1e-12)


def test_generic_is_the_aot_kernels_bits_and_eigen_the_independent_solver():
    model = hsnc.Model.from_file(model_path("seed-scenario-2.toml"))
    aot = hsnc.simulate(model, t_end=100, kernels="aot")
    generic = hsnc.simulate(model, t_end=100, kernels="generic")
    eigen = hsnc.simulate(model, t_end=100, kernels="eigen")
    assert (generic.summary["solver"], eigen.summary["solver"]) == ("generic", "eigen")
    assert np.array_equal(generic.events.t, aot.events.t) and np.array_equal(generic.x, aot.x)
    # The Eigen solver: the same closed forms written apart, equal to rounding
    # (the run is chaotic: compare its first 10 s).
    early = aot.t <= 10
    assert np.allclose(eigen.x[early], aot.x[early], rtol=0, atol=1e-9)


def test_tiered_kernels_give_the_interpreters_bits(tmp_path):
    # A low tier_evaluations starts compiles in a child process; whether or not
    # they finish before the run does, not a bit changes (tests/test_tiered.cpp
    # makes sure kernels take over).
    model = hsnc.Model.from_file(model_path("chain-8.toml"))
    interp = hsnc.simulate(model, t_end=20, kernels="interp")
    for _ in range(2):  # an empty cache, then the one the first run filled
        tiered = hsnc.simulate(model, t_end=20, kernels="tiered", tier_evaluations=500, cache_dir=str(tmp_path))
        assert tiered.summary["solver"] == "tiered"
        assert np.array_equal(tiered.x, interp.x) and np.array_equal(tiered.v, interp.v)
        assert np.array_equal(tiered.events.t, interp.events.t)
    with pytest.raises(hsnc.InputError, match=r"tier_evaluations = 0: expected an integer >= 1"):
        hsnc.simulate(model, t_end=1, kernels="tiered", tier_evaluations=0)


def test_structure_with_friction_element_equals_cli_csv(cli, tmp_path):
    # A [structure] from Matrix Market files beside the model, a friction element
    # to ground: the same numbers as the command line, rows named by the element.
    (tmp_path / "M.mtx").write_text("%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1\n2 2 2\n")
    (tmp_path / "K.mtx").write_text("%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 20\n2 1 -10\n2 2 10\n")
    path = tmp_path / "s.toml"
    path.write_text('name = "s"\n[structure]\ndofs = ["u1", "u2"]\nmass = "M.mtx"\nstiffness = "K.mtx"\n'
                    '[[friction]]\nname = "pad"\nbetween = ["u2", "ground"]\nmu_k = 0.2\nmu_s = 0.3\nnormal = 4\n'
                    '[[forcing]]\nomega = 3\namplitude = { u1 = 6 }\n')
    model = hsnc.Model.from_file(str(path))
    assert model.masses == ["u1", "u2"]
    traj, events, line = cli_run(cli, tmp_path, path, "--t-end", "10", "--dt", "0.05")
    r = hsnc.simulate(model, t_end=10, dt=0.05)
    assert_same_run(r, model, traj, events, line)
    assert set(r.events.kind) <= {"stick", "release", "reversal"}
    assert set(r.events.element) == {"pad"}


def test_segments_carried_over_reversals_are_counted_and_agree_with_eigen():
    # 16 masses on springs of their own, coupled by weaker ones, friction on
    # each: every switch is a reversal, so every segment after the first is
    # carried over (runtime/solvers/restart.h); the Eigen solver sets each up.
    text = "name = \"friction-bank-16\"\n[damping]\nbeta = 0.002\n"
    text += "".join("[[mass]]\nname = \"m%d\"\nm = 1\nmu_k = 0.05\nmu_s = 0.06\n" % i for i in range(1, 17))
    text += "".join("[[spring]]\nbetween = [\"ground\", \"m%d\"]\nk = %d\n" % (i, 100 + 10 * i) for i in range(1, 17))
    text += "".join("[[spring]]\nbetween = [\"m%d\", \"m%d\"]\nk = 20\n" % (i, i + 1) for i in range(1, 16))
    text += "[[forcing]]\nomega = 7.0\namplitude = { m1 = 5.0 }\n[initial]\nx = { "
    text += ", ".join("m%d = 0.5" % i for i in range(1, 17)) + " }\n"
    model = hsnc.Model.from_string(text)
    generic = hsnc.simulate(model, t_end=3, dt=0.01, kernels="generic")
    eigen = hsnc.simulate(model, t_end=3, dt=0.01, kernels="eigen")
    assert generic.summary["segments"] == 204 and generic.summary["restarts"] == 203
    assert eigen.summary["restarts"] == 0
    assert list(generic.events.kind) == list(eigen.events.kind) == ["reversal"] * 203
    assert np.allclose(generic.events.t, eigen.events.t, rtol=0, atol=1e-12)
    assert np.allclose(generic.x, eigen.x, rtol=0, atol=1e-12)
