// `hsnc lyapunov MODEL --t-end T [options]` (interface.md section 6): the
// Lyapunov spectrum by the QR method on the exact tangent dynamics
// (hsnc::lyapunov, api/hsnc/lyapunov.h), with its convergence CSV.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>
#include <vector>

#include "analysis_flags.h"
#include "commands.h"
#include "csv_writer.h"
#include "error.h"
#include "hsnc/lyapunov.h"
#include "model_reader.h"
#include "output_file.h"
#include "plot.h"
#include "section.h"
#include "number_text.h"

namespace hsnc::cli {
namespace {

struct LyapunovFlags {
    AnalysisFlags common;  // MODEL, --set, --x0, --v0, --kernels, --cache-dir, --no-cache, --quiet
    double t_end = NAN, transient = 0.0, row = NAN;
    bool allow_large_output = false;
    std::string out, plot, h5;
    std::string section, section_out, section_plot;
};

// The running estimates against time (gnuplot), -inf left out.
void draw_convergence(const OutputTarget& target, const Model& model, const std::vector<double>& rows,
                      std::size_t width, const LyapunovResult& r) {
    std::ostringstream s;
    s.precision(10);
    s << "set terminal pngcairo size 900,560 font ',11'\n"
      << "set title '" << gnuplot_plain(model.name) << ": Lyapunov exponents, running estimate (sum " << r.sum
      << " 1/s)' noenhanced\n"
      << "set grid\nset xlabel 't [s]'\nset ylabel 'lambda [1/s]'\nset key outside right\n"
      << "$rows << EOD\n";
    for (std::size_t k = 0; k < rows.size(); k += width) {
        for (std::size_t j = 0; j < width; ++j) {
            const double v = rows[k + j];
            s << (std::isfinite(v) ? number_text(v) : std::string("NaN")) << (j + 1 < width ? " " : "\n");
        }
    }
    s << "EOD\nplot ";
    for (std::size_t j = 1; j < width; ++j)
        s << (j > 1 ? ", " : "") << "$rows using 1:" << j + 1 << " with lines lw 2 title 'lambda_" << j << "' noenhanced";
    s << ", 0 with lines lc rgb '#888888' notitle\n";
    render_png(s.str(), target);
}

int lyapunov_command(const LyapunovFlags& f) {
    const Model model = read_model(f.common.model, f.common.overrides);
    LyapunovOptions o;
    o.t_end = f.t_end;
    o.transient = f.transient;
    o.row_interval = f.row;
    set_kernels(f.common, o);
    SectionSpec spec;
    const bool section = section_requested(model, f.section, f.section_out, f.section_plot, &spec, !f.h5.empty());
    // Every output path checked before anything runs (exit code 2, nothing written).
    AnalysisOutputs outputs;
    const OutputTarget* out = outputs.add("--out", f.out);
    const OutputTarget* plot = outputs.add("--plot", f.plot, true);
    const OutputTarget* section_out = outputs.add("--section-out", f.section_out);
    const OutputTarget* section_plot = outputs.add("--section-plot", f.section_plot, true);
    const OutputTarget* h5 = outputs.add_h5(f.h5);
    outputs.check();

    const std::size_t n2 = 2 * model.dof() + model.jenkins.size();  // and one per Jenkins slider
    // The rows are written (--out) and kept for the plot (--plot): the output
    // guard of `hsnc simulate`, before the run.
    if (out || plot || h5) {
        const double row = lyapunov_row_interval(model, o);
        if (row > 0 && std::isfinite(f.t_end) && f.t_end > 0)
            check_output_size(std::isnan(f.row) ? "--t-end " + number_text(f.t_end) + " (a row every " +
                                                      number_text(row) + " s)"
                                                : "--row-interval " + number_text(f.row),
                              out ? "the convergence --out" : "the convergence rows of --plot", std::floor(f.t_end / row) + 1,
                              n2 + 1, f.allow_large_output);
    }
    const std::unique_ptr<H5Archive> archive = open_h5(h5, model, f.common.overrides);
    std::unique_ptr<CsvFile> csv;
    std::vector<double> rows;  // for the plot: t, lambda_1..lambda_2n per row
    std::function<void(double, const std::vector<double>&)> on_row;
    if (out || archive) {
        csv = std::make_unique<CsvFile>(out, archive ? &archive->table("lyapunov/convergence") : nullptr);
        std::string header = "t";
        for (std::size_t k = 1; k <= n2; ++k) header += ",lambda_" + std::to_string(k);
        csv->text(header.c_str());
        csv->end_row();
    }
    if (csv || plot)
        on_row = [&](double t, const std::vector<double>& ex) {
            if (csv) {
                csv->number(t);
                for (double e : ex) csv->number(e);
                csv->end_row();
            }
            if (plot) {
                rows.push_back(t);
                rows.insert(rows.end(), ex.begin(), ex.end());
            }
        };
    // The section over the measurement (from t0 + transient on).
    std::unique_ptr<CsvFile> section_file;
    std::unique_ptr<SectionRecorder> recorder;
    if (section_out || (archive && section))
        section_file = std::make_unique<CsvFile>(section_out, archive ? &archive->table("lyapunov/section") : nullptr);
    if (section)
        recorder = std::make_unique<SectionRecorder>(model, spec, section_file.get(), section_plot != nullptr,
                                                     model.t0 + f.transient);
    // Progress on stderr: the time reached over transient + measurement.
    ProgressLine progress(!f.common.quiet);
    const double span = f.transient + f.t_end;
    o.progress = [&](double t) {
        if (!progress.due()) return true;
        const double done = std::min(1.0, std::max(0.0, (t - model.t0) / span)), elapsed = progress.seconds();
        char text[200];
        std::snprintf(text, sizeof text, "hsnc lyapunov: t = %.6g s, %.1f%% of %s, %.0f s, about %.0f s left", t,
                      100 * done, f.transient > 0 ? "transient and measurement" : "the measurement", elapsed,
                      done > 0 ? elapsed * (1 - done) / done : 0.0);
        progress.show(text);
        return true;
    };
    LyapunovResult r;
    try {
        r = hsnc::lyapunov(model, o, on_row, recorder.get());
    } catch (const OptionError& e) {
        throw option_flag_error(e, {{"t_end", "--t-end"}, {"transient", "--transient"}, {"row_interval", "--row-interval"}});
    }
    progress.clear();
    if (r.status != RunStatus::ok)
        throw RunError(std::string("lyapunov: ") + run_status_name(r.status) + ": " + r.message);
    if (csv) csv->commit();
    if (section_file) section_file->commit();
    if (plot) draw_convergence(*plot, model, rows, n2 + 1, r);
    if (section_plot) recorder->draw(*section_plot);
    if (archive) {
        CsvFile exponents(nullptr, &archive->table("lyapunov/exponents"));
        exponents.text("index,lambda");
        exponents.end_row();
        for (std::size_t k = 0; k < r.exponents.size(); ++k) {
            exponents.number(static_cast<double>(k + 1));
            exponents.number(r.exponents[k]);
            exponents.end_row();
        }
        archive->commit();
    }

    std::ostringstream line;
    line << "status=ok t=" << number_text(r.t);
    for (std::size_t k = 0; k < r.exponents.size(); ++k) line << " lambda_" << k + 1 << "=" << number_text(r.exponents[k]);
    line << " sum=" << number_text(r.sum) << " grazing=" << r.grazing;
    std::cout << line.str() << std::endl;
    if (r.grazing)
        std::fprintf(stderr,
                     "hsnc: warning: the motion grazes: %zu switch instants where a contact closes or opens at a "
                     "turning point of its gap (|G'| Omega / |G''| <= 1e-4; %zu of them without a saltation matrix, "
                     "skipped); the flow is not smooth there, so the exponents are not reliable\n",
                     r.grazing, r.singular);
    if (!f.common.quiet) {
        std::fprintf(stderr, "hsnc: measured from t = %s over %s s, %zu switch events, %zu directions collapsed by sticks\n",
                     number_text(r.t_start).c_str(), number_text(r.t - r.t_start).c_str(), r.events, r.collapsed);
        if (recorder)
            std::fprintf(stderr, "hsnc: Poincare section at %s: %zu points\n", f.section.c_str(), recorder->points());
    }
    return 0;
}

}  // namespace

void add_lyapunov(CLI::App& app, int& exit_code) {
    auto f = std::make_shared<LyapunovFlags>();
    auto* sub = app.add_subcommand("lyapunov", "the Lyapunov spectrum of the response");
    add_analysis_flags(sub, f->common);
    sub->add_option("--t-end", f->t_end, "length of the measurement in seconds (required)")
        ->required()
        ->check(finite_number());
    sub->add_option("--transient", f->transient, "run this long first, then measure over --t-end (default 0)")
        ->check(finite_number());
    sub->add_option("--out", f->out,
                    "convergence CSV: t,lambda_1..lambda_2n, a row per forcing period (1 s without forcing) and at "
                    "the end");
    sub->add_option("--row-interval", f->row, "spacing of the --out rows (default: the forcing period, else 1 s)")
        ->check(finite_number());
    sub->add_option("--plot", f->plot, "draw the running estimates against time into this PNG (gnuplot)");
    sub->add_flag("--allow-large-output", f->allow_large_output,
                  "write --out (and keep for --plot) more than 1e7 rows or about 1 GB (refused otherwise)");
    add_section_flags(sub, f->section, f->section_out, f->section_plot, " over the measurement");
    add_h5_flag(sub, f->h5, "lyapunov/convergence as --out, lyapunov/exponents, lyapunov/section as --section-out");
    sub->callback([f, &exit_code] { exit_code = lyapunov_command(*f); });
}

}  // namespace hsnc::cli
