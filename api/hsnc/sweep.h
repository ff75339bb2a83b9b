// hsnc -- response curves and bifurcation diagrams over one parameter
// (interface.md section 6, `hsnc sweep`), without the command line.
//
//     hsnc::SweepOptions o;
//     o.param = "omega"; o.from = 1.0; o.to = 3.0; o.points = 50;
//     o.direction = hsnc::SweepDirection::both;
//     const hsnc::SweepPlan plan = hsnc::SweepPlan::from_file("model.toml", {}, o);
//     const hsnc::SweepResult r = plan.run();       // r.points: one per point, in output order
//
// A sweep is a list of *tasks*, each a sequence of points run in order with
// state continuation: one per direction (up, down; `both` is two tasks, each
// starting from the model's initial state), times one per value of an
// optional second parameter (`param2`, `values2`); with `restart_each` every
// point starts from the model's initial state and is a task of its own.
// Tasks are independent: they run on `threads` threads, over MPI ranks
// (the command line), or in separate processes (`part`, merged by
// merge_sweep_parts), and the result is the same, bit for bit, however they
// are spread: each task is computed by the same code from the same inputs,
// and results are put in task order.
//
// One point: the model is read again with the parameter at its value (the
// file's expressions follow it: k2 = "2*k1"; nothing is compiled: the
// segments come from the Eigen solver), the motion runs whole forcing
// periods T = 2*pi/omega from the task's current state, starting at the
// model's t0, until the stroboscopic state s_k (at t0 + k*T) repeats,
// |s_k - s_(k-p)| <= 1e-9 |s_k| for some p <= 8 (settled, multiple p; the
// smallest such p at the first such k), with |s| = max(|x_i|, |v_i|/omega),
// or for max_periods periods; then it records record_periods further
// periods in one run, starting at the state reached. Over the recorded
// window [t_r, t_r + R*T], from the exact closed-form segments:
//   xmax_i = max |x_i(t)|: segment ends and every zero of v_i inside a
//            segment, bracketed on a grid of 1/16 of the shortest period
//            present (the forcing's, or the highest natural frequency with
//            every contact closed) and refined to rounding (Newton on v_i
//            with a_i, in a bisection bracket);
//   xrms_i = sqrt(1/(R*T) * integral x_i^2 dt);
//   a1_i   = sqrt(A^2 + B^2), A, B = 2/(R*T) * integral x_i cos, sin(omega (t - t_r)) dt;
//   with `harmonics` = K > 0, for k = 1..K: amp_ik = sqrt(A_k^2 + B_k^2) and
//   phase_ik = atan2(A_k, B_k) - k omega t0 in (-pi, pi], A_k, B_k as A, B with
//   k omega, so that x_i(t) = mean + sum_k amp_ik sin(k omega t + phase_ik) + ...
//   over the window, t the model's time, sin as the forcing's (amp_i1 is a1_i;
//   a linear oscillator's phase_i1 is arg H(omega));
// the integrals by 6-point Gauss-Legendre on the same grid inside each
// segment (the segments are smooth: the quadrature error is below 1e-20
// relative). A point whose run stops (chattering, Zeno, a solver failure)
// does not stop the sweep: it gives a row with settled = false, multiple 0,
// NaN for xmax, xrms, a1, no stroboscopic samples and the reason in
// `failure`; the next point starts from the state the failing one started
// from.
//
// Continuation (`continuation`): instead of running each value to a steady
// state, the periodic orbit (of period T) is followed along the parameter by
// pseudo-arclength continuation, through turning points. Unknowns
// u = (y, p): the orbit's state y = (x, v) at t0 and the parameter p,
// scaled by the first orbit's largest |x| and |v| and by |to - from|. Each
// step predicts along the unit tangent of the branch, u + h t, and corrects
// with Newton on (P(y; p) - y = 0, t . (u - u_predicted) = 0), where P is the
// exact period map from t0 to t0 + 2*pi/omega(p) and dP/dy its exact
// monodromy (analysis/shooting.h); dP/dp, needed only for the tangent and the
// Newton matrix, is a central difference (the corrector converges to the
// exact orbit whatever its accuracy). A step is accepted when the
// residual (as hsnc::periodic) is <= 1e-10 within 12 iterations and the
// tangent turns by less than 37 degrees; else it is halved (down to 1e-6 of
// the largest); it grows by 1.5 after quick corrections, up to
// 1/(points - 1) (about the sweep's own spacing where the branch is flat).
// The branch starts at `from` (`to` for the down direction) from the orbit
// hsnc::periodic finds after the steady-state transient of a sweep point,
// and ends at the other end of [from, to] (the last point landed exactly on
// it), when it leaves [from, to] through its start, or after max_steps
// points. Every point carries the stability of its orbit (the Floquet
// multipliers of the monodromy: stable when every |mu| < 1) and the
// bifurcations crossed since the previous point: fold (a real multiplier
// crosses +1: det(M - I) changes sign), period_doubling (one crosses -1:
// det(M + I) changes sign), neimark_sacker (a complex pair crosses the unit
// circle: the product over pairs of (mu_i mu_j - 1) changes sign and the
// count of non-real multipliers outside the circle changes), grazing (a
// contact's largest or smallest gap function over the orbit changes sign:
// SweepPoint::gap_max, gap_min; the grazing orbit is located to rounding by
// Illinois iterations on that extreme and written as a point of its own,
// with periods 0, unless a fold lies in the same step: then the next point
// says fold+grazing). `direction` is
// the way the parameter moved from the previous point (the task's direction
// for the first), settled is true, multiple 1, `periods` the period-map
// runs the point took, and xmax, xrms, a1 and the diagram come from one
// period of the orbit. When shooting fails (no convergence at the smallest
// step, a run that stops, the model invalid at a value), the branch stops:
// no row for the failed step, the reason in `stop` of the last point (when
// the first orbit cannot be found: one row with settled = false and the
// reason in `failure`).
//
// A numerical baseline (method != hsnc, for comparisons) gives
// the same quantities from its samples on that grid (max of the samples,
// trapezoidal integrals), so only to the grid's accuracy.
#pragma once

#include <cstddef>
#include <atomic>
#include <functional>
#include <stdexcept>
#include <limits>
#include <string>
#include <vector>

#include "error.h"
#include "integrators.h"
#include "model.h"
#include "model_reader.h"

namespace hsnc {

enum class SweepDirection { up, down, both };

/// "up", "down", "both"; InputError otherwise.
SweepDirection sweep_direction_from_name(const std::string& name);
const char* sweep_direction_name(SweepDirection direction);

/// Steady-state detection (interface.md section 6).
inline constexpr double kSweepSettleTolerance = 1e-9;
inline constexpr int kSweepMaxMultiple = 8;
/// The largest SweepOptions::start_periods.
inline constexpr std::size_t kSweepMaxStartPeriods = 1024;
/// SweepOptions::branch_switch at most (orbits of up to 64 forcing periods).
inline constexpr int kSweepMaxBranchSwitch = 6;
/// SweepOptions::harmonics at most.
inline constexpr std::size_t kSweepMaxHarmonics = 1000;

/// One point done (SweepOptions::progress).
struct SweepProgress {
    std::size_t done = 0;         ///< points done so far by this process
    std::size_t total = 0;        ///< points this process runs
    double seconds = 0;           ///< wall time of this point
    double elapsed = 0;           ///< wall time since the run started
    double value = 0;             ///< the parameter
    double value2 = 0;            ///< the second parameter (NaN without one)
    SweepDirection direction = SweepDirection::up;
    bool settled = false;
    std::size_t periods = 0;
    int multiple = 0;
    std::string failure;      ///< why the point failed ("" when it did not)
    std::string stop;         ///< continuation: why the branch stopped here early ("" when not)
    bool continuation = false;
    bool stable = false;      ///< continuation: the orbit's stability
    double max_multiplier = 0;
    std::string bifurcation;  ///< continuation: crossed since the previous point
};

/// Thrown by SweepPlan::run_task / run_tasks / run when SweepOptions::cancel is set.
class SweepCancelled : public std::runtime_error {
public:
    SweepCancelled() : std::runtime_error("sweep cancelled") {}
};

struct SweepOptions {
    std::string param;  ///< a parameter of [parameters] (required)
    double from = std::numeric_limits<double>::quiet_NaN();
    double to = std::numeric_limits<double>::quiet_NaN();
    std::size_t points = 0;  ///< >= 1: from .. to inclusive, equally spaced (just `from` when 1)
    SweepDirection direction = SweepDirection::up;
    std::size_t max_periods = 500;   ///< >= 1
    std::size_t record_periods = 16; ///< >= 1
    /// Every point from the model's initial state (points independent).
    bool restart_each = false;
    /// Optional second parameter: the sweep runs once per value, in this order.
    std::string param2;
    std::vector<double> values2;
    /// Threads of SweepPlan::run; 0: std::thread::hardware_concurrency().
    unsigned threads = 1;
    /// Keep the stroboscopic samples of the recorded periods (the diagram).
    bool diagram = true;
    /// Amplitude and phase of the first `harmonics` harmonics of every mass
    /// over the recorded window (0: none; at most kSweepMaxHarmonics).
    std::size_t harmonics = 0;
    /// > 0: a point whose displacement of some dof exceeds this in magnitude
    /// at the end of a forcing period stops there, escaped (its recorded
    /// periods follow from there); 0: no bound. Not with continuation.
    double escape = 0;
    /// hsnc (exact); a numerical baseline for comparisons (see the file comment).
    Method method = Method::hsnc;
    IntegratorOptions integrator;
    /// Called after every point, from the thread that ran it, one call at a time.
    std::function<void(const SweepProgress&)> progress;
    /// Continuation of periodic orbits over the parameter (see the file comment).
    bool continuation = false;
    /// Continuation: points at most per branch; 0: 20 * points.
    std::size_t max_steps = 0;
    /// Continuation: > 0: the branch starts at the orbit of this many forcing
    /// periods shot from the model's initial state at `from` (`to` for
    /// direction down), with no transient: a point of an earlier run (its
    /// state at t0, its multiple), stable or not; 0: a sweep point's
    /// transient from the initial state, then the orbit of one period.
    std::size_t start_periods = 0;
    /// Continuation: follow the branches born at period doublings (each
    /// located to rounding), and theirs, up to this many doublings (the
    /// branch of 2^branch_switch periods; 0: none, at most kSweepMaxBranchSwitch).
    int branch_switch = 0;
    /// Continuation: follow, instead of the branch, its first point of this
    /// kind ("fold", "period_doubling", "neimark_sacker", "grazing") over two
    /// parameters, param and param2, from param2 = values2[0] towards
    /// values2[1] ("": a branch, as without).
    std::string track;
    /// When set (from any thread), runs stop soon (between two forcing
    /// periods or two continuation steps) with SweepCancelled.
    const std::atomic<bool>* cancel = nullptr;
    /// When set (from any thread), every task ends after the point it is
    /// running (a continuation branch after its step under way) and keeps the
    /// points it has finished; tasks not started yet run none. A graceful
    /// stop (the command line's Ctrl-C): run_tasks says whether it cut any
    /// task short.
    const std::atomic<bool>* stop = nullptr;
};

/// One point of a sweep.
struct SweepPoint {
    double value = 0;   ///< the parameter
    double value2 = std::numeric_limits<double>::quiet_NaN();  ///< the second parameter (NaN without)
    SweepDirection direction = SweepDirection::up;             ///< up or down
    bool settled = false;
    bool escaped = false;     ///< left SweepOptions::escape's bound (not settled)
    std::size_t periods = 0;  ///< periods run before recording
    int multiple = 0;         ///< p; 0 when not settled
    std::vector<double> xmax, xrms, a1;  ///< one per mass (NaN when the point failed)
    /// With SweepOptions::harmonics = K: amplitude and phase (rad) of harmonic k
    /// (1..K) of mass i at [i * K + k - 1] (NaN when the point failed).
    std::vector<double> amp, phase;
    /// Each contact's gap function G = u - gap (closed while G >= 0): its
    /// largest and smallest value over the recorded window (empty when the
    /// point failed, and outside a continuation, which alone needs them). A
    /// sign change of either between two points of a branch is
    /// a grazing (the orbit starts or stops closing, or opening, the contact).
    /// A rigid stop (restitution) that the orbit hits has G = 0 at every
    /// impact: its gap_max is then the slowest impact's speed G'- > 0, which
    /// falls to 0 as the orbit comes to graze the stop.
    std::vector<double> gap_max, gap_min;
    /// Each Jenkins element's stretch e = u - s (slips at |k e| = F_s): its
    /// largest and smallest value over the window (a continuation's points only).
    std::vector<double> stretch_max, stretch_min;
    /// What the motion does over the recorded window (method hsnc; empty with a
    /// baseline or when the point failed): per contact, how often it closes
    /// (a contact closed at both ends of the window counted as one closing, as
    /// on a periodic orbit); per mass then per Jenkins element, whether it is
    /// stuck (sticks) and whether it moves or slips (slips) at some instant
    /// (a mass without friction always moves). A change of these between two
    /// points of a branch is a non-smooth transition (continuation:
    /// stick_onset, slip_onset, grazing).
    std::vector<std::size_t> closings;
    std::vector<char> sticks, slips;
    std::string failure;  ///< why the point's run stopped ("" when it did not; see the file comment)
    /// Continuation only: the orbit's stability and largest |multiplier|, the
    /// bifurcations crossed since the previous point of the branch ("" or
    /// fold, period_doubling, neimark_sacker, grazing, stick_onset, slip_onset;
    /// several joined by '+'), and why
    /// the branch stopped after this point ("" when it did not stop early).
    bool stable = false;
    double max_multiplier = std::numeric_limits<double>::quiet_NaN();
    std::string bifurcation;
    std::string stop;
    bool branch_start = false;  ///< continuation: the first point of a branch
    /// Continuation: the branch's index in the output (0 the primary; with
    /// SweepOptions::branch_switch, 1, 2, ... those switched onto, in order).
    std::size_t branch = 0;
    /// The diagram: the state at the end of every recorded period (record_periods rows).
    std::vector<double> strobe_t;
    std::vector<double> strobe_x, strobe_v;  ///< row-major, record_periods x n_mass
};

struct SweepResult {
    std::string model;                ///< the model's name
    std::string param, param2;        ///< param2 empty without one
    bool continuation = false;        ///< the curve has the columns stable,max_multiplier,bifurcation
    std::size_t harmonics = 0;        ///< the curve has amp<k>_<mass>,phase<k>_<mass> at its end, k = 1..harmonics
    int branch_switch = 0;            ///< the curve has the column branch (after bifurcation)
    std::string track;                ///< a curve of points of this kind over (param, param2) ("" for none)
    std::vector<std::string> masses;  ///< names, model order
    std::vector<SweepPoint> points;   ///< in output order (task order, points in run order)
};

/// A sweep whose every point's model has been read and checked: constructing
/// one throws InputError for anything that does not fit (an option, an
/// unknown parameter, a value at which the model is invalid, a model without
/// exactly one forcing frequency), naming the option or the point; running
/// throws only RunError.
class SweepPlan {
public:
    /// Reads the model from `toml_text` (`source` names it in messages) with
    /// `overrides` (as `hsnc simulate --set --x0 --v0`) for every point.
    SweepPlan(const std::string& toml_text, const std::string& source, const ModelOverrides& overrides,
              SweepOptions options);
    /// The same from a file (InputError when it cannot be read).
    static SweepPlan from_file(const std::string& path, const ModelOverrides& overrides, SweepOptions options);

    const SweepOptions& options() const { return options_; }
    /// The model with the overrides, the parameters as the file has them.
    const Model& model() const { return model_; }
    /// The parameter values, from .. to.
    const std::vector<double>& values() const { return values_; }

    std::size_t tasks() const { return tasks_.size(); }
    /// Points of task `i`.
    std::size_t task_points(std::size_t i) const;
    /// Run task `i` (RunError when a point's run fails: chattering, Zeno, a solver failure).
    std::vector<SweepPoint> run_task(std::size_t i) const;
    /// Run the tasks `which` on options().threads threads; results in the order of `which`.
    /// `stopped` (may be null): set to whether SweepOptions::stop cut a task short
    /// (the results then hold only the points finished).
    std::vector<std::vector<SweepPoint>> run_tasks(const std::vector<std::size_t>& which,
                                                   bool* stopped = nullptr) const;
    /// Every task, assembled.
    SweepResult run() const;
    /// An empty result with the names (to fill with tasks' points in order).
    SweepResult result_header() const;

    /// The tasks of part `index` of `count` (index from 0): every task i with i % count == index.
    std::vector<std::size_t> part_tasks(std::size_t index, std::size_t count) const;

    /// One line identifying the sweep (model, overrides, options), equal for every
    /// part of one sweep: the part files carry it and merging checks it.
    const std::string& fingerprint() const { return fingerprint_; }

private:
    struct Task {
        std::size_t line;       ///< index into values2 (0 without)
        SweepDirection direction;
        std::size_t first, count;  ///< points [first, first + count) of the direction's order
    };
    const Model& point_model(std::size_t line, std::size_t value_index) const;
    /// The model with param at p and, when given, param2 at *q, its
    /// expressions dropped (a continuation reads it at every value it reaches).
    Model model_at(double p, const double* q) const;
    std::vector<SweepPoint> run_task(std::size_t i, void* context) const;

    SweepOptions options_;
    Model model_;
    std::vector<double> values_;
    std::vector<Task> tasks_;
    std::vector<Model> models_;  // [line * points + value index], expression maps dropped
    std::string text_, source_;  // the model file, read again at every value a continuation reaches
    ModelOverrides overrides_;
    std::string fingerprint_;
};

/// A part file of `hsnc sweep --part i/n`: the fingerprint, the part, and
/// the points of each of its tasks. `interrupted`: "" for a finished part, else
/// the last line of a part stopped by SIGINT (a '#' comment; its tasks hold
/// the points done), which merge_sweep_parts refuses.
std::string sweep_part_text(const SweepPlan& plan, std::size_t index, std::size_t count,
                            const std::vector<std::vector<SweepPoint>>& task_points,
                            const std::string& interrupted = "");

/// Merge the part files `texts` (named by `names` in messages) of one sweep
/// into the result a whole run gives. InputError when they are not the parts
/// of one sweep, a part is missing or given twice, was interrupted, or a file
/// is damaged.
SweepResult merge_sweep_parts(const std::vector<std::string>& texts, const std::vector<std::string>& names);

/// `points` values from `from` to `to`, equally spaced, the ends exact
/// (just `from` when points is 1): a sweep's values, and --values2 A:B:M's.
std::vector<double> sweep_values(double from, double to, std::size_t points);

/// Whether a swept name is an initial state coordinate, x0.DOF or v0.DOF
/// (SweepOptions::param, param2), and whether a sweep is over two of them:
/// basins of attraction.
bool is_state_coordinate(const std::string& name);
bool is_basins(const SweepResult& result);

/// An attractor the points of a sweep reached: a periodic orbit of
/// `multiple` forcing periods, named by its canonical state (of its
/// `multiple` states at the ends of the recorded periods, the one of least
/// x of the first mass), or (`multiple` 0) a set the points that did not
/// settle share (chaotic, quasi-periodic), named by the recorded state of
/// least x of the first mass; and how many points reached it.
struct Attractor {
    int multiple = 0;
    std::vector<double> x, v;  ///< the canonical state, one per mass
    std::size_t points = 0;
};

/// The attractors of a sweep's points, for basins of attraction (param and
/// param2 initial state coordinates x0.DOF, v0.DOF, with restart_each).
/// Settled points with the same multiple whose canonical states agree to
/// `tolerance` of the largest |x| and |v| of all of them reached one
/// periodic attractor. Points that did not settle whose recorded states
/// share a cell of a grid over the recorded states (each coordinate's range
/// in 20 cells) reached one set (transitively), unless the last 4 recorded
/// states of a point lie in cells of periodic attractors' states (a slow
/// transient: not settled). Numbered 1, 2, ... in the order of the first
/// point that reached each (so the same for any split of the run);
/// `of_point`: each point's number, 0 for a point not settled and in no
/// set, -1 for a failed one, -2 for one that escaped (SweepOptions::escape).
struct Attractors {
    std::vector<Attractor> list;
    std::vector<int> of_point;
};
Attractors classify_attractors(const SweepResult& result, double tolerance = 1e-6);

/// The response-curve and diagram CSV headers of interface.md section 6
/// (with param2: its name as one more column at the end; with continuation:
/// then stable,max_multiplier,bifurcation; with branch switching: then
/// branch; with harmonics: then
/// amp<k>_<mass>,phase<k>_<mass> for every mass and k = 1..harmonics).
std::string sweep_curve_header(const SweepResult& r);
std::string sweep_diagram_header(const SweepResult& r);

}  // namespace hsnc
