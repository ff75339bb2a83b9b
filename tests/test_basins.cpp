// Basins of attraction (hsnc sweep over the initial state: --param x0.DOF
// --param2 v0.DOF --restart-each, hsnc::classify_attractors): the
// bistable hardening oscillator at 1.3 rad/s, whose two stable orbits are
// found by hsnc periodic (the README's orbit, and one from rest); the
// basins' fractions hold under grid refinement, and the outputs are the
// same bytes for 1 and 2 threads, two parts merged and 2 MPI ranks.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "cli_runner.h"
#include "hsnc/periodic.h"
#include "hsnc/sweep.h"
#include "model_reader.h"

namespace hsnc {
namespace {

using testing::run_hsnc;
using testing::slurp;
using testing::temp_path;

const std::string kHardening = std::string(HSNC_SOURCE_DIR) + "/examples/hardening-stop.toml";

SweepOptions grid(std::size_t points) {
    SweepOptions o;
    o.param = "x0.m";
    o.from = -3;
    o.to = 3;
    o.points = points;
    o.param2 = "v0.m";
    for (std::size_t j = 0; j < points; ++j)
        o.values2.push_back(-3 + 6 * static_cast<double>(j) / static_cast<double>(points - 1));
    o.restart_each = true;
    o.max_periods = 3000;
    o.threads = 2;
    return o;
}

TEST(Basins, BistableHardeningOscillatorAttractorsAndFractions) {
    const std::string text = slurp(kHardening);
    const ModelOverrides at13{{"omega=1.3"}, {}, {}, {}};
    const Attractors coarse = classify_attractors(SweepPlan(text, "hardening-stop.toml", at13, grid(21)).run());
    const SweepResult fine_run = SweepPlan(text, "hardening-stop.toml", at13, grid(41)).run();
    const Attractors fine = classify_attractors(fine_run);
    ASSERT_EQ(coarse.list.size(), 2u);
    ASSERT_EQ(fine.list.size(), 2u);
    EXPECT_EQ(fine.of_point.size(), 41u * 41u);
    for (int id : fine.of_point) EXPECT_GE(id, 1);  // every point settles on one of the two

    // The two attractors are hsnc periodic's two stable orbits there: the
    // README's upper one (from x = 1.5) and the lower one (from rest).
    for (const std::string& x0 : {std::string("m=1.5"), std::string("m=0")}) {
        Model m = parse_model(text, "hardening-stop.toml", ModelOverrides{{"omega=1.3"}, {x0}, {}, {}});
        PeriodicOptions po;
        po.transient = 300;
        const PeriodicResult orbit = periodic(m, po);
        ASSERT_EQ(orbit.status, PeriodicStatus::ok) << orbit.message;
        EXPECT_TRUE(orbit.stable);
        int matches = 0;
        for (const Attractor& a : fine.list)
            if (a.multiple == 1 && std::fabs(a.x[0] - orbit.x[0]) < 1e-7 && std::fabs(a.v[0] - orbit.v[0]) < 1e-7)
                ++matches;
        EXPECT_EQ(matches, 1) << x0 << ": " << orbit.x[0] << " " << orbit.v[0];
    }
    // Fractions stable under refinement (21 x 21 against 41 x 41), each
    // attractor numbered in the order of its first point on both grids.
    for (std::size_t k = 0; k < 2; ++k) {
        EXPECT_NEAR(coarse.list[k].x[0], fine.list[k].x[0], 1e-7);
        const double fc = static_cast<double>(coarse.list[k].points) / (21.0 * 21.0),
                     ff = static_cast<double>(fine.list[k].points) / (41.0 * 41.0);
        EXPECT_NEAR(fc, ff, 0.03) << k;
        EXPECT_GT(ff, 0.1);
    }
}

// The command line: threads, parts and MPI ranks give the same bytes; the
// attractors CSV, the attractor column and the picture; refusals.
TEST(BasinsCli, SameBytesForAnySplitAndRefusals) {
    const std::string args = "sweep '" + kHardening + "' --set omega=1.3 --param x0.m --from -3 --to 3 --points 15 " +
                             "--param2 v0.m --values2=-3:3:15 --restart-each --max-periods 3000 --quiet ";
    const std::string c1 = temp_path("b1.csv"), a1 = temp_path("a1.csv"), png = temp_path("basins.png");
    const auto r = run_hsnc(args + "--threads 1 --out '" + c1 + "' --attractors '" + a1 + "' --plot '" + png + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find(" attractors=2"), std::string::npos) << r.out;
    const std::string curve = slurp(c1), attractors = slurp(a1);
    EXPECT_EQ(curve.substr(0, curve.find('\n')),
              "x0.m,direction,settled,periods,multiple,xmax_m,xrms_m,a1_m,v0.m,attractor");
    EXPECT_EQ(attractors.substr(0, attractors.find('\n')), "attractor,multiple,points,fraction,x_m,v_m");
    EXPECT_EQ(std::count(attractors.begin(), attractors.end(), '\n'), 3);
    EXPECT_EQ(slurp(png).substr(1, 3), "PNG");

    const std::string c2 = temp_path("b2.csv"), a2 = temp_path("a2.csv");
    ASSERT_EQ(run_hsnc(args + "--threads 2 --out '" + c2 + "' --attractors '" + a2 + "'").exit_code, 0);
    EXPECT_EQ(slurp(c2), curve);
    EXPECT_EQ(slurp(a2), attractors);

    const std::string p1 = temp_path("part1"), p2 = temp_path("part2"), c3 = temp_path("b3.csv"),
                      a3 = temp_path("a3.csv");
    ASSERT_EQ(run_hsnc(args + "--part 1/2 --part-out '" + p1 + "'").exit_code, 0);
    ASSERT_EQ(run_hsnc(args + "--part 2/2 --part-out '" + p2 + "'").exit_code, 0);
    const auto m = run_hsnc("sweep-merge '" + p1 + "' '" + p2 + "' --out '" + c3 + "' --attractors '" + a3 + "'");
    ASSERT_EQ(m.exit_code, 0) << m.err;
    EXPECT_EQ(slurp(c3), curve);
    EXPECT_EQ(slurp(a3), attractors);

    if (HSNC_WITH_MPI) {
        const std::string c4 = temp_path("b4.csv"), a4 = temp_path("a4.csv"), log = temp_path("mpi.log");
        const int status =
            std::system(("mpirun --allow-run-as-root --oversubscribe -np 2 '" + std::string(HSNC_BINARY) + "' " + args +
                         "--out '" + c4 + "' --attractors '" + a4 + "' >'" + log + "' 2>&1")
                            .c_str());
        ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp(log);
        EXPECT_EQ(slurp(c4), curve);
        EXPECT_EQ(slurp(a4), attractors);
    }

    // Refused: a state coordinate without --restart-each or with
    // --continuation, --attractors without two state coordinates, a bad range.
    const std::string base = "sweep '" + kHardening + "' --set omega=1.3 --points 5 --quiet ";
    for (const std::string& bad :
         {std::string("--param x0.m --from -1 --to 1"), std::string("--param x0.m --from -1 --to 1 --continuation"),
          std::string("--param F --from 0.1 --to 0.2 --attractors '" + temp_path("x.csv") + "'"),
          std::string("--param x0.m --from -1 --to 1 --restart-each --param2 v0.m --values2=1:2:0"),
          std::string("--param x0.nobody --from -1 --to 1 --restart-each")}) {
        const std::string out = temp_path("bad.csv");
        const auto b = run_hsnc(base + bad + " --out '" + out + "'");
        EXPECT_EQ(b.exit_code, 2) << bad << "\n" << b.err;
        EXPECT_FALSE(testing::file_exists(out)) << bad;
    }
}

}  // namespace
}  // namespace hsnc
