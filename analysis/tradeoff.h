// hsnc -- the work-precision study (`hsnc tradeoff`): wall time and error
// against a reference of hsnc and the numerical baselines on one model.
//
//     const hsnc::Model model = hsnc::read_model("models/coulomb-1dof.toml");
//     hsnc::TradeoffOptions options;
//     options.t_end = 4.0;
//     const hsnc::RecordedRun reference = hsnc::compute_reference(model, options, hsnc::reference_runner(40));
//     const hsnc::TradeoffResult study = hsnc::tradeoff(model, options, reference);
//
// Methods and what is swept (tradeoff_settings; adding a method is one line in
// tradeoff.cpp):
//  hsnc  : no knob trades accuracy for speed -- every switch is refined to
//          machine precision and segments are closed forms -- so one point per
//          kernel kind: `auto` (KernelChoice::automatic, as hsnc::simulate and
//          `hsnc simulate` mean it: ahead-of-time kernels, the generic solver
//          for a configuration without one), when the model has AOT kernels,
//          and `generic`.
//  ab4   : the fixed step h = 10^(-3 - k/2), 1e-3 .. 1e-6; a step whose run is
//          predicted (time proportional to 1/h) to exceed the budget is skipped.
//  rk45 (and any adaptive method: cvode) : rtol = 10^-k, 1e-4 .. 1e-13, with
//          atol = 1e-2*rtol; the sweep stops after a run that exceeds the budget.
// Every run goes through hsnc::simulate (api/hsnc/simulate.h). Wall time: of
// the run alone (solver setup and recording the samples included, model
// reading not); the median of as many runs as fit in about 0.2 s (an odd
// number, at most 51; one run when the first takes over 0.1 s), or `runs`.
// Errors: work_precision.h.
#pragma once

#include <cstddef>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "engine_options.h"
#include "hsnc/simulate.h"
#include "model.h"
#include "work_precision.h"

namespace hsnc {

/// How a method's setting is swept.
enum class Sweep {
    kernels,    ///< exact method: one point per kernel kind
    step,       ///< fixed-step method: h
    tolerance,  ///< adaptive method: rtol (atol = 1e-2*rtol)
};

/// One setting of one method.
struct TradeoffSetting {
    Method method = Method::hsnc;
    Sweep sweep = Sweep::kernels;
    std::string label;  ///< "kernels=auto", "h=1e-05", "rtol=1e-08 atol=1e-10"
    double parameter = std::numeric_limits<double>::quiet_NaN();  ///< h or rtol; NaN for hsnc
    KernelChoice kernels = KernelChoice::automatic;                ///< method hsnc
    IntegratorOptions integrator;                                  ///< the baselines
};

struct TradeoffOptions {
    /// End time; NaN: the model's [simulate].t_end.
    double t_end = std::numeric_limits<double>::quiet_NaN();
    /// Positions are compared at t0, t0 + dt, ... and t_end; NaN: (t_end - t0) / 1000.
    double dt = std::numeric_limits<double>::quiet_NaN();
    /// The methods, in this order; empty: tradeoff_methods().
    std::vector<Method> methods;
    bool quick = false;    ///< fewer settings per method (about half)
    double budget = 20.0;  ///< seconds: skip a setting predicted to take longer; stop an adaptive sweep after one did
    int runs = 0;          ///< timed runs per setting (0..1001); 0: as many as fit in about 0.2 s
};

/// One measured setting: a row of the study.
struct TradeoffRow {
    TradeoffSetting setting;
    std::string status;  ///< run_status_name of the (first) run
    SolverKind solver = SolverKind::generic;  ///< what hsnc::simulate ran it with
    double wall = std::numeric_limits<double>::quiet_NaN();  ///< median wall time, seconds
    int runs = 0;
    RunErrors errors;
    double time_ratio_to_hsnc = std::numeric_limits<double>::quiet_NaN();  ///< wall / the base row's wall
};

struct TradeoffResult {
    std::vector<Method> methods;   ///< the methods measured, in order
    std::vector<TradeoffRow> rows; ///< in the order measured (methods, then settings)
    /// The row the time ratios refer to: hsnc's first setting that ran ok; -1: none.
    int base = -1;
    /// max |x_ref| over the compared sample times (the same for every row); NaN: none compared.
    double response_magnitude = std::numeric_limits<double>::quiet_NaN();
};

/// What the study tells while it runs; each may be empty.
struct TradeoffProgress {
    std::function<void(const TradeoffSetting&)> running;                         ///< before a setting runs
    std::function<void(const TradeoffRow&)> measured;                            ///< after it ran
    std::function<void(const TradeoffSetting&, const std::string& why)> skipped;  ///< a setting over the budget
};

/// The methods this build has, in the study's order (hsnc, ab4, rk45, cvode).
std::vector<Method> tradeoff_methods();
/// The settings of `method` on `model` (hsnc: kernels=auto only when the model has AOT kernels).
std::vector<TradeoffSetting> tradeoff_settings(const Model& model, Method method, bool quick);

/// OptionError when `options` do not fit `model`: option() is the field
/// ("t_end", "dt", "methods", "budget", "runs"). Nothing has run.
void check_tradeoff_options(const Model& model, const TradeoffOptions& options);
/// The runs' end time and sample grid (checked as check_tradeoff_options does).
EngineOptions tradeoff_engine_options(const Model& model, const TradeoffOptions& options);

/// The reference computed in process by `runner` on the study's sample grid;
/// RunError when it does not reach the end time (status not ok).
RecordedRun compute_reference(const Model& model, const TradeoffOptions& options, const ReferenceRunner& runner);
/// Fits `reference` (read from files, say) to the study: drops its events
/// after the end time. "" when it fits, else what is wrong: "ends at t = ...,
/// before the end time ...", or "has N of the M sample times t0 + k*dt (dt =
/// ...) and t_end" (positions are compared there and never interpolated).
std::string fit_reference(const Model& model, const TradeoffOptions& options, RecordedRun& reference);

/// Runs the study against `reference` (which must fit: InputError otherwise).
/// OptionError as check_tradeoff_options; RunError from a run that fails.
TradeoffResult tradeoff(const Model& model, const TradeoffOptions& options, const RecordedRun& reference,
                        const TradeoffProgress& progress = {});

/// The cheapest row of `method` that ran ok, did not diverge and reached a
/// relative position error <= level; null when none did.
const TradeoffRow* cheapest_reaching(const TradeoffResult& result, Method method, double level);

}  // namespace hsnc
