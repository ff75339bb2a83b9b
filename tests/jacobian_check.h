// The Jacobian of the flow map (analysis/tangent.h JacobianObserver: the
// exact transitions and saltations) against central differences of the
// exact engine, column by column: the check every tangent test shares.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "engine_runner.h"
#include "tangent.h"

namespace hsnc::testing {

// J against (y(z0 + h e_j) - y(z0 - h e_j)) / 2h, every column whose two runs
// meet the same switches as the base run; returns the columns compared.
inline int expect_jacobian_matches(const Model& m, double t_end, double h, double tol, std::size_t min_events) {
    const std::size_t n = m.dof(), nj = m.jenkins.size(), N = 2 * n + nj;
    Model base = m;
    if (base.slider0.empty())
        for (const Jenkins& e : m.jenkins)
            base.slider0.push_back((e.a == kGround ? 0.0 : m.x0[e.a]) - (e.b == kGround ? 0.0 : m.x0[e.b]));
    GenericSolverProvider provider(base);
    Engine engine(base, provider);
    EventSequence kinds;
    analysis::JacobianObserver jac(base, &kinds);
    EngineOptions opt;
    opt.t_end = t_end;
    opt.samples = false;
    const RunSummary s = engine.run(opt, jac);
    EXPECT_EQ(s.status, RunStatus::ok) << s.message;
    EXPECT_GE(kinds.seq.size(), min_events) << m.name;
    EXPECT_EQ(jac.grazing(), 0u);
    const Eigen::MatrixXd& J = jac.jacobian();
    EXPECT_EQ(static_cast<std::size_t>(J.rows()), N);
    int compared = 0;
    double worst = 0.0;
    for (std::size_t j = 0; j < N; ++j) {
        Model p = base, q = base;
        auto& yp = j < n ? p.x0 : j < 2 * n ? p.v0 : p.slider0;
        auto& yq = j < n ? q.x0 : j < 2 * n ? q.v0 : q.slider0;
        const std::size_t k = j < n ? j : j < 2 * n ? j - n : j - 2 * n;
        yp[k] += h;
        yq[k] -= h;
        EventSequence kp, kq;
        const std::vector<double> a = end_state(p, t_end, kp), b = end_state(q, t_end, kq);
        if (kp.seq != kinds.seq || kq.seq != kinds.seq)
            continue;  // a switch moved past the end: not differentiable here
        double scale = 1.0;
        for (std::size_t i = 0; i < N; ++i) scale = std::max(scale, std::fabs((a[i] - b[i]) / (2 * h)));
        for (std::size_t i = 0; i < N; ++i) {
            const double fd = (a[i] - b[i]) / (2 * h);
            const double err = std::fabs(J(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) - fd) / scale;
            worst = std::max(worst, err);
            EXPECT_LT(err, tol) << m.name << " dz" << i << "/dz0_" << j << ": J "
                                << J(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j))
                                << ", finite difference " << fd;
        }
        ++compared;
    }
    std::printf("%s: %zu switches over %g s, %d of %zu columns against central differences, worst %.2g\n",
                m.name.c_str(), kinds.seq.size(), t_end, compared, N, worst);
    return compared;
}

}  // namespace hsnc::testing
