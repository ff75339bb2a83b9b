#include "transitions.h"

#include <cmath>
#include <algorithm>
#include <limits>

#include "assembly.h"

namespace hsnc {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

// Stick rule at v_i = 0 (interface.md): stuck if |A_i| < mu_s*N_i, else slide
// in the direction of A_i. Returns 0 for stuck, else the direction. A tie
// (|A_i| = mu_s*N_i to rounding) is decided by the first derivative, as the
// contract says: stuck if |A_i| is not increasing with the mass held (a_i = 0,
// the others' accelerations from `a`, or 0 when a is null), else sliding.
signed char stick_rule(const Model& model, const Configuration& cfg, int i, double t, const double* x,
                       const double* v, const double* a) {
    const double A = force_on_mass(model, cfg, i, t, x, v);
    const double limit = model.masses[i].mu_s * model.normal_force(i);
    const double dir = A > 0 ? 1 : -1;
    if (std::fabs(std::fabs(A) - limit) <= 16 * kEps * std::max(std::fabs(A), limit)) {
        std::vector<double> held(model.dof(), 0.0);
        if (a) held.assign(a, a + model.dof());
        held[i] = 0.0;
        const double rate = dir * force_rate_on_mass(model, cfg, i, t, v, held.data());
        return rate > 0 ? static_cast<signed char>(dir) : 0;
    }
    if (std::fabs(A) < limit) return 0;
    return static_cast<signed char>(dir);
}

}  // namespace

bool apply_switches(const Model& model, double t, const double* x, double* v, const double* a, Configuration& cfg,
                    std::vector<signed char>& sgn, const std::vector<SwitchFunction>& switched,
                    std::vector<Transition>& out, std::string& why) {
    const int n = static_cast<int>(model.dof());
    // 1. Every contact change first.
    for (const SwitchFunction& f : switched) {
        if (f.kind != SwitchKind::gap) continue;
        cfg.closed[f.element] = !cfg.closed[f.element];
        out.push_back({cfg.closed[f.element] ? EventKind::contact_close : EventKind::contact_open, f.element});
    }
    // 2. Friction: masses whose velocity reached 0 are decided by the stick rule;
    //    stuck masses whose release function switched start sliding along A_i.
    std::vector<char> deciding(n, 0);
    for (const SwitchFunction& f : switched) {
        const int i = f.element;
        if (f.kind == SwitchKind::velocity) {
            v[i] = 0.0;
            deciding[i] = 1;
        } else if (f.kind == SwitchKind::release_pos || f.kind == SwitchKind::release_neg) {
            cfg.stuck[i] = 0;
            sgn[i] = f.kind == SwitchKind::release_pos ? 1 : -1;
            out.push_back({EventKind::release, i});
        }
    }
    // 3. Decide, then re-check every stuck mass against the forces of the new
    //    configuration, until nothing changes.
    for (int round = 0; round < 2 * n + 4; ++round) {
        bool changed = false;
        for (int i = 0; i < n; ++i) {
            if (!deciding[i]) continue;
            deciding[i] = 0;
            const signed char dir = stick_rule(model, cfg, i, t, x, v, a);
            if (dir == 0) {
                cfg.stuck[i] = 1;
                sgn[i] = 0;
                out.push_back({EventKind::stick, i});
            } else {
                if (dir != sgn[i]) out.push_back({EventKind::reversal, i});
                sgn[i] = dir;
            }
            changed = true;
        }
        for (int i = 0; i < n; ++i) {
            if (!cfg.stuck[i]) continue;
            const signed char dir = stick_rule(model, cfg, i, t, x, v, a);
            if (dir == 0) continue;
            cfg.stuck[i] = 0;
            sgn[i] = dir;
            out.push_back({EventKind::release, i});
            changed = true;
        }
        if (!changed) return true;
    }
    why = "friction decisions at t = " + std::to_string(t) + " do not settle";
    return false;
}

Configuration entered_configuration(const Model& model, double t, const double* x, const double* v,
                                    std::vector<signed char>& sgn) {
    Configuration cfg = Configuration::all_open(model);
    for (std::size_t c = 0; c < model.contacts.size(); ++c) {
        const Contact& k = model.contacts[c];
        const double G = gap(model, static_cast<int>(c), x);
        const double noise = 16 * kEps *
                             ((k.a == kGround ? 0 : std::fabs(x[k.a])) + (k.b == kGround ? 0 : std::fabs(x[k.b])) +
                              std::fabs(k.gap));
        if (std::fabs(G) > noise) {
            cfg.closed[c] = G > 0;
        } else {
            const double Gd = gap_rate(model, static_cast<int>(c), v);
            cfg.closed[c] = Gd >= 0;  // increasing, or resting on the boundary (x[a]-x[b] >= gap)
        }
    }
    const int n = static_cast<int>(model.dof());
    sgn.assign(n, 0);
    for (int i = 0; i < n; ++i) {
        if (!model.masses[i].has_friction) continue;
        if (v[i] != 0.0) {
            sgn[i] = v[i] > 0 ? 1 : -1;
        } else {
            const signed char dir = stick_rule(model, cfg, i, t, x, v, nullptr);
            cfg.stuck[i] = dir == 0;
            sgn[i] = dir;
        }
    }
    return cfg;
}

}  // namespace hsnc
