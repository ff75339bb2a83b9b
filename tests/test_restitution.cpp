// Rigid stops with a coefficient of restitution (`restitution = e` on a
// [[contact]], interface.md): Newton's impact law, the velocity jump that
// makes the gap's rate -e times itself with the impulse along the contact's
// direction.
//
// The truths are closed forms derived here: the sequence of impacts of a
// spring-mass on a stop (each speed e times the last, the flight between two
// impacts from the free oscillation), two free bodies colliding (momentum
// kept, relative velocity reversed and scaled by e), a stuck block that an
// impact sets sliding; a consistent-mass bar against a wall (the impulse
// only at the wall's dof, M dv parallel to w); the CLN reference and CVODE on
// a forced impact oscillator; and the refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "cli_runner.h"
#include "engine_runner.h"
#include "error.h"
#include "facade_runner.h"
#include "fe_models.h"
#include "hsnc/lyapunov.h"
#include "hsnc/periodic.h"
#include "hsnc/simulate.h"
#include "hsnc/sweep.h"
#include "kernel_mode.h"
#include "model.h"
#include "model_reader.h"
#include "tangent.h"
#include "temp_dir.h"

namespace hsnc {
namespace {

using fe::axial_bar;
using fe::dof_list;
using fe::market;
using fe::table;
using fe::write;

using testing::options_for;
using testing::run_simulate;

// The impact oscillator of the examples, at omega (rad/s).
Model impact_oscillator(double omega) {
    Model m = read_model(std::string(HSNC_SOURCE_DIR) + "/examples/impact-oscillator.toml");
    m.forcing[0].omega = omega;
    return m;
}

// A mass m on a spring k (at rest at x = 0), a rigid stop at x = d, thrown
// from x = 0 at speed V > omega d.
constexpr double kM = 2.0, kK = 8.0, kD = 0.5, kV = 3.0, kE = 0.8;

Model bouncing(double t_end) {
    char text[512];
    std::snprintf(text, sizeof text, R"(name = "bouncing"
[[mass]]
name = "m"
m = %.17g
[[spring]]
between = ["m", "ground"]
k = %.17g
[[contact]]
name = "stop"
between = ["m", "ground"]
gap = %.17g
restitution = %.17g
[initial]
v = { m = %.17g }
[simulate]
t_end = %.17g
)",
                  kM, kK, kD, kE, kV, t_end);
    return parse_model(text, "bouncing.toml");
}

// The closed form: the speed into the stop at impact n is s_n = e^(n-1) s_1,
// s_1 = sqrt(V^2 - omega^2 d^2) (energy about x = 0); the first impact at
// asin(omega d / V)/omega; after one at speed s the mass leaves x = d at -e s
// on the oscillation of amplitude A = hypot(d, e s/omega), phase phi =
// atan2(e s/omega, d), and returns to x = d after (2 pi - 2 phi)/omega.
TEST(Restitution, ASpringMassBouncesOnItsStopAsTheClosedFormSays) {
    const double w = std::sqrt(kK / kM);
    std::vector<double> t{std::asin(w * kD / kV) / w}, speed{std::sqrt(kV * kV - w * w * kD * kD)};
    for (int n = 1; n < 12; ++n) {
        const double s = kE * speed.back(), phi = std::atan2(s / w, kD);
        t.push_back(t.back() + (2 * M_PI - 2 * phi) / w);
        speed.push_back(s);
    }
    const Model model = bouncing(t.back() + 0.5 * M_PI / w);  // past the 12th impact, before the 13th
    for (const char* how : {"generic", "interp", "eigen", "mp:30", "cvode"}) {
        if (how == std::string("cvode") && !HSNC_WITH_CVODE) continue;
        const testing::Outcome r = run_simulate(model, options_for(how));
        ASSERT_EQ(r.summary.status, RunStatus::ok) << how << ": " << r.summary.message;
        ASSERT_EQ(r.events.size(), t.size()) << how;
        const double tol = how == std::string("cvode") ? 1e-9 : 1e-13;
        for (std::size_t n = 0; n < t.size(); ++n) {
            EXPECT_EQ(r.events[n].kind, EventKind::impact) << how;
            EXPECT_EQ(r.events[n].element, 0) << how;
            EXPECT_NEAR(r.events[n].t, t[n], tol * (1 + t[n])) << how << " impact " << n;
            EXPECT_NEAR(r.events[n].x[0], kD, tol) << how << " impact " << n;
            EXPECT_NEAR(r.events[n].v[0], -kE * speed[n], tol) << how << " impact " << n;  // the state after it
        }
    }
}

// Two free bodies, m1 = 1 at x = 0 moving at 1 and m2 = 3 at rest at x = 2,
// a rigid contact along u = x1 - x2 (direction) with gap -1: they meet at
// t = 1; momentum is kept and the relative velocity becomes -e times itself.
TEST(Restitution, TwoFreeBodiesCollideKeepingMomentumOnADirection) {
    const double e = 0.6, m1 = 1.0, m2 = 3.0;
    char text[512];
    std::snprintf(text, sizeof text, R"(name = "collision"
[[mass]]
name = "a"
m = %.17g
[[mass]]
name = "b"
m = %.17g
[[contact]]
name = "face"
direction = { a = 1.0, b = -1.0 }
gap = -1.0
restitution = %.17g
[initial]
x = { b = 2.0 }
v = { a = 1.0 }
[simulate]
t_end = 3.0
)",
                  m1, m2, e);
    const Model model = parse_model(text, "collision.toml");
    const double va = (m1 - e * m2) / (m1 + m2), vb = m1 * (1 + e) / (m1 + m2);
    for (const char* how : {"generic", "interp", "eigen", "mp:30", "cvode"}) {
        if (how == std::string("cvode") && !HSNC_WITH_CVODE) continue;
        const testing::Outcome r = run_simulate(model, options_for(how));
        ASSERT_EQ(r.summary.status, RunStatus::ok) << how << ": " << r.summary.message;
        ASSERT_EQ(r.events.size(), 1u) << how;
        EXPECT_NEAR(r.events[0].t, 1.0, how == std::string("cvode") ? 1e-9 : 1e-14) << how;
        EXPECT_NEAR(r.events[0].v[0], va, 1e-15) << how;
        EXPECT_NEAR(r.events[0].v[1], vb, 1e-15) << how;
        EXPECT_NEAR(r.summary.x[0], 1.0 + 2.0 * va, 1e-13) << how;
        EXPECT_NEAR(r.summary.x[1], 2.0 + 2.0 * vb, 1e-13) << how;
    }
}

// A block held by static friction is hit by a sliding body: the impact's
// impulse sets it moving (no finite friction force can stop an impulse), so
// it releases at the impact, along its new velocity, and decelerates by mu_k g.
TEST(Restitution, AnImpactReleasesTheStuckBlockItHits) {
    const double e = 0.5, m1 = 2.0, m2 = 1.0, mu = 0.3, g = 9.81;
    char text[640];
    std::snprintf(text, sizeof text, R"(name = "hit-block"
[[mass]]
name = "block"
m = %.17g
mu_k = %.17g
mu_s = 0.4
[[mass]]
name = "puck"
m = %.17g
[[contact]]
name = "face"
between = ["puck", "block"]
gap = -0.5
restitution = %.17g
[initial]
x = { puck = -1.0 }
v = { puck = 2.0 }
[simulate]
t_end = 1.0
)",
                  m1, mu, m2, e);
    const Model model = parse_model(text, "hit-block.toml");
    // The puck reaches x = -0.5 at t = 0.25; after it: the block at
    // m2 (1 + e) 2/(m1 + m2) = 1, the puck at 2 (m2 - e m1)/(m1 + m2) = 0.
    const double vb = m2 * (1 + e) * 2.0 / (m1 + m2), vp = 2.0 * (m2 - e * m1) / (m1 + m2);
    const double ts = 0.25 + vb / (mu * g);  // the block stops
    for (const char* how : {"generic", "interp", "eigen", "mp:30", "cvode"}) {
        if (how == std::string("cvode") && !HSNC_WITH_CVODE) continue;
        const testing::Outcome r = run_simulate(model, options_for(how));
        ASSERT_EQ(r.summary.status, RunStatus::ok) << how << ": " << r.summary.message;
        ASSERT_GE(r.events.size(), 3u) << how;
        EXPECT_EQ(r.events[0].kind, EventKind::impact) << how;
        EXPECT_EQ(r.events[1].kind, EventKind::release) << how;
        EXPECT_EQ(r.events[1].element, 0) << how;
        EXPECT_EQ(r.events[0].t, r.events[1].t) << how;
        EXPECT_NEAR(r.events[0].t, 0.25, how == std::string("cvode") ? 1e-9 : 1e-14) << how;
        EXPECT_NEAR(r.events[1].v[0], vb, 1e-14) << how;
        EXPECT_NEAR(r.events[1].v[1], vp, 1e-14) << how;
        EXPECT_EQ(r.events[2].kind, EventKind::stick) << how;
        EXPECT_NEAR(r.events[2].t, ts, how == std::string("cvode") ? 1e-9 : 1e-13) << how;
    }
}

// A consistent-mass free-free bar (fe_models.h axial_bar) meets a rigid wall at
// its left end: at the impact the jump M dv is an impulse at u1 alone (zero
// on every other dof), u1' becomes -e times itself, and the engine's impact
// and state after it agree with the reference's at 30 digits. (The bar then
// rattles on the wall, its elastic force pressing u1 back, and comes to rest
// there: a run past that ends "resting".)
TEST(Restitution, AConsistentMassBarHitsAWallWithItsImpulseAtTheWallsDofOnly) {
    const testing::TempDir dir;
    const int elements = 4, n = elements + 1;
    const auto [M, K] = axial_bar(elements);
    write(dir / "M.mtx", market(M));
    write(dir / "K.mtx", market(K));
    std::vector<std::string> dofs;
    Eigen::VectorXd x0(n), v0 = Eigen::VectorXd::Constant(n, -0.5);
    for (int i = 0; i < n; ++i) dofs.push_back("u" + std::to_string(i + 1)), x0(i) = 1e-3 * std::sin(2.0 * i);
    const double e = 0.7;
    write(dir / "bar.toml", "name = \"bar-wall\"\n[structure]\ndofs = " + dof_list(dofs) +
                                "\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n[[contact]]\nname = \"wall\"\nbetween = "
                                "[\"ground\", \"u1\"]\ngap = 0.01\nrestitution = 0.7\n[initial]\nx = " +
                                table(dofs, x0) + "\nv = " + table(dofs, v0) + "\n[simulate]\nt_end = 0.2\n");
    const Model model = read_model(dir / "bar.toml");
    ASSERT_TRUE(model.coupled_mass());
    // The first impact: the engine's against the reference's at 30 digits.
    SimulateOptions first = options_for("generic"), first_ref = options_for("mp:30");
    first.max_events = first_ref.max_events = 1;
    const testing::Outcome r = run_simulate(model, first), ref = run_simulate(model, first_ref);
    ASSERT_EQ(r.summary.status, RunStatus::max_events) << r.summary.message;
    ASSERT_EQ(ref.summary.status, RunStatus::max_events) << ref.summary.message;
    ASSERT_EQ(r.events.size(), 1u);
    ASSERT_EQ(ref.events.size(), 1u);
    EXPECT_EQ(r.events[0].kind, EventKind::impact);
    EXPECT_NEAR(r.events[0].t, ref.events[0].t, 1e-12);
    for (int i = 0; i < n; ++i)
        EXPECT_NEAR(r.events[0].v[static_cast<std::size_t>(i)], ref.events[0].v[static_cast<std::size_t>(i)], 1e-11);
    SimulateOptions before;
    before.kernels = KernelChoice::generic;
    before.t_end = r.events[0].t;  // up to the first impact: the state before it
    const testing::Outcome a = run_simulate(model, before);
    ASSERT_EQ(a.events.size(), 0u);
    Eigen::VectorXd dv(n);
    for (int i = 0; i < n; ++i)
        dv(i) = r.events[0].v[static_cast<std::size_t>(i)] - a.summary.v[static_cast<std::size_t>(i)];
    const Eigen::VectorXd impulse = M * dv;
    for (int i = 1; i < n; ++i) EXPECT_NEAR(impulse(i), 0.0, 1e-12 * std::abs(impulse(0))) << "dof " << i;
    EXPECT_GT(impulse(0), 0.0);  // the wall pushes u1 back
    EXPECT_NEAR(r.events[0].v[0], -e * a.summary.v[0], 1e-12);
}

// A forced impact oscillator (the classic: a harmonically driven mass-spring
// with a rigid stop beside its equilibrium, at 2.3 rad/s): the programs, the Eigen solver,
// the reference at 30 digits and CVODE give the same impacts.
TEST(Restitution, AForcedImpactOscillatorAgreesWithTheReferenceAndCvode) {
    Model model = impact_oscillator(2.3);  // examples/impact-oscillator.toml
    model.t_end = 40.0;
    const testing::Outcome ref = run_simulate(model, options_for("mp:30"));
    ASSERT_EQ(ref.summary.status, RunStatus::ok) << ref.summary.message;
    ASSERT_GT(ref.events.size(), 10u);
    for (const char* how : {"generic", "interp", "eigen", "cvode"}) {
        if (how == std::string("cvode") && !HSNC_WITH_CVODE) continue;
        const testing::Outcome r = run_simulate(model, options_for(how));
        ASSERT_EQ(r.summary.status, RunStatus::ok) << how << ": " << r.summary.message;
        ASSERT_EQ(r.events.size(), ref.events.size()) << how;
        const double tol = how == std::string("cvode") ? 1e-8 : 1e-11;
        for (std::size_t k = 0; k < r.events.size(); ++k) {
            EXPECT_EQ(r.events[k].kind, EventKind::impact) << how;
            EXPECT_NEAR(r.events[k].t, ref.events[k].t, tol) << how << " impact " << k;
            EXPECT_NEAR(r.events[k].v[0], ref.events[k].v[0], 10 * tol) << how << " impact " << k;
        }
    }
}

// Pressed onto its stop by a constant load, a bouncing mass loses its speed
// geometrically (Zeno): the run ends with a clear message, exit 1, no CSV.
TEST(Restitution, ComingToRestOnARigidStopIsRefusedByName) {
    const testing::TempDir dir;
    write(dir / "rest.toml", R"(name = "rest"
[[mass]]
name = "m"
m = 1.0
[[contact]]
name = "floor"
between = ["m", "ground"]
gap = 0.1
restitution = 0.5
[load]
m = 9.81
[simulate]
t_end = 5.0
)");
    const testing::CliRun r = testing::run_hsnc("simulate '" + dir / "rest.toml" + "' --out '" + dir / "x.csv" + "'");
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("floor"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "x.csv"));
    // Where: the accumulation point of the impacts, t1 + 2 e v1 / (g (1 - e)),
    // v1 = sqrt(2 g h) the first impact's speed at t1 = v1 / g, up to the
    // flights too short to resolve (a rebound below G's rounding).
    const double g = 9.81, v1 = std::sqrt(2 * g * 0.1), e = 0.5, t_star = v1 / g + 2 * e * v1 / (g * (1 - e));
    for (const char* how : {"generic", "eigen", "mp:30", "cvode"}) {
        if (how == std::string("cvode") && !HSNC_WITH_CVODE) continue;
        const testing::Outcome o = run_simulate(read_model(dir / "rest.toml"), options_for(how));
        EXPECT_EQ(o.summary.status, RunStatus::chattering) << how;
        EXPECT_NE(o.summary.message.find("comes to rest on the rigid stop 'floor'"), std::string::npos) << how;
        EXPECT_NEAR(o.summary.t, t_star, how == std::string("mp:30") ? 1e-15 : 1e-5) << how;
        EXPECT_GT(o.events.size(), 10u) << how;
    }
}

TEST(Restitution, TheCliCountsImpactsAndModesRefuseThem) {
    const testing::TempDir dir;
    write(dir / "b.toml", R"(name = "b"
[parameters]
p = 1.5
[[mass]]
name = "m"
m = 2.0
[[spring]]
between = ["m", "ground"]
k = 8.0
[[contact]]
name = "stop"
between = ["m", "ground"]
gap = 0.5
restitution = 0.8
[[forcing]]
omega = "p"
amplitude = { m = 1.0 }
[initial]
v = { m = 3.0 }
)");
    const testing::CliRun r =
        testing::run_hsnc("simulate '" + dir / "b.toml" + "' --t-end 5 --events '" + dir / "e.csv" + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find(" impact="), std::string::npos) << r.out;
    EXPECT_NE(testing::slurp(dir / "e.csv").find(",impact,stop,"), std::string::npos);
    // A model without rigid stops keeps its summary line: no impact count.
    const testing::CliRun plain =
        testing::run_hsnc("simulate '" + testing::model_path("bilinear-1dof.toml") + "' --t-end 1");
    ASSERT_EQ(plain.exit_code, 0) << plain.err;
    EXPECT_EQ(plain.out.find("impact"), std::string::npos) << plain.out;
    const testing::CliRun modes = testing::run_hsnc("modes '" + dir / "b.toml" + "'");
    EXPECT_EQ(modes.exit_code, 2) << modes.err;
    EXPECT_NE(modes.err.find("rigid stop (restitution)"), std::string::npos) << modes.err;
}

// The tangent across impacts (the saltation matrix of a velocity jump,
// analysis/tangent.cpp salt_impact) against central differences of the run.
TEST(Restitution, TheRunsJacobianAcrossImpactsMatchesFiniteDifferences) {
    for (double omega : {1.2, 2.6}) {
        Model m = impact_oscillator(omega);
        m.x0 = {-0.3};
        m.v0 = {0.4};
        const double t_end = 25.0;
        GenericSolverProvider provider(m);
        Engine engine(m, provider);
        testing::EventSequence kinds;
        analysis::JacobianObserver jac(m, &kinds);
        EngineOptions opt;
        opt.t_end = t_end;
        opt.samples = false;
        ASSERT_EQ(engine.run(opt, jac).status, RunStatus::ok);
        ASSERT_GE(kinds.seq.size(), 4u) << omega;
        EXPECT_EQ(jac.grazing(), 0u);
        const Eigen::MatrixXd& J = jac.jacobian();
        const double h = 1e-6;
        for (int j = 0; j < 2; ++j) {
            Model p = m, q = m;
            (j == 0 ? p.x0 : p.v0)[0] += h;
            (j == 0 ? q.x0 : q.v0)[0] -= h;
            testing::EventSequence kp, kq;
            const std::vector<double> a = testing::end_state(p, t_end, kp), b = testing::end_state(q, t_end, kq);
            ASSERT_EQ(kp.seq, kinds.seq);
            ASSERT_EQ(kq.seq, kinds.seq);
            double scale = 1.0;
            for (int i = 0; i < 2; ++i) scale = std::max(scale, std::fabs((a[i] - b[i]) / (2 * h)));
            for (int i = 0; i < 2; ++i)
                EXPECT_NEAR(J(i, j), (a[i] - b[i]) / (2 * h), 1e-6 * scale)
                    << "omega " << omega << " dy" << i << "/dy0_" << j;
        }
    }
}

// A period-1 impacting orbit (one impact per forcing period, at 1.2 rad/s):
// `periodic` finds it, a long CVODE run settles on it, and its Floquet
// multipliers are the eigenvalues of the period map's Jacobian by central
// differences of CVODE runs (an independent integrator, the same impact law).
TEST(Restitution, APeriodicImpactingOrbitAndItsMultipliersAgreeWithCvode) {
    if (!HSNC_WITH_CVODE) GTEST_SKIP() << "built without CVODE";
    const Model m = impact_oscillator(1.2);
    PeriodicOptions po;
    po.transient = 200.0;
    const PeriodicResult o = periodic(m, po);
    ASSERT_EQ(o.status, PeriodicStatus::ok) << o.message;
    EXPECT_EQ(o.events, 1u);
    EXPECT_EQ(o.grazing, 0u);
    EXPECT_TRUE(o.stable);
    const double T = 2 * M_PI / 1.2;
    auto cvode_period = [&](double x, double v) {
        Model s = m;
        s.t0 = o.t;
        s.x0 = {x};
        s.v0 = {v};
        SimulateOptions cv = options_for("cvode");
        cv.t_end = o.t + T;
        const testing::Outcome r = run_simulate(s, cv);
        EXPECT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
        return std::vector<double>{r.summary.x[0], r.summary.v[0]};
    };
    const std::vector<double> back = cvode_period(o.x[0], o.v[0]);  // the orbit is a fixed point of CVODE's map too
    EXPECT_NEAR(back[0], o.x[0], 1e-9);
    EXPECT_NEAR(back[1], o.v[0], 1e-9);
    const double h = 1e-5;
    Eigen::Matrix2d P;
    for (int j = 0; j < 2; ++j) {
        const std::vector<double> a = cvode_period(o.x[0] + (j == 0 ? h : 0), o.v[0] + (j == 1 ? h : 0));
        const std::vector<double> b = cvode_period(o.x[0] - (j == 0 ? h : 0), o.v[0] - (j == 1 ? h : 0));
        for (int i = 0; i < 2; ++i)
            P(i, j) = (a[static_cast<std::size_t>(i)] - b[static_cast<std::size_t>(i)]) / (2 * h);
    }
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j)
            EXPECT_NEAR(o.monodromy[static_cast<std::size_t>(2 * i + j)], P(i, j), 1e-5) << i << j;
    // The phase volume: the flow contracts it by e^{-alpha T} (c = alpha = 0.05
    // on m = 1), the impact by e^2 (its saltation matrix is [[-e, 0], [*, -e]]).
    const double det = (std::complex<double>(o.multipliers[0]) * o.multipliers[1]).real();
    EXPECT_NEAR(det, std::exp(-0.05 * T) * 0.8 * 0.8, 1e-12);
    // The largest multiplier: that of P.
    const Eigen::Vector2cd mu = P.eigenvalues();
    const double big = std::max(std::abs(mu(0)), std::abs(mu(1)));
    EXPECT_NEAR(o.max_multiplier, big, 1e-5);
}

// The chaotic impact oscillator (2.6 rad/s): a positive Lyapunov exponent,
// and the sum of the spectrum is the mean contraction of phase volume,
// -alpha from the damping plus 2 ln e per impact (N impacts over T):
// -alpha + (N / T) 2 ln e, in closed form.
TEST(Restitution, TheLyapunovSpectrumOfTheChaoticImpactOscillatorSumsToItsContraction) {
    const Model m = impact_oscillator(2.6);
    LyapunovOptions lo;
    lo.t_end = 1000.0;
    lo.transient = 100.0;
    const LyapunovResult r = lyapunov(m, lo);
    ASSERT_EQ(r.status, RunStatus::ok);
    ASSERT_EQ(r.exponents.size(), 2u);
    EXPECT_GT(r.events, 200u);
    EXPECT_EQ(r.grazing, 0u);
    EXPECT_GT(r.exponents[0], 0.05);  // chaos
    const double T = r.t - r.t_start;
    EXPECT_NEAR(r.sum, -0.05 + static_cast<double>(r.events) / T * 2 * std::log(0.8), 1e-10);
}

// A sweep point of the impact oscillator records the periodic orbit's
// amplitude (exact extremes of the segments between impacts); continuation
// refuses rigid stops by name, for now.
TEST(Restitution, ASweepPointRecordsThePeriodicOrbitsAmplitude) {
    const testing::TempDir dir;
    const std::string model = std::string(HSNC_SOURCE_DIR) + "/examples/impact-oscillator.toml";
    const testing::CliRun sw = testing::run_hsnc(
        "sweep '" + model + "' --param omega --from 1.2 --to 1.2 --points 1 --quiet --out '" + dir / "c.csv" + "'");
    ASSERT_EQ(sw.exit_code, 0) << sw.err;
    const testing::CliRun po = testing::run_hsnc(
        "periodic '" + model + "' --set omega=1.2 --transient 200 --dt 1e-4 --out '" + dir / "o.csv" + "'");
    ASSERT_EQ(po.exit_code, 0) << po.err;
    std::istringstream curve(testing::slurp(dir / "c.csv")), orbit(testing::slurp(dir / "o.csv"));
    std::string header, row;
    std::getline(curve, header);
    std::getline(curve, row);
    std::vector<std::string> names, values;
    for (std::istringstream h(header); std::getline(h, row, ',');) names.push_back(row);
    std::getline(std::istringstream(testing::slurp(dir / "c.csv")).ignore(1 << 20, '\n'), row);
    for (std::istringstream v(row); std::getline(v, header, ',');) values.push_back(header);
    ASSERT_EQ(names.size(), values.size());
    double xmax = NAN;
    for (std::size_t k = 0; k < names.size(); ++k)
        if (names[k] == "xmax_m") xmax = std::stod(values[k]);
    double largest = 0.0;
    std::getline(orbit, row);  // header t,x_m,v_m
    while (std::getline(orbit, row)) largest = std::max(largest, std::fabs(std::stod(row.substr(row.find(',') + 1))));
    EXPECT_NEAR(xmax, largest, 1e-6);
    EXPECT_GT(xmax, 0.5);
    const testing::CliRun cont =
        testing::run_hsnc("sweep '" + model + "' --param omega --from 1.2 --to 1.4 --points 3 --continuation");
    EXPECT_EQ(cont.exit_code, 0) << cont.err;
    EXPECT_NE(cont.out.find("status=ok"), std::string::npos) << cont.out;
}

// Continuation through impacts. The impacting period-1 branch of the impact
// oscillator from 1.0 to 2.0 rad/s: every stable row is the orbit `periodic`
// finds from rest (its largest multiplier, 1e-9); the branch loses and
// regains stability through two period doublings, located (a multiplier at
// -1, 1e-9) and switched onto (period-2 branches; subcritical: unstable, on
// the stable side), and shooting from rest finds the period-1 orbit stable
// just before the first one and unstable just past it. No
// row says grazing (an impacting orbit's largest G is 0 at every impact:
// the slowest impact's speed stands for it, so rounding cannot fake a sign
// change). From 3.0 down, the branch that misses the stop is the linear
// response F |H(omega)| (1e-12) until it grazes the stop at omega_g,
// F |H(omega_g)| = gap in closed form; there the impacting orbit's
// multipliers grow without bound (the impact map's square-root singularity)
// and the branch stops, within 1e-5 of omega_g, saying so.
TEST(Restitution, ContinuationFollowsImpactingOrbitsAndStopsAtTheirGrazing) {
    const std::string text = testing::slurp(std::string(HSNC_SOURCE_DIR) + "/examples/impact-oscillator.toml");
    auto follow = [&](double from, double to, std::size_t points, int branch_switch) {
        SweepOptions o;
        o.param = "omega";
        o.from = from;
        o.to = to;
        o.points = points;
        o.continuation = true;
        o.branch_switch = branch_switch;
        o.max_periods = 3000;
        return SweepPlan(text, "impact-oscillator.toml", {}, o).run();
    };
    auto from_rest = [](double omega, double periods) {
        PeriodicOptions po;
        po.transient = 300.0;
        po.period = periods * 2 * M_PI / omega;
        return periodic(impact_oscillator(omega), po);
    };
    const SweepResult up = follow(1.0, 2.0, 11, 1);
    ASSERT_GT(up.points.size(), 20u);
    std::vector<double> doublings;
    std::size_t checked = 0, period_two = 0;
    for (const SweepPoint& p : up.points) {
        ASSERT_EQ(p.failure, "") << p.value;
        EXPECT_EQ(p.bifurcation.find("grazing"), std::string::npos) << p.value << ": " << p.bifurcation;
        if (p.branch != 0) {
            period_two += p.multiple == 2 ? 1 : 0;
            continue;
        }
        if (p.bifurcation == "period_doubling" && p.periods == 0) {  // a located row
            EXPECT_NEAR(p.max_multiplier, 1.0, 1e-9) << p.value;
            doublings.push_back(p.value);
        }
        if (!p.stable || p.periods == 0) continue;
        const PeriodicResult o = from_rest(p.value, 1);
        ASSERT_EQ(o.status, PeriodicStatus::ok) << p.value << ": " << o.message;
        EXPECT_NEAR(o.max_multiplier, p.max_multiplier, 1e-9) << p.value;
        ++checked;
    }
    EXPECT_GT(checked, 20u);
    EXPECT_GT(period_two, 5u);
    ASSERT_EQ(doublings.size(), 2u);
    // Shooting from rest on either side of the first doubling: stable just
    // before it, unstable just past it (the same orbit, one impact a period).
    const PeriodicResult before = from_rest(doublings[0] - 2e-3, 1), past = from_rest(doublings[0] + 2e-3, 1);
    ASSERT_EQ(before.status, PeriodicStatus::ok) << before.message;
    ASSERT_EQ(past.status, PeriodicStatus::ok) << past.message;
    EXPECT_TRUE(before.stable);
    EXPECT_FALSE(past.stable);
    EXPECT_EQ(past.events, 1u);

    const SweepResult down = follow(3.0, 2.3, 8, 0);
    const double zeta2 = 0.05, gap = 0.2;  // alpha = 2 zeta on m = k = 1, F = 1
    auto response = [&](double w) { return 1.0 / std::sqrt((1 - w * w) * (1 - w * w) + zeta2 * zeta2 * w * w); };
    // (1 - s)^2 + zeta2^2 s = 1/gap^2 in s = w^2, the upper root.
    const double b = 2 - zeta2 * zeta2, c = 1 - 1 / (gap * gap);
    const double omega_g = std::sqrt((b + std::sqrt(b * b - 4 * c)) / 2);
    ASSERT_GT(down.points.size(), 5u);
    for (const SweepPoint& p : down.points) {
        ASSERT_EQ(p.failure, "") << p.value;
        EXPECT_GT(p.value, omega_g);
        EXPECT_NEAR(p.xmax[0], response(p.value), 1e-12) << p.value;
        EXPECT_LT(p.gap_max[0], 0.0) << p.value;
        EXPECT_TRUE(p.stable) << p.value;
    }
    EXPECT_LT(down.points.back().value, omega_g + 1e-5);
    EXPECT_NE(down.points.back().stop, "");  // the branch says why it stopped
    std::printf("grazing at omega_g = %.17g (closed form); the branch stops at %.17g\n", omega_g,
                down.points.back().value);
}

TEST(Restitution, TheReaderRefusesWhatARigidStopCannotBe) {
    auto message = [](const std::string& contact, const std::string& rest = "") {
        try {
            parse_model(
                "name = \"r\"\n[[mass]]\nname = \"m\"\nm = 1\n[[jenkins]]\nname = \"j\"\nbetween = "
                "[\"m\", \"ground\"]\nk = 1\nslip_force = 1\n[[contact]]\nbetween = [\"m\", \"ground\"]\n" +
                    contact + rest,
                "r.toml");
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    EXPECT_NE(message("gap = 0.1\nrestitution = 0.0\n").find("in (0, 1]"), std::string::npos);
    EXPECT_NE(message("gap = 0.1\nrestitution = 1.5\n").find("in (0, 1]"), std::string::npos);
    EXPECT_NE(message("gap = 0.1\nrestitution = 0.5\nk = 10\n").find("not both"), std::string::npos);
    EXPECT_NE(message("gap = 0.1\nrestitution = 0.5\nc = 1\n").find("not both"), std::string::npos);
    EXPECT_EQ(message("gap = 0.1\nrestitution = 0.5\n"),
              "accepted");  // with a Jenkins element (test_impact_jenkins.cpp)
    auto plain = [](const std::string& initial) {
        try {
            parse_model(
                "name = \"r\"\n[[mass]]\nname = \"m\"\nm = 1\n[[contact]]\nname = \"s\"\nbetween = [\"m\", "
                "\"ground\"]\ngap = 0.1\nrestitution = 0.5\n[initial]\n" +
                    initial,
                "r.toml");
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    EXPECT_NE(plain("x = { m = 0.2 }\n").find("starts penetrated"), std::string::npos);
    EXPECT_NE(plain("x = { m = 0.1 }\nv = { m = 1.0 }\n").find("moving into it"), std::string::npos);
    EXPECT_EQ(plain("x = { m = 0.1 }\nv = { m = -1.0 }\n"), "accepted");
    EXPECT_NE(plain("x = { m = 0.2 }\n").find("r.toml:"), std::string::npos);  // file and line
}

}  // namespace
}  // namespace hsnc
