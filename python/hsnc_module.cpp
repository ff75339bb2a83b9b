// hsnc._hsnc -- the Python binding of the library facade (interface.md
// section 7). hsnc/__init__.py wraps it: simulate() returns NumPy arrays, a
// record array of the switch events and a summary dict.
//
// The engine runs with the GIL released, collecting samples and events in
// C++ vectors; they become NumPy arrays only when the run has succeeded, so
// an error or Ctrl-C never hands back half a result. Ctrl-C: the observer's
// on_progress (and every 1024th sample) takes the GIL at most every 50 ms for
// PyErr_CheckSignals(); when a handler raised (KeyboardInterrupt), the run
// stops and that exception is raised here.
//
// Errors: hsnc::InputError (OptionError included) becomes hsnc.InputError
// (a ValueError), hsnc::RunError and a run that ends in chattering, Zeno or
// a solver failure become hsnc.RunError (a RuntimeError), with the message
// the library gives the command line.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Python.h>

#include <chrono>
#include <complex>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "engine.h"
#include "error.h"
#include "file_read.h"
#include "hsnc/generate.h"
#include "hsnc/lyapunov.h"
#include "hsnc/modes.h"
#include "hsnc/periodic.h"
#include "hsnc/simulate.h"
#include "model_reader.h"
#include "sample_grid.h"
#include "simulate_outputs.h"

namespace py = pybind11;

namespace hsnc::python {
void bind_sweep(py::module_& m);  // sweep_binding.cpp
namespace {

// Collects a run; checks for signals with the GIL taken briefly.
class Collector : public Observer {
public:
    /// nj: Jenkins sliders recorded after the masses' x (0: none; an observer
    /// of the analyses' flows, whose x has the masses only).
    explicit Collector(std::size_t n, std::size_t nj = 0)
        : n_(n), nj_(nj), last_check_(std::chrono::steady_clock::now()) {}

    void on_sample(double t, const double* x, const double* v) override {
        t_.push_back(t);
        x_.insert(x_.end(), x, x + n_);
        v_.insert(v_.end(), v, v + n_);
        s_.insert(s_.end(), x + n_, x + n_ + nj_);
        // A run with few switches calls on_progress rarely: samples check too.
        if ((++samples_ & 1023) == 0) interrupted_ = interrupted_ || !check_signals();
    }
    void on_event(double t, EventKind kind, int element, const double* x, const double* v) override {
        et_.push_back(t);
        ekind_.push_back(static_cast<int>(kind));
        eelement_.push_back(element);
        ex_.insert(ex_.end(), x, x + n_);
        ev_.insert(ev_.end(), v, v + n_);
        es_.insert(es_.end(), x + n_, x + n_ + nj_);
    }
    bool on_progress(double) override { return !interrupted_ && check_signals(); }

    bool interrupted() const { return interrupted_; }

    std::size_t n_, nj_;
    std::vector<double> t_, x_, v_, s_;
    std::vector<double> et_, ex_, ev_, es_;
    std::vector<int> ekind_, eelement_;

private:
    // False when a signal handler raised; the exception stays set on this thread.
    bool check_signals() {
        const auto now = std::chrono::steady_clock::now();
        if (now - last_check_ < std::chrono::milliseconds(50)) return true;
        last_check_ = now;
        py::gil_scoped_acquire gil;
        if (PyErr_CheckSignals() == 0) return true;
        interrupted_ = true;
        return false;
    }

    std::size_t samples_ = 0;
    bool interrupted_ = false;
    std::chrono::steady_clock::time_point last_check_;
};

// Ctrl-C in hsnc.periodic and hsnc.lyapunov: their progress hook (called
// with the GIL released) takes the GIL at most every 50 ms for
// PyErr_CheckSignals(), as Collector does for simulate; once a handler has
// raised, the hook says stop, the analysis ends soon after, and the binding
// raises that exception (KeyboardInterrupt).
class SignalCheck {
public:
    SignalCheck() : last_(std::chrono::steady_clock::now()) {}
    /// False (stop) once a signal handler has raised.
    bool operator()() {
        if (interrupted_) return false;
        const auto now = std::chrono::steady_clock::now();
        if (now - last_ < std::chrono::milliseconds(50)) return true;
        last_ = now;
        py::gil_scoped_acquire gil;
        if (PyErr_CheckSignals() == 0) return true;
        interrupted_ = true;  // the exception stays set on this thread
        return false;
    }
    bool interrupted() const { return interrupted_; }

private:
    bool interrupted_ = false;
    std::chrono::steady_clock::time_point last_;
};

py::array_t<double> matrix(const std::vector<double>& data, std::size_t rows, std::size_t cols) {
    py::array_t<double> a({rows, cols});
    if (!data.empty()) std::copy(data.begin(), data.end(), a.mutable_data());
    return a;
}

py::array_t<double> vector(const std::vector<double>& data) {
    py::array_t<double> a(data.size());
    if (!data.empty()) std::copy(data.begin(), data.end(), a.mutable_data());
    return a;
}

// NAME=VALUE texts for the reader: a number with 17 digits (it reads back
// exactly), a string as given (an expression of the model's parameters).
// hsnc/__init__.py checks the dicts (names, finite floats or str); anything
// else is still an InputError here, never pybind11's cast error.
std::vector<std::string> override_texts(const py::dict& d) {
    std::vector<std::string> out;
    for (const auto& [key, value] : d) {
        if (!py::isinstance<py::str>(key) || !(py::isinstance<py::str>(value) || py::isinstance<py::float_>(value)))
            throw InputError("override " + py::repr(key).cast<std::string>() + ": " +
                             py::repr(value).cast<std::string>() + ": expected a name and a number or an expression");
        std::string text;
        if (py::isinstance<py::str>(value)) {
            text = value.cast<std::string>();
        } else {
            char number[64];
            std::snprintf(number, sizeof number, "%.17g", value.cast<double>());
            text = number;
        }
        out.push_back(key.cast<std::string>() + "=" + text);
    }
    return out;
}

ModelOverrides overrides(const py::dict& set, const py::dict& x0, const py::dict& v0) {
    ModelOverrides o;  // t_end: the model's own (the Python calls take it as an argument)
    o.set = override_texts(set);
    o.x0 = override_texts(x0);
    o.v0 = override_texts(v0);
    return o;
}

py::dict run(const Model& model, double t_end, double dt, const std::string& method, const std::string& kernels,
             const std::string& precision, std::size_t max_events, double h, double rtol, double atol,
             const std::string& cache_dir, bool use_cache, std::uint64_t tier_evaluations) {
    SimulateOptions o;
    o.method = method_from_name(method);
    o.kernels = kernel_choice_from_name(kernels);
    o.precision_digits = precision_digits_from_name(precision);
    o.t_end = t_end;
    o.dt = dt;
    o.max_events = max_events;
    o.integrator.h = h;
    o.integrator.rtol = rtol;
    o.integrator.atol = atol;
    o.cache_dir = cache_dir;
    o.use_cache = use_cache;
    o.tier_evaluations = tier_evaluations;
    const std::size_t n = model.dof();
    const std::size_t nj = model.jenkins.size();
    Collector c(n, nj);
    SimulateSummary s;
    {
        py::gil_scoped_release nogil;
        s = simulate(model, o, c);
    }
    if (c.interrupted()) throw py::error_already_set();  // the handler's exception (KeyboardInterrupt)
    if (s.status != RunStatus::ok && s.status != RunStatus::max_events)
        throw RunError(std::string("simulate: ") + run_status_name(s.status) + ": " + s.message);

    const std::size_t ne = c.et_.size();
    py::list kinds, elements;
    for (std::size_t i = 0; i < ne; ++i) {
        const auto kind = static_cast<EventKind>(c.ekind_[i]);
        kinds.append(event_kind_name(kind));
        elements.append(event_element_name(model, kind, c.eelement_[i]));
    }
    py::dict counts;
    for (EventKind k : kSwitchEventKinds) counts[event_kind_name(k)] = 0;
    if (!model.load_steps.empty()) counts[event_kind_name(EventKind::load_change)] = 0;
    if (model.has_impacts()) counts[event_kind_name(EventKind::impact)] = 0;
    for (int k : c.ekind_) {
        const char* name = event_kind_name(static_cast<EventKind>(k));
        counts[name] = counts[name].cast<std::size_t>() + 1;
    }
    py::dict summary;
    summary["status"] = run_status_name(s.status);
    summary["message"] = s.message;
    summary["method"] = method;
    summary["t"] = s.t;
    summary["events"] = s.events;
    summary["counts"] = counts;
    summary["segments"] = s.segments;
    summary["restarts"] = s.restarts;
    summary["evaluations"] = s.evaluations;
    summary["configurations"] = s.configurations;
    summary["configuration"] = s.configuration.spec(model);
    summary["solver"] = solver_kind_name(s.solver);
    summary["solver_detail"] = s.solver_detail;
    py::dict x_end, v_end;
    for (std::size_t i = 0; i < n; ++i) {
        x_end[py::str(model.masses[i].name)] = s.x[i];
        v_end[py::str(model.masses[i].name)] = s.v[i];
    }
    summary["x"] = x_end;
    summary["v"] = v_end;
    py::dict slider_end;
    for (std::size_t j = 0; j < nj && j < s.slider.size(); ++j) slider_end[py::str(model.jenkins[j].name)] = s.slider[j];
    summary["slider"] = slider_end;

    py::dict out;
    out["t"] = vector(c.t_);
    out["x"] = matrix(c.x_, c.t_.size(), n);
    out["v"] = matrix(c.v_, c.t_.size(), n);
    out["event_t"] = vector(c.et_);
    out["event_kind"] = kinds;
    out["event_element"] = elements;
    out["event_x"] = matrix(c.ex_, ne, n);
    out["event_v"] = matrix(c.ev_, ne, n);
    out["s"] = matrix(c.s_, c.t_.size(), nj);
    out["event_s"] = matrix(c.es_, ne, nj);
    out["summary"] = summary;
    return out;
}

// The kernels of `model` into `dir`, as `hsnc generate MODEL -o DIR` writes
// them (the facade's generate_kernels and write_kernels, api/hsnc/generate.h).
std::vector<std::string> generate(const Model& model, const std::string& dir) {
    py::gil_scoped_release nogil;
    return write_kernels(model, generate_kernels(model), dir);
}

// Samples of one run (the orbit's period).
class Samples : public Observer {
public:
    explicit Samples(std::size_t n) : n_(n) {}
    void on_sample(double t, const double* x, const double* v) override {
        t_.push_back(t);
        x_.insert(x_.end(), x, x + n_);
        v_.insert(v_.end(), v, v + n_);
    }
    void on_event(double, EventKind, int, const double*, const double*) override {}
    std::size_t n_;
    std::vector<double> t_, x_, v_;
};

KernelChoice kernel_choice(const std::string& name) { return kernel_choice_from_name(name); }

// hsnc.periodic: the result of hsnc::periodic as a dict of NumPy arrays and numbers.
py::dict periodic(const Model& model, double period, int harmonic, double transient, double tolerance,
                  int max_iterations, double dt, const std::string& kernels) {
    PeriodicOptions o;
    o.period = period;
    o.harmonic = harmonic;
    o.transient = transient;
    o.tolerance = tolerance;
    o.max_iterations = max_iterations;
    o.dt = dt;
    o.kernels = kernel_choice(kernels);
    const std::size_t n = model.dof();
    Samples orbit(n);
    PeriodicResult r;
    SignalCheck signals;
    o.progress = [&signals](const PeriodicProgress&) { return signals(); };
    {
        py::gil_scoped_release nogil;
        r = hsnc::periodic(model, o, &orbit);
    }
    if (signals.interrupted()) throw py::error_already_set();  // the handler's exception (KeyboardInterrupt)
    py::dict d;
    d["status"] = periodic_status_name(r.status);
    d["message"] = r.message;
    d["period"] = r.period;
    d["t"] = r.t;
    d["iterations"] = r.iterations;
    d["residual"] = r.residual;
    d["x"] = vector(r.x);
    d["v"] = vector(r.v);
    d["s"] = vector(r.s);  // the Jenkins sliders (state after v)
    py::array_t<std::complex<double>> mu(r.multipliers.size());
    if (!r.multipliers.empty()) std::copy(r.multipliers.begin(), r.multipliers.end(), mu.mutable_data());
    d["multipliers"] = mu;
    const bool ok = r.status == PeriodicStatus::ok;
    d["max_multiplier"] = ok ? r.max_multiplier : NAN;
    d["stable"] = ok && r.stable;
    d["neutral"] = ok ? r.neutral : 0;  // a family's multipliers at +1, left out of `stable`
    const std::size_t N = 2 * n + model.jenkins.size();  // y = (x, v, s)
    d["monodromy"] = ok ? matrix(r.monodromy, N, N) : matrix({}, 0, N);
    d["events"] = r.events;
    d["grazing"] = r.grazing;
    py::dict path;
    path["t"] = vector(orbit.t_);
    path["x"] = matrix(orbit.x_, orbit.t_.size(), n);
    path["v"] = matrix(orbit.v_, orbit.t_.size(), n);
    d["orbit"] = path;
    return d;
}

// hsnc.modes: the backbone as a dict of NumPy arrays (a row per point) and
// the linear mode's numbers. The library's option names become the Python
// arguments' (from, to: start, stop).
py::dict modes(const Model& model, int mode, const std::string& dof, double start, double stop, int points, bool energy,
               bool geometric, double tolerance, int max_iterations, const std::string& kernels) {
    ModesOptions o;
    o.parameter = energy ? ModesParameter::energy : ModesParameter::amplitude;
    o.geometric = geometric;
    o.mode = mode;
    o.dof = dof;
    o.from = start;
    o.to = stop;
    o.points = points;
    o.tolerance = tolerance;
    o.max_iterations = max_iterations;
    o.kernels = kernel_choice(kernels);
    SignalCheck signals;
    o.progress = [&signals](const ModesProgress&) { return signals(); };
    ModesResult r;
    try {
        py::gil_scoped_release nogil;
        r = hsnc::modes(model, o);
    } catch (const OptionError& e) {
        const std::string name = e.option() == "from"        ? "start"
                                 : e.option() == "to"        ? "stop"
                                 : e.option() == "tolerance" ? "tol"
                                                             : e.option();
        throw InputError("hsnc.modes(): " + name + ": " + e.reason());
    }
    if (signals.interrupted()) throw py::error_already_set();  // the handler's exception (KeyboardInterrupt)
    const std::size_t n = model.dof(), nj = model.jenkins.size(), rows = r.points.size(), others = r.others.size();
    py::dict d;
    d["status"] = modes_status_name(r.status);
    d["damped"] = r.damped;
    d["linear_damping_ratio"] = r.linear_damping_ratio;
    d["message"] = r.message;
    d["mode"] = r.mode;
    d["dof"] = model.masses[r.dof].name;
    d["linear_omega"] = r.linear_omega;
    d["shape"] = vector(r.shape);
    d["equilibrium"] = vector(r.equilibrium);
    d["configuration"] = r.configuration;
    d["others"] = r.others;
    auto column = [&](auto field) {
        std::vector<double> c;
        for (const ModePoint& p : r.points) c.push_back(static_cast<double>(field(p)));
        return vector(c);
    };
    d["amplitude"] = column([](const ModePoint& p) { return p.amplitude; });
    d["omega"] = column([](const ModePoint& p) { return p.omega; });
    d["period"] = column([](const ModePoint& p) { return p.period; });
    d["energy"] = column([](const ModePoint& p) { return p.energy; });
    d["xi"] = column([](const ModePoint& p) { return p.xi; });
    d["damping_ratio"] = column([](const ModePoint& p) { return p.damping_ratio; });
    d["max_multiplier"] = column([](const ModePoint& p) { return p.max_multiplier; });
    d["residual"] = column([](const ModePoint& p) { return p.residual; });
    std::vector<double> x, v, sliders, peaks, ratios;
    py::array_t<std::complex<double>> mu({rows, 2 * n + nj});
    py::array_t<bool> stable(rows);
    py::array_t<long> events(rows), grazing(rows), iterations(rows);
    py::list resonances;
    for (std::size_t i = 0; i < rows; ++i) {
        const ModePoint& p = r.points[i];
        x.insert(x.end(), p.x.begin(), p.x.end());
        v.insert(v.end(), p.v.begin(), p.v.end());
        sliders.insert(sliders.end(), p.sliders.begin(), p.sliders.end());
        peaks.insert(peaks.end(), p.peaks.begin(), p.peaks.end());
        ratios.insert(ratios.end(), p.ratios.begin(), p.ratios.end());
        std::copy(p.multipliers.begin(), p.multipliers.end(), mu.mutable_data() + i * (2 * n + nj));
        stable.mutable_data()[i] = p.stable;
        events.mutable_data()[i] = static_cast<long>(p.events);
        grazing.mutable_data()[i] = static_cast<long>(p.grazing);
        iterations.mutable_data()[i] = p.iterations;
        resonances.append(py::cast(p.resonances));
    }
    d["x"] = matrix(x, rows, n);
    d["v"] = matrix(v, rows, n);
    d["sliders"] = matrix(sliders, rows, nj);
    d["peak"] = matrix(peaks, rows, n);
    d["ratios"] = matrix(ratios, rows, others);
    d["resonances"] = resonances;
    d["multipliers"] = mu;
    d["stable"] = stable;
    d["events"] = events;
    d["grazing"] = grazing;
    d["iterations"] = iterations;
    return d;
}

// hsnc.lyapunov: the spectrum and its convergence rows.
py::dict lyapunov(const Model& model, double t_end, double transient, double row_interval, const std::string& kernels) {
    LyapunovOptions o;
    o.t_end = t_end;
    o.transient = transient;
    o.row_interval = row_interval;
    o.kernels = kernel_choice(kernels);
    std::vector<double> row_t, rows;
    LyapunovResult r;
    SignalCheck signals;
    o.progress = [&signals](double) { return signals(); };
    {
        py::gil_scoped_release nogil;
        r = hsnc::lyapunov(model, o, [&](double t, const std::vector<double>& ex) {
            row_t.push_back(t);
            rows.insert(rows.end(), ex.begin(), ex.end());
        });
    }
    if (signals.interrupted()) throw py::error_already_set();  // the handler's exception (KeyboardInterrupt)
    if (r.status != RunStatus::ok)
        throw RunError(std::string("lyapunov: ") + run_status_name(r.status) + ": " + r.message);
    py::dict d;
    d["status"] = run_status_name(r.status);
    d["t_start"] = r.t_start;
    d["t"] = r.t;
    d["exponents"] = vector(r.exponents);
    d["sum"] = r.sum;
    d["collapsed"] = r.collapsed;
    d["events"] = r.events;
    d["grazing"] = r.grazing;
    d["singular"] = r.singular;
    d["rows_t"] = vector(row_t);
    d["rows"] = matrix(rows, row_t.size(), 2 * model.dof() + model.jenkins.size());
    return d;
}

}  // namespace
}  // namespace hsnc::python

PYBIND11_MODULE(_hsnc, m) {
    using namespace hsnc;
    namespace hp = hsnc::python;
    m.doc() = "hsnc: exact response of piecewise-linear systems with contacts and Coulomb friction (native part)";
    m.attr("__version__") = HSNC_PYTHON_VERSION;

    // Python subclasses of ValueError / RuntimeError, so callers may catch either.
    static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
    static py::exception<RunError> run_error(m, "RunError", PyExc_RuntimeError);
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const InputError& e) {
            PyErr_SetString(input_error.ptr(), e.what());
        } catch (const RunError& e) {
            PyErr_SetString(run_error.ptr(), e.what());
        }
    });

    py::class_<Model>(m, "Model")
        .def_static(
            "from_file",
            [](const std::string& path, const py::dict& set,
               const py::dict& x0, const py::dict& v0) {
                return read_model(path, hp::overrides(set, x0, v0));
            },
            py::arg("path"), py::kw_only(), py::arg("set") = py::dict(),
            py::arg("x0") = py::dict(), py::arg("v0") = py::dict(),
            "Read and validate a model file; set/x0/v0 override parameters and the initial state by name.")
        .def_static(
            "from_string",
            [](const std::string& text, const std::string& source, const py::dict& set,
               const py::dict& x0, const py::dict& v0) {
                return parse_model(text, source, hp::overrides(set, x0, v0));
            },
            py::arg("text"), py::kw_only(), py::arg("source") = "<string>",
            py::arg("set") = py::dict(), py::arg("x0") = py::dict(),
            py::arg("v0") = py::dict(),
            "Read a model from TOML text; `source` names it in messages.")
        .def_readonly("name", &Model::name)
        .def_readonly("description", &Model::description)
        .def_readonly("source", &Model::source)
        .def_property_readonly("masses",
                               [](const Model& mo) {
                                   std::vector<std::string> names;
                                   for (const Mass& ms : mo.masses) names.push_back(ms.name);
                                   return names;
                               })
        .def_property_readonly("jenkins",
                               [](const Model& mo) {
                                   std::vector<std::string> names;
                                   for (const Jenkins& j : mo.jenkins) names.push_back(j.name);
                                   return names;
                               })
        .def_property_readonly("contacts",
                               [](const Model& mo) {
                                   std::vector<std::string> names;
                                   for (const Contact& c : mo.contacts) names.push_back(c.name);
                                   return names;
                               })
        .def_property_readonly("friction_masses",
                               [](const Model& mo) {
                                   std::vector<std::string> names;
                                   for (std::size_t i = 0; i < mo.dof(); ++i)
                                       if (mo.has_friction(i)) names.push_back(mo.masses[i].name);
                                   return names;
                               })
        .def_property_readonly("parameters",
                               [](const Model& mo) {
                                   py::dict d;  // file order (dicts keep insertion order)
                                   for (const auto& [name, value] : mo.parameters) d[py::str(name)] = value;
                                   return d;
                               })
        .def_property_readonly("mass_values",
                               [](const Model& mo) {
                                   std::vector<double> v;
                                   for (const Mass& ms : mo.masses) v.push_back(ms.m);
                                   return hp::vector(v);
                               })
        .def_readonly("t0", &Model::t0)
        .def_property_readonly("t_end", [](const Model& mo) { return mo.t_end; })
        .def_property_readonly("x0", [](const Model& mo) { return hp::vector(mo.x0); })
        .def_property_readonly("v0", [](const Model& mo) { return hp::vector(mo.v0); })
        .def_property_readonly("dof", &Model::dof)
        .def("__repr__", [](const Model& mo) {
            return "<hsnc.Model '" + mo.name + "': " + std::to_string(mo.dof()) + " masses, " +
                   std::to_string(mo.contacts.size()) + " contacts>";
        });

    m.def("_simulate", &hp::run, py::arg("model"), py::arg("t_end"), py::arg("dt"), py::arg("method"),
          py::arg("kernels"), py::arg("precision"), py::arg("max_events"), py::arg("h"), py::arg("rtol"),
          py::arg("atol"), py::arg("cache_dir"), py::arg("use_cache"), py::arg("tier_evaluations"));
    m.def("_generate", &hp::generate, py::arg("model"), py::arg("dir"));
    hp::bind_sweep(m);
    m.def("_periodic", &hp::periodic, py::arg("model"), py::arg("period"), py::arg("harmonic"), py::arg("transient"),
          py::arg("tolerance"), py::arg("max_iterations"), py::arg("dt"), py::arg("kernels"));
    m.def("_modes", &hp::modes, py::arg("model"), py::arg("mode"), py::arg("dof"), py::arg("start"), py::arg("stop"),
          py::arg("points"), py::arg("energy"), py::arg("geometric"), py::arg("tolerance"), py::arg("max_iterations"),
          py::arg("kernels"));
    m.def("_lyapunov", &hp::lyapunov, py::arg("model"), py::arg("t_end"), py::arg("transient"),
          py::arg("row_interval"), py::arg("kernels"));

    // For the argument checks of hsnc/__init__.py: the CLI's output guard
    // (output/simulate_outputs.h) and model size limit (model/file_read.h),
    // the sample grid's row count, and the default spans of periodic and lyapunov.
    m.attr("_LARGE_OUTPUT_ROWS") = kLargeOutputRows;
    m.attr("_LARGE_OUTPUT_BYTES") = kLargeOutputBytes;
    m.attr("_MAX_MODEL_BYTES") = kMaxModelFileBytes;
    m.def("_sample_count", [](double t0, double t_end, double dt) { return SampleGrid(t0, t_end, dt).count(); });
    m.def("_forcing_period", &forcing_period);
    m.def("_rotation_number", [](const py::array_t<double, py::array::c_style | py::array::forcecast>& x,
                                 const py::array_t<double, py::array::c_style | py::array::forcecast>& v) {
        const RotationNumber r = rotation_number(x.data(), v.data(), static_cast<std::size_t>(x.size()));
        return py::make_tuple(r.value, r.error);
    });
    // hsnc::lyapunov's default row_interval: the period of the slowest forcing harmonic, else 1 s.
    m.def("_default_row_interval", [](const Model& mo) { return lyapunov_row_interval(mo, LyapunovOptions{}); });
}
