#include "transitions.h"

#include <cmath>
#include <algorithm>
#include <limits>

#include "assembly.h"

namespace hsnc {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

// Derivatives A_i^(k), k = 0..order, of the force on mass i at (t, x, v) in
// cfg (friction directions sgn), with the magnitude of their terms (their
// rounding level), from the equation of motion itself:
//     m_j x_j^(k+2) = A_j^(k) - [k = 0] mu_k N_j sgn_j  (0 for a stuck mass),
//     A_j^(k) = [k = 0] (load_j + contact preloads) - (K x^(k))_j - (C x^(k+1))_j
//               + sum_h F_hj Omega_h^k sin(Omega_h t + phase_h + k pi/2).
void force_series(const Model& model, const Configuration& cfg, const std::vector<signed char>& sgn, int i, double t,
                  const double* x, const double* v, int order, std::vector<double>& d, std::vector<double>& mag) {
    const int n = static_cast<int>(model.dof());
    auto at = [](const std::vector<double>& y, int b) { return b == kGround ? 0.0 : y[b]; };
    std::vector<std::vector<double>> X(order + 2, std::vector<double>(n, 0.0)), M = X;
    for (int j = 0; j < n; ++j) {
        X[0][j] = x[j], M[0][j] = std::fabs(x[j]);
        if (!cfg.stuck[j]) X[1][j] = v[j], M[1][j] = std::fabs(v[j]);
    }
    auto deriv = [&](int j, int k, double& value, double& m) {
        value = k == 0 ? model.load[j] : 0.0;
        m = std::fabs(value);
        value -= model.alpha * model.masses[j].m * X[k + 1][j];
        m += std::fabs(model.alpha) * model.masses[j].m * M[k + 1][j];
        auto link = [&](int a, int b, double kk, double gap) {
            if (a == b || (a != j && b != j)) return;
            double f = -kk * (at(X[k], a) - at(X[k], b)) - model.beta * kk * (at(X[k + 1], a) - at(X[k + 1], b));
            double fm = kk * (at(M[k], a) + at(M[k], b)) + std::fabs(model.beta) * kk * (at(M[k + 1], a) + at(M[k + 1], b));
            if (k == 0) f += kk * gap, fm += std::fabs(kk * gap);
            value += a == j ? f : -f;
            m += fm;
        };
        for (const Spring& s : model.springs) link(s.a, s.b, s.k, 0.0);
        for (std::size_t c = 0; c < model.contacts.size(); ++c)
            if (cfg.closed[c]) link(model.contacts[c].a, model.contacts[c].b, model.contacts[c].k, model.contacts[c].gap);
        for (const Harmonic& h : model.forcing) {
            const double arg = h.omega * t + h.phase;
            double s = (k % 2 == 0) ? std::sin(arg) : std::cos(arg);
            if (k % 4 == 2 || k % 4 == 3) s = -s;
            const double wk = std::pow(h.omega, k);
            value += h.amplitude[j] * wk * s;
            m += std::fabs(h.amplitude[j]) * wk;
        }
    };
    for (int k = 0; k + 2 <= order + 1; ++k)
        for (int j = 0; j < n; ++j) {
            if (cfg.stuck[j]) continue;
            double A, m;
            deriv(j, k, A, m);
            const double fr = k == 0 && model.masses[j].has_friction ? model.masses[j].mu_k * model.normal_force(j) : 0.0;
            X[k + 2][j] = (A - fr * sgn[j]) / model.masses[j].m;
            M[k + 2][j] = (m + fr * (sgn[j] != 0)) / model.masses[j].m;
        }
    d.assign(order + 1, 0.0);
    mag.assign(order + 1, 0.0);
    for (int k = 0; k <= order; ++k) deriv(i, k, d[k], mag[k]);
}

// Acceleration of every mass in cfg at (t, x, v): 0 when stuck, else
// (A_i - mu_k N_i sgn_i)/m_i (sgn_i = 0 for masses without friction); entries n..2n-1
// hold (|A_i| + mu_k N_i)/m_i, the magnitude of the terms (its rounding level).
std::vector<double> accelerations(const Model& model, const Configuration& cfg, const std::vector<signed char>& sgn,
                                  double t, const double* x, const double* v) {
    const int n = static_cast<int>(model.dof());
    std::vector<double> a(2 * n, 0.0);  // accelerations, then the magnitudes of their terms
    for (int i = 0; i < n; ++i) {
        if (cfg.stuck[i]) continue;
        const double A = force_on_mass(model, cfg, i, t, x, v);
        const double friction = model.masses[i].has_friction ? model.masses[i].mu_k * model.normal_force(i) : 0.0;
        a[i] = (A - friction * sgn[i]) / model.masses[i].m;
        a[n + i] = (std::fabs(A) + friction) / model.masses[i].m;  // magnitude of its terms
    }
    return a;
}

// Magnitude of the terms of dA_i/dt (force_rate_on_mass) at (t, v, a), its
// rounding level: a[n..2n-1] holds the magnitudes of the accelerations' terms.
double force_rate_magnitude(const Model& model, const Configuration& cfg, int i, const double* v,
                            const std::vector<double>& a) {
    auto body = [](const double* y, int b) { return b == kGround ? 0.0 : std::fabs(y[b]); };
    const double* amag = a.data() + model.dof();
    double f = std::fabs(model.alpha) * model.masses[i].m * amag[i];
    for (const Harmonic& h : model.forcing) f += std::fabs(h.amplitude[i] * h.omega);
    auto add = [&](int p, int q, double k) {
        if (p != i && q != i) return;
        f += k * (body(v, p) + body(v, q)) + std::fabs(model.beta) * k * (body(amag, p) + body(amag, q));
    };
    for (const Spring& s : model.springs) add(s.a, s.b, s.k);
    for (std::size_t c = 0; c < model.contacts.size(); ++c)
        if (cfg.closed[c]) add(model.contacts[c].a, model.contacts[c].b, model.contacts[c].k);
    return f;
}

// The double engine's arithmetic for the decision rules (transition_rules.h):
// forces and their derivatives from the equation of motion at (t, x, v), zero
// meaning within 16 ulps of the magnitude of the terms.
class DoublePhysics {
public:
    using Scalar = double;
    DoublePhysics(const Model& model, double t, const double* x, double* v, const double* a)
        : model_(model), t_(t), x_(x), v_(v), a_(a), n_(static_cast<int>(model.dof())) {}

    int sign(double y) const { return y > 0 ? 1 : y < 0 ? -1 : 0; }
    bool negligible(double value, double magnitude) const { return std::fabs(value) <= 16 * kEps * magnitude; }
    double abs(double y) const { return std::fabs(y); }
    int dof() const { return n_; }
    std::size_t contacts() const { return model_.contacts.size(); }
    bool has_friction(int i) const { return model_.masses[i].has_friction; }
    int velocity_sign(int i) const { return sign(v_[i]); }
    void stop(int i) { v_[i] = 0.0; }
    double force(const Configuration& cfg, int i) const { return force_on_mass(model_, cfg, i, t_, x_, v_); }
    double static_limit(int i) const { return model_.masses[i].mu_s * model_.normal_force(i); }
    double held_rate(const Configuration& cfg, int i) const {
        std::vector<double> held(model_.dof(), 0.0);
        if (a_) held.assign(a_, a_ + model_.dof());
        held[i] = 0.0;
        return force_rate_on_mass(model_, cfg, i, t_, v_, held.data());
    }
    // Derivatives up to the order past which a linear motion with its forcing
    // cannot keep them all zero (2n + 2H + 2).
    rules::Series<double> held_series(const Configuration& hold, const std::vector<signed char>& sgn, int i) const {
        rules::Series<double> s;
        const int order = static_cast<int>(2 * model_.dof() + 2 * model_.forcing.size() + 2);
        force_series(model_, hold, sgn, i, t_, x_, v_, order, s.d, s.mag);
        return s;
    }
    rules::Series<double> gap_now(int c) const {
        const Contact& k = model_.contacts[c];
        return {{gap(model_, c, x_), gap_rate(model_, c, v_)},
                {std::fabs(body(x_, k.a)) + std::fabs(body(x_, k.b)) + std::fabs(k.gap),
                 std::fabs(body(v_, k.a)) + std::fabs(body(v_, k.b))}};
    }
    void prepare_ties(const Configuration& cfg, const std::vector<signed char>& sgn) {
        cfg_ = cfg;
        acc_ = accelerations(model_, cfg, sgn, t_, x_, v_);
    }
    // G, G', then G'' from the accelerations of the prepared configuration and
    // G''' = A_a'/m_a - A_b'/m_b (friction forces are constant; stuck masses do not move).
    rules::Series<double> tied_gap_series(int c) const {
        const Contact& k = model_.contacts[c];
        rules::Series<double> s = gap_now(c);
        const double* amag = acc_.data() + model_.dof();  // |A| + mu_k N over m: the rounding level of a
        s.d.push_back(body(acc_.data(), k.a) - body(acc_.data(), k.b));
        s.mag.push_back(body(amag, k.a) + body(amag, k.b));
        auto jerk = [&](int b, bool level) {
            if (b == kGround || cfg_.stuck[b]) return 0.0;
            return (level ? force_rate_magnitude(model_, cfg_, b, v_, acc_)
                          : force_rate_on_mass(model_, cfg_, b, t_, v_, acc_.data())) /
                   model_.masses[b].m;
        };
        s.d.push_back(jerk(k.a, false) - jerk(k.b, false));
        s.mag.push_back(jerk(k.a, true) + jerk(k.b, true));
        return s;
    }

private:
    static double body(const double* y, int b) { return b == kGround ? 0.0 : y[b]; }
    const Model& model_;
    double t_;
    const double* x_;
    double* v_;
    const double* a_;
    int n_;
    Configuration cfg_;
    std::vector<double> acc_;
};

}  // namespace

bool apply_switches(const Model& model, double t, const double* x, double* v, const double* a, Configuration& cfg,
                    std::vector<signed char>& sgn, const std::vector<SwitchFunction>& switched,
                    std::vector<Transition>& out, std::string& why) {
    DoublePhysics p(model, t, x, v, a);
    if (rules::apply_switches(p, cfg, sgn, switched, out)) return true;
    why = "friction decisions at t = " + std::to_string(t) + " do not settle";
    return false;
}

Configuration entered_configuration(const Model& model, double t, const double* x, const double* v,
                                    std::vector<signed char>& sgn) {
    Configuration cfg = Configuration::all_open(model);
    // Nothing stops at t0: v is only read.
    DoublePhysics p(model, t, x, const_cast<double*>(v), nullptr);
    rules::entered_configuration(p, cfg, sgn);
    return cfg;
}

}  // namespace hsnc
