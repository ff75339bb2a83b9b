// Emitted kernels of random models, 1 to 8 DOF, each for one random
// configuration: derived, emitted and compiled in-process (the JIT), then held
// to the equation of motion assembled independently (model/assembly.h), to
// the initial state, and to the generic solver. The bundled and sample models
// (tests/test_emitter.cpp) cover every regime by construction; these cover
// what nobody wrote down: random couplings, masses, damping and forcing up to
// the size of a small chain, with stuck masses and closed contacts (the 24
// draws give under- and overdamped modes; rigid-body modes, critical damping
// and resonance are the sample models' business).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <string>

#include "assembly.h"
#include "derivation.h"
#include "emitter.h"
#include "generic_solver.h"
#include "jit.h"
#include "kernel_solver.h"
#include "random_model.h"

namespace hsnc {
namespace {

using testing::draw;
using testing::Drawn;

struct Out {
    std::vector<double> x, v, a, g, dg, bound, scale;
    Out(std::size_t n, std::size_t nf) : x(n), v(n), a(n), g(nf), dg(nf), bound(nf), scale(nf) {}
    SegmentEval view() { return {x.data(), v.data(), a.data(), g.data(), dg.data(), bound.data(), scale.data()}; }
};

class RandomKernel : public ::testing::TestWithParam<int> {};

TEST_P(RandomKernel, SatisfiesTheEquationOfMotionAndAgreesWithTheGenericSolver) {
    const int n = GetParam();
    for (unsigned seed = 100 * n; seed < 100 * n + 3; ++seed) {
        const Drawn d = draw(seed, n);
        const Model& m = d.model;
        const std::string what = m.name + " (" + std::to_string(n) + " dof, " + d.cfg.spec(m) + ")";
        Jit jit;
        jit.add(what, emit_kernel(derive(m, d.cfg)));
        const auto* kernel = static_cast<const hsnc_kernel*>(jit.lookup(kernel_symbol(m, d.cfg)));
        KernelSolver k(*kernel);
        GenericSolver g(m, d.cfg);
        k.setup(m.t0, m.x0.data(), m.v0.data(), d.sgn.data());
        g.setup(m.t0, m.x0.data(), m.v0.data(), d.sgn.data());
        const Eigen::MatrixXd K = stiffness_matrix(m, d.cfg), C = damping_matrix(m, d.cfg);
        const Eigen::VectorXd M = mass_vector(m), f0 = constant_force(m, d.cfg);
        const std::size_t ns = k.switches().size();
        ASSERT_EQ(ns, g.switches().size()) << what;
        for (double tau : {0.0, 1e-3, 0.07, 0.4, 1.1, 2.5}) {
            Out ko(m.dof(), ns), go(m.dof(), ns);
            k.eval(tau, ko.view());
            g.eval(tau, go.view());
            const Eigen::Map<const Eigen::VectorXd> x(ko.x.data(), n), v(ko.v.data(), n), a(ko.a.data(), n);
            const Eigen::VectorXd F = forcing(m, m.t0 + tau);
            for (int i = 0; i < n; ++i) {
                if (tau == 0.0) {  // the initial state
                    EXPECT_NEAR(ko.x[i], m.x0[i], 1e-14 * (1 + std::fabs(m.x0[i]))) << what << " mass " << i;
                    EXPECT_NEAR(ko.v[i], m.v0[i], 1e-13 * (1 + std::fabs(m.v0[i]))) << what << " mass " << i;
                }
                if (d.cfg.stuck[i]) {
                    EXPECT_EQ(ko.x[i], m.x0[i]) << what;
                    EXPECT_EQ(ko.v[i], 0.0) << what;
                    continue;
                }
                const double friction =
                    m.has_friction(i) ? m.friction_slot(i).mu_k * m.normal_force(i) * d.sgn[i] : 0.0;
                const double lhs = M(i) * a(i) + C.row(i).dot(v) + K.row(i).dot(x);
                const double rhs = f0(i) + F(i) - friction;
                const double size = std::fabs(M(i) * a(i)) + C.row(i).cwiseAbs().dot(v.cwiseAbs()) +
                                    K.row(i).cwiseAbs().dot(x.cwiseAbs()) + std::fabs(f0(i)) + std::fabs(F(i)) +
                                    std::fabs(friction);
                EXPECT_NEAR(lhs, rhs, 1e-12 * size) << what << " tau=" << tau << " mass " << i;
                // The generic solver is an independent implementation of the same closed forms.
                EXPECT_NEAR(ko.x[i], go.x[i], 1e-12 * (1 + std::fabs(go.x[i]))) << what << " tau=" << tau;
                EXPECT_NEAR(ko.v[i], go.v[i], 1e-11 * (1 + std::fabs(go.v[i]))) << what << " tau=" << tau;
            }
            for (std::size_t f = 0; f < ns; ++f) {
                EXPECT_NEAR(ko.g[f], go.g[f], 1e-11 * (1 + go.scale[f])) << what << " switch " << f;
                EXPECT_NEAR(ko.dg[f], go.dg[f], 1e-11 * (1 + std::fabs(go.dg[f]) + go.scale[f])) << what;
            }
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Dof, RandomKernel, ::testing::Range(1, 9));

}  // namespace
}  // namespace hsnc
