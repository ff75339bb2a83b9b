// `hsnc lyapunov MODEL --t-end T [options]` (interface.md section 6): the
// Lyapunov spectrum by the QR method on the exact tangent dynamics
// (hsnc::lyapunov, api/hsnc/lyapunov.h), with its convergence CSV.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>
#include <vector>

#include "commands.h"
#include "csv_writer.h"
#include "error.h"
#include "hsnc/lyapunov.h"
#include "model_reader.h"
#include "output_file.h"
#include "plot.h"

namespace hsnc::cli {
namespace {

struct LyapunovFlags {
    std::string model;
    ModelOverrides overrides;
    double t_end = NAN, transient = 0.0, row = NAN;
    std::string out, plot, kernels = "auto";
    bool quiet = false;
};

// The model's name as plain text inside a gnuplot string (quotes, backslashes
// and backquotes, which gnuplot would interpret, left out).
std::string plain_name(const std::string& name) {
    std::string s;
    for (char c : name)
        if (c != '"' && c != '\\' && c != '`' && c != '\'' && static_cast<unsigned char>(c) >= 32) s += c;
    return s;
}

std::string number_text(double v) {
    std::ostringstream s;
    s.precision(17);
    s << v;
    return s.str();
}

// The running estimates against time (gnuplot), -inf left out.
void draw_convergence(const OutputTarget& target, const Model& model, const std::vector<double>& rows,
                      std::size_t width, const LyapunovResult& r) {
    std::ostringstream s;
    s.precision(10);
    s << "set terminal pngcairo size 900,560 font ',11'\n"
      << "set title '" << plain_name(model.name) << ": Lyapunov exponents, running estimate (sum " << r.sum
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
    const Model model = read_model(f.model, f.overrides);
    LyapunovOptions o;
    o.t_end = f.t_end;
    o.transient = f.transient;
    o.row_interval = f.row;
    try {
        o.kernels = kernel_choice_from_name(f.kernels);
    } catch (const OptionError& e) {
        throw InputError("--kernels '" + f.kernels + "': " + e.reason());
    }
    if (o.kernels == KernelChoice::interp)  // the analyses' flow takes auto, aot or generic
        throw InputError("--kernels 'interp': expected auto, aot or generic");
    std::unique_ptr<OutputTarget> out, plot;
    std::vector<const OutputTarget*> all;
    if (!f.out.empty()) all.push_back((out = std::make_unique<OutputTarget>(check_output("--out", f.out))).get());
    if (!f.plot.empty()) all.push_back((plot = std::make_unique<OutputTarget>(check_output("--plot", f.plot))).get());
    check_distinct(all);
    if (plot) require_gnuplot();

    const std::size_t n2 = 2 * model.dof();
    std::unique_ptr<CsvFile> csv;
    std::vector<double> rows;  // for the plot: t, lambda_1..lambda_2n per row
    std::function<void(double, const std::vector<double>&)> on_row;
    if (out) {
        csv = std::make_unique<CsvFile>(*out);
        std::string header = "t";
        for (std::size_t k = 1; k <= n2; ++k) header += ",lambda_" + std::to_string(k);
        csv->text(header.c_str());
        csv->end_row();
    }
    if (out || plot)
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
    LyapunovResult r;
    try {
        r = hsnc::lyapunov(model, o, on_row);
    } catch (const OptionError& e) {
        static const std::pair<const char*, const char*> flags[] = {
            {"t_end", "--t-end"}, {"transient", "--transient"}, {"row_interval", "--row-interval"}, {"kernels", "--kernels"}};
        for (const auto& fl : flags)
            if (e.option() == fl.first) throw InputError(std::string(fl.second) + ": " + e.reason());
        throw;
    }
    if (r.status != RunStatus::ok)
        throw RunError(std::string("lyapunov: ") + run_status_name(r.status) + ": " + r.message);
    if (csv) csv->commit();
    if (plot) draw_convergence(*plot, model, rows, n2 + 1, r);

    std::ostringstream line;
    line << "status=ok t=" << number_text(r.t);
    for (std::size_t k = 0; k < r.exponents.size(); ++k) line << " lambda_" << k + 1 << "=" << number_text(r.exponents[k]);
    line << " sum=" << number_text(r.sum);
    std::cout << line.str() << std::endl;
    if (!f.quiet)
        std::fprintf(stderr,
                     "hsnc: measured from t = %s over %s s, %zu switch events, %zu directions collapsed by sticks%s\n",
                     number_text(r.t_start).c_str(), number_text(r.t - r.t_start).c_str(), r.events, r.collapsed,
                     r.grazing ? (", " + std::to_string(r.grazing) + " grazing switches skipped (no derivative)").c_str()
                               : "");
    return 0;
}

}  // namespace

void add_lyapunov(CLI::App& app, int& exit_code) {
    auto f = std::make_shared<LyapunovFlags>();
    auto* sub = app.add_subcommand("lyapunov", "the Lyapunov spectrum of the response");
    sub->add_option("MODEL", f->model, "model file (TOML)")->required();
    sub->add_option("--t-end", f->t_end, "length of the measurement in seconds (required)")
        ->required()
        ->check(finite_number());
    sub->add_option("--transient", f->transient, "run this long first, then measure over --t-end (default 0)")
        ->check(finite_number());
    sub->add_option("--set", f->overrides.set, "override a parameter, NAME=VALUE (repeatable)");
    sub->add_option("--x0", f->overrides.x0, "override an initial position, NAME=VALUE (repeatable)");
    sub->add_option("--v0", f->overrides.v0, "override an initial velocity, NAME=VALUE (repeatable)");
    sub->add_option("--out", f->out,
                    "convergence CSV: t,lambda_1..lambda_2n, a row per forcing period (1 s without forcing) and at "
                    "the end");
    sub->add_option("--row-interval", f->row, "spacing of the --out rows (default: the forcing period, else 1 s)")
        ->check(finite_number());
    sub->add_option("--plot", f->plot, "draw the running estimates against time into this PNG (gnuplot)");
    sub->add_option("--kernels", f->kernels, "auto (default), aot or generic");
    sub->add_flag("--quiet", f->quiet, "no statistics on stderr");
    sub->callback([f, &exit_code] { exit_code = lyapunov_command(*f); });
}

}  // namespace hsnc::cli
