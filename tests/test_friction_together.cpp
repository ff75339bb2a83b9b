// Frictions decided together (issue 36, "the exact multi-friction decision";
// runtime/engine/transition_rules.h decide_together). On a coupled M the
// force that holds one friction still depends on how the others move, so
// deciding them in turn, each with the others as they stand, depends on the
// order of the dofs and can leave one sliding that the stick rule holds once
// the others have been decided. Two dofs a, b with
//     M = [1 0.9; 0.9 1],   loads f = (-0.5, 0.7),   mu_s N = 0.8 each,
// at rest at x = 0: held together, each friction holds its own load
// (a = 0, so D = f: 0.5 and 0.7, both within 0.8) and nothing moves. In
// turn, a decided first with b free of friction would need
// D_a = f_a - M_ab f_b / M_bb = -1.13 and slide. The closed form of the
// right answer is rest: x(t) = 0 for every t.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "engine_runner.h"
#include "fe_models.h"
#include "model_reader.h"
#include "temp_dir.h"
#include "transitions.h"

namespace hsnc {
namespace {

using fe::structure_model;

const char* const kFrictions =
    "[[friction]]\nname = \"fa\"\nbetween = [\"a\", \"ground\"]\nmu_k = 0.3\nmu_s = 0.8\nnormal = 1.0\n"
    "[[friction]]\nname = \"fb\"\nbetween = [\"b\", \"ground\"]\nmu_k = 0.3\nmu_s = 0.8\nnormal = 1.0\n"
    "[load]\na = -0.5\nb = 0.7\n";

Eigen::Matrix2d mass_matrix() {
    Eigen::Matrix2d M;
    M << 1.0, 0.9, 0.9, 1.0;
    return M;
}
Eigen::Matrix2d stiffness_matrix() {
    Eigen::Matrix2d K;
    K << 150.0, -50.0, -50.0, 120.0;
    return K;
}

/// The two-dof model, its dofs in the order `dofs` ({"a", "b"} or {"b", "a"}),
/// with `extra` TOML (forcing) appended.
std::string pair_model(const testing::TempDir& dir, const std::vector<std::string>& dofs, const std::string& extra) {
    Eigen::Matrix2d M = mass_matrix(), K = stiffness_matrix();
    if (dofs.front() == "b") {  // the same structure with its dofs swapped
        const Eigen::Matrix2d P = (Eigen::Matrix2d() << 0, 1, 1, 0).finished();
        M = P * M * P, K = P * K * P;
    }
    return structure_model(dir, "pair.toml", "coupled-pair", M, K, dofs, std::string(kFrictions) + extra);
}

TEST(FrictionTogether, TheCaseDiscriminates) {
    // Independently of the engine: held together both frictions hold (a = 0,
    // each holds its own load); decided in turn from a with b free of friction,
    // a would slide.
    const Eigen::Matrix2d M = mass_matrix();
    const Eigen::Vector2d f(-0.5, 0.7);
    const double limit = 0.8;
    EXPECT_LE(std::fabs(f(0)), limit);
    EXPECT_LE(std::fabs(f(1)), limit);
    const double a_alone = f(0) - M(0, 1) * f(1) / M(1, 1);
    EXPECT_GT(std::fabs(a_alone), limit);
}

TEST(FrictionTogether, TwoFrictionsAtRestOnACoupledMassStayTogetherWhateverTheOrderOfTheDofs) {
    for (const std::vector<std::string>& dofs :
         {std::vector<std::string>{"a", "b"}, std::vector<std::string>{"b", "a"}}) {
        testing::TempDir dir;
        const Model m = read_model(pair_model(dir, dofs, ""));
        ASSERT_TRUE(m.coupled_mass());
        std::vector<signed char> sgn;
        const std::vector<double> x0(2, 0.0), v0(2, 0.0);
        const Configuration cfg = entered_configuration(m, 0.0, x0.data(), v0.data(), sgn);
        EXPECT_EQ(cfg.stuck, (std::vector<char>{1, 1})) << "dofs " << dofs[0] << ", " << dofs[1];
        for (testing::Solvers solvers : {testing::Solvers::generic, testing::Solvers::interp}) {
            const testing::Outcome run = testing::simulate(m, 2.0, 0.05, solvers);
            EXPECT_TRUE(run.events.empty()) << run.events.size() << " events; the first at t = " << run.events[0].t;
            ASSERT_FALSE(run.samples.empty());
            for (const testing::Recorded& s : run.samples) {
                EXPECT_EQ(s.x[0], 0.0) << "t = " << s.t;
                EXPECT_EQ(s.x[1], 0.0) << "t = " << s.t;
            }
        }
        EXPECT_TRUE(fe::reference_events(m, 30, 2.0).empty());
    }
}

TEST(FrictionTogether, ForcedFromRestTheyReleaseAndStickAsTheReferenceSays) {
    // A force on b: both stuck at t0 (decided together), then released,
    // stuck again and so on; the programs and the Eigen solver against the
    // CLN reference at 30 and 60 digits and CVODE, in both orders of the dofs.
    std::vector<testing::Recorded> first;
    std::vector<std::string> first_names;
    for (const std::vector<std::string>& dofs :
         {std::vector<std::string>{"a", "b"}, std::vector<std::string>{"b", "a"}}) {
        testing::TempDir dir;
        const Model m = read_model(pair_model(dir, dofs, "[[forcing]]\nomega = 3.0\namplitude = { b = 1.5 }\n"));
        const double t_end = 6.0;
        const testing::Outcome programs = testing::simulate(m, t_end, 0.0, testing::Solvers::interp),
                               eigen = testing::simulate(m, t_end, 0.0, testing::Solvers::generic);
        ASSERT_GE(programs.events.size(), 6u);
        EXPECT_EQ(programs.events[0].kind, EventKind::release) << "both are held at t0: the first event is a release";
        int stick = 0, release = 0;
        for (const testing::Recorded& e : programs.events)
            stick += e.kind == EventKind::stick, release += e.kind == EventKind::release;
        EXPECT_GE(stick, 2);
        EXPECT_GE(release, 2);
        const std::vector<testing::Recorded> r30 = fe::reference_events(m, 30, t_end),
                                             r60 = fe::reference_events(m, 60, t_end);
        const testing::Outcome cvode = testing::baseline(m, t_end, 1e-12, 1e-14, Method::cvode);
        const double to_eigen = fe::event_gap(programs, eigen), to_ref = fe::event_gap(programs.events, r30),
                     digits = fe::event_gap(r30, r60), to_cvode = fe::event_gap(programs, cvode);
        std::printf(
            "dofs %s, %s: %zu events (stick %d, release %d); the programs within %.3g s of the Eigen solver, "
            "%.3g s of the reference, 30 against 60 digits %.3g s, CVODE %.3g s\n",
            dofs[0].c_str(), dofs[1].c_str(), programs.events.size(), stick, release, to_eigen, to_ref, digits,
            to_cvode);
        EXPECT_LT(to_eigen, 1e-12);
        EXPECT_LT(to_ref, 1e-12);
        EXPECT_LT(digits, 1e-20);
        EXPECT_LT(to_cvode, 1e-8);
        // The other order of the dofs: the same events, each friction by its dof's name.
        std::vector<std::string> names;
        for (const testing::Recorded& e : programs.events)
            names.push_back(m.masses[static_cast<std::size_t>(e.element)].name);
        if (first.empty()) {
            first = programs.events, first_names = names;
            continue;
        }
        ASSERT_EQ(programs.events.size(), first.size());
        for (std::size_t e = 0; e < first.size(); ++e) {
            EXPECT_EQ(programs.events[e].kind, first[e].kind) << "event " << e;
            EXPECT_EQ(names[e], first_names[e]) << "event " << e;
            EXPECT_NEAR(programs.events[e].t, first[e].t, 1e-12) << "event " << e;
        }
    }
}

}  // namespace
}  // namespace hsnc
