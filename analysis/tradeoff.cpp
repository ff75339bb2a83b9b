#include "tradeoff.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "aot_registry.h"
#include "error.h"
#include "kernel_mode.h"
#include "sample_grid.h"

namespace hsnc {
namespace {

constexpr const char* kTradeoff = "hsnc::tradeoff";

struct MethodEntry {
    Method method;
    Sweep sweep;
};

// The study's methods, in this order in its rows (and the CSV and plot of `hsnc tradeoff`).
constexpr MethodEntry kMethods[] = {
    {Method::hsnc, Sweep::kernels},
    {Method::ab4, Sweep::step},
    {Method::rk45, Sweep::tolerance},
    {Method::cvode, Sweep::tolerance},
};

bool in_this_build(Method method) { return method != Method::cvode || HSNC_WITH_CVODE; }

Sweep sweep_of(Method method) {
    for (const MethodEntry& m : kMethods)
        if (m.method == method) return m.sweep;
    return Sweep::kernels;
}

std::string num(double v, int digits = 17) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    return buf;
}

// "1e-05", "3.2e-04": a setting as its label.
std::string sci(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.1e", v);
    std::string s = buf;
    if (s.compare(1, 2, ".0") == 0) s.erase(1, 2);
    return s;
}

double end_time(const Model& model, const TradeoffOptions& o) {
    return std::isnan(o.t_end) ? model.t_end.value_or(NAN) : o.t_end;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// One run of a setting through the facade, as `hsnc simulate` would make it.
SimulateSummary run_setting(const Model& model, const TradeoffSetting& s, const EngineOptions& eopt, Observer& obs) {
    SimulateOptions options;
    options.t_end = eopt.t_end;
    options.dt = eopt.dt;
    options.method = s.method;
    options.kernels = s.kernels;
    options.integrator = s.integrator;
    return simulate(model, options, obs);
}

TradeoffRow measure(const Model& model, const TradeoffSetting& s, const EngineOptions& eopt,
                    const RecordedRun& reference, int runs) {
    TradeoffRow row;
    row.setting = s;
    RecordedRun rec;
    const std::size_t rows = reference.t.size() + 2;
    rec.t.reserve(rows);
    rec.x.reserve(rows * model.dof());
    RecordingObserver obs(rec, model.dof());
    auto start = std::chrono::steady_clock::now();
    const SimulateSummary sum = run_setting(model, s, eopt, obs);
    std::vector<double> walls{seconds_since(start)};
    row.status = run_status_name(sum.status);
    row.solver = sum.solver;
    row.errors = compare_runs(reference, rec);
    // Repeat to about 0.2 s of run time in all (odd count, at most 51): the median.
    const int total = runs > 0 ? runs : std::min(51, 1 + 2 * static_cast<int>(0.1 / std::max(walls[0], 1e-9)));
    RecordedRun scratch;
    for (int r = 1; r < total; ++r) {
        scratch.t.clear();
        scratch.x.clear();
        scratch.events.clear();
        scratch.t.reserve(rows);
        scratch.x.reserve(rows * model.dof());
        RecordingObserver again(scratch, model.dof());
        start = std::chrono::steady_clock::now();
        run_setting(model, s, eopt, again);
        walls.push_back(seconds_since(start));
    }
    std::sort(walls.begin(), walls.end());
    row.wall = walls[walls.size() / 2];
    row.runs = total;
    return row;
}

}  // namespace

std::vector<Method> tradeoff_methods() {
    std::vector<Method> out;
    for (const MethodEntry& m : kMethods)
        if (in_this_build(m.method)) out.push_back(m.method);
    return out;
}

std::vector<TradeoffSetting> tradeoff_settings(const Model& model, Method method, bool quick) {
    std::vector<TradeoffSetting> out;
    TradeoffSetting s;
    s.method = method;
    s.sweep = sweep_of(method);
    switch (s.sweep) {
    case Sweep::kernels:
        if (has_aot_kernels(model, &aot_registry())) {
            s.label = "kernels=auto";
            s.kernels = KernelChoice::automatic;
            out.push_back(s);
        }
        if (out.empty() || !quick) {
            s.label = "kernels=generic";
            s.kernels = KernelChoice::generic;
            out.push_back(s);
        }
        break;
    case Sweep::step:
        for (int k = 0; k <= 6; k += quick ? 2 : 1) {
            s.parameter = std::pow(10.0, -3.0 - k / 2.0);
            s.integrator.h = s.parameter;
            s.label = "h=" + sci(s.parameter);
            out.push_back(s);
        }
        break;
    case Sweep::tolerance:
        for (int k = 4; k <= 13; k += quick ? 3 : 1) {
            s.parameter = std::pow(10.0, -k);
            s.integrator.rtol = s.parameter;
            s.integrator.atol = 1e-2 * s.parameter;
            s.label = "rtol=" + sci(s.integrator.rtol) + " atol=" + sci(s.integrator.atol);
            out.push_back(s);
        }
        break;
    }
    return out;
}

void check_tradeoff_options(const Model& model, const TradeoffOptions& o) {
    const double t_end = end_time(model, o);
    if (std::isnan(t_end))
        throw OptionError(kTradeoff, "t_end", "NaN",
                          "no end time: none given and the model has no [simulate].t_end (" + model.source + ")");
    if (!(t_end > model.t0) || !std::isfinite(t_end))
        throw OptionError(kTradeoff, "t_end", num(t_end), "must be finite and after t0 = " + num(model.t0));
    if (!std::isnan(o.dt) && !(o.dt > 0 && std::isfinite(o.dt)))
        throw OptionError(kTradeoff, "dt", num(o.dt), "must be > 0");
    if (o.runs < 0 || o.runs > 1001)
        throw OptionError(kTradeoff, "runs", std::to_string(o.runs), "must be in 0..1001");
    if (!(o.budget > 0)) throw OptionError(kTradeoff, "budget", num(o.budget, 3), "must be > 0 (seconds)");
    for (std::size_t i = 0; i < o.methods.size(); ++i) {
        if (!in_this_build(o.methods[i]))
            throw OptionError(kTradeoff, "methods", method_name(o.methods[i]), "not in this build");
        if (std::find(o.methods.begin(), o.methods.begin() + static_cast<std::ptrdiff_t>(i), o.methods[i]) !=
            o.methods.begin() + static_cast<std::ptrdiff_t>(i))
            throw OptionError(kTradeoff, "methods", method_name(o.methods[i]), "given twice");
    }
}

EngineOptions tradeoff_engine_options(const Model& model, const TradeoffOptions& o) {
    check_tradeoff_options(model, o);
    EngineOptions eopt;
    eopt.t_end = end_time(model, o);
    eopt.dt = std::isnan(o.dt) ? SampleGrid::default_dt(model.t0, eopt.t_end) : o.dt;
    return eopt;
}

RecordedRun compute_reference(const Model& model, const TradeoffOptions& o, const ReferenceRunner& runner) {
    const EngineOptions eopt = tradeoff_engine_options(model, o);
    RecordedRun reference;
    RecordingObserver obs(reference, model.dof());
    const RunSummary sum = runner(model, eopt, obs);
    if (sum.status != RunStatus::ok)
        throw RunError(std::string("the reference run: ") + run_status_name(sum.status) + ": " + sum.message);
    return reference;
}

std::string fit_reference(const Model& model, const TradeoffOptions& o, RecordedRun& reference) {
    const EngineOptions eopt = tradeoff_engine_options(model, o);
    const double t_end = eopt.t_end;
    const double last = reference.t.empty() ? NAN : reference.t.back();
    if (!(last >= t_end - 1e-12 * std::fabs(t_end)))
        return "ends at t = " + num(last) + ", before the end time " + num(t_end);
    while (!reference.events.empty() && reference.events.back().t > t_end) reference.events.pop_back();
    // The runs sample at t0 + k*dt and t_end: the reference must have a row at each.
    RecordedRun grid;
    grid.dof = model.dof();
    const SampleGrid times(model.t0, t_end, eopt.dt);
    for (std::size_t k = 0;; ++k) {
        grid.t.push_back(times.time(k));
        grid.x.insert(grid.x.end(), model.dof(), 0.0);
        if (times.last(k)) break;
    }
    const RunErrors e = compare_runs(reference, grid);
    if (e.sample_times == grid.t.size()) return "";
    return "has " + std::to_string(e.sample_times) + " of the " + std::to_string(grid.t.size()) +
           " sample times t0 + k*dt (dt = " + num(eopt.dt) + ") and t_end";
}

TradeoffResult tradeoff(const Model& model, const TradeoffOptions& o, const RecordedRun& reference,
                        const TradeoffProgress& progress) {
    const EngineOptions eopt = tradeoff_engine_options(model, o);
    {
        RecordedRun fitted = reference;
        const std::string problem = fit_reference(model, o, fitted);
        if (!problem.empty()) throw InputError(std::string(kTradeoff) + "(): the reference " + problem);
    }
    TradeoffResult result;
    result.methods = o.methods.empty() ? tradeoff_methods() : o.methods;
    for (Method method : result.methods) {
        double last_wall = NAN, last_parameter = NAN;
        for (const TradeoffSetting& s : tradeoff_settings(model, method, o.quick)) {
            if (s.sweep == Sweep::tolerance && last_wall > o.budget) {
                if (progress.skipped)
                    progress.skipped(s, "the previous setting took " + num(last_wall, 3) + " s > budget " +
                                            num(o.budget, 3) + " s");
                continue;
            }
            if (s.sweep == Sweep::step && !std::isnan(last_wall)) {
                // A fixed-step run costs in proportion to its number of steps.
                const double predicted = last_wall * last_parameter / s.parameter;
                if (predicted > o.budget) {
                    if (progress.skipped)
                        progress.skipped(s, "predicted " + num(predicted, 3) + " s > budget " + num(o.budget, 3) + " s");
                    continue;
                }
            }
            if (progress.running) progress.running(s);
            TradeoffRow row = measure(model, s, eopt, reference, o.runs);
            if (progress.measured) progress.measured(row);
            last_wall = row.wall;
            last_parameter = s.parameter;
            result.rows.push_back(std::move(row));
        }
    }
    // hsnc's first setting (kernels=auto when the model has AOT kernels) is the base of the ratios.
    for (std::size_t k = 0; k < result.rows.size() && result.base < 0; ++k)
        if (result.rows[k].setting.sweep == Sweep::kernels && result.rows[k].status == "ok")
            result.base = static_cast<int>(k);
    for (TradeoffRow& row : result.rows) {
        if (result.base >= 0) row.time_ratio_to_hsnc = row.wall / result.rows[static_cast<std::size_t>(result.base)].wall;
        if (std::isnan(result.response_magnitude) && row.errors.sample_times)
            result.response_magnitude = row.errors.response_magnitude;
    }
    return result;
}

const TradeoffRow* cheapest_reaching(const TradeoffResult& result, Method method, double level) {
    const TradeoffRow* best = nullptr;
    for (const TradeoffRow& r : result.rows)
        if (r.setting.method == method && r.status == "ok" && !r.errors.diverged &&
            r.errors.relative_position_error <= level && (!best || r.wall < best->wall))
            best = &r;
    return best;
}

}  // namespace hsnc
