// hsnc -- the trajectory's sample times (interface.md, `--dt`), the one rule
// every method and every check of a trajectory uses: t_k = t0 + k*dt, each
// computed from k (never accumulated, so no drift over millions of samples),
// while t_k < t_end - 1e-9 dt; the next sample is t_end itself, the last one
// (a t_k within 1e-9 dt of t_end is taken for it, so rounding in k*dt never
// gives a second row a hair before t_end).
#pragma once

#include <cmath>
#include <cstddef>

#include "engine_options.h"

namespace hsnc {

class SampleGrid {
public:
    /// Samples from t0 to t_end every dt; dt <= 0: t0 and t_end only.
    SampleGrid(double t0, double t_end, double dt) : t0_(t0), t_end_(t_end), dt_(dt > 0 ? dt : t_end - t0) {}

    /// Sample time k (k = 0: t0); t_end from the last one on.
    double time(std::size_t k) const {
        const double tk = t0_ + static_cast<double>(k) * dt_;
        return tk < t_end_ - 1e-9 * dt_ ? tk : t_end_;
    }
    /// True when sample k is the last one (t_end).
    bool last(std::size_t k) const { return !(time(k) < t_end_); }
    /// The number of samples (the last one included), as a double: it may exceed any integer type's range
    /// for a grid nobody writes out (a size check refuses it first).
    double count() const {
        if (!(t_end_ > t0_) || !(dt_ > 0)) return 1.0;
        // The first k with t0 + k dt >= t_end - 1e-9 dt, from an estimate checked against time() itself.
        double k = std::ceil((t_end_ - t0_) / dt_ - 1e-9);
        if (k < 1.0) k = 1.0;
        if (k < 9e15) {  // exactly representable: settle the rounding of the estimate
            while (k > 1.0 && last(static_cast<std::size_t>(k) - 1)) k -= 1.0;
            while (!last(static_cast<std::size_t>(k))) k += 1.0;
        }
        return k + 1.0;
    }
    /// The first sample after t (time(k) > t): where the piece of a run that
    /// starts at t takes up the grid (api/simulate.cpp, [[load_step]]).
    std::size_t first_after(double t) const {
        double k = std::floor((t - t0_) / dt_);
        if (!(k > 0.0)) k = 0.0;
        if (k > 9e15) k = 9e15;
        auto kk = static_cast<std::size_t>(k);
        while (kk > 0 && time(kk - 1) > t) --kk;
        while (!(time(kk) > t) && !last(kk)) ++kk;
        return kk;
    }
    /// The spacing without --dt: the run in kDefaultIntervals intervals.
    static constexpr int kDefaultIntervals = 1000;
    static double default_dt(double t0, double t_end) { return (t_end - t0) / kDefaultIntervals; }

    double t0() const { return t0_; }
    double t_end() const { return t_end_; }
    double dt() const { return dt_; }

private:
    double t0_, t_end_, dt_;
};

/// The sample grid of a run from t0: its own, or the longer run's it is a
/// piece of (EngineOptions::grid_t0, grid_t_end).
inline SampleGrid sample_grid(const EngineOptions& o, double t0) {
    return std::isnan(o.grid_t0) ? SampleGrid(t0, o.t_end, o.dt) : SampleGrid(o.grid_t0, o.grid_t_end, o.dt);
}

}  // namespace hsnc
