// hsnc -- the Lyapunov spectrum of the response (interface.md section 6,
// `hsnc lyapunov`), without the command line.
//
//     const hsnc::Model model = hsnc::read_model("models/seed-scenario-2.toml");
//     hsnc::LyapunovOptions options;
//     options.t_end = 300.0;
//     const hsnc::LyapunovResult r = hsnc::lyapunov(model, options);
//     // r.exponents: 2n exponents in 1/s, largest first
//
// The standard QR method (Benettin et al. 1980, Shimada and Nagashima 1979)
// on the exact tangent dynamics (analysis/tangent.h): an orthonormal basis Q
// of the 2n-dimensional tangent space is carried through every segment
// (Q <- Phi(tau) Q) and switch (Q <- S Q), re-orthonormalised by a QR
// factorisation at the end of every segment, and the logarithms of the
// diagonal of R are summed: lambda_k = sum log R_kk / (t - t_start).
// A stick collapses a direction (the stuck mass's velocity perturbation is
// gone): while m masses are stuck the tangent image has rank 2n - m at most,
// and the directions beyond the rank the basis has reached are dropped for
// good, their exponents -infinity (the smallest ones).
#pragma once

#include <cstddef>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "engine.h"
#include "model.h"
#include "simulate.h"

namespace hsnc {

struct LyapunovOptions {
    /// Length of the measurement, seconds (required: NaN is an OptionError).
    double t_end = std::numeric_limits<double>::quiet_NaN();
    /// Run this long from the initial state first; the measurement covers
    /// [t0 + transient, t0 + transient + t_end].
    double transient = 0.0;
    /// Spacing of the convergence rows (on_row); NaN: the period of the
    /// slowest forcing harmonic, or 1 s without forcing.
    double row_interval = std::numeric_limits<double>::quiet_NaN();
    /// Where the segment solvers come from (automatic, aot or generic; not jit).
    KernelChoice kernels = KernelChoice::automatic;
};

struct LyapunovResult {
    RunStatus status = RunStatus::ok;  ///< of the run (anything but ok: the exponents are not valid)
    std::string message;
    double t_start = 0.0;  ///< start of the measurement
    double t = 0.0;        ///< end of the measurement (time reached)
    /// 2n exponents, 1/s, largest first; -infinity for collapsed directions.
    std::vector<double> exponents;
    double sum = 0.0;            ///< their sum (-infinity when a direction collapsed)
    std::size_t collapsed = 0;   ///< directions collapsed by sticks
    std::size_t events = 0;      ///< switch events over the measurement
    std::size_t grazing = 0;     ///< switches without a derivative (skipped: the exponents are doubtful)
};

/// The spectrum (see the file comment). `on_row(t, exponents)` (may be empty)
/// receives the running estimate, largest first, every row_interval from the
/// measurement's start (not at the start itself) and at its end. `observer`
/// (may be null) receives the run's switch events. Throws OptionError for
/// options that do not fit, RunError when a run cannot start.
LyapunovResult lyapunov(const Model& model, const LyapunovOptions& options,
                        const std::function<void(double, const std::vector<double>&)>& on_row = {},
                        Observer* observer = nullptr);

}  // namespace hsnc
