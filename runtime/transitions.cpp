#include "transitions.h"

#include <cmath>
#include <algorithm>
#include <limits>

#include "assembly.h"
#include "tie_series.h"

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
    int tie_order() const { return hsnc::tie_order(model_); }
    rules::Series<double> held_series(const Configuration& hold, const std::vector<signed char>& sgn, int i,
                                      int order) const {
        rules::Series<double> s;
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
        sgn_ = sgn;
    }
    // G^(k), k = 0..order, in the prepared configuration: the motion's
    // derivatives from the equation of motion (tie_series.h).
    rules::Series<double> tied_gap_series(int c, int order) const {
        const MotionSeries m = motion_series(model_, cfg_, sgn_.data(), t_, 0.0, x_, v_, order + 1);
        rules::Series<double> s;
        switch_series(model_, cfg_, SwitchFunction{SwitchKind::gap, c}, t_, 0.0, m, s.d, s.mag);
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
    std::vector<signed char> sgn_;
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
