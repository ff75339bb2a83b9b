#include "held_mass.h"

#include "assembly.h"
#include "elements/direction.h"
#include "error.h"

namespace hsnc {

void HeldMass::hold(const Model& model, const std::vector<char>& held) {
    if (model_ == &model && held == held_) return;
    model_ = &model;
    held_ = held;
    const std::size_t n = held.size();
    free_.clear();
    for (std::size_t i = 0; i < n; ++i)
        if (!held[i]) free_.push_back(static_cast<int>(i));
    column_.assign(n, -1);
    for (std::size_t r = 0; r < free_.size(); ++r) column_[static_cast<std::size_t>(free_[r])] = static_cast<int>(r);
    bool riders = false;
    for (std::size_t i = 0; i < n; ++i) {  // a rider moves with the body its chain of stuck partners ends on
        if (!held[i]) continue;
        int p = model.friction_slot(i).partner;
        while (p != kGround && held[static_cast<std::size_t>(p)])
            p = model.friction_slot(static_cast<std::size_t>(p)).partner;
        if (p != kGround) column_[i] = column_[static_cast<std::size_t>(p)], riders = true;
    }
    if (!riders) {
        llt_.compute(mass_matrix(model, free_));
    } else {  // T^T M T: the rows and columns of a free coordinate's dofs summed
        const auto nf = static_cast<Eigen::Index>(free_.size());
        Eigen::MatrixXd Mq = Eigen::MatrixXd::Zero(nf, nf);
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t j = 0; j < n; ++j)
                if (column_[i] >= 0 && column_[j] >= 0) Mq(column_[i], column_[j]) += model.mass_entry(i, j);
        llt_.compute(Mq);
    }
    if (llt_.info() != Eigen::Success) throw RunError("HeldMass: T^T M T is not positive definite");
    rhs_.resize(static_cast<Eigen::Index>(free_.size()));
}

void HeldMass::accelerations(const double* f, double* a) const {
    for (std::size_t r = 0; r < free_.size(); ++r) rhs_(static_cast<Eigen::Index>(r)) = f[free_[r]];
    for (std::size_t k = 0; k < held_.size(); ++k)  // a rider's forces act on its partner's coordinate
        if (held_[k] && column_[k] >= 0) rhs_(column_[k]) += f[k];
    const Eigen::VectorXd aF = llt_.solve(rhs_);
    for (std::size_t i = 0; i < held_.size(); ++i) a[i] = column_[i] >= 0 ? aF(column_[i]) : 0.0;
}

double HeldMass::held_force(int i, const double* f, const double* a) const {
    double D = 0.0;
    bool first = true;
    for (int k : carried(*model_, held_, i)) {
        const double dk = f[k] - mass_times(*model_, static_cast<std::size_t>(k), a);
        D = first ? dk : D + dk;
        first = false;
    }
    return D;
}

Eigen::VectorXd HeldMass::release_row(int i) const {
    // P_i = s - T (T^T M T)^-1 T^T M s, s the indicator of the dofs i carries.
    const auto n = static_cast<Eigen::Index>(held_.size());
    const std::vector<int> S = carried(*model_, held_, i);
    Eigen::VectorXd MFi = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(free_.size()));
    for (Eigen::Index k = 0; k < n; ++k) {
        if (column_[static_cast<std::size_t>(k)] < 0) continue;
        for (int s : S)
            MFi(column_[static_cast<std::size_t>(k)]) +=
                model_->mass_entry(static_cast<std::size_t>(k), static_cast<std::size_t>(s));
    }
    const Eigen::VectorXd w = llt_.solve(MFi);  // (T^T M T)^-1 T^T M s
    Eigen::VectorXd P = Eigen::VectorXd::Zero(n);
    for (Eigen::Index k = 0; k < n; ++k)
        if (column_[static_cast<std::size_t>(k)] >= 0) P(k) = -w(column_[static_cast<std::size_t>(k)]);
    for (int s : S) P(s) += 1.0;
    return P;
}

Eigen::MatrixXd HeldMass::inverse() const {
    const auto n = static_cast<Eigen::Index>(held_.size()), nf = static_cast<Eigen::Index>(free_.size());
    const Eigen::MatrixXd inv = llt_.solve(Eigen::MatrixXd::Identity(nf, nf));
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n, n);
    for (Eigen::Index r = 0; r < n; ++r)
        for (Eigen::Index c = 0; c < n; ++c)
            if (column_[static_cast<std::size_t>(r)] >= 0 && column_[static_cast<std::size_t>(c)] >= 0)
                out(r, c) = inv(column_[static_cast<std::size_t>(r)], column_[static_cast<std::size_t>(c)]);
    return out;
}

void kinetic_friction(const Model& model, const std::vector<char>& held, const signed char* sgn, double* fr) {
    for (std::size_t k = 0; k < model.dof(); ++k)
        fr[k] = !held[k] && model.has_friction(k)
                    ? -model.friction_slot(k).mu_k * model.normal_force(k) * static_cast<double>(sgn[k])
                    : 0.0;
    for (std::size_t k = 0; k < model.dof(); ++k) {  // the reaction on the partner of a friction between two bodies
        const int p = model.friction_slot(k).partner;
        if (!held[k] && model.has_friction(k) && p != kGround) fr[p] -= fr[k];
    }
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
