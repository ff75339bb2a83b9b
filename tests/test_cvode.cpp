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
#include <string>

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

}  // namespace
}  // namespace hsnc
