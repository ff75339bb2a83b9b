"""Ctrl-C (SIGINT) stops a long hsnc.periodic or hsnc.lyapunov promptly with
KeyboardInterrupt, as it stops hsnc.simulate: the analyses' progress hook
looks for signals every 50 ms."""

import signal

import pytest

from conftest import interrupt_long_run, model_path

CALLS = {
    "periodic": "hsnc.periodic(model, transient=1e7)",  # a transient of hours
    "lyapunov": "hsnc.lyapunov(model, t_end=1e7, row_interval=1e6)",  # a measurement of hours, 10 rows
}


@pytest.mark.parametrize("analysis", ["periodic", "lyapunov"])
def test_sigint_stops_a_long_analysis_promptly(analysis):
    out, err, code, waited = interrupt_long_run(CALLS[analysis], model_path("seed-scenario-2.toml"), 1.0, 60)
    assert "KeyboardInterrupt" in err and "interrupted after" in out and "finished" not in out, (out, err)
    assert code == -signal.SIGINT
    assert waited < 2.0, waited
