#include "exponential_solver.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <unsupported/Eigen/MatrixFunctions>

#include <algorithm>
#include <cmath>
#include <limits>

#include "assembly.h"
#include "energy_scaling.h"
#include "kernel_abi.h"  // hsnc_phase

namespace hsnc {
namespace {

constexpr double kE = 2.718281828459045;

}  // namespace

ExponentialSolver::ExponentialSolver(const Model& model, const Configuration& cfg)
    : cfg_(cfg), switches_(switch_functions(model, cfg)) {
    n_ = static_cast<int>(model.dof());
    ns_ = static_cast<int>(switches_.size());
    for (int i = 0; i < n_; ++i) (cfg.stuck[static_cast<std::size_t>(i)] ? stuck_ : free_).push_back(i);
    nf_ = static_cast<int>(free_.size());
    t_ = configuration_terms(model, cfg);
    nh_ = static_cast<int>(t_.h_omega.size());
    m_ = 2 * nf_ + 1 + 2 * nh_;
    Z_ = Eigen::MatrixXd::Zero(m_, m_);
    z0_ = absz0_ = Eigen::VectorXd::Zero(m_);
    bound_row_ = Eigen::VectorXd::Zero(ns_);
    x_fix_ = fseg_ = Eigen::VectorXd::Zero(n_);
    slider_ = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(t_.jenkins.size()));
    theta_ = sn_ = cs_ = Eigen::VectorXd::Zero(nh_);
    z_ = zb_ = zbmag_ = zmag_ = Eigen::VectorXd::Zero(m_);
    xmag_ = vmag_ = Eigen::VectorXd::Zero(n_);
    if (model.coupled_mass())  // a coupled M_F: the rows of the state matrix are M_F^-1 times the forces
        minv_ = mass_matrix(model, free_).llt().solve(Eigen::MatrixXd::Identity(nf_, nf_));
    balance(model);
}

void ExponentialSolver::balance(const Model& model) {
    if (nf_ == 0) return;
    Eigen::MatrixXd KF(nf_, nf_), MF = Eigen::MatrixXd::Zero(nf_, nf_);
    for (int r = 0; r < nf_; ++r)
        for (int q = 0; q < nf_; ++q) KF(r, q) = t_.K(free_[r], free_[q]);
    if (model.coupled_mass())
        MF = mass_matrix(model, free_);
    else
        for (int r = 0; r < nf_; ++r) MF(r, r) = t_.mass(free_[r]);
    EnergyScaling u;
    if (!energy_scaling(KF, MF, u)) return;
    D_ = Eigen::MatrixXd::Identity(m_, m_);
    Dinv_ = D_;
    D_.topLeftCorner(nf_, nf_) = u.UK;
    D_.block(nf_, nf_, nf_, nf_) = u.UM;
    Dinv_.topLeftCorner(nf_, nf_) = u.UK_inv;
    Dinv_.block(nf_, nf_, nf_, nf_) = u.UM_inv;
    absDinv_ = Dinv_.cwiseAbs();
}

void ExponentialSolver::setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) {
    for (int i = 0; i < n_; ++i) x_fix_(i) = x0[i];
    segment_force(t_, cfg_, x0, fseg_, slider_);
    release_force(t_, fseg_, sgn, frel_);
    const int one = 2 * nf_;
    auto sine = [&](int h) { return one + 1 + 2 * h; };
    Z_.setZero();
    z0_.setZero();
    // The constant force on the free masses (loads, preloads, coupling, friction), and
    // the static offset it holds them at where K_FF is regular.
    Eigen::VectorXd force(nf_);
    Eigen::MatrixXd KF(nf_, nf_);
    for (int r = 0; r < nf_; ++r) {
        force(r) = free_mass_force(t_, fseg_, stuck_, free_[r], x0, sgn);
        for (int q = 0; q < nf_; ++q) KF(r, q) = t_.K(free_[r], free_[q]);
    }
    xs_ = Eigen::VectorXd::Zero(nf_);
    bool offset = false;
    if (nf_ > 0) {
        const Eigen::FullPivLU<Eigen::MatrixXd> lu(KF);
        if (lu.isInvertible()) {
            xs_ = lu.solve(force);
            offset = true;
        }
    }
    free_offset_ = offset;
    for (int r = 0; r < nf_; ++r) {
        const int i = free_[r];
        const double f = offset ? 0.0 : force(r);
        const double m = minv_.size() > 0 ? 1.0 : t_.mass(i);  // M_F^-1 applied below when coupled
        Z_(r, nf_ + r) = 1.0;
        for (int q = 0; q < nf_; ++q) {
            Z_(nf_ + r, q) = -t_.K(i, free_[q]) / m;
            Z_(nf_ + r, nf_ + q) = -t_.C(i, free_[q]) / m;
        }
        Z_(nf_ + r, one) = f / m;
        for (int h = 0; h < nh_; ++h) Z_(nf_ + r, sine(h)) = t_.h_amp(i, h) / m;
        z0_(r) = x0[i] - xs_(r);
        z0_(nf_ + r) = v0[i];
    }
    if (minv_.size() > 0) Z_.middleRows(nf_, nf_) = minv_ * Z_.middleRows(nf_, nf_);
    z0_(one) = 1.0;
    for (int h = 0; h < nh_; ++h) {
        const double W = t_.h_omega(h);
        Z_(sine(h), sine(h) + 1) = W;
        Z_(sine(h) + 1, sine(h)) = -W;
        theta_(h) = hsnc_phase(W, t0, t0_lo, t_.h_phase(h));
        z0_(sine(h)) = std::sin(theta_(h));
        z0_(sine(h) + 1) = std::cos(theta_(h));
    }
    // The exponential's generator, energy-scaled where balance() found D: Zb = D Z D^-1.
    if (D_.size() > 0) {
        Zb_ = D_ * Z_ * Dinv_;
        zb0_ = D_ * z0_;
    } else {
        Zb_ = Z_;
        zb0_ = z0_;
    }
    absz0_ = zb0_.cwiseAbs();
    const double norm = Zb_.cwiseAbs().rowwise().sum().maxCoeff();
    max_step_ = norm > 0.0 ? 1.0 / norm : std::numeric_limits<double>::infinity();

    // Each switch function's linear part L_f over z: g(e_k) - g(0), the affine
    // function evaluated at the unit vectors (the forcing read from z).
    std::vector<double> x(t_.jenkins.size() + static_cast<std::size_t>(n_)), v(n_), a(n_), g(ns_), dg(ns_), bnd(ns_),
        sc(ns_);
    const SegmentEval out{x.data(), v.data(), a.data(), g.data(), dg.data(), bnd.data(), sc.data()};
    auto values = [&](const Eigen::VectorXd& z, Eigen::VectorXd& gz) {
        write_at_rest(x_fix_, out, xmag_, vmag_);
        for (int h = 0; h < nh_; ++h) sn_(h) = z(sine(h)), cs_(h) = z(sine(h) + 1);
        for (int r = 0; r < nf_; ++r) x[free_[r]] = xs_(r) + z(r), v[free_[r]] = z(nf_ + r);
        for (int r = 0; r < nf_; ++r) {
            double acc = 0.0;
            for (int k = 0; k < m_; ++k) acc += Z_(nf_ + r, k) * z(k);
            a[free_[r]] = acc;
        }
        write_sliders(t_, cfg_, slider_, out);
        gz.resize(ns_);
        for (int f = 0; f < ns_; ++f) {
            double gv, dgv, scale;
            switch_value(switches_[static_cast<std::size_t>(f)], t_, t_.coupled() ? frel_ : fseg_, out, xmag_, vmag_, sn_, cs_, gv, dgv,
                         scale);
            gz(f) = gv;
        }
    };
    Eigen::VectorXd g0, gk;
    values(Eigen::VectorXd::Zero(m_), g0);
    Eigen::MatrixXd L(ns_, m_);
    for (int k = 0; k < m_; ++k) {
        values(Eigen::VectorXd::Unit(m_, k), gk);
        L.col(k) = gk - g0;
    }
    // g = L z + g0 = L D^-1 zb: g'' = L D^-1 Zb^2 zb.
    bound_row_ =
        ((D_.size() > 0 ? Eigen::MatrixXd(L * Dinv_) : L) * Zb_ * Zb_).cwiseAbs().rowwise().sum() * (kE * 1.01);
}

void ExponentialSolver::eval(double tau, const SegmentEval& out) const {
    E_ = (Zb_ * tau).exp();
    zb_.noalias() = E_ * zb0_;
    zbmag_.noalias() = E_.cwiseAbs() * absz0_;
    if (D_.size() > 0) {  // back from the energy scaling: z = D^-1 zb, |z| <= |D^-1| |zb|
        z_.noalias() = Dinv_ * zb_;
        zmag_.noalias() = absDinv_ * zbmag_;
    } else {
        z_ = zb_;
        zmag_ = zbmag_;
    }
    write_at_rest(x_fix_, out, xmag_, vmag_);
    for (int h = 0; h < nh_; ++h) {
        const double ph = t_.h_omega(h) * tau + theta_(h);
        sn_(h) = std::sin(ph);
        cs_(h) = std::cos(ph);
    }
    for (int r = 0; r < nf_; ++r) {
        const int i = free_[r];
        out.x[i] = xs_(r) + z_(r);
        out.v[i] = z_(nf_ + r);
        xmag_(i) = std::abs(xs_(r)) + zmag_(r);
        vmag_(i) = zmag_(nf_ + r);
    }
    // a = M^-1 (f - K x - C v + sum_h F_h sin): the generator's velocity rows.
    const int one = 2 * nf_;
    for (int r = 0; r < nf_; ++r) {
        double acc = Z_(nf_ + r, one);
        for (int q = 0; q < 2 * nf_; ++q) acc += Z_(nf_ + r, q) * z_(q);
        for (int h = 0; h < nh_; ++h) acc += Z_(nf_ + r, one + 1 + 2 * h) * sn_(h);
        out.a[free_[r]] = acc;
    }
    write_sliders(t_, cfg_, slider_, out);
    // Without forcing, about the static offset, (x - x_s, v) moves alone (Z's
    // columns of 1 are 0): its norm bounds g'' and the bound decays with the
    // motion (with the 1 in it, a creep into equilibrium took steps ever shorter
    // against a fixed bound: the search did not converge).
    const double zmax = (free_offset_ && nh_ == 0 ? zb_.head(2 * nf_) : zb_).cwiseAbs().maxCoeff();
    for (int f = 0; f < ns_; ++f) {
        double g, dg, scale;
        switch_value(switches_[static_cast<std::size_t>(f)], t_, t_.coupled() ? frel_ : fseg_, out, xmag_, vmag_, sn_, cs_, g, dg, scale);
        out.g[f] = g;
        out.dg[f] = dg;
        out.scale[f] = scale;
        out.bound[f] = bound_row_(f) * zmax;
    }
}

std::size_t ExponentialSolver::memory_bytes() const {
    const std::size_t m = static_cast<std::size_t>(m_), n = static_cast<std::size_t>(n_);
    return sizeof(*this) + 8 * (3 * m * m + 6 * m + 2 * n * n + 12 * n + static_cast<std::size_t>(ns_));
}

}  // namespace hsnc
