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

/// Most configurations generated for one model; beyond it only those near the
/// initial configuration are (see configurations_to_generate).
inline constexpr std::size_t kMaxGeneratedConfigurations = 64;

struct GeneratedFile {
    std::string name;  ///< file name, no directory
    std::string text;
};

struct KernelSet {
    std::vector<GeneratedFile> kernels;  ///< one per configuration
    std::vector<std::string> symbols;    ///< kernel object names, same order
    std::string note;                    ///< "" or why not every configuration was generated
};

/// The configuration the model starts in: contacts closed where G(x0) > 0 (or
/// G = 0 and rising), friction masses with v0 = 0 stuck.
Configuration initial_configuration(const Model& model);

/// All configurations when there are at most kMaxGeneratedConfigurations;
/// else those reached from the initial one by flipping one contact or one
/// friction mass at a time (breadth first), up to that many. `note` says which.
std::vector<Configuration> configurations_to_generate(const Model& model, std::string* note);

KernelSet generate_kernel_set(const Model& model);

/// All kernels of a set in one translation unit (the AOT build compiles one
/// file per model): the kernel sources one after the other.
std::string combined_source(const KernelSet& set);

/// Write `text` to dir/name unless the file already holds exactly it (keeps
/// build timestamps still). Throws RunError when the file cannot be written.
void write_if_changed(const std::string& dir, const std::string& name, const std::string& text);

}  // namespace hsnc
