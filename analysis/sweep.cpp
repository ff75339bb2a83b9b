#include "hsnc/sweep.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>
#include <utility>

#include "assembly.h"
#include "codim_curve.h"
#include "continuation.h"
#include "engine.h"
#include "file_read.h"
#include "hsnc/simulate.h"
#include "input_files.h"
#include "model_hash.h"
#include "number_text.h"
#include "sweep_detail.h"
#include "sweep_point.h"

namespace hsnc {
namespace {

constexpr const char* kPlan = "hsnc::SweepPlan";

std::string num(double v) {
    char text[40];
    std::snprintf(text, sizeof text, "%.17g", v);
    return text;
}

std::string override_name(const std::string& raw) { return raw.substr(0, raw.find('=')); }

double parameter_value(const Model& m, const std::string& name) {
    for (const auto& p : m.parameters)
        if (p.first == name) return p.second;
    return std::nan("");
}

bool has_parameter(const Model& m, const std::string& name) {
    for (const auto& p : m.parameters)
        if (p.first == name) return true;
    return false;
}

// A swept name that is an initial state coordinate (is_state_coordinate) of
// a dof of `m`: the dof's index, or npos.
std::size_t state_dof(const Model& m, const std::string& name) {
    if (!is_state_coordinate(name)) return std::string::npos;
    for (std::size_t i = 0; i < m.masses.size(); ++i)
        if (m.masses[i].name == name.substr(3)) return i;
    return std::string::npos;
}

// `name` = v in `ov`: a parameter's --set, or an initial position's or velocity's.
void set_swept(ModelOverrides& ov, const std::string& name, double v) {
    if (name.compare(0, 3, "x0.") == 0)
        ov.x0.push_back(name.substr(3) + "=" + num(v));
    else if (name.compare(0, 3, "v0.") == 0)
        ov.v0.push_back(name.substr(3) + "=" + num(v));
    else
        ov.set.push_back(name + "=" + num(v));
}

// The value of a swept name in `m`.
double swept_value(const Model& m, const std::string& name) {
    const std::size_t i = state_dof(m, name);
    if (i == std::string::npos) return parameter_value(m, name);
    return name[0] == 'x' ? m.x0[i] : m.v0[i];
}

// Whether `m` has the swept name (a parameter or an initial state coordinate).
bool has_swept(const Model& m, const std::string& name) {
    return has_parameter(m, name) || state_dof(m, name) != std::string::npos;
}

// Shared by the threads of one run: progress and the first failure.
struct Context {
    std::mutex mutex;
    std::size_t done = 0, total = 0;
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    const SweepOptions* options = nullptr;
    std::atomic<bool> cut{false};  // SweepOptions::stop ended a task early
};

}  // namespace

SweepDirection sweep_direction_from_name(const std::string& name) {
    for (SweepDirection d : {SweepDirection::up, SweepDirection::down, SweepDirection::both})
        if (name == sweep_direction_name(d)) return d;
    throw OptionError("hsnc::sweep_direction_from_name", "direction", "'" + name + "'", "expected up, down or both");
}

const char* sweep_direction_name(SweepDirection d) {
    switch (d) {
    case SweepDirection::up: return "up";
    case SweepDirection::down: return "down";
    case SweepDirection::both: return "both";
    }
    return "?";
}

SweepPlan SweepPlan::from_file(const std::string& path, const ModelOverrides& overrides, SweepOptions options) {
    struct stat st;
    const FileRead file = read_regular_file(path, kMaxModelFileBytes, &st);
    if (file.status != FileRead::Status::ok) throw InputError("cannot read model file '" + path + "': " + file.problem);
    note_input_file(path, st);  // no output of the run may replace it
    return SweepPlan(file.bytes, path, overrides, std::move(options));
}

SweepPlan::SweepPlan(const std::string& text, const std::string& source, const ModelOverrides& overrides,
                     SweepOptions options)
    : options_(std::move(options)), text_(text), source_(source), overrides_(overrides) {
    SweepOptions& o = options_;
    // The model as given (parameters at the file's values): names, checks.
    model_ = parse_model(text, source, overrides);
    if (o.param.empty()) throw OptionError(kPlan, "param", "''", "required: the parameter to sweep");
    if (!has_swept(model_, o.param))
        throw OptionError(kPlan, "param", o.param,
                          "no parameter named '" + o.param + "' in " + source + " (nor x0.DOF or v0.DOF of a dof)");
    if (!std::isfinite(o.from)) throw OptionError(kPlan, "from", shortest_text(o.from), "must be a finite number");
    if (!std::isfinite(o.to)) throw OptionError(kPlan, "to", shortest_text(o.to), "must be a finite number");
    if (o.points < 1) throw OptionError(kPlan, "points", std::to_string(o.points), "must be >= 1");
    if (o.points > 100'000'000) throw OptionError(kPlan, "points", std::to_string(o.points), "must be <= 1e8");
    if (o.max_periods < 1) throw OptionError(kPlan, "max_periods", std::to_string(o.max_periods), "must be >= 1");
    if (o.record_periods < 1)
        throw OptionError(kPlan, "record_periods", std::to_string(o.record_periods), "must be >= 1");
    if (o.max_periods > 1'000'000'000 || o.record_periods > 1'000'000'000)
        throw OptionError(kPlan, o.max_periods > 1'000'000'000 ? "max_periods" : "record_periods",
                          std::to_string(std::max(o.max_periods, o.record_periods)), "must be <= 1e9");
    if (!o.param2.empty()) {
        if (o.param2 == o.param)
            throw OptionError(kPlan, "param2", o.param2, "is the swept parameter itself");
        if (!has_swept(model_, o.param2))
            throw OptionError(
                kPlan, "param2", o.param2,
                "no parameter named '" + o.param2 + "' in " + source + " (nor x0.DOF or v0.DOF of a dof)");
        if (o.values2.empty()) throw OptionError(kPlan, "values2", "''", "required with param2: its values");
    } else if (!o.values2.empty()) {
        throw OptionError(kPlan, "values2", shortest_text(o.values2[0]), "given without param2");
    }
    for (double v : o.values2)
        if (!std::isfinite(v)) throw OptionError(kPlan, "values2", shortest_text(v), "must be finite numbers");
    for (const std::string& raw : overrides.set) {
        const std::string name = override_name(raw);
        if (name == o.param || (!o.param2.empty() && name == o.param2))
            throw OptionError(kPlan, name == o.param ? "param" : "param2", name,
                              "also set by an override ('" + raw + "'): a swept parameter takes the sweep's values");
    }
    for (const std::string* name : {&o.param, &o.param2})
        if (state_dof(model_, *name) != std::string::npos) {
            const char* which = name == &o.param ? "param" : "param2";
            if (o.continuation)
                throw OptionError(kPlan, which, *name, "an initial state coordinate does not go with continuation");
            if (!o.restart_each)
                throw OptionError(kPlan, which, *name,
                                  "an initial state coordinate is swept with restart_each only (every point from its "
                                  "own initial state)");
        }
    if (o.harmonics > kSweepMaxHarmonics)
        throw OptionError(kPlan, "harmonics", std::to_string(o.harmonics),
                          "must be <= " + std::to_string(kSweepMaxHarmonics));
    if (!(o.escape >= 0) || !std::isfinite(o.escape))
        throw OptionError(kPlan, "escape", shortest_text(o.escape), "must be finite and >= 0 (0: no bound)");
    if (o.escape > 0 && o.continuation)
        throw OptionError(kPlan, "escape", shortest_text(o.escape),
                          "does not go with continuation (a branch of periodic orbits escapes nowhere)");
    if (o.method == Method::cvode && !HSNC_WITH_CVODE)
        throw OptionError(kPlan, "method", "cvode", "not available: this build has no SUNDIALS CVODE");
    try {
        validate(o.method, o.integrator);
    } catch (const InputError& e) {
        throw OptionError(kPlan, "method", method_name(o.method), e.what());
    }
    if (o.start_periods > 0 && !o.continuation)
        throw OptionError(kPlan, "start_periods", std::to_string(o.start_periods), "only with continuation");
    if (o.continuation) {
        if (o.restart_each)
            throw OptionError(kPlan, "restart_each", "true", "does not go with continuation (a branch is followed point to point)");
        if (o.method != Method::hsnc)
            throw OptionError(kPlan, "method", method_name(o.method), "continuation needs the exact method hsnc (shooting)");
        if (o.points < 2) throw OptionError(kPlan, "points", std::to_string(o.points), "must be >= 2 with continuation");
        if (o.from == o.to)
            throw OptionError(kPlan, "to", shortest_text(o.to), "must differ from from with continuation");
        if (o.max_steps > 100'000'000)
            throw OptionError(kPlan, "max_steps", std::to_string(o.max_steps), "must be <= 1e8");
        if (o.start_periods > kSweepMaxStartPeriods)
            throw OptionError(kPlan, "start_periods", std::to_string(o.start_periods),
                              "must be <= " + std::to_string(kSweepMaxStartPeriods));
        if (o.start_periods > 1 && !o.track.empty())
            throw OptionError(kPlan, "start_periods", std::to_string(o.start_periods),
                              "track follows orbits of one forcing period, for now");
        if (!o.track.empty()) {
            if (o.track != "fold" && o.track != "period_doubling" && o.track != "neimark_sacker" &&
                o.track != "grazing")
                throw OptionError(kPlan, "track", o.track, "must be fold, period_doubling, neimark_sacker or grazing");
            if (o.param2.empty()) throw OptionError(kPlan, "track", o.track, "needs param2: the second parameter");
            if (o.values2.size() != 2 || o.values2[0] == o.values2[1])
                throw OptionError(kPlan, "values2", o.values2.empty() ? "''" : shortest_text(o.values2[0]),
                                  "with track: two different values, where the curve starts and towards where it goes");
            if (o.branch_switch != 0)
                throw OptionError(kPlan, "branch_switch", std::to_string(o.branch_switch), "does not go with track");
            if (!model_.jenkins.empty())
                throw OptionError(kPlan, "track", o.track,
                                  "the model has Jenkins elements, which track does not take, for now");
        }
        if (o.branch_switch < 0 || o.branch_switch > kSweepMaxBranchSwitch)
            throw OptionError(kPlan, "branch_switch", std::to_string(o.branch_switch),
                              "must be 0 .. " + std::to_string(kSweepMaxBranchSwitch) + " (doublings followed)");
    } else if (o.max_steps != 0) {
        throw OptionError(kPlan, "max_steps", std::to_string(o.max_steps), "only with continuation");
    } else if (o.branch_switch != 0) {
        throw OptionError(kPlan, "branch_switch", std::to_string(o.branch_switch), "only with continuation");
    } else if (!o.track.empty()) {
        throw OptionError(kPlan, "track", o.track, "only with continuation");
    }
    // Jenkins elements and stuck pairs: the points carry the sliders
    // (State::slider) on hsnc, rk45 and cvode, and so does a continuation's
    // shooting (y = (x, v, s)); ab4 takes neither.
    if (const std::string what = stick_elements(model_); !what.empty()) {
        if (o.method == Method::ab4)
            throw OptionError(kPlan, "method", method_name(o.method),
                              "the model has " + what + ", which hsnc, rk45 and cvode run, for now");
    }
    if (o.threads == 0) o.threads = std::max(1u, std::thread::hardware_concurrency());

    // The values, from .. to.
    const std::size_t N = o.points;
    values_ = sweep_values(o.from, o.to, N);

    // Every point's model, read now: a value at which the model is invalid is
    // bad input, found before anything runs.
    // (A curve of --track: one line, at its first value.)
    const std::size_t lines = o.track.empty() ? std::max<std::size_t>(1, o.values2.size()) : 1;
    models_.reserve(lines * N);
    for (std::size_t l = 0; l < lines; ++l)
        for (std::size_t j = 0; j < N; ++j) {
            ModelOverrides ov = overrides;
            set_swept(ov, o.param, values_[j]);
            std::string at = o.param + " = " + shortest_text(values_[j]);
            if (!o.param2.empty()) {
                set_swept(ov, o.param2, o.values2[l]);
                at += ", " + o.param2 + " = " + shortest_text(o.values2[l]);
            }
            Model m;
            try {
                m = parse_model(text, source, ov);
            } catch (const InputError& e) {
                throw InputError(std::string("sweep at ") + at + ": " + e.what());
            }
            // The override's text reads back as the value (17 digits), so the
            // CSV's column is the value the point ran with.
            if (swept_value(m, o.param) != values_[j])
                throw InputError("sweep at " + at + ": the value does not read back exactly");
            sweep_detail::forcing_frequency(m, "sweep at " + at);
            m.parameter_expressions.clear();
            m.field_expressions.clear();
            models_.push_back(std::move(m));
        }

    // Tasks in output order.
    std::vector<SweepDirection> dirs;
    if (o.direction != SweepDirection::down) dirs.push_back(SweepDirection::up);
    if (o.direction != SweepDirection::up) dirs.push_back(SweepDirection::down);
    for (std::size_t l = 0; l < lines; ++l)
        for (SweepDirection d : dirs) {
            if (o.restart_each)
                for (std::size_t j = 0; j < N; ++j) tasks_.push_back(Task{l, d, j, 1});
            else
                tasks_.push_back(Task{l, d, 0, N});
        }

    // The fingerprint: the model as read (values, initial state) and the options.
    std::ostringstream fp;
    std::string canon = model_canonical_text(model_);
    for (const auto& p : model_.parameters) canon += p.first + "=" + num(p.second) + "\n";
    canon += "t0=" + num(model_.t0) + "\n";
    for (std::size_t i = 0; i < model_.dof(); ++i) canon += num(model_.x0[i]) + " " + num(model_.v0[i]) + "\n";
    char hash[20];
    std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(fnv1a64(canon)));
    fp << "model=" << model_.name << " hash=" << hash << " param=" << o.param << " from=" << num(o.from)
       << " to=" << num(o.to) << " points=" << N << " direction=" << sweep_direction_name(o.direction)
       << " max_periods=" << o.max_periods << " record_periods=" << o.record_periods
       << " restart_each=" << (o.restart_each ? 1 : 0) << " param2=" << (o.param2.empty() ? "-" : o.param2)
       << " values2=";
    for (std::size_t l = 0; l < o.values2.size(); ++l) fp << (l ? "," : "") << num(o.values2[l]);
    if (o.values2.empty()) fp << "-";
    fp << " diagram=" << (o.diagram ? 1 : 0) << " method=" << method_name(o.method);
    if (o.continuation) fp << " continuation=1 max_steps=" << o.max_steps;
    if (o.branch_switch) fp << " branch_switch=" << o.branch_switch;
    if (o.start_periods) fp << " start_periods=" << o.start_periods;
    if (!o.track.empty()) fp << " track=" << o.track;
    if (o.harmonics) fp << " harmonics=" << o.harmonics;
    if (o.escape > 0) fp << " escape=" << num(o.escape);
    if (o.method != Method::hsnc)
        fp << " h=" << num(o.integrator.h) << " rtol=" << num(o.integrator.rtol) << " atol=" << num(o.integrator.atol);
    fingerprint_ = fp.str();
}

const Model& SweepPlan::point_model(std::size_t line, std::size_t j) const { return models_[line * values_.size() + j]; }

std::size_t SweepPlan::task_points(std::size_t i) const { return tasks_.at(i).count; }

std::vector<SweepPoint> SweepPlan::run_task(std::size_t i) const {
    Context c;
    c.total = tasks_.at(i).count;
    c.options = &options_;
    return run_task(i, &c);
}

namespace {

void report(Context& c, const SweepOptions& o, const SweepPoint& b, double seconds) {
    if (!o.progress) return;
    const auto t1 = std::chrono::steady_clock::now();
    std::lock_guard<std::mutex> lock(c.mutex);
    SweepProgress pr;
    pr.done = ++c.done;
    pr.total = o.continuation ? 0 : c.total;
    pr.seconds = seconds;
    pr.elapsed = std::chrono::duration<double>(t1 - c.start).count();
    pr.value = b.value;
    pr.value2 = b.value2;
    pr.direction = b.direction;
    pr.settled = b.settled;
    pr.periods = b.periods;
    pr.multiple = b.multiple;
    pr.failure = b.failure;
    pr.continuation = o.continuation;
    pr.stable = b.stable;
    pr.max_multiplier = b.max_multiplier;
    pr.bifurcation = b.bifurcation;
    o.progress(pr);
}

}  // namespace

std::vector<SweepPoint> SweepPlan::run_task(std::size_t i, void* context) const {
    Context& c = *static_cast<Context*>(context);
    const Task& task = tasks_.at(i);
    const std::size_t N = values_.size();
    const bool has2 = !options_.param2.empty();
    const double v2 = has2 ? options_.values2[task.line] : std::nan("");
    auto value_index = [&](std::size_t position) {
        return task.direction == SweepDirection::up ? position : N - 1 - position;
    };
    std::string where;
    if (has2) where += ", " + options_.param2 + " = " + shortest_text(v2);
    where += std::string(" (") + sweep_direction_name(task.direction) + ")";
    sweep_detail::check_cancel(options_);

    if (options_.continuation) {
        sweep_detail::Branch branch;
        branch.param = options_.param;
        branch.where = where;
        const bool up = task.direction == SweepDirection::up;
        branch.start = up ? options_.from : options_.to;
        branch.end = up ? options_.to : options_.from;
        branch.start_model = &point_model(task.line, up ? 0 : N - 1);
        branch.model_at = [this, v2, has2](double p) { return model_at(p, has2 ? &v2 : nullptr); };
        branch.value2 = v2;
        bool cut = false;
        const auto done = [&](const SweepPoint& p, double seconds) { report(c, options_, p, seconds); };
        std::vector<SweepPoint> out;
        if (options_.track.empty()) {
            out = sweep_detail::run_continuation(branch, options_, done, &cut);
        } else {
            sweep_detail::CurveSpec curve;
            curve.kind = options_.track;
            curve.param = options_.param;
            curve.param2 = options_.param2;
            curve.start2 = options_.values2[0];
            curve.end2 = options_.values2[1];
            curve.model_at = [this](double p, double q) { return model_at(p, &q); };
            out = sweep_detail::run_curve(branch, curve, options_, done, &cut);
        }
        if (cut) c.cut = true;
        return out;
    }

    sweep_detail::State state;
    {
        const Model& first = point_model(task.line, value_index(task.first));
        state.x = first.x0;
        state.v = first.v0;
        state.slider = first.slider0;
    }
    std::vector<SweepPoint> out;
    out.reserve(task.count);
    for (std::size_t q = task.first; q < task.first + task.count; ++q) {
        sweep_detail::check_cancel(options_);
        if (sweep_detail::stop_requested(options_)) {  // a graceful stop: keep the points finished
            c.cut = true;
            break;
        }
        const std::size_t j = value_index(q);
        const Model& m = point_model(task.line, j);
        if (options_.restart_each) {
            state.x = m.x0;
            state.v = m.v0;
            state.slider = m.slider0;
        }
        const std::string what = options_.param + " = " + shortest_text(values_[j]) + where;
        const auto t0 = std::chrono::steady_clock::now();
        const sweep_detail::State before = state;
        SweepPoint p;
        try {
            p = sweep_detail::run_point(m, state, options_, what);
        } catch (const RunError& e) {
            // The point gives a row that says so; the next starts where this one did.
            p = SweepPoint();
            p.failure = e.what();
            sweep_detail::mark_failed(p, m.dof(), options_.harmonics);
            state = before;
        }
        p.value = values_[j];
        p.value2 = v2;
        p.direction = task.direction;
        out.push_back(std::move(p));
        report(c, options_, out.back(), std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    return out;
}

std::vector<std::vector<SweepPoint>> SweepPlan::run_tasks(const std::vector<std::size_t>& which,
                                                          bool* stopped) const {
    Context c;
    c.options = &options_;
    for (std::size_t i : which) c.total += tasks_.at(i).count;
    std::vector<std::vector<SweepPoint>> results(which.size());
    std::vector<std::exception_ptr> errors(which.size());
    std::atomic<std::size_t> next{0};
    // After a failure, tasks after it in the list are not started; those
    // before it finish, so the error reported is always that of the first
    // failing task, however the threads were scheduled.
    std::atomic<std::size_t> first_failed{which.size()};
    auto worker = [&] {
        for (;;) {
            const std::size_t k = next.fetch_add(1);
            if (k >= which.size() || k > first_failed.load()) return;
            if (sweep_detail::stop_requested(options_)) {  // not started: no points
                c.cut = true;
                continue;
            }
            try {
                results[k] = run_task(which[k], &c);
            } catch (...) {
                errors[k] = std::current_exception();
                std::size_t f = first_failed.load();
                while (k < f && !first_failed.compare_exchange_weak(f, k)) {
                }
            }
        }
    };
    const std::size_t n_threads = std::min<std::size_t>(options_.threads, which.size());
    if (n_threads <= 1) {
        worker();
    } else {
        std::vector<std::thread> pool;
        for (std::size_t t = 0; t < n_threads; ++t) pool.emplace_back(worker);
        for (std::thread& t : pool) t.join();
    }
    for (std::exception_ptr& e : errors)
        if (e) std::rethrow_exception(e);
    if (stopped) *stopped = c.cut.load();
    return results;
}

Model SweepPlan::model_at(double p, const double* q) const {
    ModelOverrides ov = overrides_;
    set_swept(ov, options_.param, p);
    if (q) set_swept(ov, options_.param2, *q);
    Model m = parse_model(text_, source_, ov);
    m.parameter_expressions.clear();
    m.field_expressions.clear();
    return m;
}

SweepResult SweepPlan::result_header() const {
    SweepResult r;
    r.model = model_.name;
    r.param = options_.param;
    r.param2 = options_.param2;
    r.continuation = options_.continuation;
    r.harmonics = options_.harmonics;
    r.branch_switch = options_.branch_switch;
    r.track = options_.track;
    for (const Mass& m : model_.masses) r.masses.push_back(m.name);
    return r;
}

SweepResult SweepPlan::run() const {
    std::vector<std::size_t> all(tasks_.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
    SweepResult r = result_header();
    for (std::vector<SweepPoint>& t : run_tasks(all))
        for (SweepPoint& p : t) r.points.push_back(std::move(p));
    return r;
}

std::vector<std::size_t> SweepPlan::part_tasks(std::size_t index, std::size_t count) const {
    std::vector<std::size_t> out;
    for (std::size_t i = index; count > 0 && i < tasks_.size(); i += count) out.push_back(i);
    return out;
}

std::string sweep_curve_header(const SweepResult& r) {
    std::string h = r.param + ",direction,settled,periods,multiple";
    for (const std::string& m : r.masses) h += ",xmax_" + m + ",xrms_" + m + ",a1_" + m;
    if (!r.param2.empty()) h += "," + r.param2;
    if (r.continuation) h += ",stable,max_multiplier,bifurcation";
    if (r.branch_switch) h += ",branch";
    for (const std::string& m : r.masses)
        for (std::size_t k = 1; k <= r.harmonics; ++k) {
            const std::string ks = std::to_string(k);
            h += ",amp" + ks + "_" + m + ",phase" + ks + "_" + m;
        }
    return h;
}

std::vector<double> sweep_values(double from, double to, std::size_t points) {
    std::vector<double> v(points);
    for (std::size_t j = 0; j < points; ++j)
        v[j] = j == 0            ? from
               : j + 1 == points ? to
                                 : from + (to - from) * static_cast<double>(j) / static_cast<double>(points - 1);
    return v;
}

bool is_state_coordinate(const std::string& name) {
    return name.size() > 3 && (name.compare(0, 3, "x0.") == 0 || name.compare(0, 3, "v0.") == 0);
}

bool is_basins(const SweepResult& r) {
    return is_state_coordinate(r.param) && is_state_coordinate(r.param2);
}

namespace {

// The grid on which the recorded states of the points that did not settle
// are compared: each coordinate (x then v of every mass) over its range
// among all recorded states of the sweep, in kSetCells cells.
constexpr double kSetCells = 20;
// A point whose last kSetLast recorded states all lie in cells of settled
// points' orbits is a slow transient towards one of them, not a set.
constexpr std::size_t kSetLast = 4;

class StateGrid {
public:
    StateGrid(const SweepResult& r) : n_(r.masses.size()), lo_(2 * n_, INFINITY), width_(2 * n_, 1) {
        std::vector<double> hi(2 * n_, -INFINITY);
        for (const SweepPoint& p : r.points) {
            if (!p.failure.empty()) continue;
            for (std::size_t row = 0; row < p.strobe_t.size(); ++row)
                for (std::size_t c = 0; c < 2 * n_; ++c) {
                    lo_[c] = std::min(lo_[c], coordinate(p, row, c));
                    hi[c] = std::max(hi[c], coordinate(p, row, c));
                }
        }
        for (std::size_t c = 0; c < 2 * n_; ++c)
            if (hi[c] > lo_[c]) width_[c] = (hi[c] - lo_[c]) / kSetCells;
    }
    std::vector<long> cell(const SweepPoint& p, std::size_t row) const {
        std::vector<long> key(2 * n_);
        for (std::size_t c = 0; c < 2 * n_; ++c)
            key[c] = std::clamp(static_cast<long>(std::floor((coordinate(p, row, c) - lo_[c]) / width_[c])), 0L,
                                static_cast<long>(kSetCells) - 1);
        return key;
    }

private:
    double coordinate(const SweepPoint& p, std::size_t row, std::size_t c) const {
        return c < n_ ? p.strobe_x[row * n_ + c] : p.strobe_v[row * n_ + c - n_];
    }
    std::size_t n_;
    std::vector<double> lo_, width_;
};

// How closely the recorded states of a point that did not settle must
// repeat (of their largest |x|, |v|) to be a periodic orbit the sweep's
// settling test missed: a subharmonic beyond kSweepMaxMultiple, or a slow
// transient (a multiplier near the unit circle) towards an orbit.
constexpr double kRepeatTolerance = 1e-4;

// The least p (up to half the recorded periods) with which a point's
// recorded states repeat to kRepeatTolerance; 0: none.
int recorded_period(const SweepPoint& p, std::size_t n) {
    const std::size_t rows = p.strobe_t.size();
    double mx = 0, mv = 0;
    for (std::size_t j = 0; j < rows * n; ++j) {
        mx = std::max(mx, std::fabs(p.strobe_x[j]));
        mv = std::max(mv, std::fabs(p.strobe_v[j]));
    }
    for (std::size_t q = 1; 2 * q <= rows; ++q) {
        bool repeats = true;
        for (std::size_t j = 0; j + q * n < rows * n && repeats; ++j)
            repeats = std::fabs(p.strobe_x[j + q * n] - p.strobe_x[j]) <= kRepeatTolerance * mx &&
                      std::fabs(p.strobe_v[j + q * n] - p.strobe_v[j]) <= kRepeatTolerance * mv;
        if (repeats) return static_cast<int>(q);
    }
    return 0;
}

// The periodic attractors the points reached, `of` each point's index in
// `orbits` (-1: none). Settled points name them (canonical states agreeing
// to `tolerance`); then a point that did not settle but whose recorded
// states repeat (recorded_period) reaches the one of its period whose
// canonical state agrees to kRepeatTolerance, or names a new one.
void periodic_orbits(const SweepResult& r, double tolerance, std::vector<Attractor>& orbits, std::vector<long>& of) {
    const std::size_t n = r.masses.size();
    std::vector<int> period(r.points.size(), 0);
    for (std::size_t k = 0; k < r.points.size(); ++k) {
        const SweepPoint& p = r.points[k];
        if (p.failure.empty() && !p.escaped && !p.strobe_t.empty())
            period[k] = p.settled ? p.multiple : recorded_period(p, n);
    }
    // Each periodic point's canonical state: of its first `period` recorded
    // states (the orbit's), the one of least x of the first mass.
    std::vector<std::size_t> canonical(r.points.size(), 0);
    double sx = 0, sv = 0;
    for (std::size_t k = 0; k < r.points.size(); ++k) {
        const SweepPoint& p = r.points[k];
        if (period[k] < 1) continue;
        const std::size_t rows = std::min<std::size_t>(static_cast<std::size_t>(period[k]), p.strobe_t.size());
        for (std::size_t row = 1; row < rows; ++row)
            if (p.strobe_x[row * n] < p.strobe_x[canonical[k] * n]) canonical[k] = row;
        for (std::size_t i = 0; i < n; ++i) {
            sx = std::max(sx, std::fabs(p.strobe_x[canonical[k] * n + i]));
            sv = std::max(sv, std::fabs(p.strobe_v[canonical[k] * n + i]));
        }
    }
    if (sx == 0) sx = 1;
    if (sv == 0) sv = 1;
    // Settled points first, in output order; then the others by period (an
    // orbit of period d before a slower transient that repeats only over 2d).
    std::vector<std::size_t> order;
    for (std::size_t k = 0; k < r.points.size(); ++k)
        if (period[k] > 0 && r.points[k].settled) order.push_back(k);
    const std::size_t settled_points = order.size();
    for (std::size_t k = 0; k < r.points.size(); ++k)
        if (period[k] > 0 && !r.points[k].settled) order.push_back(k);
    std::stable_sort(order.begin() + static_cast<std::ptrdiff_t>(settled_points), order.end(),
                     [&](std::size_t a, std::size_t b) { return period[a] < period[b]; });
    of.assign(r.points.size(), -1);
    for (std::size_t o = 0; o < order.size(); ++o) {
        const std::size_t k = order[o];
        const SweepPoint& p = r.points[k];
        const bool settled = o < settled_points;
        const double tol = settled ? tolerance : std::max(tolerance, kRepeatTolerance);
        const double* x = &p.strobe_x[canonical[k] * n];
        const double* v = &p.strobe_v[canonical[k] * n];
        std::size_t a = 0;
        for (; a < orbits.size(); ++a) {
            bool same = settled ? orbits[a].multiple == period[k] : period[k] % orbits[a].multiple == 0;
            for (std::size_t i = 0; same && i < n; ++i)
                same = std::fabs(orbits[a].x[i] - x[i]) <= tol * sx && std::fabs(orbits[a].v[i] - v[i]) <= tol * sv;
            if (same) break;
        }
        if (a == orbits.size()) orbits.push_back(Attractor{period[k], {x, x + n}, {v, v + n}, 0});
        of[k] = static_cast<long>(a);
    }
}

// The sets the points that did not settle reach: points whose recorded
// states share a cell of the grid are one set (transitively); `of` each
// point's set, by the first of its points (-1: none).
std::vector<long> nonperiodic_sets(const SweepResult& r, const std::vector<long>& orbit_of) {
    const StateGrid grid(r);
    std::set<std::vector<long>> orbit_cells;
    for (std::size_t k = 0; k < r.points.size(); ++k)
        if (orbit_of[k] >= 0)
            for (std::size_t row = 0; row < r.points[k].strobe_t.size(); ++row)
                orbit_cells.insert(grid.cell(r.points[k], row));
    std::vector<long> parent(r.points.size(), -1);
    auto root = [&](long k) {
        while (parent[static_cast<std::size_t>(k)] != k) k = parent[static_cast<std::size_t>(k)];
        return k;
    };
    std::map<std::vector<long>, long> owner;
    for (std::size_t k = 0; k < r.points.size(); ++k) {
        const SweepPoint& p = r.points[k];
        const std::size_t rows = p.strobe_t.size();
        if (!p.failure.empty() || orbit_of[k] >= 0 || p.escaped || rows == 0) continue;
        bool transient = true;
        for (std::size_t row = rows - std::min(rows, kSetLast); row < rows && transient; ++row)
            transient = orbit_cells.count(grid.cell(p, row)) > 0;
        if (transient) continue;
        parent[k] = static_cast<long>(k);
        for (std::size_t row = 0; row < rows; ++row) {
            const auto [it, fresh] = owner.emplace(grid.cell(p, row), static_cast<long>(k));
            if (fresh) continue;
            const long a = root(it->second), b = root(static_cast<long>(k));
            parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);  // the first point is the root
        }
    }
    for (std::size_t k = 0; k < r.points.size(); ++k)
        if (parent[k] >= 0) parent[k] = root(static_cast<long>(k));
    return parent;
}

}  // namespace

Attractors classify_attractors(const SweepResult& r, double tolerance) {
    const std::size_t n = r.masses.size();
    std::vector<Attractor> orbits;
    std::vector<long> orbit_of;
    periodic_orbits(r, tolerance, orbits, orbit_of);
    const std::vector<long> set_of = nonperiodic_sets(r, orbit_of);
    // A set's state: of its points' recorded states, the one of least x of the first mass.
    std::map<long, Attractor> sets;
    for (std::size_t k = 0; k < r.points.size(); ++k) {
        if (set_of[k] < 0) continue;
        const SweepPoint& p = r.points[k];
        Attractor& s = sets[set_of[k]];
        for (std::size_t row = 0; row < p.strobe_t.size(); ++row)
            if (s.x.empty() || p.strobe_x[row * n] < s.x[0]) {
                s.x.assign(p.strobe_x.begin() + static_cast<std::ptrdiff_t>(row * n),
                           p.strobe_x.begin() + static_cast<std::ptrdiff_t>((row + 1) * n));
                s.v.assign(p.strobe_v.begin() + static_cast<std::ptrdiff_t>(row * n),
                           p.strobe_v.begin() + static_cast<std::ptrdiff_t>((row + 1) * n));
            }
    }
    // Numbered in the order of the first point (in output order) that reached each.
    Attractors out;
    std::map<long, int> number;  // orbit index k >= 0, set by first point -(k + 1)
    for (std::size_t k = 0; k < r.points.size(); ++k) {
        const SweepPoint& p = r.points[k];
        int id = 0;
        if (!p.failure.empty())
            id = -1;
        else if (p.escaped)
            id = -2;
        else if (orbit_of[k] >= 0 || set_of[k] >= 0) {
            const long key = orbit_of[k] >= 0 ? orbit_of[k] : -(set_of[k] + 1);
            auto [it, fresh] = number.emplace(key, static_cast<int>(out.list.size() + 1));
            if (fresh) out.list.push_back(orbit_of[k] >= 0 ? orbits[static_cast<std::size_t>(key)] : sets[set_of[k]]);
            id = it->second;
            ++out.list[static_cast<std::size_t>(id - 1)].points;
        }
        out.of_point.push_back(id);
    }
    return out;
}

std::string sweep_diagram_header(const SweepResult& r) {
    std::string h = r.param + ",direction,t";
    for (const std::string& m : r.masses) h += ",x_" + m;
    for (const std::string& m : r.masses) h += ",v_" + m;
    if (!r.param2.empty()) h += "," + r.param2;
    return h;
}

// ---- the text form of points: MPI and part files ----

namespace sweep_detail {
namespace {

// A text as one word: "-" when empty, else with \\, space, newline, tab
// and a lone "-" escaped.
std::string word(const std::string& text) {
    if (text.empty()) return "-";
    if (text == "-") return "\\-";
    std::string w;
    for (char ch : text) {
        if (ch == '\\') w += "\\\\";
        else if (ch == ' ') w += "\\s";
        else if (ch == '\n') w += "\\n";
        else if (ch == '\t') w += "\\t";
        else if (ch == '\r') w += "\\r";
        else w += ch;
    }
    return w;
}

bool unword(const std::string& w, std::string& text) {
    text.clear();
    if (w == "-") return true;
    for (std::size_t i = 0; i < w.size(); ++i) {
        if (w[i] != '\\') {
            text += w[i];
            continue;
        }
        if (++i >= w.size()) return false;
        switch (w[i]) {
        case '\\': text += '\\'; break;
        case 's': text += ' '; break;
        case 'n': text += '\n'; break;
        case 't': text += '\t'; break;
        case 'r': text += '\r'; break;
        case '-': text += '-'; break;
        default: return false;
        }
    }
    return true;
}

}  // namespace

std::vector<std::string> split_lines(const std::string& text) {
    std::vector<std::string> lines;
    std::size_t a = 0;
    while (a < text.size()) {
        std::size_t b = text.find('\n', a);
        if (b == std::string::npos) b = text.size();
        lines.push_back(text.substr(a, b - a));
        a = b + 1;
    }
    return lines;
}

std::string write_tasks(const std::vector<std::size_t>& which, const std::vector<std::vector<SweepPoint>>& points,
                        std::size_t n) {
    std::string s;
    for (std::size_t k = 0; k < which.size(); ++k) {
        s += "task " + std::to_string(which[k]) + " " + std::to_string(points[k].size()) + "\n";
        for (const SweepPoint& p : points[k]) {
            const std::size_t rows = p.strobe_t.size();
            s += num(p.value) + " " + num(p.value2) + " " + sweep_direction_name(p.direction) + " " +
                 (p.escaped   ? "e"
                  : p.settled ? "1"
                              : "0") +
                 " " + std::to_string(p.periods) + " " + std::to_string(p.multiple) + " " + std::to_string(rows);
            for (std::size_t i = 0; i < n; ++i) s += " " + num(p.xmax[i]) + " " + num(p.xrms[i]) + " " + num(p.a1[i]);
            s += " " + std::to_string(p.amp.size());
            for (std::size_t j = 0; j < p.amp.size(); ++j) s += " " + num(p.amp[j]) + " " + num(p.phase[j]);
            for (std::size_t r = 0; r < rows; ++r) {
                s += " " + num(p.strobe_t[r]);
                for (std::size_t i = 0; i < n; ++i) s += " " + num(p.strobe_x[r * n + i]);
                for (std::size_t i = 0; i < n; ++i) s += " " + num(p.strobe_v[r * n + i]);
            }
            s += " " + std::string(p.branch_start ? "1" : "0") + " " + (p.stable ? "1" : "0") + " " +
                 num(p.max_multiplier) + " " + word(p.bifurcation) + " " + word(p.failure) + " " + word(p.stop) + " " +
                 std::to_string(p.branch) + "\n";
        }
    }
    return s;
}

namespace {

struct Reader {
    std::istringstream in;
    std::string where;
    explicit Reader(const std::string& line, std::string w) : in(line), where(std::move(w)) {}
    [[noreturn]] void fail(const std::string& what) const { throw InputError(where + ": " + what); }
    std::string word() {
        std::string w;
        if (!(in >> w)) fail("the line ends early");
        return w;
    }
    double number() {
        const std::string w = word();
        char* end = nullptr;
        const double v = std::strtod(w.c_str(), &end);
        if (end == w.c_str() || *end != '\0') fail("'" + w + "' is not a number");
        return v;
    }
    std::size_t count(std::size_t max) {
        const std::string w = word();
        char* end = nullptr;
        const unsigned long long v = std::strtoull(w.c_str(), &end, 10);
        if (w.empty() || w[0] == '-' || *end != '\0' || v > max) fail("'" + w + "' is not a count up to " + std::to_string(max));
        return static_cast<std::size_t>(v);
    }
    void end() {
        std::string w;
        if (in >> w) fail("unexpected '" + w + "' at the end of the line");
    }
};

}  // namespace

void read_tasks(const std::vector<std::string>& lines, std::size_t first, std::size_t n, const std::string& where,
                std::map<std::size_t, std::vector<SweepPoint>>& out) {
    std::size_t i = first;
    auto at = [&](std::size_t line) { return where + ":" + std::to_string(line + 1); };
    while (i < lines.size()) {
        if (lines[i].empty()) {
            ++i;
            continue;
        }
        Reader head(lines[i], at(i));
        if (head.word() != "task") head.fail("expected 'task INDEX POINTS'");
        const std::size_t index = head.count(std::size_t{1} << 40), count = head.count(100'000'000);
        head.end();
        if (out.count(index)) head.fail("task " + std::to_string(index) + " given twice");
        std::vector<SweepPoint>& pts = out[index];
        ++i;
        for (std::size_t k = 0; k < count; ++k, ++i) {
            if (i >= lines.size()) throw InputError(at(i) + ": the file ends inside task " + std::to_string(index));
            Reader r(lines[i], at(i));
            SweepPoint p;
            p.value = r.number();
            p.value2 = r.number();
            const std::string d = r.word();
            if (d != "up" && d != "down") r.fail("direction '" + d + "'");
            p.direction = d == "up" ? SweepDirection::up : SweepDirection::down;
            const std::string s = r.word();
            if (s != "0" && s != "1" && s != "e") r.fail("settled '" + s + "'");
            p.settled = s == "1";
            p.escaped = s == "e";
            p.periods = r.count(std::size_t{1} << 40);
            p.multiple = static_cast<int>(r.count(kSweepMaxMultiple));
            const std::size_t rows = r.count(1'000'000'000);
            for (std::size_t m = 0; m < n; ++m) {
                p.xmax.push_back(r.number());
                p.xrms.push_back(r.number());
                p.a1.push_back(r.number());
            }
            const std::size_t harmonics = r.count(n * kSweepMaxHarmonics);
            for (std::size_t j = 0; j < harmonics; ++j) {
                p.amp.push_back(r.number());
                p.phase.push_back(r.number());
            }
            for (std::size_t row = 0; row < rows; ++row) {
                p.strobe_t.push_back(r.number());
                for (std::size_t m = 0; m < n; ++m) p.strobe_x.push_back(r.number());
                for (std::size_t m = 0; m < n; ++m) p.strobe_v.push_back(r.number());
            }
            const std::string start = r.word();
            if (start != "0" && start != "1") r.fail("branch start '" + start + "'");
            p.branch_start = start == "1";
            const std::string stable = r.word();
            if (stable != "0" && stable != "1") r.fail("stable '" + stable + "'");
            p.stable = stable == "1";
            p.max_multiplier = r.number();
            for (std::string* text : {&p.bifurcation, &p.failure, &p.stop}) {
                const std::string w = r.word();
                if (!unword(w, *text)) r.fail("'" + w + "' is not an escaped text");
            }
            p.branch = r.count(std::size_t{1} << 40);
            r.end();
            pts.push_back(std::move(p));
        }
    }
}

}  // namespace sweep_detail

// ---- part files ----

namespace {
// 4: the branch switching depth, every point its branch; 5: a point's settled word 'e' (escaped)
constexpr const char* kPartMagic = "hsnc-sweep-part 5";
}

std::string sweep_part_text(const SweepPlan& plan, std::size_t index, std::size_t count,
                            const std::vector<std::vector<SweepPoint>>& task_points, const std::string& interrupted) {
    const SweepResult names = plan.result_header();
    std::string s = std::string(kPartMagic) + "\n";
    s += "fingerprint " + plan.fingerprint() + "\n";
    s += "part " + std::to_string(index + 1) + " " + std::to_string(count) + "\n";
    s += "tasks " + std::to_string(plan.tasks()) + "\n";
    s += "model " + names.model + "\n";
    s += "param " + names.param + "\n";
    s += "param2 " + (names.param2.empty() ? std::string("-") : names.param2) + "\n";
    s += "continuation " + std::string(names.continuation ? "1" : "0") + "\n";
    s += "harmonics " + std::to_string(names.harmonics) + "\n";
    s +=
        "branch_switch " + std::to_string(names.branch_switch) + " " + (names.track.empty() ? "-" : names.track) + "\n";
    s += "masses";
    for (const std::string& m : names.masses) s += " " + m;
    s += "\n";
    s += sweep_detail::write_tasks(plan.part_tasks(index, count), task_points, names.masses.size());
    if (!interrupted.empty()) s += interrupted + "\n";
    return s;
}

SweepResult merge_sweep_parts(const std::vector<std::string>& texts, const std::vector<std::string>& names) {
    if (texts.empty()) throw InputError("sweep merge: no part files given");
    SweepResult r;
    std::string fingerprint;
    std::size_t count = 0, tasks = 0;
    std::vector<char> seen;
    std::map<std::size_t, std::vector<SweepPoint>> all;
    for (std::size_t f = 0; f < texts.size(); ++f) {
        const std::string& where = names.at(f);
        const std::vector<std::string> lines = sweep_detail::split_lines(texts[f]);
        auto field = [&](std::size_t i, const std::string& key) {
            const std::string prefix = key + " ";
            if (i >= lines.size() || lines[i].compare(0, prefix.size(), prefix) != 0)
                throw InputError(where + ":" + std::to_string(i + 1) + ": expected '" + key + " ...'" +
                                 (i == 0 ? "" : " (not a part file of hsnc sweep --part?)"));
            return lines[i].substr(prefix.size());
        };
        if (lines.empty() || lines[0] != kPartMagic)
            throw InputError(where + ":1: not a part file of hsnc sweep --part (expected '" + kPartMagic + "')");
        const std::string fp = field(1, "fingerprint");
        std::istringstream part(field(2, "part"));
        std::size_t i = 0, n = 0;
        if (!(part >> i >> n) || n < 1 || i < 1 || i > n)
            throw InputError(where + ":3: expected 'part I N' with 1 <= I <= N");
        std::size_t t = 0;
        {
            std::istringstream ts(field(3, "tasks"));
            if (!(ts >> t)) throw InputError(where + ":4: expected 'tasks N'");
        }
        const std::string model = field(4, "model"), param = field(5, "param"), param2 = field(6, "param2");
        const std::string cont = field(7, "continuation");
        if (cont != "0" && cont != "1") throw InputError(where + ":8: expected 'continuation 0|1'");
        std::size_t harmonics = 0;
        {
            std::istringstream hs(field(8, "harmonics"));
            if (!(hs >> harmonics) || harmonics > kSweepMaxHarmonics)
                throw InputError(where +
                                 ":9: expected 'harmonics K' with 0 <= K <= " + std::to_string(kSweepMaxHarmonics));
        }
        int branch_switch = 0;
        std::string track;
        {
            std::istringstream bs(field(9, "branch_switch"));
            if (!(bs >> branch_switch >> track) || branch_switch < 0 || branch_switch > kSweepMaxBranchSwitch)
                throw InputError(where + ":10: expected 'branch_switch D TRACK' with 0 <= D <= " +
                                 std::to_string(kSweepMaxBranchSwitch));
            if (track == "-") track.clear();
        }
        std::istringstream ms(field(10, "masses"));
        std::vector<std::string> masses;
        for (std::string m; ms >> m;) masses.push_back(m);
        if (f == 0) {
            fingerprint = fp;
            count = n;
            tasks = t;
            seen.assign(n, 0);
            r.model = model;
            r.param = param;
            r.param2 = param2 == "-" ? "" : param2;
            r.continuation = cont == "1";
            r.harmonics = harmonics;
            r.branch_switch = branch_switch;
            r.track = track;
            r.masses = masses;
        } else if (fp != fingerprint || n != count || t != tasks) {
            throw InputError(where + ": a part of another sweep than " + names[0] + " (" +
                             (fp != fingerprint ? "model or options differ" : "split into a different number of parts") +
                             ")");
        }
        if (seen[i - 1]) throw InputError(where + ": part " + std::to_string(i) + "/" + std::to_string(n) + " given twice");
        seen[i - 1] = 1;
        // A part stopped by SIGINT ends with its '# interrupted ...' line: its
        // tasks lack points, and a merge would be a sweep with holes.
        for (std::size_t k = 11; k < lines.size(); ++k)
            if (lines[k].compare(0, 13, "# interrupted") == 0)
                throw InputError(where + ":" + std::to_string(k + 1) + ": part " + std::to_string(i) + "/" +
                                 std::to_string(n) + " was interrupted ('" + lines[k].substr(2) +
                                 "'): run it again (hsnc sweep --part " + std::to_string(i) + "/" + std::to_string(n) +
                                 ") before merging");
        std::map<std::size_t, std::vector<SweepPoint>> mine;
        sweep_detail::read_tasks(lines, 11, masses.size(), where, mine);
        for (auto& [index, pts] : mine) {
            if (index >= tasks || index % count != i - 1)
                throw InputError(where + ": task " + std::to_string(index) + " does not belong to part " +
                                 std::to_string(i) + "/" + std::to_string(n));
            all[index] = std::move(pts);
        }
    }
    for (std::size_t i = 0; i < count; ++i)
        if (!seen[i])
            throw InputError("sweep merge: part " + std::to_string(i + 1) + "/" + std::to_string(count) + " is missing");
    for (std::size_t i = 0; i < tasks; ++i) {
        auto it = all.find(i);
        if (it == all.end()) throw InputError("sweep merge: task " + std::to_string(i) + " is missing from its part file");
        for (SweepPoint& p : it->second) r.points.push_back(std::move(p));
    }
    return r;
}

}  // namespace hsnc
