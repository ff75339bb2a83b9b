"""The run releases the GIL: two runs in two Python threads give what they
give one after the other, and Ctrl-C (SIGINT) stops a long run with
KeyboardInterrupt, promptly, without a result."""

import signal
import threading
import time

import numpy as np

import hsnc
from conftest import interrupt_long_run, model_path


def run_pair():
    a = hsnc.Model.from_file(model_path("seed-scenario-2.toml"))
    b = hsnc.Model.from_file(model_path("seed-scenario-1.toml"), set={"F1": 2.5})
    return [(a, dict(t_end=200, dt=0.01)), (b, dict(t_end=200, dt=0.01, kernels="generic"))]


def test_two_threads_equal_sequential_runs():
    jobs = run_pair()
    sequential = [hsnc.simulate(m, **kw) for m, kw in jobs]
    results = [None, None]
    errors = []
    start = threading.Barrier(2)

    def work(i):
        try:
            start.wait()
            results[i] = hsnc.simulate(jobs[i][0], **jobs[i][1])
        except BaseException as e:  # reported below
            errors.append(e)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    assert not errors and all(r is not None for r in results)
    for r, s in zip(results, sequential):
        assert len(s.events) > 100
        assert np.array_equal(r.t, s.t) and np.array_equal(r.x, s.x) and np.array_equal(r.v, s.v)
        assert np.array_equal(r.events.t, s.events.t) and np.array_equal(r.events.x, s.events.x)
        assert r.summary == s.summary


def test_gil_is_released_while_running():
    # A Python thread keeps counting while a run goes on in another one.
    model = hsnc.Model.from_file(model_path("seed-scenario-2.toml"))
    done = threading.Event()
    ticks = []

    def count():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    counter = threading.Thread(target=count)
    counter.start()
    try:
        t0 = time.perf_counter()
        # Long enough to span many ticks on a fast machine: 3000 s took 0.048 s
        # on one, under the 0.05 s this test needs to tell anything.
        r = hsnc.simulate(model, t_end=30000)
        t1 = time.perf_counter()
    finally:
        done.set()
        counter.join()
    assert r.summary["status"] == "ok" and len(r.events) > 10000
    during = [t for t in ticks if t0 < t < t1]
    # With the GIL held for the whole run the counter would not tick at all.
    assert t1 - t0 > 0.05 and len(during) >= 5, (t1 - t0, len(during))


def test_sigint_raises_keyboard_interrupt_promptly():
    out, err, code, waited = interrupt_long_run("hsnc.simulate(model, t_end=1e7)", model_path("seed-scenario-2.toml"),
                                                0.5, 20)
    # Python's default handler: KeyboardInterrupt and a traceback; an uncaught
    # KeyboardInterrupt ends the interpreter by SIGINT itself (Python >= 3.8).
    assert "KeyboardInterrupt" in err and "interrupted after" in out and "finished" not in out, (out, err)
    assert code == -signal.SIGINT
    assert waited < 2.0, waited
