// `hsnc periodic MODEL [options]` (interface.md section 6): a periodic orbit
// of the forced response by Newton shooting with the exact monodromy matrix
// (hsnc::periodic, api/hsnc/periodic.h), its Floquet multipliers and one
// period of it.
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
#include "hsnc/periodic.h"
#include "model_reader.h"
#include "output_file.h"
#include "plot.h"
#include "simulate_outputs.h"
#include "number_text.h"

namespace hsnc::cli {
namespace {

struct PeriodicFlags {
    AnalysisFlags common;  // MODEL, --set, --x0, --v0, --kernels, --cache-dir, --no-cache, --quiet
    double period = NAN, transient = 0.0, dt = NAN, tolerance = 1e-10;
    int harmonic = 1, max_iterations = 50;
    bool allow_large_output = false;
    std::string multipliers, out, plot, h5;
};

// The multipliers in the complex plane with the unit circle (gnuplot).
void draw_multipliers(const OutputTarget& target, const PeriodicResult& r, const Model& model) {
    std::ostringstream title;
    title.precision(6);
    title << gnuplot_plain(model.name) << ": Floquet multipliers\\nperiod " << r.period << " s, max |mu| " << r.max_multiplier
          << (r.stable ? " (stable" : " (unstable")
          << (r.neutral ? "; " + std::to_string(r.neutral) + " neutral: a family of orbits)" : std::string(")"));
    std::ostringstream script;
    script.precision(17);
    script << "set terminal pngcairo size 640,640 font ',11'\n"
           << "set title \"" << title.str() << "\" noenhanced\n"
           << "set size ratio -1\nset grid\nset xlabel 'Re mu'\nset ylabel 'Im mu'\nset key top right\n"
           << "set parametric\nset trange [0:2*pi]\n"
           << "R = " << std::max(1.05, 1.1 * r.max_multiplier) << "\n"
           << "set xrange [-R:R]\nset yrange [-R:R]\n"
           << "$mu << EOD\n";
    // The family's multipliers at +1 (PeriodicResult::neutral) apart: they do not make the orbit unstable.
    std::size_t neutral = r.neutral;
    std::vector<std::complex<double>> family;
    for (const auto& mu : r.multipliers) {
        if (neutral > 0 && std::abs(mu - 1.0) <= kNeutralMultiplier) {
            --neutral;
            family.push_back(mu);
            continue;
        }
        script << mu.real() << " " << mu.imag() << "\n";
    }
    script << "EOD\n";
    if (!family.empty()) {
        script << "$family << EOD\n";
        for (const auto& mu : family) script << mu.real() << " " << mu.imag() << "\n";
        script << "EOD\n";
    }
    script << "plot cos(t), sin(t) with lines lc rgb '#888888' title 'unit circle', "
           << "$mu using 1:2 with points pt 7 ps 1.6 lc rgb '#c00000' title 'multipliers'";
    if (!family.empty())
        script << ", $family using 1:2 with points pt 6 ps 2.2 lw 2 lc rgb '#0060c0' title 'neutral (a family of orbits)'";
    script << "\n";
    render_png(script.str(), target);
}

// The orbit's summary: the line on stdout and, with --h5, the table
// periodic/summary (written only when the orbit converged). The line's
// stable and max_multiplier say false and nan when it did not.
SummaryRow summary(const Model& model, const PeriodicResult& r, bool ok) {
    SummaryRow row;
    row.word("status", periodic_status_name(r.status), SummaryRow::Where::line);
    row.number("period", r.period);
    row.number("iterations", static_cast<double>(r.iterations));
    row.number("residual", r.residual);
    for (std::size_t i = 0; i < model.dof(); ++i) row.number("x_" + model.masses[i].name, r.x[i]);
    for (std::size_t i = 0; i < model.dof(); ++i) row.number("v_" + model.masses[i].name, r.v[i]);
    for (std::size_t j = 0; j < model.jenkins.size(); ++j)  // the sliders are state too (docs/interface.md)
        row.number("s_" + model.jenkins[j].name, r.s[j]);
    row.word("stable", ok && r.stable ? "true" : "false");
    row.number("max_multiplier", ok ? r.max_multiplier : std::nan(""));
    row.number("events", static_cast<double>(r.events), SummaryRow::Where::table);
    row.number("grazing", static_cast<double>(r.grazing));
    if (ok && r.neutral)  // a family's multipliers at +1 (docs/interface.md)
        row.number("neutral", static_cast<double>(r.neutral), SummaryRow::Where::line);
    return row;
}

int periodic_command(const PeriodicFlags& f) {
    const Model model = read_model(f.common.model, f.common.overrides);
    PeriodicOptions o;
    o.period = f.period;
    o.harmonic = f.harmonic;
    o.transient = f.transient;
    o.tolerance = f.tolerance;
    o.max_iterations = f.max_iterations;
    o.dt = f.dt;
    set_kernels(f.common, o);
    // Every output path checked before anything runs (exit code 2, nothing written).
    AnalysisOutputs outputs;
    const OutputTarget* out = outputs.add("--out", f.out);
    const OutputTarget* mult = outputs.add("--multipliers", f.multipliers);
    const OutputTarget* plot = outputs.add("--plot", f.plot, true);
    const OutputTarget* h5 = outputs.add_h5(f.h5);
    outputs.check();
    // One period of the orbit sampled every --dt: the output guard of `hsnc simulate`, before the run.
    if (out || h5) {
        const double period = (std::isnan(f.period) ? forcing_period(model) : f.period) * f.harmonic;
        const double dt = std::isnan(f.dt) ? period / 1000 : f.dt;
        if (period > 0 && std::isfinite(period) && dt > 0)
            check_output_size("--dt " + number_text(dt), "one period (" + number_text(period) + " s) of the orbit --out",
                              trajectory_rows(0.0, period, dt), 1 + 2 * model.dof() + model.jenkins.size(),
                              f.allow_large_output);
    }

    const std::unique_ptr<H5Archive> archive = open_h5(h5, model, f.common.overrides);
    std::unique_ptr<CsvFile> traj;
    std::unique_ptr<CsvObserver> csv;
    if (out || archive) {
        traj = std::make_unique<CsvFile>(out, archive ? &archive->table("periodic/orbit") : nullptr);
        csv = std::make_unique<CsvObserver>(model, traj.get(), nullptr);
    }
    // Progress on stderr: the stage, the Newton iterations and residual, the time reached.
    ProgressLine progress(!f.common.quiet);
    o.progress = [&](const PeriodicProgress& p) {
        if (!progress.due()) return true;
        const double span = p.t_to - p.t_from, done = span > 0 ? (p.t - p.t_from) / span : 1.0;
        char text[240];
        if (p.stage == PeriodicProgress::Stage::transient)
            std::snprintf(text, sizeof text, "hsnc periodic: transient, t = %.6g s (%.1f%%), %.0f s", p.t, 100 * done,
                          progress.seconds());
        else
            std::snprintf(text, sizeof text,
                          "hsnc periodic: %s, %d Newton iterations, residual %.3g, %zu period runs (this one %.0f%%), "
                          "%.0f s",
                          p.stage == PeriodicProgress::Stage::search ? "search" : "the orbit", p.iterations,
                          p.residual, p.runs, 100 * done, progress.seconds());
        progress.show(text);
        return true;
    };
    PeriodicResult r;
    try {
        r = hsnc::periodic(model, o, csv.get());
    } catch (const OptionError& e) {
        throw option_flag_error(e, {{"period", "--period"},
                                    {"harmonic", "--harmonic"},
                                    {"transient", "--transient"},
                                    {"tolerance", "--tol"},
                                    {"dt", "--dt"},
                                    {"max_iterations", "--max-iterations"}});
    }
    progress.clear();
    const bool ok = r.status == PeriodicStatus::ok;
    if (ok) {
        if (traj) traj->commit();
        if (mult || archive) {
            CsvFile file(mult, archive ? &archive->table("periodic/multipliers") : nullptr);
            file.text("index,re,im,abs");
            file.end_row();
            for (std::size_t i = 0; i < r.multipliers.size(); ++i) {
                file.number(static_cast<double>(i + 1));
                file.number(r.multipliers[i].real());
                file.number(r.multipliers[i].imag());
                file.number(std::abs(r.multipliers[i]));
                file.end_row();
            }
            file.commit();
        }
        if (plot) draw_multipliers(*plot, r, model);
        if (archive) {
            summary(model, r, true).write(archive->table("periodic/summary"));
            archive->commit();
        }
    }
    std::cout << summary(model, r, ok).line() << std::endl;
    if (r.grazing)
        std::fprintf(stderr,
                     "hsnc: warning: the orbit grazes: %zu switch instants a period where a contact closes or opens "
                     "at a turning point of its gap (|G'| Omega / |G''| <= 1e-4), or without a saltation matrix; the "
                     "period map is not smooth there, so its multipliers and stability are not reliable\n",
                     r.grazing);
    if (!f.common.quiet) {
        if (ok)
            std::fprintf(stderr, "hsnc: orbit at t = %s, %zu switch events a period\n", number_text(r.t).c_str(),
                         r.events);
        else
            std::fprintf(stderr, "hsnc: periodic: not converged: %s\n", r.message.c_str());
    }
    if (!ok && f.common.quiet) std::fprintf(stderr, "hsnc: periodic: not converged: %s\n", r.message.c_str());
    return ok ? 0 : 1;
}

}  // namespace

void add_periodic(CLI::App& app, int& exit_code) {
    auto f = std::make_shared<PeriodicFlags>();
    auto* sub = app.add_subcommand("periodic", "a periodic orbit of the forced response and its stability");
    add_analysis_flags(sub, f->common);
    sub->add_option("--period", f->period, "forcing period T (default 2*pi/omega of the model's forcing)")
        ->check(finite_number());
    sub->add_option("--harmonic", f->harmonic, "look for an orbit of period K*T (subharmonic; default 1)");
    sub->add_option("--transient", f->transient,
                    "simulate this long from the initial state first and start the search at the next t0 + k*K*T "
                    "(default 0)")
        ->check(finite_number());
    sub->add_option("--multipliers", f->multipliers,
                    "Floquet multipliers CSV: index,re,im,abs, largest |mu| first (written only when converged)");
    sub->add_option("--out", f->out, "one period of the orbit, trajectory CSV (written only when converged)");
    sub->add_option("--dt", f->dt, "sample spacing of --out (default period/1000)")->check(finite_number());
    sub->add_flag("--allow-large-output", f->allow_large_output,
                  "write an --out of more than 1e7 rows or about 1 GB (refused otherwise)");
    sub->add_option("--plot", f->plot, "draw the multipliers and the unit circle into this PNG (gnuplot)");
    add_h5_flag(sub, f->h5, "periodic/orbit as --out, periodic/multipliers, periodic/summary; only when converged");
    sub->add_option("--tol", f->tolerance,
                    "converged when |P(y) - y| is at most this, relative to the largest position and velocity "
                    "(default 1e-10)")
        ->check(finite_number());
    sub->add_option("--max-iterations", f->max_iterations, "Newton iterations at most (default 50)");
    sub->callback([f, &exit_code] { exit_code = periodic_command(*f); });
}

}  // namespace hsnc::cli
