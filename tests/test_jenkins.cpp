// Jenkins elements (interface.md section 5): a spring k in series with a
// massless slider that slips at slip_force F_s, the slider's position s
// carried as state after the masses' positions.
//
// The truths are closed forms written here, independent of the solvers: the
// stuck phase is a linear oscillator with the element as a spring, the
// slipping phase one with the constant force F_s; the switch instants follow
// from k*stretch = F_s and from the relative velocity reaching 0. The energy
// balance E = T + V_springs + (k/2) stretch^2 must drop by exactly F_s times
// the slider's travel in each slip and not at all while stuck, which gives
// the hysteresis loop's dissipation 4 F_s (a - F_s/k) per cycle.
#include <gtest/gtest.h>

#include <Eigen/LU>

#include <cmath>
#include <complex>
#include <iterator>
#include <cstdio>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "assembly.h"
#include "cli_runner.h"
#include "engine_runner.h"
#include "configuration.h"
#include "engine.h"
#include "error.h"
#include "hsnc/periodic.h"
#include "hsnc/simulate.h"
#include "hsnc/sweep.h"
#include "integrators.h"
#include "kernel_mode.h"
#include "model_hash.h"
#include "model_reader.h"
#include "reference_engine.h"
#include "switch_function.h"

namespace hsnc {
namespace {

using testing::Outcome;
using Row = testing::Recorded;  // x: the masses', then the sliders

Outcome run(const Model& model, double t_end, double dt = 0.0) { return testing::simulate(model, t_end, dt); }

// One mass on a spring K to ground with a Jenkins element (k, F_s) to ground.
Model mass_with_jenkins(double m, double K, double k, double Fs, double x0, double v0) {
    Model md;
    md.name = "jenkins-1dof";
    md.masses.push_back({"m1", m});
    if (K > 0) md.springs.push_back({0, kGround, K});
    md.jenkins.push_back({"j1", 0, kGround, k, Fs});
    md.load = {0.0};
    md.x0 = {x0};
    md.v0 = {v0};
    return md;
}

// The mass of mass_with_jenkins(m, K, k, Fs, 0, v0) started moving: stuck
// (a spring K + k) until k x = F_s at t1, then slipping under -F_s about the
// centre c = -F_s/K until v = 0 at t2, then stuck.
struct OneDofSlip {
    double m = 1.0, K = 4.0, k = 16.0, Fs = 2.0, v0 = 3.0;
    double W = std::sqrt((K + k) / m), w = std::sqrt(K / m);
    double x1 = Fs / k, t1 = std::asin(x1 * W / v0) / W, v1 = v0 * std::cos(W * t1);
    double c = -Fs / K;
    double tau2 = std::atan2(v1, (x1 - c) * w) / w, x2 = c + std::hypot(x1 - c, v1 / w);
    double t2 = t1 + tau2;
    Model model() const { return mass_with_jenkins(m, K, k, Fs, 0.0, v0); }
};

// Both instants and states in closed form.
TEST(JenkinsClosedForm, SlipsAtTheSlipForceAndSticksWhereTheVelocityVanishes) {
    const OneDofSlip cf;
    const double m = cf.m, K = cf.K, k = cf.k, Fs = cf.Fs, v0 = cf.v0, W = cf.W, w = cf.w, x1 = cf.x1, t1 = cf.t1,
                 v1 = cf.v1, c = cf.c, tau2 = cf.tau2, x2 = cf.x2, t2 = cf.t2;
    const Model md = mass_with_jenkins(m, K, k, Fs, 0.0, v0);
    const Outcome r = run(md, t2 + 0.05, 0.01);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    ASSERT_EQ(r.events.size(), 2u);
    EXPECT_EQ(r.events[0].kind, EventKind::release);
    EXPECT_EQ(r.events[0].element, 1);  // dof() + 0: Model::friction_event_name
    EXPECT_EQ(md.friction_event_name(r.events[0].element), "j1");
    EXPECT_NEAR(r.events[0].t, t1, 1e-15);
    EXPECT_NEAR(r.events[0].x[0], x1, 1e-15);
    EXPECT_NEAR(r.events[0].v[0], v1, 1e-14);
    EXPECT_EQ(r.events[0].x[1], 0.0);  // the slider has not moved while stuck
    EXPECT_EQ(r.events[1].kind, EventKind::stick);
    EXPECT_NEAR(r.events[1].t, t2, 1e-14);
    EXPECT_NEAR(r.events[1].x[0], x2, 1e-14);
    EXPECT_NEAR(r.events[1].x[1], x2 - Fs / k, 1e-14);  // stretch F_s/k kept through the slip
    std::printf("release at %.17g (closed form %.17g), stick at %.17g (%.17g)\n", r.events[0].t, t1, r.events[1].t, t2);
    // Every sample against the piecewise closed form, slider included.
    double worst = 0.0;
    for (const Row& s : r.samples) {
        double x, sl;
        if (s.t <= t1) {
            x = v0 / W * std::sin(W * s.t), sl = 0.0;
        } else if (s.t <= t2) {
            const double tau = s.t - t1;
            x = c + (x1 - c) * std::cos(w * tau) + v1 / w * std::sin(w * tau), sl = x - Fs / k;
        } else {
            const double s2 = x2 - Fs / k, xc = k * s2 / (K + k);  // stuck about the new slider
            x = xc + (x2 - xc) * std::cos(W * (s.t - t2)), sl = s2;
        }
        worst = std::max({worst, std::fabs(s.x[0] - x), std::fabs(s.x[1] - sl)});
    }
    std::printf("max |x - closed form| over %zu samples: %.2g\n", r.samples.size(), worst);
    EXPECT_LT(worst, 1e-14);
    // The summary carries the slider.
    ASSERT_EQ(r.summary.slider.size(), 1u);
    EXPECT_NEAR(r.summary.slider[0], x2 - Fs / k, 1e-14);
}

// Two floating masses joined only by a Jenkins element: the relative motion is
// the element on the reduced mass mu = m1 m2 / (m1 + m2) (a free pair of rigid
// modes while it slips), the centre of mass moves uniformly.
TEST(JenkinsClosedForm, BetweenTwoFloatingMasses) {
    const double m1 = 1.0, m2 = 3.0, mu = m1 * m2 / (m1 + m2), k = 12.0, Fs = 1.5, w0 = 2.0;
    const double W = std::sqrt(k / mu);
    const double t1 = std::asin(Fs * W / (k * w0)) / W, w1 = w0 * std::cos(W * t1), t2 = t1 + mu * w1 / Fs;
    Model md;
    md.name = "jenkins-pair";
    md.masses.push_back({"a", m1});
    md.masses.push_back({"b", m2});
    md.jenkins.push_back({"joint", 0, 1, k, Fs});
    md.load = {0.0, 0.0};
    md.x0 = {0.0, 0.0};
    md.v0 = {w0, 0.0};
    const double vcm = m1 * w0 / (m1 + m2);
    const Outcome r = run(md, t2 + 0.3 / W, 0.02);  // before the stretch can come back to -F_s/k
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    ASSERT_EQ(r.events.size(), 2u);
    EXPECT_EQ(r.events[0].kind, EventKind::release);
    EXPECT_NEAR(r.events[0].t, t1, 1e-15);
    EXPECT_EQ(r.events[1].kind, EventKind::stick);
    EXPECT_NEAR(r.events[1].t, t2, 1e-14);
    EXPECT_EQ(md.friction_event_name(r.events[1].element), "joint");
    double worst = 0.0;
    for (const Row& s : r.samples) {
        // Centre of mass: uniform; relative coordinate: the 1-DOF closed form.
        const double xcm = vcm * s.t;
        double e, sl;
        if (s.t <= t1) {
            e = w0 / W * std::sin(W * s.t), sl = 0.0;
        } else if (s.t <= t2) {
            const double tau = s.t - t1;
            e = Fs / k + w1 * tau - 0.5 * Fs / mu * tau * tau, sl = e - Fs / k;
        } else {
            const double s2 = Fs / k + 0.5 * mu * w1 * w1 / Fs - Fs / k;
            e = s2 + Fs / k * std::cos(W * (s.t - t2)), sl = s2;
        }
        const double xa = xcm + m2 / (m1 + m2) * e, xb = xcm - m1 / (m1 + m2) * e;
        worst = std::max({worst, std::fabs(s.x[0] - xa), std::fabs(s.x[1] - xb), std::fabs(s.x[2] - sl)});
    }
    std::printf("max |x - closed form| over %zu samples: %.2g\n", r.samples.size(), worst);
    EXPECT_LT(worst, 1e-14);
}

// The energy of a mass on a spring K with a Jenkins element to ground.
double energy(const Model& md, const Row& r) {
    const Jenkins& j = md.jenkins[0];
    const double stretch = r.x[0] - r.x[1];
    return 0.5 * md.masses[0].m * r.v[0] * r.v[0] + 0.5 * md.springs[0].k * r.x[0] * r.x[0] +
           0.5 * j.k * stretch * stretch;
}

// A heavy mass on a soft spring drives the element through a slow, nearly
// harmonic relative motion: stuck, its energy is conserved; slipping, it drops
// by F_s times the slider's travel; so each cycle of amplitude a dissipates
// 4 F_s (a - F_s/k), the area of the hysteresis loop.
TEST(JenkinsHysteresis, DissipationPerCycleIsTheLoopArea) {
    // The loop's area per cycle, 4 F_s a = 0.4 J, against the energy K a^2/2 = 50 J.
    const double M = 1e4, K = 1e4, k = 1000.0, Fs = 1.0, a0 = 0.1;
    const Model md = mass_with_jenkins(M, K, k, Fs, 0.0, a0 * std::sqrt(K / M));
    const double T = 2 * M_PI;
    const Outcome r = run(md, 20 * T);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    ASSERT_GE(r.events.size(), 60u);
    double worst_stuck = 0.0, worst_slip = 0.0, worst_cycle = 0.0;
    std::size_t cycles = 0;
    for (std::size_t i = 1; i < r.events.size(); ++i) {
        const Row &p = r.events[i - 1], &q = r.events[i];
        const double Ep = energy(md, p), Eq = energy(md, q);
        if (p.kind == EventKind::stick) {  // stuck from p to q: conserved
            ASSERT_EQ(q.kind, EventKind::release);
            worst_stuck = std::max(worst_stuck, std::fabs(Eq - Ep) / Ep);
        } else {  // slipping: F_s times the travel
            ASSERT_EQ(q.kind, EventKind::stick);
            const double lost = Fs * std::fabs(q.x[1] - p.x[1]);
            worst_slip = std::max(worst_slip, std::fabs((Ep - Eq) - lost) / lost);
        }
        // One cycle: from a stick to the stick two slips later, against the
        // loop area 4 F_s (a - F_s/k) with a the mean of its turning amplitudes
        // (exact for a loop whose amplitude changes between half-cycles:
        // F_s (|x_0| + 2|x_1| + |x_2| - 4 F_s/k)).
        if (q.kind == EventKind::stick && i >= 4 && r.events[i - 4].kind == EventKind::stick) {
            const Row &s0 = r.events[i - 4], &s1 = r.events[i - 2];
            const double area = Fs * (std::fabs(s0.x[0]) + 2 * std::fabs(s1.x[0]) + std::fabs(q.x[0]) - 4 * Fs / k);
            const double lost = energy(md, s0) - energy(md, q);
            worst_cycle = std::max(worst_cycle, std::fabs(lost - area) / area);
            const double a = std::fabs(s1.x[0]);
            EXPECT_NEAR(lost, 4 * Fs * (a - Fs / k), 1e-3 * lost);  // the quasi-static loop
            ++cycles;
        }
    }
    std::printf("%zu events, %zu cycles: stuck energy drift %.2g, slip loss error %.2g, cycle loss error %.2g\n",
                r.events.size(), cycles, worst_stuck, worst_slip, worst_cycle);
    EXPECT_GE(cycles, 15u);
    EXPECT_LT(worst_stuck, 1e-12);
    EXPECT_LT(worst_slip, 1e-9);
    EXPECT_LT(worst_cycle, 1e-9);
}

// Below the slip amplitude F_s/k the element is a spring: no event, no loss.
TEST(JenkinsHysteresis, NoSlipAndNoLossBelowTheSlipAmplitude) {
    const double M = 100.0, K = 100.0, k = 1000.0, Fs = 1.0, W = std::sqrt((K + k) / M);
    const double amplitude = 0.9 * Fs / k;
    const Model md = mass_with_jenkins(M, K, k, Fs, 0.0, amplitude * W);
    const Outcome r = run(md, 50.0, 0.5);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    EXPECT_TRUE(r.events.empty());
    double worst = 0.0;
    for (const Row& s : r.samples) worst = std::max(worst, std::fabs(s.x[0] - amplitude * std::sin(W * s.t)));
    EXPECT_LT(worst, 1e-16);
}

// Two independent solvers on one model with every kind of switch: the modal
// GenericSolver with Rayleigh alpha, and the StateSpaceSolver with alpha
// written as dampers alpha*m_i to ground (no code in common but the switch
// values and the engine). A chain with a contact, a friction mass, a
// Jenkins element between two masses and one to ground, forced.
TEST(JenkinsEquivalence, ModalAndStateSpaceSolversAgree) {
    const char* text = R"(name = "jenkins-chain"
[[mass]]
name = "m1"
m = 1.0
[[mass]]
name = "m2"
m = 0.7
mu_k = 0.05
mu_s = 0.08
[[mass]]
name = "m3"
m = 1.3
[[spring]]
between = ["ground", "m1"]
k = 40.0
[[spring]]
between = ["m1", "m2"]
k = 25.0
[[spring]]
between = ["m2", "m3"]
k = 30.0
[[jenkins]]
name = "joint"
between = ["m1", "m2"]
k = 60.0
slip_force = 0.8
[[jenkins]]
name = "root"
between = ["m3", "ground"]
k = 80.0
slip_force = 1.2
[[contact]]
name = "stop"
between = ["m3", "ground"]
gap = 0.06
k = 500.0
[damping]
alpha = 0.2
[[forcing]]
omega = 5.5
amplitude = { m1 = 3.0 }
)";
    const Model prop = parse_model(text, "jenkins-chain.toml");
    Model dmp = prop;
    for (std::size_t i = 0; i < dmp.dof(); ++i)
        dmp.dampers.push_back({static_cast<int>(i), kGround, prop.alpha * prop.masses[i].m});
    dmp.alpha = 0.0;
    const double t_end = 30.0;
    const Outcome a = run(prop, t_end), b = run(dmp, t_end);
    ASSERT_EQ(a.summary.status, RunStatus::ok) << a.summary.message;
    ASSERT_EQ(b.summary.status, RunStatus::ok) << b.summary.message;
    ASSERT_EQ(a.events.size(), b.events.size());
    std::size_t jenkins = 0, others = 0;
    double dt = 0.0, dx = 0.0;
    for (std::size_t e = 0; e < a.events.size(); ++e) {
        ASSERT_EQ(a.events[e].kind, b.events[e].kind) << "event " << e;
        ASSERT_EQ(a.events[e].element, b.events[e].element) << "event " << e;
        const bool contact = a.events[e].kind == EventKind::contact_close || a.events[e].kind == EventKind::contact_open;
        (!contact && a.events[e].element >= static_cast<int>(prop.dof()) ? jenkins : others) += 1;
        dt = std::max(dt, std::fabs(a.events[e].t - b.events[e].t));
        for (std::size_t i = 0; i < prop.state_size(); ++i)
            dx = std::max(dx, std::fabs(a.events[e].x[i] - b.events[e].x[i]));
    }
    std::printf("%zu events (%zu of the Jenkins elements) over %g s: modal vs state-space max |dt| %.2g s, |dx| %.2g m\n",
                a.events.size(), jenkins, t_end, dt, dx);
    EXPECT_GE(jenkins, 20u);
    EXPECT_GE(others, 10u);
    EXPECT_LT(dt, 1e-10);
    EXPECT_LT(dx, 1e-10);
}

// A response curve of the bundled friction damper: from the slipping
// resonance up to where it stays stuck. There the steady state is linear,
// the element a spring, so the first harmonic of each mass is
// |(K_stuck - W^2 M + i W C)^-1 F| whatever slider offset the slips before
// left; the points carry the slider (it is not reset to unstretched).
TEST(JenkinsSweep, StuckPointsFollowTheLinearResponseWithTheSliderCarried) {
    std::string text;
    {
        std::ifstream in(std::string(HSNC_SOURCE_DIR) + "/examples/jenkins/friction_damper.toml");
        text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    SweepOptions o;
    o.param = "omega";
    o.from = 9.0;
    o.to = 15.0;
    o.points = 7;
    o.max_periods = 3000;
    const SweepResult r = SweepPlan(text, "friction_damper.toml", {}, o).run();
    const Model m = parse_model(text, "friction_damper.toml");
    const Configuration stuck = Configuration::all_open(m);  // every Jenkins element stuck
    const Eigen::MatrixXd K = stiffness_matrix(m, stuck), C = damping_matrix(m, stuck);
    const Eigen::VectorXd M = mass_vector(m);
    ASSERT_EQ(r.points.size(), 7u);
    double worst = 0.0, offset = 0.0;
    std::size_t linear = 0;
    for (const SweepPoint& p : r.points) {
        SCOPED_TRACE("omega = " + std::to_string(p.value));
        EXPECT_TRUE(p.settled);
        if (p.value < 12.5) continue;  // slipping there (a loop each period)
        ++linear;
        const double W = p.value;
        Eigen::MatrixXcd H = K.cast<std::complex<double>>();
        for (int i = 0; i < 2; ++i) H(i, i) -= W * W * M(i);
        H += std::complex<double>(0.0, W) * C.cast<std::complex<double>>();
        const Eigen::VectorXcd X = H.partialPivLu().solve(2.0 * Eigen::VectorXcd::Unit(2, 0));  // 2 N on the airfoil
        for (int i = 0; i < 2; ++i) {
            worst = std::max(worst, std::fabs(p.a1[static_cast<std::size_t>(i)] / std::abs(X(i)) - 1.0));
            offset = std::max(offset, p.xmax[static_cast<std::size_t>(i)] - std::abs(X(i)));
        }
    }
    std::printf("%zu stuck points: first harmonic against the linear response %.2g relative; "
                "the slips before left an offset of up to %.3g m\n", linear, worst, offset);
    EXPECT_EQ(linear, 3u);
    EXPECT_LT(worst, 1e-8);
    EXPECT_GT(offset, 1e-4);  // the slider kept where it last stuck, so x is offset: it was carried
}

// The bundled under-platform damper: two identical blades forced out of
// phase, the damper mass between their platforms through two Jenkins
// contacts. The motion is antisymmetric (x_airfoil2 = -x_airfoil1, the
// damper mass at rest), so both contacts release and stick at the same
// instants: two elements switching together, hundreds of times. (A stick
// comes at the root of each contact's relative velocity, found apart: the
// two are apart by the rounding of the state over the relative acceleration.)
TEST(JenkinsSymmetry, TheUnderPlatformDamperStaysAntisymmetric) {
    ModelOverrides set;
    set.set = {"omega=8.3"};
    const Model md = read_model(std::string(HSNC_SOURCE_DIR) + "/examples/jenkins/under_platform_damper.toml", set);
    const Outcome r = run(md, 40.0, 0.01);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    const int a1 = md.mass_index("airfoil1"), a2 = md.mass_index("airfoil2"), p1 = md.mass_index("platform1"),
              p2 = md.mass_index("platform2"), d = md.mass_index("damper");
    double asym = 0.0, damper = 0.0, amplitude = 0.0;
    for (const Row& s : r.samples) {
        asym = std::max({asym, std::fabs(s.x[a1] + s.x[a2]), std::fabs(s.x[p1] + s.x[p2])});
        damper = std::max(damper, std::fabs(s.x[d]));
        amplitude = std::max(amplitude, std::fabs(s.x[a1]));
    }
    // Events come in pairs, one per contact, of the same kind, at one instant to rounding.
    std::size_t pairs = 0;
    double apart = 0.0;
    for (std::size_t e = 0; e + 1 < r.events.size(); e += 2) {
        apart = std::max(apart, r.events[e + 1].t - r.events[e].t);
        ASSERT_LT(r.events[e + 1].t - r.events[e].t, 1e-11) << "event " << e;
        ASSERT_EQ(r.events[e].kind, r.events[e + 1].kind) << "event " << e;
        ASSERT_NE(r.events[e].element, r.events[e + 1].element) << "event " << e;
        ++pairs;
    }
    std::printf("%zu event pairs over 40 s, at most %.2g s apart: |x1 + x2| <= %.2g, |x_damper| <= %.2g m of an "
                "amplitude %.3g m\n", pairs, apart, asym, damper, amplitude);
    EXPECT_EQ(r.events.size() % 2, 0u);
    EXPECT_GE(pairs, 100u);
    EXPECT_LT(asym, 1e-12);  // measured 6.4e-14 m
    EXPECT_LT(damper, 1e-12);  // measured 7e-14 m
}

// Against an independent integrator: CVODE (Adams, rtol 1e-12) with its own
// root finding, the sliders carried beside its state (stuck: fixed; slipping:
// x[a] - x[b] - slip F_s/k), on the chain of JenkinsEquivalence, the bundled
// friction damper and the under-platform damper (two elements at once).
TEST(JenkinsCvode, EventsAgreeWithCvode) {
#if !HSNC_WITH_CVODE
    GTEST_SKIP() << "built without CVODE";
#endif
    const std::string dir = std::string(HSNC_SOURCE_DIR) + "/examples/jenkins/";
    ModelOverrides at_resonance;
    at_resonance.set = {"omega=8.3"};
    for (const auto& [name, md] : {std::pair{"friction damper", read_model(dir + "friction_damper.toml")},
                                   std::pair{"under-platform damper", read_model(dir + "under_platform_damper.toml", at_resonance)}}) {
        SCOPED_TRACE(name);
        const double t_end = 10.0;
        const Outcome a = run(md, t_end), rec = testing::baseline(md, t_end, 1e-12, 1e-14, Method::cvode);
        const RunSummary& s = rec.summary;
        ASSERT_EQ(a.summary.status, RunStatus::ok) << a.summary.message;
        ASSERT_EQ(s.status, RunStatus::ok) << s.message;
        ASSERT_EQ(a.events.size(), rec.events.size());
        double dt = 0.0, ds = 0.0;
        for (std::size_t e = 0; e < a.events.size(); ++e) {
            // Rows of one instant to rounding may come in either order (the two contacts together):
            // the row of the same kind and element among its neighbours.
            std::size_t f = e;
            for (const std::size_t c : {e, e + 1, e - 1})
                if (c < rec.events.size() && rec.events[c].kind == a.events[e].kind &&
                    rec.events[c].element == a.events[e].element) {
                    f = c;
                    break;
                }
            ASSERT_EQ(a.events[e].kind, rec.events[f].kind) << "event " << e;
            ASSERT_EQ(a.events[e].element, rec.events[f].element) << "event " << e;
            dt = std::max(dt, std::fabs(a.events[e].t - rec.events[f].t));
            for (std::size_t j = 0; j < md.jenkins.size(); ++j)
                ds = std::max(ds, std::fabs(a.events[e].x[md.dof() + j] - rec.events[f].x[md.dof() + j]));
        }
        std::printf("%s: %zu events over %g s, hsnc against CVODE at most %.2g s and %.2g m (sliders) apart\n", name,
                    a.events.size(), t_end, dt, ds);
        EXPECT_GE(a.events.size(), 20u);
        EXPECT_LT(dt, 1e-9);
        EXPECT_LT(ds, 1e-9);
        ASSERT_EQ(s.slider.size(), md.jenkins.size());
        for (std::size_t j = 0; j < md.jenkins.size(); ++j) EXPECT_NEAR(s.slider[j], a.summary.slider[j], 1e-9);
    }
}

// ---- the model file, the facade and the command line ----

const char* kModel = R"(name = "jenkins-test"
[[mass]]
name = "m1"
m = 1.0
[[spring]]
between = ["ground", "m1"]
k = 4.0
[initial]
v = { m1 = 3.0 }
)";

std::string input_error(const std::string& text) {
    try {
        parse_model(text, "j.toml");
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << "no error for:\n" << text;
    return "";
}

TEST(JenkinsReader, KeysAndErrors) {
    const Model md = parse_model(std::string(kModel) + "[[jenkins]]\nbetween = [\"m1\", \"ground\"]\nk = 16\nslip_force = 2\n",
                                 "j.toml");
    ASSERT_EQ(md.jenkins.size(), 1u);
    EXPECT_EQ(md.jenkins[0].name, "jenkins1");
    EXPECT_EQ(md.jenkins[0].a, 0);
    EXPECT_EQ(md.jenkins[0].b, kGround);
    EXPECT_EQ(md.jenkins[0].k, 16.0);
    EXPECT_EQ(md.jenkins[0].slip_force, 2.0);
    EXPECT_EQ(md.state_size(), 2u);
    const std::string j = std::string(kModel) + "[[jenkins]]\nname = \"j1\"\nbetween = [\"m1\", \"ground\"]\n";
    EXPECT_EQ(input_error(j + "slip_force = 2\n"), "j.toml:10: key 'jenkins[1].k': required key is missing");
    EXPECT_EQ(input_error(j + "k = 16\n"), "j.toml:10: key 'jenkins[1].slip_force': required key is missing");
    EXPECT_EQ(input_error(j + "k = 0\nslip_force = 2\n"), "j.toml:13: key 'jenkins[1].k': stiffness must be > 0, got 0");
    EXPECT_EQ(input_error(j + "k = 16\nslip_force = -1\n"),
              "j.toml:14: key 'jenkins[1].slip_force': must be > 0, got -1");
    EXPECT_NE(input_error(j + "k = 16\nslip_force = 2\nmu = 1\n").find("jenkins[1]"), std::string::npos);
    EXPECT_NE(input_error(std::string(kModel) + "[[jenkins]]\nname = \"m1\"\nbetween = [\"m1\", \"ground\"]\nk = 1\n"
                                                "slip_force = 1\n")
                  .find("key 'jenkins[1].name': name 'm1' is already used"),
              std::string::npos);
    EXPECT_NE(input_error(std::string(kModel) + "[[jenkins]]\nbetween = [\"m1\", \"m1\"]\nk = 1\nslip_force = 1\n")
                  .find("key 'jenkins[1].between': connects 'm1' to itself"),
              std::string::npos);
    // The hash (kernel cache keys) and the configuration text see the elements.
    const Model other = parse_model(j + "k = 16\nslip_force = 2.5\n", "j.toml");
    EXPECT_NE(model_canonical_text(md), model_canonical_text(other));
    Configuration cfg = Configuration::parse(other, "closed= stuck= slip=j1-");
    EXPECT_EQ(cfg.slip, std::vector<signed char>{-1});
    EXPECT_EQ(cfg.spec(other), "closed= stuck= slip=j1-");
    EXPECT_EQ(cfg.key(), "c_s0_jn");
    EXPECT_THROW(Configuration::parse(other, "slip=j1"), InputError);
    EXPECT_EQ(switch_functions(other, cfg).size(), 1u);
    EXPECT_EQ(switch_functions(other, Configuration::all_open(other)).size(), 2u);
}

// Every kernel kind that is not bundled runs the closed form of the
// derivation: the interpreter and the JIT give the closed-form instants of
// the test above, to the bit alike.
TEST(JenkinsFacade, TheDerivedKernelsRunTheClosedForm) {
    const OneDofSlip cf;
    const double k = cf.k, Fs = cf.Fs, t1 = cf.t1, t2 = cf.t2;
    const Model md = cf.model();
    SimulateOptions o;
    o.t_end = t2 + 0.05;
    o.use_cache = false;
    std::vector<std::vector<double>> rows;
    for (KernelChoice kind : {KernelChoice::interp, KernelChoice::jit}) {
        o.kernels = kind;
        testing::Recorder rec(md.dof(), md.state_size());
        const SimulateSummary s = simulate(md, o, rec);
        ASSERT_EQ(s.status, RunStatus::ok) << s.message;
        ASSERT_EQ(rec.events.size(), 2u) << kernel_choice_name(kind);
        EXPECT_EQ(rec.events[0].kind, EventKind::release);
        EXPECT_EQ(rec.events[1].kind, EventKind::stick);
        EXPECT_NEAR(rec.events[0].t, t1, 1e-15) << kernel_choice_name(kind);
        EXPECT_NEAR(rec.events[1].t, t2, 1e-14) << kernel_choice_name(kind);
        EXPECT_NEAR(rec.events[1].x[1], rec.events[1].x[0] - Fs / k, 1e-15) << "the slider after the slip";
        std::vector<double> all;
        for (const Row& e : rec.events) {
            all.push_back(e.t);
            all.insert(all.end(), e.x.begin(), e.x.end());
            all.insert(all.end(), e.v.begin(), e.v.end());
        }
        rows.push_back(all);
    }
    EXPECT_EQ(rows[0], rows[1]) << "interpreter and JIT, bit for bit";
    o.kernels = KernelChoice::aot;  // no ahead-of-time kernels for a model built here
    EXPECT_THROW(simulate(md, o), OptionError);
}

// The CLN reference carries the sliders too (reference/mp_segment.h): at 40
// digits the 1-DOF closed form's instants, and the bundled damper's events
// and sliders against the double engine.
TEST(JenkinsReference, ClosedFormAndTheDamperAt40Digits) {
    const OneDofSlip cf;
    const double k = cf.k, Fs = cf.Fs, t1 = cf.t1, t2 = cf.t2;
    const Model md = cf.model();
    EngineOptions opt;
    opt.t_end = t2 + 0.05;
    opt.samples = false;
    testing::Recorder rec(md.dof(), md.state_size());
    const reference::PreciseRun r = reference::simulate_precise(md, 40, opt, rec);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    ASSERT_EQ(rec.events.size(), 2u);
    EXPECT_EQ(rec.events[0].kind, EventKind::release);
    EXPECT_EQ(rec.events[1].kind, EventKind::stick);
    EXPECT_NEAR(rec.events[0].t, t1, 1e-15);
    EXPECT_NEAR(rec.events[1].t, t2, 1e-15);
    EXPECT_NEAR(rec.events[1].x[1], rec.events[1].x[0] - Fs / k, 1e-16) << "the slider after the slip";
    ASSERT_EQ(r.summary.slider.size(), 1u);

    const Model damper = read_model(std::string(HSNC_SOURCE_DIR) + "/examples/jenkins/friction_damper.toml");
    EngineOptions o10;
    o10.t_end = 10.0;
    o10.samples = false;
    testing::Recorder ref(damper.dof(), damper.state_size());
    const reference::PreciseRun rr = reference::simulate_precise(damper, 40, o10, ref);
    ASSERT_EQ(rr.summary.status, RunStatus::ok) << rr.summary.message;
    const testing::Outcome dbl = run(damper, 10.0);
    ASSERT_EQ(ref.events.size(), dbl.events.size());
    double dt = 0.0, ds = 0.0;
    for (std::size_t e = 0; e < ref.events.size(); ++e) {
        EXPECT_EQ(ref.events[e].kind, dbl.events[e].kind) << "event " << e;
        dt = std::max(dt, std::fabs(ref.events[e].t - dbl.events[e].t));
        ds = std::max(ds, std::fabs(ref.events[e].x[2] - dbl.events[e].x[2]));
    }
    std::printf("friction damper, 10 s: %zu events, double engine against the 40-digit reference %.2g s, "
                "sliders %.2g m\n", ref.events.size(), dt, ds);
    EXPECT_GE(ref.events.size(), 50u);
    EXPECT_LT(dt, 1e-13);
    EXPECT_LT(ds, 1e-14);
}

TEST(JenkinsFacade, WhatCannotCarryTheSliderIsRefused) {
    const Model md = mass_with_jenkins(1.0, 4.0, 16.0, 2.0, 0.0, 3.0);
    SimulateOptions o;
    o.t_end = 1.0;
    o.kernels = KernelChoice::automatic;
    o.method = Method::ab4;
    o.integrator.h = 1e-3;
    EXPECT_THROW(simulate(md, o), OptionError);
    o.method = Method::rk45;  // the slider carried beside its state (tested against hsnc below)
    EXPECT_EQ(simulate(md, o).events, 3u);
    o.method = Method::hsnc;
    o.precision_digits = 30;  // the reference carries the slider (JenkinsReference below)
    EXPECT_EQ(simulate(md, o).events, 3u);
    o.precision_digits = 0;
    std::vector<std::size_t> events;
    for (KernelChoice k : {KernelChoice::automatic, KernelChoice::eigen}) {
        o.kernels = k;
        const RunSummary s = simulate(md, o);
        EXPECT_EQ(s.status, RunStatus::ok);
        events.push_back(s.events);
    }
    EXPECT_GE(events[0], 2u);
    EXPECT_EQ(events[0], events[1]);
    PeriodicOptions po;  // the tangent carries the slider (tests/test_stick_tangent.cpp)
    po.period = 1.0;
    EXPECT_NO_THROW(periodic(md, po));
}

TEST(JenkinsCli, EventsNameTheElementAndTheSliderIsTheLastColumn) {
    const std::string model = testing::temp_path("jenkins-cli.toml"), events = testing::temp_path("jenkins-cli.csv");
    std::ofstream(model) << kModel << "[[jenkins]]\nname = \"j1\"\nbetween = [\"m1\", \"ground\"]\nk = 16\nslip_force = 2\n";
    const testing::CliRun ok = testing::run_hsnc("simulate " + model + " --t-end 1 --events " + events);
    ASSERT_EQ(ok.exit_code, 0) << ok.err;
    std::ifstream in(events);
    std::string header, first, second;
    std::getline(in, header);
    std::getline(in, first);
    std::getline(in, second);
    EXPECT_EQ(header, "t,kind,element,x_m1,v_m1,s_j1");
    EXPECT_NE(first.find(",release,j1,"), std::string::npos) << first;
    EXPECT_NE(second.find(",stick,j1,"), std::string::npos) << second;
    for (const char* flags : {"--method ab4 --h 1e-3"}) {
        const testing::CliRun bad = testing::run_hsnc("simulate " + model + " --t-end 1 " + flags);
        EXPECT_EQ(bad.exit_code, 2) << flags << ": " << bad.err;
        EXPECT_NE(bad.err.find("Jenkins elements"), std::string::npos) << bad.err;
    }
    // A Poincare section at the element's sticks: one row per stick, the slider last.
    const std::string section = testing::temp_path("jenkins-section.csv");
    const testing::CliRun sec = testing::run_hsnc("simulate " + model + " --t-end 1 --section stick:j1 --section-out " + section);
    ASSERT_EQ(sec.exit_code, 0) << sec.err;
    std::ifstream sin(section);
    std::string sheader, srow;
    std::getline(sin, sheader);
    std::getline(sin, srow);
    EXPECT_EQ(sheader, "t,x_m1,v_m1,s_j1");
    EXPECT_EQ(srow.substr(0, srow.find(',')), second.substr(0, second.find(',')));  // at the stick row's instant
    for (const std::string cmd : {"sweep " + model + " --param g --from 9 --to 10 --points 2 --method ab4 --h 1e-3",
                                  "generate " + model + " --params k -o " + testing::temp_path("jenkins-gen-p")}) {
        const testing::CliRun bad = testing::run_hsnc(cmd);
        EXPECT_EQ(bad.exit_code, 2) << cmd << ": " << bad.err;
        EXPECT_NE(bad.err.find("Jenkins elements"), std::string::npos) << cmd << ": " << bad.err;
    }
    // The derivation takes it: every kernel kind writes the Eigen solver's events to
    // rounding, generic (the interpreter) and the JIT the same bytes.
    std::string bytes[3];
    const char* kinds[3] = {"eigen", "generic", "jit"};
    for (int k = 0; k < 3; ++k)
        bytes[k] = testing::events_csv(model, std::string("--t-end 1 --no-cache --kernels ") + kinds[k]);
    EXPECT_EQ(bytes[1], bytes[2]) << "generic and jit events";
    EXPECT_EQ(std::count(bytes[0].begin(), bytes[0].end(), '\n'), std::count(bytes[1].begin(), bytes[1].end(), '\n'));
    // generate: a kernel per configuration (stuck, slipping + and -) and its manifest;
    // inspect: the slider and the element's switch functions.
    const std::string dir = testing::temp_path("jenkins-gen");
    const testing::CliRun gen = testing::run_hsnc("generate " + model + " -o " + dir);
    ASSERT_EQ(gen.exit_code, 0) << gen.err;
    EXPECT_NE(gen.out.find("wrote 3 kernels"), std::string::npos) << gen.out;
    std::ifstream manifest(dir + "/jenkins-test.manifest");
    std::string manifest_text((std::istreambuf_iterator<char>(manifest)), std::istreambuf_iterator<char>());
    EXPECT_NE(manifest_text.find("slip=j1+"), std::string::npos) << manifest_text;
    const testing::CliRun cpp = testing::run_hsnc("inspect " + model + " --config slip=j1- --format cpp");
    ASSERT_EQ(cpp.exit_code, 0) << cpp.err;
    EXPECT_NE(cpp.out.find("relative velocity of j1"), std::string::npos) << cpp.out;
    const testing::CliRun stuck = testing::run_hsnc("inspect " + model + " --format cpp");
    ASSERT_EQ(stuck.exit_code, 0) << stuck.err;
    EXPECT_NE(stuck.out.find("coef[7] = x0[1];  // the slider of j1 (stuck)"), std::string::npos) << stuck.out;
    const testing::CliRun text = testing::run_hsnc("inspect " + model);
    ASSERT_EQ(text.exit_code, 0) << text.err;
    EXPECT_NE(text.out.find("s_j1(tau) = s0_j1  (slider, stuck)"), std::string::npos) << text.out;
    EXPECT_NE(text.out.find("k e - F_s of j1"), std::string::npos) << text.out;
}

// The bundled friction damper settles on one loop: its area per cycle (the
// trapezoid sum of F dx over the last seven periods of a dense trajectory, from the
// CSV's s_damper column) is 4 F_s (a - F_s/k).
TEST(JenkinsCli, TheBundledFrictionDamperRunsTheLoop) {
    const std::string model = std::string(HSNC_SOURCE_DIR) + "/examples/jenkins/friction_damper.toml";
    const std::string csv = testing::temp_path("jenkins-damper.csv");
    const testing::CliRun r = testing::run_hsnc("simulate " + model + " --dt 0.0005 --out " + csv);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(csv);
    std::string line;
    std::getline(in, line);
    ASSERT_EQ(line, "t,x_airfoil,x_platform,v_airfoil,v_platform,s_damper");
    const double k = 400.0, Fs = 5.0, T = 2 * M_PI / 10.0, to = 40.0, from = to - 7 * T;  // seven whole periods
    double area = 0.0, lo = 0.0, hi = 0.0, px = 0.0, pf = 0.0;
    bool first = true;
    while (std::getline(in, line)) {
        double t, xa, xp, va, vp, sl;
        ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf", &t, &xa, &xp, &va, &vp, &sl), 6);
        if (t < from) continue;
        const double F = k * (xp - sl);
        EXPECT_LE(std::fabs(F), Fs * (1 + 1e-12)) << "t = " << t;  // never beyond the slip force
        if (!first) area += 0.5 * (F + pf) * (xp - px);
        lo = std::min(lo, xp), hi = std::max(hi, xp), px = xp, pf = F, first = false;
    }
    const double a = 0.5 * (hi - lo), cycles = 7.0;
    std::printf("amplitude %.6g m, loop area per cycle %.6g J, 4 F_s (a - F_s/k) = %.6g J\n", a, area / cycles,
                4 * Fs * (a - Fs / k));
    EXPECT_NEAR(area / cycles, 4 * Fs * (a - Fs / k), 1e-3 * area / cycles);
}

}  // namespace
}  // namespace hsnc
