// `hsnc modes MODEL --to A [options]` (docs/interface.md, "hsnc modes"): the
// backbone of a linear mode continued in amplitude by exact shooting
// (hsnc::modes, api/hsnc/modes.h; a damped mode by the extended periodic motion
// concept): a CSV row per point, the multipliers of every point, a plot of
// frequency (and damping) against amplitude.
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>
#include <vector>

#include "analysis_flags.h"
#include "commands.h"
#include "csv_writer.h"
#include "error.h"
#include "hsnc/modes.h"
#include "model_reader.h"
#include "number_text.h"
#include "output_file.h"
#include "plot.h"

namespace hsnc::cli {
namespace {

struct ModesFlags {
    AnalysisFlags common;  // MODEL, --set, --kernels, --cache-dir, --no-cache, --quiet (--x0, --v0 refused)
    int mode = 1, points = 50, max_iterations = 30;
    std::string dof, out, multipliers, plot, record_dofs;
    double from = NAN, to = NAN, tolerance = 1e-11;
    bool energy = false, geometric = false;
};

std::string short_number(double x) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", x);
    return text;
}

// The backbone, unstable points apart and the resonances passed labelled: the
// amplitude against omega / omega_lin (the linear frequency dashed), or for an
// energy backbone omega / omega_lin against the energy (a frequency-energy
// plot, the energy logarithmic when the points span more than a decade).
void draw_backbone(const OutputTarget& target, const ModesResult& r, const Model& model, bool energy);

// A damped mode: frequency and damping ratio against the amplitude, side by side, the linear
// values dashed.
void draw_damped(const OutputTarget& target, const ModesResult& r, const Model& model) {
    std::ostringstream script;
    script.precision(17);
    const std::string dof = gnuplot_plain(model.masses[r.dof].name);
    script << "set terminal pngcairo size 1100,480 font ',11'\n"
           << "set multiplot layout 1,2 title \"" << gnuplot_plain(model.name) << ": damped mode " << r.mode
           << " (extended periodic motion; omega_lin = " << short_number(r.linear_omega) << " rad/s)\" noenhanced\n"
           << "set grid\nset xlabel 'amplitude of " << dof << " (from equilibrium)' noenhanced\n"
           << "set offsets 0, 0, graph 0.05, graph 0.05\n$b << EOD\n";
    for (const ModePoint& p : r.points)
        script << p.amplitude << " " << p.omega / r.linear_omega << " " << p.damping_ratio << "\n";
    script << "EOD\n"
           << "set ylabel 'frequency omega / omega_lin' noenhanced\n"
           << "set arrow 1 from graph 0, first 1 to graph 1, first 1 nohead dt 2 lc rgb '#888888'\n"
           << "plot $b using 1:2 with linespoints pt 7 ps 0.7 lw 1.5 lc rgb '#0060c0' notitle\n"
           << "unset arrow 1\nset ylabel 'damping ratio xi / (2 omega)' noenhanced\n"
           << "set arrow 2 from graph 0, first " << r.linear_damping_ratio << " to graph 1, first "
           << r.linear_damping_ratio << " nohead dt 2 lc rgb '#888888'\n"
           << "plot $b using 1:3 with linespoints pt 7 ps 0.7 lw 1.5 lc rgb '#c05000' notitle\n"
           << "unset multiplot\n";
    render_png(script.str(), target);
}

void draw_backbone(const OutputTarget& target, const ModesResult& r, const Model& model, bool energy) {
    auto xy = [&](const ModePoint& p) {
        std::ostringstream at;
        at.precision(17);
        if (energy)
            at << p.energy << " " << p.omega / r.linear_omega;
        else
            at << p.omega / r.linear_omega << " " << p.amplitude;
        return at.str();
    };
    std::ostringstream script;
    const std::string dof = gnuplot_plain(model.masses[r.dof].name);
    script << "set terminal pngcairo size 800,560 font ',11'\n"
           << "set title \"" << gnuplot_plain(model.name) << ": backbone of linear mode " << r.mode
           << " (omega_lin = " << short_number(r.linear_omega) << " rad/s)\" noenhanced\n"
           << "set grid\nset key top left\n"
           << "set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.02\n";
    if (energy) {
        const double lo = r.points.front().energy, hi = r.points.back().energy;
        if (std::max(lo, hi) > 10 * std::min(lo, hi))
            script << "set logscale x\nset offsets 0, 0, graph 0.05, graph 0.05\n";
        script << "set xlabel 'energy above equilibrium (J)'\n"
               << "set ylabel 'frequency omega / omega_lin' noenhanced\n"
               << "set arrow from graph 0, first 1 to graph 1, first 1 nohead dt 2 lc rgb '#888888'\n";
    } else {
        script << "set xlabel 'frequency omega / omega_lin' noenhanced\n"
               << "set ylabel 'amplitude of " << dof << " (from equilibrium)' noenhanced\n"
               << "set arrow from 1, graph 0 to 1, graph 1 nohead dt 2 lc rgb '#888888'\n";
    }
    for (const ModePoint& p : r.points) {
        std::string text;
        for (const std::string& s : p.resonances) text += (text.empty() ? "" : ", ") + s;
        if (!text.empty())
            script << "set label \"" << gnuplot_plain(text) << "\" at " << xy(p).replace(xy(p).find(' '), 1, ",")
                   << " offset 1,-0.6 font ',9' tc rgb '#7030a0' noenhanced\n";
    }
    script << "$stable << EOD\n";
    for (const ModePoint& p : r.points)
        if (p.stable) script << xy(p) << "\n";
    script << "EOD\n$unstable << EOD\n";
    bool unstable = false;
    for (const ModePoint& p : r.points)
        if (!p.stable) script << xy(p) << "\n", unstable = true;
    script << "EOD\n$all << EOD\n";
    for (const ModePoint& p : r.points) script << xy(p) << "\n";
    script << "EOD\n"
           << "plot $all using 1:2 with lines lw 1.5 lc rgb '#0060c0' notitle, "
           << "$stable using 1:2 with points pt 7 ps 0.9 lc rgb '#0060c0' title 'stable'";
    if (unstable) script << ", $unstable using 1:2 with points pt 6 ps 1.2 lw 2 lc rgb '#c00000' title 'unstable'";
    script << "\n";
    render_png(script.str(), target);
}

// The dofs whose x_, v_ and peak_ columns the backbone CSV has: --record-dofs (names,
// comma-separated, each once, in that order), else every dof.
std::vector<std::size_t> record_dofs(const Model& model, const std::string& list) {
    std::vector<std::size_t> dofs;
    if (list.empty()) {
        for (std::size_t i = 0; i < model.dof(); ++i) dofs.push_back(i);
        return dofs;
    }
    std::stringstream in(list);
    std::string name;
    while (std::getline(in, name, ',')) {
        const auto first = name.find_first_not_of(' '), last = name.find_last_not_of(' ');
        name = first == std::string::npos ? "" : name.substr(first, last - first + 1);
        const int i = model.mass_index(name);
        if (i < 0) throw InputError("--record-dofs: '" + name + "' is no dof of model '" + model.name + "'");
        if (std::find(dofs.begin(), dofs.end(), static_cast<std::size_t>(i)) != dofs.end())
            throw InputError("--record-dofs: '" + name + "' is named twice");
        dofs.push_back(static_cast<std::size_t>(i));
    }
    return dofs;
}

void write_backbone(const OutputTarget& target, const ModesResult& r, const Model& model,
                    const std::vector<std::size_t>& dofs) {
    CsvFile file(target);
    std::string header = "amplitude,omega,omega_ratio";
    if (r.damped) header += ",damping_ratio,xi";
    header += ",period,energy";
    for (std::size_t i : dofs) header += ",x_" + model.masses[i].name;
    for (std::size_t i : dofs) header += ",v_" + model.masses[i].name;
    for (const Jenkins& j : model.jenkins) header += ",s_" + j.name;
    for (std::size_t i : dofs) header += ",peak_" + model.masses[i].name;
    for (int j : r.others) header += ",ratio_mode" + std::to_string(j);
    header += ",resonance,max_multiplier,stable,events,grazing,iterations,residual";
    file.text(header.c_str());
    file.end_row();
    for (const ModePoint& p : r.points) {
        file.number(p.amplitude);
        file.number(p.omega);
        file.number(p.omega / r.linear_omega);
        if (r.damped) {
            file.number(p.damping_ratio);
            file.number(p.xi);
        }
        file.number(p.period);
        file.number(p.energy);
        for (std::size_t i : dofs) file.number(p.x[i]);
        for (std::size_t i : dofs) file.number(p.v[i]);
        for (double s : p.sliders) file.number(s);
        for (std::size_t i : dofs) file.number(p.peaks[i]);
        for (double q : p.ratios) file.number(q);
        std::string passed;
        for (const std::string& s : p.resonances) passed += (passed.empty() ? "" : ";") + s;
        file.text(passed.c_str());
        file.number(p.max_multiplier);
        file.text(p.stable ? "true" : "false");
        file.number(static_cast<double>(p.events));
        file.number(static_cast<double>(p.grazing));
        file.number(static_cast<double>(p.iterations));
        file.number(p.residual);
        file.end_row();
    }
    file.commit();
}

void write_multipliers(const OutputTarget& target, const ModesResult& r) {
    CsvFile file(target);
    file.text("amplitude,index,re,im,abs");
    file.end_row();
    for (const ModePoint& p : r.points)
        for (std::size_t i = 0; i < p.multipliers.size(); ++i) {
            file.number(p.amplitude);
            file.number(static_cast<double>(i + 1));
            file.number(p.multipliers[i].real());
            file.number(p.multipliers[i].imag());
            file.number(std::abs(p.multipliers[i]));
            file.end_row();
        }
    file.commit();
}

int modes_command(const ModesFlags& f) {
    if (!f.common.overrides.x0.empty() || !f.common.overrides.v0.empty())
        throw InputError(std::string(f.common.overrides.x0.empty() ? "--v0" : "--x0") +
                         ": hsnc modes starts from the linear mode at the static equilibrium, not from an initial "
                         "state");
    const Model model = read_model(f.common.model, f.common.overrides);
    ModesOptions o;
    o.mode = f.mode;
    o.dof = f.dof;
    o.from = f.from;
    o.to = f.to;
    o.points = f.points;
    o.parameter = f.energy ? ModesParameter::energy : ModesParameter::amplitude;
    o.geometric = f.geometric;
    o.tolerance = f.tolerance;
    o.max_iterations = f.max_iterations;
    set_kernels(f.common, o);
    // Every output path and the recorded dofs checked before anything runs (exit code 2, nothing written).
    const std::vector<std::size_t> recorded = record_dofs(model, f.record_dofs);
    AnalysisOutputs outputs;
    const OutputTarget* out = outputs.add("--out", f.out);
    const OutputTarget* mult = outputs.add("--multipliers", f.multipliers);
    const OutputTarget* plot = outputs.add("--plot", f.plot, true);
    outputs.check();

    ProgressLine progress(!f.common.quiet);
    o.progress = [&](const ModesProgress& p) {
        if (!progress.due()) return true;
        char text[240];
        std::snprintf(text, sizeof text,
                      "hsnc modes: %zu of %zu points, amplitude %.6g, %d Newton iterations, residual %.3g, %zu period "
                      "runs, %.0f s",
                      p.point, p.points, p.amplitude, p.iterations, p.residual, p.runs, progress.seconds());
        progress.show(text);
        return true;
    };
    ModesResult r;
    try {
        r = hsnc::modes(model, o);
    } catch (const OptionError& e) {
        throw option_flag_error(e, {{"mode", "--mode"},
                                    {"dof", "--dof"},
                                    {"from", "--from"},
                                    {"to", "--to"},
                                    {"parameter", "--energy"},
                                    {"points", "--points"},
                                    {"tolerance", "--tol"},
                                    {"max_iterations", "--max-iterations"}});
    }
    progress.clear();
    // The points found are written whatever the status: each is a converged orbit.
    if (out) write_backbone(*out, r, model, recorded);
    if (mult) write_multipliers(*mult, r);
    if (plot && !r.points.empty()) {
        if (r.damped)
            draw_damped(*plot, r, model);
        else
            draw_backbone(*plot, r, model, f.energy);
    }
    const bool ok = r.status == ModesStatus::ok;
    std::ostringstream line;
    line << "status=" << modes_status_name(r.status) << " mode=" << r.mode << " dof=" << model.masses[r.dof].name
         << " linear_omega=" << number_text(r.linear_omega) << " points=" << r.points.size();
    if (!r.points.empty()) {
        const ModePoint& last = r.points.back();
        line << " amplitude=" << number_text(last.amplitude) << " omega=" << number_text(last.omega)
             << " energy=" << number_text(last.energy);
        if (r.damped) line << " damping_ratio=" << number_text(last.damping_ratio);
    }
    std::size_t unstable = 0;
    for (const ModePoint& p : r.points) unstable += !p.stable;
    if (!r.damped) line << " unstable=" << unstable;  // a damped mode's multipliers are the EPMC system's
    std::cout << line.str() << std::endl;
    if (!ok) std::fprintf(stderr, "hsnc: modes: %s\n", r.message.c_str());
    return ok ? 0 : 1;
}

}  // namespace

void add_modes(CLI::App& app, int& exit_code) {
    auto f = std::make_shared<ModesFlags>();
    auto* sub = app.add_subcommand(
        "modes",
        "nonlinear normal modes, exactly: the backbone of a linear mode (conservative), or its frequency and damping "
        "against amplitude (damped: extended periodic motion)");
    add_analysis_flags(sub, f->common);
    sub->add_option("--mode", f->mode, "the linear mode to continue, 1 = lowest at the static equilibrium (default 1)");
    sub->add_option("--dof", f->dof,
                    "the dof whose amplitude parameterises the backbone (default: the mode's largest)");
    sub->add_option("--from", f->from, "first amplitude, from the dof's equilibrium position (default TO/POINTS)")
        ->check(finite_number());
    sub->add_option("--to", f->to, "last amplitude (required; negative: the turning point on the negative side)")
        ->check(finite_number());
    sub->add_option("--points", f->points, "points evenly spaced from --from to --to (default 50)");
    sub->add_flag("--energy", f->energy,
                  "--from and --to are energies above the equilibrium (J), not amplitudes: a frequency-energy "
                  "backbone");
    sub->add_flag("--geometric", f->geometric, "space the points in equal ratios (a backbone over decades)");
    sub->add_option("--out", f->out, "backbone CSV, a row per point (docs/interface.md)");
    sub->add_option("--record-dofs", f->record_dofs,
                    "the dofs whose state and peak the backbone CSV has, NAME,NAME,... in that order (default all)");
    sub->add_option("--multipliers", f->multipliers, "Floquet multipliers CSV: amplitude,index,re,im,abs");
    sub->add_option("--plot", f->plot, "draw the backbone (frequency against amplitude) into this PNG (gnuplot)");
    sub->add_option("--tol", f->tolerance, "converged when |P(y) - y| is at most this (relative; default 1e-11)")
        ->check(finite_number());
    sub->add_option("--max-iterations", f->max_iterations, "Newton iterations at most per point (default 30)");
    sub->callback([f, &exit_code] { exit_code = modes_command(*f); });
}

}  // namespace hsnc::cli
