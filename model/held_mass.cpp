#include "held_mass.h"

#include "assembly.h"
#include "elements/direction.h"
#include "error.h"

namespace hsnc {

void HeldMass::hold(const Model& model, const std::vector<char>& held) {
    if (model_ == &model && held == held_) return;
    model_ = &model;
    held_ = held;
    free_.clear();
    for (std::size_t i = 0; i < held.size(); ++i)
        if (!held[i]) free_.push_back(static_cast<int>(i));
    llt_.compute(mass_matrix(model, free_));
    if (llt_.info() != Eigen::Success) throw RunError("HeldMass: M_FF is not positive definite");
    rhs_.resize(static_cast<Eigen::Index>(free_.size()));
}

void HeldMass::accelerations(const double* f, double* a) const {
    for (std::size_t r = 0; r < free_.size(); ++r) rhs_(static_cast<Eigen::Index>(r)) = f[free_[r]];
    const Eigen::VectorXd aF = llt_.solve(rhs_);
    for (std::size_t i = 0; i < held_.size(); ++i) a[i] = 0.0;
    for (std::size_t r = 0; r < free_.size(); ++r) a[free_[r]] = aF(static_cast<Eigen::Index>(r));
}

double HeldMass::held_force(int i, const double* f, const double* a) const {
    return f[i] - mass_times(*model_, static_cast<std::size_t>(i), a);
}

Eigen::VectorXd HeldMass::release_row(int i) const {
    const auto n = static_cast<Eigen::Index>(held_.size());
    Eigen::VectorXd MFi(static_cast<Eigen::Index>(free_.size()));
    for (std::size_t r = 0; r < free_.size(); ++r)
        MFi(static_cast<Eigen::Index>(r)) = model_->mass_entry(static_cast<std::size_t>(free_[r]), static_cast<std::size_t>(i));
    const Eigen::VectorXd w = llt_.solve(MFi);  // M_FF^-1 M_Fi
    Eigen::VectorXd P = Eigen::VectorXd::Zero(n);
    P(i) = 1.0;
    for (std::size_t r = 0; r < free_.size(); ++r) P(free_[r]) = -w(static_cast<Eigen::Index>(r));
    return P;
}

Eigen::MatrixXd HeldMass::inverse() const {
    const auto n = static_cast<Eigen::Index>(held_.size()), nf = static_cast<Eigen::Index>(free_.size());
    const Eigen::MatrixXd inv = llt_.solve(Eigen::MatrixXd::Identity(nf, nf));
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n, n);
    for (Eigen::Index r = 0; r < nf; ++r)
        for (Eigen::Index c = 0; c < nf; ++c) out(free_[static_cast<std::size_t>(r)], free_[static_cast<std::size_t>(c)]) = inv(r, c);
    return out;
}

void kinetic_friction(const Model& model, const std::vector<char>& held, const signed char* sgn, double* fr) {
    for (std::size_t k = 0; k < model.dof(); ++k)
        fr[k] = !held[k] && model.has_friction(k)
                    ? -model.friction_slot(k).mu_k * model.normal_force(k) * static_cast<double>(sgn[k])
                    : 0.0;
}

void held_forces(const Model& model, const Configuration& cfg, const std::vector<char>& held, const signed char* sgn,
                 double t, const double* x, const double* v, double* f) {
    kinetic_friction(model, held, sgn, f);
    for (std::size_t k = 0; k < model.dof(); ++k) f[k] += force_on_mass(model, cfg, static_cast<int>(k), t, x, v);
}

void held_driving_force(const Model& model, const Configuration& cfg, const signed char* sgn, int i, double t,
                        const double* x, const double* v, double& D, double& rate) {
    Configuration hold = cfg;
    hold.stuck[static_cast<std::size_t>(i)] = 1;
    const HeldMass hm(model, hold.stuck);
    const std::size_t n = model.dof();
    std::vector<double> f(n), a(n), df(n), j(n);
    held_forces(model, hold, hold.stuck, sgn, t, x, v, f.data());
    hm.accelerations(f.data(), a.data());
    D = hm.held_force(i, f.data(), a.data());
    // The friction forces are constant along the held motion: f' = A'(v, a).
    for (std::size_t k = 0; k < n; ++k) df[k] = force_rate_on_mass(model, hold, static_cast<int>(k), t, v, a.data());
    hm.accelerations(df.data(), j.data());
    rate = hm.held_force(i, df.data(), j.data());
}

double impact_direction(const Model& model, int c, std::vector<double>& w, std::vector<double>& Mw) {
    const std::size_t n = model.dof();
    w.assign(n, 0.0);
    Mw.assign(n, 0.0);
    for_each_term(model.contacts[static_cast<std::size_t>(c)].direction(),
                  [&](int i, double wi) { w[static_cast<std::size_t>(i)] += wi; });
    if (model.coupled_mass())
        HeldMass(model, std::vector<char>(n, 0)).accelerations(w.data(), Mw.data());
    else
        for (std::size_t i = 0; i < n; ++i) Mw[i] = w[i] / model.masses[i].m;
    double wMw = 0.0;
    for (std::size_t i = 0; i < n; ++i) wMw += w[i] * Mw[i];
    return wMw;
}

}  // namespace hsnc
