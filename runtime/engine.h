// hsnc -- the HSNC stepping engine (paper, Fig. 3): from an initial state,
// step from switch to switch with the closed-form segment solutions, find every
// switch, and apply it by the physics of interface.md section 2.
//
// Switch detection (guaranteed, see README "How switches are found"):
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
// (h <= noise), and the stick rule decides.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "configuration.h"
#include "model.h"
#include "segment.h"

namespace hsnc {

enum class EventKind { contact_close, contact_open, stick, release, reversal };

/// The `kind` column of the events CSV.
const char* event_kind_name(EventKind kind);

/// One closed-form segment of a run, reported when it ends (Observer::on_segment):
/// the motion from the instant t + t_lo over tau seconds in configuration cfg
/// with friction directions sgn, from the state (x, v). The pointers are valid
/// during the call only.
struct SegmentRecord {
    double t = 0.0, t_lo = 0.0;  ///< start instant (t_lo: its rounding, as SegmentSolver::setup)
    double tau = 0.0;            ///< duration
    const Configuration* cfg = nullptr;
    const signed char* sgn = nullptr;  ///< n entries: direction of each sliding friction mass, else 0
    const double* x = nullptr;   ///< state at the segment start
    const double* v = nullptr;
};

/// One switch instant (Observer::on_switch), after the transitions of
/// interface.md section 2 are applied: the functions the search found
/// switching, the configuration before and after (with the friction
/// directions), the state at the instant (velocities of stopped masses 0).
struct SwitchRecord {
    double t = 0.0, t_lo = 0.0;
    const std::vector<SwitchFunction>* switched = nullptr;
    const Configuration* before = nullptr;
    const signed char* sgn_before = nullptr;
    const Configuration* after = nullptr;
    const signed char* sgn_after = nullptr;
    const double* x = nullptr;
    const double* v = nullptr;
};

/// Where a run reports what it produces. x and v hold all masses.
class Observer {
public:
    virtual ~Observer() = default;
    virtual void on_sample(double t, const double* x, const double* v) = 0;
    virtual void on_event(double t, EventKind kind, int element, const double* x, const double* v) = 0;
    /// Called now and then with the current time; return false to stop.
    virtual bool on_progress(double /*t*/) { return true; }
    /// True when the run should report every segment and switch instant
    /// (on_segment, on_switch: the tangent dynamics of analysis/ use them).
    /// Asked once at the start of Engine::run; false costs the run nothing.
    virtual bool wants_segments() const { return false; }
    virtual void on_segment(const SegmentRecord& /*segment*/) {}
    virtual void on_switch(const SwitchRecord& /*instant*/) {}
};

/// Gives the segment solver of a configuration (ahead-of-time kernel, JIT
/// kernel or generic), creating it the first time it is asked for.
class SolverProvider {
public:
    virtual ~SolverProvider() = default;
    virtual SegmentSolver& solver(const Configuration& cfg) = 0;
    /// One line for the run statistics ("generic solver: 5 configurations").
    virtual std::string describe() const { return ""; }
};

struct EngineOptions {
    double t_end = 0.0;
    double dt = 0.0;                   ///< sample spacing; 0: samples only at t0 and t_end
    bool samples = true;               ///< call on_sample at all
    std::size_t max_events = 0;        ///< 0: unlimited
    /// Zeno: zeno_events switches within zeno_span * max(1, t - t0) seconds
    /// (relative to the time the run has covered; plus the time's resolution,
    /// 8 eps |t| per switch, twice the smallest step) stop the run with RunStatus::zeno.
    std::size_t zeno_events = 1000;
    double zeno_span = 1e-9;
};

/// Named outcomes of a run (documented; the CLI maps them to exit codes).
enum class RunStatus {
    ok,          ///< reached t_end
    chattering,  ///< switches at one instant did not settle (a configuration cycle)
    zeno,        ///< switches accumulate in time (Zeno); stopped where they do
    max_events,  ///< EngineOptions::max_events reached
    stopped,     ///< the observer asked to stop
    failure,     ///< the solver gave non-finite values
};
const char* run_status_name(RunStatus status);

struct RunSummary {
    RunStatus status = RunStatus::ok;
    std::string message;              ///< what happened and where, for non-ok status
    double t = 0.0;                   ///< time reached
    std::vector<double> x, v;         ///< state reached
    Configuration configuration;      ///< configuration reached
    std::size_t events = 0;           ///< switch events (rows of the events CSV)
    std::size_t segments = 0;         ///< closed-form segments started
    std::size_t evaluations = 0;      ///< segment evaluations made to find switches
    std::size_t configurations = 0;   ///< distinct configurations visited
};

/// Keeps references to `model` and `provider`: both must outlive it.
class Engine {
public:
    Engine(const Model& model, SolverProvider& provider);
    /// A temporary Model would dangle (`Engine e(read_model(path), p)`): refused at compile time.
    Engine(const Model&& model, SolverProvider& provider) = delete;

    /// Run from the model's initial state (x0, v0 at t0) to options.t_end.
    RunSummary run(const EngineOptions& options, Observer& observer);

private:
    const Model& model_;
    SolverProvider& provider_;
};

}  // namespace hsnc
