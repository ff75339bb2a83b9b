// The HSNC engine against closed-form truths (issue: runtime, "Done when"),
// and the switch-detection cases a grid-based detector misses.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "tie_models.h"
#include "engine_runner.h"
#include "engine.h"
#include "integrators.h"
#include "model_reader.h"
#include "switch_guard.h"
#include "kernel_mode.h"

namespace hsnc {
namespace {

using testing::Outcome;
using testing::Recorded;
using testing::Recorder;
using testing::simulate;

Model model_from(const std::string& toml) { return parse_model(toml, "test.toml"); }

constexpr double kPi = 3.14159265358979323846;

// m x'' + k x = -mu m g sign(x'), omega = 10, released from x = 0.2.
constexpr const char* kCoulomb = R"(
name = "coulomb"
[[mass]]
name = "m1"
m = 1
mu_k = 0.1
[[spring]]
between = ["ground", "m1"]
k = 100
[initial]
x = { m1 = 0.2 }
)";

// Coulomb-damped free decay: m x'' + k x = -mu m g sign(x'). Each half-cycle is
// pi/omega long and centred on -+x_e = mu g / omega^2, so the extreme drops by
// 2 x_e per half-cycle (4 mu g / omega^2 per cycle); the mass sticks at the
// first extreme with |x| <= mu_s g / omega^2.
TEST(EngineClosedForm, CoulombFreeDecay) {
    const Model m = model_from(kCoulomb);
    const double omega = 10, xe = 0.1 * 9.81 / (omega * omega);
    const Outcome r = simulate(m, 5.0);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    ASSERT_EQ(r.events.size(), 10u);
    for (int k = 1; k <= 10; ++k) {
        const Recorded& e = r.events[k - 1];
        EXPECT_EQ(e.kind, k < 10 ? EventKind::reversal : EventKind::stick) << k;
        EXPECT_NEAR(e.t, k * kPi / omega, 1e-13 * k) << k;
        const double extreme = (k % 2 ? -1 : 1) * (0.2 - 2 * k * xe);
        EXPECT_NEAR(e.x[0], extreme, 1e-14) << k;
        EXPECT_EQ(e.v[0], 0.0);
    }
    EXPECT_NEAR(r.summary.x[0], 0.2 - 20 * xe, 1e-14);
    EXPECT_EQ(r.summary.v[0], 0.0);
}

// Bilinear oscillator with zero gap: stiffness k1 for x < 0, k1 + k2 for x >= 0.
// Period pi/omega1 + pi/omega2, held over 1000 periods.
TEST(EngineClosedForm, BilinearPeriodOver1000Periods) {
    const Model m = model_from(R"(
name = "bilinear"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["m1", "ground"]
k = 4
[[contact]]
between = ["m1", "ground"]
gap = 0
k = 12
[initial]
v = { m1 = 1.0 }
)");
    const double T = kPi / 2 + kPi / 4;
    const Outcome r = simulate(m, 1000 * T + 0.1);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    ASSERT_EQ(r.events.size(), 2000u);
    double worst = 0;
    for (std::size_t k = 0; k < r.events.size(); ++k) {
        const Recorded& e = r.events[k];
        const double n = static_cast<double>(k / 2);
        // Starts closed (G = 0, G' > 0): opens after pi/omega2, closes after pi/omega1 more.
        const double expected = k % 2 == 0 ? n * T + kPi / 4 : (n + 1) * T;
        EXPECT_EQ(e.kind, k % 2 == 0 ? EventKind::contact_open : EventKind::contact_close);
        worst = std::max(worst, std::fabs(e.t - expected) / expected);
    }
    EXPECT_LT(worst, 1e-13) << "relative drift of the event times";
}

// A free mass (no springs: K = 0, a rigid-body mode) sliding to rest:
// x = v0 t - mu g t^2 / 2 until t = v0 / (mu g).
TEST(EngineClosedForm, FreeMassSlidesToRest) {
    const Model m = model_from(R"(
name = "slider"
[[mass]]
name = "m1"
m = 2
mu_k = 0.3
mu_s = 0.4
[initial]
v = { m1 = 3.0 }
)");
    const double a = 0.3 * 9.81, ts = 3.0 / a;
    const Outcome r = simulate(m, 2.0);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    ASSERT_EQ(r.events.size(), 1u);
    EXPECT_EQ(r.events[0].kind, EventKind::stick);
    EXPECT_NEAR(r.events[0].t, ts, 1e-15 * 4);
    EXPECT_NEAR(r.events[0].x[0], 9.0 / (2 * a), 1e-14);
    EXPECT_NEAR(r.summary.x[0], 9.0 / (2 * a), 1e-14);
}

// A mass at rest held by static friction under F sin(omega t) releases when
// F sin(omega t) = mu_s m g, i.e. at asin(mu_s m g / F) / omega.
TEST(EngineClosedForm, ReleaseUnderHarmonicForcing) {
    const Model m = model_from(R"(
name = "release"
[[mass]]
name = "m1"
m = 1.5
mu_k = 0.2
mu_s = 0.5
[[forcing]]
omega = 3.0
amplitude = { m1 = 20.0 }
)");
    const double expected = std::asin(0.5 * 1.5 * 9.81 / 20.0) / 3.0;
    const Outcome r = simulate(m, 0.5);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    ASSERT_GE(r.events.size(), 1u);
    EXPECT_EQ(r.events[0].kind, EventKind::release);
    EXPECT_NEAR(r.events[0].t, expected, 1e-15 * 8);
    EXPECT_EQ(r.events[0].x[0], 0.0);
}

// x = A sin(omega t) meets a soft stop at gap d = A (1 - eps): the contact is
// closed for a time far shorter than any fixed grid step would resolve. While
// closed, x oscillates about xc = kc d / (k + kc) at omega_c, and returns to
// x = d after s = (2/omega_c) atan(v_in / (omega_c (d - xc))).
class GrazingContact : public ::testing::TestWithParam<double> {};

TEST_P(GrazingContact, ClosesAndOpensAtTheExactInstants) {
    const double eps = GetParam(), A = 1.0, omega = 2.0, k = 4.0, kc = 5.0, d = A * (1 - eps);
    char toml[512];
    std::snprintf(toml, sizeof toml, R"(
name = "graze"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["m1", "ground"]
k = %.17g
[[contact]]
between = ["m1", "ground"]
gap = %.17g
k = %.17g
[initial]
v = { m1 = %.17g }
)", k, d, kc, A * omega);
    const Model m = model_from(toml);
    const Outcome r = simulate(m, 1.0);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    ASSERT_EQ(r.events.size(), 2u) << "eps = " << eps;
    const double t_in = std::asin(d / A) / omega;
    const double v_in = A * omega * std::sqrt(eps * (2 - eps));  // A omega cos(omega t_in)
    const double wc = std::sqrt(k + kc), xc = kc * d / (k + kc);
    const double s = 2 / wc * std::atan(v_in / (wc * (d - xc)));
    EXPECT_EQ(r.events[0].kind, EventKind::contact_close);
    EXPECT_EQ(r.events[1].kind, EventKind::contact_open);
    // The entry time of a near-tangent crossing is ill-conditioned: the gap's
    // slope is v_in, so rounding of 1e-16 in x moves it by ~1e-16 / v_in.
    EXPECT_NEAR(r.events[0].t, t_in, 4e-16 / v_in + 1e-15);
    EXPECT_NEAR(r.events[1].t - r.events[0].t, s, 8e-16 / v_in + 1e-14);
}

// Overshoots of 1e-4 .. 1e-12 of the amplitude; at 1e-12 the contact is
// closed for about 1.4e-6 / omega.
INSTANTIATE_TEST_SUITE_P(Overshoot, GrazingContact, ::testing::Values(1e-4, 1e-6, 1e-9, 1e-12));

// A gap that comes within 1e-13 of zero but stays open changes nothing.
TEST(EngineDetection, NearMissWritesNoEvent) {
    const Model m = model_from(R"(
name = "miss"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["m1", "ground"]
k = 4
[[contact]]
between = ["m1", "ground"]
gap = 1.0000000000001
k = 5
[initial]
v = { m1 = 2.0 }
)");
    const Outcome r = simulate(m, 3.0);
    ASSERT_EQ(r.summary.status, RunStatus::ok);
    EXPECT_EQ(r.events.size(), 0u);
}

// v = v0 + F (1 - cos t) - a t with F = 2a touches zero tangentially at
// t = pi/6 (v' = F sin t - a = 0 there): a stop. Static friction (mu_s = 1.5
// mu_k) then holds the mass until F sin t > mu_s g, at t = asin(0.75).
TEST(EngineDetection, VelocityTouchingZeroIsAStop) {
    const double a = 0.2 * 9.81, F = 2 * a;
    const double v0 = a * kPi / 6 - F * (1 - std::cos(kPi / 6));
    char toml[512];
    std::snprintf(toml, sizeof toml, R"(
name = "touch"
[[mass]]
name = "m1"
m = 1
mu_k = 0.2
mu_s = 0.3
[[forcing]]
omega = 1
phase = 0
amplitude = { m1 = %.17g }
[initial]
v = { m1 = %.17g }
)", F, v0);
    const Model m = model_from(toml);
    const Outcome r = simulate(m, 1.0);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    ASSERT_EQ(r.events.size(), 2u);
    EXPECT_EQ(r.events[0].kind, EventKind::stick);
    // A tangential zero is located to ~sqrt(rounding / v''): v'' = F cos(pi/6).
    EXPECT_NEAR(r.events[0].t, kPi / 6, 1e-7);
    EXPECT_EQ(r.events[1].kind, EventKind::release);
    EXPECT_NEAR(r.events[1].t, std::asin(0.75), 1e-14);
}

// The same velocity missing zero by 1e-9 (v0 larger) is not a stop.
TEST(EngineDetection, VelocityNearMissIsNoStop) {
    const double a = 0.2 * 9.81, F = 2 * a;
    const double v0 = a * kPi / 6 - F * (1 - std::cos(kPi / 6)) + 1e-9;
    char toml[512];
    std::snprintf(toml, sizeof toml, R"(
name = "touch"
[[mass]]
name = "m1"
m = 1
mu_k = 0.2
mu_s = 0.3
[[forcing]]
omega = 1
amplitude = { m1 = %.17g }
[initial]
v = { m1 = %.17g }
)", F, v0);
    const Outcome r = simulate(model_from(toml), 1.0);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    EXPECT_EQ(r.events.size(), 0u);
}


// The Zeno guard: switches accumulating within a small span stop the run with
// a named status and a message saying where. Exercised here with a span wide
// enough that the Coulomb decay's first reversals (0.31, 0.63, 0.94 s) count.
TEST(EngineGuards, AccumulatingSwitchesStopWithZenoStatus) {
    const Model m = model_from(kCoulomb);
    GenericSolverProvider provider(m);
    Engine engine(m, provider);
    Recorder rec(m.dof());
    EngineOptions opt;
    opt.t_end = 5.0;
    opt.zeno_events = 3;
    opt.zeno_span = 1.0;
    const RunSummary s = engine.run(opt, rec);
    EXPECT_EQ(s.status, RunStatus::zeno);
    EXPECT_EQ(s.events, 3u);
    EXPECT_NEAR(s.t, 3 * kPi / 10, 1e-13);
    EXPECT_NE(s.message.find("3 switches between t = 0.314"), std::string::npos) << s.message;
}


// The guard itself (switch_guard.h), which the engine and the baselines share:
// switches one ulp of t apart (a baseline's restarts cycling at a Jenkins
// element's stick, issue 35) are an accumulation; switch instants that keep
// coming at one t are chattering; regular switches go on.
TEST(EngineGuards, SharedGuardStopsUlpApartAndSameInstantSwitches) {
    EngineOptions opt;
    SwitchGuard ulps(opt, 0.0);
    double t = 0.23026537685633708;
    std::size_t k = 0;
    RunStatus status = RunStatus::ok;
    for (; k < 100000 && status == RunStatus::ok; ++k) {
        ulps.event(t);
        status = ulps.after_switch(t, 4);
        t = std::nextafter(t, 1.0);
    }
    EXPECT_EQ(status, RunStatus::zeno);
    EXPECT_EQ(k, opt.zeno_events);
    EXPECT_NE(ulps.message("slip=j1+").find("1000 switches between t = 0.23026537685633708"), std::string::npos)
        << ulps.message("slip=j1+");
    SwitchGuard same(opt, 0.0);
    status = RunStatus::ok;
    for (k = 0; k < 100 && status == RunStatus::ok; ++k) status = same.after_switch(1.5, 3);
    EXPECT_EQ(status, RunStatus::chattering);
    EXPECT_EQ(k, 4u * (3 + 2) + 2);
    EXPECT_EQ(same.message("closed=c1"), "configuration keeps switching at t = 1.5 (now 'closed=c1')");
    SwitchGuard regular(opt, 0.0);
    for (k = 0; k < 10000; ++k) {
        regular.event(1e-3 * static_cast<double>(k));
        ASSERT_EQ(regular.after_switch(1e-3 * static_cast<double>(k), 4), RunStatus::ok) << k;
    }
}


// The Zeno guard measures on the run's own clock (issue 12). A bilinear
// oscillator (k = w^2, a stop of 3k at gap 0, so the closed half-cycle is
// pi/(2w) and the open one pi/w) switching regularly at 16 kHz from
// t0 = 1e9: 1000 switches take 62.5 ms, which a span relative to |t| (1 s at
// t = 1e9) took for an accumulation. It must run to t_end with every switch
// of the closed form, while switches accumulating on the run's clock at the
// same t0 are still refused as Zeno.
Model bilinear_at(double t0, double w, double v0) {
    char toml[512];
    std::snprintf(toml, sizeof toml, R"(
name = "bilinear_at"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["m1", "ground"]
k = %.17g
[[contact]]
between = ["m1", "ground"]
gap = 0
k = %.17g
[initial]
t0 = %.17g
v = { m1 = %.17g }
)", w * w, 3 * w * w, t0, v0);
    return model_from(toml);
}

TEST(EngineGuards, RegularSwitchingAtLargeT0IsNotZeno) {
    const double T = 1.0 / 8000;                // period: open pi/w + closed pi/(2w)
    const double w = 1.5 * kPi / T;             // 2 switches a period: 16 kHz
    const double t0 = 1e9, span = 0.1 + T / 4;  // no switch near t_end
    const Model m = bilinear_at(t0, w, -1.0);   // starts open (G' < 0)
    const Outcome r = simulate(m, t0 + span);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    // Closes at t0 + pi/w + j T, opens at t0 + j T (j >= 1): 1600 switches in 0.1 s.
    std::size_t expected = 0;
    for (int j = 0; j < 2000; ++j) {
        const long double close = static_cast<long double>(kPi) / w + j * static_cast<long double>(T);
        const long double open = (j + 1) * static_cast<long double>(T);
        expected += (close < span) + (open < span);
    }
    ASSERT_EQ(expected, 1600u);
    ASSERT_EQ(r.events.size(), expected);
    for (std::size_t k = 0; k < r.events.size(); ++k) {
        const std::size_t j = k / 2;
        const bool close = k % 2 == 0;
        EXPECT_EQ(r.events[k].kind, close ? EventKind::contact_close : EventKind::contact_open) << k;
        const double truth = t0 + (close ? kPi / w + static_cast<double>(j) * T : static_cast<double>(j + 1) * T);
        // At t = 1e9 the engine knows a switch function only to its rounding
        // level 16 eps (scale + |g'| |t|) (engine.h), i.e. a switch time to
        // 16 eps |t| = 3.6e-6 s; twice that.
        EXPECT_NEAR(r.events[k].t, truth, 32 * std::numeric_limits<double>::epsilon() * t0) << k;
    }
}

TEST(EngineGuards, AccumulationAtLargeT0IsStillZeno) {
    // The guard's span follows the run's clock at t0 = 1e9 too: the Coulomb
    // decay's first three reversals (0.31, 0.63, 0.94 s after t0) within a
    // span of 1 s (zeno_span = 1 of the 0.94 s covered) are an accumulation.
    Model m = model_from(kCoulomb);
    m.t0 = 1e9;
    GenericSolverProvider provider(m);
    Engine engine(m, provider);
    Recorder rec(m.dof());
    EngineOptions opt;
    opt.t_end = 1e9 + 5.0;
    opt.zeno_events = 3;
    opt.zeno_span = 1.0;
    const RunSummary s = engine.run(opt, rec);
    EXPECT_EQ(s.status, RunStatus::zeno) << s.message;
    EXPECT_EQ(s.events, 3u);
    EXPECT_NEAR(s.t, 1e9 + 3 * kPi / 10, 1e-6);
}

// A tie |A| = mu_s N at t0 (k x0 = 4 = mu_s m g with g = 8) is decided by the
// derivative of |A| with the mass held: not increasing -> stuck for good;
// increasing (forcing sin t adds A' = 1) -> slides from t0 on.
TEST(EngineTies, StaticLimitExactlyReachedAtT0) {
    const char* base = R"(
name = "tie"
[parameters]
g = 8
[[mass]]
name = "m1"
m = 1
mu_k = 0.25
mu_s = 0.5
[[spring]]
between = ["ground", "m1"]
k = 1
[initial]
x = { m1 = -4.0 }
)";
    const Outcome held = simulate(model_from(base), 1.0, 0.5);
    ASSERT_EQ(held.summary.status, RunStatus::ok);
    EXPECT_EQ(held.events.size(), 0u);
    EXPECT_EQ(held.summary.x[0], -4.0);
    EXPECT_EQ(held.summary.v[0], 0.0);
    const Outcome pushed = simulate(model_from(std::string(base) + "[[forcing]]\nomega = 1\namplitude = { m1 = 1.0 }\n"), 0.5, 0.5);
    ASSERT_EQ(pushed.summary.status, RunStatus::ok);
    EXPECT_EQ(pushed.events.size(), 0u);
    // Sliding from t0: x'' = -x + sin t - mu_k g = 2 + sin t + (-4 - x), so it accelerates at once.
    EXPECT_GT(pushed.summary.v[0], 0.5);
    EXPECT_GT(pushed.summary.x[0], -4.0);
}

// Contact ties at t0 (interface.md "Ties and touches", "At t0"): a mass at
// rest exactly on its stop's gap (G = 0, G' = 0) enters the configuration its
// first non-zero derivative points to, and no row is written for it.
constexpr const char* kOnTheGap = R"(
name = "on_the_gap"
[[mass]]
name = "m1"
m = 2
[[spring]]
between = ["ground", "m1"]
k = 4
[[contact]]
between = ["m1", "ground"]
gap = 0
k = 100
[damping]
alpha = 0.5
[initial]
x = { m1 = 0.0 }
)";

// G'' = load/m = -0.5 < 0: G decreases into G < 0, so the contact starts
// open; the damped motion x = -0.25 (1 - e^{-s t} (cos w_d t + s/w_d sin w_d t)),
// s = alpha/2, w_d = sqrt(2 - s^2), stays below the gap: no row at all.
TEST(EngineTies, ContactOnItsGapPulledAwayStartsOpen) {
    const Outcome r = simulate(model_from(std::string(kOnTheGap) + "[load]\nm1 = -1.0\n"), 3.0);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    EXPECT_EQ(r.events.size(), 0u) << "first row: " << (r.events.empty() ? "" : event_kind_name(r.events[0].kind));
    EXPECT_EQ(r.summary.configuration.closed[0], 0);
    const double s = 0.25, wd = std::sqrt(2.0 - s * s), t = 3.0;
    const double x = -0.25 * (1 - std::exp(-s * t) * (std::cos(wd * t) + s / wd * std::sin(wd * t)));
    EXPECT_NEAR(r.summary.x[0], x, 1e-13);
}

// G'' = 0 (no load, sin forcing is 0 at t0), so G''' = F'(0)/m decides:
// amplitude -1 pulls away (open, the first row a later close), +1 pushes in
// (closed, the first row a later open); either way nothing at t0.
TEST(EngineTies, ContactOnItsGapDecidedByTheThirdDerivative) {
    for (double amp : {-1.0, 1.0}) {
        const std::string forcing = "[[forcing]]\nomega = 1\namplitude = { m1 = " + std::to_string(amp) + " }\n";
        const Outcome r = simulate(model_from(std::string(kOnTheGap) + forcing), 10.0);
        ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
        ASSERT_FALSE(r.events.empty()) << amp;
        EXPECT_EQ(r.events[0].kind, amp < 0 ? EventKind::contact_close : EventKind::contact_open) << amp;
        EXPECT_GT(r.events[0].t, 0.5) << amp << ": no switch at t0";
    }
}

// A touch that coincides with a friction stop (issue 11 item 8): the Coulomb
// oscillator x'' + x = 0.1 from x0 = 1 (m = k = g = 1, mu_k = 0.1) follows
// x = 0.1 + 0.9 cos t and stops at t = pi on x = -0.8, exactly where the gap
// G = -x - 0.8 of a stop below it touches 0 (G = G' = 0 there). With
// mu_s = 0.9 the stick rule holds it (|A| = 0.8 < 0.9): G stays at 0, which
// changes nothing (interface.md "Ties and touches"): one stick row, no contact
// rows, the contact still open. With mu_s = 0.5 it reverses (G'' = -0.7 < 0,
// the touch turns back): reversals at pi and 2 pi (x = 0.6), a stick at 3 pi
// (x = -0.4), again no contact rows.
TEST(EngineTies, TouchAtAFrictionStopWritesNoContactRows) {
    auto model = [](double mu_s) {
        return model_from(R"(
name = "touch-at-stop"
[parameters]
g = 1
[[mass]]
name = "m1"
m = 1
mu_k = 0.1
mu_s = )" + std::to_string(mu_s) + R"(
[[spring]]
between = ["ground", "m1"]
k = 1
[[contact]]
between = ["ground", "m1"]
gap = 0.8
k = 1000
[initial]
x = { m1 = 1 }
)");
    };
    const Outcome held = simulate(model(0.9), 12.0);
    ASSERT_EQ(held.summary.status, RunStatus::ok) << held.summary.message;
    ASSERT_EQ(held.events.size(), 1u) << "second row: " << event_kind_name(held.events[1].kind);
    EXPECT_EQ(held.events[0].kind, EventKind::stick);
    EXPECT_NEAR(held.events[0].t, kPi, 1e-12);
    EXPECT_NEAR(held.summary.x[0], -0.8, 1e-14);
    EXPECT_EQ(held.summary.configuration.closed[0], 0);
    EXPECT_EQ(held.summary.configuration.stuck[0], 1);

    const Outcome turned = simulate(model(0.5), 12.0);
    ASSERT_EQ(turned.summary.status, RunStatus::ok) << turned.summary.message;
    ASSERT_EQ(turned.events.size(), 3u);
    const EventKind kinds[] = {EventKind::reversal, EventKind::reversal, EventKind::stick};
    for (int e = 0; e < 3; ++e) {
        EXPECT_EQ(turned.events[e].kind, kinds[e]) << e;
        EXPECT_NEAR(turned.events[e].t, (e + 1) * kPi, 1e-12) << e;
    }
    EXPECT_NEAR(turned.summary.x[0], -0.4, 1e-14);
    EXPECT_EQ(turned.summary.configuration.closed[0], 0);
}

// |A| = mu_s N at t0 with v = 0 and A', A'' = 0, A''' = 6 > 0 (two harmonics
// whose rates cancel): |A| is increasing, so the mass slides from t0 with no
// release row, v = (cos(w t) + 2 cos t - 3 cos 2t)/9, w^2 = 10 (the closed form
// of x'' + 10 x = -5 + 2 sin t - sin 2t from x0 = -0.5, v0 = 0).
TEST(EngineTies, FrictionTieDecidedByTheThirdDerivativeSlides) {
    const Model m = model_from(hsnc::test::kFrictionTieModel);
    const Outcome r = simulate(m, 0.5);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    EXPECT_EQ(r.events.size(), 0u) << "first row: " << (r.events.empty() ? "" : event_kind_name(r.events[0].kind));
    const double t = 0.5, w = std::sqrt(10.0);
    EXPECT_NEAR(r.summary.v[0], (std::cos(w * t) + 2 * std::cos(t) - 3 * std::cos(2 * t)) / 9, 1e-14);
}

// Samples: on the grid t0 + k dt, plus t_end, never twice at one time.
TEST(EngineOutput, SamplesOnTheGridAndAtTEnd) {
    const Model m = model_from(R"(
name = "grid"
[[mass]]
name = "m1"
m = 1
mu_k = 0.1
[[spring]]
between = ["ground", "m1"]
k = 100
[initial]
x = { m1 = 0.2 }
)");
    const Outcome r = simulate(m, 1.05, 0.1);
    ASSERT_EQ(r.samples.size(), 12u);
    for (std::size_t k = 0; k < 11; ++k) EXPECT_DOUBLE_EQ(r.samples[k].t, 0.1 * static_cast<double>(k));
    EXPECT_EQ(r.samples.back().t, 1.05);
    // Exact closed form of the first half-cycle: x = xe + (0.2 - xe) cos(10 t).
    const double xe = 0.1 * 9.81 / 100;
    EXPECT_NEAR(r.samples[2].x[0], xe + (0.2 - xe) * std::cos(10 * 0.2), 1e-15);
}

// HSNC and the adaptive baseline at tight tolerance agree on the paper's
// scenarios over a short horizon (same events, same state to ~1e-7).
class AgainstBaseline : public ::testing::TestWithParam<std::pair<const char*, double>> {};

TEST_P(AgainstBaseline, SameEventsAndState) {
    const auto [file, t_end] = GetParam();
    const Model m = read_model(std::string(HSNC_SOURCE_DIR) + "/models/" + file);
    const Outcome exact = simulate(m, t_end);
    ASSERT_EQ(exact.summary.status, RunStatus::ok) << exact.summary.message;
    const Outcome rk = testing::baseline(m, t_end, 1e-12, 1e-14);
    const RunSummary& base = rk.summary;
    const auto& rec = rk;
    ASSERT_EQ(base.status, RunStatus::ok) << base.message;
    ASSERT_EQ(rec.events.size(), exact.events.size());
    ASSERT_GT(exact.events.size(), 3u);
    for (std::size_t k = 0; k < exact.events.size(); ++k) {
        EXPECT_EQ(rec.events[k].kind, exact.events[k].kind) << k;
        EXPECT_EQ(rec.events[k].element, exact.events[k].element) << k;
        EXPECT_NEAR(rec.events[k].t, exact.events[k].t, 1e-7 * std::max(1.0, exact.events[k].t)) << k;
    }
    for (std::size_t i = 0; i < m.dof(); ++i) {
        const double scale = 1e-6 * (1 + std::fabs(exact.summary.x[i]));
        EXPECT_NEAR(base.x[i], exact.summary.x[i], scale) << i;
    }
}

INSTANTIATE_TEST_SUITE_P(Seeds, AgainstBaseline,
                         ::testing::Values(std::make_pair("seed-scenario-1.toml", 0.2),
                                           std::make_pair("seed-scenario-2.toml", 3.0),
                                           std::make_pair("chain-8.toml", 2.0)));

}  // namespace
}  // namespace hsnc
