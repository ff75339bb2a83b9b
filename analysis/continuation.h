// hsnc -- pseudo-arclength continuation of periodic orbits over a parameter
// (hsnc sweep --continuation; the method in api/hsnc/sweep.h). Private to
// the library.
#pragma once

#include <complex>
#include <functional>
#include <string>
#include <vector>

#include "hsnc/sweep.h"
#include "model.h"

namespace hsnc::sweep_detail {

/// One branch to follow.
struct Branch {
    /// The model with the parameter at a value; InputError when it is not
    /// valid there.
    std::function<Model(double)> model_at;
    /// The model at `start` (its initial state starts the transient).
    const Model* start_model = nullptr;
    double start = 0, end = 0;  ///< the parameter runs from start towards end
    double value2 = 0;          ///< the second parameter (NaN without): SweepPoint::value2
    std::string param;          ///< its name, for messages
    std::string where;          ///< the rest of a point's name (", beta = 0.3 (up)")
};

/// Follows the branch; calls `done(point, seconds)` after each point (in
/// order). Returns the points (see api/hsnc/sweep.h for what they hold).
/// SweepOptions::stop ends it after the point under way, `*cut` (when given) then true.
std::vector<SweepPoint> run_continuation(const Branch& branch, const SweepOptions& options,
                                         const std::function<void(const SweepPoint&, double)>& done,
                                         bool* cut = nullptr);

/// The bifurcations (fold, period_doubling, neimark_sacker, joined by '+')
/// crossed between orbits with multipliers `a` and `b` ("" for none).
std::string bifurcations_between(const std::vector<std::complex<double>>& a,
                                 const std::vector<std::complex<double>>& b);

}  // namespace hsnc::sweep_detail
