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
    /// Where the segment solvers come from, as for hsnc::simulate: automatic,
    /// aot, generic or jit (the tangent dynamics do not depend on it).
    KernelChoice kernels = KernelChoice::automatic;
    /// KernelChoice::jit: directory of the persistent kernel cache ("": the
    /// default, as SimulateOptions::cache_dir), and whether to use one.
    std::string cache_dir;
    bool use_cache = true;
    /// Called now and then from the calling thread with the time reached
    /// (t0 to t0 + transient + t_end; after every segment, and at least every
    /// few hundred switches), for a progress report or a cancel check; return
    /// false to stop: the result's status is then RunStatus::stopped. May be empty.
    std::function<bool(double)> progress;
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
    /// Grazing switch instants over the measurement: a contact closing or
    /// opening at a turning point of its gap, |G'| Omega / |G''| <= 1e-4
    /// (Omega the largest natural or forcing frequency; analysis/tangent.h),
    /// or a switch whose saltation matrix does not exist (dh/dt = 0:
    /// `singular`, skipped). The flow is not
    /// smooth there: exponents of motion that grazes are not reliable.
    std::size_t grazing = 0;
    std::size_t singular = 0;    ///< of them, without a saltation matrix
};

/// The spacing of the convergence rows `options` give: row_interval, or its
/// default (the period of the slowest forcing harmonic, 1 s without forcing).
double lyapunov_row_interval(const Model& model, const LyapunovOptions& options);

/// The spectrum (see the file comment). `on_row(t, exponents)` (may be empty)
/// receives the running estimate, largest first, every row_interval from the
/// measurement's start (not at the start itself) and at its end. `observer`
/// (may be null) receives the run's switch events. Throws OptionError for
/// options that do not fit, RunError when a run cannot start.
LyapunovResult lyapunov(const Model& model, const LyapunovOptions& options,
                        const std::function<void(double, const std::vector<double>&)>& on_row = {},
                        Observer* observer = nullptr);

}  // namespace hsnc
