#include "continuation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include <Eigen/Eigenvalues>
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

// A branch point whose orbit holds every Jenkins element stuck all period,
// every contact in one state and no mass stuck: its family of orbits (each
// slider may sit anywhere, s_j + d_j, the masses shifted by the static
// response dx = K^-1 sum_j k_j w_j d_j) is replaced by its centred member,
// each element's stretch e_j = u_j - s_j symmetric in its slip band
// (max e_j + min e_j = 0): the member a slow sweep drifts to (each slip
// pushes the slider towards it) and where the slipping branch begins. Exact
// (a static shift of a linear orbit); `pt` is recorded again (`periods`
// forcing periods). False, with y and pt unchanged, when it does not apply or
// the point is centred already.
bool centre_stuck_family(const Model& model, const SweepOptions& o, const std::string& what, std::size_t periods,
                         Eigen::VectorXd& y, SweepPoint& pt) {
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
    // A stuck element is a link with the slider as rest length (jenkins::forces):
    // a unit slider shift loads the masses with its spring's force k along w.
    Eigen::MatrixXd Wk = W;
    for (Eigen::Index j = 0; j < J; ++j) {
        const Jenkins& e = model.jenkins[static_cast<std::size_t>(j)];
        Wk.col(j) *= jenkins::spring_force(e.k, 1.0);
    }
    const Eigen::MatrixXd S = K.solve(Wk);  // dx per unit slider shift
    const Eigen::MatrixXd G = W.transpose() * S - Eigen::MatrixXd::Identity(J, J);
    const Eigen::VectorXd d = G.fullPivLu().solve(-centre);
    if (!d.allFinite()) return false;
    y.head(N) += S * d;
    y.segment(2 * N, J) += d;
    State s = state_of(y, n);
    pt = SweepPoint();
    record(model, s, o, what, 0, periods, pt);
    return true;
}

// Beyond a non-smooth transition where the corrector fails at the smallest
// step (at a Jenkins element's slip onset the orbit touches the slip force:
// the period map's derivative jumps there and Newton stalls): the orbit a
// little further on, dp in the direction the parameter moves (`direction`: the
// tangent's parameter component), by a sweep point's transient from the last
// orbit, then shooting (an orbit of `multiple` periods). It reaches stable
// orbits only. True with (pk, yk, v) as a converged corrector leaves them.
bool jump_over(const Branch& b, const SweepOptions& o, PeriodMaps& maps, int multiple, double p,
               const Eigen::VectorXd& y, double direction, double dp, double& pk, Eigen::VectorXd& yk,
               analysis::PeriodMapValue& v) {
    const double lo = std::min(b.start, b.end), hi = std::max(b.start, b.end);
    const double target = std::clamp(direction >= 0 ? p + dp : p - dp, lo, hi);
    if (target == p) return false;
    try {
        const Model& m = maps.model(target);
        State s = state_of(y, m.dof());
        run_point(m, s, o, b.param + " = " + shortest_text(target) + b.where);
        const PeriodicResult r = shoot_orbit(m, s, kTolerance, multiple);
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

// An orbit of a branch: the parameter, the state y = (x, v, s) at t0, the
// monodromy M over the branch's multiple of the forcing period, its
// multipliers and how many of them belong to a family.
struct OrbitAt {
    double p = 0;
    Eigen::VectorXd y;
    Eigen::MatrixXd M;
    std::vector<std::complex<double>> mu;
    std::size_t neutral = 0;
};

// `labels` ('+'-joined) with `name` (last), without it.
std::string with_label(const std::string& labels, const std::string& name) {
    return has_label(labels, name) ? labels : labels + (labels.empty() ? "" : "+") + name;
}
std::string without_label(const std::string& labels, const std::string& name) {
    std::string out, item;
    std::istringstream in(labels);
    while (std::getline(in, item, '+'))
        if (item != name) out += (out.empty() ? "" : "+") + item;
    return out;
}

// The columns of a branch point from its orbit: the direction the parameter
// moved from `previous` (null: the branch's first point, its direction),
// settled, the multiple, stability, and the bifurcations crossed since
// `previous`, with `also` ("grazing", or "") joined last.
void branch_point(SweepPoint& pt, const OrbitAt& at, const OrbitAt* previous, const Branch& b, double sense,
                  int multiple, std::size_t periods, const std::string& also) {
    pt.value = at.p;
    pt.value2 = b.value2;
    pt.direction = previous == nullptr   ? (sense > 0 ? SweepDirection::up : SweepDirection::down)
                   : at.p >= previous->p ? SweepDirection::up
                                         : SweepDirection::down;
    pt.settled = true;
    pt.multiple = multiple;
    pt.branch_start = previous == nullptr;
    pt.periods = periods;
    pt.max_multiplier = at.mu.empty() ? 0.0 : std::abs(at.mu.front());
    pt.stable = analysis::orbit_stable(at.mu, at.neutral);  // hsnc/periodic.h
    if (previous) pt.bifurcation = bifurcations_between(previous->mu, at.mu, previous->neutral, at.neutral);
    if (!also.empty()) pt.bifurcation += (pt.bifurcation.empty() ? "" : "+") + also;
}

// Points located between two orbits of a branch, a (the previous point) and
// b, each an orbit shot (to 1e-13) from the chord's state at a trial
// parameter and recorded over its period (the branch's `multiple` of the
// forcing period):
// - grazing: a contact's largest (or smallest) gap function over the orbit,
//   G = u - gap, changes sign (the orbit starts or stops closing, or opening,
//   it): Illinois iterations on that extreme (from the exact segments,
//   refined to rounding). When a fold lies between too (the branch turns
//   where the orbit starts or stops touching: at a fold the parameter is no
//   coordinate of the branch), the trial orbits are corrected on the
//   hyperplanes normal to the chord instead (`on_chord`: the continuation's
//   corrector), Illinois on the fraction of the chord. None when another
//   bifurcation lies between.
// - a period doubling: det(M + I) changes sign: Illinois iterations on it,
//   to the parameter's rounding.
// - a stick or slip onset (what sticks or slips differs): bisection on it,
//   to the parameter's rounding.
// A point of branch `b` at p in messages: "omega = 1.2 (up)".
std::string point_name(const Branch& b, double p) {
    return b.param + " = " + shortest_text(p) + b.where;
}

class Locator {
public:
    /// `centre`: a located orbit of a family of stuck orbits is its centred member.
    Locator(const Branch& b, const SweepOptions& o, PeriodMaps& maps, int multiple, bool centre)
        : b_(b), o_(o), maps_(maps), multiple_(multiple), centre_(centre) {}

    /// The corrector along a chord: the orbit (p, y) on the hyperplane through
    /// the scaled predicted point normal to t, none when it does not converge.
    using OnChord = std::function<std::optional<std::pair<double, Eigen::VectorXd>>(const Eigen::VectorXd& predicted,
                                                                                    const Eigen::VectorXd& t)>;

    std::vector<std::pair<SweepPoint, OrbitAt>> grazing(const SweepPoint& pa, const OrbitAt& a, const SweepPoint& pb,
                                                        const OrbitAt& b, const Eigen::VectorXd& D,
                                                        const OnChord& on_chord) {
        std::vector<std::pair<SweepPoint, OrbitAt>> found;
        const std::string between = bifurcations_between(a.mu, b.mu, a.neutral, b.neutral);
        const bool chord = between == "fold";
        if (a.p == b.p || !(between.empty() || chord)) return found;
        for (std::size_t c = 0; c < pa.gap_max.size() && c < pb.gap_max.size(); ++c)
            for (const bool largest : {true, false}) {
                const double fa = largest ? pa.gap_max[c] : pa.gap_min[c], fb = largest ? pb.gap_max[c] : pb.gap_min[c];
                if (!changes_sign(fa, fb)) continue;
                auto g = [&](const std::pair<SweepPoint, OrbitAt>& at) {
                    return largest ? at.first.gap_max[c] : at.first.gap_min[c];
                };
                try {
                    if (chord)
                        found.push_back(illinois(
                            0.0, 1.0, fa, fb, false, [&](double s) { return along_chord(a, b, D, s, on_chord); }, g,
                            [](double x, double z) { return std::fabs(z - x) <= 4 * kEpsilon; }));
                    else
                        found.push_back(illinois(
                            a.p, b.p, fa, fb, false, [&](double p) { return shoot(a, b, p); }, g, rounded));
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

    // The period doubling between a and b: the orbit at the end of the final
    // bracket on b's side (its multiplier just beyond -1 as b's is, so the
    // crossing lies between a and it). Empty when det(M + I) keeps its sign or
    // an orbit on the way is not found.
    std::optional<std::pair<SweepPoint, OrbitAt>> period_doubling(const OrbitAt& a, const OrbitAt& b) {
        const double fa = flip_test(a.M), fb = flip_test(b.M);
        if (a.p == b.p || !((fa < 0) != (fb < 0))) return std::nullopt;
        try {
            return illinois(
                a.p, b.p, fa, fb, true, [&](double p) { return shoot(a, b, p); },
                [](const std::pair<SweepPoint, OrbitAt>& at) { return flip_test(at.second.M); }, rounded);
        } catch (const RunError&) {
            return std::nullopt;
        } catch (const InputError&) {
            return std::nullopt;
        }
    }

    /// The grazings and the first stick or slip onset between a and b, in
    /// the order the branch meets them; each grazing's row says "grazing"
    /// in `bifurcation` (the rest is for the caller to fill in).
    std::vector<std::pair<SweepPoint, OrbitAt>> transitions(const SweepPoint& pa, const OrbitAt& a,
                                                            const SweepPoint& pb, const OrbitAt& b,
                                                            const Eigen::VectorXd& D, const OnChord& on_chord) {
        std::vector<std::pair<SweepPoint, OrbitAt>> found = grazing(pa, a, pb, b, D, on_chord);
        for (auto& g : found) g.first.bifurcation = "grazing";
        if (auto on = onset(pa, a, pb, b)) {
            if (centre_ && on->second.neutral > 0)  // a family of stuck orbits: its centred member
                centre_stuck_family(maps_.model(on->second.p), o_, point_name(b_, on->second.p),
                                    static_cast<std::size_t>(multiple_), on->second.y, on->first);
            found.push_back(std::move(*on));
            std::sort(found.begin(), found.end(), [&](const auto& x, const auto& y) {
                return std::fabs(x.second.p - a.p) < std::fabs(y.second.p - a.p);
            });
        }
        return found;
    }

    // The first stick or slip onset between a and b (an element's or mass's
    // SweepPoint::sticks or slips differ): bisection on whether an orbit
    // still does what a's does, down to the parameter's rounding; the orbit
    // at the end of the last bracket on b's side (just beyond the onset).
    // Empty when none differs, a bifurcation lies between, or an orbit on
    // the way is not found.
    std::optional<std::pair<SweepPoint, OrbitAt>> onset(const SweepPoint& pa, const OrbitAt& a, const SweepPoint& pb,
                                                        const OrbitAt& b) {
        if (a.p == b.p || (pa.sticks == pb.sticks && pa.slips == pb.slips) ||
            !bifurcations_between(a.mu, b.mu, a.neutral, b.neutral).empty())
            return std::nullopt;
        try {
            double lo = a.p, hi = b.p;  // lo does what a does, hi not
            std::optional<std::pair<SweepPoint, OrbitAt>> beyond;
            while (!rounded(lo, hi)) {
                const double p = 0.5 * (lo + hi);
                if (p == lo || p == hi) break;
                auto at = shoot(a, b, p);
                if (at.first.sticks == pa.sticks && at.first.slips == pa.slips)
                    lo = p;
                else
                    hi = p, beyond = std::move(at);
            }
            return beyond;
        } catch (const RunError&) {
            return std::nullopt;
        } catch (const InputError&) {
            return std::nullopt;
        }
    }

    // Whether a contact's largest or smallest G changes sign from pa to pb.
    static bool crossed(const SweepPoint& pa, const SweepPoint& pb) {
        for (std::size_t c = 0; c < pa.gap_max.size() && c < pb.gap_max.size(); ++c)
            if (changes_sign(pa.gap_max[c], pb.gap_max[c]) || changes_sign(pa.gap_min[c], pb.gap_min[c])) return true;
        return false;
    }

    // det(M + I): changes sign where a real multiplier crosses -1.
    static double flip_test(const Eigen::MatrixXd& M) {
        return (M + Eigen::MatrixXd::Identity(M.rows(), M.cols())).fullPivLu().determinant();
    }

private:
    static constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
    // Whether a parameter's bracket [x, z] is down to its rounding.
    static bool rounded(double x, double z) {
        return std::fabs(z - x) <= 4 * kEpsilon * std::max(std::fabs(x), std::fabs(z));
    }

    static bool changes_sign(double fa, double fb) {
        return std::isfinite(fa) && std::isfinite(fb) && (fa < 0) != (fb < 0);
    }

    // The orbit at p (from the chord's state there) recorded over its period.
    std::pair<SweepPoint, OrbitAt> shoot(const OrbitAt& a, const OrbitAt& b, double p) {
        const double s = (p - a.p) / (b.p - a.p);
        return orbit_at(p, a.y + s * (b.y - a.y));
    }

    // The orbit on the hyperplane normal to the chord from a to b at the
    // fraction s of it (scaled by D), recorded over its period.
    std::pair<SweepPoint, OrbitAt> along_chord(const OrbitAt& a, const OrbitAt& b, const Eigen::VectorXd& D, double s,
                                               const OnChord& on_chord) {
        const Eigen::Index N = a.y.size();
        Eigen::VectorXd ua(N + 1), ub(N + 1);
        ua << a.y.cwiseQuotient(D.head(N)), a.p / D(N);
        ub << b.y.cwiseQuotient(D.head(N)), b.p / D(N);
        const auto orbit = on_chord(ua + s * (ub - ua), (ub - ua).normalized());
        if (!orbit) throw RunError("no orbit found on the chord");
        return orbit_at(orbit->first, orbit->second);
    }

    // The orbit at p from `guess`, recorded over its period.
    std::pair<SweepPoint, OrbitAt> orbit_at(double p, const Eigen::VectorXd& guess) {
        const Model& model = maps_.model(p);
        const State start = state_of(guess, model.dof());
        PeriodicResult r = shoot_orbit(model, start, 1e-13, multiple_);
        if (r.status != PeriodicStatus::ok)
            r = shoot_orbit(model, start, kTolerance, multiple_);  // rounding may hold it above
        if (r.status != PeriodicStatus::ok) throw RunError(r.message);
        OrbitAt at;
        at.p = p;
        at.y = orbit_state(r);
        at.M = monodromy_of(r);
        at.mu = r.multipliers;
        at.neutral = r.neutral;
        State state{r.x, r.v, r.s};
        SweepPoint pt;
        record(model, state, o_, point_name(b_, p), 0, static_cast<std::size_t>(multiple_), pt);
        return {std::move(pt), std::move(at)};
    }

    // Illinois iterations on f over a coordinate from pa to pb (values fa, fb
    // of opposite signs; `trial` the orbit at a value) until `close` says the
    // bracket is down to rounding: the orbit of smallest |f|, or (`beyond`)
    // the last one on b's side.
    template <class Trial, class F, class Close>
    std::pair<SweepPoint, OrbitAt> illinois(double pa, double pb, double fa, double fb, bool beyond, Trial trial,
                                            F f_of, Close close) {
        const bool a_negative = fa < 0;
        std::pair<SweepPoint, OrbitAt> best;
        bool have = false;
        double fbest = INFINITY;
        int side = 0;  // the end kept twice in a row has its value halved
        for (int it = 0; it < 100; ++it) {
            double p = (pa * fb - pb * fa) / (fb - fa);
            if (!(p > std::min(pa, pb) && p < std::max(pa, pb))) p = 0.5 * (pa + pb);
            auto at = trial(p);
            const double f = f_of(at);
            const bool on_a = f != 0 && (f < 0) == a_negative;
            if (beyond ? !on_a : std::fabs(f) < fbest) fbest = std::fabs(f), best = at, have = true;
            if (f == 0) break;
            if (on_a) {
                pa = p, fa = f;
                if (side == -1) fb *= 0.5;
                side = -1;
            } else {
                pb = p, fb = f;
                if (side == 1) fa *= 0.5;
                side = 1;
            }
            if (close(pa, pb)) break;
        }
        if (!have) throw RunError("no orbit found on the far side of the crossing");
        return best;
    }

    const Branch& b_;
    const SweepOptions& o_;
    PeriodMaps& maps_;
    int multiple_;
    bool centre_;
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
    if (!located && (a.closings != b.closings || Locator::crossed(a, b))) add("grazing");
    return out;
}

// A branch started at an orbit of several periods (start_periods) that
// reaches an orbit of fewer (a divisor d: P_d(y) = y), as a step across a
// fold can, is no branch of that period any more: check() says so
// (RunError), and the branch stops there.
class ShorterPeriod {
public:
    ShorterPeriod(const Branch& b, int multiple) : multiple_(multiple) {
        for (int d = 1; d < multiple; ++d)
            if (multiple % d == 0) maps_.emplace_back(d, std::make_unique<PeriodMaps>(b, d));
    }

    void check(double p, const Eigen::VectorXd& y, const Eigen::VectorXd& D, const std::string& where) {
        for (auto& [d, maps] : maps_) {
            const analysis::PeriodMapValue v = maps->eval(p, y);
            if (!v.ok || (v.Py - y).cwiseQuotient(D.head(y.size())).cwiseAbs().maxCoeff() > kShorterPeriodTolerance)
                continue;
            const std::string ds = std::to_string(d);
            throw RunError("sweep --continuation at " + where + ": the orbit repeats after " + ds + " forcing period" +
                           (d > 1 ? "s" : "") + ", not only after " + std::to_string(multiple_) +
                           ": the branch reached an orbit of " + ds +
                           " (a fold crossed with too large a step, or a start on an orbit of " + ds +
                           "); more --points, or --start-periods " + ds);
        }
    }

private:
    // How closely (scaled) the orbit must repeat after fewer periods.
    static constexpr double kShorterPeriodTolerance = 1e-6;
    int multiple_;
    std::vector<std::pair<int, std::unique_ptr<PeriodMaps>>> maps_;
};

// A switched branch's watch for its other end, where it goes through its
// parent branch (at a period doubling of that): there the orbit's shift over
// half its period, P_half(y) - y, turns round (the branch is a parabola
// through the parent; beyond it the same orbits come again, each shifted by
// half the period).
class ParentCrossing {
public:
    ParentCrossing(const Branch& b, int multiple) : half_(b, multiple / 2) {}

    // Whether the branch went through its parent since the last call.
    bool through(double p, const Eigen::VectorXd& y, const Eigen::VectorXd& D) {
        const analysis::PeriodMapValue v = half_.eval(p, y);
        Eigen::VectorXd shift;
        if (v.ok) shift = (v.Py - y).cwiseQuotient(D.head(y.size()));
        const bool crossed = shift.size() > 0 && last_.size() > 0 && shift.dot(last_) < 0;
        last_ = shift;
        return crossed;
    }

private:
    PeriodMaps half_;
    Eigen::VectorXd last_;  // the shift at the last point, scaled
};

// Where a branch begins: its first orbit, the scales D of its unknowns
// u = (y, p) / D and its unit tangent there (over u), its multiple of the
// forcing period, the period-map runs the orbit took, and for a branch
// switched onto at a period doubling of `parent` (the branch's index in the
// output), the critical multiplier's eigenvector.
struct BranchStart {
    OrbitAt at;
    Eigen::VectorXd D, t;
    int multiple = 1;
    std::size_t periods = 0;
    std::size_t parent = 0;
    bool switched = false;
    bool skip = false;  // not to be followed (a branch already followed from its other end)
};

// Follows the branches of a continuation: the primary branch and, with
// SweepOptions::branch_switch, those born at its period doublings (each
// followed from the located point along the critical eigenvector, on the map
// over twice the period), depth first, in the order they were found.
class Continuation {
public:
    Continuation(const Branch& b, const SweepOptions& o, const std::function<void(const SweepPoint&, double)>& done,
                 bool* cut)
        : b_(b),
          o_(o),
          done_(done),
          cut_(cut),
          n_(b.start_model->dof()),
          N_(static_cast<Eigen::Index>(2 * n_ + b.start_model->jenkins.size())) {}

    std::vector<SweepPoint> run();

private:
    using Clock = std::chrono::steady_clock;

    std::string name(double p) const { return point_name(b_, p); }
    double seconds() {
        const auto now = Clock::now();
        const double s = std::chrono::duration<double>(now - clock_).count();
        clock_ = now;
        return s;
    }
    void push(SweepPoint pt) {
        out_.push_back(std::move(pt));
        done_(out_.back(), seconds());
    }
    bool is_velocity_row(Eigen::Index i) const {
        return i >= static_cast<Eigen::Index>(n_) && i < static_cast<Eigen::Index>(2 * n_);
    }
    // The scaled Jacobian [dP/dy - I, dP/dp] of the residual over u = (y, p) / D.
    Eigen::MatrixXd jacobian(const Eigen::MatrixXd& M, const Eigen::VectorXd& Pp, const Eigen::VectorXd& D) const {
        Eigen::MatrixXd J(N_, N_ + 1);
        for (Eigen::Index i = 0; i < N_; ++i) {
            for (Eigen::Index j = 0; j < N_; ++j) J(i, j) = (M(i, j) - (i == j ? 1.0 : 0.0)) * D(j) / D(i);
            J(i, N_) = Pp(i) * D(N_) / D(i);
        }
        return J;
    }
    // dP/dp at (p, y), a central difference.
    Eigen::VectorXd parameter_derivative(PeriodMaps& maps, double p, const Eigen::VectorXd& y,
                                         std::string& problem) const {
        const double d = kDifferenceStep * std::fabs(b_.end - b_.start);
        const analysis::PeriodMapValue a = maps.eval(p + d, y), c = maps.eval(p - d, y);
        if (!a.ok || !c.ok) {
            problem = "dP/d" + b_.param + ": " + (a.ok ? c.message : a.message);
            return {};
        }
        return (a.Py - c.Py) / (2 * d);
    }

    std::vector<SweepPoint> failed_row(const std::string& reason);
    // The primary branch's first tangent: the way of the task's direction
    // (empty, with the reason in `stop`, when dP/dp cannot be had).
    Eigen::VectorXd first_tangent(PeriodMaps& maps, const BranchStart& s, std::string& stop) const {
        const Eigen::VectorXd Pp = parameter_derivative(maps, s.at.p, s.at.y, stop);
        if (!stop.empty()) return {};
        Eigen::VectorXd direction = Eigen::VectorXd::Zero(N_ + 1);
        direction(N_) = b_.end > b_.start ? 1.0 : -1.0;
        return tangent(jacobian(s.at.M, Pp, s.D), direction, family_rows(s.at.M, s.at.neutral, s.D));
    }
    // A corrector's outcome: converged (else why not in `fail`) at (p, y)
    // with the map's value there, dP/dp of the Newton matrix, iterations taken.
    struct Corrected {
        bool converged = false;
        std::string fail;
        double p = 0;
        Eigen::VectorXd y, Pp;
        analysis::PeriodMapValue v;
        int iterations = 0;
    };
    Corrected correct(PeriodMaps& maps, const Eigen::VectorXd& predicted, const Eigen::VectorXd& t,
                      const Eigen::VectorXd& D) const;
    void follow(const BranchStart& start, std::vector<BranchStart>* siblings);
    std::string push_located(std::vector<std::pair<SweepPoint, OrbitAt>>& found, bool doubling, bool grazing_located,
                             OrbitAt& last, const SweepPoint& pt, std::size_t index, double sense, int multiple);
    BranchStart switched_start(const OrbitAt& at, const Eigen::VectorXd& D, const Eigen::VectorXd& t_parent,
                               int multiple, std::size_t parent) const;

    const Branch& b_;
    const SweepOptions& o_;
    const std::function<void(const SweepPoint&, double)>& done_;
    bool* cut_;
    std::size_t n_;
    Eigen::Index N_;  // y = (x, v, s): the sliders are state too
    Clock::time_point clock_ = Clock::now();
    std::vector<SweepPoint> out_;
    std::size_t branches_ = 0;  // branches begun
    bool stopped_ = false;      // a graceful stop (SweepOptions::stop)
};

std::vector<SweepPoint> Continuation::failed_row(const std::string& reason) {
    push(failed_start(b_, b_.value2, reason, n_, o_.harmonics));
    return out_;
}

// The start of the branch of twice `multiple` periods born at the period
// doubling `at` of a branch with scales D and tangent t_parent: the orbit
// itself (a fixed point of the doubled map too, whose monodromy is M^2), and
// the tangent along the eigenvector of M's multiplier closest to -1 (the
// doubled map's second null direction there), without its component along
// the parent's tangent (so the corrector's hyperplane does not meet the
// parent branch near the point).
BranchStart Continuation::switched_start(const OrbitAt& at, const Eigen::VectorXd& D, const Eigen::VectorXd& t_parent,
                                         int multiple, std::size_t parent) const {
    BranchStart s;
    s.multiple = 2 * multiple;
    s.parent = parent;
    s.switched = true;
    s.D = D;
    s.at = at;
    s.at.M = at.M * at.M;
    s.at.mu = analysis::floquet_multipliers(s.at.M);
    // The flip multiplier, squared to ~+1, counts as a family's for the
    // bifurcation test of the first step (the new branch leaves it inward or
    // outward: no fold) and for stability (the point is critical: not stable).
    s.at.neutral = at.neutral + 1;
    const Eigen::EigenSolver<Eigen::MatrixXd> es(at.M);
    Eigen::Index k = 0;
    for (Eigen::Index i = 1; i < es.eigenvalues().size(); ++i)
        if (std::abs(es.eigenvalues()(i) + 1.0) < std::abs(es.eigenvalues()(k) + 1.0)) k = i;
    Eigen::VectorXd t = Eigen::VectorXd::Zero(N_ + 1);
    t.head(N_) = es.eigenvectors().col(k).real().cwiseQuotient(D.head(N_));
    t.normalize();
    t -= t.dot(t_parent) * t_parent;
    s.t = t.normalized();
    return s;
}

std::vector<SweepPoint> Continuation::run() {
    const Model& first = *b_.start_model;
    // ---- the first orbit: a sweep point's transient, then shooting (or
    // shooting from the initial state over start_periods) ----
    State state{first.x0, first.v0, first.slider0};
    PeriodicResult orbit;
    std::string why;
    std::size_t transient = 0;
    const int multiple = o_.start_periods > 0 ? static_cast<int>(o_.start_periods) : 1;
    try {
        if (o_.start_periods == 0) transient = run_point(first, state, o_, name(b_.start)).periods;
        orbit = shoot_orbit(first, state, kTolerance, multiple);
        if (orbit.status != PeriodicStatus::ok)
            why =
                (o_.start_periods == 0 ? std::string("no periodic orbit of the forcing's period found from the steady "
                                                     "state there: ")
                                       : "no periodic orbit of " + std::to_string(multiple) +
                                             " forcing periods found from the initial state: ") +
                orbit.message;
    } catch (const RunError& e) {
        why = e.what();
    }
    if (!why.empty()) return failed_row("sweep --continuation at " + name(b_.start) + ": " + why);

    BranchStart s;
    s.multiple = multiple;
    s.periods = transient;
    // Scales: the first orbit's largest |x| and |v|, and |to - from|.
    s.D.resize(N_ + 1);
    double sx = 0, sv = 0;
    for (std::size_t i = 0; i < n_; ++i)
        sx = std::max(sx, std::fabs(orbit.x[i])), sv = std::max(sv, std::fabs(orbit.v[i]));
    for (double v : orbit.s) sx = std::max(sx, std::fabs(v));
    for (Eigen::Index i = 0; i < N_; ++i) s.D(i) = !is_velocity_row(i) ? (sx > 0 ? sx : 1) : (sv > 0 ? sv : 1);
    s.D(N_) = std::fabs(b_.end - b_.start);
    s.at = OrbitAt{b_.start, orbit_state(orbit), monodromy_of(orbit), orbit.multipliers, orbit.neutral};
    follow(s, nullptr);
    return out_;
}

// The Newton corrector from the predicted point u (scaled) on the
// hyperplane through it normal to the tangent t: P(y; p) = y to kTolerance,
// with dP/dp fixed at the prediction (a chord).
Continuation::Corrected Continuation::correct(PeriodMaps& maps, const Eigen::VectorXd& predicted,
                                              const Eigen::VectorXd& t, const Eigen::VectorXd& D) const {
    Corrected c;
    c.Pp = parameter_derivative(maps, predicted(N_) * D(N_), predicted.head(N_).cwiseProduct(D.head(N_)), c.fail);
    Eigen::VectorXd uk = predicted;
    double previous_residual = INFINITY;
    for (; c.Pp.size() > 0; ++c.iterations) {
        c.p = uk(N_) * D(N_);
        c.y = uk.head(N_).cwiseProduct(D.head(N_));
        c.v = maps.eval(c.p, c.y);
        const analysis::PeriodMapValue& v = c.v;
        if (!v.ok) {
            c.fail = v.message;
            break;
        }
        if (v.singular || !v.M.allFinite()) {
            c.fail = "the period map has no derivative there (a grazing switch with zero normal velocity)";
            break;
        }
        if (v.residual <= kTolerance) {
            c.converged = true;
            break;
        }
        if (c.iterations >= kMaxIterations) {
            c.fail = "no convergence in " + std::to_string(kMaxIterations) + " Newton iterations";
            break;
        }
        if (c.iterations >= 2 && v.residual >= previous_residual) {
            c.fail = "the Newton residual stops falling at " + shortest_text(v.residual);
            break;
        }
        previous_residual = v.residual;
        Eigen::MatrixXd A(N_ + 1, N_ + 1);
        A.topRows(N_) = jacobian(v.M, c.Pp, D);
        A.row(N_) = t.transpose();
        Eigen::VectorXd r(N_ + 1);
        r.head(N_) = (v.Py - c.y).cwiseQuotient(D.head(N_));
        r(N_) = t.dot(uk - predicted);
        const Eigen::VectorXd du = solve_with_family(A, -r, family_at(v.M, D));  // no step along a family
        if (!du.allFinite()) {
            c.fail = "the Newton step is not finite";
            break;
        }
        uk += du;
    }
    return c;
}

// Writes the rows located between the branch's last row (its orbit `last`)
// and the point `pt` to come: grazings, a stick or slip onset, or (with
// `doubling`) the period doubling alone, whose columns are already filled
// in; `last` becomes the last of them. Returns the transitions crossed since
// it, for pt's row.
std::string Continuation::push_located(std::vector<std::pair<SweepPoint, OrbitAt>>& found, bool doubling,
                                       bool grazing_located, OrbitAt& last, const SweepPoint& pt, std::size_t index,
                                       double sense, int multiple) {
    SweepPoint before = out_.back();  // the row before each located one
    for (auto& [g, at] : found) {
        if (!doubling) {
            std::string crossed = transitions_between(before, g, grazing_located);
            if (g.bifurcation == "grazing") crossed += (crossed.empty() ? "" : "+") + std::string("grazing");
            branch_point(g, at, &last, b_, sense, multiple, 0, crossed);
        }
        g.branch = index;
        before = g;
        push(std::move(g));
        last = at;
    }
    return transitions_between(before, pt, grazing_located);
}

// Follows one branch from `start` to its end, then the branches born on it.
// `siblings`: the branches born on its parent (a switched branch that ends on
// the parent marks the one starting where it ends: the same branch).
void Continuation::follow(const BranchStart& start, std::vector<BranchStart>* siblings) {
    const int multiple = start.multiple;
    const std::size_t index = branches_++;
    const double lo = std::min(b_.start, b_.end), hi = std::max(b_.start, b_.end);
    const double sense = b_.end > b_.start ? 1.0 : -1.0;
    const std::size_t budget = o_.max_steps ? o_.max_steps : 20 * o_.points;
    // Steps: at most 1/(points - 1) of [from, to] in the parameter and
    // kLargestStateStep of the largest orbit so far in any state component;
    // within that, halved on failure, grown after quick corrections.
    const double spacing = 1.0 / static_cast<double>(o_.points - 1), h_min = spacing * kSmallestStep;
    const double span = hi - lo;
    const std::size_t first_row = out_.size();
    PeriodMaps maps(b_, multiple);
    Locator locate(b_, o_, maps, multiple, !start.switched);
    const bool can_switch = multiple < (1 << o_.branch_switch);
    std::vector<BranchStart> doublings;  // born on this branch
    std::unique_ptr<ParentCrossing> parent = start.switched ? std::make_unique<ParentCrossing>(b_, multiple) : nullptr;

    Eigen::VectorXd D = start.D, y = start.at.y, t = start.t;
    double p = start.at.p;
    Eigen::MatrixXd M = start.at.M;
    std::vector<std::complex<double>> mu = start.at.mu;
    std::size_t neutral = start.at.neutral;

    // A point of the branch: the orbit at (p, y) with multipliers mu, one
    // period recorded; before it the grazing and period-doubling points since
    // the last one. False when the branch ends there (a switched branch back
    // on its parent: its orbit repeats after half its period).
    ShorterPeriod shorter(b_, start.switched ? 1 : multiple);  // a switched branch has its parent's watch

    OrbitAt last;
    std::size_t emitted = 0;
    auto emit = [&](const Model& model, bool first_point, std::size_t periods) {
        shorter.check(p, y, D, name(p));
        SweepPoint pt;
        State s = state_of(y, n_);
        record(model, s, o_, name(p), 0, static_cast<std::size_t>(multiple), pt);
        if (!start.switched && neutral > 0)
            centre_stuck_family(model, o_, name(p), static_cast<std::size_t>(multiple), y, pt);  // y moves with it
        const OrbitAt here{p, y, M, mu, neutral};
        std::string also;  // the non-smooth transitions crossed since the row before (a located grazing not among them)
        bool doubling = false;
        if (!first_point) {
            std::vector<std::pair<SweepPoint, OrbitAt>> found = locate.transitions(
                out_.back(), last, pt, here, D, [&](const Eigen::VectorXd& u, const Eigen::VectorXd& tc) {
                    const Corrected c = correct(maps, u, tc, D);
                    return c.converged ? std::optional(std::pair(c.p, c.y)) : std::nullopt;
                });
            const bool grazing_located =
                std::any_of(found.begin(), found.end(), [](const auto& g) { return g.first.bifurcation == "grazing"; });
            if (can_switch &&
                has_label(bifurcations_between(last.mu, here.mu, last.neutral, here.neutral), "period_doubling"))
                if (auto pd = locate.period_doubling(last, here)) {
                    branch_point(pd->first, pd->second, &last, b_, sense, multiple, 0, "");
                    pd->first.bifurcation = with_label(pd->first.bifurcation, "period_doubling");
                    doublings.push_back(switched_start(pd->second, D, t, multiple, index));
                    found.push_back(std::move(*pd));
                    doubling = true;
                }
            also = push_located(found, doubling, grazing_located, last, pt, index, sense, multiple);
        }
        branch_point(pt, here, first_point ? nullptr : &last, b_, sense, multiple, periods, also);
        if (doubling) pt.bifurcation = without_label(pt.bifurcation, "period_doubling");
        if (first_point && start.switched) pt.stable = false;  // the doubling itself: critical
        if (emitted++ == 1 && start.switched)                  // the first step off the doubling: no fold
            pt.bifurcation = without_label(pt.bifurcation, "fold");
        pt.branch = index;
        bool go_on = true;
        if (parent && !first_point && parent->through(p, y, D)) {
            // The branch ends at its other end; a doubling of the parent
            // found in that step is that end, not to be followed again.
            pt.bifurcation = with_label(without_label(pt.bifurcation, "fold"), "period_doubling");
            go_on = false;
            const double a = std::min(last.p, p), z = std::max(last.p, p), slack = 1e-9 * span;
            for (BranchStart& other : *siblings)
                if (other.multiple == multiple && other.at.p >= a - slack && other.at.p <= z + slack) other.skip = true;
        }
        last = here;
        push(std::move(pt));
        return go_on;
    };

    std::string stop;
    if (t.size() == 0) t = first_tangent(maps, start, stop);  // the primary branch
    try {
        emit(start.switched ? maps.model(p) : *b_.start_model, true, start.periods);
    } catch (const RunError& e) {
        stop = e.what();
    }
    double h = 1.0;
    std::size_t runs_before = maps.runs;
    bool finished = false;
    while (stop.empty() && out_.size() - first_row < budget) {
        check_cancel(o_);
        if (stop_requested(o_)) {  // a graceful stop: the points so far are the branch's result
            if (cut_) *cut_ = true;
            stopped_ = true;
            return;
        }
        Eigen::VectorXd u(N_ + 1);
        u.head(N_) = y.cwiseQuotient(D.head(N_));
        u(N_) = p / D(N_);
        const double cap = std::min(spacing / std::max(std::fabs(t(N_)), 1e-300),
                                    kLargestStateStep / std::max(t.head(N_).cwiseAbs().maxCoeff(), 1e-300));
        h = std::max(h_min, std::min(h, cap));
        const Eigen::VectorXd predicted = u + h * t;
        std::string fail;
        Corrected c = correct(maps, predicted, t, D);
        bool converged = c.converged;
        fail = c.fail;
        double pk = c.p;
        Eigen::VectorXd yk = c.y, Pn = c.Pp;
        analysis::PeriodMapValue v = std::move(c.v);
        const int it = c.iterations;
        if (!converged && h <= h_min &&
            (converged = jump_over(b_, o_, maps, multiple, p, y, t(N_), 0.02 * spacing * span, pk, yk, v)))
            Pn = parameter_derivative(maps, pk, yk, fail);  // dP/dp beyond the transition, for the tangent there
        Eigen::VectorXd tn;
        if (converged && pk >= lo && pk <= hi) {
            tn = tangent(jacobian(v.M, Pn, D), t, family_at(v.M, D));
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
                const PeriodicResult end = shoot_orbit(maps.model(bound), state_of(guess, n_), kTolerance, multiple);
                if (end.status != PeriodicStatus::ok) {
                    stop = "sweep --continuation: shooting fails at " + name(bound) + ": " + end.message;
                    break;
                }
                p = bound;
                y = orbit_state(end);
                M = monodromy_of(end);
                mu = end.multipliers;
                neutral = end.neutral;
                emit(maps.model(bound), false, maps.runs - runs_before + static_cast<std::size_t>(end.iterations) + 1);
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
        for (Eigen::Index i = 0; i < N_; ++i)
            (is_velocity_row(i) ? mv : mx) = std::max(is_velocity_row(i) ? mv : mx, std::fabs(y(i)));
        for (Eigen::Index i = 0; i < N_; ++i) D(i) = std::max(D(i), is_velocity_row(i) ? mv : mx);
        t = t.cwiseProduct(D_old).cwiseQuotient(D).normalized();
        mu = analysis::floquet_multipliers(M);
        neutral = analysis::family_multipliers(M, mu);
        try {
            if (!emit(maps.model(p), false, maps.runs - runs_before)) {
                finished = true;
                break;
            }
        } catch (const RunError& e) {
            stop = e.what();
            break;
        }
        runs_before = maps.runs;
        if (it <= 3) h = 1.5 * h;
        else if (it >= 7) h = std::max(h_min, 0.5 * h);
    }
    if (stop.empty() && !finished && out_.size() - first_row >= budget)
        stop = "sweep --continuation: the step budget (" + std::to_string(budget) + " points) ran out at " + name(p) +
               " before the branch reached " + shortest_text(b_.end);
    if (!stop.empty() && out_.size() == first_row && !start.switched) {
        failed_row(stop);
        return;
    }
    if (!stop.empty() && out_.size() > first_row) out_.back().stop = stop;
    // The branches born here, each followed to its end before the next.
    for (std::size_t i = 0; i < doublings.size() && !stopped_; ++i)
        if (!doublings[i].skip) follow(doublings[i], &doublings);
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
    return Continuation(b, o, done, cut).run();
}

PeriodMaps::PeriodMaps(std::function<Model(double, double)> model_at, std::string param, int multiple)
    : model_at_(std::move(model_at)), param_(std::move(param)), multiple_(multiple) {}

PeriodMaps::PeriodMaps(const Branch& b, int multiple)
    : PeriodMaps([&b](double p, double) { return b.model_at(p); }, b.param, multiple) {}

analysis::PeriodMapValue PeriodMaps::eval(double p, double q, const Eigen::VectorXd& y) {
    ++runs;
    At* at = nullptr;
    try {
        at = &flow_at(p, q);
    } catch (const InputError& e) {
        analysis::PeriodMapValue v;
        v.message = std::string("the model is not valid there: ") + e.what();
        return v;
    }
    return analysis::evaluate_period_map(*at->flow, at->model.t0, at->model.t0 + multiple_ * at->period, y);
}

PeriodMaps::At& PeriodMaps::flow_at(double p, double q) {
    const auto key = std::make_pair(p, q);
    auto it = cache_.find(key);
    if (it != cache_.end()) return *it->second;
    if (cache_.size() >= 6) cache_.clear();
    auto at = std::make_unique<At>();
    at->model = model_at_(p, q);
    at->period = 2 * M_PI / forcing_frequency(at->model, param_ + " = " + shortest_text(p));
    // The Eigen solver, as the sweep's own points (sweep_point.cpp): every
    // parameter value is a new model whose configurations are all entered
    // anew, where its analysis in double is the cheapest entry, and
    // threads never wait for each other (the derivation holds the GiNaC lock).
    at->flow =
        std::make_unique<analysis::Flow>(at->model, analysis::FlowKernels{KernelChoice::eigen, "", true}, kFunction);
    return *(cache_[key] = std::move(at));
}

bool has_label(const std::string& labels, const std::string& name) {
    return ("+" + labels + "+").find("+" + name + "+") != std::string::npos;
}

SweepPoint failed_start(const Branch& b, double value2, const std::string& reason, std::size_t masses,
                        std::size_t harmonics) {
    SweepPoint p;
    p.value = b.start;
    p.value2 = value2;
    p.direction = b.end > b.start ? SweepDirection::up : SweepDirection::down;
    p.failure = reason;
    p.branch_start = true;
    mark_failed(p, masses, harmonics);
    return p;
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
// every point of a sweep), to the residual `tolerance`, of `multiple` forcing periods.
PeriodicResult shoot_orbit(Model model, const State& start, double tolerance, int multiple) {
    model.x0 = start.x;
    model.v0 = start.v;
    model.slider0 = start.slider;
    PeriodicOptions po;
    po.kernels = KernelChoice::eigen;
    po.tolerance = tolerance;
    po.harmonic = multiple;
    return periodic(model, po);
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

// The monodromy of an orbit hsnc::periodic found.
Eigen::MatrixXd monodromy_of(const PeriodicResult& r) {
    const auto N = static_cast<Eigen::Index>(r.x.size() * 2 + r.s.size());
    Eigen::MatrixXd M(N, N);
    for (Eigen::Index i = 0; i < N; ++i)
        for (Eigen::Index j = 0; j < N; ++j) M(i, j) = r.monodromy[static_cast<std::size_t>(i * N + j)];
    return M;
}

}  // namespace hsnc::sweep_detail
