// hsnc -- Coulomb friction (interface.md sections 2 and 5): on a mass
// against the ground, or a [[friction]] element against another body, along
// the relative velocity u' of its direction (direction.h; today w = e_i -
// e_partner, FrictionSlot::partner below).
//
//   sliding:  the force -mu_k N sgn(u') along w; switch velocity u'
//   stuck:    u' = 0 held; it releases when the force D it must hold (A_i
//             against the ground, assembly.h driving_force) exceeds mu_s N:
//             switches release_pos  D - mu_s N,  release_neg  -D - mu_s N
//             (two smooth functions, so that root finding never meets a kink)
//   at a stop: the stick rule (runtime/engine/transition_rules.h stick_rule)
//
// The functions below are the only place these switch functions are
// written: every back end instantiates them with its own scalar and motion.
#pragma once

#include <string>

#include "direction.h"

namespace hsnc {

/// A [[friction]] element (interface.md section 5): Coulomb friction on the
/// relative velocity v[a] - v[b] with a constant normal force. It acts through
/// the friction slot of its body (FrictionSlot::element names it).
struct FrictionElement {
    std::string name;
    int a = kGround;
    int b = kGround;
    double mu_k = 0.0;
    double mu_s = 0.0;
    double normal = 0.0;  ///< N > 0
};

/// The Coulomb friction of a model's slot (model.h Model::friction_slots):
/// slot i is mass i's, on the relative velocity v[i] - v[partner].
struct FrictionSlot {
    bool active = false;  ///< true exactly when the file gave the mass mu_k or a [[friction]] element acts on it
    double mu_k = 0.0;    ///< kinetic friction coefficient, >= 0
    double mu_s = 0.0;    ///< static coefficient, >= mu_k
    /// Index into Model::frictions of the [[friction]] element this slot
    /// stands for (its mu_k, mu_s are the element's), or -1 (the mass's own
    /// mu_k, normal force m*g).
    int element = -1;
    /// The body the friction acts against: kGround, or the other mass of a
    /// [[friction]] element between two bodies (friction on the relative
    /// velocity v[i] - v[partner]; stuck, i rides the partner). A partner may
    /// carry several riders and have a friction of its own: the partners form
    /// a forest (model_reader orients it; Model::shared_partner, whose held
    /// forces come from held_mass.h).
    int partner = kGround;
    /// The normal force N of an element that gives one (`normal`), used as
    /// given: g does not enter its friction. 0 for the weight m*g (a mass's own
    /// friction, an element without `normal`), which the exact stages form as
    /// the product m*g (Model::normal_force).
    double normal = 0.0;
};

namespace friction {

/// d^k/dt^k of the relative velocity u' while sliding (SwitchKind::velocity).
template <class M>
auto velocity_value(const Direction& d, const M& m, int k) {
    return along(d, m, k + 1);
}
template <class M>
auto velocity_magnitude(const Direction& d, const M& m, int k) {
    return along_magnitude(d, m, k + 1);
}

/// d^k/dt^k of sigma D - mu_s N while stuck (sigma = +1 release_pos, -1
/// release_neg), from D^(k) and the static limit mu_s N.
template <class T>
T release_value(int sigma, const T& D, const T& limit, int k) {
    const T s = sigma > 0 ? D : -D;
    return k == 0 ? s - limit : s;
}
/// Its magnitude, from that of D^(k)'s terms.
template <class T>
T release_magnitude(const T& D_magnitude, const T& limit, int k) {
    return k == 0 ? D_magnitude + limit : D_magnitude;
}

}  // namespace friction
}  // namespace hsnc
