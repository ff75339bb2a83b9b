// Base (support) excitation (`[[base]]`, interface.md): the ground moves as
// x_g(t) along an influence vector r, the model is written relative to it
// (x = x_abs - r x_g) and the base acts as the effective force -M r x_g''.
//
// The truths are closed forms: the transmissibility of a damped oscillator
// on a shaker, the frequency response of a consistent-mass bar clamped to a
// shaker (its own M, K, C), and a stop on the moving frame against the same
// model with its effective force written by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "engine_runner.h"
#include "error.h"
#include "fe_models.h"
#include "hsnc/simulate.h"
#include "model.h"
#include "model_reader.h"
#include "temp_dir.h"

namespace hsnc {
namespace {

testing::Outcome run(const Model& model, double t_end, double dt, KernelChoice kernels = KernelChoice::generic) {
    testing::Recorder rec(model.dof(), model.state_size());
    SimulateOptions o;
    o.t_end = t_end;
    o.dt = dt;
    o.kernels = kernels;
    testing::Outcome out;
    out.summary = simulate(model, o, rec);
    out.events = rec.events;
    out.samples = rec.samples;
    return out;
}

// A 1-dof oscillator (m, k, c = beta k) on a base moving as x_g = Y sin(w t),
// given as displacement, velocity or acceleration.
std::string oscillator(const std::string& base) {
    return R"(name = "shaker"
[[mass]]
name = "m"
m = 2.0
[[spring]]
between = ["ground", "m"]
k = 200.0
[damping]
beta = 0.04
)" + base;
}

// Relative to the base, m x'' + c x' + k x = m w^2 Y sin(w t): in steady state
// x = X sin(w t - theta), X = m w^2 Y / |k - m w^2 + i c w|. The absolute motion
// x + Y sin(w t) has the amplitude T Y, T = |k + i c w| / |k - m w^2 + i c w|
// (the transmissibility). zeta = 0.2, omega_n = 10: after 25 s the start has
// decayed by exp(-50).
TEST(BaseMotion, AnOscillatorOnAShakerHasItsTransmissibility) {
    const double m = 2.0, k = 200.0, c = 0.04 * k, Y = 0.01, w = 7.0;
    const std::complex<double> dyn(k - m * w * w, c * w);
    const double X = m * w * w * Y / std::abs(dyn), theta = std::arg(dyn);
    const double T = std::abs(std::complex<double>(k, c * w)) / std::abs(dyn);
    char forms[3][256];
    std::snprintf(forms[0], sizeof forms[0], "[[base]]\nmotion = \"displacement\"\nomega = %.17g\namplitude = %.17g\n",
                  w, Y);
    std::snprintf(forms[1], sizeof forms[1],
                  "[[base]]\nmotion = \"velocity\"\nomega = %.17g\namplitude = %.17g\nphase = \"pi/2\"\n", w, Y * w);
    std::snprintf(forms[2], sizeof forms[2], "[[base]]\nmotion = \"acceleration\"\nomega = %.17g\namplitude = %.17g\n",
                  w, -Y * w * w);
    std::vector<double> ends;
    for (const char* form : forms) {
        const Model model = parse_model(oscillator(form), "shaker.toml");
        ASSERT_EQ(model.forcing.size(), 1u);
        const testing::Outcome r = run(model, 25.0, 0.01);
        ASSERT_EQ(r.summary.status, RunStatus::ok) << form;
        std::size_t checked = 0;
        for (const testing::Recorded& s : r.samples) {
            if (s.t < 24.0) continue;
            EXPECT_NEAR(s.x[0], X * std::sin(w * s.t - theta), 1e-14) << form << " t = " << s.t;
            EXPECT_NEAR(s.v[0], X * w * std::cos(w * s.t - theta), 1e-13) << form << " t = " << s.t;
            const double xa = s.x[0] + Y * std::sin(w * s.t), va = s.v[0] + Y * w * std::cos(w * s.t);
            EXPECT_NEAR(std::hypot(xa, va / w), T * Y, 1e-12 * T * Y) << form << " t = " << s.t;
            ++checked;
        }
        EXPECT_EQ(checked, 101u);
        ends.push_back(r.summary.x[0]);
    }
    EXPECT_NEAR(ends[1], ends[0], 1e-15);
    EXPECT_NEAR(ends[2], ends[0], 1e-15);
}

// A consistent-mass bar (4 elements) clamped to a shaker that accelerates it
// axially, x_g'' = A sin(w t): relative to the base, M x'' + C x' + K x =
// -M r A sin(w t), r = 1 on every node (all move with the base). In steady
// state x = Im(X e^{i w t}) with X = (K - w^2 M + i w C)^-1 (-M r A): the
// coupled M enters both sides.
TEST(BaseMotion, AConsistentMassBarOnAShakerFollowsItsOwnFrequencyResponse) {
    testing::TempDir dir;
    const fe::Beam bar = fe::clamped_bar(4);
    const double beta = 1e-3, A = 3.0, w = 90.0;
    std::string r_table = "{";
    for (std::size_t i = 0; i < bar.dofs.size(); ++i) r_table += (i ? ", " : " ") + bar.dofs[i] + " = 1.0";
    r_table += " }";
    char sections[512];
    std::snprintf(sections, sizeof sections,
                  "[damping]\nbeta = %.17g\n[[base]]\nmotion = \"acceleration\"\nomega = %.17g\namplitude = %.17g\n"
                  "direction = %s\n",
                  beta, w, A, r_table.c_str());
    const std::string path = fe::structure_model(dir, "bar.toml", "bar-on-shaker", bar.M, bar.K, bar.dofs, sections);
    const Model model = read_model(path);
    ASSERT_TRUE(model.coupled_mass());
    const Eigen::Index n = bar.M.rows();
    const Eigen::VectorXd f = -bar.M * Eigen::VectorXd::Ones(n) * A;
    ASSERT_EQ(model.forcing.size(), 1u);
    for (Eigen::Index i = 0; i < n; ++i)
        EXPECT_NEAR(model.forcing[0].amplitude[static_cast<std::size_t>(i)], f(i), 1e-15 * f.cwiseAbs().maxCoeff());
    const Eigen::MatrixXcd D = (bar.K - w * w * bar.M).cast<std::complex<double>>() +
                               std::complex<double>(0, w) * (beta * bar.K).cast<std::complex<double>>();
    const Eigen::VectorXcd X = D.partialPivLu().solve(f.cast<std::complex<double>>());
    // omega_1 = 157 rad/s, zeta_1 = beta omega_1 / 2 = 0.079: the start decays by exp(-50) in 4 s.
    const testing::Outcome r = run(model, 4.0, 1e-3);
    ASSERT_EQ(r.summary.status, RunStatus::ok);
    const double scale = X.cwiseAbs().maxCoeff();
    std::size_t checked = 0;
    for (const testing::Recorded& s : r.samples) {
        if (s.t < 3.9) continue;
        const std::complex<double> e = std::exp(std::complex<double>(0, w * s.t));
        for (Eigen::Index i = 0; i < n; ++i) {
            EXPECT_NEAR(s.x[static_cast<std::size_t>(i)], (X(i) * e).imag(), 1e-10 * scale) << s.t << " " << i;
            EXPECT_NEAR(s.v[static_cast<std::size_t>(i)], (std::complex<double>(0, w) * X(i) * e).imag(),
                        1e-10 * scale * w)
                << s.t << " " << i;
        }
        ++checked;
    }
    EXPECT_GE(checked, 100u);
}

// A mass between two stops fixed to a vibrating frame: relative to the frame
// the stops are fixed, and the frame's motion is the effective force
// -m x_g''. The same model with that force written by hand as a [[forcing]]
// gives the same bits.
TEST(BaseMotion, StopsOnAVibratingFrameAreTheRelativeModelWithItsEffectiveForce) {
    const double m = 0.5, A = 40.0, w = 25.0;
    const std::string common = R"(name = "rattle"
[[mass]]
name = "m"
m = 0.5
mu_k = 0.1
[[spring]]
between = ["ground", "m"]
k = 300.0
[[contact]]
name = "right"
between = ["m", "ground"]
gap = 0.02
k = 5.0e4
[[contact]]
name = "left"
between = ["ground", "m"]
gap = 0.02
k = 5.0e4
)";
    char base[256], hand[256];
    std::snprintf(base, sizeof base, "[[base]]\nmotion = \"acceleration\"\nomega = %.17g\namplitude = %.17g\n", w, A);
    std::snprintf(hand, sizeof hand, "[[forcing]]\nomega = %.17g\namplitude = { m = %.17g }\n", w, -m * A);
    const Model by_base = parse_model(common + base, "base.toml"), by_hand = parse_model(common + hand, "hand.toml");
    for (KernelChoice k : {KernelChoice::generic, KernelChoice::eigen}) {
        const testing::Outcome a = run(by_base, 2.0, 0.01, k), b = run(by_hand, 2.0, 0.01, k);
        ASSERT_EQ(a.summary.status, RunStatus::ok);
        EXPECT_GT(a.events.size(), 20u);
        ASSERT_EQ(a.events.size(), b.events.size());
        for (std::size_t i = 0; i < a.events.size(); ++i) {
            EXPECT_EQ(a.events[i].t, b.events[i].t) << i;
            EXPECT_EQ(a.events[i].kind, b.events[i].kind) << i;
            EXPECT_EQ(a.events[i].x, b.events[i].x) << i;
        }
    }
}

TEST(BaseMotion, BadBaseMotionsAreRefusedByKey) {
    struct Case {
        std::string base, message;
    };
    const std::vector<Case> cases = {
        {"[[base]]\nomega = 1.0\namplitude = 1.0\n", "key 'base[1].motion': required key is missing"},
        {"[[base]]\nmotion = \"jerk\"\nomega = 1.0\namplitude = 1.0\n", "key 'base[1].motion': 'jerk' is not a motion"},
        {"[[base]]\nmotion = \"velocity\"\nomega = 0.0\namplitude = 1.0\n", "key 'base[1].omega': must be > 0"},
        {"[[base]]\nmotion = \"velocity\"\nomega = 1.0\n", "key 'base[1].amplitude': required key is missing"},
        {"[[base]]\nmotion = \"velocity\"\nomega = 1.0\namplitude = 1.0\ndirection = { q = 1.0 }\n",
         "key 'base[1].direction.q': unknown mass 'q'"},
        {"[[base]]\nmotion = \"velocity\"\nomega = 1.0\namplitude = 1.0\ndirection = { ground = 1.0 }\n",
         "key 'base[1].direction.ground'"},
        {"[[base]]\nmotion = \"velocity\"\nomega = 1.0\namplitude = 1.0\nscale = 2\n",
         "key 'base[1].scale': unknown key"},
        {"[[base]]\nmotion = \"velocity\"\nomega = 1.0\namplitude = 1e308\n",
         "key 'base[1].amplitude': the effective force"},
    };
    for (const Case& c : cases) {
        try {
            parse_model(oscillator(c.base), "bad.toml");
            ADD_FAILURE() << "accepted: " << c.base;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
        }
    }
    // A [structure] says which dofs the base moves (rotations do not translate).
    testing::TempDir dir;
    const fe::Beam bar = fe::clamped_bar(2);
    const std::string path = fe::structure_model(dir, "bar.toml", "bar", bar.M, bar.K, bar.dofs,
                                                 "[[base]]\nmotion = \"displacement\"\nomega = 1.0\namplitude = 1.0\n");
    try {
        read_model(path);
        ADD_FAILURE() << "a [structure] without base.direction was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("key 'base[1].direction': required for a [structure]"), std::string::npos)
            << e.what();
    }
    // A reduced structure reads the direction over the full structure: a dof that is not one is named.
    const fe::Beam long_bar = fe::clamped_bar(8);
    const std::string reduced = fe::structure_model(
        dir, "reduced.toml", "bar", long_bar.M, long_bar.K, long_bar.dofs,
        "[reduction]\nmodes = 2\nboundary = [\"u8\"]\n[[base]]\nmotion = \"acceleration\"\nomega = 1.0\n"
        "amplitude = 1.0\ndirection = { u3 = 1.0, zz = 1.0 }\n");
    try {
        read_model(reduced);
        ADD_FAILURE() << "a base direction naming no dof of the structure was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("key 'base[1].direction.zz': 'zz' is not a dof of the structure"),
                  std::string::npos)
            << e.what();
    }
}

// A clamped bar of 8 consistent-mass elements on a shaker (r = 1 on every
// dof), reduced by Craig-Bampton to its tip u8 and fixed-interface modes:
// the effective force is T^T M r over the full bar (the interior's inertia
// included), so with every interior mode kept (a change of basis) the tip
// follows the full bar's own frequency response (K - w^2 M + i w C)^-1
// (-M r A) to 1e-10, and with 2 modes within the reduction's error. The
// direction names every dof, yet only u8 stays physical.
TEST(BaseMotion, AReducedBarOnAShakerFollowsTheFullBarsFrequencyResponse) {
    testing::TempDir dir;
    const fe::Beam bar = fe::clamped_bar(8);
    const double beta = 1e-3, A = 3.0, w = 90.0;
    const Eigen::Index n = bar.M.rows();
    const Eigen::VectorXd f = -bar.M * Eigen::VectorXd::Ones(n) * A;
    const Eigen::MatrixXcd D = (bar.K - w * w * bar.M).cast<std::complex<double>>() +
                               std::complex<double>(0, w) * (beta * bar.K).cast<std::complex<double>>();
    const std::complex<double> tip = D.partialPivLu().solve(f.cast<std::complex<double>>())(n - 1);
    // The boundary row of T^T M r: M_BB + M_BI 1 + Psi^T (M_IB + M_II 1), Psi = -K_II^-1 K_IB.
    const Eigen::Index ni = n - 1;
    const Eigen::VectorXd psi = -bar.K.topLeftCorner(ni, ni).ldlt().solve(bar.K.topRightCorner(ni, 1));
    const double boundary_force =
        -A * (bar.M.bottomRows(1).sum() + psi.dot(bar.M.topRows(ni) * Eigen::VectorXd::Ones(n)));
    std::string r_table = "{";
    for (std::size_t i = 0; i < bar.dofs.size(); ++i) r_table += (i ? ", " : " ") + bar.dofs[i] + " = 1.0";
    r_table += " }";
    for (const int modes : {7, 2}) {
        char sections[512];
        std::snprintf(sections, sizeof sections,
                      "[damping]\nbeta = %.17g\n[reduction]\nmodes = %d\nboundary = [\"u8\"]\n[[base]]\n"
                      "motion = \"acceleration\"\nomega = %.17g\namplitude = %.17g\ndirection = %s\n",
                      beta, modes, w, A, r_table.c_str());
        const std::string path =
            fe::structure_model(dir, "bar.toml", "reduced-bar-on-shaker", bar.M, bar.K, bar.dofs, sections);
        const Model model = read_model(path);
        ASSERT_EQ(model.dof(), static_cast<std::size_t>(1 + modes));
        ASSERT_EQ(model.masses[0].name, "u8");
        ASSERT_EQ(model.forcing.size(), 1u);
        EXPECT_NEAR(model.forcing[0].amplitude[0], boundary_force, 1e-13 * std::fabs(boundary_force));
        const testing::Outcome r = run(model, 4.0, 1e-3);
        ASSERT_EQ(r.summary.status, RunStatus::ok);
        double worst = 0.0;
        std::size_t checked = 0;
        for (const testing::Recorded& s : r.samples) {
            if (s.t < 3.9) continue;
            const std::complex<double> e = std::exp(std::complex<double>(0, w * s.t));
            worst = std::max(worst, std::fabs(s.x[0] - (tip * e).imag()));
            ++checked;
        }
        EXPECT_GE(checked, 100u);
        // All 7 interior modes: exact to rounding (measured 1.8e-15 of |X|); 2 modes: the
        // reduction's error (measured 9.7e-4 of |X|).
        EXPECT_LT(worst, (modes == 7 ? 1e-10 : 2e-3) * std::abs(tip)) << modes << " modes: " << worst / std::abs(tip);
    }
}

}  // namespace
}  // namespace hsnc
