// hsnc -- the contact element (interface.md, [[contact]]): a unilateral
// spring of stiffness k with a gap, along its direction u (direction.h).
//
//   G = u - gap                 the gap function; the contact is closed while G >= 0
//   closed: force -k G - c G' along w  (K += k w w^T, the preload +k gap w in the
//                                constant force, damping (beta k + c) w w^T: assembly.h;
//                                c > 0 makes the damping non-proportional)
//   open:   no force
//   switch: G itself (SwitchKind::gap); a crossing toggles the state, a touch
//           (G = G' = 0) is decided by the first non-zero derivative
//           (runtime/engine/transition_rules.h tied_contact_state)
//   rigid:  with `restitution = e` (0 < e <= 1) the contact is a rigid stop,
//           never closed: G reaching 0 is an impact (Newton's law), the
//           velocity jump that makes G' = -e G' with the impulse along w
//           (impact() below); a motion that comes to rest on the stop is
//           refused (runtime/engine/transition_rules.h)
//
// The functions below are the only place G and its derivatives are written:
// the Eigen solvers, the event rules, the tie series, the baselines, the
// 30-digit reference and the symbolic derivation instantiate them.
#pragma once

#include <string>
#include <vector>

#include "direction.h"

namespace hsnc {

struct Contact {
    std::string name;
    int a = kGround;
    int b = kGround;
    double gap = 0.0;  ///< closed while u = w^T x >= gap
    double k = 0.0;    ///< contact stiffness, > 0
    double c = 0.0;    ///< contact damping, >= 0: a dashpot c w w^T while closed (non-proportional)
    /// Newton's coefficient of restitution e, 0 < e <= 1, of a rigid stop (k
    /// and c are then 0 and the contact never closes); 0 for a spring contact.
    double restitution = 0.0;
    /// A general direction (`direction = { dof = w, ... }`): u = sum w_i x_i;
    /// empty for `between = [a, b]`, u = x[a] - x[b].
    std::vector<Weight> weights;

    Direction direction() const {
        return {a, b, weights.empty() ? nullptr : weights.data(), static_cast<int>(weights.size())};
    }
    /// A rigid stop with restitution (impacts), not a spring.
    bool rigid() const { return restitution > 0.0; }
};

namespace contact {

/// G^(k) = u^(k) - [k = 0] gap.
template <class M, class T>
auto gap_value(const Direction& d, const T& gap, const M& m, int k) {
    auto u = along(d, m, k);
    return k == 0 ? u - gap : u;
}

/// The magnitude of G^(k)'s terms.
template <class M, class T>
auto gap_magnitude(const Direction& d, const T& gap, const M& m, int k) {
    auto u = along_magnitude(d, m, k);
    return k == 0 ? u + m.abs(gap) : u;
}

/// Closed, a contact is a link of stiffness k, damping beta k (Rayleigh)
/// plus its own c, and rest length gap (its preload +k gap on a); open,
/// nothing.
/// The spring's force magnitude at gap function G, k G while closed (G > 0),
/// 0 open (its force on body a is minus this along w), and its energy
/// 1/2 k G^2 (0 open).
template <class T>
T spring_force(const T& k, const T& G) {
    return G > 0 ? k * G : T(0);
}
template <class T>
T energy(const T& k, const T& G) {
    return G > 0 ? T(0.5) * k * G * G : T(0);
}

template <class T, class V>
void forces(bool closed, const Direction& d, const T& k, const T& gap, const T& beta, const T& c, V&& visit) {
    if (closed) visit.link(d, k, beta * k + c, gap);
}

/// Newton's impact law on a rigid stop, for any scalar T: the velocity jump
/// dv = -(1 + e) G' M^-1 w / (w^T M^-1 w) at the instant G = 0, the impulse
/// along w (a body's finite forces, friction included, give none), so that
/// G' becomes -e G' and the momentum normal to w is kept. `Minv_w` is M^-1 w
/// over every body and `wMw` = w^T M^-1 w (the back end's solve with its M,
/// its own arithmetic), `rate` is G' before; dv is added to v.
template <class T>
void impact(const T& e, const T& rate, const T& wMw, const std::vector<T>& Minv_w, T* v, const T& one) {
    const T scale = (one + e) * rate / wMw;
    for (std::size_t i = 0; i < Minv_w.size(); ++i) v[i] = v[i] - scale * Minv_w[i];
}

}  // namespace contact
}  // namespace hsnc
