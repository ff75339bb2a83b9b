"""hsnc.sweep_map: the built-in sweep's points (each from the initial state)
run by any map -- the built-in one, a pool of worker processes, Dask -- give
the built-in sweep's result, the same doubles."""

import concurrent.futures
import multiprocessing

import numpy as np
import pytest

import hsnc
from conftest import SOURCE_DIR

DAMPER = str(SOURCE_DIR / "examples" / "jenkins" / "friction_damper.toml")
ARGS = ("omega", 8.0, 12.0, 7)
OPTIONS = dict(max_periods=60, record_periods=4, harmonics=3)


def builtin():
    return hsnc.sweep(hsnc.Model.from_file(DAMPER), *ARGS, restart_each=True, **OPTIONS)


def same(a, b):
    assert a["param"] == b["param"] and a["param2"] == b["param2"] and a["masses"] == b["masses"]
    for key in ("value", "value2", "direction", "settled", "escaped", "periods", "multiple", "xmax", "xrms", "a1", "amp",
                "phase"):
        assert np.array_equal(a[key], b[key], equal_nan=key not in ("direction",)), key
    for key in a["diagram"]:
        assert np.array_equal(a["diagram"][key], b["diagram"][key], equal_nan=key != "direction"), key
    assert a["failure"] == b["failure"]


def test_the_builtin_map_gives_the_builtin_sweep():
    r = hsnc.sweep_map(hsnc.Model.from_file(DAMPER), *ARGS, **OPTIONS)
    assert len(r["value"]) == 7 and r["value"][0] == 8.0 and r["value"][-1] == 12.0
    same(r, builtin())


def test_a_pool_of_processes_gives_the_builtin_sweep():
    with concurrent.futures.ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as pool:
        r = hsnc.sweep_map(hsnc.Model.from_file(DAMPER), *ARGS, map=pool.map, **OPTIONS)
    same(r, builtin())


def test_dask_gives_the_builtin_sweep():
    bag = pytest.importorskip("dask.bag")

    def dask_map(function, items):
        return bag.from_sequence(list(items), npartitions=3).map(function).compute(scheduler="processes",
                                                                                     num_workers=2)

    r = hsnc.sweep_map(hsnc.Model.from_file(DAMPER), *ARGS, map=dask_map, **OPTIONS)
    same(r, builtin())


def test_bad_arguments_are_refused_by_name():
    model = hsnc.Model.from_file(DAMPER)
    with pytest.raises(hsnc.InputError, match="map"):
        hsnc.sweep_map(model, *ARGS, map="pool")
    with pytest.raises(hsnc.InputError, match="points"):
        hsnc.sweep_map(model, "omega", 8.0, 12.0, 0)
    with pytest.raises(hsnc.InputError, match="nothing"):
        hsnc.sweep_map(model, "nothing", 8.0, 12.0, 3)
