#include "sweep_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <utility>
#include <vector>

#include "plot.h"

namespace hsnc {
namespace {

const char* const kColours[8] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728",
                                 "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"};
constexpr std::size_t kDiagramPanels = 3;

std::string num(double v) {
    if (!std::isfinite(v)) return "NaN";
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.10g", v);
    return buf;
}

std::string quoted(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("''") : std::string(1, c);
    return q + "'";
}

// A curve of --track: the second parameter over the first (one line per
// task), and below the largest |x| of the orbits along it.
std::string curve_plot_script(const SweepResult& r, const std::string& title, const std::vector<std::size_t>& dofs) {
    std::string s = "set terminal pngcairo size 1100,900 noenhanced font ',11'\nset encoding utf8\n";
    std::vector<std::vector<const SweepPoint*>> tasks;
    for (const SweepPoint& p : r.points) {
        if (p.branch_start || tasks.empty()) tasks.emplace_back();
        if (p.failure.empty()) tasks.back().push_back(&p);
    }
    for (std::size_t t = 0; t < tasks.size(); ++t) {
        s += "$curve" + std::to_string(t) + " << EOD\n";
        for (const SweepPoint* p : tasks[t]) {
            s += num(p->value) + " " + num(p->value2);
            for (std::size_t i : dofs) s += " " + num(p->xmax[i]);
            s += "\n";
        }
        s += "EOD\n";
    }
    s += "set multiplot title " + quoted(title) + "\nset grid\nset key inside left top\n";
    s += "set lmargin at screen 0.1\nset rmargin at screen 0.95\n";
    s += "set title " + quoted(r.track + " curve in the (" + r.param + ", " + r.param2 + ") plane") + "\n";
    s += "set tmargin at screen 0.9\nset bmargin at screen 0.5\n";
    s += "set xlabel " + quoted(r.param) + "\nset ylabel " + quoted(r.param2) + "\n";
    std::string plot;
    for (std::size_t t = 0; t < tasks.size(); ++t) {
        std::string name = r.track;
        if (!tasks[t].empty())
            name += " from " + r.param + " = " + num(tasks[t][0]->value) + ", " + r.param2 + " = " +
                    num(tasks[t][0]->value2);
        plot += (plot.empty() ? "" : ", ") + std::string("$curve") + std::to_string(t) +
                " using 1:2 with linespoints lw 2 pt 7 ps 0.5 lc rgb '" + kColours[t % 8] + "' title " + quoted(name);
    }
    s += "plot " + (plot.empty() ? std::string("NaN notitle") : plot) + "\n";
    s += "set title " + quoted("largest |x| over a period of the orbit along the curve") + "\n";
    s += "set tmargin at screen 0.4\nset bmargin at screen 0.07\nset ylabel 'xmax'\n";
    plot.clear();
    for (std::size_t t = 0; t < tasks.size(); ++t)
        for (std::size_t k = 0; k < dofs.size(); ++k)
            plot += (plot.empty() ? "" : ", ") + std::string("$curve") + std::to_string(t) +
                    " using 1:" + std::to_string(k + 3) + " with lines lw 2 lc rgb '" +
                    kColours[(t * dofs.size() + k) % 8] + "' title " + quoted(r.masses[dofs[k]]);
    s += "plot " + (plot.empty() ? std::string("NaN notitle") : plot) + "\nunset multiplot\n";
    return s;
}

}  // namespace

std::string sweep_plot_script(const SweepResult& r, const std::string& title, const std::vector<std::size_t>& dofs) {
    if (!r.track.empty()) return curve_plot_script(r, title, dofs);
    const std::size_t n = r.masses.size(), shown = dofs.size();
    const std::size_t panels = std::min(shown, kDiagramPanels);
    // Units by dof kind (plot.h dof_unit): one axis label when they agree, else each legend entry says its own.
    std::vector<std::string> names;
    for (std::size_t i : dofs) names.push_back(r.masses[i]);
    const std::string unit = common_unit(names);
    auto label = [&](std::size_t i) {
        return unit == "mixed" ? r.masses[i] + " [" + dof_unit(r.masses[i]) + "]" : r.masses[i];
    };
    const bool has2 = !r.param2.empty();
    const int height = 520 + 330 * static_cast<int>(panels);
    std::string s = "set terminal pngcairo size 1300," + std::to_string(height) + " noenhanced font ',11'\n";
    s += "set encoding utf8\n";

    // The points grouped by (second value, direction), in the order they ran.
    std::vector<std::pair<double, SweepDirection>> keys;
    std::map<std::size_t, std::vector<const SweepPoint*>> groups;
    for (const SweepPoint& p : r.points) {
        std::size_t g = 0;
        while (g < keys.size() && !(keys[g].second == p.direction &&
                                    (keys[g].first == p.value2 || (std::isnan(keys[g].first) && std::isnan(p.value2)))))
            ++g;
        if (g == keys.size()) keys.emplace_back(p.value2, p.direction);
        groups[g].push_back(&p);
    }
    // Continuation: the branches, each cut into runs of one stability
    // (blank lines between runs; neighbouring runs share their end point).
    std::vector<std::vector<const SweepPoint*>> branches;
    if (r.continuation)
        for (const SweepPoint& p : r.points) {
            if (p.branch_start || branches.empty()) branches.emplace_back();
            if (p.failure.empty()) branches.back().push_back(&p);
        }
    for (std::size_t b = 0; b < branches.size(); ++b)
        for (int stable = 1; stable >= 0; --stable) {
            s += std::string(stable ? "$stable" : "$unstable") + std::to_string(b) + " << EOD\n";
            const std::vector<const SweepPoint*>& pts = branches[b];
            for (std::size_t k = 0; k < pts.size(); ++k) {
                const bool in = pts[k]->stable == (stable == 1);
                const bool next_in = k + 1 < pts.size() && pts[k + 1]->stable == (stable == 1);
                if (!in && !next_in) continue;
                s += num(pts[k]->value);
                for (std::size_t i = 0; i < n; ++i) s += " " + num(pts[k]->xmax[i]);
                s += "\n";
                if (!next_in) s += "\n";  // the run ends (with the first point of the next run)
            }
            s += "EOD\n";
        }
    const char* const kBifurcations[6] = {"fold",    "period_doubling", "neimark_sacker",
                                          "grazing", "stick_onset",     "slip_onset"};
    bool has_bifurcation[6] = {false, false, false, false, false, false};
    for (int k = 0; k < 6; ++k) {
        s += "$bif" + std::to_string(k) + " << EOD\n";
        for (const SweepPoint& p : r.points)
            if (r.continuation && ("+" + p.bifurcation + "+").find("+" + std::string(kBifurcations[k]) + "+") !=
                                      std::string::npos) {
                has_bifurcation[k] = true;
                s += num(p.value);
                for (std::size_t i = 0; i < n; ++i) s += " " + num(p.xmax[i]);
                s += "\n";
            }
        s += "EOD\n";
    }
    for (std::size_t g = 0; g < keys.size(); ++g) {
        s += "$curve" + std::to_string(g) + " << EOD\n";
        for (const SweepPoint* p : groups[g]) {
            s += num(p->value);
            for (std::size_t i = 0; i < n; ++i) s += " " + num(p->xmax[i]);
            s += "\n";
        }
        s += "EOD\n";
    }
    s += "$unsettled << EOD\n";
    bool any_unsettled = false;
    for (const SweepPoint& p : r.points)
        if (!p.settled) {
            any_unsettled = true;
            s += num(p.value);
            for (std::size_t i = 0; i < n; ++i) s += " " + num(p.xmax[i]);
            s += "\n";
        }
    s += "EOD\n";
    // The diagram: up and down apart (two colours).
    bool has_dir[2] = {false, false};
    for (int d = 0; d < 2; ++d) {
        s += std::string("$diagram") + (d ? "down" : "up") + " << EOD\n";
        for (const SweepPoint& p : r.points) {
            if ((p.direction == SweepDirection::down) != (d == 1)) continue;
            has_dir[d] = has_dir[d] || !p.strobe_t.empty();
            for (std::size_t row = 0; row < p.strobe_t.size(); ++row) {
                s += num(p.value);
                for (std::size_t k = 0; k < panels; ++k) s += " " + num(p.strobe_x[row * n + dofs[k]]);
                s += "\n";
            }
        }
        s += "EOD\n";
    }

    const double top = 1.0 - 75.0 / height, split = 1.0 - 520.0 / height;
    s += "set multiplot title " + quoted(title) + "\n";
    s += "set lmargin at screen 0.09\nset rmargin at screen 0.80\nset grid\nset key outside right top\n";
    // The response curve.
    s += "set title " + quoted(r.continuation ? std::string("periodic orbits by continuation: largest |x| over a period "
                                                            "(solid: stable, dashed: unstable)")
                                              : "response curve: largest |x| over the recorded periods" +
                                                    std::string(any_unsettled ? " (ringed: not settled or failed)" : "")) +
         "\n";
    s += "set tmargin at screen " + num(top) + "\nset bmargin at screen " + num(split + 60.0 / height) + "\n";
    s += "set xlabel " + quoted(r.param) + "\nset ylabel " +
         quoted(unit == "mixed" ? "xmax [m; rad for rotations]" : "xmax [" + unit + "]") + "\n";
    std::string plot;
    for (std::size_t b = 0; b < branches.size(); ++b)
        for (std::size_t k = 0; k < shown; ++k) {
            const std::size_t i = dofs[k], colour = (b * shown + k) % 8;
            std::string name = label(i);
            if (branches[b].size() && branches[b][0]->direction == SweepDirection::down) name += " (from " + r.param + " = " + num(branches[b][0]->value) + ")";
            if (has2 && branches[b].size()) name += " (" + r.param2 + " = " + num(branches[b][0]->value2) + ")";
            if (branches[b].size() && branches[b][0]->multiple > 1)
                name += " (period " + std::to_string(branches[b][0]->multiple) + " T)";
            const bool titled = b * shown + k < 8;
            plot += (plot.empty() ? "" : ", ") + std::string("$stable") + std::to_string(b) + " using 1:" +
                    std::to_string(i + 2) + " with lines lw 2 dt 1 lc rgb '" + kColours[colour] + "' " +
                    (titled ? "title " + quoted(name + " stable") : "notitle");
            plot += ", $unstable" + std::to_string(b) + " using 1:" + std::to_string(i + 2) +
                    " with lines lw 2 dt 2 lc rgb '" + kColours[colour] + "' " +
                    (titled ? "title " + quoted(name + " unstable") : "notitle");
        }
    const char* const kMarks[6] = {"pt 9 ps 1.6", "pt 5 ps 1.3", "pt 13 ps 1.6",
                                   "pt 6 ps 1.8", "pt 4 ps 1.6", "pt 12 ps 1.8"};
    const char* const kMarkNames[6] = {"fold",    "period doubling", "Neimark-Sacker",
                                       "grazing", "stick onset",     "slip onset"};
    for (int k = 0; k < 6; ++k)
        if (has_bifurcation[k])
            for (std::size_t j = 0; j < shown; ++j)
                plot += ", $bif" + std::to_string(k) + " using 1:" + std::to_string(dofs[j] + 2) + " with points " +
                        kMarks[k] + " lc rgb 'black' " + (j == 0 ? "title " + quoted(kMarkNames[k]) : "notitle");
    for (std::size_t g = 0; g < keys.size() && !r.continuation; ++g) {
        const bool down = keys[g].second == SweepDirection::down;
        for (std::size_t k = 0; k < shown; ++k) {
            // One colour per dof (and value of param2); a single curve's down sweep in the next colour.
            const std::size_t i = dofs[k], colour = ((has2 ? g / 2 * shown + k : k) + (shown == 1 && down ? 1 : 0)) % 8;
            std::string name = label(i) + (down ? " down" : " up");
            if (has2) name += " (" + r.param2 + " = " + num(keys[g].first) + ")";
            plot += (plot.empty() ? "" : ", ") + std::string("$curve") + std::to_string(g) +
                    " using 1:" + std::to_string(i + 2) + " with linespoints lw 1.5 " +
                    (down ? "dt 2 pt 6" : "dt 1 pt 7") + " ps 0.7 lc rgb '" + kColours[colour] + "' " +
                    (k < 8 && g < 8 ? "title " + quoted(name) : "notitle");
        }
    }
    if (any_unsettled)
        for (std::size_t k = 0; k < shown; ++k)
            plot += ", $unsettled using 1:" + std::to_string(dofs[k] + 2) +
                    " with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' " + (k == 0 ? "title 'not settled'" : "notitle");
    if (plot.empty()) plot = "NaN notitle";
    s += "plot " + plot + "\n";

    // The diagram, one panel per mass.
    const double panel = (split - 20.0 / height) / static_cast<double>(std::max<std::size_t>(panels, 1));
    for (std::size_t i = 0; i < panels; ++i) {
        const double hi = split - static_cast<double>(i) * panel, lo = hi - panel;
        const std::string& dof = r.masses[dofs[i]];
        s += "set title " +
             quoted(r.continuation ? "x_" + dof + " of each orbit at t0 (colour: the way the parameter moved)"
                                   : "bifurcation diagram: x_" + dof + " at the end of every recorded forcing period") +
             "\n";
        s += "set tmargin at screen " + num(hi - 45.0 / height) + "\nset bmargin at screen " + num(lo + 50.0 / height) +
             "\n";
        s += "set ylabel " + quoted("x_" + dof + " [" + dof_unit(dof) + "]") + "\n";
        std::string dots;
        if (has_dir[0])
            dots = "$diagramup using 1:" + std::to_string(i + 2) + " with points pt 7 ps 0.35 lc rgb '#1f4fb4' title 'up'";
        if (has_dir[1])
            dots += (dots.empty() ? "" : ", ") + std::string("$diagramdown using 1:") + std::to_string(i + 2) +
                    " with points pt 7 ps 0.35 lc rgb '#e06000' title 'down'";
        if (dots.empty()) dots = "NaN notitle";
        s += "plot " + dots + "\n";
    }
    s += "unset multiplot\n";
    return s;
}

namespace {
constexpr const char* kEscapedColour = "#8c510a";  // the basin picture's points that escaped
}

std::string basin_plot_script(const SweepResult& r, const Attractors& a, const std::string& title) {
    const std::size_t K = a.list.size();
    std::string s = "set terminal pngcairo size 1100,850 noenhanced font ',11'\nset encoding utf8\n";
    s += "$basin << EOD\n";
    for (std::size_t k = 0; k < r.points.size(); ++k) {
        if (k > 0 && r.points[k].value2 != r.points[k - 1].value2) s += "\n";  // a scan line per value of param2
        s += num(r.points[k].value) + " " + num(r.points[k].value2) + " " + std::to_string(a.of_point[k]) + "\n";
    }
    s += "EOD\n";
    // The palette: -2 brown (escaped), -1 black (failed), 0 grey (not settled), attractor k its
    // colour, each over [k - 0.5, k + 0.5].
    s += "set palette defined (-2.5 '" + std::string(kEscapedColour) + "', -1.5 '" + kEscapedColour +
         "', -1.5 'black', -0.5 'black', -0.5 '#bbbbbb', 0.5 '#bbbbbb'";
    for (std::size_t k = 1; k <= K; ++k) {
        const std::string c = std::string("'") + kColours[(k - 1) % 8] + "'";
        s += ", " + num(static_cast<double>(k) - 0.5) + " " + c + ", " + num(static_cast<double>(k) + 0.5) + " " + c;
    }
    s += ")\nset cbrange [-2.5:" + num(static_cast<double>(K) + 0.5) + "]\nunset colorbox\n";
    s += "set title " + quoted(title + ": basins of attraction (the attractor each initial state reaches)") + "\n";
    s += "set xlabel " + quoted(r.param) + "\nset ylabel " + quoted(r.param2) + "\n";
    s += "set key outside right top\nset rmargin at screen 0.62\nset autoscale xfix\nset autoscale yfix\n";
    std::string plot = "$basin using 1:2:3 with image notitle";
    const auto total = static_cast<double>(std::max<std::size_t>(1, r.points.size()));
    auto short_num = [](double v, int digits) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.*g", digits, v);
        return std::string(buf);
    };
    for (std::size_t k = 0; k < K; ++k) {
        const Attractor& at = a.list[k];
        const std::string what = at.multiple > 0
                                     ? "period " + std::to_string(at.multiple) + " T, x_" + r.masses[0] + " = "
                                     : "not periodic (a set), x_" + r.masses[0] + " from ";
        std::string name = std::to_string(k + 1) + ": " + what + short_num(at.x[0], 5) + " (" +
                           short_num(100 * static_cast<double>(at.points) / total, 3) + "%)";
        plot += ", NaN with boxes fs solid 1.0 lc rgb '" + std::string(kColours[k % 8]) + "' title " + quoted(name);
    }
    for (const int id : {0, -1, -2}) {
        const auto count = static_cast<std::size_t>(std::count(a.of_point.begin(), a.of_point.end(), id));
        if (count == 0) continue;
        plot += std::string(", NaN with boxes fs solid 1.0 lc rgb '") +
                (id == 0    ? "#bbbbbb"
                 : id == -1 ? "black"
                            : kEscapedColour) +
                "' title " +
                quoted(std::string(id == 0    ? "not settled"
                                   : id == -1 ? "failed"
                                              : "escaped") +
                       " (" + short_num(100 * static_cast<double>(count) / total, 3) + "%)");
    }
    s += "plot " + plot + "\n";
    return s;
}

void draw_basin_plot(const SweepResult& r, const Attractors& a, const std::string& title, const OutputTarget& png) {
    const std::string bytes = run_gnuplot(basin_plot_script(r, a, title));
    OutputFile file(png);
    file.write(bytes.data(), bytes.size());
    file.commit();
}

void draw_sweep_plot(const SweepResult& r, const std::string& title, const OutputTarget& png,
                     const std::vector<std::size_t>& dofs) {
    const std::string bytes = run_gnuplot(sweep_plot_script(r, title, dofs));
    OutputFile file(png);
    file.write(bytes.data(), bytes.size());
    file.commit();
}

}  // namespace hsnc
