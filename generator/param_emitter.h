// hsnc -- sweep kernels: emitted C++ whose chosen model parameters are
// run-time arguments (`hsnc generate MODEL -o DIR --params k1,m2`).
//
// A folded kernel (emitter.h) bakes every number of the configuration into
// the code, including its modes. A sweep kernel keeps the named parameters as
// inputs of `configure(coef, params, &max_step)` (kernels/kernel_abi.h):
//   - every parameter computed from a kept one (k2 = "2*k1" in the file) and
//     every model field written with them (m = "m1", mu_s = "1.25*mu_k") is
//     emitted as that expression, so the file's relations hold for every value;
//     all other parameters and fields stay folded 17-digit constants;
//   - configure assembles M, K(cfg), C = alpha M + beta K(cfg), the constant
//     forces, runs a fixed-size cyclic Jacobi eigen-solver on
//     M^-1/2 K_FF M^-1/2 (no allocation, no exceptions, __builtin_ math only),
//     decides each mode's regime numerically with the folded kernels' stable
//     forms (undamped, under-, critically, over-damped, rigid, rigid damped;
//     the resonance-stable form of an undamped mode forced within 1% of its
//     frequency), and the forcing particular solutions and switch-bound
//     coefficients, into the first part of the coefficient block;
//   - setup and eval read that state and compute what the folded kernels do,
//     with the same formulas and the same term order, in loops.
// Fixed at generation (a configure that would change them is rejected):
// the configuration, its switch functions, which springs and contacts have
// k > 0 (so the rigid-body modes), which masses have friction.
#pragma once

#include <string>
#include <vector>

#include "derivation.h"

namespace hsnc {

/// The kept parameters of `--params LIST`, in the order LIST gives them (the
/// order configure() takes them in): LIST is "all" (model parameter order) or
/// names separated by commas. Throws InputError naming the flag on
/// an empty list, an unknown or repeated name, or a model without source
/// expressions.
std::vector<std::string> kept_parameters(const Model& model, const std::string& list);

/// C identifier of a sweep kernel object: "hsnc_sweep_<model>_<key>".
std::string sweep_kernel_symbol(const Model& model, const Configuration& cfg);

/// The sweep-kernel translation unit of derivation `d` with the parameters
/// `kept` (as kept_parameters returns them) as run-time arguments. Throws
/// InputError when a field expression uses a function a kernel cannot call.
std::string emit_sweep_kernel(const Derivation& d, const std::vector<std::string>& kept);

}  // namespace hsnc
