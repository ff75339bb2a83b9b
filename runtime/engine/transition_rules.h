// hsnc -- the decision rules of the contract at a switch and at t0
// (interface.md section 2, "Ties and touches", "At t0"), written once for any
// scalar type. The double engine (runtime/engine/transitions.cpp, also behind the
// event-locating integrators) and the CLN reference (reference/reference.cpp)
// instantiate them, each with its own arithmetic: the forces, their time
// derivatives and the rounding level below which a value counts as zero are
// the method's (the reference's independence from the double code is what
// makes it a check); which switch applies, what the new configuration is and
// how a tie is broken are these functions.
//
// A method supplies a class P with
//   using Scalar = T;
//   int sign(const T&) const;                          // -1, 0, +1
//   bool negligible(const T& value, const T& magnitude) const;  // zero to its rounding
//   T abs(const T&) const;
//   int dof() const; std::size_t contacts() const; bool has_friction(int i) const;
//   bool coupled() const;                              // a held force depends on the other frictions'
//                                                      // states (a coupled M): decided together
//   int velocity_sign(int i) const;                    // of v_i; 0 when v_i = 0 exactly
//   void stop(int i);                                  // v_i = 0 exactly (a stop)
//   T force(const Configuration&, int i) const;        // A_i: every force on mass i but friction
//   T static_limit(int i) const;                       // mu_s N_i
//   T held_rate(const Configuration&, int i) const;    // dA_i/dt, mass i held, the others' accelerations
//                                                      // from just before (0 when there are none: t0)
//   int tie_order() const;                             // 2n + 2H + 2 (H forcing harmonics)
//   Series<T> held_series(const Configuration&, const std::vector<signed char>& sgn, int i, int order) const;
//                                                      // A_i^(k), k = 0..order, in cfg with mass i held
//   Series<T> gap_now(int c) const;                    // G_c, G_c' at the current state
//   void prepare_ties(const Configuration&, const std::vector<signed char>& sgn);
//   Series<T> tied_gap_series(int c, int order) const; // G_c^(k), k = 0..order, in the configuration
//                                                      // of the last prepare_ties
//   std::size_t jenkins() const;                       // number of Jenkins elements
//   bool slips_on(const Configuration&, int j) const;  // a slipping element whose relative velocity
//                                                      // touched 0 while its relative acceleration (from
//                                                      // just before) keeps the slip's sign: no stick
//   int slip_velocity_sign(int j) const;               // of Jenkins element j's u' now; 0 when zero to rounding
//   bool rigid(int c) const;                           // contact c is a rigid stop (restitution)
//   void impact(int c);                                // its velocity jump at G_c = 0 (contact.h impact)
// where Series<T> holds derivatives d[k] with the magnitudes mag[k] of their
// terms (their rounding level). A tie is decided by the first non-zero
// derivative of any order: the rules ask for the series up to tie_order(),
// the order past which a function of the motion cannot vanish with all its
// derivatives unless it vanishes identically (the motion and the forcing
// harmonics are a linear system of dimension at most 2n + 2H + 1:
// Cayley-Hamilton), so "none non-zero" means the function stays at 0.
#pragma once

#include <algorithm>
#include <cstddef>
#include <numeric>
#include <vector>

#include "configuration.h"
#include "event_kind.h"
#include "switch_function.h"

namespace hsnc {

/// One change of the configuration at a switch instant.
struct Transition {
    EventKind kind;
    int element;
};

namespace rules {

/// Time derivatives d[0], d[1], ... of a quantity with the magnitudes of their terms.
template <class T>
struct Series {
    std::vector<T> d, mag;
};

/// The sign of the first d[k], k >= from, that is not zero to its rounding
/// (the first non-zero derivative, interface.md "Ties and touches"); 0 when
/// none is. `order`, when given, receives that k.
template <class P, class T>
int first_nonzero_sign(const P& p, const Series<T>& s, std::size_t from, int* order = nullptr) {
    for (std::size_t k = from; k < s.d.size(); ++k)
        if (!p.negligible(s.d[k], s.mag[k])) {
            if (order) *order = static_cast<int>(k);
            return p.sign(s.d[k]);
        }
    return 0;
}

/// Stick rule at v_i = 0: 0 when the mass sticks (|A_i| < mu_s N_i), else the
/// direction it slides in (that of A_i). A tie |A_i| = mu_s N_i (to rounding)
/// is decided by the first non-zero derivative of |A_i| - mu_s N_i with the
/// mass held: stuck unless it is increasing. When mu_s N_i = 0 and A_i = 0 the
/// mass slides along the first non-zero derivative of A_i (|A_i| grows as soon
/// as A_i does not vanish).
template <class P>
signed char stick_rule(const P& p, const Configuration& cfg, const std::vector<signed char>& sgn, int i) {
    using T = typename P::Scalar;
    const T A = p.force(cfg, i), limit = p.static_limit(i);
    const signed char dir = p.sign(A) > 0 ? 1 : -1;
    const T absA = p.abs(A);
    if (!p.negligible(absA - limit, absA < limit ? limit : absA)) return absA < limit ? 0 : dir;
    Configuration hold = cfg;  // the held motion: mass i stuck, no friction force on it
    hold.stuck[i] = 1;
    std::vector<signed char> s = sgn;
    s[static_cast<std::size_t>(i)] = 0;
    const Series<T> series = p.held_series(hold, s, i, p.tie_order());
    const T rate = p.held_rate(cfg, i);
    if (!p.negligible(rate, series.mag[1])) return p.sign(rate) == dir ? dir : 0;
    if (p.sign(limit) == 0 && p.negligible(A, series.mag[0]))
        return static_cast<signed char>(first_nonzero_sign(p, series, 1));
    // |A_i| - mu_s N_i has the derivatives dir * A_i^(k): none non-zero, it stays at the limit.
    return first_nonzero_sign(p, series, 1) == dir ? dir : 0;
}

/// The most frictions decided together by enumeration (3^k assignments of
/// stuck, sliding + and sliding -); more at one instant are decided in turn.
inline constexpr std::size_t kMaxDecidedTogether = 8;

/// Whether every friction of `among` is in the state the stick rule gives it
/// with the others as assigned (cfg.stuck, sgn): a stuck one's held force
/// within mu_s N, a sliding one's beyond it and in its direction.
template <class P>
bool consistent(const P& p, const Configuration& cfg, const std::vector<signed char>& sgn,
                const std::vector<int>& among) {
    for (int j : among) {
        const auto u = static_cast<std::size_t>(j);
        const signed char dir = stick_rule(p, cfg, sgn, j);
        if (cfg.stuck[u] ? dir != 0 : dir != sgn[u]) return false;
    }
    return true;
}

/// The frictions of `among` (at rest or stuck at one instant) decided
/// together, where the force that holds one depends on how the others move
/// (P::coupled(): a coupled M; interface.md "Coupled mass matrices"): the
/// assignment in which every one obeys the stick rule with the others as
/// assigned (consistent()), and of several the one with the most stuck, then
/// the one whose stuck frictions come first in model order, then sliding + before -.
/// Sets cfg.stuck and sgn over `among`; false (both left as they came) when no
/// assignment is consistent. `sgn` must be the vector P reads the sliding
/// directions from (the engine's live one): each trial is written into it.
template <class P>
bool decide_together(const P& p, Configuration& cfg, std::vector<signed char>& sgn, const std::vector<int>& among) {
    const std::size_t k = among.size();
    std::vector<unsigned> stuck_sets(std::size_t{1} << k);
    std::iota(stuck_sets.begin(), stuck_sets.end(), 0u);
    auto count = [](unsigned m) {
        int c = 0;
        for (; m; m &= m - 1) ++c;
        return c;
    };
    // Bit j of a set (friction among[j]) as bit k-1-j: the first friction weighs most.
    auto first_in_order = [k](unsigned m) {
        unsigned r = 0;
        for (std::size_t j = 0; j < k; ++j)
            if (m >> j & 1u) r |= 1u << (k - 1 - j);
        return r;
    };
    std::stable_sort(stuck_sets.begin(), stuck_sets.end(), [&](unsigned a, unsigned b) {
        return count(a) != count(b) ? count(a) > count(b) : first_in_order(a) > first_in_order(b);
    });
    const Configuration cfg_in = cfg;
    const std::vector<signed char> sgn_in = sgn;
    for (unsigned stuck : stuck_sets) {
        const std::size_t sliding = k - static_cast<std::size_t>(count(stuck));
        for (unsigned dirs = 0; dirs < (1u << sliding); ++dirs) {
            std::size_t r = 0;
            for (std::size_t j = 0; j < k; ++j) {
                const auto u = static_cast<std::size_t>(among[j]);
                const bool held = (stuck >> j & 1u) != 0;
                cfg.stuck[u] = held ? 1 : 0;
                sgn[u] = held ? 0 : (dirs >> r++ & 1u) ? -1 : 1;
            }
            if (consistent(p, cfg, sgn, among)) return true;
        }
    }
    cfg = cfg_in;
    sgn = sgn_in;
    return false;
}

/// The state a contact enters from G, G', ... at an instant where it is tied
/// (G = G' = 0 to rounding): closed (1) if its first non-zero derivative from
/// G'' on (of any order the series holds: the rules pass tied_gap_series(c,
/// p.tie_order())) is positive, open (0) if negative; -1 when none decides (G
/// stays at 0: a touch changes nothing, the contact keeps its state).
template <class P, class T>
int tied_contact_state(const P& p, const Series<T>& G) {
    const int s = first_nonzero_sign(p, G, 2);
    return s > 0 ? 1 : s < 0 ? 0 : -1;
}

/// Whether G = G' = 0 to rounding (a touch, not a crossing).
template <class P, class T>
bool tied(const P& p, const Series<T>& G) {
    return p.negligible(G.d[0], G.mag[0]) && p.negligible(G.d[1], G.mag[1]);
}

/// The impacts among `switched` (rigid stops the search found reached):
/// each one's velocity jump, an `impact` event, then every friction's state
/// by the new velocities: a held one set moving releases along its velocity,
/// a sliding one reverses with it or, stopped exactly, is decided by the
/// stick rule (`deciding`); a slipping Jenkins element sticks where the jump
/// turned its relative velocity against the slip (a `stick` event). True
/// when one is a touch (G' = 0 to rounding) or its rebound is too low for G
/// to resolve while the forces press on: the motion rests on the stop
/// (`*resting`).
template <class P>
bool impacts(P& p, Configuration& cfg, std::vector<signed char>& sgn, const std::vector<SwitchFunction>& switched,
             std::vector<Transition>& out, std::vector<char>& deciding, int* resting) {
    bool any = false;
    for (const SwitchFunction& f : switched) {
        if (f.kind != SwitchKind::gap || !p.rigid(f.element)) continue;
        const auto G = p.gap_now(f.element);
        if (tied(p, G) || p.sign(G.d[1]) <= 0) {  // no speed into the stop left: resting on it
            if (resting) *resting = f.element;
            return true;
        }
        p.impact(f.element);
        // A rebound too low for G to resolve, (G')^2 / (2 G'') within G's
        // rounding while the forces press on, is the motion at rest on the
        // stop (the end of a Zeno sequence: the next impacts would be found
        // at rounding-level penetrations, at no speed, without end).
        p.prepare_ties(cfg, sgn);
        const auto after = p.tied_gap_series(f.element, 2);
        if (p.sign(after.d[2]) > 0 && p.negligible(after.d[1] * after.d[1] / (after.d[2] + after.d[2]), G.mag[0])) {
            if (resting) *resting = f.element;
            return true;
        }
        out.push_back({EventKind::impact, f.element});
        any = true;
    }
    if (!any) return false;
    for (int i = 0; i < p.dof(); ++i) {
        if (!p.has_friction(i)) continue;
        const auto u = static_cast<std::size_t>(i);
        const int v = p.velocity_sign(i);
        if (cfg.stuck[u]) {
            if (v == 0) continue;
            cfg.stuck[u] = 0;
            sgn[u] = static_cast<signed char>(v);
            out.push_back({EventKind::release, i});
        } else if (v == 0) {
            deciding[u] = 1;
        } else if (v != sgn[u]) {
            sgn[u] = static_cast<signed char>(v);
            out.push_back({EventKind::reversal, i});
        }
    }
    // A slipping Jenkins element whose relative velocity the jump turned
    // against its slip sticks (its force starts to fall from slip_force); one
    // the jump left at rest to rounding is decided as at a slip_velocity
    // switch (P::slips_on). A stuck one stays stuck: its stretch is continuous.
    for (std::size_t j = 0; j < p.jenkins(); ++j) {
        const int sigma = cfg.slip[j];
        if (sigma == 0) continue;
        const int v = p.slip_velocity_sign(static_cast<int>(j));
        if (v == sigma || (v == 0 && p.slips_on(cfg, static_cast<int>(j)))) continue;
        cfg.slip[j] = 0;
        out.push_back({EventKind::stick, p.dof() + static_cast<int>(j)});
    }
    return false;
}

/// Applies the switch functions that reached zero at this instant (interface.md
/// section 2): a stop sets v_i = 0 exactly; every contact change first (a
/// switched contact that is only tied is decided in the last step); then the
/// friction decisions -- stopped masses by the stick rule, released masses slide
/// along A_i, Jenkins elements that reach slip_force slip and those whose
/// relative velocity reaches 0 stick (interface.md section 5; their slider
/// position is already the state's) -- and every stuck mass re-checked against the forces of the new
/// configuration, until nothing changes; then the contacts at G = G' = 0 enter
/// the state the resulting forces give them, and the friction is decided again
/// if one changed. Updates cfg, sgn (the friction direction of sliding masses),
/// appends the events to `out`; false when the decisions do not settle
/// (chattering), or when the motion comes to rest on a rigid stop (a touch,
/// G = G' = 0, whose forces press on: `*resting` is then the stop's index).
/// A rigid stop the search found reached is an impact: the velocities jump
/// (P::impact) before any friction is decided, so a friction held still
/// that the jump sets moving slides, and one sliding reverses or stops by
/// its new velocity (finite friction forces give no impulse).
template <class P>
bool apply_switches(P& p, Configuration& cfg, std::vector<signed char>& sgn,
                    const std::vector<SwitchFunction>& switched, std::vector<Transition>& out, int* resting = nullptr) {
    const int n = p.dof();
    for (const SwitchFunction& f : switched)
        if (f.kind == SwitchKind::velocity) p.stop(f.element);
    std::vector<char> is_tied(p.contacts(), 0);
    std::vector<char> deciding(static_cast<std::size_t>(n), 0);
    if (impacts(p, cfg, sgn, switched, out, deciding, resting)) return false;
    for (const SwitchFunction& f : switched) {
        if (f.kind != SwitchKind::gap || p.rigid(f.element)) continue;
        if (tied(p, p.gap_now(f.element))) {
            is_tied[static_cast<std::size_t>(f.element)] = 1;
            continue;
        }
        cfg.closed[f.element] = !cfg.closed[f.element];
        out.push_back({cfg.closed[f.element] ? EventKind::contact_close : EventKind::contact_open, f.element});
    }
    for (const SwitchFunction& f : switched) {
        const auto j = static_cast<std::size_t>(f.element);
        if (f.kind == SwitchKind::slip_pos || f.kind == SwitchKind::slip_neg) {
            cfg.slip[j] = f.kind == SwitchKind::slip_pos ? 1 : -1;
            out.push_back({EventKind::release, n + f.element});
        } else if (f.kind == SwitchKind::slip_velocity && !p.slips_on(cfg, f.element)) {
            cfg.slip[j] = 0;
            out.push_back({EventKind::stick, n + f.element});
        }
    }
    for (const SwitchFunction& f : switched) {
        const int i = f.element;
        if (f.kind == SwitchKind::velocity) {
            deciding[i] = 1;
        } else if (f.kind == SwitchKind::release_pos || f.kind == SwitchKind::release_neg) {  // a mass's
            cfg.stuck[i] = 0;
            sgn[i] = f.kind == SwitchKind::release_pos ? 1 : -1;
            out.push_back({EventKind::release, i});
        }
    }
    for (int round = 0; round < 2 * n + 4; ++round) {
        bool changed = false;
        std::vector<int> among;  // a coupled M's frictions at rest or stuck: decided together
        for (int i = 0; i < n && p.coupled(); ++i)
            if (p.has_friction(i) && (deciding[i] || cfg.stuck[static_cast<std::size_t>(i)])) among.push_back(i);
        const bool together = among.size() >= 2 && among.size() <= kMaxDecidedTogether;
        if (together) {
            const Configuration before = cfg;
            const std::vector<signed char> sgn_before = sgn;
            if (!decide_together(p, cfg, sgn, among)) return false;  // no consistent assignment: they do not settle
            for (int i : among) {  // the events, in the order of the decisions in turn below
                const auto u = static_cast<std::size_t>(i);
                if (!deciding[u]) continue;
                deciding[u] = 0;
                changed = true;
                if (cfg.stuck[u])
                    out.push_back({EventKind::stick, i});
                else if (sgn[u] != sgn_before[u])
                    out.push_back({EventKind::reversal, i});
            }
            for (int i : among) {
                const auto u = static_cast<std::size_t>(i);
                if (!before.stuck[u] || cfg.stuck[u]) continue;
                out.push_back({EventKind::release, i});
                changed = true;
            }
        }
        for (int i = 0; i < n && !together; ++i) {  // in turn: each with the others as they stand
            if (!deciding[i]) continue;
            deciding[i] = 0;
            const signed char dir = stick_rule(p, cfg, sgn, i);
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
        for (int i = 0; i < n && !together; ++i) {
            if (!cfg.stuck[i]) continue;
            const signed char dir = stick_rule(p, cfg, sgn, i);
            if (dir == 0) continue;
            cfg.stuck[i] = 0;
            sgn[i] = dir;
            out.push_back({EventKind::release, i});
            changed = true;
        }
        if (changed) continue;
        // Contacts at G = G' = 0 at this instant (a touch, or a mass stopped or
        // released on its stop) enter the state the forces of the resulting
        // configuration give them; contacts the search found crossing keep their change.
        p.prepare_ties(cfg, sgn);
        for (std::size_t c = 0; c < p.contacts(); ++c) {
            const SwitchFunction gf{SwitchKind::gap, static_cast<int>(c)};
            if (!is_tied[c] && std::find(switched.begin(), switched.end(), gf) != switched.end()) continue;
            if (!is_tied[c] && !tied(p, p.gap_now(static_cast<int>(c)))) continue;
            const int state = tied_contact_state(p, p.tied_gap_series(static_cast<int>(c), p.tie_order()));
            if (p.rigid(static_cast<int>(c))) {  // never closed: pressing on at G = G' = 0 is resting on it
                if (state != 1) continue;
                if (resting) *resting = static_cast<int>(c);
                return false;
            }
            if (state < 0 || state == cfg.closed[c]) continue;
            cfg.closed[c] = static_cast<char>(state);
            out.push_back({state ? EventKind::contact_close : EventKind::contact_open, static_cast<int>(c)});
            changed = true;
        }
        if (!changed) return true;
    }
    return false;
}

/// The friction decisions of a configuration entered from rest or carried:
/// a friction mass (or pair) with v_i != 0 slides along v_i; one at rest
/// sticks or slides by the stick rule, with the forces of `cfg` as it stands.
template <class P>
void decide_entered_friction(P& p, Configuration& cfg, std::vector<signed char>& sgn) {
    std::vector<int> at_rest;  // a coupled M's frictions at rest: decided together
    for (int i = 0; i < p.dof() && p.coupled(); ++i) {
        if (!p.has_friction(i)) continue;
        const int v = p.velocity_sign(i);
        cfg.stuck[static_cast<std::size_t>(i)] = 0;
        sgn[static_cast<std::size_t>(i)] = static_cast<signed char>(v);
        if (v == 0) at_rest.push_back(i);
    }
    if (at_rest.size() >= 2 && at_rest.size() <= kMaxDecidedTogether && decide_together(p, cfg, sgn, at_rest)) return;
    for (int i = 0; i < p.dof(); ++i) {  // in turn (none consistent together: as they stand)
        if (!p.has_friction(i)) continue;
        const int v = p.velocity_sign(i);
        if (v != 0) {
            cfg.stuck[i] = 0;
            sgn[i] = static_cast<signed char>(v);
        } else {
            const signed char dir = stick_rule(p, cfg, sgn, i);
            cfg.stuck[i] = dir == 0;
            sgn[i] = dir;
        }
    }
}

/// The configuration the motion enters at t0 (interface.md "At t0"): a contact
/// by the sign of G, then of G' (a rigid stop stays open); one with G = G' = 0 is provisionally closed (at
/// rest on the boundary) and decided by tied_contact_state once the friction is
/// decided. A friction mass with v_i != 0 slides along v_i; one at rest sticks
/// or slides by the stick rule. A tied contact carries no force (G = G' = 0), so
/// its state changes no friction decision directly; the friction is decided
/// again after any change, at most 4 rounds. `cfg` comes in all open.
template <class P>
void entered_configuration(P& p, Configuration& cfg, std::vector<signed char>& sgn) {
    sgn.assign(static_cast<std::size_t>(p.dof()), 0);
    std::vector<int> ties;
    for (std::size_t c = 0; c < p.contacts(); ++c) {
        if (p.rigid(static_cast<int>(c))) continue;  // a rigid stop is never closed (the reader checks G <= 0)
        const int s = first_nonzero_sign(p, p.gap_now(static_cast<int>(c)), 0);  // G, then G'
        cfg.closed[c] = s >= 0;
        if (s == 0) ties.push_back(static_cast<int>(c));
    }
    decide_entered_friction(p, cfg, sgn);
    for (int round = 0; round < 4 && !ties.empty(); ++round) {
        p.prepare_ties(cfg, sgn);
        bool changed = false;
        for (int c : ties) {
            const int state = tied_contact_state(p, p.tied_gap_series(c, p.tie_order()));
            if (state >= 0 && state != cfg.closed[c]) {
                cfg.closed[c] = static_cast<char>(state);
                changed = true;
            }
        }
        if (!changed) break;
        decide_entered_friction(p, cfg, sgn);
    }
}

/// The configuration a run carries across a change of its constant load (a
/// [[load_step]]): the state is continuous there, so every contact and every
/// Jenkins element keeps its state (`cfg` comes in as the run left it); only
/// friction is decided again, by the forces of the new load (a stuck mass the
/// new load pulls beyond mu_s N slides at once).
template <class P>
void carried_configuration(P& p, Configuration& cfg, std::vector<signed char>& sgn) {
    sgn.assign(static_cast<std::size_t>(p.dof()), 0);
    decide_entered_friction(p, cfg, sgn);
}

/// Whether an armed sliding velocity, h = side*v within its rounding level eps
/// of zero, with rate hd and |h''| <= B, stops here. One that has reached zero,
/// or touches it (turns back: hd >= 0), does (interface.md: a sliding velocity
/// that touches 0 is a stop). One still falling stops only where its bound says
/// that it reaches zero, h + hd s + B s^2/2 <= 0 for some s (hd^2 >= 2 B h),
/// with a rate beyond its own rounding (rate_noise(), evaluated only then: the
/// double engine's level of the equation of motion's terms; the reference's
/// 40 digits pass zero). An overdamped creep into equilibrium (w ~ exp(-lambda t),
/// |h''| ~ lambda^2 h) never does: it reaches zero only as t grows without
/// bound (tests/test_dampers.cpp DamperCreep). B + B: 2 B exactly in every
/// arithmetic, so both methods compare the same quantity.
template <class T, class RateNoise>
bool stops_here(const T& h, const T& hd, const T& B, const T& eps, const T& zero, RateNoise&& rate_noise) {
    if (h > eps) return false;
    if (h <= zero || hd >= zero) return true;
    return hd * hd >= (B + B) * h && -hd > rate_noise();
}

}  // namespace rules
}  // namespace hsnc
