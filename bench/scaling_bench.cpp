// hsnc_scaling_bench: how the exact method scales with the size of a model,
// against this build's CVODE (issue 13's benchmark).
//
//   build/hsnc_scaling_bench [--quick] [--jit] [--csv FILE] [--targets [PAIRS]]
//
// Chains of 2, 8, 32, 64 and 128 masses (bench_common.h friction_chain(): friction on
// every mass, three stiff contacts, forced at both ends), as hsnc_bench's. Each
// chain runs through hsnc::simulate (a new provider every run, so every
// configuration entered is analysed again):
//   eigen    the Eigen solver (--kernels eigen);
//   generic  the interpreted programs (--kernels generic, and auto for such a
//            model: the double-double derivation of every configuration
//            entered, then its program);
//   jit      (with --jit, up to 8 masses) kernels compiled in-process, from
//            an empty cache (cold) and again from the cache it filled (warm);
//            at 32 masses the cold run took more than 20 minutes of LLVM;
//   cvode    CVODE (Adams, rtol 1e-12, atol 1e-14) with root finding.
// Then the first run of --kernels tiered from an empty cache against the
// interpreter alone, in wall time (chains of 2 to 32 masses). Then chains
// whose switches are few (one contact, one friction joint): one eval against
// the search's own program (SegmentSolver::eval_switches), and whole runs
// against CVODE. Last, issue 13's targets: the 32- and 128-mass friction
// chains over 100 s, generic and CVODE in turn (5 pairs at 32 masses), the
// median of the pairs' ratios, and what entering the 32-mass chain's
// configurations costs (derive, lower, build the programs). --targets runs
// those two alone, with PAIRS pairs at 32 masses (default 5).
// Times are thread CPU time, medians of the runs (5, or 3 with --quick; one
// cold JIT run); per switch and per evaluation are the Eigen solver's, the
// ratios are CVODE's time over the Eigen solver's and over generic's. --csv writes the table
// for the plot (bench/scaling.gp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <stdlib.h>

#include "bench_common.h"
#include "derivation.h"
#include "hsnc/simulate.h"
#include "interpreted_solver.h"
#include "lowering.h"
#include "model_reader.h"

namespace {

using namespace hsnc;
using bench::friction_chain;
using bench::cpu_seconds;

struct Timed {
    double ms = NAN;
    SimulateSummary summary;
};

Timed run(const Model& m, SimulateOptions o, int reps) {
    std::vector<double> t;
    Timed out;
    o.warn = [](const std::string&) {};
    for (int r = 0; r < reps; ++r) {
        const double start = cpu_seconds();
        out.summary = simulate(m, o);
        t.push_back(1e3 * (cpu_seconds() - start));
    }
    out.ms = bench::median(t);
    return out;
}

/// This build's CVODE as the benchmark runs it: Adams, rtol 1e-12, atol 1e-14.
SimulateOptions cvode_options(double t_end) {
    SimulateOptions c;
    c.t_end = t_end;
    c.method = Method::cvode;
    c.integrator.rtol = 1e-12;
    c.integrator.atol = 1e-14;
    return c;
}

/// The number of configurations a run's solver line names ("... for 84 configurations ...").
std::string configurations(const SimulateSummary& s) {
    const std::string& d = s.solver_detail;
    const std::size_t at = d.find("for ") + 4;
    return d.substr(at, d.find(" config") - at);
}

}  // namespace

/// The tables before the targets': chains of 2 to 128 masses over 10 s, the
/// first run of tiered kernels, and chains whose switches are few.
/// False when it cannot make a temporary cache directory.
bool scale_tables(bool quick, bool jit, const std::string& csv) {
    const int reps = quick ? 3 : 5;
    const double t_end = quick ? 2.0 : 10.0;
    std::printf("chains of n masses over %g s, whole runs through hsnc::simulate (thread CPU time, median of %d)\n",
                t_end, reps);
    std::printf("%5s %8s %9s %11s %9s %8s %11s %10s %10s %11s %9s %10s %12s\n", "n", "switches", "cfgs", "eigen_ms",
                "us/switch", "us/eval", "generic_ms", "jit_cold", "jit_warm", "cvode_ms", "us/switch", "cvode/eigen",
                "cvode/generic");
    std::ofstream table;
    if (!csv.empty()) {
        table.open(csv);
        table << "n,switches,eigen_ms,eigen_us_per_switch,eigen_us_per_eval,generic_ms,jit_cold_ms,jit_warm_ms,"
                 "cvode_ms,cvode_over_eigen,cvode_over_generic\n";
    }
    for (int n : {2, 8, 32, 64, 128}) {
        const Model m = parse_model(friction_chain(n), "chain-" + std::to_string(n) + ".toml");
        SimulateOptions o;
        o.t_end = t_end;
        o.kernels = KernelChoice::eigen;
        const Timed g = run(m, o, reps);
        o.kernels = KernelChoice::generic;
        const Timed in = run(m, o, n >= 64 ? 1 : reps);
        double cold = NAN, warm = NAN;
        if (jit && n <= 8) {  // beyond, compiling every configuration takes minutes (32 masses: over 20 min)
            std::string dir = (std::filesystem::temp_directory_path() / "hsnc_scaling_XXXXXX").string();
            if (::mkdtemp(dir.data())) {
                o.kernels = KernelChoice::jit;
                o.cache_dir = dir;
                try {
                    cold = run(m, o, 1).ms;
                    warm = run(m, o, reps).ms;
                } catch (const std::exception& e) {
                    std::fprintf(stderr, "n = %d: jit: %s\n", n, e.what());
                }
                std::filesystem::remove_all(dir);
                o.cache_dir.clear();
            }
        }
        const Timed cv = run(m, cvode_options(t_end), n >= 64 ? 1 : std::min(reps, 3));
        const double sw = static_cast<double>(g.summary.events), ev = static_cast<double>(g.summary.evaluations);
        std::printf("%5d %8zu %9s %11.2f %9.2f %8.3f %11.2f %10.2f %10.2f %11.2f %9.2f %10.1f %12.1f\n", n, g.summary.events,
                    configurations(g.summary).c_str(),
                    g.ms, 1e3 * g.ms / std::max(sw, 1.0), 1e3 * g.ms / std::max(ev, 1.0), in.ms, cold, warm, cv.ms,
                    1e3 * cv.ms / std::max(static_cast<double>(cv.summary.events), 1.0), cv.ms / g.ms, cv.ms / in.ms);
        if (table)
            table << n << ',' << g.summary.events << ',' << g.ms << ',' << 1e3 * g.ms / std::max(sw, 1.0) << ','
                  << 1e3 * g.ms / std::max(ev, 1.0) << ',' << in.ms << ',' << cold << ',' << warm << ',' << cv.ms << ','
                  << cv.ms / g.ms << ',' << cv.ms / in.ms << std::endl;
        std::fflush(stdout);
    }

    // A first run never waits for a compiler (issue 13): --kernels tiered from
    // an empty cache against generic (the interpreter) alone, wall time (a compile would
    // run in a child process: thread CPU time would not see it), the two in
    // turn, median of the ratios of each pair.
    std::printf("\nfirst run, kernels tiered from an empty cache against generic (wall time, median of %d pairs in turn)\n",
                reps);
    std::printf("%5s %11s %11s %8s %s\n", "n", "generic_ms", "tiered_ms", "ratio", "tiers");
    for (int n : {2, 8, 16, 32}) {
        const Model m = parse_model(friction_chain(n), "chain-" + std::to_string(n) + ".toml");
        std::vector<double> ti, tt, ratio;
        std::string tiers;
        for (int r = 0; r < reps; ++r) {
            SimulateOptions o;
            o.t_end = t_end;
            o.warn = [](const std::string&) {};
            o.kernels = KernelChoice::generic;
            auto start = std::chrono::steady_clock::now();
            simulate(m, o);
            ti.push_back(1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
            std::string dir = (std::filesystem::temp_directory_path() / "hsnc_scaling_XXXXXX").string();
            if (!::mkdtemp(dir.data())) return false;
            o.kernels = KernelChoice::tiered;
            o.cache_dir = dir;
            start = std::chrono::steady_clock::now();
            const SimulateSummary s = simulate(m, o);
            tt.push_back(1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
            std::filesystem::remove_all(dir);
            ratio.push_back(tt.back() / ti.back());
            tiers = s.solver_detail.substr(0, s.solver_detail.find(';'));
        }
        std::printf("%5d %11.2f %11.2f %8.2f %s\n", n, bench::median(ti), bench::median(tt), bench::median(ratio),
                    tiers.c_str());
        std::fflush(stdout);
    }

    // Few switches (bench_common.h jointed_chain: one contact and one friction
    // joint at the far end): the search's own program (eval_switches) against
    // a whole eval, one call in the all-open configuration (median of 15
    // rounds of 2000 calls each, the two in turn), then whole runs of eigen,
    // generic and CVODE (thread CPU time).
    const double t_joint = quick ? 50.0 : 200.0;
    std::printf("\nfew switches: a chain with one contact and one friction joint at its far end, over %g s\n", t_joint);
    std::printf("%5s %9s %9s %8s %8s %10s %11s %10s %12s %13s\n", "n", "eval_ns", "search_ns", "ratio", "switches",
                "eigen_ms", "generic_ms", "cvode_ms", "cvode/eigen", "cvode/generic");
    for (int n : {32, 64, 128}) {
        const Model m = parse_model(bench::jointed_chain(n), "jointed-" + std::to_string(n) + ".toml");
        const Configuration cfg = Configuration::all_open(m);
        InterpretedSolver s(lower(derive(m, cfg)));
        const std::size_t ns = s.switches().size();
        std::vector<double> x(m.state_size()), v(m.dof()), a(m.dof()), g(ns), dg(ns), b(ns), sc(ns);
        std::vector<signed char> sgn(m.dof(), 0);
        s.setup(0.0, m.x0.data(), m.v0.data(), sgn.data());
        const SegmentEval o{x.data(), v.data(), a.data(), g.data(), dg.data(), b.data(), sc.data()};
        std::vector<double> te, ts;
        constexpr int kCalls = 2000;
        for (int round = 0; round < 15; ++round) {
            double start = cpu_seconds();
            for (int i = 0; i < kCalls; ++i) s.eval(1e-3 * i, o);
            te.push_back(1e9 * (cpu_seconds() - start) / kCalls);
            start = cpu_seconds();
            for (int i = 0; i < kCalls; ++i) s.eval_switches(1e-3 * i, o);
            ts.push_back(1e9 * (cpu_seconds() - start) / kCalls);
        }
        SimulateOptions e;
        e.t_end = t_joint;
        e.kernels = KernelChoice::eigen;
        const Timed eig = run(m, e, 3);
        e.kernels = KernelChoice::generic;
        const Timed gen = run(m, e, 3);
        const Timed cv = run(m, cvode_options(t_joint), 1);
        std::printf("%5d %9.0f %9.0f %8.2f %8zu %10.1f %11.1f %10.1f %12.1f %13.1f%s\n", n, bench::median(te),
                    bench::median(ts), bench::median(ts) / bench::median(te), gen.summary.events, eig.ms, gen.ms,
                    cv.ms, cv.ms / eig.ms, cv.ms / gen.ms, s.has_switch_program() ? "" : " (no program of its own)");
        std::fflush(stdout);
    }
    return true;
}

int main(int argc, char** argv) {
    bool quick = false, jit = false, targets_only = false;
    int target_pairs = 5;
    std::string csv;
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--quick") == 0) {
            quick = true;
        } else if (std::strcmp(argv[i], "--jit") == 0) {
            jit = true;
        } else if (std::strcmp(argv[i], "--csv") == 0 && i + 1 < argc) {
            csv = argv[++i];
        } else if (std::strcmp(argv[i], "--targets") == 0) {
            targets_only = true;
            if (i + 1 < argc && std::atoi(argv[i + 1]) > 0) target_pairs = std::atoi(argv[++i]);
        } else {
            std::fprintf(stderr, "usage: %s [--quick] [--jit] [--csv FILE] [--targets [PAIRS]]\n", argv[0]);
            return 2;
        }
    }
    if (!targets_only && !scale_tables(quick, jit, csv)) return 1;

    // Issue 13's targets, on long runs of the friction chains: over 100 s a
    // run revisits its configurations, so entering them (the derivation and
    // program of each, the cost that dominates the 10 s table above at 64-128
    // masses) is paid once and the time per switch decides. generic and CVODE
    // in turn, pairs (5 at 32 masses, 1 at 128 masses or with --quick: CVODE
    // takes 40-50 s there), and the median of the pairs' ratios: this
    // machine's speed drifts between runs by more than the ratio's own noise
    // (CVODE's one run at 32 masses took 2.97 to 3.81 s in runs of the bench).
    const double t_long = 100.0;
    std::printf("\nissue 13's targets: friction chains over %g s, generic against CVODE (thread CPU time, pairs in turn)\n",
                t_long);
    std::printf("%5s %8s %9s %11s %10s %10s %6s %12s %8s\n", "n", "switches", "cfgs", "generic_ms", "us/switch",
                "cvode_ms", "pairs", "cvode/generic", "target");
    for (const auto& [n, target] : {std::pair{32, 30.0}, std::pair{128, 10.0}}) {
        const Model m = parse_model(friction_chain(n), "chain-" + std::to_string(n) + ".toml");
        SimulateOptions o;
        o.t_end = t_long;
        o.kernels = KernelChoice::generic;
        const int pairs = quick || n > 32 ? 1 : target_pairs;
        std::vector<double> tg, tc, ratio;
        Timed gen;
        for (int i = 0; i < pairs; ++i) {
            gen = run(m, o, 1);
            const Timed cv = run(m, cvode_options(t_long), 1);
            tg.push_back(gen.ms), tc.push_back(cv.ms), ratio.push_back(cv.ms / gen.ms);
        }
        const double g = bench::median(tg);
        std::printf("%5d %8zu %9s %11.1f %10.2f %10.1f %6d %12.1f %7.0fx\n", n, gen.summary.events,
                    configurations(gen.summary).c_str(), g,
                    1e3 * g / std::max(static_cast<double>(gen.summary.events), 1.0), bench::median(tc), pairs,
                    bench::median(ratio), target);
        std::fflush(stdout);
    }

    // What entering costs: the configurations the 32-mass chain visits over
    // 100 s (a run of the Eigen solver records them), each derived, lowered
    // and built into the interpreter's programs as a run does it
    // (lowering.h program_source: one DerivationCache for the run).
    {
        const Model m = parse_model(friction_chain(32), "chain-32.toml");
        bench::Recorder recorder(m);
        bench::run(m, recorder, t_long);
        const std::vector<Configuration> cfgs = recorder.seen;
        std::vector<double> td, tl, tc;
        for (int round = 0; round < (quick ? 3 : 5); ++round) {
            DerivationCache cache;
            double d = 0, l = 0, c = 0;
            for (const Configuration& cfg : cfgs) {
                const double t0 = cpu_seconds();
                const Derivation der = derive(m, cfg, EigenMethod::refined, ExactMatrices::no, &cache);
                const double t1 = cpu_seconds();
                Program p = lower(der, ProgramNames::no);
                const double t2 = cpu_seconds();
                const InterpretedSolver s(std::move(p));
                c += cpu_seconds() - t2, l += t2 - t1, d += t1 - t0;
            }
            const double k = 1e6 / static_cast<double>(cfgs.size());
            td.push_back(k * d), tl.push_back(k * l), tc.push_back(k * c);
        }
        std::printf("\nentering the %zu configurations the 32-mass chain visits over %g s (us each, median of %d rounds)\n",
                    cfgs.size(), t_long, quick ? 3 : 5);
        std::printf("%9s %9s %9s %9s\n", "derive", "lower", "build", "total");
        std::printf("%9.1f %9.1f %9.1f %9.1f\n", bench::median(td), bench::median(tl), bench::median(tc),
                    bench::median(td) + bench::median(tl) + bench::median(tc));
    }
    return 0;
}
