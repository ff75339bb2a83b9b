// Tests of `hsnc inspect --symbolic` through the real binary: exact strings
// for a 1-DOF configuration, the closed-form eigenvalues of a 2-DOF one
// checked against Eigen at the model's values, the fallback above 2 free DOF,
// and the LaTeX form.
#include <gtest/gtest.h>
#include <ginac/ginac.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <sstream>
#include <string>

#include "assembly.h"
#include "cli_runner.h"
#include "configuration.h"
#include "derivation.h"
#include "model_reader.h"

namespace {

using hsnc::testing::model_path;
using hsnc::testing::run_hsnc;

const std::string kSeed1 = model_path("seed-scenario-1.toml");

/// The text after "NAME = " on the line that starts (after indentation) with it.
std::string rhs(const std::string& out, const std::string& name) {
    const std::string key = "\n  " + name + " = ";
    const auto p = out.find(key);
    if (p == std::string::npos) return "";
    const auto b = p + key.size();
    return out.substr(b, out.find('\n', b) - b);
}

TEST(InspectSymbolic, OneFreeDofExactStrings) {
    // closed=contact1 stuck=m2: m1 alone, held by k1, k2 and k* (m2 fixed at x0).
    const auto r = run_hsnc("inspect " + kSeed1 + " --config \"closed=contact1 stuck=m2\" --symbolic");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err, "");
    EXPECT_EQ(rhs(r.out, "M"), "[m1]");
    EXPECT_EQ(rhs(r.out, "K"), "[k1+k2+k_star]");
    EXPECT_EQ(rhs(r.out, "C"), "[beta*(k1+k2+k_star)]");
    EXPECT_EQ(rhs(r.out, "lambda_1"), "(k1+k2+k_star)/m1");
    EXPECT_EQ(rhs(r.out, "omega_1"), "sqrt((k1+k2+k_star)/m1)");
    EXPECT_EQ(rhs(r.out, "c_1"), "beta*(k1+k2+k_star)/m1");
    // Constant force: friction of the sliding m1, contact preload, stuck m2 through k2 and k*.
    EXPECT_EQ(rhs(r.out, "f_m1"), "-g*m1*mu_k*sgn_m1+k_star*phi1+x0_m2*(k2+k_star)");
    EXPECT_EQ(rhs(r.out, "x_m2(t)"), "x0_m2");
    EXPECT_EQ(rhs(r.out, "x_m1(t)"), "q_1(t)+x_st_m1");
    EXPECT_NE(r.out.find("underdamped or undamped"), std::string::npos);
    EXPECT_EQ(rhs(r.out, "g_1 (gap of contact1)"), "-phi1-x0_m2+x_m1");
    EXPECT_NE(r.out.find("g_4 (-A - mu_s N of m2) = "), std::string::npos);
    // Deterministic: a second process prints the same bytes.
    EXPECT_EQ(run_hsnc("inspect " + kSeed1 + " --config \"closed=contact1 stuck=m2\" --symbolic").out, r.out);
}

TEST(InspectSymbolic, TwoFreeDofEigenvaluesAreTheRootsOfTheDeterminant) {
    const auto r = run_hsnc("inspect " + kSeed1 + " --symbolic");  // all open, none stuck: m1, m2 free
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const hsnc::Model model = hsnc::read_model(kSeed1);
    GiNaC::symtab values;
    for (const auto& [name, value] : model.parameters) values[name] = GiNaC::numeric(value);
    const long saved = GiNaC::Digits;
    GiNaC::Digits = 40;
    double lambda[2];
    for (int j = 0; j < 2; ++j) {
        const std::string text = rhs(r.out, "lambda_" + std::to_string(j + 1));
        ASSERT_FALSE(text.empty()) << r.out;
        GiNaC::parser reader(values, /*strict=*/true);
        const GiNaC::ex v = reader(text).evalf();
        ASSERT_TRUE(GiNaC::is_a<GiNaC::numeric>(v)) << text;
        lambda[j] = GiNaC::ex_to<GiNaC::numeric>(v).to_double();
    }
    GiNaC::Digits = saved;
    const hsnc::Configuration cfg = hsnc::Configuration::all_open(model);
    const Eigen::MatrixXd K = hsnc::stiffness_matrix(model, cfg);
    const Eigen::MatrixXd M = hsnc::mass_vector(model).asDiagonal();
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(K, M);
    ASSERT_EQ(eig.info(), Eigen::Success);
    for (int j = 0; j < 2; ++j) EXPECT_NEAR(lambda[j], eig.eigenvalues()(j), 1e-12 * eig.eigenvalues()(j)) << j;
    // And omega_1^2 = lambda_1 as printed.
    GiNaC::parser reader(values, true);
    const double omega1 = GiNaC::ex_to<GiNaC::numeric>(reader(rhs(r.out, "omega_1")).evalf()).to_double();
    EXPECT_NEAR(omega1 * omega1, lambda[0], 1e-12 * lambda[0]);
}

TEST(InspectSymbolic, ThreeOrMoreFreeDofFallBackToNumbers) {
    const auto r = run_hsnc("inspect " + model_path("chain-8.toml") + " --symbolic");
    ASSERT_EQ(r.exit_code, 0);
    EXPECT_EQ(r.err,
              "hsnc inspect: --symbolic: the configuration has 8 free DOF, more than 2 (the limit for a closed-form "
              "eigen-decomposition); printing numbers\n");
    EXPECT_NE(r.out.find("mode 8: lambda = "), std::string::npos);  // the numeric view
}

TEST(InspectSymbolic, LatexIsBalancedAndHasNoCTokens) {
    for (const char* config : {"closed=contact1 stuck=m2", "closed= stuck="}) {
        const auto r = run_hsnc("inspect " + kSeed1 + " --config \"" + config + "\" --symbolic --format latex");
        ASSERT_EQ(r.exit_code, 0) << r.err;
        int depth = 0;
        bool never_negative = true;
        for (char ch : r.out) {
            depth += ch == '{' ? 1 : ch == '}' ? -1 : 0;
            never_negative = never_negative && depth >= 0;
        }
        EXPECT_EQ(depth, 0) << config;
        EXPECT_TRUE(never_negative) << config;
        for (const char* token : {"*", "__builtin", "pow(", "sqrt(", "exp(", "std::", "==", "double"})
            EXPECT_EQ(r.out.find(token), std::string::npos) << config << ": " << token;
        EXPECT_NE(r.out.find("\\left("), std::string::npos);
    }
    const auto r = run_hsnc("inspect " + kSeed1 + " --config \"closed=contact1 stuck=m2\" --symbolic --format latex");
    EXPECT_NE(r.out.find("\\[ \\omega_{1} = \\sqrt{\\frac{k_{1} + k_{2} + k_{star}}{m_{1}}} \\]"), std::string::npos)
        << r.out;
}

TEST(InspectSymbolic, HelpStatesTheLimit) {
    const auto r = run_hsnc("inspect --help");
    EXPECT_NE(r.out.find("at most 2 free DOF"), std::string::npos) << r.out;
}

}  // namespace

namespace {

/// Every "  NAME = EXPR" line of a --symbolic printout from the modes on,
/// parsed in order with `table` (parameters, initial state, t0 as numbers; t a
/// symbol) and added to it, so later lines use earlier ones. "q_j(t)" and
/// "x_m(t)" become q_j and x_m.
void evaluate_printout(std::string out, GiNaC::symtab& table) {
    for (const char* f : {"q_1(t)", "q_2(t)"})
        for (auto p = out.find(f); p != std::string::npos; p = out.find(f)) out.replace(p, 6, std::string(f, 3));
    std::istringstream in(out.substr(out.find("\nModes")));
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("  ", 0) != 0 || line.rfind("  g_", 0) == 0) continue;
        const auto eq = line.find(" = ");
        std::string name = line.substr(2, eq - 2);
        if (name.size() > 3 && name.compare(name.size() - 3, 3, "(t)") == 0) name.resize(name.size() - 3);
        GiNaC::parser reader(table, /*strict=*/true);
        table[name] = reader(line.substr(eq + 3));
    }
}

TEST(InspectSymbolic, ResponseSolvesTheEquationsOfMotion) {
    // Randomised-consistency tier: the printed x_i(t), evaluated at the model's
    // values, a start state and sliding directions, satisfies m_i x_i'' = A_i -
    // mu_k m_i g sgn_i for the free masses and the initial state at t0.
    const hsnc::Model model = hsnc::read_model(kSeed1);
    const long saved = GiNaC::Digits;
    GiNaC::Digits = 40;
    for (const char* config : {"closed=contact1 stuck=m2", "closed= stuck=", "closed=contact1 stuck="}) {
        const auto r = run_hsnc("inspect " + kSeed1 + " --config \"" + config + "\" --symbolic");
        ASSERT_EQ(r.exit_code, 0) << r.err;
        const hsnc::Configuration cfg = hsnc::Configuration::parse(model, config);
        const double t0 = 0.3, x0[2] = {0.21, -0.13}, v0[2] = {-1.5, 0.7};
        const int sgn[2] = {-1, 1};
        GiNaC::symtab table;
        for (const auto& [name, value] : model.parameters) table[name] = GiNaC::numeric(value);
        const GiNaC::symbol t("t");
        table["t"] = t;
        table["t0"] = hsnc::exact(t0);
        for (int i = 0; i < 2; ++i) {
            const std::string nm = model.masses[i].name;
            table["x0_" + nm] = hsnc::exact(x0[i]);
            table["v0_" + nm] = hsnc::exact(v0[i]);
            table["sgn_" + nm] = sgn[i];
        }
        evaluate_printout(r.out, table);
        for (double tt : {t0, t0 + 0.01, t0 + 0.37}) {
            double x[2], v[2], a[2];
            for (int i = 0; i < 2; ++i) {
                const GiNaC::ex xi = table.at("x_" + model.masses[i].name);
                auto at = [&](const GiNaC::ex& e) {
                    return GiNaC::ex_to<GiNaC::numeric>(e.subs(t == hsnc::exact(tt)).evalf()).to_double();
                };
                x[i] = at(xi);
                v[i] = at(xi.diff(t));
                a[i] = at(xi.diff(t, 2));
            }
            if (tt == t0)
                for (int i = 0; i < 2; ++i) {
                    EXPECT_NEAR(x[i], x0[i], 1e-13) << config;
                    EXPECT_NEAR(v[i], cfg.stuck[i] ? 0.0 : v0[i], 1e-12) << config;
                }
            for (int i = 0; i < 2; ++i) {
                if (cfg.stuck[i]) continue;
                const double m = model.masses[i].m,
                             friction = model.friction_slot(i).mu_k * model.normal_force(i) * sgn[i];
                const double A = hsnc::force_on_mass(model, cfg, i, tt, x, v);
                EXPECT_NEAR(m * a[i], A - friction, 1e-9 * 22500) << config << " t=" << tt << " mass " << i;
            }
        }
    }
    GiNaC::Digits = saved;
}

TEST(InspectSymbolic, ReaderKeepsTheSourceTexts) {
    const hsnc::Model model = hsnc::read_model(kSeed1);
    EXPECT_EQ(model.field_expressions.at("mass[1].m"), "m1");
    EXPECT_EQ(model.field_expressions.at("contact[1].gap"), "phi1");
    EXPECT_EQ(model.field_expressions.at("forcing[1].amplitude.m2"), "F2");
    EXPECT_EQ(model.field_expressions.at("initial.x.m1"), "0.2");
    EXPECT_EQ(model.field_expressions.count("damping.alpha"), 0u);  // not in the file
    ASSERT_FALSE(model.parameter_expressions.empty());
    EXPECT_EQ(model.parameter_expressions.front(), (std::pair<std::string, std::string>{"m1", "1"}));
}

}  // namespace
