#include "plot.h"

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <sstream>
#include <utility>

#include "error.h"

extern char** environ;

namespace hsnc {

std::vector<std::size_t> named_dofs(const Model& model) {
    std::vector<char> named(model.dof(), 0);
    auto direction = [&](const Direction& d) {  // the bodies of an element's w (direction.h)
        for_each_term(d, [&](int body, double) { named[static_cast<std::size_t>(body)] = 1; });
    };
    for (const Contact& c : model.contacts) direction(c.direction());
    for (const FrictionElement& f : model.frictions) direction(Direction{f.a, f.b});
    for (const Jenkins& j : model.jenkins) direction(j.direction());
    for (const Damper& d : model.dampers)
        if (!d.from_structure) direction(d.direction());
    for (std::size_t i = 0; i < model.dof(); ++i) {
        bool loaded = model.has_friction(i) || (i < model.load.size() && model.load[i] != 0.0);
        for (const Harmonic& h : model.forcing) loaded = loaded || (i < h.amplitude.size() && h.amplitude[i] != 0.0);
        for (const LoadStep& s : model.load_steps) loaded = loaded || (i < s.load.size() && s.load[i] != 0.0);
        if (loaded) named[i] = 1;
    }
    std::vector<std::size_t> dofs;
    for (std::size_t i = 0; i < named.size(); ++i)
        if (named[i]) dofs.push_back(i);
    return dofs;
}

std::vector<std::size_t> plot_dofs(const std::vector<std::string>& names, const std::string& list,
                                   const std::vector<std::size_t>& named, const std::string& flag) {
    std::vector<std::size_t> dofs;
    if (list.empty()) {
        const bool all = names.size() <= kMaxPlotDofs || named.empty();
        for (std::size_t k = 0; k < (all ? names.size() : named.size()) && dofs.size() < kMaxPlotDofs; ++k)
            dofs.push_back(all ? k : named[k]);
        return dofs;
    }
    std::size_t start = 0;
    while (start <= list.size()) {
        const std::size_t comma = std::min(list.find(',', start), list.size());
        const std::string name = list.substr(start, comma - start);
        const auto it = std::find(names.begin(), names.end(), name);
        if (it == names.end())
            throw InputError(flag + " '" + list + "': '" + name + "' is not a dof of the model" +
                             (names.empty() ? ""
                                            : " (its dofs: " + names.front() +
                                                  (names.size() > 1 ? ", ..., " + names.back() : "") + ")"));
        const auto index = static_cast<std::size_t>(it - names.begin());
        if (std::find(dofs.begin(), dofs.end(), index) != dofs.end())
            throw InputError(flag + " '" + list + "': '" + name + "' is named twice");
        dofs.push_back(index);
        start = comma + 1;
    }
    if (dofs.size() > kMaxPlotDofs)
        throw InputError(flag + " '" + list + "': " + std::to_string(dofs.size()) + " dofs; a figure draws at most " +
                         std::to_string(kMaxPlotDofs) + " (each its colour and legend entry)");
    return dofs;
}

std::vector<std::size_t> plot_dofs(const Model& model, const std::string& list, const std::vector<std::size_t>& named,
                                   const std::string& flag) {
    std::vector<std::string> names;
    names.reserve(model.masses.size());
    for (const Mass& m : model.masses) names.push_back(m.name);
    return plot_dofs(names, list, named, flag);
}

std::string common_unit(const std::vector<std::string>& names) {
    std::string unit;
    for (const std::string& n : names) unit = unit.empty() || unit == dof_unit(n) ? dof_unit(n) : "mixed";
    return unit.empty() ? "m" : unit;
}

std::string dof_unit(const std::string& name) {
    for (const char* prefix : {"theta", "rot", "phi", "psi", "th", "t"}) {
        const std::size_t n = std::char_traits<char>::length(prefix);
        if (name.compare(0, n, prefix) != 0) continue;
        const std::string rest = name.substr(n);
        const std::size_t digits = rest.find_first_not_of("0123456789_");
        if (digits == std::string::npos) return "rad";
    }
    return "m";
}
namespace {

constexpr std::size_t kBuckets = 2000;     // envelope resolution: about one bucket per pixel column
constexpr std::size_t kMaxMarks = 20000;   // events drawn at most
constexpr std::size_t kMaxPng = 64 << 20;  // gnuplot's output, read at most
constexpr int kDistinctMasses = 8;         // up to this many: distinct colours and a legend

// Single-quoted gnuplot string: a quote inside is doubled.
std::string quoted(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("''") : std::string(1, c);
    return q + "'";
}

std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.10g", v);
    return buf;
}

// Distinct colours (matplotlib's tab10) for up to kDistinctMasses masses.
const char* const kMassColours[kDistinctMasses] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728",
                                                   "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"};
// Per event kind (EventKind order): colour of its tick row and its mark's point type.
const char* const kKindColours[5] = {"#000000", "#777777", "#b00000", "#0030c0", "#008000"};
const int kKindPoints[5] = {9, 11, 7, 6, 12};  // filled up/down triangle, filled/open circle, open diamond

struct Range {
    double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
    void add(double v) {
        if (!std::isfinite(v)) return;
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    }
    void pad() {
        if (!(lo <= hi)) lo = -1, hi = 1;
        if (hi - lo <= 1e-12 * std::max(1.0, std::abs(lo))) {
            const double d = std::max(1e-6, 0.1 * std::abs(lo));
            lo -= d, hi += d;
        }
    }
};

// Rows "t x_1 ... x_n" of a series: every sample, or per bucket its min and
// max (in the order they came) at the bucket's first and third quarter.
std::string datablock(const char* name, const PlotRecorder::Series& s, std::size_t n, Range& range) {
    std::string out = std::string(name) + " << EOD\n";
    auto row = [&](double t, auto value) {
        out += num(t);
        for (std::size_t i = 0; i < n; ++i) {
            const double v = value(i);
            range.add(v);
            out += ' ';
            out += num(v);
        }
        out += '\n';
    };
    if (!s.envelope) {
        for (std::size_t r = 0; r + n + 1 <= s.rows.size(); r += n + 1)
            row(s.rows[r], [&](std::size_t i) { return s.rows[r + 1 + i]; });
    } else {
        const double w = (s.b - s.a) / kBuckets;
        for (std::size_t k = 0; k < kBuckets; ++k) {
            if (!s.count[k]) continue;
            const std::size_t base = k * n;
            for (int half = 0; half < 2; ++half)
                row(s.a + (static_cast<double>(k) + 0.25 + 0.5 * half) * w, [&](std::size_t i) {
                    const bool lo_now = (s.lo_first[base + i] != 0) == (half == 0);
                    return lo_now ? s.lo[base + i] : s.hi[base + i];
                });
        }
    }
    return out + "EOD\n";
}

}  // namespace

std::string run_gnuplot(const std::string& script) {
    int in[2], out[2], err[2];
    if (::pipe2(in, O_CLOEXEC) != 0) throw RunError(std::string("--plot: pipe: ") + std::strerror(errno));
    if (::pipe2(out, O_CLOEXEC) != 0) {
        ::close(in[0]), ::close(in[1]);
        throw RunError(std::string("--plot: pipe: ") + std::strerror(errno));
    }
    if (::pipe2(err, O_CLOEXEC) != 0) {
        ::close(in[0]), ::close(in[1]), ::close(out[0]), ::close(out[1]);
        throw RunError(std::string("--plot: pipe: ") + std::strerror(errno));
    }
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, in[0], 0);  // dup2 clears close-on-exec on the copy
    posix_spawn_file_actions_adddup2(&fa, out[1], 1);
    posix_spawn_file_actions_adddup2(&fa, err[1], 2);
    char arg0[] = "gnuplot";
    char* argv[] = {arg0, nullptr};
    pid_t pid = 0;
    const int rc = ::posix_spawnp(&pid, "gnuplot", &fa, nullptr, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    ::close(in[0]), ::close(out[1]), ::close(err[1]);
    if (rc != 0) {
        ::close(in[1]), ::close(out[0]), ::close(err[0]);
        throw RunError(std::string("--plot: cannot start gnuplot: ") + std::strerror(rc) +
                       " (install the Debian package gnuplot-nox)");
    }
    set_interrupt_child(pid);
    ::fcntl(in[1], F_SETFL, O_NONBLOCK);
    std::string png, diag;
    std::size_t written = 0;
    int fds[3] = {in[1], out[0], err[0]};
    char buf[1 << 16];
    while (fds[0] >= 0 || fds[1] >= 0 || fds[2] >= 0) {
        pollfd p[3];
        for (int k = 0; k < 3; ++k) p[k] = {fds[k], static_cast<short>(k == 0 ? POLLOUT : POLLIN), 0};
        if (::poll(p, 3, -1) < 0) {
            if (errno == EINTR) continue;
            break;
        }
        if (fds[0] >= 0 && p[0].revents) {
            const ssize_t n = ::write(fds[0], script.data() + written, script.size() - written);
            if (n > 0) written += static_cast<std::size_t>(n);
            if ((n < 0 && errno != EAGAIN && errno != EINTR) || written == script.size()) {
                ::close(fds[0]);  // done, or gnuplot stopped reading (EPIPE: SIGPIPE is ignored)
                fds[0] = -1;
            }
        }
        for (int k = 1; k < 3; ++k) {
            if (fds[k] < 0 || !p[k].revents) continue;
            const ssize_t n = ::read(fds[k], buf, sizeof buf);
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) {
                ::close(fds[k]);
                fds[k] = -1;
                continue;
            }
            std::string& to = k == 1 ? png : diag;
            if (to.size() < (k == 1 ? kMaxPng : 1 << 16)) to.append(buf, static_cast<std::size_t>(n));
        }
    }
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    set_interrupt_child(0);
    const bool ok = WIFEXITED(status) && WEXITSTATUS(status) == 0 && png.size() > 8 && png.compare(1, 3, "PNG") == 0;
    if (ok) return png;
    // The first few lines of its diagnostics, each cut short.
    std::string msg;
    std::istringstream lines(diag);
    int kept = 0;
    for (std::string l; kept < 4 && std::getline(lines, l);) {
        if (l.find_first_not_of(" \t^") == std::string::npos) continue;
        msg += "\n  gnuplot: " + l.substr(0, 200);
        ++kept;
    }
    throw RunError("--plot: gnuplot failed (" +
                   (WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                      : std::string("killed by a signal")) +
                   (png.empty() ? ", no image" : "") + ")" + msg);
}

void require_gnuplot() {
    const char* path = std::getenv("PATH");
    std::istringstream dirs(path ? path : "/usr/bin:/bin");
    for (std::string d; std::getline(dirs, d, ':');)
        if (::access(((d.empty() ? "." : d) + "/gnuplot").c_str(), X_OK) == 0) return;
    throw RunError("--plot: gnuplot not found on PATH (install the Debian package gnuplot-nox)");
}

void PlotRecorder::Series::add(double t, const double* x, std::size_t n) {
    if (!(t >= a && t <= b)) return;
    if (!envelope) {
        rows.push_back(t);
        rows.insert(rows.end(), x, x + n);
        return;
    }
    const auto k = std::min<std::size_t>(kBuckets - 1, static_cast<std::size_t>((t - a) / (b - a) * kBuckets));
    const std::size_t base = k * n;
    const bool first = count[k]++ == 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (first || x[i] < lo[base + i]) {
            lo[base + i] = x[i];
            lo_first[base + i] = first ? 1 : 0;  // a new minimum after the maximum
        }
        if (first || x[i] > hi[base + i]) {
            hi[base + i] = x[i];
            if (!first) lo_first[base + i] = 1;  // a new maximum after the minimum
        }
    }
}

PlotRecorder::PlotRecorder(const Model& model, double t0, double t_end, double dt, std::vector<std::size_t> dofs)
    : model_(model), dofs_(std::move(dofs)) {
    if (dofs_.empty())
        for (std::size_t i = 0; i < model.dof(); ++i) dofs_.push_back(i);
    drawn_.resize(dofs_.size());
    const std::size_t n = dofs_.size();
    auto setup = [&](Series& s, double a, double b) {
        s.a = a;
        s.b = b;
        const double rows = (b - a) / dt + 2;
        s.envelope = rows > 2.0 * kBuckets;
        if (s.envelope) {
            s.count.assign(kBuckets, 0);
            s.lo.assign(kBuckets * n, 0.0);
            s.hi.assign(kBuckets * n, 0.0);
            s.lo_first.assign(kBuckets * n, 1);
        } else {
            s.rows.reserve(static_cast<std::size_t>(rows) * (n + 1));
        }
    };
    setup(whole_, t0, t_end);
    // Zoom: the last 5 periods of the slowest forcing harmonic when they are
    // at most a quarter of the run (the steady response), else the first 10%
    // of the run (the transient, where a free motion does most).
    double omega = 0;
    for (const Harmonic& h : model.forcing)
        if (h.omega > 0 && (omega == 0 || h.omega < omega)) omega = h.omega;
    const double span = t_end - t0, periods = omega > 0 ? 5 * 2 * M_PI / omega : 0;
    if (periods > 0 && periods <= span / 4) {
        setup(zoom_, t_end - periods, t_end);
        zoom_title_ = "last 5 forcing periods";
    } else {
        setup(zoom_, t0, t0 + span / 10);
        zoom_title_ = "first 10% of the run";
    }
    char range[80];
    std::snprintf(range, sizeof range, ", t = %.6g .. %.6g s", zoom_.a, zoom_.b);
    zoom_title_ += range;
}

void PlotRecorder::on_sample(double t, const double* x, const double*) {
    for (std::size_t k = 0; k < dofs_.size(); ++k) drawn_[k] = x[dofs_[k]];
    whole_.add(t, drawn_.data(), drawn_.size());
    zoom_.add(t, drawn_.data(), drawn_.size());
}

void PlotRecorder::on_event(double t, EventKind kind, int element, const double* x, const double*) {
    if (marks_.size() == kMaxMarks) {
        ++unmarked_;
        return;
    }
    int body = element;  // the mass whose curve carries the mark
    if (kind == EventKind::contact_close || kind == EventKind::contact_open || kind == EventKind::impact) {
        const Contact& c = model_.contacts[static_cast<std::size_t>(element)];
        body = kGround;  // the first body it acts on
        for_each_term(c.direction(), [&](int i, double) {
            if (body == kGround) body = i;
        });
    }
    // On the curve of its mass when that is drawn; else a tick in the strip only.
    const bool drawn =
        body >= 0 && std::find(dofs_.begin(), dofs_.end(), static_cast<std::size_t>(body)) != dofs_.end();
    marks_.push_back({t, kind, body < 0 ? 0.0 : drawn ? x[body] : std::numeric_limits<double>::quiet_NaN()});
}

std::string PlotRecorder::script() const {
    const std::size_t n = dofs_.size();
    const bool distinct = n <= static_cast<std::size_t>(kDistinctMasses);
    auto name = [&](std::size_t i) -> const std::string& { return model_.masses[dofs_[i]].name; };
    // The y axis in the unit of the dofs drawn; when they mix, each legend entry says its own.
    std::vector<std::string> names;
    for (std::size_t i = 0; i < n; ++i) names.push_back(name(i));
    const std::string unit = common_unit(names);
    const std::string ylabel =
        "set ylabel " + quoted(unit == "mixed" ? "x [m; rad for rotations]" : "x [" + unit + "]") + "\n";
    Range whole_range, zoom_range;
    std::string s = "set terminal pngcairo size 1400,1000 noenhanced font ',11'\nset encoding utf8\n";
    s += datablock("$whole", whole_, n, whole_range);
    s += datablock("$zoom", zoom_, n, zoom_range);
    whole_range.pad();
    zoom_range.pad();
    bool kinds[5] = {}, zoom_kinds[5] = {};
    s += "$events << EOD\n";
    for (const Mark& m : marks_) {
        const int k = static_cast<int>(m.kind);
        kinds[k] = true;
        if (m.t >= zoom_.a && m.t <= zoom_.b) zoom_kinds[k] = true;
        s += num(m.t) + ' ' + std::to_string(k) + ' ' + num(m.y) + '\n';
    }
    s += "EOD\n";
    int rows = 0;  // of the event strip: one per kind that occurs
    for (bool k : kinds) rows += k;

    // Screen layout (fractions of the height): the whole run on top, the
    // event strip under it sharing its time axis, the zoom at the bottom;
    // margins fixed so that the time axes line up and the legends fit.
    const double strip_top = 0.5 + (rows ? 0.015 + 0.024 * rows : 0.0);
    const std::string what = n == model_.dof()
                                 ? "the " + std::to_string(n) + (n == 1 ? " mass" : " masses")
                                 : std::to_string(n) + " of the " + std::to_string(model_.dof()) + " dofs";
    s += "set multiplot title " + quoted(model_.name + ": positions of " + what) + "\n";
    s += "set lmargin at screen 0.1\nset rmargin at screen 0.84\nset grid\n" + ylabel;
    s += "set key outside right top\n";
    if (!distinct) {
        // A colour scale by mass index: neighbours along a chain get neighbouring colours.
        s += "set palette defined (0 '#440154', 1 '#3b528b', 2 '#21918c', 3 '#5ec962', 4 '#e08a00')\n";
        s += "set cbrange [1:" + std::to_string(n) + "]\nset cbtics (";
        const std::size_t step = std::max<std::size_t>(1, (n + 6) / 7);
        // Every step-th mass and the last (its neighbour below dropped when they would crowd).
        for (std::size_t i = 0; i < n; i += step)
            if (i == 0 || i + 1 == n || n - 1 - i >= step / 2)
                s += (i ? ", " : "") + quoted(name(i)) + " " + std::to_string(i + 1);
        if ((n - 1) % step) s += ", " + quoted(name(n - 1)) + " " + std::to_string(n);
        s += ")\nset colorbox user origin screen 0.87, screen 0.53 size screen 0.015, screen 0.37\n";
    }
    auto curves = [&](const char* block) {
        std::string c;
        for (std::size_t i = 0; i < n; ++i) {
            c += (i ? ", " : "") + std::string(block) + " using 1:" + std::to_string(i + 2) + " with lines lw 1.2 ";
            if (distinct)
                c += "lc rgb '" + std::string(kMassColours[i]) + "' title " +
                     quoted(unit == "mixed" ? name(i) + " [" + dof_unit(name(i)) + "]" : name(i));
            else
                c += "lc palette cb " + std::to_string(i + 1) + " notitle";
        }
        return c;
    };

    // Top: the whole run.
    std::string title = "whole run, t = " + num(whole_.a) + " .. " + num(whole_.b) + " s";
    if (whole_.envelope) title += " (min/max envelope of the samples)";
    s += "set title " + quoted(title) + "\n";
    s += "set tmargin at screen 0.91\nset bmargin at screen " + num(strip_top) + "\n";
    s += "set xrange [" + num(whole_.a) + ":" + num(whole_.b) + "]\n";
    const double wspan = whole_range.hi - whole_range.lo;
    s += "set yrange [" + num(whole_range.lo - 0.05 * wspan) + ":" + num(whole_range.hi + 0.05 * wspan) + "]\n";
    s += rows ? "set format x ''\nunset xlabel\n" : "set xlabel 't [s]'\n";
    s += "plot " + curves("$whole") + "\n";

    // The event strip: a tick per switch event, one row per kind.
    if (rows) {
        std::string tics;
        std::string plots;
        for (int k = 0, row = rows; k < 5; ++k) {
            if (!kinds[k]) continue;
            const std::string name = event_kind_name(static_cast<EventKind>(k));
            tics += (tics.empty() ? "" : ", ") + quoted(name) + " " + std::to_string(row);
            plots += (plots.empty() ? "" : ", ") + std::string("$events using 1:($2 == ") + std::to_string(k) + " ? " +
                     std::to_string(row) + " - 0.4 : NaN):(0):(0.8) with vectors nohead lw 1 lc rgb '" +
                     kKindColours[k] + "' notitle";
            --row;
        }
        s += "unset title\nset tmargin at screen " + num(strip_top) + "\nset bmargin at screen 0.5\n";
        s += "set yrange [0.5:" + std::to_string(rows) + ".5]\nset ytics (" + tics + ")\nset grid noytics\n";
        s += "set format x '% h'\nset xlabel 't [s]'\nunset ylabel\n";
        if (unmarked_) s += "set label 1 " + quoted("first " + std::to_string(kMaxMarks) + " events") +
                            " at graph 1, graph 1 right offset 0,0.8\n";
        s += "plot " + plots + "\n";
        s += "set ytics auto\nset grid ytics\n" + ylabel + "unset label 1\n";
    }

    // Bottom: the zoom window; each event marked on the curve of its mass.
    title = zoom_title_;
    if (zoom_.envelope) title += " (min/max envelope of the samples)";
    if (rows) title += "; switch events marked";
    s += "set title " + quoted(title) + "\n";
    s += "set tmargin at screen 0.39\nset bmargin at screen 0.07\nset format x '% h'\nset xlabel 't [s]'\n";
    s += "set xrange [" + num(zoom_.a) + ":" + num(zoom_.b) + "]\n";
    const double zspan = zoom_range.hi - zoom_range.lo;
    s += "set yrange [" + num(zoom_range.lo - 0.05 * zspan) + ":" + num(zoom_range.hi + 0.05 * zspan) + "]\n";
    s += "plot " + curves("$zoom");
    for (int k = 0; k < 5; ++k) {
        if (!zoom_kinds[k]) continue;
        s += ", $events using 1:($2 == " + std::to_string(k) + " ? $3 : NaN) with points pt " +
             std::to_string(kKindPoints[k]) + " ps 1.1 lc rgb '" + kKindColours[k] + "' title " +
             quoted(event_kind_name(static_cast<EventKind>(k)));
    }
    s += "\nunset multiplot\n";
    return s;
}

void render_png(const std::string& script, const OutputTarget& png) {
    const std::string bytes = run_gnuplot(script);
    OutputFile file(png);
    file.write(bytes.data(), bytes.size());
    file.commit();
}

void PlotRecorder::draw(const OutputTarget& png) const { render_png(script(), png); }

}  // namespace hsnc
