// hsnc -- the switch function of any kind (switch_function.h) from its
// element's file, dispatched once for every back end.
//
// A back end supplies its view P of the elements' parameters in its scalar:
//     P::contact(e)  -> {Direction d; T gap}            (contact.h)
//     P::jenkins(e)  -> {Direction d; T k, slip_force, s}  (jenkins.h; s the slider now)
//     P::friction(e) -> Direction                        (friction.h; mass e against its partner)
// and a motion M (direction.h). The release kinds are the friction force a
// stuck body must hold against mu_s N; that force is the structure's, so the
// back end computes it and hands it to friction::release_value; these two
// functions take every other kind.
#pragma once

#include <stdexcept>
#include <utility>

#include "elements/contact.h"
#include "elements/friction.h"
#include "elements/jenkins.h"
#include "model.h"
#include "switch_function.h"

namespace hsnc {

/// Whether f is a release function (its force comes from the back end).
inline bool is_release(SwitchKind k) { return k == SwitchKind::release_pos || k == SwitchKind::release_neg; }

/// The view P of a Model's elements in scalar T: each parameter through
/// convert(double) -> T, the slider of Jenkins element j through slider(j).
template <class T, class Convert, class Slider>
class ModelElements {
public:
    struct ContactView {
        Direction d;
        T gap;
    };
    struct JenkinsView {
        Direction d;
        T k, slip_force, s;
    };
    ModelElements(const Model& model, Convert convert, Slider slider)
        : model_(model), convert_(std::move(convert)), slider_(std::move(slider)) {}
    ContactView contact(int e) const {
        const Contact& c = model_.contacts[static_cast<std::size_t>(e)];
        return {c.direction(), convert_(c.gap)};
    }
    JenkinsView jenkins(int e) const {
        const Jenkins& j = model_.jenkins[static_cast<std::size_t>(e)];
        return {j.direction(), convert_(j.k), convert_(j.slip_force), slider_(e)};
    }
    Direction friction(int e) const { return {e, model_.friction_slot(static_cast<std::size_t>(e)).partner}; }

private:
    const Model& model_;
    Convert convert_;
    Slider slider_;
};

template <class T, class Convert, class Slider>
ModelElements<T, Convert, Slider> model_elements(const Model& model, Convert convert, Slider slider) {
    return {model, std::move(convert), std::move(slider)};
}

/// d^k/dt^k of switch function f (any kind but the release kinds).
template <class P, class M>
auto switch_derivative(const P& p, const SwitchFunction& f, const M& m, int k) {
    switch (f.kind) {
        case SwitchKind::gap: {
            const auto c = p.contact(f.element);
            return contact::gap_value(c.d, c.gap, m, k);
        }
        case SwitchKind::velocity: return friction::velocity_value(p.friction(f.element), m, k);
        case SwitchKind::slip_pos:
        case SwitchKind::slip_neg: {
            const auto j = p.jenkins(f.element);
            return jenkins::slip_value(f.kind == SwitchKind::slip_pos ? 1 : -1, j.k, j.slip_force, j.d, j.s, m, k);
        }
        case SwitchKind::slip_velocity: return jenkins::slip_velocity_value(p.jenkins(f.element).d, m, k);
        case SwitchKind::release_pos:
        case SwitchKind::release_neg: break;
    }
    throw std::logic_error("switch_derivative(): a release function's force is the back end's");
}

/// The magnitude of the terms of d^k/dt^k of f (any kind but the release kinds).
template <class P, class M>
auto switch_magnitude(const P& p, const SwitchFunction& f, const M& m, int k) {
    switch (f.kind) {
        case SwitchKind::gap: {
            const auto c = p.contact(f.element);
            return contact::gap_magnitude(c.d, c.gap, m, k);
        }
        case SwitchKind::velocity: return friction::velocity_magnitude(p.friction(f.element), m, k);
        case SwitchKind::slip_pos:
        case SwitchKind::slip_neg: {
            const auto j = p.jenkins(f.element);
            return jenkins::slip_magnitude(j.k, j.slip_force, j.d, j.s, m, k);
        }
        case SwitchKind::slip_velocity: return jenkins::slip_velocity_magnitude(p.jenkins(f.element).d, m, k);
        case SwitchKind::release_pos:
        case SwitchKind::release_neg: break;
    }
    throw std::logic_error("switch_magnitude(): a release function's force is the back end's");
}

}  // namespace hsnc
