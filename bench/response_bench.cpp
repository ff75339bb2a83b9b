// hsnc response-curve benchmark (hsnc sweep, api/hsnc/sweep.h), in one run:
// a 200-point response curve (100 values of the forcing frequency, swept up
// and down: two independent tasks) of seed scenario 1 and of a 16-mass
// chain, by hsnc on 1 and 2 threads and by the same sweep with this build's
// CVODE baseline (method cvode, rtol 1e-10, atol 1e-12, through the same
// library: the same transient and settling rules, the same number of
// recorded periods; its xmax, xrms and a1 from samples). Prints, per case,
// the median wall time of `repeats` runs, the periods simulated, the ratio
// CVODE / hsnc, the speed-up of 2 threads and the parallel efficiency
// (speed-up / 2).
//
//   build/hsnc_response_bench [repeats]   (default 3)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench_common.h"
#include "file_read.h"
#include "hsnc/sweep.h"

using namespace hsnc;

namespace {

// 16 unit masses in a chain held to the ground at both ends, friction on
// every mass, contacts m4-m5, m11-m12 and m16 to ground, forced at m1.
std::string chain16() {
    std::string t = "name = \"chain-16\"\n[parameters]\nomega = 5.0\n[damping]\nalpha = 0.05\nbeta = 0.0005\n";
    for (int i = 1; i <= 16; ++i)
        t += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = 1\nmu_k = 0.3\nmu_s = 0.4\n";
    for (int i = 0; i <= 16; ++i)
        t += "[[spring]]\nbetween = [\"" + (i == 0 ? std::string("ground") : "m" + std::to_string(i)) + "\", \"" +
             (i == 16 ? std::string("ground") : "m" + std::to_string(i + 1)) + "\"]\nk = 100\n";
    t += "[[contact]]\nbetween = [\"m4\", \"m5\"]\ngap = 0.02\nk = 1000\n";
    t += "[[contact]]\nbetween = [\"m11\", \"m12\"]\ngap = 0.02\nk = 1000\n";
    t += "[[contact]]\nbetween = [\"m16\", \"ground\"]\ngap = 0.05\nk = 1000\n";
    t += "[[forcing]]\nomega = \"omega\"\namplitude = { m1 = 30.0 }\n";
    return t;
}

struct Case {
    std::string name, text, source;
    double from, to;
    std::size_t max_periods;
};

struct Timing {
    double seconds = 0;
    std::size_t periods = 0, settled = 0;
};

Timing time_sweep(const Case& c, Method method, unsigned threads, int repeats) {
    SweepOptions o;
    o.param = "omega";
    o.from = c.from;
    o.to = c.to;
    o.points = 100;
    o.direction = SweepDirection::both;
    o.max_periods = c.max_periods;
    o.record_periods = 16;
    o.threads = threads;
    o.method = method;
    const SweepPlan plan(c.text, c.source, {}, o);
    std::vector<double> t;
    Timing r;
    for (int k = 0; k < repeats; ++k) {
        const auto start = bench::Clock::now();
        const SweepResult res = plan.run();
        t.push_back(bench::seconds_since(start));
        r.periods = r.settled = 0;
        for (const SweepPoint& p : res.points) {
            r.periods += p.periods + o.record_periods;
            r.settled += p.settled;
        }
    }
    r.seconds = bench::median(t);
    return r;
}

}  // namespace

int main(int argc, char** argv) {
    const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
    const std::string s1_path = std::string(HSNC_SOURCE_DIR) + "/models/seed-scenario-1.toml";
    const FileRead s1 = read_regular_file(s1_path, kMaxModelFileBytes);
    if (s1.status != FileRead::Status::ok) {
        std::fprintf(stderr, "cannot read %s\n", s1_path.c_str());
        return 1;
    }
    const std::vector<Case> cases = {
        {"seed scenario 1 (2 DOF), omega 150..200", s1.bytes, s1_path, 150.0, 200.0, 500},
        {"16-mass chain, omega 3..8", chain16(), "chain-16", 3.0, 8.0, 500},
    };
    std::printf("200-point response curves (100 values, up and down), median of %d runs\n\n", repeats);
    std::printf("%-40s %-16s %10s %9s %8s %12s\n", "case", "method", "wall [s]", "periods", "settled", "us/period");
    for (const Case& c : cases) {
        const Timing h1 = time_sweep(c, Method::hsnc, 1, repeats);
        const Timing h2 = time_sweep(c, Method::hsnc, 2, repeats);
        const Timing cv = time_sweep(c, Method::cvode, 1, repeats);
        auto row = [&](const char* method, const Timing& t) {
            std::printf("%-40s %-16s %10.3f %9zu %8zu %12.2f\n", c.name.c_str(), method, t.seconds, t.periods,
                        t.settled, 1e6 * t.seconds / static_cast<double>(t.periods));
        };
        row("hsnc, 1 thread", h1);
        row("hsnc, 2 threads", h2);
        row("cvode, 1 thread", cv);
        std::printf("%-40s cvode / hsnc (1 thread) = %.1f; 2 threads: speed-up %.2f, parallel efficiency %.0f%%\n\n",
                    "", cv.seconds / h1.seconds, h1.seconds / h2.seconds, 50 * h1.seconds / h2.seconds);
    }
    return 0;
}
