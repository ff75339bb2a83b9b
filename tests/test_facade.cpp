// The library facade (api/hsnc/simulate.h): hsnc::simulate gives what
// `hsnc simulate` gives, bad options are an OptionError that names the
// option and no command-line flag, every kernel choice and method runs through
// it, and the engine and providers refuse a temporary Model they would keep a
// reference to.
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <functional>
#include <iterator>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "cached_kernel_provider.h"
#include "kernel_cache.h"
#include "cli_runner.h"
#include "engine_runner.h"
#include "hsnc/check.h"
#include "hsnc/generate.h"
#include "hsnc/hsnc.h"
#include "jit_solver_provider.h"
#include "kernel_mode.h"
#include "temp_dir.h"

namespace hsnc {
namespace {

namespace fs = std::filesystem;
using testing::model_path;
using testing::Recorder;

// ---- the lifetime fix ---------------------------------------------------------
// `Engine e(read_model(path), provider)` kept a reference to a destroyed Model.
static_assert(!std::is_constructible_v<Engine, Model, SolverProvider&>, "a temporary Model would dangle");
static_assert(!std::is_constructible_v<Engine, const Model, SolverProvider&>, "a temporary Model would dangle");
static_assert(std::is_constructible_v<Engine, Model&, SolverProvider&>);
static_assert(std::is_constructible_v<Engine, const Model&, SolverProvider&>);
static_assert(!std::is_constructible_v<GenericSolverProvider, Model>);
static_assert(std::is_constructible_v<GenericSolverProvider, const Model&>);
static_assert(!std::is_constructible_v<AotSolverProvider, Model, const AotRegistry&, bool>);
static_assert(std::is_constructible_v<AotSolverProvider, const Model&, const AotRegistry&, bool>);
static_assert(!std::is_constructible_v<JitSolverProvider, Model, JitSolverProvider::SourceFn, JitOptions>);
static_assert(std::is_constructible_v<JitSolverProvider, const Model&, JitSolverProvider::SourceFn, JitOptions>);
static_assert(!std::is_constructible_v<CachedKernelProvider, Model, JitSolverProvider::SourceFn, JitOptions,
                                       CachedKernelProvider::JitFactory>);
static_assert(std::is_constructible_v<CachedKernelProvider, const Model&, JitSolverProvider::SourceFn, JitOptions,
                                      CachedKernelProvider::JitFactory>);
template <class M, class = void>
struct CanMakeProvider : std::false_type {};
template <class M>
struct CanMakeProvider<M, std::void_t<decltype(make_solver_provider(std::declval<M>(), KernelChoice::generic,
                                                                    nullptr))>> : std::true_type {};
static_assert(!CanMakeProvider<Model>::value, "make_solver_provider(read_model(p), ...) would dangle");
static_assert(CanMakeProvider<const Model&>::value);

// The facade itself takes the model for the call only: a temporary is safe.
TEST(Facade, ATemporaryModelIsSafe) {
    SimulateOptions o;
    o.t_end = 1.0;
    const SimulateSummary s = hsnc::simulate(read_model(model_path("coulomb-1dof.toml")), o);
    EXPECT_EQ(s.status, RunStatus::ok);
    EXPECT_EQ(s.t, 1.0);
    EXPECT_GT(s.events, 0u);
}

// ---- the same events as the command line ----------------------------------------
std::vector<std::vector<std::string>> csv_rows(const std::string& path) {
    std::vector<std::vector<std::string>> rows;
    std::istringstream in(testing::slurp(path));
    for (std::string line; std::getline(in, line);) {
        std::vector<std::string> f;
        std::istringstream l(line);
        for (std::string cell; std::getline(l, cell, ',');) f.push_back(cell);
        rows.push_back(f);
    }
    return rows;
}

std::string element_name(const Model& m, const testing::Recorded& e) {
    const bool contact = e.kind == EventKind::contact_close || e.kind == EventKind::contact_open;
    return contact ? m.contacts[e.element].name : m.masses[e.element].name;
}

struct Case {
    const char* model;
    const char* flags;  ///< of `hsnc simulate`
    double t_end;
    Method method;
    double h;  ///< ab4
    KernelChoice kernels;
    SolverKind solver;
};

class FacadeAgreesWithCli : public ::testing::TestWithParam<Case> {};

TEST_P(FacadeAgreesWithCli, SameEventsSameEndState) {
    const Case& c = GetParam();
    const Model model = read_model(model_path(c.model));
    SimulateOptions o;
    o.t_end = c.t_end;
    o.method = c.method;
    o.integrator.h = c.h;
    o.kernels = c.kernels;
    Recorder rec(model.dof());
    const SimulateSummary s = hsnc::simulate(model, o, rec);
    ASSERT_EQ(s.status, RunStatus::ok) << s.message;
    EXPECT_EQ(s.solver, c.solver) << solver_kind_name(s.solver);
    EXPECT_EQ(s.events, rec.events.size());
    EXPECT_FALSE(s.solver_detail.empty());

    const std::string ev = testing::temp_path("events.csv");
    const auto r = testing::run_hsnc("simulate '" + model_path(c.model) + "' --quiet --t-end " +
                                     std::to_string(c.t_end) + " " + c.flags + " --events '" + ev + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto rows = csv_rows(ev);
    ASSERT_EQ(rows.size(), rec.events.size() + 1) << "header and one row per event";
    ASSERT_GE(rec.events.size(), 10u);
    for (std::size_t i = 0; i < rec.events.size(); ++i) {
        const auto& e = rec.events[i];
        // The same computation: the printed times read back to the same doubles.
        EXPECT_EQ(std::stod(rows[i + 1][0]), e.t) << i;
        EXPECT_EQ(rows[i + 1][1], event_kind_name(e.kind)) << i;
        EXPECT_EQ(rows[i + 1][2], element_name(model, e)) << i;
    }
    std::ostringstream x0;
    x0.precision(17);
    x0 << " x_" << model.masses[0].name << "=" << s.x[0] << " ";
    EXPECT_NE(r.out.find(x0.str()), std::string::npos) << r.out << " lacks" << x0.str();
    EXPECT_NE(r.out.find(" events=" + std::to_string(s.events) + " "), std::string::npos) << r.out;
    std::remove(ev.c_str());
}

INSTANTIATE_TEST_SUITE_P(
    Methods, FacadeAgreesWithCli,
    ::testing::Values(
        Case{"seed-scenario-2.toml", "", 20.0, Method::hsnc, 0, KernelChoice::automatic, SolverKind::aot},
        Case{"seed-scenario-2.toml", "--kernels generic", 20.0, Method::hsnc, 0, KernelChoice::generic,
             SolverKind::generic},
        Case{"seed-scenario-2.toml", "--kernels interp", 20.0, Method::hsnc, 0, KernelChoice::interp,
             SolverKind::interp},
        Case{"seed-scenario-2.toml", "--kernels eigen", 20.0, Method::hsnc, 0, KernelChoice::eigen,
             SolverKind::eigen},
        Case{"seed-scenario-1.toml", "--kernels aot", 1.0, Method::hsnc, 0, KernelChoice::aot, SolverKind::aot},
        Case{"coulomb-1dof.toml", "", 5.0, Method::hsnc, 0, KernelChoice::automatic, SolverKind::aot},
        Case{"coulomb-1dof.toml", "--method rk45", 5.0, Method::rk45, 0, KernelChoice::automatic,
             SolverKind::integrator},
        Case{"coulomb-1dof.toml", "--method ab4 --h 1e-4", 5.0, Method::ab4, 1e-4, KernelChoice::automatic,
             SolverKind::integrator},
        Case{"coulomb-1dof.toml", HSNC_WITH_CVODE ? "--method cvode" : "--method rk45", 5.0,
             HSNC_WITH_CVODE ? Method::cvode : Method::rk45, 0, KernelChoice::automatic, SolverKind::integrator}),
    [](const ::testing::TestParamInfo<Case>& i) {
        std::string name = std::string(i.param.model) + "_" + method_name(i.param.method) + "_" +
                           kernel_choice_name(i.param.kernels);
        for (char& c : name)
            if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
        return name;
    });

// auto on a model without ahead-of-time kernels is the generic solver: no
// compilation, no cache.
TEST(Facade, AutoWithoutAotKernelsIsTheGenericSolverAndNeverTheCache) {
    const std::string dir = testing::temp_path("cache");
    const Model model = read_model(model_path("seed-scenario-2.toml"), {{"mu_k=0.31"}, {}, {}});
    SimulateOptions o;
    o.t_end = 5;
    o.cache_dir = dir;
    const SimulateSummary s = hsnc::simulate(model, o);
    EXPECT_EQ(s.status, RunStatus::ok);
    EXPECT_EQ(s.solver, SolverKind::generic);
    EXPECT_NE(s.solver_detail.find("generic solver for 2 configurations"), std::string::npos) << s.solver_detail;
    EXPECT_FALSE(fs::exists(dir));
}

#if HSNC_WITH_JIT
// jit: compiled, then from the cache, the same switches as the Eigen solver.
TEST(Facade, JitKernelsThroughTheCache) {
    const std::string dir = testing::temp_path("cache");
    const Model model = read_model(model_path("seed-scenario-2.toml"), {{"mu_k=0.31"}, {}, {}});
    SimulateOptions o;
    o.t_end = 5;
    o.kernels = KernelChoice::eigen;
    Recorder generic(model.dof());
    hsnc::simulate(model, o, generic);
    o.kernels = KernelChoice::jit;
    o.cache_dir = dir;
    std::vector<std::string> warnings;
    o.warn = [&](const std::string& w) { warnings.push_back(w); };
    for (const char* run : {"compiled", "cached"}) {
        Recorder jit(model.dof());
        const SimulateSummary s = hsnc::simulate(model, o, jit);
        EXPECT_EQ(s.solver, SolverKind::jit) << run;
        EXPECT_NE(s.solver_detail.find("JIT: 2 configurations visited"), std::string::npos) << s.solver_detail;
        ASSERT_EQ(jit.events.size(), generic.events.size()) << run;
        for (std::size_t i = 0; i < jit.events.size(); ++i) {
            EXPECT_EQ(jit.events[i].kind, generic.events[i].kind) << run << i;
            EXPECT_NEAR(jit.events[i].t, generic.events[i].t, 1e-9) << run << i;
        }
    }
    EXPECT_TRUE(warnings.empty());
    EXPECT_FALSE(fs::is_empty(dir));
    fs::remove_all(dir);
}
#endif

TEST(Facade, HighPrecisionReference) {
    const Model model = read_model(model_path("coulomb-1dof.toml"));
    SimulateOptions o;
    o.t_end = 1;
    o.precision_digits = 30;
    const SimulateSummary ref = hsnc::simulate(model, o);
    o.precision_digits = 0;
    const SimulateSummary dbl = hsnc::simulate(model, o);
    EXPECT_EQ(ref.solver, SolverKind::reference);
    EXPECT_NE(ref.solver_detail.find("30 digits"), std::string::npos) << ref.solver_detail;
    EXPECT_EQ(ref.events, dbl.events);
    EXPECT_NEAR(ref.x[0], dbl.x[0], 1e-12);
}

// ---- bad options ------------------------------------------------------------------
struct BadOption {
    const char* what;
    std::function<void(SimulateOptions&)> set;
    const char* option;
    const char* message;  ///< what() contains it
};

class FacadeBadOptions : public ::testing::TestWithParam<BadOption> {};

TEST_P(FacadeBadOptions, OptionErrorNamingTheFieldAndNoFlag) {
    const Model model = read_model(model_path("coulomb-1dof.toml"), {{"k=99"}, {}, {}});  // no AOT kernels
    SimulateOptions o;
    GetParam().set(o);
    Recorder rec(model.dof());
    try {
        hsnc::simulate(model, o, rec);
        FAIL() << GetParam().what << ": no error";
    } catch (const OptionError& e) {
        const std::string what = e.what();
        EXPECT_EQ(what.rfind("hsnc::simulate(): ", 0), 0u) << what;
        EXPECT_EQ(e.option(), GetParam().option) << what;
        EXPECT_NE(what.find(GetParam().message), std::string::npos) << what;
        EXPECT_EQ(what.find("--"), std::string::npos) << "names a command-line flag: " << what;
        EXPECT_NE(what.find(e.reason()), std::string::npos);
    }
    EXPECT_TRUE(rec.events.empty() && rec.samples.empty()) << "nothing ran";
}

INSTANTIATE_TEST_SUITE_P(
    Cases, FacadeBadOptions,
    ::testing::Values(
        BadOption{"t_end before t0", [](SimulateOptions& o) { o.t_end = -1; }, "t_end",
                  "t_end = -1: must be finite and after t0 = 0"},
        BadOption{"dt 0", [](SimulateOptions& o) { o.t_end = 1, o.dt = 0; }, "dt", "dt = 0: must be > 0"},
        BadOption{"ab4 without h", [](SimulateOptions& o) { o.t_end = 1, o.method = Method::ab4; },
                  "integrator.h", "method ab4 needs a fixed step h > 0"},
        BadOption{"rk45 rtol 0",
                  [](SimulateOptions& o) { o.t_end = 1, o.method = Method::rk45, o.integrator.rtol = 0; },
                  "integrator.rtol", "must be finite and > 0"},
        BadOption{"rk45 atol < 0",
                  [](SimulateOptions& o) { o.t_end = 1, o.method = Method::rk45, o.integrator.atol = -1; },
                  "integrator.atol", "must be finite and > 0"},
        BadOption{"19 digits", [](SimulateOptions& o) { o.t_end = 1, o.precision_digits = 19; },
                  "precision_digits", "expected 0 (double), or N in 20..100"},
        BadOption{"digits with rk45",
                  [](SimulateOptions& o) { o.t_end = 1, o.precision_digits = 30, o.method = Method::rk45; },
                  "precision_digits", "only with method hsnc (not rk45)"},
        BadOption{"digits with generic",
                  [](SimulateOptions& o) { o.t_end = 1, o.precision_digits = 30, o.kernels = KernelChoice::generic; },
                  "kernels", "applies to double precision only"},
        BadOption{"kernels with a baseline",
                  [](SimulateOptions& o) { o.t_end = 1, o.method = Method::rk45, o.kernels = KernelChoice::jit; },
                  "kernels", "applies to method hsnc only (not rk45)"},
        BadOption{"aot without kernels", [](SimulateOptions& o) { o.t_end = 1, o.kernels = KernelChoice::aot; },
                  "kernels", "no ahead-of-time kernels for model 'coulomb-1dof'"}),
    [](const ::testing::TestParamInfo<BadOption>& i) {
        std::string name = i.param.what;
        for (char& c : name)
            if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
        return name;
    });

TEST(Facade, NoEndTimeIsAnOptionError) {
    const Model model = parse_model("name = \"spring\"\n[[mass]]\nname = \"m1\"\nm = 1.0\n"
                                    "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 1.0\n",
                                    "spring.toml");
    try {
        hsnc::simulate(model);
        FAIL() << "no error";
    } catch (const OptionError& e) {
        EXPECT_EQ(e.option(), "t_end");
        EXPECT_STREQ(e.what(), "hsnc::simulate(): t_end = NaN: no end time: none given and the model has no "
                               "[simulate].t_end (spring.toml)");
    }
}

// The library guide shows examples/simulate_model.cpp as it is.
TEST(Facade, LibraryGuideShowsTheExampleConsumer) {
    const std::string readme = testing::slurp(std::string(HSNC_SOURCE_DIR) + "/docs/guide/library.md");
    const auto section = readme.find("\n## The C++ library\n");
    ASSERT_NE(section, std::string::npos);
    const auto start = readme.find("```cpp\n", section);
    ASSERT_NE(start, std::string::npos);
    const auto end = readme.find("```\n", start + 7);
    const std::string shown = readme.substr(start + 7, end - start - 7);
    std::string example = testing::slurp(std::string(HSNC_SOURCE_DIR) + "/examples/simulate_model.cpp");
    example = example.substr(example.find("#include"));  // after its header comment
    EXPECT_EQ(shown, example);
}

// One name table (kernel_choice.h) for the command line, the facade, Python
// and the runtime: every kind parses back from its name, and a run reports a
// kernel kind by the same name.
TEST(Facade, KernelChoiceNamesAreOneTable) {
    const std::vector<std::pair<const char*, KernelChoice>> expected = {
        {"auto", KernelChoice::automatic}, {"aot", KernelChoice::aot},     {"generic", KernelChoice::generic},
        {"interp", KernelChoice::interp},  {"eigen", KernelChoice::eigen}, {"jit", KernelChoice::jit},
        {"tiered", KernelChoice::tiered}};
    ASSERT_EQ(std::size(kKernelChoiceNames), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) {
        EXPECT_STREQ(kKernelChoiceNames[i].name, expected[i].first);
        EXPECT_EQ(kernel_choice_from_name(expected[i].first), expected[i].second);
        EXPECT_STREQ(kernel_choice_name(expected[i].second), expected[i].first);
    }
    EXPECT_EQ(kernel_choice_names(), "auto, aot, generic, interp, eigen, jit or tiered");
    for (SolverKind k : {SolverKind::aot, SolverKind::jit, SolverKind::generic, SolverKind::interp, SolverKind::eigen,
                         SolverKind::tiered})
        EXPECT_EQ(kernel_choice_from_name(solver_kind_name(k)), static_cast<KernelChoice>(k));
    EXPECT_STREQ(solver_kind_name(SolverKind::reference), "reference");
    EXPECT_STREQ(solver_kind_name(SolverKind::integrator), "integrator");
}

// generate and check through the facade (api/hsnc/generate.h, check.h): the
// command line and the Python module call these, so the library writes what
// `hsnc generate` writes and returns what `hsnc check` prints.
TEST(Facade, GenerateAndCheckAreTheCommandLines) {
    const std::string path = model_path("seed-scenario-2.toml");
    const Model model = read_model(path);
    testing::TempDir lib, cli;
    const GeneratedKernels k = generate_kernels(model);
    const std::vector<std::string> written = write_kernels(model, k, lib.path());
    EXPECT_EQ(written.size(), k.kernels() + 2);
    const auto g = testing::run_hsnc("generate '" + path + "' -o '" + cli.path() + "'");
    ASSERT_EQ(g.exit_code, 0) << g.err;
    ASSERT_EQ(lib.names().size(), written.size());
    ASSERT_EQ(lib.names(), cli.names());
    for (const std::string& name : lib.names())
        EXPECT_EQ(testing::slurp(lib / name), testing::slurp(cli / name)) << name;
    std::ostringstream report;
    check_report(model, report);
    const auto c = testing::run_hsnc("check '" + path + "'");
    ASSERT_EQ(c.exit_code, 0) << c.err;
    EXPECT_EQ(report.str(), c.out);
}

TEST(Facade, NamesParseOrSayWhat) {
    EXPECT_EQ(method_from_name("cvode"), Method::cvode);
    EXPECT_EQ(kernel_choice_from_name("auto"), KernelChoice::automatic);
    EXPECT_EQ(kernel_choice_from_name("jit"), KernelChoice::jit);
    EXPECT_EQ(precision_digits_from_name("double"), 0);
    EXPECT_EQ(precision_digits_from_name("mp:50"), 50);
    for (Method m : {Method::hsnc, Method::ab4, Method::rk45, Method::cvode})
        EXPECT_EQ(method_from_name(method_name(m)), m);
    struct Bad {
        std::function<void()> parse;
        const char* option;
        const char* message;
    };
    const Bad bad[] = {
        {[] { method_from_name("euler"); }, "method",
         "hsnc::method_from_name(): method = 'euler': expected hsnc, ab4, rk45 or cvode"},
        {[] { kernel_choice_from_name("fast"); }, "kernels",
         "hsnc::kernel_choice_from_name(): kernels = 'fast': expected auto, aot, generic, interp, eigen, jit or tiered"},
        {[] { precision_digits_from_name("mp:3x"); }, "precision_digits",
         "hsnc::precision_digits_from_name(): precision_digits = mp:3x: expected double, or mp:N with N in 20..100"},
        {[] { precision_digits_from_name("long-double"); }, "precision_digits", "not offered; use mp:N"},
    };
    for (const Bad& b : bad) {
        try {
            b.parse();
            ADD_FAILURE() << b.message << ": no error";
        } catch (const OptionError& e) {
            EXPECT_EQ(e.option(), b.option);
            EXPECT_NE(std::string(e.what()).find(b.message), std::string::npos) << e.what();
        }
    }
}

}  // namespace
}  // namespace hsnc

// The facade's default cache size is the cache's own (one default, not two).
TEST(Facade, DefaultCacheSizeIsTheCachesDefault) {
    EXPECT_EQ(hsnc::SimulateOptions{}.cache_max_bytes, hsnc::kDefaultCacheMaxBytes);
}
