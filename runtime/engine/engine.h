// hsnc -- the HSNC stepping engine (paper, Fig. 3): from an initial state,
// step from switch to switch with the closed-form segment solutions, find every
// switch, and apply it by the physics of interface.md section 2.
//
// Switch detection (guaranteed, see docs/architecture.md "How switches are found"):
// every switch function g_f is watched on its "safe side" h_f = side_f*g_f > 0,
// where side_f follows from the configuration (a closed contact watches G > 0,
// an open one -G > 0, a sliding mass sgn*v > 0, a stuck mass mu_s*N -+ A > 0),
// never from a re-evaluation that rounding could flip. At each evaluation point
// the solver returns B_f >= |g_f''| over the step, so
//     h_f(tau + s) >= h_f + h_f' s - B_f s^2 / 2,
// and the step is the smallest positive root of that bound over all f: no
// function can change sign inside a step, however close two roots are. Near a
// root this is a Newton step taken from the safe side (quadratic convergence).
// A contact or release function switches when it is certainly negative
// (h < -noise, noise = 16*eps*(scale + |g'|*|t|), at least the level it had at
// the last event); it is then moved back to its zero by one
// Newton step. A function that only touches zero within rounding changes
// nothing. A sliding velocity that reaches zero, crossing or touching, is a stop
// (h <= noise), and the stick rule decides; one still falling inside its
// noise stops only where the bound says it reaches zero (an overdamped creep
// into equilibrium never does: transition_rules.h stops_here).
#pragma once

#include "engine_options.h"
#include "model.h"
#include "observer.h"
#include "run_summary.h"
#include "solver_provider.h"

namespace hsnc {

/// Keeps references to `model` and `provider`: both must outlive it.
class Engine {
public:
    Engine(const Model& model, SolverProvider& provider);
    /// A temporary Model would dangle (`Engine e(read_model(path), p)`): refused at compile time.
    Engine(const Model&& model, SolverProvider& provider) = delete;

    /// Run from the model's initial state (x0, v0 at t0) to options.t_end.
    /// A model with [[load_step]]s is refused (refuse_load_steps): its pieces run one by one.
    RunSummary run(const EngineOptions& options, Observer& observer);

private:
    const Model& model_;
    SolverProvider& provider_;
};

/// InputError when the model has [[load_step]]s (Model::load_steps): `who`
/// (an engine, a baseline, an analysis) runs one constant load, and only
/// hsnc::simulate runs a model whose load changes in time, piece by piece.
void refuse_load_steps(const Model& model, const std::string& who);

/// InputError when a contact is a rigid stop with restitution (Contact::rigid):
/// `who` (nonlinear modes, continuation) does not take impacts yet.
void refuse_impacts(const Model& model, const std::string& who);

}  // namespace hsnc
