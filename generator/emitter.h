// hsnc -- the C++ emitter: one translation unit per configuration.
//
// The emitted unit includes only "kernel_abi.h", calls only __builtin_ math
// (no <cmath>, so it compiles fast in-process too), folds every parameter as a
// 17-significant-digit constant that round-trips, names quantities after the
// maths (q_1, omega_d_1, ...), computes each per-mode exponential and
// trigonometric factor once, and exports one extern "C" hsnc_kernel object.
// The text is printed from the Derivation's own ordered structures, never from
// GiNaC's term order, so the same model gives the same bytes in every run.
#pragma once

#include <string>
#include <vector>

#include "derivation.h"
#include "double_literal.h"  // format_double, used with the emitters
#include "program.h"

namespace hsnc {

/// C identifier of the kernel object: "hsnc_kernel_<model>_<key>", with every
/// character of the model name outside [A-Za-z0-9_] written as '_'.
std::string kernel_symbol(const Model& model, const Configuration& cfg);

/// The kernel translation unit of derivation `d`: its program
/// (generator/lowering.h) printed as C++.
std::string emit_kernel(const Derivation& d);
/// The same with the program given (lower(d) for the kernel of `d`).
std::string emit_kernel(const Derivation& d, const Program& program);

/// The `extern "C" const hsnc_kernel SYM = {...}` object closing an emitted
/// kernel: the identity fields from `d` (ABI, model, hash, configuration,
/// generator version, sizes, NS::switches), then `rest` -- n_coef and max_step,
/// followed by NS::setup and NS::eval, then any further fields (sweep kernels:
/// n_param, param_names, configure) -- one per line.
std::string emit_kernel_object(const Derivation& d, const std::string& sym, const std::string& ns,
                               const std::vector<std::string>& rest);

/// C++ source of `double hsnc_phase(omega, t0, t0_lo, phase)`: the forcing
/// phase at a segment start, computed as GenericSolver does; sweep kernels
/// with forcing contain it (folded ones call kernels/kernel_abi.h's).
extern const char* const kPhaseFunctionSource;

/// A registry source defining `const AotRegistry& hsnc::<function>()` over the
/// kernel objects named in `symbols` (kernels/aot_registry.h), in that order.
std::string emit_registry(const std::vector<std::string>& symbols, const std::string& function = "aot_registry");


}  // namespace hsnc
