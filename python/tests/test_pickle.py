"""Models and results travel: pickled, and through a pool of worker processes."""

import concurrent.futures
import multiprocessing
import pickle

import numpy as np
import pytest

import hsnc
from conftest import TWO_MASS, model_path


def same_run(a, b):
    assert np.array_equal(a.t, b.t) and np.array_equal(a.x, b.x) and np.array_equal(a.v, b.v)
    assert np.array_equal(a.events.t, b.events.t) and list(a.events.kind) == list(b.events.kind)
    assert a.summary["x"] == b.summary["x"]


def run(model):
    return hsnc.simulate(model, dt=0.01)


def test_a_model_from_text_comes_back_with_its_overrides():
    m = hsnc.Model.from_string(TWO_MASS, source="pair.toml", set={"k": 5.5}, x0={"right": 0.01})
    back = pickle.loads(pickle.dumps(m))
    assert back.parameters["k"] == 5.5 and back.x0[1] == 0.01 and back.source == "pair.toml"
    same_run(run(m), run(back))


def test_a_model_from_a_file_comes_back_and_refuses_a_changed_file(tmp_path):
    path = tmp_path / "pair.toml"
    path.write_text(TWO_MASS)
    m = hsnc.Model.from_file(str(path), set={"k": 3})
    data = pickle.dumps(m)
    same_run(run(m), run(pickle.loads(data)))
    path.write_text(TWO_MASS.replace("gap = 0.05", "gap = 0.06"))
    with pytest.raises(hsnc.InputError, match="the file changed since the model was pickled"):
        pickle.loads(data)


def test_a_result_pickles():
    r = run(hsnc.Model.from_file(model_path("seed-scenario-1.toml")))
    back = pickle.loads(pickle.dumps(r))
    same_run(r, back)
    assert back.masses == r.masses and back.summary == r.summary


def test_two_worker_processes_give_the_bits_of_the_run_in_process():
    models = [hsnc.Model.from_string(TWO_MASS, set={"k": k}) for k in (3.0, 4.0, 5.0)]
    here = [run(m) for m in models]
    with concurrent.futures.ProcessPoolExecutor(max_workers=2, mp_context=multiprocessing.get_context("spawn")) as pool:
        there = list(pool.map(run, models))
    for a, b in zip(here, there):
        same_run(a, b)
