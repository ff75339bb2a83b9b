// Rigid stops (restitution) in a model with Jenkins elements (interface.md,
// "Impacts with restitution"): at the velocity jump a slipping element whose
// relative velocity turns against its slip sticks (a `stick` row after the
// `impact` row), one that keeps its direction slips on, a stuck one stays
// stuck.
//
// The truths: a closed form derived below for a mass on a Jenkins joint
// thrown into a wall (stick, slip, impact and stick, slip back), the CLN
// reference and CVODE on a forced oscillator with a joint and a stop, and the
// periodic orbit's monodromy matrix against central differences of CVODE's
// period map.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "engine.h"
#include "engine_runner.h"
#include "facade_runner.h"
#include "generic_solver.h"
#include "hsnc/periodic.h"
#include "hsnc/simulate.h"
#include "kernel_mode.h"
#include "model.h"
#include "model_reader.h"
#include "tangent.h"

namespace hsnc {
namespace {

using testing::options_for;
using testing::run_simulate;

// A mass m on a Jenkins joint (k, slip force F) to the ground, a rigid stop
// at x = d, thrown from rest position at speed V.
constexpr double kM = 1.0, kK = 4.0, kF = 1.0, kD = 0.6, kV = 2.0, kE = 0.5;

Model thrown_joint(double t_end) {
    char text[640];
    std::snprintf(text, sizeof text, R"(name = "thrown-joint"
[[mass]]
name = "m"
m = %.17g
[[jenkins]]
name = "joint"
between = ["m", "ground"]
k = %.17g
slip_force = %.17g
[[contact]]
name = "wall"
between = ["m", "ground"]
gap = %.17g
restitution = %.17g
[initial]
v = { m = %.17g }
[simulate]
t_end = %.17g
)",
                  kM, kK, kF, kD, kE, kV, t_end);
    return parse_model(text, "thrown-joint.toml");
}

// The closed form (omega = sqrt(k/m), x1 = F/k the stretch at slip):
//   stuck, x = (V/omega) sin(omega t): it slips at t1 = asin(omega x1/V)/omega,
//     at speed v1 = sqrt(V^2 - omega^2 x1^2);
//   slipping, the force -F: x = x1 + v1 s - (F/2m) s^2 reaches d after
//     s2 = (v1 - v2) m/F, v2 = sqrt(v1^2 - 2 (F/m)(d - x1)): the impact;
//   the mass leaves at -e v2, against the slip: the joint sticks with its
//     slider at d - x1, and the stretch x1 cos(omega s) - (e v2/omega)
//     sin(omega s) = A cos(omega s + phi) falls to -x1 (slip the other way)
//     at s3 = (acos(-x1/A) - phi)/omega.
struct ThrownJoint {
    double t1, v1, t2, v2, t3;
};

ThrownJoint closed_form() {
    const double w = std::sqrt(kK / kM), x1 = kF / kK;
    ThrownJoint c{};
    c.t1 = std::asin(w * x1 / kV) / w;
    c.v1 = std::sqrt(kV * kV - w * w * x1 * x1);
    c.v2 = std::sqrt(c.v1 * c.v1 - 2 * (kF / kM) * (kD - x1));
    c.t2 = c.t1 + (c.v1 - c.v2) * kM / kF;
    const double b = kE * c.v2 / w, A = std::hypot(x1, b), phi = std::atan2(b, x1);
    c.t3 = c.t2 + (std::acos(-x1 / A) - phi) / w;
    return c;
}

TEST(ImpactJenkins, AJointThrownIntoAWallSticksAtTheImpactAsTheClosedFormSays) {
    const ThrownJoint c = closed_form();
    const Model model = thrown_joint(c.t3 + 0.05);
    const int joint = 1;  // events name Jenkins element j as dof() + j
    for (const char* how : {"generic", "interp", "eigen", "mp:30", "cvode"}) {
        if (how == std::string("cvode") && !HSNC_WITH_CVODE) continue;
        const testing::Outcome r = run_simulate(model, options_for(how));
        ASSERT_EQ(r.summary.status, RunStatus::ok) << how << ": " << r.summary.message;
        ASSERT_EQ(r.events.size(), 4u) << how;
        const double tol = how == std::string("cvode") ? 1e-9 : 1e-13;
        EXPECT_EQ(r.events[0].kind, EventKind::release) << how;
        EXPECT_EQ(r.events[0].element, joint) << how;
        EXPECT_NEAR(r.events[0].t, c.t1, tol) << how;
        EXPECT_NEAR(r.events[0].v[0], c.v1, tol) << how;
        EXPECT_EQ(r.events[1].kind, EventKind::impact) << how;
        EXPECT_EQ(r.events[1].element, 0) << how;
        EXPECT_NEAR(r.events[1].t, c.t2, tol) << how;
        EXPECT_NEAR(r.events[1].x[0], kD, tol) << how;
        EXPECT_NEAR(r.events[1].v[0], -kE * c.v2, tol) << how;  // the state after the jump
        EXPECT_EQ(r.events[2].kind, EventKind::stick) << how;
        EXPECT_EQ(r.events[2].element, joint) << how;
        EXPECT_EQ(r.events[2].t, r.events[1].t) << how;           // at the impact's instant
        EXPECT_NEAR(r.events[2].x[1], kD - kF / kK, tol) << how;  // the slider where the slip left it
        EXPECT_EQ(r.events[3].kind, EventKind::release) << how;
        EXPECT_EQ(r.events[3].element, joint) << how;
        EXPECT_NEAR(r.events[3].t, c.t3, tol) << how;
        EXPECT_NEAR(r.events[3].x[0] - r.events[3].x[1], -kF / kK, tol) << how;  // the stretch at -slip
    }
}

// The forced oscillator of the tests below: a mass on a spring and a Jenkins
// joint, damped (alpha = 0.05), a rigid stop at 0.5 (e = 0.8), driven at 1.3
// rad/s: a period-1 orbit of one impact, at which the slipping joint sticks,
// and five slips and sticks (periodic finds it from rest after 200 s).
Model forced_joint() {
    return parse_model(R"(name = "forced-joint-stop"
[[mass]]
name = "m"
m = 1.0
[[spring]]
between = ["m", "ground"]
k = 1.0
[[jenkins]]
name = "joint"
between = ["m", "ground"]
k = 4.0
slip_force = 0.5
[[contact]]
name = "wall"
between = ["m", "ground"]
gap = 0.5
restitution = 0.8
[damping]
alpha = 0.05
[[forcing]]
omega = 1.3
amplitude = { m = 1.5 }
)",
                       "forced-joint-stop.toml");
}

// The tangent across an impact that sticks a slipping joint (the saltation
// matrix of the jump on the full state (x, v, s), analysis/tangent.cpp
// salt_impact_stick) against central differences of the run, from a state
// where the joint is stuck (so that every perturbation of (x, v, s) is one
// the model allows).
TEST(ImpactJenkins, TheRunsJacobianAcrossImpactsWithAJointMatchesFiniteDifferences) {
    Model m = forced_joint();
    m.x0 = {0.0};
    m.v0 = {0.3};
    m.slider0 = {0.02};
    const double t_end = 14.0;
    GenericSolverProvider provider(m);
    Engine engine(m, provider);
    testing::EventSequence kinds;
    analysis::JacobianObserver jac(m, &kinds);
    EngineOptions opt;
    opt.t_end = t_end;
    opt.samples = false;
    ASSERT_EQ(engine.run(opt, jac).status, RunStatus::ok);
    std::size_t impacts = 0, sticks_at_impacts = 0;
    for (std::size_t k = 0; k < kinds.seq.size(); ++k)
        if (kinds.seq[k].first == EventKind::impact) {
            ++impacts;
            if (k + 1 < kinds.seq.size() && kinds.seq[k + 1].first == EventKind::stick) ++sticks_at_impacts;
        }
    ASSERT_GE(impacts, 2u);
    ASSERT_GE(sticks_at_impacts, 2u);
    EXPECT_EQ(jac.grazing(), 0u);
    const Eigen::MatrixXd& J = jac.jacobian();
    ASSERT_EQ(J.rows(), 3);
    const double h = 1e-6;
    for (int j = 0; j < 3; ++j) {
        Model p = m, q = m;
        std::vector<double>& pj = j == 0 ? p.x0 : j == 1 ? p.v0 : p.slider0;
        std::vector<double>& qj = j == 0 ? q.x0 : j == 1 ? q.v0 : q.slider0;
        pj[0] += h;
        qj[0] -= h;
        testing::EventSequence kp, kq;
        const std::vector<double> a = testing::end_state(p, t_end, kp), b = testing::end_state(q, t_end, kq);
        ASSERT_EQ(kp.seq, kinds.seq);
        ASSERT_EQ(kq.seq, kinds.seq);
        double scale = 1.0;
        for (int i = 0; i < 3; ++i) scale = std::max(scale, std::fabs((a[i] - b[i]) / (2 * h)));
        for (int i = 0; i < 3; ++i)
            EXPECT_NEAR(J(i, j), (a[i] - b[i]) / (2 * h), 1e-6 * scale) << "dy" << i << "/dy0_" << j;
    }
}

// The period-1 orbit: no grazing (the impact's saltation matrix is taken),
// the same orbit and multipliers on every kernel kind, and a fixed point of
// the 30-digit reference's period map; the largest multiplier that of the
// period map's Jacobian by central differences of CVODE runs, perturbed
// along the states the orbit's phase allows (the joint slips there: its
// slider moves with the mass, ds = dx).
TEST(ImpactJenkins, APeriodicOrbitWithAJointAndAStopHasTheMultipliersOfItsPeriodMap) {
    const Model m = forced_joint();
    PeriodicOptions po;
    po.transient = 200.0;
    const PeriodicResult o = periodic(m, po);
    ASSERT_EQ(o.status, PeriodicStatus::ok) << o.message;
    EXPECT_EQ(o.grazing, 0u);
    EXPECT_GE(o.events, 4u);
    EXPECT_TRUE(o.stable);
    const double T = 2 * M_PI / 1.3;
    for (const char* how : {"eigen", "interp"}) {
        PeriodicOptions other = po;
        other.kernels = kernel_choice_from_name(how);
        const PeriodicResult r = periodic(m, other);
        ASSERT_EQ(r.status, PeriodicStatus::ok) << how << ": " << r.message;
        EXPECT_NEAR(r.x[0], o.x[0], 1e-10) << how;
        EXPECT_NEAR(r.max_multiplier, o.max_multiplier, 1e-10) << how;
    }
    auto period_map = [&](const std::string& how, double x, double v, double s) {
        Model p = m;
        p.t0 = o.t;
        p.x0 = {x};
        p.v0 = {v};
        p.slider0 = {s};
        SimulateOptions so = options_for(how);
        so.t_end = o.t + T;
        const testing::Outcome r = run_simulate(p, so);
        EXPECT_EQ(r.summary.status, RunStatus::ok) << how << ": " << r.summary.message;
        return std::vector<double>{r.summary.x[0], r.summary.v[0], r.summary.slider[0]};
    };
    const std::vector<double> ref = period_map("mp:30", o.x[0], o.v[0], o.s[0]);
    EXPECT_NEAR(ref[0], o.x[0], 1e-12);
    EXPECT_NEAR(ref[1], o.v[0], 1e-12);
    EXPECT_NEAR(ref[2], o.s[0], 1e-12);
    if (!HSNC_WITH_CVODE) return;
    // The monodromy applied to the allowed perturbations (dx, 0, dx) and (0, dv, 0).
    const Eigen::Map<const Eigen::Matrix3d> Mt(o.monodromy.data());  // column-major view of row-major: M^T
    const Eigen::Matrix3d M = Mt.transpose();
    const double h = 1e-5;
    Eigen::Matrix<double, 3, 2> D, MD;
    for (int j = 0; j < 2; ++j) {
        const Eigen::Vector3d d = j == 0 ? Eigen::Vector3d(1, 0, 1) : Eigen::Vector3d(0, 1, 0);
        const std::vector<double> a = period_map("cvode", o.x[0] + h * d(0), o.v[0] + h * d(1), o.s[0] + h * d(2));
        const std::vector<double> b = period_map("cvode", o.x[0] - h * d(0), o.v[0] - h * d(1), o.s[0] - h * d(2));
        for (int i = 0; i < 3; ++i)
            D(i, j) = (a[static_cast<std::size_t>(i)] - b[static_cast<std::size_t>(i)]) / (2 * h);
        MD.col(j) = M * d;
    }
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 2; ++j) EXPECT_NEAR(MD(i, j), D(i, j), 1e-5) << i << j;
}

}  // namespace
}  // namespace hsnc
