// hsnc -- the segment solvers of the exact method for a KernelChoice, picked
// as hsnc::simulate picks them: shared with the analyses (analysis/flow.h),
// so that periodic orbits and Lyapunov exponents run on whichever kernel kind
// the facade selects (ahead-of-time, JIT-compiled with the persistent cache,
// generic). Private to the library (not installed).
#pragma once

#include <memory>

#include "hsnc/simulate.h"
#include "solver_provider.h"

namespace hsnc::api {

/// The provider for options.kernels (with options.cache_dir, use_cache,
/// cache_max_bytes and warn for KernelChoice::jit); `model` must outlive it.
/// Sets *kind (may be null) to what computes the run. Checks nothing of the
/// options: check_simulate_options first (KernelChoice::aot for a model
/// without ahead-of-time kernels fails at its first configuration). Throws RunError
/// (api::JitUnavailable) when the JIT is asked for and cannot be loaded;
/// messages start with `function` ("hsnc::periodic").
std::unique_ptr<SolverProvider> make_provider(const Model& model, const SimulateOptions& options, SolverKind* kind,
                                              const char* function);

}  // namespace hsnc::api
