// The double engine at ties and touches (interface.md section 2, "Ties and
// touches"; issue 11): against closed forms, and against the high-precision
// reference (reference/reference.h) with every kernel kind the tests can
// build (the generic solver, and kernels compiled in-process).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "derivation.h"
#include "emitter.h"
#include "engine.h"
#include "engine_runner.h"
#include "generic_solver.h"
#include "model_reader.h"
#include "reference_engine.h"
#include "kernel_mode.h"
#include "tie_models.h"
#include "transitions.h"
#if HSNC_WITH_JIT
#include "jit.h"
#include "jit_solver_provider.h"
#include "kernel_solver.h"
#endif

namespace hsnc {
namespace {

using testing::Recorded;
using testing::Recorder;

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kPi = 3.141592653589793;

Model model_from(const std::string& toml) { return parse_model(toml, "test.toml"); }

// A mass at rest exactly on a zero gap (G = G' = 0 at t0) under F sin(10 t)
// at exact resonance (k/m = 100): G'' = 0 too, and G''' = 10 F decides
// (the models of the reference's tie tests, tests/test_reference.cpp).
std::string zero_gap_model(double amplitude) {
    return R"(
name = "zero-gap-at-rest"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["ground", "m1"]
k = 100
[[contact]]
between = ["m1", "ground"]
gap = 0
k = 1000
[[forcing]]
omega = 10
amplitude = { m1 = )" + std::to_string(amplitude) + " }\n";
}

// G = G' = 0, G'' = -1 < 0: a constant load pulls the mass off a zero gap;
// x = -(1 - cos 10 t)/100 only touches 0.
constexpr const char* kZeroGapLoad = R"(
name = "zero-gap-load"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["ground", "m1"]
k = 100
[[contact]]
between = ["m1", "ground"]
gap = 0
k = 1000
[load]
m1 = -1
)";

struct RunResult {
    RunSummary summary;
    std::vector<Recorded> events;
};

RunResult run_with(const Model& model, SolverProvider& provider, double t_end) {
    Engine engine(model, provider);
    Recorder rec(model.dof());
    EngineOptions opt;
    opt.t_end = t_end;
    opt.samples = false;
    RunResult r;
    r.summary = engine.run(opt, rec);
    r.events = std::move(rec.events);
    testing::canonical_order(r.events);
    return r;
}

RunResult run_reference(const Model& model, double t_end, int digits = 30) {
    Recorder rec(model.dof());
    EngineOptions opt;
    opt.t_end = t_end;
    opt.samples = false;
    RunResult r;
    r.summary = reference::simulate_precise(model, digits, opt, rec).summary;
    r.events = std::move(rec.events);
    testing::canonical_order(r.events);
    return r;
}

std::string describe(const std::vector<Recorded>& ev) {
    std::ostringstream s;
    s.precision(17);
    for (const Recorded& e : ev) s << "  " << e.t << " " << event_kind_name(e.kind) << " " << e.element << "\n";
    return s.str();
}

// The engine's event rows against the reference's: the same kinds and
// elements in the same order (rows of one instant in canonical order), times
// within `tol` seconds. The tie models all start at t0 = 0 and their fastest
// motion has a period of 0.19 s (sqrt(1100) rad/s) to 2 pi s, so 1e-9 s is
// below 1e-8 of any period: far above the double engine's rounding (event
// times within a few ulps), far below any physical difference (a missed or
// spurious switch moves the next row by a fraction of a period).
void expect_same_rows(const RunResult& engine, const RunResult& ref, double tol, const std::string& what) {
    ASSERT_EQ(engine.summary.status, RunStatus::ok) << what << ": " << engine.summary.message;
    ASSERT_EQ(ref.summary.status, RunStatus::ok) << what << " (reference): " << ref.summary.message;
    ASSERT_EQ(engine.events.size(), ref.events.size())
        << what << "\nengine:\n" << describe(engine.events) << "reference:\n" << describe(ref.events);
    for (std::size_t k = 0; k < ref.events.size(); ++k) {
        EXPECT_EQ(engine.events[k].kind, ref.events[k].kind) << what << " row " << k;
        EXPECT_EQ(engine.events[k].element, ref.events[k].element) << what << " row " << k;
        EXPECT_NEAR(engine.events[k].t, ref.events[k].t, tol) << what << " row " << k;
    }
    EXPECT_TRUE(engine.summary.configuration == ref.summary.configuration) << what << ": end configuration";
}

#if HSNC_WITH_JIT
JitSolverProvider::SourceFn emitter_of(const Model& model) {
    return [&model](const Configuration& cfg) {
        return JitKernelSource{kernel_symbol(model, cfg), emit_kernel(derive(model, cfg))};
    };
}
#endif

// The kernel kinds the tests can build for any model: the generic solver, and
// kernels emitted and compiled in-process (the ahead-of-time kernels exist
// for the bundled models only, and are the same printed code).
struct Kind {
    std::string name;
    std::unique_ptr<SolverProvider> provider;
};

std::vector<Kind> kernel_kinds(const Model& m) {
    std::vector<Kind> kinds;
    kinds.push_back({"generic", std::make_unique<GenericSolverProvider>(m)});
#if HSNC_WITH_JIT
    kinds.push_back({"jit", std::make_unique<JitSolverProvider>(m, emitter_of(m))});
#endif
    return kinds;
}

// The first positive root of tan u = u (sin u - u cos u = 0), by Newton from 4.5.
double first_tan_root() {
    double u = 4.5;
    for (int k = 0; k < 50; ++k) u -= (std::sin(u) - u * std::cos(u)) / (u * std::sin(u));
    return u;
}

// Issue 11: G = G' = G'' = 0 at t0 and G''' = -10 < 0 (a mass at rest on a zero
// gap under -sin(10 t)): the contact starts open and stays open while
// x = -(sin 10t - 10t cos 10t)/200 < 0, that is until 10 t = 4.4934..., the
// first root of tan u = u; the first row is that contact_close. The engine
// wrote a contact_close at 3.8e-159 s and a contact_open at 6.4e-9 s (both
// kernel kinds: the resonant terms claimed the rounding of their sum, ~t^3,
// instead of that of their terms, ~t), and with an honest rounding level the
// search crawled (30000 evaluations on the first segment) until the tie logic
// of tie_series.h.
TEST(EngineTies, ZeroGapUnderNegativeSineClosesFirstWhereTheClosedFormSays) {
    const Model m = model_from(zero_gap_model(-1.0));
    const double t1 = first_tan_root() / 10;
    for (Kind& k : kernel_kinds(m)) {
        const RunResult r = run_with(m, *k.provider, 1.0);
        ASSERT_EQ(r.summary.status, RunStatus::ok) << k.name << ": " << r.summary.message;
        ASSERT_FALSE(r.events.empty()) << k.name;
        EXPECT_EQ(r.events[0].kind, EventKind::contact_close) << k.name << "\n" << describe(r.events);
        EXPECT_NEAR(r.events[0].t, t1, 4 * kEps) << k.name << "\n" << describe(r.events);
        // 3 rows in 1 s: 40 evaluations; the crawl took 30000.
        EXPECT_LT(r.summary.evaluations, 400u) << k.name;
    }
}

// The resonant (coupled) terms of an undamped mode forced at its own
// frequency, from rest: x = F/(2 W^2) (sin u - u cos u), u = W tau, is ~u^3/3
// while its terms are ~u. Each kernel kind's value of G = x must lie within the
// rounding level it states (16 eps (scale + |G'| tau), engine.h) of the exact
// value (the series of sin u - u cos u in long double).
TEST(EngineTies, ResonantTermsStateTheRoundingOfTheirTerms) {
    const Model m = model_from(zero_gap_model(-1.0));
    const Configuration open = Configuration::all_open(m);
    std::vector<std::unique_ptr<SegmentSolver>> solvers;
    std::vector<std::string> names;
    solvers.push_back(std::make_unique<GenericSolver>(m, open));
    names.push_back("generic");
#if HSNC_WITH_JIT
    Jit jit;
    jit.add("zero-gap", emit_kernel(derive(m, open)));
    solvers.push_back(
        std::make_unique<KernelSolver>(*static_cast<const hsnc_kernel*>(jit.lookup(kernel_symbol(m, open)))));
    names.push_back("jit");
#endif
    const double x0[1] = {0.0}, v0[1] = {0.0};
    const signed char sgn[1] = {0};
    for (std::size_t s = 0; s < solvers.size(); ++s) {
        SegmentSolver& S = *solvers[s];
        S.setup(0.0, x0, v0, sgn);
        ASSERT_EQ(S.switches().size(), 1u);
        for (double tau : {1e-200, 1e-12, 1e-9, 1e-6, 1e-3, 0.1, 0.4}) {
            double x[1], v[1], a[1], g[1], dg[1], bound[1], scale[1];
            S.eval(tau, {x, v, a, g, dg, bound, scale});
            const long double u = 10.0L * tau;
            long double series = 0, term = u;  // sum_k (-1)^(k+1) 2k u^(2k+1)/(2k+1)!
            for (int k = 1; k < 40; ++k) {
                term *= u * u / ((2 * k) * (2 * k + 1));
                series += (k % 2 ? 1 : -1) * 2 * k * term;
            }
            const long double exact = -series / 200;
            const double level = 16 * kEps * (scale[0] + std::fabs(dg[0]) * tau);
            EXPECT_LE(std::fabs(static_cast<double>(g[0] - exact)), level)
                << names[s] << " tau = " << tau << ": G = " << g[0] << ", exact " << static_cast<double>(exact)
                << ", scale " << scale[0];
        }
    }
}

// Issue 11: the engine writes the reference's rows on the four tie models of
// the reference's tie tests: +-sin forcing on a zero gap (G''' decides closed
// or open), a load pulling off a zero gap (G'' decides open; its later returns
// to 0 only touch: no rows), and the friction tie (|A| = mu_s N with
// A' = A'' = 0, A''' decides: it slides from t0).
TEST(EngineTies, TieModelsWriteTheReferenceRows) {
    struct Case {
        std::string what, toml;
        double t_end;
        std::size_t min_rows;
    };
    const Case cases[] = {
        {"zero gap, +sin", zero_gap_model(1.0), 2.0, 4},
        {"zero gap, -sin", zero_gap_model(-1.0), 2.0, 4},
        {"zero gap, load", kZeroGapLoad, 2.0, 0},
        {"friction tie", hsnc::test::kFrictionTieModel, 6.0, 1},
    };
    for (const Case& c : cases) {
        const Model m = model_from(c.toml);
        const RunResult ref = run_reference(m, c.t_end);
        ASSERT_GE(ref.events.size(), c.min_rows) << c.what << "\n" << describe(ref.events);
        for (Kind& k : kernel_kinds(m))
            expect_same_rows(run_with(m, *k.provider, c.t_end), ref, 1e-9, c.what + ", " + k.name);
    }
}

// Issue 11: a touch (G = 0 with G' = 0) at a friction stop under harmonic
// forcing. m = k = g = 1, mu_k = 1/8, x0 = 1, forcing F sin 3t, a stop with
// G = -x - 3/4. While the mass slides back,
//     x = 1/8 + (7/8) cos t + (F/8)(3 sin t - sin 3t),
//     v = -sin t (7/8 - (3F/4) sin 2t) < 0 on (0, pi) for |F| < 7/6,
// so it stops at t = pi on x = -3/4, exactly on the gap (G = G' = 0, G at its
// maximum). |A| = 3/4 < mu_s N = 7/8: it sticks, and G stays at 0 while it is
// stuck, which is no switch (interface.md "Ties and touches"): no contact
// rows, however many forcing periods pass. It releases at the first t > pi
// with |A| = |3/4 + F sin 3t| > 7/8: for F = 1/2, sin 3t = 1/4 rising,
// t_r = (4 pi + asin(1/4))/3, and slides away from the stop (A > 0, G'' < 0:
// the contact stays open). For F = 1/10, |A| <= 0.85 < 7/8: stuck for good.
std::string touch_model(double amplitude) {
    return R"(
name = "touch-at-forced-stop"
[parameters]
g = 1
[[mass]]
name = "m1"
m = 1
mu_k = 0.125
mu_s = 0.875
[[spring]]
between = ["ground", "m1"]
k = 1
[[contact]]
between = ["ground", "m1"]
gap = 0.75
k = 1000
[[forcing]]
omega = 3
amplitude = { m1 = )" + std::to_string(amplitude) + R"( }
[initial]
x = { m1 = 1 }
)";
}

TEST(EngineTies, TouchAtAForcedFrictionStopReleasesWhereTheClosedFormSays) {
    const Model m = model_from(touch_model(0.5));
    const double t_release = (4 * kPi + std::asin(0.25)) / 3;
    for (Kind& k : kernel_kinds(m)) {
        const RunResult r = run_with(m, *k.provider, t_release + 0.5);
        ASSERT_EQ(r.summary.status, RunStatus::ok) << k.name << ": " << r.summary.message;
        ASSERT_EQ(r.events.size(), 2u) << k.name << "\n" << describe(r.events);
        EXPECT_EQ(r.events[0].kind, EventKind::stick) << k.name;
        EXPECT_NEAR(r.events[0].t, kPi, 8 * kEps * kPi) << k.name;
        EXPECT_NEAR(r.events[0].x[0], -0.75, 4 * kEps) << k.name;
        EXPECT_EQ(r.events[1].kind, EventKind::release) << k.name;
        EXPECT_NEAR(r.events[1].t, t_release, 8 * kEps * t_release) << k.name;
        EXPECT_EQ(r.summary.configuration.closed[0], 0) << k.name;
        EXPECT_EQ(r.summary.configuration.stuck[0], 0) << k.name;
        EXPECT_GT(r.summary.v[0], 0.0) << k.name << ": it slides away from the stop";
    }
}

TEST(EngineTies, TouchAtAForcedFrictionStopWritesNoContactRowsOverManyPeriods) {
    const Model m = model_from(touch_model(0.1));
    for (Kind& k : kernel_kinds(m)) {
        const RunResult r = run_with(m, *k.provider, 60.0);  // 27 forcing periods stuck on the gap
        ASSERT_EQ(r.summary.status, RunStatus::ok) << k.name << ": " << r.summary.message;
        ASSERT_EQ(r.events.size(), 1u) << k.name << "\n" << describe(r.events);
        EXPECT_EQ(r.events[0].kind, EventKind::stick) << k.name;
        EXPECT_NEAR(r.events[0].t, kPi, 8 * kEps * kPi) << k.name;
        EXPECT_EQ(r.summary.configuration.closed[0], 0) << k.name;
        EXPECT_EQ(r.summary.x[0], r.events[0].x[0]) << k.name;
    }
}

// The same touch with the reference: it wrote a contact_close at the stop and
// a contact_open at the release (its transitions toggled a contact found at
// G = G' = 0 by the rounding of the stopping velocity); now both engines write
// stick, release, stick, release, stick (t = 20 s), with no contact rows.
TEST(EngineTies, TouchAtAForcedFrictionStopWritesTheReferenceRows) {
    const Model m = model_from(touch_model(0.5));
    const RunResult ref = run_reference(m, 20.0);
    ASSERT_EQ(ref.events.size(), 5u) << describe(ref.events);
    for (const Recorded& e : ref.events)
        EXPECT_TRUE(e.kind == EventKind::stick || e.kind == EventKind::release) << describe(ref.events);
    for (Kind& k : kernel_kinds(m)) expect_same_rows(run_with(m, *k.provider, 20.0), ref, 1e-9, "touch, " + k.name);
}

// A contact tied to the fifth derivative: a mass at rest on a zero gap
// (G = x) with x'' + x = -sin t + (1/2) sin 2t. At t0 = 0: G'' = A = 0,
// G''' = A' = -1 + 2 (1/2) = 0, G'''' = A'' - G'' = 0, and
// G^(5) = A''' - G''' = 1 - 4 = -3 < 0: the contact enters open
// (interface.md "Ties and touches": the first non-zero derivative of any
// order). The open motion is x = (t cos t)/2 - (sin 2t)/6 - (sin t)/6
// (= -t^5/40 + ...), which returns to 0 first at the root of
// 3 t cos t = sin t (2 cos t + 1) near 4.65: the first row is that
// contact_close. Deciding by G'' and G''' alone left the contact in its
// provisional closed state.
constexpr const char* kFifthOrderTie = R"(
name = "fifth-order-tie"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["ground", "m1"]
k = 1
[[contact]]
between = ["m1", "ground"]
gap = 0
k = 1000
[[forcing]]
omega = 1
amplitude = { m1 = -1 }
[[forcing]]
omega = 2
amplitude = { m1 = 0.5 }
)";

// The first positive root of 3 t cos t - sin t (2 cos t + 1) (x above), by
// bisection in long double on [4.5, 4.8], where it changes sign once.
double fifth_order_tie_return() {
    auto f = [](long double t) { return 3 * t * std::cos(t) - std::sin(t) * (2 * std::cos(t) + 1); };
    long double lo = 4.5L, hi = 4.8L;
    EXPECT_TRUE(f(lo) < 0 && f(hi) > 0);
    for (int k = 0; k < 200; ++k) {
        const long double mid = (lo + hi) / 2;
        (f(mid) < 0 ? lo : hi) = mid;
    }
    return static_cast<double>((lo + hi) / 2);
}

TEST(EngineTies, ContactTiedToTheFifthDerivativeEntersOpenAtT0) {
    const Model m = model_from(kFifthOrderTie);
    const double x0[1] = {0.0}, v0[1] = {0.0};
    std::vector<signed char> sgn;
    const Configuration cfg = entered_configuration(m, 0.0, x0, v0, sgn);
    EXPECT_EQ(cfg.closed[0], 0);
    const double t1 = fifth_order_tie_return();
    const RunResult ref = run_reference(m, 5.0);
    ASSERT_FALSE(ref.events.empty()) << describe(ref.events);
    EXPECT_EQ(ref.events[0].kind, EventKind::contact_close) << describe(ref.events);
    EXPECT_NEAR(ref.events[0].t, t1, 1e-12) << describe(ref.events);
    for (Kind& k : kernel_kinds(m)) {
        const RunResult r = run_with(m, *k.provider, 5.0);
        expect_same_rows(r, ref, 1e-9, "fifth-order tie, " + k.name);
        ASSERT_FALSE(r.events.empty()) << k.name;
        EXPECT_EQ(r.events[0].kind, EventKind::contact_close) << k.name << "\n" << describe(r.events);
        EXPECT_NEAR(r.events[0].t, t1, 8 * kEps * t1) << k.name << "\n" << describe(r.events);
    }
}

// The same tie at a switch instant: a closed contact whose switch function
// reached 0 with G = G' = 0 is decided after the friction decisions by its
// first non-zero derivative, here G^(5) < 0: it opens (one contact_open row).
// An open one stays open: no row.
TEST(EngineTies, ContactTiedToTheFifthDerivativeOpensAtASwitch) {
    const Model m = model_from(kFifthOrderTie);
    double x[1] = {0.0}, v[1] = {0.0};
    const double a[1] = {0.0};
    for (char closed : {1, 0}) {
        Configuration cfg = Configuration::all_open(m);
        cfg.closed[0] = closed;
        std::vector<signed char> sgn(1, 0);
        std::vector<Transition> out;
        std::string why;
        ASSERT_TRUE(apply_switches(m, 0.0, x, v, a, cfg, sgn, {SwitchFunction{SwitchKind::gap, 0}}, out, why)) << why;
        EXPECT_EQ(cfg.closed[0], 0) << int(closed);
        if (closed) {
            ASSERT_EQ(out.size(), 1u);
            EXPECT_EQ(out[0].kind, EventKind::contact_open);
            EXPECT_EQ(out[0].element, 0);
        } else {
            EXPECT_TRUE(out.empty());
        }
    }
}

// Issue 11: at t0 = 1e9 the smallest step, the time's own resolution 4 eps |t|,
// is 8.9e-7 s. A bilinear oscillator of 1e7-1.4e7 rad/s (periods 4.4e-7 to
// 6.3e-7 s) switched 35 times in 1e-5 s from t0 = 0, and from t0 = 1e9 the
// engine wrote no row at all and reported ok (every value of its gap within
// the rounding |G'| 16 eps |t| = 35 m gave it). Now it is refused with a
// message saying why; from t0 = 0 it still runs.
TEST(LargeT0, MotionFasterThanTheTimeResolutionIsRefused) {
    auto fast = [](double t0) {
        return model_from(R"(
name = "fast"
[[mass]]
name = "m1"
m = 1e-6
[[spring]]
between = ["ground", "m1"]
k = 1e8
[[contact]]
between = ["m1", "ground"]
gap = 0.5
k = 1e8
[initial]
x = { m1 = 1 }
t0 = )" + std::to_string(t0) + "\n");
    };
    const Model m0 = fast(0.0);
    for (Kind& k : kernel_kinds(m0)) {
        const RunResult r = run_with(m0, *k.provider, 1e-5);
        ASSERT_EQ(r.summary.status, RunStatus::ok) << k.name << ": " << r.summary.message;
        EXPECT_EQ(r.events.size(), 35u) << k.name;
    }
    const Model m = fast(1e9);
    for (Kind& k : kernel_kinds(m)) {
        const RunResult r = run_with(m, *k.provider, 1e9 + 1e-5);
        EXPECT_EQ(r.summary.status, RunStatus::failure) << k.name;
        EXPECT_TRUE(r.events.empty()) << k.name;
        EXPECT_NE(r.summary.message.find("too fast for the time resolution at t = 1000000000"), std::string::npos)
            << r.summary.message;
        EXPECT_NE(r.summary.message.find("smallest step there is 8.88e-07 s"), std::string::npos) << r.summary.message;
    }
}

}  // namespace
}  // namespace hsnc
