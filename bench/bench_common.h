// hsnc benches -- what the kernel benches share: timing helpers, an observer
// that counts events, a provider that records the configurations a run
// visits, one engine run, and the 12-mass chain (as tests/test_jit.cpp).
#pragma once

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include "engine.h"
#include "kernel_mode.h"

namespace hsnc::bench {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

inline double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

class Counter : public Observer {
public:
    void on_sample(double, const double*, const double*) override {}
    void on_event(double, EventKind, int, const double*, const double*) override { ++events; }
    std::size_t events = 0;
};

/// The generic solver, remembering the configurations the engine asks for.
class Recorder : public SolverProvider {
public:
    explicit Recorder(const Model& m) : inner_(m) {}
    SegmentSolver& solver(const Configuration& cfg) override {
        if (std::find(seen.begin(), seen.end(), cfg) == seen.end()) seen.push_back(cfg);
        return inner_.solver(cfg);
    }
    std::vector<Configuration> seen;

private:
    GenericSolverProvider inner_;
};

/// One run to t_end without samples.
inline RunSummary run(const Model& m, SolverProvider& p, double t_end) {
    EngineOptions eo;
    eo.t_end = t_end;
    eo.samples = false;
    Counter c;
    Engine engine(m, p);
    return engine.run(eo, c);
}

/// A chain of 12 unit masses with friction on each, contacts m3-m4, m8-m9 and
/// m12 to ground, forced at m1.
inline std::string chain12() {
    std::string t = "name = \"chain-12\"\n[damping]\nalpha = 0.02\nbeta = 0.0005\n";
    for (int i = 1; i <= 12; ++i)
        t += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = 1\nmu_k = 1.0\nmu_s = 1.5\n";
    for (int i = 0; i <= 12; ++i)
        t += "[[spring]]\nbetween = [\"" + (i == 0 ? std::string("ground") : "m" + std::to_string(i)) + "\", \"" +
             (i == 12 ? std::string("ground") : "m" + std::to_string(i + 1)) + "\"]\nk = 100\n";
    t += "[[contact]]\nbetween = [\"m3\", \"m4\"]\ngap = 0.02\nk = 1000\n";
    t += "[[contact]]\nbetween = [\"m8\", \"m9\"]\ngap = 0.02\nk = 1000\n";
    t += "[[contact]]\nbetween = [\"m12\", \"ground\"]\ngap = 0.02\nk = 1000\n";
    t += "[[forcing]]\nomega = 5.0\namplitude = { m1 = 60.0 }\n";
    return t;
}

}  // namespace hsnc::bench
