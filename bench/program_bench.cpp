// hsnc program benchmark: the interpreter of a configuration's Program
// (runtime/solvers/interpreted_solver.h, --kernels generic) against the kernel printed
// from the same program (ahead of time, JIT) and the Eigen solver
// (runtime/solvers/generic_solver.h, --kernels eigen, the tests' independent oracle), in one run:
//   1. one SegmentSolver::eval, in nanoseconds, as bench/jit_bench.cpp section
//      2 measures it (the same configurations, instants and setup), and one
//      SegmentSolver::setup the same way;
//   2. one long simulation per model (median of repeated runs after a
//      warm-up, every solver built beforehand), with the switch counts;
//   3. the same simulation from nothing: the interpreter derives and lowers
//      (double-double) each configuration it enters, the Eigen solver analyses it
//      in double; before: the interpreter with the former derivation (Jacobi
//      rotations in GiNaC numerics, EigenMethod::jacobi);
//   4. one all-open chain configuration of 8 to 64 masses: derive + lower
//      (refined, Jacobi) against building the Eigen solver;
//   5. one segment start in the all-open friction chain of 16 to 128 masses:
//      setup from the state against a restart at a reversal, and the search's
//      first evaluation there (set up, and carried over) against an eval later
//      in the segment.
//
// Times are this thread's CPU time (CLOCK_THREAD_CPUTIME_ID), medians.
//
//   build/hsnc_program_bench [--quick] [MODEL]   (MODEL: one of the cases only)
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "aot_registry.h"
#include "derivation.h"
#include "emitter.h"
#include "engine.h"
#include "generic_solver.h"
#include "interpreted_solver.h"
#include "jit_solver_provider.h"
#include "kernel_solver.h"
#include "lowering.h"
#include "model_reader.h"
#include "restart.h"
#include "kernel_mode.h"
#include "bench_common.h"

namespace {

using namespace hsnc;
using namespace hsnc::bench;

struct Case {
    std::string name;
    Model model;
    double t_end;
};


/// A chain of n unit masses as bench_common.h's 12-mass chain (friction on
/// each, contacts m3-m4, m(n-4)-m(n-3) and mn to ground), with lighter
/// friction and forced at m1, m(n/2) and mn, so that most masses slide.
std::string chain(int n) {
    std::string t = "name = \"chain-" + std::to_string(n) + "\"\n[damping]\nalpha = 0.02\nbeta = 0.0005\n";
    for (int i = 1; i <= n; ++i)
        t += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = 1\nmu_k = 0.02\nmu_s = 0.03\n";
    for (int i = 0; i <= n; ++i)
        t += "[[spring]]\nbetween = [\"" + (i == 0 ? std::string("ground") : "m" + std::to_string(i)) + "\", \"" +
             (i == n ? std::string("ground") : "m" + std::to_string(i + 1)) + "\"]\nk = 100\n";
    t += "[[contact]]\nbetween = [\"m3\", \"m4\"]\ngap = 0.02\nk = 1000\n";
    t += "[[contact]]\nbetween = [\"m" + std::to_string(n - 4) + "\", \"m" + std::to_string(n - 3) +
         "\"]\ngap = 0.02\nk = 1000\n";
    t += "[[contact]]\nbetween = [\"m" + std::to_string(n) + "\", \"ground\"]\ngap = 0.02\nk = 1000\n";
    t += "[[forcing]]\nomega = 5.0\namplitude = { m1 = 60.0, m" + std::to_string(n / 2) + " = 40.0, m" +
         std::to_string(n) + " = -30.0 }\n";
    return t;
}

}  // namespace

int main(int argc, char** argv) {
    bool quick = false;
    std::string only;
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--quick") == 0)
            quick = true;
        else
            only = argv[i];
    }
    const std::size_t max_configs = quick ? 4 : 12;
    const int reps = quick ? 3 : 11, reps3 = quick ? 1 : 3;
    const std::string models = HSNC_SOURCE_DIR "/models/";
    std::vector<Case> cases = {
        {"seed-scenario-1", read_model(models + "seed-scenario-1.toml"), 2.0},
        {"seed-scenario-2", read_model(models + "seed-scenario-2.toml"), 300.0},
        {"chain-8", read_model(models + "chain-8.toml"), 20.0},
        {"chain-12", parse_model(chain12(), "chain-12"), 4.0},
        {"chain-32", parse_model(chain(32), "chain-32"), 0.5},
    };
    if (!only.empty())
        cases.erase(std::remove_if(cases.begin(), cases.end(), [&](const Case& c) { return c.name != only; }),
                    cases.end());
    auto lowering = [](const Model& m) {
        return [&m](const Configuration& cfg) { return lower(derive(m, cfg)); };
    };
    auto emitter = [](const Model& m) {
        return [&m](const Configuration& cfg) {
            return JitKernelSource{kernel_symbol(m, cfg), emit_kernel(derive(m, cfg))};
        };
    };

    const int rounds = quick ? 15 : 51, burst = 2000;
    // Per case one row of eval times and one of setup times, printed as two tables.
    std::vector<std::string> eval_rows, setup_rows;
    volatile double sink = 0;
    for (const Case& c : cases) {
        Recorder rec(c.model);
        const RunSummary visit = run(c.model, rec, c.t_end);
        std::vector<Configuration> cfgs = rec.seen;
        if (cfgs.size() > max_configs) cfgs.resize(max_configs);
        const double span = 2 * (c.t_end - c.model.t0) / static_cast<double>(std::max<std::size_t>(visit.segments, 1));
        JitSolverProvider jit(c.model, emitter(c.model));  // no persistent cache
        auto aot = has_aot_kernels(c.model, &aot_registry())
                       ? make_solver_provider(c.model, KernelChoice::automatic, &aot_registry())
                       : nullptr;
        GenericSolverProvider gen(c.model);
        InterpretedSolverProvider interp(lowering(c.model));
        const std::size_t n = c.model.dof(), nf = c.model.contacts.size() + 2 * n;  // switch functions at most
        std::vector<double> x(n), v(n), a(n), g(nf), dg(nf), bound(nf), scale(nf);
        const SegmentEval out{x.data(), v.data(), a.data(), g.data(), dg.data(), bound.data(), scale.data()};
        // The solvers of one configuration in turn, in short bursts, so that a
        // noisy neighbour (2 cores shared) slows all of them alike; per solver
        // the median over the rounds. setup: the same state at instants 1e-7 apart.
        auto time_config = [&](std::vector<SegmentSolver*> solvers, const Configuration& cfg, bool setup) {
            std::vector<double> x0 = c.model.x0, v0 = c.model.v0;
            std::vector<signed char> sgn(n, 0);
            for (std::size_t i = 0; i < n; ++i) {
                if (cfg.stuck[i]) v0[i] = 0;
                if (c.model.has_friction(i) && !cfg.stuck[i]) sgn[i] = 1;
            }
            const double t_mid = 0.5 * (c.model.t0 + c.t_end);  // mid-run, so that the forcing phases are as large as the engine sees them
            std::vector<std::vector<double>> t(solvers.size());
            for (SegmentSolver* s : solvers)
                if (s) s->setup(t_mid, x0.data(), v0.data(), sgn.data());
            for (int r = 0; r < rounds + 1; ++r)  // the first round warms up
                for (std::size_t k = 0; k < solvers.size(); ++k) {
                    if (!solvers[k]) continue;
                    const double start = cpu_seconds();
                    if (setup) {
                        for (int e = 0; e < burst; ++e) solvers[k]->setup(t_mid + 1e-7 * e, x0.data(), v0.data(), sgn.data());
                    } else {
                        for (int e = 0; e < burst; ++e) {
                            solvers[k]->eval(span * e / burst, out);
                            sink = sink + g[0];
                        }
                    }
                    if (r > 0) t[k].push_back(1e9 * (cpu_seconds() - start) / burst);
                }
            std::vector<double> med;
            for (auto& tk : t) med.push_back(tk.empty() ? -1 : median(tk));
            return med;
        };
        for (bool setup : {false, true}) {
            std::vector<double> ta, tj, ti, tg;
            for (const Configuration& cfg : cfgs) {
                SegmentSolver* a_s = nullptr;
                if (aot) {
                    SegmentSolver& s = aot->solver(cfg);
                    if (dynamic_cast<KernelSolver*>(&s)) a_s = &s;
                }
                const std::vector<double> m =
                    time_config({a_s, &jit.solver(cfg), &interp.solver(cfg), &gen.solver(cfg)}, cfg, setup);
                if (a_s) ta.push_back(m[0]);
                tj.push_back(m[1]);
                ti.push_back(m[2]);
                tg.push_back(m[3]);
            }
            const double mi = median(ti), mj = median(tj), mg = median(tg);
            char aot_text[32] = "-", row[256];
            if (!ta.empty()) std::snprintf(aot_text, sizeof aot_text, "%.1f", median(ta));
            std::snprintf(row, sizeof row, "%-16s %5zu %8s %8.1f %9.1f %11.1f %11.2f %10.2f\n", c.name.c_str(),
                          cfgs.size(), aot_text, mj, mi, mg, mi / mg, mi / mj);
            (setup ? setup_rows : eval_rows).push_back(row);
        }
    }
    for (bool setup : {false, true}) {
        std::printf("%s. One SegmentSolver::%s (ns, median over the configurations a run visits, at most %zu;%s\n"
                    "   per configuration the four solvers in turn, %d rounds of %d calls, median over the rounds)\n",
                    setup ? "\n1b" : "1", setup ? "setup" : "eval", max_configs,
                    setup ? " the same state" : " taus spread over two mean segment lengths;", rounds, burst);
        std::printf("%-16s %5s %8s %8s %9s %11s %11s %10s\n", "model", "cfgs", "aot_ns", "jit_ns", "interp_ns",
                    "eigen_ns", "interp/eig", "interp/jit");
        for (const std::string& r : setup ? setup_rows : eval_rows) std::printf("%s", r.c_str());
    }

    std::printf("\n2. One long simulation, every solver built beforehand (median of %d runs after a warm-up)\n", reps);
    std::printf("%-16s %7s %21s %9s %9s %10s %10s %11s %10s\n", "model", "t_end", "switches aot/jit/int/eig",
                "aot_ms", "jit_ms", "interp_ms", "eigen_ms", "interp/eig", "interp/jit");
    for (const Case& c : cases) {
        std::unique_ptr<SolverProvider> aot;
        if (has_aot_kernels(c.model, &aot_registry()))
            aot = make_solver_provider(c.model, KernelChoice::automatic, &aot_registry());
        JitSolverProvider jit(c.model, emitter(c.model));
        InterpretedSolverProvider interp(lowering(c.model));
        GenericSolverProvider gen(c.model);
        SolverProvider* providers[4] = {aot.get(), &jit, &interp, &gen};
        RunSummary s[4];
        std::vector<double> t[4];
        for (int p = 0; p < 4; ++p)
            if (providers[p]) s[p] = run(c.model, *providers[p], c.t_end);  // warm-up: every solver built
        for (int r = 0; r < reps; ++r)  // in turn, so that a noisy neighbour slows all alike
            for (int p = 0; p < 4; ++p) {
                if (!providers[p]) continue;
                const double start = cpu_seconds();
                s[p] = run(c.model, *providers[p], c.t_end);
                t[p].push_back(1e3 * (cpu_seconds() - start));
            }
        char sw[64], aot_ms[32] = "-";
        if (aot) {
            std::snprintf(sw, sizeof sw, "%zu/%zu/%zu/%zu", s[0].events, s[1].events, s[2].events, s[3].events);
            std::snprintf(aot_ms, sizeof aot_ms, "%.3f", median(t[0]));
        } else {
            std::snprintf(sw, sizeof sw, "-/%zu/%zu/%zu", s[1].events, s[2].events, s[3].events);
        }
        const double mj = median(t[1]), mi = median(t[2]), mg = median(t[3]);
        std::printf("%-16s %7g %21s %9s %9.3f %10.3f %10.3f %11.2f %10.2f\n", c.name.c_str(), c.t_end, sw, aot_ms, mj,
                    mi, mg, mi / mg, mi / mj);
    }

    std::printf("\n3. The same simulation from nothing: each run with new providers, so every configuration entered is\n"
                "   derived and lowered (interpreter) or analysed by the Eigen solver (eigen), median of %d runs in turn\n",
                reps3);
    std::printf("   (before: the interpreter with the former derivation, Jacobi rotations in GiNaC numerics)\n");
    std::printf("%-16s %7s %9s %6s %10s %10s %11s %16s %14s %13s\n", "model", "t_end", "switches", "cfgs", "interp_ms",
                "eigen_ms", "interp/eig", "derive+lower/cfg", "before_ms", "before/eig");
    for (const Case& c : cases) {
        std::vector<double> ti, tg, tb, per_cfg;
        RunSummary si, sg;
        std::size_t cfgs = 0;
        for (int r = 0; r < reps3; ++r) {
            {
                const double start = cpu_seconds();
                InterpretedSolverProvider before([&m = c.model](const Configuration& cfg) {
                    return lower(derive(m, cfg, EigenMethod::jacobi));
                });
                run(c.model, before, c.t_end);
                tb.push_back(1e3 * (cpu_seconds() - start));
            }
            {
                const double start = cpu_seconds();
                InterpretedSolverProvider interp(lowering(c.model));
                si = run(c.model, interp, c.t_end);
                ti.push_back(1e3 * (cpu_seconds() - start));
                cfgs = interp.built();
                per_cfg.push_back(1e3 * interp.lower_seconds() / static_cast<double>(std::max<std::size_t>(cfgs, 1)));
            }
            {
                const double start = cpu_seconds();
                GenericSolverProvider gen(c.model);
                sg = run(c.model, gen, c.t_end);
                tg.push_back(1e3 * (cpu_seconds() - start));
            }
        }
        char sw[64];
        std::snprintf(sw, sizeof sw, "%zu/%zu", si.events, sg.events);
        const double mi = median(ti), mg = median(tg);
        std::printf("%-16s %7g %9s %6zu %10.3f %10.3f %11.2f %13.3f ms %14.3f %13.2f\n", c.name.c_str(), c.t_end, sw,
                    cfgs, mi, mg, mi / mg, median(per_cfg), median(tb), median(tb) / mg);
    }

    // 4. One configuration: the all-open chain of n masses (chain(n) above), derived
    //    and lowered (refined and Jacobi) against the Eigen solver's analysis.
    std::printf("\n4. One configuration, the all-open n-mass chain (8-64): derive (double-double) + lower, refined and former (Jacobi),\n"
                "   against building the Eigen solver (modal analysis in double); median of runs, thread CPU time\n");
    std::printf("%6s %12s %12s %12s %12s %12s %14s\n", "masses", "refined_ms", "of which lower", "jacobi_ms", "eigen_ms",
                "refined/eigen", "jacobi/refined");
    for (int nm : {8, 16, 32, 64}) {
        if (quick && nm > 32) continue;
        const Model m = parse_model(chain(nm), "chain-" + std::to_string(nm));
        const Configuration cfg = Configuration::all_open(m);
        std::vector<double> tr, tl, tj, te;
        const int k = nm <= 16 ? (quick ? 5 : 21) : (quick ? 3 : 7);
        for (int r = 0; r < k; ++r) {
            double start = cpu_seconds();
            const Derivation d = derive(m, cfg);
            const double mid = cpu_seconds();
            const Program p = lower(d);
            tr.push_back(1e3 * (cpu_seconds() - start));
            tl.push_back(1e3 * (cpu_seconds() - mid));
            sink = sink + static_cast<double>(p.constants.size());
            if (r < (nm >= 64 ? 1 : nm >= 32 ? 3 : k)) {  // Jacobi at 64 masses: seconds
                start = cpu_seconds();
                sink = sink + static_cast<double>(lower(derive(m, cfg, EigenMethod::jacobi)).constants.size());
                tj.push_back(1e3 * (cpu_seconds() - start));
            }
            start = cpu_seconds();
            GenericSolverProvider gen(m);
            gen.solver(cfg);
            te.push_back(1e3 * (cpu_seconds() - start));
        }
        std::printf("%6d %12.3f %14.3f %12.3f %12.3f %12.1f %14.0f\n", nm, median(tr), median(tl), median(tj), median(te),
                    median(tr) / median(te), median(tj) / median(tr));
    }

    // 5. A segment carried over a reversal (runtime/solvers/restart.h) against a
    //    setup from the state, in the all-open configuration of bench_common.h's
    //    friction chain: the interpreter, one mass's friction flipped each call.
    std::printf("\n5. One segment start in the all-open n-mass friction chain (bench_common.h friction_chain): the\n"
                "   interpreter's setup from the state against restart_coefficients at a reversal, then the search's\n"
                "   first evaluation at the start (eval_switches at tau = 0) against an eval at tau > 0, and a carried\n"
                "   segment's first evaluation (eval_start: the bounds and the flipped mass's velocity) (ns, median\n"
                "   of %d rounds of %d calls in turn)\n", rounds, burst);
    std::printf("%6s %6s %10s %11s %15s %14s %9s %16s\n", "masses", "modes", "setup_ns", "restart_ns", "restart/setup",
                "start_eval_ns", "eval_ns", "carried_start_ns");
    for (int nm : {16, 32, 64, 128}) {
        if (quick && nm > 32) continue;
        const Model m = parse_model(friction_chain(nm), "chain-" + std::to_string(nm));
        Program p = lower(derive(m, Configuration::all_open(m)), ProgramNames::no);
        const RestartPlan plan = p.restart;
        InterpretedSolver s(std::move(p));
        const std::size_t n = m.dof();
        std::vector<double> x(n, 0.01), v(n, 0.1);
        std::vector<signed char> up(n, 1), flipped(n, 1);
        flipped[n / 2] = -1;
        const std::size_t ns = s.switches().size();
        std::vector<double> xs(m.state_size()), vs(n), as(n), g(ns), dg(ns), bound(ns), scale(ns);
        const SegmentEval eval_out{xs.data(), vs.data(), as.data(), g.data(), dg.data(), bound.data(), scale.data()};
        std::vector<double> ts, tr, t0, te, tc;
        // A carried start evaluates the bounds and, among others, the flipped mass's velocity.
        std::uint32_t flipped_function = 0;
        for (std::size_t f = 0; f < ns; ++f)
            if (s.switches()[f].kind == SwitchKind::velocity && s.switches()[f].element == static_cast<int>(n / 2))
                flipped_function = static_cast<std::uint32_t>(f);
        for (int r = 0; r < rounds + 1; ++r) {
            double start = cpu_seconds();
            for (int e = 0; e < burst; ++e)
                s.setup(1.0 + 1e-7 * e, 0.0, x.data(), v.data(), (e & 1) ? up.data() : flipped.data());
            const double mid = cpu_seconds();
            for (int e = 0; e < burst; ++e)
                restart_coefficients(plan, s.coefficient_block(), 1e-3, 1.0 + 1e-7 * e, 0.0,
                                     (e & 1) ? up.data() : flipped.data(), (e & 1) ? flipped.data() : up.data());
            const double end = cpu_seconds();
            for (int e = 0; e < burst; ++e) s.eval_switches(0.0, eval_out), sink = sink + g[0];
            const double at_start = cpu_seconds();
            for (int e = 0; e < burst; ++e) s.eval(1e-3 + 1e-9 * e, eval_out), sink = sink + g[0];
            const double at_tau = cpu_seconds();
            for (int e = 0; e < burst; ++e) s.eval_start(0.0, &flipped_function, 1, eval_out), sink = sink + bound[0];
            const double carried = cpu_seconds();
            sink = sink + s.coefficient_block()[0];
            if (r > 0) {
                ts.push_back(1e9 * (mid - start) / burst), tr.push_back(1e9 * (end - mid) / burst);
                t0.push_back(1e9 * (at_start - end) / burst), te.push_back(1e9 * (at_tau - at_start) / burst);
                tc.push_back(1e9 * (carried - at_tau) / burst);
            }
        }
        std::printf("%6d %6zu %10.0f %11.0f %15.2f %14.0f %9.0f %16.0f\n", nm, plan.modes.size(), median(ts),
                    median(tr), median(tr) / median(ts), median(t0), median(te), median(tc));
    }
    return sink == 12345.678 ? 1 : 0;
}
