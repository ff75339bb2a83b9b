#include "engine.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <sstream>
#include <type_traits>

#include "assembly.h"
#include "error.h"
#include "number_text.h"
#include "restart.h"
#include "sample_grid.h"
#include "switch_guard.h"
#include "tie_series.h"
#include "transition_rules.h"
#include "transitions.h"

namespace hsnc {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kInf = std::numeric_limits<double>::infinity();
// A scheduled search evaluates, beside the functions due at the next instant,
// those due within this many times the step to it.
constexpr double kScheduleAhead = 1.0;

// Rounding level of a switch function whose summed terms have magnitude `scale`.
double noise_of(double scale) { return 16 * kEps * scale; }

// Working storage for one segment's evaluations (sized for the largest switch list).
// x holds the Jenkins sliders after the masses (nx = Model::state_size()).
struct Buffers {
    std::vector<double> x, v, a, g, dg, bound, scale;
    std::vector<double> slow, slow_dg, fast, slow_bound;  // the split bound (segment_solver.h)
    Buffers(std::size_t nx, std::size_t n, std::size_t nsw)
        : x(nx),
          v(n),
          a(n),
          g(nsw),
          dg(nsw),
          bound(nsw),
          scale(nsw),
          slow(nsw),
          slow_dg(nsw),
          fast(nsw),
          slow_bound(nsw) {}
    SegmentEval view() {
        return {x.data(),     v.data(),    a.data(),       g.data(),    dg.data(),        bound.data(),
                scale.data(), slow.data(), slow_dg.data(), fast.data(), slow_bound.data()};
    }
    // A view for the state alone (dense output): no split bound asked for.
    SegmentEval state_view() {
        SegmentEval e = view();
        e.slow = e.slow_dg = e.fast = e.slow_bound = nullptr;
        return e;
    }
    // Function f's split bound from another evaluation.
    void take_split(const Buffers& o, std::size_t f) {
        slow[f] = o.slow[f], slow_dg[f] = o.slow_dg[f], fast[f] = o.fast[f], slow_bound[f] = o.slow_bound[f];
    }
};

// Side on which switch function f is watched in the current configuration:
// h = side*g > 0 until it switches.
double side_of(const SwitchFunction& f, const Configuration& cfg, const std::vector<signed char>& sgn) {
    switch (f.kind) {
        case SwitchKind::gap: return cfg.closed[f.element] ? 1.0 : -1.0;
        case SwitchKind::velocity: return sgn[f.element] >= 0 ? 1.0 : -1.0;
        case SwitchKind::slip_velocity: return cfg.slip[static_cast<std::size_t>(f.element)] >= 0 ? 1.0 : -1.0;
        default: return -1.0;  // release and slip functions are negative while stuck
    }
}

// An upper bound on the rates of the motion in cfg (1/s): the fastest mode
// (Gershgorin on M^-1 K of the free masses: omega^2 <= 2 sum_links k / m_i),
// its Rayleigh damping rate alpha + beta omega^2, the dampers' rates, and every
// forcing frequency.
double fastest_rate(const Model& model, const Configuration& cfg) {
    const std::size_t n = model.dof();
    std::vector<double> stiff(n, 0.0);
    auto add = [&](int a, int b, double k) {
        if (a == b) return;
        // |k|: a [structure]'s springs may be negative (Gershgorin needs |K_ij|).
        if (a != kGround) stiff[static_cast<std::size_t>(a)] += std::fabs(k);
        if (b != kGround) stiff[static_cast<std::size_t>(b)] += std::fabs(k);
    };
    for (const Spring& s : model.springs) add(s.a, s.b, s.k);
    for (std::size_t c = 0; c < model.contacts.size(); ++c)  // as pair links when along a general direction
        link_of(model, cfg, ElementKind::contact, c, [&](int a, int b, double k, double, double) { add(a, b, k); });
    for (std::size_t j = 0; j < model.jenkins.size(); ++j)  // stuck, a link (pair links along a direction)
        link_of(model, cfg, ElementKind::jenkins, j, [&](int a, int b, double k, double, double) { add(a, b, k); });
    // A coupled M: lambda_max(K_F, M_F) <= lambda_max(K_F) / lambda_min(M) (interlacing), and
    // lambda_max(K_F) <= max_i 2 stiff_i (Gershgorin), so m_i becomes M's smallest eigenvalue.
    auto mass_of = [&](std::size_t i) { return model.coupled_mass() ? model.mass_floor : model.masses[i].m; };
    double w2 = 0.0;
    for (std::size_t i = 0; i < n; ++i)
        if (!fixed_in(model, cfg, i)) w2 = std::max(w2, 2 * stiff[i] / mass_of(i));
    double rate = std::max(std::sqrt(w2), std::fabs(model.alpha) + std::fabs(model.beta) * w2);
    // Dampers: the damping rates of M^-1 C_d, by Gershgorin as for K.
    std::vector<double> visc(n, 0.0);
    for (const Damper& d : model.dampers)
        for (int b : {d.a, d.b})
            if (b != kGround && d.a != d.b) visc[static_cast<std::size_t>(b)] += std::fabs(d.c);
    for (std::size_t e = 0; e < model.contacts.size(); ++e) {  // a closed contact's own c w w^T: row sums
        const Contact& ct = model.contacts[e];
        if (!cfg.closed[e] || ct.c == 0.0) continue;
        double norm1 = 0.0;
        for_each_term(ct.direction(), [&](int, double w) { norm1 += std::fabs(w); });
        for_each_term(ct.direction(), [&](int b, double w) { visc[static_cast<std::size_t>(b)] += ct.c * std::fabs(w) * norm1 / 2; });
    }
    for (std::size_t i = 0; i < n; ++i)
        if (!fixed_in(model, cfg, i)) rate = std::max(rate, 2 * visc[i] / mass_of(i));
    for (const Harmonic& h : model.forcing) rate = std::max(rate, std::fabs(h.omega));
    return rate;
}

// The earliest switch of one segment.
struct Found {
    bool any = false;
    double tau = 0.0;
    std::vector<SwitchFunction> switched;
};

// The segment the search runs on: its solver, switch functions and instant,
// and the state and friction directions it starts from.
struct SearchSegment {
    SegmentSolver* solver = nullptr;
    const std::vector<SwitchFunction>* switches = nullptr;
    const Configuration* cfg = nullptr;
    const std::vector<signed char>* sgn = nullptr;
    const std::vector<signed char>* sgn_before = nullptr;  // before the last event (a carried start)
    const double* x = nullptr;
    const double* v = nullptr;
    double t = 0.0, t_lo = 0.0;
    double tau_end = 0.0, max_step = 0.0;
    bool carried_start = false;  // the coefficient block carried over a switch (restart.h)
};

// The switch search of one segment: the earliest instant in (0, tau_end] at
// which a switch function reaches its trigger level, the functions that
// switch there, and the event state (buf), with the rounding level each
// function passes on to the next segment (inherited). Phases, each a member:
//   start()       evaluate every function at the segment start (or take a
//                 carried segment's values), arm the velocities;
//   start_ties()  decide the functions at zero with a vanishing rate by
//                 their Taylor series (tie_series.h);
//   step loop     safe steps from each function's bound until one is beyond
//                 its trigger level (search<scheduled>);
//   take_event()  evaluate the instant in full, Newton-refine it, collect
//                 every function that switches there.
// With few switch functions every instant evaluates all of them, and the
// step is the smallest of their safe steps. With many (kScheduleFrom,
// segment_solver.h) each is evaluated on its own schedule: at_f is the
// instant at which function f's values in buf (g, dg, bound, scale) were
// taken, before_f the one before, next_f the instant up to which its bound
// keeps it from its trigger level. An instant takes the functions whose
// next_f it reaches, or soon will (`due`), and the others keep their values
// and their guarantee. So a function far from switching is not evaluated at
// every instant another one needs, and a solver that computes a function
// alone (the interpreter, SegmentSolver::eval_some) does only what is due.
// The instants depend on the values alone, so every kind of solver takes the
// same ones (a kernel computes every function and the search reads the due
// ones). The search is compiled for each case, so that the unscheduled one
// (every small model) pays nothing for the schedule.
class SwitchSearch {
public:
    SwitchSearch(const Model& model, std::size_t nx, std::size_t max_switches, RunSummary& sum)
        : buf(nx, model.dof(), max_switches), model_(model), sum_(sum), probe_(nx, model.dof(), max_switches),
          probe_view_(probe_.view()), side_(max_switches), floor_(max_switches), root_(max_switches),
          clear_until_(max_switches), at_(max_switches), before_(max_switches), next_(max_switches),
          armed_(max_switches), leaving_(max_switches), leaves_now_(max_switches),
          stride_(std::max({model.contacts.size(), model.dof(), model.jenkins.size()})),
          inherited_(kSwitchKinds * stride_, 0.0) {
        due_.reserve(max_switches);
        start_due_.reserve(max_switches);
        found.switched.reserve(max_switches);
    }

    /// Searches segment s; "" or why the search failed. `scheduled`: each
    /// function on its own schedule.
    std::string run(const SearchSegment& s, bool scheduled) {
        seg_ = s;
        nsw_ = s.switches->size();
        out_ = buf.view();
        split_ = solver().splits_bound();
        for (std::size_t f = 0; f < nsw_; ++f) {
            side_[f] = side_of((*s.switches)[f], *s.cfg, *s.sgn);
            floor_[f] = inherited_[slot((*s.switches)[f])];
        }
        failure_.clear();
        if (scheduled)
            search<true>();
        else
            search<false>();
        return failure_;
    }

    Buffers buf;  // the event state: the last full evaluation
    Found found;

private:
    const SwitchFunction& fn(std::size_t f) const { return (*seg_.switches)[f]; }
    SegmentSolver& solver() const { return *seg_.solver; }
    // Rounding level each switch function had at the last event, by (kind,
    // element): a value that should be 0 after a switch comes back as ~1e-17
    // from the previous segment, whatever the new segment's own terms are.
    // Flat table indexed by kind * stride + element; 0 where nothing was inherited.
    std::size_t slot(const SwitchFunction& f) const {
        return static_cast<std::size_t>(f.kind) * stride_ + static_cast<std::size_t>(f.element);
    }
    // Rounding level of g_f at the point last evaluated: its terms (scale), the
    // rounding of the time itself (|g'| * ulp-ish of t + at_f, which also covers
    // the rounding of each omega*tau), and what it inherited from the last event.
    // Unscheduled, every function has the values of the last instant (tau_now).
    template <bool scheduled>
    double noise(std::size_t f) const {
        const double at_f = scheduled ? at_[f] : tau_now_;
        return std::max(noise_of(buf.scale[f] + std::fabs(buf.dg[f]) * (std::fabs(seg_.t) + at_f)), floor_[f]);
    }
    // Every function's values in buf are now those at tau.
    template <bool scheduled>
    void all_at(double tau) {
        prev_tau_ = tau_now_, tau_now_ = tau;
        if (scheduled)
            for (std::size_t f = 0; f < nsw_; ++f) before_[f] = at_[f], at_[f] = tau;
        ++sum_.evaluations;
    }
    // The search reads only the switch outputs; the state (x, v, a) is read
    // at the segment's last instant, evaluated in full.
    template <bool scheduled>
    void eval_all(double tau, bool full) {
        if (full)
            solver().eval(tau, out_);
        else
            solver().eval_switches(tau, out_);
        all_at<scheduled>(tau);
    }
    void eval_due(double tau) {
        solver().eval_some(tau, due_.data(), due_.size(), probe_view_);
        for (std::uint32_t f : due_) {
            buf.g[f] = probe_.g[f], buf.dg[f] = probe_.dg[f], buf.bound[f] = probe_.bound[f];
            buf.scale[f] = probe_.scale[f];
            if (split_) buf.take_split(probe_, f);
            before_[f] = at_[f];
            at_[f] = tau;
        }
        ++sum_.evaluations;
    }
    // The functions evaluated at the last instant: all of them, or those due.
    template <bool scheduled>
    std::size_t evaluated() const { return scheduled ? due_.size() : nsw_; }
    template <bool scheduled>
    std::size_t function(std::size_t k) const { return scheduled ? due_[k] : k; }

    template <bool scheduled>
    void start();
    template <bool scheduled>
    void start_ties();
    template <bool scheduled>
    void take_event(double tau_star);
    template <bool scheduled>
    bool scan(std::size_t iter, double tau, double& tau_star);
    template <bool scheduled>
    double own_step(std::size_t f, double tau) const;
    template <bool scheduled>
    bool land(std::size_t f, double tau, double horizon, double step_cap);
    template <bool scheduled>
    void search();

    const Model& model_;
    RunSummary& sum_;
    SearchSegment seg_;
    std::size_t nsw_ = 0;
    SegmentEval out_{};
    bool split_ = false;  // the solver writes the split bound
    Buffers probe_;  // a search evaluation: its due functions go to buf
    SegmentEval probe_view_;
    std::vector<double> side_, floor_, root_, clear_until_;
    // The per-function schedule: when each function was evaluated (at), the
    // evaluation before (before), until when it is safe (next).
    std::vector<double> at_, before_, next_;
    std::vector<std::uint32_t> due_, start_due_;  // start_due: a carried segment's functions evaluated at its start
    std::vector<char> armed_, leaving_, leaves_now_;
    std::vector<double> series_d_, series_mag_;
    std::size_t stride_;
    std::vector<double> inherited_;
    double tau_now_ = 0.0, prev_tau_ = 0.0;
    std::string failure_;
};

// Evaluates every function at the segment start. A segment carried over a
// switch starts where the event's full evaluation (buf) left every function:
// positions and velocities are continuous, and the only accelerations that
// jump are those of the masses whose friction flipped. So g, g' and the scale
// are the event's, but for the velocities of those masses and the release
// functions (their g' reads the neighbours' accelerations); every bound is
// the new segment's own. A velocity function that starts at 0 (a release, a
// reversal, a stop that slides on) is not watched for a stop until it has
// left 0.
template <bool scheduled>
void SwitchSearch::start() {
    tau_now_ = 0.0, prev_tau_ = 0.0;
    std::fill(armed_.begin(), armed_.end(), 0);
    found.any = false;
    found.tau = 0.0;
    found.switched.clear();
    if (seg_.carried_start) {
        start_due_.clear();
        for (std::size_t f = 0; f < nsw_; ++f) {
            const SwitchFunction& w = fn(f);
            const bool jumps = w.kind == SwitchKind::release_pos || w.kind == SwitchKind::release_neg ||
                               (w.kind == SwitchKind::velocity &&
                                (*seg_.sgn_before)[static_cast<std::size_t>(w.element)] !=
                                    (*seg_.sgn)[static_cast<std::size_t>(w.element)]);
            if (jumps) start_due_.push_back(static_cast<std::uint32_t>(f));
        }
        solver().eval_start(0.0, start_due_.data(), start_due_.size(), probe_view_);
        for (std::size_t f = 0; f < nsw_; ++f) buf.bound[f] = probe_.bound[f];
        // The split is the new segment's own at 0 for every function (a bound
        // of its g, whatever the rounding of the event's values kept in buf).
        if (split_)
            for (std::size_t f = 0; f < nsw_; ++f) buf.take_split(probe_, f);
        for (std::uint32_t f : start_due_)
            buf.g[f] = probe_.g[f], buf.dg[f] = probe_.dg[f], buf.scale[f] = probe_.scale[f];
        all_at<scheduled>(0.0);
    } else {
        eval_all<scheduled>(0.0, false);
    }
    if (scheduled) {
        due_.resize(nsw_);
        for (std::size_t f = 0; f < nsw_; ++f) {
            due_[f] = static_cast<std::uint32_t>(f);
            before_[f] = 0.0;
        }
    }
    for (std::size_t f = 0; f < nsw_; ++f)
        if (is_velocity(fn(f).kind)) armed_[f] = side_[f] * buf.g[f] > noise<scheduled>(f);
}

// Ties at the segment start (tie_series.h): a function at zero whose rate
// vanishes too. Its first non-zero derivative, of order m, decides
// (interface.md "Ties and touches"): one heading across switches now, at this
// instant; one heading into its safe side is `leaving` zero, where the bound
// h + h' s - B s^2/2 would make the steps shrink like s^(m/2) (a contact at
// rest on its gap under sin forcing took 30000 evaluations). By Taylor's
// theorem with B' >= |h^(m+1)| on [0, T], h > 0 on (0, (m+1)|h^(m)(0)|/B'),
// so it is left out of the bound up to half that (clear_until) and watched
// by the bound from there. A function with no non-zero derivative
// (identically zero to rounding, by Cayley-Hamilton) stays leaving, with
// steps of at most tau (doubling), unless its g'' bound is 0 (then the bound
// gives an unlimited step).
template <bool scheduled>
void SwitchSearch::start_ties() {
    std::fill(leaving_.begin(), leaving_.end(), 0);
    std::fill(leaves_now_.begin(), leaves_now_.end(), 0);
    const Configuration& cfg = *seg_.cfg;
    MotionSeries low, full;  // order 2 for the rate; the full expansion only at a true tie
    for (std::size_t f = 0; f < nsw_; ++f) {
        if (std::fabs(buf.g[f]) > noise<scheduled>(f)) continue;
        // A rate clearly beyond its rounding (almost every function that has
        // just switched) needs no series: the bound works.
        if (std::fabs(buf.dg[f]) > 4 * tie_noise(rate_magnitude(model_, cfg, fn(f), seg_.x, seg_.v))) continue;
        if (low.x.empty()) low = motion_series(model_, cfg, seg_.sgn->data(), seg_.t, seg_.t_lo, seg_.x, seg_.v, 2);
        switch_series(model_, cfg, fn(f), seg_.t, seg_.t_lo, low, series_d_, series_mag_);
        if (std::fabs(series_d_[1]) > tie_noise(series_mag_[1])) continue;  // h' decides: the bound works
        const int max_order = tie_order(model_);
        if (full.x.empty())
            full = motion_series(model_, cfg, seg_.sgn->data(), seg_.t, seg_.t_lo, seg_.x, seg_.v, max_order + 2);
        switch_series(model_, cfg, fn(f), seg_.t, seg_.t_lo, full, series_d_, series_mag_);
        int order = 0;
        const int dir = first_nonzero_sign(series_d_, series_mag_, max_order, &order) * (side_[f] > 0 ? 1 : -1);
        if (dir < 0) {
            leaves_now_[f] = 1;
            continue;
        }
        if (dir == 0) {
            leaving_[f] = buf.bound[f] > 0;
            clear_until_[f] = 0.0;
            continue;
        }
        // clear_until = c/B'(T) for B' valid on [0, T], T <= c/B'(0): any T
        // gives a valid interval [0, min(T, c/B'(T))].
        const double c = 0.5 * (order + 1) * std::fabs(series_d_[static_cast<std::size_t>(order)]);
        const double T = std::min(seg_.tau_end, c / derivative_bound(model_, cfg, fn(f), full, order + 1, 0.0));
        const double clear = std::min(T, c / derivative_bound(model_, cfg, fn(f), full, order + 1, T));
        if (clear > 0) {
            leaving_[f] = 1;
            clear_until_[f] = clear;
        }
    }
}

// The event at tau_star: every function whose zero lies there (to rounding)
// switches, and so do the others within rounding of zero and heading across
// at that instant, evaluated in full.
template <bool scheduled>
void SwitchSearch::take_event(double tau_star) {
    const double t = seg_.t;
    const double tol = 4 * kEps * (std::fabs(t) + std::fabs(tau_star)) + 1e-300;
    found.any = true;
    found.tau = std::min(tau_star, seg_.tau_end);
    for (std::size_t f = 0; f < nsw_; ++f)
        if (root_[f] <= tau_star + tol) found.switched.push_back(fn(f));
    eval_all<scheduled>(found.tau, true);
    // The Newton step that located the event is clamped to the last instant
    // inside the trigger level (the root may lie before it), and that level
    // may be what the function inherited, above its own rounding: where the
    // event's function is still beyond its own rounding, Newton steps on from
    // the located instant (at most 3, while they shrink), as the reference
    // iterates. A contact was located at G = 14 times its rounding, which the
    // tie rules, judging G by its own rounding, may read as the other side.
    {
        std::size_t lead = nsw_;
        for (std::size_t f = 0; f < nsw_ && lead == nsw_; ++f)
            if (root_[f] == tau_star && !(is_velocity(fn(f).kind) && armed_[f])) lead = f;
        double last = kInf;
        for (int it = 0; lead < nsw_ && it < 3; ++it) {
            const double h = side_[lead] * buf.g[lead], hd = side_[lead] * buf.dg[lead];
            const double own = noise_of(buf.scale[lead] + std::fabs(buf.dg[lead]) * (std::fabs(t) + found.tau));
            if (std::fabs(h) <= own || !(hd < 0)) break;
            const double r = found.tau - h / hd;
            if (!(r >= 0 && r <= seg_.tau_end) || !(std::fabs(r - found.tau) < last) || r == found.tau) break;
            last = std::fabs(r - found.tau);
            found.tau = r;
            eval_all<scheduled>(found.tau, true);
        }
    }
    for (std::size_t f = 0; f < nsw_; ++f) {
        if (root_[f] <= tau_star + tol) continue;
        const double h = side_[f] * buf.g[f], hd = side_[f] * buf.dg[f];
        const double eps_f = noise<scheduled>(f);
        const bool stop = is_velocity(fn(f).kind) && armed_[f];
        // buf holds the full evaluation at found.tau: its state gives the rate's terms.
        auto rate_noise = [&] {
            return 4 * tie_noise(rate_magnitude(model_, *seg_.cfg, fn(f), buf.x.data(), buf.v.data()));
        };
        if (stop ? rules::stops_here(h, hd, buf.bound[f], eps_f, 0.0, rate_noise) : (h < -eps_f || (h <= eps_f && hd < 0)))
            found.switched.push_back(fn(f));
    }
    // What the next segment inherits: each function's rounding at this
    // instant. The level it had itself inherited is passed on only by an
    // event at that same instant (a chain of switches at one t). Passed on
    // always, it was a ratchet: once a function's terms were large (a stiff
    // Jenkins element stuck), their level stayed for the rest of the run, and
    // a contact was located 18 times its own rounding from zero (clamped to
    // the last instant inside that level), where the tie rules, which judge G
    // by its own rounding, then saw it open (tests/test_contact_location.cpp).
    const bool same_instant = found.tau <= 4 * kEps * std::fabs(t);
    std::fill(inherited_.begin(), inherited_.end(), 0.0);
    for (std::size_t f = 0; f < nsw_; ++f)
        inherited_[slot(fn(f))] = same_instant
                                      ? noise<scheduled>(f)
                                      : noise_of(buf.scale[f] + std::fabs(buf.dg[f]) * (std::fabs(t) + found.tau));
}

// Which of the functions just evaluated (at tau) have switched, and where is
// each one's zero (root_)? tau_star: the earliest. False on a failure.
template <bool scheduled>
bool SwitchSearch::scan(std::size_t iter, double tau, double& tau_star) {
    tau_star = kInf;
    for (std::size_t k = 0, count = evaluated<scheduled>(); k < count; ++k) {
        const std::size_t f = function<scheduled>(k);
        root_[f] = kInf;
        const double h = side_[f] * buf.g[f], hd = side_[f] * buf.dg[f];
        if (!std::isfinite(h) || !std::isfinite(hd) || !std::isfinite(buf.bound[f])) {
            failure_ = "non-finite switch function in configuration '" + seg_.cfg->spec(model_) + "' at t = " +
                       number_text(seg_.t + tau);
            return false;
        }
        if (iter == 0 && leaves_now_[f]) {  // a tie heading across: it switches at the segment start
            root_[f] = 0.0;
            tau_star = 0.0;
            continue;
        }
        const double eps_f = noise<scheduled>(f);
        const bool stop = is_velocity(fn(f).kind) && armed_[f];
        // The rate's terms from the state at tau (a search evaluation has the
        // switch functions only): asked for only by a velocity falling in its band.
        auto rate_noise = [&] {
            solver().eval(tau, probe_view_);
            return 4 * tie_noise(rate_magnitude(model_, *seg_.cfg, fn(f), probe_.x.data(), probe_.v.data()));
        };
        if (stop ? !rules::stops_here(h, hd, buf.bound[f], eps_f, 0.0, rate_noise) : h >= -eps_f) continue;
        // Move to the zero by one Newton step (the function is monotone
        // there), never before the last point known to be on the safe side.
        const double prev = scheduled ? before_[f] : prev_tau_;
        double r = tau;
        if (hd < 0 && std::fabs(hd) > 0) r = tau - h / hd;
        if (stop && h <= 0 && hd >= 0) r = tau;  // touched zero and turned back
        r = std::min(std::max(r, prev), std::max(tau, prev));
        if (stop && hd < 0 && h > 0) r = tau + h / -hd;  // tiny forward step onto v = 0
        root_[f] = r;
        tau_star = std::min(tau_star, r);
    }
    return true;
}

// Safe step of function f from tau: it cannot reach its trigger level inside it.
template <bool scheduled>
double SwitchSearch::own_step(std::size_t f, double tau) const {
    const double floor_step = 4 * kEps * (std::fabs(seg_.t) + std::fabs(tau)) + 1e-300;
    // A function leaving zero: up to its clear instant, then doubling.
    if (leaving_[f]) return tau < clear_until_[f] ? clear_until_[f] - tau : std::max(tau, floor_step);
    const double h = side_[f] * buf.g[f], hd = side_[f] * buf.dg[f];
    const bool stop = is_velocity(fn(f).kind) && armed_[f];
    // Contacts and releases switch only when certainly negative (level
    // -2*noise); armed velocities stop at zero.
    const double level = stop ? 0.0 : -2 * noise<scheduled>(f);
    const double step = safe_step(h - level, hd, buf.bound[f]);
    if (!split_) return step;
    // The split bound: the slow part's curvature, the fast modes' amplitude.
    const double hs = side_[f] * buf.slow[f] - buf.fast[f] - level;
    if (!(hs > 0)) return step;
    return std::max(step, safe_step(hs, side_[f] * buf.slow_dg[f], buf.slow_bound[f]));
}

// A sliding velocity whose Newton step s = h / -h' lands on its zero to half
// the time's resolution (B s^2 / (2 |h'|) <= eps |t| / 2: the bound keeps the
// zero within that of tau + s), before any other function can reach its
// trigger level (`horizon`) and within the bound's validity (step_cap): its
// zero is known, and the event is taken there without one more instant to
// find it. True when it was.
template <bool scheduled>
bool SwitchSearch::land(std::size_t f, double tau, double horizon, double step_cap) {
    if (f >= nsw_ || leaving_[f] || !is_velocity(fn(f).kind) || !armed_[f]) return false;
    const double h = side_[f] * buf.g[f], hd = side_[f] * buf.dg[f];
    if (!(hd < 0)) return false;
    const double s = h / -hd;
    if (!(buf.bound[f] * s * s <= -hd * kEps * (std::fabs(seg_.t) + tau)) || s > step_cap) return false;
    if (!(tau + s <= horizon)) return false;
    root_[f] = tau + s;
    take_event<scheduled>(tau + s);
    return true;
}

// ---- find the earliest switch in (0, tau_end] ----
template <bool scheduled>
void SwitchSearch::search() {
    start<scheduled>();
    start_ties<scheduled>();
    const double tau_end = seg_.tau_end;
    double tau = 0.0;  // the instant evaluated last
    for (std::size_t iter = 0;; ++iter) {
        if (iter > 10'000'000) {
            failure_ = "switch search does not converge at t = " + number_text(seg_.t + tau);
            return;
        }
        double tau_star = kInf;
        if (!scan<scheduled>(iter, tau, tau_star)) return;
        if (tau_star < kInf) {
            take_event<scheduled>(tau_star);
            break;
        }
        if (tau >= tau_end) break;  // every function was evaluated at tau_end (next_f <= tau_end)
        // Safe step of each function just evaluated: none can reach its
        // trigger level inside it.
        const double step_cap = std::min(seg_.max_step, tau_end - tau);
        const double floor_step = 4 * kEps * (std::fabs(seg_.t) + std::fabs(tau)) + 1e-300;
        double tau_next;
        if (!scheduled) {
            // The smallest step and the one after it (the horizon of the others).
            double step = step_cap, second = step_cap;
            std::size_t first = nsw_;
            for (std::size_t f = 0; f < nsw_; ++f) {
                const double s = own_step<scheduled>(f, tau);
                if (s < step) second = step, step = s, first = f;
                else if (s < second) second = s;
            }
            if (land<scheduled>(first, tau, tau + second, step_cap)) break;
            tau_next = std::min(tau + std::max(step, floor_step), tau_end);
            eval_all<scheduled>(tau_next, false);
        } else {
            // Each function just evaluated is safe up to next_f; the next
            // instant is the earliest next_f. It evaluates the functions due
            // by then, and those due soon after: one evaluation of a few more
            // functions is cheaper than an instant more.
            for (std::uint32_t f : due_)
                next_[f] = std::min(tau + std::max(std::min(step_cap, own_step<scheduled>(f, tau)), floor_step), tau_end);
            tau_next = kInf;
            double second = kInf;
            std::size_t first = nsw_;
            for (std::size_t f = 0; f < nsw_; ++f) {
                if (next_[f] < tau_next) second = tau_next, tau_next = next_[f], first = f;
                else if (next_[f] < second) second = next_[f];
            }
            if (first < nsw_ && at_[first] == tau && land<scheduled>(first, tau, second, step_cap)) break;  // evaluated at this instant
            const double by = tau_next + kScheduleAhead * (tau_next - tau);
            due_.clear();
            for (std::size_t f = 0; f < nsw_; ++f)
                if (next_[f] <= by) due_.push_back(static_cast<std::uint32_t>(f));
            eval_due(tau_next);
        }
        tau = tau_next;
        for (std::size_t k = 0, count = evaluated<scheduled>(); k < count; ++k) {
            const std::size_t f = function<scheduled>(k);
            if (is_velocity(fn(f).kind) && !armed_[f] && side_[f] * buf.g[f] > 2 * noise<scheduled>(f)) armed_[f] = 1;
            // Past its clear interval the bound watches it again (a function
            // leaving an exact zero, clear_until = 0, once it is above its rounding).
            if (leaving_[f] && tau >= clear_until_[f] && (clear_until_[f] > 0 || side_[f] * buf.g[f] > 2 * noise<scheduled>(f)))
                leaving_[f] = 0;
        }
    }
    if (!found.any) eval_all<scheduled>(tau_end, true);  // an event's instant was evaluated in full above
}

// Restarts (restart.h): an event that keeps the configuration (a reversal,
// a stop that slides on, a touch) carries the segment's coefficient block
// over, where the configuration has kRestartFrom modes or more, its solver's
// block is the programs' layout and a plan is known (the solver's own, else
// options.restart_plans, asked once per configuration). The rule reads
// nothing a kind of solver decides, so every kind restarts at the same events
// and keeps the same bits.
class Restarts {
public:
    Restarts(const Model& model, const EngineOptions& options)
        : options_(options),
          // Dampers, Jenkins elements and friction pairs never have a plan
          // (restart_plan(), generator/lowering.h): no derivation is asked for one.
          plain_(model.proportional_damping() && model.jenkins.empty() &&
                 std::none_of(model.friction_slots.begin(), model.friction_slots.end(),
                              [](const FrictionSlot& f) { return f.partner != kGround; })) {}

    /// A new configuration, with `free_masses` (an upper bound on its modes).
    void enter(std::size_t free_masses) {
        carried = false;
        asked_ = false;
        free_masses_ = free_masses;
    }
    /// Carries the last segment's block over to S when the rule allows; true when it did.
    bool restart(SegmentSolver& S, const Configuration& cfg, double t, double t_lo, const signed char* sgn_before,
                 const signed char* sgn) {
        if (!carried || !plain_ || !options_.restart_plans || free_masses_ < kRestartFrom) return false;
        double* block = S.coefficient_block();
        if (!block) return false;
        const RestartPlan* plan = S.restart_plan();
        if (!plan && !asked_) {
            auto it = plans_.find(cfg);
            if (it == plans_.end()) {
                std::shared_ptr<const RestartPlan> given = options_.restart_plans(cfg);
                const std::size_t bytes = given ? sizeof(double) * given->vt.size() + 64 * given->modes.size() : 0;
                if (plan_bytes_ + bytes > kPlanBytes) plans_.clear(), plan_bytes_ = 0;
                plan_bytes_ += bytes;
                it = plans_.emplace(cfg, std::move(given)).first;
            }
            asked_plan_ = it->second.get();
            asked_ = true;
        }
        if (!plan) plan = asked_plan_;
        if (!plan || plan->empty() || plan->modes.size() < kRestartFrom) return false;
        restart_coefficients(*plan, block, carried_tau, t, t_lo, sgn_before, sgn);
        return true;
    }

    bool carried = false;      // the last event kept the configuration (and the solver)
    double carried_tau = 0.0;  // its instant in the last segment

private:
    // The plans asked for, kept within kPlanBytes (V is n^2 doubles: 128 kB
    // at 128 masses); beyond it they are dropped and asked for again.
    static constexpr std::size_t kPlanBytes = std::size_t{32} << 20;
    const EngineOptions& options_;
    const bool plain_;
    std::size_t free_masses_ = 0;
    std::map<Configuration, std::shared_ptr<const RestartPlan>> plans_;
    std::size_t plan_bytes_ = 0;
    const RestartPlan* asked_plan_ = nullptr;  // the configuration's, once asked for
    bool asked_ = false;
};

// The state at t0: the masses' positions, then the Jenkins sliders' (the
// model's, else at rest, unstretched: s = u = w^T x).
std::vector<double> initial_positions(const Model& model) {
    std::vector<double> x = model.x0;
    if (model.slider0.size() == model.jenkins.size())
        x.insert(x.end(), model.slider0.begin(), model.slider0.end());
    else
        for (const Jenkins& j : model.jenkins) x.push_back(jenkins::unstretched_slider(j, model.x0.data()));
    return x;
}

// The smallest step is the time's own resolution, 4 eps |t|: a motion whose
// period is not several of them cannot be searched (at t = 1e9 an oscillation
// of 1.4e7 rad/s was stepped over without a row, every value of its gap
// within the rounding that |G'| eps |t| gives it). Refused with a message
// rather than run wrong: rate * step > 1, a period under 2 pi smallest steps.
// "" when the motion can be searched.
std::string too_fast(const Model& model, const Configuration& cfg, double rate, double t) {
    if (!(rate * 4 * kEps * std::fabs(t) > 1.0)) return "";
    std::ostringstream msg;
    msg.precision(3);
    msg << "the motion is too fast for the time resolution at t = " << number_text(t) << ": configuration '"
        << cfg.spec(model) << "' has rates up to " << rate << " 1/s, and the smallest step there is "
        << 4 * kEps * std::fabs(t) << " s (a period must span at least 2 pi of them); "
        << "start nearer t = 0 (t0 shifts the forcing phase only)";
    return msg.str();
}

// (t, t_lo) += tau, the sum kept exactly (Knuth's TwoSum).
void advance_time(double& t, double& t_lo, double tau) {
    const double a = t, b = t_lo + tau;
    const double s = a + b, bb = s - a;
    t_lo = (a - (s - bb)) + (b - bb);
    t = s;
}

}  // namespace

Engine::Engine(const Model& model, SolverProvider& provider) : model_(model), provider_(provider) {}

void refuse_load_steps(const Model& model, const std::string& who) {
    if (model.load_steps.empty()) return;
    throw InputError(who + ": " + model.source +
                     ": [[load_step]] (the load changes at t = " + number_text(model.load_steps.front().t) +
                     "): only simulate runs a load that changes in time; this needs a constant load");
}

void refuse_impacts(const Model& model, const std::string& who) {
    for (const Contact& c : model.contacts)
        if (c.rigid())
            throw InputError(who + ": " + model.source + ": contact '" + c.name +
                             "' is a rigid stop (restitution): it does not take impacts yet; simulate, periodic, "
                             "lyapunov and sweep do");
}

RunSummary Engine::run(const EngineOptions& options, Observer& observer) {
    refuse_load_steps(model_, "hsnc::Engine::run()");
    const std::size_t n = model_.dof();
    RunSummary sum;
    // The state: positions of the masses, then of the Jenkins sliders, and the masses' velocities.
    std::vector<double> x = initial_positions(model_), v = model_.v0;
    const ElementIndex elements(model_);  // the friction decisions' forces visit each mass's own elements
    double t = model_.t0;
    // The segment start is the double-double t + t_lo: t is the representable
    // time that events report, t_lo (|t_lo| <= ulp(t)/2) the rounding of the
    // last event's instant t + tau; the solvers take the forcing phase at
    // t + t_lo (SegmentSolver::setup), so state and forcing refer to one
    // instant (with the phase at t alone, a forced model's contact times were
    // a median 18-26 ulp off the 40-digit reference on seed scenario 1;
    // bench/reference_check.sh). Without it, a switch
    // that resets the state to its switching surface (a velocity reset to 0
    // at a stop or reversal) would restart the motion at the rounded time,
    // and since the rounding of t + tau repeats while tau does (Coulomb
    // half-cycles all last pi/omega), the event times would drift by up to
    // ulp(t)/2 per event, linearly (measured in tests/test_extremes.cpp:
    // 170 ulp of t after 2000 reversals, before t_lo was kept).
    double t_lo = 0.0;
    const double t_end = options.t_end;
    std::vector<signed char> sgn;
    Configuration cfg = entered_configuration(model_, t, x.data(), v.data(), sgn,  // stuck only where v = 0
                                              options.carried ? &*options.carried : nullptr);

    // Per-segment working arrays, sized once for the largest switch list.
    const std::size_t max_switches = model_.max_switches();
    SwitchSearch search(model_, x.size(), max_switches, sum);
    Buffers& buf = search.buf;  // the event state
    const Found& found = search.found;
    Buffers dense(x.size(), n, max_switches);  // trajectory samples, so buf keeps the event state
    std::set<Configuration> visited;
    SwitchGuard guard(options, model_.t0);  // chattering and Zeno

    // Trajectory samples at t0 + k*dt (never accumulated), and t_end (sample_grid.h),
    // or a longer run's grid (EngineOptions::grid_t0).
    const SampleGrid grid = sample_grid(options, model_.t0);
    std::size_t k_next = options.first_sample;
    bool samples_done = !options.samples;

    auto finish = [&](RunStatus status, const std::string& message) {
        sum.status = status;
        sum.message = message;
        sum.t = t;
        sum.x.assign(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(n));  // the masses' (sliders: sum.slider)
        sum.slider.assign(x.begin() + static_cast<std::ptrdiff_t>(n), x.end());
        sum.v = v;
        sum.configuration = cfg;
        sum.configurations = visited.size();
        return sum;
    };

    std::vector<Transition> transitions;
    SegmentSolver* current = nullptr;  // solver of current_cfg
    Configuration current_cfg;
    std::string why;
    std::size_t progress_counter = 0;
    // Segment and switch records for observers that ask for them (the tangent dynamics).
    const bool records = observer.wants_segments();
    Configuration cfg_before;
    std::vector<signed char> sgn_before;  // the friction directions before the last event
    double rate = 0.0;  // fastest_rate(current_cfg)
    Restarts restarts(model_, options);
    while (true) {
        if (!current || cfg != current_cfg) {  // a reversal keeps the configuration: no lookup
            visited.insert(cfg);
            current = &provider_.solver(cfg);
            current_cfg = cfg;
            rate = fastest_rate(model_, cfg);
            std::size_t free_masses = 0;
            for (std::size_t i = 0; i < n; ++i) free_masses += !fixed_in(model_, cfg, i);
            restarts.enter(free_masses);
        }
        if (const std::string fast = too_fast(model_, cfg, rate, t); !fast.empty())
            return finish(RunStatus::failure, fast);
        SegmentSolver& S = *current;
        const bool carried_start = restarts.restart(S, cfg, t, t_lo, sgn_before.data(), sgn.data());
        if (carried_start)
            ++sum.restarts;
        else
            S.setup(t, t_lo, x.data(), v.data(), sgn.data());
        ++sum.segments;
        const std::size_t nsw = S.switches().size();
        const double tau_end = (t_end - t) - t_lo;

        SearchSegment seg;
        seg.solver = &S, seg.switches = &S.switches(), seg.cfg = &cfg, seg.sgn = &sgn, seg.sgn_before = &sgn_before;
        seg.x = x.data(), seg.v = v.data(), seg.t = t, seg.t_lo = t_lo;
        seg.tau_end = tau_end, seg.max_step = S.max_step(), seg.carried_start = carried_start;
        if (const std::string failure = search.run(seg, nsw > 0 && nsw >= options.schedule_from); !failure.empty())
            return finish(RunStatus::failure, failure);

        // ---- dense output up to the event (or t_end) from the closed form ----
        const double t_seg_end = found.any ? t + found.tau : t_end;
        if (!samples_done) {
            while (true) {
                const double tk = grid.time(k_next);
                if (found.any ? tk >= t_seg_end : tk > t_end) break;
                if (tk == t) {
                    // The segment's start state itself, not its modal round trip.
                    observer.on_sample(tk, x.data(), v.data());
                } else {
                    // dense output: not a search evaluation, and buf keeps the event state
                    S.eval(std::max(0.0, (tk - t) - t_lo), dense.state_view());
                    observer.on_sample(tk, dense.x.data(), dense.v.data());
                }
                if (grid.last(k_next)) {
                    samples_done = true;
                    break;
                }
                ++k_next;
            }
        }

        if (records) {
            SegmentRecord rec;
            rec.t = t, rec.t_lo = t_lo, rec.tau = found.any ? found.tau : tau_end;
            rec.cfg = &cfg, rec.sgn = sgn.data(), rec.x = x.data(), rec.v = v.data();
            observer.on_segment(rec);
        }

        // ---- advance to the event instant: the state at tau, the time as t + t_lo ----
        x = buf.x;
        v = buf.v;
        for (std::size_t i = 0; i < n; ++i)
            if (fixed_in(model_, cfg, i)) v[i] = 0.0;
            else if (rides_partner(model_, cfg, i))
                v[i] = v[static_cast<std::size_t>(carrier(model_, cfg, i))];
        if (!found.any) {
            t = t_end;
            break;
        }
        advance_time(t, t_lo, found.tau);

        transitions.clear();
        if (records) cfg_before = cfg;
        sgn_before = sgn;
        if (!apply_switches(model_, t, x.data(), v.data(), buf.a.data(), cfg, sgn, found.switched, transitions, why,
                            &elements))
            return finish(RunStatus::chattering, why);
        restarts.carried = cfg == current_cfg &&  // an impact's velocity jump is no restart's
                           std::none_of(transitions.begin(), transitions.end(),
                                        [](const Transition& tr) { return tr.kind == EventKind::impact; });
        restarts.carried_tau = found.tau;
        if (records) {
            SwitchRecord rec;
            rec.t = t, rec.t_lo = t_lo, rec.switched = &found.switched;
            rec.before = &cfg_before, rec.sgn_before = sgn_before.data();
            rec.after = &cfg, rec.sgn_after = sgn.data(), rec.x = x.data(), rec.v = v.data();
            observer.on_switch(rec);
        }
        for (const Transition& tr : transitions) {
            observer.on_event(t, tr.kind, tr.element, x.data(), v.data());
            ++sum.events;
            guard.event(t);
        }
        if (const RunStatus g = guard.after_switch(t, nsw); g != RunStatus::ok)
            return finish(g, guard.message(cfg.spec(model_)));
        if (options.max_events && sum.events >= options.max_events)
            return finish(RunStatus::max_events, "stopped after " + std::to_string(sum.events) + " events");
        if ((++progress_counter & 255) == 0 && !observer.on_progress(t))
            return finish(RunStatus::stopped, "stopped at t = " + number_text(t));
    }
    return finish(RunStatus::ok, "");
}

}  // namespace hsnc
