// Figures of many dofs (issue 41 item 5): which dofs a figure draws
// (named_dofs, plot_dofs, --plot-dofs), their units by dof kind, and the
// sweep figure's script drawing those and no others.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cli_runner.h"
#include "error.h"
#include "hsnc/sweep.h"
#include "model_reader.h"
#include "plot.h"
#include "sweep_plot.h"
#include "temp_dir.h"

namespace hsnc {
namespace {

const std::string kChain40 = std::string(HSNC_SOURCE_DIR) + "/examples/chain-40/chain-40.toml";

std::vector<std::string> names_of(const Model& m) {
    std::vector<std::string> names;
    for (const Mass& mass : m.masses) names.push_back(mass.name);
    return names;
}

TEST(PlotDofs, ElementsForcingAndFrictionNameTheDofsDrawn) {
    const Model chain = read_model(kChain40);
    EXPECT_EQ(named_dofs(chain), (std::vector<std::size_t>{19, 39}));  // the stop's m20, the forced m40
    EXPECT_EQ(plot_dofs(names_of(chain), "", named_dofs(chain)), (std::vector<std::size_t>{19, 39}));
    // Seed scenario 2 (2 masses): every dof, whatever is named.
    const Model s2 = read_model(std::string(HSNC_SOURCE_DIR) + "/models/seed-scenario-2.toml");
    EXPECT_EQ(plot_dofs(names_of(s2), "", {}), (std::vector<std::size_t>{0, 1}));
    // Nothing named on a large model: the first 8.
    EXPECT_EQ(plot_dofs(names_of(chain), "", {}).size(), kMaxPlotDofs);
    EXPECT_EQ(plot_dofs(names_of(chain), "", {})[7], 7u);
}

TEST(PlotDofs, AListIsCheckedAndKeptInItsOrder) {
    const std::vector<std::string> names = {"w1", "t1", "w2", "t2"};
    EXPECT_EQ(plot_dofs(names, "t2,w1", {}), (std::vector<std::size_t>{3, 0}));
    try {
        plot_dofs(names, "w1,w9", {});
        FAIL() << "an unknown dof must be refused";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "--plot-dofs 'w1,w9': 'w9' is not a dof of the model (its dofs: w1, ..., t2)");
    }
    EXPECT_THROW(plot_dofs(names, "w1,w1", {}), InputError);
    EXPECT_THROW(plot_dofs(names, "w1,", {}), InputError);  // an empty name
    std::vector<std::string> many;
    std::string list;
    for (int i = 1; i <= 9; ++i) many.push_back("m" + std::to_string(i)), list += (i > 1 ? "," : "") + many.back();
    EXPECT_THROW(plot_dofs(many, list, {}), InputError);  // 9 > kMaxPlotDofs
}

TEST(PlotDofs, RotationsAreRadiansByName) {
    for (const char* r : {"t1", "t12", "theta", "theta_2", "th3", "rot", "rot4", "phi1", "psi"})
        EXPECT_EQ(dof_unit(r), "rad") << r;
    for (const char* m : {"m1", "w3", "time", "tip", "x", "rotor1", "airfoil", "platform"})
        EXPECT_EQ(dof_unit(m), "m") << m;
}

// The sweep figure of a 40-dof chain draws the dofs asked for, each with its
// legend entry, and labels rotations in rad.
TEST(PlotDofs, TheSweepFigureDrawsTheChosenDofs) {
    SweepResult r;
    r.model = "beam";
    r.param = "omega";
    r.masses = {"w1", "t1", "w2", "t2"};
    SweepPoint p;
    p.value = 1.0;
    p.settled = true;
    p.xmax = p.xrms = p.a1 = {0.1, 0.2, 0.3, 0.4};
    r.points = {p};
    const std::string mixed = sweep_plot_script(r, "t", {3, 0});
    EXPECT_NE(mixed.find("using 1:5 "), std::string::npos);  // t2: column 2 + 3
    EXPECT_NE(mixed.find("using 1:2 "), std::string::npos);  // w1
    EXPECT_EQ(mixed.find("using 1:3 "), std::string::npos);  // t1 not drawn
    EXPECT_NE(mixed.find("'t2 [rad] up'"), std::string::npos);
    EXPECT_NE(mixed.find("'w1 [m] up'"), std::string::npos);
    EXPECT_NE(mixed.find("xmax [m; rad for rotations]"), std::string::npos);
    EXPECT_NE(mixed.find("'x_t2 [rad]'"), std::string::npos);  // the first diagram panel
    const std::string rotations = sweep_plot_script(r, "t", {1, 3});
    EXPECT_NE(rotations.find("'xmax [rad]'"), std::string::npos);
    EXPECT_NE(rotations.find("'t1 up'"), std::string::npos);
}

// The simulate figure: every dof by default (a colour scale beyond 8), the
// dofs of --plot-dofs when given, and their units.
TEST(PlotDofs, TheSimulateFigureDrawsTheChosenDofs) {
    const Model chain = read_model(kChain40);
    PlotRecorder all(chain, 0.0, 1.0, 0.1);
    PlotRecorder some(chain, 0.0, 1.0, 0.1, {39, 19});
    const std::vector<double> x = [] {
        std::vector<double> v(40);
        for (std::size_t i = 0; i < v.size(); ++i) v[i] = 0.001 * static_cast<double>(i + 1);
        return v;
    }();
    for (PlotRecorder* r : {&all, &some})
        for (int k = 0; k <= 10; ++k) r->on_sample(0.1 * k, x.data(), x.data());
    const std::string a = all.script(), s = some.script();
    EXPECT_NE(a.find("lc palette cb 40 notitle"), std::string::npos);
    EXPECT_NE(a.find("positions of the 40 masses"), std::string::npos);
    EXPECT_NE(s.find("positions of 2 of the 40 dofs"), std::string::npos);
    EXPECT_NE(s.find("title 'm40'"), std::string::npos);
    EXPECT_NE(s.find("title 'm20'"), std::string::npos);
    EXPECT_EQ(s.find("palette"), std::string::npos);
    EXPECT_EQ(s.find("using 1:4 "), std::string::npos);  // two columns of data only
    EXPECT_NE(s.find("\n0 0.04 0.02\n"), std::string::npos) << "m40 then m20 in each row";
    EXPECT_NE(s.find("set ylabel 'x [m]'"), std::string::npos);
    // A beam's deflection and rotation: each legend entry says its unit.
    const Model beam = read_model(std::string(HSNC_SOURCE_DIR) + "/examples/fe-cantilever/fe-cantilever.toml");
    PlotRecorder tip(beam, 0.0, 1.0, 0.1, {14, 15});
    const std::string b = tip.script();
    EXPECT_NE(b.find("title 'w8 [m]'"), std::string::npos);
    EXPECT_NE(b.find("title 't8 [rad]'"), std::string::npos);
    EXPECT_NE(b.find("set ylabel 'x [m; rad for rotations]'"), std::string::npos);
}

TEST(PlotDofs, SweepPlotDofsFlag) {
    const testing::TempDir dir;
    const std::string args = "sweep '" + kChain40 + "' --param omega --from 0.3 --to 0.4 --points 2 --max-periods 20 ";
    auto r = testing::run_hsnc(args + "--plot '" + dir / "a.png" + "' --plot-dofs m1,m99 --quiet");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("--plot-dofs 'm1,m99': 'm99' is not a dof of the model"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "a.png"));
    r = testing::run_hsnc(args + "--plot-dofs m1 --quiet");
    EXPECT_EQ(r.exit_code, 2);  // needs --plot
    EXPECT_NE(r.err.find("--plot-dofs requires --plot"), std::string::npos) << r.err;
    r = testing::run_hsnc(args + "--plot '" + dir / "b.png" + "' --plot-dofs m1,m40 --quiet");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_GT(std::filesystem::file_size(dir / "b.png"), 10000u);
    const std::string sim = "simulate '" + kChain40 + "' --t-end 5 --quiet --plot '" + dir / "c.png" + "' ";
    r = testing::run_hsnc(sim + "--plot-dofs m20,m0");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("--plot-dofs 'm20,m0': 'm0' is not a dof of the model"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "c.png"));
    r = testing::run_hsnc(sim + "--plot-dofs m20,m40");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_GT(std::filesystem::file_size(dir / "c.png"), 10000u);
}

}  // namespace
}  // namespace hsnc
