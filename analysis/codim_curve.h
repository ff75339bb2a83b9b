// hsnc -- the curve of special periodic orbits (fold, period doubling,
// Neimark-Sacker, grazing) over two parameters: hsnc sweep --continuation
// --track (the method in api/hsnc/sweep.h). Private to the library.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "continuation.h"

namespace hsnc::sweep_detail {

/// The second parameter and the kind of point a curve follows.
struct CurveSpec {
    std::string kind;             ///< fold, period_doubling, neimark_sacker or grazing
    std::string param;            ///< the first parameter's name (messages)
    std::string param2;           ///< the second's
    double start2 = 0, end2 = 0;  ///< q from start2 (where the curve starts) towards end2
    /// The model at (p, q); InputError when it is not valid there.
    std::function<Model(double, double)> model_at;
};

/// Follows the one-parameter branch `b` (at q = start2) to its first point
/// of the kind, then that point over (p, q) from q = start2 towards end2
/// until it leaves [b.start, b.end] x [start2, end2] or after
/// SweepOptions::max_steps points; done(point, seconds) after each.
std::vector<SweepPoint> run_curve(const Branch& b, const CurveSpec& c, const SweepOptions& o,
                                  const std::function<void(const SweepPoint&, double)>& done, bool* cut = nullptr);

}  // namespace hsnc::sweep_detail
