// Tests of the derivation and the emitted kernels. The kernels of
// generator/sample_models.h are emitted and compiled at build time
// (hsnc_gen --samples); here they are checked against
//  - the textbook closed forms built by GiNaC (symbolic_segment), evaluated
//    at 40 digits, derivatives by GiNaC diff;
//  - the equation of motion assembled independently (model/assembly.h);
//  - the initial state; continuity through xi = 1 and Omega = omega;
//  - the bound on |g''| sampled over [tau, tau + step].
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "aot_registry.h"
#include "assembly.h"
#include "derivation.h"
#include "emitter.h"
#include "generic_solver.h"
#include "kernel_set.h"
#include "model_reader.h"
#include "kernel_solver.h"
#include "model_hash.h"
#include "sample_models.h"
#include "state_space_solver.h"

namespace hsnc {
const AotRegistry& sample_registry();  // tests' build-time kernels (hsnc_gen --samples)

namespace {

using GiNaC::ex;
using GiNaC::numeric;

const hsnc_kernel& sample_kernel(const Model& m, const Configuration& cfg) {
    const hsnc_kernel* k = find_aot_kernel(sample_registry(), m.name.c_str(), model_hash(m), cfg.key().c_str());
    if (!k) throw std::runtime_error("no sample kernel for " + m.name + " " + cfg.key());
    return *k;
}

// A legal segment start for cfg: stuck masses at rest, sliding friction masses
// moving in the direction sgn (taken from v0, or +1 when v0 = 0); x0 holds
// the masses, then each Jenkins slider, set a third of the slip force's
// stretch away from unstretched (what the setup of a slipping element ignores).
struct Start {
    double t0;
    std::vector<double> x0, v0;
    std::vector<signed char> sgn;
};
Start start_of(const Model& m, const Configuration& cfg) {
    Start s{m.t0 + 0.37, m.x0, m.v0, std::vector<signed char>(m.dof(), 0)};
    for (std::size_t i = 0; i < m.dof(); ++i) {
        const int p = m.friction_slot(i).partner;  // friction against the ground or a partner (no friction of its own)
        const double vp = p == kGround ? 0.0 : s.v0[static_cast<std::size_t>(p)];
        if (cfg.stuck[i]) {
            s.v0[i] = vp;
        } else if (m.has_friction(i)) {
            s.sgn[i] = s.v0[i] < vp ? -1 : 1;
        }
    }
    for (const Jenkins& e : m.jenkins) {
        auto pos = [&](int b) { return b == kGround ? 0.0 : m.x0[static_cast<std::size_t>(b)]; };
        s.x0.push_back(pos(e.a) - pos(e.b) - e.slip_force / (3 * e.k));
    }
    return s;
}

SegmentInputs inputs_of(const Start& s) {
    SegmentInputs in;
    in.t0 = exact(s.t0);
    for (double x : s.x0) in.x0.push_back(exact(x));  // masses, then sliders
    for (std::size_t i = 0; i < s.v0.size(); ++i) {
        in.v0.push_back(exact(s.v0[i]));
        in.sgn.push_back(static_cast<int>(s.sgn[i]));
    }
    return in;
}

double eval40(const ex& e, const GiNaC::symbol& tau, double t) {
    return GiNaC::ex_to<numeric>(e.subs(tau == exact(t)).evalf()).to_double();
}

struct KernelOut {
    std::vector<double> x, v, a, g, dg, bound, scale;  // x: masses, then sliders
    KernelOut(std::size_t n, std::size_t nf, std::size_t nj)
        : x(n + nj), v(n), a(n), g(nf), dg(nf), bound(nf), scale(nf) {}
    SegmentEval view() { return {x.data(), v.data(), a.data(), g.data(), dg.data(), bound.data(), scale.data()}; }
};

KernelOut run(KernelSolver& k, std::size_t n, double tau, std::size_t nj = 0) {
    KernelOut o(n, k.switches().size(), nj);
    k.eval(tau, o.view());
    return o;
}
KernelOut run(KernelSolver& k, const Model& m, double tau) { return run(k, m.dof(), tau, m.jenkins.size()); }

const std::vector<double> kTaus = {0.0, 1e-3, 0.05, 0.4, 1.3, 3.0};

TEST(Derivation, SampleCatalogueCoversEveryRegime) {
    std::set<Regime> seen;
    bool resonant = false;
    for (const Model& m : sample_models())
        for (const Configuration& cfg : all_configurations(m)) {
            const Derivation d = derive(m, cfg);
            for (const Mode& mode : d.modes) seen.insert(mode.regime);
            for (const HarmonicData& h : d.harmonics)
                for (const ModalHarmonic& mh : h.modal) resonant = resonant || mh.resonant;
        }
    EXPECT_EQ(seen.size(), 6u);
    EXPECT_TRUE(resonant);
}

TEST(Derivation, ModesDiagonaliseTheReducedSystem) {
    // V^T K V = diag(lambda), V^T M V = I, at the working precision (the modes
    // of Rayleigh damping; the state-space pseudo-modes of dampers are checked
    // through their eigenpairs, tests/test_mp_complex_eigen.cpp).
    for (const Model& m : sample_models()) {
        if (!m.proportional_damping()) continue;
        const Configuration cfg = all_configurations(m).back();
        const Derivation d = derive(m, cfg);
        // Each coordinate's masses: its free mass and the riders stuck to it (T^T M T, T^T K T).
        auto folded_k = [&](std::size_t r, std::size_t s) {
            DD k = 0;
            for (std::size_t i = 0; i < m.dof(); ++i)
                for (std::size_t q = 0; q < m.dof(); ++q)
                    if (d.coordinate(static_cast<int>(i)) == static_cast<int>(r) &&
                        d.coordinate(static_cast<int>(q)) == static_cast<int>(s))
                        k += to_dd(GiNaC::ex_to<numeric>(d.K(i, q)));
            return k;
        };
        for (std::size_t j = 0; j < d.modes.size(); ++j)
            for (std::size_t l = 0; l < d.modes.size(); ++l) {
                DD kjl = 0, mjl = 0;
                for (std::size_t r = 0; r < d.n_free(); ++r) {
                    DD mr = 0;
                    for (std::size_t i = 0; i < m.dof(); ++i)
                        if (d.coordinate(static_cast<int>(i)) == static_cast<int>(r)) mr += DD(m.masses[i].m);
                    mjl += d.modes[j].v[r] * mr * d.modes[l].v[r];
                    for (std::size_t s = 0; s < d.n_free(); ++s) kjl += d.modes[j].v[r] * folded_k(r, s) * d.modes[l].v[s];
                }
                EXPECT_NEAR(mjl.to_double(), j == l ? 1.0 : 0.0, 1e-30) << m.name;
                EXPECT_NEAR(kjl.to_double(), j == l ? d.modes[j].lambda.to_double() : 0.0, 1e-28) << m.name;
            }
    }
}

TEST(Kernel, MatchesGiNaCClosedFormAt40Digits) {
    GiNaC::symbol tau("tau");
    int checked = 0;
    for (const Model& m : sample_models())
        for (const Configuration& cfg : all_configurations(m)) {
            const Derivation d = derive(m, cfg);
            const Start st = start_of(m, cfg);
            const SymbolicSegment sym = symbolic_segment(d, inputs_of(st), tau);
            KernelSolver k(sample_kernel(m, cfg));
            ASSERT_EQ(k.switches(), d.switches);
            k.setup(st.t0, st.x0.data(), st.v0.data(), st.sgn.data());
            // Reference magnitudes over the samples, for relative comparisons.
            std::vector<std::vector<double>> X, Vv, A;
            double xmax = 1e-300, vmax = 1e-300, amax = 1e-300;
            for (double t : kTaus) {
                std::vector<double> x, v, a;
                for (std::size_t i = 0; i < m.dof(); ++i) {
                    x.push_back(eval40(sym.x[i], tau, t));
                    v.push_back(eval40(sym.v[i], tau, t));
                    a.push_back(eval40(sym.a[i], tau, t));
                    xmax = std::max(xmax, std::fabs(x.back()));
                    vmax = std::max(vmax, std::fabs(v.back()));
                    amax = std::max(amax, std::fabs(a.back()));
                }
                X.push_back(x);
                Vv.push_back(v);
                A.push_back(a);
            }
            for (std::size_t s = 0; s < kTaus.size(); ++s) {
                const double t = kTaus[s];
                KernelOut o = run(k, m, t);
                const std::string where = m.name + " " + cfg.key() + " tau=" + std::to_string(t);
                for (std::size_t i = 0; i < m.dof(); ++i) {
                    EXPECT_NEAR(o.x[i], X[s][i], 1e-12 * xmax) << where << " x" << i;
                    EXPECT_NEAR(o.v[i], Vv[s][i], 1e-12 * vmax) << where << " v" << i;
                    EXPECT_NEAR(o.a[i], A[s][i], 1e-12 * amax) << where << " a" << i;
                }
                for (std::size_t j = 0; j < m.jenkins.size(); ++j)
                    EXPECT_NEAR(o.x[m.dof() + j], eval40(sym.x[m.dof() + j], tau, t), 1e-12 * (xmax + 1.0))
                        << where << " slider " << j;
                for (std::size_t f = 0; f < d.switches.size(); ++f) {
                    EXPECT_NEAR(o.g[f], eval40(sym.g[f], tau, t), 1e-13 * o.scale[f]) << where << " g" << f;
                    const double dg = eval40(sym.dg[f], tau, t);
                    EXPECT_NEAR(o.dg[f], dg, 1e-12 * (std::fabs(dg) + o.scale[f] * (1 + vmax / (xmax + vmax))))
                        << where << " dg" << f;
                }
                ++checked;
            }
        }
    EXPECT_GT(checked, 500);
}

TEST(Kernel, InitialStateIsReproduced) {
    for (const Model& m : sample_models())
        for (const Configuration& cfg : all_configurations(m)) {
            const Start st = start_of(m, cfg);
            KernelSolver k(sample_kernel(m, cfg));
            k.setup(st.t0, st.x0.data(), st.v0.data(), st.sgn.data());
            const KernelOut o = run(k, m, 0.0);
            for (std::size_t j = 0; j < m.jenkins.size(); ++j)
                if (cfg.slip[j] == 0) EXPECT_EQ(o.x[m.dof() + j], st.x0[m.dof() + j]) << m.name << cfg.key();
            for (std::size_t i = 0; i < m.dof(); ++i) {
                EXPECT_NEAR(o.x[i], st.x0[i], 1e-13 * (1 + std::fabs(st.x0[i])) * 1e2) << m.name << cfg.key();
                EXPECT_NEAR(o.v[i], st.v0[i], 1e-13 * (1 + std::fabs(st.v0[i])) * 1e2) << m.name << cfg.key();
            }
        }
}

TEST(Kernel, SatisfiesTheEquationOfMotion) {
    // M a + C v + K x = loads + preload + forcing - friction for free masses,
    // assembled by model/assembly.h (independent of the derivation).
    for (const Model& m : sample_models())
        for (const Configuration& cfg : all_configurations(m)) {
            const Start st = start_of(m, cfg);
            KernelSolver k(sample_kernel(m, cfg));
            k.setup(st.t0, st.x0.data(), st.v0.data(), st.sgn.data());
            const Eigen::MatrixXd K = stiffness_matrix(m, cfg), C = damping_matrix(m, cfg);
            const Eigen::VectorXd M = mass_vector(m);
            Eigen::VectorXd f0 = constant_force(m, cfg);
            add_slider_preload(m, cfg, st.x0.data() + m.dof(), f0);  // k s of the stuck Jenkins elements
            for (int s = 0; s <= 40; ++s) {
                const double t = 0.1 * s;
                const KernelOut o = run(k, m, t);
                for (std::size_t j = 0; j < m.jenkins.size(); ++j)  // the slider: fixed, or the stretch held
                    EXPECT_NEAR(o.x[m.dof() + j], slider_position(m, cfg, j, o.x.data()), 1e-15)
                        << m.name << " " << cfg.key() << " slider " << j;
                const Eigen::Map<const Eigen::VectorXd> x(o.x.data(), m.dof()), v(o.v.data(), m.dof()),
                    a(o.a.data(), m.dof());
                const Eigen::VectorXd F = forcing(m, st.t0 + t);
                // Kinetic friction: -mu_k N sgn on a sliding mass, the opposite on its partner.
                Eigen::VectorXd friction = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(m.dof()));
                for (std::size_t i = 0; i < m.dof(); ++i)
                    if (m.has_friction(i) && !cfg.stuck[i]) {
                        const double fk = m.friction_slot(i).mu_k * m.normal_force(i) * st.sgn[i];
                        friction(static_cast<Eigen::Index>(i)) += fk;
                        if (m.friction_slot(i).partner != kGround) friction(m.friction_slot(i).partner) -= fk;
                    }
                Eigen::VectorXd res(static_cast<Eigen::Index>(m.dof())), size(res.size());
                for (std::size_t i = 0; i < m.dof(); ++i) {
                    const double lhs = M(i) * a(i) + C.row(i).dot(v) + K.row(i).dot(x);
                    res(i) = lhs - (f0(i) + F(i) - friction(i));
                    size(i) = std::fabs(M(i) * a(i)) + (C.row(i).cwiseAbs()).dot(v.cwiseAbs()) +
                              (K.row(i).cwiseAbs()).dot(x.cwiseAbs()) + std::fabs(f0(i)) + std::fabs(F(i)) +
                              std::fabs(friction(i));
                }
                for (std::size_t i = 0; i < m.dof(); ++i) {
                    if (fixed_in(m, cfg, i)) {
                        EXPECT_EQ(o.x[i], st.x0[i]);
                        EXPECT_EQ(o.v[i], 0.0);
                        continue;
                    }
                    const int p = m.friction_slot(i).partner;
                    if (rides_partner(m, cfg, i)) {  // moves with its partner; the pair's equation below
                        EXPECT_NEAR(o.x[i] - o.x[p], st.x0[i] - st.x0[p], 1e-15 * (1 + std::fabs(o.x[i])));
                        EXPECT_EQ(o.v[i], o.v[p]);
                        EXPECT_EQ(o.a[i], o.a[p]);
                        continue;
                    }
                    double r = res(i), sz = size(i);  // with its riders: the stuck pair is one body
                    for (std::size_t q = 0; q < m.dof(); ++q)
                        if (rides_partner(m, cfg, q) && m.friction_slot(q).partner == static_cast<int>(i))
                            r += res(q), sz += size(q);
                    EXPECT_NEAR(r, 0.0, 1e-12 * sz) << m.name << " " << cfg.key() << " tau=" << t << " mass " << i;
                }
            }
        }
}

TEST(Kernel, BoundHoldsOverTheStep) {
    // bound[f] >= |g_f''(s)| for s in [tau, tau + step]; step = max_step or 2.
    GiNaC::symbol tau("tau");
    for (const Model& m : sample_models())
        for (const Configuration& cfg : all_configurations(m)) {
            const Derivation d = derive(m, cfg);
            const Start st = start_of(m, cfg);
            const SymbolicSegment sym = symbolic_segment(d, inputs_of(st), tau);
            KernelSolver k(sample_kernel(m, cfg));
            k.setup(st.t0, st.x0.data(), st.v0.data(), st.sgn.data());
            const double step = std::min(k.max_step(), 2.0);
            for (double t0 : {0.0, 0.7}) {
                const KernelOut o = run(k, m, t0);
                for (std::size_t f = 0; f < d.switches.size(); ++f) {
                    const ex g2 = sym.dg[f].diff(tau);
                    for (int s = 0; s <= 16; ++s) {
                        const double t = t0 + step * s / 16;
                        EXPECT_LE(std::fabs(eval40(g2, tau, t)), o.bound[f] * (1 + 1e-12))
                            << m.name << " " << cfg.key() << " g" << f << " at " << t;
                    }
                }
            }
        }
}

// Same start state in two models differing only by a parameter close to a
// regime boundary: the responses must agree to the size of the change.
void expect_close_models(const std::string& a, const std::string& b, double rel) {
    const auto models = sample_models();
    const auto find = [&](const std::string& name) {
        return *std::find_if(models.begin(), models.end(), [&](const Model& m) { return m.name == name; });
    };
    const Model ma = find(a), mb = find(b);
    const Configuration cfg = Configuration::all_open(ma);
    const Start st = start_of(ma, cfg);
    KernelSolver ka(sample_kernel(ma, cfg)), kb(sample_kernel(mb, cfg));
    ka.setup(st.t0, st.x0.data(), st.v0.data(), st.sgn.data());
    kb.setup(st.t0, st.x0.data(), st.v0.data(), st.sgn.data());
    for (double t : {0.0, 0.1, 0.5, 1.0, 2.5, 6.0, 20.0}) {
        const KernelOut oa = run(ka, 1, t), ob = run(kb, 1, t);
        EXPECT_NEAR(oa.x[0], ob.x[0], rel * (1 + std::fabs(oa.x[0]))) << a << " vs " << b << " tau=" << t;
        EXPECT_NEAR(oa.v[0], ob.v[0], rel * (1 + std::fabs(oa.v[0]))) << a << " vs " << b << " tau=" << t;
        EXPECT_NEAR(oa.a[0], ob.a[0], rel * (1 + std::fabs(oa.a[0]))) << a << " vs " << b << " tau=" << t;
    }
}

TEST(Kernel, ContinuousThroughCriticalDamping) {
    expect_close_models("osc_crit_below", "osc_critical", 1e-8);
    expect_close_models("osc_crit_above", "osc_critical", 1e-8);
}

TEST(Kernel, ContinuousThroughResonance) {
    // Omega = omega (1 + 1e-9): secular growth over tau <= 20 changes x by ~1e-8 relative.
    expect_close_models("res_near", "res_exact", 1e-7);
}

TEST(Kernel, ResonanceGrowsSecularly) {
    // Undamped resonance from rest at the static offset: amplitude P tau/(2 omega).
    const auto models = sample_models();
    const Model m = *std::find_if(models.begin(), models.end(), [](const Model& x) { return x.name == "res_exact"; });
    const Configuration cfg = Configuration::all_open(m);
    KernelSolver k(sample_kernel(m, cfg));
    const double xst = m.load[0] / 4.0;  // p / lambda with k = 4, m = 1
    const double x0[] = {xst}, v0[] = {0.0};
    const signed char sgn[] = {0};
    k.setup(0.0, x0, v0, sgn);  // phase 0.4
    // Closed form: x - xst = P/(2 w^2) sin(w t) cos(0.4) - P t cos(w t + 0.4)/(2 w), P = 0.7, w = 2.
    for (double t : {1.0, 10.0, 100.0}) {
        const KernelOut o = run(k, 1, t);
        const double expected = 0.7 / 8.0 * std::sin(2 * t) * std::cos(0.4) - 0.7 * t * std::cos(2 * t + 0.4) / 4.0;
        EXPECT_NEAR(o.x[0] - xst, expected, 1e-12 * (1 + t));
    }
}

// The segment start is the double-double t0 + t0_lo (the engine keeps event
// instants so): the forcing phase must be taken there, in the kernels and in
// the generic solver alike. Starting at (1.0, 0.25) is starting at 1.25.
TEST(Kernel, ForcingPhaseIsTakenAtT0PlusT0Lo) {
    const Model m = read_model(std::string(HSNC_SOURCE_DIR) + "/models/seed-scenario-1.toml");
    const Configuration cfg = Configuration::all_open(m);
    const hsnc_kernel* kp = find_aot_kernel(aot_registry(), m.name.c_str(), model_hash(m), cfg.key().c_str());
    ASSERT_NE(kp, nullptr);
    KernelSolver ka(*kp), kb(*kp), kc(*kp);
    GenericSolver ga(m, cfg), gb(m, cfg);
    const Start st = start_of(m, cfg);
    const double* x0 = st.x0.data();
    const double* v0 = st.v0.data();
    const signed char* sgn = st.sgn.data();
    ka.setup(1.0, 0.25, x0, v0, sgn);
    kb.setup(1.25, 0.0, x0, v0, sgn);
    kc.setup(1.0, 0.0, x0, v0, sgn);  // t0_lo ignored: a different segment
    ga.setup(1.0, 0.25, x0, v0, sgn);
    gb.setup(1.25, x0, v0, sgn);
    const std::size_t n = m.dof();
    for (double tau : {1e-3, 0.01, 0.05}) {
        const KernelOut a = run(ka, n, tau), b = run(kb, n, tau), c = run(kc, n, tau);
        KernelOut g(n, ga.switches().size(), 0), h(n, gb.switches().size(), 0);
        ga.eval(tau, g.view());
        gb.eval(tau, h.view());
        double apart = 0;
        for (std::size_t i = 0; i < n; ++i) {
            EXPECT_NEAR(a.x[i], b.x[i], 1e-14 * (1 + std::fabs(b.x[i]))) << "tau=" << tau;
            EXPECT_NEAR(a.v[i], b.v[i], 1e-14 * (1 + std::fabs(b.v[i]))) << "tau=" << tau;
            EXPECT_NEAR(g.x[i], h.x[i], 1e-14 * (1 + std::fabs(h.x[i]))) << "tau=" << tau;
            EXPECT_NEAR(g.x[i], a.x[i], 1e-13 * (1 + std::fabs(a.x[i]))) << "tau=" << tau;
            apart = std::max(apart, std::fabs(c.x[i] - b.x[i]));
        }
        EXPECT_GT(apart, 1e-6) << "tau=" << tau;  // a quarter second of forcing phase shows
    }
}

// A kernel of m in cfg against the Eigen generic solver (the state-space one
// for dampers) at a few instants; the number of instants compared.
int compare_with_generic(const Model& m, const Configuration& cfg, const hsnc_kernel& kernel, const std::string& name) {
    int compared = 0;
    KernelSolver k(kernel);
    const std::unique_ptr<SegmentSolver> generic = m.proportional_damping()
                                                       ? std::unique_ptr<SegmentSolver>(new GenericSolver(m, cfg))
                                                       : std::unique_ptr<SegmentSolver>(new StateSpaceSolver(m, cfg));
    SegmentSolver& gs = *generic;
    if (k.switches() != gs.switches()) {
        ADD_FAILURE() << name << " " << cfg.key() << ": other switch functions";
        return 0;
    }
    const Start st = start_of(m, cfg);
    k.setup(st.t0, st.x0.data(), st.v0.data(), st.sgn.data());
    gs.setup(st.t0, st.x0.data(), st.v0.data(), st.sgn.data());
    // Gershgorin bound on the highest natural frequency: rounding in x of size
    // eps*|x| shows in v as eps*omega_max*|x|.
    const Eigen::MatrixXd K = stiffness_matrix(m, cfg);
    const Eigen::VectorXd M = mass_vector(m);
    double omega_max = 0;
    for (std::size_t i = 0; i < m.dof(); ++i)
        omega_max = std::max(omega_max, std::sqrt(K.row(i).cwiseAbs().sum() / M(i)));
    for (double t : {0.0, 0.01, 0.3, 1.7}) {
        KernelOut a = run(k, m, t), b(m.dof(), gs.switches().size(), m.jenkins.size());
        gs.eval(t, b.view());
        // Reference sizes: the largest state component, or the term magnitudes the
        // solvers report for gaps (x) and velocities (v) when the state is ~0.
        double xs = 1e-300, vs = 1e-300;
        for (std::size_t i = 0; i < m.dof(); ++i) {
            xs = std::max(xs, std::fabs(b.x[i]));
            vs = std::max(vs, std::fabs(b.v[i]));
        }
        for (std::size_t f = 0; f < a.g.size(); ++f) {
            if (k.switches()[f].kind == SwitchKind::gap) xs = std::max(xs, b.scale[f]);
            if (is_velocity(k.switches()[f].kind)) vs = std::max(vs, b.scale[f]);
        }
        vs = std::max(vs, omega_max * xs);
        const std::string where = std::string(name) + " " + cfg.key() + " tau=" + std::to_string(t);
        for (std::size_t i = 0; i < m.dof(); ++i) {
            EXPECT_NEAR(a.x[i], b.x[i], 1e-12 * xs) << where;
            EXPECT_NEAR(a.v[i], b.v[i], 1e-12 * vs) << where;
        }
        for (std::size_t i = m.dof(); i < a.x.size(); ++i)  // the sliders
            EXPECT_NEAR(a.x[i], b.x[i], 1e-12 * (xs + std::fabs(b.x[i]))) << where << " slider";
        for (std::size_t f = 0; f < a.g.size(); ++f) {
            EXPECT_NEAR(a.g[f], b.g[f], 1e-12 * std::max(a.scale[f], b.scale[f])) << where << " g" << f;
            EXPECT_NEAR(a.dg[f], b.dg[f], 1e-12 * (std::fabs(b.dg[f]) + std::max(a.scale[f], b.scale[f]) * 1e3))
                << where << " dg" << f;
        }
        ++compared;
    }
    return compared;
}

TEST(Kernel, AgreesWithGenericSolverOnBundledModels) {
    // The AOT kernels of models/*.toml against the Eigen generic solver.
    int compared = 0;
    for (const char* name : {"bilinear-1dof", "coulomb-1dof", "seed-scenario-1", "seed-scenario-2", "chain-8"}) {
        const Model m = read_model(std::string(HSNC_SOURCE_DIR) + "/models/" + name + ".toml");
        for (const Configuration& cfg : configurations_to_generate(m, nullptr)) {
            const hsnc_kernel* kp = find_aot_kernel(aot_registry(), m.name.c_str(), model_hash(m), cfg.key().c_str());
            ASSERT_NE(kp, nullptr) << name << " " << cfg.key();
            compared += compare_with_generic(m, cfg, *kp, name);
        }
    }
    EXPECT_GT(compared, 100);
}

// Jenkins elements and friction between two bodies: every configuration of
// the samples that have them (an element stuck, slipping either way, the
// sliders in x0 and x; a pair sliding, or stuck and folded into one
// coordinate) against the generic solver, whose sliders
// (runtime/solvers/switch_values.h) and folding (model/modal.h) share no code
// with lowering.
TEST(Kernel, AgreesWithGenericSolverWithJenkinsElementsAndFrictionPairs) {
    int compared = 0;
    for (const Model& m : sample_models()) {
        if (stick_elements(m).empty()) continue;
        for (const Configuration& cfg : all_configurations(m)) compared += compare_with_generic(m, cfg, sample_kernel(m, cfg), m.name);
    }
    EXPECT_EQ(compared, 4 * (18 + 3 + 4 + 2));
}

// Dampers: every configuration of the sample with dampers (complex pairs, and
// real eigenvalues only) against the state-space solver.
TEST(Kernel, AgreesWithStateSpaceSolverWithDampers) {
    int compared = 0;
    for (const Model& m : sample_models()) {
        if (m.proportional_damping()) continue;
        for (const Configuration& cfg : all_configurations(m)) compared += compare_with_generic(m, cfg, sample_kernel(m, cfg), m.name);
    }
    EXPECT_EQ(compared, 4 * 4);
}

TEST(Emitter, DeterministicAndSelfContained) {
    for (const Model& m : sample_models()) {
        const Configuration cfg = all_configurations(m).front();
        const std::string a = emit_kernel(derive(m, cfg)), b = emit_kernel(derive(m, cfg));
        EXPECT_EQ(a, b);
        EXPECT_EQ(a.find("#include <"), std::string::npos);
        EXPECT_EQ(a.find("std::"), std::string::npos);
        EXPECT_EQ(a.find("new "), std::string::npos);
        EXPECT_NE(a.find("#include \"kernel_abi.h\""), std::string::npos);
        EXPECT_NE(a.find(HSNC_VERSION), std::string::npos);
    }
}

TEST(Emitter, ConstantsRoundTrip) {
    for (double v : {0.1, 1.0 / 3.0, 175.5151, -2.5e-300, 6.02214076e23, 5.0, -0.0})
        EXPECT_EQ(std::strtod(format_double(v).c_str(), nullptr), v) << format_double(v);
    EXPECT_EQ(format_double(5.0), "5.0");
    EXPECT_EQ(format_double(0.1), "0.10000000000000001");
}

}  // namespace
}  // namespace hsnc
