"""Shared helpers: the built `hsnc` executable and the source tree (ctest
sets HSNC_BINARY and HSNC_SOURCE_DIR; run by hand they default to build/hsnc
and this checkout)."""

import csv
import os
import pathlib
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("HSNC_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
BINARY = pathlib.Path(os.environ.get("HSNC_BINARY", SOURCE_DIR / "build" / "hsnc"))


# Two masses, a contact and friction: the model of test_model.py and test_pickle.py.
TWO_MASS = """
name = "pair"
description = "two masses, a contact and friction"
[parameters]
k = 4
kc = "3 * k"
[[mass]]
name = "left"
m = 1
[[mass]]
name = "right"
m = 2
mu_k = 0.1
mu_s = 0.2
[[spring]]
between = ["left", "ground"]
k = "k"
[[spring]]
between = ["left", "right"]
k = "k"
[[contact]]
name = "stop"
between = ["right", "ground"]
gap = 0.05
k = "kc"
[initial]
x = { left = 2.0 }
[simulate]
t_end = 4
"""


def model_path(name):
    return str(SOURCE_DIR / "models" / name)


def run_cli(*args, check=True):
    """Runs `hsnc ARGS...`; returns the CompletedProcess (text)."""
    p = subprocess.run([str(BINARY), *map(str, args)], capture_output=True, text=True, timeout=120)
    if check and p.returncode != 0:
        raise AssertionError("hsnc %s: exit %d: %s" % (" ".join(map(str, args)), p.returncode, p.stderr))
    return p


def read_csv(path):
    """Header and rows of a CSV, cells as text."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def numbers(rows, columns):
    """The cells of `columns` as floats: float(text) of a 17-digit number is that double exactly."""
    return np.array([[float(r[c]) for c in columns] for r in rows], dtype=float).reshape(len(rows), len(columns))


@pytest.fixture
def cli():
    if not BINARY.exists():
        pytest.fail("no hsnc executable at %s (set HSNC_BINARY)" % BINARY)
    return run_cli


def interrupt_long_run(call, model, delay, timeout):
    """Runs `result = CALL` (Python text; `model` is hsnc.Model.from_file(MODEL),
    `hsnc` imported) in a fresh interpreter, sends SIGINT `delay` s after the
    run started, and returns (stdout, stderr, returncode, seconds from the
    signal to the end). The script prints "interrupted after S s" when the run
    raises KeyboardInterrupt (then re-raised) and "finished" when it returns."""
    script = textwrap.dedent("""
        import sys, time
        import hsnc
        model = hsnc.Model.from_file(sys.argv[1])
        print("running", flush=True)
        start = time.monotonic()
        try:
            result = %s
        except KeyboardInterrupt:
            print("interrupted after %%.3f s" %% (time.monotonic() - start), flush=True)
            raise
        print("finished", flush=True)
    """) % call
    p = subprocess.Popen([sys.executable, "-c", script, model], env=dict(os.environ), stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "running"
        time.sleep(delay)
        sent = time.monotonic()
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=timeout)
        waited = time.monotonic() - sent
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    return out, err, p.returncode, waited
