// hsnc -- the set of kernels generated for one model: which configurations,
// the emitted sources and their registry (used by `hsnc generate` and by the
// build's generator tool hsnc_gen).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "configuration.h"
#include "model.h"

namespace hsnc {

/// Most configurations for which every one is generated; beyond it only those
/// listed in the model's manifest are (see configurations_to_generate).
inline constexpr std::size_t kMaxGeneratedConfigurations = 64;
/// Most configurations in a manifest (the visited ones always are; initial
/// neighbours fill up to this).
inline constexpr std::size_t kMaxManifestConfigurations = 128;

struct GeneratedFile {
    std::string name;  ///< file name, no directory
    std::string text;
};

struct KernelSet {
    std::vector<GeneratedFile> kernels;  ///< one per configuration
    std::vector<std::string> symbols;    ///< kernel object names, same order
    std::string note;                    ///< "" or why not every configuration was generated
    std::string manifest;                ///< <model>.manifest: the configurations, one spec per line
};

/// The configuration the model starts in (runtime/engine/transitions.h
/// entered_configuration at t0, x0, v0: the stick rule decides by A_i).
Configuration initial_configuration(const Model& model);

/// All configurations when there are at most kMaxGeneratedConfigurations;
/// else every configuration the model's default run visits (the engine with
/// the Eigen solver from t0 to [simulate].t_end), plus the initial one and
/// its single-switch neighbours while fewer than kMaxManifestConfigurations.
/// Sorted (Configuration::operator<). `note` says which.
std::vector<Configuration> configurations_to_generate(const Model& model, std::string* note);

/// The manifest of a kernel set: a comment header saying how the list was
/// made (`note`, or "all N configurations"), then one configuration spec per
/// line, sorted.
std::string manifest_text(const Model& model, const std::vector<Configuration>& configurations, const std::string& note);

/// The kernels of `model`: folded (emitter.h) when `kept` is empty, else
/// sweep kernels keeping those parameters as run-time arguments
/// (param_emitter.h; `kept` as kept_parameters() returns it). The manifest
/// then says so in a comment line.
KernelSet generate_kernel_set(const Model& model, const std::vector<std::string>& kept = {});

/// All kernels of a set in one translation unit (the AOT build compiles one
/// file per model): the kernel sources one after the other.
std::string combined_source(const KernelSet& set);

/// Write `text` to dir/name unless the file already holds exactly it (keeps
/// build timestamps still). Throws RunError when the file cannot be written.
void write_if_changed(const std::string& dir, const std::string& name, const std::string& text);

}  // namespace hsnc
