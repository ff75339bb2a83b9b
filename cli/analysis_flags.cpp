#include "analysis_flags.h"

#include <sstream>

#include "commands.h"
#include "plot.h"

namespace hsnc::cli {

void add_analysis_flags(CLI::App* sub, AnalysisFlags& f) {
    sub->add_option("MODEL", f.model, "model file (TOML)")->required();
    sub->add_option("--set", f.overrides.set, "override a parameter, NAME=VALUE (repeatable)");
    sub->add_option("--x0", f.overrides.x0, "override an initial position, NAME=VALUE (repeatable)");
    sub->add_option("--v0", f.overrides.v0, "override an initial velocity, NAME=VALUE (repeatable)");
    sub->add_option("--kernels", f.kernels,
                    "the segment solvers, as simulate --kernels: auto (default), aot, generic, interp, eigen, jit or tiered (the tangent "
                    "dynamics are the same closed forms whatever the kind)");
    sub->add_option("--cache-dir", f.cache_dir,
                    "keep compiled kernels (jit, tiered) in DIR (default $XDG_CACHE_HOME/hsnc, else ~/.cache/hsnc)");
    sub->add_flag("--no-cache", f.no_cache, "read and write no cache: jit compiles every kernel, tiered stays interpreted")
        ->excludes(sub->get_option("--cache-dir"));
    sub->add_flag("--quiet", f.quiet, "no statistics on stderr");
}

void add_section_flags(CLI::App* sub, std::string& section, std::string& out, std::string& plot,
                       const std::string& what) {
    sub->add_option("--section", section,
                    "Poincare section at a switch kind" + what +
                        ": KIND[:NAME], KIND contact_close, contact_open, stick, release or reversal, NAME the "
                        "contact or mass (default: any); needs --section-out or --section-plot");
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

void AnalysisOutputs::check() const {
    std::vector<const OutputTarget*> all;
    for (const auto& t : targets_) all.push_back(t.get());
    check_distinct(all);
    if (png_) require_gnuplot();
}

std::string gnuplot_plain(const std::string& text) {
    std::string s;
    for (char c : text)
        if (c != '"' && c != '\\' && c != '`' && c != '\'' && static_cast<unsigned char>(c) >= 32) s += c;
    return s;
}

std::string full_number(double v) {
    std::ostringstream s;
    s.precision(17);
    s << v;
    return s.str();
}

}  // namespace hsnc::cli
