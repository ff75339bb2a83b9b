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
    if (model.alpha != 0.0 || model.beta != 0.0) refuse("[damping] (Rayleigh alpha, beta)");
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

ModesResult modes(const Model& model, const ModesOptions& o) {
    refuse_nonconservative(model);
    const std::size_t n = model.dof();
    if (o.mode < 1 || static_cast<std::size_t>(o.mode) > n)
        throw OptionError(kModes, "mode", std::to_string(o.mode),
                          "must be 1 to " + std::to_string(n) + " (the model's dofs with mass)");
    if (!std::isfinite(o.to) || o.to == 0.0)
        throw OptionError(kModes, "to", number_text(o.to), "must be given, finite and not 0");
    if (o.points < 1) throw OptionError(kModes, "points", std::to_string(o.points), "must be >= 1");
    const double from = std::isnan(o.from) ? o.to / o.points : o.from;
    if (!std::isfinite(from) || from == 0.0 || (from > 0) != (o.to > 0))
        throw OptionError(kModes, "from", number_text(from), "must be finite, not 0, and of the sign of `to`");
    analysis::check_number(kModes, "tolerance", o.tolerance, true);
    if (o.max_iterations < 1)
        throw OptionError(kModes, "max_iterations", std::to_string(o.max_iterations), "must be >= 1");
    if (o.max_halvings < 0) throw OptionError(kModes, "max_halvings", std::to_string(o.max_halvings), "must be >= 0");

    const Model work = free_model(model);
    Field field(work);
    const Equilibrium eq = equilibrium(work, field);
    const auto N = static_cast<Eigen::Index>(2 * n);
    const auto nn = static_cast<Eigen::Index>(n);
    ModesResult r;
    r.mode = o.mode;
    const Eigen::Index mode = o.mode - 1;
    Eigen::VectorXd shape = eq.shapes.col(mode);
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
    r.dof = static_cast<std::size_t>(k);
    r.linear_omega = std::sqrt(eq.omega2(mode));
    r.shape.assign(shape.data(), shape.data() + nn);
    r.equilibrium.assign(eq.x.data(), eq.x.data() + nn);
    r.configuration = eq.cfg.spec(work);

    std::vector<double> targets;
    for (int p = 0; p < o.points; ++p)
        targets.push_back(o.points == 1 ? o.to : from + (o.to - from) * p / (o.points - 1));

    analysis::Flow flow(work, {o.kernels, o.cache_dir, o.use_cache}, kModes);
    ModesProgress progress;
    progress.points = targets.size();
    if (o.progress) flow.set_progress([&](double) { return o.progress(progress); });
    const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(N, N);
    // The unknowns: y without x_k and v_k, then T.
    std::vector<Eigen::Index> unknown;
    for (Eigen::Index j = 0; j < N; ++j)
        if (j != k && j != nn + k) unknown.push_back(j);
    const auto U = static_cast<Eigen::Index>(unknown.size()) + 1;

    struct Orbit {
        double A = 0.0, T = 0.0;
        Eigen::VectorXd y;
    };
    struct Corrected {
        bool ok = false;
        std::string why;
        Orbit orbit;
        analysis::PeriodMapValue pm;
        int iterations = 0;
    };
    // |P(y) - y|: positions relative to the orbit's largest excursion from
    // the equilibrium, velocities to that times 2 pi/T (a turning point has
    // no velocity scale of its own).
    auto evaluate = [&](const Eigen::VectorXd& y, double T) {
        ++progress.runs;
        analysis::PeriodMapValue pm = analysis::evaluate_period_map(flow, 0.0, T, y);
        if (pm.ok) {
            const double sx = (y.head(nn) - eq.x).cwiseAbs().maxCoeff(), sv = sx * 2 * M_PI / T;
            const Eigen::VectorXd d = pm.Py - y;
            pm.residual = std::max(d.head(nn).cwiseAbs().maxCoeff() / sx, d.tail(nn).cwiseAbs().maxCoeff() / sv);
            if (!std::isfinite(pm.residual)) pm.residual = INFINITY;
        }
        return pm;
    };
    // Newton on P_T(y) - y = 0 at amplitude A from the guess `g`.
    auto correct = [&](const Orbit& g) {
        Corrected c;
        c.orbit = g;
        Eigen::VectorXd& y = c.orbit.y;
        double& T = c.orbit.T;
        y(k) = eq.x(k) + g.A;
        y(nn + k) = 0.0;
        progress.amplitude = g.A;
        c.pm = evaluate(y, T);
        for (int it = 0;; ++it) {
            progress.iterations = it;
            progress.residual = c.pm.residual;
            if (flow.stopped()) return c;
            if (!c.pm.ok) {
                c.why = c.pm.message;
                return c;
            }
            if (c.pm.residual <= o.tolerance) {
                c.ok = true;
                c.iterations = it;
                return c;
            }
            if (it >= o.max_iterations) {
                c.why = "no convergence in " + std::to_string(o.max_iterations) + " Newton iterations (residual " +
                        number_text(c.pm.residual) + ")";
                return c;
            }
            if (c.pm.singular || !c.pm.M.allFinite()) {
                c.why = "the period map has no derivative here (a grazing switch with zero normal velocity)";
                return c;
            }
            Eigen::MatrixXd J(N, U);
            for (Eigen::Index u = 0; u + 1 < U; ++u) J.col(u) = (c.pm.M - I).col(unknown[static_cast<std::size_t>(u)]);
            J.col(U - 1) = field(c.pm.end, c.pm.Py);
            const Eigen::VectorXd step = J.colPivHouseholderQr().solve(-(c.pm.Py - y));
            if (!step.allFinite()) {
                c.why = "the Newton step is not finite";
                return c;
            }
            bool accepted = false;
            double lambda = 1.0;
            for (int halving = 0; halving <= 10 && !accepted; ++halving, lambda *= 0.5) {
                Eigen::VectorXd ty = y;
                for (Eigen::Index u = 0; u + 1 < U; ++u) ty(unknown[static_cast<std::size_t>(u)]) += lambda * step(u);
                const double tT = T + lambda * step(U - 1);
                if (!(tT > 0)) continue;
                analysis::PeriodMapValue next = evaluate(ty, tT);
                if (flow.stopped()) return c;
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
    };
    auto energy = [&](const Eigen::VectorXd& y) {
        const Eigen::VectorXd v = y.segment(nn, nn);
        return 0.5 * v.dot(field.M() * v) + potential(work, field, y.head(nn)) - potential(work, field, eq.x);
    };

    // The linear limit: amplitude 0 at the equilibrium, period 2 pi/omega.
    std::vector<Orbit> history{{0.0, 2 * M_PI / r.linear_omega, Eigen::VectorXd::Zero(N)}};
    history.back().y.head(nn) = eq.x;
    auto predict = [&](double A) {
        Orbit g;
        g.A = A;
        const Orbit& b = history.back();
        if (history.size() == 1) {
            g.T = b.T;
            g.y = b.y;
            g.y.head(nn) += (A / shape(k)) * shape;
        } else {
            const Orbit& a = history[history.size() - 2];
            const double s = (A - b.A) / (b.A - a.A);
            g.T = b.T + s * (b.T - a.T);
            g.y = b.y + s * (b.y - a.y);
        }
        return g;
    };
    auto stopped = [&]() {
        r.status = ModesStatus::stopped;
        r.message = "stopped by the progress callback";
        return r;
    };
    for (const double target : targets) {
        double step = target - history.back().A;
        int halvings = 0;
        while (history.back().A != target) {
            const double A = std::fabs(target - history.back().A) <= std::fabs(step) ? target : history.back().A + step;
            const Orbit guess = predict(A);
            Corrected c = correct(guess);
            if (flow.stopped()) return stopped();
            // A point whose period moved by more than a fifth from the last is not trusted to lie on
            // this branch (a jump onto another family): the step is halved as for a failure.
            if (c.ok && std::fabs(c.orbit.T - history.back().T) > 0.2 * history.back().T) {
                c.ok = false;
                c.why = "the period jumps from " + number_text(history.back().T) + " to " + number_text(c.orbit.T) +
                        " s in one step";
            }
            if (!c.ok) {
                if (++halvings > o.max_halvings) {
                    r.status = ModesStatus::not_converged;
                    r.message = "the backbone cannot be followed beyond amplitude " + number_text(history.back().A) +
                                " toward " + number_text(target) + " (" + std::to_string(o.max_halvings) +
                                " halvings of the step): " + c.why;
                    return r;
                }
                step /= 2;
                continue;
            }
            history.push_back(c.orbit);
            step *= 2;  // grow back toward the next target
            if (A != target) continue;
            ModePoint p;
            p.amplitude = target;
            p.period = c.orbit.T;
            p.omega = 2 * M_PI / c.orbit.T;
            p.energy = energy(c.orbit.y);
            p.x.assign(c.orbit.y.data(), c.orbit.y.data() + nn);
            p.v.assign(c.orbit.y.data() + nn, c.orbit.y.data() + N);
            p.multipliers = analysis::floquet_multipliers(c.pm.M);
            // The family's pair at +1: the two multipliers nearest to it.
            std::vector<std::complex<double>> rest = p.multipliers;
            for (int drop = 0; drop < 2 && !rest.empty(); ++drop)
                rest.erase(std::min_element(rest.begin(), rest.end(), [](const auto& a, const auto& b) {
                    return std::abs(a - 1.0) < std::abs(b - 1.0);
                }));
            p.max_multiplier = rest.empty() ? 1.0 : 0.0;
            for (const auto& mu : rest) p.max_multiplier = std::max(p.max_multiplier, std::abs(mu));
            p.stable = p.max_multiplier <= 1 + kConservativeMultiplier;
            p.events = c.pm.events;
            p.grazing = c.pm.grazing;
            p.iterations = c.iterations;
            p.residual = c.pm.residual;
            r.points.push_back(std::move(p));
            progress.point = r.points.size();
        }
    }
    r.status = ModesStatus::ok;
    return r;
}

}  // namespace hsnc
