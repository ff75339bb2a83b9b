"""Ctrl-C (SIGINT) stops a long hsnc.periodic or hsnc.lyapunov promptly with
KeyboardInterrupt, as it stops hsnc.simulate: the analyses' progress hook
looks for signals every 50 ms."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from conftest import model_path

LONG_RUN = textwrap.dedent("""
    import sys, time
    import hsnc
    model = hsnc.Model.from_file(sys.argv[1])
    print("running", flush=True)
    start = time.monotonic()
    try:
        if sys.argv[2] == "periodic":
            r = hsnc.periodic(model, transient=1e7)   # a transient of hours
        else:
            r = hsnc.lyapunov(model, t_end=1e7, row_interval=1e6)  # a measurement of hours, 10 rows
    except KeyboardInterrupt:
        print("interrupted after %.3f s" % (time.monotonic() - start), flush=True)
        raise
    print("finished", r["status"], flush=True)
""")


@pytest.mark.parametrize("analysis", ["periodic", "lyapunov"])
def test_sigint_stops_a_long_analysis_promptly(analysis):
    p = subprocess.Popen([sys.executable, "-c", LONG_RUN, model_path("seed-scenario-2.toml"), analysis],
                         env=dict(os.environ), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "running"
        time.sleep(1.0)
        sent = time.monotonic()
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=60)
        waited = time.monotonic() - sent
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    assert "KeyboardInterrupt" in err and "interrupted after" in out and "finished" not in out, (out, err)
    assert p.returncode == -signal.SIGINT
    assert waited < 2.0, waited
