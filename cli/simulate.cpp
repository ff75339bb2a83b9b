// `hsnc simulate MODEL [options]` (interface.md sections 3 and 4).
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <sstream>

#include "analysis_flags.h"
#include "commands.h"
#include "csv_writer.h"
#include "engine.h"
#include "error.h"
#include "hsnc/periodic.h"
#include "hsnc/simulate.h"
#include "kernel_cache.h"
#include "model_reader.h"
#include "number_text.h"
#include "sample_grid.h"
#include "section.h"
#include "simulate_outputs.h"

namespace hsnc::cli {
namespace {

struct SimulateOptions {
    std::string model;
    double t_end = NAN;
    ModelOverrides overrides;
    double dt = NAN;
    OutputRequest outputs;  // --out, --events, --plot, --allow-large-output
    std::string method = "hsnc";
    double h = NAN;
    double rtol = 1e-10, atol = 1e-12;
    std::string kernels = "auto";
    std::string cache_dir;
    bool no_cache = false;
    std::uint64_t cache_max_bytes = kDefaultCacheMaxBytes;
    std::uint64_t tier_evaluations = hsnc::SimulateOptions().tier_evaluations;
    std::size_t max_events = 0;
    bool quiet = false;
    std::string precision = "double";
};

// Wraps the CSV observer: counts event kinds, draws a progress bar on a terminal.
class RunObserver : public Observer {
public:
    /// show: the bar (stderr a terminal); log: a line every 10 s instead (stderr not a terminal).
    RunObserver(Observer& inner, double t0, double t_end, bool show, bool log = false)
        : inner_(inner), t0_(t0), t_end_(t_end), show_(show), log_(log && !show),
          start_(std::chrono::steady_clock::now()) {}
    void on_sample(double t, const double* x, const double* v) override {
        inner_.on_sample(t, x, v);
        if ((++samples_ & 1023) == 0) on_progress(t);
    }
    void on_event(double t, EventKind kind, int element, const double* x, const double* v) override {
        inner_.on_event(t, kind, element, x, v);
        ++counts_[static_cast<int>(kind)];
    }
    bool on_progress(double t) override {
        if (!show_ && !log_) return true;
        const double elapsed = seconds();
        const double frac = std::min(1.0, std::max(0.0, (t - t0_) / (t_end_ - t0_)));
        if (log_) {  // not a terminal: a line every 10 s of a long run (the reference takes minutes)
            if (elapsed >= last_draw_ + 10.0) {
                last_draw_ = elapsed;
                std::fprintf(stderr, "hsnc simulate: t = %.6g s, %.1f%%, %.0f s\n", t, 100 * frac, elapsed);
            }
            return true;
        }
        if (elapsed < 0.5 || elapsed - last_draw_ < 0.1) return true;
        last_draw_ = elapsed;
        const int width = 30, filled = static_cast<int>(frac * width);
        std::fprintf(stderr, "\r[%.*s%*s] %5.1f%%  t = %.6g s", filled, "##############################",
                     width - filled, "", 100 * frac, t);
        drawn_ = true;
        return true;
    }
    ~RunObserver() override { clear(); }  // also when the run stops on an error
    void clear() {
        if (drawn_) std::fprintf(stderr, "\r%60s\r", "");
        drawn_ = false;
    }
    double seconds() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    }
    std::size_t count(EventKind k) const { return counts_[static_cast<int>(k)]; }

private:
    Observer& inner_;
    double t0_, t_end_;
    bool show_, log_;
    std::chrono::steady_clock::time_point start_;
    double last_draw_ = 0;
    bool drawn_ = false;
    std::size_t samples_ = 0;
    std::size_t counts_[std::size(kEventKinds)] = {};  // per EventKind
};

// The library names the option (hsnc::OptionError); the command line puts
// back the flag and the text the user gave for it.
std::string flag_value(double v) {
    if (std::isnan(v)) return "";
    return shortest_text(v);
}
InputError flagged(const OptionError& e, const SimulateOptions& o, bool quoted = false) {
    struct Flag {
        const char* option;
        const char* flag;
        std::string value;
    };
    const Flag flags[] = {{"t_end", "--t-end", flag_value(o.t_end)},
                          {"dt", "--dt", flag_value(o.dt)},
                          {"method", "--method", o.method},
                          {"integrator.h", "--h", flag_value(o.h)},
                          {"integrator.rtol", "--rtol", flag_value(o.rtol)},
                          {"integrator.atol", "--atol", flag_value(o.atol)},
                          {"kernels", "--kernels", o.kernels},
                          {"tier_evaluations", "--tier-evaluations", std::to_string(o.tier_evaluations)},
                          {"precision_digits", "--precision", o.precision}};
    for (const Flag& f : flags)
        if (e.option() == f.option) {
            const std::string value = quoted ? "'" + f.value + "'" : f.value;
            return InputError(std::string(f.flag) + (f.value.empty() ? "" : " " + value) + ": " + e.reason());
        }
    return InputError(e.what());
}

// --section period: the rotation number of the section (hsnc::rotation_number)
// in each dof's (x, v) plane; the summary takes the dof whose estimate has
// the smallest error (its two halves agree best), stderr lists them all.
void add_rotation(const Model& model, const SectionRecorder& section, SummaryRow& summary, bool quiet) {
    const std::size_t n = model.dof(), width = 1 + 2 * n, points = section.rows().size() / width;
    RotationNumber best;
    std::string each;
    for (std::size_t i = 0; i < n; ++i) {
        const double* row = section.rows().data();
        const RotationNumber r = rotation_number(row + 1 + i, row + 1 + n + i, points, width);
        if (!std::isnan(r.value) && (std::isnan(best.value) || r.error < best.error)) best = r;
        each += (each.empty() ? "" : ", ") + model.masses[i].name + " " +
                (std::isnan(r.value) ? std::string("-") : shortest_text(r.value) + " (" + shortest_text(r.error) + ")");
    }
    summary.number("rotation", best.value);
    summary.number("rotation_error", best.error);
    if (!quiet)
        std::fprintf(stderr, "hsnc: rotation number over %zu section points (error), per dof: %s\n", points,
                     each.c_str());
}

int simulate(const SimulateOptions& o) {
    const Model model = read_model(o.model, with_t_end(o.overrides, o.t_end));
    hsnc::SimulateOptions run;
    try {
        run.method = method_from_name(o.method);
        run.kernels = kernel_choice_from_name(o.kernels);
        run.precision_digits = precision_digits_from_name(o.precision);
    } catch (const OptionError& e) {
        throw flagged(e, o, e.option() != "precision_digits");
    }
    run.t_end = o.t_end;
    run.dt = o.dt;
    run.max_events = o.max_events;
    run.integrator.h = o.h;
    run.integrator.rtol = o.rtol;
    run.integrator.atol = o.atol;
    run.cache_dir = o.cache_dir;
    run.use_cache = !o.no_cache;
    run.cache_max_bytes = o.cache_max_bytes;
    run.tier_evaluations = o.tier_evaluations;
    try {
        check_simulate_options(model, run);
    } catch (const OptionError& e) {
        throw flagged(e, o);
    }
    const double t_end = std::isnan(o.t_end) ? *model.t_end : o.t_end;
    // Default sampling: 1000 intervals over the run (as the library does).
    const double dt = std::isnan(o.dt) ? SampleGrid::default_dt(model.t0, t_end) : o.dt;
    // Every output path checked before anything is written or run.
    std::unique_ptr<OutputTarget> h5;
    if (!o.outputs.h5.empty()) h5 = std::make_unique<OutputTarget>(check_h5(o.outputs.h5));
    SimulateOutputs outputs(model, o.outputs, t_end, dt, h5.get());
    if (outputs.stroboscopic() && !std::isnan(o.dt)) {
        const double period = outputs.section_period(), m = std::round(period / o.dt);
        if (!(m >= 1.0) || !(std::fabs(period / o.dt - m) <= 1e-9 * m))
            throw InputError("--dt " + shortest_text(o.dt) + ": --section " + o.outputs.section +
                             " takes the state every " + shortest_text(period) +
                             " s: give a --dt that divides it (that period over a whole number), " +
                             "or leave --dt out");
    }
    const std::unique_ptr<H5Archive> archive = open_h5(h5.get(), model, o.overrides);
    SimulateMirror mirror;
    if (archive)
        mirror = {&archive->table("simulate/trajectory"), &archive->table("simulate/events"),
                  &archive->table("simulate/section")};
    outputs.open(mirror);
    RunObserver obs(outputs, model.t0, t_end, !o.quiet && ::isatty(2), !o.quiet);

    run.samples = outputs.samples();
    if (outputs.sample_dt() != dt) run.dt = outputs.sample_dt();  // the plot alone: bounded samples
    const SimulateSummary sum = hsnc::simulate(model, run, obs);
    const std::string& detail = sum.solver_detail;
    obs.clear();
    if (sum.status != RunStatus::ok && sum.status != RunStatus::max_events)
        throw RunError(std::string("simulate: ") + run_status_name(sum.status) + ": " + sum.message);
    outputs.commit();
    // The summary: the line on stdout and, with --h5, the table simulate/summary.
    SummaryRow summary;
    summary.word("status", run_status_name(sum.status));
    summary.word("method", o.method);
    summary.number("t", sum.t);
    summary.number("events", static_cast<double>(sum.events));
    for (EventKind k : kSwitchEventKinds) summary.number(event_kind_name(k), static_cast<double>(obs.count(k)));
    if (!model.load_steps.empty())  // [[load_step]]: the load changes, in the same form (absent otherwise)
        summary.number(event_kind_name(EventKind::load_change), static_cast<double>(obs.count(EventKind::load_change)));
    if (model.has_impacts())  // rigid stops with restitution (absent otherwise)
        summary.number(event_kind_name(EventKind::impact), static_cast<double>(obs.count(EventKind::impact)));
    for (std::size_t i = 0; i < model.dof(); ++i) summary.number("x_" + model.masses[i].name, sum.x[i]);
    for (std::size_t i = 0; i < model.dof(); ++i) summary.number("v_" + model.masses[i].name, sum.v[i]);
    if (outputs.stroboscopic()) add_rotation(model, *outputs.section(), summary, o.quiet);
    if (archive) {
        summary.write(archive->table("simulate/summary"));
        archive->commit();
    }
    std::cout << summary.line() << std::endl;
    if (!o.quiet) {
        const std::string carried =
            sum.restarts ? " (" + std::to_string(sum.restarts) + " carried over a switch)" : std::string();
        std::fprintf(stderr, "hsnc: %zu segments%s, %zu evaluations (%.1f per switch), %zu configurations visited%s%s, %.3f s\n",
                     sum.segments, carried.c_str(), sum.evaluations,
                     sum.events ? static_cast<double>(sum.evaluations) / static_cast<double>(sum.events) : 0.0,
                     sum.configurations, detail.empty() ? "" : ", ", detail.c_str(), obs.seconds());
        if (!o.outputs.section.empty())
            std::fprintf(stderr, "hsnc: Poincare section at %s: %zu points\n", o.outputs.section.c_str(),
                         outputs.section_points());
        if (sum.status == RunStatus::max_events) std::fprintf(stderr, "hsnc: %s\n", sum.message.c_str());
    }
    return 0;
}

}  // namespace

void add_simulate(CLI::App& app, int& exit_code) {
    auto o = std::make_shared<SimulateOptions>();
    auto* sub = app.add_subcommand("simulate", "run a simulation from the model's initial state");
    sub->add_option("MODEL", o->model, "model file (TOML)")->required();
    sub->add_option("--t-end", o->t_end, "end time (default [simulate].t_end)")->check(finite_number());
    sub->add_option("--set", o->overrides.set, "override a parameter, NAME=VALUE (repeatable)");
    sub->add_option("--x0", o->overrides.x0, "override an initial position, NAME=VALUE (repeatable)");
    sub->add_option("--v0", o->overrides.v0, "override an initial velocity, NAME=VALUE (repeatable)");
    sub->add_option("--dt", o->dt, "trajectory rows at t0, t0+DT, ... and t_end (default: (t_end-t0)/1000)")
        ->check(finite_number());
    sub->add_option("--out", o->outputs.out,
                    "trajectory CSV (default: none). A device or FIFO (/dev/null, /dev/stdout) is written "
                    "directly; a directory is refused");
    sub->add_option("--events", o->outputs.events, "switch-event CSV (default: none)");
    sub->add_option("--plot", o->outputs.plot,
                    "draw x(t) of every mass into this PNG (gnuplot): the whole run with the switch events as "
                    "ticks, and a zoom (last 5 forcing periods, else the first 10%) with the events marked");
    add_section_flags(sub, o->outputs.section, o->outputs.section_out, o->outputs.section_plot, "", true);
    sub->add_option("--plot-dofs", o->outputs.plot_dofs,
                    "the dofs --plot draws, comma separated, at most 8 (default: every dof, more than 8 along a colour "
                    "scale)")
        ->needs(sub->get_option("--plot"));
    add_h5_flag(sub, o->outputs.h5,
                "simulate/trajectory as --out, simulate/events as --events, simulate/section, simulate/summary");
    sub->add_flag("--allow-large-output", o->outputs.allow_large_output,
                  "write a trajectory of more than 1e7 rows or about 1 GB (refused without it)");
    sub->add_option("--method", o->method,
                    "hsnc (exact, default); ab4 (fixed-step Adams-Bashforth 4, needs --h); "
                    "rk45 (adaptive Dormand-Prince with event location, --rtol/--atol); "
                    "cvode (SUNDIALS CVODE, Adams with root finding, --rtol/--atol)");
    sub->add_option("--h", o->h, "step of --method ab4 (at most t_end - t0, at least 1e-12 of it)")
        ->check(finite_number());
    sub->add_option("--rtol", o->rtol, "relative tolerance of --method rk45/cvode (default 1e-10)")
        ->check(finite_number());
    sub->add_option("--atol", o->atol, "absolute tolerance of --method rk45/cvode (default 1e-12)")
        ->check(finite_number());
    sub->add_option("--kernels", o->kernels,
                    "auto (default: ahead-of-time kernels when the model has them, else generic; "
                    "never compiles), aot, generic (each configuration's program, derived in double-double, "
                    "interpreted: the kernels' bits without a compiler; interp is another name for it), jit (a "
                    "kernel compiled in-process, or taken from the cache, for each configuration the run enters), "
                    "tiered (generic, then a configuration's kernel from the cache at once, or compiled by a child "
                    "process once it has run --tier-evaluations evaluations: never waits for a compiler), eigen (the "
                    "Eigen solver, written apart from the programs: agrees to rounding, not to the bit; enters a "
                    "configuration faster). Every kind but eigen writes the same bits");
    sub->add_option("--tier-evaluations", o->tier_evaluations,
                    "kernels tiered: evaluations a configuration runs interpreted before its kernel is compiled "
                    "(default 200000)")
        ->check(CLI::PositiveNumber);
    sub->add_option("--cache-dir", o->cache_dir,
                    "keep compiled kernels (jit, tiered) in DIR (default $XDG_CACHE_HOME/hsnc, else ~/.cache/hsnc)");
    auto* no_cache = sub->add_flag("--no-cache", o->no_cache, "read and write no cache: jit compiles every kernel, tiered stays interpreted");
    no_cache->excludes(sub->get_option("--cache-dir"));
    sub->add_option_function<std::string>(
        "--cache-max-size", [o](const std::string& t) { o->cache_max_bytes = parse_byte_size(t, "--cache-max-size"); },
        "keep the cache under this size, evicting the least recently used kernels (default 256M; 0: no limit)");
    sub->add_option("--max-events", o->max_events, "stop after this many switch events (0: no limit)");
    sub->add_option("--precision", o->precision,
                    "double (default); mp:N: the high-precision reference engine, every quantity at N decimal "
                    "digits (N in 20..100, CLN) from the model's double values taken exactly; output still "
                    "rounded to 17 digits. long-double is not offered");
    sub->add_flag("--quiet", o->quiet, "no progress or statistics on stderr");
    sub->callback([o, &exit_code] { exit_code = simulate(*o); });
}

}  // namespace hsnc::cli
