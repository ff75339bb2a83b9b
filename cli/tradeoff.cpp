// `hsnc tradeoff MODEL [options]`: the work-precision study of hsnc and the
// numerical baselines on one model (hsnc::tradeoff, analysis/tradeoff.h says
// what is swept and measured). Here: the flags, the reference (read from CSVs
// or computed in process), the progress on stderr, the CSV, the plot
// (output/tradeoff_plot.h) and the summary of the time ratios to hsnc at fixed
// relative accuracies. Every flag and output path is checked before any work.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands.h"
#include "csv_writer.h"
#include "error.h"
#include "input_files.h"
#include "output_file.h"
#include "model_reader.h"
#include "tradeoff.h"
#include "tradeoff_cli.h"
#include "tradeoff_plot.h"

namespace hsnc::cli {
namespace {

std::string num(double v, int digits = 3) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    return buf;
}

// --methods LIST: the methods of this build, each once; empty: all of them.
std::vector<Method> chosen_methods(const std::string& list) {
    const std::vector<Method> known = tradeoff_methods();
    std::vector<Method> out;
    if (list.empty()) return known;
    std::istringstream in(list);
    for (std::string name; std::getline(in, name, ',');) {
        const auto found = std::find_if(known.begin(), known.end(), [&](Method m) { return name == method_name(m); });
        if (found == known.end()) {
            std::string names;
            for (Method m : known) names += std::string(names.empty() ? "" : ", ") + method_name(m);
            throw InputError("--methods: unknown method '" + name + "' (this build has: " + names + ")");
        }
        if (std::find(out.begin(), out.end(), *found) != out.end())
            throw InputError("--methods: '" + name + "' given twice");
        out.push_back(*found);
    }
    if (out.empty()) throw InputError("--methods: empty list");
    return out;
}

// The library names the option (hsnc::OptionError); the command line puts
// back the flag and the value the user gave for it.
InputError flagged(const OptionError& e, const TradeoffOptions& o) {
    struct Flag {
        const char* option;
        const char* flag;
        std::string value;
    };
    const Flag flags[] = {{"t_end", "--t-end", std::isnan(o.t_end) ? "" : num(o.t_end, 17)},
                          {"dt", "--dt", num(o.dt, 17)},
                          {"runs", "--runs", std::to_string(o.runs)},
                          {"budget", "--budget", num(o.budget)},
                          {"methods", "--methods", o.methods},
                          {"digits", "--reference-digits", std::to_string(o.reference_digits)}};
    for (const Flag& f : flags)
        if (e.option() == f.option)
            return InputError(std::string(f.flag) + (f.value.empty() ? "" : " " + f.value) + ": " + e.reason());
    return InputError(e.what());
}

std::string describe(const TradeoffRow& r) {
    std::ostringstream s;
    s << method_name(r.setting.method) << " " << r.setting.label << ": " << num(r.wall) << " s";
    if (r.runs > 1) s << " (median of " << r.runs << ")";
    if (r.status != "ok") s << ", status " << r.status;
    if (r.errors.diverged) s << ", DIVERGED";
    s << ", position error " << num(r.errors.max_position_error, 2) << " m ("
      << num(r.errors.relative_position_error, 2) << " relative), events " << r.errors.matched_events << " of "
      << r.errors.reference_events << " matched (" << r.errors.events << " found)";
    if (r.errors.matched_events) s << ", event-time error " << num(r.errors.max_event_time_error, 2);
    return s.str();
}

void write_csv(CsvFile& csv, const TradeoffResult& study) {
    csv.text("method,setting,parameter,wall_seconds,runs,status,max_position_error,sample_times,events,"
             "reference_events,matched_events,max_event_time_error,time_ratio_to_hsnc,response_magnitude,"
             "relative_position_error,diverged");
    csv.end_row();
    for (const TradeoffRow& r : study.rows) {
        csv.text(method_name(r.setting.method));
        csv.text(r.setting.label.c_str());
        csv.number(r.setting.parameter);
        csv.number(r.wall);
        csv.number(r.runs);
        csv.text(r.status.c_str());
        csv.number(r.errors.max_position_error);
        csv.number(static_cast<double>(r.errors.sample_times));
        csv.number(static_cast<double>(r.errors.events));
        csv.number(static_cast<double>(r.errors.reference_events));
        csv.number(static_cast<double>(r.errors.matched_events));
        csv.number(r.errors.max_event_time_error);
        csv.number(r.time_ratio_to_hsnc);
        csv.number(r.errors.response_magnitude);
        csv.number(r.errors.relative_position_error);
        csv.number(r.errors.diverged ? 1 : 0);
        csv.end_row();
    }
    csv.commit();
}

TradeoffPlot plot_of(const Model& model, const TradeoffResult& study, const std::string& reference_label) {
    TradeoffPlot p;
    p.model = model.name;
    p.reference_label = reference_label;
    p.magnitude = study.response_magnitude;
    p.diverged_ratio = kDivergedRatio;
    for (Method m : study.methods) p.curves.push_back({method_name(m), m != Method::hsnc});
    p.min_wall = INFINITY;
    for (const TradeoffRow& r : study.rows) {
        p.any_diverged = p.any_diverged || r.errors.diverged;
        p.any_matched = p.any_matched || (r.status == "ok" && !r.errors.diverged && r.errors.matched_events > 0);
        p.min_wall = std::min(p.min_wall, r.wall);
        p.max_wall = std::max(p.max_wall, r.wall);
    }
    return p;
}

// The summary (stdout): the response's magnitude, hsnc's point, then for each
// baseline the cheapest run that reaches each relative accuracy, as a time
// ratio to hsnc. Diverged runs reach nothing.
void print_summary(const TradeoffResult& study, std::ostream& out) {
    out << "response magnitude max |x_ref| = " << num(study.response_magnitude) << " m; errors relative to it\n";
    const TradeoffRow* base = study.base >= 0 ? &study.rows[static_cast<std::size_t>(study.base)] : nullptr;
    if (base)
        out << "hsnc " << base->setting.label << ": " << num(base->wall) << " s, position error "
            << num(base->errors.relative_position_error, 2) << " relative (" << num(base->errors.max_position_error, 2)
            << " m), events " << base->errors.matched_events << " of " << base->errors.reference_events
            << " matched\n";
    for (Method m : study.methods) {
        if (m == Method::hsnc) continue;
        std::ostringstream line;
        line << method_name(m) << ":";
        for (double level : {1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12}) {
            const TradeoffRow* best = cheapest_reaching(study, m, level);
            line << "  relative error<=" << num(level, 1) << ": ";
            if (!best)
                line << "not reached";
            else if (base)
                line << num(best->time_ratio_to_hsnc) << "x hsnc (" << best->setting.label << ")";
            else
                line << num(best->wall) << " s (" << best->setting.label << ")";
        }
        const auto diverged = std::count_if(study.rows.begin(), study.rows.end(), [m](const TradeoffRow& r) {
            return r.setting.method == m && r.errors.diverged;
        });
        if (diverged) line << "  (" << diverged << " diverged)";
        out << line.str() << "\n";
    }
}

}  // namespace

int tradeoff(const TradeoffOptions& o, const ReferenceRunner& in_process) {
    const Model model = read_model(o.model, with_t_end(o.overrides, o.t_end));
    hsnc::TradeoffOptions study;
    study.t_end = o.t_end;
    study.dt = o.dt;
    study.quick = o.quick;
    study.budget = o.budget;
    study.runs = o.runs;
    ReferenceRunner runner = in_process;
    try {
        check_tradeoff_options(model, study);  // --t-end, --dt, --runs, --budget
        if (o.reference_out.empty() != o.reference_events.empty())
            throw InputError(
                "--reference-out and --reference-events: give both (the reference trajectory and its events)");
        if (o.reference_out.empty() && !runner) runner = reference_runner(o.reference_digits);
    } catch (const OptionError& e) {
        throw flagged(e, o);
    }
    if (!o.plot.empty() && o.csv.empty()) throw InputError("--plot: needs --csv (the table it draws)");
    study.methods = chosen_methods(o.methods);
    // Every output path before any work (the reference alone can take minutes).
    // The reference files are inputs: no output may replace them (input_files.h).
    if (!o.reference_out.empty()) note_input_file(o.reference_out);
    if (!o.reference_events.empty()) note_input_file(o.reference_events);
    std::unique_ptr<OutputTarget> csv_target, plot_target;
    std::vector<const OutputTarget*> targets;
    if (!o.csv.empty()) targets.push_back((csv_target = std::make_unique<OutputTarget>(check_output("--csv", o.csv))).get());
    if (!o.plot.empty())
        targets.push_back((plot_target = std::make_unique<OutputTarget>(check_output("--plot", o.plot))).get());
    check_distinct(targets);
    std::unique_ptr<CsvFile> csv;  // opened now, committed at the end; removed on any error before
    if (csv_target) csv = std::make_unique<CsvFile>(*csv_target);

    // The reference: read, or computed in process.
    RecordedRun reference;
    std::string reference_label;
    if (!o.reference_out.empty()) {
        reference = read_reference(model, o.reference_out, o.reference_events);
        const std::string problem = fit_reference(model, study, reference);
        if (!problem.empty())
            throw InputError("--reference-out '" + o.reference_out + "': " + problem +
                             (problem.compare(0, 4, "has ") == 0 ? "; sample the reference on that grid, or give its --dt"
                                                                 : ""));
        reference_label = o.reference_out.substr(o.reference_out.find_last_of('/') + 1);
        std::fprintf(stderr, "tradeoff: reference from %s and %s: %zu samples, %zu events up to t = %s\n",
                     o.reference_out.c_str(), o.reference_events.c_str(), reference.t.size(), reference.events.size(),
                     num(tradeoff_engine_options(model, study).t_end, 6).c_str());
    } else {
        std::fprintf(stderr, "tradeoff: computing the reference (%d digits) ...\n", o.reference_digits);
        const auto start = std::chrono::steady_clock::now();
        try {
            reference = compute_reference(model, study, runner);
        } catch (const RunError& e) {
            throw RunError(std::string("tradeoff: ") + e.what());
        }
        const std::string problem = fit_reference(model, study, reference);
        if (!problem.empty()) throw RunError("tradeoff: the reference run " + problem);
        reference_label = std::to_string(o.reference_digits) + "-digit engine";
        std::fprintf(stderr, "tradeoff: reference (%d digits): %s s, %zu samples, %zu events\n", o.reference_digits,
                     num(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()).c_str(),
                     reference.t.size(), reference.events.size());
    }

    // On a terminal, say what is running (a slow setting takes seconds), then overwrite it.
    const bool tty = ::isatty(2) != 0;
    TradeoffProgress progress;
    progress.running = [tty](const TradeoffSetting& s) {
        if (tty) std::fprintf(stderr, "tradeoff: running %s %s ...", method_name(s.method), s.label.c_str());
    };
    progress.measured = [tty](const TradeoffRow& r) {
        if (tty) std::fprintf(stderr, "\r\033[K");
        std::fprintf(stderr, "tradeoff: %s\n", describe(r).c_str());
    };
    progress.skipped = [](const TradeoffSetting& s, const std::string& why) {
        std::fprintf(stderr, "tradeoff: %s %s: skipped (%s)\n", method_name(s.method), s.label.c_str(), why.c_str());
    };
    const TradeoffResult result = hsnc::tradeoff(model, study, reference, progress);

    if (csv) write_csv(*csv, result);
    // The figure reads the table where it is now: under its temporary name
    // until the command's outputs are renamed together (output_file.h).
    if (!o.plot.empty() && !result.rows.empty())
        plot_tradeoff(plot_of(model, result, reference_label), csv->file().committed_at(), *plot_target);
    print_summary(result, std::cout);
    return 0;
}

void add_tradeoff(CLI::App& app, int& exit_code) {
    auto o = std::make_shared<TradeoffOptions>();
    auto* sub = app.add_subcommand(
        "tradeoff", "work-precision: wall time and error against a reference of hsnc and the numerical baselines");
    sub->add_option("MODEL", o->model, "model file (TOML)")->required();
    sub->add_option("--t-end", o->t_end, "end time (default [simulate].t_end)");
    sub->add_option("--set", o->overrides.set, "override a parameter, NAME=VALUE (repeatable)");
    sub->add_option("--x0", o->overrides.x0, "override an initial position, NAME=VALUE (repeatable)");
    sub->add_option("--v0", o->overrides.v0, "override an initial velocity, NAME=VALUE (repeatable)");
    sub->add_option("--dt", o->dt, "positions are compared at t0, t0+DT, ... and t_end (default: (t_end-t0)/1000)");
    sub->add_option("--reference-out", o->reference_out,
                    "reference trajectory CSV (contract format, sampled at t0 + k*DT); with --reference-events");
    sub->add_option("--reference-events", o->reference_events, "reference events CSV (contract format)");
    sub->add_option("--reference-digits", o->reference_digits,
                    "digits of the in-process reference when no reference CSVs are given (default 40)");
    sub->add_option("--csv", o->csv,
                    "write one row per run: setting, wall time, errors (absolute and relative to max |x_ref|), "
                    "time ratio to hsnc, diverged");
    sub->add_option("--plot", o->plot, "draw the work-precision plot from --csv into this PNG (gnuplot)");
    sub->add_option("--methods", o->methods, "comma-separated methods to measure (default: all this build has)");
    sub->add_flag("--quick", o->quick, "fewer settings per method (about half)");
    sub->add_option("--budget", o->budget,
                    "seconds: skip a setting predicted to take longer; stop an adaptive sweep after one did (default 20)");
    sub->add_option("--runs", o->runs,
                    "timed runs per setting, the median reported (default 0: as many as fit in about 0.2 s, "
                    "odd, at most 51)");
    sub->callback([o, &exit_code] { exit_code = tradeoff(*o); });
}

}  // namespace hsnc::cli
