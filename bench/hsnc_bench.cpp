// hsnc benchmark: switches, wall time, microseconds per switch, and the ratios
// to the numerical-integration baselines, all measured in one run.
//
//   build/hsnc_bench [--quick] [--kinds]   (--kinds: the kernel kinds' table only)
//
// Engine times are medians of repeated runs (the machines are noisy); ab4
// and rk45 run once, CVODE (the --method cvode baseline: Adams, fixed-point
// corrector, root finding) three times (median), and once with the Newton
// corrector. ab4 at h = 1e-6 over 300 s would take about a minute, so it is
// timed over a shorter horizon and its cost per simulated second is scaled to
// the full horizon (its cost is proportional to the horizon: fixed step).
// That scaling is printed with the figure.
//
// Kernel kinds: one run of each model through hsnc::simulate (the facade, as
// `hsnc simulate` runs it) with kernels aot, jit (persistent cache in a
// temporary directory under $TMPDIR, filled by a warm-up run), eigen (the
// Eigen solver) and generic (each configuration derived in double-double,
// lowered and interpreted), in turn, each run making its provider anew
// (kernels looked up or loaded, the Eigen and interpreted solvers built for
// every configuration entered); medians of the thread's CPU time.
// generic/eigen is what a run pays for the kernels' bits without a compiler.
//
// The whole process: `hsnc simulate` on scenario 2 to 300 s is spawned
// (posix_spawn, no shell, stdout and stderr to /dev/null) 21 times after 2
// warm-up runs; the bench prints the median wall time from spawn to exit and
// the median CPU time of the child (user + system, from wait4), and their
// ratio to CVODE's in-process time on the same run measured above; the same
// with --t-end 0.001 (start-up, command line, model file, exit) and with the
// docs' trajectory and event files. The wall time includes fork/exec and
// the kernel's process set-up; the CPU time is what the process itself costs
// when other work competes for the two cores.
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "aot_registry.h"
#include "bench_common.h"
#include "assembly.h"
#include "engine.h"
#include "hsnc/simulate.h"
#include "integrators.h"
#include "kernel_mode.h"
#include "lowering.h"
#include "model_reader.h"

namespace {

using namespace hsnc;
using bench::friction_chain;
using bench::cpu_seconds;
using Clock = std::chrono::steady_clock;

class Counter : public Observer {
public:
    void on_sample(double, const double*, const double*) override {}
    void on_event(double, EventKind, int, const double*, const double*) override { ++events; }
    std::size_t events = 0;
};

double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

struct Timed {
    double seconds;
    RunSummary summary;
};

Timed run_engine(const Model& m, double t_end, KernelChoice mode) {
    EngineOptions eo;
    eo.t_end = t_end;
    eo.samples = false;
    Counter c;
    auto provider = make_solver_provider(m, mode, &aot_registry(), program_source(m));
    Engine engine(m, *provider);
    engine.run(eo, c);  // warm: kernels and solvers created
    const auto start = Clock::now();
    RunSummary s = engine.run(eo, c);
    return {seconds_since(start), s};
}

double median_engine(const Model& m, double t_end, KernelChoice mode, int reps, RunSummary& summary) {
    std::vector<double> t;
    for (int r = 0; r < reps; ++r) {
        Timed x = run_engine(m, t_end, mode);
        t.push_back(x.seconds);
        summary = x.summary;
    }
    std::sort(t.begin(), t.end());
    return t[t.size() / 2];
}

Timed run_baseline(const Model& m, double t_end, Method method, const IntegratorOptions& io) {
    EngineOptions eo;
    eo.t_end = t_end;
    eo.samples = false;
    Counter c;
    const auto start = Clock::now();
    RunSummary s = integrate(m, method, io, eo, c);
    return {seconds_since(start), s};
}

/// friction_chain(n) with a dashpot of 0.05 N s/m between every pair of neighbours
/// in place of its Rayleigh beta: non-proportional damping.
std::string chain_with_dampers(int n) {
    std::string t = friction_chain(n);
    t.replace(t.find("beta = 0.002"), 12, "alpha = 0.0");
    t = "name = \"chain-" + std::to_string(n) + "-dampers\"" + t.substr(t.find('\n'));
    for (int i = 1; i < n; ++i)
        t += "[[damper]]\nbetween = [\"m" + std::to_string(i) + "\", \"m" + std::to_string(i + 1) + "\"]\nc = 0.05\n";
    return t;
}

struct ProcessTimes {
    double wall = -1, cpu = -1;  ///< medians, seconds
};

// Spawn argv (no shell) reps times, stdout and stderr to /dev/null.
ProcessTimes process_times(const std::vector<std::string>& args, int reps, int warmup = 2) {
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
    std::vector<double> wall, cpu;
    for (int r = -warmup; r < reps; ++r) {
        const auto start = Clock::now();
        pid_t pid;
        if (posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ) != 0) return {};
        int status = 0;
        struct rusage ru {};
        if (wait4(pid, &status, 0, &ru) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) return {};
        const double w = seconds_since(start);
        const double c = static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
                         1e-6 * static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
        if (r >= 0) wall.push_back(w), cpu.push_back(c);
    }
    posix_spawn_file_actions_destroy(&fa);
    std::sort(wall.begin(), wall.end());
    std::sort(cpu.begin(), cpu.end());
    return {wall[wall.size() / 2], cpu[cpu.size() / 2]};
}

double median_baseline(const Model& m, double t_end, Method method, const IntegratorOptions& io, int reps,
                       RunSummary& summary) {
    std::vector<double> t;
    for (int r = 0; r < reps; ++r) {
        const Timed x = run_baseline(m, t_end, method, io);
        t.push_back(x.seconds);
        summary = x.summary;
    }
    std::sort(t.begin(), t.end());
    return t[t.size() / 2];
}


// A directory for the JIT cache under $TMPDIR (else the system's temporary
// directory); empty when none can be made.
std::string make_temp_dir() {
    std::string templ = (std::filesystem::temp_directory_path() / "hsnc_bench_cache_XXXXXX").string();
    return ::mkdtemp(templ.data()) ? templ : std::string();
}

// Whole runs per kernel kind through the facade (see the header comment).
void kernel_kinds(const std::vector<std::pair<std::string, Model>>& models, const std::vector<double>& t_ends,
                  int reps) {
    const std::string dir = make_temp_dir();
    std::printf("\nkernel kinds, whole run through hsnc::simulate (new provider each run; median of %d, thread CPU time):\n",
                reps);
    std::printf("%-16s %6s %26s %9s %9s %10s %9s %13s %11s %10s\n", "model", "t_end", "switches aot/jit/eig/gen",
                "aot_ms", "jit_ms", "eigen_ms", "generic_ms", "generic/eigen", "eigen/aot", "generic/jit");
    constexpr int kKinds = 4;
    const KernelChoice kinds[kKinds] = {KernelChoice::aot, KernelChoice::jit, KernelChoice::eigen,
                                        KernelChoice::generic};
    for (std::size_t c = 0; c < models.size(); ++c) {
        const Model& m = models[c].second;
        const bool aot = has_aot_kernels(m, &aot_registry());
        std::vector<double> t[kKinds];
        std::size_t events[kKinds] = {};
        bool ok[kKinds] = {aot, !dir.empty(), true, true};
        for (int r = -1; r < reps; ++r)  // r = -1: warm-up (fills the JIT cache)
            for (int k = 0; k < kKinds; ++k) {
                if (!ok[k]) continue;
                SimulateOptions o;
                o.t_end = t_ends[c];
                o.kernels = kinds[k];
                if (!dir.empty()) o.cache_dir = dir;
                o.warn = [](const std::string&) {};
                try {
                    const double start = cpu_seconds();
                    const SimulateSummary s = simulate(m, o);
                    if (r >= 0) t[k].push_back(1e3 * (cpu_seconds() - start));
                    events[k] = s.events;
                } catch (const std::exception& e) {
                    std::printf("  %s %s: %s\n", models[c].first.c_str(), kernel_choice_name(kinds[k]), e.what());
                    ok[k] = false;
                }
            }
        auto med = [&](int k) {
            std::sort(t[k].begin(), t[k].end());
            return t[k].empty() ? NAN : t[k][t[k].size() / 2];
        };
        const double a = med(0), j = med(1), g = med(2), i = med(3);
        char sw[80];
        std::snprintf(sw, sizeof sw, "%s/%zu/%zu/%zu", aot ? std::to_string(events[0]).c_str() : "-", events[1],
                      events[2], events[3]);
        std::printf("%-16s %6g %26s %9.3f %9.3f %10.3f %9.3f %13.2f %11.2f %10.2f\n", models[c].first.c_str(),
                    t_ends[c], sw, a, j, g, i, i / g, g / a, i / j);
    }
    if (!dir.empty()) std::filesystem::remove_all(dir);
}

}  // namespace

int main(int argc, char** argv) {
    bool quick = false, kinds_only = false;
    for (int i = 1; i < argc; ++i) {
        quick = quick || std::strcmp(argv[i], "--quick") == 0;
        kinds_only = kinds_only || std::strcmp(argv[i], "--kinds") == 0;
    }
    const std::string models = HSNC_SOURCE_DIR "/models/";
    struct Case {
        std::string name;
        Model model;
        double t_end;
        double ab4_horizon;  // ab4 at h = 1e-6 is timed over this much, then scaled
    };
    std::vector<Case> cases = {
        {"seed-scenario-1", read_model(models + "seed-scenario-1.toml"), 2.0, quick ? 0.2 : 2.0},
        {"seed-scenario-2", read_model(models + "seed-scenario-2.toml"), 300.0, quick ? 1.0 : 10.0},
        {"chain-16", parse_model(friction_chain(16), "chain-16"), 20.0, quick ? 0.2 : 2.0},
        // Non-proportional damping (dampers): the generic path's state-space solver.
        {"absorber", read_model(HSNC_SOURCE_DIR "/examples/dashpot/absorber.toml"), 60.0, quick ? 0.6 : 6.0},
        {"chain-16-dampers", parse_model(chain_with_dampers(16), "chain-16-dampers"), 20.0, quick ? 0.2 : 2.0},
        // Jenkins elements and friction between two bodies: hsnc (every kernel kind), rk45 and CVODE (no ab4).
        {"friction-damper", read_model(HSNC_SOURCE_DIR "/examples/jenkins/friction_damper.toml"), 40.0, 0.0},
        {"platform-damper", read_model(HSNC_SOURCE_DIR "/examples/jenkins/under_platform_damper.toml", [] {
             ModelOverrides near_resonance;
             near_resonance.set = {"omega=8.3"};
             return near_resonance;
         }()),
         40.0, 0.0},
        {"stacked-blocks", read_model(HSNC_SOURCE_DIR "/examples/friction/stacked_blocks.toml"), 5.0, 0.0},
    };
    const int reps = quick ? 3 : 11;
    auto run_kinds = [&] {
        std::vector<std::pair<std::string, Model>> kind_models;
        std::vector<double> kind_t_ends;
        for (const Case& c : cases) kind_models.emplace_back(c.name, c.model), kind_t_ends.push_back(c.t_end);
        kind_models.emplace_back("chain-8", read_model(models + "chain-8.toml"));
        kind_t_ends.push_back(20.0);
        kind_models.emplace_back("chain-32", parse_model(friction_chain(32), "chain-32"));
        kind_t_ends.push_back(5.0);
        kernel_kinds(kind_models, kind_t_ends, reps);
    };
    if (kinds_only) {
        run_kinds();
        return 0;
    }
    std::printf("%-16s %6s %8s %9s %9s %7s %11s %7s %12s %6s %13s %9s %6s\n", "model", "t_end", "switches",
                "engine_s", "us/switch", "kernels", "ab4(1e-6)_s", "ratio", "rk45(1e-12)_s", "ratio",
                "cvode(1e-12)_s", "us/switch", "ratio");
    double cvode_scenario2 = 0;
    std::vector<std::string> notes;
    for (Case& c : cases) {
        RunSummary s;
        const KernelChoice mode = KernelChoice::automatic;
        const double engine = median_engine(c.model, c.t_end, mode, reps, s);
        IntegratorOptions ab4;
        ab4.h = 1e-6;
        const bool with_ab4 = c.ab4_horizon > 0;  // ab4 keeps its own stick rules: masses against the ground
        const Timed a = with_ab4 ? run_baseline(c.model, c.ab4_horizon, Method::ab4, ab4) : Timed{};
        const double ab4_full =
            with_ab4 ? a.seconds * (c.t_end - c.model.t0) / (c.ab4_horizon - c.model.t0) : std::nan("");
        IntegratorOptions rk;
        rk.rtol = 1e-12;
        rk.atol = 1e-14;
        const Timed r = run_baseline(c.model, c.t_end, Method::rk45, rk);
        IntegratorOptions cv = rk;  // CVODE at the same tolerances
        RunSummary cs;
        const double cvode = median_baseline(c.model, c.t_end, Method::cvode, cv, quick ? 1 : 3, cs);
        cv.cvode_newton = true;
        RunSummary ns;
        const double newton = median_baseline(c.model, c.t_end, Method::cvode, cv, 1, ns);
        if (c.name == "seed-scenario-2") cvode_scenario2 = cvode;
        auto provider = make_solver_provider(c.model, mode, &aot_registry(), program_source(c.model));
        Engine probe(c.model, *provider);
        EngineOptions eo;
        eo.t_end = 1e-9 + c.model.t0;
        Counter cnt;
        probe.run(eo, cnt);
        std::printf("%-16s %6g %8zu %9.4g %9.3g %7s %11.4g %7.0f %12.4g %6.0f %13.4g %9.3g %6.0f\n", c.name.c_str(),
                    c.t_end, s.events, engine, 1e6 * engine / static_cast<double>(std::max<std::size_t>(s.events, 1)),
                    provider->describe().find("ahead") != std::string::npos ? "aot" : "generic", ab4_full,
                    ab4_full / engine, r.seconds, r.seconds / engine, cvode,
                    1e6 * cvode / static_cast<double>(std::max<std::size_t>(cs.events, 1)), cvode / engine);
        char note[256];
        if (!with_ab4) {
            std::snprintf(note, sizeof note, "%s: no ab4 (its own stick rules take masses against the ground only)",
                          c.name.c_str());
            notes.push_back(note);
        } else if (c.ab4_horizon < c.t_end) {
            std::snprintf(note, sizeof note, "%s: ab4 timed over %g s and scaled x%g to the full horizon", c.name.c_str(),
                          c.ab4_horizon, (c.t_end - c.model.t0) / (c.ab4_horizon - c.model.t0));
            notes.push_back(note);
        }
        std::snprintf(note, sizeof note,
                      "%s: cvode %zu switches, %zu steps; with the Newton corrector (dense DQ Jacobian) %.4g s, %zu steps",
                      c.name.c_str(), cs.events, cs.evaluations, newton, ns.evaluations);
        notes.push_back(note);
    }
    for (const std::string& n : notes) std::printf("  %s\n", n.c_str());
    run_kinds();
    // The whole process, start-up included: `hsnc simulate` on scenario 2 to 300 s.
    const std::string scenario2 = models + "seed-scenario-2.toml";
    const int preps = quick ? 5 : 21;
    const ProcessTimes quiet = process_times({HSNC_BINARY, "simulate", scenario2, "--t-end", "300", "--quiet"}, preps);
    // The same process stopped at once: start-up, command line, model file and exit.
    const ProcessTimes startup =
        process_times({HSNC_BINARY, "simulate", scenario2, "--t-end", "0.001", "--quiet"}, preps);
    const std::string out =
        (std::filesystem::temp_directory_path() / ("hsnc_bench_" + std::to_string(::getpid()))).string();
    const ProcessTimes files = process_times({HSNC_BINARY, "simulate", scenario2, "--t-end", "300", "--dt", "0.01", "--out",
                                              out + ".csv", "--events", out + "-events.csv"},
                                             preps);
    std::remove((out + ".csv").c_str());
    std::remove((out + "-events.csv").c_str());
    std::printf("\nwhole process, hsnc simulate seed-scenario-2 --t-end 300 (median of %d spawns):\n", preps);
    std::printf("  %-38s wall %7.2f ms (%5.2f%% of cvode)  cpu %7.2f ms (%5.2f%% of cvode)\n", "--quiet",
                1e3 * quiet.wall, 100 * quiet.wall / cvode_scenario2, 1e3 * quiet.cpu, 100 * quiet.cpu / cvode_scenario2);
    std::printf("  %-38s wall %7.2f ms (%5.2f%% of cvode)  cpu %7.2f ms (%5.2f%% of cvode)\n",
                "--t-end 0.001 --quiet (start-up alone)", 1e3 * startup.wall, 100 * startup.wall / cvode_scenario2,
                1e3 * startup.cpu, 100 * startup.cpu / cvode_scenario2);
    std::printf("  %-38s wall %7.2f ms (%5.2f%% of cvode)  cpu %7.2f ms (%5.2f%% of cvode)\n",
                "--dt 0.01 --out F --events F", 1e3 * files.wall, 100 * files.wall / cvode_scenario2, 1e3 * files.cpu,
                100 * files.cpu / cvode_scenario2);
    // The issue states its target against a CVODE figure quoted for these
    // machines (0.6 s, 140 us per switch); this build's CVODE is measured above.
    constexpr double kQuotedCvode = 0.6;
    std::printf("  cvode (in-process, rtol 1e-12) on the same run: %.4g s; the process (--quiet, wall) is %.0fx faster\n",
                cvode_scenario2, cvode_scenario2 / quiet.wall);
    std::printf("  against the issue's quoted CVODE figure (%.1f s): %.0fx faster; target: at least 100x\n",
                kQuotedCvode, kQuotedCvode / quiet.wall);
    return 0;
}
