#include "transitions.h"

#include <cmath>
#include <algorithm>
#include <limits>

#include "assembly.h"
#include "tie_series.h"

namespace hsnc {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

// Derivatives A_i^(k), k = 0..order, of the force on mass i at (t, x, v) in
// cfg (friction directions sgn), with the magnitude of their terms (their
// rounding level), from the equation of motion itself:
//     m_j x_j^(k+2) = A_j^(k) - [k = 0] mu_k N_j sgn_j  (0 for a stuck mass),
//     A_j^(k) = [k = 0] (load_j + contact preloads) - (K x^(k))_j - (C x^(k+1))_j
//               + sum_h F_hj Omega_h^k sin(Omega_h t + phase_h + k pi/2).
void force_series(const Model& model, const Configuration& cfg, const std::vector<signed char>& sgn, int i, double t,
                  const double* x, const double* v, int order, std::vector<double>& d, std::vector<double>& mag) {
    const int n = static_cast<int>(model.dof());
    auto at = [](const std::vector<double>& y, int b) { return b == kGround ? 0.0 : y[b]; };
    std::vector<std::vector<double>> X(order + 2, std::vector<double>(n, 0.0)), M = X;
    for (int j = 0; j < n; ++j) {
        X[0][j] = x[j], M[0][j] = std::fabs(x[j]);
        if (!cfg.stuck[j]) X[1][j] = v[j], M[1][j] = std::fabs(v[j]);
    }
    auto deriv = [&](int j, int k, double& value, double& m) {
        value = k == 0 ? model.load[j] : 0.0;
        m = std::fabs(value);
        value -= model.alpha * model.masses[j].m * X[k + 1][j];
        m += std::fabs(model.alpha) * model.masses[j].m * M[k + 1][j];
        auto link = [&](int a, int b, double kk, double gap) {
            if (a == b || (a != j && b != j)) return;
            double f = -kk * (at(X[k], a) - at(X[k], b)) - model.beta * kk * (at(X[k + 1], a) - at(X[k + 1], b));
            double fm = kk * (at(M[k], a) + at(M[k], b)) + std::fabs(model.beta) * kk * (at(M[k + 1], a) + at(M[k + 1], b));
            if (k == 0) f += kk * gap, fm += std::fabs(kk * gap);
            value += a == j ? f : -f;
            m += fm;
        };
        for (const Spring& s : model.springs) link(s.a, s.b, s.k, 0.0);
        for (std::size_t c = 0; c < model.contacts.size(); ++c)
            if (cfg.closed[c]) link(model.contacts[c].a, model.contacts[c].b, model.contacts[c].k, model.contacts[c].gap);
        for (const Harmonic& h : model.forcing) {
            const double arg = h.omega * t + h.phase;
            double s = (k % 2 == 0) ? std::sin(arg) : std::cos(arg);
            if (k % 4 == 2 || k % 4 == 3) s = -s;
            const double wk = std::pow(h.omega, k);
            value += h.amplitude[j] * wk * s;
            m += std::fabs(h.amplitude[j]) * wk;
        }
    };
    for (int k = 0; k + 2 <= order + 1; ++k)
        for (int j = 0; j < n; ++j) {
            if (cfg.stuck[j]) continue;
            double A, m;
            deriv(j, k, A, m);
            const double fr = k == 0 && model.masses[j].has_friction ? model.masses[j].mu_k * model.normal_force(j) : 0.0;
            X[k + 2][j] = (A - fr * sgn[j]) / model.masses[j].m;
            M[k + 2][j] = (m + fr * (sgn[j] != 0)) / model.masses[j].m;
        }
    d.assign(order + 1, 0.0);
    mag.assign(order + 1, 0.0);
    for (int k = 0; k <= order; ++k) deriv(i, k, d[k], mag[k]);
}

// Stick rule at v_i = 0 (interface.md): stuck if |A_i| < mu_s*N_i, else slide
// in the direction of A_i. Returns 0 for stuck, else the direction. A tie
// (|A_i| = mu_s*N_i to rounding) is decided by the first derivative, as the
// contract says: stuck if |A_i| is not increasing with the mass held (a_i = 0,
// the others' accelerations from `a`, or 0 when a is null), else sliding.
signed char stick_rule(const Model& model, const Configuration& cfg, const std::vector<signed char>& sgn, int i,
                       double t, const double* x, const double* v, const double* a) {
    const double A = force_on_mass(model, cfg, i, t, x, v);
    const double limit = model.masses[i].mu_s * model.normal_force(i);
    const double dir = A > 0 ? 1 : -1;
    if (std::fabs(std::fabs(A) - limit) <= 16 * kEps * std::max(std::fabs(A), limit)) {
        std::vector<double> held(model.dof(), 0.0);
        if (a) held.assign(a, a + model.dof());
        held[i] = 0.0;
        const double rate = dir * force_rate_on_mass(model, cfg, i, t, v, held.data());
        // The held motion's derivatives: the rate's rounding level, and the
        // higher orders when the rate vanishes (the first non-zero derivative
        // decides; none at all: |A_i| stays at the limit, not increasing).
        Configuration hold = cfg;
        hold.stuck[i] = 1;
        std::vector<signed char> s = sgn;
        s[i] = 0;
        const int order = static_cast<int>(2 * model.dof() + 2 * model.forcing.size() + 2);
        std::vector<double> d, mag;
        force_series(model, hold, s, i, t, x, v, order, d, mag);
        if (std::fabs(rate) <= 16 * kEps * mag[1]) {
            for (int k = 2; k <= order; ++k)
                if (std::fabs(d[k]) > 16 * kEps * mag[k]) return dir * d[k] > 0 ? static_cast<signed char>(dir) : 0;
            return 0;
        }
        return rate > 0 ? static_cast<signed char>(dir) : 0;
    }
    if (std::fabs(A) < limit) return 0;
    return static_cast<signed char>(dir);
}

// State a contact enters at (t, x, v) when G = 0 and G' = 0 there (to
// rounding): closed if its first non-zero derivative (G'', G''', ...; the
// series of tie_series.h, in cfg) is positive, open if negative. -1: not tied,
// or no derivative decides (G stays at 0, e.g. a mass stuck exactly on the
// gap): a function that only touches 0 changes nothing (interface.md "Ties
// and touches"), so the contact keeps its state (at t0 the provisional
// closed: at rest on the boundary). A tied contact carries no force (G = G' =
// 0), and its own force enters G^(k) only through G^(k-2) and G^(k-1), so its
// own state does not change the decision.
int tied_contact_state(const Model& model, const Configuration& cfg, const std::vector<signed char>& sgn, int c,
                       double t, const double* x, const double* v) {
    auto body = [](const double* y, int b) { return b == kGround ? 0.0 : y[b]; };
    const Contact& k = model.contacts[c];
    const double G = gap(model, c, x);
    if (std::fabs(G) > 16 * kEps * (std::fabs(body(x, k.a)) + std::fabs(body(x, k.b)) + std::fabs(k.gap))) return -1;
    const double Gd = gap_rate(model, c, v);
    if (std::fabs(Gd) > 16 * kEps * (std::fabs(body(v, k.a)) + std::fabs(body(v, k.b)))) return -1;
    const int order = tie_order(model);
    const MotionSeries s = motion_series(model, cfg, sgn.data(), t, 0.0, x, v, order + 1);
    std::vector<double> d, mag;
    switch_series(model, cfg, SwitchFunction{SwitchKind::gap, c}, t, 0.0, s, d, mag);
    d[1] = 0.0;  // G' is zero to the rounding checked above
    const int dir = first_nonzero_sign(d, mag, order);
    return dir == 0 ? -1 : dir > 0 ? 1 : 0;
}

}  // namespace

bool apply_switches(const Model& model, double t, const double* x, double* v, const double* a, Configuration& cfg,
                    std::vector<signed char>& sgn, const std::vector<SwitchFunction>& switched,
                    std::vector<Transition>& out, std::string& why) {
    const int n = static_cast<int>(model.dof());
    // A stop sets its velocity to 0 exactly, before the contacts are judged.
    for (const SwitchFunction& f : switched)
        if (f.kind == SwitchKind::velocity) v[f.element] = 0.0;
    // 1. Every contact change first. A switched contact with G = 0 and G' = 0
    //    (to rounding; e.g. a touch at a friction stop, found "heading across"
    //    only by the rounding of the stopping velocity) is a tie: step 4 decides
    //    it by its first non-zero derivative in the configuration the friction
    //    decisions give.
    std::vector<char> tied(model.contacts.size(), 0);
    auto body = [](const double* y, int b) { return b == kGround ? 0.0 : y[b]; };
    for (const SwitchFunction& f : switched) {
        if (f.kind != SwitchKind::gap) continue;
        const Contact& k = model.contacts[f.element];
        const double G = gap(model, f.element, x), Gd = gap_rate(model, f.element, v);
        if (std::fabs(G) <= 16 * kEps * (std::fabs(body(x, k.a)) + std::fabs(body(x, k.b)) + std::fabs(k.gap)) &&
            std::fabs(Gd) <= 16 * kEps * (std::fabs(body(v, k.a)) + std::fabs(body(v, k.b)))) {
            tied[f.element] = 1;
            continue;
        }
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
            const signed char dir = stick_rule(model, cfg, sgn, i, t, x, v, a);
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
            const signed char dir = stick_rule(model, cfg, sgn, i, t, x, v, a);
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
            for (std::size_t c = 0; c < model.contacts.size(); ++c) {
                const SwitchFunction gf{SwitchKind::gap, static_cast<int>(c)};
                if (!tied[c] && std::find(switched.begin(), switched.end(), gf) != switched.end()) continue;
                const int state = tied_contact_state(model, cfg, sgn, static_cast<int>(c), t, x, v);
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
            const signed char dir = stick_rule(model, cfg, sgn, i, t, x, v, nullptr);
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
    // Contacts with G = 0 and G' = 0 at t are decided below by G'', G''', ...
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
        bool changed = false;
        for (int c : tied) {
            const int state = tied_contact_state(model, cfg, sgn, c, t, x, v);
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
