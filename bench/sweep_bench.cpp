// hsnc sweep-kernel benchmark: what keeping parameters as run-time arguments
// (hsnc generate --params, generator/param_emitter.h) costs, in one run:
// the JIT compile time of a sweep kernel against the folded kernel of the
// same configuration, configure() per parameter value, and setup / eval per
// call against the folded kernel (both JIT-compiled, -O2) and the generic
// solver. Medians of 11 batches.
//
//   build/hsnc_sweep_bench
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "derivation.h"
#include "emitter.h"
#include "generic_solver.h"
#include "jit.h"
#include "kernel_solver.h"
#include "model_reader.h"
#include "param_emitter.h"

using namespace hsnc;
using Clock = std::chrono::steady_clock;

namespace {

template <class F>
double median_ns(int per_batch, F&& f) {
    std::vector<double> t;
    for (int b = 0; b < 11; ++b) {
        const auto t0 = Clock::now();
        for (int i = 0; i < per_batch; ++i) f(i);
        t.push_back(std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / per_batch);
    }
    std::sort(t.begin(), t.end());
    return t[5];
}

struct Costs {
    double setup = 0, eval = 0;
};

volatile double g_sink = 0;

Costs segment_costs(SegmentSolver& s, const Model& m, const Configuration& cfg) {
    const std::size_t n = m.dof(), ns = s.switches().size();
    std::vector<double> x0 = m.x0, v0 = m.v0;
    std::vector<signed char> sgn(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        if (cfg.stuck[i]) v0[i] = 0.0;
        if (m.has_friction(i) && !cfg.stuck[i]) sgn[i] = v0[i] < 0 ? -1 : 1;
    }
    std::vector<double> x(n), v(n), a(n), g(ns), dg(ns), b(ns), sc(ns);
    const SegmentEval out{x.data(), v.data(), a.data(), g.data(), dg.data(), b.data(), sc.data()};
    Costs c;
    c.setup = median_ns(20000, [&](int i) {
        x0[0] += 1e-12 * (i & 1 ? 1 : -1);
        s.setup(0.1 * (i & 7), x0.data(), v0.data(), sgn.data());
    });
    c.eval = median_ns(20000, [&](int i) {
        s.eval(1e-3 * (i & 63), out);
        g_sink = g_sink + x[0];
    });
    return c;
}

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

}  // namespace

int main() {
    const std::string models = HSNC_MODELS_DIR;
    struct Case {
        std::string file, spec, params;
    };
    std::printf("%-36s %-10s %9s %9s %10s %9s %9s %9s %9s %9s\n", "model [configuration]", "params", "jit fold",
                "jit sweep", "configure", "setup F", "setup S", "eval F", "eval S", "eval G");
    std::printf("%-36s %-10s %9s %9s %10s %9s %9s %9s %9s %9s\n", "", "", "ms", "ms", "us", "ns", "ns", "ns", "ns", "ns");
    for (const Case& c : {Case{"seed-scenario-1.toml", "closed=contact1", "k1,beta"},
                          Case{"seed-scenario-2.toml", "", "omega"},
                          Case{"chain-8.toml", "closed=c23,c56", "all"}}) {
        const Model model = read_model(models + "/" + c.file);
        const Configuration cfg = Configuration::parse(model, c.spec);
        const std::vector<std::string> kept = kept_parameters(model, c.params);
        std::vector<double> values;
        for (const auto& [name, value] : model.parameters)
            if (std::find(kept.begin(), kept.end(), name) != kept.end()) values.push_back(value);

        Jit jit;
        auto t0 = Clock::now();
        jit.add("folded.cpp", emit_kernel(derive(model, cfg)));
        const auto* folded = static_cast<const hsnc_kernel*>(jit.lookup(kernel_symbol(model, cfg)));
        const double jit_folded = ms_since(t0);
        t0 = Clock::now();
        jit.add("sweep.cpp", emit_sweep_kernel(derive(model, cfg), kept));
        const auto* sweep = static_cast<const hsnc_kernel*>(jit.lookup(sweep_kernel_symbol(model, cfg)));
        const double jit_sweep = ms_since(t0);

        KernelSolver fs(*folded), ss(*sweep, values);
        GenericSolver gs(model, cfg);
        std::vector<double> v2 = values;
        const double configure = median_ns(2000, [&](int i) {
            v2[0] = values[0] * (1.0 + 1e-9 * (i & 1));
            ss.configure(v2);
        });
        ss.configure(values);
        const Costs cf = segment_costs(fs, model, cfg), cs = segment_costs(ss, model, cfg),
                    cg = segment_costs(gs, model, cfg);
        std::printf("%-36s %-10s %9.1f %9.1f %10.2f %9.0f %9.0f %9.0f %9.0f %9.0f\n",
                    (model.name + " [" + c.spec + "]").c_str(), c.params.c_str(), jit_folded, jit_sweep,
                    configure / 1000.0, cf.setup, cs.setup, cf.eval, cs.eval, cg.eval);
    }
    std::printf("F = folded kernel, S = sweep kernel (both JIT -O2), G = generic solver; medians of 11 batches.\n");
    return 0;
}
