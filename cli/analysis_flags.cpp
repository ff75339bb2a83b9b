#include "analysis_flags.h"

#include <unistd.h>

#include <cstdio>
#include <sstream>

#include "commands.h"
#include "plot.h"
#include "plugin_module.h"
#include "simulate_outputs.h"

namespace hsnc::cli {

void add_analysis_flags(CLI::App* sub, AnalysisFlags& f) {
    sub->add_option("MODEL", f.model, "model file (TOML)")->required();
    sub->add_option("--set", f.overrides.set, "override a parameter, NAME=VALUE (repeatable)");
    sub->add_option("--x0", f.overrides.x0, "override an initial position, NAME=VALUE (repeatable)");
    sub->add_option("--v0", f.overrides.v0, "override an initial velocity, NAME=VALUE (repeatable)");
    std::string kernels = kernel_choice_names();  // "auto, aot, ...": auto is the default
    kernels.insert(std::string(kKernelChoiceNames[0].name).size(), " (default)");
    sub->add_option("--kernels", f.kernels,
                    "the segment solvers, as simulate --kernels: " + kernels +
                        " (the tangent dynamics are the same closed forms whatever the kind)");
    sub->add_option("--cache-dir", f.cache_dir,
                    "keep compiled kernels (jit, tiered) in DIR (default $XDG_CACHE_HOME/hsnc, else ~/.cache/hsnc)");
    sub->add_flag("--no-cache", f.no_cache, "read and write no cache: jit compiles every kernel, tiered stays interpreted")
        ->excludes(sub->get_option("--cache-dir"));
    sub->add_flag("--quiet", f.quiet, "no statistics on stderr");
}

void add_section_flags(CLI::App* sub, std::string& section, std::string& out, std::string& plot,
                       const std::string& what, bool stroboscopic) {
    sub->add_option("--section", section,
                    "Poincare section at a switch kind" + what +
                        ": KIND[:NAME], KIND contact_close, contact_open, stick, release or reversal (or impact, "
                        "at a rigid stop), NAME the contact or mass (default: any)" +
                        (stroboscopic ? "; or period[:OMEGA], the state every 2 pi/OMEGA s (default OMEGA: the "
                                        "forcing's frequency) with its rotation number in the summary"
                                      : "") +
                        "; needs --section-out or --section-plot");
    sub->add_option("--section-out", out,
                    "the section's CSV: t,x_<mass>...,v_<mass>..., the state at each instant of such an event");
    sub->add_option("--section-plot", plot, "draw the section (v against x, one panel per mass) into this PNG (gnuplot)");
}

AnalysisKernels analysis_kernels(const AnalysisFlags& f) {
    AnalysisKernels k;
    try {
        k.kernels = kernel_choice_from_name(f.kernels);
    } catch (const OptionError& e) {
        throw InputError("--kernels '" + f.kernels + "': " + e.reason());
    }
    k.cache_dir = f.cache_dir;
    k.use_cache = !f.no_cache;
    return k;
}

InputError option_flag_error(const OptionError& e, std::initializer_list<std::pair<const char*, const char*>> flags) {
    if (e.option() == "kernels") return InputError("--kernels: " + e.reason());
    for (const auto& f : flags)
        if (e.option() == f.first) return InputError(std::string(f.second) + ": " + e.reason());
    return InputError(e.what());
}

const OutputTarget* AnalysisOutputs::add(const char* flag, const std::string& path, bool png) {
    if (path.empty()) return nullptr;
    targets_.push_back(std::make_unique<OutputTarget>(check_output(flag, path)));
    png_ = png_ || png;
    return targets_.back().get();
}

const OutputTarget* AnalysisOutputs::add_h5(const std::string& path) {
    if (path.empty()) return nullptr;
    targets_.push_back(std::make_unique<OutputTarget>(check_h5(path)));
    return targets_.back().get();
}

H5Open h5_module() {
#ifdef HSNC_H5_MODULE
    static H5Open open = nullptr;
    if (!open) {
        std::string problem;
        open = reinterpret_cast<H5Open>(api::plugin_module_symbol(api::plugin_module_path(HSNC_H5_MODULE),
                                                                  "hsnc_h5_open", api::SymbolScope::kLocal, problem));
        if (!open) throw RunError("--h5: cannot load the HDF5 module: " + problem);
    }
    return open;
#else
    throw InputError(
        "--h5: this hsnc was built without HDF5 (configure with -DHSNC_WITH_HDF5=ON, Debian's libhdf5-dev)");
#endif
}

OutputTarget check_h5(const std::string& path) {
    OutputTarget target = check_h5_output(path);
    h5_module();  // loaded before anything runs: a missing module is said at once
    return target;
}

std::unique_ptr<H5Archive> open_h5(const OutputTarget* target, const Model& model, const ModelOverrides& overrides) {
    if (!target) return nullptr;
    auto archive = std::make_unique<H5Archive>(*target, h5_module());
    write_h5_provenance(*archive, model.name, model.source, overrides_given(overrides));
    return archive;
}

std::vector<std::string> overrides_given(const ModelOverrides& overrides) {
    std::vector<std::string> given;
    for (const auto& s : overrides.set) given.push_back("--set " + s);
    for (const auto& s : overrides.x0) given.push_back("--x0 " + s);
    for (const auto& s : overrides.v0) given.push_back("--v0 " + s);
    return given;
}

void add_h5_flag(CLI::App* sub, std::string& path, const std::string& tables) {
    sub->add_option("--h5", path,
                    "HDF5 file of the results (" + tables +
                        ": one dataset per CSV column) with the model text, overrides, hsnc version and command");
}

void AnalysisOutputs::check() const {
    std::vector<const OutputTarget*> all;
    for (const auto& t : targets_) all.push_back(t.get());
    check_distinct(all);
    if (png_) require_gnuplot();
}

void check_output_size(const std::string& cause, const std::string& what, double rows, std::size_t columns,
                       bool allowed) {
    if (allowed) return;
    // Every number is printed with 17 significant digits: about 22 bytes with its comma.
    const double bytes = rows * static_cast<double>(columns) * 22;
    if (!(rows > static_cast<double>(kLargeOutputRows) || bytes > kLargeOutputBytes)) return;
    auto short_number = [](double v) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.3g", v);
        return std::string(buf);
    };
    const char* units[] = {"B", "kB", "MB", "GB", "TB", "PB", "EB"};
    double b = bytes;
    int u = 0;
    while (b >= 1000 && u < 6) b /= 1000, ++u;
    throw InputError(cause + ": " + what + " would have " + short_number(rows) + " rows, about " + short_number(b) +
                     " " + units[u] + " (the limit is 1e7 rows or 1 GB): give fewer rows, or --allow-large-output " +
                     "to write it anyway");
}

ProgressLine::ProgressLine(bool enabled)
    : enabled_(enabled), terminal_(enabled && ::isatty(2)), start_(std::chrono::steady_clock::now()) {}

double ProgressLine::seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

bool ProgressLine::due() {
    if (!enabled_) return false;
    const double now = seconds();
    const double first = terminal_ ? 0.5 : 10.0, every = terminal_ ? 0.1 : 10.0;
    if (now < first || (last_ > 0 && now - last_ < every)) return false;
    last_ = now;
    return true;
}

void ProgressLine::show(const std::string& text) {
    if (terminal_) {
        std::fprintf(stderr, "\r%-79.79s", text.c_str());
        drawn_ = true;
    } else {
        std::fprintf(stderr, "%s\n", text.c_str());
    }
}

void ProgressLine::clear() {
    if (drawn_) std::fprintf(stderr, "\r%79s\r", "");
    drawn_ = false;
}

std::string gnuplot_plain(const std::string& text) {
    std::string s;
    for (char c : text)
        if (c != '"' && c != '\\' && c != '`' && c != '\'' && static_cast<unsigned char>(c) >= 32) s += c;
    return s;
}

}  // namespace hsnc::cli
