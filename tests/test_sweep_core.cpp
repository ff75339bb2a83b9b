// The core of the sweep kernels (generator/sweep_kernel_core.h), compiled here
// as ordinary C++ with the declarations a sweep kernel gives it, for two small
// models written by hand: decompose(), setup() and eval() against closed forms
// (a forced undamped oscillator off and inside the resonance band, a damped
// floating pair pushed by a constant force). The generator prints the same
// text into every sweep kernel (tests/test_sweep_kernels.cpp runs those).
#include <gtest/gtest.h>

#include <cmath>

#include "derivation.h"  // kResonanceBand
#include "kernel_abi.h"

namespace hsnc::sweep_core_test {

// ---- one mass: m x'' + k x = f + F sin(Omega t + phase), no contact, no friction ----
namespace oscillator {
constexpr int N = 1, NF = 1, NH = 1, NS = 0, NS_STUCK = 0, NR = 0, NC = 0;
constexpr int N1 = 1, NF1 = 1, NH1 = 1, NS1 = 1, NR1 = 1, NC1 = 1, NST1 = 1;
constexpr int free_dof[NF1] = {0};
constexpr int stuck_dof[NST1] = {0};
constexpr int free_of[N1] = {0};
constexpr int contact_a[NC1] = {0}, contact_b[NC1] = {0};
constexpr int contact_a_free[NC1] = {0}, contact_b_free[NC1] = {0};
constexpr int rigid_member[NR1][NF1] = {{0}};
const hsnc_switch switches[NS1] = {{0, -1}};
constexpr double resonance_band = kResonanceBand;
#include "sweep_kernel_core.h"
}  // namespace oscillator

// ---- two masses joined by a spring, nothing else: one floating component ----
namespace pair {
constexpr int N = 2, NF = 2, NH = 0, NS = 0, NS_STUCK = 0, NR = 1, NC = 0;
constexpr int N1 = 2, NF1 = 2, NH1 = 1, NS1 = 1, NR1 = 1, NC1 = 1, NST1 = 1;
constexpr int free_dof[NF1] = {0, 1};
constexpr int stuck_dof[NST1] = {0};
constexpr int free_of[N1] = {0, 1};
constexpr int contact_a[NC1] = {0}, contact_b[NC1] = {0};
constexpr int contact_a_free[NC1] = {0}, contact_b_free[NC1] = {0};
constexpr int rigid_member[NR1][NF1] = {{1, 1}};
const hsnc_switch switches[NS1] = {{0, -1}};
constexpr double resonance_band = kResonanceBand;
#include "sweep_kernel_core.h"
}  // namespace pair

namespace {

struct Oscillator {
    double m = 2.0, k = 8.0, f = 0.5, F = 1.0, Omega = 3.0, phase = 0.3;
    // x_p(t) = f/k + F/(k - m Omega^2) sin(Omega t + phase); x = x_p + a cos(w tau) + b sin(w tau)/w.
    double xp(double t) const { return f / k + F / (k - m * Omega * Omega) * std::sin(Omega * t + phase); }
    double vp(double t) const { return F * Omega / (k - m * Omega * Omega) * std::cos(Omega * t + phase); }
};

int configure(oscillator::Block& b, const Oscillator& o, double* max_step) {
    oscillator::State& st = b.st;
    st.M[0] = o.m;
    st.K[0][0] = o.k;
    st.C[0][0] = 0.0;
    st.f_const[0] = o.f;
    st.mu_k_n[0] = st.mu_s_n[0] = 0.0;
    st.gap[0] = 0.0;
    st.Omega[0] = o.Omega;
    st.phase[0] = o.phase;
    st.F[0][0] = o.F;
    return oscillator::decompose(st, 0.0, 0.0, max_step);
}

TEST(SweepCore, ForcedOscillatorAgainstItsClosedForm) {
    for (const double Omega : {3.0, 2.0 * (1.0 + 0.5 * kResonanceBand)}) {
        SCOPED_TRACE("Omega = " + std::to_string(Omega));
        Oscillator o;
        o.Omega = Omega;
        oscillator::Block b{};
        double max_step = 0.0;
        ASSERT_EQ(configure(b, o, &max_step), HSNC_CONFIGURE_OK);
        const double w = std::sqrt(o.k / o.m);
        EXPECT_EQ(b.st.regime[0], oscillator::R_UNDAMPED);
        EXPECT_NEAR(b.st.lambda[0], w * w, 1e-15 * w * w);
        EXPECT_NEAR(std::fabs(b.st.V[0][0]), 1.0 / std::sqrt(o.m), 1e-16);
        const bool inside = std::fabs(Omega - w) <= kResonanceBand * w;
        EXPECT_EQ(b.st.resonant[0][0], inside);
        EXPECT_EQ(max_step, inside ? 2.0 * 3.14159265358979323846 / Omega : HUGE_VAL);

        const double t0 = 0.7, x0 = 0.1, v0 = -0.2;
        const signed char sgn = 0;
        oscillator::setup(reinterpret_cast<double*>(&b), t0, 0.0, &x0, &v0, &sgn);
        const double a0 = x0 - o.xp(t0), b0 = v0 - o.vp(t0);
        for (const double tau : {0.0, 0.25, 0.9, 2.5}) {
            double x, v, a, g, dg, bound, scale;
            oscillator::eval(reinterpret_cast<const double*>(&b), tau, &x, &v, &a, &g, &dg, &bound, &scale);
            const double xe = o.xp(t0 + tau) + a0 * std::cos(w * tau) + b0 * std::sin(w * tau) / w;
            const double ve = o.vp(t0 + tau) - a0 * w * std::sin(w * tau) + b0 * std::cos(w * tau);
            const double ae = (o.f + o.F * std::sin(Omega * (t0 + tau) + o.phase) - o.k * xe) / o.m;
            // Near resonance the particular amplitude is 12 (F/(k - m Omega^2)): its rounding counts.
            const double level = 1e-13 * (1.0 + std::fabs(o.F / (o.k - o.m * Omega * Omega)));
            EXPECT_NEAR(x, xe, level) << "tau = " << tau;
            EXPECT_NEAR(v, ve, level * w) << "tau = " << tau;
            EXPECT_NEAR(a, ae, level * w * w) << "tau = " << tau;
        }
    }
}

TEST(SweepCore, DampedFloatingPairMovesAsItsCentreOfMass) {
    const double m1 = 1.0, m2 = 3.0, k = 5.0, alpha = 0.3, f = 0.8;
    pair::Block b{};
    pair::State& st = b.st;
    st.M[0] = m1;
    st.M[1] = m2;
    st.K[0][0] = st.K[1][1] = k;
    st.K[0][1] = st.K[1][0] = -k;
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) st.C[i][j] = i == j ? alpha * st.M[i] : 0.0;
    st.f_const[0] = f;
    st.f_const[1] = 0.0;
    double max_step = 0.0;
    ASSERT_EQ(pair::decompose(st, alpha, 0.0, &max_step), HSNC_CONFIGURE_OK);
    EXPECT_EQ(st.lambda[0], 0.0);  // the structural rigid-body mode
    EXPECT_EQ(st.regime[0], pair::R_RIGID_DAMPED);
    EXPECT_NEAR(st.lambda[1], k * (1.0 / m1 + 1.0 / m2), 1e-14 * k);
    EXPECT_EQ(st.regime[1], pair::R_UNDERDAMPED);

    // Centre of mass X = (m1 x1 + m2 x2)/M: M X'' + alpha M X' = f, so
    // X = X0 + V0 (1 - e^{-alpha t})/alpha + f/(M alpha) (t - (1 - e^{-alpha t})/alpha).
    const double x0[2] = {0.2, -0.1}, v0[2] = {0.5, 0.1};
    const signed char sgn[2] = {0, 0};
    pair::setup(reinterpret_cast<double*>(&b), 0.0, 0.0, x0, v0, sgn);
    const double M = m1 + m2, X0 = (m1 * x0[0] + m2 * x0[1]) / M, V0 = (m1 * v0[0] + m2 * v0[1]) / M;
    for (const double t : {0.0, 1e-3, 0.4, 3.0, 20.0}) {
        double x[2], v[2], a[2], g, dg, bound, scale;
        pair::eval(reinterpret_cast<const double*>(&b), t, x, v, a, &g, &dg, &bound, &scale);
        const double e = -std::expm1(-alpha * t) / alpha;  // (1 - e^{-alpha t})/alpha
        const double X = X0 + V0 * e + f / (M * alpha) * (t - e);
        const double V = V0 * std::exp(-alpha * t) + f / (M * alpha) * (1.0 - std::exp(-alpha * t));
        EXPECT_NEAR((m1 * x[0] + m2 * x[1]) / M, X, 1e-14 * (1.0 + std::fabs(X))) << "t = " << t;
        EXPECT_NEAR((m1 * v[0] + m2 * v[1]) / M, V, 1e-14 * (1.0 + std::fabs(V))) << "t = " << t;
        EXPECT_NEAR((m1 * a[0] + m2 * a[1]) / M, (f - alpha * M * V) / M, 1e-14) << "t = " << t;
    }
}

}  // namespace
}  // namespace hsnc::sweep_core_test
