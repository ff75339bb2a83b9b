#include "sweep_point.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>
#include <utility>

#include <Eigen/Eigenvalues>

#include "assembly.h"
#include "engine.h"
#include "error.h"
#include "generic_solver.h"
#include "hsnc/periodic.h"
#include "kernel_mode.h"
#include "modal.h"
#include "number_text.h"

namespace hsnc::sweep_detail {
namespace {

constexpr double kPi = 3.14159265358979323846;
// A repeat over a divisor of the multiple found is awaited when it is this
// close to the tolerance already (run_point).
constexpr double kGhostFactor = 1e3;

// The recorded window's metrics resolve every term of the motion larger than
// this share of its size (SegmentSolver::resolving_rate): a term left out
// changes a metric by about its size, so they hold to about this, relative.
constexpr double kRecordTolerance = 1e-12;

// 6-point Gauss-Legendre on [-1, 1].
constexpr double kGaussNode[6] = {-0.93246951420315202781, -0.66120938646626451366, -0.23861918608319690863,
                                  0.23861918608319690863,  0.66120938646626451366,  0.93246951420315202781};
constexpr double kGaussWeight[6] = {0.17132449237917034504, 0.36076157304813860757, 0.46791393457269104739,
                                    0.46791393457269104739, 0.36076157304813860757, 0.17132449237917034504};

class NullObserver : public Observer {
public:
    void on_sample(double, const double*, const double*) override {}
    void on_event(double, EventKind, int, const double*, const double*) override {}
};

// What the recorded window accumulates, per mass: with K harmonics also the
// integrals of x cos(k theta), x sin(k theta) for k = 2..K (k = 1: sxc, sxs);
// with `extremes` (a continuation's points: its transitions) the extremes of
// every contact's gap and Jenkins element's stretch.
struct Accumulator {
    Accumulator(const Model& m, std::size_t harmonics, bool extremes)
        : xmax(m.dof(), 0.0),
          sxx(m.dof(), 0.0),
          sxc(m.dof(), 0.0),
          sxs(m.dof(), 0.0),
          K(harmonics),
          hc(harmonics > 1 ? m.dof() * (harmonics - 1) : 0, 0.0),
          hs(hc.size(), 0.0),
          gmax(extremes ? m.contacts.size() + m.jenkins.size() : 0, -INFINITY),
          gmin(gmax.size(), INFINITY),
          closings(m.contacts.size(), 0),
          sticks(m.dof() + m.jenkins.size(), 0),
          slips(sticks.size(), 0),
          ck(K + 1),
          sk(K + 1) {}
    std::vector<double> xmax, sxx, sxc, sxs;
    std::size_t K;
    std::vector<double> hc, hs;  // [i * (K - 1) + k - 2]
    double length = 0;           // of the window covered so far
    // The largest and smallest value of every contact's gap function G = u -
    // gap, then of every Jenkins element's stretch (SegmentRecorder::coordinate;
    // empty without `extremes`).
    std::vector<double> gmax, gmin;
    // The configurations the window passes through (SweepPoint::closings,
    // sticks, slips), counted over its segments of positive length.
    std::vector<std::size_t> closings;
    std::vector<char> sticks, slips;
    std::vector<char> first_closed, last_closed;  // of the window's first and last segments

    void configuration(const Configuration& cfg) {
        if (first_closed.empty()) first_closed.assign(cfg.closed.begin(), cfg.closed.end());
        for (std::size_t c = 0; c < cfg.closed.size(); ++c) {
            if (cfg.closed[c] && !(c < last_closed.size() && last_closed[c])) ++closings[c];
        }
        last_closed.assign(cfg.closed.begin(), cfg.closed.end());
        for (std::size_t i = 0; i < cfg.stuck.size(); ++i) (cfg.stuck[i] ? sticks : slips)[i] = 1;
        for (std::size_t j = 0; j < cfg.slip.size(); ++j) (cfg.slip[j] == 0 ? sticks : slips)[cfg.stuck.size() + j] = 1;
    }
    // The closings of a periodic window: a contact closed at both its ends closes once less.
    void close_window() {
        for (std::size_t c = 0; c < closings.size() && c < first_closed.size() && c < last_closed.size(); ++c)
            if (first_closed[c] && last_closed[c] && closings[c] > 0) --closings[c];
    }

    void extreme(std::size_t i, double x) { xmax[i] = std::max(xmax[i], std::fabs(x)); }
    void gap_extreme(std::size_t c, double g) {
        gmax[c] = std::max(gmax[c], g);
        gmin[c] = std::min(gmin[c], g);
    }

    // Adds w x(theta) to the integrals (x: one value per mass).
    void add(double w, double theta, const double* x) {
        const double c = std::cos(theta), sn = std::sin(theta);
        for (std::size_t i = 0; i < sxx.size(); ++i) {
            sxx[i] += w * x[i] * x[i];
            sxc[i] += w * x[i] * c;
            sxs[i] += w * x[i] * sn;
        }
        if (K < 2) return;
        // cos, sin of k theta by the angle-addition recurrence (rounding grows
        // as k eps: 1e-13 at k = 1000).
        ck[1] = c;
        sk[1] = sn;
        for (std::size_t k = 2; k <= K; ++k) {
            ck[k] = ck[k - 1] * c - sk[k - 1] * sn;
            sk[k] = sk[k - 1] * c + ck[k - 1] * sn;
        }
        for (std::size_t i = 0; i < sxx.size(); ++i)
            for (std::size_t k = 2; k <= K; ++k) {
                hc[i * (K - 1) + k - 2] += w * x[i] * ck[k];
                hs[i * (K - 1) + k - 2] += w * x[i] * sk[k];
            }
    }

private:
    std::vector<double> ck, sk;
};

// The exact metrics of the recorded window: every segment the engine starts
// is set up again on a solver of its own (the same Eigen solver, so the
// same trajectory) and integrated once its end is known (the next segment's
// start, or the end of the run).
class SegmentRecorder {
public:
    SegmentRecorder(const Model& model, double omega, double t_window, double h, Accumulator& acc)
        : provider_(model),
          model_(model),
          n_(model.dof()),
          nx_(model.state_size()),
          omega_(omega),
          t_window_(t_window),
          h_(h),
          acc_(acc) {
        const std::size_t ns = model.max_switches();
        x_.resize(nx_);
        v_.resize(n_);
        a_.resize(n_);
        g_.resize(ns);
        dg_.resize(ns);
        b_.resize(ns);
        sc_.resize(ns);
    }

    void start(const Configuration& cfg, double t, double t_lo, const double* x, const double* v,
               const signed char* sgn) {
        if (pending_) finish(t, t_lo);
        pending_ = true;
        cfg_ = cfg;
        t_ = t;
        t_lo_ = t_lo;
        x0_.assign(x, x + nx_);  // the sliders too
        v0_.assign(v, v + n_);
        sgn_.assign(sgn, sgn + n_);
    }

    // The pending segment ends at t_end + t_end_lo.
    void finish(double t_end, double t_end_lo) {
        if (!pending_) return;
        pending_ = false;
        const double length = (t_end - t_) + (t_end_lo - t_lo_);
        if (!(length > 0)) return;
        acc_.configuration(cfg_);
        SegmentSolver& s = provider_.solver(cfg_);
        s.setup(t_, t_lo_, x0_.data(), v0_.data(), sgn_.data());
        solver_ = &s;
        const double offset = (t_ - t_window_) + t_lo_;  // segment start in window time
        eval(0.0);
        for (std::size_t i = 0; i < n_; ++i) acc_.extreme(i, x_[i]);
        gap_extremes();
        double b = 0.0;
        while (b < length) {
            const double a = b;
            b = next_piece(a, length);
            va_ = v_;  // x_, v_, a_ hold the state at a
            // Gauss-Legendre nodes of [a, b].
            const double mid = 0.5 * (a + b), half = 0.5 * (b - a);
            for (int q = 0; q < 6; ++q) {
                const double tau = mid + half * kGaussNode[q];
                eval(tau);
                acc_.add(half * kGaussWeight[q], omega_ * (offset + tau), x_.data());
                for (std::size_t i = 0; i < n_; ++i) acc_.extreme(i, x_[i]);
            }
            // A zero of v_i inside: x_i has an extremum there.
            eval(b);
            vb_ = v_;
            bool searched = false;
            for (std::size_t i = 0; i < n_; ++i)
                if ((va_[i] < 0 && vb_[i] > 0) || (va_[i] > 0 && vb_[i] < 0)) {
                    extremum([&] { return std::pair(v_[i], a_[i]); }, a, b, va_[i]);
                    acc_.extreme(i, x_[i]);
                    searched = true;
                }
            // A zero of a contact's G' or a Jenkins element's stretch rate inside: an extremum there.
            for (std::size_t c = 0; c < acc_.gmax.size(); ++c) {
                const double ra = rate(c, va_.data()), rb = rate(c, vb_.data());
                if ((ra < 0 && rb > 0) || (ra > 0 && rb < 0)) {
                    extremum([&] { return std::pair(rate(c, v_.data()), rate(c, a_.data())); }, a, b, ra);
                    acc_.gap_extreme(c, coordinate(c));
                    searched = true;
                }
            }
            if (searched) eval(b);  // the state at b for the next piece
            for (std::size_t i = 0; i < n_; ++i) acc_.extreme(i, x_[i]);
            gap_extremes();
        }
        acc_.length += length;
    }

private:
    // The end of the piece that starts at a: equal pieces of the stretch
    // [a, length] no longer than the grid step 2 pi/(16 rate) of the terms
    // still present at a (SegmentSolver::resolving_rate; rates only fall as
    // the damped terms decay), or than h_ when the solver cannot say.
    double next_piece(double a, double length) const {
        const double rate = solver_->resolving_rate(a, kRecordTolerance);
        const double top = omega_ * static_cast<double>(std::max<std::size_t>(1, acc_.K));  // the highest harmonic
        const double h = rate < 0 ? h_ : 2 * kPi / (16 * std::max(rate, top));
        const double pieces = std::max(1.0, std::ceil((length - a) / h));
        const double b = a + (length - a) / pieces;
        // A piece below the time's rounding (a rate beyond what the instant can
        // resolve) ends the walk rather than stalling it.
        return pieces == 1.0 || !(b > a) ? length : b;
    }

    void eval(double tau) {
        const SegmentEval out{x_.data(), v_.data(), a_.data(), g_.data(), dg_.data(), b_.data(), sc_.data()};
        solver_->eval(tau, out);
    }

    // The coordinates whose extremes the window keeps: every contact's gap
    // function G, then every Jenkins element's stretch e = u - s (constant,
    // +-F_s/k, while it slips; its rate u' while stuck).
    double coordinate(std::size_t c) const {
        const std::size_t nc = model_.contacts.size();
        if (c < nc) return gap(model_, static_cast<int>(c), x_.data());
        const double* rows[] = {x_.data()};
        return jenkins::stretch(model_.jenkins[c - nc].direction(), x_[n_ + c - nc], double_motion(rows), 0);
    }
    // Its rate from the velocities `v` (or its second derivative from the accelerations).
    double rate(std::size_t c, const double* v) const {
        const std::size_t nc = model_.contacts.size();
        if (c < nc) return gap_rate(model_, static_cast<int>(c), v);
        if (cfg_.slip[c - nc] != 0) return 0.0;  // held at slip F_s / k
        const double* rows[] = {nullptr, v};
        return jenkins::stretch(model_.jenkins[c - nc].direction(), 0.0, double_motion(rows), 1);
    }
    void gap_extremes() {
        for (std::size_t c = 0; c < acc_.gmax.size(); ++c) acc_.gap_extreme(c, coordinate(c));
    }

    // Leaves in x_, v_, a_ the state where a coordinate's rate is zero in
    // (a, b) (its rate at a is va, at b of the other sign); `rate()` gives the
    // rate and its derivative from the state evaluated last. Newton, kept
    // inside a bisection bracket. The coordinate is stationary there, so the
    // error of the root enters it squared.
    template <class Rate>
    void extremum(Rate rate, double a, double b, double va) {
        double lo = a, hi = b;
        const bool rising = va < 0;  // the rate goes from - to +
        double tau = 0.5 * (a + b);
        for (int it = 0; it < 100; ++it) {
            eval(tau);
            const auto [vi, ai] = rate();
            if (vi == 0) break;
            if ((vi < 0) == rising) lo = tau;
            else hi = tau;
            double next = ai != 0 ? tau - vi / ai : 0.5 * (lo + hi);
            if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
            if (std::fabs(next - tau) <= 1e-14 * (b - a) || hi - lo <= 1e-14 * (b - a)) {
                tau = next;
                eval(tau);
                break;
            }
            tau = next;
        }
    }

    GenericSolverProvider provider_;
    const Model& model_;
    std::size_t n_, nx_;
    double omega_, t_window_, h_;
    Accumulator& acc_;
    bool pending_ = false;
    Configuration cfg_;
    double t_ = 0, t_lo_ = 0;
    std::vector<double> x0_, v0_;
    std::vector<signed char> sgn_;
    const SegmentSolver* solver_ = nullptr;
    std::vector<double> x_, v_, a_, g_, dg_, b_, sc_, va_, vb_;
};

// Passes the engine's solvers through, telling the recorder where every
// segment starts.
class RecordingSolver : public SegmentSolver {
public:
    RecordingSolver(SegmentRecorder& rec) : rec_(rec) {}
    void bind(SegmentSolver& inner) { inner_ = &inner; }
    const Configuration& configuration() const override { return inner_->configuration(); }
    const std::vector<SwitchFunction>& switches() const override { return inner_->switches(); }
    using SegmentSolver::setup;
    void setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) override {
        rec_.start(inner_->configuration(), t0, t0_lo, x0, v0, sgn);
        inner_->setup(t0, t0_lo, x0, v0, sgn);
    }
    void eval(double tau, const SegmentEval& out) const override { inner_->eval(tau, out); }
    double max_step() const override { return inner_->max_step(); }

private:
    SegmentRecorder& rec_;
    SegmentSolver* inner_ = nullptr;
};

class RecordingProvider : public SolverProvider {
public:
    RecordingProvider(SolverProvider& inner, SegmentRecorder& rec) : inner_(inner), rec_(rec) {}
    SegmentSolver& solver(const Configuration& cfg) override {
        // The inner reference is valid until the inner provider's next call, as
        // the engine's is until ours: bind it afresh on every call.
        auto& slot = wrappers_[cfg];
        if (!slot) slot = std::make_unique<RecordingSolver>(rec_);
        slot->bind(inner_.solver(cfg));
        return *slot;
    }

private:
    SolverProvider& inner_;
    SegmentRecorder& rec_;
    std::map<Configuration, std::unique_ptr<RecordingSolver>> wrappers_;
};

// The state at the end of every recorded period (samples every T), and the
// slowest impact on each rigid stop (the speed G'- into it, from the state
// after the jump: G'+ = -e G'-; +infinity where the window has none).
class StrobeObserver : public Observer {
public:
    StrobeObserver(const Model& model, SweepPoint& point, std::size_t n, double t_first, bool keep)
        : model_(model),
          point_(point),
          n_(n),
          t_first_(t_first),
          keep_(keep),
          slowest_impact(model.contacts.size(), INFINITY) {}
    void on_sample(double t, const double* x, const double* v) override {
        if (!keep_ || t == t_first_) return;  // the window's start is the last transient period's end
        point_.strobe_t.push_back(t);
        point_.strobe_x.insert(point_.strobe_x.end(), x, x + n_);
        point_.strobe_v.insert(point_.strobe_v.end(), v, v + n_);
    }
    void on_event(double, EventKind kind, int element, const double*, const double* v) override {
        if (kind != EventKind::impact) return;
        const auto c = static_cast<std::size_t>(element);
        const double speed = -gap_rate(model_, element, v) / model_.contacts[c].restitution;
        slowest_impact[c] = std::min(slowest_impact[c], speed);
    }

private:
    const Model& model_;
    SweepPoint& point_;
    std::size_t n_;
    double t_first_;
    bool keep_;

public:
    std::vector<double> slowest_impact;  ///< per contact (read after the run)
};

// A baseline's recorded window from its samples every h (max of the
// samples, trapezoidal integrals), and the stroboscopic samples.
class GridObserver : public Observer {
public:
    GridObserver(const Model& model, Accumulator& acc, SweepPoint& point, std::size_t n, double omega, double t_window,
                 double h, std::size_t per_period, bool keep)
        : model_(model),
          acc_(acc),
          point_(point),
          n_(n),
          omega_(omega),
          t_window_(t_window),
          h_(h),
          per_period_(per_period),
          keep_(keep) {}
    void on_sample(double t, const double* x, const double* v) override {
        const double s = t - t_window_, theta = omega_ * s;
        const double w = count_ == 0 ? 0.5 * h_ : h_;  // trapezoid; the last sample's half is taken back in close()
        for (std::size_t i = 0; i < n_; ++i) acc_.extreme(i, x[i]);
        for (std::size_t c = 0; c < std::min(acc_.gmax.size(), model_.contacts.size()); ++c)
            acc_.gap_extreme(c, gap(model_, static_cast<int>(c), x));
        acc_.add(w, theta, x);
        if (keep_ && count_ > 0 && count_ % per_period_ == 0) {
            point_.strobe_t.push_back(t);
            point_.strobe_x.insert(point_.strobe_x.end(), x, x + n_);
            point_.strobe_v.insert(point_.strobe_v.end(), v, v + n_);
        }
        last_x_.assign(x, x + n_);
        last_t_ = t;
        ++count_;
    }
    void on_event(double, EventKind, int, const double*, const double*) override {}
    void close() {
        acc_.add(-0.5 * h_, omega_ * (last_t_ - t_window_), last_x_.data());
        acc_.length = last_t_ - t_window_;
    }

private:
    const Model& model_;
    Accumulator& acc_;
    SweepPoint& point_;
    std::size_t n_;
    double omega_, t_window_, h_;
    std::size_t per_period_;
    bool keep_;
    std::size_t count_ = 0;
    std::vector<double> last_x_;
    double last_t_ = 0;
};

// An angle in (-pi, pi].
double harmonic_phase(double angle) {
    double a = std::remainder(angle, 2 * kPi);
    if (a <= -kPi) a += 2 * kPi;
    return a;
}

// The norm of a state: max(|x_i|, |v_i|/omega) (v/omega is a length too).
double magnitude(const State& a, double omega) {
    double mag = 0;
    for (std::size_t i = 0; i < a.x.size(); ++i) mag = std::max({mag, std::fabs(a.x[i]), std::fabs(a.v[i]) / omega});
    for (double s : a.slider) mag = std::max(mag, std::fabs(s));
    return mag;
}
double distance(const State& a, const State& b, double omega) {
    double diff = 0;
    for (std::size_t i = 0; i < a.x.size(); ++i)
        diff = std::max({diff, std::fabs(a.x[i] - b.x[i]), std::fabs(a.v[i] - b.v[i]) / omega});
    for (std::size_t j = 0; j < a.slider.size() && j < b.slider.size(); ++j)
        diff = std::max(diff, std::fabs(a.slider[j] - b.slider[j]));
    return diff;
}
// |a - b| <= tol |a|.
bool repeats(const State& a, const State& b, double omega, double tol) {
    return distance(a, b, omega) <= tol * magnitude(a, omega);
}

}  // namespace

double forcing_frequency(const Model& model, const std::string& what) {
    refuse_load_steps(model, what);
    if (model.forcing.empty())
        throw InputError(what + ": the model has no [[forcing]]; a sweep needs one forcing frequency");
    // Several commensurate frequencies (engine orders): their fundamental, the common period's.
    const double omega = forcing_fundamental(model);
    if (std::isnan(omega)) {
        const double a = model.forcing[0].omega;
        double b = a;
        for (const Harmonic& h : model.forcing) b = h.omega != a ? h.omega : b;
        throw InputError(what + ": the forcing's frequencies (" + number_text(a) + " and " + number_text(b) +
                         " rad/s) are not commensurate (no common period with harmonic orders up to 1000); a sweep "
                         "needs a common period (a quasi-periodic response: hsnc simulate --section period:OMEGA "
                         "gives its section and rotation number)");
    }
    return omega;
}

double highest_natural_frequency(const Model& model) {
    Configuration cfg = Configuration::all_open(model);
    std::fill(cfg.closed.begin(), cfg.closed.end(), 1);
    const ModalDecomposition d = modal_analysis(model, cfg);
    double top = 0;
    for (Eigen::Index j = 0; j < d.lambda.size(); ++j) top = std::max(top, d.lambda[j]);
    return std::sqrt(top);
}

namespace {

// A run from `state` at ta to tb (dt, samples, observer as the engine's),
// leaving the end state in `state`; RunError naming `what` when it stops.
void advance(Model& m, State& state, const SweepOptions& o, const std::string& what, double ta, double tb, double dt,
             bool samples, Observer& obs, SolverProvider* p) {
    m.t0 = ta;
    m.x0 = state.x;
    m.v0 = state.v;
    m.slider0 = state.slider;
    EngineOptions eo;
    eo.t_end = tb;
    eo.dt = dt;
    eo.samples = samples;
    RunSummary s;
    if (o.method == Method::hsnc) {
        Engine engine(m, *p);
        s = engine.run(eo, obs);
    } else {
        s = integrate(m, o.method, o.integrator, eo, obs);
    }
    if (s.status != RunStatus::ok)
        throw RunError("sweep: " + what + ": the run stopped: " + run_status_name(s.status) + ": " + s.message);
    state.x = s.x;
    state.v = s.v;
    state.slider = s.slider;
}

}  // namespace

void check_cancel(const SweepOptions& o) {
    if (o.cancel && o.cancel->load(std::memory_order_relaxed)) throw SweepCancelled();
}

void mark_failed(SweepPoint& p, std::size_t masses, std::size_t harmonics) {
    const double nan = std::nan("");
    p.xmax.assign(masses, nan);
    p.xrms.assign(masses, nan);
    p.a1.assign(masses, nan);
    p.amp.assign(masses * harmonics, nan);
    p.phase.assign(masses * harmonics, nan);
}

bool stop_requested(const SweepOptions& o) { return o.stop && o.stop->load(std::memory_order_relaxed); }

void record(const Model& point_model, State& state, const SweepOptions& o, const std::string& what, std::size_t k,
            std::size_t periods, SweepPoint& pt, SolverProvider* provider) {
    Model m = point_model;
    const std::size_t n = m.dof();
    const double omega = forcing_frequency(m, what);
    const double period = 2 * kPi / omega;
    const double t0 = m.t0;
    // The baselines' grid (and the recorder's where a solver cannot say, SegmentRecorder::next_piece):
    // 1/16 of the shortest period present.
    const double ratio = std::max({1.0, highest_natural_frequency(m) / omega, static_cast<double>(o.harmonics)});
    const auto per_period = static_cast<std::size_t>(16 * std::ceil(ratio));
    const double h = period / static_cast<double>(per_period);
    const double tr = t0 + static_cast<double>(k) * period;
    const double te = t0 + static_cast<double>(k + periods) * period;
    const std::size_t K = o.harmonics;
    Accumulator acc(m, K, o.continuation);
    if (o.method == Method::hsnc) {
        std::unique_ptr<SolverProvider> own;
        if (!provider) provider = (own = std::make_unique<GenericSolverProvider>(m)).get();
        SegmentRecorder rec(m, omega, tr, h, acc);
        RecordingProvider recording(*provider, rec);
        StrobeObserver strobe(m, pt, n, tr, o.diagram);
        advance(m, state, o, what, tr, te, period, true, strobe, &recording);
        rec.finish(te, 0.0);
        acc.close_window();
        // An orbit that hits a rigid stop has G = 0 at each impact, its largest
        // G no sign of how near it is to grazing: the slowest impact's speed
        // stands for it (positive; it falls to 0 as the orbit grazes, where
        // the orbit that misses the stop has its largest G rise to 0).
        for (std::size_t c = 0; c < m.contacts.size() && !acc.gmax.empty(); ++c)
            if (m.contacts[c].rigid() && std::isfinite(strobe.slowest_impact[c]))
                acc.gmax[c] = strobe.slowest_impact[c];
        pt.closings = acc.closings;
        pt.sticks = acc.sticks;
        pt.slips = acc.slips;
    } else {
        GridObserver grid(m, acc, pt, n, omega, tr, h, per_period, o.diagram);
        advance(m, state, o, what, tr, te, h, true, grid, nullptr);
        grid.close();
    }
    pt.xmax = acc.xmax;
    pt.xrms.resize(n);
    pt.a1.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        pt.xrms[i] = std::sqrt(acc.sxx[i] / acc.length);
        pt.a1[i] = std::hypot(2 * acc.sxc[i] / acc.length, 2 * acc.sxs[i] / acc.length);
    }
    if (!acc.gmax.empty()) {
        const auto contacts = static_cast<std::ptrdiff_t>(m.contacts.size());
        pt.gap_max.assign(acc.gmax.begin(), acc.gmax.begin() + contacts);
        pt.gap_min.assign(acc.gmin.begin(), acc.gmin.begin() + contacts);
        pt.stretch_max.assign(acc.gmax.begin() + contacts, acc.gmax.end());
        pt.stretch_min.assign(acc.gmin.begin() + contacts, acc.gmin.end());
    }
    pt.amp.resize(n * K);
    pt.phase.resize(n * K);
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t k = 1; k <= K; ++k) {
            const double c = k == 1 ? acc.sxc[i] : acc.hc[i * (K - 1) + k - 2];
            const double s = k == 1 ? acc.sxs[i] : acc.hs[i * (K - 1) + k - 2];
            const double A = 2 * c / acc.length, B = 2 * s / acc.length;
            pt.amp[i * K + k - 1] = std::hypot(A, B);
            // x = A cos(k theta) + B sin(k theta) = amp sin(k theta + atan2(A, B)), theta = omega (t - t_r);
            // omega t_r = omega t0 + 2 pi (whole periods): the phase against sin(k omega t), the
            // forcing's own form (a linear oscillator's phase is arg H).
            pt.phase[i * K + k - 1] = harmonic_phase(std::atan2(A, B) - static_cast<double>(k) * omega * t0);
        }
}

SweepPoint run_point(const Model& point_model, State& state, const SweepOptions& o, const std::string& what) {
    Model m = point_model;  // its t0, x0, v0 move with the runs; solvers do not depend on them
    const double omega = forcing_frequency(m, what);
    const double period = 2 * kPi / omega;
    const double t0 = m.t0;

    std::unique_ptr<SolverProvider> provider;
    if (o.method == Method::hsnc) provider = std::make_unique<GenericSolverProvider>(m);

    SweepPoint pt;
    // ---- transient: whole periods until the stroboscopic state repeats ----
    // s_k, k = 0, 1, ...; the last kSweepMaxMultiple + 1 kept (history.back() is s_k).
    std::vector<State> history{state};
    const std::size_t keep = static_cast<std::size_t>(kSweepMaxMultiple) + 1;
    auto s = [&](std::size_t back) -> const State& { return history[history.size() - 1 - back]; };
    NullObserver none;
    std::size_t k = 0;
    int pending = 0;  // a multiple found while a divisor of it still converged
    while (k < o.max_periods) {
        const double ta = t0 + static_cast<double>(k) * period, tb = t0 + static_cast<double>(k + 1) * period;
        check_cancel(o);
        advance(m, state, o, what, ta, tb, 0.0, false, none, provider.get());
        ++k;
        if (o.escape > 0 &&
            std::any_of(state.x.begin(), state.x.end(), [&](double x) { return !(std::fabs(x) <= o.escape); })) {
            pt.escaped = true;
            break;
        }
        history.push_back(state);
        if (history.size() > keep) history.erase(history.begin());
        const std::size_t last = history.size() - 1;
        int found = 0;
        for (int p = 1; p <= kSweepMaxMultiple && static_cast<std::size_t>(p) <= last && !found; ++p)
            if (repeats(s(0), s(static_cast<std::size_t>(p)), omega, kSweepSettleTolerance)) found = p;
        pending = found;
        if (!found) continue;
        // A transient whose multipliers turn by about 2*pi*q/p per period
        // (a multiplier near -1: p = 2) makes s_k - s_(k-p) small before
        // s_k - s_(k-d) for a divisor d of p, on an orbit of period d. A
        // subharmonic orbit keeps its p points apart; so when s_k and
        // s_(k-d) already agree to 1e3 times the tolerance, the motion runs
        // on (up to max_periods) until they agree to the tolerance: the
        // smallest multiple is reported, not a false subharmonic.
        bool converging = false;
        for (int d = 1; d < found && !converging; ++d)
            converging = found % d == 0 && distance(s(0), s(static_cast<std::size_t>(d)), omega) <=
                                               kGhostFactor * kSweepSettleTolerance * magnitude(s(0), omega);
        if (converging) continue;
        pending = 0;
        pt.settled = true;
        pt.multiple = found;
        break;
    }
    if (pending && !pt.escaped) {  // max_periods reached while a divisor was still converging
        pt.settled = true;
        pt.multiple = pending;
    }
    pt.periods = k;

    record(point_model, state, o, what, k, o.record_periods, pt, provider.get());
    return pt;
}

}  // namespace hsnc::sweep_detail
