"""Every bad argument of every public function raises hsnc.InputError naming
the argument and saying what is allowed -- never pybind11's RuntimeError or
TypeError, an OverflowError, a folder named "None", or a NaN taken for "not
given". Each row is refused before anything runs."""

import math
import pathlib
import re

import numpy as np
import pytest

import hsnc
from conftest import model_path

NAN, INF = math.nan, math.inf
HUGE = 10**400  # beyond double (float() raises OverflowError)
BIG = 2**70     # beyond std::size_t

# Where the library's message names an option by its field, not the Python argument.
FIELD = {"precision": "precision_digits", "tol": "tolerance"}


def bad_numbers(*extra):
    """Values that are not a finite number."""
    return [NAN, INF, -INF, HUGE, True, "1", [1.0], 1j] + list(extra)


def bad_counts(*extra):
    """Values that are not an integer in range."""
    return [BIG, -BIG, 1.5, INF, NAN, True, "1", None] + list(extra)


def bad_dicts(name):
    """Bad set/x0/v0 dicts for an override of `name`."""
    return [1, "%s=1" % name, [(name, 1.0)], {name: None}, {name: NAN}, {name: INF}, {name: HUGE}, {name: True},
            {1: 1.0}, {None: 1.0}, {name + "=2": 1.0}, {name: "1\0garbage"}, {name: [1.0]}]


def rows(function, argument, values):
    return [pytest.param(function, argument, v, id="%s-%s-%d" % (function, argument, i)) for i, v in enumerate(values)]


TABLE = (
    rows("simulate", "model", [None, "models/bilinear-1dof.toml"])
    + rows("simulate", "t_end", bad_numbers(-1.0, 0.0))
    + rows("simulate", "dt", bad_numbers(0.0, -1.0, 1e-300, 5e-324))
    + rows("simulate", "method", [None, 1, "euler", "hsnc\0"])
    + rows("simulate", "kernels", [None, 3, "fast", "aot\0"])
    + rows("simulate", "precision", [None, 5, "mp:5", "mp:30\0"])
    + rows("simulate", "x0", bad_dicts("m1") + [{"nope": 1.0}])
    + rows("simulate", "v0", bad_dicts("m1"))
    + rows("simulate", "max_events", bad_counts(-1))
    + rows("simulate", "h", bad_numbers())
    + rows("simulate", "rtol", bad_numbers(None, 0.0, -1.0))
    + rows("simulate", "atol", bad_numbers(None, 0.0))
    + rows("simulate", "cache_dir", [1, b"a\0b", "a\0b", ["dir"]])
    + rows("simulate", "use_cache", [None, "yes", 1, 0.0])
    + rows("simulate", "tier_evaluations", bad_counts(0, -1))
    + rows("simulate", "allow_large_output", [None, "yes", 1])
    + rows("generate", "model", [None, "models/bilinear-1dof.toml"])
    + rows("generate", "directory", [None, "", 1, "a\0b", ["out"]])
    + rows("from_file", "path", [None, "", 1, "a\0b", b"a\0b", ["models/bilinear-1dof.toml"]])
    + rows("from_file", "set", bad_dicts("k1") + [{"nope": 1.0}])
    + rows("from_file", "x0", bad_dicts("m1"))
    + rows("from_file", "v0", bad_dicts("m1"))
    + rows("from_string", "text", [None, 1, b"name = 'x'", "name = 'x'\0", "\ud800"])
    + rows("from_string", "source", [None, 1, "a\0b"])
    + rows("from_string", "set", bad_dicts("k1"))
    + rows("from_string", "x0", bad_dicts("m1"))
    + rows("from_string", "v0", bad_dicts("m1"))
    + rows("with_overrides", "set", bad_dicts("k1"))
    + rows("with_overrides", "x0", bad_dicts("m1"))
    + rows("with_overrides", "v0", bad_dicts("m1"))
    + rows("sweep", "model", [None, "models/seed-scenario-1.toml"])
    + rows("sweep", "param", [None, 1, "", "nope", "F1\0"])
    + rows("sweep", "start", bad_numbers(None))
    + rows("sweep", "stop", bad_numbers(None))
    + rows("sweep", "points", bad_counts(0, -5, 10**9))
    + rows("sweep", "direction", [None, 1, "sideways"])
    + rows("sweep", "max_periods", bad_counts(0, -1))
    + rows("sweep", "record_periods", bad_counts(0, -1))
    + rows("sweep", "restart_each", [None, "yes", 1])
    + rows("sweep", "param2", [1, "nope", "F1"])
    + rows("sweep", "values2", ["12", 1, {"a": 1.0}, [NAN], [None], [HUGE], [True]])
    + rows("sweep", "threads", bad_counts(-1, 2**33))
    + rows("sweep", "method", [None, 1, "euler"])
    + rows("sweep", "rtol", bad_numbers(None, 0.0))
    + rows("sweep", "atol", bad_numbers(None, -1.0))
    + rows("sweep", "continuation", [None, "yes", 1])
    + rows("sweep", "max_steps", bad_counts(-1, 7))
    + rows("periodic", "model", [None, "models/seed-scenario-1.toml"])
    + rows("periodic", "period", bad_numbers(0.0, -1.0))
    + rows("periodic", "harmonic", bad_counts(0, -1, 2**31))
    + rows("periodic", "transient", bad_numbers(-1.0))
    + rows("periodic", "tol", bad_numbers(0.0, -1.0))
    + rows("periodic", "max_iterations", bad_counts(-1, 2**31))
    + rows("periodic", "dt", bad_numbers(0.0, -1.0, 1e-300))
    + rows("periodic", "kernels", [None, 1, "fast"])
    + rows("periodic", "x0", bad_dicts("m1"))
    + rows("periodic", "v0", bad_dicts("m2"))
    + rows("periodic", "allow_large_output", [None, "yes", 1])
    + rows("lyapunov", "model", [None, "models/seed-scenario-1.toml"])
    + rows("lyapunov", "t_end", bad_numbers(None, 0.0, -1.0))
    + rows("lyapunov", "transient", bad_numbers(-1.0))
    + rows("lyapunov", "row_interval", bad_numbers(0.0, -1.0, 1e-300))
    + rows("lyapunov", "kernels", [None, 1, "fast"])
    + rows("lyapunov", "x0", bad_dicts("m1"))
    + rows("lyapunov", "v0", bad_dicts("m1"))
    + rows("lyapunov", "allow_large_output", [None, "yes", 1])
)


@pytest.fixture(scope="module")
def models():
    return {"bilinear": hsnc.Model.from_file(model_path("bilinear-1dof.toml")),
            "forced": hsnc.Model.from_file(model_path("seed-scenario-1.toml"))}


def call(function, argument, value, models, tmp_path):
    """The function with good arguments but `argument` = value."""
    bilinear_text = open(model_path("bilinear-1dof.toml")).read()
    if function == "simulate":
        kwargs = {"model": models["bilinear"], "t_end": 1.0}
        kwargs[argument] = value
        return hsnc.simulate(**kwargs)
    if function == "generate":
        kwargs = {"model": models["bilinear"], "directory": tmp_path / "kernels"}
        kwargs[argument] = value
        return hsnc.generate(**kwargs)
    if function == "from_file":
        kwargs = {"path": model_path("bilinear-1dof.toml")}
        kwargs[argument] = value
        return hsnc.Model.from_file(**kwargs)
    if function == "from_string":
        kwargs = {"text": bilinear_text}
        kwargs[argument] = value
        return hsnc.Model.from_string(**kwargs)
    if function == "with_overrides":
        return models["bilinear"].with_overrides(**{argument: value})
    if function == "sweep":
        kwargs = {"model": models["forced"], "param": "F1", "start": 1.0, "stop": 2.0, "points": 2}
        kwargs[argument] = value
        if argument == "values2":
            kwargs["param2"] = "F2"
        return hsnc.sweep(**kwargs)
    if function == "periodic":
        kwargs = {"model": models["forced"]}
        kwargs[argument] = value
        return hsnc.periodic(**kwargs)
    if function == "lyapunov":
        kwargs = {"model": models["forced"], "t_end": 1.0}
        kwargs[argument] = value
        return hsnc.lyapunov(**kwargs)
    raise AssertionError(function)


@pytest.mark.parametrize("function, argument, value", TABLE)
def test_bad_argument_is_input_error_naming_it(function, argument, value, models, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # generate(model, "") wrote its files into the working directory, (model, 1) into ./1
    with pytest.raises(hsnc.InputError) as e:
        call(function, argument, value, models, tmp_path)
    message = str(e.value)
    assert isinstance(e.value, ValueError)  # hsnc.InputError stays a ValueError
    names = "|".join(re.escape(n) for n in (argument, FIELD.get(argument, argument)))
    assert re.search(r"(?<![A-Za-z0-9_])(%s)(?![A-Za-z0-9_])" % names, message), message
    assert re.search(r"expected|must|required|no parameter|no mass|unknown|not |larger than|only|is the|the limit is", message), message
    assert list(tmp_path.iterdir()) == []  # nothing written: no ./None, no kernels


def test_nan_t_end_is_refused_not_taken_for_the_model_default(models):
    """t_end=nan ran the file's t_end (10 s) silently; the CLI refuses --t-end nan."""
    with pytest.raises(hsnc.InputError, match=r"hsnc.simulate\(\): t_end = nan: expected a finite number"):
        hsnc.simulate(models["bilinear"], t_end=NAN)
    assert hsnc.simulate(models["bilinear"], t_end=None).summary["t"] == 10.0  # None: the model's t_end


def test_generate_none_directory_writes_nothing(models, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(hsnc.InputError, match=r"hsnc.generate\(\): directory = None: expected a path"):
        hsnc.generate(models["bilinear"], None)
    assert list(tmp_path.iterdir()) == []


def test_good_arguments_of_other_types_are_taken(tmp_path):
    """NumPy numbers, integral floats, path objects and expressions as texts stay accepted."""
    model = hsnc.Model.from_file(pathlib.Path(model_path("bilinear-1dof.toml")),
                                 set={"k1": np.float64(4.0), "k2": "3 * 4"}, x0={"m1": np.int64(0)})
    r = hsnc.simulate(model, t_end=np.float64(1.0), dt=np.float32(0.5), max_events=np.int64(0),
                      use_cache=np.bool_(True), tier_evaluations=1000.0, cache_dir=tmp_path / "cache")
    assert list(r.t) == [0.0, 0.5, 1.0]
    assert model.parameters["k2"] == 12.0
    forced = hsnc.Model.from_file(model_path("seed-scenario-1.toml"))
    r = hsnc.sweep(forced, "F1", np.int64(22000), 22500.0, np.int32(2), max_periods=3.0, record_periods=np.uint8(1),
                   restart_each=np.bool_(True), rtol=np.float32(1e-6))
    assert list(r["value"]) == [22000.0, 22500.0]


def test_from_string_refuses_text_beyond_the_model_file_limit():
    """As `hsnc check` refuses a model file over 16 MiB (model/file_read.h
    kMaxModelFileBytes), counted in UTF-8 bytes, not characters."""
    limit = 16 << 20
    text = open(model_path("bilinear-1dof.toml")).read()
    padded = text + "#" * (limit - len(text.encode()) - 1) + "\n"  # exactly the limit: read
    assert len(padded.encode()) == limit
    assert hsnc.Model.from_string(padded).name == "bilinear-1dof"
    message = r"hsnc.Model.from_string\(\): text: larger than 16777216 bytes \(UTF-8\), the limit of a model file"
    with pytest.raises(hsnc.InputError, match=message):
        hsnc.Model.from_string(padded + "\n")
    wide = text + "#" + "\u00e9" * ((limit - len(text)) // 2)  # fewer characters than the limit, more bytes
    assert len(wide) < limit < len(wide.encode())
    with pytest.raises(hsnc.InputError, match=message):
        hsnc.Model.from_string(wide)
