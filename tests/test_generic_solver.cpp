// Tests of the generic closed-form segment solver (runtime/solvers/generic_solver.h).
//
// Three kinds: closed-form answers written here independently (free sliding
// mass, critical damping, exact undamped resonance, rigid + elastic pair, stuck
// coupling), randomised consistency over many small systems (initial state,
// derivatives by central differences, the physical ODE residual, an independent
// fixed-step RK4 integration, the second-derivative bound), and special regimes
// hit on purpose (damping ratios around 1, heavy damping, near resonance, large t0).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include "assembly.h"
#include "configuration.h"
#include "engine_runner.h"
#include "fe_models.h"
#include "generic_solver.h"
#include "kernel_mode.h"
#include "model_reader.h"
#include "segment_solver.h"

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
            else if (model.has_friction(i))
                r(i) -= model.friction_slot(i).mu_k * model.normal_force(i) * sgn[i];
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
            if (model.has_friction(i)) r(i) += model.friction_slot(i).mu_k * model.normal_force(i);
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
        m.masses.push_back({"m" + std::to_string(i), uni(rng, 0.5, 2.0)});
        if (uni(rng, 0, 1) < 0.5) {
            FrictionSlot& f = m.set_friction(static_cast<std::size_t>(i));
            f.active = true;
            f.mu_k = uni(rng, 0.0, 0.5);
            f.mu_s = f.mu_k + uni(rng, 0.0, 0.3);
        }
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
        if (!m.has_friction(i)) continue;
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
    // A power of two, so that tau +- h and tau +- 2h are exact and the
    // differences are not polluted by the rounding of the abscissae.
    const double h = std::exp2(std::floor(std::log2(1e-3 / rate)));
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
        if (!ph.cfg.stuck[i]) {
            EXPECT_LE(std::abs(res(i)), 1e-12 * size(i)) << what << " residual[" << i << "]";
        }
    // Switch function values from their definitions (segment.h).
    for (std::size_t f = 0; f < ns; ++f) {
        const SwitchFunction& sf = s.switches()[f];
        double expect = 0.0;
        if (sf.kind == SwitchKind::gap) {
            expect = gap(m, sf.element, o.x.data());
        } else if (sf.kind == SwitchKind::velocity) {
            expect = o.v[sf.element];
        } else {
            const Eigen::VectorXd A = -ph.K * x - ph.C * v + ph.f + forcing(m, t0 + tau);
            const double sg = sf.kind == SwitchKind::release_pos ? 1.0 : -1.0;
            expect = sg * A(sf.element) - m.friction_slot(sf.element).mu_s * m.normal_force(sf.element);
        }
        EXPECT_NEAR(o.g[f], expect, 1e-13 * o.scale[f]) << what << " g[" << f << "]";
    }
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
        {
            // Phi^T M_F Phi = I, Phi^T K_F Phi = diag(lambda); structural rigid modes exact.
            const ModalDecomposition& md = s.modes();
            const Eigen::MatrixXd K = stiffness_matrix(m, cs.cfg);
            const int nf = static_cast<int>(md.free.size());
            Eigen::MatrixXd KF(nf, nf), MF = Eigen::MatrixXd::Zero(nf, nf);
            for (int r = 0; r < nf; ++r) {
                MF(r, r) = m.masses[md.free[r]].m;
                for (int c = 0; c < nf; ++c) KF(r, c) = K(md.free[r], md.free[c]);
            }
            const double kscale = nf == 0 ? 1.0 : std::max(1.0, KF.cwiseAbs().maxCoeff());
            EXPECT_TRUE((md.phi.transpose() * MF * md.phi).isApprox(Eigen::MatrixXd::Identity(nf, nf), 1e-13) ||
                        nf == 0) << what;
            const Eigen::MatrixXd L = md.phi.transpose() * KF * md.phi;
            for (int j = 0; j < nf; ++j)
                for (int k = 0; k < nf; ++k)
                    EXPECT_NEAR(L(j, k), j == k ? md.lambda(j) : 0.0, 1e-12 * kscale) << what;
            for (int j = 0; j < nf; ++j)
                if (md.rigid[j]) {
                    EXPECT_EQ(md.lambda(j), 0.0) << what;
                }
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

// ---------------------------------------------------------------------------
// One degree of freedom, written independently in long double:
// m x'' + c x' + k x = F0 + P sin(W t + th), underdamped or undamped off resonance.
long double sdof_ld(long double m, long double k, long double c, long double F0, long double P, long double W,
                    long double th, long double x0, long double v0, long double t) {
    const long double lam = k / m, cc = c / m, p = P / m, sig = cc / 2;
    const long double wd = std::sqrt(lam - sig * sig);
    const long double det = lam - W * W, D = det * det + cc * W * cc * W;
    const long double a = -p * cc * W / D, b = p * det / D;  // x_p = a cos + b sin
    const long double xs = F0 / k;
    const long double A = x0 - xs - (a * std::cos(th) + b * std::sin(th));
    const long double Ad = v0 - W * (-a * std::sin(th) + b * std::cos(th));
    const long double B = (Ad + sig * A) / wd;
    return xs + a * std::cos(W * t + th) + b * std::sin(W * t + th) +
           std::exp(-sig * t) * (A * std::cos(wd * t) + B * std::sin(wd * t));
}

// One mass m on a spring k to ground, Rayleigh alpha, one harmonic, a load, an
// open contact to ground (a gap function) and friction with mu_k = 0 (a
// velocity function that never adds force).
Model sdof(double m, double k, double alpha, double P, double W, double phase, double load, double x0,
           double v0) {
    Model md;
    md.name = "sdof";
    md.masses = {{"m1", m}};
    md.friction_slots = {{true, 0.0, 0.1}};
    md.springs = {{kGround, 0, k}};
    md.contacts = {{"c1", 0, kGround, 50.0, 10.0}};
    md.alpha = alpha;
    if (P != 0.0) md.forcing = {{W, phase, {P}}};
    md.load = {load};
    md.x0 = {x0};
    md.v0 = {v0};
    return md;
}

TEST(GenericSolver, DampingRatiosAroundCriticalAreContinuous) {
    const double m = 1.5, k = 6.0, w = 2.0;  // omega = sqrt(k/m) = 2
    const double xis[] = {0.0, 1e-12, 1 - 1e-9, 1.0, 1 + 1e-9, 1e3};
    const GenericSolver::Regime expect[] = {
        GenericSolver::Regime::underdamped, GenericSolver::Regime::underdamped, GenericSolver::Regime::underdamped,
        GenericSolver::Regime::critical,    GenericSolver::Regime::overdamped,  GenericSolver::Regime::overdamped};
    const signed char sgn[] = {1};
    const double taus[] = {0.0, 0.05, 0.7, 2.0, 6.0, 15.0};
    std::vector<std::vector<double>> xs;
    for (int r = 0; r < 6; ++r) {
        const Model md = sdof(m, k, 2.0 * xis[r] * w, 0.8, 3.0, 0.4, 0.5, 0.3, -1.0);
        const Configuration cfg = Configuration::all_open(md);
        GenericSolver s(md, cfg);
        ASSERT_EQ(s.regime(0), expect[r]) << "xi = " << xis[r];
        s.setup(0.0, md.x0.data(), md.v0.data(), sgn);
        std::vector<double> row;
        for (double t : taus) row.push_back(eval_at(s, 1, t).x[0]);
        xs.push_back(row);
        // No inf/nan up to 1e3 periods, and the ODE holds there.
        const Physics ph(md, cfg, {1}, md.x0.data());
        const double far = 1e3 * 2 * kPi / w;
        const Out o = eval_at(s, 1, far);
        for (double v : {o.x[0], o.v[0], o.a[0], o.g[0], o.dg[0], o.bound[0], o.scale[0], o.g[1], o.bound[1]})
            EXPECT_TRUE(std::isfinite(v)) << "xi = " << xis[r];
        check_consistency(s, md, ph, 0.0, 0.3, 2 * kPi / w, "xi = " + std::to_string(xis[r]));
        check_consistency(s, md, ph, 0.0, far, 2 * kPi / w, "xi = " + std::to_string(xis[r]) + " far");
        if (r <= 2) {
            // Underdamped: the long-double closed form (xi = 0: undamped).
            for (std::size_t i = 0; i < std::size(taus); ++i)
                EXPECT_NEAR(xs[r][i],
                            static_cast<double>(sdof_ld(m, k, m * 2.0L * xis[r] * w, 0.5, 0.8, 3.0, 0.4, 0.3, -1.0,
                                                        taus[i])),
                            1e-13)
                    << "xi = " << xis[r] << " tau = " << taus[i];
        }
        if (r == 5) {
            // xi = 1e3: two real roots, long double; far out the slow root still matters.
            const long double sig = 1e3L * w, g = std::sqrt(sig * sig - 4.0L);
            const long double r1 = -sig + g, r2 = -sig - g, c = m * 2 * sig;
            const long double W = 3.0, th = 0.4, lam = 4.0, p = 0.8L / m;
            const long double det = lam - W * W, D = det * det + (2 * sig * W) * (2 * sig * W);
            const long double a = -p * 2 * sig * W / D, b = p * det / D, xs0 = 0.5L / k;
            const long double u0 = 0.3L - xs0 - (a * std::cos(th) + b * std::sin(th));
            const long double ud0 = -1.0L - W * (-a * std::sin(th) + b * std::cos(th));
            const long double U1 = (r2 * u0 - ud0) / (r2 - r1), U2 = (ud0 - r1 * u0) / (r2 - r1);
            (void)c;
            for (double t : {0.7, 6.0, far}) {
                const long double x = xs0 + a * std::cos(W * t + th) + b * std::sin(W * t + th) +
                                      U1 * std::exp(r1 * t) + U2 * std::exp(r2 * t);
                EXPECT_NEAR(eval_at(s, 1, t).x[0], static_cast<double>(x), 1e-12) << "xi = 1e3, tau = " << t;
            }
        }
    }
    // Critical damping in closed form: x = xs + xp + e^{-w t}(A + (A' + w A) t).
    {
        const double c = 2.0 * w, lam = 4.0, W = 3.0, th = 0.4, p = 0.8 / m;
        const double det = lam - W * W, D = det * det + c * W * c * W, a = -p * c * W / D, b = p * det / D;
        const double xs0 = 0.5 / k, A = 0.3 - xs0 - (a * std::cos(th) + b * std::sin(th));
        const double Ad = -1.0 - W * (-a * std::sin(th) + b * std::cos(th));
        for (std::size_t i = 0; i < std::size(taus); ++i) {
            const double t = taus[i];
            const double x = xs0 + a * std::cos(W * t + th) + b * std::sin(W * t + th) +
                             std::exp(-w * t) * (A + (Ad + w * A) * t);
            EXPECT_NEAR(xs[3][i], x, 1e-14) << "critical, tau = " << t;
        }
    }
    // Continuity across xi = 1: the three solutions differ by O(1e-9).
    for (std::size_t i = 0; i < std::size(taus); ++i) {
        EXPECT_NEAR(xs[2][i], xs[3][i], 1e-8) << "tau = " << taus[i];
        EXPECT_NEAR(xs[4][i], xs[3][i], 1e-8) << "tau = " << taus[i];
    }
}

TEST(GenericSolver, ExactAndNearResonance) {
    const double m = 1.0, w = 3.0, P = 2.0, th = 0.4;
    const signed char sgn[] = {1};
    // Exact undamped resonance from rest: y = P/(2w) [-t cos(w t + th) + cos(th) sin(w t)/w].
    auto exact = [&](double t) { return P / (2 * w) * (-t * std::cos(w * t + th) + std::cos(th) * std::sin(w * t) / w); };
    const double T = 2 * kPi / w;
    for (double detune : {0.0, 1e-10, -1e-10}) {
        const Model md = sdof(m, w * w, 0.0, P, w * (1 + detune), th, 0.0, 0.0, 0.0);
        GenericSolver s(md, Configuration::all_open(md));
        ASSERT_TRUE(s.coupled(0, 0));
        EXPECT_NEAR(s.max_step(), T / (1 + detune), 1e-12);
        s.setup(0.0, md.x0.data(), md.v0.data(), sgn);
        for (int k = 1; k <= 40; ++k) {
            const double t = 5 * T * k / 40;
            // The detuned forcing itself differs from the resonant one by |detune| w t
            // (relative, 3e-9 after 5 periods): that is the physical difference.
            const double tol = 1e-13 + 2 * std::abs(detune) * w * t;
            EXPECT_NEAR(eval_at(s, 1, t).x[0], exact(t), tol * P * t / (2 * w)) << "detune " << detune << " t " << t;
        }
        // Linear growth: the envelope after 20 periods is P t/(2 w).
        const double t20 = 20 * T;
        EXPECT_NEAR(std::abs(eval_at(s, 1, t20).x[0]), P * t20 / (2 * w) * std::cos(th), 1e-6 * P * t20);
        const Physics ph(md, Configuration::all_open(md), {1}, md.x0.data());
        check_consistency(s, md, ph, 0.0, 0.0, s.max_step(), "resonance");
        check_consistency(s, md, ph, 0.0, 10 * T, s.max_step(), "resonance later");
    }
    // A lightly damped and a detuned sweep against the long-double closed form,
    // crossing the coupled/standard threshold; with initial motion and a load.
    for (double xi : {0.0, 1e-6, 1e-3, 2e-2})
        for (double ratio : {0.9, 0.95, 0.97, 0.99, 0.999, 1.0, 1.001, 1.03, 1.05, 1.2, 2.0}) {
            if (xi == 0.0 && ratio == 1.0) continue;
            const double W = w * ratio;
            const Model md = sdof(m, w * w, 2 * xi * w, P, W, th, 0.3, 0.2, -0.5);
            GenericSolver s(md, Configuration::all_open(md));
            s.setup(0.0, md.x0.data(), md.v0.data(), sgn);
            for (int k = 1; k <= 20; ++k) {
                const double t = 6 * T * k / 20;
                const double ref = static_cast<double>(
                    sdof_ld(m, w * w, 2.0L * xi * w * m, 0.3, P, W, th, 0.2, -0.5, t));
                EXPECT_NEAR(eval_at(s, 1, t).x[0], ref, 1e-13 * (1 + P * t))
                    << "xi " << xi << " ratio " << ratio << " t " << t << (s.coupled(0, 0) ? " coupled" : "");
            }
            const Physics ph(md, Configuration::all_open(md), {1}, md.x0.data());
            check_consistency(s, md, ph, 0.0, 3 * T, std::min(s.max_step(), 2 * T), "sweep");
        }
    // xi = 1e-12 at exact resonance behaves as the undamped secular response.
    const Model md = sdof(m, w * w, 2e-12 * w, P, w, th, 0.0, 0.0, 0.0);
    GenericSolver s(md, Configuration::all_open(md));
    s.setup(0.0, md.x0.data(), md.v0.data(), sgn);
    for (int k = 1; k <= 10; ++k) {
        const double t = 5 * T * k / 10;
        EXPECT_NEAR(eval_at(s, 1, t).x[0], exact(t), 1e-9 * P * t / (2 * w));
    }
}

TEST(GenericSolver, FreeMassWithFriction) {
    // No springs: x = x0 + v0 t - mu g t^2/2 (alpha = 0); with alpha > 0,
    // v = (v0 + mu g/alpha) e^{-alpha t} - mu g/alpha.
    for (double alpha : {0.0, 1e-12, 0.7}) {
        Model md;
        md.name = "slider";
        md.masses = {{"m1", 2.0}};
        md.friction_slots = {{true, 0.3, 0.4}};
        md.alpha = alpha;
        md.load = {0.0};
        md.x0 = {0.5};
        md.v0 = {3.0};
        const signed char sgn[] = {1};
        GenericSolver s(md, Configuration::all_open(md));
        EXPECT_EQ(s.regime(0), GenericSolver::Regime::rigid);
        s.setup(4.0, md.x0.data(), md.v0.data(), sgn);
        const double mg = 0.3 * 9.81;
        for (double t : {0.0, 0.1, 0.5, 1.0, 1.01}) {
            const Out o = eval_at(s, 1, t);
            double x, v, a;
            if (alpha == 0.7) {
                const double e = std::exp(-alpha * t);
                v = (3.0 + mg / alpha) * e - mg / alpha;
                x = 0.5 + (3.0 + mg / alpha) * (1 - e) / alpha - mg / alpha * t;
                a = -alpha * v - mg;
            } else {
                x = 0.5 + 3.0 * t - mg * t * t / 2;
                v = 3.0 - mg * t;
                a = -mg;
            }
            // alpha = 1e-12 is compared with the undamped form: the physical
            // difference is about alpha (v0 + mu g) (1 + t^2).
            const double tol = 4e-13 + (alpha < 1e-6 ? alpha * (3.0 + mg) * (1 + t * t) : 0.0);
            EXPECT_NEAR(o.x[0], x, tol) << "alpha " << alpha << " t " << t;
            EXPECT_NEAR(o.v[0], v, tol) << "alpha " << alpha << " t " << t;
            EXPECT_NEAR(o.a[0], a, tol) << "alpha " << alpha << " t " << t;
            EXPECT_EQ(o.g[0], o.v[0]);  // velocity switch function
            EXPECT_EQ(o.dg[0], o.a[0]);
            EXPECT_GE(o.bound[0], alpha * std::abs(a) * (1 - 1e-12));  // |v''| = alpha |a|, decreasing
        }
    }
}

TEST(GenericSolver, TwoMassesWithoutGround) {
    // m1 -- k -- m2, nothing to ground: one rigid mode (lambda = 0 exactly,
    // phi = 1/sqrt(M)) and one elastic mode lambda = k (1/m1 + 1/m2).
    Model md;
    md.name = "pair";
    md.masses = {{"m1", 1.0}, {"m2", 3.0}};
    md.springs = {{0, 1, 12.0}};
    md.beta = 0.05;
    md.load = {0.6, 0.0};
    md.x0 = {0.2, -0.1};
    md.v0 = {1.0, -0.5};
    GenericSolver s(md, Configuration::all_open(md));
    ASSERT_EQ(s.modes().lambda.size(), 2);
    EXPECT_TRUE(s.modes().rigid[0]);
    EXPECT_EQ(s.modes().lambda(0), 0.0);
    EXPECT_EQ(s.modes().phi(0, 0), 0.5);
    EXPECT_EQ(s.modes().phi(1, 0), 0.5);
    const double lam = 12.0 * (1.0 + 1.0 / 3.0);
    EXPECT_NEAR(s.modes().lambda(1), lam, 1e-14 * lam);
    s.setup(0.0, md.x0.data(), md.v0.data(), nullptr);
    // Centre of mass moves uniformly accelerated by the load; the relative
    // coordinate d = x1 - x2 obeys d'' + beta lam d' + lam d = F/m1.
    const double M = 4.0, xc0 = (0.2 - 0.3) / M, vc0 = (1.0 - 1.5) / M;
    const double c = 0.05 * lam, sig = c / 2, wd = std::sqrt(lam - sig * sig), ds = 0.6 / (1.0 * lam);
    const double A = 0.3 - ds, B = (1.5 + sig * A) / wd;
    for (double t : {0.0, 0.3, 1.7, 5.0, 20.0}) {
        const Out o = eval_at(s, 2, t);
        EXPECT_NEAR((1.0 * o.x[0] + 3.0 * o.x[1]) / M, xc0 + vc0 * t + 0.6 * t * t / (2 * M), 1e-13 * (1 + t * t));
        const double d = ds + std::exp(-sig * t) * (A * std::cos(wd * t) + B * std::sin(wd * t));
        EXPECT_NEAR(o.x[0] - o.x[1], d, 1e-13) << "t " << t;
    }
}

TEST(GenericSolver, StuckMassCouplingIsAConstantForce) {
    // ground -k1- m1 -k12- m2 (stuck) -k23- m3: the free masses see the
    // constant force -K[F,S] x_S = (k12 x2, k23 x2) (paper Eq. 7).
    Model md;
    md.name = "chain";
    md.masses = {{"m1", 1.0}, {"m2", 2.0}, {"m3", 0.5}};
    md.friction_slots = {{false, 0, 0}, {true, 0.2, 0.3}, {false, 0, 0}};
    const double k1 = 10, k12 = 20, k23 = 5;
    md.springs = {{kGround, 0, k1}, {0, 1, k12}, {1, 2, k23}};
    md.alpha = 3.0;
    md.beta = 0.01;
    md.load = {0.0, 0.7, 0.0};
    md.x0 = {0.1, 0.4, -0.2};
    md.v0 = {0.5, 0.0, 0.0};
    const Configuration cfg = Configuration::parse(md, "stuck=m2");
    GenericSolver s(md, cfg);
    const signed char sgn[] = {0, 0, 0};
    s.setup(0.0, md.x0.data(), md.v0.data(), sgn);
    ASSERT_EQ(s.switches().size(), 2u);  // release_pos, release_neg of m2
    // At tau = 0: accelerations and the release functions by hand.
    const Out o = eval_at(s, 3, 0.0);
    const double x1 = 0.1, x2 = 0.4, x3 = -0.2, v1 = 0.5;
    const double c11 = 3.0 * 1.0 + 0.01 * (k1 + k12), c21 = -0.01 * k12;
    EXPECT_NEAR(o.a[0], (-(k1 + k12) * x1 + k12 * x2 - c11 * v1) / 1.0, 1e-13);
    EXPECT_NEAR(o.a[2], (-k23 * x3 + k23 * x2) / 0.5, 1e-13);
    EXPECT_EQ(o.x[1], x2);
    EXPECT_EQ(o.v[1], 0.0);
    EXPECT_EQ(o.a[1], 0.0);
    const double A0 = -k12 * (x2 - x1) - k23 * (x2 - x3) - c21 * v1 + 0.7, N = 2.0 * 9.81;
    EXPECT_NEAR(o.g[0], A0 - 0.3 * N, 1e-13);
    EXPECT_NEAR(o.g[1], -A0 - 0.3 * N, 1e-13);
    // Long after: the free masses rest where the constant force holds them.
    const Out late = eval_at(s, 3, 60.0);
    const double x1s = k12 * x2 / (k1 + k12), x3s = x2;
    EXPECT_NEAR(late.x[0], x1s, 1e-12);
    EXPECT_NEAR(late.x[2], x3s, 1e-12);
    EXPECT_NEAR(late.g[0], -k12 * (x2 - x1s) + 0.7 - 0.3 * N, 1e-11);
}

TEST(GenericSolver, LargeT0OnlyShiftsThePhase) {
    // The same motion from t0 = 1e6 with phase ph, and from t0 = 0 with phase
    // ph + W*1e6 (reduced in long double): time is measured from the segment start.
    const double W = 1.25, t0 = 1e6;  // W*t0 exact in double
    const long double two_pi = 6.283185307179586476925286766559L;
    const double shifted = static_cast<double>(std::fmod(1.25e6L + 0.3L, two_pi));
    auto make = [&](double phase) {
        Model md;
        md.name = "t0";
        md.masses = {{"m1", 1.0}, {"m2", 2.0}};
        md.springs = {{kGround, 0, 4.0}, {0, 1, 3.0}};
        md.alpha = 0.05;
        md.forcing = {{W, phase, {1.0, -0.5}}};
        md.load = {0.1, 0.0};
        md.x0 = {0.2, 0.0};
        md.v0 = {0.0, 0.3};
        return md;
    };
    const Model a = make(0.3), b = make(shifted);
    GenericSolver sa(a, Configuration::all_open(a)), sb(b, Configuration::all_open(b));
    sa.setup(t0, a.x0.data(), a.v0.data(), nullptr);
    sb.setup(0.0, b.x0.data(), b.v0.data(), nullptr);
    for (double t : {0.0, 0.5, 3.0, 17.0, 40.0}) {
        const Out oa = eval_at(sa, 2, t), ob = eval_at(sb, 2, t);
        for (int i = 0; i < 2; ++i) {
            EXPECT_NEAR(oa.x[i], ob.x[i], 1e-13) << "t " << t;
            EXPECT_NEAR(oa.v[i], ob.v[i], 1e-13) << "t " << t;
        }
    }
}

// The provider's cache is bounded by memory (issue 11: a 64-mass chain kept
// 5.4 GB of configurations by t = 40 s). With a budget that holds a single
// solver, every change of configuration evicts the previous one and a return
// to it rebuilds it; the run must be the same, event for event and bit for
// bit, as with an unbounded cache (a solver depends only on its configuration).
TEST(GenericSolverProvider, BoundedCacheEvictsLeastRecentlyUsedAndRebuilds) {
    const Model m = read_model(std::string(HSNC_SOURCE_DIR) + "/models/chain-8.toml");
    auto run = [&](GenericSolverProvider& provider) {
        Engine engine(m, provider);
        testing::Recorder rec(m.dof());
        EngineOptions opt;
        opt.t_end = 5.0;
        opt.samples = false;
        const RunSummary s = engine.run(opt, rec);
        EXPECT_EQ(s.status, RunStatus::ok) << s.message;
        return rec.events;
    };
    GenericSolverProvider unbounded(m, std::numeric_limits<std::size_t>::max());
    GenericSolverProvider one(m, 1);  // below any solver's size: keeps only the one in use
    const auto a = run(unbounded), b = run(one);
    EXPECT_EQ(unbounded.evicted(), 0u);
    EXPECT_EQ(unbounded.built(), unbounded.cached());
    ASSERT_GT(unbounded.cached(), 3u) << "the run should visit several configurations";
    EXPECT_EQ(one.cached(), 1u);
    EXPECT_GT(one.evicted(), 0u);
    EXPECT_GT(one.built(), unbounded.built()) << "revisited configurations are rebuilt";
    EXPECT_EQ(one.built(), one.evicted() + one.cached());
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t k = 0; k < a.size(); ++k) {
        EXPECT_EQ(a[k].t, b[k].t) << k;
        EXPECT_EQ(a[k].kind, b[k].kind) << k;
        EXPECT_EQ(a[k].element, b[k].element) << k;
        EXPECT_EQ(a[k].x, b[k].x) << k;
    }
    EXPECT_NE(one.describe().find("rebuilt"), std::string::npos) << one.describe();

    // A budget of a few solvers: the kept ones stay within it (the one in use
    // aside), and the least recently used go first.
    GenericSolverProvider few(m, 3 * GenericSolver(m, Configuration::all_open(m)).memory_bytes());
    Configuration c0 = Configuration::all_open(m), c1 = c0, c2 = c0, c3 = c0;
    c1.closed[0] = 1;
    c2.stuck[0] = 1;
    c3.stuck[1] = 1;
    SegmentSolver* s0 = &few.solver(c0);
    few.solver(c1);
    few.solver(c2);
    EXPECT_EQ(&few.solver(c0), s0) << "c0 kept, and now the most recently used";
    few.solver(c3);  // evicts c1, the least recently used
    EXPECT_LE(few.cached_bytes(), 3 * GenericSolver(m, c0).memory_bytes() + GenericSolver(m, c3).memory_bytes());
    const std::size_t built = few.built();
    few.solver(c0);
    EXPECT_EQ(few.built(), built) << "c0 was not evicted";
    few.solver(c1);
    EXPECT_EQ(few.built(), built + 1) << "c1 was evicted and is rebuilt";
}

// resolving_rate (segment_solver.h): the fastest rate among the terms of a
// segment still larger than tol of their dof's motion. A 20-element
// consistent-mass cantilever (40 dofs, omega_max 1.7e5 rad/s) released from
// the static deflection of a tip load carries every mode. Damped (Rayleigh,
// the top modes overdamped), the stiff terms count at first and drop out as
// they decay: the rate falls, never rises, to a mode that is still ringing;
// undamped, the top mode counts at every tau. Released from mode 1's shape,
// only mode 1 (and the rounding of the others, below tol) moves.
TEST(GenericSolver, ResolvingRateFollowsTheTermsThatStillMove) {
    const fe::Beam beam = fe::cantilever(20);
    const Eigen::Index n = beam.K.rows();
    Eigen::VectorXd load = Eigen::VectorXd::Zero(n);
    load(beam.tip) = 1.0;
    const Eigen::VectorXd deflection = beam.K.ldlt().solve(load);
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(beam.K, beam.M);
    const double omega_max = std::sqrt(eig.eigenvalues()(n - 1)), omega_1 = std::sqrt(eig.eigenvalues()(0));
    const Eigen::VectorXd shape1 = 0.01 * eig.eigenvectors().col(0) / eig.eigenvectors().col(0).cwiseAbs().maxCoeff();
    testing::TempDir dir;
    auto released = [&](const std::string& damping, const Eigen::VectorXd& x0) {
        const Model m = read_model(fe::structure_model(dir, "beam.toml", "beam", beam.M, beam.K, beam.dofs, damping));
        auto solver = std::make_unique<GenericSolver>(m, Configuration::all_open(m));
        const std::vector<double> x(x0.data(), x0.data() + n), v(static_cast<std::size_t>(n), 0.0);
        const std::vector<signed char> sgn(static_cast<std::size_t>(n), 0);
        solver->setup(0.0, x.data(), v.data(), sgn.data());
        return solver;
    };
    const double tol = 1e-12;

    const auto damped = released("[damping]\nalpha = 0.2\nbeta = 2e-5\n", deflection);
    // The top mode is overdamped: its fast root -(sigma + gamma) > omega_max sets the rate at first.
    const double zeta_max = 0.5 * (0.2 / omega_max + 2e-5 * omega_max);
    ASSERT_GT(zeta_max, 1.0);
    EXPECT_NEAR(damped->resolving_rate(0.0, tol), omega_max * (zeta_max + std::sqrt(zeta_max * zeta_max - 1)),
                1e-9 * omega_max * 2 * zeta_max);
    // Falling, never rising; a mode of sigma_j = (alpha + beta omega_j^2)/2 no
    // longer counts once e^{-sigma_j tau} < tol (a term is at most its dof's
    // size), so by 0.02 s nothing above 0.1 omega_max is left; and with no
    // forcing, nothing at all once mode 1 (sigma_1 = 0.1 /s) has decayed.
    // (From 2 ms on: the overdamped roots, whose decay is their rate, are gone by then.)
    double last = damped->resolving_rate(0.0, tol);
    for (double tau : {1e-5, 1e-4, 2e-3, 1e-2, 0.02, 0.1, 1.0, 10.0}) {
        const double rate = damped->resolving_rate(tau, tol);
        EXPECT_LE(rate, last) << tau;
        if (tau >= 2e-3) EXPECT_LT(0.5 * (0.2 + 2e-5 * rate * rate) * tau, std::log(1 / tol)) << tau << ": " << rate;
        last = rate;
    }
    EXPECT_LT(damped->resolving_rate(0.02, tol), 0.1 * omega_max);
    EXPECT_GT(damped->resolving_rate(10.0, tol), omega_1);  // the modes of sigma_j * 10 s < ln(1/tol) ring on
    EXPECT_LT(damped->resolving_rate(10.0, tol), std::sqrt((2 * std::log(1 / tol) / 10.0 - 0.2) / 2e-5));
    EXPECT_EQ(damped->resolving_rate(1e3, tol), 0.0);
    // A looser tolerance lets terms go sooner, never later.
    EXPECT_LE(damped->resolving_rate(1e-3, 1e-6), damped->resolving_rate(1e-3, tol));

    const auto undamped = released("", deflection);
    for (double tau : {0.0, 1.0, 1e3})
        EXPECT_NEAR(undamped->resolving_rate(tau, tol), omega_max, 1e-9 * omega_max) << tau;

    // Mode 1 alone (the others at the rounding of the modal projection, ~1e-12
    // of the root dofs' small motion); with mode 10 at 1e-6 of it, mode 10
    // counts at a tolerance below its share and not above.
    const auto mode1 = released("", shape1);
    EXPECT_NEAR(mode1->resolving_rate(0.0, 1e-9), omega_1, 1e-9 * omega_1);
    const Eigen::VectorXd mode10 = eig.eigenvectors().col(9) / eig.eigenvectors().col(9).cwiseAbs().maxCoeff();
    const auto mixed = released("", shape1 + 1e-8 * mode10);
    const double omega_10 = std::sqrt(eig.eigenvalues()(9));
    EXPECT_NEAR(mixed->resolving_rate(0.0, 1e-9), omega_10, 1e-9 * omega_10);
    EXPECT_NEAR(mixed->resolving_rate(0.0, 1e-4), omega_1, 1e-9 * omega_1);
}

}  // namespace
}  // namespace hsnc
