// The CVODE baseline (--method cvode): SUNDIALS CVODE, Adams, with root
// finding on the switch functions and the transitions the engine applies.
//
// The independent truth is the HSNC engine's closed form (itself tested
// against closed forms and a tighter integrator elsewhere): CVODE must find
// the same switches, in the same order, at the same times to its own
// integration error -- and that difference must shrink when CVODE is
// tightened, which shows it is CVODE's error and not a different physics.
// Each bound states the value measured when the test was written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

#include "cli_runner.h"
#include "engine_runner.h"
#include "error.h"
#include "integrators.h"
#include "model_reader.h"

namespace hsnc {
namespace {

using testing::Outcome;
using testing::Recorder;

Outcome cvode(const Model& model, double t_end, double rtol, double atol, bool newton = false) {
    Recorder rec(model.dof());
    EngineOptions eo;
    eo.t_end = t_end;
    eo.dt = t_end / 50;
    IntegratorOptions io;
    io.rtol = rtol;
    io.atol = atol;
    io.cvode_newton = newton;
    Outcome r;
    r.summary = integrate(model, Method::cvode, io, eo, rec);
    r.events = std::move(rec.events);
    r.samples = std::move(rec.samples);
    return r;
}

struct Difference {
    double t = 0, x = 0;  ///< max over events of |dt|, of |dx| at the events and at t_end
};

// Same events (kind, element, order); the largest differences of time and position.
Difference compare(const Model& m, const Outcome& e, const Outcome& c) {
    EXPECT_EQ(c.summary.status, RunStatus::ok) << c.summary.message;
    EXPECT_EQ(e.events.size(), c.events.size());
    Difference d;
    for (std::size_t k = 0; k < std::min(e.events.size(), c.events.size()); ++k) {
        EXPECT_EQ(e.events[k].kind, c.events[k].kind) << "event " << k;
        EXPECT_EQ(e.events[k].element, c.events[k].element) << "event " << k;
        d.t = std::max(d.t, std::fabs(e.events[k].t - c.events[k].t));
        for (std::size_t i = 0; i < m.dof(); ++i) d.x = std::max(d.x, std::fabs(e.events[k].x[i] - c.events[k].x[i]));
    }
    for (std::size_t i = 0; i < m.dof(); ++i) d.x = std::max(d.x, std::fabs(e.summary.x[i] - c.summary.x[i]));
    std::printf("cvode vs hsnc: %zu events, max |dt| %.2g s, max |dx| %.2g m\n", c.events.size(), d.t, d.x);
    return d;
}

Model seed(const char* name) { return read_model(std::string(HSNC_SOURCE_DIR) + "/models/" + name); }

// Scenario 1 (22500 N at 175.5 rad/s): reversals and a contact, 68 events in 0.5 s.
TEST(Cvode, Scenario1AgreesWithTheClosedForm) {
    const Model m = seed("seed-scenario-1.toml");
    const double t_end = 0.5;
    const Outcome e = testing::simulate(m, t_end, t_end / 50);
    ASSERT_EQ(e.summary.status, RunStatus::ok);
    ASSERT_GT(e.events.size(), 60u);
    const Difference d12 = compare(m, e, cvode(m, t_end, 1e-12, 1e-14));
    const Difference d13 = compare(m, e, cvode(m, t_end, 1e-13, 1e-15));
    // Measured: rtol 1e-12: 4.5e-12 s, 4.0e-10 m; rtol 1e-13: 8.4e-13 s, 8.5e-11 m
    // (x reaches 1.1 m: a relative error of a few 1e-10, what a global error of
    // rtol 1e-12 grows to over ~16000 steps). Bounds: 10x, for libm and compilers.
    EXPECT_LT(d12.t, 5e-11);
    EXPECT_LT(d12.x, 4e-9);
    EXPECT_LT(d13.t, d12.t) << "a tighter CVODE should come closer to the closed form";
    EXPECT_LT(d13.x, d12.x);
}

// Scenario 2 (stick-slip with a contact): 135 events in 10 s, one stick and
// its release among them -- the release functions and a velocity that starts
// exactly at zero after the release (CVODE's zero-at-restart trap).
TEST(Cvode, Scenario2AgreesWithTheClosedForm) {
    const Model m = seed("seed-scenario-2.toml");
    const double t_end = 10;
    const Outcome e = testing::simulate(m, t_end, t_end / 50);
    ASSERT_EQ(e.summary.status, RunStatus::ok);
    const auto has = [&](EventKind k) {
        return std::any_of(e.events.begin(), e.events.end(), [k](const auto& r) { return r.kind == k; });
    };
    ASSERT_TRUE(has(EventKind::stick) && has(EventKind::release) && has(EventKind::contact_close));
    const Difference d12 = compare(m, e, cvode(m, t_end, 1e-12, 1e-14));
    const Difference d13 = compare(m, e, cvode(m, t_end, 1e-13, 1e-15));
    // Measured: rtol 1e-12: 1.6e-11 s, 3.2e-10 m; rtol 1e-13: 3.0e-12 s, 3.1e-11 m.
    // Bounds: 10x.
    EXPECT_LT(d12.t, 2e-10);
    EXPECT_LT(d12.x, 4e-9);
    EXPECT_LT(d13.t, d12.t) << "a tighter CVODE should come closer to the closed form";
    EXPECT_LT(d13.x, d12.x);
}

// A 20-mass chain with friction on every mass and three contacts: more switch
// functions than kScheduleFrom, so the engine searches each on its own
// schedule (engine.cpp); CVODE watches all of them at every step.
TEST(Cvode, FrictionChainSearchedByFunctionAgrees) {
    auto m = [](int i) { return "m" + std::to_string(i); };
    std::string t = "name = \"friction-chain\"\n[damping]\nbeta = 0.002\n";
    for (int i = 1; i <= 20; ++i) t += "[[mass]]\nname = \"" + m(i) + "\"\nm = 1\nmu_k = 0.05\nmu_s = 0.07\n";
    t += "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 400\n";
    for (int i = 1; i < 20; ++i) t += "[[spring]]\nbetween = [\"" + m(i) + "\", \"" + m(i + 1) + "\"]\nk = 400\n";
    t += "[[spring]]\nbetween = [\"m20\", \"ground\"]\nk = 400\n";
    t += "[[contact]]\nbetween = [\"m5\", \"m6\"]\ngap = 0.01\nk = 4000\n";
    t += "[[contact]]\nbetween = [\"m10\", \"m11\"]\ngap = 0.01\nk = 4000\n";
    t += "[[contact]]\nbetween = [\"m15\", \"ground\"]\ngap = 0.02\nk = 4000\n";
    t += "[[forcing]]\nomega = 9.0\namplitude = { m1 = 30.0, m20 = -20.0 }\n[initial]\nv = { m10 = 1.0 }\n";
    const Model model = parse_model(t, "friction-chain.toml");
    ASSERT_GE(model.dof(), kScheduleFrom);
    const double t_end = 2.0;
    for (auto solvers : {testing::Solvers::generic, testing::Solvers::interp}) {
        const Outcome e = testing::simulate(model, t_end, t_end / 50, solvers);
        ASSERT_EQ(e.summary.status, RunStatus::ok) << e.summary.message;
        ASSERT_GT(e.events.size(), 100u);
        const Difference d = compare(model, e, cvode(model, t_end, 1e-12, 1e-14));
        // Measured: 198 events, 3.0e-11 s, 2.3e-11 m (both solvers). Bounds: 10x.
        EXPECT_LT(d.t, 3e-10);
        EXPECT_LT(d.x, 3e-10);
    }
}

// The Newton corrector (dense difference-quotient Jacobian) finds the same switches.
TEST(Cvode, NewtonCorrectorAgreesToo) {
    const Model m = seed("seed-scenario-2.toml");
    const double t_end = 10;
    const Outcome e = testing::simulate(m, t_end);
    const Difference d = compare(m, e, cvode(m, t_end, 1e-12, 1e-14, true));
    // Measured: 1.9e-11 s, 3.2e-10 m. Bounds: 10x.
    EXPECT_LT(d.t, 2e-10);
    EXPECT_LT(d.x, 4e-9);
}

// Samples come at the requested times, t0 and t_end included, from CVODE's
// interpolant; they agree with the closed form to the same error.
TEST(Cvode, SamplesAtTheRequestedTimes) {
    const Model m = seed("seed-scenario-2.toml");
    const double t_end = 10;
    const Outcome e = testing::simulate(m, t_end, t_end / 50);
    const Outcome c = cvode(m, t_end, 1e-12, 1e-14);
    ASSERT_EQ(c.samples.size(), 51u);
    ASSERT_EQ(e.samples.size(), c.samples.size());
    double dx = 0;
    for (std::size_t k = 0; k < c.samples.size(); ++k) {
        EXPECT_EQ(c.samples[k].t, e.samples[k].t) << k;
        for (std::size_t i = 0; i < m.dof(); ++i) dx = std::max(dx, std::fabs(c.samples[k].x[i] - e.samples[k].x[i]));
    }
    EXPECT_EQ(c.samples.back().t, t_end);
    std::printf("cvode vs hsnc samples: max |dx| %.2g m\n", dx);
    // Measured: 3.1e-10 m. Bound: 10x.
    EXPECT_LT(dx, 4e-9);
}

TEST(Cvode, BadTolerancesAreInputErrors) {
    IntegratorOptions io;
    io.rtol = 0;
    EXPECT_THROW(validate(Method::cvode, io), InputError);
    io.rtol = 1e-10;
    io.atol = INFINITY;
    EXPECT_THROW(validate(Method::cvode, io), InputError);
    EXPECT_EQ(parse_method("cvode"), Method::cvode);
}


// ---- Releases of a stuck mass under harmonic forcing ----------------------------
//
// m x'' + k x = F sin(Omega t) - mu_k m g sign(v) (mu_s > mu_k), from rest at
// x0 = 0.01 where |k x0| < mu_s m g: stuck. A stuck mass at x_s sees
// A(t) = F sin(Omega t) - k x_s and releases at the first t after it stuck with
// |A(t)| = mu_s m g: F sin(Omega t) = k x_s +- mu_s m g, an asin. With every mass
// stuck the right-hand side is 0, so an error-controlled step used to grow until
// it stepped over the release (cvode released at 9.88 s instead of 0.454 s,
// rk45 missed a later one); the closed form checks every release of a 10 s run,
// from the stuck position each method itself reached.
constexpr const char* kForcedStickSlip = R"(
name = "forced-stick-slip"
[parameters]
g = 9.81
[[mass]]
name = "m1"
m = 1
mu_k = 0.2
mu_s = 0.3
[[spring]]
between = ["ground", "m1"]
k = 100
[[forcing]]
omega = 2
amplitude = { m1 = 5 }
[initial]
x = { m1 = 0.01 }
)";

// The first t > t_s with |F sin(Omega t) - k x_s| = L.
double release_time(double t_s, double x_s, double F, double Omega, double k, double L) {
    double best = INFINITY;
    for (const double c : {k * x_s + L, k * x_s - L}) {
        if (std::fabs(c) > F) continue;
        const double a = std::asin(c / F);
        for (const double theta : {a, M_PI - a}) {
            // theta + 2 pi j > Omega t_s: the smallest such j
            const double j = std::ceil((Omega * t_s - theta) / (2 * M_PI));
            for (double jj = j - 1; jj <= j + 1; ++jj) {
                const double t = (theta + 2 * M_PI * jj) / Omega;
                if (t > t_s) best = std::min(best, t);
            }
        }
    }
    return best;
}

Outcome baseline(const Model& model, Method method, double t_end, const IntegratorOptions& io) {
    Recorder rec(model.dof());
    EngineOptions eo;
    eo.t_end = t_end;
    eo.samples = false;
    Outcome r;
    r.summary = integrate(model, method, io, eo, rec);
    r.events = std::move(rec.events);
    return r;
}

// Every release of `run` against the closed form from the stick before it (or t0);
// returns the largest |t - t_closed_form|.
double worst_release_error(const Model& m, const Outcome& run, std::size_t expect_releases) {
    const double F = 5, Omega = 2, k = 100, L = 0.3 * 1 * 9.81;
    double t_s = m.t0, x_s = m.x0[0], worst = 0;
    std::size_t releases = 0;
    for (const auto& e : run.events) {
        if (e.kind == EventKind::stick) {
            t_s = e.t;
            x_s = e.x[0];
        } else if (e.kind == EventKind::release) {
            const double t = release_time(t_s, x_s, F, Omega, k, L);
            worst = std::max(worst, std::fabs(e.t - t) / t);
            ++releases;
        }
    }
    EXPECT_EQ(releases, expect_releases);
    return worst;
}

TEST(BaselineRelease, StuckMassReleasesWhereTheClosedFormSays) {
    const Model m = parse_model(kForcedStickSlip, "forced-stick-slip.toml");
    const double t_end = 10;
    const Outcome e = testing::simulate(m, t_end);
    ASSERT_EQ(e.summary.status, RunStatus::ok);
    std::size_t releases = 0;
    for (const auto& r : e.events) releases += r.kind == EventKind::release;
    ASSERT_EQ(releases, 8u);  // and 8 sticks: 16 events
    ASSERT_EQ(e.events.size(), 16u);
    EXPECT_NEAR(e.events[0].t, release_time(0, 0.01, 5, 2, 100, 0.3 * 9.81), 1e-14);  // 0.4543 s
    EXPECT_LT(worst_release_error(m, e, 8), 1e-13);  // the engine itself

    IntegratorOptions io;
    io.rtol = 1e-12;
    io.atol = 1e-14;
    for (const Method method : {Method::cvode, Method::rk45}) {
        const Outcome c = baseline(m, method, t_end, io);
        ASSERT_EQ(c.summary.status, RunStatus::ok) << c.summary.message;
        EXPECT_EQ(c.events.size(), e.events.size()) << (method == Method::cvode ? "cvode" : "rk45");
        const double err = worst_release_error(m, c, 8);
        std::printf("%s: releases within %.2g relative of the closed form\n", method == Method::cvode ? "cvode" : "rk45",
                    err);
        EXPECT_LT(err, 1e-8) << (method == Method::cvode ? "cvode" : "rk45");
    }
    // ab4 decides at step ends: each release at most one step after the closed form's.
    IntegratorOptions fixed;
    fixed.h = 1e-4;
    const Outcome a = baseline(m, Method::ab4, t_end, fixed);
    ASSERT_EQ(a.summary.status, RunStatus::ok) << a.summary.message;
    EXPECT_EQ(a.events.size(), e.events.size());
    double t_s = m.t0, x_s = m.x0[0];
    for (const auto& r : a.events) {
        if (r.kind == EventKind::stick) t_s = r.t, x_s = r.x[0];
        if (r.kind != EventKind::release) continue;
        const double t = release_time(t_s, x_s, 5, 2, 100, 0.3 * 9.81);
        EXPECT_GE(r.t, t - 1e-12);
        EXPECT_LE(r.t, t + fixed.h * (1 + 1e-9));
    }
}

// ---- A Jenkins element's stick (issue 35, 8a) ----------------------------------
//
// A mass on a Jenkins element to ground, a spring, a dashpot and forcing:
// the element sticks where the mass's velocity (its relative velocity)
// reaches 0, and its slip function F_s + k e then starts at zero, a
// rounding below it, heading into its safe side. The baselines took that
// rounding for a switch: release, then the relative velocity a rounding
// the wrong way, stick, one ulp of t apart for ever (CVODE; 17 of 50 random
// runs never finished, `tradeoff` counted 5.7 million events). Now a
// function that starts unarmed switches only when it falls below its start
// (integrators.cpp falls_from_zero), and the engine's chattering/Zeno guard
// (switch_guard.h) stops whatever still cycles with a named status.
constexpr const char* kJenkinsStick = R"(
name = "cvode-jenkins-stick"
[[mass]]
name = "m1"
m = 2.2
[[spring]]
between = ["ground", "m1"]
k = 20.0
[[jenkins]]
name = "j1"
between = ["m1", "ground"]
k = 460.0
slip_force = 2.9
[[damper]]
between = ["m1", "ground"]
c = 3.4
[[forcing]]
omega = 17.0
amplitude = { m1 = -7.3 }
[initial]
x = { m1 = -0.12 }
v = { m1 = -0.65 }
)";

TEST(BaselineJenkinsStick, CvodeAndRk45StickOnceAsTheEngineDoes) {
    const Model m = parse_model(kJenkinsStick, "cvode-jenkins-stick.toml");
    const double t_end = 5.0;
    const Outcome e = testing::simulate(m, t_end);
    ASSERT_EQ(e.summary.status, RunStatus::ok) << e.summary.message;
    ASSERT_GE(e.events.size(), 20u);
    for (const Method method : {Method::cvode, Method::rk45}) {
        SCOPED_TRACE(method == Method::cvode ? "cvode" : "rk45");
        Recorder rec(m.dof(), m.state_size());
        EngineOptions eo;
        eo.t_end = t_end;
        eo.samples = false;
        eo.max_events = 100 * e.events.size();  // a loop fails here instead of running for ever
        IntegratorOptions io;
        io.rtol = 1e-12;
        io.atol = 1e-14;
        const RunSummary s = integrate(m, method, io, eo, rec);
        ASSERT_EQ(s.status, RunStatus::ok) << s.message;
        ASSERT_EQ(rec.events.size(), e.events.size());
        double dt = 0.0;
        for (std::size_t k = 0; k < e.events.size(); ++k) {
            EXPECT_EQ(rec.events[k].kind, e.events[k].kind) << "event " << k;
            EXPECT_EQ(rec.events[k].element, e.events[k].element) << "event " << k;
            dt = std::max(dt, std::fabs(rec.events[k].t - e.events[k].t));
        }
        std::printf("%zu events, at most %.2g s from the engine's\n", rec.events.size(), dt);
        EXPECT_LT(dt, method == Method::cvode ? 2.5e-11 : 1.4e-7);  // measured: 2.5e-12 (cvode), 1.4e-8 (rk45)
    }
}

// The same through the command line: `simulate --method cvode` finishes with
// the engine's events, and `tradeoff` matches the reference's events.
TEST(BaselineJenkinsStick, CliSimulateAndTradeoffFinish) {
    const std::string model = testing::write_temp("cvode-jenkins-stick.toml", kJenkinsStick);
    auto events_of = [](const std::string& out) {
        const std::size_t at = out.find(" events=");
        return at == std::string::npos ? std::string("none") : out.substr(at, out.find(' ', at + 1) - at);
    };
    const testing::CliRun exact = testing::run_hsnc("simulate '" + model + "' --t-end 5 --quiet");
    ASSERT_EQ(exact.exit_code, 0) << exact.err;
    const testing::CliRun cv =
        testing::run_hsnc("simulate '" + model + "' --t-end 5 --quiet --method cvode --max-events 100000");
    ASSERT_EQ(cv.exit_code, 0) << cv.err;
    EXPECT_NE(cv.out.find("status=ok"), std::string::npos) << cv.out;
    EXPECT_EQ(events_of(cv.out), events_of(exact.out)) << cv.out << exact.out;
    const testing::CliRun tr =
        testing::run_hsnc("tradeoff '" + model + "' --t-end 1 --methods cvode --quick --runs 1 --budget 5");
    ASSERT_EQ(tr.exit_code, 0) << tr.err;
    std::istringstream lines(tr.err);
    int settings = 0;
    for (std::string line; std::getline(lines, line);) {
        if (line.rfind("tradeoff: cvode", 0) != 0) continue;
        ++settings;
        unsigned matched = 0, of = 0;
        const std::size_t at = line.find("events ");
        ASSERT_NE(at, std::string::npos) << line;
        ASSERT_EQ(std::sscanf(line.c_str() + at, "events %u of %u matched", &matched, &of), 2) << line;
        EXPECT_GT(of, 0u) << line;
        EXPECT_EQ(matched, of) << line;
    }
    EXPECT_GE(settings, 2) << tr.err;
}

}  // namespace
}  // namespace hsnc
