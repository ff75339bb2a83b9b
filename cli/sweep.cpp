// `hsnc sweep MODEL [options]` (interface.md section 6; docs/interface.md,
// "hsnc sweep") and `hsnc sweep-merge PART... [outputs]`: flags, the library
// (api/hsnc/sweep.h), the output files.
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <chrono>
#include <cmath>
#include <functional>
#include <thread>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <memory>
#include <sstream>

#include "analysis_flags.h"
#include "commands.h"
#include "csv_writer.h"
#include "error.h"
#include "file_read.h"
#include "hsnc/simulate.h"
#include "hsnc/sweep.h"
#include "input_files.h"
#include "model_reader.h"
#include "number_text.h"
#include "output_file.h"
#include "plot.h"
#include "sweep_distributed.h"
#include "sweep_plot.h"

namespace hsnc::cli {
namespace {

struct SweepFlags {
    std::string model;
    ModelOverrides overrides;
    std::string param;
    double from = NAN, to = NAN;
    // Signed, so that a negative count is said as such (an unsigned flag wraps -5 to 2^64 - 5).
    long long points = 0;
    std::string direction = "up";
    long long max_periods = 500, record_periods = 16;
    bool restart_each = false;
    std::string param2, values2;
    unsigned threads = 1;
    std::string part, part_out;
    std::string out, diagram, plot, h5, plot_dofs, attractors;
    std::string method = "hsnc";
    double h = NAN, rtol = 1e-10, atol = 1e-12;
    bool quiet = false;
    bool continuation = false;
    long long max_steps = 0;
    long long branch_switch = 0;
    long long start_periods = 0;
    std::string track;
    long long harmonics = 0;
    double escape = 0;
};

// A count flag's value, refused below `least` naming the flag.
std::size_t count_flag(const char* flag, long long value, long long least) {
    if (value < least)
        throw InputError(std::string(flag) + ": must be >= " + std::to_string(least) +
                         (least >= 1 ? " (a positive whole number)" : "") + ", not " + std::to_string(value));
    return static_cast<std::size_t>(value);
}

struct MergeFlags {
    std::vector<std::string> parts;
    std::string out, diagram, plot, h5, plot_dofs, attractors;
};

// The flag of each SweepOptions field, for the library's OptionError.
InputError flagged(const OptionError& e) {
    static const std::pair<const char*, const char*> flags[] = {{"param", "--param"},
                                                                {"from", "--from"},
                                                                {"to", "--to"},
                                                                {"points", "--points"},
                                                                {"direction", "--direction"},
                                                                {"max_periods", "--max-periods"},
                                                                {"record_periods", "--record-periods"},
                                                                {"param2", "--param2"},
                                                                {"values2", "--values2"},
                                                                {"method", "--method"},
                                                                {"restart_each", "--restart-each"},
                                                                {"max_steps", "--max-steps"},
                                                                {"branch_switch", "--branch-switch"},
                                                                {"start_periods", "--start-periods"},
                                                                {"track", "--track"},
                                                                {"harmonics", "--harmonics"},
                                                                {"escape", "--escape"}};
    for (const auto& f : flags)
        if (e.option() == f.first) return InputError(std::string(f.second) + ": " + e.reason());
    return InputError(e.what());
}

// "I/N" with 1 <= I <= N.
std::pair<std::size_t, std::size_t> parse_part(const std::string& text) {
    const std::size_t slash = text.find('/');
    auto count = [&](const std::string& s) {
        char* end = nullptr;
        const unsigned long long v = std::strtoull(s.c_str(), &end, 10);
        if (s.empty() || s[0] == '-' || s[0] == '+' || *end != '\0' || v > 1'000'000) return 0ull;
        return v;
    };
    if (slash != std::string::npos) {
        const unsigned long long i = count(text.substr(0, slash)), n = count(text.substr(slash + 1));
        if (i >= 1 && n >= 1 && i <= n) return {static_cast<std::size_t>(i - 1), static_cast<std::size_t>(n)};
    }
    throw InputError("--part '" + text + "': expected I/N with 1 <= I <= N (N at most 1000000), e.g. --part 3/16");
}

std::vector<double> parse_values(const std::string& text) {
    std::vector<double> out;
    // A:B:M: M values from A to B, equally spaced (as --from, --to, --points).
    if (text.find(',') == std::string::npos && std::count(text.begin(), text.end(), ':') == 2) {
        const std::size_t c1 = text.find(':'), c2 = text.find(':', c1 + 1);
        char* end1 = nullptr;
        char* end2 = nullptr;
        char* end3 = nullptr;
        const std::string a = text.substr(0, c1), b = text.substr(c1 + 1, c2 - c1 - 1), m = text.substr(c2 + 1);
        const double from = std::strtod(a.c_str(), &end1), to = std::strtod(b.c_str(), &end2);
        const long long count = std::strtoll(m.c_str(), &end3, 10);
        if (a.empty() || b.empty() || m.empty() || *end1 != '\0' || *end2 != '\0' || *end3 != '\0' ||
            !std::isfinite(from) || !std::isfinite(to) || count < 1 || count > 100'000'000)
            throw InputError("--values2 '" + text + "': expected A:B:M (M values from A to B, 1 <= M <= 1e8)");
        return sweep_values(from, to, static_cast<std::size_t>(count));
    }
    std::size_t a = 0;
    while (true) {
        const std::size_t b = text.find(',', a);
        const std::string item = text.substr(a, b == std::string::npos ? std::string::npos : b - a);
        char* end = nullptr;
        const double v = std::strtod(item.c_str(), &end);
        if (item.empty() || *end != '\0' || !std::isfinite(v))
            throw InputError("--values2 '" + text + "': '" + item + "' is not a finite number (expected a,b,c)");
        out.push_back(v);
        if (b == std::string::npos) break;
        a = b + 1;
    }
    return out;
}

// Ctrl-C on a sweep in one process (a whole sweep or a --part): the first SIGINT asks
// every task to stop after the point under way (SweepOptions::stop), so the
// points done are written, and puts back the handler that was there (the
// interrupt cleanup of output_file.h), so a second Ctrl-C stops at once as
// on any run. Only async-signal-safe calls in the handler: an atomic store,
// write, sigaction.
std::atomic<bool> g_stop_sweep{false};
struct sigaction g_previous_sigint;

extern "C" void on_sweep_interrupt(int) {
    const int saved = errno;
    g_stop_sweep.store(true);
    static const char msg[] =
        "\nhsnc sweep: interrupted (SIGINT): finishing the points under way, then writing the points done "
        "(Ctrl-C again: stop at once, nothing written)\n";
    (void)!::write(2, msg, sizeof msg - 1);
    ::sigaction(SIGINT, &g_previous_sigint, nullptr);
    errno = saved;
}

class GracefulInterrupt {
public:
    GracefulInterrupt() {
        struct sigaction old;
        // A SIGINT ignored by whoever started us (nohup, a background job) stays ignored.
        if (::sigaction(SIGINT, nullptr, &old) != 0 || old.sa_handler == SIG_IGN) return;
        struct sigaction sa;
        std::memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_sweep_interrupt;
        sigemptyset(&sa.sa_mask);
        installed_ = ::sigaction(SIGINT, &sa, &g_previous_sigint) == 0;
    }
    /// The previous handler back (before the outputs are written: Ctrl-C then removes them).
    void restore() {
        if (installed_ && !g_stop_sweep.load()) ::sigaction(SIGINT, &g_previous_sigint, nullptr);
        installed_ = false;
    }
    ~GracefulInterrupt() { restore(); }
    GracefulInterrupt(const GracefulInterrupt&) = delete;
    GracefulInterrupt& operator=(const GracefulInterrupt&) = delete;

private:
    bool installed_ = false;
};

// The last line of the CSVs of an interrupted sweep (a comment: the rows
// above are complete points; interface.md).
std::string interrupted_note(std::size_t done, std::size_t total) {
    return "# interrupted (SIGINT) after " + std::to_string(done) +
           (total ? " of " + std::to_string(total) : std::string()) + " points: the rest were not run";
}

// Writes the response curve and the diagram CSVs (interface.md section 6);
// `note`: a last comment line ("" for none).
constexpr const char* kAttractorsNeedBasins =
    "--attractors: only for basins of attraction (--param and --param2 initial state coordinates x0.DOF, v0.DOF)";

void write_curve(const SweepResult& r, CsvFile& f, const std::string& note, const Attractors* basins = nullptr) {
    f.text((sweep_curve_header(r) + (basins ? ",attractor" : "")).c_str());
    f.end_row();
    const bool has2 = !r.param2.empty();
    for (std::size_t k = 0; k < r.points.size(); ++k) {
        const SweepPoint& p = r.points[k];
        f.number(p.value);
        f.text(sweep_direction_name(p.direction));
        f.text(p.settled ? "true" : "false");
        f.text(std::to_string(p.periods).c_str());
        f.text(std::to_string(p.multiple).c_str());
        for (std::size_t i = 0; i < r.masses.size(); ++i) {
            f.number(p.xmax[i]);
            f.number(p.xrms[i]);
            f.number(p.a1[i]);
        }
        if (has2) f.number(p.value2);
        if (r.continuation) {
            f.text(p.failure.empty() ? (p.stable ? "true" : "false") : "");
            f.number(p.max_multiplier);
            f.text(p.bifurcation.c_str());
        }
        if (r.branch_switch) f.text(std::to_string(p.branch).c_str());
        for (std::size_t j = 0; j < p.amp.size(); ++j) {
            f.number(p.amp[j]);
            f.number(p.phase[j]);
        }
        if (basins) f.text(std::to_string(basins->of_point[k]).c_str());
        f.end_row();
    }
    if (!note.empty()) {
        f.text(note.c_str());
        f.end_row();
    }
}

void write_diagram(const SweepResult& r, CsvFile& f, const std::string& note) {
    f.text(sweep_diagram_header(r).c_str());
    f.end_row();
    const std::size_t n = r.masses.size();
    const bool has2 = !r.param2.empty();
    for (const SweepPoint& p : r.points)
        for (std::size_t row = 0; row < p.strobe_t.size(); ++row) {
            f.number(p.value);
            f.text(sweep_direction_name(p.direction));
            f.number(p.strobe_t[row]);
            for (std::size_t i = 0; i < n; ++i) f.number(p.strobe_x[row * n + i]);
            for (std::size_t i = 0; i < n; ++i) f.number(p.strobe_v[row * n + i]);
            if (has2) f.number(p.value2);
            f.end_row();
        }
    if (!note.empty()) {
        f.text(note.c_str());
        f.end_row();
    }
}

// The attractors of a basin study, one row each (0: the points not
// settled, -1: those failed, -2: those escaped, when there are any).
void write_attractors(const SweepResult& r, const Attractors& a, CsvFile& f) {
    std::string header = "attractor,multiple,points,fraction";
    for (const std::string& m : r.masses) header += ",x_" + m;
    for (const std::string& m : r.masses) header += ",v_" + m;
    f.text(header.c_str());
    f.end_row();
    const auto total = static_cast<double>(std::max<std::size_t>(1, r.points.size()));
    for (std::size_t k = 0; k < a.list.size(); ++k) {
        const Attractor& at = a.list[k];
        f.text(std::to_string(k + 1).c_str());
        f.text(std::to_string(at.multiple).c_str());
        f.text(std::to_string(at.points).c_str());
        f.number(static_cast<double>(at.points) / total);
        for (double x : at.x) f.number(x);
        for (double v : at.v) f.number(v);
        f.end_row();
    }
    for (const int id : {0, -1, -2}) {
        const auto count = static_cast<std::size_t>(std::count(a.of_point.begin(), a.of_point.end(), id));
        if (count == 0) continue;
        f.text(std::to_string(id).c_str());
        f.text("0");
        f.text(std::to_string(count).c_str());
        f.number(static_cast<double>(count) / total);
        for (std::size_t i = 0; i < 2 * r.masses.size(); ++i) f.text("");
        f.end_row();
    }
}

// The outputs of a whole sweep (--out, --diagram, --plot, --h5, --attractors), checked before anything runs.
struct Outputs {
    std::unique_ptr<OutputTarget> out, diagram, plot, h5, attractors;
    std::string model_path;  // for --h5: the model file and its overrides as given
    std::vector<std::string> overrides;
    std::string plot_dofs;           // --plot-dofs
    std::vector<std::size_t> named;  // the dofs the model's elements and loads name (plot.h named_dofs)
    Outputs(const std::string& o, const std::string& d, const std::string& p, const std::string& h = "",
            const std::string& a = "") {
        std::vector<const OutputTarget*> all;
        if (!a.empty())
            all.push_back((attractors = std::make_unique<OutputTarget>(check_output("--attractors", a))).get());
        if (!o.empty()) all.push_back((out = std::make_unique<OutputTarget>(check_output("--out", o))).get());
        if (!d.empty()) all.push_back((diagram = std::make_unique<OutputTarget>(check_output("--diagram", d))).get());
        if (!p.empty()) all.push_back((plot = std::make_unique<OutputTarget>(check_output("--plot", p))).get());
        if (!h.empty()) all.push_back((h5 = std::make_unique<OutputTarget>(check_h5(h))).get());
        check_distinct(all);
        if (plot) require_gnuplot();
    }
    // Writes the outputs; returns the attractors of a basin study (empty otherwise), for the summary.
    Attractors write(const SweepResult& r, const std::string& title, const std::string& note = "") const {
        std::unique_ptr<H5Archive> archive;
        if (h5) {
            archive = std::make_unique<H5Archive>(*h5, h5_module());
            write_h5_provenance(*archive, r.model, model_path, overrides);
        }
        const bool basins = is_basins(r);
        if (attractors && !basins) throw InputError(kAttractorsNeedBasins);
        const Attractors found = basins ? classify_attractors(r) : Attractors();
        if (out || archive) {
            CsvFile f(out.get(), archive ? &archive->table("sweep/curve") : nullptr);
            write_curve(r, f, note, basins ? &found : nullptr);
            f.commit();
        }
        if (attractors) {
            CsvFile f(attractors.get(), nullptr);
            write_attractors(r, found, f);
            f.commit();
        }
        if (diagram || archive) {
            CsvFile f(diagram.get(), archive ? &archive->table("sweep/diagram") : nullptr);
            write_diagram(r, f, note);
            f.commit();
        }
        if (plot && basins)
            draw_basin_plot(r, found, note.empty() ? title : title + " (interrupted)", *plot);
        else if (plot)
            draw_sweep_plot(r, note.empty() ? title : title + " (interrupted)", *plot,
                            hsnc::plot_dofs(r.masses, plot_dofs, named));
        if (archive) archive->commit();
        return found;
    }
};

// What went wrong in a finished run: failed points and branches that
// stopped early (each already said on stderr as it happened).
struct Problems {
    std::size_t failed = 0, stopped = 0;
    std::string first;
    explicit Problems(const SweepResult& r) {
        for (const SweepPoint& p : r.points) {
            failed += !p.failure.empty();
            stopped += !p.stop.empty();
            if (first.empty()) first = !p.failure.empty() ? p.failure : p.stop;
        }
    }
    bool any() const { return failed + stopped > 0; }
    std::string message() const {
        std::string m;
        if (failed) m += std::to_string(failed) + (failed == 1 ? " point" : " points") + " failed";
        if (stopped)
            m += (m.empty() ? "" : ", ") + std::to_string(stopped) + (stopped == 1 ? " branch" : " branches") +
                 " stopped early";
        return m + " (the outputs are written; the first: " + first + ")";
    }
};

// `found`: the attractors Outputs::write classified (a basin study's count).
std::string summary_line(const SweepResult& r, const Attractors& found, bool interrupted = false) {
    std::size_t settled = 0, up = 0, stable = 0, bifurcations = 0, escaped = 0;
    for (const SweepPoint& p : r.points) {
        settled += p.settled;
        escaped += p.escaped;
        up += p.direction == SweepDirection::up;
        stable += p.stable;
        bifurcations += !p.bifurcation.empty();
    }
    const Problems problems(r);
    std::ostringstream s;
    s << "status=" << (interrupted ? "interrupted" : problems.any() ? "failed" : "ok") << " points=" << r.points.size()
      << " up=" << up
      << " down=" << r.points.size() - up << " settled=" << settled << " unsettled=" << r.points.size() - settled
      << " failed=" << problems.failed;
    if (r.continuation)
        s << " stable=" << stable << " unstable=" << r.points.size() - stable - problems.failed
          << " bifurcations=" << bifurcations << " stopped=" << problems.stopped;
    if (escaped) s << " escaped=" << escaped;
    if (is_basins(r)) s << " attractors=" << found.list.size();
    return s.str();
}

// Rank 0's line for the whole MPI run: points done on every rank (its own
// and what the others sent), the time per point over all ranks, an estimate.
struct OverallProgress {
    std::size_t total = 0;  // 0: not known (continuation)
    int ranks = 1;
    long long others = 0, printed = -1;
    int finished = 0;  // other ranks done
    std::size_t mine = 0;
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();

    // After one of rank 0's own points.
    void own_point(Communicator& comm) {
        ++mine;
        comm.poll_progress(others, finished);
        print();
    }
    // Rank 0, its own tasks done: the others' progress until every rank has finished.
    void wait_for_others(Communicator& comm) {
        while (comm.poll_progress(others, finished) && finished < ranks - 1) {
            if (others + static_cast<long long>(mine) != printed) print();
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
        if (others + static_cast<long long>(mine) != printed) print();
    }
    void print() {
        const long long done = others + static_cast<long long>(mine);
        printed = done;
        const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (total == 0) {
            std::fprintf(stderr, "hsnc sweep [all %d ranks]: %lld points, %.1f s\n", ranks, done, elapsed);
            return;
        }
        const double left =
            done > 0 ? elapsed / static_cast<double>(done) * static_cast<double>(static_cast<long long>(total) - done)
                     : 0.0;
        std::fprintf(stderr, "hsnc sweep [all %d ranks]: %lld/%zu points, %.1f s, about %.0f s left\n", ranks, done,
                     total, elapsed, left);
    }
};

// The study's options from the flags (progress and the part are set by sweep()).
SweepOptions sweep_options(const SweepFlags& f) {
    SweepOptions o;
    o.param = f.param;
    o.from = f.from;
    o.to = f.to;
    o.points = count_flag("--points", f.points, 1);
    o.max_periods = count_flag("--max-periods", f.max_periods, 1);
    o.record_periods = count_flag("--record-periods", f.record_periods, 1);
    o.restart_each = f.restart_each;
    o.param2 = f.param2;
    if (!f.values2.empty()) o.values2 = parse_values(f.values2);
    o.threads = f.threads;
    o.continuation = f.continuation;
    o.max_steps = count_flag("--max-steps", f.max_steps, 0);
    if (f.branch_switch < 0 || f.branch_switch > kSweepMaxBranchSwitch)
        throw InputError("--branch-switch: must be 0 .. " + std::to_string(kSweepMaxBranchSwitch) +
                         " (period doublings followed), not " + std::to_string(f.branch_switch));
    o.branch_switch = static_cast<int>(f.branch_switch);
    o.start_periods = count_flag("--start-periods", f.start_periods, 0);
    o.track = f.track;
    if (!f.attractors.empty() && !(is_state_coordinate(f.param) && is_state_coordinate(f.param2)))
        throw InputError(kAttractorsNeedBasins);
    o.harmonics = count_flag("--harmonics", f.harmonics, 0);
    o.escape = f.escape;
    o.integrator.h = f.h;
    o.integrator.rtol = f.rtol;
    o.integrator.atol = f.atol;
    try {
        o.direction = sweep_direction_from_name(f.direction);
        o.method = method_from_name(f.method);
    } catch (const OptionError& e) {
        throw flagged(e);
    }
    return o;
}

int sweep(const SweepFlags& f) {
    // Under an MPI launcher: the ranks (MPI loaded only now, from its module).
    std::unique_ptr<Communicator> comm;
    if (launched_by_mpi()) comm = mpi_communicator();
    const int rank = comm ? comm->rank() : 0, ranks = comm ? comm->size() : 1;
    auto overall = std::make_shared<OverallProgress>();
    overall->ranks = ranks;
    try {
        SweepOptions o = sweep_options(f);
        std::size_t part = 0, parts = 1;
        if (!f.part.empty()) {
            std::tie(part, parts) = parse_part(f.part);
            if (f.part_out.empty()) throw InputError("--part " + f.part + ": needs --part-out FILE (the part file)");
            if (!f.out.empty() || !f.diagram.empty() || !f.plot.empty() || !f.h5.empty())
                throw InputError("--part " + f.part +
                                 ": writes only the part file (--part-out); --out, --diagram, --plot and --h5 come "
                                 "from hsnc sweep-merge");
        } else if (!f.part_out.empty()) {
            throw InputError("--part-out: only with --part I/N");
        }
        {
            const std::string prefix = ranks > 1 ? "hsnc sweep [rank " + std::to_string(rank) + "/" +
                                                       std::to_string(ranks) + "]: "
                                                 : "hsnc sweep: ";
            const std::string param = f.param, param2 = f.param2;
            const bool quiet = f.quiet;
            // Failures are said even with --quiet (they are not progress).
            // Under MPI each rank says its own points; the others also send
            // each point to rank 0, which adds a line for the whole run.
            Communicator* world = ranks > 1 && !quiet ? comm.get() : nullptr;
            o.progress = [prefix, param, param2, quiet, world, rank, overall](const SweepProgress& p) {
                if (world) {
                    if (rank != 0) world->send_progress(1);
                    else overall->own_point(*world);
                }
                std::string at = param + " = " + shortest_text(p.value);
                if (!param2.empty()) at += ", " + param2 + " = " + shortest_text(p.value2);
                if (!p.failure.empty()) {
                    std::fprintf(stderr, "%spoint %zu %s %s failed: %s\n", prefix.c_str(), p.done, at.c_str(),
                                 sweep_direction_name(p.direction), p.failure.c_str());
                    return;
                }
                if (quiet) return;
                if (p.continuation) {
                    std::fprintf(stderr, "%sbranch point %zu %s (%s): %s, max |multiplier| %.6g%s%s, %zu period runs, %.3f s\n",
                                 prefix.c_str(), p.done, at.c_str(), sweep_direction_name(p.direction),
                                 p.stable ? "stable" : "unstable", p.max_multiplier,
                                 p.bifurcation.empty() ? "" : ", crossed: ", p.bifurcation.c_str(), p.periods,
                                 p.seconds);
                    return;
                }
                const double per = p.elapsed / static_cast<double>(p.done);
                std::fprintf(stderr, "%spoint %zu/%zu %s %s: %s after %zu periods, %.3f s; %.3f s/point, about %.0f s left\n",
                             prefix.c_str(), p.done, p.total, at.c_str(), sweep_direction_name(p.direction),
                             p.settled ? ("settled (multiple " + std::to_string(p.multiple) + ")").c_str()
                                       : "not settled",
                             p.periods, p.seconds, per, per * static_cast<double>(p.total - p.done));
            };
        }
        if (!comm) o.stop = &g_stop_sweep;
        SweepPlan plan = [&] {
            try {
                return SweepPlan::from_file(f.model, f.overrides, o);
            } catch (const OptionError& e) {
                throw flagged(e);
            }
        }();

        // Every output checked before anything runs (rank 0 writes them all).
        std::unique_ptr<Outputs> outputs;
        std::unique_ptr<OutputTarget> part_target;
        int go = 0;
        std::string refusal;
        if (rank == 0) {
            try {
                if (!f.part.empty())
                    part_target = std::make_unique<OutputTarget>(check_output("--part-out", f.part_out));
                else {
                    outputs = std::make_unique<Outputs>(f.out, f.diagram, f.plot, f.h5, f.attractors);
                    outputs->model_path = f.model;
                    outputs->overrides = overrides_given(f.overrides);
                    outputs->plot_dofs = f.plot_dofs;
                    outputs->named = named_dofs(plan.model());
                    hsnc::plot_dofs(plan.model(), f.plot_dofs, outputs->named);  // --plot-dofs checked before the run
                }
            } catch (const InputError& e) {
                go = 2;
                refusal = e.what();
            } catch (const RunError& e) {
                go = 1;
                refusal = e.what();
            }
        }
        if (comm) go = comm->broadcast(go);
        if (go == 2) throw InputError(rank == 0 ? refusal : "");
        if (go != 0) throw RunError(rank == 0 ? refusal : "");

        const std::vector<std::size_t> which = plan.part_tasks(part, parts);
        if (!o.continuation)
            for (std::size_t i : which) overall->total += plan.task_points(i);
        std::function<void()> finished;
        if (comm && ranks > 1 && !f.quiet)
            finished = [&] {
                if (rank != 0) comm->send_progress(-1);
                else overall->wait_for_others(*comm);
            };
        // A sweep in one process (whole or a part) keeps its finished points on
        // Ctrl-C (GracefulInterrupt); an MPI rank stops at once, as any run.
        bool interrupted = false;
        std::vector<std::vector<SweepPoint>> results;
        if (comm) {
            results = run_tasks_distributed(plan, which, *comm, finished);
        } else {
            GracefulInterrupt graceful;
            results = plan.run_tasks(which, &interrupted);
            graceful.restore();
        }

        int code = 0;
        std::string failure;
        if (rank == 0) {
            try {
                if (part_target) {
                    SweepResult r = plan.result_header();
                    for (const std::vector<SweepPoint>& t : results) r.points.insert(r.points.end(), t.begin(), t.end());
                    // An interrupted part keeps its finished points and says so on its
                    // last line; sweep-merge refuses it (run the part again).
                    const std::string note =
                        interrupted ? interrupted_note(r.points.size(), overall->total) : std::string();
                    const std::string text = sweep_part_text(plan, part, parts, results, note);
                    OutputFile file(*part_target);
                    file.write(text.data(), text.size());
                    file.commit();
                    // Failed points are recorded in it: the part stays even when the command exits 1.
                    commit_outputs();
                    const Problems problems(r);
                    std::cout << "status=" << (interrupted ? "interrupted" : problems.any() ? "failed" : "ok")
                              << " part=" << part + 1 << "/" << parts << " tasks=" << which.size();
                    if (interrupted) std::cout << " points=" << r.points.size();
                    std::cout << "\n";
                    for (const SweepPoint& p : r.points)
                        if (!p.stop.empty()) std::fprintf(stderr, "hsnc sweep: %s\n", p.stop.c_str());
                    if (interrupted) {
                        std::cout.flush();
                        std::fprintf(stderr,
                                     "hsnc sweep: interrupted (SIGINT): the part file holds the %zu points done "
                                     "(sweep-merge refuses it: run part %zu/%zu again)\n",
                                     r.points.size(), part + 1, parts);
                        std::signal(SIGINT, SIG_DFL);
                        std::raise(SIGINT);
                    }
                    if (problems.any()) {
                        code = 1;
                        failure = problems.message();
                    }
                } else {
                    SweepResult r = plan.result_header();
                    for (std::vector<SweepPoint>& t : results)
                        for (SweepPoint& p : t) r.points.push_back(std::move(p));
                    const std::string note =
                        interrupted ? interrupted_note(r.points.size(), overall->total) : std::string();
                    const Attractors found = outputs->write(r, r.model + ": sweep over " + r.param, note);
                    // Failed points are rows of the outputs: they stay when the command exits 1.
                    commit_outputs();
                    std::cout << summary_line(r, found, interrupted) << "\n";
                    const Problems problems(r);
                    for (const SweepPoint& p : r.points)
                        if (!p.stop.empty()) std::fprintf(stderr, "hsnc sweep: %s\n", p.stop.c_str());
                    if (interrupted) {
                        // The outputs hold the points done; end by the signal, as an
                        // interrupted run does (the shell reports 130).
                        std::cout.flush();
                        std::fprintf(stderr, "hsnc sweep: interrupted (SIGINT): the outputs hold the %zu points done\n",
                                     r.points.size());
                        std::signal(SIGINT, SIG_DFL);
                        std::raise(SIGINT);
                    }
                    if (problems.any()) {
                        code = 1;
                        failure = problems.message();
                    }
                }
            } catch (const RunError& e) {
                code = 1;
                failure = e.what();
            }
        }
        if (comm) code = comm->broadcast(code);
        if (code != 0) throw RunError(rank == 0 ? failure : "");
        return 0;
    } catch (const std::exception&) {
        if (rank != 0) {
            // Rank 0 says what went wrong; the others leave quietly with its exit code.
            std::cerr.setstate(std::ios::failbit);
        }
        throw;
    }
}

int merge(const MergeFlags& f) {
    for (const std::string& path : f.parts) note_input_file(path);  // no output may replace a part
    Outputs outputs(f.out, f.diagram, f.plot, f.h5, f.attractors);  // --h5: the model's text is not in the parts
    outputs.plot_dofs = f.plot_dofs;
    std::vector<std::string> texts;
    for (const std::string& path : f.parts) {
        const FileRead file = read_regular_file(path, std::size_t{1} << 34);
        if (file.status != FileRead::Status::ok) throw InputError("cannot read part file '" + path + "': " + file.problem);
        texts.push_back(file.bytes);
    }
    const SweepResult r = merge_sweep_parts(texts, f.parts);
    const Attractors found = outputs.write(r, r.model + ": sweep over " + r.param);
    commit_outputs();  // failed points are rows of the outputs: they stay when the command exits 1
    std::cout << summary_line(r, found) << "\n";
    const Problems problems(r);
    if (problems.any()) throw RunError(problems.message());
    return 0;
}

}  // namespace

void add_sweep(CLI::App& app, int& exit_code) {
    auto f = std::make_shared<SweepFlags>();
    auto* sub = app.add_subcommand(
        "sweep", "response curves and bifurcation diagrams over one parameter (threads, MPI ranks, --part)");
    sub->add_option("MODEL", f->model, "model file (TOML)")->required();
    sub->add_option("--param", f->param, "the parameter to sweep (of [parameters])")->required();
    sub->add_option("--from", f->from, "first value")->required()->check(finite_number());
    sub->add_option("--to", f->to, "last value")->required()->check(finite_number());
    sub->add_option("--points", f->points, "number of values from --from to --to inclusive, equally spaced")
        ->required();
    sub->add_option("--direction", f->direction,
                    "up (default), down (from --to to --from) or both (up, then down; each from the initial state)");
    sub->add_option("--max-periods", f->max_periods,
                    "forcing periods at most before recording, when the state does not settle (default 500)");
    sub->add_option("--record-periods", f->record_periods, "forcing periods recorded at each point (default 16)");
    sub->add_option("--set", f->overrides.set, "override a parameter, NAME=VALUE (repeatable)");
    sub->add_option("--x0", f->overrides.x0, "override an initial position, NAME=VALUE (repeatable)");
    sub->add_option("--v0", f->overrides.v0, "override an initial velocity, NAME=VALUE (repeatable)");
    sub->add_option("--out", f->out, "response curve CSV");
    sub->add_option("--diagram", f->diagram, "bifurcation diagram CSV (the stroboscopic samples of every point)");
    sub->add_option("--attractors", f->attractors,
                    "basins of attraction (--param and --param2 initial state coordinates x0.DOF or v0.DOF, with "
                    "--restart-each): the attractors CSV, one row per attractor (its period, 0 for a set that is not "
                    "periodic, and canonical "
                    "state, the fraction of points that reach it); the curve CSV gains the column attractor and "
                    "--plot draws the basins");
    sub->add_option("--plot", f->plot, "draw the response curve and the diagram into this PNG (gnuplot)");
    add_h5_flag(sub, f->h5, "sweep/curve as --out, sweep/diagram as --diagram");
    sub->add_option("--plot-dofs", f->plot_dofs,
                    "the dofs --plot draws, comma separated, at most 8 (default: every dof of a model of at most 8, "
                    "else the first 8 that elements, friction, forcing or loads act on)")
        ->needs(sub->get_option("--plot"));
    sub->add_flag("--restart-each", f->restart_each,
                  "start every point from the model's initial state (no continuation; points run in parallel)");
    sub->add_option("--param2", f->param2, "a second parameter: one sweep per value of --values2")
        ->needs(sub->add_option("--values2", f->values2,
                                "values of --param2, comma separated (a,b,c), or A:B:M (M values from A to B)"));
    sub->add_option("--threads", f->threads,
                    "threads for independent sweeps and points (default 1; 0: every core); output identical for any");
    sub->add_option("--part", f->part,
                    "run only part I of N (I/N, 1 <= I <= N) of the independent sweeps and points, into --part-out; "
                    "hsnc sweep-merge joins the parts");
    sub->add_option("--part-out", f->part_out, "the part file of --part");
    sub->add_option("--method", f->method,
                    "hsnc (exact, default); ab4 (--h), rk45, cvode (--rtol/--atol): a numerical baseline, for "
                    "comparisons (its xmax, xrms, a1 from samples)");
    sub->add_option("--h", f->h, "step of --method ab4")->check(finite_number());
    sub->add_option("--rtol", f->rtol, "relative tolerance of --method rk45/cvode (default 1e-10)")
        ->check(finite_number());
    sub->add_option("--atol", f->atol, "absolute tolerance of --method rk45/cvode (default 1e-12)")
        ->check(finite_number());
    sub->add_flag(
        "--continuation", f->continuation,
        "follow the periodic orbit over the parameter by pseudo-arclength continuation (exact shooting), "
        "through folds, with each point's stability and the bifurcations and transitions crossed (fold, "
        "period_doubling, neimark_sacker, grazing located as a row of its own, stick_onset, slip_onset; extra columns "
        "stable,max_multiplier,bifurcation); the branch starts at --from (--to for --direction down)");
    sub->add_option("--max-steps", f->max_steps,
                    "--continuation: points at most per branch (default 20 x --points)");
    sub->add_option("--branch-switch", f->branch_switch,
                    "--continuation: locate every period doubling to rounding (a row of its own) and follow the "
                    "branch of twice the period born there, and theirs, up to D doublings (1..6); extra column branch "
                    "(0 the primary, then 1, 2, ... in the order they are followed)");
    sub->add_option("--track", f->track,
                    "--continuation: follow the branch's first fold, period_doubling, neimark_sacker or grazing "
                    "point over two parameters, --param and --param2, from --values2 A,B's A towards B (the "
                    "curve's rows: both parameters, the orbit there)");
    sub->add_option("--escape", f->escape,
                    "a bound R: a point whose displacement of some dof exceeds R in magnitude at the end of a "
                    "forcing period stops there, escaped (basins: attractor -2; not with --continuation)");
    sub->add_option("--start-periods", f->start_periods,
                    "--continuation: start the branch at the orbit of K forcing periods shot from the model's initial "
                    "state (--x0, --v0) at --from, with no transient: a row of an earlier run (its state at t0 from "
                    "--diagram, its multiple; stable or not)");
    sub->add_option("--harmonics", f->harmonics,
                    "amplitude and phase of the first K harmonics of every mass over the recorded periods "
                    "(columns amp<k>_<mass>,phase<k>_<mass> at the end; x = mean + sum of amp sin(k omega t + phase), "
                    "phase in rad)");
    sub->add_flag("--quiet", f->quiet, "no progress lines on stderr (failures are still said)");
    sub->callback([f, &exit_code] { exit_code = sweep(*f); });

    auto m = std::make_shared<MergeFlags>();
    auto* merge_cmd = app.add_subcommand("sweep-merge", "join the part files of hsnc sweep --part into the outputs of a whole run");
    merge_cmd->add_option("PARTS", m->parts, "the part files (every part of one sweep, in any order)")->required();
    merge_cmd->add_option("--out", m->out, "response curve CSV");
    merge_cmd->add_option("--diagram", m->diagram, "bifurcation diagram CSV");
    merge_cmd->add_option("--attractors", m->attractors, "basins: the attractors CSV (as hsnc sweep --attractors)");
    merge_cmd->add_option("--plot", m->plot, "the figure (PNG, gnuplot)");
    add_h5_flag(merge_cmd, m->h5, "sweep/curve, sweep/diagram");
    merge_cmd
        ->add_option("--plot-dofs", m->plot_dofs,
                     "the dofs --plot draws, comma separated, at most 8 (default: the first 8)")
        ->needs(merge_cmd->get_option("--plot"));
    merge_cmd->callback([m, &exit_code] { exit_code = merge(*m); });
}

}  // namespace hsnc::cli
