// `hsnc tradeoff` against exact references built here from closed forms:
// the Coulomb oscillator (models/coulomb-1dof.toml: half-cycles of pi/omega
// about the friction offsets, then stuck) and a frictionless oscillator
// (x = x0 cos(omega t)). hsnc must come out at rounding level, ab4 with its
// textbook order where the motion is smooth; the event matching and the error
// paths (exit 2, nothing written) are checked too.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <vector>

#include "cli_runner.h"
#include "error.h"
#include "hsnc/simulate.h"
#include "tradeoff.h"
#include "tradeoff_cli.h"
#include "work_precision.h"

namespace hsnc {
namespace {

using testing::file_exists;
using testing::model_path;
using testing::run_hsnc;
using testing::slurp;
using testing::temp_path;
using testing::write_temp;

constexpr double kPi = 3.14159265358979323846;

std::string g17(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

// The sample grid of a run: t0 + k*dt, and t_end (runtime's sampler rule).
std::vector<double> grid(double t_end, double dt) {
    std::vector<double> t;
    for (std::size_t k = 0;; ++k) {
        const double tk = static_cast<double>(k) * dt;
        if (!(tk < t_end - 1e-9 * dt)) break;
        t.push_back(tk);
    }
    t.push_back(t_end);
    return t;
}

struct Reference {
    std::string trajectory, events;
};

// models/coulomb-1dof.toml: m = 1, k = 100 (omega = 10), mu_s = mu_k = 0.1,
// g = 9.81, x0 = 0.2 at rest. Half-cycle n runs from t_n = n*pi/omega about the
// centre c_n = sign(X_n)*a, a = mu*g/omega^2: x = c_n + (X_n - c_n) cos(omega (t - t_n)),
// and the next extreme is X_{n+1} = 2 c_n - X_n. A reversal at each t_n while
// |X_n| > a; at X_10 = 0.0038 (|X| < a) the mass sticks for good.
struct CoulombExact {
    double w = 10.0, a = 0.1 * 9.81 / (10.0 * 10.0);
    std::vector<double> t_n{0.0}, X{0.2};
    CoulombExact() {
        while (std::fabs(X.back()) > a) {
            const double c = X.back() > 0 ? a : -a;
            X.push_back(2 * c - X.back());
            t_n.push_back(static_cast<double>(t_n.size()) * kPi / w);
        }
    }
    void state(double t, double& x, double& v) const {
        std::size_t n = 0;
        while (n + 1 < t_n.size() && t >= t_n[n + 1]) ++n;
        x = X[n];
        v = 0.0;
        if (n + 1 < t_n.size()) {  // sliding
            const double c = X[n] > 0 ? a : -a;
            x = c + (X[n] - c) * std::cos(w * (t - t_n[n]));
            v = -(X[n] - c) * w * std::sin(w * (t - t_n[n]));
        }
    }
    bool stick(std::size_t n) const { return n + 1 == t_n.size(); }  // the last extreme: stuck
};

Reference coulomb_reference(double t_end, double dt) {
    const CoulombExact exact;
    std::string traj = "t,x_m1,v_m1\n", events = "t,kind,element,x_m1,v_m1\n";
    for (double t : grid(t_end, dt)) {
        double x, v;
        exact.state(t, x, v);
        traj += g17(t) + "," + g17(x) + "," + g17(v) + "\n";
    }
    for (std::size_t n = 1; n < exact.t_n.size(); ++n)
        if (exact.t_n[n] <= t_end)
            events += g17(exact.t_n[n]) + (exact.stick(n) ? ",stick" : ",reversal") + ",m1," + g17(exact.X[n]) + ",0\n";
    return {write_temp("coulomb_ref.csv", traj), write_temp("coulomb_ref_events.csv", events)};
}

std::vector<std::string> fields(const std::string& line) {
    std::vector<std::string> out;
    std::istringstream in(line);
    for (std::string f; std::getline(in, f, ',');) out.push_back(f);
    return out;
}

// The tradeoff CSV: header check, then rows keyed by "method setting".
std::map<std::string, std::vector<std::string>> read_tradeoff(const std::string& path) {
    std::istringstream in(slurp(path));
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line,
              "method,setting,parameter,wall_seconds,runs,status,max_position_error,sample_times,events,"
              "reference_events,matched_events,max_event_time_error,time_ratio_to_hsnc,response_magnitude,"
              "relative_position_error,diverged");
    std::map<std::string, std::vector<std::string>> rows;
    while (std::getline(in, line)) {
        const auto f = fields(line);
        EXPECT_EQ(f.size(), 16u) << line;
        if (f.size() == 16u) rows[f[0] + " " + f[1]] = f;
    }
    return rows;
}

enum Col { kParameter = 2, kWall = 3, kStatus = 5, kXErr = 6, kSamples = 7, kEvents = 8, kRefEvents = 9,
           kMatched = 10, kTErr = 11, kMagnitude = 13, kRelErr = 14, kDiverged = 15 };

TEST(Tradeoff, CoulombOscillatorAgainstItsClosedForm) {
    const Reference ref = coulomb_reference(4.0, 0.004);
    const std::string csv = temp_path("tradeoff.csv");
    const auto r = run_hsnc("tradeoff '" + model_path("coulomb-1dof.toml") + "' --t-end 4 --reference-out '" +
                            ref.trajectory + "' --reference-events '" + ref.events + "' --methods hsnc,ab4 "
                            "--runs 1 --budget 0.2 --csv '" + csv + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto rows = read_tradeoff(csv);
    ASSERT_TRUE(rows.count("hsnc kernels=auto")) << slurp(csv);
    ASSERT_TRUE(rows.count("ab4 h=1e-03") && rows.count("ab4 h=1e-04")) << slurp(csv);
    // Progress on stderr, one line per run.
    EXPECT_NE(r.err.find("tradeoff: ab4 h=1e-03: "), std::string::npos) << r.err;
    for (const char* key : {"hsnc kernels=auto", "hsnc kernels=generic"}) {
        const auto& h = rows.at(key);
        EXPECT_EQ(h[kStatus], "ok");
        EXPECT_EQ(h[kSamples], "1001");
        EXPECT_EQ(h[kRefEvents], "10");  // 9 reversals, then the stick at t = pi
        EXPECT_EQ(h[kMatched], "10");
        EXPECT_LT(std::stod(h[kXErr]), 1e-15) << key;  // x ~ 0.2: a few units of rounding
        EXPECT_LT(std::stod(h[kTErr]), 1e-14) << key;  // t up to pi
    }
    // ab4 reports events at step ends: every one found, each within about a step.
    for (const char* key : {"ab4 h=1e-03", "ab4 h=1e-04"}) {
        const auto& a = rows.at(key);
        EXPECT_EQ(a[kMatched], "10") << key;
        EXPECT_LT(std::stod(a[kTErr]), 2 * std::stod(a[kParameter])) << key;
        EXPECT_GT(std::stod(a[kXErr]), 1e-8) << key;  // far from hsnc: the friction jump inside a step
    }
    EXPECT_LT(std::stod(rows.at("ab4 h=1e-04")[kXErr]), std::stod(rows.at("ab4 h=1e-03")[kXErr]));
    // The summary line of each baseline on stdout, as time ratios to hsnc.
    EXPECT_NE(r.out.find("ab4:  relative error<=0.01: "), std::string::npos) << r.out;
}

TEST(Tradeoff, TheBenchScriptsClosedFormAgreesWithHsnc) {
    // bench/coulomb_exact.sh writes the reference of the committed Coulomb figure.
    const std::string tr = temp_path("exact.csv"), ev = temp_path("exact_events.csv"), csv = temp_path("t.csv");
    const std::string script = std::string(HSNC_SOURCE_DIR) + "/bench/coulomb_exact.sh";
    ASSERT_EQ(std::system(("sh '" + script + "' 4 0.004 '" + tr + "' '" + ev + "'").c_str()), 0);
    const auto r = run_hsnc("tradeoff '" + model_path("coulomb-1dof.toml") + "' --t-end 4 --reference-out '" + tr +
                            "' --reference-events '" + ev + "' --methods hsnc --runs 1 --csv '" + csv + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto rows = read_tradeoff(csv);
    // hsnc with its ahead-of-time kernels and with the generic solver; ab4's
    // matching against a closed-form reference is tested above (its step sweep
    // depends on --budget, i.e. on the machine's speed, so it is left out here).
    ASSERT_EQ(rows.size(), 2u) << slurp(csv);
    for (const char* name : {"hsnc kernels=auto", "hsnc kernels=generic"}) {
        const auto& h = rows.at(name);
        EXPECT_LT(std::stod(h[kXErr]), 1e-15) << name;
        EXPECT_EQ(h[kMatched], "10") << name;
        EXPECT_LT(std::stod(h[kTErr]), 1e-14) << name;
    }
}

TEST(Tradeoff, WithoutHsncThereIsNoRatioAndThePlotIsDrawn) {
    const Reference ref = coulomb_reference(1.0, 0.001);
    const std::string csv = temp_path("t.csv"), png = temp_path("t.png");
    const auto r = run_hsnc("tradeoff '" + model_path("coulomb-1dof.toml") + "' --t-end 1 --reference-out '" +
                            ref.trajectory + "' --reference-events '" + ref.events +
                            "' --methods rk45 --quick --runs 1 --csv '" + csv + "' --plot '" + png + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(slurp(png).substr(0, 4), "\x89PNG");
    const auto rows = read_tradeoff(csv);
    ASSERT_EQ(rows.size(), 4u);  // --quick: rtol 1e-4, 1e-7, 1e-10, 1e-13
    EXPECT_EQ(rows.at("rk45 rtol=1e-07 atol=1e-09")[12], "nan");
    EXPECT_NE(r.out.find("rk45:  relative error<=0.01: "), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("x hsnc"), std::string::npos) << r.out;
}

TEST(Tradeoff, Ab4IsFourthOrderOnASmoothMotion) {
    // No friction, no contact: x = 0.2 cos(10 t), no events.
    const std::string model = write_temp("oscillator.toml",
                                         "name = \"oscillator\"\n[[mass]]\nname = \"m1\"\nm = 1\n"
                                         "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 100\n"
                                         "[initial]\nx = { m1 = 0.2 }\n");
    std::string traj = "t,x_m1,v_m1\n";
    for (double t : grid(2.0, 0.002))
        traj += g17(t) + "," + g17(0.2 * std::cos(10 * t)) + "," + g17(-2 * std::sin(10 * t)) + "\n";
    const std::string tr = write_temp("osc_ref.csv", traj), ev = write_temp("osc_ref_events.csv", "t,kind,element,x_m1,v_m1\n");
    const std::string csv = temp_path("tradeoff.csv");
    const auto r = run_hsnc("tradeoff '" + model + "' --t-end 2 --reference-out '" + tr + "' --reference-events '" + ev +
                            "' --methods ab4,hsnc --runs 1 --budget 0.05 --csv '" + csv + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto rows = read_tradeoff(csv);
    ASSERT_TRUE(rows.count("ab4 h=1e-03") && rows.count("ab4 h=3.2e-04")) << slurp(csv);
    const auto& a = rows.at("ab4 h=1e-03");
    const auto& b = rows.at("ab4 h=3.2e-04");
    const double order = std::log(std::stod(a[kXErr]) / std::stod(b[kXErr])) /
                         std::log(std::stod(a[kParameter]) / std::stod(b[kParameter]));
    EXPECT_GT(order, 3.6) << a[kXErr] << " " << b[kXErr];
    EXPECT_LT(order, 4.4) << a[kXErr] << " " << b[kXErr];
    EXPECT_EQ(a[kEvents], "0");
    EXPECT_EQ(a[kMatched], "0");
    EXPECT_EQ(a[kTErr], "nan");  // no event to match
    // hsnc (generic solver: this model has no AOT kernels) at rounding level.
    ASSERT_TRUE(rows.count("hsnc kernels=generic")) << slurp(csv);
    EXPECT_LT(std::stod(rows.at("hsnc kernels=generic")[kXErr]), 1e-15);
}

TEST(Tradeoff, InProcessReferenceIsSampledOnTheRunsGrid) {
    // The in-process path (the mp engine once merged) with the closed form as the runner.
    const CoulombExact exact;
    const ReferenceRunner runner = [&exact](const Model&, const EngineOptions& o, Observer& obs) {
        for (double t : grid(o.t_end, o.dt)) {
            double x, v;
            exact.state(t, x, v);
            obs.on_sample(t, &x, &v);
        }
        for (std::size_t n = 1; n < exact.t_n.size(); ++n) {
            const double x = exact.X[n], v = 0.0;
            if (exact.t_n[n] <= o.t_end)
                obs.on_event(exact.t_n[n], exact.stick(n) ? EventKind::stick : EventKind::reversal, 0, &x, &v);
        }
        RunSummary s;
        s.t = o.t_end;
        return s;
    };
    cli::TradeoffOptions o;
    o.model = model_path("coulomb-1dof.toml");
    o.t_end = 4;
    o.dt = 0.01;
    o.methods = "hsnc";
    o.runs = 1;
    o.csv = temp_path("tradeoff.csv");
    ASSERT_EQ(cli::tradeoff(o, runner), 0);
    const auto rows = read_tradeoff(o.csv);
    ASSERT_TRUE(rows.count("hsnc kernels=generic")) << slurp(o.csv);
    const auto& h = rows.at("hsnc kernels=generic");
    EXPECT_EQ(h[kSamples], "401");
    EXPECT_EQ(h[kMatched], "10");
    EXPECT_LT(std::stod(h[kXErr]), 1e-15);
    EXPECT_LT(std::stod(h[kTErr]), 1e-14);
}

// The library function itself (hsnc::tradeoff), without the command line:
// rows against the closed-form reference, in the order of the methods, the
// hsnc rows run by hsnc::simulate with the same kernels it would choose.
TEST(Tradeoff, TheLibraryStudyReturnsItsRows) {
    const CoulombExact exact;
    const ReferenceRunner runner = [&exact](const Model&, const EngineOptions& o, Observer& obs) {
        for (double t : grid(o.t_end, o.dt)) {
            double x, v;
            exact.state(t, x, v);
            obs.on_sample(t, &x, &v);
        }
        for (std::size_t n = 1; n < exact.t_n.size(); ++n) {
            const double x = exact.X[n], v = 0.0;
            if (exact.t_n[n] <= o.t_end)
                obs.on_event(exact.t_n[n], exact.stick(n) ? EventKind::stick : EventKind::reversal, 0, &x, &v);
        }
        RunSummary s;
        s.t = o.t_end;
        return s;
    };
    const Model model = read_model(model_path("coulomb-1dof.toml"));
    TradeoffOptions o;
    o.t_end = 1;
    o.dt = 0.01;
    o.methods = {Method::hsnc, Method::ab4};
    o.quick = true;
    o.runs = 1;
    const RecordedRun reference = compute_reference(model, o, runner);
    EXPECT_EQ(reference.t.size(), 101u);
    std::size_t told = 0;
    TradeoffProgress progress;
    progress.measured = [&told](const TradeoffRow&) { ++told; };
    const TradeoffResult study = tradeoff(model, o, reference, progress);
    ASSERT_EQ(study.methods, o.methods);
    ASSERT_GE(study.rows.size(), 3u);
    EXPECT_EQ(told, study.rows.size());
    // hsnc first: the bundled model's AOT kernels (quick: no generic point), as hsnc::simulate chooses them.
    const TradeoffRow& h = study.rows[0];
    EXPECT_EQ(h.setting.method, Method::hsnc);
    EXPECT_EQ(h.setting.label, "kernels=auto");
    SimulateOptions auto_kernels;
    auto_kernels.t_end = 1;
    EXPECT_EQ(h.solver, simulate(model, auto_kernels).solver);
    EXPECT_EQ(h.solver, SolverKind::aot);
    EXPECT_EQ(h.status, "ok");
    EXPECT_LT(h.errors.relative_position_error, 1e-13);
    EXPECT_EQ(h.errors.matched_events, 3u);  // reversals at pi/10, 2 pi/10, 3 pi/10
    EXPECT_EQ(study.base, 0);
    EXPECT_EQ(h.time_ratio_to_hsnc, 1.0);
    // Then ab4's sweep, h = 1e-3, 1e-4, ... (quick: every other half decade).
    ASSERT_EQ(study.rows[1].setting.label, "h=1e-03");
    ASSERT_EQ(study.rows[2].setting.label, "h=1e-04");
    for (std::size_t k = 1; k < study.rows.size(); ++k) {
        EXPECT_EQ(study.rows[k].setting.method, Method::ab4);
        EXPECT_EQ(study.rows[k].status, "ok");
        EXPECT_EQ(study.rows[k].time_ratio_to_hsnc, study.rows[k].wall / h.wall);
    }
    EXPECT_EQ(study.response_magnitude, 0.2);  // max |x_ref| = x0
    const TradeoffRow* reached = cheapest_reaching(study, Method::ab4, 1e-4);
    ASSERT_NE(reached, nullptr);
    EXPECT_EQ(reached->setting.method, Method::ab4);
    EXPECT_LE(reached->errors.relative_position_error, 1e-4);
    for (const TradeoffRow& r : study.rows)  // the cheapest of those that reached it
        if (r.setting.method == Method::ab4 && r.errors.relative_position_error <= 1e-4) EXPECT_LE(reached->wall, r.wall);
    EXPECT_EQ(cheapest_reaching(study, Method::rk45, 1.0), nullptr);  // not measured
    // A reference off the study's grid is refused before anything runs.
    TradeoffOptions other = o;
    other.dt = 0.0037;
    RecordedRun copy = reference;
    EXPECT_NE(fit_reference(model, other, copy).find("sample times t0 + k*dt"), std::string::npos);
    EXPECT_THROW(tradeoff(model, other, reference), InputError);
    other = o;
    other.budget = 0;
    try {
        tradeoff(model, other, reference);
        ADD_FAILURE() << "no OptionError for budget 0";
    } catch (const OptionError& e) {
        EXPECT_EQ(e.option(), "budget");
    }
}

TEST(Tradeoff, TheMpReferenceAgreesWithTheClosedForm) {
    // Default reference: the 40-digit engine in process. hsnc against it at
    // rounding level, and ab4's error the same against it as against the exact
    // closed form (the two references differ by rounding only).
    const std::string csv_mp = temp_path("mp.csv"), csv_exact = temp_path("exact.csv");
    const std::string common =
        "tradeoff '" + model_path("coulomb-1dof.toml") + "' --t-end 4 --methods hsnc,ab4 --runs 1 --budget 0.001 ";
    const auto r = run_hsnc(common + "--csv '" + csv_mp + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("tradeoff: reference (40 digits): "), std::string::npos) << r.err;
    const Reference ref = coulomb_reference(4.0, 0.004);
    const auto r2 = run_hsnc(common + "--reference-out '" + ref.trajectory + "' --reference-events '" + ref.events +
                             "' --csv '" + csv_exact + "'");
    ASSERT_EQ(r2.exit_code, 0) << r2.err;
    const auto mp = read_tradeoff(csv_mp), exact = read_tradeoff(csv_exact);
    ASSERT_TRUE(mp.count("hsnc kernels=auto") && mp.count("ab4 h=1e-03")) << slurp(csv_mp);
    EXPECT_LT(std::stod(mp.at("hsnc kernels=auto")[kXErr]), 1e-15);
    EXPECT_LT(std::stod(mp.at("hsnc kernels=auto")[kTErr]), 1e-14);
    EXPECT_EQ(mp.at("hsnc kernels=auto")[kMatched], "10");
    const double a = std::stod(mp.at("ab4 h=1e-03")[kXErr]), b = std::stod(exact.at("ab4 h=1e-03")[kXErr]);
    EXPECT_NEAR(a, b, 1e-15) << a << " " << b;
    EXPECT_NEAR(std::stod(mp.at("ab4 h=1e-03")[kTErr]), std::stod(exact.at("ab4 h=1e-03")[kTErr]), 1e-14);
    // Its digits are checked like every flag.
    const auto bad = run_hsnc(common + "--reference-digits 5");
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_NE(bad.err.find("--reference-digits 5: must be in "), std::string::npos) << bad.err;
}

TEST(Tradeoff, EventsOfOneInstantMatchInAnyOrderAndMatchingStopsAtAMismatch) {
    RecordedRun ref, run;
    ref.dof = run.dof = 1;
    ref.t = run.t = {0.0, 1.0};
    ref.x = {0.0, 1.0};
    run.x = {0.0, 1.5};
    ref.events = {{0.5, EventKind::contact_close, 0}, {0.5, EventKind::release, 0}, {0.7, EventKind::stick, 0},
                  {0.9, EventKind::release, 0}};
    run.events = {{0.5 + 1e-3, EventKind::release, 0}, {0.5 + 1e-3, EventKind::contact_close, 0},
                  {0.7 - 2e-3, EventKind::stick, 0}, {0.8, EventKind::reversal, 0}, {0.9, EventKind::release, 0}};
    const RunErrors e = compare_runs(ref, run);
    EXPECT_EQ(e.sample_times, 2u);
    EXPECT_DOUBLE_EQ(e.max_position_error, 0.5);
    EXPECT_EQ(e.events, 5u);
    EXPECT_EQ(e.reference_events, 4u);
    EXPECT_EQ(e.matched_events, 3u);  // the extra reversal ends the matched prefix
    EXPECT_NEAR(e.max_event_time_error, 2e-3, 1e-15);
}

TEST(Tradeoff, BadInputExitsTwoAndWritesNothing) {
    const Reference ref = coulomb_reference(1.0, 0.001);
    const std::string m = "'" + model_path("coulomb-1dof.toml") + "'";
    const std::string refs = " --reference-out '" + ref.trajectory + "' --reference-events '" + ref.events + "'";
    const std::string csv = temp_path("never.csv");
    const std::string png = temp_path("never.png");
    const std::string out = " --csv '" + csv + "' --plot '" + png + "' --runs 1";
    struct Case {
        std::string args, message;
    };
    const Case cases[] = {
        {"--t-end 1 --reference-out '" + ref.trajectory + "'" + out, "--reference-out and --reference-events"},
        {"--t-end 1" + refs + " --methods hsnc,euler" + out, "--methods: unknown method 'euler'"},
        {"--t-end 1" + refs + " --budget 0" + out, "--budget"},
        {"--t-end 1" + refs + " --dt 0" + out, "--dt"},
        {"--t-end 1" + refs + " --dt 0.00037" + out, "sample times t0 + k*dt"},  // not the reference's grid
        {"--t-end 2" + refs + out, "ends at t = 1"},                   // reference too short
        {"--t-end 1" + refs + " --plot '" + png + "'", "--plot: needs --csv"},
        {"--t-end 1 --reference-out '" + ref.events + "' --reference-events '" + ref.events + "'" + out,
         ref.events + ":1: header"},
        {"--t-end 1 --bogus" + refs + out, "bogus"},
        {"--t-end 1" + refs + " --csv /nonexistent-dir/x.csv", "--csv '/nonexistent-dir/x.csv': directory '/nonexistent-dir' does not exist"},
    };
    for (const Case& c : cases) {
        const auto r = run_hsnc("tradeoff " + m + " " + c.args);
        EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
        EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << "\n" << r.err;
        EXPECT_FALSE(file_exists(csv)) << c.args;
        EXPECT_FALSE(file_exists(png)) << c.args;
    }
    // A model whose masses differ from the reference's columns.
    const auto r = run_hsnc("tradeoff '" + model_path("seed-scenario-1.toml") + "' --t-end 1" + refs + out);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find(ref.trajectory + ":1: header 't,x_m1,v_m1' does not match"), std::string::npos) << r.err;
    EXPECT_FALSE(file_exists(csv));
}


// Errors relative to the response: a stiff oscillator moving by 3e-4 m
// (x = 3e-4 cos(1000 t), m = 1, k = 1e6), where an absolute 1e-4 m would be a
// third of the motion. ab4 at h = 1e-3 (h omega = 1, outside its stability
// region) blows up: marked diverged, left out of the summary, pinned in the plot.
TEST(Tradeoff, ErrorsAreRelativeToTheResponseAndDivergedRunsAreMarked) {
    const std::string model = write_temp("stiff.toml",
                                         "name = \"stiff\"\n[[mass]]\nname = \"m1\"\nm = 1\n"
                                         "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 1e6\n"
                                         "[initial]\nx = { m1 = 3e-4 }\n");
    std::string traj = "t,x_m1,v_m1\n";
    for (double t : grid(0.05, 5e-5))
        traj += g17(t) + "," + g17(3e-4 * std::cos(1000 * t)) + "," + g17(-0.3 * std::sin(1000 * t)) + "\n";
    const std::string tr = write_temp("stiff_ref.csv", traj), ev = write_temp("stiff_ref_events.csv", "t,kind,element,x_m1,v_m1\n");
    const std::string csv = temp_path("tradeoff.csv"), png = temp_path("tradeoff.png");
    const auto r = run_hsnc("tradeoff '" + model + "' --t-end 0.05 --dt 5e-5 --reference-out '" + tr +
                            "' --reference-events '" + ev + "' --methods hsnc,ab4 --quick --runs 1 --csv '" + csv +
                            "' --plot '" + png + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(slurp(png).substr(0, 4), "\x89PNG");
    const auto rows = read_tradeoff(csv);
    ASSERT_TRUE(rows.count("hsnc kernels=generic") && rows.count("ab4 h=1e-03") && rows.count("ab4 h=1e-04"))
        << slurp(csv);
    for (const auto& [key, row] : rows) {
        // The magnitude is max |x_ref| = x(0) = 3e-4; the relative error is the absolute one over it.
        EXPECT_EQ(std::stod(row[kMagnitude]), 3e-4) << key;
        if (std::isfinite(std::stod(row[kXErr])))
            EXPECT_DOUBLE_EQ(std::stod(row[kRelErr]), std::stod(row[kXErr]) / 3e-4) << key;
    }
    const auto& blown = rows.at("ab4 h=1e-03");
    EXPECT_EQ(blown[kDiverged], "1");
    EXPECT_GT(std::stod(blown[kRelErr]), kDivergedRatio);
    EXPECT_EQ(rows.at("ab4 h=1e-04")[kDiverged], "0");
    EXPECT_LT(std::stod(rows.at("ab4 h=1e-04")[kRelErr]), 1.0);
    EXPECT_EQ(rows.at("hsnc kernels=generic")[kDiverged], "0");
    EXPECT_LT(std::stod(rows.at("hsnc kernels=generic")[kRelErr]), 1e-12);
    // The summary speaks of relative errors and counts the diverged run; stderr flags it.
    EXPECT_NE(r.out.find("response magnitude max |x_ref| = 0.0003 m; errors relative to it"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("ab4:  relative error<=0.01: "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("(1 diverged)"), std::string::npos) << r.out;
    EXPECT_NE(r.err.find("tradeoff: ab4 h=1e-03: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(", DIVERGED, "), std::string::npos) << r.err;
}

// Every output path is checked before any work: the reference (minutes for a
// long run at many digits) is not even started.
TEST(Tradeoff, OutputPathsAreCheckedBeforeTheReference) {
    bool reference_ran = false;
    const ReferenceRunner runner = [&reference_ran](const Model&, const EngineOptions& o, Observer&) {
        reference_ran = true;
        RunSummary s;
        s.t = o.t_end;
        return s;
    };
    const std::string dir = temp_path("a-directory");
    ASSERT_EQ(std::system(("mkdir '" + dir + "'").c_str()), 0);
    struct Case {
        std::string csv, plot, message;
    };
    const std::string good_csv = temp_path("t.csv");
    const Case cases[] = {
        {"/nonexistent-dir/x.csv", "", "--csv '/nonexistent-dir/x.csv': directory '/nonexistent-dir' does not exist"},
        {dir, "", "--csv '" + dir + "': is a directory"},
        {good_csv, "/nonexistent-dir/x.png", "--plot '/nonexistent-dir/x.png': directory '/nonexistent-dir' does not exist"},
        {good_csv, dir, "--plot '" + dir + "': is a directory"},
    };
    for (const Case& c : cases) {
        cli::TradeoffOptions o;
        o.model = model_path("coulomb-1dof.toml");
        o.t_end = 1;
        o.methods = "hsnc";
        o.runs = 1;
        o.csv = c.csv;
        o.plot = c.plot;
        reference_ran = false;
        try {
            cli::tradeoff(o, runner);
            ADD_FAILURE() << "no InputError for --csv " << c.csv << " --plot " << c.plot;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
        }
        EXPECT_FALSE(reference_ran) << c.message;
        EXPECT_FALSE(file_exists(good_csv));
    }
    // From the command line: exit 2, one message, nothing written, and no reference computed.
    const auto r = run_hsnc("tradeoff '" + model_path("coulomb-1dof.toml") + "' --t-end 1 --csv '" + good_csv +
                            "' --plot /nonexistent-dir/x.png");
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("--plot '/nonexistent-dir/x.png': directory '/nonexistent-dir' does not exist"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("computing the reference"), std::string::npos) << r.err;
    EXPECT_FALSE(file_exists(good_csv));
    std::system(("rmdir '" + dir + "'").c_str());
}

}  // namespace
}  // namespace hsnc
