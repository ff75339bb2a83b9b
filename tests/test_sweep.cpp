// hsnc sweep (api/hsnc/sweep.h, cli/sweep.cpp): response curves against
// closed forms (Den Hartog's friction oscillator, the linear oscillator's
// |H(omega)|), the two branches of a hardening contact oscillator, and the
// distribution (threads, --part, MPI ranks) giving identical bytes.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <csignal>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Dense>

#include "cli_runner.h"
#include "fe_models.h"
#include "hsnc/simulate.h"
#include "hsnc/sweep.h"
#include "model_reader.h"

namespace hsnc {
namespace {

using testing::file_exists;
using testing::run_hsnc;
using testing::slurp;
using testing::temp_path;
using testing::write_temp;

constexpr double kPi = 3.14159265358979323846;

// m x'' + k x + F_f sign(x') = F0 sin(omega t) with m = k = F0 = 1 (so
// r = omega) and F_f = beta (g = 1, mu_k = beta): Den Hartog (1930).
const char* const kDenHartog = R"(
name = "den-hartog"
[parameters]
r = 2.0
beta = 0.3
g = 1.0
[[mass]]
name = "m"
m = 1.0
mu_k = "beta"
[[spring]]
between = ["ground", "m"]
k = 1.0
[[forcing]]
omega = "r"
amplitude = { m = 1.0 }
)";

// x'' + 2 zeta x' + x = sin(omega t) (Rayleigh alpha = 2 zeta).
const char* const kLinear = R"(
name = "linear"
[parameters]
omega = 1.0
zeta = 0.05
F = 1.0
[[mass]]
name = "m"
m = 1.0
[[spring]]
between = ["ground", "m"]
k = 1.0
[damping]
alpha = "2*zeta"
[[forcing]]
omega = "omega"
amplitude = { m = "F" }
)";

// A linear oscillator (omega_n = 1, zeta = 0.02) that meets a stiff stop
// (k = 10) at x = 0.5: a hardening response curve that leans to the right.
const char* const kHardening = R"(
name = "hardening"
[parameters]
omega = 1.0
F = 0.1
[[mass]]
name = "m"
m = 1.0
[[spring]]
between = ["ground", "m"]
k = 1.0
[damping]
alpha = 0.04
[[contact]]
between = ["m", "ground"]
gap = 0.5
k = 10.0
[[forcing]]
omega = "omega"
amplitude = { m = "F" }
)";

double den_hartog_amplitude(double r, double beta) {
    const double U = std::tan(kPi / (2 * r)) / r, V = 1 / (1 - r * r);
    return std::sqrt(V * V - beta * beta * U * U);
}

// Den Hartog's non-sticking steady amplitude X = sqrt(V^2 - beta^2 U^2)
// (in units of F0/k), r = omega/omega_n, U = tan(pi/(2r))/r, V = 1/(1-r^2):
// xmax over several r and two friction levels (a second parameter), up and
// down, to 1e-8.
TEST(SweepClosedForm, DenHartogFrictionOscillator) {
    SweepOptions o;
    o.param = "r";
    o.from = 1.5;
    o.to = 3.0;
    o.points = 7;
    o.direction = SweepDirection::both;
    o.max_periods = 2000;
    o.param2 = "beta";
    o.values2 = {0.1, 0.3};
    const SweepResult r = SweepPlan(kDenHartog, "den-hartog.toml", {}, o).run();
    ASSERT_EQ(r.points.size(), 2u * 2u * 7u);
    std::size_t up = 0;
    for (const SweepPoint& p : r.points) {
        SCOPED_TRACE("r = " + std::to_string(p.value) + ", beta = " + std::to_string(p.value2) + ", " +
                     sweep_direction_name(p.direction));
        EXPECT_TRUE(p.settled);
        EXPECT_EQ(p.multiple, 1);
        const double X = den_hartog_amplitude(p.value, p.value2);
        EXPECT_NEAR(p.xmax[0] / X, 1.0, 1e-8);
        up += p.direction == SweepDirection::up;
    }
    EXPECT_EQ(up, 14u);
    // Output order: beta = 0.1 up (r rising), down (r falling), then beta = 0.3.
    EXPECT_EQ(r.points[0].value, 1.5);
    EXPECT_EQ(r.points[6].value, 3.0);
    EXPECT_EQ(r.points[7].value, 3.0);
    EXPECT_EQ(r.points[7].direction, SweepDirection::down);
    EXPECT_EQ(r.points[14].value2, 0.3);
}

// The linear oscillator's steady response x = F |H| sin(omega t + phi),
// |H| = 1/sqrt((1 - r^2)^2 + (2 zeta r)^2): xmax = a1 = F |H|,
// xrms = F |H| / sqrt(2), through resonance.
TEST(SweepClosedForm, LinearOscillatorResponseCurve) {
    SweepOptions o;
    o.param = "omega";
    o.from = 0.5;
    o.to = 1.5;
    o.points = 11;
    o.max_periods = 2000;
    o.record_periods = 8;
    const SweepResult r = SweepPlan(kLinear, "linear.toml", ModelOverrides{{"F=2.5"}, {}, {}, {}}, o).run();
    ASSERT_EQ(r.points.size(), 11u);
    for (const SweepPoint& p : r.points) {
        SCOPED_TRACE("omega = " + std::to_string(p.value));
        const double w = p.value, X = 2.5 / std::sqrt((1 - w * w) * (1 - w * w) + (0.1 * w) * (0.1 * w));
        EXPECT_TRUE(p.settled);
        EXPECT_EQ(p.multiple, 1);
        EXPECT_NEAR(p.xmax[0] / X, 1.0, 1e-8);
        EXPECT_NEAR(p.a1[0] / X, 1.0, 1e-8);
        EXPECT_NEAR(p.xrms[0] / (X / std::sqrt(2.0)), 1.0, 1e-8);
        ASSERT_EQ(p.strobe_t.size(), 8u);
        // The diagram: one state per recorded period, all the same on a period-1 orbit.
        for (std::size_t k = 1; k < 8; ++k) EXPECT_NEAR(p.strobe_x[k], p.strobe_x[0], 1e-8 * X);
        EXPECT_NEAR(p.strobe_t[7] - p.strobe_t[6], 2 * kPi / w, 1e-12 * p.strobe_t[7]);
    }
}

// Up and down sweeps of the hardening oscillator: inside the hysteresis band
// the up sweep stays on the upper branch (beyond the stop, xmax > 0.5) and
// the down sweep on the lower (linear, xmax < 0.5); outside it they agree.
TEST(SweepClosedForm, HardeningContactOscillatorBranches) {
    SweepOptions o;
    o.param = "omega";
    o.from = 0.8;
    o.to = 2.0;
    o.points = 25;  // step 0.05
    o.direction = SweepDirection::both;
    o.max_periods = 3000;
    const SweepResult r = SweepPlan(kHardening, "hardening.toml", {}, o).run();
    ASSERT_EQ(r.points.size(), 50u);
    std::size_t inside = 0, outside = 0;
    for (std::size_t j = 0; j < 25; ++j) {
        const SweepPoint& up = r.points[j];
        const SweepPoint& down = r.points[49 - j];
        ASSERT_EQ(up.value, down.value);
        SCOPED_TRACE("omega = " + std::to_string(up.value));
        EXPECT_TRUE(up.settled && down.settled);
        const double w = up.value;
        if (w > 1.17 && w < 1.33) {  // the band
            EXPECT_GT(up.xmax[0], 0.5);
            EXPECT_LT(down.xmax[0], 0.5);
            EXPECT_GT(up.xmax[0], 2.5 * down.xmax[0]);
            ++inside;
        } else if (w < 1.08 || w > 1.42) {
            EXPECT_NEAR(up.xmax[0], down.xmax[0], 1e-7 * up.xmax[0]);
            ++outside;
        }
        // Below the stop the oscillator is linear: the closed form holds on either branch.
        for (const SweepPoint* p : {&up, &down})
            if (p->xmax[0] < 0.49) {
                const double X = 0.1 / std::sqrt((1 - w * w) * (1 - w * w) + (0.04 * w) * (0.04 * w));
                EXPECT_NEAR(p->xmax[0] / X, 1.0, 1e-7);
            }
    }
    EXPECT_EQ(inside, 3u);
    EXPECT_GE(outside, 18u);
}

// A 20-element consistent-mass cantilever (40 dofs, omega_max = 1.7e5 rad/s,
// the top modes overdamped) forced at its tip: the recorder grids a segment
// at the terms that still move (SegmentSolver::resolving_rate), not at
// omega_max. Linear, its steady response is X = (K - omega^2 M + i omega C)^-1 F:
// xmax = a1 = |X_i|, xrms = |X_i|/sqrt(2) at every dof, rotations and
// deflections alike, to 1e-8.
TEST(SweepClosedForm, StiffBeamResponseAtEveryDof) {
    const fe::Beam beam = fe::cantilever(20);
    testing::TempDir dir;
    const std::string path = fe::structure_model(dir, "beam.toml", "beam", beam.M, beam.K, beam.dofs,
                                                 "[parameters]\nomega = 15.0\n[damping]\nalpha = 2.5\nbeta = 2e-5\n"
                                                 "[[forcing]]\nomega = \"omega\"\namplitude = { w20 = 5.0 }\n");
    SweepOptions o;
    o.param = "omega";
    o.from = 15;
    o.to = 60;
    o.points = 2;
    o.max_periods = 2000;
    o.record_periods = 4;
    const SweepResult r = SweepPlan(slurp(path), path, {}, o).run();
    ASSERT_EQ(r.points.size(), 2u);
    const Eigen::Index n = beam.K.rows();
    Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
    f(beam.tip) = 5.0;
    for (const SweepPoint& p : r.points) {
        SCOPED_TRACE("omega = " + std::to_string(p.value));
        EXPECT_TRUE(p.settled);
        EXPECT_EQ(p.multiple, 1);
        const double w = p.value;
        const Eigen::MatrixXcd D = (beam.K - w * w * beam.M).cast<std::complex<double>>() +
                                   std::complex<double>(0, w) * (2.5 * beam.M + 2e-5 * beam.K);
        const Eigen::VectorXcd X = D.partialPivLu().solve(f.cast<std::complex<double>>());
        for (Eigen::Index i = 0; i < n; ++i) {
            const auto k = static_cast<std::size_t>(i);
            const double a = std::abs(X(i));
            EXPECT_NEAR(p.xmax[k] / a, 1.0, 1e-8) << beam.dofs[k];
            EXPECT_NEAR(p.a1[k] / a, 1.0, 1e-8) << beam.dofs[k];
            EXPECT_NEAR(p.xrms[k] / (a / std::sqrt(2.0)), 1.0, 1e-8) << beam.dofs[k];
        }
    }
}

// One sweep point at omega recording one period, against the steady orbit
// sampled densely by the engine (20000 samples a period: Simpson's
// integrals, the largest sample) at every dof, to 1e-6 (the dense
// sampling's own error); `events` switch events a period.
void expect_recorded_metrics_of_a_dense_run(const std::string& path, double omega, std::size_t events) {
    SweepOptions o;
    o.param = "omega";
    o.from = o.to = omega;
    o.points = 1;
    o.max_periods = 2000;
    o.record_periods = 1;
    const SweepResult r = SweepPlan(slurp(path), path, {}, o).run();
    ASSERT_EQ(r.points.size(), 1u);
    const SweepPoint& p = r.points[0];
    ASSERT_TRUE(p.settled);
    ASSERT_EQ(p.multiple, 1);

    // The steady orbit: the model's run to the window's start, then one period sampled densely.
    Model m = read_model(path);
    const double T = 2 * kPi / omega;
    SimulateOptions so;
    so.t_end = m.t0 + static_cast<double>(p.periods) * T;
    so.samples = false;
    const SimulateSummary settle = simulate(m, so);
    ASSERT_EQ(settle.status, RunStatus::ok) << settle.message;
    m.x0 = settle.x;
    m.v0 = settle.v;
    m.t0 = so.t_end;
    constexpr int kN = 20000;
    struct Dense : Observer {
        std::size_t n = 0, events = 0;
        std::vector<std::vector<double>> x;
        void on_sample(double, const double* xs, const double*) override {
            x.emplace_back(xs, xs + static_cast<std::ptrdiff_t>(n));
        }
        void on_event(double, EventKind, int, const double*, const double*) override { ++events; }
    } dense;
    dense.n = m.dof();
    so.t_end = m.t0 + T;
    so.dt = T / kN;
    so.samples = true;
    const SimulateSummary window = simulate(m, so, dense);
    ASSERT_EQ(window.status, RunStatus::ok) << window.message;
    ASSERT_EQ(dense.x.size(), static_cast<std::size_t>(kN) + 1);
    EXPECT_EQ(dense.events, events) << "switch events a period";
    for (std::size_t i = 0; i < m.dof(); ++i) {
        double xmax = 0, sxx = 0, sxc = 0, sxs = 0;
        for (int k = 0; k <= kN; ++k) {
            const double x = dense.x[static_cast<std::size_t>(k)][i], wk = (k == 0 || k == kN) ? 1 : (k % 2 ? 4 : 2);
            const double th = 2 * kPi * k / kN;
            xmax = std::max(xmax, std::abs(x));
            sxx += wk * x * x;
            sxc += wk * x * std::cos(th);
            sxs += wk * x * std::sin(th);
        }
        const double h = T / kN / 3;  // Simpson
        const double rms = std::sqrt(h * sxx / T), a1 = std::hypot(2 * h * sxc / T, 2 * h * sxs / T);
        SCOPED_TRACE(m.masses[i].name);
        EXPECT_NEAR(p.xmax[i] / xmax, 1.0, 1e-6);
        EXPECT_NEAR(p.xrms[i] / rms, 1.0, 1e-6);
        EXPECT_NEAR(p.a1[i] / a1, 1.0, 1e-6);
    }
}

// The same beam with a stop under its tip (two impacts a period, each
// exciting the stiff modes, which the damping then takes away).
TEST(SweepClosedForm, StiffBeamWithAStopAgainstADenseRun) {
    const fe::Beam beam = fe::cantilever(20);
    testing::TempDir dir;
    const std::string path =
        fe::structure_model(dir, "beam.toml", "beam", beam.M, beam.K, beam.dofs,
                            "[parameters]\nomega = 15.0\n[damping]\nalpha = 0.2\nbeta = 2e-5\n"
                            "[[contact]]\nbetween = [\"w20\", \"ground\"]\ngap = 0.004\nk = 2000.0\n"
                            "[[forcing]]\nomega = \"omega\"\namplitude = { w20 = 5.0 }\n");
    expect_recorded_metrics_of_a_dense_run(path, 15.0, 4);
}

// A chain with a discrete damper (non-proportional damping: the state-space
// solver's segments and its resolving_rate) across a stiffer spring, and a stop.
TEST(SweepClosedForm, AChainWithADamperAndAStopAgainstADenseRun) {
    std::string text = "name = \"damped-chain\"\n[parameters]\nomega = 3.0\n";
    for (int i = 1; i <= 6; ++i) text += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = 1.0\n";
    for (int i = 0; i < 6; ++i)
        text += "[[spring]]\nbetween = [\"" + (i == 0 ? std::string("ground") : "m" + std::to_string(i)) + "\", \"m" +
                std::to_string(i + 1) + "\"]\nk = " + (i == 5 ? "400.0" : "100.0") + "\n";
    text +=
        "[damping]\nalpha = 0.1\n[[damper]]\nbetween = [\"m5\", \"m6\"]\nc = 2.0\n"
        "[[contact]]\nbetween = [\"m6\", \"ground\"]\ngap = 0.05\nk = 500.0\n"
        "[[forcing]]\nomega = \"omega\"\namplitude = { m6 = 10.0 }\n";
    const std::string path = write_temp("damped-chain.toml", text);
    expect_recorded_metrics_of_a_dense_run(path, 3.0, 2);
}

// The same plan on 1 and 2 threads, with tasks of every kind (directions,
// a second parameter, points restarted from the initial state): bit-equal.
TEST(SweepClosedForm, ThreadsGiveTheSameBits) {
    for (bool restart : {false, true}) {
        SweepOptions o;
        o.param = "omega";
        o.from = 1.0;
        o.to = 1.4;
        o.points = 5;
        o.direction = SweepDirection::both;
        o.restart_each = restart;
        o.param2 = "F";
        o.values2 = {0.1, 0.12};
        o.max_periods = 300;
        o.record_periods = 4;
        const SweepResult one = SweepPlan(kHardening, "hardening.toml", {}, o).run();
        o.threads = 2;
        const SweepResult two = SweepPlan(kHardening, "hardening.toml", {}, o).run();
        ASSERT_EQ(one.points.size(), two.points.size());
        ASSERT_EQ(one.points.size(), 20u);
        for (std::size_t i = 0; i < one.points.size(); ++i) {
            const SweepPoint &a = one.points[i], &b = two.points[i];
            EXPECT_EQ(a.value, b.value);
            EXPECT_EQ(a.periods, b.periods);
            EXPECT_EQ(a.xmax, b.xmax);
            EXPECT_EQ(a.xrms, b.xrms);
            EXPECT_EQ(a.a1, b.a1);
            EXPECT_EQ(a.strobe_x, b.strobe_x);
            EXPECT_EQ(a.strobe_v, b.strobe_v);
        }
    }
}

TEST(Sweep, PlanRefusesWhatDoesNotFit) {
    auto plan = [](const std::string& model, SweepOptions o, const ModelOverrides& ov = {}) {
        SweepPlan p(model, "m.toml", ov, std::move(o));
    };
    SweepOptions o;
    o.param = "omega";
    o.from = 1;
    o.to = 2;
    o.points = 3;
    EXPECT_NO_THROW(plan(kLinear, o));
    auto expect = [&](SweepOptions bad, const std::string& option, const std::string& text,
                      const ModelOverrides& ov = {}) {
        try {
            plan(kLinear, bad, ov);
            ADD_FAILURE() << "no error for " << option;
        } catch (const OptionError& e) {
            EXPECT_EQ(e.option(), option);
            EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
        }
    };
    SweepOptions b = o;
    b.param = "nope";
    expect(b, "param", "no parameter named 'nope'");
    b = o;
    b.points = 0;
    expect(b, "points", ">= 1");
    b = o;
    b.from = NAN;
    expect(b, "from", "finite");
    b = o;
    b.record_periods = 0;
    expect(b, "record_periods", ">= 1");
    b = o;
    b.param2 = "omega";
    b.values2 = {1};
    expect(b, "param2", "swept parameter");
    b = o;
    b.param2 = "zeta";
    expect(b, "values2", "required");
    expect(o, "param", "also set by an override", ModelOverrides{{"omega=3"}, {}, {}, {}});
    // A value at which the model is invalid: named, before anything runs.
    try {
        SweepOptions z = o;
        z.param = "zeta";
        z.from = 0.1;
        z.to = -0.1;  // alpha = 2*zeta < 0 at the last point
        plan(kLinear, z);
        ADD_FAILURE() << "negative damping accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("sweep at zeta = -0.1"), std::string::npos) << e.what();
    }
    // No forcing: no period to sweep over.
    const std::string unforced = R"(
name = "free"
[parameters]
k = 1.0
[[mass]]
name = "m"
m = 1.0
[[spring]]
between = ["ground", "m"]
k = "k"
)";
    SweepOptions f = o;
    f.param = "k";
    EXPECT_THROW(plan(unforced, f), InputError);
}

// ---- the command line ----

std::string sweep_args(const std::string& model, const std::string& extra) {
    return "sweep '" + model + "' --param omega --from 1.0 --to 1.4 --points 5 --direction both --max-periods 300 " +
           "--record-periods 4 --quiet " + extra;
}

TEST(SweepCli, CurveAndDiagramFiles) {
    const std::string model = write_temp("hardening.toml", kHardening);
    const std::string out = temp_path("curve.csv"), diagram = temp_path("diagram.csv"), png = temp_path("sweep.png");
    const auto r = run_hsnc(sweep_args(model, "--out '" + out + "' --diagram '" + diagram + "' --plot '" + png + "'"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.out, "status=ok points=10 up=5 down=5 settled=10 unsettled=0 failed=0\n");
    const std::string curve = slurp(out);
    EXPECT_EQ(curve.substr(0, curve.find('\n')), "omega,direction,settled,periods,multiple,xmax_m,xrms_m,a1_m");
    EXPECT_EQ(std::count(curve.begin(), curve.end(), '\n'), 11);
    EXPECT_NE(curve.find("\n1,up,true,"), std::string::npos);
    EXPECT_NE(curve.find("\n1,down,true,"), std::string::npos);
    const std::string d = slurp(diagram);
    EXPECT_EQ(d.substr(0, d.find('\n')), "omega,direction,t,x_m,v_m");
    EXPECT_EQ(std::count(d.begin(), d.end(), '\n'), 1 + 10 * 4);
    EXPECT_EQ(slurp(png).substr(1, 3), "PNG");
}

TEST(SweepCli, ProgressLinePerPoint) {
    const std::string model = write_temp("hardening.toml", kHardening);
    const auto r = run_hsnc("sweep '" + model + "' --param omega --from 1.0 --to 1.2 --points 3 --max-periods 50");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("hsnc sweep: point 1/3 omega = 1 up:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("hsnc sweep: point 3/3 omega = 1.2 up:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(" s/point, about "), std::string::npos) << r.err;
    // Values as a person writes them: 20, not the shortest %g "2e+01".
    const auto tens = run_hsnc("sweep '" + model + "' --param omega --from 10 --to 20 --points 2 --max-periods 5");
    ASSERT_EQ(tens.exit_code, 0) << tens.err;
    EXPECT_NE(tens.err.find("hsnc sweep: point 1/2 omega = 10 up:"), std::string::npos) << tens.err;
    EXPECT_NE(tens.err.find("hsnc sweep: point 2/2 omega = 20 up:"), std::string::npos) << tens.err;
    const auto q = run_hsnc("sweep '" + model + "' --param omega --from 1.0 --to 1.2 --points 3 --max-periods 50 --quiet");
    EXPECT_EQ(q.err, "");
}

// Runs hsnc with `args` (stdout to `out`, stderr to `err`), sends one SIGINT
// once stderr says `marker`, and returns the wait status; `seconds`: from the
// signal to the end.
int interrupt_run(const std::vector<std::string>& args, const std::string& out, const std::string& err,
                  const std::string& marker, double& seconds) {
    const pid_t pid = testing::spawn_hsnc(args, out, err);
    if (pid < 0) return -1;
    bool started = false;
    for (int i = 0; i < 3000 && !started; ++i) {
        started = slurp(err).find(marker) != std::string::npos;
        if (!started) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    EXPECT_TRUE(started) << slurp(err);
    const auto t0 = std::chrono::steady_clock::now();
    ::kill(pid, SIGINT);
    int status = 0;
    if (::waitpid(pid, &status, 0) != pid) return -1;
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return status;
}

// A barely damped linear model: no point settles, each runs its --max-periods.
std::string slow_model() {
    std::string text = kLinear;
    text.replace(text.find("zeta = 0.05"), 11, "zeta = 1e-7");
    return write_temp("slow.toml", text);
}

// Ctrl-C on a whole sweep keeps the points done: the sweep stops after the
// point under way, writes the curve and the diagram with the finished points
// and a last comment line saying it was interrupted, says status=interrupted
// and ends by SIGINT (the shell reports 130).
TEST(SweepCli, SigintKeepsTheFinishedPoints) {
    const std::string model = slow_model();
    const std::string out = temp_path("curve.csv"), diagram = temp_path("diagram.csv"), err = temp_path("stderr"),
                      stdout_path = temp_path("stdout");
    double seconds = 0.0;
    const int status = interrupt_run({"sweep", model, "--param", "omega", "--from", "0.5", "--to", "1.5", "--points",
                                      "1000", "--max-periods", "3000", "--record-periods", "2", "--out", out,
                                      "--diagram", diagram},
                                     stdout_path, err, "point 2/1000", seconds);  // once two points are done
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << status << "\n" << slurp(err);
    EXPECT_LT(seconds, 30.0);  // one point at most after the signal
    const std::string curve = slurp(out), d = slurp(diagram), line = slurp(stdout_path);
    ASSERT_EQ(line.rfind("status=interrupted points=", 0), 0u) << line << slurp(err);
    const std::size_t done = std::stoul(line.substr(std::string("status=interrupted points=").size()));
    EXPECT_GE(done, 2u);
    EXPECT_LT(done, 1000u);
    EXPECT_EQ(curve.substr(0, curve.find('\n')), "omega,direction,settled,periods,multiple,xmax_m,xrms_m,a1_m");
    const std::string note =
        "# interrupted (SIGINT) after " + std::to_string(done) + " of 1000 points: the rest were not run\n";
    EXPECT_EQ(std::count(curve.begin(), curve.end(), '\n'), static_cast<long>(done + 2));
    ASSERT_GE(curve.size(), note.size());
    EXPECT_EQ(curve.substr(curve.size() - note.size()), note);
    EXPECT_NE(curve.find("\n0.5,up,false,3000,0,"), std::string::npos) << curve;
    EXPECT_EQ(std::count(d.begin(), d.end(), '\n'), static_cast<long>(1 + 2 * done + 1));
    ASSERT_GE(d.size(), note.size());
    EXPECT_EQ(d.substr(d.size() - note.size()), note);
    EXPECT_NE(slurp(err).find("interrupted (SIGINT)"), std::string::npos);
    std::remove(err.c_str());
    std::remove(stdout_path.c_str());
}

// Ctrl-C on `sweep --part` keeps the points done in the part file (a part is
// hours of a long study), which ends with the same '# interrupted' line; and
// sweep-merge refuses that part, naming the file and the line (exit 2, nothing
// written), rather than merge a sweep with holes.
TEST(SweepCli, SigintOnAPartKeepsTheFinishedPointsAndMergeRefusesThem) {
    const std::string model = slow_model();
    const std::string part = temp_path("part1"), err = temp_path("stderr"), stdout_path = temp_path("stdout");
    double seconds = 0.0;
    const int status = interrupt_run({"sweep", model, "--param", "omega", "--from", "0.5", "--to", "1.5", "--points",
                                      "1000", "--max-periods", "3000", "--part", "1/2", "--part-out", part},
                                     stdout_path, err, "point 2/", seconds);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << status << "\n" << slurp(err);
    EXPECT_LT(seconds, 30.0);
    const std::string line = slurp(stdout_path), text = slurp(part);
    ASSERT_EQ(line.rfind("status=interrupted part=1/2 ", 0), 0u) << line << slurp(err);
    const std::size_t at = line.find(" points=");
    ASSERT_NE(at, std::string::npos) << line;
    const std::size_t done = std::stoul(line.substr(at + 8));
    EXPECT_GE(done, 2u);
    EXPECT_LT(done, 1000u);
    ASSERT_EQ(text.rfind("hsnc-sweep-part 5\n", 0), 0u) << text.substr(0, 200);
    const std::string note = "# interrupted (SIGINT) after " + std::to_string(done) + " of ";
    const std::size_t last = text.rfind('\n', text.size() - 2) + 1;
    EXPECT_EQ(text.substr(last, note.size()), note) << text.substr(last);
    EXPECT_NE(slurp(err).find("interrupted (SIGINT): the part file holds the " + std::to_string(done) + " points done"),
              std::string::npos)
        << slurp(err);
    // The merge refuses it for what it is (before it says that part 2/2 is missing).
    const std::string merged = temp_path("merged.csv");
    const auto m = run_hsnc("sweep-merge '" + part + "' --out '" + merged + "'");
    EXPECT_EQ(m.exit_code, 2) << m.err;
    EXPECT_NE(m.err.find(part + ":"), std::string::npos) << m.err;
    EXPECT_NE(m.err.find("part 1/2 was interrupted"), std::string::npos) << m.err;
    EXPECT_FALSE(file_exists(merged));
    std::remove(err.c_str());
    std::remove(stdout_path.c_str());
}

// Output identical for 1 and 2 threads, and for --part merged against a whole run.
TEST(SweepCli, ThreadsAndPartsGiveTheSameBytes) {
    const std::string model = write_temp("hardening.toml", kHardening);
    for (const std::string& mode : {std::string(""), std::string("--restart-each --param2 F --values2 0.1,0.12")}) {
        SCOPED_TRACE(mode);
        const std::string a = temp_path("a.csv"), ad = temp_path("ad.csv");
        const std::string b = temp_path("b.csv"), bd = temp_path("bd.csv");
        ASSERT_EQ(run_hsnc(sweep_args(model, mode + " --out '" + a + "' --diagram '" + ad + "'")).exit_code, 0);
        ASSERT_EQ(run_hsnc(sweep_args(model, mode + " --threads 2 --out '" + b + "' --diagram '" + bd + "'")).exit_code, 0);
        EXPECT_EQ(slurp(a), slurp(b));
        EXPECT_EQ(slurp(ad), slurp(bd));
        EXPECT_GT(slurp(a).size(), 100u);
        // Three parts, merged in another order.
        std::vector<std::string> parts;
        for (int i = 1; i <= 3; ++i) {
            parts.push_back(temp_path("part" + std::to_string(i)));
            const auto r = run_hsnc(sweep_args(model, mode + " --part " + std::to_string(i) + "/3 --part-out '" +
                                                          parts.back() + "'"));
            ASSERT_EQ(r.exit_code, 0) << r.err;
        }
        const std::string c = temp_path("c.csv"), cd = temp_path("cd.csv");
        const auto m = run_hsnc("sweep-merge '" + parts[2] + "' '" + parts[0] + "' '" + parts[1] + "' --out '" + c +
                                "' --diagram '" + cd + "'");
        ASSERT_EQ(m.exit_code, 0) << m.err;
        EXPECT_EQ(slurp(a), slurp(c));
        EXPECT_EQ(slurp(ad), slurp(cd));
        // A part missing, or given twice: bad input, nothing written.
        const std::string e = temp_path("e.csv");
        const auto missing = run_hsnc("sweep-merge '" + parts[0] + "' '" + parts[1] + "' --out '" + e + "'");
        EXPECT_EQ(missing.exit_code, 2);
        EXPECT_NE(missing.err.find("part 3/3 is missing"), std::string::npos) << missing.err;
        const auto twice = run_hsnc("sweep-merge '" + parts[0] + "' '" + parts[0] + "' '" + parts[1] + "' --out '" + e + "'");
        EXPECT_EQ(twice.exit_code, 2);
        EXPECT_NE(twice.err.find("given twice"), std::string::npos) << twice.err;
        EXPECT_FALSE(file_exists(e));
    }
}

TEST(SweepCli, PartsOfAnotherSweepAreRefused) {
    const std::string model = write_temp("hardening.toml", kHardening);
    const std::string p1 = temp_path("p1"), p2 = temp_path("p2"), out = temp_path("o.csv");
    ASSERT_EQ(run_hsnc(sweep_args(model, "--part 1/2 --part-out '" + p1 + "'")).exit_code, 0);
    ASSERT_EQ(run_hsnc(sweep_args(model, "--set F=0.2 --part 2/2 --part-out '" + p2 + "'")).exit_code, 0);
    const auto r = run_hsnc("sweep-merge '" + p1 + "' '" + p2 + "' --out '" + out + "'");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("a part of another sweep"), std::string::npos) << r.err;
    EXPECT_FALSE(file_exists(out));
}

// Output identical for 1 and 2 MPI ranks (and without mpirun).
TEST(SweepCli, MpiRanksGiveTheSameBytes) {
    if (!HSNC_WITH_MPI) GTEST_SKIP() << "built without MPI";
    ASSERT_EQ(std::system("command -v mpirun >/dev/null 2>&1"), 0) << "mpirun not on PATH (Debian package openmpi-bin)";
    const std::string model = write_temp("hardening.toml", kHardening);
    // With harmonics: the ranks send them with the points (write_tasks).
    const std::string mode = "--restart-each --param2 F --values2 0.1,0.12 --harmonics 3";
    const std::string a = temp_path("a.csv"), ad = temp_path("ad.csv");
    ASSERT_EQ(run_hsnc(sweep_args(model, mode + " --out '" + a + "' --diagram '" + ad + "'")).exit_code, 0);
    ASSERT_NE(slurp(a).find(",amp3_m,phase3_m\n"), std::string::npos) << slurp(a).substr(0, 300);
    for (int ranks : {1, 2}) {
        SCOPED_TRACE(std::to_string(ranks) + " ranks");
        const std::string b = temp_path("b.csv"), bd = temp_path("bd.csv"), log = temp_path("mpi.log");
        const std::string cmd = "mpirun --allow-run-as-root --oversubscribe -np " + std::to_string(ranks) + " '" +
                                HSNC_BINARY + "' " + sweep_args(model, mode + " --out '" + b + "' --diagram '" + bd + "'") +
                                " >'" + log + "' 2>&1";
        const int status = std::system(cmd.c_str());
        ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp(log);
        EXPECT_EQ(slurp(a), slurp(b));
        EXPECT_EQ(slurp(ad), slurp(bd));
        // Rank 0 alone prints the summary.
        EXPECT_EQ(slurp(log), "status=ok points=20 up=10 down=10 settled=20 unsettled=0 failed=0\n");
    }
}

TEST(SweepCli, BadInputWritesNothing) {
    const std::string model = write_temp("hardening.toml", kHardening);
    const std::string out = temp_path("never.csv");
    struct Case {
        std::string args, message;
    };
    const Case cases[] = {
        {"--param nope --from 1 --to 2 --points 3", "--param: no parameter named 'nope'"},
        {"--param omega --from 1 --to 2 --points 0", "--points: must be >= 1"},
        {"--param omega --from 1 --to 2 --points -5", "--points: must be >= 1 (a positive whole number), not -5"},
        {"--param omega --from 1 --to 2 --points 3 --max-periods -1", "--max-periods: must be >= 1"},
        {"--param omega --from 1 --to nan --points 3", "--to"},
        {"--param omega --from 1 --to 2 --points 3 --direction sideways", "--direction: expected up, down or both"},
        {"--param omega --from 1 --to -1 --points 3", "sweep at omega = 0: "},
        {"--param omega --from 1 --to 2 --points 3 --set omega=2", "also set by an override"},
        {"--param omega --from 1 --to 2 --points 3 --part 4/3 --part-out x", "--part '4/3'"},
        {"--param omega --from 1 --to 2 --points 3 --part 1/3", "needs --part-out"},
        {"--param omega --from 1 --to 2 --points 3 --param2 F --values2 1,x", "--values2"},
        {"--param omega --from 1 --to 2 --points 3 --diagram /", "--diagram"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.args);
        const auto r = run_hsnc("sweep '" + model + "' " + c.args + " --quiet --out '" + out + "'");
        EXPECT_EQ(r.exit_code, 2) << r.err;
        EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_FALSE(file_exists(out));
    }
}

}  // namespace
}  // namespace hsnc
