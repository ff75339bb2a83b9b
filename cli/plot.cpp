#include "plot.h"

#include <cstdio>
#include <string>

#include "error.h"

namespace hsnc::cli {
namespace {

// Single-quoted gnuplot string: a quote inside is doubled.
std::string quoted(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("''") : std::string(1, c);
    return q + "'";
}

}  // namespace

void plot_trajectory(const Model& model, const std::string& csv, const std::string& png) {
    std::string script = "set terminal pngcairo size 1400,700 noenhanced font ',11'\n"
                         "set output " + quoted(png) + "\n"
                         "set datafile separator ','\n"
                         "set key autotitle columnhead outside right\n"
                         "set grid\nset xlabel 't [s]'\nset ylabel 'x'\n"
                         "set multiplot layout 2,1 title " + quoted(model.name + ": positions (hsnc)") + "\n";
    // Top: the whole run; bottom: its first seconds, where single oscillations show.
    std::string curves;
    for (std::size_t i = 0; i < model.dof(); ++i)
        curves += (i ? ", " : "") + quoted(csv) + " using 1:" + std::to_string(i + 2) + " with lines lw 1";
    script += "plot " + curves + "\n";
    script += "set title 'first 5 s'\nset xrange [" + std::to_string(model.t0) + ":" + std::to_string(model.t0 + 5) +
              "]\nplot " + curves + "\nunset multiplot\n";
    std::FILE* gp = ::popen("gnuplot 2>&1", "w");
    if (!gp) throw RunError("--plot: cannot start gnuplot (install the Debian package gnuplot-nox)");
    std::fputs(script.c_str(), gp);
    const int status = ::pclose(gp);
    if (status != 0) throw RunError("--plot: gnuplot failed (exit status " + std::to_string(status) +
                                    "); is the Debian package gnuplot-nox installed?");
}

}  // namespace hsnc::cli
