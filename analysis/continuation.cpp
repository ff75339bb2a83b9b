#include "continuation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>

#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>

#include "assembly.h"
#include "configuration.h"
#include "elements/motion.h"
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

// mu with its `neutral` multipliers closest to +1 (a family's) put just
// inside the unit circle, at 1 - 1e-9.
std::vector<std::complex<double>> neutral_inside(std::vector<std::complex<double>> mu, std::size_t neutral) {
    std::vector<char> done(mu.size(), 0);
    for (std::size_t k = 0; k < neutral; ++k) {
        std::size_t best = mu.size();
        for (std::size_t i = 0; i < mu.size(); ++i)
            if (!done[i] && (best == mu.size() || std::abs(mu[i] - 1.0) < std::abs(mu[best] - 1.0))) best = i;
        if (best == mu.size()) break;
        mu[best] = 1.0 - 1e-9;
        done[best] = 1;
    }
    return mu;
}

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

// The directions of a family of orbits at a point of the branch (stuck
// Jenkins sliders or stuck masses, whose positions any orbit may shift: the
// `neutral` multipliers at +1 of the monodromy M, hsnc/periodic.h), as rows
// over the scaled unknowns u = (y, p) / D: the null vectors of M - I,
// v / D, with 0 for p. The tangent has no component along them: the
// branch does not walk along a family (centre_stuck_family puts each point
// on the family's centred member).
Eigen::MatrixXd family_rows(const Eigen::MatrixXd& M, std::size_t neutral, const Eigen::VectorXd& D) {
    const Eigen::Index N = M.rows(), k = static_cast<Eigen::Index>(neutral);
    Eigen::MatrixXd F = Eigen::MatrixXd::Zero(k, N + 1);
    if (k == 0) return F;
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(M - Eigen::MatrixXd::Identity(N, N), Eigen::ComputeFullV);
    for (Eigen::Index j = 0; j < k; ++j)
        F.row(j).head(N) = svd.matrixV().col(N - 1 - j).cwiseQuotient(D.head(N)).normalized().transpose();
    return F;
}

// family_rows at the orbit whose monodromy is M.
Eigen::MatrixXd family_at(const Eigen::MatrixXd& M, const Eigen::VectorXd& D) {
    return family_rows(M, analysis::family_multipliers(M, analysis::floquet_multipliers(M)), D);
}

// The solution x of A x = b with F x = 0 (F: family rows): A alone (square)
// by LU without a family, else the stacked (consistent) system by a complete
// orthogonal decomposition.
Eigen::VectorXd solve_with_family(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, const Eigen::MatrixXd& F) {
    if (F.rows() == 0) return A.fullPivLu().solve(b);
    Eigen::MatrixXd S(A.rows() + F.rows(), A.cols());
    S << A, F;
    Eigen::VectorXd r = Eigen::VectorXd::Zero(S.rows());
    r.head(b.size()) = b;
    return S.completeOrthogonalDecomposition().solve(r);
}

// The unit tangent of the branch (the null vector of the N x (N + 1)
// Jacobian J with no component along the family rows F), turned the way of
// `previous`.
Eigen::VectorXd tangent(const Eigen::MatrixXd& J, const Eigen::VectorXd& previous, const Eigen::MatrixXd& F) {
    const Eigen::Index N = J.rows();
    Eigen::MatrixXd A(N + 1, N + 1);
    A.topRows(N) = J;
    A.row(N) = previous.transpose();
    Eigen::VectorXd e = Eigen::VectorXd::Zero(N + 1);
    e(N) = 1;
    Eigen::VectorXd t = solve_with_family(A, e, F);
    t.normalize();
    if (t.dot(previous) < 0) t = -t;
    return t;
}

// The state y = (x, v, s) as the sweep carries it (n masses).
State state_of(const Eigen::VectorXd& y, std::size_t n) {
    const double* d = y.data();
    return State{{d, d + n}, {d + n, d + 2 * n}, {d + 2 * n, d + y.size()}};
}

// hsnc::periodic's orbit of `model` from `start` (on the Eigen solver, as
// every point of a sweep), to the residual `tolerance`.
PeriodicResult shoot_orbit(Model model, const State& start, double tolerance) {
    model.x0 = start.x;
    model.v0 = start.v;
    model.slider0 = start.slider;
    PeriodicOptions po;
    po.kernels = KernelChoice::eigen;
    po.tolerance = tolerance;
    return periodic(model, po);
}

// A branch point whose orbit holds every Jenkins element stuck all period,
// every contact in one state and no mass stuck: its family of orbits (each
// slider may sit anywhere, s_j + d_j, the masses shifted by the static
// response dx = K^-1 sum_j k_j w_j d_j) is replaced by its centred member,
// each element's stretch e_j = u_j - s_j symmetric in its slip band
// (max e_j + min e_j = 0): the member a slow sweep drifts to (each slip
// pushes the slider towards it) and where the slipping branch begins. Exact
// (a static shift of a linear orbit); `pt` is recorded again. False, with y
// and pt unchanged, when it does not apply or the point is centred already.
bool centre_stuck_family(const Model& model, const SweepOptions& o, const std::string& what, Eigen::VectorXd& y,
                         SweepPoint& pt) {
    const std::size_t n = model.dof(), nj = model.jenkins.size();
    if (nj == 0 || pt.sticks.size() != n + nj || pt.stretch_max.size() != nj) return false;
    for (std::size_t i = 0; i < n; ++i)
        if (pt.sticks[i]) return false;
    Configuration cfg = Configuration::all_open(model);
    for (std::size_t c = 0; c < model.contacts.size(); ++c) {
        if ((pt.gap_max[c] >= 0) != (pt.gap_min[c] >= 0)) return false;
        cfg.closed[c] = pt.gap_min[c] >= 0;
    }
    const auto J = static_cast<Eigen::Index>(nj), N = static_cast<Eigen::Index>(n);
    Eigen::VectorXd centre(J);
    double size = 0;
    for (std::size_t j = 0; j < nj; ++j) {
        if (!pt.sticks[n + j] || pt.slips[n + j]) return false;
        centre(static_cast<Eigen::Index>(j)) = 0.5 * (pt.stretch_max[j] + pt.stretch_min[j]);
        size = std::max({size, std::fabs(pt.stretch_max[j]), std::fabs(pt.stretch_min[j])});
    }
    if (centre.cwiseAbs().maxCoeff() <= 1e-15 * size) return false;
    const Eigen::FullPivLU<Eigen::MatrixXd> K(stiffness_matrix(model, cfg));
    if (!K.isInvertible()) return false;
    // W: the directions w_j as columns; G d = the stretches' change, W^T dx - d.
    Eigen::MatrixXd W(N, J);
    for (Eigen::Index i = 0; i < N; ++i) {
        Eigen::VectorXd unit = Eigen::VectorXd::Unit(N, i);
        const double* rows[] = {unit.data()};
        for (Eigen::Index j = 0; j < J; ++j)
            W(i, j) = along(model.jenkins[static_cast<std::size_t>(j)].direction(), double_motion(rows), 0);
    }
    Eigen::MatrixXd Wk = W;
    for (Eigen::Index j = 0; j < J; ++j) Wk.col(j) *= model.jenkins[static_cast<std::size_t>(j)].k;
    const Eigen::MatrixXd S = K.solve(Wk);  // dx per unit slider shift
    const Eigen::MatrixXd G = W.transpose() * S - Eigen::MatrixXd::Identity(J, J);
    const Eigen::VectorXd d = G.fullPivLu().solve(-centre);
    if (!d.allFinite()) return false;
    y.head(N) += S * d;
    y.segment(2 * N, J) += d;
    State s = state_of(y, n);
    pt = SweepPoint();
    record(model, s, o, what, 0, 1, pt);
    return true;
}

// The state y = (x, v, s) of an orbit hsnc::periodic found.
Eigen::VectorXd orbit_state(const PeriodicResult& r) {
    const std::size_t n = r.x.size();
    Eigen::VectorXd y(static_cast<Eigen::Index>(2 * n + r.s.size()));
    for (std::size_t i = 0; i < n; ++i)
        y(static_cast<Eigen::Index>(i)) = r.x[i], y(static_cast<Eigen::Index>(n + i)) = r.v[i];
    for (std::size_t j = 0; j < r.s.size(); ++j) y(static_cast<Eigen::Index>(2 * n + j)) = r.s[j];
    return y;
}

// Beyond a non-smooth transition where the corrector fails at the smallest
// step (at a Jenkins element's slip onset the orbit touches the slip force:
// the period map's derivative jumps there and Newton stalls): the orbit a
// little further on, dp in the direction the parameter moves (`direction`: the
// tangent's parameter component), by a sweep point's transient from the last
// orbit, then shooting. It reaches stable orbits only. True with (pk, yk, v)
// as a converged corrector leaves them.
bool jump_over(const Branch& b, const SweepOptions& o, PeriodMaps& maps, double p, const Eigen::VectorXd& y,
               double direction, double dp, double& pk, Eigen::VectorXd& yk, analysis::PeriodMapValue& v) {
    const double lo = std::min(b.start, b.end), hi = std::max(b.start, b.end);
    const double target = std::clamp(direction >= 0 ? p + dp : p - dp, lo, hi);
    if (target == p) return false;
    try {
        const Model& m = maps.model(target);
        State s = state_of(y, m.dof());
        run_point(m, s, o, b.param + " = " + shortest_text(target) + b.where);
        const PeriodicResult r = shoot_orbit(m, s, kTolerance);
        if (r.status != PeriodicStatus::ok) return false;
        const Eigen::VectorXd orbit = orbit_state(r);
        const analysis::PeriodMapValue at = maps.eval(target, orbit);
        if (!at.ok || at.singular || !(at.residual <= kTolerance)) return false;
        pk = target;
        yk = orbit;
        v = at;
        return true;
    } catch (const InputError&) {
        return false;
    } catch (const RunError&) {
        return false;
    }
}

// An orbit of a branch: the parameter, the state y = (x, v, s) at t0, its multipliers.
struct OrbitAt {
    double p = 0;
    Eigen::VectorXd y;
    std::vector<std::complex<double>> mu;
    std::size_t neutral = 0;
};

// The columns of a branch point from its orbit: the direction the parameter
// moved from `previous` (null: the branch's first point, its direction),
// settled, multiple 1, stability, and the bifurcations crossed since
// `previous`, with `also` ("grazing", or "") joined last.
void branch_point(SweepPoint& pt, const OrbitAt& at, const OrbitAt* previous, const Branch& b, double sense,
                  std::size_t periods, const std::string& also) {
    pt.value = at.p;
    pt.value2 = b.value2;
    pt.direction = previous == nullptr   ? (sense > 0 ? SweepDirection::up : SweepDirection::down)
                   : at.p >= previous->p ? SweepDirection::up
                                         : SweepDirection::down;
    pt.settled = true;
    pt.multiple = 1;
    pt.branch_start = previous == nullptr;
    pt.periods = periods;
    pt.max_multiplier = at.mu.empty() ? 0.0 : std::abs(at.mu.front());
    pt.stable = analysis::orbit_stable(at.mu, at.neutral);  // hsnc/periodic.h
    if (previous) pt.bifurcation = bifurcations_between(previous->mu, at.mu, previous->neutral, at.neutral);
    if (!also.empty()) pt.bifurcation += (pt.bifurcation.empty() ? "" : "+") + also;
}

// Grazing between two orbits of a branch, a (the previous point) and b: a
// contact's largest (or smallest) gap function over the orbit, G = u - gap,
// changes sign (the orbit starts or stops closing, or opening, it), and its
// parameter is located to rounding as a point of the branch: Illinois
// iterations on that extreme, each an orbit shot (to 1e-13) from the chord's
// state at the trial parameter and recorded over one period (the extreme from
// the exact segments, refined to rounding). Returns the grazing points, in
// the order of the branch; empty when none, or when a fold lies between (the
// parameter is then no coordinate of the chord).
class GrazingLocator {
public:
    GrazingLocator(const Branch& b, const SweepOptions& o, PeriodMaps& maps) : b_(b), o_(o), maps_(maps) {}

    std::vector<std::pair<SweepPoint, OrbitAt>> between(const SweepPoint& pa, const OrbitAt& a, const SweepPoint& pb,
                                                        const OrbitAt& b) {
        std::vector<std::pair<SweepPoint, OrbitAt>> found;
        if (a.p == b.p || !bifurcations_between(a.mu, b.mu, a.neutral, b.neutral).empty()) return found;
        for (std::size_t c = 0; c < pa.gap_max.size() && c < pb.gap_max.size(); ++c)
            for (const bool largest : {true, false}) {
                const double fa = largest ? pa.gap_max[c] : pa.gap_min[c], fb = largest ? pb.gap_max[c] : pb.gap_min[c];
                if (!changes_sign(fa, fb)) continue;
                try {
                    found.push_back(locate(a, b, c, largest, fa, fb));
                } catch (const RunError&) {
                    // Not located (no orbit found near the grazing): the branch
                    // goes on and its next row names the crossing (transitions_between).
                } catch (const InputError&) {
                    // The model is not valid at a trial value: the same.
                }
            }
        std::sort(found.begin(), found.end(), [&](const auto& x, const auto& y) {
            return std::fabs(x.second.p - a.p) < std::fabs(y.second.p - a.p);
        });
        return found;
    }

    // Whether a contact's largest or smallest G changes sign from pa to pb.
    static bool crossed(const SweepPoint& pa, const SweepPoint& pb) {
        for (std::size_t c = 0; c < pa.gap_max.size() && c < pb.gap_max.size(); ++c)
            if (changes_sign(pa.gap_max[c], pb.gap_max[c]) || changes_sign(pa.gap_min[c], pb.gap_min[c])) return true;
        return false;
    }

private:
    static bool changes_sign(double fa, double fb) {
        return std::isfinite(fa) && std::isfinite(fb) && (fa < 0) != (fb < 0);
    }

    // The orbit at p (from the chord's state there) recorded over one period.
    std::pair<SweepPoint, OrbitAt> shoot(const OrbitAt& a, const OrbitAt& b, double p) {
        const double s = (p - a.p) / (b.p - a.p);
        const Eigen::VectorXd guess = a.y + s * (b.y - a.y);
        const Model& model = maps_.model(p);
        const State start = state_of(guess, model.dof());
        PeriodicResult r = shoot_orbit(model, start, 1e-13);
        if (r.status != PeriodicStatus::ok) r = shoot_orbit(model, start, kTolerance);  // rounding may hold it above
        if (r.status != PeriodicStatus::ok) throw RunError(r.message);
        OrbitAt at;
        at.p = p;
        at.y = orbit_state(r);
        at.mu = r.multipliers;
        at.neutral = r.neutral;
        State state{r.x, r.v, r.s};
        SweepPoint pt;
        record(model, state, o_, b_.param + " = " + shortest_text(p) + b_.where, 0, 1, pt);
        return {std::move(pt), std::move(at)};
    }

    std::pair<SweepPoint, OrbitAt> locate(const OrbitAt& a, const OrbitAt& b, std::size_t c, bool largest, double fa,
                                          double fb) {
        double pa = a.p, pb = b.p;
        std::pair<SweepPoint, OrbitAt> best;
        double fbest = INFINITY;
        int side = 0;  // Illinois: the end kept twice in a row has its value halved
        for (int it = 0; it < 100; ++it) {
            double p = (pa * fb - pb * fa) / (fb - fa);
            if (!(p > std::min(pa, pb) && p < std::max(pa, pb))) p = 0.5 * (pa + pb);
            auto at = shoot(a, b, p);
            const double f = largest ? at.first.gap_max[c] : at.first.gap_min[c];
            if (std::fabs(f) < fbest) fbest = std::fabs(f), best = at;
            if (f == 0) break;
            if ((f < 0) == (fa < 0)) {
                pa = p, fa = f;
                if (side == -1) fb *= 0.5;
                side = -1;
            } else {
                pb = p, fb = f;
                if (side == 1) fa *= 0.5;
                side = 1;
            }
            // The bracket at the parameter's rounding.
            if (std::fabs(pb - pa) <=
                4 * std::numeric_limits<double>::epsilon() * std::max(std::fabs(pa), std::fabs(pb)))
                break;
        }
        return best;
    }

    const Branch& b_;
    const SweepOptions& o_;
    PeriodMaps& maps_;
};

// The non-smooth transitions between the points a and b of a branch, from
// what their orbits do (SweepPoint::sticks, slips, closings, gap_max,
// gap_min): "stick_onset" when an element sticks somewhere on one orbit and
// nowhere on the other, "slip_onset" the same for slipping, "grazing" when a
// contact's extreme gap changes sign or its closings per period change (unless
// `located`: the grazing is a row of its own), joined by '+'.
std::string transitions_between(const SweepPoint& a, const SweepPoint& b, bool located) {
    std::string out;
    auto add = [&](const char* name) { out += (out.empty() ? "" : "+") + std::string(name); };
    if (a.sticks != b.sticks) add("stick_onset");
    if (a.slips != b.slips) add("slip_onset");
    if (!located && (a.closings != b.closings || GrazingLocator::crossed(a, b))) add("grazing");
    return out;
}

}  // namespace

std::string bifurcations_between(const std::vector<std::complex<double>>& a, const std::vector<std::complex<double>>& b,
                                 std::size_t neutral_a, std::size_t neutral_b) {
    const TestFunctions fa = test_functions(neutral_inside(a, neutral_a)),
                        fb = test_functions(neutral_inside(b, neutral_b));
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
        orbit = shoot_orbit(first, state, kTolerance);
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

    Eigen::VectorXd y = orbit_state(orbit);
    double p = b.start;
    Eigen::MatrixXd M(N, N);
    for (Eigen::Index i = 0; i < N; ++i)
        for (Eigen::Index j = 0; j < N; ++j) M(i, j) = orbit.monodromy[static_cast<std::size_t>(i * N + j)];
    std::vector<std::complex<double>> mu = orbit.multipliers;
    std::size_t neutral = orbit.neutral;  // of mu: a family's multipliers at +1 (hsnc/periodic.h)

    // A point of the branch: the orbit at (p, y) with multipliers mu, one
    // period recorded; before it the grazing points since the last one.
    GrazingLocator grazing(b, o, maps);
    OrbitAt last;
    auto emit = [&](const Model& model, bool first_point, std::size_t periods) {
        SweepPoint pt;
        State s = state_of(y, n);
        record(model, s, o, name(p), 0, 1, pt);
        if (neutral > 0) centre_stuck_family(model, o, name(p), y, pt);  // y moves with it
        const OrbitAt here{p, y, mu, neutral};
        std::string also;  // the non-smooth transitions crossed (a grazing not located among them)
        if (!first_point) {
            auto found = grazing.between(out.back(), last, pt, here);
            also = transitions_between(out.back(), pt, !found.empty());
            for (auto& [g, at] : found) {
                branch_point(g, at, &last, b, sense, 0, "grazing");
                out.push_back(std::move(g));
                done(out.back(), seconds());
                last = at;
            }
        }
        branch_point(pt, here, first_point ? nullptr : &last, b, sense, periods, also);
        last = here;
        out.push_back(std::move(pt));
        done(out.back(), seconds());
    };

    std::string stop;
    const Eigen::VectorXd Pp = parameter_derivative(p, y, stop);
    Eigen::VectorXd t;
    if (stop.empty()) {
        Eigen::VectorXd start_direction = Eigen::VectorXd::Zero(N + 1);
        start_direction(N) = sense;
        t = tangent(jacobian(M, Pp), start_direction, family_rows(M, neutral, D));
    }
    try {
        emit(first, true, transient);
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
        Eigen::VectorXd Pn = parameter_derivative(p_predicted, predicted.head(N).cwiseProduct(D.head(N)), fail);
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
            const Eigen::VectorXd du = solve_with_family(A, -r, family_at(v.M, D));  // no step along a family
            if (!du.allFinite()) {
                fail = "the Newton step is not finite";
                break;
            }
            uk += du;
        }
        if (!converged && h <= h_min &&
            (converged = jump_over(b, o, maps, p, y, t(N), 0.02 * spacing * span, pk, yk, v)))
            Pn = parameter_derivative(pk, yk, fail);  // dP/dp beyond the transition, for the tangent there
        Eigen::VectorXd tn;
        if (converged && pk >= lo && pk <= hi) {
            tn = tangent(jacobian(v.M, Pn), t, family_at(v.M, D));
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
        if (pk < lo || pk > hi) {
            // The branch leaves [from, to]: its last point exactly on the
            // bound, by shooting at that value from the state interpolated there.
            const double bound = pk > hi ? hi : lo;
            finished = true;
            if (bound == p) break;
            const double s = (bound - p) / (pk - p);
            const Eigen::VectorXd guess = y + s * (yk - y);
            try {
                const PeriodicResult end = shoot_orbit(maps.model(bound), state_of(guess, n), kTolerance);
                if (end.status != PeriodicStatus::ok) {
                    stop = "sweep --continuation: shooting fails at " + name(bound) + ": " + end.message;
                    break;
                }
                p = bound;
                y = orbit_state(end);
                mu = end.multipliers;
                neutral = end.neutral;
                emit(maps.model(bound), false, maps.runs - runs_before + end.iterations + 1);
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
            emit(maps.model(p), false, maps.runs - runs_before);
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
