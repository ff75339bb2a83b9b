#include "assembly.h"

#include <cmath>

#include "elements/contact.h"
#include "elements/jenkins.h"
#include "elements/motion.h"
#include "error.h"

namespace hsnc {
namespace {

// Add a spring of stiffness k between bodies a and b to K.
void add_spring(Eigen::MatrixXd& K, int a, int b, double k) {
    if (a != kGround) K(a, a) += k;
    if (b != kGround) K(b, b) += k;
    if (a != kGround && b != kGround) {
        K(a, b) -= k;
        K(b, a) -= k;
    }
}

double position(const double* x, int body) { return body == kGround ? 0.0 : x[body]; }

}  // namespace

void require_proportional_damping(const Model& model, const std::string& who) {
    if (model.proportional_damping()) return;
    throw InputError(who + ": model '" + model.name +
                     "' has non-proportional damping ([[damper]] or a non-proportional structure.damping); "
                     "only the generic solver (state-space modes) takes it, for now");
}

std::string friction_pairs(const Model& model) {
    for (std::size_t i = 0; i < model.dof(); ++i)
        if (model.has_friction(i) && model.friction_slot(i).partner != kGround)
            return "friction between two bodies ([[friction]] '" + model.friction_name(i) + "')";
    return "";
}

std::string stick_elements(const Model& model) {
    if (!model.jenkins.empty()) return "Jenkins elements ([[jenkins]] '" + model.jenkins[0].name + "')";
    return friction_pairs(model);
}

void require_no_stick_elements(const Model& model, const std::string& who) {
    const std::string what = stick_elements(model);
    if (what.empty()) return;
    throw InputError(who + ": model '" + model.name + "' has " + what + ", which it does not take yet");
}

Eigen::VectorXd mass_vector(const Model& model) {
    Eigen::VectorXd m(model.dof());
    for (std::size_t i = 0; i < model.dof(); ++i) m(i) = model.masses[i].m;
    return m;
}

Eigen::MatrixXd mass_matrix(const Model& model) {
    const auto n = static_cast<Eigen::Index>(model.dof());
    if (!model.coupled_mass()) return mass_vector(model).asDiagonal();
    Eigen::MatrixXd M(n, n);
    for (Eigen::Index i = 0; i < n; ++i)
        for (Eigen::Index j = 0; j < n; ++j)
            M(i, j) = model.mass_entry(static_cast<std::size_t>(i), static_cast<std::size_t>(j));
    return M;
}

Eigen::MatrixXd mass_matrix(const Model& model, const std::vector<int>& dofs) {
    const auto n = static_cast<Eigen::Index>(dofs.size());
    Eigen::MatrixXd M(n, n);
    for (Eigen::Index r = 0; r < n; ++r)
        for (Eigen::Index c = 0; c < n; ++c)
            M(r, c) = model.mass_entry(static_cast<std::size_t>(dofs[static_cast<std::size_t>(r)]),
                                       static_cast<std::size_t>(dofs[static_cast<std::size_t>(c)]));
    return M;
}

double mass_times(const Model& model, std::size_t i, const double* y) {
    if (!model.coupled_mass()) return model.masses[i].m * y[i];
    const std::size_t n = model.dof();
    double s = 0.0;
    for (std::size_t j = 0; j < n; ++j) s += model.mass_matrix[i * n + j] * y[j];
    return s;
}

Eigen::MatrixXd stiffness_matrix(const Model& model, const Configuration& cfg) {
    const auto n = static_cast<Eigen::Index>(model.dof());
    Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, n);
    for_each_link(model, cfg, [&](int a, int b, double k, double, double) {
        if (k != 0.0) add_spring(K, a, b, k);  // a dashpot: stiffness 0
    });
    return K;
}

Eigen::MatrixXd damping_matrix(const Model& model, const Configuration& cfg) {
    Eigen::MatrixXd C = model.beta * stiffness_matrix(model, cfg);
    if (model.coupled_mass()) C += model.alpha * mass_matrix(model);
    else C.diagonal() += model.alpha * mass_vector(model);
    for (std::size_t e = 0; e < model.dampers.size(); ++e)  // a dashpot adds to C as a spring to K
        link_of(model, cfg, ElementKind::damper, e, [&](int a, int b, double, double c, double) { add_spring(C, a, b, c); });
    for (std::size_t e = 0; e < model.contacts.size(); ++e) {  // a closed contact's own c w w^T (contact.h)
        const Contact& ct = model.contacts[e];
        if (!cfg.closed[e] || ct.c == 0.0) continue;
        for_each_term(ct.direction(), [&](int i, double wi) {
            for_each_term(ct.direction(), [&](int j, double wj) { C(i, j) += ct.c * wi * wj; });
        });
    }
    return C;
}

Eigen::VectorXd constant_force(const Model& model, const Configuration& cfg) {
    Eigen::VectorXd f = Eigen::Map<const Eigen::VectorXd>(model.load.data(),
                                                          static_cast<Eigen::Index>(model.dof()));
    // A link -k (u - length) along w: the constant part +k length w (paper Eq. 6); the
    // stuck sliders' lengths are state (add_slider_preload).
    for_each_link(model, cfg, [&](int a, int b, double k, double, double length) {
        if (k == 0.0 || length == 0.0) return;
        if (a != kGround) f(a) += k * length;
        if (b != kGround) f(b) -= k * length;
    });
    for_each_constant(model, cfg, [&](int a, int b, double fa) {
        if (a != kGround) f(a) += fa;
        if (b != kGround) f(b) -= fa;
    });
    return f;
}

void add_slider_preload(const Model& model, const Configuration& cfg, const double* slider, Eigen::VectorXd& f) {
    for (std::size_t j = 0; j < model.jenkins.size(); ++j) {
        if (model.jenkins[j].direction().weighted()) {  // k s w: a constant force of the pair links (direction.h)
            if (cfg.slip[j] == 0)
                constant_of(
                    model, cfg, ElementKind::jenkins, j, [&](int a, int, double fa) { f(a) += fa; }, slider);
            continue;
        }
        link_of(model, cfg, ElementKind::jenkins, j, [&](int a, int b, double k, double, double length) {
            if (a != kGround) f(a) += k * length;
            if (b != kGround) f(b) -= k * length;
        }, slider);
    }
}

double slider_position(const Model& model, const Configuration& cfg, std::size_t j, const double* x) {
    if (cfg.slip[j] == 0) return x[model.dof() + j];
    const Jenkins& e = model.jenkins[j];
    const double* rows[] = {x};
    return along(e.direction(), double_motion(rows), 0) - jenkins::held_stretch(cfg.slip[j], e.k, e.slip_force);
}

Eigen::VectorXd forcing(const Model& model, double t) {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(model.dof()));
    for (const Harmonic& h : model.forcing) {
        const double s = std::sin(h.omega * t + h.phase);
        for (std::size_t i = 0; i < model.dof(); ++i) f(i) += h.amplitude[i] * s;
    }
    return f;
}

Eigen::VectorXd forcing_rate(const Model& model, double t) {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(model.dof()));
    for (const Harmonic& h : model.forcing) {
        const double c = h.omega * std::cos(h.omega * t + h.phase);
        for (std::size_t i = 0; i < model.dof(); ++i) f(i) += h.amplitude[i] * c;
    }
    return f;
}

double gap(const Model& model, int c, const double* x) {
    const Contact& k = model.contacts[static_cast<std::size_t>(c)];
    const double* rows[] = {x};
    return contact::gap_value(k.direction(), k.gap, double_motion(rows), 0);
}

double gap_rate(const Model& model, int c, const double* v) {
    const Contact& k = model.contacts[static_cast<std::size_t>(c)];
    const double* rows[] = {nullptr, v};
    return contact::gap_value(k.direction(), k.gap, double_motion(rows), 1);
}

}  // namespace hsnc

namespace hsnc {

ElementIndex::ElementIndex(const Model& model) {
    const std::size_t n = model.dof();
    std::vector<std::vector<std::uint32_t>> of(n);
    auto put = [&](ElementKind k, std::size_t e, const Direction& d) {
        const std::uint32_t code = static_cast<std::uint32_t>(k) << 28 | static_cast<std::uint32_t>(e);
        for_each_term(d, [&](int body, double) {
            auto& list = of[static_cast<std::size_t>(body)];
            if (list.empty() || list.back() != code) list.push_back(code);
        });
    };
    for (std::size_t e = 0; e < model.springs.size(); ++e) put(ElementKind::spring, e, model.springs[e].direction());
    for (std::size_t e = 0; e < model.contacts.size(); ++e) put(ElementKind::contact, e, model.contacts[e].direction());
    for (std::size_t e = 0; e < model.dampers.size(); ++e) put(ElementKind::damper, e, model.dampers[e].direction());
    for (std::size_t e = 0; e < model.jenkins.size(); ++e) put(ElementKind::jenkins, e, model.jenkins[e].direction());
    start_.assign(n + 1, 0);
    for (std::size_t i = 0; i < n; ++i) {
        start_[i + 1] = start_[i] + of[i].size();
        codes_.insert(codes_.end(), of[i].begin(), of[i].end());
    }
}

double force_on_mass(const Model& model, const Configuration& cfg, int i, double t, const double* x,
                     const double* v, const ElementIndex* elements) {
    const std::size_t ii = static_cast<std::size_t>(i);
    double f = model.load[ii] - (model.coupled_mass() ? model.alpha * mass_times(model, ii, v)
                                                      : model.alpha * model.masses[ii].m * v[i]);  // (alpha m) v
    for (const Harmonic& h : model.forcing) f += h.amplitude[i] * std::sin(h.omega * t + h.phase);
    // A link of stiffness k and damping c stretched by s = x[a] - x[b] - d pulls a with
    // -k*s - c*s' and pushes b with the opposite: a spring or closed contact has
    // c = beta*k (C = alpha*M + beta*K(cfg)), a damper k = 0.
    auto add = [&](int a, int b, double k, double c, double d) {
        if (a != i && b != i) return;
        const double s = position(x, a) - position(x, b) - d;
        const double sd = position(v, a) - position(v, b);
        const double fa = -k * s - c * sd;
        f += a == i ? fa : -fa;
    };
    auto slipping = [&](int a, int b, double fa) {
        if (a == i) f += fa;
        if (b == i) f -= fa;
    };
    if (!elements) {
        for_each_link(model, cfg, add, x + model.dof());
        for_each_constant(model, cfg, slipping, x + model.dof());
        return f;
    }
    // The same links in the same order (for_each_link's, then for_each_constant's), mass i's alone.
    for (const std::uint32_t* e = elements->begin(i); e != elements->end(i); ++e)
        link_of(model, cfg, ElementIndex::kind(*e), ElementIndex::index(*e), add, x + model.dof());
    for (const std::uint32_t* e = elements->begin(i); e != elements->end(i); ++e) {
        const ElementKind kind = ElementIndex::kind(*e);
        const std::size_t j = ElementIndex::index(*e);
        if (kind == ElementKind::jenkins || (kind == ElementKind::contact && model.contacts[j].direction().weighted()))
            constant_of(model, cfg, kind, j, slipping, x + model.dof());
    }
    return f;
}

}  // namespace hsnc

namespace hsnc {

namespace {

// A_i against the ground; against a partner p, against_partner(.., A_i, A_p)
// with A_p = of(p): the force on i in the frame of the pair moving as one body.
template <class Of>
double on_partner(const Model& model, int i, double Ai, Of&& of) {
    const int p = model.friction_slot(static_cast<std::size_t>(i)).partner;
    if (p == kGround) return Ai;
    return against_partner(model.masses[static_cast<std::size_t>(i)].m, model.masses[static_cast<std::size_t>(p)].m, Ai,
                           of(p));
}

}  // namespace

double driving_force(const Model& model, const Configuration& cfg, int i, double t, const double* x, const double* v,
                     const ElementIndex* elements) {
    return on_partner(model, i, force_on_mass(model, cfg, i, t, x, v, elements),
                           [&](int p) { return force_on_mass(model, cfg, p, t, x, v, elements); });
}

double driving_force_rate(const Model& model, const Configuration& cfg, int i, double t, const double* v,
                          const double* a) {
    return on_partner(model, i, force_rate_on_mass(model, cfg, i, t, v, a),
                           [&](int p) { return force_rate_on_mass(model, cfg, p, t, v, a); });
}

double force_rate_on_mass(const Model& model, const Configuration& cfg, int i, double t, const double* v,
                          const double* a) {
    const std::size_t ii = static_cast<std::size_t>(i);
    double f = model.coupled_mass() ? -model.alpha * mass_times(model, ii, a) : -model.alpha * model.masses[ii].m * a[i];
    for (const Harmonic& h : model.forcing) f += h.amplitude[i] * h.omega * std::cos(h.omega * t + h.phase);
    auto add = [&](int p, int q, double k, double c, double) {
        if (p != i && q != i) return;
        const double sd = position(v, p) - position(v, q);
        const double sdd = position(a, p) - position(a, q);
        const double fa = -k * sd - c * sdd;
        f += p == i ? fa : -fa;
    };
    for_each_link(model, cfg, add);
    return f;
}

}  // namespace hsnc
