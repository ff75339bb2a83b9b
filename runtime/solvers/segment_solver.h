// hsnc -- the closed-form solution of one configuration, as the engine sees it.
//
// Between two switches the system is linear with constant forces (paper,
// "PWLDFE standard formulation", Eq. 9). A SegmentSolver holds the solution of
// one configuration: `setup` fixes it from the state at the segment start, then
// `eval` gives the exact state and every switch function (switch_function.h,
// in that order) at any later time.
// Three implementations give the same answers to rounding: ahead-of-time
// generated kernels, kernels compiled in-process (JIT), and the generic
// Eigen-based solver.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "configuration.h"
#include "switch_function.h"

namespace hsnc {

struct RestartPlan;  // kernels/program.h

/// Where SegmentSolver::eval writes. Every pointer is required and points to
/// Model::state_size() (x), n_dof (v, a) or n_switch (the rest) doubles.
struct SegmentEval {
    double* x;      ///< positions of all masses (stuck ones at their fixed x), then of
                    ///  every Jenkins slider (model.h Jenkins)
    double* v;      ///< velocities (0 for stuck masses)
    double* a;      ///< accelerations (0 for stuck masses)
    double* g;      ///< switch function values
    double* dg;     ///< their first time derivatives
    double* bound;  ///< B_f >= |g_f''(s)| for every s in [tau, tau + max_step()]
    double* scale;  ///< magnitude of the terms summed into g_f (sum of |terms|):
                    ///  g_f is known to about 1e-16*scale_f, no better
    /// The split bound, written only by a solver whose splits_bound() is true
    /// (n_switch doubles each, or null): g_f = s_f + r_f, where r_f is the
    /// free oscillation of the configuration's fast modes and s_f the rest.
    /// Then |r_f(s)| <= fast_f and |s_f''(s)| <= slow_bound_f for every s in
    /// [tau, tau + max_step()], so that g_f(tau + s) >= slow_f + slow_dg_f s
    /// - slow_bound_f s^2/2 - fast_f: a safe step that a stiff mode of tiny
    /// amplitude does not shorten (its |r''| ~ omega^2 |r| would in `bound`).
    double* slow = nullptr;        ///< s_f(tau) = g_f - r_f
    double* slow_dg = nullptr;     ///< s_f'(tau)
    double* fast = nullptr;        ///< bound of |r_f| over the horizon
    double* slow_bound = nullptr;  ///< bound of |s_f''| over the horizon
};

/// Largest s >= 0 such that h + hd*s - B*s^2/2 > 0 for every smaller s: no
/// function with h(0) = h > 0, h'(0) = hd and |h''| <= B can reach zero
/// before it. Written without cancellation in both signs of hd.
inline double safe_step(double h, double hd, double B) {
    if (!(B > 0)) return hd >= 0 ? std::numeric_limits<double>::infinity() : h / -hd;
    const double root = std::sqrt(hd * hd + 2 * B * h);
    return hd >= 0 ? (hd + root) / B : 2 * h / (root - hd);
}

/// A switch search over a configuration with at least this many switch
/// functions evaluates each function on its own schedule (engine.cpp,
/// EngineOptions::schedule_from): an instant computes the functions whose
/// safe step ends there (SegmentSolver::eval_some), not all of them. Solvers
/// prepare for eval_some() from this many.
inline constexpr std::size_t kScheduleFrom = 16;

class SegmentSolver {
public:
    virtual ~SegmentSolver() = default;

    virtual const Configuration& configuration() const = 0;
    virtual const std::vector<SwitchFunction>& switches() const = 0;

    /// Start a segment at absolute time t0 + t0_lo from the full state (x0, v0
    /// of all masses, x0 followed by the Jenkins sliders' positions; stuck
    /// masses must have v0 = 0). t0_lo is the rounding of
    /// the start instant (|t0_lo| <= ulp(t0)/2; the engine keeps event instants
    /// as t + t_lo): the forcing phase is taken at t0 + t0_lo, so the state and
    /// the forcing refer to one instant. sgn[i] in {-1, 0, +1} is the
    /// direction of motion of each sliding friction mass, which fixes the sign
    /// of its kinetic friction force -mu_k*N_i*sgn[i]; it is 0 for masses that
    /// are stuck or have no friction.
    virtual void setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) = 0;

    /// A segment starting at the representable instant t0 (t0_lo = 0).
    void setup(double t0, const double* x0, const double* v0, const signed char* sgn) {
        setup(t0, 0.0, x0, v0, sgn);
    }

    /// Evaluate at tau = t - t0 >= 0 (time measured from the segment start).
    virtual void eval(double tau, const SegmentEval& out) const = 0;

    /// What the switch search needs at tau: g, dg, bound and scale, each with
    /// the bits eval() gives them; x, v and a are left unspecified (their
    /// buffers may be written or not). The default is eval(); a solver that
    /// can skip the state of masses no switch function reads overrides it.
    virtual void eval_switches(double tau, const SegmentEval& out) const { eval(tau, out); }

    /// The switch functions which[0 .. count) at tau, as eval_switches gives
    /// them (g, dg, bound, scale); the others' outputs are left unspecified.
    /// The default is eval_switches(); the interpreter computes only what the
    /// listed functions read.
    virtual void eval_some(double tau, const std::uint32_t* /*which*/, std::size_t /*count*/,
                           const SegmentEval& out) const {
        eval_switches(tau, out);
    }

    /// Every function's bound at tau, and the g, dg, bound and scale of the
    /// functions which[0 .. count), each with the bits eval() gives it; the
    /// other functions' g, dg and scale are left unspecified. The engine
    /// starts a segment carried over a switch with it (engine.cpp: the
    /// others' values are the event's). The default is eval_switches(); the
    /// interpreter leaves out the states of the masses only g, dg and scale read.
    virtual void eval_start(double tau, const std::uint32_t* /*which*/, std::size_t /*count*/,
                            const SegmentEval& out) const {
        eval_switches(tau, out);
    }

    /// The longest step over which `bound` is valid: +infinity unless the
    /// segment has secular (resonant, growing) terms.
    virtual double max_step() const = 0;

    /// Whether eval, eval_switches and eval_start write the split bound
    /// (SegmentEval::slow, slow_dg, fast, slow_bound) of every function (the
    /// new segment's own, also where eval_start leaves g to the event's),
    /// eval_some that of the listed ones.
    virtual bool splits_bound() const { return false; }

    /// The coefficient block setup writes and eval reads (kernels/program.h:
    /// its layout is the same, bit for bit, for every solver of a program),
    /// which the engine may carry over an event that keeps the configuration
    /// (runtime/solvers/restart.h) instead of calling setup; null (the
    /// default) for a solver whose block is not that layout. Valid until the
    /// solver's next setup.
    virtual double* coefficient_block() { return nullptr; }

    /// The configuration's restart plan when the solver carries one (the
    /// interpreter's, from its program), else null: the engine then asks
    /// EngineOptions::restart_plans.
    virtual const RestartPlan* restart_plan() const { return nullptr; }

    /// The fastest rate (rad/s) of the terms of the motion that, from tau on,
    /// are still larger than tol times the size of the whole motion (after
    /// setup): a time grid of step 2 pi/(16 rate) from tau resolves the
    /// motion to about tol of its size. A mode excited to 1e-9 of the motion
    /// and damped away counts until it has decayed below tol, so a stiff,
    /// damped tail does not set the grid of a whole segment (the sweep's
    /// recorder, analysis/sweep_point.cpp). Negative: not known (the default);
    /// the caller then grids at the highest natural frequency.
    virtual double resolving_rate(double /*tau*/, double /*tol*/) const { return -1.0; }
};

}  // namespace hsnc
