// Several frictions on one body (issue 36, "any number of frictions per
// body"): a partner carrying two riders, the smallest under-platform damper,
// and a chain (a block on a block on the ground; below).
// A partner p (m_p = 2, a spring k = 100 to the ground, forced F sin(w t))
// carries two riders r1 (m 1) and r2 (m 0.5), each held by Coulomb friction
// against it (mu_s N = 0.3 and 0.5, mu_k N = 0.2 and 0.4). From rest all
// three move as one body of mass 3.5, so
//     x(t) = A (sin w t - (w / W) sin W t),   A = F / (k - 3.5 w^2),  W^2 = k / 3.5,
// and a rider holds D_i = -m_i x''(t): r1 releases first, at the first
// |x''| = 0.3. From there r1 slides (its friction -mu_k N s on it, the
// reaction +mu_k N s on p) while r2 rides p: p and r2 are one body of mass
// 2.5 under k, the forcing and that reaction, in closed form again, and r2
// releases at the first m_2 |x_b''| = 0.5. Both instants are computed here
// from these closed forms, apart from the engine; a held force that left out
// the other rider's mass (the pairwise rule, (m_p A_i - m_i A_p)/(m_i + m_p))
// or the sliding rider's reaction would move them by 1e-2 s and 1e-2 s.
// The tangent (periodic orbits, Lyapunov exponents, continuation, modes) is
// checked on both: Jacobians across every rider's switches against central
// differences, and a forced damper's periodic orbit against CVODE.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>

#include "engine_runner.h"
#include "error.h"
#include "fe_models.h"
#include "hsnc/periodic.h"
#include "jacobian_check.h"
#include "model_reader.h"

namespace hsnc {
namespace {

using Real = long double;

constexpr double kMp = 2.0, kK = 100.0, kM1 = 1.0, kM2 = 0.5, kF = 5.0, kW = 3.0;
constexpr double kMuS1N = 0.3, kMuK1N = 0.2, kMuS2N = 0.5, kMuK2N = 0.4;

/// The model; `swap` writes each friction as [partner, rider] (the reader
/// then makes the partner carry both: the same physics).
std::string damper_model(bool swap, double amplitude = kF) {
    auto friction = [&](const char* name, const char* rider, double mu_s, double mu_k) {
        const std::string between =
            swap ? std::string("[\"p\", \"") + rider + "\"]" : std::string("[\"") + rider + "\", \"p\"]";
        return std::string("[[friction]]\nname = \"") + name + "\"\nbetween = " + between +
               "\nmu_s = " + fe::num(mu_s) + "\nmu_k = " + fe::num(mu_k) + "\nnormal = 1.0\n";
    };
    return std::string("name = \"shared-partner\"\n") + "[[mass]]\nname = \"p\"\nm = " + fe::num(kMp) +
           "\n[[mass]]\nname = \"r1\"\nm = " + fe::num(kM1) + "\n[[mass]]\nname = \"r2\"\nm = " + fe::num(kM2) +
           "\n[[spring]]\nbetween = [\"p\", \"ground\"]\nk = " + fe::num(kK) + "\n" +
           friction("f1", "r1", kMuS1N, kMuK1N) + friction("f2", "r2", kMuS2N, kMuK2N) +
           "[[forcing]]\nomega = " + fe::num(kW) + "\namplitude = { p = " + fe::num(amplitude) + " }\n";
}

/// The first t in (a, b] where f changes sign, to the last bit of Real
/// (scanned at `step`, then bisected).
Real first_root(const std::function<Real(Real)>& f, Real a, Real b, Real step) {
    Real lo = a, flo = f(a);
    for (Real t = a + step; t <= b; t += step) {
        const Real ft = f(t);
        if ((flo < 0) != (ft < 0)) {
            Real hi = t;
            for (int k = 0; k < 200 && hi - lo > 0; ++k) {
                const Real mid = (lo + hi) / 2;
                if (mid == lo || mid == hi) break;
                ((f(mid) < 0) == (flo < 0) ? lo : hi) = mid;
            }
            return hi;
        }
        lo = t, flo = ft;
    }
    return NAN;
}

struct ClosedForm {
    Real t1, t2, stick1;  ///< r1's release, r2's release, and the instant r1 would stick again (after t2)
    Real t1_pairwise, t2_without_reaction;
};

ClosedForm closed_form() {
    ClosedForm c{};
    const Real mc = kMp + kM1 + kM2, W = std::sqrt(Real(kK) / mc), A = kF / (kK - mc * kW * kW);
    auto x = [&](Real t) { return A * (std::sin(kW * t) - kW / W * std::sin(W * t)); };
    auto v = [&](Real t) { return A * kW * (std::cos(kW * t) - std::cos(W * t)); };
    auto a = [&](Real t) { return A * (-kW * kW * std::sin(kW * t) + kW * W * std::sin(W * t)); };
    c.t1 = first_root([&](Real t) { return kM1 * std::fabs(a(t)) - kMuS1N; }, 1e-9L, 2, 1e-4L);
    // The pairwise rule: r1 against p alone, D = (m_p A_1 - m_1 A_p)/(m_1 + m_p), A_1 = 0.
    c.t1_pairwise =
        first_root([&](Real t) { return std::fabs(kM1 * (-kK * x(t) + kF * std::sin(kW * t)) / (kM1 + kMp)) - kMuS1N; },
                   1e-9L, 2, 1e-4L);
    // r1 slides along s = sgn D_1 = -sgn x''(t1); p and r2 one body under k, F sin and +mu_k N s.
    const Real s = a(c.t1) > 0 ? -1 : 1, mb = kMp + kM2, Wb = std::sqrt(Real(kK) / mb);
    auto phase2 = [&](bool reaction) {
        const Real r = reaction ? kMuK1N * s : 0, Ab = kF / (kK - mb * kW * kW);
        const Real C = x(c.t1) - (Ab * std::sin(kW * c.t1) + r / kK);
        const Real S = (v(c.t1) - Ab * kW * std::cos(kW * c.t1)) / Wb;
        struct Body {
            std::function<Real(Real)> x, v, a;
        } b;
        b.x = [=](Real t) {
            return Ab * std::sin(kW * t) + r / kK + C * std::cos(Wb * (t - c.t1)) + S * std::sin(Wb * (t - c.t1));
        };
        b.v = [=](Real t) {
            return Ab * kW * std::cos(kW * t) - C * Wb * std::sin(Wb * (t - c.t1)) + S * Wb * std::cos(Wb * (t - c.t1));
        };
        b.a = [=, xb = b.x](Real t) { return (-kK * xb(t) + kF * std::sin(kW * t) + r) / mb; };
        return b;
    };
    const auto body = phase2(true), plain = phase2(false);
    c.t2 = first_root([&](Real t) { return kM2 * std::fabs(body.a(t)) - kMuS2N; }, c.t1, 3, 1e-4L);
    c.t2_without_reaction = first_root([&](Real t) { return kM2 * std::fabs(plain.a(t)) - kMuS2N; }, c.t1, 3, 1e-4L);
    // r1's velocity v(t1) - mu_k N s (t - t1)/m_1 meets the body's only later.
    const Real v1 = v(c.t1);
    c.stick1 =
        first_root([&](Real t) { return v1 - kMuK1N * s * (t - c.t1) / kM1 - body.v(t); }, c.t1 + 1e-6L, 3, 1e-4L);
    return c;
}

TEST(SharedPartner, TheClosedFormDiscriminates) {
    const ClosedForm c = closed_form();
    std::printf(
        "r1 releases at %.17Lg (pairwise rule %.17Lg), r2 at %.17Lg (without the reaction %.17Lg); r1 would "
        "stick at %.17Lg\n",
        c.t1, c.t1_pairwise, c.t2, c.t2_without_reaction, c.stick1);
    ASSERT_TRUE(std::isfinite(static_cast<double>(c.t1)) && std::isfinite(static_cast<double>(c.t2)));
    EXPECT_GT(std::fabs(c.t1 - c.t1_pairwise), 1e-3L);
    EXPECT_GT(std::fabs(c.t2 - c.t2_without_reaction), 1e-3L);
    EXPECT_GT(c.stick1, c.t2);  // r2's release comes first
}

TEST(SharedPartner, TheReaderLetsAPartnerCarrySeveralFrictionsWrittenEitherWay) {
    for (bool swap : {false, true}) {
        const Model m = parse_model(damper_model(swap), "shared.toml");
        EXPECT_TRUE(m.shared_partner());
        EXPECT_TRUE(m.coupled_friction());
        EXPECT_FALSE(m.has_friction(0)) << "the partner p carries, it has no friction of its own";
        EXPECT_EQ(m.friction_slot(1).partner, 0);
        EXPECT_EQ(m.friction_slot(2).partner, 0);
        EXPECT_EQ(m.friction_name(1), "f1");
        EXPECT_EQ(m.friction_name(2), "f2");
    }
    // a - b - c: b is in both frictions, so both a and c ride b.
    auto masses = [](int n) {
        std::string t = "name = \"chain\"\n";
        for (int i = 0; i < n; ++i)
            t += "[[mass]]\nname = \"" + std::string(1, static_cast<char>('a' + i)) + "\"\nm = 1.0\n";
        return t;
    };
    auto friction = [](const char* a, const char* b) {
        return std::string("[[friction]]\nbetween = [\"") + a + "\", \"" + b + "\"]\nmu_k = 0.1\nnormal = 1.0\n";
    };
    const Model abc = parse_model(masses(3) + friction("a", "b") + friction("b", "c"), "abc.toml");
    EXPECT_EQ(abc.friction_slot(0).partner, 1);
    EXPECT_EQ(abc.friction_slot(2).partner, 1);
    // a - b - c - d: a tree rooted at b (the first of the two in two frictions): a and c ride b, d rides c.
    const Model abcd =
        parse_model(masses(4) + friction("a", "b") + friction("b", "c") + friction("c", "d"), "abcd.toml");
    EXPECT_EQ(abcd.friction_slot(0).partner, 1);
    EXPECT_EQ(abcd.friction_slot(2).partner, 1);
    EXPECT_EQ(abcd.friction_slot(3).partner, 2);
    EXPECT_FALSE(abcd.has_friction(1));
    // A loop: a - b, b - c and c - a, or two bodies with ground friction joined by one.
    for (const std::string& loop :
         {masses(3) + friction("a", "b") + friction("b", "c") + friction("c", "a"),
          masses(2) + friction("a", "ground") + friction("b", "ground") + friction("a", "b")}) {
        try {
            parse_model(loop, "loop.toml");
            ADD_FAILURE() << "a loop of frictions was accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("loop"), std::string::npos) << e.what();
        }
    }
}

TEST(SharedPartner, TwoRidersReleaseAtTheClosedFormsInstantsOnEveryBackEnd) {
    const ClosedForm c = closed_form();
    const double t_end = 3.0;
    testing::Outcome first;
    for (bool swap : {false, true}) {
        const Model m = parse_model(damper_model(swap), "shared.toml");
        const testing::Outcome programs = testing::simulate(m, t_end, 0.0, testing::Solvers::interp);
        ASSERT_GE(programs.events.size(), 4u);
        EXPECT_EQ(programs.events[0].kind, EventKind::release);
        EXPECT_EQ(programs.events[0].element, 1);  // r1
        EXPECT_NEAR(programs.events[0].t, static_cast<double>(c.t1), 1e-12);
        EXPECT_EQ(programs.events[1].kind, EventKind::release);
        EXPECT_EQ(programs.events[1].element, 2);  // r2
        EXPECT_NEAR(programs.events[1].t, static_cast<double>(c.t2), 1e-12);
        const fe::BackEndGaps gap = fe::back_end_gaps(m, programs, t_end);
        std::printf(
            "%s: %zu events; first two %.3g s and %.3g s from the closed form; the programs within %.3g s of "
            "the Eigen solver, %.3g s of the reference, 30 against 60 digits %.3g s, CVODE %.3g s\n",
            swap ? "written [p, rider]" : "written [rider, p]", programs.events.size(),
            std::fabs(programs.events[0].t - static_cast<double>(c.t1)),
            std::fabs(programs.events[1].t - static_cast<double>(c.t2)), gap.eigen, gap.reference, gap.digits,
            gap.cvode);
        EXPECT_LT(gap.eigen, 1e-12);
        EXPECT_LT(gap.reference, 1e-12);
        EXPECT_LT(gap.digits, 1e-20);
        EXPECT_LT(gap.cvode, 1e-8);
        if (first.events.empty()) {
            first = programs;
            continue;
        }
        EXPECT_LT(fe::event_gap(programs, first), 1e-13) << "the same events whichever way `between` is written";
    }
}

// A chain: a block b (1 kg) on a block a (2 kg) on the ground, a on a spring
// k = 100, forced F sin(w t) (F = 10, w = 3), a constant load L = 0.5 on b;
// mu_s N = 6 and mu_k N = 5 between a and the ground, 1 and 0.8 between b
// and a. From rest both hold: the ground friction holds the whole stack,
// D_a = F sin(w t) + L (b's load included: without it a would release
// 2e-2 s later), and a releases at the first |D_a| = 6. Then the stack
// slides as one body of 3 kg under k, the forcing, L and -mu_k N s, and b,
// riding a, holds D_b = L - m_b x''(t): it releases at the first |D_b| = 1,
// before the stack stops.
constexpr double kMa = 2.0, kMb = 1.0, kKa = 100.0, kFa = 10.0, kWa = 3.0, kL = 0.5;
constexpr double kMuSaN = 6.0, kMuKaN = 5.0, kMuSbN = 1.0, kMuKbN = 0.8;

std::string stack_model(bool upper_first) {
    const std::string top =
        "[[friction]]\nname = \"top\"\nbetween = " + std::string(upper_first ? "[\"b\", \"a\"]" : "[\"a\", \"b\"]") +
        "\nmu_s = " + fe::num(kMuSbN) + "\nmu_k = " + fe::num(kMuKbN) + "\nnormal = 1.0\n";
    const std::string bottom =
        "[[friction]]\nname = \"bottom\"\nbetween = [\"a\", \"ground\"]\nmu_s = " + fe::num(kMuSaN) +
        "\nmu_k = " + fe::num(kMuKaN) + "\nnormal = 1.0\n";
    return "name = \"stack\"\n[[mass]]\nname = \"a\"\nm = " + fe::num(kMa) +
           "\n[[mass]]\nname = \"b\"\nm = " + fe::num(kMb) +
           "\n[[spring]]\nbetween = [\"a\", \"ground\"]\nk = " + fe::num(kKa) + "\n" +
           (upper_first ? top + bottom : bottom + top) + "[[forcing]]\nomega = " + fe::num(kWa) +
           "\namplitude = { a = " + fe::num(kFa) + " }\n[load]\nb = " + fe::num(kL) + "\n";
}

TEST(FrictionChain, ABlockOnABlockOnTheGroundReleasesAtTheClosedFormsInstants) {
    const Real t1 =
        first_root([](Real t) { return std::fabs(kFa * std::sin(kWa * t) + kL) - kMuSaN; }, 1e-9L, 2, 1e-4L);
    const Real t1_alone =
        first_root([](Real t) { return std::fabs(kFa * std::sin(kWa * t)) - kMuSaN; }, 1e-9L, 2, 1e-4L);
    EXPECT_GT(t1_alone - t1, 1e-2L) << "b's load must count in the ground friction's held force";
    const Real s = kFa * std::sin(kWa * t1) + kL > 0 ? 1 : -1, m = kMa + kMb, W = std::sqrt(Real(kKa) / m);
    const Real c = kL - kMuKaN * s, Ap = kFa / (kKa - m * kWa * kWa);
    const Real C = -(Ap * std::sin(kWa * t1) + c / kKa), S = -Ap * kWa * std::cos(kWa * t1) / W;
    auto x = [&](Real t) {
        return Ap * std::sin(kWa * t) + c / kKa + C * std::cos(W * (t - t1)) + S * std::sin(W * (t - t1));
    };
    auto v = [&](Real t) {
        return Ap * kWa * std::cos(kWa * t) - C * W * std::sin(W * (t - t1)) + S * W * std::cos(W * (t - t1));
    };
    auto a = [&](Real t) { return (-kKa * x(t) + kFa * std::sin(kWa * t) + c) / m; };
    const Real t2 = first_root([&](Real t) { return std::fabs(kL - kMb * a(t)) - kMuSbN; }, t1, 3, 1e-4L);
    const Real stop = first_root(v, t1 + 1e-6L, 3, 1e-4L);
    std::printf("a releases at %.17Lg (without b's load %.17Lg), b at %.17Lg, the stack would stop at %.17Lg\n", t1,
                t1_alone, t2, stop);
    ASSERT_LT(t2, stop);
    const double t_end = 3.0;
    testing::Outcome first;
    for (bool upper_first : {true, false}) {
        const Model mdl = parse_model(stack_model(upper_first), "stack.toml");
        EXPECT_TRUE(mdl.friction_chain());
        EXPECT_EQ(mdl.friction_slot(1).partner, 0) << "b rides a, whichever way `between` is written";
        const testing::Outcome programs = testing::simulate(mdl, t_end, 0.0, testing::Solvers::interp);
        ASSERT_GE(programs.events.size(), 3u);
        EXPECT_EQ(programs.events[0].kind, EventKind::release);
        EXPECT_EQ(programs.events[0].element, 0);
        EXPECT_NEAR(programs.events[0].t, static_cast<double>(t1), 1e-12);
        EXPECT_EQ(programs.events[1].kind, EventKind::release);
        EXPECT_EQ(programs.events[1].element, 1);
        EXPECT_NEAR(programs.events[1].t, static_cast<double>(t2), 1e-12);
        const fe::BackEndGaps gap = fe::back_end_gaps(mdl, programs, t_end);
        std::printf(
            "%zu events; first two %.3g s and %.3g s from the closed form; the programs within %.3g s of the "
            "Eigen solver, %.3g s of the reference, 30 against 60 digits %.3g s, CVODE %.3g s\n",
            programs.events.size(), std::fabs(programs.events[0].t - static_cast<double>(t1)),
            std::fabs(programs.events[1].t - static_cast<double>(t2)), gap.eigen, gap.reference, gap.digits, gap.cvode);
        EXPECT_LT(gap.eigen, 1e-12);
        EXPECT_LT(gap.reference, 1e-12);
        EXPECT_LT(gap.digits, 1e-20);
        EXPECT_LT(gap.cvode, 1e-8);
        if (first.events.empty()) {
            first = programs;
            continue;
        }
        EXPECT_LT(fe::event_gap(programs, first), 1e-13);
    }
}

// A tower (examples/friction/friction_tower.toml: feet on the floor, a box on
// the table, a lid on the box, a cup on the table): every friction releases
// and sticks, each configuration on the programs (they write the held force
// of a chain, sum over S_i of A_k - (M_S / M_b) sum over its body of A_k),
// against the Eigen solver, the reference at 30 and 60 digits and CVODE.
TEST(FrictionChain, ATowerOfFrictionsRunsOnTheProgramsAgainstEveryBackEnd) {
    const Model m = read_model(std::string(HSNC_SOURCE_DIR) + "/examples/friction/friction_tower.toml");
    const double t_end = 10.0;
    const testing::Outcome programs = testing::simulate(m, t_end, 0.0, testing::Solvers::interp);
    std::vector<int> released(m.dof(), 0), stuck(m.dof(), 0);
    for (const auto& e : programs.events) {
        if (e.kind == EventKind::release) ++released[static_cast<std::size_t>(e.element)];
        if (e.kind == EventKind::stick) ++stuck[static_cast<std::size_t>(e.element)];
    }
    for (std::size_t i = 0; i < m.dof(); ++i) {
        EXPECT_GT(released[i], 0) << m.friction_name(i);
        EXPECT_GT(stuck[i], 0) << m.friction_name(i);
    }
    const fe::BackEndGaps gap = fe::back_end_gaps(m, programs, t_end);
    std::printf(
        "tower: %zu events; the programs within %.3g s of the Eigen solver, %.3g s of the reference, "
        "30 against 60 digits %.3g s, CVODE %.3g s\n",
        programs.events.size(), gap.eigen, gap.reference, gap.digits, gap.cvode);
    EXPECT_GE(programs.events.size(), 80u);
    EXPECT_LT(gap.eigen, 1e-12);
    EXPECT_LT(gap.reference, 1e-12);
    EXPECT_LT(gap.digits, 1e-20);
    EXPECT_LT(gap.cvode, 1e-8);
}

// The tangent where several frictions meet on a body (analysis/stick_tangent.h:
// a body's rows over everything riding it, the release gradients P_i . df):
// the Jacobian of runs across sticks and releases of every friction against
// central differences of the engine, the riders started sliding (a velocity
// perturbation of a stuck body at t0 is a slip of its own, not differentiable).
TEST(SharedPartner, TheJacobianAcrossBothRidersSwitchesMatchesCentralDifferences) {
    Model m = parse_model(damper_model(false), "shared.toml");
    m.v0[1] = 0.3, m.v0[2] = -0.2;
    EXPECT_EQ(testing::expect_jacobian_matches(m, 3.0, 1e-6, 2e-6, 6), 6);
    // r2 (on a spring of its own) stays stuck on p, so r1 releases (three times) from the body p + r2: its
    // release gradient takes r2's force too, not p's alone (the velocity columns of p and r2
    // slip at t0: not differentiable)
    m = parse_model(damper_model(false) + "[[spring]]\nbetween = [\"r2\", \"ground\"]\nk = 5.0\n", "shared.toml");
    m.v0[1] = 0.3;
    EXPECT_EQ(testing::expect_jacobian_matches(m, 2.2, 1e-6, 2e-6, 6), 4);
}

TEST(FrictionChain, TheJacobianAcrossBothBlocksSwitchesMatchesCentralDifferences) {
    Model m = parse_model(stack_model(false), "stack.toml");
    m.v0[0] = -0.1, m.v0[1] = 0.2;
    EXPECT_EQ(testing::expect_jacobian_matches(m, 3.0, 1e-6, 2e-6, 6), 4);
}

// The forced damper's periodic orbit: a fixed point of the period map that
// CVODE computes on its own, and the monodromy matrix (what its Floquet
// multipliers come from) against central differences of that map.
TEST(SharedPartner, ThePeriodicOrbitAndItsMonodromyHoldIndependently) {
    const Model m = parse_model(damper_model(false, 2 * kF), "shared.toml");
    PeriodicOptions opt;
    opt.kernels = KernelChoice::generic;
    opt.transient = 20.0;
    const PeriodicResult r = periodic(m, opt);
    ASSERT_EQ(r.status, PeriodicStatus::ok) << r.message;
    EXPECT_EQ(r.grazing, 0u);
    EXPECT_EQ(r.events, 6u) << "f1 reverses twice, f2 sticks and releases twice a period";
    Model at = m;
    at.t0 = r.t, at.x0 = r.x, at.v0 = r.v;
    const testing::Outcome cvode = testing::baseline(at, r.t + r.period, 1e-12, 1e-14, Method::cvode);
    double off = 0.0, scale = 0.0;
    for (std::size_t i = 0; i < m.dof(); ++i) {
        off = std::max({off, std::fabs(cvode.summary.x[i] - r.x[i]), std::fabs(cvode.summary.v[i] - r.v[i])});
        scale = std::max({scale, std::fabs(r.x[i]), std::fabs(r.v[i])});
    }
    analysis::FlowKernels kernels;
    kernels.kernels = KernelChoice::generic;
    analysis::Flow flow(at, kernels, "test");
    Eigen::VectorXd y(static_cast<Eigen::Index>(2 * m.dof()));
    for (std::size_t i = 0; i < m.dof(); ++i)
        y(static_cast<Eigen::Index>(i)) = r.x[i], y(static_cast<Eigen::Index>(m.dof() + i)) = r.v[i];
    std::size_t events = 0;
    const double jac = fe::off_central_differences(flow, r.period, y, events);
    std::printf(
        "orbit: %zu events a period, max |mu| %.6g, CVODE's period map returns it within %.3g (scale %.3g), "
        "|J - central differences| / |J| = %.3g\n",
        r.events, r.max_multiplier, off, scale, jac);
    EXPECT_LT(off, 1e-8 * scale);
    EXPECT_LT(jac, 1e-6);
    EXPECT_TRUE(r.stable);
}

}  // namespace
}  // namespace hsnc
