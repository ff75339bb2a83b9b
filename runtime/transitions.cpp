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

// Acceleration of every mass in cfg at (t, x, v): 0 when stuck, else
// (A_i - mu_k N_i sgn_i)/m_i (sgn_i = 0 for masses without friction); entries n..2n-1
// hold (|A_i| + mu_k N_i)/m_i, the magnitude of the terms (its rounding level).
std::vector<double> accelerations(const Model& model, const Configuration& cfg, const std::vector<signed char>& sgn,
                                  double t, const double* x, const double* v) {
    const int n = static_cast<int>(model.dof());
    std::vector<double> a(2 * n, 0.0);  // accelerations, then the magnitudes of their terms
    for (int i = 0; i < n; ++i) {
        if (cfg.stuck[i]) continue;
        const double A = force_on_mass(model, cfg, i, t, x, v);
        const double friction = model.masses[i].has_friction ? model.masses[i].mu_k * model.normal_force(i) : 0.0;
        a[i] = (A - friction * sgn[i]) / model.masses[i].m;
        a[n + i] = (std::fabs(A) + friction) / model.masses[i].m;  // magnitude of its terms
    }
    return a;
}

// State a contact enters at (t, x, v) when G = 0 and G' = 0 there (to
// rounding): closed if the first non-zero of G'', G''' is positive, open if
// negative, closed when all are 0 (at rest on the boundary). -1: not tied.
int tied_contact_state(const Model& model, const Configuration& cfg, int c, double t, const double* x,
                       const double* v, const std::vector<double>& a) {
    auto body = [](const double* y, int b) { return b == kGround ? 0.0 : y[b]; };
    const Contact& k = model.contacts[c];
    const double G = gap(model, c, x);
    if (std::fabs(G) > 16 * kEps * (std::fabs(body(x, k.a)) + std::fabs(body(x, k.b)) + std::fabs(k.gap))) return -1;
    const double Gd = gap_rate(model, c, v);
    if (std::fabs(Gd) > 16 * kEps * (std::fabs(body(v, k.a)) + std::fabs(body(v, k.b)))) return -1;
    double decide = body(a.data(), k.a) - body(a.data(), k.b);  // G''
    const double* amag = a.data() + model.dof();  // |A| + mu_k N over m: the rounding level of a
    if (std::fabs(decide) <= 16 * kEps * (body(amag, k.a) + body(amag, k.b))) {
        // G''' = A_a'/m_a - A_b'/m_b (friction forces are constant; stuck masses do not move).
        auto jerk = [&](int b) {
            if (b == kGround || cfg.stuck[b]) return 0.0;
            return force_rate_on_mass(model, cfg, b, t, v, a.data()) / model.masses[b].m;
        };
        decide = jerk(k.a) - jerk(k.b);
    }
    return decide >= 0 ? 1 : 0;
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
        if (!changed) {
            // 4. Contacts at G = 0, G' = 0 at this instant (a touch, or a mass
            //    stopped or released on its stop) enter the state the forces of
            //    the configuration that results give them (interface.md: contacts
            //    re-decided after the friction decisions, until settled).
            //    Contacts the search found crossing keep their change.
            const std::vector<double> acc = accelerations(model, cfg, sgn, t, x, v);
            for (std::size_t c = 0; c < model.contacts.size(); ++c) {
                const SwitchFunction gf{SwitchKind::gap, static_cast<int>(c)};
                if (std::find(switched.begin(), switched.end(), gf) != switched.end()) continue;
                const int state = tied_contact_state(model, cfg, static_cast<int>(c), t, x, v, acc);
                if (state < 0 || state == cfg.closed[c]) continue;
                cfg.closed[c] = static_cast<char>(state);
                out.push_back({state ? EventKind::contact_close : EventKind::contact_open, static_cast<int>(c)});
                changed = true;
            }
            if (!changed) return true;
        }
    }
    why = "friction decisions at t = " + std::to_string(t) + " do not settle";
    return false;
}

namespace {

// Friction masses: sliding along v, or at rest stuck or sliding by the stick rule, in cfg.
void decide_friction(const Model& model, Configuration& cfg, std::vector<signed char>& sgn, double t, const double* x,
                     const double* v) {
    const int n = static_cast<int>(model.dof());
    for (int i = 0; i < n; ++i) {
        if (!model.masses[i].has_friction) continue;
        if (v[i] != 0.0) {
            cfg.stuck[i] = 0;
            sgn[i] = v[i] > 0 ? 1 : -1;
        } else {
            const signed char dir = stick_rule(model, cfg, i, t, x, v, nullptr);
            cfg.stuck[i] = dir == 0;
            sgn[i] = dir;
        }
    }
}

}  // namespace

Configuration entered_configuration(const Model& model, double t, const double* x, const double* v,
                                    std::vector<signed char>& sgn) {
    Configuration cfg = Configuration::all_open(model);
    const int n = static_cast<int>(model.dof());
    sgn.assign(n, 0);
    auto body = [](const double* y, int b) { return b == kGround ? 0.0 : y[b]; };
    // Contacts with G = 0 and G' = 0 at t are decided below by G'', then G'''
    // (the first non-zero derivative, interface.md "Ties and touches"), which
    // need the accelerations of the configuration the friction decisions give.
    std::vector<int> tied;
    for (std::size_t c = 0; c < model.contacts.size(); ++c) {
        const Contact& k = model.contacts[c];
        const double G = gap(model, static_cast<int>(c), x);
        const double noise = 16 * kEps * (std::fabs(body(x, k.a)) + std::fabs(body(x, k.b)) + std::fabs(k.gap));
        if (std::fabs(G) > noise) {
            cfg.closed[c] = G > 0;
            continue;
        }
        const double Gd = gap_rate(model, static_cast<int>(c), v);
        if (std::fabs(Gd) > 16 * kEps * (std::fabs(body(v, k.a)) + std::fabs(body(v, k.b)))) {
            cfg.closed[c] = Gd > 0;
        } else {
            cfg.closed[c] = 1;  // provisionally: resting on the boundary (x[a]-x[b] >= gap)
            tied.push_back(static_cast<int>(c));
        }
    }
    decide_friction(model, cfg, sgn, t, x, v);
    // A tied contact carries no spring force (G = 0) and no damper force
    // (G' = 0), so its own state changes neither the accelerations nor the
    // friction decisions; friction is still re-decided after any change.
    for (int round = 0; round < 4 && !tied.empty(); ++round) {
        const std::vector<double> a = accelerations(model, cfg, sgn, t, x, v);
        bool changed = false;
        for (int c : tied) {
            const int state = tied_contact_state(model, cfg, c, t, x, v, a);
            if (state >= 0 && state != cfg.closed[c]) {
                cfg.closed[c] = static_cast<char>(state);
                changed = true;
            }
        }
        if (!changed) break;
        decide_friction(model, cfg, sgn, t, x, v);
    }
    return cfg;
}

}  // namespace hsnc
