// hsnc -- the linear system of one configuration, assembled from a Model.
//
// In configuration `cfg` every mass obeys, apart from friction,
//     M x'' = A(x, v, t),
//     A(x, v, t) = -K x - C v + f_const + sum_h F_h sin(omega_h t + phase_h),
// with K = K(cfg) (springs + closed contacts), C = alpha*M + beta*K(cfg) + the
// dampers (model.h Damper), and
// f_const = loads + contact preload (a closed contact [a, b] with gap d adds
// +k*d on a and -k*d on b; paper Eq. 5-6) + the force of every slipping
// Jenkins element. A stuck Jenkins element is a link like a closed contact
// whose gap is its slider position s (state, not a constant of the
// configuration): its preload k*s is added per segment (add_slider_preload). A_i is the force "from everything
// but friction" of interface.md section 2. Stuck masses are not removed here:
// these are the full n x n matrices.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

#include "configuration.h"
#include "elements/contact.h"
#include "elements/jenkins.h"
#include "elements/spring.h"
#include "model.h"

namespace hsnc {

/// Throws InputError "WHO: model 'NAME' has non-proportional damping ..."
/// unless model.proportional_damping(): for the stages that decouple the
/// damped equations by the modes of K (the derivation, the kernels, the
/// interpreter, the reference, the tangent), which take Rayleigh damping only.
void require_proportional_damping(const Model& model, const std::string& who);

/// Diagonal of M.
Eigen::VectorXd mass_vector(const Model& model);

/// M whole (diagonal for a lumped model).
Eigen::MatrixXd mass_matrix(const Model& model);

/// M[dofs, dofs]: the mass matrix of the masses `dofs` (model indices), in that order.
Eigen::MatrixXd mass_matrix(const Model& model, const std::vector<int>& dofs);

/// (M y)_i: m_i y_i for a lumped model, the row of a coupled M (model.h) times y.
double mass_times(const Model& model, std::size_t i, const double* y);

/// "friction between two bodies ([[friction]] 'f1')" when a [[friction]]
/// element joins two bodies (a stuck pair moves as one body), else "".
std::string friction_pairs(const Model& model);

/// The elements whose stick is not a mass held against the ground, as a
/// phrase: "Jenkins elements ([[jenkins]] 'j1')" (a slider state), else
/// friction_pairs(model).
std::string stick_elements(const Model& model);

/// Throws InputError "WHO: model 'NAME' has PHRASE, which it does not take
/// yet" unless stick_elements(model) is empty: for the stages that take
/// neither a slider nor a stuck pair (the tangent's flows, ab4's stick rules,
/// the reference, sweep kernels).
void require_no_stick_elements(const Model& model, const std::string& who);

/// K(cfg): springs plus the contacts closed and the Jenkins elements stuck in
/// cfg (stuck mass flags are ignored).
Eigen::MatrixXd stiffness_matrix(const Model& model, const Configuration& cfg);

/// C = alpha*M + beta*K(cfg) + the dampers' matrix.
Eigen::MatrixXd damping_matrix(const Model& model, const Configuration& cfg);

/// Loads plus the preload of the contacts closed in cfg plus the forces of
/// the Jenkins elements slipping in cfg.
Eigen::VectorXd constant_force(const Model& model, const Configuration& cfg);

/// f += the preload k_j*s_j (+ on a, - on b) of every Jenkins element stuck
/// in cfg, slider[j] = s_j; nothing without Jenkins elements.
void add_slider_preload(const Model& model, const Configuration& cfg, const double* slider, Eigen::VectorXd& f);

/// Slider position of Jenkins element j in state x (masses, then sliders):
/// x[n + j] while stuck; while slipping, x[a] - x[b] - slip*F_s/k (its
/// stretch is held at slip*F_s/k).
double slider_position(const Model& model, const Configuration& cfg, std::size_t j, const double* x);

/// Sum of the forcing harmonics at time t, and its time derivative.
Eigen::VectorXd forcing(const Model& model, double t);
Eigen::VectorXd forcing_rate(const Model& model, double t);

/// Gap function G_c = x[a] - x[b] - d of contact c (ground at 0), and its rate.
double gap(const Model& model, int c, const double* x);
double gap_rate(const Model& model, int c, const double* v);

}  // namespace hsnc

namespace hsnc {

/// The kinds of element between two bodies, in the order for_each_link visits them.
enum class ElementKind : std::uint32_t { spring, contact, damper, jenkins };

/// A visitor of an element's forces (model/elements/direction.h) that hands
/// its links to fn(a, b, stiffness, damping, length) and its constant forces
/// to force(a, b, f on a).
template <class Link, class Force>
struct BodyForces {
    Link& link_fn;
    Force& force_fn;
    void link(const Direction& d, double k, double c, double length) { link_fn(d.a, d.b, k, c, length); }
    void force(const Direction& d, double f) { force_fn(d.a, d.b, f); }
    double zero() const { return 0.0; }
};
template <class Link, class Force>
BodyForces<Link, Force> body_forces(Link& link, Force& force) {
    return {link, force};
}

/// Element e of `kind` in cfg through the visitor of body_forces(link,
/// force): its links and its constant forces (its file in model/elements/
/// says which).
template <class Link, class Force>
void visit_element(const Model& model, const Configuration& cfg, ElementKind kind, std::size_t e, Link&& link,
                   Force&& force, const double* slider) {
    auto bodies = body_forces(link, force);
    auto v = pair_links(bodies, [](double w) { return w; });
    switch (kind) {
        case ElementKind::spring:
            spring::forces(model.springs[e].direction(), model.springs[e].k, model.beta, v);
            break;
        case ElementKind::contact: {
            const Contact& c = model.contacts[e];
            contact::forces(cfg.closed[e] != 0, c.direction(), c.k, c.gap, model.beta, c.c, v);
            break;
        }
        case ElementKind::damper:
            damper::forces(model.dampers[e].direction(), model.dampers[e].c, v);
            break;
        case ElementKind::jenkins: {
            const Jenkins& j = model.jenkins[e];
            jenkins::forces(cfg.slip[e], j.direction(), j.k, j.slip_force, slider ? slider[e] : 0.0, model.beta, v);
            break;
        }
    }
}

/// Element e of `kind` as a link in cfg, fn(a, b, stiffness, damping, length),
/// when it acts as one: a spring or a closed contact (damping beta*k,
/// Rayleigh), a damper (stiffness 0, damping c), a stuck Jenkins element (as
/// a closed contact, length = slider[e]; 0 when `slider` is null: for the
/// callers that do not read the length); length is a link's preload length.
/// A link along a general direction comes as the pair links of
/// as_pair_links (direction.h), length 0: its preload is a constant force
/// (constant_of).
template <class Fn>
void link_of(const Model& model, const Configuration& cfg, ElementKind kind, std::size_t e, Fn&& fn,
             const double* slider = nullptr) {
    visit_element(model, cfg, kind, e, fn, [](int, int, double) {}, slider);
}

/// Every element acting between two bodies in cfg, as link_of gives it:
/// springs, contacts, dampers, then Jenkins elements, each kind in model order.
template <class Fn>
void for_each_link(const Model& model, const Configuration& cfg, Fn&& fn, const double* slider = nullptr) {
    for (std::size_t e = 0; e < model.springs.size(); ++e) link_of(model, cfg, ElementKind::spring, e, fn, slider);
    for (std::size_t e = 0; e < model.contacts.size(); ++e) link_of(model, cfg, ElementKind::contact, e, fn, slider);
    for (std::size_t e = 0; e < model.dampers.size(); ++e) link_of(model, cfg, ElementKind::damper, e, fn, slider);
    for (std::size_t e = 0; e < model.jenkins.size(); ++e) link_of(model, cfg, ElementKind::jenkins, e, fn, slider);
}

/// Element e's constant forces in cfg as fn(a, b, force on a) (the opposite
/// on b): a slipping Jenkins element's, and the preload k length w_i of a
/// link along a general direction, as (i, kGround, f_i).
template <class Fn>
void constant_of(const Model& model, const Configuration& cfg, ElementKind kind, std::size_t e, Fn&& fn,
                 const double* slider = nullptr) {
    visit_element(model, cfg, kind, e, [](int, int, double, double, double) {}, fn, slider);
}

/// Every element's constant forces in cfg, as constant_of gives them, in
/// for_each_link's order.
template <class Fn>
void for_each_constant(const Model& model, const Configuration& cfg, Fn&& fn, const double* slider = nullptr) {
    for (std::size_t e = 0; e < model.contacts.size(); ++e)
        if (model.contacts[e].direction().weighted()) constant_of(model, cfg, ElementKind::contact, e, fn, slider);
    for (std::size_t e = 0; e < model.jenkins.size(); ++e) constant_of(model, cfg, ElementKind::jenkins, e, fn, slider);
}

/// The elements touching each mass (springs, contacts, dampers, Jenkins
/// elements), in the order for_each_link visits them. force_on_mass given one
/// visits a mass's own elements, O(its degree) where the model's whole list is
/// O(n): the engine's friction decisions ask for the force on every stuck
/// mass, several times per event. The same terms in the same order, so the
/// same bits. Built once per model (its element lists only; parameters may
/// change).
class ElementIndex {
public:
    explicit ElementIndex(const Model& model);
    /// Mass i's elements, each (kind << 28 | index), springs first, then
    /// contacts, dampers and Jenkins elements, each kind in model order.
    const std::uint32_t* begin(int i) const { return codes_.data() + start_[static_cast<std::size_t>(i)]; }
    const std::uint32_t* end(int i) const { return codes_.data() + start_[static_cast<std::size_t>(i) + 1]; }
    static ElementKind kind(std::uint32_t code) { return static_cast<ElementKind>(code >> 28); }
    static std::size_t index(std::uint32_t code) { return code & ((1u << 28) - 1); }

private:
    std::vector<std::size_t> start_;
    std::vector<std::uint32_t> codes_;
};

/// A_i: force on mass i from everything but its own friction (springs, closed
/// contacts, Rayleigh damping, dampers, Jenkins elements, forcing, loads) at
/// time t and state (x, v), in cfg; x holds the sliders after the masses.
/// No allocation; with `elements`, loops over the elements touching i only.
double force_on_mass(const Model& model, const Configuration& cfg, int i, double t, const double* x,
                     const double* v, const ElementIndex* elements = nullptr);

/// dA_i/dt at (t, v, a): the time derivative of force_on_mass.
double force_rate_on_mass(const Model& model, const Configuration& cfg, int i, double t, const double* v,
                          const double* a);

/// The body mass i moves with in cfg: i itself while its friction is not
/// stuck; else, following the partners of stuck frictions, the first body
/// whose friction is not stuck (i rides it), or kGround when that chain ends
/// at the ground (i is held still). Without chains of frictions (a partner
/// with a friction of its own) that is i's partner.
inline int carrier(const Model& model, const Configuration& cfg, std::size_t i) {
    int b = static_cast<int>(i);
    while (b != kGround && cfg.stuck[static_cast<std::size_t>(b)])
        b = model.friction_slot(static_cast<std::size_t>(b)).partner;
    return b;
}
/// Mass i is held still in cfg: stuck against the ground, or on a body held still.
inline bool fixed_in(const Model& model, const Configuration& cfg, std::size_t i) {
    return cfg.stuck[i] && carrier(model, cfg, i) == kGround;
}
/// Mass i moves with another body in cfg (a stuck pair: one body; carrier()).
inline bool rides_partner(const Model& model, const Configuration& cfg, std::size_t i) {
    return cfg.stuck[i] && carrier(model, cfg, i) != kGround;
}
/// S_i, the dofs the stuck friction of dof i carries: i, then in dof order
/// every dof stuck on it, directly or up a chain of stuck frictions (the
/// force that friction holds is theirs less their mass times the body's
/// acceleration: model/held_mass.h).
inline std::vector<int> carried(const Model& model, const std::vector<char>& stuck, int i) {
    std::vector<int> S{i};
    for (std::size_t k = 0; k < stuck.size(); ++k) {
        if (!stuck[k] || static_cast<int>(k) == i) continue;
        for (int p = model.friction_slot(k).partner; p != kGround;
             p = model.friction_slot(static_cast<std::size_t>(p)).partner) {
            if (p == i) S.push_back(static_cast<int>(k));
            if (p == i || !stuck[static_cast<std::size_t>(p)]) break;
        }
    }
    return S;
}

/// A quantity of mass i (mass mi) in the frame of its pair with p (mass mp)
/// moving as one body, (m_p a_i - m_i a_p)/(m_i + m_p): the force that keeps
/// them together (driving_force), its rate, series, rows and bounds.
inline double against_partner(double mi, double mp, double ai, double ap) { return (mp * ai - mi * ap) / (mi + mp); }
/// The magnitude of its terms from the magnitudes of a_i's and a_p's.
inline double against_partner_magnitude(double mi, double mp, double mag_i, double mag_p) {
    return (mp * mag_i + mi * mag_p) / (mi + mp);
}

/// The force that mass i's friction must hold to keep its relative velocity
/// w = v[i] - v[partner] at 0 (interface.md: it sticks while this is below
/// mu_s N): against the ground A_i; against a partner p, moving as one body
/// of mass m_i + m_p, D_i = (m_p A_i - m_i A_p)/(m_i + m_p).
double driving_force(const Model& model, const Configuration& cfg, int i, double t, const double* x, const double* v,
                     const ElementIndex* elements = nullptr);

/// dD_i/dt at (t, v, a).
double driving_force_rate(const Model& model, const Configuration& cfg, int i, double t, const double* v,
                          const double* a);

}  // namespace hsnc
