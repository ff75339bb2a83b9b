// hsnc benches -- what the kernel benches share: timing helpers, an observer
// that counts events, a provider that records the configurations a run
// visits, one engine run, and the 12-mass chain (as tests/test_jit.cpp).
#pragma once

#include <algorithm>
#include <chrono>
#include <ctime>
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

/// The Eigen solver, remembering the configurations the engine asks for.
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

/// This thread's CPU time: what a run costs, without the time a noisy
/// neighbour (2 cores shared) keeps it off the processor.
inline double cpu_seconds() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// The chain of n masses of hsnc_bench and hsnc_scaling_bench: unit masses
/// with friction (mu_k 0.05, mu_s 0.07) joined by 400 N/m springs and to
/// ground at both ends, contacts between masses n/4 and n/4+1, n/2 and
/// n/2+1, and 3n/4 to ground (each at least mass 1; one left out where it
/// would repeat another or leave the chain), beta = 0.002, forced at both
/// ends at 9 rad/s, the middle mass started at 1 m/s. friction_chain(16) is the
/// 16-mass chain of the figures in docs/results.md.
inline std::string friction_chain(int n) {
    auto m = [](int i) { return "m" + std::to_string(i); };
    const int q1 = std::max(1, n / 4), q2 = std::max(1, n / 2), q3 = std::max(1, 3 * n / 4);
    std::string t = "name = \"chain-" + std::to_string(n) + "\"\n[damping]\nbeta = 0.002\n";
    for (int i = 1; i <= n; ++i) t += "[[mass]]\nname = \"" + m(i) + "\"\nm = 1\nmu_k = 0.05\nmu_s = 0.07\n";
    t += "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 400\n";
    for (int i = 1; i < n; ++i) t += "[[spring]]\nbetween = [\"" + m(i) + "\", \"" + m(i + 1) + "\"]\nk = 400\n";
    t += "[[spring]]\nbetween = [\"" + m(n) + "\", \"ground\"]\nk = 400\n";
    if (q1 < n) t += "[[contact]]\nbetween = [\"" + m(q1) + "\", \"" + m(q1 + 1) + "\"]\ngap = 0.01\nk = 4000\n";
    if (q2 != q1 && q2 < n) t += "[[contact]]\nbetween = [\"" + m(q2) + "\", \"" + m(q2 + 1) + "\"]\ngap = 0.01\nk = 4000\n";
    t += "[[contact]]\nbetween = [\"" + m(q3) + "\", \"ground\"]\ngap = 0.02\nk = 4000\n";
    t += "[[forcing]]\nomega = 9.0\namplitude = { m1 = 30.0" + (n > 1 ? ", " + m(n) + " = -20.0" : std::string()) + " }\n";
    t += "[initial]\nv = { " + m(q2) + " = 1.0 }\n";
    return t;
}

/// A chain of n unit masses whose switches are few, as in a structure with a
/// crack or a bolted joint: springs of 400 N/m, beta = 0.002, one contact
/// (gap 0.02 m, 4000 N/m) and one friction joint (mu_k 0.05, mu_s 0.07) at its
/// far end, forced at m1 at 9 rad/s. Its switch functions read the state of
/// mn alone.
inline std::string jointed_chain(int n) {
    auto m = [](int i) { return "m" + std::to_string(i); };
    std::string t = "name = \"jointed-" + std::to_string(n) + "\"\n[damping]\nbeta = 0.002\n";
    for (int i = 1; i <= n; ++i)
        t += "[[mass]]\nname = \"" + m(i) + "\"\nm = 1\n" + (i == n ? "mu_k = 0.05\nmu_s = 0.07\n" : "");
    t += "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 400\n";
    for (int i = 1; i < n; ++i) t += "[[spring]]\nbetween = [\"" + m(i) + "\", \"" + m(i + 1) + "\"]\nk = 400\n";
    t += "[[contact]]\nbetween = [\"" + m(n) + "\", \"ground\"]\ngap = 0.02\nk = 4000\n";
    t += "[[forcing]]\nomega = 9.0\namplitude = { m1 = 30.0 }\n";
    return t;
}

}  // namespace hsnc::bench
