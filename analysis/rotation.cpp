// hsnc -- the rotation number of a stroboscopic section (api/hsnc/periodic.h
// rotation_number; interface.md, `--section period`).
#include <cmath>
#include <vector>

#include "hsnc/periodic.h"

namespace hsnc {
namespace {

// The weighted Birkhoff average, in turns, of turns[lo, hi): each the
// step's angle about the centre, clockwise, in [0, 2 pi).
double weighted_turns(const std::vector<double>& turns, std::size_t lo, std::size_t hi) {
    const double steps = static_cast<double>(hi - lo);
    double sum = 0.0, weights = 0.0;
    for (std::size_t k = lo; k < hi; ++k) {
        const double s = static_cast<double>(k - lo + 1) / (steps + 1.0);  // in (0, 1)
        const double w = std::exp(-1.0 / (s * (1.0 - s)));
        sum += w * turns[k];
        weights += w;
    }
    return sum / weights / (2 * M_PI);
}

}  // namespace

RotationNumber rotation_number(const double* x, const double* v, std::size_t n, std::size_t stride) {
    RotationNumber r;
    if (n < 8 || stride == 0) return r;
    // About the centroid, each coordinate in units of its own spread (any point
    // inside the curve gives the same rotation number; the scaling keeps the
    // angles well conditioned whatever x's and v's units).
    double cx = 0.0, cv = 0.0;
    for (std::size_t k = 0; k < n; ++k) cx += x[k * stride], cv += v[k * stride];
    cx /= static_cast<double>(n), cv /= static_cast<double>(n);
    double sx = 0.0, sv = 0.0, ax = 0.0, av = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
        sx = std::fmax(sx, std::fabs(x[k * stride] - cx)), sv = std::fmax(sv, std::fabs(v[k * stride] - cv));
        ax = std::fmax(ax, std::fabs(x[k * stride])), av = std::fmax(av, std::fabs(v[k * stride]));
    }
    // x or v the same in every point but for rounding: a fixed point of the
    // section (a periodic orbit of its period), or a dof the motion leaves still.
    if (!(sx > 1e-10 * ax) || !(sv > 1e-10 * av) || !std::isfinite(sx + sv)) return r;
    // turns[k]: the step from point k to point k + 1.
    const auto angle = [&](std::size_t k) { return std::atan2(-(v[k * stride] - cv) / sv, (x[k * stride] - cx) / sx); };
    std::vector<double> turns(n - 1);
    double before = angle(0);
    for (std::size_t k = 0; k + 1 < n; ++k) {
        const double now = angle(k + 1);
        double turn = now - before;
        if (turn < 0.0) turn += 2 * M_PI;
        if (turn >= 2 * M_PI) turn -= 2 * M_PI;
        turns[k] = turn;
        before = now;
    }
    r.value = weighted_turns(turns, 0, n - 1);
    // The halves: points [0, n/2) and [n/2, n).
    const double first = weighted_turns(turns, 0, n / 2 - 1);
    const double second = weighted_turns(turns, n / 2, n - 1);
    r.error = std::fabs(first - second);
    if (r.value >= 1.0) r.value -= 1.0;
    return r;
}

}  // namespace hsnc
