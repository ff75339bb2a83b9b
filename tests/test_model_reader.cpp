// Tests of the model reader (model/model_reader.h, interface.md section 1).
// Good input: every field of Model against the numbers written in the TOML
// (or their closed-form expressions). Bad input: one test per failure, each
// checking the message names the file, the line (where toml++ has one), the
// key and the reason.
#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "error.h"
#include "model_reader.h"

namespace hsnc {
namespace {

/// The message of the InputError that parsing `text` (as "test.toml") throws.
std::string error_of(const std::string& text, const ModelOverrides& overrides = {}) {
    try {
        parse_model(text, "test.toml", overrides);
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected an InputError for:\n" << text;
    return "";
}

/// `message` contains every one of `parts`, and is a single line.
void expect_message(const std::string& message, std::initializer_list<const char*> parts) {
    for (const char* part : parts)
        EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
}

// Line numbers in these documents: count from the `name` line, which is line 1.
const char* const kTwoMasses =
    "name = \"t\"\n"       // 1
    "[[mass]]\n"           // 2
    "name = \"m1\"\n"      // 3
    "m = 1\n"              // 4
    "[[mass]]\n"           // 5
    "name = \"m2\"\n"      // 6
    "m = 2\n";             // 7

// ---------------------------------------------------------------- good input

// GiNaC is not thread-safe: the reader holds ginac_lock() (ginac_lock.h).
// Without it, threads reading models with expressions at once corrupted the
// heap (a continuation on two threads aborted one run in two).
TEST(ModelReader, ThreadsMayReadModelsAtOnce) {
    const std::string text = R"toml(
name = "expr"
[parameters]
k = "40 + sin(pi/7)^2"
m = "sqrt(2) * 3/7"
[[mass]]
name = "a"
m = "m"
[[spring]]
between = ["a", "ground"]
k = "k * exp(1/3)"
)toml";
    const Model reference = parse_model(text, "expr.toml");
    std::vector<std::thread> pool;
    std::vector<int> wrong(4, 0);
    for (int t = 0; t < 4; ++t)
        pool.emplace_back([&, t] {
            for (int i = 0; i < 150; ++i) {
                const Model m = parse_model(text, "expr.toml", ModelOverrides{{"k=" + std::to_string(40 + i % 3)}, {}, {}, {}});
                const Model same = parse_model(text, "expr.toml");
                wrong[static_cast<std::size_t>(t)] += same.springs[0].k != reference.springs[0].k || m.masses[0].m != reference.masses[0].m;
            }
        });
    for (std::thread& th : pool) th.join();
    for (int w : wrong) EXPECT_EQ(w, 0);
}

TEST(ModelReader, ReadsEveryFieldOfTheInterfaceExample) {
    const std::string text = R"toml(
name = "seed-scenario-1"
description = "free text"
[parameters]
m1 = 1.0
k1 = 5.0
beta = 0.1
mu = 0.6
g = 9.81
[[mass]]
name = "m1"
m = "m1"
mu_k = "mu"
mu_s = 0.75
[[mass]]
name = "m2"
m = 2
[[spring]]
between = ["ground", "m1"]
k = "k1"
[[spring]]
between = ["m1", "m2"]
k = "2*k1"
[damping]
alpha = 0.5
beta = "beta"
[[contact]]
name = "c1"
between = ["m1", "m2"]
gap = 0.2
k = 100.0
[[contact]]
between = ["m2", "ground"]
gap = -0.1
k = 50
[[forcing]]
omega = 175.5151
phase = 0.25
amplitude = { m1 = 22500.0 }
[load]
m2 = 1.0
[initial]
t0 = 0.5
x = { m1 = 0.2 }
v = { m2 = -2.0 }
[simulate]
t_end = 10.0
)toml";
    const Model m = parse_model(text, "seed.toml");
    EXPECT_EQ(m.name, "seed-scenario-1");
    EXPECT_EQ(m.description, "free text");
    EXPECT_EQ(m.source, "seed.toml");
    ASSERT_EQ(m.parameters.size(), 5u);
    EXPECT_EQ(m.parameters[0].first, "m1");  // file order, g where the file put it
    EXPECT_EQ(m.parameters[4].first, "g");
    EXPECT_DOUBLE_EQ(m.g, 9.81);

    ASSERT_EQ(m.dof(), 2u);
    EXPECT_EQ(m.masses[0].name, "m1");
    EXPECT_DOUBLE_EQ(m.masses[0].m, 1.0);
    EXPECT_TRUE(m.has_friction(0));
    EXPECT_DOUBLE_EQ(m.friction_slot(0).mu_k, 0.6);
    EXPECT_DOUBLE_EQ(m.friction_slot(0).mu_s, 0.75);
    EXPECT_EQ(m.masses[1].name, "m2");
    EXPECT_DOUBLE_EQ(m.masses[1].m, 2.0);
    EXPECT_FALSE(m.has_friction(1));

    ASSERT_EQ(m.springs.size(), 2u);
    EXPECT_EQ(m.springs[0].a, kGround);
    EXPECT_EQ(m.springs[0].b, 0);
    EXPECT_DOUBLE_EQ(m.springs[0].k, 5.0);
    EXPECT_EQ(m.springs[1].a, 0);
    EXPECT_EQ(m.springs[1].b, 1);
    EXPECT_DOUBLE_EQ(m.springs[1].k, 10.0);

    EXPECT_DOUBLE_EQ(m.alpha, 0.5);
    EXPECT_DOUBLE_EQ(m.beta, 0.1);

    ASSERT_EQ(m.contacts.size(), 2u);
    EXPECT_EQ(m.contacts[0].name, "c1");
    EXPECT_EQ(m.contacts[0].a, 0);
    EXPECT_EQ(m.contacts[0].b, 1);
    EXPECT_DOUBLE_EQ(m.contacts[0].gap, 0.2);
    EXPECT_DOUBLE_EQ(m.contacts[0].k, 100.0);
    EXPECT_EQ(m.contacts[1].name, "contact2");  // default "contact<N>", N counted from 1
    EXPECT_EQ(m.contacts[1].b, kGround);
    EXPECT_DOUBLE_EQ(m.contacts[1].gap, -0.1);  // negative gap = preloaded, allowed

    ASSERT_EQ(m.forcing.size(), 1u);
    EXPECT_DOUBLE_EQ(m.forcing[0].omega, 175.5151);
    EXPECT_DOUBLE_EQ(m.forcing[0].phase, 0.25);
    ASSERT_EQ(m.forcing[0].amplitude.size(), 2u);
    EXPECT_DOUBLE_EQ(m.forcing[0].amplitude[0], 22500.0);
    EXPECT_DOUBLE_EQ(m.forcing[0].amplitude[1], 0.0);  // unnamed mass gets 0

    ASSERT_EQ(m.load.size(), 2u);
    EXPECT_DOUBLE_EQ(m.load[0], 0.0);
    EXPECT_DOUBLE_EQ(m.load[1], 1.0);
    EXPECT_DOUBLE_EQ(m.t0, 0.5);
    ASSERT_EQ(m.x0.size(), 2u);
    ASSERT_EQ(m.v0.size(), 2u);
    EXPECT_DOUBLE_EQ(m.x0[0], 0.2);
    EXPECT_DOUBLE_EQ(m.x0[1], 0.0);
    EXPECT_DOUBLE_EQ(m.v0[0], 0.0);
    EXPECT_DOUBLE_EQ(m.v0[1], -2.0);
    ASSERT_TRUE(m.t_end.has_value());
    EXPECT_DOUBLE_EQ(*m.t_end, 10.0);
}

TEST(ModelReader, OptionalSectionsDefault) {
    const Model m = parse_model(kTwoMasses, "t.toml");
    EXPECT_TRUE(m.springs.empty());
    EXPECT_TRUE(m.contacts.empty());
    EXPECT_TRUE(m.forcing.empty());
    EXPECT_EQ(m.load, std::vector<double>(2, 0.0));
    EXPECT_EQ(m.x0, std::vector<double>(2, 0.0));
    EXPECT_EQ(m.v0, std::vector<double>(2, 0.0));
    EXPECT_DOUBLE_EQ(m.t0, 0.0);
    EXPECT_DOUBLE_EQ(m.alpha, 0.0);
    EXPECT_DOUBLE_EQ(m.beta, 0.0);
    EXPECT_FALSE(m.t_end.has_value());
    EXPECT_EQ(m.description, "");
}

TEST(ModelReader, ExpressionsEvaluateOverEarlierParameters) {
    const Model m = parse_model(R"toml(name = "t"
[parameters]
k = 8
m = 2
w = "sqrt(k/m)"
half = "1/2"
[[mass]]
name = "a"
m = "m*w^2/k"
[[forcing]]
omega = "2*Pi*w"
phase = "-Pi/4"
amplitude = { a = "exp(1)" }
)toml",
                                "t.toml");
    ASSERT_EQ(m.parameters.size(), 5u);  // g, k, m, w, half
    EXPECT_EQ(m.parameters[3].first, "w");
    EXPECT_DOUBLE_EQ(m.parameters[3].second, 2.0);
    EXPECT_DOUBLE_EQ(m.parameters[4].second, 0.5);
    EXPECT_DOUBLE_EQ(m.masses[0].m, 1.0);
    EXPECT_DOUBLE_EQ(m.forcing[0].omega, 4.0 * M_PI);
    EXPECT_DOUBLE_EQ(m.forcing[0].phase, -M_PI / 4.0);
    EXPECT_DOUBLE_EQ(m.forcing[0].amplitude[0], std::exp(1.0));
}

TEST(ModelReader, ExpressionStringsRoundLikeTomlLiterals) {
    // `k = 0.1` and `k = "0.1"` (and --set k=0.1) must give the same double.
    // The first values were one ulp off at GiNaC's default 17 digits.
    std::vector<std::string> decimals = {"-7.856e-05", "-5.146e-15", "4.546e-17", "-3.928e-05", "-4.91e-06",
                                         "1.455e-11", "0.1", "0.3", "175.5151", "17.5515", "9.81"};
    std::mt19937_64 rng(20240601);
    std::uniform_real_distribution<double> mantissa(-1000.0, 1000.0);
    std::uniform_int_distribution<int> exponent(-20, 20);
    for (int i = 0; i < 2000; ++i) {
        char text[40];
        std::snprintf(text, sizeof text, i % 2 ? "%.4g" : "%.17g", mantissa(rng) * std::pow(10.0, exponent(rng)));
        decimals.push_back(text);
    }
    for (std::size_t first = 0; first < decimals.size(); first += 100) {
        std::string doc = "name = \"t\"\n[[mass]]\nname = \"a\"\nm = 1\n[parameters]\n";
        const std::size_t last = std::min(decimals.size(), first + 100);
        for (std::size_t i = first; i < last; ++i) {
            doc += "p" + std::to_string(i) + " = " + decimals[i] + "\n";
            doc += "q" + std::to_string(i) + " = \"" + decimals[i] + "\"\n";
        }
        const Model m = parse_model(doc, "t.toml");
        ASSERT_EQ(m.parameters.size(), 1 + 2 * (last - first));
        for (std::size_t i = first; i < last; ++i) {
            const double literal = m.parameters[1 + 2 * (i - first)].second;
            const double expression = m.parameters[2 + 2 * (i - first)].second;
            EXPECT_EQ(literal, std::strtod(decimals[i].c_str(), nullptr)) << decimals[i];
            EXPECT_EQ(expression, literal) << decimals[i];
        }
    }
}

TEST(ModelReader, PiIsTheConstantUnlessAParameterIsNamedPi) {
    // `pi` as well as GiNaC's own `Pi`; the text other readers parse says Pi.
    const Model m = parse_model("name = \"t\"\n[parameters]\nw = \"2*pi\"\nv = \"Pi/2\"\n[[mass]]\nname = \"a\"\n"
                                "m = 1\n[[forcing]]\nomega = \"pi*w\"\namplitude = { a = 1 }\n",
                                "t.toml");
    EXPECT_EQ(m.parameters[1].second, 2 * M_PI);
    EXPECT_EQ(m.parameters[2].second, M_PI / 2);
    EXPECT_EQ(m.parameter_expressions[1].second, "2*Pi");
    EXPECT_DOUBLE_EQ(m.forcing[0].omega, 2 * M_PI * M_PI);
    EXPECT_EQ(m.field_expressions.at("forcing[1].omega"), "Pi*w");
    // A file that names a parameter pi keeps it: pi is then that parameter.
    const Model own = parse_model("name = \"t\"\n[parameters]\npi = 3\nw = \"2*pi\"\n[[mass]]\nname = \"a\"\nm = 1\n",
                                  "t.toml");
    EXPECT_EQ(own.parameters[2].second, 6.0);
    EXPECT_EQ(own.parameter_expressions[2].second, "2*pi");
}

TEST(ModelReader, SinAndCosOfLargeArgumentsAreEvaluatedExactly) {
    // At 40 digits sin(1e80) came out as 0 and cos(1e80) as 1. The argument is
    // now known to 1e-40 absolutely, so the result is the correctly rounded
    // sine of the double x, as the C library computes it.
    for (const double x : {1e22, 1e80, 1e200, 1.5e300}) {
        SCOPED_TRACE(x);
        ModelOverrides o;
        char set[64];
        std::snprintf(set, sizeof set, "x=%.17g", x);
        o.set = {set};
        const Model m = parse_model("name = \"t\"\n[parameters]\nx = 1\ns = \"sin(x)\"\nc = \"cos(x)\"\n"
                                    "t = \"tan(x)\"\n[[mass]]\nname = \"a\"\nm = 1\n",
                                    "t.toml", o);
        ASSERT_EQ(m.parameters[1].second, x);
        EXPECT_DOUBLE_EQ(m.parameters[2].second, std::sin(x));
        EXPECT_DOUBLE_EQ(m.parameters[3].second, std::cos(x));
        EXPECT_DOUBLE_EQ(m.parameters[4].second, std::tan(x));
    }
    // 1e22 is a double exactly, and so is the literal in an expression.
    EXPECT_DOUBLE_EQ(parse_model("name = \"t\"\n[parameters]\ns = \"sin(1e22)\"\n[[mass]]\nname = \"a\"\nm = 1\n",
                                 "t.toml").parameters[1].second,
                     std::sin(1e22));
}

TEST(ModelReader, ExpressionsNestedUpToTheLimitAreRead) {
    std::string nested = "1";
    // Each "-(" is two levels (a sign and a parenthesis), the innermost 1 one more.
    for (int i = 0; i < 150; ++i) nested = "-(" + nested + ")";  // 301 levels
    const std::string text = "name = \"t\"\n[parameters]\nk = \"" + nested + "\"\n[[mass]]\nname = \"a\"\nm = 1\n";
    EXPECT_NE(error_of(text).find("more than 200 levels deep"), std::string::npos);
    nested = "1";
    for (int i = 0; i < 99; ++i) nested = "-(" + nested + ")";  // 199 levels
    EXPECT_EQ(parse_model("name = \"t\"\n[parameters]\nk = \"" + nested + "\"\n[[mass]]\nname = \"a\"\nm = 1\n", "t.toml")
                  .parameters[1]
                  .second,
              -1.0);
}

TEST(ModelReader, EndTimeOverrideReplacesTheFilesEndTime) {
    // [simulate].t_end before t0 is no error when --t-end replaces it.
    const std::string text = std::string(kTwoMasses) + "[initial]\nt0 = 5\n[simulate]\nt_end = 1\n";
    const Model m = parse_model(text, "t.toml", with_t_end({}, 8.0));
    ASSERT_TRUE(m.t_end.has_value());
    EXPECT_EQ(*m.t_end, 8.0);
    EXPECT_FALSE(with_t_end({}, NAN).t_end.has_value());
    expect_message(error_of(text), {"test.toml:11: key 'simulate.t_end': must be > t0 = 5, got 1"});
    expect_message(error_of(text, with_t_end({}, 4.0)), {"--t-end 4: must be finite and after t0 = 5"});
}

TEST(ModelReader, ParametersFollowFileOrderNotKeyOrder) {
    // toml++ sorts keys; "aa" uses "zz", which comes first in the file.
    const Model m = parse_model("name = \"t\"\n[parameters]\nzz = 3\naa = \"zz*2\"\n[[mass]]\nname = \"a\"\nm = \"aa\"\n",
                                "t.toml");
    ASSERT_EQ(m.parameters.size(), 3u);
    EXPECT_EQ(m.parameters[0].first, "g");  // implicit g comes first
    EXPECT_EQ(m.parameters[1].first, "zz");
    EXPECT_EQ(m.parameters[2].first, "aa");
    EXPECT_DOUBLE_EQ(m.masses[0].m, 6.0);
}

TEST(ModelReader, GravityDefaultsTo981AndIsAParameter) {
    const Model m = parse_model("name = \"t\"\n[parameters]\nN = \"2*g\"\n[[mass]]\nname = \"a\"\nm = \"g\"\n", "t.toml");
    EXPECT_DOUBLE_EQ(m.g, 9.81);
    EXPECT_EQ(m.parameters[0].first, "g");
    EXPECT_DOUBLE_EQ(m.parameters[0].second, 9.81);
    EXPECT_DOUBLE_EQ(m.parameters[1].second, 19.62);
    EXPECT_DOUBLE_EQ(m.masses[0].m, 9.81);
    EXPECT_DOUBLE_EQ(m.normal_force(0), 9.81 * 9.81);

    const Model moon = parse_model("name = \"t\"\n[parameters]\ng = 1.62\n[[mass]]\nname = \"a\"\nm = 1\n", "t.toml");
    EXPECT_DOUBLE_EQ(moon.g, 1.62);
    EXPECT_EQ(moon.parameters.size(), 1u);
}

TEST(ModelReader, FrictionFlagsAndDefaults) {
    const Model m = parse_model(R"toml(name = "t"
[[mass]]
name = "a"
m = 1
mu_k = 0.3
[[mass]]
name = "b"
m = 1
mu_k = 0
mu_s = 0.2
[[mass]]
name = "c"
m = 1
)toml",
                                "t.toml");
    EXPECT_TRUE(m.has_friction(0));
    EXPECT_DOUBLE_EQ(m.friction_slot(0).mu_s, 0.3);  // mu_s defaults to mu_k
    EXPECT_TRUE(m.has_friction(1));                  // mu_k = 0: slides freely, can still stick
    EXPECT_DOUBLE_EQ(m.friction_slot(1).mu_k, 0.0);
    EXPECT_DOUBLE_EQ(m.friction_slot(1).mu_s, 0.2);
    EXPECT_FALSE(m.has_friction(2));
}

TEST(ModelReader, MassMayShareItsNameWithAParameter) {
    // Table 1 notation: the mass m1 has the value of the parameter m1.
    const Model m = parse_model("name = \"t\"\n[parameters]\nm1 = 3\n[[mass]]\nname = \"m1\"\nm = \"m1\"\n", "t.toml");
    EXPECT_DOUBLE_EQ(m.masses[0].m, 3.0);
}

TEST(ModelReader, SetOverrideReachesLaterParametersAndFields) {
    const std::string text = R"toml(name = "t"
[parameters]
k = 4
m = 1
w = "sqrt(k/m)"
[[mass]]
name = "a"
m = "m"
[[spring]]
between = ["ground", "a"]
k = "k"
[[forcing]]
omega = "w"
amplitude = { a = 1 }
)toml";
    ModelOverrides o;
    o.set = {"k=9", "m=k/9"};  // VALUE may use earlier parameters (k, already overridden)
    const Model m = parse_model(text, "t.toml", o);
    EXPECT_DOUBLE_EQ(m.parameters[1].second, 9.0);
    EXPECT_DOUBLE_EQ(m.parameters[2].second, 1.0);
    EXPECT_DOUBLE_EQ(m.springs[0].k, 9.0);
    EXPECT_DOUBLE_EQ(m.forcing[0].omega, 3.0);  // sqrt(9/1), a later parameter sees the override
    ModelOverrides og;
    og.set = {"g=1.62"};
    EXPECT_DOUBLE_EQ(parse_model(text, "t.toml", og).g, 1.62);  // implicit g can be overridden
}

TEST(ModelReader, InitialStateOverrides) {
    ModelOverrides o;
    o.x0 = {"m2=0.5"};
    o.v0 = {"m1=-g/9.81"};
    const Model m = parse_model(std::string(kTwoMasses) + "[initial]\nx = { m1 = 0.2 }\n", "t.toml", o);
    EXPECT_DOUBLE_EQ(m.x0[0], 0.2);
    EXPECT_DOUBLE_EQ(m.x0[1], 0.5);
    EXPECT_DOUBLE_EQ(m.v0[0], -1.0);
    EXPECT_DOUBLE_EQ(m.v0[1], 0.0);
}

TEST(ModelReader, ReadsAFileAndNamesItAsSource) {
    const std::string path = std::string(HSNC_SOURCE_DIR) + "/models/coulomb-1dof.toml";
    const Model m = read_model(path);
    EXPECT_EQ(m.source, path);
    EXPECT_EQ(m.name, "coulomb-1dof");
}

TEST(ModelReader, ValidNames) {
    EXPECT_TRUE(is_valid_name("m1"));
    EXPECT_TRUE(is_valid_name("_x_9"));
    EXPECT_TRUE(is_valid_name("K"));
    EXPECT_FALSE(is_valid_name(""));
    EXPECT_FALSE(is_valid_name("1m"));
    EXPECT_FALSE(is_valid_name("a-b"));
    EXPECT_FALSE(is_valid_name("a b"));
    EXPECT_FALSE(is_valid_name("m\xc3\xa9"));
}

// ---------------------------------------------------------- bundled models

TEST(BundledModels, EveryFileInModelsParses) {
    int count = 0;
    for (const auto& entry : std::filesystem::directory_iterator(std::string(HSNC_SOURCE_DIR) + "/models")) {
        if (entry.path().extension() != ".toml") continue;
        SCOPED_TRACE(entry.path().string());
        Model m;
        EXPECT_NO_THROW(m = read_model(entry.path().string()));
        EXPECT_GT(m.dof(), 0u);
        EXPECT_EQ(m.name, entry.path().stem().string());  // file named after its model
        EXPECT_TRUE(m.t_end.has_value());
        // Each starts with a comment block saying what it is.
        std::ifstream in(entry.path());
        std::string first;
        std::getline(in, first);
        EXPECT_EQ(first.rfind("# ", 0), 0u) << first;
        ++count;
    }
    EXPECT_GE(count, 5);
}

// Table 1 of the paper, rows 1 and 2, and the Results section's initial state.
void expect_seed_scenario(const Model& m, double beta, double F1, double F2, double omega, double t_end) {
    ASSERT_EQ(m.dof(), 2u);
    EXPECT_EQ(m.masses[0].name, "m1");
    EXPECT_EQ(m.masses[1].name, "m2");
    EXPECT_DOUBLE_EQ(m.masses[0].m, 1.0);
    EXPECT_DOUBLE_EQ(m.masses[1].m, 2.0);
    for (std::size_t i = 0; i < m.dof(); ++i) {
        EXPECT_TRUE(m.has_friction(i));
        EXPECT_DOUBLE_EQ(m.friction_slot(i).mu_k, 0.6);
        EXPECT_DOUBLE_EQ(m.friction_slot(i).mu_s, 0.75);
    }
    ASSERT_EQ(m.springs.size(), 3u);  // Fig. 4: ground-m1 (k1), m1-m2 (k2), m2-ground (k3)
    EXPECT_EQ(m.springs[0].a, kGround);
    EXPECT_EQ(m.springs[0].b, 0);
    EXPECT_DOUBLE_EQ(m.springs[0].k, 5.0);
    EXPECT_EQ(m.springs[1].a, 0);
    EXPECT_EQ(m.springs[1].b, 1);
    EXPECT_DOUBLE_EQ(m.springs[1].k, 10.0);
    EXPECT_EQ(m.springs[2].a, 1);
    EXPECT_EQ(m.springs[2].b, kGround);
    EXPECT_DOUBLE_EQ(m.springs[2].k, 40.0);
    ASSERT_EQ(m.contacts.size(), 1u);
    EXPECT_EQ(m.contacts[0].name, "contact1");
    EXPECT_EQ(m.contacts[0].a, 0);
    EXPECT_EQ(m.contacts[0].b, 1);
    EXPECT_DOUBLE_EQ(m.contacts[0].gap, 0.2);
    EXPECT_DOUBLE_EQ(m.contacts[0].k, 100.0);
    EXPECT_DOUBLE_EQ(m.alpha, 0.0);
    EXPECT_DOUBLE_EQ(m.beta, beta);
    ASSERT_EQ(m.forcing.size(), 1u);
    EXPECT_DOUBLE_EQ(m.forcing[0].omega, omega);
    EXPECT_DOUBLE_EQ(m.forcing[0].phase, 0.0);
    EXPECT_DOUBLE_EQ(m.forcing[0].amplitude[0], F1);
    EXPECT_DOUBLE_EQ(m.forcing[0].amplitude[1], F2);
    EXPECT_DOUBLE_EQ(m.g, 9.81);
    EXPECT_EQ(m.x0, (std::vector<double>{0.2, -0.1}));
    EXPECT_EQ(m.v0, (std::vector<double>{-5.0, -2.0}));
    EXPECT_EQ(m.load, (std::vector<double>{0.0, 0.0}));
    EXPECT_DOUBLE_EQ(m.t0, 0.0);
    ASSERT_TRUE(m.t_end.has_value());
    EXPECT_DOUBLE_EQ(*m.t_end, t_end);
}

TEST(BundledModels, SeedScenariosMatchTable1) {
    const std::string dir = std::string(HSNC_SOURCE_DIR) + "/models/";
    expect_seed_scenario(read_model(dir + "seed-scenario-1.toml"), 0.1, 22500.0, -15000.0, 175.5151, 2.0);
    expect_seed_scenario(read_model(dir + "seed-scenario-2.toml"), 0.0, 225.0, 150.0, 17.5515, 300.0);
}

// ------------------------------------------------------------ files, syntax

TEST(ModelReaderErrors, MissingFile) {
    try {
        read_model("/nonexistent/x.toml");
        FAIL();
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "cannot read model file '/nonexistent/x.toml': No such file or directory");
    }
}

TEST(ModelReaderErrors, DirectoryIsNotAModelFile) {
    try {
        read_model(HSNC_SOURCE_DIR);
        FAIL();
    } catch (const InputError& e) {
        expect_message(e.what(), {"cannot read model file '", "Is a directory"});
    }
}

TEST(ModelReaderErrors, TomlSyntaxError) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nname = \"m1\nm = 1\n"), {"test.toml:3:", "TOML syntax error"});
}

TEST(ModelReaderErrors, ParameterDefinedTwice) {
    // TOML itself forbids the second definition; toml++ reports it.
    expect_message(error_of("name = \"t\"\n[parameters]\nk = 1\nk = 2\n"),
                   {"test.toml:4:", "TOML syntax error", "'k'"});
}

// ------------------------------------------------------------- unknown keys

TEST(ModelReaderErrors, UnknownTopLevelKey) {
    expect_message(error_of("name = \"t\"\nmas = 1\n[[mass]]\nname = \"m1\"\nm = 1\n"),
                   {"test.toml:2: key 'mas': unknown key (expected one of: name, description"});
}

TEST(ModelReaderErrors, UnknownMassKey) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nname = \"m1\"\nm = 1\nmu = 0.5\n"),
                   {"test.toml:5: key 'mass[1].mu': unknown key", "mu_k"});
}

TEST(ModelReaderErrors, UnknownSpringKey) {
    expect_message(error_of(std::string(kTwoMasses) + "[[spring]]\nbetween = [\"m1\", \"m2\"]\nk = 1\nc = 2\n"),
                   {"test.toml:11: key 'spring[1].c': unknown key"});
}

TEST(ModelReaderErrors, UnknownContactKey) {
    expect_message(
        error_of(std::string(kTwoMasses) + "[[contact]]\nbetween = [\"m1\", \"m2\"]\ngap = 0\nk = 1\ndamping = 2\n"),
        {"test.toml:12: key 'contact[1].damping': unknown key"});
}

TEST(ModelReaderErrors, UnknownDampingKey) {
    expect_message(error_of(std::string(kTwoMasses) + "[damping]\ngamma = 0.1\n"),
                   {"test.toml:9: key 'damping.gamma': unknown key (expected one of: alpha, beta)"});
}

TEST(ModelReaderErrors, UnknownForcingKey) {
    expect_message(error_of(std::string(kTwoMasses) + "[[forcing]]\nomega = 1\namplitude = {}\nfrequency = 2\n"),
                   {"test.toml:11: key 'forcing[1].frequency': unknown key"});
}

TEST(ModelReaderErrors, UnknownInitialKey) {
    expect_message(error_of(std::string(kTwoMasses) + "[initial]\nx0 = { m1 = 1 }\n"),
                   {"test.toml:9: key 'initial.x0': unknown key (expected one of: t0, x, v)"});
}

TEST(ModelReaderErrors, UnknownSimulateKey) {
    expect_message(error_of(std::string(kTwoMasses) + "[simulate]\ntend = 1\n"),
                   {"test.toml:9: key 'simulate.tend': unknown key (expected one of: t_end)"});
}

TEST(ModelReaderErrors, InitialNamesUnknownMass) {
    expect_message(error_of(std::string(kTwoMasses) + "[initial]\nx = { m3 = 1 }\n"),
                   {"test.toml:9: key 'initial.x.m3': unknown mass 'm3'"});
}

TEST(ModelReaderErrors, LoadNamesUnknownMass) {
    expect_message(error_of(std::string(kTwoMasses) + "[load]\nground = 1\n"),
                   {"test.toml:9: key 'load.ground': unknown mass 'ground'"});
}

TEST(ModelReaderErrors, AmplitudeNamesUnknownMass) {
    expect_message(error_of(std::string(kTwoMasses) + "[[forcing]]\nomega = 1\namplitude = { m9 = 1 }\n"),
                   {"test.toml:10: key 'forcing[1].amplitude.m9': unknown mass 'm9'"});
}

// ------------------------------------------------------------- missing keys

TEST(ModelReaderErrors, MissingModelName) {
    // No line: the key is missing from the document as a whole.
    expect_message(error_of("[[mass]]\nname = \"m1\"\nm = 1\n"), {"test.toml: key 'name': required key is missing"});
}

TEST(ModelReaderErrors, MissingMassName) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nm = 1\n"),
                   {"test.toml:2: key 'mass[1].name': required key is missing"});
}

TEST(ModelReaderErrors, MissingMassValue) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nname = \"m1\"\n[[mass]]\nname = \"m2\"\n"),
                   {"test.toml:2: key 'mass[1].m': required key is missing"});
}

TEST(ModelReaderErrors, MissingSpringBetween) {
    expect_message(error_of(std::string(kTwoMasses) + "[[spring]]\nk = 1\n"),
                   {"test.toml:8: key 'spring[1].between': required key is missing"});
}

TEST(ModelReaderErrors, MissingSpringStiffness) {
    expect_message(error_of(std::string(kTwoMasses) + "[[spring]]\nbetween = [\"m1\", \"m2\"]\n"),
                   {"test.toml:8: key 'spring[1].k': required key is missing"});
}

TEST(ModelReaderErrors, MissingContactBetween) {
    expect_message(error_of(std::string(kTwoMasses) + "[[contact]]\ngap = 0\nk = 1\n"),
                   {"test.toml:8: key 'contact[1].between': required key is missing"});
}

TEST(ModelReaderErrors, MissingContactGap) {
    expect_message(error_of(std::string(kTwoMasses) + "[[contact]]\nbetween = [\"m1\", \"m2\"]\nk = 1\n"),
                   {"test.toml:8: key 'contact[1].gap': required key is missing"});
}

TEST(ModelReaderErrors, MissingContactStiffness) {
    expect_message(error_of(std::string(kTwoMasses) + "[[contact]]\nbetween = [\"m1\", \"m2\"]\ngap = 0\n"),
                   {"test.toml:8: key 'contact[1].k': required key is missing"});
}

TEST(ModelReaderErrors, MissingForcingOmega) {
    expect_message(error_of(std::string(kTwoMasses) + "[[forcing]]\namplitude = { m1 = 1 }\n"),
                   {"test.toml:8: key 'forcing[1].omega': required key is missing"});
}

TEST(ModelReaderErrors, MissingForcingAmplitude) {
    expect_message(error_of(std::string(kTwoMasses) + "[[forcing]]\nomega = 1\n"),
                   {"test.toml:8: key 'forcing[1].amplitude': required key is missing"});
}

TEST(ModelReaderErrors, NoMassesAtAll) {
    expect_message(error_of("name = \"t\"\n"), {"test.toml: key 'mass': no masses"});
}

TEST(ModelReaderErrors, EmptyMassArray) {
    expect_message(error_of("name = \"t\"\nmass = []\n"), {"test.toml:2: key 'mass': no masses"});
}

TEST(ModelReaderErrors, MassAsPlainTable) {
    expect_message(error_of("name = \"t\"\n[mass]\nname = \"m1\"\nm = 1\n"),
                   {"test.toml:2: key 'mass': expected an array of tables [[mass]], got table"});
}

// ---------------------------------------------------------- names and bodies

TEST(ModelReaderErrors, DuplicateMassName) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nname = \"m1\"\nm = 1\n[[mass]]\nname = \"m1\"\nm = 2\n"),
                   {"test.toml:6: key 'mass[2].name': name 'm1' is already used by mass[1]"});
}

TEST(ModelReaderErrors, DuplicateContactName) {
    expect_message(error_of(std::string(kTwoMasses) +
                            "[[contact]]\nname = \"c\"\nbetween = [\"m1\", \"m2\"]\ngap = 0\nk = 1\n"
                            "[[contact]]\nname = \"c\"\nbetween = [\"m1\", \"m2\"]\ngap = 0\nk = 1\n"),
                   {"test.toml:14: key 'contact[2].name': name 'c' is already used by contact[1]"});
}

TEST(ModelReaderErrors, ContactNamedLikeAMass) {
    // One name space for masses and contacts: the events CSV names either.
    expect_message(
        error_of(std::string(kTwoMasses) + "[[contact]]\nname = \"m2\"\nbetween = [\"m1\", \"m2\"]\ngap = 0\nk = 1\n"),
        {"test.toml:9: key 'contact[1].name': name 'm2' is already used by mass[2]"});
}

TEST(ModelReaderErrors, DefaultContactNameClashesWithAMass) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nname = \"contact1\"\nm = 1\n"
                            "[[contact]]\nbetween = [\"contact1\", \"ground\"]\ngap = 0\nk = 1\n"),
                   {"test.toml:5: key 'contact[1].name': name 'contact1' is already used by mass[1]"});
}

TEST(ModelReaderErrors, MassNamedGround) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nname = \"ground\"\nm = 1\n"),
                   {"test.toml:3: key 'mass[1].name': 'ground' is reserved"});
}

TEST(ModelReaderErrors, ContactNamedGround) {
    expect_message(
        error_of(std::string(kTwoMasses) + "[[contact]]\nname = \"ground\"\nbetween = [\"m1\", \"m2\"]\ngap = 0\nk = 1\n"),
        {"test.toml:9: key 'contact[1].name': 'ground' is reserved"});
}

TEST(ModelReaderErrors, InvalidMassName) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nname = \"1m\"\nm = 1\n"),
                   {"test.toml:3: key 'mass[1].name': '1m' is not a valid name"});
}

TEST(ModelReaderErrors, InvalidContactName) {
    expect_message(
        error_of(std::string(kTwoMasses) + "[[contact]]\nname = \"c-1\"\nbetween = [\"m1\", \"m2\"]\ngap = 0\nk = 1\n"),
        {"test.toml:9: key 'contact[1].name': 'c-1' is not a valid name"});
}

TEST(ModelReaderErrors, InvalidParameterName) {
    // A bare TOML key may contain '-', an expression name may not.
    expect_message(error_of("name = \"t\"\n[parameters]\nk-1 = 2\n"),
                   {"test.toml:3: key 'parameters.k-1': 'k-1' is not a valid name"});
}

TEST(ModelReaderErrors, ParameterNamedLikeAParserConstant) {
    expect_message(error_of("name = \"t\"\n[parameters]\nPi = 3\n"),
                   {"test.toml:3: key 'parameters.Pi': 'Pi' is a constant of the expression parser"});
}

TEST(ModelReaderErrors, ParameterNamedGround) {
    expect_message(error_of("name = \"t\"\n[parameters]\nground = 0\n"),
                   {"test.toml:3: key 'parameters.ground': 'ground' is reserved"});
}

TEST(ModelReaderErrors, UnknownBody) {
    expect_message(error_of(std::string(kTwoMasses) + "[[spring]]\nbetween = [\"m1\", \"m3\"]\nk = 1\n"),
                   {"test.toml:9: key 'spring[1].between': unknown body 'm3'"});
}

TEST(ModelReaderErrors, BetweenWithOneBody) {
    expect_message(error_of(std::string(kTwoMasses) + "[[spring]]\nbetween = [\"m1\"]\nk = 1\n"),
                   {"test.toml:9: key 'spring[1].between': expected a list of two body names"});
}

TEST(ModelReaderErrors, BetweenWithThreeBodies) {
    expect_message(error_of(std::string(kTwoMasses) + "[[contact]]\nbetween = [\"m1\", \"m2\", \"ground\"]\ngap = 0\nk = 1\n"),
                   {"test.toml:9: key 'contact[1].between': expected a list of two body names"});
}

TEST(ModelReaderErrors, BetweenAsAString) {
    expect_message(error_of(std::string(kTwoMasses) + "[[spring]]\nbetween = \"m1 m2\"\nk = 1\n"),
                   {"test.toml:9: key 'spring[1].between': expected a list of two body names"});
}

TEST(ModelReaderErrors, BetweenHoldsANumber) {
    expect_message(error_of(std::string(kTwoMasses) + "[[spring]]\nbetween = [\"m1\", 2]\nk = 1\n"),
                   {"test.toml:9: key 'spring[1].between': expected a string, got integer"});
}

TEST(ModelReaderErrors, SpringFromAMassToItself) {
    expect_message(error_of(std::string(kTwoMasses) + "[[spring]]\nbetween = [\"m2\", \"m2\"]\nk = 1\n"),
                   {"test.toml:9: key 'spring[1].between': connects 'm2' to itself"});
}

TEST(ModelReaderErrors, ContactFromGroundToGround) {
    expect_message(error_of(std::string(kTwoMasses) + "[[contact]]\nbetween = [\"ground\", \"ground\"]\ngap = 0\nk = 1\n"),
                   {"test.toml:9: key 'contact[1].between': connects 'ground' to itself"});
}

// -------------------------------------------------------------- expressions

TEST(ModelReaderErrors, UnknownParameterInExpression) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nname = \"m1\"\nm = \"2*mass1\"\n"),
                   {"test.toml:4: key 'mass[1].m': expression '2*mass1': unknown parameter 'mass1'"});
}

TEST(ModelReaderErrors, ParameterUsesALaterOne) {
    expect_message(error_of("name = \"t\"\n[parameters]\na = \"2*b\"\nb = 1\n"),
                   {"test.toml:3: key 'parameters.a': expression '2*b': unknown parameter 'b'",
                    "defined later; a parameter may use only earlier parameters"});
}

TEST(ModelReaderErrors, ExpressionDoesNotParse) {
    expect_message(error_of("name = \"t\"\n[parameters]\nk1 = 1\nk2 = \"k1+\"\n"),
                   {"test.toml:4: key 'parameters.k2': expression 'k1+' does not parse"});
}

TEST(ModelReaderErrors, EmptyExpression) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nname = \"m1\"\nm = \"\"\n"),
                   {"test.toml:4: key 'mass[1].m': expression '' does not parse"});
}

TEST(ModelReaderErrors, ExpressionIsComplex) {
    expect_message(error_of("name = \"t\"\n[parameters]\nk = \"sqrt(-1)\"\n"),
                   {"test.toml:3: key 'parameters.k': expression 'sqrt(-1)' is not a real number"});
}

TEST(ModelReaderErrors, ExpressionDividesByZero) {
    expect_message(error_of("name = \"t\"\n[parameters]\nk = \"1/0\"\n"),
                   {"test.toml:3: key 'parameters.k': expression '1/0' cannot be evaluated", "division by zero"});
}

TEST(ModelReaderErrors, ExpressionOverflows) {
    expect_message(error_of("name = \"t\"\n[parameters]\nk = \"exp(1000)\"\n"),
                   {"test.toml:3: key 'parameters.k': expression 'exp(1000)' is not a finite double"});
}

TEST(ModelReaderErrors, SubnormalValuesAreRefusedByName) {
    // A subnormal literal parameter used to end in "internal error: floating
    // point underflow" (no file, line or key), and a subnormal expression
    // used to read as 0. Both are refused like any out-of-range value; the
    // expression's value is computed on the subnormal grid to say which.
    const std::string reason = " is a subnormal double (magnitude below 2.2250738585072014e-308), too small to "
                               "compute with; write 0 or a magnitude of at least 2.2250738585072014e-308";
    expect_message(error_of("name = \"t\"\n[parameters]\nk = 1e-310\n"),
                   {("test.toml:3: key 'parameters.k': value 9.9999999999999694e-311" + reason).c_str()});
    expect_message(error_of("name = \"t\"\n[parameters]\nk = \"3*2^(-1074)\"\n"),
                   {("test.toml:3: key 'parameters.k': value 1.4821969375237396e-323" + reason).c_str()});
    expect_message(error_of(std::string(kTwoMasses) + "[[spring]]\nbetween = [\"m1\", \"m2\"]\nk = \"-1e-310\"\n"),
                   {("test.toml:10: key 'spring[1].k': value -9.9999999999999694e-311" + reason).c_str()});
    ModelOverrides o;
    o.set = {"k=2^(-1030)"};
    expect_message(error_of("name = \"t\"\n[parameters]\nk = 1\n", o),
                   {("--set 'k=2^(-1030)': value 8.6916947597937554e-311" + reason).c_str()});
    // The smallest normal double is accepted, from a literal and an expression.
    const Model m = parse_model("name = \"t\"\n[parameters]\na = 2.2250738585072014e-308\nb = \"2^(-1022)\"\n"
                                "[[mass]]\nname = \"m1\"\nm = 1\n",
                                "t.toml");
    EXPECT_EQ(m.parameters[1].second, DBL_MIN);
    EXPECT_EQ(m.parameters[2].second, DBL_MIN);
}

TEST(ModelReaderErrors, ValueBelowTheSmallestDouble) {
    expect_message(error_of("name = \"t\"\n[parameters]\nk = \"1e-400\"\n"),
                   {"test.toml:3: key 'parameters.k': expression '1e-400' is 1.0E-400, not 0 but below the smallest "
                    "positive double (4.9e-324)"});
}

TEST(ModelReaderErrors, FunctionOutsideTheAllowedList) {
    expect_message(error_of("name = \"t\"\n[parameters]\nk = \"zeta(3)\"\n"),
                   {"test.toml:3: key 'parameters.k': expression 'zeta(3)' does not parse: no function 'zeta' of 1 "
                    "argument (a model expression may use sin, cos, tan, asin, acos, atan, atan2, sinh, cosh, tanh, "
                    "asinh, acosh, atanh, exp, log, sqrt, abs, pow, factorial)"});
    expect_message(error_of("name = \"t\"\n[parameters]\nk = \"sin(1, 2)\"\n"), {"no function 'sin' of 2 arguments"});
}

TEST(ModelReaderErrors, MessagesShowAnExcerptOfALongExpression) {
    // 100 KB of expression: the message shows its first 80 characters.
    std::string sum;
    while (sum.size() < 100000) sum += "1+";
    const std::string message = error_of("name = \"t\"\n[parameters]\nk = \"" + sum + "x\"\n");
    expect_message(message, {"test.toml:3: key 'parameters.k': expression '", "...': unknown parameter 'x'"});
    EXPECT_NE(message.find("'" + sum.substr(0, 80) + "...'"), std::string::npos) << message;
    EXPECT_LT(message.size(), 200u);
    // Cut between characters, never inside one: 100 two-byte characters.
    std::string accents;
    for (int i = 0; i < 100; ++i) accents += "\xc3\xa9";  // U+00E9
    const std::string unicode = error_of("name = \"t\"\n[parameters]\nk = \"" + accents + "\"\n");
    EXPECT_NE(unicode.find("expression '" + accents.substr(0, 160) + "...'"), std::string::npos) << unicode;
    // A --set value too.
    ModelOverrides o;
    o.set = {"k=" + sum + "y"};
    const std::string flag = error_of("name = \"t\"\n[parameters]\nk = 1\n", o);
    EXPECT_LT(flag.size(), 300u) << flag;
    EXPECT_NE(flag.find("unknown parameter 'y'"), std::string::npos) << flag;
}

// ------------------------------------------------------- types and finiteness

TEST(ModelReaderErrors, TableWhereANumberIsExpected) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nname = \"m1\"\nm = { value = 1 }\n"),
                   {"test.toml:4: key 'mass[1].m': expected a number or an expression string, got table"});
}

TEST(ModelReaderErrors, BooleanWhereANumberIsExpected) {
    expect_message(error_of(std::string(kTwoMasses) + "[damping]\nbeta = true\n"),
                   {"test.toml:9: key 'damping.beta': expected a number or an expression string, got boolean"});
}

TEST(ModelReaderErrors, NumberWhereANameIsExpected) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nname = 1\nm = 1\n"),
                   {"test.toml:3: key 'mass[1].name': expected a string, got integer"});
}

TEST(ModelReaderErrors, InitialStateNotATable) {
    expect_message(error_of(std::string(kTwoMasses) + "[initial]\nx = 0.2\n"),
                   {"test.toml:9: key 'initial.x': expected a table of mass names"});
}

TEST(ModelReaderErrors, NanLiteral) {
    expect_message(error_of(std::string(kTwoMasses) + "[load]\nm1 = nan\n"),
                   {"test.toml:9: key 'load.m1': must be finite, got nan"});
}

TEST(ModelReaderErrors, InfLiteral) {
    expect_message(error_of(std::string(kTwoMasses) + "[[spring]]\nbetween = [\"m1\", \"ground\"]\nk = inf\n"),
                   {"test.toml:10: key 'spring[1].k': must be finite, got inf"});
}

// ------------------------------------------------------------ value ranges

TEST(ModelReaderErrors, MassNotPositive) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nname = \"m1\"\nm = 0\n"),
                   {"test.toml:4: key 'mass[1].m': mass must be > 0, got 0"});
}

TEST(ModelReaderErrors, NegativeSpringStiffness) {
    expect_message(error_of(std::string(kTwoMasses) + "[[spring]]\nbetween = [\"m1\", \"ground\"]\nk = \"-1\"\n"),
                   {"test.toml:10: key 'spring[1].k': spring stiffness must be >= 0, got -1"});
}

TEST(ModelReaderErrors, ContactStiffnessNotPositive) {
    expect_message(error_of(std::string(kTwoMasses) + "[[contact]]\nbetween = [\"m1\", \"m2\"]\ngap = 0\nk = 0\n"),
                   {"test.toml:11: key 'contact[1].k': contact stiffness must be > 0, got 0"});
}

TEST(ModelReaderErrors, NegativeKineticFriction) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nname = \"m1\"\nm = 1\nmu_k = -0.1\n"),
                   {"test.toml:5: key 'mass[1].mu_k': must be >= 0, got -0.1"});
}

TEST(ModelReaderErrors, StaticBelowKineticFriction) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nname = \"m1\"\nm = 1\nmu_k = 0.6\nmu_s = 0.5\n"),
                   {"test.toml:6: key 'mass[1].mu_s': static coefficient must be >= mu_k = 0.6, got 0.5"});
}

TEST(ModelReaderErrors, StaticWithoutKineticFriction) {
    expect_message(error_of("name = \"t\"\n[[mass]]\nname = \"m1\"\nm = 1\nmu_s = 0.5\n"),
                   {"test.toml:5: key 'mass[1].mu_s': mu_s given without mu_k"});
}

TEST(ModelReaderErrors, NegativeAlpha) {
    expect_message(error_of(std::string(kTwoMasses) + "[damping]\nalpha = -0.1\n"),
                   {"test.toml:9: key 'damping.alpha': must be >= 0, got -0.1"});
}

TEST(ModelReaderErrors, NegativeBeta) {
    expect_message(error_of(std::string(kTwoMasses) + "[damping]\nbeta = \"-1e-3\"\n"),
                   {"test.toml:9: key 'damping.beta': must be >= 0, got -0.001"});
}

TEST(ModelReaderErrors, ForcingOmegaZero) {
    // omega = 0 would be a constant force: [load] says that directly.
    expect_message(error_of(std::string(kTwoMasses) + "[[forcing]]\nomega = 0\namplitude = { m1 = 1 }\n"),
                   {"test.toml:9: key 'forcing[1].omega': must be > 0, got 0", "[load]"});
}

TEST(ModelReaderErrors, ForcingOmegaNegative) {
    expect_message(error_of(std::string(kTwoMasses) + "[[forcing]]\nomega = -3\namplitude = { m1 = 1 }\n"),
                   {"test.toml:9: key 'forcing[1].omega': must be > 0, got -3"});
}

TEST(ModelReaderErrors, EndTimeNotAfterStart) {
    expect_message(error_of(std::string(kTwoMasses) + "[initial]\nt0 = 1\n[simulate]\nt_end = 1\n"),
                   {"test.toml:11: key 'simulate.t_end': must be > t0 = 1, got 1"});
}

TEST(ModelReaderErrors, GravityNotPositive) {
    expect_message(error_of("name = \"t\"\n[parameters]\ng = 0\n[[mass]]\nname = \"m1\"\nm = 1\n"),
                   {"test.toml:3: key 'parameters.g': gravity g must be > 0"});
}

// -------------------------------------------------------------------- flags

TEST(ModelReaderErrors, SetUnknownParameter) {
    ModelOverrides o;
    o.set = {"k9=1"};
    EXPECT_EQ(error_of(kTwoMasses, o), "--set 'k9=1': no parameter named 'k9'");
}

TEST(ModelReaderErrors, SetWithoutEquals) {
    ModelOverrides o;
    o.set = {"k1"};
    EXPECT_EQ(error_of(kTwoMasses, o), "--set 'k1': expected NAME=VALUE");
}

TEST(ModelReaderErrors, SetWithEmptyValue) {
    ModelOverrides o;
    o.set = {"g="};
    expect_message(error_of(kTwoMasses, o), {"--set 'g=': expected NAME=VALUE, VALUE is empty"});
}

TEST(ModelReaderErrors, SetWithBadExpression) {
    ModelOverrides o;
    o.set = {"g=9.81*"};
    expect_message(error_of(kTwoMasses, o), {"--set 'g=9.81*': expression '9.81*' does not parse"});
}

TEST(ModelReaderErrors, SetUsesALaterParameter) {
    ModelOverrides o;
    o.set = {"a=b"};
    expect_message(error_of("name = \"t\"\n[parameters]\na = 1\nb = 2\n[[mass]]\nname = \"m1\"\nm = 1\n", o),
                   {"--set 'a=b': expression 'b': unknown parameter 'b'", "defined later"});
}

TEST(ModelReaderErrors, SetTwice) {
    ModelOverrides o;
    o.set = {"g=1", "g=2"};
    expect_message(error_of(kTwoMasses, o), {"--set 'g=2': 'g' is already set by --set 'g=1'"});
}

TEST(ModelReaderErrors, X0WithoutEquals) {
    ModelOverrides o;
    o.x0 = {"m1"};
    EXPECT_EQ(error_of(kTwoMasses, o), "--x0 'm1': expected NAME=VALUE");
}

TEST(ModelReaderErrors, X0UnknownMass) {
    ModelOverrides o;
    o.x0 = {"ground=1"};
    EXPECT_EQ(error_of(kTwoMasses, o), "--x0 'ground=1': no mass named 'ground'");
}

TEST(ModelReaderErrors, V0NotARealNumber) {
    ModelOverrides o;
    o.v0 = {"m2=sqrt(-4)"};
    expect_message(error_of(kTwoMasses, o), {"--v0 'm2=sqrt(-4)': expression 'sqrt(-4)' is not a real number"});
}

TEST(ModelReaderErrors, V0InvalidName) {
    ModelOverrides o;
    o.v0 = {"2m=1"};
    expect_message(error_of(kTwoMasses, o), {"--v0 '2m=1': '2m' is not a valid name"});
}

// ------------------------------------------------- rates beyond the double range

// k = 1e300 on m = 1e-300: k/m overflows and every solver stepped NaN states
// to a run that ended "ok". The reader refuses the element whose stiffness
// (or damping, or force) over the mass is beyond the double range, by key.
TEST(ModelReaderErrors, StiffnessOverMassBeyondTheDoubleRange) {
    const std::string tiny = "name = \"t\"\n[[mass]]\nname = \"m1\"\nm = 1e-300\n";  // lines 1-4
    expect_message(error_of(tiny + "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 1e300\n"),
                   {"test.toml:7: key 'spring[1].k': the spring: stiffness 1e+300 over "
                    "mass 'm1' (m = 1e-300) is beyond the double range: the natural frequency "
                    "sqrt(k/m) would not be finite"});
    expect_message(error_of(tiny + "[[contact]]\nname = \"stop\"\nbetween = [\"m1\", \"ground\"]\ngap = 0\nk = 1e300\n"),
                   {"test.toml:9: key 'contact[1].k': contact 'stop': stiffness", "natural frequency"});
    expect_message(error_of(tiny + "[[jenkins]]\nbetween = [\"m1\", \"ground\"]\nk = 1e300\nslip_force = 1\n"),
                   {"test.toml:7: key 'jenkins[1].k': Jenkins element 'jenkins1': stiffness", "natural frequency"});
    expect_message(error_of(tiny + "[[damper]]\nbetween = [\"m1\", \"ground\"]\nc = 1e300\n"),
                   {"test.toml:7: key 'damper[1].c': the damper: damping 1e+300", "decay rate c/m"});
    expect_message(error_of(tiny + "[load]\nm1 = 1e300\n"),
                   {"test.toml:6: key 'load.m1': the load: force 1e+300 over mass 'm1'", "acceleration F/m"});
    // Two springs each within range whose sum over the mass is not: the mass is named.
    const std::string one = "name = \"t\"\n[[mass]]\nname = \"m1\"\nm = 0.5\n";
    expect_message(error_of(one + "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 8e307\n"
                                  "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 8e307\n"),
                   {"test.toml:4: key 'mass[1].m': the stiffnesses on mass 'm1' (m = 0.5) sum to 1.6e+308; over the "
                    "mass that is beyond the double range"});
    expect_message(error_of(one + "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 1e300\n[damping]\nbeta = 1e10\n"),
                   {"key 'damping.beta': beta = 1e+10 times the stiffness over mass 'm1'", "modal damping"});
    // Within the range: read.
    EXPECT_NO_THROW(parse_model(tiny + "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 1e7\n", "ok.toml"));
}

}  // namespace
}  // namespace hsnc
