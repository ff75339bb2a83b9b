// hsnc._hsnc._sweep -- the binding of hsnc::SweepPlan (api/hsnc/sweep.h)
// for hsnc.sweep() (hsnc/__init__.py): the model read again at every point
// from its file or text with the overrides as "NAME=VALUE" texts, the run with
// the GIL released, the result as NumPy arrays in a dict.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "file_read.h"
#include "hsnc/simulate.h"
#include "hsnc/sweep.h"

namespace py = pybind11;

namespace hsnc::python {
namespace {

py::array_t<double> matrix(const std::vector<double>& data, std::size_t rows, std::size_t cols) {
    py::array_t<double> a({rows, cols});
    std::copy(data.begin(), data.end(), a.mutable_data());
    return a;
}

py::dict sweep(const std::string& kind, const std::string& what, const std::string& source,
               const std::vector<std::string>& set, const std::vector<std::string>& x0,
               const std::vector<std::string>& v0, const std::string& param, double from, double to, std::size_t points,
               const std::string& direction, std::size_t max_periods, std::size_t record_periods, bool restart_each,
               const std::string& param2, const std::vector<double>& values2, unsigned threads,
               const std::string& method, double rtol, double atol, bool continuation, std::size_t max_steps,
               std::size_t harmonics, int branch_switch, const std::string& track, double escape,
               std::size_t start_periods) {
    SweepOptions o;
    o.param = param;
    o.from = from;
    o.to = to;
    o.points = points;
    o.direction = sweep_direction_from_name(direction);
    o.max_periods = max_periods;
    o.record_periods = record_periods;
    o.restart_each = restart_each;
    o.param2 = param2;
    o.values2 = values2;
    o.threads = threads;
    o.method = method_from_name(method);
    o.integrator.rtol = rtol;
    o.integrator.atol = atol;
    o.continuation = continuation;
    o.max_steps = max_steps;
    o.harmonics = harmonics;
    o.branch_switch = branch_switch;
    o.track = track;
    o.escape = escape;
    o.start_periods = start_periods;
    std::atomic<bool> cancel{false};
    o.cancel = &cancel;
    const ModelOverrides ov{set, x0, v0, {}};
    std::string text = what, src = source;
    if (kind == "file") {
        const FileRead file = read_regular_file(what, kMaxModelFileBytes);
        if (file.status != FileRead::Status::ok)
            throw InputError("cannot read model file '" + what + "': " + file.problem);
        text = file.bytes;
        src = what;
    }
    const SweepPlan plan(text, src, ov, o);
    // The run on a thread of its own; this one waits without the GIL and
    // looks for signals every 50 ms (only the main thread runs Python's
    // signal handlers): Ctrl-C sets `cancel`, the run stops within a forcing
    // period or a continuation step, and KeyboardInterrupt is raised here.
    SweepResult r;
    std::exception_ptr error;
    {
        std::mutex mutex;
        std::condition_variable finished;
        bool done = false;
        std::thread worker([&] {
            try {
                r = plan.run();
            } catch (...) {
                error = std::current_exception();
            }
            std::lock_guard<std::mutex> lock(mutex);
            done = true;
            finished.notify_all();
        });
        bool interrupted = false;
        for (;;) {
            {
                py::gil_scoped_release nogil;
                std::unique_lock<std::mutex> lock(mutex);
                if (finished.wait_for(lock, std::chrono::milliseconds(50), [&] { return done; })) break;
            }
            if (!interrupted && PyErr_CheckSignals() != 0) {
                interrupted = true;
                cancel = true;
            }
        }
        {
            py::gil_scoped_release nogil;
            worker.join();
        }
        if (interrupted) throw py::error_already_set();
    }
    if (error) std::rethrow_exception(error);
    const std::size_t np = r.points.size(), n = r.masses.size();
    py::array_t<double> value(np), value2(np);
    py::array_t<bool> settled(np), escaped(np);
    py::array_t<long long> periods(np), multiple(np), branch(np);
    py::array_t<bool> stable(np);
    py::array_t<double> max_multiplier(np);
    py::list bifurcation, failure, stop;
    std::vector<double> xmax, xrms, a1, amp, phase;
    py::list dirs;
    std::vector<double> dv, dv2, dt, dx, dvel;
    py::list ddirs;
    for (std::size_t i = 0; i < np; ++i) {
        const SweepPoint& p = r.points[i];
        value.mutable_at(i) = p.value;
        value2.mutable_at(i) = p.value2;
        settled.mutable_at(i) = p.settled;
        escaped.mutable_at(i) = p.escaped;
        periods.mutable_at(i) = static_cast<long long>(p.periods);
        multiple.mutable_at(i) = p.multiple;
        branch.mutable_at(i) = static_cast<long long>(p.branch);
        stable.mutable_at(i) = p.stable;
        max_multiplier.mutable_at(i) = p.max_multiplier;
        bifurcation.append(p.bifurcation);
        failure.append(p.failure);
        stop.append(p.stop);
        dirs.append(sweep_direction_name(p.direction));
        xmax.insert(xmax.end(), p.xmax.begin(), p.xmax.end());
        xrms.insert(xrms.end(), p.xrms.begin(), p.xrms.end());
        a1.insert(a1.end(), p.a1.begin(), p.a1.end());
        amp.insert(amp.end(), p.amp.begin(), p.amp.end());
        phase.insert(phase.end(), p.phase.begin(), p.phase.end());
        for (std::size_t k = 0; k < p.strobe_t.size(); ++k) {
            dv.push_back(p.value);
            dv2.push_back(p.value2);
            dt.push_back(p.strobe_t[k]);
            ddirs.append(sweep_direction_name(p.direction));
        }
        dx.insert(dx.end(), p.strobe_x.begin(), p.strobe_x.end());
        dvel.insert(dvel.end(), p.strobe_v.begin(), p.strobe_v.end());
    }
    py::dict diagram;
    diagram["value"] = py::array_t<double>(dv.size(), dv.data());
    diagram["value2"] = py::array_t<double>(dv2.size(), dv2.data());
    diagram["direction"] = py::array(ddirs);
    diagram["t"] = py::array_t<double>(dt.size(), dt.data());
    diagram["x"] = matrix(dx, dt.size(), n);
    diagram["v"] = matrix(dvel, dt.size(), n);
    py::dict d;
    d["param"] = r.param;
    d["param2"] = r.param2.empty() ? py::object(py::none()) : py::object(py::str(r.param2));
    d["masses"] = r.masses;
    d["value"] = value;
    d["value2"] = value2;
    d["direction"] = py::array(dirs);
    d["settled"] = settled;
    d["escaped"] = escaped;
    d["periods"] = periods;
    d["multiple"] = multiple;
    d["xmax"] = matrix(xmax, np, n);
    d["xrms"] = matrix(xrms, np, n);
    d["a1"] = matrix(a1, np, n);
    if (r.harmonics) {
        const std::size_t K = r.harmonics;
        py::array_t<double> a({np, n, K}), ph({np, n, K});
        std::copy(amp.begin(), amp.end(), a.mutable_data());
        std::copy(phase.begin(), phase.end(), ph.mutable_data());
        d["amp"] = a;
        d["phase"] = ph;
    }
    d["diagram"] = diagram;
    d["failure"] = failure;
    if (r.continuation) {
        d["stable"] = stable;
        d["max_multiplier"] = max_multiplier;
        d["bifurcation"] = bifurcation;
        d["stop"] = stop;
    }
    if (r.branch_switch) d["branch"] = branch;
    // Basins of attraction: both swept names initial state coordinates.
    if (is_basins(r)) {
        const Attractors a = classify_attractors(r);
        py::array_t<int> ids(np);
        for (std::size_t i = 0; i < np; ++i) ids.mutable_at(i) = a.of_point[i];
        py::list list;
        for (const Attractor& at : a.list) {
            py::dict e;
            e["multiple"] = at.multiple;
            e["points"] = at.points;
            e["x"] = py::array_t<double>(at.x.size(), at.x.data());
            e["v"] = py::array_t<double>(at.v.size(), at.v.data());
            list.append(e);
        }
        d["attractor"] = ids;
        d["attractors"] = list;
    }
    return d;
}

}  // namespace

void bind_sweep(py::module_& m) {
    m.def("_sweep", &sweep, py::arg("kind"), py::arg("what"), py::arg("source"), py::arg("set"), py::arg("x0"),
          py::arg("v0"), py::arg("param"), py::arg("from_"), py::arg("to"), py::arg("points"), py::arg("direction"),
          py::arg("max_periods"), py::arg("record_periods"), py::arg("restart_each"), py::arg("param2"),
          py::arg("values2"), py::arg("threads"), py::arg("method"), py::arg("rtol"), py::arg("atol"),
          py::arg("continuation") = false, py::arg("max_steps") = 0, py::arg("harmonics") = 0,
          py::arg("branch_switch") = 0, py::arg("track") = "", py::arg("escape") = 0.0, py::arg("start_periods") = 0);
}

}  // namespace hsnc::python
