// A contact's own damping `c` (a dashpot that acts only while the contact is
// closed): a mass in free flight hitting a spring-dashpot wall leaves it
// after half a damped period with the closed-form coefficient of
// restitution, in every back end; it is non-proportional damping, so the
// state-space path and the matrix exponential carry it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "engine_runner.h"
#include "fe_models.h"
#include "model_reader.h"
#include "temp_dir.h"

namespace hsnc {
namespace {

using namespace fe;

// m = 1 at v0 = 1 toward a wall 0.1 away: k = 100, c = 2 (omega_n = 10,
// zeta = 0.1). In contact x = gap + v0/omega_d e^{-zeta omega_n t} sin(omega_d t),
// so it opens at G = 0 after pi/omega_d with v = -v0 e^{-zeta omega_n pi / omega_d}.
constexpr double kV0 = 1.0, kGap = 0.1, kK = 100.0, kC = 2.0;

std::string wall(const testing::TempDir& dir, const std::string& extra = "") {
    write(dir / "wall.toml", "name = \"damped-wall\"\n[[mass]]\nname = \"m1\"\nm = 1.0\n"
                             "[[contact]]\nname = \"wall\"\nbetween = [\"m1\", \"ground\"]\ngap = " + num(kGap) +
                                 "\nk = " + num(kK) + "\nc = " + num(kC) + "\n[initial]\nv = { m1 = " + num(kV0) + " }\n" +
                                 extra);
    return dir / "wall.toml";
}

TEST(ContactDamping, AnImpactLeavesWithTheClosedFormRestitution) {
    testing::TempDir dir;
    const Model model = read_model(wall(dir));
    ASSERT_FALSE(model.proportional_damping());
    const double wn = std::sqrt(kK), zeta = kC / (2 * wn), wd = wn * std::sqrt(1 - zeta * zeta);
    const double t_open = kGap / kV0 + M_PI / wd, v_out = -kV0 * std::exp(-zeta * wn * M_PI / wd);
    for (testing::Solvers s : {testing::Solvers::generic, testing::Solvers::interp}) {
        const testing::Outcome run = testing::simulate(model, 1.0, 0.0, s);
        ASSERT_EQ(run.events.size(), 2u) << testing::solvers_name(s);
        const testing::Recorded &in = run.events[0], &out = run.events[1];
        std::printf("%s: closes %.3g s off, opens %.3g s off, leaves at %.3g off the closed form\n",
                    testing::solvers_name(s), in.t - kGap / kV0, out.t - t_open, out.v[0] - v_out);
        EXPECT_NEAR(in.t, kGap / kV0, 1e-15);
        EXPECT_NEAR(out.t, t_open, 1e-14);
        EXPECT_NEAR(out.v[0], v_out, 1e-14);
        EXPECT_NEAR(out.x[0], kGap, 1e-15);
    }
    // Without c the same impact is elastic: the damping is the contact's own.
    testing::TempDir plain;
    const Model elastic = read_model(wall(plain));
    Model undamped = elastic;
    undamped.contacts[0].c = 0.0;
    const testing::Outcome e = testing::simulate(undamped, 1.0);
    ASSERT_EQ(e.events.size(), 2u);
    EXPECT_NEAR(e.events[1].v[0], -kV0, 1e-14);
}

TEST(ContactDamping, TheReferenceAndCvodeAgree) {
    // A mass on a spring, forced, against the damped wall: many impacts.
    testing::TempDir dir;
    const Model model = read_model(wall(dir,
                                        "[[spring]]\nbetween = [\"m1\", \"ground\"]\nk = 4.0\n"
                                        "[[forcing]]\nomega = 1.7\namplitude = { m1 = 0.5 }\n"));
    const testing::Outcome exact = testing::simulate(model, 20.0, 0.0, testing::Solvers::interp);
    ASSERT_GE(exact.events.size(), 6u);
    const testing::Outcome cvode = testing::baseline(model, 20.0, 1e-12, 1e-14, Method::cvode);
    const std::vector<testing::Recorded> r30 = reference_events(model, 30, 20.0);
    const double to_reference = event_gap(exact.events, r30), to_cvode = event_gap(exact, cvode);
    std::printf("%zu events: %.3g s from the reference, %.3g s from CVODE\n", exact.events.size(), to_reference,
                to_cvode);
    EXPECT_LT(to_reference, 1e-12);
    EXPECT_LT(to_cvode, 1e-8);
}

TEST(ContactDamping, ThePeriodMapsExactJacobianMatchesCentralDifferences) {
    // The saltation of a closing and an opening carries the jump of the
    // dashpot's force, -(beta k + c) G' along w.
    testing::TempDir dir;
    const Model model = read_model(wall(dir,
                                        "[[spring]]\nbetween = [\"m1\", \"ground\"]\nk = 4.0\n"
                                        "[[forcing]]\nomega = 1.7\namplitude = { m1 = 0.5 }\n"));
    analysis::FlowKernels kernels;
    kernels.kernels = KernelChoice::eigen;
    analysis::Flow flow(model, kernels, "test");
    std::size_t events = 0;
    const double off = off_central_differences(flow, 2 * M_PI / 1.7, Eigen::Vector2d(0.0, 1.0), events);
    std::printf("%zu events a period, |J - central differences| / |J| = %.3g\n", events, off);
    EXPECT_GE(events, 2u);
    EXPECT_LT(off, 1e-6);
}

TEST(ContactDamping, JitAndInterpreterWriteTheSameBytes) {
    testing::TempDir dir;
    const std::string path = "'" + wall(dir, "[[spring]]\nbetween = [\"m1\", \"ground\"]\nk = 4.0\n"
                                             "[[forcing]]\nomega = 1.7\namplitude = { m1 = 0.5 }\n") + "'";
    const std::string interp = testing::events_csv(path, "--t-end 10 --kernels interp");
    EXPECT_GE(std::count(interp.begin(), interp.end(), '\n'), 5);
    EXPECT_EQ(interp, testing::events_csv(path, "--t-end 10 --no-cache --kernels jit"));
}

TEST(ContactDamping, ANegativeCIsRefusedByKey) {
    testing::TempDir dir;
    write(dir / "bad.toml", "name = \"bad\"\n[[mass]]\nname = \"m1\"\nm = 1.0\n"
                            "[[contact]]\nbetween = [\"m1\", \"ground\"]\ngap = 0.1\nk = 100.0\nc = -1.0\n");
    const testing::CliRun r = testing::run_hsnc("check '" + (dir / "bad.toml") + "'");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("'contact[1].c': contact damping must be >= 0"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace hsnc
