// hsnc JIT benchmark, all in one run:
//   1. one long simulation of each model under ahead-of-time kernels, JIT
//      kernels and the generic solver (medians of repeated runs after a
//      warm-up, kernels already built), with the ratios;
//   2. one SegmentSolver::eval alone (what the engine calls 7-8 times per
//      switch), in nanoseconds, the same three ways;
//   3. per configuration kernel: derive+emit, cold compile (Clang + LLVM code
//      generation + JIT link, the persistent cache empty) and warm (a cache
//      hit: read, check, JIT link), medians over the configurations a run of
//      each model visits, and a hit the way `hsnc simulate` takes it, without
//      LLVM (CachedKernelProvider, runtime/jit/object_loader.h);
//   4. the whole `hsnc simulate` process on a model without ahead-of-time
//      kernels: every kernel cached, none cached, the generic solver.
//
//   build/hsnc_jit_bench [--quick]
//
// The cache lives in a fresh temporary directory, removed at the end.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <unistd.h>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <cmath>

#include "aot_registry.h"
#include "derivation.h"
#include "emitter.h"
#include "cached_kernel_provider.h"
#include "engine.h"
#include "generic_solver.h"
#include "kernel_solver.h"
#include "jit_solver_provider.h"
#include "model_reader.h"
#include "kernel_mode.h"
#include "bench_common.h"

namespace {

using namespace hsnc;
using namespace hsnc::bench;

struct Case {
    std::string name;
    Model model;
    double t_end;      // the long run
    double visit_end;  // the run whose configurations are compiled
};

}  // namespace

int main(int argc, char** argv) {
    const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
    const std::size_t max_configs = quick ? 4 : 12;
    const int reps = quick ? 3 : 11;
    const std::string models = HSNC_SOURCE_DIR "/models/";
    std::vector<Case> cases = {
        {"seed-scenario-1", read_model(models + "seed-scenario-1.toml"), 2.0, 2.0},
        {"seed-scenario-2", read_model(models + "seed-scenario-2.toml"), 300.0, 300.0},
        {"chain-8", read_model(models + "chain-8.toml"), 20.0, 20.0},
        {"chain-12", parse_model(chain12(), "chain-12"), 4.0, 4.0},
    };
    const std::string cache_dir =
        (std::filesystem::temp_directory_path() / ("hsnc-jit-bench-" + std::to_string(::getpid()))).string();

    std::printf("1. One long simulation, kernels built beforehand (median of %d runs after a warm-up)\n", reps);
    std::printf("%-16s %7s %9s %11s %11s %11s %9s %9s %9s\n", "model", "t_end", "switches", "aot_ms", "jit_ms",
                "generic_ms", "gen/aot", "gen/jit", "jit/aot");
    for (const Case& c : cases) {
        RunSummary sa, sj, sg;
        std::unique_ptr<SolverProvider> aot_p;
        std::string aot_note;
        if (has_aot_kernels(c.model, &aot_registry()))
            aot_p = make_solver_provider(c.model, KernelChoice::automatic, &aot_registry());
        JitOptions jo;
        jo.cache_dir = cache_dir;
        JitSolverProvider jit(c.model,
                              [&c](const Configuration& cfg) {
                                  return JitKernelSource{kernel_symbol(c.model, cfg), emit_kernel(derive(c.model, cfg))};
                              },
                              jo);
        GenericSolverProvider gen(c.model);
        // Warm-up (every solver built), then the three in turn in each
        // repetition, so that a noisy neighbour slows all three alike.
        if (aot_p) sa = run(c.model, *aot_p, c.t_end);
        sj = run(c.model, jit, c.t_end);
        sg = run(c.model, gen, c.t_end);
        std::vector<double> ta, tj, tg;
        auto time_one = [&](SolverProvider& p, RunSummary& s, std::vector<double>& t) {
            const auto start = Clock::now();
            s = run(c.model, p, c.t_end);
            t.push_back(1e3 * seconds_since(start));
        };
        for (int r = 0; r < reps; ++r) {
            if (aot_p) time_one(*aot_p, sa, ta);
            time_one(jit, sj, tj);
            time_one(gen, sg, tg);
        }
        const double aot = aot_p ? median(ta) : -1, j = median(tj), g = median(tg);
        if (aot_p) aot_note = aot_p->describe();
        if (aot > 0)
            std::printf("%-16s %7g %9zu %11.3f %11.3f %11.3f %9.2f %9.2f %9.2f\n", c.name.c_str(), c.t_end, sg.events,
                        aot, j, g, g / aot, g / j, j / aot);
        else
            std::printf("%-16s %7g %9zu %11s %11.3f %11.3f %9s %9.2f %9s\n", c.name.c_str(), c.t_end, sg.events, "-", j,
                        g, "-", g / j, "-");
        if (sj.events != sg.events || (aot > 0 && sa.events != sg.events))
            std::printf("%-16s switches: aot %zu, jit %zu, generic %zu (rounding-level differences)\n", "",
                        sa.events, sj.events, sg.events);
        if (!aot_note.empty() && aot_note.find(" 0 configurations") == std::string::npos &&
            aot_note.find("generic solver for 0") == std::string::npos)
            std::printf("%-16s aot: %s\n", "", aot_note.c_str());
    }

    std::printf("\n2. One SegmentSolver::eval (ns, median over the configurations a run visits, at most %zu; %s)\n", max_configs,
                "taus spread over two mean segment lengths");
    std::printf("%-16s %5s %9s %9s %11s %9s %9s\n", "model", "cfgs", "aot_ns", "jit_ns", "generic_ns", "gen/aot",
                "gen/jit");
    const int n_eval = quick ? 20000 : 100000;
    volatile double sink = 0;
    for (const Case& c : cases) {
        Recorder rec(c.model);
        const RunSummary visit = run(c.model, rec, c.visit_end);
        std::vector<Configuration> cfgs = rec.seen;
        if (cfgs.size() > max_configs) cfgs.resize(max_configs);
        // Evaluate where the engine does: within a segment's usual length.
        const double span = 2 * (c.visit_end - c.model.t0) / static_cast<double>(std::max<std::size_t>(visit.segments, 1));
        JitOptions jo;
        jo.cache_dir = cache_dir;
        JitSolverProvider jit(c.model,
                              [&c](const Configuration& cfg) {
                                  return JitKernelSource{kernel_symbol(c.model, cfg), emit_kernel(derive(c.model, cfg))};
                              },
                              jo);
        auto aot = has_aot_kernels(c.model, &aot_registry())
                       ? make_solver_provider(c.model, KernelChoice::automatic, &aot_registry())
                       : nullptr;
        GenericSolverProvider gen(c.model);
        const std::size_t n = c.model.dof(), nf = 64;
        std::vector<double> x(n), v(n), a(n), g(nf), dg(nf), bound(nf), scale(nf);
        const SegmentEval out{x.data(), v.data(), a.data(), g.data(), dg.data(), bound.data(), scale.data()};
        auto ns_per_eval = [&](SegmentSolver& s, const Configuration& cfg) {
            std::vector<double> x0 = c.model.x0, v0 = c.model.v0;
            std::vector<signed char> sgn(n, 0);
            for (std::size_t i = 0; i < n; ++i) {
                if (cfg.stuck[i]) v0[i] = 0;
                if (c.model.has_friction(i) && !cfg.stuck[i]) sgn[i] = 1;
            }
            // Mid-run, so that the forcing phases are as large as the engine sees them.
            s.setup(0.5 * (c.model.t0 + c.visit_end), x0.data(), v0.data(), sgn.data());
            std::vector<double> t;
            for (int r = 0; r < 4; ++r) {  // the first one warms up
                const auto start = Clock::now();
                for (int k = 0; k < n_eval; ++k) {
                    s.eval(span * k / n_eval, out);
                    sink = sink + g[0];
                }
                if (r > 0) t.push_back(1e9 * seconds_since(start) / n_eval);
            }
            return median(t);
        };
        std::vector<double> ta, tj, tg;
        for (const Configuration& cfg : cfgs) {
            if (aot) {
                SegmentSolver& s = aot->solver(cfg);
                if (dynamic_cast<KernelSolver*>(&s)) ta.push_back(ns_per_eval(s, cfg));
            }
            tj.push_back(ns_per_eval(jit.solver(cfg), cfg));
            tg.push_back(ns_per_eval(gen.solver(cfg), cfg));
        }
        const double ma = median(ta), mj = median(tj), mg = median(tg);
        if (!ta.empty())
            std::printf("%-16s %5zu %9.1f %9.1f %11.1f %9.2f %9.2f\n", c.name.c_str(), cfgs.size(), ma, mj, mg,
                        mg / ma, mg / mj);
        else
            std::printf("%-16s %5zu %9s %9.1f %11.1f %9s %9.2f\n", c.name.c_str(), cfgs.size(), "-", mj, mg, "-",
                        mg / mj);
    }

    // Build latency last: after it had compiled some 30 kernels, this
    // process ran the generic solver 1.8x slower than a fresh one (measured;
    // the same runs before it agree with `hsnc simulate`), so the run times
    // are measured first.
    std::printf("\n3. Kernel build latency per configuration (median [max] over the configurations compiled)\n");
    std::printf("%-16s %5s %5s %14s %18s %18s %18s %8s\n", "model", "dof", "cfgs", "derive+emit_ms", "cold_compile_ms",
                "hit_llvm_ms", "hit_bare_ms", "obj_kB");
    for (const Case& c : cases) {
        Recorder rec(c.model);
        run(c.model, rec, c.visit_end);
        std::vector<Configuration> cfgs = rec.seen;
        if (cfgs.size() > max_configs) cfgs.resize(max_configs);

        std::vector<double> emit, cold, warm;
        std::map<Configuration, JitKernelSource> sources;
        for (const Configuration& cfg : cfgs) {
            const auto start = Clock::now();
            sources[cfg] = JitKernelSource{kernel_symbol(c.model, cfg), emit_kernel(derive(c.model, cfg))};
            emit.push_back(1e3 * seconds_since(start));
        }
        auto from_sources = [&sources](const Configuration& cfg) { return sources.at(cfg); };
        std::filesystem::remove_all(cache_dir);
        JitOptions jo;
        jo.cache_dir = cache_dir;
        {
            JitSolverProvider jit(c.model, from_sources, jo);  // cold: empty cache
            for (const Configuration& cfg : cfgs) {
                const auto start = Clock::now();
                jit.solver(cfg);
                cold.push_back(1e3 * seconds_since(start));
            }
        }
        {
            JitSolverProvider jit(c.model, from_sources, jo);  // warm: every kernel a cache hit
            for (const Configuration& cfg : cfgs) {
                const auto start = Clock::now();
                jit.solver(cfg);
                warm.push_back(1e3 * seconds_since(start));
            }
            if (jit.cache_hits() != cfgs.size()) std::printf("  (!) only %zu of %zu hits\n", jit.cache_hits(), cfgs.size());
        }
        std::vector<double> bare;  // a hit as `hsnc simulate` takes it: no LLVM (CachedKernelProvider)
        {
            CachedKernelProvider cached(c.model, from_sources, jo, [](JitSolverProvider::SourceFn, const JitOptions&) {
                return std::unique_ptr<JitSolverProvider>();  // never asked: every kernel is cached
            });
            for (const Configuration& cfg : cfgs) {
                const auto start = Clock::now();
                cached.solver(cfg);
                bare.push_back(1e3 * seconds_since(start));
            }
        }
        const KernelCache::Stats st = KernelCache::stats(cache_dir);
        std::printf("%-16s %5zu %5zu %14.2f %11.1f [%4.0f] %11.2f [%4.1f] %11.2f [%4.1f] %8.1f\n", c.name.c_str(),
                    c.model.dof(), cfgs.size(), median(emit), median(cold), *std::max_element(cold.begin(), cold.end()),
                    median(warm), *std::max_element(warm.begin(), warm.end()), median(bare),
                    *std::max_element(bare.begin(), bare.end()),
                    st.entries ? 1e-3 * static_cast<double>(st.bytes) / static_cast<double>(st.entries) : 0.0);
    }

    // 4. The whole `hsnc simulate` process on models without ahead-of-time
    // kernels (edited bundled ones): every kernel cached (found by the index),
    // none (compiled, LLVM and Clang loaded), and the generic solver.
    std::printf("\n4. hsnc simulate on an edited model, whole process (median of %d)\n", reps);
    for (const std::string& args : {std::string("seed-scenario-2.toml' --set mu_k=0.31 --t-end 300"),
                                    std::string("chain-8.toml' --set gap=0.011")}) {
        std::filesystem::remove_all(cache_dir);
        const std::string run_cmd = std::string("'") + HSNC_BINARY + "' simulate '" + models + args + " --quiet >/dev/null ";
        auto process_ms = [&](const std::string& flags) {
            std::vector<double> t;
            for (int r = 0; r < reps; ++r) {
                const auto start = Clock::now();
                if (std::system((run_cmd + flags).c_str()) != 0) return -1.0;
                t.push_back(1e3 * seconds_since(start));
            }
            return median(t);
        };
        if (std::system((run_cmd + "--cache-dir '" + cache_dir + "'").c_str()) != 0) std::printf("(!) hsnc failed\n");
        const double warm_p = process_ms("--cache-dir '" + cache_dir + "'");
        const double cold_p = process_ms("--no-cache");
        const double gen_p = process_ms("--kernels generic");
        std::printf("   %-45s cached: %6.1f ms   compiled (--no-cache): %7.1f ms   generic: %6.1f ms\n",
                    args.c_str(), warm_p, cold_p, gen_p);
    }
    std::filesystem::remove_all(cache_dir);
    return 0;
}
