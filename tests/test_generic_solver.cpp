// Tests of the generic closed-form segment solver (runtime/generic_solver.h).
//
// Three kinds: closed-form answers written here independently (free sliding
// mass, critical damping, exact undamped resonance, rigid + elastic pair, stuck
// coupling), randomised consistency over many small systems (initial state,
// derivatives by central differences, the physical ODE residual, an independent
// fixed-step RK4 integration, the second-derivative bound), and special regimes
// hit on purpose (damping ratios around 1, heavy damping, near resonance, large t0).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Dense>

#include "assembly.h"
#include "configuration.h"
#include "generic_solver.h"
#include "segment.h"

namespace hsnc {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Owns the output arrays of one eval.
struct Out {
    std::vector<double> x, v, a, g, dg, bound, scale;
    SegmentEval view;
    Out(std::size_t n, std::size_t ns)
        : x(n), v(n), a(n), g(ns), dg(ns), bound(ns), scale(ns),
          view{x.data(), v.data(), a.data(), g.data(), dg.data(), bound.data(), scale.data()} {}
};

Out eval_at(const GenericSolver& s, std::size_t n, double tau) {
    Out o(n, s.switches().size());
    s.eval(tau, o.view);
    return o;
}

// ---------------------------------------------------------------------------
// Independent physics used as the reference: the force on every mass and a
// fixed-step classical Runge-Kutta (RK4) integration of M x'' = force.

struct Physics {
    const Model& model;
    Configuration cfg;
    std::vector<signed char> sgn;
    std::vector<double> x_stuck;  // stuck positions
    Eigen::MatrixXd K, C;
    Eigen::VectorXd m, f;

    Physics(const Model& mdl, const Configuration& c, const std::vector<signed char>& s, const double* x0)
        : model(mdl), cfg(c), sgn(s), x_stuck(x0, x0 + mdl.dof()), K(stiffness_matrix(mdl, c)),
          C(damping_matrix(mdl, c)), m(mass_vector(mdl)), f(constant_force(mdl, c)) {}

    // Force on each free mass (0 on stuck ones): -K x - C v + f + F(t) - friction.
    Eigen::VectorXd force(double t, const Eigen::VectorXd& x, const Eigen::VectorXd& v) const {
        Eigen::VectorXd r = -K * x - C * v + f + forcing(model, t);
        for (std::size_t i = 0; i < model.dof(); ++i) {
            if (cfg.stuck[i]) r(i) = 0.0;
            else if (model.masses[i].has_friction) r(i) -= model.masses[i].mu_k * model.normal_force(i) * sgn[i];
        }
        return r;
    }
    // Sum of |terms| of that force, per mass.
    Eigen::VectorXd force_size(double t, const Eigen::VectorXd& x, const Eigen::VectorXd& v) const {
        Eigen::VectorXd r = K.cwiseAbs() * x.cwiseAbs() + C.cwiseAbs() * v.cwiseAbs() + f.cwiseAbs();
        for (const Harmonic& h : model.forcing)
            for (std::size_t i = 0; i < model.dof(); ++i)
                r(i) += std::abs(h.amplitude[i] * std::sin(h.omega * t + h.phase));
        for (std::size_t i = 0; i < model.dof(); ++i)
            if (model.masses[i].has_friction) r(i) += model.masses[i].mu_k * model.normal_force(i);
        return r;
    }

    // RK4 from (x0, v0) at t0 with step h; returns states at the sample times.
    void rk4(double t0, Eigen::VectorXd x, Eigen::VectorXd v, double h, int steps_per_sample, int samples,
             std::vector<Eigen::VectorXd>& xs, std::vector<Eigen::VectorXd>& vs) const {
        const Eigen::VectorXd minv = m.cwiseInverse();
        double t = t0;
        for (int s = 0; s < samples; ++s) {
            for (int k = 0; k < steps_per_sample; ++k) {
                const Eigen::VectorXd k1x = v, k1v = minv.cwiseProduct(force(t, x, v));
                const Eigen::VectorXd x2 = x + 0.5 * h * k1x, v2 = v + 0.5 * h * k1v;
                const Eigen::VectorXd k2x = v2, k2v = minv.cwiseProduct(force(t + 0.5 * h, x2, v2));
                const Eigen::VectorXd x3 = x + 0.5 * h * k2x, v3 = v + 0.5 * h * k2v;
                const Eigen::VectorXd k3x = v3, k3v = minv.cwiseProduct(force(t + 0.5 * h, x3, v3));
                const Eigen::VectorXd x4 = x + h * k3x, v4 = v + h * k3v;
                const Eigen::VectorXd k4x = v4, k4v = minv.cwiseProduct(force(t + h, x4, v4));
                x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
                v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
                t = t0 + (s * steps_per_sample + k + 1) * h;
            }
            xs.push_back(x);
            vs.push_back(v);
        }
    }
};

// ---------------------------------------------------------------------------
// Random systems.

struct Case {
    Model model;
    Configuration cfg;
    std::vector<signed char> sgn;
    double t0 = 0.0;
};

double uni(std::mt19937& rng, double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
int pick(std::mt19937& rng, int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); }

Case random_case(unsigned seed) {
    std::mt19937 rng(seed);
    Case cs;
    Model& m = cs.model;
    const int n = 1 + static_cast<int>(seed % 8);
    m.name = "random";
    for (int i = 0; i < n; ++i) {
        Mass ms{"m" + std::to_string(i), uni(rng, 0.5, 2.0), false, 0.0, 0.0};
        if (uni(rng, 0, 1) < 0.5) {
            ms.has_friction = true;
            ms.mu_k = uni(rng, 0.0, 0.5);
            ms.mu_s = ms.mu_k + uni(rng, 0.0, 0.3);
        }
        m.masses.push_back(ms);
    }
    auto k_or_zero = [&] { return uni(rng, 0, 1) < 0.2 ? 0.0 : uni(rng, 1.0, 50.0); };
    for (int i = 0; i < n; ++i) {
        if (uni(rng, 0, 1) < 0.4) m.springs.push_back({kGround, i, k_or_zero()});
        if (i > 0 && uni(rng, 0, 1) < 0.8) m.springs.push_back({i - 1, i, k_or_zero()});
    }
    if (n > 2) m.springs.push_back({pick(rng, n), pick(rng, n), k_or_zero()});
    const int nc = pick(rng, 3);
    for (int c = 0; c < nc; ++c) {
        const int a = pick(rng, n + 1) - 1, b = pick(rng, n) ;
        m.contacts.push_back({"c" + std::to_string(c), a == b ? kGround : a, b, uni(rng, -0.5, 0.5),
                              uni(rng, 5.0, 100.0)});
    }
    switch (pick(rng, 4)) {
        case 0: break;
        case 1: m.alpha = uni(rng, 0, 0.05); m.beta = uni(rng, 0, 0.002); break;
        case 2: m.alpha = uni(rng, 0, 1.0); m.beta = uni(rng, 0, 0.05); break;
        default: m.alpha = uni(rng, 0, 5.0); m.beta = uni(rng, 0, 0.3); break;
    }
    const int nh = pick(rng, 3);
    for (int h = 0; h < nh; ++h) {
        Harmonic hm{uni(rng, 0.5, 15.0), uni(rng, -3.0, 3.0), std::vector<double>(n, 0.0)};
        for (int i = 0; i < n; ++i)
            if (uni(rng, 0, 1) < 0.6) hm.amplitude[i] = uni(rng, -2.0, 2.0);
        m.forcing.push_back(hm);
    }
    m.load.resize(n);
    m.x0.resize(n);
    m.v0.resize(n);
    for (int i = 0; i < n; ++i) {
        m.load[i] = uni(rng, -1.0, 1.0);
        m.x0[i] = uni(rng, -1.0, 1.0);
        m.v0[i] = uni(rng, -2.0, 2.0);
    }
    cs.cfg = Configuration::all_open(m);
    for (std::size_t c = 0; c < m.contacts.size(); ++c) cs.cfg.closed[c] = uni(rng, 0, 1) < 0.5;
    cs.sgn.assign(n, 0);
    for (int i = 0; i < n; ++i) {
        if (!m.masses[i].has_friction) continue;
        if (uni(rng, 0, 1) < 0.4) {
            cs.cfg.stuck[i] = 1;
            m.v0[i] = 0.0;
        } else {
            cs.sgn[i] = static_cast<signed char>(pick(rng, 3) - 1);
        }
    }
    cs.t0 = uni(rng, 0.0, 10.0);
    return cs;
}

// Fastest rate in the solution (1/time): modal frequencies and damping, forcing.
double fastest_rate(const GenericSolver& s, const Model& m) {
    double r = 1.0;
    for (int j = 0; j < s.modes().lambda.size(); ++j)
        r = std::max({r, std::sqrt(s.modes().lambda(j)), s.modal_damping(j)});
    for (const Harmonic& h : m.forcing) r = std::max(r, std::abs(h.omega));
    return r;
}
// Period of the slowest elastic mode (or 5 time units if none).
double slowest_period(const GenericSolver& s) {
    double w = std::numeric_limits<double>::infinity();
    for (int j = 0; j < s.modes().lambda.size(); ++j)
        if (s.modes().lambda(j) > 0) w = std::min(w, std::sqrt(s.modes().lambda(j)));
    return std::isinf(w) ? 5.0 : std::min(2 * kPi / w, 20.0);
}

// 4th-order central difference of component k of a function of tau.
template <class F>
double central(F f, double tau, double h) {
    return (8.0 * (f(tau + h) - f(tau - h)) - (f(tau + 2 * h) - f(tau - 2 * h))) / (12.0 * h);
}

double max_abs(const std::vector<double>& v) {
    double r = 0.0;
    for (double x : v) r = std::max(r, std::abs(x));
    return r;
}

// Checks that are valid for any solver state: derivatives, ODE residual, bound.
// Returns the largest ratio |g''| / bound seen (for the tightness report).
double check_consistency(const GenericSolver& s, const Model& m, const Physics& ph, double t0, double tau,
                         double window, const std::string& what) {
    const std::size_t n = m.dof(), ns = s.switches().size();
    const double rate = fastest_rate(s, m);
    const double h = 1e-3 / rate;
    const Out o = eval_at(s, n, tau);
    // v, a against central differences of x, v.
    double xscale = 0, vscale = 0, ascale = 0;
    for (double t : {tau, tau + 0.5 * window, tau + window}) {
        const Out q = eval_at(s, n, t);
        xscale = std::max(xscale, max_abs(q.x));
        vscale = std::max(vscale, max_abs(q.v));
        ascale = std::max(ascale, max_abs(q.a));
    }
    const double tol_fd = 1e-9;
    for (std::size_t i = 0; i < n; ++i) {
        const double dx = central([&](double t) { return eval_at(s, n, t).x[i]; }, tau, h);
        const double dv = central([&](double t) { return eval_at(s, n, t).v[i]; }, tau, h);
        EXPECT_NEAR(o.v[i], dx, tol_fd * (vscale + rate * xscale)) << what << " v[" << i << "]";
        EXPECT_NEAR(o.a[i], dv, tol_fd * (ascale + rate * vscale)) << what << " a[" << i << "]";
    }
    // Physical ODE residual on the free masses: M a = -K x - C v + f + F(t) - friction.
    Eigen::Map<const Eigen::VectorXd> x(o.x.data(), n), v(o.v.data(), n), a(o.a.data(), n);
    const Eigen::VectorXd res = ph.m.cwiseProduct(a) - ph.force(t0 + tau, x, v);
    const Eigen::VectorXd size = ph.m.cwiseProduct(a.cwiseAbs()) + ph.force_size(t0 + tau, x, v);
    for (std::size_t i = 0; i < n; ++i)
        if (!ph.cfg.stuck[i]) EXPECT_LE(std::abs(res(i)), 1e-12 * size(i)) << what << " residual[" << i << "]";
    // dg against central differences of g; |g''| over [tau, tau + window] below bound(tau).
    double worst = 0.0;
    for (std::size_t f = 0; f < ns; ++f) {
        const double dgf = central([&](double t) { return eval_at(s, n, t).g[f]; }, tau, h);
        const double gs = std::max(o.scale[f], 1e-300);
        EXPECT_NEAR(o.dg[f], dgf, tol_fd * (std::abs(o.dg[f]) + rate * gs + o.bound[f] / rate))
            << what << " dg[" << f << "]";
        EXPECT_TRUE(std::isfinite(o.g[f]) && std::isfinite(o.dg[f]) && std::isfinite(o.bound[f]) &&
                    std::isfinite(o.scale[f]))
            << what;
    }
    const int grid = 200;
    for (int k = 0; k <= grid; ++k) {
        const double t = tau + window * k / grid;
        for (std::size_t f = 0; f < ns; ++f) {
            const double g2 = central([&](double u) { return eval_at(s, n, u).dg[f]; }, t, h);
            const double slack = 1e-8 * rate * rate * o.scale[f];
            EXPECT_LE(std::abs(g2), o.bound[f] * (1 + 1e-9) + slack)
                << what << " bound of switch " << f << " at tau=" << tau << " s=" << t;
            if (o.bound[f] > 0) worst = std::max(worst, std::abs(g2) / o.bound[f]);
        }
    }
    return worst;
}

// ---------------------------------------------------------------------------

TEST(GenericSolver, RandomisedConsistencyAndRk4) {
    std::vector<double> tightness;
    int rk4_cases = 0, regimes[4] = {0, 0, 0, 0}, coupled = 0, stuck = 0, closed = 0;
    for (unsigned seed = 1; seed <= 96; ++seed) {
        const Case cs = random_case(seed);
        const Model& m = cs.model;
        const std::size_t n = m.dof();
        const std::string what = "seed " + std::to_string(seed) + " (" + std::to_string(n) + " dof, " +
                                 cs.cfg.spec(m) + ")";
        GenericSolver s(m, cs.cfg);
        for (int j = 0; j < s.modes().lambda.size(); ++j) {
            ++regimes[static_cast<int>(s.regime(j))];
            for (std::size_t h = 0; h < m.forcing.size(); ++h) coupled += s.coupled(j, static_cast<int>(h));
        }
        for (char c : cs.cfg.stuck) stuck += c;
        for (char c : cs.cfg.closed) closed += c;
        s.setup(cs.t0, m.x0.data(), m.v0.data(), cs.sgn.data());
        const Physics ph(m, cs.cfg, cs.sgn, m.x0.data());

        // eval(0) reproduces the initial state.
        const Out o0 = eval_at(s, n, 0.0);
        const double x0s = max_abs(m.x0) + 1.0, v0s = max_abs(m.v0) + 1.0;
        for (std::size_t i = 0; i < n; ++i) {
            EXPECT_NEAR(o0.x[i], m.x0[i], 1e-13 * x0s) << what << " x0[" << i << "]";
            EXPECT_NEAR(o0.v[i], cs.cfg.stuck[i] ? 0.0 : m.v0[i], 1e-13 * v0s) << what << " v0[" << i << "]";
        }

        const double window = std::min(s.max_step(), 2.0 * slowest_period(s));
        for (double tau : {0.0 + 4e-3 / fastest_rate(s, m), 0.37 * slowest_period(s), 3.0 * slowest_period(s)})
            tightness.push_back(check_consistency(s, m, ph, cs.t0, tau, window, what));

        // Independent RK4 over two periods of the slowest mode; step small enough
        // for the fastest rate (global error well below the tolerance).
        const double T = 2.0 * slowest_period(s);
        const double rate = fastest_rate(s, m);
        const int samples = 8;
        int per = static_cast<int>(std::ceil(T * rate * 300.0 / samples));
        if (per * samples > 400000) continue;  // too stiff for a quick RK4 check
        ++rk4_cases;
        const double hstep = T / (per * samples);
        std::vector<Eigen::VectorXd> xs, vs;
        Eigen::VectorXd x0 = Eigen::Map<const Eigen::VectorXd>(m.x0.data(), n);
        Eigen::VectorXd v0 = Eigen::Map<const Eigen::VectorXd>(m.v0.data(), n);
        ph.rk4(cs.t0, x0, v0, hstep, per, samples, xs, vs);
        double xscale = max_abs(m.x0), vscale = max_abs(m.v0);
        for (const auto& x : xs) xscale = std::max(xscale, x.cwiseAbs().maxCoeff());
        for (const auto& v : vs) vscale = std::max(vscale, v.cwiseAbs().maxCoeff());
        for (int k = 0; k < samples; ++k) {
            const Out o = eval_at(s, n, (k + 1) * per * hstep);
            for (std::size_t i = 0; i < n; ++i) {
                EXPECT_NEAR(o.x[i], xs[k](i), 1e-9 * xscale) << what << " RK4 x[" << i << "] sample " << k;
                EXPECT_NEAR(o.v[i], vs[k](i), 1e-9 * vscale) << what << " RK4 v[" << i << "] sample " << k;
            }
        }
    }
    std::sort(tightness.begin(), tightness.end());
    std::printf("[ info ] %d RK4 cases; max |g''|/bound over windows: median %.3g, max %.3g\n", rk4_cases,
                tightness[tightness.size() / 2], tightness.back());
    std::printf("[ info ] modes: %d rigid, %d underdamped, %d overdamped; %d coupled pairs, %d stuck masses, "
                "%d closed contacts\n", regimes[0], regimes[1], regimes[3], coupled, stuck, closed);
    // The random set must reach the special paths it is meant to exercise.
    EXPECT_GE(rk4_cases, 60);
    EXPECT_GT(regimes[0], 10);
    EXPECT_GT(regimes[3], 5);
    EXPECT_GT(stuck, 10);
    EXPECT_GT(closed, 10);
}

}  // namespace
}  // namespace hsnc
