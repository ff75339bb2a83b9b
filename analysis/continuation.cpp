#include "continuation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>

#include <Eigen/LU>

#include "error.h"
#include "flow.h"
#include "hsnc/periodic.h"
#include "number_text.h"
#include "shooting.h"
#include "sweep_point.h"

namespace hsnc::sweep_detail {
namespace {

constexpr const char* kFunction = "hsnc sweep --continuation";
constexpr double kTolerance = 1e-10;     // the residual of an accepted orbit (as hsnc::periodic's default)
constexpr int kMaxIterations = 12;       // Newton iterations of one corrector
constexpr double kMinTurnCosine = 0.8;   // tangents of consecutive points at most ~37 degrees apart
constexpr double kSmallestStep = 1e-6;   // of the largest
constexpr double kDifferenceStep = 1e-6; // of |to - from|: the central difference of dP/dp
constexpr double kLargestStateStep = 0.1;

// The period map at parameter values, a few flows kept (the corrector and
// the central difference come back to the same values).
class PeriodMaps {
public:
    explicit PeriodMaps(const Branch& b) : branch_(b) {}

    // P(y) and dP/dy at p; not ok (with the reason) when the model is invalid at p.
    analysis::PeriodMapValue eval(double p, const Eigen::VectorXd& y) {
        ++runs;
        At* at = nullptr;
        try {
            at = &flow_at(p);
        } catch (const InputError& e) {
            analysis::PeriodMapValue v;
            v.message = std::string("the model is not valid there: ") + e.what();
            return v;
        }
        return analysis::evaluate_period_map(*at->flow, at->model.t0, at->model.t0 + at->period, y);
    }

    // The model at p (InputError when invalid there).
    const Model& model(double p) { return flow_at(p).model; }

    std::size_t runs = 0;  // period-map runs so far

private:
    struct At {
        Model model;
        double period = 0;
        std::unique_ptr<analysis::Flow> flow;
    };
    At& flow_at(double p) {
        auto it = cache_.find(p);
        if (it != cache_.end()) return *it->second;
        if (cache_.size() >= 6) cache_.clear();
        auto at = std::make_unique<At>();
        at->model = branch_.model_at(p);
        at->period = 2 * M_PI / forcing_frequency(at->model, branch_.param + " = " + shortest_text(p));
        // The Eigen solver, as the sweep's own points (sweep_point.cpp): every
        // parameter value is a new model whose configurations are all entered
        // anew, where its analysis in double is the cheapest entry, and
        // threads never wait for each other (the derivation holds the GiNaC lock).
        at->flow = std::make_unique<analysis::Flow>(at->model, analysis::FlowKernels{KernelChoice::eigen, "", true}, kFunction);
        return *(cache_[p] = std::move(at));
    }
    const Branch& branch_;
    std::map<double, std::unique_ptr<At>> cache_;
};

struct TestFunctions {
    int det_minus = 1;    // sign of det(M - I)
    int det_plus = 1;     // sign of det(M + I)
    int bialternate = 1;  // sign of the product over pairs i < j of (mu_i mu_j - 1)
    int complex_outside = 0;  // non-real multipliers with |mu| > 1
};

TestFunctions test_functions(const std::vector<std::complex<double>>& mu) {
    TestFunctions f;
    // Eigen gives real eigenvalues (1 x 1 blocks of the real Schur form) an
    // imaginary part of exactly 0; non-real ones come in conjugate pairs,
    // whose factors multiply to a positive number.
    for (const std::complex<double>& m : mu)
        if (m.imag() == 0) {
            if (m.real() < 1) f.det_minus = -f.det_minus;
            if (m.real() < -1) f.det_plus = -f.det_plus;
        } else if (std::abs(m) > 1) {
            ++f.complex_outside;
        }
    std::complex<double> phase = 1;
    for (std::size_t i = 0; i < mu.size(); ++i)
        for (std::size_t j = i + 1; j < mu.size(); ++j) {
            const std::complex<double> z = mu[i] * mu[j] - 1.0;
            const double a = std::abs(z);
            if (a > 0) phase *= z / a;
        }
    f.bialternate = phase.real() < 0 ? -1 : 1;
    return f;
}

}  // namespace

std::string bifurcations_between(const std::vector<std::complex<double>>& a,
                                 const std::vector<std::complex<double>>& b) {
    const TestFunctions fa = test_functions(a), fb = test_functions(b);
    std::string out;
    auto add = [&](const char* name) { out += (out.empty() ? "" : "+") + std::string(name); };
    if (fa.det_minus != fb.det_minus) add("fold");
    if (fa.det_plus != fb.det_plus) add("period_doubling");
    if (fa.bialternate != fb.bialternate && fa.complex_outside != fb.complex_outside) add("neimark_sacker");
    return out;
}

std::vector<SweepPoint> run_continuation(const Branch& b, const SweepOptions& o,
                                         const std::function<void(const SweepPoint&, double)>& done, bool* cut) {
    using Clock = std::chrono::steady_clock;
    const Model& first = *b.start_model;
    const std::size_t n = first.dof(), nj = first.jenkins.size();
    const Eigen::Index N = static_cast<Eigen::Index>(2 * n + nj);  // y = (x, v, s): the sliders are state too
    // y's lengths (positions and sliders) and velocities.
    auto is_velocity_row = [&](Eigen::Index i) { return i >= static_cast<Eigen::Index>(n) && i < static_cast<Eigen::Index>(2 * n); };
    const double lo = std::min(b.start, b.end), hi = std::max(b.start, b.end), span = hi - lo;
    const double sense = b.end > b.start ? 1.0 : -1.0;
    const std::size_t budget = o.max_steps ? o.max_steps : 20 * o.points;
    // Steps: at most 1/(points - 1) of [from, to] in the parameter and
    // kLargestStateStep of the largest orbit so far in any state component;
    // within that, halved on failure, grown after quick corrections.
    const double spacing = 1.0 / static_cast<double>(o.points - 1), h_min = spacing * kSmallestStep;
    auto name = [&](double p) { return b.param + " = " + shortest_text(p) + b.where; };
    std::vector<SweepPoint> out;
    PeriodMaps maps(b);
    auto clock = Clock::now();
    auto seconds = [&] {
        const auto now = Clock::now();
        const double s = std::chrono::duration<double>(now - clock).count();
        clock = now;
        return s;
    };

    // ---- the first orbit: a sweep point's transient, then shooting ----
    State state{first.x0, first.v0, first.slider0};
    PeriodicResult orbit;
    std::string why;
    std::size_t transient = 0;
    try {
        transient = run_point(first, state, o, name(b.start)).periods;
        Model m = first;
        m.x0 = state.x;
        m.v0 = state.v;
        m.slider0 = state.slider;
        PeriodicOptions po;
        po.kernels = KernelChoice::eigen;
        po.tolerance = kTolerance;
        orbit = periodic(m, po);
        if (orbit.status != PeriodicStatus::ok)
            why = "no periodic orbit of the forcing's period found from the steady state there: " + orbit.message;
    } catch (const RunError& e) {
        why = e.what();
    }
    auto failed_row = [&](const std::string& reason) {
        SweepPoint p;
        p.value = b.start;
        p.value2 = b.value2;
        p.direction = sense > 0 ? SweepDirection::up : SweepDirection::down;
        p.failure = reason;
        p.branch_start = true;
        sweep_detail::mark_failed(p, n, o.harmonics);
        out.push_back(p);
        done(out.back(), seconds());
        return out;
    };
    if (!why.empty()) return failed_row("sweep --continuation at " + name(b.start) + ": " + why);

    // Scales: the first orbit's largest |x| and |v|, and |to - from|.
    Eigen::VectorXd D(N + 1);
    double sx = 0, sv = 0;
    for (std::size_t i = 0; i < n; ++i) sx = std::max(sx, std::fabs(orbit.x[i])), sv = std::max(sv, std::fabs(orbit.v[i]));
    for (double s : orbit.s) sx = std::max(sx, std::fabs(s));
    for (Eigen::Index i = 0; i < N; ++i) D(i) = !is_velocity_row(i) ? (sx > 0 ? sx : 1) : (sv > 0 ? sv : 1);
    D(N) = span;

    // The scaled Jacobian [dP/dy - I, dP/dp] of the residual over u = (y, p) / D.
    auto jacobian = [&](const Eigen::MatrixXd& M, const Eigen::VectorXd& Pp) {
        Eigen::MatrixXd J(N, N + 1);
        for (Eigen::Index i = 0; i < N; ++i) {
            for (Eigen::Index j = 0; j < N; ++j) J(i, j) = (M(i, j) - (i == j ? 1.0 : 0.0)) * D(j) / D(i);
            J(i, N) = Pp(i) * D(N) / D(i);
        }
        return J;
    };
    // dP/dp at (p, y), a central difference.
    auto parameter_derivative = [&](double p, const Eigen::VectorXd& y, std::string& problem) {
        const double d = kDifferenceStep * span;
        const analysis::PeriodMapValue a = maps.eval(p + d, y), c = maps.eval(p - d, y);
        if (!a.ok || !c.ok) {
            problem = "dP/d" + b.param + ": " + (a.ok ? c.message : a.message);
            return Eigen::VectorXd();
        }
        return Eigen::VectorXd((a.Py - c.Py) / (2 * d));
    };
    // The unit tangent of the branch, turned the way of `previous`.
    auto tangent = [&](const Eigen::MatrixXd& J, const Eigen::VectorXd& previous) {
        Eigen::MatrixXd A(N + 1, N + 1);
        A.topRows(N) = J;
        A.row(N) = previous.transpose();
        Eigen::VectorXd e = Eigen::VectorXd::Zero(N + 1);
        e(N) = 1;
        Eigen::VectorXd t = A.fullPivLu().solve(e);
        t.normalize();
        if (t.dot(previous) < 0) t = -t;
        return t;
    };

    Eigen::VectorXd y(N);
    for (std::size_t i = 0; i < n; ++i) y(static_cast<Eigen::Index>(i)) = orbit.x[i], y(static_cast<Eigen::Index>(n + i)) = orbit.v[i];
    for (std::size_t j = 0; j < nj; ++j) y(static_cast<Eigen::Index>(2 * n + j)) = orbit.s[j];
    double p = b.start;
    Eigen::MatrixXd M(N, N);
    for (Eigen::Index i = 0; i < N; ++i)
        for (Eigen::Index j = 0; j < N; ++j) M(i, j) = orbit.monodromy[static_cast<std::size_t>(i * N + j)];
    std::vector<std::complex<double>> mu = orbit.multipliers;
    std::size_t neutral = orbit.neutral;  // of mu: a family's multipliers at +1 (hsnc/periodic.h)

    // A point of the branch: the orbit at (p, y) with multipliers mu, one period recorded.
    auto emit = [&](const Model& model, double previous_p, const std::vector<std::complex<double>>* previous_mu,
                    std::size_t periods) {
        SweepPoint pt;
        State s;
        s.x.assign(y.data(), y.data() + n);
        s.v.assign(y.data() + n, y.data() + 2 * n);
        s.slider.assign(y.data() + 2 * n, y.data() + N);
        record(model, s, o, name(p), 0, 1, pt);
        pt.value = p;
        pt.value2 = b.value2;
        pt.direction = previous_mu == nullptr ? (sense > 0 ? SweepDirection::up : SweepDirection::down)
                       : p >= previous_p     ? SweepDirection::up
                                             : SweepDirection::down;
        pt.settled = true;
        pt.multiple = 1;
        pt.branch_start = previous_mu == nullptr;
        pt.periods = periods;
        pt.max_multiplier = mu.empty() ? 0.0 : std::abs(mu.front());
        pt.stable = analysis::orbit_stable(mu, neutral);  // hsnc/periodic.h
        if (previous_mu) pt.bifurcation = bifurcations_between(*previous_mu, mu);
        out.push_back(std::move(pt));
        done(out.back(), seconds());
    };

    std::string stop;
    const Eigen::VectorXd Pp = parameter_derivative(p, y, stop);
    Eigen::VectorXd t;
    if (stop.empty()) {
        Eigen::VectorXd start_direction = Eigen::VectorXd::Zero(N + 1);
        start_direction(N) = sense;
        t = tangent(jacobian(M, Pp), start_direction);
    }
    try {
        emit(first, p, nullptr, transient);
    } catch (const RunError& e) {
        stop = e.what();
    }
    double h = 1.0;
    std::size_t runs_before = maps.runs;
    bool finished = false;
    while (stop.empty() && out.size() < budget) {
        check_cancel(o);
        if (stop_requested(o)) {  // a graceful stop: the points so far are the branch's result
            if (cut) *cut = true;
            return out;
        }
        Eigen::VectorXd u(N + 1);
        u.head(N) = y.cwiseQuotient(D.head(N));
        u(N) = p / D(N);
        const double cap = std::min(spacing / std::max(std::fabs(t(N)), 1e-300),
                                    kLargestStateStep / std::max(t.head(N).cwiseAbs().maxCoeff(), 1e-300));
        h = std::max(h_min, std::min(h, cap));
        const Eigen::VectorXd predicted = u + h * t;
        // dP/dp at the predicted point: the column of the Newton matrix (a
        // chord) and of the tangent at the new point.
        std::string fail;
        const double p_predicted = predicted(N) * D(N);
        const Eigen::VectorXd Pn = parameter_derivative(p_predicted, predicted.head(N).cwiseProduct(D.head(N)), fail);
        Eigen::VectorXd uk = predicted;
        analysis::PeriodMapValue v;
        bool converged = false;
        int it = 0;
        double last = INFINITY;
        Eigen::VectorXd yk(N);
        double pk = 0;
        for (; Pn.size() > 0; ++it) {
            pk = uk(N) * D(N);
            yk = uk.head(N).cwiseProduct(D.head(N));
            v = maps.eval(pk, yk);
            if (!v.ok) {
                fail = v.message;
                break;
            }
            if (v.singular || !v.M.allFinite()) {
                fail = "the period map has no derivative there (a grazing switch with zero normal velocity)";
                break;
            }
            if (v.residual <= kTolerance) {
                converged = true;
                break;
            }
            if (it >= kMaxIterations) {
                fail = "no convergence in " + std::to_string(kMaxIterations) + " Newton iterations";
                break;
            }
            if (it >= 2 && v.residual >= last) {
                fail = "the Newton residual stops falling at " + shortest_text(v.residual);
                break;
            }
            last = v.residual;
            Eigen::MatrixXd A(N + 1, N + 1);
            A.topRows(N) = jacobian(v.M, Pn);
            A.row(N) = t.transpose();
            Eigen::VectorXd r(N + 1);
            r.head(N) = (v.Py - yk).cwiseQuotient(D.head(N));
            r(N) = t.dot(uk - predicted);
            const Eigen::VectorXd du = A.fullPivLu().solve(-r);
            if (!du.allFinite()) {
                fail = "the Newton step is not finite";
                break;
            }
            uk += du;
        }
        Eigen::VectorXd tn;
        if (converged && pk >= lo && pk <= hi) {
            tn = tangent(jacobian(v.M, Pn), t);
            if (tn.dot(t) < kMinTurnCosine && h > h_min) {
                h = std::max(h_min, 0.5 * h);
                continue;
            }
        }
        if (!converged) {
            if (h > h_min) {
                h = std::max(h_min, 0.5 * h);
                continue;
            }
            stop = "sweep --continuation: shooting fails beyond " + name(p) + " (step " + shortest_text(h) +
                   ", the smallest): " + fail;
            break;
        }
        const double previous_p = p;
        const std::vector<std::complex<double>> previous_mu = mu;
        if (pk < lo || pk > hi) {
            // The branch leaves [from, to]: its last point exactly on the
            // bound, by shooting at that value from the state interpolated there.
            const double bound = pk > hi ? hi : lo;
            finished = true;
            if (bound == p) break;
            const double s = (bound - p) / (pk - p);
            const Eigen::VectorXd guess = y + s * (yk - y);
            try {
                Model m = maps.model(bound);
                m.x0.assign(guess.data(), guess.data() + n);
                m.v0.assign(guess.data() + n, guess.data() + 2 * n);
                m.slider0.assign(guess.data() + 2 * n, guess.data() + N);
                PeriodicOptions po;
                po.kernels = KernelChoice::eigen;
                po.tolerance = kTolerance;
                const PeriodicResult end = periodic(m, po);
                if (end.status != PeriodicStatus::ok) {
                    stop = "sweep --continuation: shooting fails at " + name(bound) + ": " + end.message;
                    break;
                }
                p = bound;
                for (std::size_t i = 0; i < n; ++i)
                    y(static_cast<Eigen::Index>(i)) = end.x[i], y(static_cast<Eigen::Index>(n + i)) = end.v[i];
                for (std::size_t j = 0; j < nj; ++j) y(static_cast<Eigen::Index>(2 * n + j)) = end.s[j];
                mu = end.multipliers;
                neutral = end.neutral;
                emit(maps.model(bound), previous_p, &previous_mu, maps.runs - runs_before + end.iterations + 1);
            } catch (const InputError& e) {
                stop = "sweep --continuation: shooting fails at " + name(bound) + ": " + e.what();
            } catch (const RunError& e) {
                stop = e.what();
            }
            break;
        }
        p = pk;
        y = yk;
        M = v.M;
        t = tn;
        // The state scales follow the largest orbit so far (steps relative
        // to the amplitude), the tangent expressed in the new scales.
        const Eigen::VectorXd D_old = D;
        double mx = 0, mv = 0;
        for (Eigen::Index i = 0; i < N; ++i) (is_velocity_row(i) ? mv : mx) = std::max(is_velocity_row(i) ? mv : mx, std::fabs(y(i)));
        for (Eigen::Index i = 0; i < N; ++i) D(i) = std::max(D(i), is_velocity_row(i) ? mv : mx);
        t = t.cwiseProduct(D_old).cwiseQuotient(D).normalized();
        mu = analysis::floquet_multipliers(M);
        neutral = analysis::family_multipliers(M, mu);
        try {
            emit(maps.model(p), previous_p, &previous_mu, maps.runs - runs_before);
        } catch (const RunError& e) {
            stop = e.what();
            break;
        }
        runs_before = maps.runs;
        if (it <= 3) h = 1.5 * h;
        else if (it >= 7) h = std::max(h_min, 0.5 * h);
    }
    if (stop.empty() && !finished && out.size() >= budget)
        stop = "sweep --continuation: the step budget (" + std::to_string(budget) + " points) ran out at " + name(p) +
               " before the branch reached " + shortest_text(b.end);
    if (!stop.empty() && out.empty()) return failed_row(stop);
    if (!stop.empty()) out.back().stop = stop;
    return out;
}

}  // namespace hsnc::sweep_detail
