// hsnc -- what the analysis commands `hsnc periodic` and `hsnc lyapunov`
// share on the command line: the model and its overrides, the kernel kind
// (as `hsnc simulate --kernels`, with its cache flags), --quiet, the output
// paths checked before anything runs, the library's option names turned back
// into flags, and the Poincare section flags (also `hsnc simulate`'s).
#pragma once

#include <chrono>
#include <cstddef>
#include <initializer_list>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "error.h"
#include "h5_archive.h"
#include "hsnc/simulate.h"
#include "model_reader.h"
#include "output_file.h"

namespace hsnc::cli {

struct AnalysisFlags {
    std::string model;
    ModelOverrides overrides;
    std::string kernels = "auto", cache_dir;
    bool no_cache = false, quiet = false;
};

/// Registers MODEL, --set, --x0, --v0, --kernels, --cache-dir, --no-cache and --quiet on `sub`.
void add_analysis_flags(CLI::App* sub, AnalysisFlags& flags);

/// Registers --section KIND[:NAME], --section-out CSV and --section-plot PNG
/// (output/section.h); `what` ends the --section help ("" or " of the measurement");
/// `stroboscopic`: the help names period[:OMEGA] too (hsnc simulate).
void add_section_flags(CLI::App* sub, std::string& section, std::string& out, std::string& plot,
                       const std::string& what = "", bool stroboscopic = false);

/// --kernels, --cache-dir, --no-cache as the library takes them.
struct AnalysisKernels {
    KernelChoice kernels = KernelChoice::automatic;
    std::string cache_dir;
    bool use_cache = true;
};
/// InputError naming --kernels when its value is not a kernel kind.
AnalysisKernels analysis_kernels(const AnalysisFlags& flags);
/// The same into an analysis's options (PeriodicOptions, LyapunovOptions,
/// ModesOptions: each has kernels, cache_dir and use_cache).
template <class Options>
void set_kernels(const AnalysisFlags& flags, Options& o) {
    const AnalysisKernels k = analysis_kernels(flags);
    o.kernels = k.kernels;
    o.cache_dir = k.cache_dir;
    o.use_cache = k.use_cache;
}

/// The library names its option (OptionError::option()), the command line
/// names the flag: "FLAG: reason" for an option listed in `flags` (pairs of
/// option and flag; "kernels" is --kernels without being listed), else e.what().
InputError option_flag_error(const OptionError& e, std::initializer_list<std::pair<const char*, const char*>> flags);

/// The --h5 archive of a command (null without `target`), its provenance
/// written: the model file's text and name, `overrides` as given, the command line.
std::unique_ptr<H5Archive> open_h5(const OutputTarget* target, const Model& model, const ModelOverrides& overrides);

/// The entry point of libhsnc_h5.so (loaded the first time; RunError when it
/// cannot be, InputError when hsnc was built without HDF5).
H5Open h5_module();
/// check_h5_output(path), and the module loaded: everything --h5 needs, before the run.
OutputTarget check_h5(const std::string& path);

/// The overrides as given on the command line ("--set F=2"), for --h5 files.
std::vector<std::string> overrides_given(const ModelOverrides& overrides);

/// Registers --h5 FILE on `sub`; `tables` says what the file holds (its help).
void add_h5_flag(CLI::App* sub, std::string& path, const std::string& tables);

/// The output paths of one command, each checked when added (check_output:
/// InputError, nothing written), then all together by check().
class AnalysisOutputs {
public:
    /// The target of `path` for `flag`; null when `path` is empty. `png`:
    /// drawn by gnuplot (check() then requires it).
    const OutputTarget* add(const char* flag, const std::string& path, bool png = false);
    /// --h5 FILE (h5_archive.h: a regular file or a new name); null when `path` is empty.
    const OutputTarget* add_h5(const std::string& path);
    /// No two of them one file; gnuplot on PATH when a PNG is asked for.
    void check() const;

private:
    std::vector<std::unique_ptr<OutputTarget>> targets_;
    bool png_ = false;
};

/// The output guard of `hsnc simulate` (simulate_outputs.h: kLargeOutputRows,
/// kLargeOutputBytes) for a CSV of `rows` rows of `columns` numbers: an
/// InputError naming `cause` (the flags that set the rows, "--dt 1e-09") and
/// `what` ("the orbit --out") unless `allowed` (--allow-large-output).
void check_output_size(const std::string& cause, const std::string& what, double rows, std::size_t columns,
                       bool allowed);

/// A long command's progress on stderr (as `hsnc simulate`'s bar and `hsnc
/// sweep`'s lines): on a terminal one line redrawn in place, at most 10 times
/// a second from 0.5 s on, erased at the end; otherwise (a log) a line every
/// 10 s from 10 s on, so that a long run is seen to be alive. Nothing when
/// not enabled (--quiet).
class ProgressLine {
public:
    explicit ProgressLine(bool enabled);
    ~ProgressLine() { clear(); }
    ProgressLine(const ProgressLine&) = delete;
    ProgressLine& operator=(const ProgressLine&) = delete;
    /// True when a line is due now (then call show()).
    bool due();
    /// Seconds since the start.
    double seconds() const;
    void show(const std::string& text);
    /// Erases the terminal line (before other output).
    void clear();

private:
    bool enabled_, terminal_, drawn_ = false;
    double last_ = 0.0;
    std::chrono::steady_clock::time_point start_;
};

/// Text inside a gnuplot string: quotes, backslashes, backquotes and control
/// characters (which gnuplot would interpret) left out.
std::string gnuplot_plain(const std::string& text);

}  // namespace hsnc::cli
