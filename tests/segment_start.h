// A legal segment start for tests that drive a segment solver directly:
// stuck masses at rest (or moving with the body they ride), sliding masses moving
// as sgn says, Jenkins sliders inside their slip force, t0 with a rounding
// part t0_lo.
#pragma once

#include <random>
#include <vector>

#include "assembly.h"
#include "configuration.h"
#include "model.h"

namespace hsnc::testing {

struct Start {
    double t0, t0_lo;
    std::vector<double> x0, v0;
    std::vector<signed char> sgn;
};
inline Start start_of(const Model& m, const Configuration& cfg, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Start s{m.t0 + 3.7 + u(rng), 1e-17 * u(rng), m.x0, m.v0, std::vector<signed char>(m.dof(), 0)};
    for (std::size_t i = 0; i < m.dof(); ++i) {
        s.x0[i] += 0.01 * u(rng);
        s.v0[i] += 0.1 * u(rng);
    }
    for (std::size_t i = 0; i < m.dof(); ++i)  // stuck: with the body it rides (up a chain), or at rest
        if (cfg.stuck[i]) {
            const int c = carrier(m, cfg, i);
            s.v0[i] = c == kGround ? 0.0 : s.v0[static_cast<std::size_t>(c)];
        }
    for (std::size_t i = 0; i < m.dof(); ++i) {  // sliding against the ground or its partner
        const int p = m.friction_slot(i).partner;
        const double vp = p == kGround ? 0.0 : s.v0[static_cast<std::size_t>(p)];
        if (!cfg.stuck[i] && m.has_friction(i)) s.sgn[i] = s.v0[i] < vp ? -1 : 1;
    }
    for (const Jenkins& e : m.jenkins) {  // the sliders after the masses, stretched below the slip force
        auto pos = [&](int b) { return b == kGround ? 0.0 : s.x0[static_cast<std::size_t>(b)]; };
        s.x0.push_back(pos(e.a) - pos(e.b) - 0.9 * u(rng) * e.slip_force / e.k);
    }
    return s;
}

}  // namespace hsnc::testing
