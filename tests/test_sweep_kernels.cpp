// Sweep kernels (generator/param_emitter.h): kernels whose chosen parameters
// are run-time arguments of configure(). Each is compiled in-process (JIT) and
// configured over a sweep of values; for every value it must give what the
// generic solver (and, for some values, the folded kernel) of the model read
// with that value (--set) gives, to rounding: across a damping regime
// boundary, through a resonance, over a stiffness range, with a parameter the
// model computes from the kept one. Also: byte-identical output, the
// provenance header, configure's refusals, and the CLI flag.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "derivation.h"
#include "emitter.h"
#include "error.h"
#include "generic_solver.h"
#include "jit.h"
#include "kernel_solver.h"
#include "model_reader.h"
#include "param_emitter.h"

namespace hsnc {
namespace {

using testing::model_path;

/// One compiled kernel (sweep or folded) of a configuration.
struct Compiled {
    std::unique_ptr<Jit> jit;
    const hsnc_kernel* kernel = nullptr;
};

Compiled compile(const std::string& source, const std::string& symbol) {
    Compiled c;
    c.jit = std::make_unique<Jit>();
    c.jit->add(symbol + ".cpp", source);
    c.kernel = static_cast<const hsnc_kernel*>(c.jit->lookup(symbol));
    return c;
}

Compiled sweep_kernel(const Model& model, const Configuration& cfg, const std::vector<std::string>& kept) {
    return compile(emit_sweep_kernel(derive(model, cfg), kept), sweep_kernel_symbol(model, cfg));
}

Compiled folded_kernel(const Model& model, const Configuration& cfg) {
    return compile(emit_kernel(derive(model, cfg)), kernel_symbol(model, cfg));
}

/// A segment start for `cfg`: the model's initial state, stuck masses at rest,
/// sliding friction masses moving in the direction of their velocity (+ at rest).
struct Start {
    double t0 = 0.37;
    std::vector<double> x0, v0;
    std::vector<signed char> sgn;
};

Start start_of(const Model& model, const Configuration& cfg) {
    Start s;
    s.x0 = model.x0;
    s.v0 = model.v0;
    for (std::size_t i = 0; i < model.dof(); ++i) {
        if (cfg.stuck[i]) s.v0[i] = 0.0;
        s.sgn.push_back(!model.has_friction(i) || cfg.stuck[i] ? 0 : (s.v0[i] < 0 ? -1 : 1));
    }
    return s;
}

/// Largest difference between a and b over the segment (x, v, a relative to the
/// largest |x|, |v|, |a| there; g, dg relative to the g's scale), at taus up to 3 s.
/// With `bounds`, bound and scale are compared too (same formulas: folded kernels).
double max_difference(SegmentSolver& a, SegmentSolver& b, const Start& s, std::size_t n, bool bounds) {
    a.setup(s.t0, s.x0.data(), s.v0.data(), s.sgn.data());
    b.setup(s.t0, s.x0.data(), s.v0.data(), s.sgn.data());
    const std::size_t ns = a.switches().size();
    EXPECT_EQ(b.switches().size(), ns);
    std::vector<double> xa(n), va(n), aa(n), ga(ns), dga(ns), ba(ns), sa(ns);
    std::vector<double> xb(n), vb(n), ab(n), gb(ns), dgb(ns), bb(ns), sb(ns);
    double worst = 0.0;
    for (double tau : {0.0, 1e-3, 0.05, 0.3, 1.0, 3.0}) {
        a.eval(tau, {xa.data(), va.data(), aa.data(), ga.data(), dga.data(), ba.data(), sa.data()});
        b.eval(tau, {xb.data(), vb.data(), ab.data(), gb.data(), dgb.data(), bb.data(), sb.data()});
        auto rel = [&](const std::vector<double>& p, const std::vector<double>& q) {
            double big = 0.0, diff = 0.0;
            for (std::size_t i = 0; i < p.size(); ++i) {
                big = std::max(big, std::abs(q[i]));
                diff = std::max(diff, std::abs(p[i] - q[i]));
            }
            return big == 0.0 ? diff : diff / big;
        };
        worst = std::max({worst, rel(xa, xb), rel(va, vb), rel(aa, ab)});
        for (std::size_t f = 0; f < ns; ++f) {
            const double sc = std::max(sb[f], 1e-300);
            worst = std::max(worst, std::abs(ga[f] - gb[f]) / sc);
            // g' against the scale of the rates: |g'| + the rate terms' own size.
            worst = std::max(worst, std::abs(dga[f] - dgb[f]) / (std::abs(dgb[f]) + sc));
            if (bounds) {
                worst = std::max(worst, std::abs(ba[f] - bb[f]) / std::max(bb[f], 1e-300));
                worst = std::max(worst, std::abs(sa[f] - sb[f]) / sc);
            }
        }
    }
    return worst;
}

/// bound[f] >= |g_f''(s)| over [tau, tau + 1]: g'' from central differences of g'
/// at 50 points, against the bound given at tau.
void expect_bound_holds(SegmentSolver& k, const Start& s, std::size_t n) {
    k.setup(s.t0, s.x0.data(), s.v0.data(), s.sgn.data());
    const std::size_t ns = k.switches().size();
    std::vector<double> x(n), v(n), a(n), g(ns), dg(ns), b(ns), sc(ns), b0(ns), dp(ns), dm(ns);
    const SegmentEval out{x.data(), v.data(), a.data(), g.data(), dg.data(), b.data(), sc.data()};
    for (double tau : {0.0, 0.7, 2.5}) {
        k.eval(tau, out);
        b0 = b;
        for (int i = 1; i <= 50; ++i) {
            const double t = tau + 0.02 * i, h = 1e-5;
            k.eval(t + h, out);
            dp = dg;
            k.eval(t - h, out);
            dm = dg;
            for (std::size_t f = 0; f < ns; ++f) {
                const double g2 = (dp[f] - dm[f]) / (2 * h);
                EXPECT_LE(std::abs(g2), b0[f] * (1 + 1e-6) + 1e-6 * sc[f]) << "f = " << f << " tau = " << tau << " t = " << t;
            }
        }
    }
}

std::string set_flag(const std::string& name, double value) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", value);
    return name + "=" + buf;
}

// Sweep one parameter of a model over `values` in configuration `spec`.
// Returns the regimes the generic solver reported (to show the sweep crossed them).
void sweep(const std::string& file, const std::string& spec, const std::string& param,
           const std::vector<double>& values, double tol, std::vector<int>* regimes = nullptr) {
    const Model model = read_model(model_path(file));
    const Configuration cfg = Configuration::parse(model, spec);
    const Compiled sk = sweep_kernel(model, cfg, {param});
    ASSERT_EQ(sk.kernel->n_param, 1);
    EXPECT_STREQ(sk.kernel->param_names[0], param.c_str());
    KernelSolver solver(*sk.kernel, {values.front()});
    for (double value : values) {
        SCOPED_TRACE(file + " " + spec + " " + set_flag(param, value));
        ModelOverrides o;
        o.set = {set_flag(param, value)};
        const Model mv = read_model(model_path(file), o);
        solver.configure({value});
        GenericSolver generic(mv, cfg);
        const Start s = start_of(mv, cfg);
        EXPECT_LE(max_difference(solver, generic, s, mv.dof(), false), tol);
        expect_bound_holds(solver, s, mv.dof());
        if (regimes)
            for (int j = 0; j < static_cast<int>(generic.modes().lambda.size()); ++j)
                regimes->push_back(static_cast<int>(generic.regime(j)));
    }
}

TEST(SweepKernel, StiffnessSweepMatchesGenericSolver) {
    // k1 (m1 to ground) over three decades, contact closed, and with one mass stuck
    // (the open configuration is swept in the damping test).
    const std::vector<double> k1 = {0.5, 2.0, 5.0, 20.0, 80.0, 500.0};
    sweep("seed-scenario-1.toml", "closed=contact1", "k1", k1, 1e-12);
    sweep("seed-scenario-1.toml", "stuck=m2", "k1", k1, 1e-12);
}

TEST(SweepKernel, DampingSweepAcrossCriticalMatchesGenericSolver) {
    // Open contact, both masses free: omega = 3.367 and 5.354 rad/s, c = beta lambda,
    // critical at beta = 2/omega = 0.594 and 0.374. The sweep goes from undamped
    // through both critical points (and within 1e-9 of them) to overdamped.
    const Model model = read_model(model_path("seed-scenario-1.toml"));
    const GenericSolver g0(model, Configuration::parse(model, ""));
    const double w1 = std::sqrt(g0.modes().lambda(0)), w2 = std::sqrt(g0.modes().lambda(1));
    const std::vector<double> beta = {0.0,  0.05, 2.0 / w2 * (1 - 1e-9), 2.0 / w2, 2.0 / w2 * (1 + 1e-9), 0.45,
                                      2.0 / w1 * (1 - 1e-7), 2.0 / w1 * (1 + 1e-7), 1.0, 3.0};
    std::vector<int> regimes;
    sweep("seed-scenario-1.toml", "", "beta", beta, 1e-12, &regimes);
    using R = GenericSolver::Regime;
    for (R r : {R::underdamped, R::overdamped})
        EXPECT_NE(std::find(regimes.begin(), regimes.end(), static_cast<int>(r)), regimes.end());
    // The contact-closed configuration too (damping also through the contact).
    sweep("seed-scenario-1.toml", "closed=contact1", "beta", {0.0, 0.02, 0.3, 2.0}, 1e-12);
}

TEST(SweepKernel, ForcingFrequencyThroughResonanceMatchesGenericSolver) {
    // Scenario 2 is undamped: Omega swept through the second natural frequency
    // (the kernel switches to the resonance-stable form within 1%, and at
    // Omega = omega exactly has a secular term and a finite max_step).
    const Model model = read_model(model_path("seed-scenario-2.toml"));
    const GenericSolver g0(model, Configuration::parse(model, ""));
    const double w2 = std::sqrt(g0.modes().lambda(1));
    sweep("seed-scenario-2.toml", "", "omega", {0.5 * w2, 0.985 * w2, 0.999 * w2, w2, 1.002 * w2, 17.5515}, 1e-12);
    const Compiled sk = sweep_kernel(model, Configuration::parse(model, ""), {"omega"});
    KernelSolver at(*sk.kernel, {w2});
    EXPECT_NEAR(at.max_step(), 2 * M_PI / w2, 1e-12);
    KernelSolver off(*sk.kernel, {0.5 * w2});
    EXPECT_TRUE(std::isinf(off.max_step()));
}

TEST(SweepKernel, MatchesFoldedKernelIncludingBounds) {
    // Against the folded kernel of the model read with the same value: the same
    // formulas, so bound and scale agree too.
    const Model model = read_model(model_path("seed-scenario-1.toml"));
    for (const char* spec : {"closed=contact1", "stuck=m1"}) {
        const Configuration cfg = Configuration::parse(model, spec);
        const Compiled sk = sweep_kernel(model, cfg, {"k1", "beta"});
        for (const auto& [k1, beta] : std::vector<std::pair<double, double>>{{5.0, 0.1}, {30.0, 0.9}}) {
            SCOPED_TRACE(std::string(spec) + " k1 = " + std::to_string(k1) + " beta = " + std::to_string(beta));
            ModelOverrides o;
            o.set = {set_flag("k1", k1), set_flag("beta", beta)};
            const Model mv = read_model(model_path("seed-scenario-1.toml"), o);
            const Compiled fk = folded_kernel(mv, cfg);
            KernelSolver sweep_solver(*sk.kernel, {k1, beta}), folded(*fk.kernel);
            EXPECT_LE(max_difference(sweep_solver, folded, start_of(mv, cfg), mv.dof(), true), 1e-12);
        }
    }
}

TEST(SweepKernel, HonoursTheModelsParameterExpressions) {
    // k2 = 2*k1 and mu_s = 1.25*mu_k in the file; mass m2 = 2*m; a ground stop.
    const std::string toml = R"toml(name = "derived"
[parameters]
m = 1.5
k1 = 40
k2 = "2*k1"
mu = 0.3
w = "sqrt(k1/m)"
[[mass]]
name = "a"
m = "m"
mu_k = "mu"
mu_s = "1.25*mu"
[[mass]]
name = "b"
m = "2*m"
[[spring]]
between = ["ground", "a"]
k = "k1"
[[spring]]
between = ["a", "b"]
k = "k2"
[[contact]]
name = "stop"
between = ["b", "ground"]
gap = 0.05
k = "10*k1"
[damping]
beta = 0.002
[[forcing]]
omega = "1.3*w"
amplitude = { a = 20 }
[initial]
x = { a = 0.1, b = -0.02 }
v = { a = 0.4 }
)toml";
    const Model model = parse_model(toml, "derived.toml");
    for (const char* spec : {"", "closed=stop"}) {
        const Configuration cfg = Configuration::parse(model, spec);
        const std::string source = emit_sweep_kernel(derive(model, cfg), {"m", "k1", "mu"});
        EXPECT_NE(source.find("parameters computed from them: k2 = 2*k1, w = sqrt(k1/m)"), std::string::npos);
        const Compiled sk = compile(source, sweep_kernel_symbol(model, cfg));
        KernelSolver solver(*sk.kernel, {1.5, 40.0, 0.3});
        for (const auto& v : std::vector<std::vector<double>>{{1.5, 40.0, 0.3}, {0.7, 95.0, 0.5}, {4.0, 12.0, 0.0}}) {
            SCOPED_TRACE(std::string(spec) + " m = " + std::to_string(v[0]) + " k1 = " + std::to_string(v[1]));
            ModelOverrides o;
            o.set = {set_flag("m", v[0]), set_flag("k1", v[1]), set_flag("mu", v[2])};
            const Model mv = parse_model(toml, "derived.toml", o);
            solver.configure(v);
            GenericSolver generic(mv, cfg);
            EXPECT_LE(max_difference(solver, generic, start_of(mv, cfg), mv.dof(), false), 1e-12);
        }
    }
}

TEST(SweepKernel, RigidBodyModeUndampedAndDamped) {
    // Two masses joined by a spring, a stop to ground that is open: a floating
    // pair (one rigid-body mode). alpha = 0 gives the rigid form, alpha > 0 the
    // damped rigid form; the stop closed anchors the pair (no rigid mode). At
    // alpha = 1e-6 the folded kernels' former split (p/c) tau + (q'(0) - p/c) eS
    // lost 5.9e-10 (measured); both kernels now write p tau^2 phi2(-c tau).
    const std::string toml = R"toml(name = "float-pair"
[parameters]
alpha = 0.3
k = 8
F = 0.8
[[mass]]
name = "m1"
m = 1.5
mu_k = 0.2
mu_s = 0.3
[[mass]]
name = "m2"
m = 0.5
[[spring]]
between = ["m1", "m2"]
k = "k"
[[contact]]
name = "stop"
between = ["m2", "ground"]
gap = 0.5
k = 50
[damping]
alpha = "alpha"
beta = 0.01
[[forcing]]
omega = 1.3
phase = 0.2
amplitude = { m2 = "F" }
[load]
m1 = 0.1
m2 = -0.2
[initial]
x = { m2 = 0.3 }
v = { m1 = 0.4, m2 = -0.1 }
)toml";
    const Model model = parse_model(toml, "float-pair.toml");
    for (const char* spec : {"", "closed=stop", "stuck=m1"}) {
        const Configuration cfg = Configuration::parse(model, spec);
        const Compiled sk = compile(emit_sweep_kernel(derive(model, cfg), {"alpha", "k"}), sweep_kernel_symbol(model, cfg));
        KernelSolver solver(*sk.kernel, {0.3, 8.0});
        for (const auto& v : std::vector<std::vector<double>>{{0.0, 8.0}, {0.3, 8.0}, {2.0, 0.5}, {1e-6, 30.0}}) {
            SCOPED_TRACE(std::string(spec) + " alpha = " + std::to_string(v[0]) + " k = " + std::to_string(v[1]));
            ModelOverrides o;
            o.set = {set_flag("alpha", v[0]), set_flag("k", v[1])};
            const Model mv = parse_model(toml, "float-pair.toml", o);
            solver.configure(v);
            GenericSolver generic(mv, cfg);
            EXPECT_LE(max_difference(solver, generic, start_of(mv, cfg), mv.dof(), false), 1e-12);
            expect_bound_holds(solver, start_of(mv, cfg), mv.dof());
            // The folded kernel of the same values: the same rigid-body form.
            const Compiled fk = folded_kernel(mv, cfg);
            KernelSolver folded(*fk.kernel);
            EXPECT_LE(max_difference(folded, generic, start_of(mv, cfg), mv.dof(), false), 1e-12);
        }
    }
}

TEST(SweepKernel, ConfigureRefusesInvalidAndStructureChangingValues) {
    const Model model = read_model(model_path("seed-scenario-1.toml"));
    const Compiled sk = sweep_kernel(model, Configuration::parse(model, ""), {"k1", "m2", "beta"});
    KernelSolver solver(*sk.kernel, {5.0, 2.0, 0.1});
    auto refused = [&](const std::vector<double>& v, const std::string& why) {
        try {
            solver.configure(v);
            ADD_FAILURE() << "configure accepted " << v[0] << ", " << v[1] << ", " << v[2];
        } catch (const RunError& e) {
            EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
        }
    };
    refused({5.0, -1.0, 0.1}, "not a valid model");    // m2 <= 0
    refused({-5.0, 2.0, 0.1}, "not a valid model");    // k1 < 0
    refused({5.0, 2.0, -0.1}, "not a valid model");    // beta < 0
    refused({5.0, NAN, 0.1}, "not a valid model");
    refused({0.0, 2.0, 0.1}, "changes the rigid-body modes");  // k1 > 0 at generation
    const double x0[2] = {0, 0}, v0[2] = {0, 0};
    const signed char sgn[2] = {1, 1};
    EXPECT_THROW(solver.setup(0.0, x0, v0, sgn), RunError);  // not configured after a refusal
    EXPECT_THROW(solver.configure({1.0}), RunError);           // wrong count
    solver.configure({5.0, 2.0, 0.1});
    EXPECT_NO_THROW(solver.setup(0.0, x0, v0, sgn));
}

TEST(SweepKernel, OutputIsDeterministicAndSaysWhatItKeeps) {
    const Model model = read_model(model_path("seed-scenario-2.toml"));
    const Configuration cfg = Configuration::parse(model, "closed=contact1 stuck=m2");
    const std::string a = emit_sweep_kernel(derive(model, cfg), kept_parameters(model, "omega,k_star"));
    const std::string b = emit_sweep_kernel(derive(model, cfg), kept_parameters(model, "omega,k_star"));
    EXPECT_EQ(a, b);
    EXPECT_NE(a.find("// parameters given to configure(), in this order: omega, k_star\n"), std::string::npos);
    EXPECT_NE(a.find("// model:         seed-scenario-2 (hash 0x"), std::string::npos);
    EXPECT_NE(a.find("// configuration: closed=contact1 stuck=m2 (key c1_s01)"), std::string::npos);
    EXPECT_EQ(a.find("/work"), std::string::npos);
    EXPECT_EQ(a.find("#include <"), std::string::npos);
    EXPECT_EQ(kept_parameters(model, "all").size(), model.parameter_expressions.size());
    EXPECT_THROW(kept_parameters(model, "k1,nope"), InputError);
    EXPECT_THROW(kept_parameters(model, "k1,k1"), InputError);
    EXPECT_THROW(kept_parameters(model, "k1,"), InputError);
}

TEST(SweepKernel, GenerateFlagWritesSweepKernelsTwiceTheSame) {
    const std::string d1 = testing::temp_path("sweep1"), d2 = testing::temp_path("sweep2");
    for (const std::string& d : {d1, d2}) {
        const auto r = testing::run_hsnc("generate '" + model_path("coulomb-1dof.toml") + "' -o '" + d + "' --params all");
        ASSERT_EQ(r.exit_code, 0) << r.err;
        EXPECT_NE(r.out.find("sweep kernels"), std::string::npos) << r.out;
    }
    const std::string m1 = testing::slurp(d1 + "/coulomb-1dof.manifest");
    EXPECT_NE(m1.find("# sweep kernels: parameters given at run time (configure): "), std::string::npos) << m1;
    EXPECT_EQ(m1, testing::slurp(d2 + "/coulomb-1dof.manifest"));
    EXPECT_EQ(testing::slurp(d1 + "/registry.cpp"), testing::slurp(d2 + "/registry.cpp"));
    for (const char* kernel : {"/coulomb_1dof_c_s0.cpp", "/coulomb_1dof_c_s1.cpp"}) {
        const std::string k1 = testing::slurp(d1 + kernel);
        EXPECT_NE(k1.find("// parameters given to configure(), in this order: g, m, k, mu\n"), std::string::npos) << kernel;
        EXPECT_EQ(k1, testing::slurp(d2 + kernel)) << kernel;
    }
    const std::string bad = testing::temp_path("sweep_bad");
    const auto r = testing::run_hsnc("generate '" + model_path("coulomb-1dof.toml") + "' -o '" + bad + "' --params zzz");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("--params"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("unknown parameter 'zzz'"), std::string::npos) << r.err;
    EXPECT_FALSE(testing::file_exists(bad + "/registry.cpp"));
}

}  // namespace
}  // namespace hsnc
