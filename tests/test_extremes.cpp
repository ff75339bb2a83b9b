// Numerical extremes (issue 7): the engine driven far from comfortable
// parameter values, every case compared with a closed form evaluated here in
// long double (or with an independent computation), never with hsnc's own
// earlier output.
//
// Each test states its bound next to the value measured when it was written
// ("measured 3e-15"); the bounds leave room for compilers and libm, not for
// regressions. Every measurement is also recorded as a test property and, when
// the environment variable HSNC_EXTREMES_TABLE names a file, appended to it as
// one tab-separated row (case, quantity, achieved, bound, verdict);
// bench/extremes_table.sh turns those rows into docs/extremes.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "engine_runner.h"
#include "error.h"
#include "engine.h"
#include "integrators.h"
#include "model_reader.h"
#include "kernel_mode.h"

namespace hsnc {
namespace {

using LD = long double;
constexpr LD kPiL = 3.141592653589793238462643383279502884L;

// ---------------------------------------------------------------------------
// The table of what holds.

std::string fmt(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return buf;
}

// Record (case, quantity, achieved error, bound) and check achieved <= bound.
void measured(const std::string& name, const std::string& quantity, double achieved, double bound) {
    const bool ok = achieved <= bound;  // NaN fails
    ::testing::Test::RecordProperty(name + " | " + quantity, fmt(achieved) + " (bound " + fmt(bound) + ")");
    if (const char* path = std::getenv("HSNC_EXTREMES_TABLE"); path && *path) {
        if (std::FILE* f = std::fopen(path, "a")) {
            std::fprintf(f, "%s\t%s\t%s\t%s\t%s\n", name.c_str(), quantity.c_str(), fmt(achieved).c_str(),
                         fmt(bound).c_str(), ok ? "holds" : "FAILS");
            std::fclose(f);
        }
    }
    EXPECT_LE(achieved, bound) << name << ": " << quantity;
}

// ---------------------------------------------------------------------------
// Driving the engine.

using testing::canonical_order;
using testing::Outcome;
using testing::Recorded;
using testing::Recorder;

// The engine and the baseline, with each instant's rows in canonical order.
Outcome simulate(const Model& model, double t_end, double dt = 0.0) {
    Outcome r = testing::simulate(model, t_end, dt);
    canonical_order(r.events);
    return r;
}

Outcome baseline(const Model& model, double t_end, double rtol, double atol) {
    Outcome r = testing::baseline(model, t_end, rtol, atol);
    canonical_order(r.events);
    return r;
}

Model model_from(const std::string& toml) { return parse_model(toml, "extremes.toml"); }

std::string num(LD v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", static_cast<double>(v));
    return buf;
}

// ---------------------------------------------------------------------------
// 1. Contact-to-structure stiffness ratio 1e2 .. 1e9: bilinear oscillator
// m = 1, k1 = 1, contact k2 = r k1 at gap 0, started at x = 0 with v = 1 (so
// the contact is closed at t0). Event k: open at n T + pi/w2, close at (n+1) T,
// with T = pi/w1 + pi/w2, over 1000 periods.

class StiffnessRatio : public ::testing::TestWithParam<double> {};

TEST_P(StiffnessRatio, BilinearPeriodOver1000Periods) {
    const double r = GetParam();
    const Model m = model_from(R"(
name = "bilinear"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["m1", "ground"]
k = 1
[[contact]]
between = ["m1", "ground"]
gap = 0
k = )" + num(r) + R"(
[initial]
v = { m1 = 1.0 }
)");
    const LD w1 = 1, w2 = std::sqrt(1.0L + static_cast<LD>(r)), T = kPiL / w1 + kPiL / w2;
    const int periods = 1000;
    const Outcome o = simulate(m, static_cast<double>(periods * T + 0.5L * kPiL / w2));
    ASSERT_EQ(o.summary.status, RunStatus::ok) << o.summary.message;
    ASSERT_EQ(o.events.size(), 2u * periods);
    double worst = 0;
    for (std::size_t k = 0; k < o.events.size(); ++k) {
        const LD n = static_cast<LD>(k / 2);
        const LD expected = k % 2 == 0 ? n * T + kPiL / w2 : (n + 1) * T;
        ASSERT_EQ(o.events[k].kind, k % 2 == 0 ? EventKind::contact_open : EventKind::contact_close) << k;
        worst = std::max(worst, static_cast<double>(std::fabs(o.events[k].t - expected) / expected));
    }
    // Measured: 1.3e-16 (r = 1e2), 3.5e-15 (1e4, 1e6), 6.0e-16 (1e9); beyond
    // the issue's range, 1.5e-16 (1e12) and 3.5e-15 (1e15).
    measured("stiffness ratio " + fmt(r), "max rel. error of 2000 event times", worst, 1e-13);
}

INSTANTIATE_TEST_SUITE_P(Extremes, StiffnessRatio, ::testing::Values(1e2, 1e4, 1e6, 1e9, 1e12, 1e15));

// ---------------------------------------------------------------------------
// 2. Gap from 1e-9 to 1e3 of the response amplitude: x'' + w^2 x = 0 (w = 2,
// amplitude A = 1) against a stop of stiffness kc = 5 at gap d = eps A. Open,
// the motion is an arc of the free sinusoid, (pi + 2 asin eps)/w long; closed,
// it oscillates about xc = kc d / (k + kc) at wc and is closed for
// 2 atan2(v_in / wc, d - xc) / wc with v_in = A w sqrt(1 - eps^2). For eps > 1
// the stop is never reached.

std::string gname(double eps) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.7g", eps);
    return buf;
}

class GapRatio : public ::testing::TestWithParam<double> {};

TEST_P(GapRatio, PeriodOver200Periods) {
    const double eps = GetParam();
    const LD A = 1, w = 2, k = 4, kc = 5, d = static_cast<LD>(eps) * A;
    const Model m = model_from(R"(
name = "gap"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["m1", "ground"]
k = 4
[[contact]]
between = ["m1", "ground"]
gap = )" + num(d) + R"(
k = 5
[initial]
v = { m1 = 2.0 }
)");
    if (eps >= 1) {
        const Outcome o = simulate(m, 100.0);
        ASSERT_EQ(o.summary.status, RunStatus::ok) << o.summary.message;
        EXPECT_EQ(o.events.size(), 0u);
        const double err = std::fabs(o.summary.x[0] - static_cast<double>(A * std::sin(w * 100.0L)));
        // Measured: 0 (eps = 1 + 1e-6 and 1e3).
        measured("gap " + gname(eps) + " x amplitude", "no events; |x(100) - sin(200)|", err, 1e-13);
        return;
    }
    const LD a = std::asin(static_cast<LD>(eps));
    const LD v_in = A * w * std::sqrt((1 - static_cast<LD>(eps)) * (1 + static_cast<LD>(eps)));
    const LD wc = std::sqrt(k + kc), xc = kc * d / (k + kc);
    const LD closed = 2 * std::atan2(v_in / wc, d - xc) / wc, open = (kPiL + 2 * a) / w;
    const LD t_first = a / w, T = open + closed;
    const int periods = 200;
    const Outcome o = simulate(m, static_cast<double>(t_first + periods * T - 0.1L * open));
    ASSERT_EQ(o.summary.status, RunStatus::ok) << o.summary.message;
    ASSERT_EQ(o.events.size(), 2u * periods) << "eps = " << eps;
    double worst = 0;
    for (std::size_t j = 0; j < o.events.size(); ++j) {
        const LD n = static_cast<LD>(j / 2);
        const LD expected = t_first + n * T + (j % 2 ? closed : 0.0L);
        ASSERT_EQ(o.events[j].kind, j % 2 == 0 ? EventKind::contact_close : EventKind::contact_open) << j;
        worst = std::max(worst, static_cast<double>(std::fabs(o.events[j].t - expected) / expected));
    }
    // Measured: 6.7e-15 (eps = 1e-15), 1.2e-16 (1e-12), 1.0e-16 (eps = 1e-9)
    // .. 4.3e-16 (eps = 0.5); 3.9e-14 at
    // eps = 1 - 1e-6, where the entry slope v_in = 2.8e-3 makes the entry time
    // ill-conditioned (~1e-16 / v_in).
    measured("gap " + gname(eps) + " x amplitude", "max rel. error of 400 event times", worst, 1e-13);
}

INSTANTIATE_TEST_SUITE_P(Extremes, GapRatio, ::testing::Values(1e-15, 1e-12, 1e-9, 1e-6, 1e-3, 0.5, 0.999999, 1.000001, 1e3));

// ---------------------------------------------------------------------------
// 3. Mass ratio up to 1e6: ground -k1- m1 -k2- m2, m1 = 1, m2 = R, no
// contacts. Modal closed form (2x2 generalized eigenproblem solved here in long
// double), free vibration from x = (1, -1), compared on samples over 3 periods
// of the slow mode.

class MassRatio : public ::testing::TestWithParam<double> {};

TEST_P(MassRatio, ModalClosedForm) {
    const LD R = GetParam(), m1 = 1, m2 = R, k1 = 1, k2 = 1;
    const Model m = model_from(R"(
name = "massratio"
[[mass]]
name = "m1"
m = 1
[[mass]]
name = "m2"
m = )" + num(R) + R"(
[[spring]]
between = ["ground", "m1"]
k = 1
[[spring]]
between = ["m1", "m2"]
k = 1
[initial]
x = { m1 = 1.0, m2 = -1.0 }
)");
    // det(K - lambda M) = m1 m2 l^2 - ((k1+k2) m2 + k2 m1) l + k1 k2 = 0.
    const LD a = m1 * m2, b = (k1 + k2) * m2 + k2 * m1, c = k1 * k2;
    const LD disc = std::sqrt(b * b - 4 * a * c);
    const LD l_hi = (b + disc) / (2 * a), l_lo = c / (a * l_hi);  // no cancellation
    LD lam[2] = {l_lo, l_hi}, phi[2][2], q0[2];
    for (int j = 0; j < 2; ++j) {
        // (k1 + k2 - l m1) p1 - k2 p2 = 0  ->  p = (k2, k1 + k2 - l m1)
        phi[j][0] = k2;
        phi[j][1] = k1 + k2 - lam[j] * m1;
        const LD mm = m1 * phi[j][0] * phi[j][0] + m2 * phi[j][1] * phi[j][1];
        q0[j] = (m1 * phi[j][0] * 1 + m2 * phi[j][1] * -1) / mm;
    }
    const LD t_end = 3 * 2 * kPiL / std::sqrt(l_lo);
    const double dt = static_cast<double>(t_end / 3000);
    const Outcome o = simulate(m, static_cast<double>(t_end), dt);
    ASSERT_EQ(o.summary.status, RunStatus::ok) << o.summary.message;
    ASSERT_GT(o.samples.size(), 2000u);
    double worst = 0;
    for (const Recorded& s : o.samples) {
        for (int i = 0; i < 2; ++i) {
            LD x = 0;
            for (int j = 0; j < 2; ++j) x += phi[j][i] * q0[j] * std::cos(std::sqrt(lam[j]) * s.t);
            worst = std::max(worst, static_cast<double>(std::fabs(s.x[i] - x)));
        }
    }
    // Amplitudes are O(1). The fast mode's phase w_hi t is only known to
    // ~eps w_hi t (its eigenvalue is a double), so the bound is
    // 2e-15 (1 + w_hi t_end): 9x that. Measured: 9.6e-15 (R = 1), 5.8e-14
    // (1e2), 1.2e-12 (1e4), 1.8e-13 (1e6), 1.8e-10 (1e9, t_end 8.4e5 s),
    // 1.3e-13 (1e-6), 2.0e-10 (1e-9: w_hi = 4.5e4 rad/s, w_hi t_end = 8.4e5).
    const double phase = static_cast<double>(std::sqrt(l_hi) * t_end);
    measured("mass ratio " + fmt(static_cast<double>(R)), "max abs. error of x on samples over 3 slow periods",
             worst, 2e-15 * (1 + phase));
}

INSTANTIATE_TEST_SUITE_P(Extremes, MassRatio, ::testing::Values(1.0, 1e2, 1e4, 1e6, 1e-6, 1e9, 1e-9));

// ---------------------------------------------------------------------------
// 4. Damping ratio xi in {0, 1e-12, 1-1e-9, 1, 1+1e-9, 1e3}: m = 1, k = 1,
// C = alpha M with alpha = 2 xi. Free response from x0 = 1 and forced response
// (F = 1 sin(0.7 t)) from rest, closed form in long double written for every
// regime without cancellation: e^{-s t}(u0 C(t) + (v0 + s u0) S(t)), with
// C, S = cos, sin(wd t)/wd; 1, t; cosh, sinh(kt)/k.

LD damped_free(LD sigma, LD xi, LD x0, LD v0, LD t) {
    // wd^2 = 1 - xi^2 = (1 - xi)(1 + xi), exact enough near xi = 1.
    const LD d2 = (1 - xi) * (1 + xi);
    LD C, S;
    if (d2 > 0) {
        const LD wd = std::sqrt(d2);
        C = std::cos(wd * t);
        S = std::sin(wd * t) / wd;
    } else if (d2 < 0) {
        // e^{-s t} cosh(k t) and e^{-s t} sinh(k t) / k from the two decaying
        // exponentials r1 = -1/(s + k) (slow; w = 1) and r2 = -(s + k), so that
        // nothing overflows for s t >> 1.
        const LD kd = std::sqrt(-d2);
        const LD e1 = std::exp(-t / (sigma + kd)), e2 = std::exp(-(sigma + kd) * t);
        const LD Ce = (e1 + e2) / 2;
        const LD Se = kd * t < 1e-4L ? std::exp(-sigma * t) * t * (1 + (kd * t) * (kd * t) / 6) : (e1 - e2) / (2 * kd);
        return x0 * Ce + (v0 + sigma * x0) * Se;
    } else {
        C = 1;
        S = t;
    }
    return std::exp(-sigma * t) * (x0 * C + (v0 + sigma * x0) * S);
}

std::string xi_name(double xi) {
    if (xi == 1 || std::fabs(xi - 1) > 1e-6) return fmt(xi);
    char buf[64];
    std::snprintf(buf, sizeof buf, "1 %c %.3g", xi < 1 ? '-' : '+', std::fabs(xi - 1));
    return buf;
}

struct DampingCase {
    double xi;
    bool forced;
};

class DampingRatio : public ::testing::TestWithParam<DampingCase> {};

TEST_P(DampingRatio, FreeAndForcedClosedForm) {
    const auto [xi_d, forced] = GetParam();
    const LD xi = xi_d, alpha = 2 * static_cast<LD>(xi_d), sigma = alpha / 2, F = forced ? 1 : 0, W = 0.7L;
    std::string toml = R"(
name = "damped"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["m1", "ground"]
k = 1
[damping]
alpha = )" + num(alpha) + "\n";
    if (forced) toml += "[[forcing]]\nomega = 0.7\namplitude = { m1 = 1.0 }\n";
    else toml += "[initial]\nx = { m1 = 1.0 }\n";
    const Model m = model_from(toml);
    const LD Wd = 0.7;  // the double 0.7, as the model has it
    (void)W;
    // Particular a cos(W t) + b sin(W t): D = (1 - W^2)^2 + (alpha W)^2.
    const LD D = (1 - Wd * Wd) * (1 - Wd * Wd) + alpha * alpha * Wd * Wd;
    const LD pb = F * (1 - Wd * Wd) / D, pa = -F * alpha * Wd / D;
    const LD x0 = forced ? 0 : 1;
    const double t_end = 20.0;
    const Outcome o = simulate(m, t_end, 0.01);
    ASSERT_EQ(o.summary.status, RunStatus::ok) << o.summary.message;
    double worst = 0, size = 0;
    for (const Recorded& s : o.samples) {
        const LD t = s.t;
        const LD x = pa * std::cos(Wd * t) + pb * std::sin(Wd * t) + damped_free(sigma, xi, x0 - pa, -pb * Wd, t);
        worst = std::max(worst, static_cast<double>(std::fabs(s.x[0] - x)));
        size = std::max(size, static_cast<double>(std::fabs(x)));
    }
    // Relative to max |x| over [0, 20]. Measured: <= 5.5e-16 (free) and
    // <= 8.4e-16 (forced) for every xi, 1 -+ 1.1e-15 and 1e6 included.
    measured(std::string(forced ? "forced" : "free") + " response, xi = " + xi_name(xi_d),
             "max error of x / max |x| over t in [0, 20]", worst / size, 1e-13);
}

INSTANTIATE_TEST_SUITE_P(Extremes, DampingRatio,
                         ::testing::Values(DampingCase{0, false}, DampingCase{1e-12, false},
                                           DampingCase{1 - 1e-9, false}, DampingCase{1, false},
                                           DampingCase{1 + 1e-9, false}, DampingCase{1e3, false},
                                           DampingCase{0, true}, DampingCase{1e-12, true},
                                           DampingCase{1 - 1e-9, true}, DampingCase{1, true},
                                           DampingCase{1 + 1e-9, true}, DampingCase{1e3, true}, DampingCase{1e6, false}, DampingCase{1e6, true}, DampingCase{1 - 1e-15, false}, DampingCase{1 + 1e-15, false}));

// ---------------------------------------------------------------------------
// 5. Undamped forcing at and next to resonance: x'' + w^2 x = P sin(W t),
// w = 2, P = 3, from rest. At W = w: x = P/(2 w^2) sin(w t) - P t/(2 w) cos(w t)
// (secular growth P t / (2 w)). At W = w + D:
//   x = -P/(W + w) [2 cos((W + w) t / 2) sin(D t / 2) / D - sin(w t) / w],
// the cancellation in 1/(w^2 - W^2) removed by hand.

class Resonance : public ::testing::TestWithParam<double> {};

TEST_P(Resonance, SecularGrowth) {
    const double delta = GetParam();
    const double W = 2.0 * (1 + delta);
    const Model m = model_from(R"(
name = "resonance"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["m1", "ground"]
k = 4
[[forcing]]
omega = )" + num(W) + R"(
amplitude = { m1 = 3.0 }
)");
    const LD w = 2, P = 3, Dl = static_cast<LD>(W) - w;
    const double t_end = 100 * 2 * 3.141592653589793 / 2;  // 100 periods
    const Outcome o = simulate(m, t_end, 0.05);
    ASSERT_EQ(o.summary.status, RunStatus::ok) << o.summary.message;
    double worst = 0;
    for (const Recorded& s : o.samples) {
        const LD t = s.t;
        LD x;
        if (Dl == 0) x = P / (2 * w * w) * std::sin(w * t) - P * t / (2 * w) * std::cos(w * t);
        else
            x = -P / (static_cast<LD>(W) + w) *
                (2 * std::cos((static_cast<LD>(W) + w) * t / 2) * std::sin(Dl * t / 2) / Dl - std::sin(w * t) / w);
        worst = std::max(worst, static_cast<double>(std::fabs(s.x[0] - x)));
    }
    const double envelope = 3.0 * t_end / 4;  // P t / (2 w) at t_end
    // Relative to the envelope P t_end / (2 w) = 236. Measured: 2.2e-16 ..
    // 4.3e-16, also at w(1 + 1e-14) and w(1 - 1e-15).
    measured("undamped forcing at w(1 " + std::string(delta < 0 ? "- " : "+ ") + fmt(std::fabs(delta)) + ")",
             "max error of x / envelope P t/(2w), 100 periods", worst / envelope, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Extremes, Resonance, ::testing::Values(0.0, 1e-10, -1e-10, 1e-6, 1e-14, -1e-15));

// ---------------------------------------------------------------------------
// 6. Coulomb friction from mu = 1e-9 to a mass that sticks at once.
// x'' + w^2 x = -mu g sign(x'), w = 10, x0 = 1: reversals at k pi / w, the
// extreme drops by 2 mu g / w^2 per half cycle.

class CoulombDecay : public ::testing::TestWithParam<double> {};

TEST_P(CoulombDecay, ExtremesDropByTwoMuGOverW2) {
    const double mu = GetParam();
    const Model m = model_from(R"(
name = "coulomb"
[[mass]]
name = "m1"
m = 1
mu_k = )" + num(mu) + R"(
[[spring]]
between = ["ground", "m1"]
k = 100
[initial]
x = { m1 = 1.0 }
)");
    const LD w = 10, xe = static_cast<LD>(mu) * 9.81L / (w * w);
    // Half cycles before the stick: extremes 1 - 2 k xe > xe(mu_s = mu_k).
    const int half = static_cast<int>(std::min(2000.0L, (1 - xe) / (2 * xe)));
    const Outcome o = simulate(m, static_cast<double>((half + 0.5L) * kPiL / w));
    ASSERT_EQ(o.summary.status, RunStatus::ok) << o.summary.message;
    ASSERT_GE(o.events.size(), static_cast<std::size_t>(half));
    double t_err = 0, x_err = 0;
    for (int k = 1; k <= half; ++k) {
        const Recorded& e = o.events[static_cast<std::size_t>(k - 1)];
        ASSERT_TRUE(e.kind == EventKind::reversal || (k == half && e.kind == EventKind::stick)) << k;
        t_err = std::max(t_err, static_cast<double>(std::fabs(e.t - k * kPiL / w) / (k * kPiL / w)));
        const LD extreme = (k % 2 ? -1 : 1) * (1 - 2 * k * xe);
        x_err = std::max(x_err, static_cast<double>(std::fabs(e.x[0] - extreme)));
    }
    // Measured: times 1.5e-16 relative for every mu (2000 half cycles, t up
    // to 628 s); extremes 1.1e-13 (mu = 1e-9) .. 8.6e-15 (mu = 0.01). Before
    // the engine kept the rounding of event instants (t_lo in engine.cpp) the
    // times drifted linearly to 3.1e-14 (170 ulp of t): every reversal reset
    // v to 0 at the rounded time, and the rounding of t + pi/w repeats.
    // The extremes' error is linear too, +5.48e-17 per half cycle at mu = 1e-9
    // (1.37e-14 at k = 250 ... 1.10e-13 at k = 2000, amplitude too large):
    // x_{k+1} = -(x_k - 2 x_e) rounds the same way every time, since x_k stays
    // in one binade and x_e's bits below ulp(x_k) do not change. Inherent to
    // a double state (about ulp/4 per half cycle); not changed.
    measured("Coulomb decay mu = " + fmt(mu), "max rel. error of " + std::to_string(half) + " reversal times",
             t_err, 1e-14);
    measured("Coulomb decay mu = " + fmt(mu), "max abs. error of the extremes 1 - 2k mu g/w^2", x_err, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Extremes, CoulombDecay, ::testing::Values(1e-15, 1e-9, 1e-6, 1e-3, 1e-2));

// mu so large the mass is held at once: at rest it never moves (no event), and
// launched with v0 = 1 it stops after t = atan2(v0, w (x0 + xe)) / w ~ v0/(mu g).
TEST(CoulombExtreme, HugeMuSticksAtOnce) {
    const Model held = model_from(R"(
name = "held"
[[mass]]
name = "m1"
m = 1
mu_k = 1e6
[[spring]]
between = ["ground", "m1"]
k = 100
[initial]
x = { m1 = 1.0 }
)");
    const Outcome h = simulate(held, 10.0);
    ASSERT_EQ(h.summary.status, RunStatus::ok) << h.summary.message;
    EXPECT_EQ(h.events.size(), 0u);
    EXPECT_EQ(h.summary.x[0], 1.0);
    EXPECT_EQ(h.summary.v[0], 0.0);

    const Model launched = model_from(R"(
name = "launched"
[[mass]]
name = "m1"
m = 1
mu_k = 1e6
[[spring]]
between = ["ground", "m1"]
k = 100
[initial]
v = { m1 = 1.0 }
)");
    const Outcome o = simulate(launched, 10.0);
    ASSERT_EQ(o.summary.status, RunStatus::ok) << o.summary.message;
    ASSERT_EQ(o.events.size(), 1u);
    EXPECT_EQ(o.events[0].kind, EventKind::stick);
    const LD w = 10, xe = 1e6L * 9.81L / (w * w);
    const LD ts = std::atan2(1.0L, w * xe) / w;
    const LD s2 = std::sin(w * ts / 2), xs = -xe * 2 * s2 * s2 + std::sin(w * ts) / w;
    // The stop comes after 1.02e-7 s at x = 5.1e-8 m. Measured: stick time
    // exact to 2e-17 (relative). The stop position is the difference of the
    // static offset -xe = -98100 m and a cosine term of that size, so double
    // rounding leaves ~1e-16 * xe = 1e-11 m: measured 7.6e-12 m absolute,
    // 1.5e-4 relative to the 5.1e-8 m travelled (a limitation of the
    // static-offset form, not a bug; bound: 1e-15 of xe).
    measured("Coulomb mu = 1e6, v0 = 1", "rel. error of stick time", std::fabs(o.events[0].t - ts) / ts, 1e-12);
    measured("Coulomb mu = 1e6, v0 = 1", "|x_stop error| / (mu g / w^2)",
             static_cast<double>(std::fabs(o.summary.x[0] - xs) / xe), 1e-15);
    measured("Coulomb mu = 1e6, v0 = 1", "|x_stop error| / x_stop (informative)",
             static_cast<double>(std::fabs(o.summary.x[0] - xs) / xs), 1e-3);
}

// ---------------------------------------------------------------------------
// 7. Grazing: x = A sin(w t) against a stop at exactly d = A (a tangent touch:
// either nothing happens, or a close/open pair so short it changes nothing),
// and at d = A (1 - 1e-14), where a pair must appear and the motion after it
// must still be the free sinusoid.

TEST(Grazing, ExactTouchAndOvershootOf1e14) {
    for (const double eps : {0.0, 1e-14}) {
        const Model m = model_from(R"(
name = "graze"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["m1", "ground"]
k = 4
[[contact]]
between = ["m1", "ground"]
gap = )" + num(1 - eps) + R"(
k = 5
[initial]
v = { m1 = 2.0 }
)");
        const Outcome o = simulate(m, 10.0);
        ASSERT_EQ(o.summary.status, RunStatus::ok) << o.summary.message;
        ASSERT_EQ(o.events.size() % 2, 0u) << "touches come as close/open pairs";
        if (eps > 0) EXPECT_GE(o.events.size(), 2u) << "an overshoot of 1e-14 A is a real contact";
        double closed = 0;
        for (std::size_t j = 0; j + 1 < o.events.size(); j += 2) closed += o.events[j + 1].t - o.events[j].t;
        const double err = std::fabs(o.summary.x[0] - static_cast<double>(std::sin(20.0L)));
        // Measured: eps = 0: 0 events, error 0; eps = 1e-14: 6 events (3
        // touches), x(10) error 1.1e-16.
        measured("grazing, overshoot " + fmt(eps) + " A", "|x(10) - sin(20)| after " +
                     std::to_string(o.events.size()) + " events", err, 1e-12);
        EXPECT_LT(closed, 1e-5);
    }
}

// ---------------------------------------------------------------------------
// 7b. Beyond double range: clear refusals, not wrong numbers.

Model bilinear_mk(const std::string& m, const std::string& k) {
    return model_from(R"(
name = "ovf"
[[mass]]
name = "m1"
m = )" + m + R"(
[[spring]]
between = ["m1", "ground"]
k = )" + k + R"(
[[contact]]
between = ["m1", "ground"]
gap = 0
k = 12
[initial]
v = { m1 = 1.0 }
)");
}

TEST(Refusal, OverflowingStiffnessOverMassIsRefusedWhenRead) {
    // k/m = 1e400 overflows: the reader refuses the model (model_reader.cpp,
    // check_finite_rates), naming the spring, before any run.
    try {
        bilinear_mk("1e-200", "1e200");
        ADD_FAILURE() << "read";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("key 'spring[1].k': the spring: stiffness 1e+200 over mass 'm1'"),
                  std::string::npos)
            << e.what();
    }
}

TEST(Refusal, TinyPeriodIsReportedAsZeno) {
    // w = 1e150 rad/s: the contact really switches every ~2e-150 s; 1000
    // switches within 1e-9 s is the Zeno guard's refusal, with where it was.
    for (const auto& [mass, k] : {std::pair<const char*, const char*>{"1e-300", "1"}, {"1", "1e300"}}) {
        const Outcome o = simulate(bilinear_mk(mass, k), 1.0);
        EXPECT_EQ(o.summary.status, RunStatus::zeno) << mass << " " << k;
        EXPECT_EQ(o.events.size(), 1000u);
        EXPECT_NE(o.summary.message.find("1000 switches between t = "), std::string::npos) << o.summary.message;
        // The times are right: 1000 switches = 500 periods pi/w_open + pi/w_closed.
        // Measured: 6.4e-17 (m = 1e-300) and 1.2e-16 (k = 1e300) relative.
        const LD mm = static_cast<LD>(std::stod(mass)), kk = static_cast<LD>(std::stod(k));
        const LD T = kPiL / std::sqrt(kk / mm) + kPiL / std::sqrt((kk + 12) / mm);
        const LD last = o.events.back().t;
        measured(std::string("w = 1e150 (m = ") + mass + ", k = " + k + "), Zeno refusal",
                 "rel. error of the 1000th switch time", static_cast<double>(std::fabs(last - 500 * T) / (500 * T)),
                 1e-13);
    }
}

// ---------------------------------------------------------------------------
// 8. Simultaneous switches: two equal masses, each with a spring to ground
// (k = 4) and a stop to ground (kc = 12, gap 0, on opposite sides), coupled by
// k12 = 1.5, launched antisymmetrically (v = +1, -1). In the antisymmetric mode
// both stops open and close together: w_open = sqrt(4 + 3), w_closed = sqrt(19).

TEST(Simultaneous, SymmetricPairSwitchesTogether) {
    const Model m = model_from(R"(
name = "pair"
[[mass]]
name = "m1"
m = 1
[[mass]]
name = "m2"
m = 1
[[spring]]
between = ["m1", "ground"]
k = 4
[[spring]]
between = ["m2", "ground"]
k = 4
[[spring]]
between = ["m1", "m2"]
k = 1.5
[[contact]]
name = "c1"
between = ["m1", "ground"]
gap = 0
k = 12
[[contact]]
name = "c2"
between = ["ground", "m2"]
gap = 0
k = 12
[initial]
v = { m1 = 1.0, m2 = -1.0 }
)");
    const LD wo = std::sqrt(7.0L), wc = std::sqrt(19.0L), T = kPiL / wo + kPiL / wc;
    const int periods = 100;
    const Outcome o = simulate(m, static_cast<double>(periods * T + 0.2L));
    ASSERT_EQ(o.summary.status, RunStatus::ok) << o.summary.message;
    ASSERT_EQ(o.events.size(), 4u * periods);
    double spread = 0, t_err = 0;
    for (std::size_t j = 0; j < o.events.size(); j += 2) {
        const Recorded &a = o.events[j], &b = o.events[j + 1];
        EXPECT_EQ(a.kind, b.kind) << j;
        EXPECT_NE(a.element, b.element) << j;
        const std::size_t k = j / 2;
        const LD n = static_cast<LD>(k / 2);
        const LD expected = k % 2 == 0 ? n * T + kPiL / wc : (n + 1) * T;
        spread = std::max(spread, std::fabs(a.t - b.t));
        t_err = std::max(t_err, static_cast<double>(std::max(std::fabs(a.t - expected), std::fabs(b.t - expected))));
    }
    // Measured: both rows of every pair at the same time (spread 0), 3.7e-14 s from the closed form.
    measured("symmetric pair, 2 stops", "max time between the two rows of a simultaneous switch (s)", spread, 1e-12);
    measured("symmetric pair, 2 stops", "max abs. error of 400 event times (s)", t_err, 1e-12);
}

// ---------------------------------------------------------------------------
// 9. A million periods of a bilinear oscillator (k1 = 4, contact 12, gap 0):
// event-time drift against t_k in long double, without storing the events.

class DriftObserver : public Observer {
public:
    DriftObserver(LD T, LD first) : T_(T), first_(first) {}
    void on_sample(double, const double*, const double*) override {}
    void on_event(double t, EventKind kind, int, const double*, const double*) override {
        const LD n = static_cast<LD>(count / 2);
        const LD expected = count % 2 == 0 ? n * T_ + first_ : (n + 1) * T_;
        if (kind != (count % 2 == 0 ? EventKind::contact_open : EventKind::contact_close)) ++wrong_kind;
        const double err = static_cast<double>(std::fabs(t - expected));
        worst = std::max(worst, err);
        last = err;
        ++count;
    }
    std::size_t count = 0, wrong_kind = 0;
    double worst = 0, last = 0;

private:
    LD T_, first_;
};

TEST(LongRun, MillionPeriodsBilinear) {
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
    const LD T = kPiL / 2 + kPiL / 4;
    const std::size_t periods = 1000000;
    GenericSolverProvider provider(m);
    Engine engine(m, provider);
    DriftObserver obs(T, kPiL / 4);
    EngineOptions opt;
    opt.t_end = static_cast<double>(periods * T + 0.1L);
    opt.samples = false;
    const RunSummary s = engine.run(opt, obs);
    ASSERT_EQ(s.status, RunStatus::ok) << s.message;
    ASSERT_EQ(obs.count, 2 * periods);
    EXPECT_EQ(obs.wrong_kind, 0u);
    // t_end = 2.4e6 s, where one ulp of t is 4.7e-10 s. Measured: worst
    // 3.3e-10 s (under one ulp of t; 1.4e-16 relative): no drift. Runs in
    // ~1.8 s (2e6 events), so the full 1e6 periods are kept.
    measured("bilinear, 1e6 periods", "max abs. drift of 2e6 event times (s)", obs.worst, 1e-8);
    measured("bilinear, 1e6 periods", "same, relative to t", obs.worst / static_cast<double>(periods * T), 1e-14);
}

// ---------------------------------------------------------------------------
// 10. Large t0 = 1e6 s: the same motion as from t0 = 0, shifted, for a bilinear
// oscillator (event times) and a harmonically forced damped oscillator whose
// forcing phase at t0 is W t0 (closed form in long double).

class LargeT0Bilinear : public ::testing::TestWithParam<double> {};

TEST_P(LargeT0Bilinear, Shifted) {
    const double t0 = GetParam();
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
t0 = )" + num(t0) + R"(
v = { m1 = 1.0 }
)");
    const LD T = kPiL / 2 + kPiL / 4;
    const Outcome o = simulate(m, t0 + 100);
    ASSERT_EQ(o.summary.status, RunStatus::ok) << o.summary.message;
    const std::size_t expect_n = 2 * static_cast<std::size_t>(100 / T) + (std::fmod(100.0L, T) > kPiL / 4 ? 1 : 0);
    ASSERT_EQ(o.events.size(), expect_n);
    double worst = 0;
    for (std::size_t k = 0; k < o.events.size(); ++k) {
        const LD n = static_cast<LD>(k / 2);
        const LD expected = static_cast<LD>(t0) + (k % 2 == 0 ? n * T + kPiL / 4 : (n + 1) * T);
        worst = std::max(worst, static_cast<double>(std::fabs(o.events[k].t - expected)));
    }
    // In ulp of t0 (1.2e-10 s at 1e6, 1.2e-7 s at 1e9): an event time cannot
    // be better than 0.5 ulp. Measured: 0.49 ulp (1e6), 0.50 ulp (1e9).
    // At t0 = 1e12 (ulp 1.2e-4 s) 21.8 ulp = 2.7e-3 s: the engine's noise
    // model counts |g'| * 16 eps * |t| as the rounding of every switch
    // function (engine.cpp, noise()), so a contact switches only once
    // G < -7e-3 m here and the Newton step back leaves an error of the order
    // of B (7e-3)^2 / |G'|. Exploratory (beyond the issue's t0 = 1e6); the
    // bound for 1e12 is 40 ulp.
    const double ulp = std::nextafter(t0, 2 * t0) - t0;
    measured("t0 = " + fmt(t0) + " s, bilinear", "max error of event times over 100 s, in ulp(t0)", worst / ulp,
             t0 < 1e11 ? 4.0 : 40.0);
}

INSTANTIATE_TEST_SUITE_P(Extremes, LargeT0Bilinear, ::testing::Values(1e6, 1e9, 1e12));

TEST(LargeT0, ForcedDampedShifted) {
    const Model m = model_from(R"(
name = "forced"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["m1", "ground"]
k = 1
[damping]
alpha = 0.1
[[forcing]]
omega = 0.7
amplitude = { m1 = 1.0 }
[initial]
t0 = 1e6
x = { m1 = 0.5 }
)");
    const LD W = 0.7, alpha = 0.1, t0 = 1e6L, sigma = alpha / 2, xi = alpha / 2;
    const LD D = (1 - W * W) * (1 - W * W) + alpha * alpha * W * W;
    const LD pb = (1 - W * W) / D, pa = -alpha * W / D;
    const LD th = W * t0;  // forcing sin(W t0 + W tau) = sin(th) cos + cos(th) sin
    const LD A = pb * std::cos(th) - pa * std::sin(th), B = pb * std::sin(th) + pa * std::cos(th);
    // particular = A sin(W tau) + B cos(W tau)
    const Outcome o = simulate(m, 1e6 + 20, 0.01);
    ASSERT_EQ(o.summary.status, RunStatus::ok) << o.summary.message;
    double worst = 0;
    for (const Recorded& s : o.samples) {
        const LD tau = static_cast<LD>(s.t) - t0;
        const LD x = A * std::sin(W * tau) + B * std::cos(W * tau) + damped_free(sigma, xi, 0.5L - B, -A * W, tau);
        worst = std::max(worst, static_cast<double>(std::fabs(s.x[0] - x)));
    }
    // The forcing phase W t0 = 7e5 rad is known to ~1e-10 rad in double (what
    // the model states, and both sides use that double); x is O(1).
    // Measured: 4.6e-14.
    measured("t0 = 1e6 s, forced damped", "max abs. error of x over 20 s", worst, 1e-8);
}

// ---------------------------------------------------------------------------
// 11. Paper scenario 1 (22500 N at 175.5 rad/s, stick-slip, a contact) against
// the rk45 baseline at rtol 1e-12 over 0.5 s.

TEST(LargeForcing, Scenario1AgainstRk45) {
    const Model m = read_model(std::string(HSNC_SOURCE_DIR) + "/models/seed-scenario-1.toml");
    const double t_end = 0.5;
    const Outcome e = simulate(m, t_end);
    const Outcome b = baseline(m, t_end, 1e-12, 1e-14);
    const Outcome b2 = baseline(m, t_end, 1e-13, 1e-15);
    ASSERT_EQ(e.summary.status, RunStatus::ok) << e.summary.message;
    ASSERT_EQ(b.summary.status, RunStatus::ok) << b.summary.message;
    ASSERT_EQ(b2.summary.status, RunStatus::ok) << b2.summary.message;
    ASSERT_EQ(e.events.size(), b.events.size());
    ASSERT_EQ(e.events.size(), b2.events.size());
    ASSERT_GT(e.events.size(), 10u);
    double dx2 = 0, dt2 = 0;
    for (std::size_t k = 0; k < e.events.size(); ++k) dt2 = std::max(dt2, std::fabs(e.events[k].t - b2.events[k].t));
    for (std::size_t i = 0; i < m.dof(); ++i) dx2 = std::max(dx2, std::fabs(e.summary.x[i] - b2.summary.x[i]));
    double dt = 0, dx = 0;
    for (std::size_t k = 0; k < e.events.size(); ++k) {
        ASSERT_EQ(e.events[k].kind, b.events[k].kind) << k;
        ASSERT_EQ(e.events[k].element, b.events[k].element) << k;
        dt = std::max(dt, std::fabs(e.events[k].t - b.events[k].t));
    }
    for (std::size_t i = 0; i < m.dof(); ++i) dx = std::max(dx, std::fabs(e.summary.x[i] - b.summary.x[i]));
    // Same 68 events, same kinds and elements. The difference is rk45's own
    // error: it shrinks when rk45 is tightened. Measured: rtol 1e-12: 2.4e-8 s,
    // 2.0e-6 m; rtol 1e-13: 5.5e-9 s, 6.8e-7 m.
    measured("scenario 1 (22500 N), " + std::to_string(e.events.size()) + " events in 0.5 s",
             "max |t_hsnc - t_rk45(rtol 1e-12)| of events (s)", dt, 1e-7);
    measured("scenario 1 (22500 N)", "max |x_hsnc - x_rk45(rtol 1e-12)| at 0.5 s (m)", dx, 1e-5);
    measured("scenario 1 (22500 N)", "max |t_hsnc - t_rk45(rtol 1e-13)| of events (s)", dt2, 2.5e-8);
    measured("scenario 1 (22500 N)", "max |x_hsnc - x_rk45(rtol 1e-13)| at 0.5 s (m)", dx2, 3e-6);
    EXPECT_LT(dx2, dx) << "a tighter rk45 should come closer to the closed form";
}

// ---------------------------------------------------------------------------
// 12. A 64-mass chain (fixed-fixed, friction on every mass, 8 contacts between
// neighbours, forced at m1) runs, and agrees with rk45 at tight tolerance.

std::string chain_toml(int n) {
    std::string s = "name = \"chain64\"\n[parameters]\nk = 100.0\n";
    for (int i = 1; i <= n; ++i)
        s += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = 1\nmu_k = 0.05\nmu_s = 0.08\n";
    s += "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = \"k\"\n";
    for (int i = 1; i < n; ++i)
        s += "[[spring]]\nbetween = [\"m" + std::to_string(i) + "\", \"m" + std::to_string(i + 1) + "\"]\nk = \"k\"\n";
    s += "[[spring]]\nbetween = [\"m" + std::to_string(n) + "\", \"ground\"]\nk = \"k\"\n";
    for (int i = 1; i < n; i += 8)
        s += "[[contact]]\nbetween = [\"m" + std::to_string(i) + "\", \"m" + std::to_string(i + 1) +
             "\"]\ngap = 0.01\nk = 1000\n";
    s += "[damping]\nalpha = 0.02\nbeta = 0.0005\n";
    s += "[[forcing]]\nomega = 6.8\namplitude = { m1 = 40.0 }\n";
    s += "[initial]\nv = { m1 = 1.0, m9 = -1.0, m33 = 0.5 }\n";
    return s;
}

TEST(LargeModel, Chain64AgainstRk45) {
    const Model m = model_from(chain_toml(64));
    const double t_end = 1.0;
    const Outcome e = simulate(m, t_end);
    const Outcome b = baseline(m, t_end, 1e-12, 1e-14);
    ASSERT_EQ(e.summary.status, RunStatus::ok) << e.summary.message;
    ASSERT_EQ(b.summary.status, RunStatus::ok) << b.summary.message;
    ASSERT_GT(e.events.size(), 10u);
    ASSERT_EQ(e.events.size(), b.events.size());
    double dt = 0, dx = 0;
    for (std::size_t k = 0; k < e.events.size(); ++k) {
        if (e.events[k].kind != b.events[k].kind || e.events[k].element != b.events[k].element) {
            for (std::size_t j = k > 3 ? k - 3 : 0; j < std::min(k + 4, e.events.size()); ++j)
                std::printf("%zu hsnc %.17g %s %d | rk45 %.17g %s %d\n", j, e.events[j].t,
                            event_kind_name(e.events[j].kind), e.events[j].element, b.events[j].t,
                            event_kind_name(b.events[j].kind), b.events[j].element);
            FAIL() << "event " << k << " differs";
        }
        dt = std::max(dt, std::fabs(e.events[k].t - b.events[k].t));
    }
    for (std::size_t i = 0; i < m.dof(); ++i) dx = std::max(dx, std::fabs(e.summary.x[i] - b.summary.x[i]));
    // Same 103 events (same-instant rows compared in a canonical order).
    // Measured: 7.8e-9 s, 5.0e-10 m; against rk45 at rtol 1e-13 the event
    // times come 4x closer, 1.9e-9 s (rk45's own error dominates).
    const Outcome b2 = baseline(m, t_end, 1e-13, 1e-15);
    ASSERT_EQ(b2.events.size(), e.events.size());
    double dt2 = 0;
    for (std::size_t k = 0; k < e.events.size(); ++k) dt2 = std::max(dt2, std::fabs(e.events[k].t - b2.events[k].t));
    measured("64-mass chain, " + std::to_string(e.events.size()) + " events in 1 s",
             "max |t_hsnc - t_rk45(rtol 1e-12)| of events (s)", dt, 4e-8);
    measured("64-mass chain", "max |x_hsnc - x_rk45(rtol 1e-12)| at 1 s (m)", dx, 4e-9);
    measured("64-mass chain", "max |t_hsnc - t_rk45(rtol 1e-13)| of events (s)", dt2, 4e-8);
}

// ---------------------------------------------------------------------------
// 13. Energy balance: undamped, friction-free, three masses, four contacts;
// E = v'Mv/2 + sum springs k (xa - xb)^2 / 2 + sum closed contacts k G^2 / 2
// is constant across every switch.

TEST(EnergyBalance, ConservedAcrossManySwitches) {
    const Model m = model_from(R"(
name = "energy"
[[mass]]
name = "m1"
m = 1
[[mass]]
name = "m2"
m = 2.5
[[mass]]
name = "m3"
m = 0.7
[[spring]]
between = ["ground", "m1"]
k = 10
[[spring]]
between = ["m1", "m2"]
k = 7
[[spring]]
between = ["m2", "m3"]
k = 3
[[spring]]
between = ["m3", "ground"]
k = 5
[[contact]]
between = ["m1", "m2"]
gap = 0.05
k = 200
[[contact]]
between = ["m3", "m2"]
gap = 0.02
k = 1000
[[contact]]
between = ["m3", "ground"]
gap = 0.1
k = 50
[[contact]]
between = ["ground", "m1"]
gap = 0.08
k = 5000
[initial]
x = { m1 = 0.3, m2 = -0.1 }
v = { m3 = 1.0 }
)");
    auto pos = [](const std::vector<double>& x, int b) { return b == kGround ? 0.0 : x[static_cast<std::size_t>(b)]; };
    auto energy = [&](const std::vector<double>& x, const std::vector<double>& v) {
        LD e = 0;
        for (std::size_t i = 0; i < m.dof(); ++i) e += 0.5L * m.masses[i].m * v[i] * v[i];
        for (const Spring& s : m.springs) {
            const LD d = pos(x, s.a) - pos(x, s.b);
            e += 0.5L * s.k * d * d;
        }
        for (const Contact& c : m.contacts) {
            const LD G = static_cast<LD>(pos(x, c.a)) - pos(x, c.b) - c.gap;
            if (G > 0) e += 0.5L * c.k * G * G;
        }
        return e;
    };
    const double t_end = 2000.0;
    const Outcome o = simulate(m, t_end, 1.0);
    ASSERT_EQ(o.summary.status, RunStatus::ok) << o.summary.message;
    ASSERT_GT(o.events.size(), 1000u);
    const LD e0 = energy(m.x0, m.v0);
    double worst = 0;
    for (const auto* list : {&o.events, &o.samples})
        for (const Recorded& r : *list) worst = std::max(worst, static_cast<double>(std::fabs(energy(r.x, r.v) - e0) / e0));
    const double final_drift = static_cast<double>(std::fabs(energy(o.summary.x, o.summary.v) - e0) / e0);
    // The slowest all-open period is ~2.9 s, so ~690 periods. Measured now:
    // max 1.6e-13, 2.2e-16 per period, 1.2e-17 per switch. Before the
    // generic solver refined its modal initial conditions (see EnergySmall)
    // the error grew linearly, always upwards (+1.4e-13 at t = 250, +7.5e-13
    // at 1000, +1.34e-12 at 2000): 1.9e-15 per period, 1.0e-16 per switch.
    // The switch count (~1.3e4) moves with ulp-level changes (13160, 12979,
    // 13203 across the engine changes of this branch): the motion is
    // sensitive to rounding, so only the energy is compared.
    measured("energy, 3 masses 4 contacts, " + std::to_string(o.events.size()) + " switches",
             "max |E - E0| / E0 at events and samples over 2000 s", worst, 1e-12);
    measured("energy, 3 masses 4 contacts", "|E(2000) - E0| / E0 per period (~690)", final_drift / 690, 2e-15);
    measured("energy, 3 masses 4 contacts", "|E(2000) - E0| / E0 per switch", final_drift / static_cast<double>(o.events.size()), 1e-16);
}

// Where the energy gain of EnergyBalance showed up: a 1-DOF oscillator against
// a stiff stop (kc = 5000) has none (random, ~5e-15 after 2203 switches); a
// 2-DOF pair with one contact between the masses gained linearly, always
// upwards, 1.0e-16 (kc = 200) and 1.5e-16 (kc = 5000) of E per switch, all of
// it in the open segments. Cause: the modal round trip x0 -> Phi^T M x0 ->
// Phi q0 is a fixed matrix I + E (E ~ eps) per configuration, applied at every
// segment start; generic_solver.cpp now refines q0 once against the residual.
// Now 1.9e-17 and 1.8e-17 per switch.
class EnergySmall : public ::testing::TestWithParam<int> {};

TEST_P(EnergySmall, DriftPerSwitch) {
    const int which = GetParam();
    std::string toml;
    if (which == 0)
        toml = R"(
name = "e1"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["m1", "ground"]
k = 4
[[contact]]
between = ["m1", "ground"]
gap = 0.1
k = 5000
[initial]
v = { m1 = 1.0 }
)";
    else
        toml = std::string(R"(
name = "e2"
[[mass]]
name = "m1"
m = 1
[[mass]]
name = "m2"
m = 2.5
[[spring]]
between = ["ground", "m1"]
k = 10
[[spring]]
between = ["m1", "m2"]
k = 7
[[spring]]
between = ["m2", "ground"]
k = 3
[[contact]]
between = ["m1", "m2"]
gap = 0.05
k = )") + (which == 1 ? "200" : "5000") + R"(
[initial]
x = { m1 = 0.3, m2 = -0.1 }
)";
    const Model m = model_from(toml);
    auto pos = [](const std::vector<double>& x, int b) { return b == kGround ? 0.0 : x[static_cast<std::size_t>(b)]; };
    auto energy = [&](const std::vector<double>& x, const std::vector<double>& v) {
        LD e = 0;
        for (std::size_t i = 0; i < m.dof(); ++i) e += 0.5L * m.masses[i].m * v[i] * v[i];
        for (const Spring& s : m.springs) {
            const LD d = pos(x, s.a) - pos(x, s.b);
            e += 0.5L * s.k * d * d;
        }
        for (const Contact& c : m.contacts) {
            const LD G = static_cast<LD>(pos(x, c.a)) - pos(x, c.b) - c.gap;
            if (G > 0) e += 0.5L * c.k * G * G;
        }
        return e;
    };
    const Outcome o = simulate(m, 2000.0, 1.0);
    ASSERT_EQ(o.summary.status, RunStatus::ok) << o.summary.message;
    const LD e0 = energy(m.x0, m.v0);
    double worst = 0;
    for (const Recorded& r : o.samples) worst = std::max(worst, static_cast<double>(std::fabs(energy(r.x, r.v) - e0) / e0));
    const double per_switch = static_cast<double>((energy(o.summary.x, o.summary.v) - e0) / e0) /
                              static_cast<double>(o.events.size());
    const char* names[] = {"energy, 1 DOF, stop kc = 5000", "energy, 2 DOF, contact kc = 200",
                           "energy, 2 DOF, contact kc = 5000"};
    // Measured: 1 DOF: max 5.1e-15, per switch 1.0e-18; 2 DOF: max 7.8e-14 /
    // 8.6e-14, per switch 1.9e-17 / 1.8e-17 (before the refinement: 4.1e-13 /
    // 7.1e-13 and 1.0e-16 / 1.5e-16).
    measured(std::string(names[which]) + ", " + std::to_string(o.events.size()) + " switches",
             "max |E - E0| / E0 on samples over 2000 s", worst, which == 0 ? 2e-14 : 4e-13);
    measured(names[which], "|E(2000) - E0| / E0 per switch", std::fabs(per_switch),
             which == 0 ? 1e-17 : 8e-17);
}

INSTANTIATE_TEST_SUITE_P(Extremes, EnergySmall, ::testing::Values(0, 1, 2));

}  // namespace
}  // namespace hsnc
