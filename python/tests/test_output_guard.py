"""The CLI's output guard (`hsnc simulate --out`: more than 1e7 rows or about
1 GB refused unless --allow-large-output) on what simulate, periodic and
lyapunov collect in memory: refused before the run with InputError naming
the argument, unless allow_large_output=True. dt=1e-300 used to collect
samples until the OOM killer ended the process.

The limits are tested at their edges without collecting anything large:
a run accepted just below the limit stops at its first switch event
(max_events=1), a periodic search after one iteration (no orbit sampled)."""

import math
import time

import pytest

import hsnc
from conftest import model_path

LIMIT = 10_000_000  # rows (output/simulate_outputs.h kLargeOutputRows)


@pytest.fixture(scope="module")
def bilinear():
    # t0 = 0, t_end = 10; starting a hair inside the open side, the contact closes within 1e-3 s.
    return hsnc.Model.from_file(model_path("bilinear-1dof.toml"), x0={"m1": -1e-3})


def test_simulate_tiny_dt_is_refused_before_the_run(bilinear):
    start = time.monotonic()
    with pytest.raises(hsnc.InputError) as e:
        hsnc.simulate(bilinear, t_end=1, dt=1e-300)
    assert time.monotonic() - start < 5
    assert str(e.value) == ("hsnc.simulate(): dt = 1e-300: the result would have 1e+300 rows, about 2.4e+283 EB "
                            "(the limit is 1e7 rows or 1 GB): give a larger dt or a shorter t_end, "
                            "or allow_large_output=True to collect it anyway")


def test_simulate_rows_limit_at_its_edge(bilinear):
    # Rows from t0 to t_end every dt, the last one t_end: 10 / dt + 1.
    above = 10.0 / LIMIT  # LIMIT + 1 rows
    below = 10.0 / (LIMIT - 1)  # LIMIT rows
    with pytest.raises(hsnc.InputError, match=r"dt = 1e-06: the result would have 1e\+07 rows, about 240 MB"):
        hsnc.simulate(bilinear, dt=above)
    r = hsnc.simulate(bilinear, dt=below, max_events=1)
    assert r.summary["status"] == "max_events" and 0 < len(r.t) <= 1001
    r = hsnc.simulate(bilinear, dt=above, max_events=1, allow_large_output=True)
    assert r.summary["status"] == "max_events" and 0 < len(r.t) <= 1001
    assert r.t[1] == above


def test_simulate_bytes_limit_counts_every_column():
    # 8 masses: t, x, v = 17 doubles a row, so 1 GB is 7.35e6 rows, under the row limit.
    model = hsnc.Model.from_file(model_path("chain-8.toml"))
    rows = 7_500_000
    with pytest.raises(hsnc.InputError, match=r"7\.5e\+06 rows, about 1\.02 GB \(the limit is 1e7 rows or 1 GB\)"):
        hsnc.simulate(model, t_end=20.0, dt=20.0 / (rows - 1))
    r = hsnc.simulate(model, t_end=20.0, dt=20.0 / (rows - 1), max_events=1, allow_large_output=True)
    assert r.summary["status"] == "max_events"


def test_periodic_tiny_dt_is_refused_and_allowed_on_request():
    model = hsnc.Model.from_file(model_path("seed-scenario-2.toml"))
    with pytest.raises(hsnc.InputError, match=r"hsnc.periodic\(\): dt = 1e-300: .* give a larger dt or a shorter "
                                              r"period, or allow_large_output=True"):
        hsnc.periodic(model, dt=1e-300)
    # One period of 2 s, sampled every dt: 2 / dt + 1 rows (one iteration: not converged, no orbit sampled).
    with pytest.raises(hsnc.InputError, match=r"dt = 2e-07: the result would have 1e\+07 rows"):
        hsnc.periodic(model, period=1.0, harmonic=2, dt=2.0 / LIMIT, max_iterations=1)
    for kwargs in ({"dt": 2.0 / (LIMIT - 1)}, {"dt": 2.0 / LIMIT, "allow_large_output": True}):
        r = hsnc.periodic(model, period=1.0, harmonic=2, max_iterations=1, **kwargs)
        assert r["status"] == "not_converged" and r["orbit"]["t"].shape == (0,)


def test_lyapunov_tiny_row_interval_is_refused():
    model = hsnc.Model.from_file(model_path("seed-scenario-2.toml"))
    with pytest.raises(hsnc.InputError, match=r"hsnc.lyapunov\(\): row_interval = 1e-300: the result would have "
                                              r"1e\+300 rows, .* give a larger row_interval or a shorter t_end"):
        hsnc.lyapunov(model, t_end=1.0, row_interval=1e-300)
    # The default spacing (the forcing period, 0.358 s) counts too.
    with pytest.raises(hsnc.InputError, match=r"row_interval = 0\.358: the result would have 2\.79e\+07 rows"):
        hsnc.lyapunov(model, t_end=1e7)
