// Loads that change in time (`[[load_step]]`, interface.md): a run goes in
// pieces, one per constant load, each from the exact state where the last one
// ended, and the step's instant is a `load_change` row.
//
// The truths are closed forms derived here: code_aster's validation case
// SDND106 (two masses, Coulomb stick-slip with mu_s != mu_k, a push switched
// off at 0.2 s) and a step-loaded oscillator; CVODE and the CLN reference on
// the same models; and the refusals (bad steps, analyses that need a constant load).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "engine_runner.h"
#include "error.h"
#include "fe_models.h"
#include "hsnc/simulate.h"
#include "model.h"
#include "model_reader.h"
#include "sample_grid.h"
#include "temp_dir.h"

namespace hsnc {
namespace {

using Real = long double;

// SDND106: m1 = m2 = 5 kg, a spring k = 1e4 N/m between them, friction of
// m1 on the ground with N = 1e4 N (mu_s 0.3, mu_k 0.2), a push F = 3000 N on
// m2 from t = 0, switched off at t1 = 0.2 s; from rest.
constexpr double kM = 5.0, kK = 1.0e4, kN = 1.0e4, kMuS = 0.3, kMuK = 0.2, kF = 3000.0, kT1 = 0.2;

std::string sdnd106(double t_end = 1.0) {
    char text[1024];
    std::snprintf(text, sizeof text, R"(name = "sdnd106"
[parameters]
push = %.17g
[[mass]]
name = "m1"
m = %.17g
[[mass]]
name = "m2"
m = %.17g
[[spring]]
between = ["m1", "m2"]
k = %.17g
[[friction]]
name = "f1"
between = ["m1", "ground"]
mu_k = %.17g
mu_s = %.17g
normal = %.17g
[load]
m2 = "push"
[[load_step]]
name = "push_off"
t = %.17g
load = { m2 = 0.0 }
[simulate]
t_end = %.17g
)",
                  kF, kM, kM, kK, kMuK, kMuS, kN, kT1, t_end);
    return text;
}

// The motion of SDND106 in closed form, phase by phase.
//  A, [0, tr]: m1 stuck at 0; m2 x2'' = F - k x2: x2 = (F/k)(1 - cos w t), w = sqrt(k/m).
//     The spring pulls m1 with k x2 = F(1 - cos w t); it releases where that
//     reaches mu_s N = 3000 = F: cos w tr = 0, tr = pi/(2w) (the force then grows: a release).
//  B, [tr, t1]: both slide, m1 forward: in the centre c = (x1 + x2)/2 and the
//     stretch r = x2 - x1, c'' = (F - mu_k N)/(2m), r'' = (F + mu_k N - 2 k r)/m.
//  C, [t1, ts]: the push off: c'' = -mu_k N/(2m), r'' = (mu_k N - 2 k r)/m,
//     until v1 = c' - r'/2 returns to 0 at ts.
//  D, [ts, ...]: m1 sticks if |k r(ts)| < mu_s N; m2 then oscillates about x1
//     (r'' = -k r/m) and m1 stays while k |r| stays below mu_s N.
struct Sdnd106 {
    Real w = std::sqrt(Real(kK) / kM), W = std::sqrt(2 * Real(kK) / kM);
    Real tr = std::acos(Real(-1)) / (2 * w);
    // A phase of c and r: c(tau) = c0 + c1 tau + a tau^2/2, r = rs + (r0 - rs) cos W tau + (r1/W) sin W tau.
    struct Phase {
        Real c0, c1, a, r0, r1, rs, W;
        Real c(Real tau) const { return c0 + c1 * tau + a * tau * tau / 2; }
        Real dc(Real tau) const { return c1 + a * tau; }
        Real r(Real tau) const { return rs + (r0 - rs) * std::cos(W * tau) + r1 / W * std::sin(W * tau); }
        Real dr(Real tau) const { return -(r0 - rs) * W * std::sin(W * tau) + r1 * std::cos(W * tau); }
        Real x1(Real tau) const { return c(tau) - r(tau) / 2; }
        Real x2(Real tau) const { return c(tau) + r(tau) / 2; }
        Real v1(Real tau) const { return dc(tau) - dr(tau) / 2; }
        Real v2(Real tau) const { return dc(tau) + dr(tau) / 2; }
    };
    Phase B, C;
    Real ts = 0, x1s = 0, r_s = 0, dr_s = 0;
    Sdnd106() {
        const Real x2r = Real(kF) / kK, v2r = Real(kF) / kK * w;  // phase A at tr
        B = {x2r / 2, v2r / 2, (kF - kMuK * kN) / (2 * Real(kM)), x2r, v2r, (kF + kMuK * kN) / (2 * Real(kK)), W};
        const Real tB = kT1 - tr;
        C = {B.c(tB), B.dc(tB), -kMuK * kN / (2 * Real(kM)), B.r(tB), B.dr(tB), kMuK * kN / (2 * Real(kK)), W};
        // ts: the first zero of v1 in phase C, bracketed on a fine grid, then bisected to the last bit.
        Real lo = 0, hi = 0;
        for (int i = 1; i < 100000; ++i)
            if (C.v1(i * Real(1e-5)) <= 0) {
                lo = (i - 1) * Real(1e-5), hi = i * Real(1e-5);
                break;
            }
        for (int i = 0; i < 200; ++i) {
            const Real mid = (lo + hi) / 2;
            (C.v1(mid) > 0 ? lo : hi) = mid;
        }
        ts = kT1 + lo;
        x1s = C.x1(lo), r_s = C.r(lo), dr_s = C.dr(lo);
    }
    bool phase_b_slides() const {  // v1 > 0 inside phase B (it starts at 0 with a1 > 0)
        for (int i = 1; i <= 10000; ++i)
            if (B.v1((kT1 - tr) * i / 10000) <= 0) return false;
        return true;
    }
    // Phase D: m2 about the stuck m1.
    Real x2_d(Real t) const { return x1s + r_s * std::cos(w * (t - ts)) + dr_s / w * std::sin(w * (t - ts)); }
    Real v2_d(Real t) const { return -r_s * w * std::sin(w * (t - ts)) + dr_s * std::cos(w * (t - ts)); }
    Real amplitude_d() const { return std::sqrt(r_s * r_s + dr_s * dr_s / (w * w)); }
};

Model sdnd106_model(double t_end = 1.0) {
    return parse_model(sdnd106(t_end), "sdnd106.toml");
}

testing::Outcome run(const Model& model, SimulateOptions o, double dt = 0.0) {
    testing::Recorder rec(model.dof(), model.state_size());
    o.dt = dt > 0 ? dt : NAN;
    o.samples = dt > 0;
    testing::Outcome out;
    out.summary = simulate(model, o, rec);
    out.events = rec.events;
    out.samples = rec.samples;
    return out;
}

// The run's events against the closed form: release, the step, stick; then
// the end state at t = 1 s (m1 stuck, m2 oscillating about it).
void expect_closed_form(const testing::Outcome& r, double tol_t, double tol_x, const std::string& who) {
    const Sdnd106 e;
    ASSERT_EQ(r.summary.status, RunStatus::ok) << who << ": " << r.summary.message;
    ASSERT_EQ(r.events.size(), 3u) << who;
    EXPECT_EQ(r.events[0].kind, EventKind::release) << who;
    EXPECT_NEAR(r.events[0].t, static_cast<double>(e.tr), tol_t) << who;
    EXPECT_EQ(r.events[0].x[0], 0.0) << who;  // stuck until then, exactly
    EXPECT_NEAR(r.events[0].x[1], kF / kK, tol_x) << who;

    const testing::Recorded& step = r.events[1];
    EXPECT_EQ(step.kind, EventKind::load_change) << who;
    EXPECT_EQ(step.element, 0) << who;
    EXPECT_EQ(step.t, kT1) << who;  // the step's own instant, exactly
    const Real tB = kT1 - e.tr;
    EXPECT_NEAR(step.x[0], static_cast<double>(e.B.x1(tB)), tol_x) << who;
    EXPECT_NEAR(step.x[1], static_cast<double>(e.B.x2(tB)), tol_x) << who;
    EXPECT_NEAR(step.v[0], static_cast<double>(e.B.v1(tB)), tol_x * 100) << who;
    EXPECT_NEAR(step.v[1], static_cast<double>(e.B.v2(tB)), tol_x * 100) << who;

    EXPECT_EQ(r.events[2].kind, EventKind::stick) << who;
    EXPECT_NEAR(r.events[2].t, static_cast<double>(e.ts), tol_t) << who;
    EXPECT_NEAR(r.events[2].x[0], static_cast<double>(e.x1s), tol_x) << who;
    EXPECT_NEAR(r.events[2].x[1], static_cast<double>(e.x1s + e.r_s), tol_x) << who;

    EXPECT_EQ(r.summary.t, 1.0) << who;
    EXPECT_EQ(r.summary.v[0], 0.0) << who;
    EXPECT_NEAR(r.summary.x[0], static_cast<double>(e.x1s), tol_x) << who;
    EXPECT_NEAR(r.summary.x[1], static_cast<double>(e.x2_d(1)), tol_x) << who;
    EXPECT_NEAR(r.summary.v[1], static_cast<double>(e.v2_d(1)), tol_x * 100) << who;
}

TEST(LoadStep, TheClosedFormOfSdnd106HoldsItsOwnAssumptions) {
    // The derivation's phases are the motion's: m1 slides forward all of phase
    // B, sticks at ts (the spring's pull below mu_s N), and stays stuck to 1 s.
    const Sdnd106 e;
    EXPECT_NEAR(static_cast<double>(e.tr), M_PI / (2 * std::sqrt(2000.0)), 1e-16);
    EXPECT_TRUE(e.phase_b_slides());
    EXPECT_GT(e.ts, Real(kT1));
    EXPECT_LT(e.ts, Real(1));
    EXPECT_LT(kK * std::fabs(static_cast<double>(e.r_s)), kMuS * kN);      // it sticks, not reverses
    EXPECT_LT(kK * static_cast<double>(e.amplitude_d()), kMuS * kN);       // and never releases again
    EXPECT_LT(std::fabs(static_cast<double>(e.C.v1(e.ts - kT1))), 1e-15);  // v1 = 0 there
}

TEST(LoadStep, Sdnd106FollowsItsClosedFormOnEveryKernelKindAndTheReference) {
    const Model model = sdnd106_model();
    for (KernelChoice k : {KernelChoice::generic, KernelChoice::interp, KernelChoice::eigen}) {
        SimulateOptions o;
        o.kernels = k;
        expect_closed_form(run(model, o), 1e-12, 1e-12, kernel_choice_name(k));
    }
    SimulateOptions ref;
    ref.precision_digits = 30;
    expect_closed_form(run(model, ref), 1e-13, 1e-13, "mp:30");
    // The bundled example is this model.
    const Model example = read_model(std::string(HSNC_SOURCE_DIR) + "/examples/load_step/sdnd106.toml");
    expect_closed_form(run(example, SimulateOptions{}), 1e-12, 1e-12, "examples/load_step/sdnd106.toml");
    if (HSNC_WITH_CVODE) {
        SimulateOptions cv;
        cv.method = Method::cvode;
        cv.integrator.rtol = 1e-12;
        cv.integrator.atol = 1e-14;
        expect_closed_form(run(model, cv), 1e-9, 1e-8, "cvode");
    }
}

TEST(LoadStep, SamplesStayOnTheWholeRunsGridAcrossASteps) {
    // dt = 0.03: the step (0.2) is not on the grid, which goes on from t0 as
    // if there were no step: 0, 0.03, ..., 0.99, and t_end, each once.
    const Model model = sdnd106_model();
    const double dt = 0.03;
    const testing::Outcome r = run(model, SimulateOptions{}, dt);
    const SampleGrid grid(0.0, 1.0, dt);
    ASSERT_EQ(static_cast<double>(r.samples.size()), grid.count());
    for (std::size_t k = 0; k < r.samples.size(); ++k) EXPECT_EQ(r.samples[k].t, grid.time(k)) << k;
    // The sample in phase C agrees with the closed form.
    const Sdnd106 e;
    const testing::Recorded& s = r.samples[7];  // t = 0.21
    ASSERT_EQ(s.t, 7 * dt);
    EXPECT_NEAR(s.x[0], static_cast<double>(e.C.x1(Real(s.t) - kT1)), 1e-12);
    EXPECT_NEAR(s.v[1], static_cast<double>(e.C.v2(Real(s.t) - kT1)), 1e-10);
    // dt = 0.1: the step is on the grid, and its row is written once.
    const testing::Outcome on = run(model, SimulateOptions{}, 0.1);
    ASSERT_EQ(on.samples.size(), 11u);
    EXPECT_EQ(on.samples[2].t, 0.2);
    EXPECT_EQ(on.samples[2].x, on.events[1].x);  // the sample at the step is the state the step row holds
}

// A 1-dof oscillator (m, k) from rest under a load F0, which steps to F1 at t1
// and to 0 at t2: x = x_eq + (x(tk) - x_eq) cos w(t - tk) + v(tk)/w sin w(t - tk) per piece.
TEST(LoadStep, AStepLoadedOscillatorFollowsItsClosedFormPieceByPiece) {
    const double m = 2.0, k = 800.0, F0 = 10.0, F1 = -4.0, t1 = 0.13, t2 = 0.41, t_end = 0.7;
    char text[512];
    std::snprintf(text, sizeof text, R"(name = "stepped"
[[mass]]
name = "m"
m = %.17g
[[spring]]
between = ["ground", "m"]
k = %.17g
[load]
m = %.17g
[[load_step]]
t = %.17g
load = { m = %.17g }
[[load_step]]
name = "off"
t = %.17g
load = { m = 0.0 }
)",
                  m, k, F0, t1, F1, t2);
    const Model model = parse_model(text, "stepped.toml");
    ASSERT_EQ(model.load_steps.size(), 2u);
    EXPECT_EQ(model.load_steps[0].name, "load_step1");
    SimulateOptions o;
    o.t_end = t_end;
    const testing::Outcome r = run(model, o, 0.01);
    ASSERT_EQ(r.summary.status, RunStatus::ok);
    ASSERT_EQ(r.events.size(), 2u);
    const Real w = std::sqrt(Real(k) / m);
    Real x = 0, v = 0, tk = 0, F = F0;
    auto at = [&](Real t, Real& xo, Real& vo) {
        const Real xe = F / k, s = std::sin(w * (t - tk)), c = std::cos(w * (t - tk));
        xo = xe + (x - xe) * c + v / w * s;
        vo = -(x - xe) * w * s + v * c;
    };
    std::size_t checked = 0;
    auto check_samples_to = [&](Real until) {
        for (const testing::Recorded& s : r.samples)
            if (Real(s.t) >= tk && Real(s.t) <= until) {
                Real xs, vs;
                at(s.t, xs, vs);
                EXPECT_NEAR(s.x[0], static_cast<double>(xs), 1e-14) << s.t;
                EXPECT_NEAR(s.v[0], static_cast<double>(vs), 1e-12) << s.t;
                ++checked;
            }
    };
    const Real t_next[] = {t1, t2}, F_next[] = {F1, 0};
    const char* names[] = {"load_step1", "off"};
    for (std::size_t i = 0; i < 2; ++i) {
        check_samples_to(t_next[i]);
        Real xn, vn;
        at(t_next[i], xn, vn);
        const testing::Recorded& e = r.events[i];
        EXPECT_EQ(e.kind, EventKind::load_change);
        EXPECT_EQ(e.t, static_cast<double>(t_next[i]));
        EXPECT_EQ(model.load_steps[static_cast<std::size_t>(e.element)].name, names[i]);
        EXPECT_NEAR(e.x[0], static_cast<double>(xn), 1e-14);
        EXPECT_NEAR(e.v[0], static_cast<double>(vn), 1e-12);
        x = xn, v = vn, tk = t_next[i], F = F_next[i];
    }
    check_samples_to(t_end);
    EXPECT_EQ(checked, r.samples.size() + 1);  // t = 0.13 is no sample; 0.41 is one, checked on both sides
}

// Contacts, a Jenkins joint and friction across two steps: the engine against
// CVODE (tight) and the reference, event for event; the sliders carry over.
std::string stepped_joint(const std::string& steps) {
    return R"(name = "stepped-joint"
[[mass]]
name = "a"
m = 1.0
[[mass]]
name = "b"
m = 0.5
mu_k = 0.3
mu_s = 0.4
[[spring]]
between = ["ground", "a"]
k = 400.0
[[spring]]
between = ["a", "b"]
k = 200.0
[[jenkins]]
name = "joint"
between = ["a", "ground"]
k = 300.0
slip_force = 2.0
[[contact]]
name = "stop"
between = ["a", "ground"]
gap = 0.012
k = 5000.0
[damping]
alpha = 0.5
[[forcing]]
omega = 17.0
amplitude = { a = 3.0 }
[load]
a = 4.0
)" + steps;
}

TEST(LoadStep, ContactsJenkinsAndFrictionCrossTwoStepsAsCvodeAndTheReferenceSay) {
    const Model model = parse_model(stepped_joint(R"([[load_step]]
t = 0.8
load = { a = -3.0, b = 1.0 }
[[load_step]]
t = 1.7
load = { a = 0.0, b = 0.0 }
)"),
                                    "stepped-joint.toml");
    SimulateOptions o;
    o.t_end = 2.5;
    const testing::Outcome r = run(model, o);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    std::size_t changes = 0, kinds[6] = {};
    for (const testing::Recorded& e : r.events)
        changes += e.kind == EventKind::load_change, ++kinds[static_cast<int>(e.kind)];
    EXPECT_EQ(changes, 2u);
    EXPECT_GT(kinds[static_cast<int>(EventKind::contact_close)], 0u);
    EXPECT_GT(kinds[static_cast<int>(EventKind::release)], 0u);
    EXPECT_GT(kinds[static_cast<int>(EventKind::stick)], 0u);

    auto compare = [&](const testing::Outcome& other, double tol, const std::string& who) {
        ASSERT_EQ(other.summary.status, RunStatus::ok) << who << ": " << other.summary.message;
        ASSERT_EQ(other.events.size(), r.events.size()) << who;
        for (std::size_t i = 0; i < r.events.size(); ++i) {
            EXPECT_EQ(other.events[i].kind, r.events[i].kind) << who << " " << i;
            EXPECT_EQ(other.events[i].element, r.events[i].element) << who << " " << i;
            EXPECT_NEAR(other.events[i].t, r.events[i].t, tol) << who << " " << i;
            for (std::size_t j = 0; j < r.events[i].x.size(); ++j)  // the masses, then the slider
                EXPECT_NEAR(other.events[i].x[j], r.events[i].x[j], tol * 10) << who << " " << i << " " << j;
        }
    };
    SimulateOptions ref = o;
    ref.precision_digits = 30;
    compare(run(model, ref), 1e-12, "mp:30");
    if (HSNC_WITH_CVODE) {
        SimulateOptions cv = o;
        cv.method = Method::cvode;
        cv.integrator.rtol = 1e-12;
        cv.integrator.atol = 1e-14;
        compare(run(model, cv), 1e-8, "cvode");
    }
}

// A step to the load there already is changes nothing: the run goes on from
// the state it reached (masses, velocities, the joint's slider, the stuck
// mass, the closed stop) as if it had not stopped there; only the row is new.
TEST(LoadStep, AStepToTheSameLoadChangesNothingButItsRow) {
    const Model plain = parse_model(stepped_joint(""), "plain.toml");
    const Model stepped = parse_model(stepped_joint(R"([[load_step]]
t = 0.8
load = { a = 4.0 }
[[load_step]]
t = 1.7
load = { b = 0.0 }
)"),
                                      "stepped.toml");
    for (const char* how : {"generic", "eigen", "mp:30"}) {
        SimulateOptions o;
        o.t_end = 2.5;
        if (how == std::string("mp:30"))
            o.precision_digits = 30;
        else
            o.kernels = kernel_choice_from_name(how);
        const testing::Outcome a = run(plain, o), b = run(stepped, o);
        ASSERT_EQ(a.summary.status, RunStatus::ok);
        ASSERT_EQ(b.summary.status, RunStatus::ok);
        std::vector<testing::Recorded> switches;
        for (const testing::Recorded& e : b.events)
            if (e.kind != EventKind::load_change) switches.push_back(e);
        ASSERT_EQ(b.events.size(), a.events.size() + 2) << how;
        ASSERT_EQ(switches.size(), a.events.size());
        for (std::size_t i = 0; i < switches.size(); ++i) {
            EXPECT_EQ(switches[i].kind, a.events[i].kind) << i;
            EXPECT_EQ(switches[i].element, a.events[i].element) << i;
            EXPECT_NEAR(switches[i].t, a.events[i].t, 1e-12) << i;
            for (std::size_t j = 0; j < a.events[i].x.size(); ++j)  // the masses, then the slider
                EXPECT_NEAR(switches[i].x[j], a.events[i].x[j], 1e-12) << i << " " << j;
        }
        for (std::size_t j = 0; j < a.summary.x.size(); ++j) EXPECT_NEAR(b.summary.x[j], a.summary.x[j], 1e-12);
        EXPECT_NEAR(b.summary.slider[0], a.summary.slider[0], 1e-12);
    }
}

// A stuck block (friction mu_s N = 6 N) under a load of 5 N, raised to 8 N at
// t1: it releases at that very instant (the row after the step's) and slides
// with x'' = (8 - mu_k N)/m; lowered to 0 at t2 it slows at mu_k N/m and sticks
// where v returns to 0: t2 + v(t2) m/(mu_k N).
TEST(LoadStep, AStuckBlockThatTheNewLoadPullsBeyondStaticFrictionReleasesAtTheStep) {
    const double m = 2.0, normal = 20.0, mu_s = 0.3, mu_k = 0.2, t1 = 0.25, t2 = 0.5;
    char text[512];
    std::snprintf(text, sizeof text, R"(name = "block"
[[mass]]
name = "b"
m = %.17g
[[friction]]
between = ["b", "ground"]
mu_k = %.17g
mu_s = %.17g
normal = %.17g
[load]
b = 5.0
[[load_step]]
t = %.17g
load = { b = 8.0 }
[[load_step]]
t = %.17g
load = { b = 0.0 }
)",
                  m, mu_k, mu_s, normal, t1, t2);
    const Model model = parse_model(text, "block.toml");
    for (const char* how : {"generic", "interp", "mp:30", "cvode"}) {
        if (how == std::string("cvode") && !HSNC_WITH_CVODE) continue;
        SimulateOptions o;
        o.t_end = 1.0;
        if (how == std::string("mp:30"))
            o.precision_digits = 30;
        else if (how == std::string("cvode"))
            o.method = Method::cvode, o.integrator.rtol = 1e-12, o.integrator.atol = 1e-14;
        else
            o.kernels = kernel_choice_from_name(how);
        const testing::Outcome r = run(model, o);
        ASSERT_EQ(r.summary.status, RunStatus::ok) << how;
        ASSERT_EQ(r.events.size(), 4u) << how;
        const double a = (8.0 - mu_k * normal) / m, v2 = a * (t2 - t1), x2 = a * (t2 - t1) * (t2 - t1) / 2;
        const double ts = t2 + v2 * m / (mu_k * normal), xs = x2 + v2 * v2 / (2 * mu_k * normal / m);
        const double tol = how == std::string("cvode") ? 1e-9 : 1e-14;
        EXPECT_EQ(r.events[0].kind, EventKind::load_change) << how;
        EXPECT_EQ(r.events[1].kind, EventKind::release) << how;
        EXPECT_EQ(r.events[1].t, t1) << how;
        EXPECT_EQ(r.events[2].kind, EventKind::load_change) << how;
        EXPECT_NEAR(r.events[2].x[0], x2, tol) << how;
        EXPECT_NEAR(r.events[2].v[0], v2, tol) << how;
        EXPECT_EQ(r.events[3].kind, EventKind::stick) << how;
        EXPECT_NEAR(r.events[3].t, ts, tol) << how;
        EXPECT_NEAR(r.summary.x[0], xs, tol) << how;
    }
}

// A step of the load on a massless (condensed) dof: u (m = 1) and a massless
// r, K = [3 -1; -1 2]. Condensed, k_eff = 3 - 1/2 = 2.5 and r's load f_r acts
// on u as f_r / 2; r follows as x_r = (f_r + x_u) / 2. From rest with f_r = 1,
// then 3 from t = 1: x_u = 0.2 (1 - cos w t), then about 0.6 from the step's
// state, w = sqrt(2.5); the CSV's recovered x_r takes the new load at once.
TEST(LoadStep, AStepOnAMasslessDofMovesItsRecoveredResponseAndTheMassesByTheCondensedLoad) {
    testing::TempDir dir;
    Eigen::MatrixXd M(2, 2), K(2, 2);
    M << 1, 0, 0, 0;
    K << 3, -1, -1, 2;
    const std::string model =
        fe::structure_model(dir, "massless.toml", "massless-step", M, K, {"u", "r"},
                            "[load]\nr = 1.0\n[[load_step]]\nt = 1.0\nload = { r = 3.0 }\n[simulate]\nt_end = 3.0\n");
    const testing::CliRun run =
        testing::run_hsnc("simulate '" + model + "' --dt 0.125 --out '" + dir / "x.csv" + "' --quiet");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const std::string csv = testing::slurp(dir / "x.csv");
    std::istringstream in(csv);
    std::string header;
    std::getline(in, header);
    ASSERT_EQ(header.rfind("t,x_u,", 0), 0u) << header;
    const auto names = [&] {
        std::vector<std::string> v;
        std::istringstream h(header);
        for (std::string c; std::getline(h, c, ',');) v.push_back(c);
        return v;
    }();
    const auto col = [&](const std::string& name) {
        return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
    };
    ASSERT_LT(col("x_r"), names.size()) << header;
    const double w = std::sqrt(2.5), x1 = 0.2 * (1 - std::cos(w)), v1 = 0.2 * w * std::sin(w);
    int rows = 0;
    for (std::string line; std::getline(in, line); ++rows) {
        std::vector<double> cells;
        std::istringstream l(line);
        for (std::string c; std::getline(l, c, ',');) cells.push_back(std::stod(c));
        const double t = cells[0];
        const double xu = t < 1.0 ? 0.2 * (1 - std::cos(w * t))
                                  : 0.6 + (x1 - 0.6) * std::cos(w * (t - 1)) + v1 / w * std::sin(w * (t - 1));
        const double fr = t < 1.0 ? 1.0 : 3.0;
        EXPECT_NEAR(cells[col("x_u")], xu, 1e-13) << "t = " << t;
        EXPECT_NEAR(cells[col("x_r")], (fr + xu) / 2, 1e-13) << "t = " << t;
    }
    EXPECT_EQ(rows, 25);
}

TEST(LoadStep, BadStepsAreRefusedByKeyAndLine) {
    struct Case {
        std::string steps, message;
    };
    const std::vector<Case> cases = {
        {"[[load_step]]\nt = 0.0\nload = { m = 1.0 }\n", "key 'load_step[1].t': must be after t0 = 0"},
        {"[[load_step]]\nt = 0.5\nload = { m = 1.0 }\n[[load_step]]\nt = 0.5\nload = { m = 0.0 }\n",
         "key 'load_step[2].t': must be after the previous step's t = 0.5"},
        {"[[load_step]]\nt = 0.5\n", "key 'load_step[1].load': required key is missing"},
        {"[[load_step]]\nt = 0.5\nload = { q = 1.0 }\n", "key 'load_step[1].load.q': unknown"},
        {"[[load_step]]\nload = { m = 1.0 }\n", "key 'load_step[1].t': required key is missing"},
        {"[[load_step]]\nt = 0.5\nload = { m = 1.0 }\nramp = 0.1\n", "key 'load_step[1].ramp': unknown key"},
        {"[[load_step]]\nname = \"m\"\nt = 0.5\nload = { m = 1.0 }\n", "load_step[1].name"},
    };
    for (const Case& c : cases) {
        const std::string text =
            "name = \"x\"\n[[mass]]\nname = \"m\"\nm = 1.0\n[[spring]]\nbetween = [\"ground\", \"m\"]\n"
            "k = 1.0\n" +
            c.steps;
        try {
            parse_model(text, "bad.toml");
            ADD_FAILURE() << "accepted: " << c.steps;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
            EXPECT_EQ(std::string(e.what()).rfind("bad.toml:", 0), 0u) << e.what();
        }
    }
}

TEST(LoadStep, TheCommandLineWritesTheStepRowAndTheAnalysesThatNeedAConstantLoadSayWhy) {
    testing::TempDir dir;
    const std::string model = dir.path() + "/sdnd106.toml", events = dir.path() + "/events.csv";
    {
        std::FILE* f = std::fopen(model.c_str(), "w");
        ASSERT_NE(f, nullptr);
        std::fputs(sdnd106().c_str(), f);
        std::fclose(f);
    }
    const testing::CliRun r = testing::run_hsnc("simulate '" + model + "' --events '" + events + "' --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find(" events=3 "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(" load_change=1 "), std::string::npos) << r.out;
    const std::string csv = testing::slurp(events);
    EXPECT_NE(csv.find("\n0.20000000000000001,load_change,push_off,"), std::string::npos) << csv;
    const testing::CliRun c = testing::run_hsnc("check '" + model + "'");
    ASSERT_EQ(c.exit_code, 0) << c.err;
    EXPECT_NE(c.out.find("load steps: 1  (the constant load from t on)\n  push_off  t = 0.2  m2 = 0\n"),
              std::string::npos)
        << c.out;

    for (const std::string& command :
         {std::string("periodic '") + model + "' --period 0.1", std::string("lyapunov '") + model + "' --t-end 1",
          std::string("sweep '") + model + "' --param push --from 1 --to 2 --points 2"}) {
        const testing::CliRun a = testing::run_hsnc(command);
        EXPECT_EQ(a.exit_code, 2) << command << ": " << a.err;
        EXPECT_NE(a.err.find("[[load_step]]"), std::string::npos) << command << ": " << a.err;
    }
}

}  // namespace
}  // namespace hsnc
