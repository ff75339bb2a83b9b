#include "switch_values.h"

#include "assembly.h"

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
        const Mass& m = model.masses[static_cast<std::size_t>(i)];
        t.normal(i) = model.normal_force(static_cast<std::size_t>(i));
        t.mu_k(i) = m.mu_k;
        t.mu_s(i) = m.mu_s;
        t.friction[static_cast<std::size_t>(i)] = m.has_friction ? 1 : 0;
        t.partner.push_back(m.partner);
    }
    t.K = stiffness_matrix(model, cfg);
    t.C = damping_matrix(model, cfg);
    t.f_const = constant_force(model, cfg);
    t.contact_gap.resize(static_cast<Eigen::Index>(model.contacts.size()));
    for (std::size_t c = 0; c < model.contacts.size(); ++c) {
        t.contact_a.push_back(model.contacts[c].a);
        t.contact_b.push_back(model.contacts[c].b);
        t.contact_gap(static_cast<Eigen::Index>(c)) = model.contacts[c].gap;
    }
    const Eigen::Index nj = static_cast<Eigen::Index>(model.jenkins.size());
    t.jenkins_k.resize(nj);
    t.jenkins_fs.resize(nj);
    for (Eigen::Index j = 0; j < nj; ++j) {
        const Jenkins& e = model.jenkins[static_cast<std::size_t>(j)];
        t.jenkins_a.push_back(e.a);
        t.jenkins_b.push_back(e.b);
        t.jenkins_k(j) = e.k;
        t.jenkins_fs(j) = e.slip_force;
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
