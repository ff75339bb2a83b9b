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
/// `neutral_a`, `neutral_b`: each orbit's multipliers at +1 of a family of
/// orbits (stuck sliders or masses, hsnc/periodic.h): that many multipliers
/// closest to +1 count as just inside the unit circle (a family's +1 wobbles
/// about 1 by rounding: no fold; a multiplier leaving a family's +1 outward is one).
std::string bifurcations_between(const std::vector<std::complex<double>>& a, const std::vector<std::complex<double>>& b,
                                 std::size_t neutral_a = 0, std::size_t neutral_b = 0);

}  // namespace hsnc::sweep_detail
