// hsnc benchmark: switches, wall time, microseconds per switch, and the ratios
// to the numerical-integration baselines, all measured in one run.
//
//   build/hsnc_bench [--quick]
//
// Engine times are medians of repeated runs (the machines are noisy); each
// baseline runs once. ab4 at h = 1e-6 over 300 s would take about a minute,
// so it is timed over a shorter horizon and its cost per simulated second is
// scaled to the full horizon (its cost is proportional to the horizon: fixed
// step). That scaling is printed with the figure.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "aot_registry.h"
#include "engine.h"
#include "integrators.h"
#include "model_reader.h"
#include "solver_provider.h"

namespace {

using namespace hsnc;
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

Timed run_engine(const Model& m, double t_end, KernelMode mode) {
    EngineOptions eo;
    eo.t_end = t_end;
    eo.samples = false;
    Counter c;
    auto provider = make_solver_provider(m, mode, &aot_registry());
    Engine engine(m, *provider);
    engine.run(eo, c);  // warm: kernels and solvers created
    const auto start = Clock::now();
    RunSummary s = engine.run(eo, c);
    return {seconds_since(start), s};
}

double median_engine(const Model& m, double t_end, KernelMode mode, int reps, RunSummary& summary) {
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

// The 16-mass chain: springs between neighbours and to ground at both ends,
// contacts between masses 4-5, 8-9 and 12 to ground, friction on every mass.
std::string chain16() {
    std::string t = "name = \"chain-16\"\n[damping]\nbeta = 0.002\n";
    for (int i = 1; i <= 16; ++i)
        t += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = 1\nmu_k = 0.05\nmu_s = 0.07\n";
    t += "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 400\n";
    for (int i = 1; i < 16; ++i)
        t += "[[spring]]\nbetween = [\"m" + std::to_string(i) + "\", \"m" + std::to_string(i + 1) + "\"]\nk = 400\n";
    t += "[[spring]]\nbetween = [\"m16\", \"ground\"]\nk = 400\n";
    t += "[[contact]]\nbetween = [\"m4\", \"m5\"]\ngap = 0.01\nk = 4000\n";
    t += "[[contact]]\nbetween = [\"m8\", \"m9\"]\ngap = 0.01\nk = 4000\n";
    t += "[[contact]]\nbetween = [\"m12\", \"ground\"]\ngap = 0.02\nk = 4000\n";
    t += "[[forcing]]\nomega = 9.0\namplitude = { m1 = 30.0, m16 = -20.0 }\n";
    t += "[initial]\nv = { m8 = 1.0 }\n";
    return t;
}

double process_seconds(const std::string& command, int reps) {
    std::vector<double> t;
    for (int r = 0; r < reps; ++r) {
        const auto start = Clock::now();
        if (std::system(command.c_str()) != 0) return -1;
        t.push_back(seconds_since(start));
    }
    std::sort(t.begin(), t.end());
    return t[t.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
    const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
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
        {"chain-16", parse_model(chain16(), "chain-16"), 20.0, quick ? 0.2 : 2.0},
    };
    const int reps = quick ? 3 : 11;
    std::printf("%-16s %8s %10s %10s %10s %9s %12s %9s %12s %9s\n", "model", "t_end", "switches", "engine_s",
                "us/switch", "kernels", "ab4(1e-6)_s", "ratio", "rk45(1e-12)_s", "ratio");
    for (Case& c : cases) {
        RunSummary s;
        const KernelMode mode = KernelMode::automatic;
        const double engine = median_engine(c.model, c.t_end, mode, reps, s);
        IntegratorOptions ab4;
        ab4.h = 1e-6;
        const Timed a = run_baseline(c.model, c.ab4_horizon, Method::ab4, ab4);
        const double ab4_full = a.seconds * (c.t_end - c.model.t0) / (c.ab4_horizon - c.model.t0);
        IntegratorOptions rk;
        rk.rtol = 1e-12;
        rk.atol = 1e-14;
        const Timed r = run_baseline(c.model, c.t_end, Method::rk45, rk);
        auto provider = make_solver_provider(c.model, mode, &aot_registry());
        Engine probe(c.model, *provider);
        EngineOptions eo;
        eo.t_end = 1e-9 + c.model.t0;
        Counter cnt;
        probe.run(eo, cnt);
        std::printf("%-16s %8g %10zu %10.4g %10.3g %9s %12.4g %9.0f %12.4g %9.0f\n", c.name.c_str(), c.t_end, s.events,
                    engine, 1e6 * engine / static_cast<double>(std::max<std::size_t>(s.events, 1)),
                    provider->describe().find("ahead") != std::string::npos ? "aot" : "generic", ab4_full,
                    ab4_full / engine, r.seconds, r.seconds / engine);
        if (c.ab4_horizon < c.t_end)
            std::printf("%-16s ab4 timed over %g s and scaled x%g to the full horizon\n", "", c.ab4_horizon,
                        (c.t_end - c.model.t0) / (c.ab4_horizon - c.model.t0));
    }
    // The whole process, start-up included: `hsnc simulate` on scenario 2 to 300 s.
    const std::string cmd =
        std::string("'") + HSNC_BINARY + "' simulate '" + models + "seed-scenario-2.toml' --t-end 300 --quiet >/dev/null";
    const double proc = process_seconds(cmd, quick ? 3 : 7);
    std::printf("\nhsnc simulate seed-scenario-2 --t-end 300 (whole process, median): %.4f s\n", proc);
    return 0;
}
