// The analyses' rules beyond the closed forms of tests/test_periodic.cpp:
//  - KernelKinds: hsnc::periodic and hsnc::lyapunov run on whichever kernel
//    kind the facade selects (generic, aot, jit) with the same tangent
//    dynamics: orbits and multipliers agree across kinds to 1e-12;
//  - TangentRank: a stick collapses a direction: the number of -inf
//    exponents is the number of masses stuck at the end of a decay, and the
//    Jacobian of the flow (the monodromy of an orbit with a stick phase)
//    loses one rank per stuck mass;
//  - GrazingOrbit: an orbit that touches a stop with zero normal velocity is
//    reported as grazing (periodic, lyapunov and their command lines), one
//    that crosses it transversally is not.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/SVD>

#include "cli_runner.h"
#include "engine.h"
#include "hsnc/lyapunov.h"
#include "hsnc/periodic.h"
#include "hsnc/simulate.h"
#include "kernel_mode.h"
#include "model_reader.h"
#include "tangent.h"

namespace hsnc {
namespace {

using testing::model_path;
using testing::run_hsnc;
using testing::temp_path;
using testing::write_temp;

// Each expected multiplier has a computed one within tol (and the counts agree).
void expect_same_set(std::vector<std::complex<double>> got, const std::vector<std::complex<double>>& want, double tol,
                     const std::string& what) {
    ASSERT_EQ(got.size(), want.size()) << what;
    for (const auto& w : want) {
        auto best = std::min_element(got.begin(), got.end(),
                                     [&](const auto& a, const auto& b) { return std::abs(a - w) < std::abs(b - w); });
        EXPECT_LT(std::abs(*best - w), tol * (1 + std::abs(w))) << what << ": multiplier " << w << ", nearest " << *best;
        got.erase(best);
    }
}

// eigen: the Eigen solver, the independent reference the others are held to.
// generic: the configurations' programs, without a compiler (the bits of jit).
// aot: the bundled models' kernels as generated (chain-8's cover the
// configurations of its bundled run, not every one its orbit enters: automatic
// falls back to generic for those).
std::vector<KernelChoice> kinds(bool aot = true) {
    std::vector<KernelChoice> k = {KernelChoice::eigen, KernelChoice::generic, KernelChoice::automatic};
    if (aot) k.push_back(KernelChoice::aot);
#if HSNC_WITH_JIT
    k.push_back(KernelChoice::jit);
#endif
    return k;
}

TEST(KernelKinds, PeriodicOrbitsAndMultipliersAgree) {
    const std::string cache = temp_path("cache");
    struct Case {
        const char* file;
        double transient;
        bool aot;
    };
    for (const Case& c : {Case{"seed-scenario-1.toml", 0.0, true}, Case{"chain-8.toml", 100.0, false}}) {
        const Model m = read_model(model_path(c.file));
        PeriodicResult ref;
        for (KernelChoice k : kinds(c.aot)) {
            const std::string what = std::string(c.file) + " kernels " + kernel_choice_name(k);
            PeriodicOptions o;
            o.transient = c.transient;
            o.kernels = k;
            o.cache_dir = cache;
            o.tolerance = 1e-12;
            const PeriodicResult p = periodic(m, o);
            ASSERT_EQ(p.status, PeriodicStatus::ok) << what << ": " << p.message;
            if (k == KernelChoice::eigen) {
                ref = p;
                continue;
            }
            double worst = 0;
            for (std::size_t i = 0; i < m.dof(); ++i) {
                worst = std::max({worst, std::fabs(p.x[i] - ref.x[i]) / (1 + std::fabs(ref.x[i])),
                                  std::fabs(p.v[i] - ref.v[i]) / (1 + std::fabs(ref.v[i]))});
                EXPECT_NEAR(p.x[i], ref.x[i], 1e-12 * (1 + std::fabs(ref.x[i]))) << what << " x" << i;
                EXPECT_NEAR(p.v[i], ref.v[i], 1e-12 * (1 + std::fabs(ref.v[i]))) << what << " v" << i;
            }
            EXPECT_EQ(p.events, ref.events) << what;
            expect_same_set(p.multipliers, ref.multipliers, 1e-12, what);
            std::printf("%s: orbit within %.3g of the Eigen solver's, max |mu| %.17g (eigen %.17g)\n", what.c_str(),
                        worst, p.max_multiplier, ref.max_multiplier);
        }
    }
    std::error_code ec;
    std::filesystem::remove_all(cache, ec);
}

TEST(KernelKinds, LyapunovSpectraAgree) {
    const std::string cache = temp_path("cache");
    const Model m = read_model(model_path("seed-scenario-2.toml"));
    LyapunovResult ref;
    for (KernelChoice k : kinds()) {
        LyapunovOptions o;
        o.t_end = 30;
        o.kernels = k;
        o.cache_dir = cache;
        const LyapunovResult r = lyapunov(m, o);
        ASSERT_EQ(r.status, RunStatus::ok) << kernel_choice_name(k);
        if (k == KernelChoice::eigen) {
            ref = r;
            continue;
        }
        EXPECT_EQ(r.events, ref.events) << kernel_choice_name(k);
        EXPECT_EQ(r.collapsed, ref.collapsed) << kernel_choice_name(k);
        for (std::size_t i = 0; i < r.exponents.size(); ++i) {
            if (std::isinf(ref.exponents[i])) {
                EXPECT_EQ(r.exponents[i], ref.exponents[i]);
                continue;
            }
            EXPECT_NEAR(r.exponents[i], ref.exponents[i], 1e-12) << kernel_choice_name(k) << " lambda_" << i + 1;
        }
    }
    std::error_code ec;
    std::filesystem::remove_all(cache, ec);
}

TEST(KernelKinds, AotWithoutKernelsIsAnOptionError) {
    Model m = read_model(model_path("seed-scenario-1.toml"), {{"k1=6"}, {}, {}});  // not as generated
    PeriodicOptions o;
    o.kernels = KernelChoice::aot;
    try {
        periodic(m, o);
        FAIL() << "no OptionError";
    } catch (const OptionError& e) {
        EXPECT_EQ(e.option(), "kernels");
    }
}

// Which masses are stuck at the end of a run (from its events).
class StuckAtEnd : public Observer {
public:
    explicit StuckAtEnd(std::size_t n) : stuck(n, 0) {}
    void on_sample(double, const double*, const double*) override {}
    void on_event(double, EventKind k, int e, const double*, const double*) override {
        if (k == EventKind::stick) stuck[static_cast<std::size_t>(e)] = 1;
        if (k == EventKind::release) stuck[static_cast<std::size_t>(e)] = 0;
        if (k == EventKind::stick) ++sticks;
    }
    std::size_t count() const { return static_cast<std::size_t>(std::count(stuck.begin(), stuck.end(), 1)); }
    std::vector<char> stuck;
    int sticks = 0;
};

// Numerical rank: singular values above 1e-10 of the largest.
int rank_of(const Eigen::MatrixXd& J) {
    const Eigen::VectorXd s = Eigen::JacobiSVD<Eigen::MatrixXd>(J).singularValues();
    int r = 0;
    for (Eigen::Index i = 0; i < s.size(); ++i) r += s(i) > 1e-10 * s(0);
    return r;
}

// Unforced, undamped: two friction masses (both end stuck), or a friction
// mass beside a frictionless one that keeps oscillating (the first ends stuck).
Model decay(bool both_friction) {
    Model m;
    m.name = "decay";
    m.g = 9.81;
    m.masses = {{"m1", 1.0}, {"m2", 2.0}};
    m.friction_slots = {{true, 0.3, 0.4}, {both_friction, 0.2, 0.25}};
    m.springs = {{kGround, 0, 10.0}, {0, 1, both_friction ? 5.0 : 0.2}, {1, kGround, 8.0}};
    m.load = {0.0, 0.0};
    m.x0 = {0.3, -0.2};
    m.v0 = {1.0, 0.5};
    return m;
}

TEST(TangentRank, MinusInfExponentsAreTheStuckMassesAtTheEnd) {
    for (bool both : {true, false}) {
        const Model m = decay(both);
        const std::size_t n = m.dof();
        // The run's events: which masses are stuck at its end.
        StuckAtEnd end(n);
        SimulateOptions so;
        so.t_end = 20;
        so.samples = false;
        so.kernels = KernelChoice::generic;
        ASSERT_EQ(simulate(m, so, end).status, RunStatus::ok);
        ASSERT_GT(end.sticks, 0);
        ASSERT_EQ(end.count(), both ? 2u : 1u) << "the model ends with these stuck";
        LyapunovOptions o;
        o.t_end = 20;
        o.kernels = KernelChoice::generic;
        const LyapunovResult r = lyapunov(m, o);
        ASSERT_EQ(r.status, RunStatus::ok);
        const std::size_t minus_inf = static_cast<std::size_t>(
            std::count(r.exponents.begin(), r.exponents.end(), -std::numeric_limits<double>::infinity()));
        EXPECT_EQ(minus_inf, end.count()) << "both friction " << both;
        EXPECT_EQ(r.collapsed, end.count());
        // The flow's Jacobian over the run: rank 2n minus the stuck masses,
        // the velocity rows of the stuck masses exactly 0.
        GenericSolverProvider provider(m);
        Engine engine(m, provider);
        analysis::JacobianObserver jac(m);
        EngineOptions eo;
        eo.t_end = 20;
        eo.samples = false;
        ASSERT_EQ(engine.run(eo, jac).status, RunStatus::ok);
        const Eigen::MatrixXd& J = jac.jacobian();
        EXPECT_EQ(rank_of(J), static_cast<int>(2 * n - end.count())) << "both friction " << both;
        for (std::size_t i = 0; i < n; ++i)
            if (end.stuck[i]) EXPECT_TRUE(J.row(static_cast<Eigen::Index>(n + i)).isZero(0.0)) << i;
        std::printf("%s: %zu stuck at t = 20, exponents %g %g %g %g, rank of the Jacobian %d\n",
                    both ? "two friction masses" : "one friction mass", end.count(), r.exponents[0], r.exponents[1],
                    r.exponents[2], r.exponents[3], rank_of(J));
    }
}

// Den Hartog's oscillator (m = k = 1, friction beta, forcing sin(r t)) at low
// frequency sticks every half period: its monodromy has rank 1 (2n - 1), one
// multiplier exactly 0, and one -inf exponent.
TEST(TangentRank, StickPhaseDropsTheMonodromysRank) {
    Model m;
    m.name = "den_hartog_stick";
    m.g = 1.0;
    m.masses.push_back({"m1", 1.0});
    m.set_friction(m.masses.size() - 1) = {true, 0.5, 0.5};
    m.springs.push_back({kGround, 0, 1.0});
    m.forcing.push_back({0.5, 0.0, {1.0}});
    m.load = {0.0};
    m.x0 = {0.0};
    m.v0 = {0.0};
    PeriodicOptions o;
    o.transient = 100;
    o.kernels = KernelChoice::generic;
    StuckAtEnd events(1);
    const PeriodicResult p = periodic(m, o, &events);
    ASSERT_EQ(p.status, PeriodicStatus::ok) << p.message;
    ASSERT_EQ(events.sticks, 2) << "two stick phases a period";
    const Eigen::Map<const Eigen::Matrix<double, 2, 2, Eigen::RowMajor>> M(p.monodromy.data());
    EXPECT_EQ(rank_of(M), 1);
    EXPECT_LT(std::abs(p.multipliers.back()), 1e-15 * std::abs(p.multipliers.front()));
    LyapunovOptions lo;
    lo.transient = 100;
    lo.t_end = 4000;
    lo.kernels = KernelChoice::generic;
    const LyapunovResult r = lyapunov(m, lo);
    ASSERT_EQ(r.status, RunStatus::ok);
    EXPECT_EQ(r.collapsed, 1u);
    EXPECT_EQ(r.exponents[1], -std::numeric_limits<double>::infinity());
    EXPECT_TRUE(std::isfinite(r.exponents[0]));
    // The remaining multiplier is exp(lambda_1 T) of the orbit; a measurement
    // over t converges as 1/t (measured: 0.0148 apart after 50 s).
    EXPECT_NEAR(std::log(std::abs(p.multipliers[0])) / p.period, r.exponents[0], 1e-3);
    std::printf("sticking orbit: multipliers %.6g, %.3g; exponents %.6g, %g\n", std::abs(p.multipliers[0]),
                std::abs(p.multipliers[1]), r.exponents[0], r.exponents[1]);
}

// A damped oscillator (m = k = 1, C = 0.2 M + 0.01 K) forced by sin(1.3 t)
// moves on x = X sin(1.3 t - phase) (started on it: x0 = -c w X^2, v0 =
// w (1 - w^2) X^2); a stop at gap d = X (1 - eps) is touched once a period
// with normal velocity about 1.3 X sqrt(2 eps). (Started at rest, the
// transient hits the stop and the motion settles on another, impacting orbit.)
constexpr double kOmega = 1.3, kAlpha = 0.2, kBeta = 0.01;
double linear_amplitude() {
    const double c = kAlpha + kBeta;
    return 1.0 / std::sqrt((1 - kOmega * kOmega) * (1 - kOmega * kOmega) + (c * kOmega) * (c * kOmega));
}

Model grazing_model(double eps) {
    Model m;
    m.name = "graze";
    m.masses = {{"m1", 1.0}};
    m.springs = {{kGround, 0, 1.0}};
    m.contacts = {{"stop", 0, kGround, linear_amplitude() * (1 - eps), 50.0}};
    m.alpha = kAlpha;
    m.beta = kBeta;
    m.forcing.push_back({kOmega, 0.0, {1.0}});
    m.load = {0.0};
    const double X = linear_amplitude(), c = kAlpha + kBeta;
    m.x0 = {-c * kOmega * X * X};
    m.v0 = {kOmega * (1 - kOmega * kOmega) * X * X};
    return m;
}

class ContactEvents : public Observer {
public:
    void on_sample(double, const double*, const double*) override {}
    void on_event(double, EventKind k, int, const double*, const double*) override {
        count += k == EventKind::contact_close || k == EventKind::contact_open;
    }
    std::size_t count = 0;
};

TEST(GrazingOrbit, TouchingOrbitIsReportedTransversalIsNot) {
    for (double eps : {1e-10, 1e-12, 0.05}) {
        const bool grazes = eps < 1e-3;
        const Model m = grazing_model(eps);
        PeriodicOptions o;
        o.kernels = KernelChoice::generic;
        // A stop well inside the free motion: the orbit the motion settles on hits it.
        if (!grazes) o.transient = 300;
        ContactEvents per_period;
        const PeriodicResult p = periodic(m, o, &per_period);
        ASSERT_EQ(p.status, PeriodicStatus::ok) << eps << ": " << p.message;
        ASSERT_EQ(per_period.count, 2u) << eps << ": the stop is reached once a period";
        EXPECT_EQ(p.grazing, grazes ? 2u : 0u) << eps;
        // The measurement over 30 periods from the orbit: every contact switch grazes, or none.
        Model on = m;
        on.t0 = p.t;
        on.x0 = p.x;
        on.v0 = p.v;
        LyapunovOptions lo;
        lo.t_end = 30 * p.period;
        lo.kernels = KernelChoice::generic;
        ContactEvents all;
        const LyapunovResult r = lyapunov(on, lo, {}, &all);
        ASSERT_EQ(r.status, RunStatus::ok);
        EXPECT_GE(all.count, 58u) << eps;
        EXPECT_EQ(r.grazing, grazes ? all.count : 0u) << eps;
        EXPECT_EQ(r.singular, 0u) << eps;
        std::printf("stop at X (1 - %g): %zu contact switches a period, grazing %zu; over 30 periods %zu switches, "
                    "grazing %zu; max |mu| %.6f\n",
                    eps, per_period.count, p.grazing, all.count, r.grazing, p.max_multiplier);
    }
}

const char* const kGrazeToml = R"toml(
name = "graze"
[parameters]
eps = 1e-10
D = "(1 - 1.3^2)^2 + (0.21*1.3)^2"   # 1/X^2 of the motion without the stop
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["m1", "ground"]
k = 1
[damping]
alpha = 0.2
beta = 0.01
[[contact]]
name = "stop"
between = ["m1", "ground"]
gap = "(1 - eps)/sqrt(D)"
k = 50
[[forcing]]
omega = 1.3
amplitude = { m1 = 1 }
[initial]
x = { m1 = "-(0.21*1.3)/D" }
v = { m1 = "1.3*(1 - 1.3^2)/D" }
)toml";

TEST(PeriodicCli, GrazingOrbitIsReported) {
    const std::string model = write_temp("graze.toml", kGrazeToml);
    const testing::CliRun r = run_hsnc("periodic '" + model + "' --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find(" grazing=2\n"), std::string::npos) << r.out;
    EXPECT_NE(r.err.find("hsnc: warning: the orbit grazes: 2 switch instants a period"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("not reliable"), std::string::npos) << r.err;
    const testing::CliRun clear = run_hsnc("periodic '" + model + "' --quiet --set eps=0.05 --transient 300");
    ASSERT_EQ(clear.exit_code, 0) << clear.err;
    EXPECT_NE(clear.out.find(" grazing=0\n"), std::string::npos) << clear.out;
    EXPECT_TRUE(clear.err.empty()) << clear.err;
}

TEST(LyapunovCli, GrazingIsReported) {
    const std::string model = write_temp("graze.toml", kGrazeToml);
    const testing::CliRun r = run_hsnc("lyapunov '" + model + "' --t-end 50 --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto at = r.out.find(" grazing=");
    ASSERT_NE(at, std::string::npos) << r.out;
    const int n = std::stoi(r.out.substr(at + 9));
    // 50 s is 10.3 periods of 4.83 s: 20 or 22 contact switches, all grazing.
    EXPECT_GE(n, 20) << r.out;
    EXPECT_LE(n, 22) << r.out;
    EXPECT_NE(r.err.find("hsnc: warning: the motion grazes: " + std::to_string(n) + " switch instants"),
              std::string::npos)
        << r.err;
}

}  // namespace
}  // namespace hsnc
