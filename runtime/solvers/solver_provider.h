// hsnc -- SolverProvider: where the engine gets the segment solver of each
// configuration it enters (kernel_mode.h: the ahead-of-time and generic
// providers; runtime/jit/: the JIT's and the cache's).
#pragma once

#include <string>

#include "configuration.h"
#include "segment_solver.h"

namespace hsnc {

/// Gives the segment solver of a configuration (ahead-of-time kernel, JIT
/// kernel or generic), creating it the first time it is asked for.
class SolverProvider {
public:
    virtual ~SolverProvider() = default;
    virtual SegmentSolver& solver(const Configuration& cfg) = 0;
    /// One line for the run statistics ("generic solver: 5 configurations").
    virtual std::string describe() const { return ""; }
};

}  // namespace hsnc
