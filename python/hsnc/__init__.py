"""hsnc: the exact response of piecewise-linear mechanical systems with
contacts and Coulomb friction, from Python (interface.md section 7).

    import hsnc
    model = hsnc.Model.from_file("models/seed-scenario-2.toml", set={"F1": 2.0})
    r = hsnc.simulate(model, t_end=60, dt=0.01)
    r.t, r.x, r.v          # NumPy: (N,), (N, n_mass), (N, n_mass)
    r.events               # record array: t, kind, element, x, v
    r.summary["status"]    # "ok"

The samples are those of `hsnc simulate --dt` (default (t_end - t0) / 1000)
and equal its CSV numbers bit for bit. The run releases the GIL (other
Python threads carry on, two runs may go in parallel) and stops on Ctrl-C
with KeyboardInterrupt. Bad input raises InputError (a ValueError), a
failure while running RunError (a RuntimeError), with the library's message.
"""

import collections.abc
import hashlib
import math
import operator
import os
import re

import numpy as np

from . import _hsnc
from ._hsnc import InputError, RunError

__all__ = ["InputError", "Model", "Result", "RunError", "generate", "lyapunov", "modes", "periodic", "rotation_number",
           "simulate", "sweep", "sweep_map"]


# Argument checks. Every argument is checked here for what the native part
# cannot take (a type, a NaN or an infinity, an integer beyond its C++ type,
# a NUL in a text) and refused as InputError naming it and saying what is
# allowed; what depends on the model (t_end after t0, a parameter that
# exists, ...) is the library's check, with the message the CLI prints.
# Numbers are int, float or NumPy numbers; a bool is not a number here.

_REQUIRED = object()
_SIZE_MAX = 2**64 - 1  # std::size_t, std::uint64_t
_UINT_MAX = 2**32 - 1  # unsigned
_INT_MAX = 2**31 - 1   # int
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")  # a name of the model (interface.md section 1)


def _show(value):
    try:
        text = repr(value)
    except Exception:  # an int beyond sys.get_int_max_str_digits() has no repr
        text = "<%s>" % type(value).__name__
    return text if len(text) <= 60 else text[:57] + "..."


def _refuse(function, name, value, allowed):
    raise InputError("%s(): %s = %s: expected %s" % (function, name, _show(value), allowed))


def _real(function, name, value, default=_REQUIRED, allowed="a finite number"):
    """value as a finite float; None is `default` (not given) unless required."""
    if value is None and default is not _REQUIRED:
        return default
    if not isinstance(value, (bool, np.bool_, str, bytes)):
        try:
            number = float(value)
        except (TypeError, ValueError, OverflowError):  # float(10**400): OverflowError
            pass
        else:
            if math.isfinite(number):
                return number
    _refuse(function, name, value, allowed)


def _positive(function, name, value):
    number = _real(function, name, value, allowed="a finite number > 0")
    if number > 0:
        return number
    _refuse(function, name, value, "a finite number > 0")


def _int(function, name, value, low, high, allowed=None):
    """value as an int in [low, high] (an integral float is taken: 3.0 is 3)."""
    if not isinstance(value, (bool, np.bool_)):
        try:
            number = operator.index(value)
        except TypeError:
            number = int(value) if isinstance(value, float) and value.is_integer() else None
        if number is not None and low <= number <= high:
            return number
    _refuse(function, name, value, allowed or "an integer >= %d (at most %s)" % (
        low, {_SIZE_MAX: "2**64 - 1", _UINT_MAX: "2**32 - 1", _INT_MAX: "2**31 - 1"}.get(high, high)))


def _bool(function, name, value):
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    _refuse(function, name, value, "True or False")


def _text(function, name, value, allowed="a str"):
    """A str the C++ part takes whole: UTF-8 (no lone surrogate), no NUL."""
    if isinstance(value, str):
        try:
            value.encode()
        except UnicodeEncodeError:
            _refuse(function, name, value, allowed + " (encodable as UTF-8)")
        if "\0" not in value:
            return value
        _refuse(function, name, value, allowed + " (without NUL characters)")
    _refuse(function, name, value, allowed)


def _path(function, name, value, allowed="a path (str or os.PathLike)"):
    """A file system path as str; a NUL would cut it short in the C++ part."""
    try:
        path = os.fsdecode(os.fspath(value))
    except TypeError:
        _refuse(function, name, value, allowed)
    if path and "\0" not in path:
        try:
            path.encode()
            return path
        except UnicodeEncodeError:  # undecodable bytes (os.fsdecode's surrogates)
            _refuse(function, name, value, allowed + " (encodable as UTF-8)")
    _refuse(function, name, value, allowed + (" (not empty)" if not path else " (without NUL characters)"))


def _overrides(function, name, value):
    """set, x0 or v0: {name: number or expression}, values a finite float or a str."""
    if value is None:
        return {}
    if not isinstance(value, collections.abc.Mapping):
        _refuse(function, name, value, "a dict {name: number or expression str}")
    out = {}
    for key, item in value.items():
        if not isinstance(key, str) or not _NAME.match(key):
            raise InputError("%s(): %s key %s: expected a name (str: letters, digits, _)" % (function, name, _show(key)))
        if isinstance(item, str):
            out[key] = _text(function, "%s[%r]" % (name, key), item, "a finite number or an expression str")
        else:
            out[key] = _real(function, "%s[%r]" % (name, key), item, allowed="a finite number or an expression str")
    return out


def _model(function, model):
    if not isinstance(model, Model):
        raise InputError("%s(): model = %s: expected an hsnc.Model" % (function, _show(model)))
    return model


_METHODS = "a str: 'hsnc', 'ab4', 'rk45' or 'cvode'"
_KERNELS = "a str: 'auto', 'aot', 'generic', 'interp', 'eigen', 'jit' or 'tiered'"


def _bytes_text(size):
    units = ["B", "kB", "MB", "GB", "TB", "PB", "EB"]
    u = 0
    while size >= 1000 and u < len(units) - 1:
        size /= 1000
        u += 1
    return "%.3g %s" % (size, units[u])


def _output_guard(function, name, value, rows, width, allow, shorter):
    """The CLI's output guard (output/simulate_outputs.h, --allow-large-output)
    on what a call collects in memory: `rows` rows of `width` doubles. Checked
    before the run, so a dt of 1e-300 is refused instead of filling memory."""
    if allow:
        return
    size = rows * width * 8.0
    if rows > _hsnc._LARGE_OUTPUT_ROWS or size > _hsnc._LARGE_OUTPUT_BYTES:
        raise InputError("%s(): %s = %.3g: the result would have %.3g rows, about %s (the limit is 1e7 rows or 1 GB): "
                         "give a larger %s or a shorter %s, or allow_large_output=True to collect it anyway"
                         % (function, name, value, rows, _bytes_text(size), name, shorter))


class Model:
    """A validated model. Read-only views: name, description, source,
    masses, contacts, friction_masses (names, in model order), parameters
    (a dict in file order, with their values after overrides), mass_values,
    t0, t_end (None when the file has none), x0, v0 (NumPy), dof."""

    def __init__(self, native, read):
        self._native = native
        self._read = read  # (function, argument, overrides) to read it again

    @classmethod
    def from_file(cls, path, *, set=None, x0=None, v0=None):
        """Read and validate a model file. set, x0, v0: dicts {name: value}
        overriding parameters and the initial state (as `hsnc simulate --set
        --x0 --v0`); a value may be a number or an expression string."""
        f = "hsnc.Model.from_file"
        path = _path(f, "path", path)
        overrides = (_overrides(f, "set", set), _overrides(f, "x0", x0), _overrides(f, "v0", v0))
        native = _hsnc.Model.from_file(path, set=overrides[0], x0=overrides[1], v0=overrides[2])
        return cls(native, ("file", path, "", overrides))

    @classmethod
    def from_string(cls, text, *, source="<string>", set=None, x0=None, v0=None):
        """Read a model from TOML text; `source` names it in messages. Text
        of more than 16 MiB (in UTF-8) is refused, as a model file is."""
        f = "hsnc.Model.from_string"
        limit = _hsnc._MAX_MODEL_BYTES
        # len(text) <= its UTF-8 size: a huge text is refused before it is encoded (by _text).
        if isinstance(text, str) and len(text) > limit or len(_text(f, "text", text, "a str (TOML)").encode()) > limit:
            raise InputError("%s(): text: larger than %d bytes (UTF-8), the limit of a model file" % (f, limit))
        source = _text(f, "source", source)
        overrides = (_overrides(f, "set", set), _overrides(f, "x0", x0), _overrides(f, "v0", v0))
        native = _hsnc.Model.from_string(text, source=source, set=overrides[0], x0=overrides[1], v0=overrides[2])
        return cls(native, ("text", text, source, overrides))

    def with_overrides(self, *, set=None, x0=None, v0=None):
        """The same model read again with these overrides added to its own."""
        f = "hsnc.Model.with_overrides"
        kind, what, source, (s0, x00, v00) = self._read
        s, x, v = dict(s0), dict(x00), dict(v00)
        s.update(_overrides(f, "set", set))
        x.update(_overrides(f, "x0", x0))
        v.update(_overrides(f, "v0", v0))
        if kind == "file":
            return Model.from_file(what, set=s, x0=x, v0=v)
        return Model.from_string(what, source=source, set=s, x0=x, v0=v)

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        return getattr(self._native, name)

    def __repr__(self):
        return repr(self._native)

    def __reduce__(self):
        """Pickled as it was read (the file's path, or the text, and the
        overrides): unpickling reads it again, so the workers of a pool get
        the same model. A file model carries the SHA-256 of its file's bytes,
        and a file that changed since is refused where it is unpickled
        (matrix files a [structure] names are read again as they are)."""
        kind, what, source, overrides = self._read
        if kind == "file":
            what = os.path.abspath(what)  # a worker may run elsewhere
        digest = _file_digest(what) if kind == "file" else None
        return (_unpickle_model, (kind, what, source, overrides, digest))


def _file_digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def _unpickle_model(kind, what, source, overrides, digest):
    s, x, v = (dict(o) for o in overrides)
    if kind == "text":
        return Model.from_string(what, source=source, set=s, x0=x, v0=v)
    try:
        now = _file_digest(what)
    except OSError as e:
        raise InputError("hsnc.Model (unpickled): %s: cannot read the model file: %s" % (what, e.strerror)) from None
    if now != digest:
        raise InputError("hsnc.Model (unpickled): %s: the file changed since the model was pickled" % what)
    return Model.from_file(what, set=s, x0=x, v0=v)


class Result:
    """One run: `t` (N,), `x` and `v` (N, n_mass) NumPy arrays, one row per
    sample; `events`, a NumPy record array with fields t, kind, element, x,
    v (x and v of length n_mass: the state at the switch); `summary`, a dict
    (status, t, events, counts per kind, segments, restarts (the segments
    carried over a switch), evaluations, configurations, solver, x and v at
    the end by mass name, slider by Jenkins element, ...); `masses` names the columns of x and v. A model
    with Jenkins elements also gives `s` (N, n_jenkins), their sliders'
    positions, named by `jenkins` (events gain the field s too)."""

    def __init__(self, t, x, v, events, summary, masses, s=None, jenkins=()):
        self.t = t
        self.x = x
        self.v = v
        self.events = events
        self.summary = summary
        self.masses = masses
        self.s = s if s is not None else np.zeros((len(t), 0))
        self.jenkins = list(jenkins)

    def __repr__(self):
        return "<hsnc.Result status=%s t=%r: %d samples, %d events>" % (
            self.summary["status"], self.summary["t"], len(self.t), len(self.events))


def _events(raw, n, nj=0):
    kinds, elements = raw["event_kind"], raw["event_element"]
    width = lambda names: max([1] + [len(s) for s in names])
    fields = [("t", "f8"), ("kind", "U%d" % width(kinds)), ("element", "U%d" % width(elements)),
              ("x", "f8", (n,)), ("v", "f8", (n,))]
    if nj:
        fields.append(("s", "f8", (nj,)))
    dtype = np.dtype(fields)
    events = np.zeros(len(kinds), dtype=dtype)
    events["t"] = raw["event_t"]
    events["kind"] = kinds
    events["element"] = elements
    events["x"] = raw["event_x"]
    events["v"] = raw["event_v"]
    if nj:
        events["s"] = raw["event_s"]
    return events.view(np.recarray)


def simulate(model, t_end=None, dt=None, method="hsnc", kernels="auto", precision="double", x0=None, v0=None,
             max_events=0, h=None, rtol=1e-10, atol=1e-12, cache_dir="", use_cache=True, tier_evaluations=200000,
             allow_large_output=False):
    """Run `model` (a Model) from its initial state to `t_end` (default: the
    model's [simulate].t_end) and return a Result.

    dt: sample spacing (default (t_end - t0) / 1000); method: "hsnc" (exact),
    "ab4" (needs h), "rk45", "cvode" (rtol, atol); kernels: "auto", "aot",
    "generic" (= "interp"), "eigen", "jit", "tiered" (cache_dir, use_cache; tiered also
    tier_evaluations, as `--tier-evaluations`); precision: "double" or "mp:N";
    x0, v0: dicts {mass name: value} overriding the initial state (as
    `hsnc simulate --x0 --v0`: the model is read again with them);
    max_events: stop after that many switch events (0: no limit; the result
    then has status "max_events"). More than 1e7 samples, or about 1 GB of
    them, are refused before the run (as `hsnc simulate --out`) unless
    allow_large_output=True."""
    f = "hsnc.simulate"
    model = _model(f, model)
    x0, v0 = _overrides(f, "x0", x0), _overrides(f, "v0", v0)
    t_end = _real(f, "t_end", t_end, math.nan, "a finite number (None: the model's [simulate].t_end)")
    dt = _real(f, "dt", dt, math.nan, "a finite number > 0 (None: (t_end - t0) / 1000)")
    method = _text(f, "method", method, _METHODS)
    kernels = _text(f, "kernels", kernels, _KERNELS)
    precision = _text(f, "precision", precision, "a str: 'double' or 'mp:N'")
    max_events = _int(f, "max_events", max_events, 0, _SIZE_MAX, "an integer >= 0 (0: no limit; at most 2**64 - 1)")
    h = _real(f, "h", h, math.nan, "a finite number > 0 (the ab4 step; None: not given)")
    rtol = _real(f, "rtol", rtol, allowed="a finite number > 0")
    atol = _real(f, "atol", atol, allowed="a finite number > 0")
    cache_dir = "" if cache_dir is None or cache_dir == "" else _path(f, "cache_dir", cache_dir,
                                                                      "a path (str or os.PathLike; \"\": the default)")
    use_cache = _bool(f, "use_cache", use_cache)
    tier_evaluations = _int(f, "tier_evaluations", tier_evaluations, 1, _SIZE_MAX)
    allow_large_output = _bool(f, "allow_large_output", allow_large_output)
    if x0 or v0:
        model = model.with_overrides(x0=x0, v0=v0)
    end = t_end if not math.isnan(t_end) else model.t_end
    if not math.isnan(dt) and end is not None:
        rows = _hsnc._sample_count(model.t0, end, dt)
        _output_guard(f, "dt", dt, rows, 1 + 2 * model.dof + len(model.jenkins), allow_large_output, "t_end")
    raw = _hsnc._simulate(model._native, t_end, dt, method, kernels, precision, max_events, h, rtol, atol, cache_dir,
                          use_cache, tier_evaluations)
    masses, jenkins = model.masses, model.jenkins
    return Result(raw["t"], raw["x"], raw["v"], _events(raw, len(masses), len(jenkins)), raw["summary"], masses,
                  raw["s"], jenkins)


def generate(model, directory):
    """Write the specialised C++ kernels of `model` into `directory` (as
    `hsnc generate MODEL -o DIR`; the directory is created if needed) and
    return the names of the files written."""
    f = "hsnc.generate"
    model = _model(f, model)
    return _hsnc._generate(model._native, _path(f, "directory", directory))


def _override_texts(d):
    return ["%s=%s" % (k, v if isinstance(v, str) else repr(float(v))) for k, v in d.items()]


def sweep(model, param, start, stop, points, direction="up", max_periods=500, record_periods=16,
          restart_each=False, param2=None, values2=None, threads=1, method="hsnc", rtol=1e-10, atol=1e-12,
          continuation=False, max_steps=0, harmonics=0, branch_switch=0, track=None, escape=0,
          start_periods=0):
    """The response curve and bifurcation diagram of `model` (a Model) over
    the parameter `param`, as `hsnc sweep --param PARAM --from START --to
    STOP --points POINTS` (interface.md section 6): `points` values from
    start to stop, swept "up", "down" or "both" with state continuation (or
    every point from the initial state: restart_each), each point run to a
    steady state on the stroboscopic map (at most max_periods forcing
    periods) and recorded over record_periods periods. param2, values2: a
    second parameter, one sweep per value. threads: independent sweeps and
    points in parallel (the result does not depend on it).

    Returns a dict: "param", "param2" (None without), "masses"; one entry
    per point, in the order run: "value", "value2" (NaN without param2),
    "direction" (str), "settled" (bool), "periods" (run before recording),
    "multiple" (0 when not settled), "xmax", "xrms", "a1" (points x masses);
    "diagram": a dict with "value", "value2", "direction", "t", "x", "v"
    (x, v: rows x masses), one row per recorded period of every point;
    "failure" (str per point, "" unless its run stopped: then settled is
    False and xmax, xrms, a1 are NaN; the sweep goes on); "escaped" (bool
    per point: with escape=R > 0, as `--escape R`, a point whose
    displacement of some dof exceeds R at the end of a forcing period stops
    there, escaped and not settled; its recorded periods follow from there).

    harmonics=K > 0 (as `--harmonics K`): also "amp" and "phase" (points x
    masses x K): amplitude and phase (rad, in (-pi, pi]) of harmonics 1..K
    over the recorded periods, x_i(t) = mean + sum_k amp[., i, k-1]
    sin(k omega t + phase[., i, k-1]) + ..., omega the forcing frequency (a
    linear oscillator's phase is arg H(omega)).

    continuation=True (as `--continuation`): the periodic orbit followed
    over the parameter by pseudo-arclength continuation with exact shooting,
    through folds, from start (stop for direction "down") until the
    parameter leaves [start, stop] or after max_steps points per branch (0:
    20 * points); then also "stable" (bool), "max_multiplier" (largest
    |Floquet multiplier|), "bifurcation" (str: "", "fold", "period_doubling",
    "neimark_sacker", "grazing", "stick_onset", "slip_onset", crossed since
    the previous point, several
    joined by "+"; a grazing orbit located to rounding is a point of its
    own) and "stop" (str: why
    the branch stopped early after this point, "" when it did not).
    branch_switch=D > 0 (as `--branch-switch D`): every period doubling is
    located to rounding (a point of its own) and the branch of twice the
    period born there followed too, and theirs, up to D doublings; then also
    "branch" (int per point: 0 the primary branch, 1, 2, ... the switched
    ones in the order followed; "multiple" is each branch's period in
    forcing periods).
    start_periods=K > 0 (as `--start-periods K`, with continuation): the
    branch starts at the orbit of K forcing periods shot from the model's
    initial state at start, with no transient (a point of an earlier run:
    its state at t0 as the model's x0, v0; stable or not).
    Basins of attraction: param and param2 initial state coordinates
    ("x0.DOF" or "v0.DOF", with restart_each=True): then also "attractor"
    (int per point: 1, 2, ... the attractor it reached, numbered in the
    order first reached; 0 not settled and in no set; -1 failed; -2
    escaped) and "attractors" (a list of dicts: "multiple", "points", "x",
    "v": the canonical state; "multiple" 0 for a set that is not periodic,
    a chaotic or quasi-periodic attractor, shared by points that did not
    settle, as the CLI's --attractors).
    track="fold", "period_doubling", "neimark_sacker" or "grazing" (as
    `--track`, with param2 and values2=[q0, q1]): instead of the branch, its
    first point of that kind followed over (param, param2) from param2 = q0
    towards q1; each point of the result is a point of that curve ("value",
    "value2": both parameters; the orbit there).

    Ctrl-C (SIGINT) stops the run within a forcing period or a continuation
    step and raises KeyboardInterrupt."""
    f = "hsnc.sweep"
    kind, what, source, (s, x0, v0) = _model(f, model)._read
    param = _text(f, "param", param, "a parameter's name (str)")
    start = _real(f, "start", start)
    stop = _real(f, "stop", stop)
    points = _int(f, "points", points, 1, _SIZE_MAX)
    direction = _text(f, "direction", direction, "a str: 'up', 'down' or 'both'")
    max_periods = _int(f, "max_periods", max_periods, 1, _SIZE_MAX)
    record_periods = _int(f, "record_periods", record_periods, 1, _SIZE_MAX)
    restart_each = _bool(f, "restart_each", restart_each)
    param2 = "" if param2 is None else _text(f, "param2", param2, "a parameter's name (str) or None")
    if values2 is None:
        values2 = []
    elif isinstance(values2, (str, bytes, collections.abc.Mapping)) or not isinstance(values2, collections.abc.Iterable):
        _refuse(f, "values2", values2, "a sequence of finite numbers or None")
    else:
        values2 = [_real(f, "values2[%d]" % i, v) for i, v in enumerate(values2)]
    threads = _int(f, "threads", threads, 0, _UINT_MAX, "an integer >= 0 (0: every core; at most 2**32 - 1)")
    method = _text(f, "method", method, _METHODS)
    # As hsnc.simulate's (api/simulate.cpp): checked whatever the method, a bad one is a mistake even where unused.
    rtol = _positive(f, "rtol", rtol)
    atol = _positive(f, "atol", atol)
    continuation = _bool(f, "continuation", continuation)
    max_steps = _int(f, "max_steps", max_steps, 0, _SIZE_MAX, "an integer >= 0 (0: 20 * points; at most 2**64 - 1)")
    harmonics = _int(f, "harmonics", harmonics, 0, 1000, "an integer from 0 to 1000")
    branch_switch = _int(f, "branch_switch", branch_switch, 0, 6, "an integer from 0 to 6 (period doublings followed)")
    track = "" if track is None else _text(f, "track", track,
                                           "None or a str: 'fold', 'period_doubling', 'neimark_sacker' or 'grazing'")
    start_periods = _int(f, "start_periods", start_periods, 0, 1024, "an integer from 0 to 1024")
    escape = _real(f, "escape", escape, allowed="a finite number >= 0 (0: no bound)")
    if escape < 0:
        _refuse(f, "escape", escape, "a finite number >= 0 (0: no bound)")
    return _hsnc._sweep(kind, what, source, _override_texts(s), _override_texts(x0), _override_texts(v0),
                        param, start, stop, points, direction, max_periods, record_periods, restart_each, param2,
                        values2, threads, method, rtol, atol, continuation, max_steps, harmonics,
                        branch_switch, track, escape, start_periods)


def _sweep_point(task):
    """One point of sweep_map, where the map runs it (a process of a pool,
    a Dask worker): the built-in sweep of that single value."""
    model, param, value, options = task
    return sweep(model, param, value, value, 1, restart_each=True, **options)


def sweep_map(model, param, start, stop, points, map=map, max_periods=500, record_periods=16, method="hsnc",
              rtol=1e-10, atol=1e-12, harmonics=0):
    """hsnc.sweep(model, param, start, stop, points, restart_each=True) with
    its points run by `map` (any map(function, iterable) that keeps the order:
    the built-in map, multiprocessing.Pool.map, an Executor's map, a Dask
    bag's): each point from the model's initial state, so the points are
    independent and the result is the built-in sweep's, the same doubles
    (docs/interface.md). The model and the points' results are pickled to
    where the map runs them."""
    f = "hsnc.sweep_map"
    model = _model(f, model)
    param = _text(f, "param", param, "a parameter's name (str)")
    start = _real(f, "start", start)
    stop = _real(f, "stop", stop)
    points = _int(f, "points", points, 1, _SIZE_MAX)
    if not callable(map):
        _refuse(f, "map", map, "a callable map(function, iterable)")
    options = dict(max_periods=_int(f, "max_periods", max_periods, 1, _SIZE_MAX),
                   record_periods=_int(f, "record_periods", record_periods, 1, _SIZE_MAX),
                   method=_text(f, "method", method, _METHODS), rtol=_positive(f, "rtol", rtol),
                   atol=_positive(f, "atol", atol),
                   harmonics=_int(f, "harmonics", harmonics, 0, 1000, "an integer from 0 to 1000"))
    # The built-in sweep's values (analysis/sweep.cpp), the same double operations.
    values = [start if j == 0 else stop if j + 1 == points else start + (stop - start) * float(j) / float(points - 1)
              for j in range(points)]
    parts = list(map(_sweep_point, [(model, param, v, options) for v in values]))
    if len(parts) != points:
        raise RunError("%s(): the map returned %d results for %d points" % (f, len(parts), points))
    joined = {key: parts[0][key] for key in ("param", "param2", "masses")}
    for key in ("value", "value2", "direction", "settled", "escaped", "periods", "multiple", "xmax", "xrms", "a1") + \
            (("amp", "phase") if options["harmonics"] else ()):
        joined[key] = np.concatenate([p[key] for p in parts])
    joined["diagram"] = {key: np.concatenate([p["diagram"][key] for p in parts]) for key in parts[0]["diagram"]}
    joined["failure"] = [text for p in parts for text in p["failure"]]
    return joined


def periodic(model, period=None, harmonic=1, transient=0.0, tol=1e-10, max_iterations=50, dt=None,
             kernels="auto", x0=None, v0=None, allow_large_output=False):
    """A periodic orbit of the forced response and its stability (as
    `hsnc periodic`): Newton shooting on the period map with the exact
    monodromy matrix. Returns a dict: status ("ok" or "not_converged"),
    message, period (harmonic * T), t (time of the state), iterations,
    residual, x, v, s (the orbit's state at t, arrays; s: the Jenkins
    sliders), multipliers (complex array, largest |mu| first),
    max_multiplier, stable, neutral (multipliers of a family of orbits at +1,
    left out of stable), monodromy ((2n + nj) square array, state (x, v,
    s)), events (switches a period), grazing (grazing switch
    instants a period: the multipliers are not reliable when > 0) and orbit (dict of t, x,
    v arrays: one period sampled every dt, default period/1000; empty when not
    converged). period: default 2*pi/omega of the model's forcing;
    transient: run this long first. An orbit of more than 1e7 samples, or
    about 1 GB, is refused before the run unless allow_large_output=True.
    Ctrl-C (SIGINT) stops it promptly with KeyboardInterrupt."""
    f = "hsnc.periodic"
    model = _model(f, model)
    x0, v0 = _overrides(f, "x0", x0), _overrides(f, "v0", v0)
    period = _real(f, "period", period, math.nan, "a finite number > 0 (None: 2*pi/omega of the model's forcing)")
    harmonic = _int(f, "harmonic", harmonic, 1, _INT_MAX)
    transient = _real(f, "transient", transient, 0.0, "a finite number >= 0")
    tol = _real(f, "tol", tol, 1e-10, "a finite number > 0")
    max_iterations = _int(f, "max_iterations", max_iterations, 0, _INT_MAX)
    dt = _real(f, "dt", dt, math.nan, "a finite number > 0 (None: the period / 1000)")
    kernels = _text(f, "kernels", kernels, _KERNELS)
    allow_large_output = _bool(f, "allow_large_output", allow_large_output)
    if x0 or v0:
        model = model.with_overrides(x0=x0, v0=v0)
    span = harmonic * (period if not math.isnan(period) else _hsnc._forcing_period(model._native))
    if not math.isnan(dt) and math.isfinite(span) and span > 0:  # else the library refuses the period
        _output_guard(f, "dt", dt, _hsnc._sample_count(0.0, span, dt), 1 + 2 * model.dof, allow_large_output,
                      "period")
    return _hsnc._periodic(model._native, period, harmonic, transient, tol, max_iterations, dt, kernels)


def modes(model, stop, start=None, points=50, mode=1, dof=None, parameter="amplitude", geometric=False, tol=1e-11,
          max_iterations=30, kernels="auto"):
    """The backbone of linear mode `mode` (as `hsnc modes --to STOP --from
    START`, docs/interface.md "hsnc modes"): its
    periodic orbits continued in amplitude from the linear limit, each found
    by exact shooting with the period as an unknown. The amplitude is that of
    `dof` (a name; None: the mode shape's largest entry) from its equilibrium
    at its turning point; `points` amplitudes from start (None: stop/points)
    to stop, or energies above the equilibrium with parameter="energy"
    (a frequency-energy backbone); geometric=True spaces them in equal
    ratios. Returns a dict: status ("ok", "not_converged"), message, mode,
    dof, linear_omega, shape and equilibrium (arrays), configuration (at
    rest), others (the other modes' numbers), and a row per point found:
    amplitude, omega, period, energy, max_multiplier, residual (arrays), x, v
    (rows x n: the state at the turning point), ratios (rows x len(others):
    each other mode's frequency over the backbone's, from its multipliers),
    resonances (a list per row of the internal resonances passed, e.g.
    "mode2 2:1"), multipliers (rows x (2n + Jenkins elements) complex),
    stable, events, grazing, iterations. A model with Jenkins elements or
    Rayleigh damping gives a damped mode (damped True; the extended periodic
    motion concept, amplitudes > 0 only): xi and damping_ratio (arrays),
    sliders (rows x Jenkins elements), linear_damping_ratio. Ctrl-C (SIGINT)
    stops it promptly with KeyboardInterrupt."""
    f = "hsnc.modes"
    model = _model(f, model)
    stop = _real(f, "stop", stop)
    start = _real(f, "start", start, math.nan)
    points = _int(f, "points", points, 1, _INT_MAX)
    mode = _int(f, "mode", mode, 1, _INT_MAX)
    dof = "" if dof is None else _text(f, "dof", dof)
    if parameter not in ("amplitude", "energy"):
        _refuse(f, "parameter", parameter, "'amplitude' or 'energy'")
    geometric = _bool(f, "geometric", geometric)
    tol = _real(f, "tol", tol, 1e-11, "a finite number > 0")
    max_iterations = _int(f, "max_iterations", max_iterations, 1, _INT_MAX)
    kernels = _text(f, "kernels", kernels, _KERNELS)
    return _hsnc._modes(model._native, mode, dof, start, stop, points, parameter == "energy", geometric, tol,
                        max_iterations, kernels)


def lyapunov(model, t_end, transient=0.0, row_interval=None, kernels="auto", x0=None, v0=None,
             allow_large_output=False):
    """The Lyapunov spectrum (as `hsnc lyapunov`), by the QR method on the
    exact tangent dynamics, measured over t_end seconds after transient.
    Returns a dict: exponents (array of 2n, plus one per Jenkins element,
    1/s, largest first, -inf for directions a stick or a slip collapses), sum, t_start, t, collapsed, events,
    grazing (switch instants at a turning point of a contact's gap, or
    without a saltation matrix: the exponents are not reliable when > 0),
    singular (of them, without a saltation matrix), rows_t and rows (the running estimates every row_interval,
    default the forcing period, else 1 s; k x 2n; more than 1e7 rows, or about
    1 GB, are refused before the run unless allow_large_output=True). A run
    that stops early raises RunError; Ctrl-C (SIGINT) stops it promptly with
    KeyboardInterrupt."""
    f = "hsnc.lyapunov"
    model = _model(f, model)
    x0, v0 = _overrides(f, "x0", x0), _overrides(f, "v0", v0)
    t_end = _real(f, "t_end", t_end, allowed="a finite number > 0")
    transient = _real(f, "transient", transient, 0.0, "a finite number >= 0")
    row_interval = _real(f, "row_interval", row_interval, math.nan,
                         "a finite number > 0 (None: the period of the slowest forcing, else 1 s)")
    kernels = _text(f, "kernels", kernels, _KERNELS)
    allow_large_output = _bool(f, "allow_large_output", allow_large_output)
    if x0 or v0:
        model = model.with_overrides(x0=x0, v0=v0)
    row = row_interval if not math.isnan(row_interval) else _hsnc._default_row_interval(model._native)
    if t_end > 0 and row > 0:  # else the library refuses them
        _output_guard(f, "row_interval", row, _hsnc._sample_count(0.0, t_end, row),
                      1 + 2 * model.dof + len(model.jenkins), allow_large_output, "t_end")
    return _hsnc._lyapunov(model._native, t_end, transient, row_interval, kernels)


def rotation_number(x, v):
    """The rotation number of a stroboscopic Poincare section (as `hsnc
    simulate --section period` gives it): x and v, one dof's states at
    t0 + k T (for example simulate(model, dt=T)'s x[:, i] and v[:, i]). The
    mean turn per period about the points' centroid, clockwise in the (x, v)
    plane, in [0, 1), as a weighted Birkhoff average: omega_2/omega_1 modulo
    1 on an invariant circle (a quasi-periodic response), q/p on a periodic
    orbit of p points. Returns (value, error), error the difference between
    the two halves' averages (rounding level on an invariant circle, about
    1/sqrt(n) on a chaotic set); (nan, nan) for fewer than 8 points or a
    section whose x or v does not move."""
    f = "hsnc.rotation_number"
    arrays = []
    for name, a in (("x", x), ("v", v)):
        try:
            a = np.asarray(a, dtype=float)
        except (TypeError, ValueError):
            _refuse(f, name, a, "a 1-D sequence of finite numbers")
        if a.ndim != 1 or not np.all(np.isfinite(a)):
            _refuse(f, name, x if name == "x" else v, "a 1-D sequence of finite numbers")
        arrays.append(a)
    if arrays[0].size != arrays[1].size:
        raise InputError(f"{f}(): x and v must have the same length (got {arrays[0].size} and {arrays[1].size})")
    return _hsnc._rotation_number(arrays[0], arrays[1])


# ---- to_h5: a result with what made it, in the layout of the command line's --h5 ----

__version__ = _hsnc.__version__


def _h5_table(group, columns):
    """One dataset per column (name, values): float64, or UTF-8 strings for words; the CSV header as `columns`."""
    import h5py
    for name, values in columns:
        values = list(values) if not isinstance(values, np.ndarray) else values
        if len(values) and isinstance(values[0], str):
            group.create_dataset(name, data=np.array(values, dtype=h5py.string_dtype("utf-8")))
        else:
            group.create_dataset(name, data=np.asarray(values, dtype=np.float64).reshape(-1))
    group.attrs["columns"] = ",".join(name for name, _ in columns)


def _h5_state(names, x, v, jenkins=(), s=None):
    columns = [("x_" + m, x[:, i]) for i, m in enumerate(names)] + [("v_" + m, v[:, i]) for i, m in enumerate(names)]
    if s is not None:
        columns += [("s_" + j, s[:, k]) for k, j in enumerate(jenkins)]
    return columns


def _h5_words(flags):
    return ["true" if b else "false" for b in flags]


def _h5_simulate(root, r):
    jenkins = r.jenkins if r.jenkins else ()
    s = r.s if jenkins else None
    _h5_table(root.create_group("simulate/trajectory"), [("t", r.t)] + _h5_state(r.masses, r.x, r.v, jenkins, s))
    e = r.events
    _h5_table(root.create_group("simulate/events"),
              [("t", e["t"]), ("kind", list(e["kind"])), ("element", list(e["element"]))] +
              _h5_state(r.masses, e["x"].reshape(len(e), -1), e["v"].reshape(len(e), -1), jenkins,
                        e["s"].reshape(len(e), -1) if jenkins else None))
    summary = r.summary
    kinds = ("contact_close", "contact_open", "stick", "release", "reversal")
    if "load_change" in summary["counts"]:  # a model with load steps, as the command's summary line
        kinds += ("load_change",)
    if "impact" in summary["counts"]:  # a model with rigid stops (restitution)
        kinds += ("impact",)
    counts = [(k, [summary["counts"].get(k, 0)]) for k in kinds]
    _h5_table(root.create_group("simulate/summary"),
              [("status", [summary["status"]]), ("method", [summary.get("method", "hsnc")]), ("t", [summary["t"]]),
               ("events", [summary["events"]])] + counts +
              [("x_" + m, [summary["x"][m]]) for m in r.masses] + [("v_" + m, [summary["v"][m]]) for m in r.masses])


def _h5_sweep(root, r):
    masses, param, param2 = r["masses"], r["param"], r["param2"]
    xmax, xrms, a1 = np.asarray(r["xmax"]), np.asarray(r["xrms"]), np.asarray(r["a1"])
    columns = [(param, r["value"]), ("direction", list(r["direction"])), ("settled", _h5_words(r["settled"])),
               ("periods", r["periods"]), ("multiple", r["multiple"])]
    for i, m in enumerate(masses):
        columns += [("xmax_" + m, xmax[:, i]), ("xrms_" + m, xrms[:, i]), ("a1_" + m, a1[:, i])]
    if param2:
        columns.append((param2, r["value2"]))
    if "stable" in r:
        stable = ["" if fail else w for fail, w in zip(r["failure"], _h5_words(r["stable"]))]
        columns += [("stable", stable), ("max_multiplier", r["max_multiplier"]), ("bifurcation", list(r["bifurcation"]))]
    if "branch" in r:
        columns.append(("branch", r["branch"]))
    if "amp" in r:
        amp, phase = np.asarray(r["amp"]), np.asarray(r["phase"])
        for i, m in enumerate(masses):
            for k in range(amp.shape[2]):
                columns += [("amp%d_%s" % (k + 1, m), amp[:, i, k]), ("phase%d_%s" % (k + 1, m), phase[:, i, k])]
    _h5_table(root.create_group("sweep/curve"), columns)
    d = r["diagram"]
    columns = [(param, d["value"]), ("direction", list(d["direction"])), ("t", d["t"])] + \
        _h5_state(masses, np.asarray(d["x"]).reshape(len(d["t"]), -1), np.asarray(d["v"]).reshape(len(d["t"]), -1))
    if param2:
        columns.append((param2, d["value2"]))
    _h5_table(root.create_group("sweep/diagram"), columns)


def _h5_periodic(root, r, masses, jenkins):
    orbit = r["orbit"]
    s = orbit.get("s") if jenkins else None
    _h5_table(root.create_group("periodic/orbit"),
              [("t", orbit["t"])] + _h5_state(masses, orbit["x"], orbit["v"], jenkins, s))
    mu = np.asarray(r["multipliers"])
    _h5_table(root.create_group("periodic/multipliers"),
              [("index", np.arange(1, len(mu) + 1)), ("re", mu.real), ("im", mu.imag), ("abs", np.abs(mu))])
    columns = [("period", [r["period"]]), ("iterations", [r["iterations"]]), ("residual", [r["residual"]])]
    columns += [("x_" + m, [r["x"][i]]) for i, m in enumerate(masses)]
    columns += [("v_" + m, [r["v"][i]]) for i, m in enumerate(masses)]
    columns += [("s_" + j, [r["s"][k]]) for k, j in enumerate(jenkins)]
    columns += [("stable", _h5_words([r["stable"]])), ("max_multiplier", [r["max_multiplier"]]),
                ("events", [r["events"]]), ("grazing", [r["grazing"]])]
    _h5_table(root.create_group("periodic/summary"), columns)


def _h5_lyapunov(root, r):
    rows = np.asarray(r["rows"])
    _h5_table(root.create_group("lyapunov/convergence"),
              [("t", r["rows_t"])] + [("lambda_%d" % (k + 1), rows[:, k]) for k in range(rows.shape[1])])
    exponents = np.asarray(r["exponents"])
    _h5_table(root.create_group("lyapunov/exponents"),
              [("index", np.arange(1, len(exponents) + 1)), ("lambda", exponents)])


def to_h5(result, path, model):
    """Write `result` (of hsnc.simulate, sweep, periodic or lyapunov, run on
    `model`) to the HDF5 file `path`, as the command's `--h5 FILE` does
    (docs/interface.md, "HDF5 output"): one dataset per CSV column under
    simulate/, sweep/, periodic/ or lyapunov/, the model's text, path and
    overrides under model/, and the format, hsnc version, command and
    model name as attributes. Needs h5py (Debian's python3-h5py). The file
    is written under a temporary name and renamed into place."""
    import h5py
    f = "hsnc.to_h5"
    model = _model(f, model)
    path = _path(f, "path", path)
    kind, what, source, (s, x0, v0) = model._read
    if isinstance(result, Result):
        write = lambda root: _h5_simulate(root, result)
    elif isinstance(result, dict) and "diagram" in result:
        write = lambda root: _h5_sweep(root, result)
    elif isinstance(result, dict) and "monodromy" in result:
        if result.get("status") != "ok":
            raise InputError("%s(): result: a periodic orbit that did not converge (status %r)" % (f, result.get("status")))
        write = lambda root: _h5_periodic(root, result, list(model.masses), list(model.jenkins))
    elif isinstance(result, dict) and "rows_t" in result:
        write = lambda root: _h5_lyapunov(root, result)
    else:
        _refuse(f, "result", result, "a result of hsnc.simulate, sweep, periodic or lyapunov")
    if kind == "file":
        with open(what, "rb") as m:
            text, where = m.read().decode("utf-8", "replace"), what
    else:
        text, where = what, source
    overrides = ["--set " + t for t in _override_texts(s)] + ["--x0 " + t for t in _override_texts(x0)] + \
        ["--v0 " + t for t in _override_texts(v0)]
    tmp = "%s.tmp.%d" % (path, os.getpid())
    try:
        with h5py.File(tmp, "w") as root:
            root.attrs["format"] = "hsnc-h5 1"
            root.attrs["hsnc_version"] = __version__
            root.attrs["command"] = "python: hsnc.to_h5"
            root.attrs["model_name"] = model.name
            string = h5py.string_dtype("utf-8")
            root.create_dataset("model/text", data=text, dtype=string)
            root.create_dataset("model/path", data=where, dtype=string)
            root.create_dataset("model/overrides", data=np.array(overrides, dtype=string))
            write(root)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


# Named as users see them: hsnc.InputError, not hsnc._hsnc.InputError.
InputError.__module__ = RunError.__module__ = Result.__module__ = Model.__module__ = __name__
