// hsnc -- curves of special periodic orbits over two parameters (hsnc sweep
// --continuation --track KIND --param2 Q): folds, period doublings,
// Neimark-Sacker points or grazing orbits continued in (p, q) (the method
// in api/hsnc/sweep.h).
#include "codim_curve.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <utility>

#include <Eigen/LU>

#include "continuation.h"
#include "error.h"
#include "flow.h"
#include "number_text.h"
#include "shooting.h"

namespace hsnc::sweep_detail {
namespace {

constexpr double kTolerance = 1e-10;      // the residual of an accepted orbit (as hsnc::periodic's default)
constexpr double kStepTolerance = 1e-10;  // of the scaled Newton step, for the test function's root
constexpr int kMaxIterations = 10;
constexpr double kSmallestStep = 1e-6;  // of the largest
constexpr double kLargestStateStep = 0.1;
constexpr double kDifference = 1e-7;  // central differences: this of each unknown's scale

enum class Kind { fold, period_doubling, neimark_sacker, grazing };

Kind kind_of(const std::string& name) {
    if (name == "fold") return Kind::fold;
    if (name == "period_doubling") return Kind::period_doubling;
    if (name == "neimark_sacker") return Kind::neimark_sacker;
    return Kind::grazing;
}

// The defining system of the curve at u = (y, p, q): the orbit's residual
// P(y) - y and the test function g (fold: det(M - I); period doubling:
// det(M + I); Neimark-Sacker: the product over pairs i < j of
// (mu_i mu_j - 1), real; grazing: the contact's largest or smallest gap
// function G = u - gap over one period from y).
class System {
public:
    System(const CurveSpec& c, const SweepOptions& o, Kind kind, std::size_t contact, bool largest)
        : c_(c), o_(o), kind_(kind), contact_(contact), largest_(largest), maps_(c.model_at, c.param, 1) {}

    struct Value {
        bool ok = false;
        std::string message;
        Eigen::VectorXd Py;
        Eigen::MatrixXd M;
        double g = 0;
        double residual = INFINITY;
    };

    Value eval(const Eigen::VectorXd& u) {
        const Eigen::Index N = u.size() - 2;
        const double p = u(N), q = u(N + 1);
        const Eigen::VectorXd y = u.head(N);
        Value v;
        const analysis::PeriodMapValue m = maps_.eval(p, q, y);
        if (!m.ok) {
            v.message = m.message;
            return v;
        }
        if (m.singular || !m.M.allFinite()) {
            v.message = "the period map has no derivative there (a grazing switch with zero normal velocity)";
            return v;
        }
        v.Py = m.Py;
        v.M = m.M;
        v.residual = m.residual;
        v.g = kind_ == Kind::grazing ? gap_extreme(p, q, y) : test(m.M);
        v.ok = std::isfinite(v.g);
        if (!v.ok) v.message = "the test function is not finite there";
        return v;
    }

    // The Jacobian of (P(y) - y, g) over u, its columns scaled by D (rows
    // as they are): M - I exact, the rest central differences.
    bool jacobian(const Eigen::VectorXd& u, const Value& at, const Eigen::VectorXd& D, Eigen::MatrixXd& J,
                  std::string& why) {
        const Eigen::Index N = u.size() - 2;
        J.resize(N + 1, N + 2);
        for (Eigen::Index j = 0; j < N + 2; ++j) {
            const double h = kDifference * D(j);
            Eigen::VectorXd a = u, b = u;
            a(j) += h;
            b(j) -= h;
            const Value va = eval(a), vb = eval(b);
            if (!va.ok || !vb.ok) {
                why = va.ok ? vb.message : va.message;
                return false;
            }
            if (j < N)
                J.col(j).head(N) = (at.M.col(j) - Eigen::VectorXd::Unit(N, j)) * D(j);
            else
                J.col(j).head(N) = (va.Py - vb.Py) / (2 * h) * D(j);
            J(N, j) = (va.g - vb.g) / (2 * h) * D(j);
        }
        return true;
    }

    // Newton on (P(y) - y, g, t . (u - predicted)) = 0 from `predicted` (t:
    // the unit normal of the hyperplane, over u scaled by D): true with the
    // point in uk, its value and Jacobian; else false with the reason.
    bool correct(const Eigen::VectorXd& predicted, const Eigen::VectorXd& t, const Eigen::VectorXd& D,
                 Eigen::VectorXd& uk, Value& v, Eigen::MatrixXd& J, int& iterations, std::string& why) {
        const Eigen::Index N = predicted.size() - 2;
        uk = predicted;
        for (iterations = 0;; ++iterations) {
            v = eval(uk);
            if (!v.ok) {
                why = v.message;
                return false;
            }
            if (!jacobian(uk, v, D, J, why)) return false;
            Eigen::MatrixXd A(N + 2, N + 2);
            A.topRows(N + 1) = J;
            A.row(N + 1) = t.transpose();
            Eigen::VectorXd r(N + 2);
            r.head(N) = v.Py - uk.head(N);
            r(N) = v.g;
            r(N + 1) = t.dot((uk - predicted).cwiseQuotient(D));
            const Eigen::VectorXd du = A.fullPivLu().solve(-r);
            if (!du.allFinite()) {
                why = "the Newton step is not finite";
                return false;
            }
            if (v.residual <= kTolerance && du.cwiseAbs().maxCoeff() <= kStepTolerance) return true;
            if (iterations >= kMaxIterations) {
                why = "no convergence in " + std::to_string(kMaxIterations) + " Newton iterations";
                return false;
            }
            uk += du.cwiseProduct(D);
        }
    }

    const Model& model(double p, double q) { return maps_.model(p, q); }
    std::size_t runs() const { return maps_.runs; }

private:
    double test(const Eigen::MatrixXd& M) const {
        const Eigen::Index n = M.rows();
        const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
        if (kind_ == Kind::fold) return (M - I).fullPivLu().determinant();
        if (kind_ == Kind::period_doubling) return (M + I).fullPivLu().determinant();
        const std::vector<std::complex<double>> mu = analysis::floquet_multipliers(M);
        std::complex<double> prod = 1;
        for (std::size_t i = 0; i < mu.size(); ++i)
            for (std::size_t j = i + 1; j < mu.size(); ++j) prod *= mu[i] * mu[j] - 1.0;
        return prod.real();
    }
    double gap_extreme(double p, double q, const Eigen::VectorXd& y) {
        const Model& m = maps_.model(p, q);
        State s = state_of(y, m.dof());
        SweepPoint pt;
        SweepOptions o = o_;
        o.continuation = true;  // the recorder keeps the gaps' extremes
        o.diagram = false;
        o.harmonics = 0;
        record(m, s, o, c_.param + " = " + shortest_text(p), 0, 1, pt);
        if (contact_ >= pt.gap_max.size()) return NAN;
        return largest_ ? pt.gap_max[contact_] : pt.gap_min[contact_];
    }

    const CurveSpec& c_;
    const SweepOptions& o_;
    Kind kind_;
    std::size_t contact_;
    bool largest_;
    PeriodMaps maps_;
};

}  // namespace

std::vector<SweepPoint> run_curve(const Branch& b, const CurveSpec& c, const SweepOptions& o,
                                  const std::function<void(const SweepPoint&, double)>& done, bool* cut) {
    using Clock = std::chrono::steady_clock;
    auto clock = Clock::now();
    auto seconds = [&] {
        const auto now = Clock::now();
        const double s = std::chrono::duration<double>(now - clock).count();
        clock = now;
        return s;
    };
    const Model& first = *b.start_model;
    const std::size_t n = first.dof();
    const auto N = static_cast<Eigen::Index>(2 * n);
    std::vector<SweepPoint> out;
    auto failed = [&](const std::string& reason) {
        out.push_back(failed_start(b, c.start2, reason, n, o.harmonics));
        done(out.back(), seconds());
        return out;
    };

    // ---- the start: the one-parameter branch at q = start2, its first point of the kind ----
    SweepOptions one = o;
    one.track.clear();
    one.diagram = true;
    one.branch_switch = 0;
    const std::vector<SweepPoint> branch = run_continuation(b, one, [](const SweepPoint&, double) {});
    const SweepPoint* found = nullptr;
    for (const SweepPoint& p : branch)
        if (has_label(p.bifurcation, c.kind) && p.failure.empty()) {
            found = &p;
            break;
        }
    if (!found)
        return failed("sweep --track " + c.kind + ": the branch at " + c.param2 + " = " + shortest_text(c.start2) +
                      " from " + b.param + " = " + shortest_text(b.start) + " to " + shortest_text(b.end) +
                      " crosses no " + c.kind +
                      (branch.empty() || branch.back().stop.empty() ? "" : " (" + branch.back().stop + ")"));
    // Grazing: the contact and the extreme that is (closest to) zero there.
    std::size_t contact = 0;
    bool largest = true;
    double smallest = INFINITY;
    for (std::size_t k = 0; k < found->gap_max.size(); ++k)
        for (const bool hi : {true, false}) {
            const double g = std::fabs(hi ? found->gap_max[k] : found->gap_min[k]);
            if (g < smallest) smallest = g, contact = k, largest = hi;
        }
    if (kind_of(c.kind) == Kind::grazing && found->gap_max.empty())
        return failed("sweep --track grazing: the model has no contact");
    System sys(c, o, kind_of(c.kind), contact, largest);

    // Scales: the orbit's largest |x| and |v|, |to - from|, |to2 - from2|.
    Eigen::VectorXd u(N + 2), D(N + 2);
    double sx = 0, sv = 0;
    for (std::size_t i = 0; i < n; ++i) {
        u(static_cast<Eigen::Index>(i)) = found->strobe_x[found->strobe_x.size() - n + i];
        u(static_cast<Eigen::Index>(n + i)) = found->strobe_v[found->strobe_v.size() - n + i];
        sx = std::max(sx, found->xmax[i]);
        sv = std::max(sv, std::fabs(u(static_cast<Eigen::Index>(n + i))));
    }
    u(N) = found->value;
    u(N + 1) = c.start2;
    for (Eigen::Index i = 0; i < N; ++i)
        D(i) = i < static_cast<Eigen::Index>(n) ? (sx > 0 ? sx : 1) : (sv > 0 ? sv : 1);
    D(N) = std::fabs(b.end - b.start);
    D(N + 1) = std::fabs(c.end2 - c.start2);

    std::string why;
    int iterations = 0;
    auto correct = [&](const Eigen::VectorXd& predicted, const Eigen::VectorXd& t, Eigen::VectorXd& uk,
                       System::Value& v,
                       Eigen::MatrixXd& J) { return sys.correct(predicted, t, D, uk, v, J, iterations, why); };

    // The curve's first point: at q = start2 (the hyperplane normal to q).
    Eigen::VectorXd eq = Eigen::VectorXd::Zero(N + 2);
    eq(N + 1) = 1;
    Eigen::VectorXd uk;
    System::Value v;
    Eigen::MatrixXd J;
    if (!correct(u, eq, uk, v, J))
        return failed("sweep --track " + c.kind + ": the " + c.kind + " near " + b.param + " = " +
                      shortest_text(found->value) + " is not found to rounding: " + why +
                      (c.kind != "grazing" && found->bifurcation.find("grazing") != std::string::npos
                           ? " (it lies at a grazing, where the period map has no derivative)"
                           : ""));
    u = uk;

    const double sense2 = c.end2 > c.start2 ? 1.0 : -1.0;
    Eigen::VectorXd t = tangent(J, eq * sense2, Eigen::MatrixXd(0, N + 2));
    const double lo = std::min(b.start, b.end), hi = std::max(b.start, b.end);
    const double lo2 = std::min(c.start2, c.end2), hi2 = std::max(c.start2, c.end2);
    const std::size_t budget = o.max_steps ? o.max_steps : 20 * o.points;
    const double spacing = 1.0 / static_cast<double>(o.points - 1), h_min = spacing * kSmallestStep;
    double h = spacing;
    std::size_t runs_before = 0;
    auto emit = [&](bool first_point) {
        const double p = u(N), q = u(N + 1);
        const Model& m = sys.model(p, q);
        State s = state_of(u.head(N), n);
        SweepPoint pt;
        record(m, s, o, b.param + " = " + shortest_text(p) + ", " + c.param2 + " = " + shortest_text(q), 0, 1, pt);
        pt.value = p;
        pt.value2 = q;
        pt.direction = first_point ? (b.end > b.start ? SweepDirection::up : SweepDirection::down)
                                   : (p >= out.back().value ? SweepDirection::up : SweepDirection::down);
        pt.settled = true;
        pt.multiple = 1;
        pt.periods = sys.runs() - runs_before;
        runs_before = sys.runs();
        pt.branch_start = first_point;
        const std::vector<std::complex<double>> mu = analysis::floquet_multipliers(v.M);
        pt.max_multiplier = mu.empty() ? 0.0 : std::abs(mu.front());
        pt.stable = analysis::orbit_stable(mu, 0);
        pt.bifurcation = c.kind;
        out.push_back(std::move(pt));
        done(out.back(), seconds());
    };
    try {
        emit(true);
    } catch (const RunError& e) {
        return failed(e.what());
    }
    std::string stop;
    while (out.size() < budget) {
        check_cancel(o);
        if (stop_requested(o)) {
            if (cut) *cut = true;
            return out;
        }
        const Eigen::VectorXd us = u.cwiseQuotient(D);
        h = std::max(h_min, std::min(h, kLargestStateStep / std::max(t.head(N).cwiseAbs().maxCoeff(), 1e-300)));
        const Eigen::VectorXd predicted = (us + h * t).cwiseProduct(D);
        if (!correct(predicted, t, uk, v, J)) {
            if (h > h_min) {
                h = std::max(h_min, 0.5 * h);
                continue;
            }
            stop = "sweep --track " + c.kind + ": the curve cannot be followed beyond " + b.param + " = " +
                   shortest_text(u(N)) + ", " + c.param2 + " = " + shortest_text(u(N + 1)) + ": " + why;
            break;
        }
        const Eigen::VectorXd tn = tangent(J, t, Eigen::MatrixXd(0, N + 2));
        if (tn.dot(t) < 0.8 && h > h_min) {
            h = std::max(h_min, 0.5 * h);
            continue;
        }
        if (uk(N) < lo || uk(N) > hi || uk(N + 1) < lo2 || uk(N + 1) > hi2) break;  // it leaves the box
        u = uk;
        // The state scales follow the largest orbit so far, the tangent in the new scales.
        const Eigen::VectorXd D_old = D;
        for (Eigen::Index i = 0; i < N; ++i) {
            const bool velocity = i >= static_cast<Eigen::Index>(n);
            for (Eigen::Index j = velocity ? n : 0; j < (velocity ? N : static_cast<Eigen::Index>(n)); ++j)
                D(i) = std::max(D(i), std::fabs(u(j)));
        }
        t = tn.cwiseProduct(D_old).cwiseQuotient(D).normalized();
        try {
            emit(false);
        } catch (const RunError& e) {
            stop = e.what();
            break;
        }
        if (iterations <= 3)
            h = std::min(spacing, 1.5 * h);
        else if (iterations >= 7)
            h = std::max(h_min, 0.5 * h);
    }
    if (stop.empty() && out.size() >= budget)
        stop = "sweep --track " + c.kind + ": the step budget (" + std::to_string(budget) + " points) ran out at " +
               b.param + " = " + shortest_text(u(N)) + ", " + c.param2 + " = " + shortest_text(u(N + 1));
    if (!stop.empty()) out.back().stop = stop;
    return out;
}

}  // namespace hsnc::sweep_detail
