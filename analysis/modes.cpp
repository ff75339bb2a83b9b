// Backbones of conservative piecewise-linear models by exact shooting (api/hsnc/modes.h).
#include "hsnc/modes.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include "assembly.h"
#include "configuration.h"
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

// A nonlinear mode here is a family of periodic orbits of a conservative
// model: anything that takes energy out is refused by name.
void refuse_nonconservative(const Model& model) {
    const std::string where = std::string(kModes) + "(): " + (model.source.empty() ? model.name : model.source) + ": ";
    auto refuse = [&](const std::string& what) {
        throw InputError(where + what +
                         ": backbones are built for conservative models (springs, masses and undamped contacts); "
                         "friction, Jenkins elements and damping are not supported by hsnc modes yet");
    };
    for (const Mass& m : model.masses)
        if (m.has_friction) refuse("mass " + m.name + " has friction (mu_k)");
    if (!model.jenkins.empty()) refuse("Jenkins element " + model.jenkins.front().name);
    if (!model.dampers.empty())
        refuse(model.dampers.front().from_structure ? "[structure] damping (a damping matrix)" : "[[damper]]");
    if (model.alpha != 0.0 || model.beta != 0.0)
        refuse("[damping] (Rayleigh alpha, beta, or a [structure]'s proportional damping)");
    for (const Contact& c : model.contacts)
        if (c.c != 0.0) refuse("contact " + c.name + " has damping c");
    if (!model.load_steps.empty()) refuse("[[load_step]] " + model.load_steps.front().name);
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
        if (G > 0) V += 0.5 * model.contacts[c].k * G * G;
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

// The multipliers but the family's pair at +1 (the two nearest to it).
std::vector<std::complex<double>> nontrivial(std::vector<std::complex<double>> mu) {
    for (int drop = 0; drop < 2 && !mu.empty(); ++drop)
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
// square root of the energy: both grow as the mode's coordinate), period and
// state at the turning point.
struct Orbit {
    double s = 0.0, T = 0.0;
    Eigen::VectorXd y;
};

// The continuation of one backbone (api/hsnc/modes.h): the shooting at one
// amplitude (correct), the secant prediction, and the points.
class Backbone {
public:
    Backbone(const Model& work, const ModesOptions& o, ModesResult& r)
        : work_(work),
          o_(o),
          r_(r),
          field_(work),
          eq_(equilibrium(work, field_)),
          n_(static_cast<Eigen::Index>(work.dof())),
          flow_(work, {o.kernels, o.cache_dir, o.use_cache}, kModes) {
        const Eigen::Index mode = o.mode - 1;
        shape_ = eq_.shapes.col(mode);
        k_ = amplitude_dof(work, o, shape_);
        r.mode = o.mode;
        r.dof = static_cast<std::size_t>(k_);
        r.linear_omega = std::sqrt(eq_.omega2(mode));
        r.shape.assign(shape_.data(), shape_.data() + n_);
        r.equilibrium.assign(eq_.x.data(), eq_.x.data() + n_);
        r.configuration = eq_.cfg.spec(work);
        rest_potential_ = potential(work, field_, eq_.x);
        // The unknowns: y without v_k (the phase) and, continued in amplitude, without x_k; then T.
        energy_ = o.parameter == ModesParameter::energy;
        for (Eigen::Index j = 0; j < 2 * n_; ++j)
            if (j != n_ + k_ && (energy_ || j != k_)) unknown_.push_back(j);
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
        // The linear limit: amplitude 0 at the equilibrium, period 2 pi/omega; the other modes'
        // rotations Theta_j = omega_j T (j != mode) there.
        history_.push_back({0.0, 2 * M_PI / r.linear_omega, Eigen::VectorXd::Zero(2 * n_)});
        history_.back().y.head(n_) = eq_.x;
        for (Eigen::Index j = 0; j < n_; ++j)
            if (j != mode) {
                r.others.push_back(static_cast<int>(j) + 1);
                rotation_.push_back(2 * M_PI * std::sqrt(eq_.omega2(j)) / r.linear_omega);
            }
        if (o.progress) flow_.set_progress([this](double) { return o_.progress(progress_); });
    }

    // Every point asked for, in order, until the continuation stops (ModesResult::status says how).
    void run(const std::vector<double>& targets) {
        progress_.points = targets.size();
        for (const double target : targets)
            if (!reach(target)) return;
        r_.status = ModesStatus::ok;
    }

private:
    struct Corrected {
        bool ok = false;
        std::string why;
        Orbit orbit;
        analysis::PeriodMapValue pm;
        int iterations = 0;
    };

    // From the last orbit to `target`: steps of the points' spacing, halved on a failure (down
    // to min_step of the parameter's value) and doubled back after a success. At that floor a
    // step that still fails may meet a branch point or a kink of the branch (where another
    // family crosses, or the orbit's switches change): longer steps from the last orbit leap
    // over it. Adds the point; false (with the status set) when none of this gets there.
    bool reach(double target) {
        target_ = target;
        const double spacing = target - history_.back().s;
        const double floor = o_.min_step * std::max(std::fabs(history_.back().s), std::fabs(target));
        double step = spacing;
        while (history_.back().s != target) {
            const double last = history_.back().s, rest = target - last;
            const double at = std::fabs(rest) <= std::fabs(step) ? target : last + step;
            const bool may_halve = std::fabs(step) / 2 >= floor;
            std::string why = advance(at, may_halve);
            if (flow_.stopped()) return stop();
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
                if (flow_.stopped()) return stop();
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
        if (flow_.stopped()) return "stopped";
        check_jump(c, guess);
        if (!c.ok) return c.why;
        const std::vector<std::complex<double>> mu = analysis::floquet_multipliers(c.pm.M);
        const std::vector<std::complex<double>> rest = nontrivial(mu);
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
        if (!c.ok) return;
        const double correction = distance(c.orbit, guess), stride = distance(guess, history_.back());
        if (correction > kMaxCorrection * stride) {
            c.ok = false;
            c.why = "the correction (" + number_text(correction) + ") exceeds the step (" + number_text(stride) +
                    "): the branch turns back or leaves for another family here";
        }
    }

    // `rest`: the multipliers `mu` but the family's pair at +1 (nontrivial()).
    void add_point(const Corrected& c, const std::vector<std::complex<double>>& mu,
                   const std::vector<std::complex<double>>& rest) {
        ModePoint p;
        p.amplitude = c.orbit.y(k_) - eq_.x(k_);
        p.period = c.orbit.T;
        p.omega = 2 * M_PI / c.orbit.T;
        p.energy = energy(c.orbit.y);
        p.x.assign(c.orbit.y.data(), c.orbit.y.data() + n_);
        p.v.assign(c.orbit.y.data() + n_, c.orbit.y.data() + 2 * n_);
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
                x.insert(x.end(), xs, xs + n);
                v.insert(v.end(), vs, vs + n);
            }
            void on_event(double, EventKind, int, const double*, const double*) override {}
            std::size_t n = 0;
        } samples;
        const auto n = static_cast<std::size_t>(n_);
        samples.n = n;
        const RunSummary run = flow_.run(0.0, o.y.data(), o.y.data() + n_, o.T, samples, true, o.T / kPeakSamples);
        std::vector<double> peak(n, 0.0);
        if (run.status != RunStatus::ok) return std::vector<double>(n, NAN);
        analysis::NullObserver none;
        auto state_at = [&](std::size_t s, double t, std::size_t i, double& x) {
            const RunSummary r = flow_.run(samples.t[s], &samples.x[s * n], &samples.v[s * n], t, none, false, 0.0);
            x = r.x[i];
            return r.v[i];
        };
        for (std::size_t i = 0; i < n; ++i) {
            const double eq = eq_.x(static_cast<Eigen::Index>(i));
            for (std::size_t s = 0; s < samples.t.size(); ++s) {
                peak[i] = std::max(peak[i], std::fabs(samples.x[s * n + i] - eq));
                if (s + 1 == samples.t.size()) break;
                double ta = samples.t[s], tb = samples.t[s + 1];
                double va = samples.v[s * n + i], vb = samples.v[(s + 1) * n + i];
                if (!(va * vb < 0)) continue;
                double x = NAN, last = ta;
                for (int it = 0, side = 0; it < 60; ++it) {
                    double t = (ta * vb - tb * va) / (vb - va);
                    if (!(t > ta && t < tb)) t = 0.5 * (ta + tb);
                    const double vt = state_at(s, t, i, x);
                    if (vt == 0.0 || std::fabs(t - last) <= 1e-15 * o.T) break;
                    last = t;
                    if ((vt < 0) == (va < 0)) {
                        ta = t, va = vt;
                        if (side == -1) vb /= 2;  // Illinois: the stale end's value halved
                        side = -1;
                    } else {
                        tb = t, vb = vt;
                        if (side == 1) va /= 2;
                        side = 1;
                    }
                }
                if (!std::isnan(x)) peak[i] = std::max(peak[i], std::fabs(x - eq));
            }
        }
        return peak;
    }

    // The secant through the last two orbits; from the linear limit, the mode shape
    // (an amplitude s of dof k; an energy s^2 in the mode coordinate sqrt(2) s / omega).
    Orbit predict(double at) const {
        Orbit g;
        g.s = at;
        const Orbit& b = history_.back();
        if (history_.size() == 1) {
            g.T = b.T;
            g.y = b.y;
            const double q = energy_ ? std::sqrt(2.0) * at / r_.linear_omega : at / shape_(k_);
            g.y.head(n_) += q * shape_;
        } else {
            const Orbit& a = history_[history_.size() - 2];
            const double f = (at - b.s) / (b.s - a.s);
            g.T = b.T + f * (b.T - a.T);
            g.y = b.y + f * (b.y - a.y);
        }
        return g;
    }

    // Scaled distance of two orbits: positions against the first's amplitude (of dof k),
    // velocities against that times its 2 pi/T, periods against T.
    double distance(const Orbit& a, const Orbit& b) const {
        const double sx = std::fabs(a.y(k_) - eq_.x(k_)), sv = sx * 2 * M_PI / a.T;
        const Eigen::VectorXd d = a.y - b.y;
        return std::max(
            {d.head(n_).cwiseAbs().maxCoeff() / sx, d.tail(n_).cwiseAbs().maxCoeff() / sv, std::fabs(a.T - b.T) / a.T});
    }

    // The continuation parameter as the user gave it.
    std::string parameter(double s) const {
        return energy_ ? "energy " + number_text(s * s) : "amplitude " + number_text(s);
    }

    double energy(const Eigen::VectorXd& y) {
        const Eigen::VectorXd v = y.segment(n_, n_);
        return 0.5 * v.dot(field_.M() * v) + potential(work_, field_, y.head(n_)) - rest_potential_;
    }

    // P_T(y) and |P(y) - y|: positions relative to the orbit's largest excursion from the
    // equilibrium, velocities to that times 2 pi/T (a turning point has no velocity scale of its
    // own); for the energy s^2, also |E(y) - s^2| / s^2.
    analysis::PeriodMapValue evaluate(const Eigen::VectorXd& y, double T, double s) {
        ++progress_.runs;
        analysis::PeriodMapValue pm = analysis::evaluate_period_map(flow_, 0.0, T, y);
        if (pm.ok) {
            const double sx = (y.head(n_) - eq_.x).cwiseAbs().maxCoeff(), sv = sx * 2 * M_PI / T;
            const Eigen::VectorXd d = pm.Py - y;
            pm.residual = std::max(d.head(n_).cwiseAbs().maxCoeff() / sx, d.tail(n_).cwiseAbs().maxCoeff() / sv);
            if (energy_) pm.residual = std::max(pm.residual, std::fabs(energy(y) - s * s) / (s * s));
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
    // more residual): the residuals in the unknowns and T, least squares, each step halved
    // until the residual falls.
    Corrected correct(const Orbit& g) {
        Corrected c;
        c.orbit = g;
        Eigen::VectorXd& y = c.orbit.y;
        double& T = c.orbit.T;
        if (!energy_) y(k_) = eq_.x(k_) + g.s;
        y(n_ + k_) = 0.0;
        progress_.amplitude = energy_ ? g.s * g.s : g.s;
        c.pm = evaluate(y, T, g.s);
        for (int it = 0;; ++it) {
            progress_.iterations = it;
            progress_.residual = c.pm.residual;
            if (flow_.stopped()) return c;
            if (c.pm.ok && c.pm.residual <= o_.tolerance) {
                c.ok = true;
                c.iterations = it;
                return c;
            }
            c.why = stuck(c.pm, it);
            if (!c.why.empty()) return c;
            const Eigen::VectorXd step = newton_step(c.pm, y, g.s);
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
                const double tT = T + lambda * step(U);
                if (!(tT > 0)) continue;
                analysis::PeriodMapValue next = evaluate(ty, tT, g.s);
                if (flow_.stopped()) return c;
                if (next.ok && next.residual < c.pm.residual) {
                    y = ty;
                    T = tT;
                    c.pm = std::move(next);
                    accepted = true;
                }
            }
            if (!accepted) {
                c.why = "the residual stops falling at " + number_text(c.pm.residual);
                return c;
            }
        }
    }

    // The least-squares step in the unknowns and T: (M - I) on the unknowns' columns, dP/dT =
    // f(P(y)); for the energy, the row grad E weighted to a length (dE/E = 2 dA/A).
    Eigen::VectorXd newton_step(const analysis::PeriodMapValue& pm, const Eigen::VectorXd& y, double s) {
        const auto U = static_cast<Eigen::Index>(unknown_.size());
        const Eigen::Index rows = 2 * n_ + (energy_ ? 1 : 0);
        Eigen::MatrixXd J = Eigen::MatrixXd::Zero(rows, U + 1);
        Eigen::VectorXd rhs(rows);
        for (Eigen::Index u = 0; u < U; ++u) {
            const Eigen::Index j = unknown_[static_cast<std::size_t>(u)];
            J.block(0, u, 2 * n_, 1) = pm.M.col(j);
            J(j, u) -= 1.0;
        }
        J.block(0, U, 2 * n_, 1) = field_(pm.end, pm.Py);
        rhs.head(2 * n_) = -(pm.Py - y);
        if (energy_) {
            const double w = (y.head(n_) - eq_.x).cwiseAbs().maxCoeff() / (2 * s * s);
            const Eigen::VectorXd grad = energy_gradient(y);
            for (Eigen::Index u = 0; u < U; ++u) J(2 * n_, u) = w * grad(unknown_[static_cast<std::size_t>(u)]);
            rhs(2 * n_) = -w * (energy(y) - s * s);
        }
        return J.colPivHouseholderQr().solve(rhs);
    }

    // dE/dy: (K_open x - f_open + sum over closed contacts of k G w, M v).
    Eigen::VectorXd energy_gradient(const Eigen::VectorXd& y) {
        const Configuration open = Configuration::all_open(work_);
        const Eigen::VectorXd x = y.head(n_);
        Eigen::VectorXd grad(2 * n_);
        grad.head(n_) = field_.K(open) * x - field_.f(open);
        for (std::size_t c = 0; c < work_.contacts.size(); ++c) {
            const double G = gap(work_, static_cast<int>(c), x.data());
            if (G > 0) grad.head(n_) += work_.contacts[c].k * G * contact_direction_[c];
        }
        grad.tail(n_) = field_.M() * y.tail(n_);
        return grad;
    }

    const Model& work_;
    const ModesOptions& o_;
    ModesResult& r_;
    Field field_;
    Equilibrium eq_;
    Eigen::Index n_;
    analysis::Flow flow_;
    Eigen::VectorXd shape_;
    Eigen::Index k_ = 0;
    double rest_potential_ = 0.0;                     // the potential at the equilibrium (energies are above it)
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
    refuse_nonconservative(model);
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
