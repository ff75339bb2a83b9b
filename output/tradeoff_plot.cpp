#include "tradeoff_plot.h"

#include <unistd.h>

#include <cstdio>

#include "error.h"
#include "plot.h"

namespace hsnc {
namespace {

std::string num(double v, int digits = 3) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    return buf;
}

// Single-quoted gnuplot string: a quote inside is doubled.
std::string quoted(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("''") : std::string(1, c);
    return q + "'";
}

}  // namespace

// Log-log: wall time against the relative position error (left) and the
// event-time error (right), one curve per method, each point labelled with its
// setting (and on the right, the matched count when the run did not match
// every event). Runs that did not reach t_end (status not ok) are left out; an
// error of exactly 0 is drawn at 1e-17. Diverged runs (column `diverged`) are
// pinned at diverged_ratio on the left, labelled with method and setting, so
// that a 1e100 does not squash the axis, and left out on the right.
void plot_tradeoff(const TradeoffPlot& plot, const std::string& csv, const OutputTarget& png) {
    const std::string& reference_label = plot.reference_label;
    const double magnitude = plot.magnitude, diverged_ratio = plot.diverged_ratio;
    const bool any_diverged = plot.any_diverged, any_matched = plot.any_matched;
    const double min_wall = plot.min_wall, max_wall = plot.max_wall;
    const std::string top = num(diverged_ratio);
    std::string script = "set terminal pngcairo size 1600,700 noenhanced font ',11'\n"
                         "set datafile separator ','\n"
                         "set logscale xy\nset grid\nset offsets graph 0.04, graph 0.04, 0, 0\nset format y '%.0e'\nset format x '%.0e'\n"
                         "set key below horizontal\nset bmargin 7\nset xlabel 'wall time [s]'\n"
                         "set multiplot layout 1,2 title " +
                         quoted(plot.model + ": work-precision, reference " + reference_label) + "\n";
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
        script += std::string(left ? "set yrange [1e-18:" + num(10 * diverged_ratio) + "]\n" : "set yrange [1e-18:*]\n");
        script += "set ylabel " + quoted(panel[1]) + "\nplot ";
        bool first = true;
        int curve = 0;  // one line type per method, the same on both panels
        for (const TradeoffPlot::Curve& m : plot.curves) {
            ++curve;
            const std::string sel = "(strcol(1) eq " + quoted(m.method) + " && strcol(6) eq 'ok' && strcol(16) ne '1'";
            const std::string y = "($" + panel[0] + " > 1e-17 ? $" + panel[0] + " : 1e-17)";
            const std::string using_xy = sel + " ? $4 : NaN):" + y;
            // Labels: the setting; on the event panel also "(matched/total)" when not all matched.
            std::string label = "(word(strcol(2), 1)";
            if (!left) label += " . (column(11) < column(10) ? sprintf(' (%d/%d)', column(11), column(10)) : '')";
            label += ")";
            // hsnc's points are kernel kinds, not a sweep: points, no line.
            const char* style = !m.sweep ? "points pt 7 ps 1.5" : "linespoints lw 2 pt 7";
            script += std::string(first ? "" : ", ") + quoted(csv) + " skip 1 using " + using_xy + " with " + style +
                      " lt " + std::to_string(curve) + " title " + quoted(m.method);
            if (!m.sweep) {
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
    // The PNG through gnuplot's stdout into an output file (output_file.h):
    // checked, written under a temporary name, renamed with the other outputs.
    const std::string bytes = run_gnuplot(script);
    OutputFile file(png);
    file.write(bytes.data(), bytes.size());
    file.commit();
}

}  // namespace hsnc
