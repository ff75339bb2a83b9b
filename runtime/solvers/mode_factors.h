// hsnc -- the modes' factors e^{-sigma tau}, sin and cos(omega_d tau), four
// lanes at a time (kernel_abi.h hsnc_exp4, hsnc_sincos4), for the
// interpreter's modes and the restart of a carried segment alike.
#pragma once

#include <cstddef>

namespace hsnc {

/// e[i] = e^{xe[i]}, sn[i] = sin(xt[i]), cs[i] = cos(xt[i]) for i < n (n a
/// multiple of 4; e only when `exp`), in AVX2 registers where the processor
/// has them: a lane's bits are its own argument's, whatever the grouping or
/// the clone. The outputs may be the inputs (e = xe, sn = xt).
void mode_factors(const double* xe, const double* xt, double* e, double* sn, double* cs, std::size_t n, bool exp);

}  // namespace hsnc
