// Basins of attraction (hsnc sweep over the initial state: --param x0.DOF
// --param2 v0.DOF --restart-each, hsnc::classify_attractors): the
// bistable hardening oscillator at 1.3 rad/s, whose two stable orbits are
// found by hsnc periodic (the README's orbit, and one from rest); the
// basins' fractions hold under grid refinement, and the outputs are the
// same bytes for 1 and 2 threads, two parts merged and 2 MPI ranks. Beyond
// periodic orbits: the bilinear cascade's coexisting period-4 and
// period-12 orbits (a subharmonic beyond the sweep's settling test) and its
// chaotic attractor (a positive Lyapunov exponent), and points escaping an
// undamped resonance.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "hsnc/lyapunov.h"
#include "hsnc/periodic.h"
#include "hsnc/sweep.h"
#include "model_reader.h"

namespace hsnc {
namespace {

using testing::run_hsnc;
using testing::slurp;
using testing::temp_path;

const std::string kHardening = std::string(HSNC_SOURCE_DIR) + "/examples/hardening-stop.toml";
const std::string kCascade = std::string(HSNC_SOURCE_DIR) + "/examples/bilinear-cascade.toml";

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

// The bilinear oscillator x'' + 0.1 x' + x + 50 max(x, 0) = sin(omega t)
// at omega = 2.64, just before its period-4 orbit doubles: that orbit and
// a stable period-12 orbit (found by no sweep's settling test, which stops
// at period 8) share the plane of initial states; hsnc periodic confirms
// both from the listed canonical states. At omega = 2.7 every initial
// state reaches one chaotic set (hsnc lyapunov: the largest exponent > 0).
TEST(Basins, CascadeSubharmonicBeyondEightAndChaoticSet) {
    const std::string text = slurp(kCascade);
    SweepOptions o = grid(15);
    o.max_periods = 1000;
    o.record_periods = 64;
    const Attractors two = classify_attractors(
        SweepPlan(text, "bilinear-cascade.toml", ModelOverrides{{"omega=2.64"}, {}, {}, {}}, o).run());
    ASSERT_EQ(two.list.size(), 2u);
    for (int id : two.of_point) EXPECT_GE(id, 1);
    std::vector<int> periods;
    for (const Attractor& a : two.list) {
        periods.push_back(a.multiple);
        EXPECT_GT(a.points, 15u);
        Model m = parse_model(
            text, "bilinear-cascade.toml",
            ModelOverrides{{"omega=2.64"}, {"m=" + std::to_string(a.x[0])}, {"m=" + std::to_string(a.v[0])}, {}});
        PeriodicOptions po;
        po.harmonic = a.multiple;
        const PeriodicResult orbit = periodic(m, po);
        ASSERT_EQ(orbit.status, PeriodicStatus::ok) << a.multiple << ": " << orbit.message;
        EXPECT_TRUE(orbit.stable) << a.multiple;
        EXPECT_NEAR(orbit.x[0], a.x[0], 1e-6) << a.multiple;
        EXPECT_NEAR(orbit.v[0], a.v[0], 1e-6) << a.multiple;
        // Not an orbit of a shorter period: the same start over a third
        // (period 12) or half (period 4) of it finds another state, or none.
        po.harmonic = a.multiple == 12 ? 4 : 2;
        const PeriodicResult shorter = periodic(m, po);
        if (shorter.status == PeriodicStatus::ok) EXPECT_GT(std::fabs(shorter.x[0] - orbit.x[0]), 1e-3) << a.multiple;
    }
    std::sort(periods.begin(), periods.end());
    EXPECT_EQ(periods, (std::vector<int>{4, 12}));

    const ModelOverrides at27{{"omega=2.7"}, {}, {}, {}};
    const SweepResult chaos = SweepPlan(text, "bilinear-cascade.toml", at27, o).run();
    const Attractors one = classify_attractors(chaos);
    ASSERT_EQ(one.list.size(), 1u);
    EXPECT_EQ(one.list[0].multiple, 0);  // a set, not a periodic orbit
    EXPECT_EQ(one.list[0].points, 15u * 15u);
    for (const SweepPoint& p : chaos.points) EXPECT_FALSE(p.settled);
    LyapunovOptions lo;
    lo.t_end = 2000;
    lo.transient = 200;
    const LyapunovResult ly = lyapunov(parse_model(text, "bilinear-cascade.toml", at27), lo);
    EXPECT_GT(ly.exponents[0], 0.05);
    EXPECT_NEAR(ly.exponents[0] + ly.exponents[1], -0.1, 1e-9);  // the trace of the damping
}

// An undamped oscillator forced at resonance grows without bound: with
// --escape R every point stops as escaped once |x| > R at a period's end,
// as x(t) = -t cos(t) / 2 says (|x| at t = 2 pi k is pi k), attractor -2.
TEST(BasinsCli, EscapeAtAnUndampedResonance) {
    const std::string model = temp_path("resonance.toml");
    {
        std::ofstream f(model);
        f << "name = \"resonance\"\n[[mass]]\nname = \"m\"\nm = 1.0\n[[spring]]\nbetween = [\"ground\", \"m\"]\n"
             "k = 1.0\n[[forcing]]\nomega = 1.0\namplitude = { m = 1.0 }\n";
    }
    const std::string args = "sweep '" + model + "' --param x0.m --from -0.5 --to 0.5 --points 3 --param2 v0.m " +
                             "--values2=-0.5:0.5:3 --restart-each --max-periods 1000 --quiet --escape 30 ";
    const std::string c = temp_path("esc.csv"), a = temp_path("esc-attractors.csv");
    const auto r = run_hsnc(args + "--out '" + c + "' --attractors '" + a + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find(" escaped=9 attractors=0"), std::string::npos) << r.out;
    const std::string attractors = slurp(a);
    EXPECT_NE(attractors.find("\n-2,0,9,1,,\n"), std::string::npos) << attractors;
    // From rest (x0 = v0 = 0: the middle point) |x(2 pi k)| = pi k > 30 first at k = 10.
    const std::string curve = slurp(c);
    EXPECT_NE(curve.find("\n0,up,false,10,0,"), std::string::npos) << curve;
    const std::string p1 = temp_path("esc-part1"), p2 = temp_path("esc-part2"), c2 = temp_path("esc2.csv"),
                      a2 = temp_path("esc-attractors2.csv");
    ASSERT_EQ(run_hsnc(args + "--part 1/2 --part-out '" + p1 + "'").exit_code, 0);
    ASSERT_EQ(run_hsnc(args + "--part 2/2 --part-out '" + p2 + "'").exit_code, 0);
    ASSERT_EQ(run_hsnc("sweep-merge '" + p1 + "' '" + p2 + "' --out '" + c2 + "' --attractors '" + a2 + "'").exit_code,
              0);
    EXPECT_EQ(slurp(c2), curve);
    EXPECT_EQ(slurp(a2), attractors);
    for (const std::string& bad : {std::string("--escape -1"), std::string("--escape nan")}) {
        const auto b = run_hsnc(args + bad + " --out '" + temp_path("bad-esc.csv") + "'");
        EXPECT_EQ(b.exit_code, 2) << bad;
        EXPECT_NE(b.err.find("--escape"), std::string::npos) << b.err;
    }
    const auto cont = run_hsnc("sweep '" + kCascade +
                               "' --param omega --from 2 --to 2.1 --points 3 --quiet "
                               "--escape 30 --continuation");
    EXPECT_EQ(cont.exit_code, 2);
    EXPECT_NE(cont.err.find("--escape"), std::string::npos) << cont.err;
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
