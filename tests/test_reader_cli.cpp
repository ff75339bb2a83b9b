// Front-end defects of issue 11 around reading a model and its flags:
// `--t-end` replacing an end time before t0, `generate -o ""`, and
// `generate --params` honouring the order it is given.
#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "derivation.h"
#include "jit.h"
#include "kernel_solver.h"
#include "model_reader.h"
#include "param_emitter.h"

namespace hsnc {
namespace {

using testing::CliRun;
using testing::model_path;
using testing::run_hsnc;
using testing::write_temp;

const char* const kEndBeforeStart = R"toml(name = "end-before-start"
[parameters]
k = 100
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["ground", "m1"]
k = "k"
[initial]
t0 = 5
x = { m1 = 0.1 }
[simulate]
t_end = 1
)toml";

TEST(ReaderCli, TEndFlagReplacesAnEndTimeBeforeT0) {
    const std::string path = write_temp("end_before_start.toml", kEndBeforeStart);
    const CliRun ok = run_hsnc("simulate '" + path + "' --t-end 6 --quiet");
    EXPECT_EQ(ok.exit_code, 0) << ok.err;
    EXPECT_EQ(ok.err, "");
    // Without the flag the file's end time is used, and it is still an error.
    const CliRun bad = run_hsnc("simulate '" + path + "' --quiet");
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_EQ(bad.err, "hsnc: " + path + ":14: key 'simulate.t_end': must be > t0 = 5, got 1\n");
    // And the flag is checked in its turn.
    const CliRun early = run_hsnc("simulate '" + path + "' --t-end 4 --quiet");
    EXPECT_EQ(early.exit_code, 2);
    EXPECT_EQ(early.err, "hsnc: --t-end 4: must be finite and after t0 = 5\n");
}

TEST(ReaderCli, GenerateRefusesAnEmptyOutputDirectory) {
    // Run from an empty directory, so that anything written there shows.
    const std::string dir = testing::temp_path("generate_cwd");
    std::filesystem::create_directories(dir);
    const std::filesystem::path cwd = std::filesystem::current_path();
    std::filesystem::current_path(dir);
    const CliRun r = run_hsnc("generate '" + model_path("coulomb-1dof.toml") + "' -o ''");
    std::filesystem::current_path(cwd);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_EQ(r.out, "");
    EXPECT_EQ(r.err, "hsnc: generate: -o '': empty output directory (write -o . for the current directory)\n");
    EXPECT_TRUE(std::filesystem::is_empty(dir));
    std::filesystem::remove_all(dir);
}

/// A sweep kernel of seed-scenario-2 in "closed=contact1 stuck=m2", kept
/// parameters as `--params list` gives them, configured with `values` in that
/// order; x, v, a and g at a few times of one segment.
std::vector<double> sweep_run(const std::string& list, const std::vector<double>& values, std::string* names) {
    const Model model = read_model(model_path("seed-scenario-2.toml"));
    const Configuration cfg = Configuration::parse(model, "closed=contact1 stuck=m2");
    const std::vector<std::string> kept = kept_parameters(model, list);
    Jit jit;
    jit.add("sweep.cpp", emit_sweep_kernel(derive(model, cfg), kept));
    const auto* kernel = static_cast<const hsnc_kernel*>(jit.lookup(sweep_kernel_symbol(model, cfg)));
    for (int p = 0; p < kernel->n_param; ++p) *names += (p ? "," : "") + std::string(kernel->param_names[p]);
    KernelSolver solver(*kernel, values);
    const std::size_t n = model.dof(), ns = solver.switches().size();
    const std::vector<double> x0 = {0.1, 0.05}, v0 = {0.3, 0.0};
    const std::vector<signed char> sgn = {1, 0};
    solver.setup(0.0, x0.data(), v0.data(), sgn.data());
    std::vector<double> x(n), v(n), a(n), g(ns), dg(ns), b(ns), sc(ns), out;
    for (double tau : {0.0, 0.01, 0.1, 0.5}) {
        solver.eval(tau, {x.data(), v.data(), a.data(), g.data(), dg.data(), b.data(), sc.data()});
        for (const auto* vec : {&x, &v, &a, &g}) out.insert(out.end(), vec->begin(), vec->end());
    }
    return out;
}

TEST(ReaderCli, SweepKernelTakesParametersInTheOrderOfParams) {
    // The model lists omega before k_star. A caller that asks for
    // "k_star,omega" passes {k_star, omega}: the kernel must read them so
    // (it used to take them in model order, so swapped).
    std::string model_order, given_order;
    const std::vector<double> a = sweep_run("omega,k_star", {12.5, 300.0}, &model_order);
    const std::vector<double> b = sweep_run("k_star,omega", {300.0, 12.5}, &given_order);
    EXPECT_EQ(model_order, "omega,k_star");
    EXPECT_EQ(given_order, "k_star,omega");
    EXPECT_EQ(a, b);  // the same kernel arithmetic, only the argument order differs
    const Model model = read_model(model_path("seed-scenario-2.toml"));
    const Configuration cfg = Configuration::parse(model, "closed=contact1 stuck=m2");
    const std::string text = emit_sweep_kernel(derive(model, cfg), kept_parameters(model, "k_star,omega"));
    EXPECT_NE(text.find("// parameters given to configure(), in this order: k_star, omega\n"), std::string::npos);
}

}  // namespace
}  // namespace hsnc
