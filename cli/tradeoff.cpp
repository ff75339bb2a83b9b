// `hsnc tradeoff MODEL [options]`: work-precision of hsnc and the numerical
// baselines on one model. Runs (or reads) a reference, then every method over
// its accuracy settings; measures wall time and the error against the
// reference, in metres and relative to the response's magnitude max |x_ref|
// (cli/work_precision.h); writes a CSV, a log-log plot (diverged runs pinned at
// the top), and a summary of the time ratios to hsnc at fixed relative
// accuracies. Every flag and output path is checked before any work.
//
// Methods and what is swept (kMethods; adding a method is one line there):
//  hsnc  : no knob trades accuracy for speed -- every switch is refined to
//          machine precision and segments are closed forms -- so one point per
//          kernel kind: `auto` (the default of `hsnc simulate`: ahead-of-time
//          kernels, the generic solver for a configuration without one), when
//          the model has AOT kernels, and `generic`.
//  ab4   : the fixed step h = 10^(-3 - k/2), 1e-3 .. 1e-6; a step whose run is
//          predicted (time proportional to 1/h) to exceed --budget is skipped.
//  rk45 (and any adaptive method: cvode) : rtol = 10^-k, 1e-4 .. 1e-13, with
//          atol = 1e-2*rtol; the sweep stops after a run that exceeds --budget.
// Wall time: of the run alone (solver setup and recording the samples included,
// model reading not); the median of as many runs as fit in about 0.2 s (an odd
// number, at most 51; one run when the first takes over 0.1 s), or --runs N;
// column `runs`.
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
#include "engine.h"
#include "error.h"
#include "integrators.h"
#include "lowering.h"
#include "model_hash.h"
#include "model_reader.h"
#include "solver_provider.h"
#include "tradeoff.h"

namespace hsnc::cli {
namespace {

enum class Sweep {
    kernels,    ///< exact method: one point per kernel kind
    step,       ///< fixed-step method: h
    tolerance,  ///< adaptive method: rtol (atol = 1e-2*rtol)
};

struct MethodEntry {
    const char* name;  ///< as parse_method (runtime/integrators.h) reads it
    Sweep sweep;
};

// In this order in the CSV and plot. A name this build's parse_method does not
// know (cvode before the SUNDIALS baseline is merged) is left out of the default
// list and rejected by --methods.
constexpr MethodEntry kMethods[] = {
    {"hsnc", Sweep::kernels},
    {"ab4", Sweep::step},
    {"rk45", Sweep::tolerance},
    {"cvode", Sweep::tolerance},
};

std::string num(double v, int digits = 3) {
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

bool known_method(const std::string& name) {
    try {
        parse_method(name);
        return true;
    } catch (const InputError&) {
        return false;
    }
}

std::vector<const MethodEntry*> chosen_methods(const std::string& list) {
    std::vector<const MethodEntry*> out;
    if (list.empty()) {
        for (const auto& m : kMethods)
            if (known_method(m.name)) out.push_back(&m);
        return out;
    }
    std::istringstream in(list);
    for (std::string name; std::getline(in, name, ',');) {
        const MethodEntry* found = nullptr;
        for (const auto& m : kMethods)
            if (name == m.name && known_method(m.name)) found = &m;
        if (!found) {
            std::string names;
            for (const auto& m : kMethods)
                if (known_method(m.name)) names += std::string(names.empty() ? "" : ", ") + m.name;
            throw InputError("--methods: unknown method '" + name + "' (this build has: " + names + ")");
        }
        if (std::find(out.begin(), out.end(), found) != out.end())
            throw InputError("--methods: '" + name + "' given twice");
        out.push_back(found);
    }
    if (out.empty()) throw InputError("--methods: empty list");
    return out;
}

/// One setting of one method.
struct Point {
    const MethodEntry* method;
    std::string setting;  ///< "kernels=aot", "h=1e-05", "rtol=1e-08 atol=1e-10"
    double parameter;     ///< h or rtol; NaN for hsnc
    KernelMode kernels = KernelMode::automatic;
    IntegratorOptions integrator;
};

std::vector<Point> points_of(const MethodEntry& m, const Model& model, bool quick) {
    std::vector<Point> pts;
    switch (m.sweep) {
    case Sweep::kernels: {
        bool has_aot = false;
        const std::uint64_t hash = model_hash(model);
        const AotRegistry& reg = aot_registry();
        for (std::size_t i = 0; i < reg.count; ++i)
            has_aot = has_aot || (reg.kernels[i]->model_hash == hash && model.name == reg.kernels[i]->model_name);
        if (has_aot) pts.push_back({&m, "kernels=auto", NAN, KernelMode::automatic, {}});
        if (!has_aot || !quick) pts.push_back({&m, "kernels=generic", NAN, KernelMode::generic, {}});
        break;
    }
    case Sweep::step:
        for (int k = 0; k <= 6; k += quick ? 2 : 1) {
            Point p{&m, "", std::pow(10.0, -3.0 - k / 2.0), KernelMode::automatic, {}};
            p.integrator.h = p.parameter;
            p.setting = "h=" + sci(p.parameter);
            pts.push_back(p);
        }
        break;
    case Sweep::tolerance:
        for (int k = 4; k <= 13; k += quick ? 3 : 1) {
            Point p{&m, "", std::pow(10.0, -k), KernelMode::automatic, {}};
            p.integrator.rtol = p.parameter;
            p.integrator.atol = 1e-2 * p.parameter;
            p.setting = "rtol=" + sci(p.integrator.rtol) + " atol=" + sci(p.integrator.atol);
            pts.push_back(p);
        }
        break;
    }
    return pts;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

RunSummary run_point(const Model& model, const Point& p, const EngineOptions& eopt, Observer& obs) {
    const Method method = parse_method(p.method->name);
    if (method == Method::hsnc) {
        auto provider = make_solver_provider(model, p.kernels, &aot_registry(), program_source(model));
        Engine engine(model, *provider);
        return engine.run(eopt, obs);
    }
    return integrate(model, method, p.integrator, eopt, obs);
}

struct Measured {
    const Point* point;
    std::string status;
    double wall = NAN;
    int runs = 0;
    RunErrors errors;
};

Measured measure(const Model& model, const Point& p, const EngineOptions& eopt, const RecordedRun& reference,
                 int runs) {
    Measured m{&p, "", NAN, 0, {}};
    RecordedRun rec;
    const std::size_t rows = reference.t.size() + 2;
    rec.t.reserve(rows);
    rec.x.reserve(rows * model.dof());
    RecordingObserver obs(rec, model.dof());
    auto start = std::chrono::steady_clock::now();
    const RunSummary sum = run_point(model, p, eopt, obs);
    std::vector<double> walls{seconds_since(start)};
    m.status = run_status_name(sum.status);
    m.errors = compare_runs(reference, rec);
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
        run_point(model, p, eopt, again);
        walls.push_back(seconds_since(start));
    }
    std::sort(walls.begin(), walls.end());
    m.wall = walls[walls.size() / 2];
    m.runs = total;
    return m;
}

std::string describe(const Measured& m) {
    std::ostringstream s;
    s << m.point->method->name << " " << m.point->setting << ": " << num(m.wall) << " s";
    if (m.runs > 1) s << " (median of " << m.runs << ")";
    if (m.status != "ok") s << ", status " << m.status;
    if (m.errors.diverged) s << ", DIVERGED";
    s << ", position error " << num(m.errors.max_position_error, 2) << " m ("
      << num(m.errors.relative_position_error, 2) << " relative), events " << m.errors.matched_events << " of "
      << m.errors.reference_events << " matched (" << m.errors.events << " found)";
    if (m.errors.matched_events) s << ", event-time error " << num(m.errors.max_event_time_error, 2);
    return s.str();
}

// Single-quoted gnuplot string: a quote inside is doubled.
std::string quoted(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("''") : std::string(1, c);
    return q + "'";
}

// Log-log: wall time against the relative position error (left) and the
// event-time error (right), one curve per method, each point labelled with its
// setting (and on the right, the matched count when the run did not match
// every event). Runs that did not reach t_end (status not ok) are left out; an
// error of exactly 0 is drawn at 1e-17. Diverged runs (column `diverged`) are
// pinned at kDivergedRatio on the left, labelled with method and setting, so
// that a 1e100 does not squash the axis, and left out on the right.
void plot_tradeoff(const Model& model, const std::vector<const MethodEntry*>& methods, const std::string& csv,
                   const std::string& png, const std::string& reference_label, double magnitude, bool any_diverged,
                   bool any_matched, double min_wall, double max_wall) {
    const std::string tmp = png + ".tmp." + std::to_string(::getpid()) + ".png";
    const std::string top = num(kDivergedRatio);
    std::string script = "set terminal pngcairo size 1600,700 noenhanced font ',11'\n"
                         "set output " + quoted(tmp) + "\n"
                         "set datafile separator ','\n"
                         "set logscale xy\nset grid\nset offsets graph 0.04, graph 0.04, 0, 0\nset format y '%.0e'\nset format x '%.0e'\n"
                         "set key below horizontal\nset bmargin 7\nset xlabel 'wall time [s]'\n"
                         "set multiplot layout 1,2 title " +
                         quoted(model.name + ": work-precision, reference " + reference_label) + "\n";
    const std::string left_label =
        "max |x - x_ref| / max |x_ref|  (max |x_ref| = " + num(magnitude, 3) + " m; 0 drawn at 1e-17)";
    const std::string panels[2][2] = {{"15", left_label},
                                      {"12", "max |t_event - t_event_ref| over the matched events [s]  (0 drawn at 1e-17)"}};
    for (const auto& panel : panels) {
        const bool left = panel[0] == "15";
        if (!left && !any_matched) {
            // No event to compare (none in the reference, or none matched): gnuplot
            // refuses a plot whose points are all undefined, so say so instead.
            script += "set yrange [1e-18:1]\nset xrange [" + num(min_wall / 2, 17) + ":" + num(max_wall * 2, 17) +
                      "]\nset ylabel " + quoted(panel[1]) +
                      "\nset label 1 'no event matched: nothing to compare' at graph 0.5, graph 0.5 center\n"
                      "plot 1e-30 notitle\n";
            continue;
        }
        script += std::string(left ? "set yrange [1e-18:" + num(10 * kDivergedRatio) + "]\n" : "set yrange [1e-18:*]\n");
        script += "set ylabel " + quoted(panel[1]) + "\nplot ";
        bool first = true;
        int curve = 0;  // one line type per method, the same on both panels
        for (const MethodEntry* m : methods) {
            ++curve;
            const std::string sel = "(strcol(1) eq " + quoted(m->name) + " && strcol(6) eq 'ok' && strcol(16) ne '1'";
            const std::string y = "($" + panel[0] + " > 1e-17 ? $" + panel[0] + " : 1e-17)";
            const std::string using_xy = sel + " ? $4 : NaN):" + y;
            // Labels: the setting; on the event panel also "(matched/total)" when not all matched.
            std::string label = "(word(strcol(2), 1)";
            if (!left) label += " . (column(11) < column(10) ? sprintf(' (%d/%d)', column(11), column(10)) : '')";
            label += ")";
            // hsnc's points are kernel kinds, not a sweep: points, no line.
            const char* style = m->sweep == Sweep::kernels ? "points pt 7 ps 1.5" : "linespoints lw 2 pt 7";
            script += std::string(first ? "" : ", ") + quoted(csv) + " skip 1 using " + using_xy + " with " + style +
                      " lt " + std::to_string(curve) + " title " + quoted(m->name);
            if (m->sweep == Sweep::kernels) {
                // Kernel kinds cost about the same: label the generic point below, the others above.
                const std::string generic = sel + " && strcol(2) eq 'kernels=generic'";
                const std::string other = sel + " && strcol(2) ne 'kernels=generic'";
                script += ", " + quoted(csv) + " skip 1 using " + other + " ? $4 : NaN):" + y + ":" + label +
                          " with labels offset 0,0.8 font ',8' notitle, " + quoted(csv) + " skip 1 using " + generic +
                          " ? $4 : NaN):" + y + ":" + label + " with labels offset 0,-0.8 font ',8' notitle";
            } else {
                script += ", " + quoted(csv) + " skip 1 using " + using_xy + ":" + label +
                          " with labels offset 0,0.8 font ',8' notitle";
            }
            first = false;
        }
        if (left && any_diverged) {
            // Every diverged run, whatever its method, pinned at the top.
            const std::string dsel = "(strcol(16) eq '1' ? $4 : NaN):(" + top + ")";
            script += ", " + quoted(csv) + " skip 1 using " + dsel + " with points pt 6 ps 1.5 lc rgb 'black' title " +
                      quoted("diverged (error > " + top + " x max |x_ref|): pinned at " + top + ", not on the right") +
                      ", " + quoted(csv) + " skip 1 using " + dsel +
                      ":(strcol(1) . ' ' . word(strcol(2), 1)) with labels offset 0,-0.9 font ',8' notitle";
        }
        script += "\n";
    }
    script += "unset multiplot\n";
    std::FILE* gp = ::popen("gnuplot 2>&1", "w");
    if (!gp) throw RunError("--plot: cannot start gnuplot (install the Debian package gnuplot-nox)");
    std::fputs(script.c_str(), gp);
    const int status = ::pclose(gp);
    if (status != 0 || std::rename(tmp.c_str(), png.c_str()) != 0) {
        std::remove(tmp.c_str());
        throw RunError("--plot: gnuplot failed (exit status " + std::to_string(status) +
                       "); is the Debian package gnuplot-nox installed?");
    }
}

// An output file that cannot be written is bad input, found before any work:
// a directory, or a directory we cannot create a file in (probed with a
// temporary file beside it, removed at once).
void check_output_path(const char* flag, const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
        throw InputError(std::string(flag) + " '" + path + "': is a directory");
    const std::string probe = path + ".probe." + std::to_string(::getpid());
    std::FILE* f = std::fopen(probe.c_str(), "w");
    if (!f) throw InputError(std::string(flag) + " '" + path + "': cannot write it (" + std::strerror(errno) + ")");
    std::fclose(f);
    std::remove(probe.c_str());
}

}  // namespace

int tradeoff(const TradeoffOptions& o, const ReferenceRunner& in_process) {
    const Model model = read_model(o.model, with_t_end(o.overrides, o.t_end));
    const double t_end = std::isnan(o.t_end) ? model.t_end.value_or(NAN) : o.t_end;
    if (std::isnan(t_end))
        throw InputError("--t-end: no end time: give --t-end or [simulate].t_end in " + o.model);
    if (!(t_end > model.t0) || !std::isfinite(t_end))
        throw InputError("--t-end " + num(t_end, 17) + ": must be finite and after t0 = " + num(model.t0, 17));
    if (!std::isnan(o.dt) && !(o.dt > 0 && std::isfinite(o.dt)))
        throw InputError("--dt " + num(o.dt, 17) + ": must be > 0");
    if (o.reference_out.empty() != o.reference_events.empty())
        throw InputError("--reference-out and --reference-events: give both (the reference trajectory and its events)");
    const ReferenceRunner runner = o.reference_out.empty() && !in_process ? reference_runner(o.reference_digits)
                                                                           : in_process;
    if (o.runs < 0 || o.runs > 1001) throw InputError("--runs " + std::to_string(o.runs) + ": must be in 0..1001");
    if (!(o.budget > 0)) throw InputError("--budget " + num(o.budget) + ": must be > 0 (seconds)");
    if (!o.plot.empty() && o.csv.empty()) throw InputError("--plot: needs --csv (the table it draws)");
    const auto methods = chosen_methods(o.methods);
    // Every output path before any work (the reference alone can take minutes).
    if (!o.csv.empty()) check_output_path("--csv", o.csv);
    if (!o.plot.empty()) check_output_path("--plot", o.plot);
    std::unique_ptr<CsvFile> csv;  // opened now, committed at the end; removed on any error before
    if (!o.csv.empty()) csv = std::make_unique<CsvFile>(o.csv);

    EngineOptions eopt;
    eopt.t_end = t_end;
    eopt.dt = std::isnan(o.dt) ? (t_end - model.t0) / 1000 : o.dt;

    // The reference: read, or computed in process.
    RecordedRun reference;
    std::string reference_label;
    if (!o.reference_out.empty()) {
        reference = read_reference(model, o.reference_out, o.reference_events);
        const double last = reference.t.back();
        if (last < t_end - 1e-12 * std::fabs(t_end))
            throw InputError("--reference-out '" + o.reference_out + "': ends at t = " + num(last, 17) +
                             ", before the end time " + num(t_end, 17));
        while (!reference.events.empty() && reference.events.back().t > t_end) reference.events.pop_back();
        reference_label = o.reference_out.substr(o.reference_out.find_last_of('/') + 1);
        std::fprintf(stderr, "tradeoff: reference from %s and %s: %zu samples, %zu events up to t = %s\n",
                     o.reference_out.c_str(), o.reference_events.c_str(), reference.t.size(), reference.events.size(),
                     num(t_end, 6).c_str());
    } else {
        RecordingObserver obs(reference, model.dof());
        std::fprintf(stderr, "tradeoff: computing the reference (%d digits) ...\n", o.reference_digits);
        const auto start = std::chrono::steady_clock::now();
        const RunSummary sum = runner(model, eopt, obs);
        if (sum.status != RunStatus::ok)
            throw RunError(std::string("tradeoff: the reference run: ") + run_status_name(sum.status) + ": " +
                           sum.message);
        reference_label = std::to_string(o.reference_digits) + "-digit engine";
        std::fprintf(stderr, "tradeoff: reference (%d digits): %s s, %zu samples, %zu events\n", o.reference_digits,
                     num(seconds_since(start)).c_str(), reference.t.size(), reference.events.size());
    }
    {
        // The runs sample at t0 + k*dt and t_end: the reference must have a row at each.
        RecordedRun grid;
        grid.dof = model.dof();
        for (std::size_t k = 0;; ++k) {
            const double t = model.t0 + static_cast<double>(k) * eopt.dt;
            const bool last = !(t < t_end - 1e-9 * eopt.dt);
            grid.t.push_back(last ? t_end : t);
            grid.x.insert(grid.x.end(), model.dof(), 0.0);
            if (last) break;
        }
        const RunErrors e = compare_runs(reference, grid);
        const std::string has = std::to_string(e.sample_times) + " of the " + std::to_string(grid.t.size()) +
                                " sample times t0 + k*dt (dt = " + num(eopt.dt, 17) + ") and t_end";
        if (e.sample_times != grid.t.size() && !o.reference_out.empty())
            throw InputError("--reference-out '" + o.reference_out + "': has " + has +
                             "; sample the reference on that grid, or give its --dt");
        if (e.sample_times != grid.t.size()) throw RunError("tradeoff: the reference run gave " + has);
    }

    std::vector<Point> points;
    for (const MethodEntry* m : methods)
        for (const Point& p : points_of(*m, model, o.quick)) points.push_back(p);
    std::vector<Measured> results;
    double last_wall = NAN, last_parameter = NAN;
    for (std::size_t k = 0; k < points.size(); ++k) {
        const Point& p = points[k];
        const MethodEntry* m = p.method;
        if (k == 0 || points[k - 1].method != m) last_wall = last_parameter = NAN;
        if (m->sweep == Sweep::tolerance && last_wall > o.budget) {
            std::fprintf(stderr, "tradeoff: %s %s: skipped (the previous setting took %s s > --budget %s s)\n", m->name,
                         p.setting.c_str(), num(last_wall).c_str(), num(o.budget).c_str());
            continue;
        }
        if (m->sweep == Sweep::step && !std::isnan(last_wall)) {
            // A fixed-step run costs in proportion to its number of steps.
            const double predicted = last_wall * last_parameter / p.parameter;
            if (predicted > o.budget) {
                std::fprintf(stderr, "tradeoff: %s %s: skipped (predicted %s s > --budget %s s)\n", m->name,
                             p.setting.c_str(), num(predicted).c_str(), num(o.budget).c_str());
                continue;
            }
        }
        // On a terminal, say what is running (a slow setting takes seconds), then overwrite it.
        const bool tty = ::isatty(2) != 0;
        if (tty) std::fprintf(stderr, "tradeoff: running %s %s ...", m->name, p.setting.c_str());
        Measured r = measure(model, p, eopt, reference, o.runs);
        if (tty) std::fprintf(stderr, "\r\033[K");
        std::fprintf(stderr, "tradeoff: %s\n", describe(r).c_str());
        last_wall = r.wall;
        last_parameter = p.parameter;
        results.push_back(std::move(r));
    }

    // hsnc's first point (kernels=auto when the model has AOT kernels) is the base of the ratios.
    const Measured* base = nullptr;
    for (const auto& r : results)
        if (!base && r.point->method->sweep == Sweep::kernels && r.status == "ok") base = &r;

    if (csv) {
        csv->text("method,setting,parameter,wall_seconds,runs,status,max_position_error,sample_times,events,"
                  "reference_events,matched_events,max_event_time_error,time_ratio_to_hsnc,response_magnitude,"
                  "relative_position_error,diverged");
        csv->end_row();
        for (const auto& r : results) {
            csv->text(r.point->method->name);
            csv->text(r.point->setting.c_str());
            csv->number(r.point->parameter);
            csv->number(r.wall);
            csv->number(r.runs);
            csv->text(r.status.c_str());
            csv->number(r.errors.max_position_error);
            csv->number(static_cast<double>(r.errors.sample_times));
            csv->number(static_cast<double>(r.errors.events));
            csv->number(static_cast<double>(r.errors.reference_events));
            csv->number(static_cast<double>(r.errors.matched_events));
            csv->number(r.errors.max_event_time_error);
            csv->number(base ? r.wall / base->wall : NAN);
            csv->number(r.errors.response_magnitude);
            csv->number(r.errors.relative_position_error);
            csv->number(r.errors.diverged ? 1 : 0);
            csv->end_row();
        }
        csv->commit();
    }
    double magnitude = NAN;  // the same for every run: the reference's, over the common sample grid
    for (const auto& r : results)
        if (std::isnan(magnitude) && r.errors.sample_times) magnitude = r.errors.response_magnitude;
    const bool any_diverged =
        std::any_of(results.begin(), results.end(), [](const Measured& r) { return r.errors.diverged; });
    const bool any_matched = std::any_of(results.begin(), results.end(), [](const Measured& r) {
        return r.status == "ok" && !r.errors.diverged && r.errors.matched_events > 0;
    });
    double min_wall = INFINITY, max_wall = 0;
    for (const auto& r : results) min_wall = std::min(min_wall, r.wall), max_wall = std::max(max_wall, r.wall);
    if (!o.plot.empty() && !results.empty())
        plot_tradeoff(model, methods, o.csv, o.plot, reference_label, magnitude, any_diverged, any_matched, min_wall,
                      max_wall);

    // Summary (stdout): the response's magnitude, hsnc's point, then for each
    // baseline the cheapest run that reaches each relative accuracy, as a time
    // ratio to hsnc. Diverged runs reach nothing.
    std::cout << "response magnitude max |x_ref| = " << num(magnitude) << " m; errors relative to it\n";
    if (base)
        std::cout << "hsnc " << base->point->setting << ": " << num(base->wall) << " s, position error "
                  << num(base->errors.relative_position_error, 2) << " relative (" << num(base->errors.max_position_error, 2)
                  << " m), events " << base->errors.matched_events << " of " << base->errors.reference_events
                  << " matched\n";
    for (const MethodEntry* m : methods) {
        if (m->sweep == Sweep::kernels) continue;
        std::ostringstream line;
        line << m->name << ":";
        for (double level : {1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12}) {
            const Measured* best = nullptr;
            for (const auto& r : results)
                if (r.point->method == m && r.status == "ok" && !r.errors.diverged &&
                    r.errors.relative_position_error <= level && (!best || r.wall < best->wall))
                    best = &r;
            line << "  relative error<=" << num(level, 1) << ": ";
            if (!best)
                line << "not reached";
            else if (base)
                line << num(best->wall / base->wall) << "x hsnc (" << best->point->setting << ")";
            else
                line << num(best->wall) << " s (" << best->point->setting << ")";
        }
        const std::size_t diverged = static_cast<std::size_t>(std::count_if(
            results.begin(), results.end(), [m](const Measured& r) { return r.point->method == m && r.errors.diverged; }));
        if (diverged) line << "  (" << diverged << " diverged)";
        std::cout << line.str() << "\n";
    }
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
