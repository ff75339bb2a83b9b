// Elements along a general direction, u = w^T x (`direction = { dof = w }`):
// a breathing crack in a consistent-mass cantilever (a contact on the
// opening of the crack's outer fibre, a weighted difference of the two
// rotations at the crack) against CVODE and the 30- and 60-digit reference;
// a scaled direction against the same contact written with `between`; and
// the input and back ends that refuse it by name. The same for a Jenkins
// element along a direction: a friction joint on the crack's relative
// rotation, and a scaled direction against the element between two bodies.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "assembly.h"
#include "cli_runner.h"
#include "engine_runner.h"
#include "fe_models.h"
#include "flow.h"
#include "hsnc/lyapunov.h"
#include "hsnc/modes.h"
#include "hsnc/periodic.h"
#include "model_reader.h"
#include "shooting.h"
#include "temp_dir.h"

namespace hsnc {
namespace {

using namespace fe;

/// A cantilever of 4 Euler-Bernoulli elements (1 m, EI = 100 N m^2,
/// 2 kg/m, consistent mass) cracked at mid-span: node 2 keeps one
/// deflection w2 but two rotations, tL (the root side) and tR (the tip
/// side), joined by the open crack's rotational spring k_r.
Beam cracked_cantilever(double k_r) {
    const double h = 0.25;
    Eigen::Matrix4d ke, me;
    beam_element(h, 100.0, 2.0, ke, me);
    const std::vector<std::string> dofs = {"w1", "t1", "w2", "tL", "tR", "w3", "t3", "w4", "t4"};
    const int of[4][4] = {{-1, -1, 0, 1}, {0, 1, 2, 3}, {2, 4, 5, 6}, {5, 6, 7, 8}};  // element -> dofs (-1: clamped)
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(9, 9), K = Eigen::MatrixXd::Zero(9, 9);
    for (const auto& e : of)
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c)
                if (e[r] >= 0 && e[c] >= 0) {
                    M(e[r], e[c]) += me(r, c);
                    K(e[r], e[c]) += ke(r, c);
                }
    K(3, 3) += k_r, K(4, 4) += k_r, K(3, 4) -= k_r, K(4, 3) -= k_r;
    return {M, K, dofs, 7};
}

/// The cracked cantilever forced at its tip near its first mode; the crack's
/// faces touch where the outer fibre (0.05 m from the axis) has opened by
/// `gap`: u = 0.05 (tR - tL), contact stiffness k_c.
std::string breathing_crack(const testing::TempDir& dir, const std::string& contact) {
    const Beam b = cracked_cantilever(1000.0);
    return structure_model(dir, "crack.toml", "breathing-crack", b.M, b.K, b.dofs,
                           "[damping]\nalpha = 0.2\nbeta = 5e-4\n"
                           "[[forcing]]\nomega = 20.0\namplitude = { w4 = 5.0 }\n" +
                               contact);
}

const char* kCrack = "[[contact]]\nname = \"crack\"\ndirection = { tL = -0.05, tR = 0.05 }\ngap = 2e-5\nk = 4e6\n";

// A frictional joint across the crack: a Jenkins element on the relative
// rotation tR - tL (a spring k_j in series with a slider that slips at the
// moment slip_force), in parallel with the open crack's spring.
const char* kJoint =
    "[[jenkins]]\nname = \"joint\"\ndirection = { tL = -1.0, tR = 1.0 }\nk = 3000.0\n"
    "slip_force = 0.6\n";

/// The events of the cracked cantilever with `element` over 2 s: the
/// programs against CVODE (rtol 1e-12) and the 30-digit reference, the Eigen
/// solver (modal analysis in double) against the reference, 30 against 60
/// digits.
void expect_events_of_cvode_and_the_reference(const Model& model) {
    const testing::Outcome eigen = testing::simulate(model, 2.0);
    ASSERT_GE(eigen.events.size(), 8u);
    const testing::Outcome programs = testing::simulate(model, 2.0, 0.0, testing::Solvers::interp);
    const testing::Outcome cvode = testing::baseline(model, 2.0, 1e-12, 1e-14, Method::cvode);
    const std::vector<testing::Recorded> r30 = reference_events(model, 30, 2.0), r60 = reference_events(model, 60, 2.0);
    const double eigen_off = event_gap(eigen.events, r30), to_cvode = event_gap(programs, cvode),
                 to_reference = event_gap(programs.events, r30), self = event_gap(r30, r60);
    std::printf("%zu events: programs within %.3g s of the reference, %.3g s of CVODE; the Eigen solver (modal "
                "analysis in double) %.3g s of the reference; 30 against 60 digits %.3g s\n",
                programs.events.size(), to_reference, to_cvode, eigen_off, self);
    EXPECT_LT(eigen_off, 1e-11);  // as on the cantilever with a tip stop (test_coupled_mass.cpp)
    EXPECT_LT(to_cvode, 1e-9);
    EXPECT_LT(to_reference, 1e-11);
    EXPECT_LT(self, 1e-20);
}

TEST(Direction, ABreathingCrackGivesTheEventsOfCvodeAndTheReference) {
    testing::TempDir dir;
    const Model model = read_model(breathing_crack(dir, kCrack));
    ASSERT_TRUE(model.contacts[0].direction().weighted());
    expect_events_of_cvode_and_the_reference(model);
}

TEST(Direction, AClosedContactStampsKWwTAndItsPreload) {
    // K(closed) - K(open) = k w w^T, f(closed) - f(open) = k gap w, from the
    // pair links every back end stamps (direction.h as_pair_links).
    testing::TempDir dir;
    const Model model = read_model(breathing_crack(dir, kCrack));
    Configuration open = Configuration::all_open(model), closed = open;
    closed.closed[0] = 1;
    Eigen::VectorXd w = Eigen::VectorXd::Zero(9);
    w(3) = -0.05, w(4) = 0.05;
    const Eigen::MatrixXd dK = stiffness_matrix(model, closed) - stiffness_matrix(model, open);
    const Eigen::VectorXd df = constant_force(model, closed) - constant_force(model, open);
    EXPECT_LT((dK - 4e6 * w * w.transpose()).norm(), 1e-12 * 4e6 * w.squaredNorm());
    EXPECT_LT((df - 4e6 * 2e-5 * w).norm(), 1e-15 * 4e6 * 2e-5 * w.norm());
    EXPECT_GT(df.norm(), 0.0);
}

/// Two writings of one element (between two bodies, along a scaled
/// direction): the same events on the Eigen solver and the programs.
void expect_the_same_instants(const Model& between, const Model& scaled) {
    for (testing::Solvers s : {testing::Solvers::generic, testing::Solvers::interp}) {
        const testing::Outcome x = testing::simulate(between, 2.0, 0.0, s), y = testing::simulate(scaled, 2.0, 0.0, s);
        ASSERT_GE(x.events.size(), 6u);
        const double gap = event_gap(x, y);
        std::printf("%s: %zu events, %.3g s apart\n", testing::solvers_name(s), x.events.size(), gap);
        EXPECT_LT(gap, 1e-12);
    }
}

TEST(Direction, AScaledDirectionIsTheContactBetweenTwoBodies) {
    // u = 2 w4 >= 2 g with k / 4 is w4 - ground >= g with k: the same force
    // k (w4 - g) when closed, the same instants.
    testing::TempDir a, b;
    const Model between = read_model(breathing_crack(
        a, "[[contact]]\nname = \"stop\"\nbetween = [\"w4\", \"ground\"]\ngap = 0.004\nk = 2000.0\n"));
    const Model scaled =
        read_model(breathing_crack(b, "[[contact]]\nname = \"stop\"\ndirection = { w4 = 2.0 }\ngap = 0.008\nk = 500.0\n"));
    expect_the_same_instants(between, scaled);
}

/// The period map's exact Jacobian over one forcing period from rest, on the
/// cracked cantilever with `element`, against central differences.
void expect_tangent_matches_central_differences(const char* element) {
    testing::TempDir dir;
    const Model model = read_model(breathing_crack(dir, element));
    analysis::FlowKernels kernels;
    kernels.kernels = KernelChoice::eigen;
    analysis::Flow flow(model, kernels, "test");
    std::size_t events = 0;
    const Eigen::VectorXd rest =
        Eigen::VectorXd::Zero(static_cast<Eigen::Index>(2 * model.dof() + model.jenkins.size()));
    const double off = off_central_differences(flow, 2 * M_PI / 20.0, rest, events);
    std::printf("%zu events a period, |J - central differences| / |J| = %.3g\n", events, off);
    EXPECT_GE(events, 2u);
    EXPECT_LT(off, 1e-6);
}

TEST(Direction, ThePeriodMapsExactJacobianMatchesCentralDifferences) {
    // The tangent's gradient of the crack's gap function is w (saltation at
    // each closing and opening), over one forcing period from rest.
    expect_tangent_matches_central_differences(kCrack);
}

TEST(Direction, JitAndInterpreterWriteTheSameBytesOnADirection) {
    testing::TempDir dir;
    const std::string path = "'" + breathing_crack(dir, kCrack) + "'";
    const std::string interp = testing::events_csv(path, "--t-end 0.5 --kernels interp");
    EXPECT_GE(std::count(interp.begin(), interp.end(), '\n'), 3);
    EXPECT_EQ(interp, testing::events_csv(path, "--t-end 0.5 --no-cache --kernels jit"));
}

TEST(Direction, BadDirectionsAreRefusedByKey) {
    testing::TempDir dir;
    struct Case {
        std::string contact, says;
    };
    const std::vector<Case> cases = {
        {"direction = { tL = -0.05, tR = 0.05 }\nbetween = [\"w4\", \"ground\"]", "not both"},
        {"direction = { tL = 0.0, tR = 0.05 }", "'contact[1].direction.tL': a weight of 0"},
        {"direction = { tX = 1.0 }", "'contact[1].direction.tX': unknown dof 'tX'"},
        {"direction = { ground = 1.0 }", "leave it out"},
        {"direction = {}", "contact[1].direction"},
        {"direction = [\"tL\", \"tR\"]", "contact[1].direction"},
        {"direction = { tL = \"a\" }", "contact[1].direction.tL"},
    };
    for (const Case& c : cases) {
        const std::string path =
            breathing_crack(dir, "[[contact]]\nname = \"crack\"\n" + c.contact + "\ngap = 2e-5\nk = 4e6\n");
        const testing::CliRun r = testing::run_hsnc("check '" + path + "'");
        EXPECT_EQ(r.exit_code, 2) << c.contact;
        EXPECT_NE(r.err.find(c.says), std::string::npos) << c.contact << " -> " << r.err;
        EXPECT_NE(r.err.find("crack.toml"), std::string::npos) << r.err;
    }
}

TEST(Direction, ADirectionClosedOnAFloatingPartIsRefusedByName) {
    // k (x1 + x2)^2 holds the pair's common motion and leaves its stretch
    // free: which rigid-body modes remain is not said by the bodies alone.
    testing::TempDir dir;
    write(dir / "float.toml", "name = \"floating\"\n[[mass]]\nname = \"m1\"\nm = 1.0\n[[mass]]\nname = \"m2\"\nm = 1.0\n"
                              "[[spring]]\nbetween = [\"m1\", \"m2\"]\nk = 10.0\n"
                              "[[contact]]\nname = \"c\"\ndirection = { m1 = 1.0, m2 = 1.0 }\ngap = 0.1\nk = 100.0\n"
                              "[initial]\nv = { m1 = 1.0, m2 = 1.0 }\n");
    const std::string out = dir / "trajectory.csv";
    const testing::CliRun r = testing::run_hsnc("simulate '" + (dir / "float.toml") + "' --t-end 1 --out '" + out + "'");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("contact 'c' acts along a direction on 'm1', which floats"), std::string::npos) << r.err;
    EXPECT_FALSE(std::ifstream(out).good());
}

TEST(Direction, SweepKernelsRefuseADirectionByName) {
    testing::TempDir dir;
    const std::string path = breathing_crack(dir, kCrack);
    const testing::CliRun r = testing::run_hsnc("generate '" + path + "' --params all -o '" + (dir / "kernels") + "'");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("contact 'crack' acts along a direction"), std::string::npos) << r.err;
}

TEST(JenkinsOnACoupledMass, TheReferenceSticksOnceWhereTheRelativeRotationTurns) {
    // A joint between the crack's two rotations (k 3000, slip moment 0.6) on
    // the consistent-mass beam. Where it sticks, the stuck configuration's
    // slip function starts at the slip force to the rounding of the slider
    // just set; the reference once evaluated it from the modal reconstruction
    // of the start state, off by the modal transformation's rounding times
    // its condition (1.6 times its noise at 30 digits), released at once and
    // chattered (stick, release, ... 1000 times at one instant) up to 34
    // digits. It now starts from the state carried in: 30 and 60 digits and
    // the Eigen solver see the same 26 events.
    testing::TempDir dir;
    const Model model = read_model(breathing_crack(
        dir, "[[jenkins]]\nname = \"joint\"\nbetween = [\"tR\", \"tL\"]\nk = 3000.0\nslip_force = 0.6\n"));
    const std::vector<testing::Recorded> r30 = reference_events(model, 30, 2.0), r60 = reference_events(model, 60, 2.0);
    const testing::Outcome eigen = testing::simulate(model, 2.0);
    ASSERT_EQ(eigen.events.size(), 26u);
    const double self = event_gap(r30, r60), eigen_off = event_gap(eigen.events, r30);
    std::printf("%zu events at 30 digits, %.3g s from 60 digits, the Eigen solver %.3g s\n", r30.size(), self,
                eigen_off);
    EXPECT_LT(self, 1e-20);
    EXPECT_LT(eigen_off, 1e-11);
}

TEST(JenkinsDirection, AFrictionJointOnARelativeRotationGivesTheEventsOfCvodeAndTheReference) {
    testing::TempDir dir;
    const Model model = read_model(breathing_crack(dir, kJoint));
    ASSERT_TRUE(model.jenkins[0].direction().weighted());
    expect_events_of_cvode_and_the_reference(model);
}

// One Jenkins element written twice: between w4 and the ground (k, F_s),
// and along u = 2 w4 (k / 4, F_s / 2).
const char* kJointBetween = "[[jenkins]]\nname = \"j\"\nbetween = [\"w4\", \"ground\"]\nk = 2000.0\nslip_force = 2.0\n";
const char* kJointScaled = "[[jenkins]]\nname = \"j\"\ndirection = { w4 = 2.0 }\nk = 500.0\nslip_force = 1.0\n";

TEST(JenkinsDirection, AScaledDirectionIsTheElementBetweenTwoBodies) {
    // u = 2 w4 with k / 4 and F_s / 2 is w4 - ground with k and F_s: stuck,
    // the force on w4 is 2 (k/4) (2 w4 - s') = k (w4 - s'/2); it slips where
    // (k/4) |2 w4 - s'| = F_s / 2, i.e. k |w4 - s'/2| = F_s, and then pushes
    // with 2 F_s / 2 = F_s: the same motion, the same instants.
    testing::TempDir a, b;
    const Model between = read_model(breathing_crack(a, kJointBetween)),
                scaled = read_model(breathing_crack(b, kJointScaled));
    expect_the_same_instants(between, scaled);
}

TEST(JenkinsDirection, OrbitsAndExponentsOfAScaledDirectionAreThoseOfTheElementBetweenTwoBodies) {
    // The two writings of one element: the same periodic orbit (its slider at
    // twice the position on u = 2 w4) and the same Floquet multipliers, on the
    // Eigen solver and the programs; Lyapunov exponents that converge to each
    // other (a finite time's depend on the slider's scale, below).
    testing::TempDir a, b;
    const Model between = read_model(breathing_crack(a, kJointBetween)),
                scaled = read_model(breathing_crack(b, kJointScaled));
    for (KernelChoice kernels : {KernelChoice::eigen, KernelChoice::generic}) {
        PeriodicOptions o;
        o.kernels = kernels;
        o.transient = 4.0;
        const PeriodicResult p = periodic(between, o), q = periodic(scaled, o);
        ASSERT_EQ(p.status, PeriodicStatus::ok) << p.message;
        ASSERT_EQ(q.status, PeriodicStatus::ok) << q.message;
        EXPECT_GE(p.events, 2u) << "the joint should stick and slip on the orbit";
        EXPECT_EQ(p.events, q.events);
        double dx = 0.0;
        for (std::size_t i = 0; i < p.x.size(); ++i)
            dx = std::max({dx, std::fabs(p.x[i] - q.x[i]), std::fabs(p.v[i] - q.v[i]) / 20.0});
        ASSERT_EQ(p.multipliers.size(), q.multipliers.size());
        auto by_size = [](std::vector<std::complex<double>> mu) {
            std::sort(mu.begin(), mu.end(), [](auto x, auto y) {
                return std::abs(x) != std::abs(y) ? std::abs(x) > std::abs(y) : x.imag() > y.imag();
            });
            return mu;
        };
        const auto mp = by_size(p.multipliers), mq = by_size(q.multipliers);
        double dmu = 0.0;
        for (std::size_t k = 0; k < mp.size(); ++k) dmu = std::max(dmu, std::abs(mp[k] - mq[k]));
        // Lyapunov exponents over a finite time T depend on the scale of the
        // state (here the slider's: 2) by O(ln 2 / T); they converge as T
        // grows. Over T and 4 T the differences must shrink about fourfold.
        double dl[2] = {0.0, 0.0}, largest = 0.0;
        for (int r = 0; r < 2 && kernels == KernelChoice::generic; ++r) {  // the analysis is the same on either
            LyapunovOptions lo;
            lo.kernels = kernels;
            lo.t_end = r == 0 ? 5.0 : 20.0;
            const LyapunovResult lp = lyapunov(between, lo), lq = lyapunov(scaled, lo);
            ASSERT_EQ(lp.status, RunStatus::ok) << lp.message;
            ASSERT_EQ(lq.status, RunStatus::ok) << lq.message;
            ASSERT_EQ(lp.exponents.size(), lq.exponents.size());
            for (std::size_t k = 0; k < lp.exponents.size(); ++k)
                dl[r] = std::max(dl[r], std::fabs(lp.exponents[k] - lq.exponents[k]));
            largest = lp.exponents[0];
        }
        std::printf(
            "%s: orbit with %zu events, states %.3g apart, sliders %.9g and %.9g, multipliers %.3g apart "
            "(largest %.6f)\n",
            kernels == KernelChoice::eigen ? "eigen" : "programs", p.events, dx, p.s[0], q.s[0], dmu, p.max_multiplier);
        EXPECT_LT(dx, 1e-9);
        EXPECT_NEAR(q.s[0], 2.0 * p.s[0], 1e-9);
        EXPECT_LT(dmu, 1e-8);
        if (kernels == KernelChoice::eigen) continue;
        std::printf("exponents %.3g apart over 5 s, %.3g over 20 s (largest %.6f /s)\n", dl[0], dl[1], largest);
        EXPECT_LT(dl[0], 2 * std::log(2.0) / 5.0);
        EXPECT_LT(dl[1], 0.4 * dl[0]);
    }
}

TEST(JenkinsDirection, TheDampedModeOfAScaledDirectionIsThatOfTheElementBetweenTwoBodies) {
    // The first damped mode (EPMC) of the cracked cantilever with the joint on
    // w4, written both ways: through stick (below 1e-3 at w4 the joint holds)
    // into slip, the same frequency and damping ratio at every amplitude.
    testing::TempDir a, b;
    const Model between = read_model(breathing_crack(a, kJointBetween)),
                scaled = read_model(breathing_crack(b, kJointScaled));
    ModesOptions o;
    o.dof = "w4";
    o.from = 5e-4;
    o.to = 2e-3;
    o.points = 4;
    o.kernels = KernelChoice::generic;
    const ModesResult p = modes(between, o), q = modes(scaled, o);
    ASSERT_EQ(p.status, ModesStatus::ok) << p.message;
    ASSERT_EQ(q.status, ModesStatus::ok) << q.message;
    ASSERT_EQ(p.points.size(), q.points.size());
    ASSERT_EQ(p.points.size(), 4u);
    double d_omega = 0.0, d_zeta = 0.0;
    for (std::size_t k = 0; k < p.points.size(); ++k) {
        EXPECT_NEAR(p.points[k].amplitude, q.points[k].amplitude, 1e-15);
        d_omega = std::max(d_omega, std::fabs(p.points[k].omega - q.points[k].omega) / p.points[k].omega);
        d_zeta = std::max(d_zeta, std::fabs(p.points[k].damping_ratio - q.points[k].damping_ratio));
    }
    const ModePoint &first = p.points.front(), &last = p.points.back();
    std::printf(
        "%zu points: omega %.6f -> %.6f rad/s, damping ratio %.5f -> %.5f; the two writings %.3g (omega, "
        "relative) and %.3g (ratio) apart\n",
        p.points.size(), first.omega, last.omega, first.damping_ratio, last.damping_ratio, d_omega, d_zeta);
    EXPECT_LT(last.omega, first.omega) << "slip in the joint should soften the mode";
    EXPECT_GT(last.damping_ratio, first.damping_ratio) << "and damp it";
    EXPECT_LT(d_omega, 1e-9);
    EXPECT_LT(d_zeta, 1e-9);
}

TEST(JenkinsDirection, AStuckJointStampsKWwTAndItsSlidersPreload) {
    // Stuck, the joint adds k w w^T to K and k s w to the constant force
    // (assembly.h, the pair links of direction.h); slipping, the force
    // -slip F_s w and nothing to K.
    testing::TempDir dir;
    const Model model = read_model(breathing_crack(dir, kJoint));
    Configuration stuck = Configuration::all_open(model), slipping = stuck;
    slipping.slip[0] = 1;
    Eigen::VectorXd w = Eigen::VectorXd::Zero(9);
    w(3) = -1.0, w(4) = 1.0;
    const Eigen::MatrixXd dK = stiffness_matrix(model, stuck) - stiffness_matrix(model, slipping);
    EXPECT_LT((dK - 3000.0 * w * w.transpose()).norm(), 1e-12 * 3000.0);
    std::vector<double> state(model.state_size(), 0.0);
    state[model.dof()] = 0.01;  // the slider
    Eigen::VectorXd f_stuck = Eigen::VectorXd::Zero(9), f_slip = Eigen::VectorXd::Zero(9);
    constant_of(
        model, stuck, ElementKind::jenkins, 0,
        [&](int i, int j, double f) {
            if (i != kGround) f_stuck(i) += f;
            if (j != kGround) f_stuck(j) -= f;
        },
        state.data() + model.dof());
    constant_of(
        model, slipping, ElementKind::jenkins, 0,
        [&](int i, int j, double f) {
            if (i != kGround) f_slip(i) += f;
            if (j != kGround) f_slip(j) -= f;
        },
        state.data() + model.dof());
    EXPECT_LT((f_stuck - 3000.0 * 0.01 * w).norm(), 1e-15 * 30.0);
    EXPECT_LT((f_slip + 0.6 * w).norm(), 1e-15);
}

TEST(JenkinsDirection, JitAndInterpreterWriteTheSameBytes) {
    testing::TempDir dir;
    const std::string path = "'" + breathing_crack(dir, kJoint) + "'";
    const std::string interp = testing::events_csv(path, "--t-end 0.5 --kernels interp");
    EXPECT_GE(std::count(interp.begin(), interp.end(), '\n'), 3);
    EXPECT_EQ(interp, testing::events_csv(path, "--t-end 0.5 --no-cache --kernels jit"));
}

TEST(JenkinsDirection, ThePeriodMapsExactJacobianMatchesCentralDifferences) {
    // The joint's stick and slip switches along w, saltation at each, over
    // one forcing period from rest.
    expect_tangent_matches_central_differences(kJoint);
}

TEST(JenkinsDirection, InputAndFloatingPartsAreRefused) {
    testing::TempDir dir;
    struct Case {
        std::string element, says;
    };
    const std::vector<Case> cases = {
        {"direction = { tL = -1.0, tR = 1.0 }\nbetween = [\"w4\", \"ground\"]", "not both"},
        {"direction = { tL = 0.0, tR = 1.0 }", "'jenkins[1].direction.tL': a weight of 0"},
        {"direction = { tX = 1.0 }", "'jenkins[1].direction.tX': unknown dof 'tX'"},
    };
    for (const Case& c : cases) {
        const std::string path =
            breathing_crack(dir, "[[jenkins]]\nname = \"joint\"\n" + c.element + "\nk = 3000.0\nslip_force = 0.6\n");
        const testing::CliRun r = testing::run_hsnc("check '" + path + "'");
        EXPECT_EQ(r.exit_code, 2) << c.element;
        EXPECT_NE(r.err.find(c.says), std::string::npos) << c.element << " -> " << r.err;
    }
    // Stuck at t0, k (x1 + x2)^2 on a pair with no spring to the ground: refused as a contact's.
    write(dir / "float.toml",
          "name = \"floating\"\n[[mass]]\nname = \"m1\"\nm = 1.0\n[[mass]]\nname = \"m2\"\nm = 1.0\n"
          "[[spring]]\nbetween = [\"m1\", \"m2\"]\nk = 10.0\n"
          "[[jenkins]]\nname = \"j\"\ndirection = { m1 = 1.0, m2 = 1.0 }\nk = 100.0\n"
          "slip_force = 1.0\n[initial]\nv = { m1 = 1.0, m2 = 1.0 }\n");
    const std::string out = dir / "trajectory.csv";
    const testing::CliRun r =
        testing::run_hsnc("simulate '" + (dir / "float.toml") + "' --t-end 1 --out '" + out + "'");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("Jenkins element 'j' acts along a direction on 'm1', which floats"), std::string::npos)
        << r.err;
    EXPECT_FALSE(std::ifstream(out).good());
}

TEST(JenkinsDirection, CheckSaysWhatTheElementActsAlong) {
    testing::TempDir dir;
    const testing::CliRun r = testing::run_hsnc("check '" + breathing_crack(dir, kJoint) + "'");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("joint  along -1 tL 1 tR  k = 3000"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace hsnc
