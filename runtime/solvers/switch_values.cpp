#include "switch_values.h"

#include <algorithm>

#include "assembly.h"
#include "held_mass.h"

namespace hsnc {

ConfigurationTerms configuration_terms(const Model& model, const Configuration& cfg) {
    constexpr double kPi = 3.141592653589793;
    const Eigen::Index n = static_cast<Eigen::Index>(model.dof());
    ConfigurationTerms t;
    t.mass = mass_vector(model);
    t.normal.resize(n);
    t.mu_k.resize(n);
    t.mu_s.resize(n);
    t.friction.resize(static_cast<std::size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) {
        const FrictionSlot& f = model.friction_slot(static_cast<std::size_t>(i));
        t.normal(i) = model.normal_force(static_cast<std::size_t>(i));
        t.mu_k(i) = f.mu_k;
        t.mu_s(i) = f.mu_s;
        t.friction[static_cast<std::size_t>(i)] = f.active ? 1 : 0;
        t.partner.push_back(f.partner);
    }
    t.K = stiffness_matrix(model, cfg);
    t.C = damping_matrix(model, cfg);
    t.f_const = constant_force(model, cfg);
    t.contacts = model.contacts;
    t.jenkins = model.jenkins;
    if (model.coupled_friction()) {  // every stuck dof's P_i (held_mass.h)
        const HeldMass held(model, cfg.stuck);
        t.release_row.assign(static_cast<std::size_t>(n), -1);
        t.release = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(std::count(cfg.stuck.begin(), cfg.stuck.end(), 1)), n);
        for (Eigen::Index i = 0, r = 0; i < n; ++i)
            if (cfg.stuck[static_cast<std::size_t>(i)]) {
                t.release_row[static_cast<std::size_t>(i)] = static_cast<int>(r);
                t.release.row(r++) = held.release_row(static_cast<int>(i)).transpose();
            }
    }
    std::vector<const Harmonic*> dyn;
    for (const Harmonic& hm : model.forcing) {
        if (hm.omega == 0.0) {
            for (Eigen::Index i = 0; i < n; ++i) t.f_const(i) += hm.amplitude[static_cast<std::size_t>(i)] * std::sin(hm.phase);
        } else {
            dyn.push_back(&hm);
        }
    }
    const Eigen::Index nh = static_cast<Eigen::Index>(dyn.size());
    t.h_omega.resize(nh);
    t.h_phase.resize(nh);
    t.h_amp.resize(n, nh);
    for (Eigen::Index h = 0; h < nh; ++h) {
        const Harmonic& hm = *dyn[static_cast<std::size_t>(h)];
        t.h_omega(h) = std::abs(hm.omega);
        t.h_phase(h) = hm.omega > 0.0 ? hm.phase : kPi - hm.phase;
        for (Eigen::Index i = 0; i < n; ++i) t.h_amp(i, h) = hm.amplitude[static_cast<std::size_t>(i)];
    }
    return t;
}

}  // namespace hsnc
