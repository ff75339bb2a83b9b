// Running a model through the library facade (hsnc::simulate) from tests, in
// one of the ways the tests compare: a kernel kind, the reference at 30
// digits or CVODE; every event recorded, no samples.
#pragma once

#include <cmath>
#include <string>

#include "engine_runner.h"
#include "hsnc/simulate.h"
#include "kernel_mode.h"
#include "model.h"

namespace hsnc::testing {

/// A run through hsnc::simulate, its events recorded, no samples.
inline Outcome run_simulate(const Model& model, SimulateOptions o) {
    Recorder rec(model.dof(), model.state_size());
    o.dt = NAN;
    o.samples = false;
    Outcome out;
    out.summary = hsnc::simulate(model, o, rec);
    out.events = rec.events;
    return out;
}

/// The options of one way to run a model: a kernel kind's name ("generic",
/// "interp", "eigen", ...), "mp:30" (the reference at 30 digits) or "cvode"
/// (rtol 1e-12, atol 1e-14).
inline SimulateOptions options_for(const std::string& how) {
    SimulateOptions o;
    if (how == "mp:30")
        o.precision_digits = 30;
    else if (how == "cvode")
        o.method = Method::cvode, o.integrator.rtol = 1e-12, o.integrator.atol = 1e-14;
    else
        o.kernels = kernel_choice_from_name(how);
    return o;
}

}  // namespace hsnc::testing
