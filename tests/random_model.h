// Random models for tests: a chain of n masses with random springs,
// contacts, friction, damping and forcing, and a random configuration of it
// (tests/test_kernel_random.cpp, tests/test_program.cpp).
#pragma once

#include <random>
#include <string>
#include <vector>

#include "configuration.h"
#include "model.h"

namespace hsnc::testing {

inline double uni(std::mt19937& rng, double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }

struct Drawn {
    Model model;
    Configuration cfg;
    std::vector<signed char> sgn;
};

// n masses in a chain with random springs (either end grounded or not, so
// some draws float), contacts between neighbours and to ground, friction on
// about half the masses, Rayleigh damping from none to heavy, one or two
// harmonics and constant loads; a random configuration of the result.
inline Drawn draw(unsigned seed, int n) {
    std::mt19937 rng(seed);
    Drawn d;
    Model& m = d.model;
    m.name = "random_" + std::to_string(seed);
    for (int i = 0; i < n; ++i) {
        m.masses.push_back({"m" + std::to_string(i + 1), uni(rng, 0.3, 3.0)});
        if (uni(rng, 0, 1) < 0.5) {
            FrictionSlot& f = m.set_friction(static_cast<std::size_t>(i));
            f.active = true;
            f.mu_k = uni(rng, 0.0, 0.4);
            f.mu_s = f.mu_k + uni(rng, 0.0, 0.3);
        }
    }
    if (uni(rng, 0, 1) < 0.5) m.springs.push_back({kGround, 0, uni(rng, 1.0, 80.0)});
    for (int i = 0; i + 1 < n; ++i) m.springs.push_back({i, i + 1, uni(rng, 1.0, 80.0)});
    if (uni(rng, 0, 1) < 0.5) m.springs.push_back({n - 1, kGround, uni(rng, 1.0, 80.0)});
    for (int i = 0; i + 1 < n; ++i)
        if (uni(rng, 0, 1) < 0.5)
            m.contacts.push_back({"c" + std::to_string(i + 1), i, i + 1, uni(rng, -0.1, 0.2), uni(rng, 10.0, 300.0)});
    m.contacts.push_back({"stop", n - 1, kGround, uni(rng, 0.1, 0.5), uni(rng, 10.0, 300.0)});
    const double damping = uni(rng, 0, 1);
    m.alpha = damping < 0.2 ? 0.0 : uni(rng, 0.0, 2.0);
    m.beta = damping < 0.4 ? 0.0 : uni(rng, 0.0, damping < 0.8 ? 0.05 : 1.0);
    for (int h = 0, nh = uni(rng, 0, 1) < 0.5 ? 1 : 2; h < nh; ++h) {
        Harmonic hm{uni(rng, 0.5, 30.0), uni(rng, 0.0, 6.0), {}};
        for (int i = 0; i < n; ++i) hm.amplitude.push_back(uni(rng, -10.0, 10.0));
        m.forcing.push_back(hm);
    }
    for (int i = 0; i < n; ++i) {
        m.load.push_back(uni(rng, -2.0, 2.0));
        m.x0.push_back(uni(rng, -0.3, 0.3));
        m.v0.push_back(uni(rng, -1.0, 1.0));
    }
    m.t0 = uni(rng, 0.0, 5.0);
    d.cfg = Configuration::all_open(m);
    for (std::size_t c = 0; c < m.contacts.size(); ++c) d.cfg.closed[c] = uni(rng, 0, 1) < 0.5;
    d.sgn.assign(static_cast<std::size_t>(n), 0);
    for (int i = 0; i < n; ++i) {
        if (!m.has_friction(i)) continue;
        if (uni(rng, 0, 1) < 0.4) {
            d.cfg.stuck[i] = 1;
            m.v0[i] = 0.0;
        } else {
            d.sgn[i] = m.v0[i] < 0 ? -1 : 1;
        }
    }
    return d;
}

// Two dampers at random places of d's model (between masses or to ground):
// non-proportional damping.
inline void add_random_dampers(Drawn& d, unsigned seed) {
    std::mt19937 rng(seed);
    const int n = static_cast<int>(d.model.dof());
    for (int k = 0; k < 2; ++k) {
        const int a = static_cast<int>(uni(rng, 0, n - 0.001));
        int b = static_cast<int>(uni(rng, -1, n - 0.001));
        if (b == a) b = kGround;
        d.model.dampers.push_back({a, b, uni(rng, 0.05, 3.0)});
    }
}

}  // namespace hsnc::testing
