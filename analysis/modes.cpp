// Backbones of conservative piecewise-linear models by exact shooting (api/hsnc/modes.h).
#include "hsnc/modes.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include "assembly.h"
#include "configuration.h"
#include "elements/motion.h"
#include "flow.h"
#include "number_text.h"
#include "shooting.h"

namespace hsnc {
namespace {

constexpr const char* kModes = "hsnc::modes";
// The most a step may turn another mode's rotation, rad (see follow()).
constexpr double kMaxTurn = 0.5;
// The longest correction a step may need, against the step (see check_jump()).
constexpr double kMaxCorrection = 0.3;
// Samples of one period that bracket the turning points of the peaks.
constexpr double kPeakSamples = 256;
// A damped branch's first orbit beyond the slip onset: at kAnchor times the onset amplitude, or
// 1.5 times that and so on up to kMaxAnchor (Backbone::reach()).
constexpr double kAnchor = 2.0, kMaxAnchor = 64.0;
// The relative step of the finite differences in T and xi of a damped mode's Newton matrix.
constexpr double kDifference = 1e-7;

// A nonlinear mode here is a family of periodic orbits of a conservative model, or of
// the EPMC system of one with Jenkins elements or viscous damping (the file comment of
// hsnc/modes.h): what neither takes is refused by name.
void refuse_unsupported(const Model& model) {
    const std::string where = std::string(kModes) + "(): " + (model.source.empty() ? model.name : model.source) + ": ";
    auto refuse = [&](const std::string& what) {
        throw InputError(where + what +
                         ": hsnc modes takes springs, masses, contacts, Jenkins elements, friction and viscous "
                         "damping (Rayleigh, dampers, a damping matrix, contact damping); load steps are not "
                         "supported yet");
    };
    if (!model.load_steps.empty()) refuse("[[load_step]] " + model.load_steps.front().name);
    refuse_impacts(model, std::string(kModes) + "()");
}

// Damped modes (EPMC): Jenkins elements, friction or viscous damping of any kind.
bool damped_model(const Model& model) {
    const bool friction = model.any_friction();
    return friction || !model.jenkins.empty() || model.alpha != 0.0 || model.beta != 0.0 ||
           !model.proportional_damping();
}

// The linear limit of a damped mode whose C is not Rayleigh's (dampers, a damping matrix):
// the xi that puts the mode's eigenvalue of (M, C - xi M, K) on the imaginary axis, the
// frequency omega there (lambda = i omega) and its complex position shape. From the undamped
// mode (omega0, `shape` mass-normalised) by the secant method on Re lambda(xi), whose
// derivative is 1/2 to first order (exactly 1/2 with Rayleigh damping, where xi = phi^T C phi);
// the state scaled as the state-space solver's, y = [x; v/s].
struct DampedLinearMode {
    double xi = 0.0, omega = 0.0;
    Eigen::VectorXcd shape;
};
DampedLinearMode damped_linear_mode(const Eigen::MatrixXd& M, const Eigen::MatrixXd& K, const Eigen::MatrixXd& C,
                                    const Eigen::VectorXd& shape, double omega0, const std::string& cfg) {
    const Eigen::Index n = M.rows();
    const Eigen::LLT<Eigen::MatrixXd> llt(M);
    const Eigen::MatrixXd MK = llt.solve(K), MC = llt.solve(C);
    const double s = std::sqrt(MK.diagonal().maxCoeff());
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2 * n, 2 * n);
    A.topRightCorner(n, n) = s * Eigen::MatrixXd::Identity(n, n);
    A.bottomLeftCorner(n, n) = -MK / s;
    A.bottomRightCorner(n, n) = -MC;
    DampedLinearMode d;
    std::complex<double> near(0.0, omega0);
    auto re_lambda = [&](double xi) {  // the eigenvalue nearest the last one, Im > 0
        Eigen::MatrixXd Ax = A;
        Ax.bottomRightCorner(n, n).diagonal().array() += xi;
        const Eigen::EigenSolver<Eigen::MatrixXd> es(Ax);
        if (es.info() != Eigen::Success)
            throw RunError(std::string(kModes) + "(): the state matrix of configuration " + cfg +
                           " has no eigenvalues");
        Eigen::Index best = -1;
        for (Eigen::Index k = 0; k < 2 * n; ++k)
            if (es.eigenvalues()(k).imag() > 0 &&
                (best < 0 || std::abs(es.eigenvalues()(k) - near) < std::abs(es.eigenvalues()(best) - near)))
                best = k;
        if (best < 0)
            throw RunError(std::string(kModes) + "(): the damped mode of configuration " + cfg + " does not oscillate");
        near = es.eigenvalues()(best);
        d.omega = near.imag();
        d.shape = es.eigenvectors().col(best).head(n);
        return near.real();
    };
    double x0 = shape.dot(C * shape), r0 = re_lambda(x0);
    double x1 = x0 - 2 * r0, r1 = r0;
    for (int it = 0; it < 60 && r0 != 0.0; ++it) {
        r1 = re_lambda(x1);
        if (std::fabs(r1) <= 1e-15 * s || r1 == r0) break;
        const double next = x1 - r1 * (x1 - x0) / (r1 - r0);
        x0 = x1;
        r0 = r1;
        x1 = next;
    }
    if (r0 == 0.0) x1 = x0;
    if (!(std::fabs(r1) <= 1e-12 * s))
        throw RunError(std::string(kModes) + "(): the linear limit of the damped mode (configuration " + cfg +
                       ") was not found: Re lambda " + number_text(r1) + " at xi " + number_text(x1));
    d.xi = x1;
    return d;
}

// The model without its Jenkins elements: its equilibrium is the one with every Jenkins spring unstretched.
Model without_jenkins(const Model& model) {
    Model bare = model;
    bare.jenkins.clear();
    bare.slider0.clear();
    return bare;
}

// u = w^T x along an element's direction (direction.h's along() over the positions x).
double along_x(const Direction& d, const Eigen::VectorXd& x) {
    const double* rows[] = {x.data()};
    return along(d, double_motion(rows), 0);
}

// The free model: the harmonic forcing and the base motion left out.
Model free_model(const Model& model) {
    Model work = model;
    work.forcing.clear();
    work.base.clear();
    for (auto& a : work.condensation.amplitude) std::fill(a.begin(), a.end(), 0.0);
    work.t0 = 0.0;
    return work;
}

// K(cfg), the constant force f(cfg) and M: the vector field of a configuration.
class Field {
public:
    explicit Field(const Model& model) : model_(model), M_(mass_matrix(model)), llt_(M_) {}
    const Eigen::MatrixXd& M() const { return M_; }
    // (v, M^-1 (f - K x)) at y = (x, v).
    Eigen::VectorXd operator()(const Configuration& cfg, const Eigen::VectorXd& y) {
        const Eigen::Index n = M_.rows();
        const Parts& p = parts(cfg);
        Eigen::VectorXd f(2 * n);
        f.head(n) = y.segment(n, n);
        f.tail(n) = llt_.solve(p.f - p.K * y.head(n));
        return f;
    }
    const Eigen::MatrixXd& K(const Configuration& cfg) { return parts(cfg).K; }
    const Eigen::VectorXd& f(const Configuration& cfg) { return parts(cfg).f; }

private:
    struct Parts {
        Eigen::MatrixXd K;
        Eigen::VectorXd f;
    };
    const Parts& parts(const Configuration& cfg) {
        auto it = cache_.find(cfg);
        if (it == cache_.end())
            it = cache_.emplace(cfg, Parts{stiffness_matrix(model_, cfg), constant_force(model_, cfg)}).first;
        return it->second;
    }
    const Model& model_;
    Eigen::MatrixXd M_;
    Eigen::LLT<Eigen::MatrixXd> llt_;
    std::map<Configuration, Parts> cache_;
};

// The contacts closed at x (G > 0; G = 0 counts as open).
Configuration configuration_at(const Model& model, const Eigen::VectorXd& x) {
    Configuration cfg = Configuration::all_open(model);
    for (std::size_t c = 0; c < model.contacts.size(); ++c)
        cfg.closed[c] = gap(model, static_cast<int>(c), x.data()) > 0;
    return cfg;
}

// The potential: springs, closed contacts' 1/2 k G^2, minus the constant load's work.
double potential(const Model& model, Field& field, const Eigen::VectorXd& x) {
    const Configuration open = Configuration::all_open(model);
    double V = 0.5 * x.dot(field.K(open) * x) - field.f(open).dot(x);
    for (std::size_t c = 0; c < model.contacts.size(); ++c) {
        const double G = gap(model, static_cast<int>(c), x.data());
        V += contact::energy(model.contacts[c].k, G);
    }
    return V;
}

struct Equilibrium {
    Configuration cfg;
    Eigen::VectorXd x;
    Eigen::VectorXd omega2;  ///< the eigenvalues of (K, M), ascending
    Eigen::MatrixXd shapes;  ///< M-normalised
};

// The static equilibrium: a configuration whose K x = f solution closes
// exactly its closed contacts (from every contact open, closing and opening
// until that holds).
Equilibrium equilibrium(const Model& model, Field& field) {
    const std::string where = std::string(kModes) + "(): " + (model.source.empty() ? model.name : model.source) + ": ";
    Equilibrium e;
    e.cfg = Configuration::all_open(model);
    for (std::size_t round = 0; round <= model.contacts.size() + 1; ++round) {
        const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> ges(field.K(e.cfg), field.M());
        if (ges.info() != Eigen::Success)
            throw RunError(where + "the eigenproblem (K, M) of configuration " + e.cfg.spec(model) + " failed");
        const Eigen::VectorXd& lambda = ges.eigenvalues();
        if (!(lambda(0) > 1e-12 * std::max(1.0, lambda(lambda.size() - 1))))
            throw InputError(where + "no static equilibrium: configuration " + e.cfg.spec(model) +
                             " has a mode of zero frequency (a free body, or a mechanism); a backbone needs positive "
                             "stiffness at rest");
        e.x = field.K(e.cfg).ldlt().solve(field.f(e.cfg));
        e.omega2 = lambda;
        e.shapes = ges.eigenvectors();
        const Configuration next = configuration_at(model, e.x);
        if (next == e.cfg) return e;
        e.cfg = next;
    }
    throw InputError(where + "no static equilibrium found: the contacts' states at rest do not settle");
}

// The multipliers but the family's `family` at +1 (the ones nearest to it): the pair of a
// conservative family (phase and energy), the phase of a damped one.
std::vector<std::complex<double>> nontrivial(std::vector<std::complex<double>> mu, int family) {
    for (int drop = 0; drop < family && !mu.empty(); ++drop)
        mu.erase(std::min_element(mu.begin(), mu.end(),
                                  [](const auto& a, const auto& b) { return std::abs(a - 1.0) < std::abs(b - 1.0); }));
    return mu;
}

// Each pair of the other modes, e^{+-i phi} on the circle or mu, 1/mu off it,
// as one angle phi in [0, pi] (a real pair: 0 or pi); empty unless `pairs`
// angles come out (a rounding that splits a real pair into a complex one).
std::vector<double> pair_angles(const std::vector<std::complex<double>>& rest, std::size_t pairs) {
    std::vector<double> phi;
    std::size_t positive = 0, negative = 0;
    for (const auto& mu : rest) {
        if (std::fabs(mu.imag()) > 1e-12 * std::abs(mu)) {
            if (mu.imag() > 0) phi.push_back(std::arg(mu));
        } else {
            ++(mu.real() > 0 ? positive : negative);
        }
    }
    if (positive % 2 || negative % 2) return {};
    phi.insert(phi.end(), positive / 2, 0.0);
    phi.insert(phi.end(), negative / 2, M_PI);
    if (phi.size() != pairs) return {};
    return phi;
}

// The rotations Theta_j (unwrapped: omega_j T at the linear limit) carried to
// the new angles: each angle goes to the pair whose nearest branch 2 pi m +-
// phi is nearest to its last Theta (greedily, nearest first).
std::vector<double> follow(const std::vector<double>& last, const std::vector<double>& phi) {
    struct Option {
        double distance, theta;
        std::size_t pair, angle;
    };
    std::vector<Option> options;
    for (std::size_t j = 0; j < last.size(); ++j)
        for (std::size_t a = 0; a < phi.size(); ++a)
            for (const double sign : {1.0, -1.0}) {
                const double m = std::round((last[j] - sign * phi[a]) / (2 * M_PI));
                const double theta = 2 * M_PI * m + sign * phi[a];
                options.push_back({std::fabs(theta - last[j]), theta, j, a});
            }
    std::sort(options.begin(), options.end(), [](const Option& x, const Option& y) { return x.distance < y.distance; });
    std::vector<double> next = last;
    std::vector<char> pair_done(last.size(), 0), angle_done(phi.size(), 0);
    for (const Option& o : options)
        if (!pair_done[o.pair] && !angle_done[o.angle]) {
            next[o.pair] = o.theta;
            pair_done[o.pair] = angle_done[o.angle] = 1;
        }
    return next;
}

// The multiples m pi a rotation passed from `from` to `to` (reaching one counts, leaving it does not).
std::vector<long> passed(double from, double to) {
    std::vector<long> m;
    if (to > from)
        for (double k = std::floor(from / M_PI) + 1; k * M_PI <= to; ++k) m.push_back(static_cast<long>(k));
    else if (to < from)
        for (double k = std::ceil(from / M_PI) - 1; k * M_PI >= to; --k) m.push_back(static_cast<long>(k));
    return m;
}

// The zero of v(t) between ta and tb (va, vb of opposite signs, or vb = 0) by the secant method
// (Illinois: the stale end's value halved), to 1e-15 T; a NaN v(t) stops it. Returns the last
// instant it evaluated v at.
template <class V>
double velocity_zero(double ta, double va, double tb, double vb, double T, V&& v) {
    double t = ta;
    for (int it = 0, side = 0; it < 60; ++it) {
        const double last = t;
        t = (ta * vb - tb * va) / (vb - va);
        if (!(t > ta && t < tb)) t = 0.5 * (ta + tb);
        const double vt = v(t);
        if (vt == 0.0 || std::fabs(t - last) <= 1e-15 * T || std::isnan(vt)) break;
        if ((vt < 0) == (va < 0)) {
            ta = t, va = vt;
            if (side == -1) vb /= 2;
            side = -1;
        } else {
            tb = t, vb = vt;
            if (side == 1) va /= 2;
            side = 1;
        }
    }
    return t;
}

}  // namespace

const char* modes_status_name(ModesStatus status) {
    switch (status) {
        case ModesStatus::ok:
            return "ok";
        case ModesStatus::not_converged:
            return "not_converged";
        case ModesStatus::stopped:
            return "stopped";
    }
    return "?";
}

namespace {

// Checks the options; returns the first point's value (`from`, or to/points when not given).
double check_options(const Model& model, const ModesOptions& o) {
    const std::size_t n = model.dof();
    if (o.mode < 1 || static_cast<std::size_t>(o.mode) > n)
        throw OptionError(kModes, "mode", std::to_string(o.mode),
                          "must be 1 to " + std::to_string(n) + " (the model's dofs with mass)");
    if (!std::isfinite(o.to) || o.to == 0.0)
        throw OptionError(kModes, "to", number_text(o.to), "must be given, finite and not 0");
    if (o.points < 1) throw OptionError(kModes, "points", std::to_string(o.points), "must be >= 1");
    const double from = std::isnan(o.from) ? o.to / o.points : o.from;
    if (!std::isfinite(from) || from == 0.0 || (from > 0) != (o.to > 0))
        throw OptionError(kModes, "from", number_text(from),
                          "must be finite, not 0, and of the same sign as the last point");
    if (o.parameter == ModesParameter::energy && !(o.to > 0))
        throw OptionError(kModes, "to", number_text(o.to), "an energy must be > 0");
    if (damped_model(model) && !(o.to > 0))
        throw OptionError(kModes, "to", number_text(o.to),
                          "a damped mode's amplitude is where the amplitude dof turns after passing its equilibrium "
                          "upward: must be > 0");
    if (o.parameter == ModesParameter::energy && damped_model(model))
        throw OptionError(kModes, "parameter", "energy",
                          "a damped mode (Jenkins elements or Rayleigh damping) is continued in amplitude only: its "
                          "energy is not constant over the period");
    analysis::check_number(kModes, "tolerance", o.tolerance, true);
    if (o.max_iterations < 1)
        throw OptionError(kModes, "max_iterations", std::to_string(o.max_iterations), "must be >= 1");
    if (!(o.min_step > 0 && o.min_step < 1))
        throw OptionError(kModes, "min_step", number_text(o.min_step), "must be > 0 and < 1");
    return from;
}

// The amplitude dof: named, or the mode shape's largest entry; the shape turned so that it is positive there.
Eigen::Index amplitude_dof(const Model& model, const ModesOptions& o, Eigen::VectorXd& shape) {
    Eigen::Index k = 0;
    if (o.dof.empty()) {
        shape.cwiseAbs().maxCoeff(&k);
    } else {
        const int i = model.mass_index(o.dof);
        if (i < 0) throw OptionError(kModes, "dof", o.dof, "no dof with mass of that name in the model");
        k = i;
        if (!(std::fabs(shape(k)) > 1e-9 * shape.cwiseAbs().maxCoeff()))
            throw OptionError(kModes, "dof", o.dof,
                              "mode " + std::to_string(o.mode) + " does not move it (a node of the mode shape)");
    }
    if (shape(k) < 0) shape = -shape;
    return k;
}

// An orbit of the backbone: its continuation parameter (the amplitude, or the
// square root of the energy: both grow as the mode's coordinate), period, state
// on the section (x, v, then the Jenkins sliders) and, of a damped mode, the
// EPMC coefficient xi. The section of a conservative backbone is the amplitude
// dof's turning point (v_k = 0, x_k = x_eq,k + A); of a damped one its passage
// through the equilibrium upward (x_k = x_eq,k, v_k > 0), the amplitude being
// where it turns next: at a turning point a Jenkins element may stick (always,
// on one dof), an event at the section's instant where the map has no
// derivative.
struct Orbit {
    double s = 0.0, T = 0.0, xi = 0.0;
    Eigen::VectorXd y;
};

// The linear limit's coordinates, x = T q: one q per mass without friction; a mass with
// friction against the ground is held (its row of T 0), one with friction against another body
// moves with that body (its row that body's; up a chain, the first without friction).
Eigen::MatrixXd held_basis(const Model& model) {
    const std::size_t n = model.dof();
    std::vector<Eigen::Index> col(n, -1);
    Eigen::Index nq = 0;
    for (std::size_t i = 0; i < n; ++i)
        if (!model.has_friction(i)) col[i] = nq++;
    Eigen::MatrixXd T = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), nq);
    Configuration all_stuck = Configuration::all_open(model);
    for (std::size_t i = 0; i < n; ++i) all_stuck.stuck[i] = model.has_friction(i);
    for (std::size_t i = 0; i < n; ++i)  // up the chain to the first body without friction
        if (const int body = carrier(model, all_stuck, i); body != kGround)
            T(static_cast<Eigen::Index>(i), col[static_cast<std::size_t>(body)]) = 1.0;
    return T;
}

// The linear modes at the equilibrium: of the model itself, or, with Jenkins
// elements or friction, of the configuration with all of them stuck (eq: the model
// without the Jenkins elements), a mass stuck to the ground held still (its rows of the
// shapes 0), one stuck to another body moving with it (held_basis()).
void stuck_modes(const Model& work, Field& field, Equilibrium& eq) {
    const Eigen::MatrixXd T = held_basis(work);
    const auto n = static_cast<Eigen::Index>(work.dof());
    if (work.jenkins.empty() && T.cols() == n) return;
    if (T.cols() == 0)
        throw InputError(std::string(kModes) + "(): " + (work.source.empty() ? work.name : work.source) +
                         ": every mass has friction: nothing moves while they stick (no linear mode to start from)");
    Configuration cfg = Configuration::all_open(work);
    cfg.closed = eq.cfg.closed;
    for (Eigen::Index i = 0; i < n; ++i)
        if (work.has_friction(static_cast<std::size_t>(i))) cfg.stuck[static_cast<std::size_t>(i)] = true;
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> ges(T.transpose() * stiffness_matrix(work, cfg) * T,
                                                                        T.transpose() * field.M() * T);
    if (ges.info() != Eigen::Success)
        throw RunError(std::string(kModes) + "(): the eigenproblem (K, M) of configuration " + cfg.spec(work) +
                       " failed");
    eq.omega2 = ges.eigenvalues();
    eq.shapes = T * ges.eigenvectors();
    eq.cfg = cfg;
}

// The continuation of one backbone (api/hsnc/modes.h): the shooting at one
// amplitude (correct), the secant prediction, and the points.
class Backbone {
public:
    Backbone(const Model& work, const ModesOptions& o, ModesResult& r)
        : work_(work),
          bare_(without_jenkins(work)),
          o_(o),
          r_(r),
          field_(bare_),
          eq_(equilibrium(bare_, field_)),
          n_(static_cast<Eigen::Index>(work.dof())),
          nj_(static_cast<Eigen::Index>(work.jenkins.size())),
          damped_(damped_model(work)) {
        stuck_modes(work, field_, eq_);
        const Eigen::Index mode = o.mode - 1;
        if (mode >= eq_.omega2.size())
            throw OptionError(kModes, "mode", std::to_string(o.mode),
                              "must be 1 to " + std::to_string(eq_.omega2.size()) +
                                  " (the dofs that move while every friction mass sticks)");
        shape_ = eq_.shapes.col(mode);
        k_ = amplitude_dof(work, o, shape_);
        r.mode = o.mode;
        r.dof = static_cast<std::size_t>(k_);
        r.damped = damped_;
        r.linear_omega = std::sqrt(eq_.omega2(mode));
        // The linear limit's modal damping c = alpha + beta omega^2: EPMC's xi there. With
        // dampers, the xi and omega where the damped mode's eigenvalue is i omega, and the
        // mode's complex shape (phase lags between the dofs), scaled to shape_k at dof k.
        double xi0 = work.alpha + work.beta * eq_.omega2(mode);
        shape_re_ = shape_;
        shape_im_ = Eigen::VectorXd::Zero(n_);
        const Eigen::MatrixXd K = stiffness_matrix(work, eq_.cfg);
        if (!work.proportional_damping()) {  // in the held coordinates q (x = T q: friction masses stuck)
            const Eigen::MatrixXd T = held_basis(work), MT = T.transpose() * field_.M() * T;
            const Eigen::VectorXd q = T.transpose() * field_.M() * shape_;  // shape_ = T phi, phi M-normalised
            const DampedLinearMode d =
                damped_linear_mode(MT, T.transpose() * K * T, T.transpose() * damping_matrix(work, eq_.cfg) * T,
                                   MT.ldlt().solve(q), r.linear_omega, eq_.cfg.spec(work));
            xi0 = d.xi;
            r.linear_omega = d.omega;
            Eigen::VectorXcd phi = T.cast<std::complex<double>>() * d.shape;
            phi *= shape_(k_) / phi(k_);
            shape_re_ = phi.real();
            shape_im_ = phi.imag();
        }
        r.linear_damping_ratio = xi0 / (2 * r.linear_omega);
        r.shape.assign(shape_.data(), shape_.data() + n_);
        r.equilibrium.assign(eq_.x.data(), eq_.x.data() + n_);
        r.configuration = eq_.cfg.spec(work);
        rest_potential_ = potential(bare_, field_, eq_.x);
        // The unknowns: y without v_k (the phase) and, continued in amplitude, without x_k; then T
        // (and xi of a damped mode).
        energy_ = o.parameter == ModesParameter::energy;
        for (Eigen::Index j = 0; j < 2 * n_ + nj_; ++j)
            if (damped_ ? j != k_ : j != n_ + k_ && (energy_ || j != k_)) unknown_.push_back(j);
        const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n_);
        for (std::size_t c = 0; c < work.contacts.size(); ++c) {
            Eigen::VectorXd w(n_);
            const double g0 = gap(work, static_cast<int>(c), zero.data());
            for (Eigen::Index i = 0; i < n_; ++i) {
                Eigen::VectorXd e = zero;
                e(i) = 1.0;
                w(i) = gap(work, static_cast<int>(c), e.data()) - g0;
            }
            contact_direction_.push_back(w);
        }
        // The linear limit: amplitude 0 at the equilibrium (the sliders where their springs are
        // unstretched), period 2 pi/omega; the other modes' rotations Theta_j = omega_j T (j !=
        // mode) there, followed on a conservative backbone only.
        history_.push_back({0.0, 2 * M_PI / r.linear_omega, xi0, Eigen::VectorXd::Zero(2 * n_ + nj_)});
        history_.back().y.head(n_) = eq_.x;
        for (Eigen::Index j = 0; j < nj_; ++j)
            history_.back().y(2 * n_ + j) = along_x(work.jenkins[static_cast<std::size_t>(j)].direction(), eq_.x);
        const Eigen::VectorXd s0 = history_.back().y.tail(nj_);
        r.sliders.assign(s0.data(), s0.data() + nj_);
        for (Eigen::Index j = 0; j < n_ && !damped_; ++j)
            if (j != mode) {
                r.others.push_back(static_cast<int>(j) + 1);
                rotation_.push_back(2 * M_PI * std::sqrt(eq_.omega2(j)) / r.linear_omega);
            }
        xi_scale_ = r.linear_omega;
        // Where the linear (all stuck) mode first makes a Jenkins element slip: |k (u - s0)| =
        // F_s with u - s0 = A |w . shape| / shape_k (the complex shape's modulus with dampers).
        for (const Jenkins& e : work.jenkins) {
            const double wu =
                std::abs(std::complex<double>(along_x(e.direction(), shape_re_), along_x(e.direction(), shape_im_))) /
                shape_(k_);
            if (wu > 0) slip_onset_ = std::min(slip_onset_, jenkins::held_stretch(1, e.k, e.slip_force) / wu);
        }
        // And where it first makes a held mass i slip: the force holding it, q (omega^2 (M phi)_i -
        // (K phi)_i) in the mode's coordinate q = A / shape_k (the damping force left out: a
        // starting point only), reaches mu_s N_i.
        const Eigen::VectorXd hold = eq_.omega2(mode) * (field_.M() * shape_) - K * shape_;
        for (Eigen::Index i = 0; i < n_; ++i) {
            const FrictionSlot& f = work.friction_slot(static_cast<std::size_t>(i));
            if (f.active && std::fabs(hold(i)) > 0)
                slip_onset_ = std::min(slip_onset_, f.mu_s * work.normal_force(static_cast<std::size_t>(i)) *
                                                        shape_(k_) / std::fabs(hold(i)));
        }
    }

    // Every point asked for, in order, until the continuation stops (ModesResult::status says how).
    void run(const std::vector<double>& targets) {
        progress_.points = targets.size();
        for (const double target : targets)
            if (!reach(target)) return;
        r_.status = ModesStatus::ok;
    }

private:
    // A damped orbit's turning point after the section: its time, x_k there, and d x_k / dy
    // (the flow map's row k to that time: x_k is stationary in t there, so the time's own
    // change does not enter).
    struct Turn {
        double t = NAN, x = NAN;
        Eigen::RowVectorXd row;
    };
    struct Corrected {
        bool ok = false;
        std::string why;
        Orbit orbit;
        analysis::PeriodMapValue pm;
        Turn turn;
        int iterations = 0;
    };

    // The flow of the model with xi: the model itself on a conservative backbone; of a damped
    // mode its EPMC system, alpha - xi, on the Eigen solver (negative damping). The last few
    // are kept (Newton alternates between xi and xi + its difference step).
    analysis::Flow& flow(double xi) {
        for (auto& f : flows_)
            if (f.first == xi) return *f.second;
        Model m = work_;
        analysis::FlowKernels kernels{o_.kernels, o_.cache_dir, o_.use_cache};
        if (damped_) {
            m.alpha = work_.alpha - xi;
            kernels.kernels = KernelChoice::eigen;
        }
        if (flows_.size() >= 3) flows_.erase(flows_.begin());
        flows_.emplace_back(xi, std::make_unique<analysis::Flow>(m, kernels, kModes));
        analysis::Flow& f = *flows_.back().second;
        if (o_.progress)
            f.set_progress([this](double) {
                if (!o_.progress(progress_)) stopped_ = true;
                return !stopped_;
            });
        return f;
    }

    // From the last orbit to `target`: steps of the points' spacing, halved on a failure (down
    // to min_step of the parameter's value) and doubled back after a success. At that floor a
    // step that still fails may meet a branch point or a kink of the branch (where another
    // family crosses, or the orbit's switches change): longer steps from the last orbit leap
    // over it. Adds the point; false (with the status set) when none of this gets there.
    bool reach(double target) {
        target_ = target;
        if (stuck_below(history_.back().s) && !stuck_below(target)) {
            // Below the slip onset the orbits are the linear mode's; there the branch has a kink
            // (xi and T leave their linear values in proportion to A - onset), and just beyond it
            // every release is nearly grazing (the joint barely exceeds F_s before it reverses),
            // where Newton's region is tiny; far beyond it the linear guess is poor. So the first
            // orbit beyond is found at twice the onset (or 1.5 times that, and so on), from the
            // linear guess, and the amplitudes asked for are reached from there, backward or
            // forward along the branch.
            if (history_.back().s < slip_onset_) history_.push_back(linear_orbit(slip_onset_));
            for (double anchor = kAnchor * slip_onset_; anchor <= kMaxAnchor * slip_onset_;
                 anchor *= 1.5) {
                const bool found = advance(anchor, false).empty();
                if (stopped_) return stop();
                if (found) break;
            }
        }
        const double spacing = target - history_.back().s;
        const double floor = o_.min_step * std::max(std::fabs(history_.back().s), std::fabs(target));
        double step = spacing;
        while (history_.back().s != target) {
            const double last = history_.back().s, rest = target - last;
            const double at = std::fabs(rest) <= std::fabs(step) ? target : last + step;
            const bool may_halve = std::fabs(step) / 2 >= floor;
            std::string why = advance(at, may_halve);
            if (stopped_) return stop();
            if (why.empty()) {
                step = std::fabs(2 * step) < std::fabs(spacing) ? 2 * step : spacing;
                continue;
            }
            if (may_halve) {
                step /= 2;
                continue;
            }
            bool leapt = false;
            for (double leap = 2 * step; !leapt; leap *= 2) {
                const double to = std::fabs(leap) >= std::fabs(rest) ? target : last + leap;
                leapt = advance(to, false).empty();
                if (stopped_) return stop();
                if (to == target) break;
                step = leap;
            }
            if (!leapt) {
                r_.status = ModesStatus::not_converged;
                r_.message = "the backbone cannot be followed beyond " + parameter(last) + " toward " +
                             parameter(target) + " (steps down to " + number_text(o_.min_step) +
                             " of it, and longer ones beyond): " + why;
                return false;
            }
        }
        return true;
    }

    // One step to `at`: the orbit there, unless Newton fails, the correction is too long
    // (check_jump) or, when `strict`, another mode's pair turns by more than kMaxTurn (so that no
    // pass through +1 or -1 is missed). Returns why not ("" when the orbit is taken).
    std::string advance(double at, bool strict) {
        const Orbit guess = predict(at);
        Corrected c = correct(guess);
        if (stopped_) return "stopped";
        // A damped branch has a kink wherever an element's stick pattern changes (nothing else
        // crosses it: no families): at the floor the steps that leap over it are not checked.
        if (strict || !damped_) check_jump(c, guess);
        if (!c.ok) return c.why;
        const std::vector<std::complex<double>> mu = analysis::floquet_multipliers(c.pm.M);
        const std::vector<std::complex<double>> rest = nontrivial(mu, damped_ ? 1 : 2);
        const std::vector<double> phi = pair_angles(rest, rotation_.size());
        const std::vector<double> turned = phi.empty() ? rotation_ : follow(rotation_, phi);
        double turn = 0.0;
        for (std::size_t j = 0; j < rotation_.size(); ++j) turn = std::max(turn, std::fabs(turned[j] - rotation_[j]));
        if (strict && turn > kMaxTurn) return "another mode's multipliers turn by " + number_text(turn) + " rad";
        for (std::size_t j = 0; j < rotation_.size(); ++j)
            for (const long m : passed(rotation_[j], turned[j]))
                pending_.push_back("mode" + std::to_string(r_.others[j]) + " " +
                                   (m % 2 == 0 ? std::to_string(m / 2) + ":1" : std::to_string(m) + ":2"));
        rotation_ = turned;
        history_.push_back(c.orbit);
        if (at == target_) add_point(c, mu, rest);
        return "";
    }

    bool stop() {
        r_.status = ModesStatus::stopped;
        r_.message = "stopped by the progress callback";
        return false;
    }

    // Newton converges to the orbit nearest the prediction, which a long step can leave for
    // another family (across an internal-resonance tongue): a correction longer than the step
    // itself is not trusted, and the step is halved as for a failure. Near a branch that bends
    // sharply (a contact just reached) the correction falls faster than the step.
    void check_jump(Corrected& c, const Orbit& guess) const {
        // The first steps beyond the slip onset are predicted across its kink.
        const std::size_t h = history_.size();
        if (!c.ok || stuck_below(history_[h - 1].s) || stuck_below(history_[h > 1 ? h - 2 : 0].s)) return;
        const double correction = distance(c.orbit, guess), stride = distance(guess, history_.back());
        if (correction > kMaxCorrection * stride) {
            c.ok = false;
            c.why = "the correction (" + number_text(correction) + ") exceeds the step (" + number_text(stride) +
                    "): the branch turns back or leaves for another family here";
        }
    }

    // `rest`: the multipliers `mu` but the family's ones at +1 (nontrivial()).
    void add_point(const Corrected& c, const std::vector<std::complex<double>>& mu,
                   const std::vector<std::complex<double>>& rest) {
        ModePoint p;
        Eigen::VectorXd at = c.orbit.y;  // the state at the turning point
        if (damped_) at = state_of(run_to(c.orbit.y, c.orbit.xi, c.turn.t));
        p.amplitude = at(k_) - eq_.x(k_);
        p.period = c.orbit.T;
        p.omega = 2 * M_PI / c.orbit.T;
        p.xi = c.orbit.xi;
        p.damping_ratio = c.orbit.xi / (2 * p.omega);
        p.energy = energy(at);
        p.x.assign(at.data(), at.data() + n_);
        p.v.assign(at.data() + n_, at.data() + 2 * n_);
        p.sliders.assign(at.data() + 2 * n_, at.data() + 2 * n_ + nj_);
        p.peaks = peaks(c.orbit);
        p.multipliers = mu;
        p.max_multiplier = rest.empty() ? 1.0 : 0.0;
        for (const auto& m : rest) p.max_multiplier = std::max(p.max_multiplier, std::abs(m));
        p.stable = p.max_multiplier <= 1 + kConservativeMultiplier;
        for (const double theta : rotation_) p.ratios.push_back(theta / (2 * M_PI));
        p.resonances = std::move(pending_);
        pending_.clear();
        p.events = c.pm.events;
        p.grazing = c.pm.grazing;
        p.iterations = c.iterations;
        p.residual = c.pm.residual;
        r_.points.push_back(std::move(p));
        progress_.point = r_.points.size();
    }

    // Each dof's largest excursion from equilibrium over the orbit: the samples of one period
    // (kPeakSamples) bracket every turning point (v_i changes sign), each found by the secant
    // method (Illinois) on v_i(t) with the exact state from the sample before it.
    std::vector<double> peaks(const Orbit& o) {
        struct Sampler : Observer {
            std::vector<double> t, x, v;
            void on_sample(double ts, const double* xs, const double* vs) override {
                t.push_back(ts);
                x.insert(x.end(), xs, xs + nx);
                v.insert(v.end(), vs, vs + n);
            }
            void on_event(double, EventKind, int, const double*, const double*) override {}
            std::size_t n = 0, nx = 0;
        } samples;
        const auto n = static_cast<std::size_t>(n_), nx = n + static_cast<std::size_t>(nj_);
        samples.n = n;
        samples.nx = nx;
        analysis::Flow& f = flow(o.xi);
        const double* s0 = nj_ ? o.y.data() + 2 * n_ : nullptr;
        const RunSummary run = f.run(0.0, o.y.data(), o.y.data() + n_, o.T, samples, true, o.T / kPeakSamples, s0);
        std::vector<double> peak(n, 0.0);
        if (run.status != RunStatus::ok) return std::vector<double>(n, NAN);
        analysis::NullObserver none;
        auto state_at = [&](std::size_t s, double t, std::size_t i, double& x) {
            const double* xs = &samples.x[s * nx];
            const RunSummary r = f.run(samples.t[s], xs, &samples.v[s * n], t, none, false, 0.0, nj_ ? xs + n : nullptr);
            x = r.x[i];
            return r.v[i];
        };
        for (std::size_t i = 0; i < n; ++i) {
            const double eq = eq_.x(static_cast<Eigen::Index>(i));
            for (std::size_t s = 0; s < samples.t.size(); ++s) {
                peak[i] = std::max(peak[i], std::fabs(samples.x[s * nx + i] - eq));
                if (s + 1 == samples.t.size()) break;
                double ta = samples.t[s], tb = samples.t[s + 1];
                double va = samples.v[s * n + i], vb = samples.v[(s + 1) * n + i];
                if (!(va * vb < 0)) continue;
                double x = NAN;  // at the last instant velocity_zero() evaluates
                velocity_zero(ta, va, tb, vb, o.T, [&](double t) { return state_at(s, t, i, x); });
                if (!std::isnan(x)) peak[i] = std::max(peak[i], std::fabs(x - eq));
            }
        }
        return peak;
    }

    // The secant through the last two orbits; from the linear limit, the mode shape
    // (an amplitude s of dof k; an energy s^2 in the mode coordinate sqrt(2) s / omega).
    Orbit predict(double at) const {
        if (stuck_below(history_.back().s)) return linear_orbit(at);
        Orbit g;
        g.s = at;
        const Orbit& b = history_.back();
        if (history_.size() == 1) {
            g.T = b.T;
            g.xi = b.xi;
            g.y = b.y;
            const double q = energy_ ? std::sqrt(2.0) * at / r_.linear_omega : at / shape_(k_);
            if (damped_) {  // passing the equilibrium upward: x = q Re(-i phi e^{i omega t})
                g.y.head(n_) += q * shape_im_;
                g.y.segment(n_, n_) += r_.linear_omega * q * shape_re_;
            } else {
                g.y.head(n_) += q * shape_;
            }
        } else {
            const Orbit& a = history_[history_.size() - 2];
            const double f = (at - b.s) / (b.s - a.s);
            g.T = b.T + f * (b.T - a.T);
            g.xi = b.xi + f * (b.xi - a.xi);
            g.y = b.y + f * (b.y - a.y);
        }
        return g;
    }

    // Whether amplitude s is at or below the slip onset (the linear, all-stuck part of a damped
    // branch with Jenkins elements).
    bool stuck_below(double s) const { return std::isfinite(slip_onset_) && s <= slip_onset_ * (1 + 1e-9); }

    // A damped mode's guess from the linear limit: the stuck mode passing its equilibrium upward
    // with amplitude `at`; each Jenkins element whose stretch amplitude a = at |w . shape| /
    // shape_k exceeds F_s/k_t as on the slipping orbit there: stuck since its last reversal
    // (stretch -F_s/k_t then) over a travel a, or slipping, stretched +F_s/k_t (in its direction
    // of motion). The linear mode's own sliders (centred) would make each release a near-grazing
    // one, where the map's derivative is of no use to Newton.
    Orbit linear_orbit(double at) const {
        Orbit g = history_.front();
        g.s = at;
        const double q = at / shape_(k_);
        g.y.head(n_) += q * shape_im_;
        g.y.segment(n_, n_) += r_.linear_omega * q * shape_re_;
        for (Eigen::Index j = 0; j < nj_; ++j) {
            const Jenkins& e = work_.jenkins[static_cast<std::size_t>(j)];
            const double wu = along_x(e.direction(), shape_re_) * q, held = jenkins::held_stretch(1, e.k, e.slip_force);
            const double a = std::abs(std::complex<double>(wu, along_x(e.direction(), shape_im_) * q));
            if (a > held) g.y(2 * n_ + j) -= std::copysign(std::min(a - held, held), wu);
        }
        return g;
    }

    // Scaled distance of two orbits: positions (and sliders) against the first's amplitude
    // (of dof k), velocities against that times its 2 pi/T, periods against T, xi against the
    // linear frequency.
    double distance(const Orbit& a, const Orbit& b) const {
        const double sx = damped_ ? std::fabs(a.s) : std::fabs(a.y(k_) - eq_.x(k_)), sv = sx * 2 * M_PI / a.T;
        const Eigen::VectorXd d = a.y - b.y;
        double x = d.head(n_).cwiseAbs().maxCoeff();
        if (nj_) x = std::max(x, d.tail(nj_).cwiseAbs().maxCoeff());
        return std::max({x / sx, d.segment(n_, n_).cwiseAbs().maxCoeff() / sv, std::fabs(a.T - b.T) / a.T,
                         std::fabs(a.xi - b.xi) / xi_scale_});
    }

    // The continuation parameter as the user gave it.
    std::string parameter(double s) const {
        return energy_ ? "energy " + number_text(s * s) : "amplitude " + number_text(s);
    }

    // Kinetic plus potential energy above the equilibrium: springs, closed contacts, the
    // constant load, and the Jenkins springs' 1/2 k (u - s)^2.
    double energy(const Eigen::VectorXd& y) {
        const Eigen::VectorXd x = y.head(n_), v = y.segment(n_, n_);
        double E = 0.5 * v.dot(field_.M() * v) + potential(bare_, field_, x) - rest_potential_;
        for (Eigen::Index j = 0; j < nj_; ++j) {
            const Jenkins& e = work_.jenkins[static_cast<std::size_t>(j)];
            E += jenkins::energy(e.k, along_x(e.direction(), x) - y(2 * n_ + j));
        }
        return E;
    }

    // P_T(y) and |P(y) - y|: positions and sliders relative to the orbit's largest excursion
    // from the equilibrium, velocities to that times 2 pi/T (a turning point has no velocity
    // scale of its own); for the energy s^2, also |E(y) - s^2| / s^2.
    // A damped orbit: also its turning point (`turn`), and |x_k there - x_eq,k - A| / A.
    analysis::PeriodMapValue evaluate(const Eigen::VectorXd& y, double T, double xi, double s, Turn& turn) {
        ++progress_.runs;
        analysis::PeriodMapValue pm;
        try {  // a Newton trial may take xi beyond what the solver takes (critical negative damping)
            pm = analysis::evaluate_period_map(flow(xi), 0.0, T, y);
            if (pm.ok && damped_) turn = turning_point(y, T, xi);
        } catch (const RunError& e) {
            pm.ok = false;
            pm.message = e.what();
        }
        if (pm.ok && damped_) {
            if (std::isnan(turn.x)) {
                pm.ok = false;
                pm.message = "the amplitude dof does not turn within the period";
            }
        }
        if (pm.ok) {
            double sx = (y.head(n_) - eq_.x).cwiseAbs().maxCoeff();
            if (damped_) sx = std::max(sx, std::fabs(s));
            const double sv = sx * 2 * M_PI / T;
            const Eigen::VectorXd d = pm.Py - y;
            double dx = d.head(n_).cwiseAbs().maxCoeff();
            if (nj_) dx = std::max(dx, d.tail(nj_).cwiseAbs().maxCoeff());
            pm.residual = std::max(dx / sx, d.segment(n_, n_).cwiseAbs().maxCoeff() / sv);
            if (energy_) pm.residual = std::max(pm.residual, std::fabs(energy(y) - s * s) / (s * s));
            if (damped_) pm.residual = std::max(pm.residual, std::fabs(turn.x - eq_.x(k_) - s) / std::fabs(s));
            if (!std::isfinite(pm.residual)) pm.residual = INFINITY;
        }
        return pm;
    }

    // Why Newton cannot go on from `pm` ("" when it can).
    std::string stuck(const analysis::PeriodMapValue& pm, int it) const {
        if (!pm.ok) return pm.message;
        if (it >= o_.max_iterations)
            return "no convergence in " + std::to_string(o_.max_iterations) + " Newton iterations (residual " +
                   number_text(pm.residual) + ")";
        if (pm.singular || !pm.M.allFinite())
            return "the period map has no derivative here (a grazing switch with zero normal velocity)";
        return "";
    }

    // Newton on P_T(y) - y = 0 at the guess's amplitude (x_k fixed) or energy (E(y) = s^2, one
    // more residual): the residuals in the unknowns, T and (damped) xi, least squares (the
    // minimum-norm step: a family of orbits leaves directions free), each step halved until
    // the residual falls.
    Corrected correct(const Orbit& g) {
        Corrected c;
        c.orbit = g;
        Eigen::VectorXd& y = c.orbit.y;
        double& T = c.orbit.T;
        double& xi = c.orbit.xi;
        if (damped_) {
            y(k_) = eq_.x(k_);
        } else {
            if (!energy_) y(k_) = eq_.x(k_) + g.s;
            y(n_ + k_) = 0.0;
        }
        progress_.amplitude = energy_ ? g.s * g.s : g.s;
        c.pm = evaluate(y, T, xi, g.s, c.turn);
        for (int it = 0;; ++it) {
            progress_.iterations = it;
            progress_.residual = c.pm.residual;
            if (stopped_) return c;
            if (c.pm.ok && c.pm.residual <= o_.tolerance) {
                c.ok = true;
                c.iterations = it;
                return c;
            }
            c.why = stuck(c.pm, it);
            if (!c.why.empty()) return c;
            const Eigen::VectorXd step = newton_step(c, g.s);
            if (stopped_) return c;
            if (!step.allFinite()) {
                c.why = "the Newton step is not finite";
                return c;
            }
            const auto U = static_cast<Eigen::Index>(unknown_.size());
            bool accepted = false;
            double lambda = 1.0;
            for (int halving = 0; halving <= 10 && !accepted; ++halving, lambda *= 0.5) {
                Eigen::VectorXd ty = y;
                for (Eigen::Index u = 0; u < U; ++u) ty(unknown_[static_cast<std::size_t>(u)]) += lambda * step(u);
                const double tT = T + lambda * step(U), txi = damped_ ? xi + lambda * step(U + 1) : xi;
                if (!(tT > 0)) continue;
                Turn turn;
                analysis::PeriodMapValue next = evaluate(ty, tT, txi, g.s, turn);
                if (stopped_) return c;
                if (next.ok && next.residual < c.pm.residual) {
                    y = ty;
                    T = tT;
                    xi = txi;
                    c.pm = std::move(next);
                    c.turn = std::move(turn);
                    accepted = true;
                }
            }
            if (!accepted) {
                c.why = "the residual stops falling at " + number_text(c.pm.residual);
                return c;
            }
        }
    }

    // The least-squares step in the unknowns, T and (damped) xi: (M - I) on the unknowns'
    // columns; dP/dT = f(P(y)) (conservative: the vector field; damped: a difference over a
    // short run on from P(y)); dP/dxi a forward difference of the period map; for the energy,
    // the row grad E weighted to a length (dE/E = 2 dA/A).
    // A damped mode's amplitude row: d x_k(turning point) / d(unknowns, T, xi), weighted as a
    // position relative to the amplitude.
    Eigen::VectorXd newton_step(const Corrected& c, double s) {
        const analysis::PeriodMapValue& pm = c.pm;
        const Orbit& o = c.orbit;
        const Eigen::VectorXd& y = o.y;
        const auto U = static_cast<Eigen::Index>(unknown_.size());
        const Eigen::Index N = 2 * n_ + nj_, rows = N + (energy_ || damped_ ? 1 : 0), cols = U + (damped_ ? 2 : 1);
        Eigen::MatrixXd J = Eigen::MatrixXd::Zero(rows, cols);
        Eigen::VectorXd rhs(rows);
        for (Eigen::Index u = 0; u < U; ++u) {
            const Eigen::Index j = unknown_[static_cast<std::size_t>(u)];
            J.block(0, u, N, 1) = pm.M.col(j);
            J(j, u) -= 1.0;
        }
        if (damped_) {
            J.block(0, U, N, 1) = time_derivative(pm, o);
            J.block(0, U + 1, N, 1) = xi_derivative(pm, o);
            for (Eigen::Index u = 0; u < U; ++u) J(N, u) = c.turn.row(unknown_[static_cast<std::size_t>(u)]);
            const double d = kDifference * xi_scale_;
            J(N, U + 1) = (state_of(run_to(y, o.xi + d, c.turn.t))(k_) - c.turn.x) / d;
            rhs(N) = -(c.turn.x - eq_.x(k_) - s);
        } else {
            J.block(0, U, N, 1) = field_(pm.end, pm.Py);
        }
        rhs.head(N) = -(pm.Py - y);
        if (energy_) {
            const double w = (y.head(n_) - eq_.x).cwiseAbs().maxCoeff() / (2 * s * s);
            const Eigen::VectorXd grad = energy_gradient(y);
            for (Eigen::Index u = 0; u < U; ++u) J(N, u) = w * grad(unknown_[static_cast<std::size_t>(u)]);
            rhs(N) = -w * (energy(y) - s * s);
        }
        if (!damped_) return J.colPivHouseholderQr().solve(rhs);
        // Rows and columns in the residual's own units (positions and sliders against the
        // amplitude, velocities against it times 2 pi/T, T against itself, xi against omega_lin):
        // the minimum-norm step of a nearly singular system (near a slip onset the sliders are
        // barely determined) is then the one the residual measures.
        const double sx = std::fabs(s), sv = sx * 2 * M_PI / o.T;
        Eigen::VectorXd row_scale(rows), col_scale(cols);
        for (Eigen::Index i = 0; i < rows; ++i) row_scale(i) = i >= n_ && i < 2 * n_ ? 1 / sv : 1 / sx;
        for (Eigen::Index u = 0; u < U; ++u) {
            const Eigen::Index j = unknown_[static_cast<std::size_t>(u)];
            col_scale(u) = j >= n_ && j < 2 * n_ ? sv : sx;
        }
        col_scale(U) = o.T;
        col_scale(U + 1) = xi_scale_;
        const Eigen::MatrixXd scaled = row_scale.asDiagonal() * J * col_scale.asDiagonal();
        const Eigen::VectorXd z = scaled.completeOrthogonalDecomposition().solve(row_scale.asDiagonal() * rhs);
        return col_scale.asDiagonal() * z;
    }

    // The run from the section state y to t with xi (NaN state when it fails).
    RunSummary run_to(const Eigen::VectorXd& y, double xi, double t) {
        analysis::NullObserver none;
        try {
            return flow(xi).run(0.0, y.data(), y.data() + n_, t, none, false, 0.0, nj_ ? y.data() + 2 * n_ : nullptr);
        } catch (const RunError& e) {
            RunSummary failed;
            failed.status = RunStatus::failure;
            failed.message = e.what();
            return failed;
        }
    }

    // The amplitude dof's first turning point after the section (v_k from + to -): bracketed by
    // kPeakSamples samples of the period, then the secant method (Illinois) on v_k(t); x_k there
    // and the flow map's row k to it. NaN when v_k does not turn.
    Turn turning_point(const Eigen::VectorXd& y, double T, double xi) {
        struct Sampler : Observer {
            std::vector<double> t, v, states;  // states: x (with the sliders), then v, per sample
            void on_sample(double ts, const double* xs, const double* vs) override {
                t.push_back(ts);
                v.push_back(vs[k]);
                states.insert(states.end(), xs, xs + nx);
                states.insert(states.end(), vs, vs + n);
            }
            void on_event(double, EventKind, int, const double*, const double*) override {}
            Eigen::Index k = 0;
            std::size_t n = 0, nx = 0;
        } samples;
        samples.k = k_;
        samples.n = static_cast<std::size_t>(n_);
        samples.nx = static_cast<std::size_t>(n_ + nj_);
        Turn turn;
        analysis::Flow& f = flow(xi);
        const RunSummary run = f.run(0.0, y.data(), y.data() + n_, T, samples, true, T / kPeakSamples,
                                     nj_ ? y.data() + 2 * n_ : nullptr);
        if (run.status != RunStatus::ok) return turn;
        std::size_t s = 0;
        while (s + 1 < samples.t.size() && !(samples.v[s] > 0 && samples.v[s + 1] <= 0)) ++s;
        if (s + 1 >= samples.t.size()) return turn;
        // v_k(t) by a run from the sample before the bracket (exact from any state).
        const double t0 = samples.t[s], *xs = &samples.states[s * (samples.nx + samples.n)];
        analysis::NullObserver none;
        auto v_at = [&](double to) {
            const RunSummary r = f.run(t0, xs, xs + samples.nx, to, none, false, 0.0, nj_ ? xs + n_ : nullptr);
            return r.status == RunStatus::ok ? r.v[static_cast<std::size_t>(k_)] : NAN;
        };
        const double t = velocity_zero(t0, samples.v[s], samples.t[s + 1], samples.v[s + 1], T, v_at);
        const analysis::PeriodMapValue to = analysis::evaluate_period_map(f, 0.0, t, y);
        if (to.Py.size() != y.size() || !to.Py.allFinite() || !to.M.allFinite()) return turn;
        turn.t = t;
        turn.x = to.Py(k_);
        turn.row = to.M.row(k_);
        return turn;
    }

    // The state's rate at the period's end: (P_{T+h}(y) - P_T(y)) / h, by a run of h = 1e-7 T
    // on from P(y) (a column of Newton's matrix: its error of order h only slows Newton).
    Eigen::VectorXd time_derivative(const analysis::PeriodMapValue& pm, const Orbit& o) {
        const double h = kDifference * o.T;
        analysis::NullObserver none;
        const Eigen::VectorXd& P = pm.Py;
        const RunSummary r = flow(o.xi).run(o.T, P.data(), P.data() + n_, o.T + h, none, false, 0.0,
                                            nj_ ? P.data() + 2 * n_ : nullptr);
        return (state_of(r) - P) / h;
    }

    // dP/dxi: the period map at xi + d (d = 1e-7 of the linear frequency) against P.
    Eigen::VectorXd xi_derivative(const analysis::PeriodMapValue& pm, const Orbit& o) {
        const double d = kDifference * xi_scale_;
        return (state_of(run_to(o.y, o.xi + d, o.T)) - pm.Py) / d;
    }

    // (x, v, sliders) of a run's end; NaN when it did not end well (the step is then not finite).
    Eigen::VectorXd state_of(const RunSummary& r) const {
        Eigen::VectorXd z(2 * n_ + nj_);
        if (r.status != RunStatus::ok) return z.setConstant(NAN);
        for (Eigen::Index i = 0; i < n_; ++i) z(i) = r.x[static_cast<std::size_t>(i)], z(n_ + i) = r.v[static_cast<std::size_t>(i)];
        for (Eigen::Index j = 0; j < nj_; ++j) z(2 * n_ + j) = r.slider[static_cast<std::size_t>(j)];
        return z;
    }

    // dE/dy: (K_open x - f_open + sum over closed contacts of k G w + over Jenkins k (u - s) w,
    // M v, -k (u - s) per slider).
    Eigen::VectorXd energy_gradient(const Eigen::VectorXd& y) {
        const Configuration open = Configuration::all_open(bare_);
        const Eigen::VectorXd x = y.head(n_);
        Eigen::VectorXd grad(2 * n_ + nj_);
        grad.head(n_) = field_.K(open) * x - field_.f(open);
        for (std::size_t c = 0; c < work_.contacts.size(); ++c) {
            const double G = gap(work_, static_cast<int>(c), x.data());
            grad.head(n_) += contact::spring_force(work_.contacts[c].k, G) * contact_direction_[c];
        }
        grad.segment(n_, n_) = field_.M() * y.segment(n_, n_);
        for (Eigen::Index j = 0; j < nj_; ++j) {
            const Jenkins& e = work_.jenkins[static_cast<std::size_t>(j)];
            const double force = jenkins::spring_force(e.k, along_x(e.direction(), x) - y(2 * n_ + j));
            for_each_term(e.direction(), [&](int i, double w) { grad(i) += force * w; });
            grad(2 * n_ + j) = -force;
        }
        return grad;
    }

    const Model& work_;
    const Model bare_;  // work_ without its Jenkins elements (the equilibrium, the potential)
    const ModesOptions& o_;
    ModesResult& r_;
    Field field_;
    Equilibrium eq_;
    Eigen::Index n_, nj_;
    bool damped_ = false;  // EPMC: xi is an unknown, the runs on the Eigen solver
    std::vector<std::pair<double, std::unique_ptr<analysis::Flow>>> flows_;  // by xi (flow())
    bool stopped_ = false;                                                    // the progress callback said so
    Eigen::VectorXd shape_;
    Eigen::VectorXd shape_re_, shape_im_;  // a damped mode's linear shape (complex with dampers; shape_ and 0 else)
    Eigen::Index k_ = 0;
    double rest_potential_ = 0.0;                     // the potential at the equilibrium (energies are above it)
    double xi_scale_ = 1.0;                           // xi's scale: the linear frequency
    double slip_onset_ = INFINITY;                    // the amplitude where the linear mode first slips (damped)
    bool energy_ = false;                             // continued in energy (Orbit::s = sqrt(E)), else in amplitude
    std::vector<Eigen::VectorXd> contact_direction_;  // w of each contact: G = w^T x - gap
    std::vector<Eigen::Index> unknown_;
    std::vector<Orbit> history_;
    std::vector<double> rotation_;
    std::vector<std::string> pending_;  // resonances passed since the last point
    double target_ = NAN;               // the point reach() is after
    ModesProgress progress_;
};

}  // namespace

ModesResult modes(const Model& model, const ModesOptions& o) {
    refuse_unsupported(model);
    const double from = check_options(model, o);
    const Model work = free_model(model);
    // The continuation runs in the amplitude, or in sqrt(E) (as the amplitude grows).
    std::vector<double> targets;
    for (int p = 0; p < o.points; ++p) {
        const double f = o.points == 1 ? 1.0 : static_cast<double>(p) / (o.points - 1);
        const double value = o.geometric ? from * std::pow(o.to / from, f) : from + (o.to - from) * f;
        targets.push_back(o.parameter == ModesParameter::energy ? std::sqrt(value) : value);
    }
    ModesResult r;
    Backbone backbone(work, o, r);
    backbone.run(targets);
    return r;
}

}  // namespace hsnc
