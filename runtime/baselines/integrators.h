// hsnc -- numerical-integration baselines in the same tool (issue: users
// compare hsnc with them on their own models). They share the model, the
// transition rules (transitions.h) and the output code with the engine.
//
//  ab4  : fixed-step Adams-Bashforth 4 with an RK4 start, the paper's baseline.
//         Friction is -mu_k*N*sign(v); contacts act while G >= 0, read from the
//         state at every right-hand-side evaluation. The stick rule is applied
//         at step ends: a sliding mass whose velocity changed sign (or reached 0)
//         in a step sticks if |A_i| < mu_s*N_i (v_i = 0, held), else slides on
//         along A_i; a stuck mass releases at the first step end with
//         |A_i| > mu_s*N_i. After a stick or release the history restarts with
//         RK4. Events are reported at step ends, so their times are only as
//         good as the step.
//  rk45 : adaptive Dormand-Prince 5(4) inside each configuration (smooth
//         right-hand side), switch functions watched by sign changes between
//         accepted steps, located by bisection on cubic Hermite interpolation,
//         then the same transitions as hsnc. Like CVODE, it sees only sign
//         changes: two roots inside one step are missed.
//  cvode: SUNDIALS CVODE, Adams (orders 1-12) with CVODE's root finding on the
//         same switch functions and the same transitions as rk45 and hsnc; the
//         restart after a switch is one-sided as in rk45 (integrators.cpp).
//         --rtol/--atol as rk45. SUNDIALS is linked statically (start-up).
//  rk45 and cvode: while a mass is stuck under harmonic forcing, the step is at
//         most 1/32 of the shortest forcing period (the state of a stuck mass
//         does not follow the forcing that releases it; integrators.cpp).
#pragma once

#include <string>

#include "engine_options.h"
#include "model.h"
#include "observer.h"
#include "run_summary.h"

namespace hsnc {

enum class Method { hsnc, ab4, rk45, cvode };

/// "hsnc", "ab4", "rk45", "cvode"; InputError otherwise.
Method parse_method(const std::string& name);

struct IntegratorOptions {
    double h = 0.0;       ///< ab4 step (required for ab4)
    double rtol = 1e-10;  ///< rk45 and cvode tolerances
    double atol = 1e-12;
    bool cvode_newton = false;  ///< cvode corrector: Newton (dense DQ Jacobian) instead of fixed-point
};

/// InputError when the options do not fit the method (e.g. ab4 without --h).
void validate(Method method, const IntegratorOptions& options);
/// The same, and for ab4 the step against the run from t0 to t_end: at most
/// the run, at most kMaxSteps steps, and large enough that t + h != t.
void validate(Method method, const IntegratorOptions& options, double t0, double t_end);
inline constexpr double kMaxSteps = 1e12;

/// Run a baseline from the model's initial state; reports through `observer`
/// like Engine::run (samples at the same times, events as described above).
RunSummary integrate(const Model& model, Method method, const IntegratorOptions& options,
                     const EngineOptions& engine_options, Observer& observer);

}  // namespace hsnc
