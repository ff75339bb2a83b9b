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

import math

import numpy as np

from . import _hsnc
from ._hsnc import InputError, RunError

__all__ = ["InputError", "Model", "Result", "RunError", "generate", "lyapunov", "periodic", "simulate", "sweep"]


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
        overrides = (dict(set or {}), dict(x0 or {}), dict(v0 or {}))
        native = _hsnc.Model.from_file(str(path), set=overrides[0], x0=overrides[1], v0=overrides[2])
        return cls(native, ("file", str(path), "", overrides))

    @classmethod
    def from_string(cls, text, *, source="<string>", set=None, x0=None, v0=None):
        """Read a model from TOML text; `source` names it in messages."""
        overrides = (dict(set or {}), dict(x0 or {}), dict(v0 or {}))
        native = _hsnc.Model.from_string(text, source=source, set=overrides[0], x0=overrides[1], v0=overrides[2])
        return cls(native, ("text", text, source, overrides))

    def with_overrides(self, *, set=None, x0=None, v0=None):
        """The same model read again with these overrides added to its own."""
        kind, what, source, (s0, x00, v00) = self._read
        s, x, v = dict(s0), dict(x00), dict(v00)
        s.update(set or {})
        x.update(x0 or {})
        v.update(v0 or {})
        if kind == "file":
            return Model.from_file(what, set=s, x0=x, v0=v)
        return Model.from_string(what, source=source, set=s, x0=x, v0=v)

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        return getattr(self._native, name)

    def __repr__(self):
        return repr(self._native)


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


def _number(name, value, default=math.nan, function="hsnc.simulate"):
    if value is None:
        return default
    try:
        return float(value)
    except (TypeError, ValueError):
        raise InputError("%s(): %s = %r: expected a number" % (function, name, value)) from None


def simulate(model, t_end=None, dt=None, method="hsnc", kernels="auto", precision="double", x0=None, v0=None,
             max_events=0, h=None, rtol=1e-10, atol=1e-12, cache_dir="", use_cache=True, tier_evaluations=200000):
    """Run `model` (a Model) from its initial state to `t_end` (default: the
    model's [simulate].t_end) and return a Result.

    dt: sample spacing (default (t_end - t0) / 1000); method: "hsnc" (exact),
    "ab4" (needs h), "rk45", "cvode" (rtol, atol); kernels: "auto", "aot",
    "generic" (= "interp"), "eigen", "jit", "tiered" (cache_dir, use_cache; tiered also
    tier_evaluations, as `--tier-evaluations`); precision: "double" or "mp:N";
    x0, v0: dicts {mass name: value} overriding the initial state (as
    `hsnc simulate --x0 --v0`: the model is read again with them);
    max_events: stop after that many switch events (0: no limit; the result
    then has status "max_events")."""
    if not isinstance(model, Model):
        raise InputError("hsnc.simulate(): model = %r: expected an hsnc.Model" % (model,))
    if x0 or v0:
        model = model.with_overrides(x0=x0, v0=v0)
    try:
        max_events = int(max_events)
    except (TypeError, ValueError):
        raise InputError("hsnc.simulate(): max_events = %r: expected an integer >= 0" % (max_events,)) from None
    if max_events < 0:
        raise InputError("hsnc.simulate(): max_events = %d: expected an integer >= 0" % max_events)
    if isinstance(tier_evaluations, bool) or not isinstance(tier_evaluations, int) or tier_evaluations < 1:
        raise InputError("hsnc.simulate(): tier_evaluations = %r: expected an integer >= 1" % (tier_evaluations,))
    raw = _hsnc._simulate(model._native, _number("t_end", t_end), _number("dt", dt), str(method), str(kernels), str(precision),
                    max_events, _number("h", h), _number("rtol", rtol), _number("atol", atol), str(cache_dir),
                    bool(use_cache), tier_evaluations)
    masses, jenkins = model.masses, model.jenkins
    return Result(raw["t"], raw["x"], raw["v"], _events(raw, len(masses), len(jenkins)), raw["summary"], masses,
                  raw["s"], jenkins)


def generate(model, directory):
    """Write the specialised C++ kernels of `model` into `directory` (as
    `hsnc generate MODEL -o DIR`; the directory is created if needed) and
    return the names of the files written."""
    return _hsnc._generate(model._native, str(directory))


def _override_texts(d):
    return ["%s=%s" % (k, v if isinstance(v, str) else repr(float(v))) for k, v in d.items()]


def sweep(model, param, start, stop, points, direction="up", max_periods=500, record_periods=16,
          restart_each=False, param2=None, values2=None, threads=1, method="hsnc", rtol=1e-10, atol=1e-12,
          continuation=False, max_steps=0):
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
    False and xmax, xrms, a1 are NaN; the sweep goes on).

    continuation=True (as `--continuation`): the periodic orbit followed
    over the parameter by pseudo-arclength continuation with exact shooting,
    through folds, from start (stop for direction "down") until the
    parameter leaves [start, stop] or after max_steps points per branch (0:
    20 * points); then also "stable" (bool), "max_multiplier" (largest
    |Floquet multiplier|), "bifurcation" (str: "", "fold", "period_doubling",
    "neimark_sacker", crossed since the previous point) and "stop" (str: why
    the branch stopped early after this point, "" when it did not).

    Ctrl-C (SIGINT) stops the run within a forcing period or a continuation
    step and raises KeyboardInterrupt."""
    if not isinstance(model, Model):
        raise InputError("hsnc.sweep(): model = %r: expected an hsnc.Model" % (model,))
    kind, what, source, (s, x0, v0) = model._read
    try:
        points, max_periods, record_periods, threads, max_steps = (int(points), int(max_periods),
                                                                   int(record_periods), int(threads), int(max_steps))
    except (TypeError, ValueError):
        raise InputError("hsnc.sweep(): points, max_periods, record_periods, threads, max_steps: expected integers") from None
    if min(points, max_periods, record_periods, threads, max_steps) < 0:
        raise InputError("hsnc.sweep(): points, max_periods, record_periods, threads, max_steps: expected integers >= 0")
    values2 = [] if values2 is None else [float(v) for v in values2]
    return _hsnc._sweep(kind, what, source, _override_texts(s), _override_texts(x0), _override_texts(v0),
                        str(param), _number("start", start), _number("stop", stop), points, str(direction),
                        max_periods, record_periods, bool(restart_each), "" if param2 is None else str(param2),
                        values2, threads, str(method), _number("rtol", rtol), _number("atol", atol),
                        bool(continuation), max_steps)
def _integer(function, name, value):
    try:
        if isinstance(value, bool) or int(value) != value:
            raise ValueError
        return int(value)
    except (TypeError, ValueError):
        raise InputError("%s(): %s = %r: expected an integer" % (function, name, value)) from None


def periodic(model, period=None, harmonic=1, transient=0.0, tol=1e-10, max_iterations=50, dt=None,
             kernels="auto", x0=None, v0=None):
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
    transient: run this long first. Ctrl-C (SIGINT) stops it promptly with
    KeyboardInterrupt."""
    if not isinstance(model, Model):
        raise InputError("hsnc.periodic(): model = %r: expected an hsnc.Model" % (model,))
    if x0 or v0:
        model = model.with_overrides(x0=x0, v0=v0)
    f = "hsnc.periodic"
    return _hsnc._periodic(model._native, _number("period", period, function=f), _integer(f, "harmonic", harmonic),
                           _number("transient", transient, 0.0, f), _number("tol", tol, 1e-10, f),
                           _integer(f, "max_iterations", max_iterations), _number("dt", dt, function=f),
                           str(kernels))


def lyapunov(model, t_end, transient=0.0, row_interval=None, kernels="auto", x0=None, v0=None):
    """The Lyapunov spectrum (as `hsnc lyapunov`), by the QR method on the
    exact tangent dynamics, measured over t_end seconds after transient.
    Returns a dict: exponents (array of 2n, plus one per Jenkins element,
    1/s, largest first, -inf for directions a stick or a slip collapses), sum, t_start, t, collapsed, events,
    grazing (switch instants at a turning point of a contact's gap, or
    without a saltation matrix: the exponents are not reliable when > 0),
    singular (of them, without a saltation matrix), rows_t and rows (the running estimates every row_interval,
    default the forcing period, else 1 s; k x 2n). A run that stops early
    raises RunError; Ctrl-C (SIGINT) stops it promptly with KeyboardInterrupt."""
    if not isinstance(model, Model):
        raise InputError("hsnc.lyapunov(): model = %r: expected an hsnc.Model" % (model,))
    if x0 or v0:
        model = model.with_overrides(x0=x0, v0=v0)
    f = "hsnc.lyapunov"
    return _hsnc._lyapunov(model._native, _number("t_end", t_end, function=f), _number("transient", transient, 0.0, f),
                           _number("row_interval", row_interval, function=f), str(kernels))


# Named as users see them: hsnc.InputError, not hsnc._hsnc.InputError.
InputError.__module__ = RunError.__module__ = Result.__module__ = Model.__module__ = __name__
