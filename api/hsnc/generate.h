// hsnc -- the library facade: the specialised C++ kernels of a model, as
// `hsnc generate MODEL -o DIR` writes them (interface.md section 3), for the
// command line and the Python module alike.
//
//     const hsnc::Model model = hsnc::read_model("models/seed-scenario-1.toml");
//     const hsnc::GeneratedKernels k = hsnc::generate_kernels(model);
//     const std::vector<std::string> files = hsnc::write_kernels(model, k, "out");
//
// Two steps, so that a caller can say which configurations were generated
// (`note`) before anything is written.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "model.h"

namespace hsnc {

struct KernelSet;  // generator/kernel_set.h

/// The kernels of a model, ready to be written.
struct GeneratedKernels {
    GeneratedKernels();
    ~GeneratedKernels();
    GeneratedKernels(GeneratedKernels&&) noexcept;
    GeneratedKernels& operator=(GeneratedKernels&&) noexcept;

    std::size_t kernels() const;  ///< translation units, one per configuration
    /// "" when every configuration was generated, else which were (the
    /// model's default run, the initial configuration and its neighbours).
    const std::string& note() const;

    std::unique_ptr<KernelSet> set;  ///< the sources (private to the library: kernel_set.h)
};

/// Every configuration's kernel while there are at most 64 configurations,
/// else those of the model's default run plus the initial one and its
/// neighbours; sweep kernels when `sweep_parameters` is not empty (the
/// parameters that become run-time arguments, as kept_parameters() in
/// param_emitter.h gives them from "--params NAME,NAME,..." or "all").
/// Throws InputError (a field expression a kernel cannot call).
GeneratedKernels generate_kernels(const Model& model, const std::vector<std::string>& sweep_parameters = {});

/// Writes the kernels into `dir` (which must exist): <model>_<key>.cpp for
/// each configuration, <model>.manifest and registry.cpp, each file only when
/// its text changed (build timestamps stay). Returns the names written, in
/// that order. Throws RunError when a file cannot be written.
std::vector<std::string> write_kernels(const Model& model, const GeneratedKernels& kernels, const std::string& dir);

}  // namespace hsnc
