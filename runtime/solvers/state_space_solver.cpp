#include "state_space_solver.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <string>

#include "assembly.h"
#include "energy_scaling.h"
#include "error.h"
#include "free_components.h"
#include "kernel_abi.h"  // hsnc_phase: Omega (t0 + t0_lo) + phase, reduced as every solver does
#include "switch_values.h"

namespace hsnc {
namespace {

using cplx = std::complex<double>;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.141592653589793;
/// |mu - lambda| < kNear |mu|: a harmonic near a mode's resonance (bounds use one forcing period).
constexpr double kNear = 0.1;
/// Negative damping: the bounds hold over kGrowthHorizon / (largest Re lambda) (the header).
constexpr double kGrowthHorizon = 0.5;

cplx expc(cplx w) { return std::exp(w.real()) * cplx(std::cos(w.imag()), std::sin(w.imag())); }

/// |z| for the magnitudes and bounds: sqrt(re^2 + im^2) (std::abs, hypot,
/// guards against overflow the values here never reach, at several times the cost).
double mod(cplx z) { return std::sqrt(z.real() * z.real() + z.imag() * z.imag()); }

/// E(lambda, mu, tau) = int_0^tau e^{lambda (tau - s)} e^{mu s} ds, given
/// el = e^{lambda tau}, em = e^{mu tau}, d = mu - lambda and its inverse.
cplx duhamel(cplx d, cplx inv_d, double tau, cplx el, cplx em) {
    const cplx w = d * tau;
    if (std::norm(w) < 1.0) return w == cplx(0.0) ? el * tau : el * (expm1c(w) * inv_d);
    return (em - el) * inv_d;
}

/// A bound on |E''(s)| for s in [tau, s_end] (state_space_solver.h), given
/// |lambda|, |mu|, |mu - lambda|, |lambda + mu|, the largest |e^{lambda s}| there
/// (`ahead`) and over [0, s_end] (`reach`; both |e^{lambda tau}| and 1 for a decaying
/// mode), |e^{mu s}| = 1.
double duhamel_bound(double l, double m, double dm, double sum, double ahead, double reach, double s_end) {
    const double first = dm > 0.0 ? (m * m + l * l * ahead) / dm : kInf;
    const double second = l == 0.0 ? m : l * l * s_end * reach + sum;
    return std::min(first, second);
}

}  // namespace

void StateSpaceSolver::coupled_rigid_basis(const Eigen::MatrixXd& MF, const std::vector<char>& pivot,
                                           const std::function<void(const std::string&)>& refuse) {
    // x_F = R q + T e with R^T M_F T = 0 (the file's construction, M_F coupled):
    // w_j = M_F r_j; T's column of a non-pivot slot s is e_s - sum_j c_j e_{p_j}
    // with W c = w(s), W(k, j) = w_k(p_j). q_j'' = r_j^T f / (r_j^T M r_j) needs
    // R^T M_F R diagonal: rigid translations that M couples are refused.
    const auto nr = static_cast<Eigen::Index>(rigid_.size());
    rigid_w_ = Eigen::MatrixXd::Zero(nf_, nr);
    for (Eigen::Index j = 0; j < nr; ++j) {
        Rigid& rg = rigid_[static_cast<std::size_t>(j)];
        for (int r : rg.members) rigid_w_.col(j) += MF.col(r);
        double total = 0.0;
        for (int r : rg.members) total += rigid_w_(r, j);
        rg.mass = total;
        for (Eigen::Index k = 0; k < j; ++k) {
            double cross = 0.0;
            for (int r : rigid_[static_cast<std::size_t>(k)].members) cross += rigid_w_(r, j);
            if (std::abs(cross) > 1e-12 * std::sqrt(total * rigid_[static_cast<std::size_t>(k)].mass))
                refuse("two free-floating parts coupled through the mass matrix (not yet supported)");
        }
    }
    Eigen::MatrixXd W(nr, nr);
    for (Eigen::Index k = 0; k < nr; ++k)
        for (Eigen::Index j = 0; j < nr; ++j) W(k, j) = rigid_w_(rigid_[static_cast<std::size_t>(j)].members.front(), k);
    const Eigen::PartialPivLU<Eigen::MatrixXd> lu(nr > 0 ? W : Eigen::MatrixXd::Identity(1, 1));
    int col = 0;
    for (int r = 0; r < nf_; ++r) {
        if (pivot[static_cast<std::size_t>(r)]) continue;
        T_(r, col) = 1.0;
        if (nr > 0) {
            const Eigen::VectorXd c = lu.solve(Eigen::VectorXd(rigid_w_.row(r).transpose()));
            for (Eigen::Index j = 0; j < nr; ++j) T_(rigid_[static_cast<std::size_t>(j)].members.front(), col) -= c(j);
        }
        e_slot_.push_back(r);
        ++col;
    }
}

Eigen::MatrixXd StateSpaceSolver::rigid_basis(const Model& model, const Configuration& cfg) {
    // Free translations that no damping resists (C r = 0 for a floating
    // component's r, free_components.h) are taken out of the state: x_F =
    // R q + T e with q_j the mass-weighted mean position of component j and
    // T the basis of R^T M x = 0 made of e_i - (m_i/m_p) e_p for every member
    // i but the component's first, p, and e_i for the rest. Then
    // q_j'' = r_j^T f(t) / m_j exactly (R^T K = R^T C = 0), and the state
    // matrix of e has no double zero eigenvalue.
    std::vector<int> slot(static_cast<std::size_t>(n_), -1);
    for (int r = 0; r < nf_; ++r) slot[static_cast<std::size_t>(free_[r])] = r;
    const double cmax = t_.C.cwiseAbs().maxCoeff();
    std::vector<char> pivot(static_cast<std::size_t>(nf_), 0);
    for (const std::vector<int>& members : free_components(model, cfg).floating_members()) {
        // C r on the free masses: every row of C_FF summed over the members.
        double resist = 0.0;
        for (int i : free_) {
            double row = 0.0;
            for (int j : members) row += t_.C(i, j);
            resist = std::max(resist, std::abs(row));
        }
        if (resist > 1e-13 * cmax) continue;  // a damped translation: a simple zero eigenvalue, no deflation
        Rigid rg;
        double total = 0.0;
        for (int i : members) {
            rg.members.push_back(slot[static_cast<std::size_t>(i)]);
            total += t_.mass(i);
        }
        rg.mass = total;
        pivot[static_cast<std::size_t>(rg.members.front())] = 1;
        rigid_.push_back(rg);
    }
    ne_ = nf_ - static_cast<int>(rigid_.size());
    T_ = Eigen::MatrixXd::Zero(nf_, ne_);
    Eigen::MatrixXd MF = Eigen::MatrixXd::Zero(nf_, nf_);
    for (int r = 0; r < nf_; ++r) MF(r, r) = t_.mass(free_[r]);
    if (model.coupled_mass()) {
        MF = mass_matrix(model, free_);
        coupled_rigid_basis(MF, pivot, [&](const std::string& why) {
            throw RunError("StateSpaceSolver(): configuration '" + cfg.spec(model) + "' of model '" + model.name +
                           "': " + why);
        });
    } else {
        int col = 0;
        std::vector<int> pivot_of(static_cast<std::size_t>(nf_), -1);
        for (const Rigid& rg : rigid_)
            for (int r : rg.members) pivot_of[static_cast<std::size_t>(r)] = rg.members.front();
        for (int r = 0; r < nf_; ++r) {
            if (pivot[static_cast<std::size_t>(r)]) continue;
            T_(r, col) = 1.0;
            const int p = pivot_of[static_cast<std::size_t>(r)];
            if (p >= 0) T_(p, col) = -t_.mass(free_[r]) / t_.mass(free_[p]);
            e_slot_.push_back(r);
            ++col;
        }
    }
    if (model.coupled_mass() && ne_ > 0) {
        // Mass-normalised e: with T^T M_F T = L L^T, T becomes T L^-T and e L^T e, so that Me = I.
        // The eigenvectors of the state matrix then stay well conditioned where the masses of the
        // dofs differ by orders (translations and rotations of finite elements).
        const Eigen::MatrixXd Me0 = T_.transpose() * MF * T_;
        const Eigen::LLT<Eigen::MatrixXd> llt(0.5 * (Me0 + Me0.transpose()));
        if (llt.info() != Eigen::Success)
            throw RunError("StateSpaceSolver(): configuration '" + cfg.spec(model) + "' of model '" + model.name +
                           "': the mass matrix of the free dofs is not positive definite");
        e_lt_ = llt.matrixU();
        T_ = llt.matrixU().solve<Eigen::OnTheRight>(T_);  // T U^-1, U = L^T
    }
    absT_ = T_.cwiseAbs();
    return MF;
}

void StateSpaceSolver::decompose(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Me, const Eigen::MatrixXd& Ke,
                                 bool may_grow, const std::string& where) {
    const auto m = A.rows();
    growth_ = 0.0;
    if (m == 0) return;
    // The energy scaling z = B y, B = diag(L^T / s, R^T) (Ke = L L^T, Me = R R^T): B A B^-1 =
    // [0, L^T R^-T; -R^-1 L, -R^-1 Ce R^-T] is skew-symmetric but for the damping, so its
    // eigenvectors are orthogonal for undamped modes and lose conditioning only as modes near
    // critical damping, not with the spread of the frequencies (y's single s leaves a mode of
    // omega_k a velocity half omega_k / s of its position half: a condition ~ omega_max /
    // omega_1, 3e3 on a 16-dof cantilever). Ke singular (a translation a damper alone holds):
    // y itself.
    Eigen::MatrixXd B = Eigen::MatrixXd::Identity(m, m), Binv = B;
    EnergyScaling u;
    if (energy_scaling(Ke, Me, u)) {
        B.topLeftCorner(ne_, ne_) = u.UK / scale_s_;
        B.bottomRightCorner(ne_, ne_) = u.UM;
        Binv.topLeftCorner(ne_, ne_) = scale_s_ * u.UK_inv;
        Binv.bottomRightCorner(ne_, ne_) = u.UM_inv;
    }
    const Eigen::MatrixXd Ab = B * A * Binv;
    const Eigen::EigenSolver<Eigen::MatrixXd> es(Ab);
    if (es.info() != Eigen::Success) throw RunError(where + "the eigen-solver of the state matrix did not converge");
    lambda_ = es.eigenvalues();
    const Eigen::MatrixXcd& W = es.eigenvectors();
    const Eigen::PartialPivLU<Eigen::MatrixXcd> lu(W);
    const Eigen::MatrixXcd Winv = lu.inverse();
    condition_ = W.cwiseAbs().colwise().sum().maxCoeff() * Winv.cwiseAbs().colwise().sum().maxCoeff();
    // V = B^-1 W and V^-1 = W^-1 B, real and imaginary parts apart so that a conjugate pair's
    // columns (rows) stay exactly conjugate.
    V_.resize(m, m);
    V_.real() = Binv * W.real();
    V_.imag() = Binv * W.imag();
    Vinv_.resize(m, m);
    Vinv_.real() = Winv.real() * B;
    Vinv_.imag() = Winv.imag() * B;
    if (!(condition_ <= kMaxCondition)) {
        char text[32];
        std::snprintf(text, sizeof text, "%.2g", condition_);
        throw DefectiveModes(where + "its state-space modes are nearly defective (eigenvector condition " + text +
                             " > 200: critically damped motion)");
    }
    const double anorm = Ab.cwiseAbs().rowwise().sum().maxCoeff();
    for (Eigen::Index k = 0; k < m; ++k) {
        // Passive damping (C >= 0): Re lambda <= 0. Rounding may put an undamped pair a few ulps
        // to the right; it is put on the axis. Negative damping (hsnc modes' EPMC) grows.
        const double re = lambda_(k).real();
        if (re > 1e-12 * anorm) {
            if (!may_grow) throw RunError(where + "an eigenvalue of the state matrix has Re > 0");
            growth_ = std::max(growth_, re);
        } else if (re > 0.0) {
            lambda_(k) = cplx(0.0, lambda_(k).imag());
        }
    }
}

StateSpaceSolver::StateSpaceSolver(const Model& model, const Configuration& cfg)
    : cfg_(cfg), switches_(switch_functions(model, cfg)) {
    n_ = static_cast<int>(model.dof());
    ns_ = static_cast<int>(switches_.size());
    for (int i = 0; i < n_; ++i) (cfg.stuck[static_cast<std::size_t>(i)] ? stuck_ : free_).push_back(i);
    nf_ = static_cast<int>(free_.size());

    t_ = configuration_terms(model, cfg);
    nh_ = static_cast<int>(t_.h_omega.size());

    const Eigen::MatrixXd MF = rigid_basis(model, cfg);
    std::vector<int> slot(static_cast<std::size_t>(n_), -1);  // the free slot of each mass, -1 when stuck
    for (int r = 0; r < nf_; ++r) slot[static_cast<std::size_t>(free_[r])] = r;
    const int m = 2 * ne_;
    Eigen::MatrixXd KF(nf_, nf_), CF(nf_, nf_);
    for (int r = 0; r < nf_; ++r)
        for (int q = 0; q < nf_; ++q) KF(r, q) = t_.K(free_[r], free_[q]), CF(r, q) = t_.C(free_[r], free_[q]);
    const Eigen::MatrixXd Me = T_.transpose() * MF * T_, Ke = T_.transpose() * KF * T_, Ce = T_.transpose() * CF * T_;
    Me_lu_ = Eigen::PartialPivLU<Eigen::MatrixXd>(Me.rows() > 0 ? Me : Eigen::MatrixXd::Identity(1, 1));
    const Eigen::MatrixXd MK = ne_ > 0 ? Eigen::MatrixXd(Me_lu_.solve(Ke)) : Eigen::MatrixXd(0, 0);
    const Eigen::MatrixXd MC = ne_ > 0 ? Eigen::MatrixXd(Me_lu_.solve(Ce)) : Eigen::MatrixXd(0, 0);

    // y = [e; e' / s], s the largest sqrt of the diagonal of Me^-1 Ke (else of Me^-1 Ce, else 1).
    double w2 = 0.0, rate = 0.0;
    for (int r = 0; r < ne_; ++r) {
        w2 = std::max(w2, MK(r, r));
        rate = std::max(rate, MC(r, r));
    }
    scale_s_ = w2 > 0.0 ? std::sqrt(w2) : (rate > 0.0 ? rate : 1.0);
    const double s = scale_s_;
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m, m);
    for (int r = 0; r < ne_; ++r) {
        A(r, ne_ + r) = s;
        for (int q = 0; q < ne_; ++q) {
            A(ne_ + r, q) = -MK(r, q) / s;
            A(ne_ + r, ne_ + q) = -MC(r, q);
        }
    }
    decompose(A, Me, Ke, model.alpha < 0.0 || model.beta < 0.0,
              "StateSpaceSolver(): configuration '" + cfg.spec(model) + "' of model '" + model.name + "': ");

    Eigen::MatrixXd bh = Eigen::MatrixXd::Zero(m, nh_);
    if (ne_ > 0)
        for (int h = 0; h < nh_; ++h) {
            Eigen::VectorXd F(nf_);
            for (int r = 0; r < nf_; ++r) F(r) = t_.h_amp(free_[r], h);
            bh.block(ne_, h, ne_, 1) = Me_lu_.solve(T_.transpose() * F) / s;
        }
    beta_h_ = Vinv_ * bh.cast<cplx>();
    bh_tail_ = bh.bottomRows(ne_);
    // The static offset where A is regular (every eigenvalue off 0: K_e regular).
    if (m > 0) {
        const double anorm = A.cwiseAbs().rowwise().sum().maxCoeff();
        offset_ = true;
        for (int k = 0; k < m; ++k)
            if (!(std::abs(lambda_(k)) > 1e-12 * anorm)) offset_ = false;
        if (offset_) Ke_lu_ = Eigen::PartialPivLU<Eigen::MatrixXd>(Ke);
    }
    // The rigid coordinates' forcing: q_j'' = (r_j^T f + sum_h r_j^T F_h sin) / m_j.
    rigid_h_ = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(rigid_.size()), nh_);
    for (std::size_t j = 0; j < rigid_.size(); ++j)
        for (int h = 0; h < nh_; ++h)
            for (int r : rigid_[j].members) rigid_h_(static_cast<Eigen::Index>(j), h) += t_.h_amp(free_[r], h) / rigid_[j].mass;

    // Near resonance: the bound's second form, over one forcing period.
    max_step_ = kInf;
    near_ = Eigen::Matrix<char, Eigen::Dynamic, Eigen::Dynamic>::Zero(m, 2 * nh_);
    for (int k = 0; k < m; ++k)
        for (int h = 0; h < nh_; ++h)
            for (int sign = 0; sign < 2; ++sign) {
                const cplx mu(0.0, sign == 0 ? t_.h_omega(h) : -t_.h_omega(h));
                if (beta_h_(k, h) != cplx(0.0) && std::abs(mu - lambda_(k)) < kNear * std::abs(mu)) {
                    near_(k, 2 * h + sign) = 1;
                    max_step_ = std::min(max_step_, 2 * kPi / t_.h_omega(h));
                }
            }

    if (growth_ > 0.0) max_step_ = std::min(max_step_, kGrowthHorizon / growth_);

    // Per mode and forcing term (mu = 0, +i Omega_h, -i Omega_h): 1/(mu - lambda) and the moduli the bounds use.
    const int nmu = 1 + 2 * nh_;
    inv_d_.resize(m, nmu);
    mod_d_.resize(m, nmu);
    mod_sum_.resize(m, nmu);
    mod_lambda_.resize(m);
    mod_beta_h_.resize(m, nh_);
    for (int k = 0; k < m; ++k) {
        mod_lambda_(k) = mod(lambda_(k));
        for (int u = 0; u < nmu; ++u) {
            const cplx mu = u == 0 ? cplx(0.0) : cplx(0.0, (u % 2 == 1 ? 1.0 : -1.0) * t_.h_omega((u - 1) / 2));
            const cplx d = mu - lambda_(k);
            inv_d_(k, u) = d == cplx(0.0) ? cplx(0.0) : 1.0 / d;
            mod_d_(k, u) = mod(d);
            mod_sum_(k, u) = mod(lambda_(k) + mu);
        }
        for (int h = 0; h < nh_; ++h) mod_beta_h_(k, h) = 0.5 * mod(beta_h_(k, h));
    }

    // Each switch function as a row over (x_F, v_F) (and the forcing it sees
    // directly), then over y = [e; e'/s] through T, and over the rigid
    // coordinates through R.
    Eigen::MatrixXd L = Eigen::MatrixXd::Zero(ns_, 2 * nf_);
    bound_sin_ = Eigen::VectorXd::Zero(ns_);
    for (int f = 0; f < ns_; ++f) {
        const SwitchFunction& sf = switches_[static_cast<std::size_t>(f)];
        const int e = sf.element;
        // w * (x[a] - x[b]) (offset 0) or w * (v[a] - v[b]) (offset nf) as a row of L.
        auto difference = [&](int a, int b, int offset, double w) {
            if (a != kGround && slot[static_cast<std::size_t>(a)] >= 0) L(f, offset + slot[static_cast<std::size_t>(a)]) += w;
            if (b != kGround && slot[static_cast<std::size_t>(b)] >= 0) L(f, offset + slot[static_cast<std::size_t>(b)]) -= w;
        };
        const auto ee = static_cast<std::size_t>(e);
        if (sf.kind == SwitchKind::gap) {
            for_each_term(t_.contacts[ee].direction(), [&](int b, double w) { difference(b, kGround, 0, w); });
        } else if (sf.kind == SwitchKind::slip_pos || sf.kind == SwitchKind::slip_neg) {
            const Jenkins& j = t_.jenkins[ee];
            const double ks = sf.kind == SwitchKind::slip_pos ? j.k : -j.k;
            for_each_term(j.direction(), [&](int b, double w) { difference(b, kGround, 0, ks * w); });
        } else if (sf.kind == SwitchKind::slip_velocity) {
            for_each_term(t_.jenkins[ee].direction(), [&](int b, double w) { difference(b, kGround, nf_, w); });
        } else if (sf.kind == SwitchKind::velocity) {
            L(f, nf_ + slot[static_cast<std::size_t>(e)]) = 1.0;
        } else {
            for (int r = 0; r < nf_; ++r) {
                L(f, r) = -t_.K(e, free_[r]);
                L(f, nf_ + r) = -t_.C(e, free_[r]);
            }
            for (int h = 0; h < nh_; ++h) bound_sin_(f) += std::abs(t_.h_amp(e, h)) * t_.h_omega(h) * t_.h_omega(h);
        }
    }
    Eigen::MatrixXd Ly(ns_, m);
    if (ne_ > 0) {
        Ly.leftCols(ne_) = L.leftCols(nf_) * T_;
        Ly.rightCols(ne_) = L.rightCols(nf_) * T_ * s;
    }
    absG_ = (Ly.cast<cplx>() * V_).cwiseAbs();

    // Conjugate pairs: y is real and b real, so the modal coordinate of
    // conj(lambda) is the conjugate of lambda's, and the pair adds 2 Re(V_k eta_k).
    // Eigen's real eigen-solver gives each pair adjacent, exactly conjugate;
    // eval then takes one of each (weight 2). Anything else: every mode, weight 1.
    std::vector<double> weight;
    for (int k = 0; k < m; ++k) {
        const bool pair = lambda_(k).imag() > 0.0 && k + 1 < m && lambda_(k + 1) == std::conj(lambda_(k)) &&
                          V_.col(k + 1) == V_.col(k).conjugate();
        rep_.push_back(k);
        weight.push_back(pair ? 2.0 : 1.0);
        if (pair) ++k;
    }
    const int nr = static_cast<int>(rep_.size());
    Vre_.resize(m, nr);
    Vim_.resize(m, nr);
    absV_.resize(m, nr);
    Eigen::MatrixXd absG(ns_, nr);
    for (int c = 0; c < nr; ++c) {
        const int k = rep_[static_cast<std::size_t>(c)];
        const double w = weight[static_cast<std::size_t>(c)];
        Vre_.col(c) = w * V_.col(k).real();
        Vim_.col(c) = w * V_.col(k).imag();
        absV_.col(c) = w * V_.col(k).cwiseAbs();
        absG.col(c) = w * absG_.col(k);
    }
    absG_ = absG;
    // Rigid part of g'': x'' = R q'', v'' = R q''' with |q''| <= (|r^T f| + sum_h |P_h|),
    // |q'''| <= sum_h |P_h| Omega_h; r^T f depends on setup (friction, stuck masses): rigid_bound_ there.
    rigid_lx_ = Eigen::MatrixXd::Zero(ns_, static_cast<Eigen::Index>(rigid_.size()));
    rigid_lv_ = rigid_lx_;
    for (std::size_t j = 0; j < rigid_.size(); ++j)
        for (int r : rigid_[j].members) {
            rigid_lx_.col(static_cast<Eigen::Index>(j)) += L.col(r);
            rigid_lv_.col(static_cast<Eigen::Index>(j)) += L.col(nf_ + r);
        }

    x_fix_ = fseg_ = Eigen::VectorXd::Zero(n_);
    slider_ = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(t_.jenkins.size()));
    theta_ = Eigen::VectorXd::Zero(nh_);
    e_theta_ = Eigen::VectorXcd::Zero(nh_);
    eta0_ = beta0_ = Eigen::VectorXcd::Zero(m);
    eta_ = deta_ = Eigen::VectorXcd::Zero(static_cast<Eigen::Index>(rep_.size()));
    ys_ = fe_ = Eigen::VectorXd::Zero(ne_);
    dy_ = Eigen::VectorXd::Zero(m);
    af_ = Eigen::VectorXd::Zero(nf_);
    mod_eta0_ = mod_beta0_ = Eigen::VectorXd::Zero(m);
    B_ = Eigen::VectorXd::Zero(ns_);
    q0_ = qd0_ = rigid_f_ = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(rigid_.size()));
    rigid_bound_ = Eigen::VectorXd::Zero(ns_);
    eta_mag_ = b2_ = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(rep_.size()));
    y_ = ymag_ = Eigen::VectorXd::Zero(m);
    xmag_ = vmag_ = Eigen::VectorXd::Zero(n_);
    force_ = xf_ = vf_ = xfm_ = vfm_ = Eigen::VectorXd::Zero(nf_);
    sn_ = cs_ = Eigen::VectorXd::Zero(nh_);
    e_omega_ = Eigen::VectorXcd::Zero(nh_);
}

void StateSpaceSolver::setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) {
    lifetimes_.invalidate();
    const int m = 2 * ne_;
    const double s = scale_s_;
    for (int i = 0; i < n_; ++i) x_fix_(i) = x0[i];
    segment_force(t_, cfg_, x0, fseg_, slider_);
    release_force(t_, fseg_, sgn, frel_);
    for (int h = 0; h < nh_; ++h) {
        theta_(h) = hsnc_phase(t_.h_omega(h), t0, t0_lo, t_.h_phase(h));
        e_theta_(h) = cplx(std::cos(theta_(h)), std::sin(theta_(h)));
    }
    // Constant force on the free masses: loads and preloads, the coupling to
    // the stuck masses (their v = 0: no damper force), kinetic friction.
    Eigen::VectorXd f(nf_), x(nf_), v(nf_);
    for (int r = 0; r < nf_; ++r) {
        const int i = free_[r];
        force_(r) = f(r) = free_mass_force(t_, fseg_, stuck_, i, x0, sgn);
        x(r) = x0[i];
        v(r) = v0[i];
    }
    // Rigid coordinates: mass-weighted means; e: the rest at the non-pivot slots (T's construction).
    Eigen::VectorXd xe = x, ve = v;
    for (std::size_t j = 0; j < rigid_.size(); ++j) {
        const Rigid& rg = rigid_[j];
        double q = 0.0, qd = 0.0, fr = 0.0;
        if (rigid_w_.size() > 0) {  // coupled M: q = r^T M x / (r^T M r)
            const auto jj = static_cast<Eigen::Index>(j);
            q = rigid_w_.col(jj).dot(x), qd = rigid_w_.col(jj).dot(v);
            for (int r : rg.members) fr += f(r);
        } else {
            for (int r : rg.members) q += t_.mass(free_[r]) * x(r), qd += t_.mass(free_[r]) * v(r), fr += f(r);
        }
        q /= rg.mass;
        qd /= rg.mass;
        q0_(static_cast<Eigen::Index>(j)) = q;
        qd0_(static_cast<Eigen::Index>(j)) = qd;
        rigid_f_(static_cast<Eigen::Index>(j)) = fr / rg.mass;
        for (int r : rg.members) xe(r) -= q, ve(r) -= qd;
    }
    Eigen::VectorXcd b0 = Eigen::VectorXcd::Zero(m), y0(m);
    if (ne_ > 0) {
        const Eigen::VectorXd Tf = T_.transpose() * f;
        // With the static offset the modes see no constant force (b0 = 0) and start from y0 - y_s.
        if (offset_) {
            ys_ = Ke_lu_.solve(Tf);
            fe_.setZero();
        } else {
            ys_.setZero();
            fe_ = Me_lu_.solve(Tf) / s;
        }
        Eigen::VectorXd ex(ne_), ev(ne_);
        for (int c = 0; c < ne_; ++c)
            ex(c) = xe(e_slot_[static_cast<std::size_t>(c)]), ev(c) = ve(e_slot_[static_cast<std::size_t>(c)]);
        if (e_lt_.size() > 0) ex = e_lt_ * ex, ev = e_lt_ * ev;  // coupled M: e in mass-normalised form
        for (int c = 0; c < ne_; ++c) {
            b0(ne_ + c) = fe_(c);
            y0(c) = ex(c) - ys_(c);
            y0(ne_ + c) = ev(c) / s;
        }
    }
    for (int fn = 0; fn < ns_; ++fn) {
        double b = 0.0;
        for (std::size_t j = 0; j < rigid_.size(); ++j) {
            double amp = std::abs(rigid_f_(static_cast<Eigen::Index>(j))), rate = 0.0;
            for (int h = 0; h < nh_; ++h) {
                const double P = std::abs(rigid_h_(static_cast<Eigen::Index>(j), h));
                amp += P;
                rate += P * t_.h_omega(h);
            }
            b += std::abs(rigid_lx_(fn, static_cast<Eigen::Index>(j))) * amp +
                 std::abs(rigid_lv_(fn, static_cast<Eigen::Index>(j))) * rate;
        }
        rigid_bound_(fn) = b;
    }
    beta0_ = Vinv_ * b0;
    // eta0 = V^-1 y0, refined once against the residual y0 - Re(V eta0) (long
    // double), so that y0 -> eta0 -> y0 is no fixed bias per segment start.
    eta0_ = Vinv_ * y0;
    Eigen::VectorXcd res(m);
    for (int r = 0; r < m; ++r) {
        long double e = y0(r).real();
        for (int k = 0; k < m; ++k)
            e -= static_cast<long double>(V_(r, k).real()) * eta0_(k).real() -
                 static_cast<long double>(V_(r, k).imag()) * eta0_(k).imag();
        res(r) = static_cast<double>(e);
    }
    eta0_ += Vinv_ * res;
    // Once more against what eval computes at tau = 0 (its order, in double):
    // a state near the static offset is a sum of modal terms far larger than it
    // (near critical damping, 1e2 times: V is ill-conditioned), whose rounding
    // in eval is the error at the segment start.
    if (m > 0) {
        Eigen::VectorXcd er(static_cast<Eigen::Index>(rep_.size()));
        for (int c = 0; c < static_cast<int>(rep_.size()); ++c) er(c) = eta0_(rep_[static_cast<std::size_t>(c)]);
        Eigen::VectorXd yv(m);
        yv.noalias() = Vre_ * er.real();
        yv.noalias() -= Vim_ * er.imag();
        Eigen::VectorXcd r2(m);
        for (int r = 0; r < m; ++r) r2(r) = y0(r).real() - yv(r);
        eta0_ += Vinv_ * r2;
    }
    for (int k = 0; k < m; ++k) {
        mod_eta0_(k) = mod(eta0_(k));
        mod_beta0_(k) = mod(beta0_(k));
    }
}

void StateSpaceSolver::eval(double tau, const SegmentEval& out) const {
    const int m = 2 * ne_;
    const double s = scale_s_, s_end = tau + max_step_;
    for (int h = 0; h < nh_; ++h) {
        const double ph = t_.h_omega(h) * tau + theta_(h), wt = t_.h_omega(h) * tau;
        sn_(h) = std::sin(ph);
        cs_(h) = std::cos(ph);
        e_omega_(h) = cplx(std::cos(wt), std::sin(wt));
    }
    for (int c = 0; c < static_cast<int>(rep_.size()); ++c) {
        const int k = rep_[static_cast<std::size_t>(c)];
        const cplx lam = lambda_(k), el = expc(lam * tau);
        const double ael = std::exp(lam.real() * tau), l = mod_lambda_(k);
        // A growing mode (negative damping) is largest at the horizon's end.
        const double grow = lam.real() > 0.0 ? std::exp(lam.real() * max_step_) : 1.0, ahead = ael * grow;
        const double reach = lam.real() > 0.0 ? ahead : 1.0;
        cplx eta = el * eta0_(k);
        double mag = ael * mod_eta0_(k), b2 = l * l * mag * grow;
        if (beta0_(k) != cplx(0.0)) {
            const cplx E = duhamel(-lam, inv_d_(k, 0), tau, el, 1.0);
            eta += beta0_(k) * E;
            mag += mod(beta0_(k) * E);
            b2 += mod_beta0_(k) * duhamel_bound(l, 0.0, mod_d_(k, 0), mod_sum_(k, 0), ahead, reach, s_end);
        }
        for (int h = 0; h < nh_; ++h) {
            const cplx bh = beta_h_(k, h);
            if (bh == cplx(0.0)) continue;
            const double W = t_.h_omega(h);
            const cplx mu(0.0, W), ew = e_omega_(h);
            const int up = 1 + 2 * h, um = 2 + 2 * h;
            const cplx Ep = duhamel(mu - lam, inv_d_(k, up), tau, el, ew);
            const cplx Em = duhamel(-mu - lam, inv_d_(k, um), tau, el, std::conj(ew));
            const cplx c = bh * cplx(0.0, -0.5);  // beta/(2i)
            eta += c * (e_theta_(h) * Ep - std::conj(e_theta_(h)) * Em);
            const double cm = mod_beta_h_(k, h);
            mag += cm * (mod(Ep) + mod(Em));
            // The near-resonant form needs a finite horizon (max_step); a far one never does.
            const double sp = near_(k, 2 * h) ? s_end : kInf, sm = near_(k, 2 * h + 1) ? s_end : kInf;
            b2 += cm * (duhamel_bound(l, W, mod_d_(k, up), mod_sum_(k, up), ahead, reach, sp) +
                        duhamel_bound(l, W, mod_d_(k, um), mod_sum_(k, um), ahead, reach, sm));
        }
        eta_(c) = eta;
        deta_(c) = lam * eta;
        eta_mag_(c) = mag;
        b2_(c) = b2;
    }

    // y = Re(V eta): positions, velocities / s.
    write_at_rest(x_fix_, out, xmag_, vmag_);
    if (m > 0) {  // y = Re(V eta) and its magnitude |V| |eta|: two matrix-vector products
        y_.noalias() = Vre_ * eta_.real();
        y_.noalias() -= Vim_ * eta_.imag();
        ymag_.noalias() = absV_ * eta_mag_;
        B_.noalias() = absG_ * b2_;
        // y' = Re(V lambda eta) + b0 + sum_h b_h sin(Omega_h tau + theta_h): its velocity half
        // gives e'' = s y'_v, decaying with the modes (b0 = 0 about the static offset).
        dy_.noalias() = Vre_.bottomRows(ne_) * deta_.real();
        dy_.noalias() -= Vim_.bottomRows(ne_) * deta_.imag();
        for (int c = 0; c < ne_; ++c) {
            y_(c) += ys_(c);
            ymag_(c) += std::abs(ys_(c));
        }
    }
    // x_F = R q + T e, v_F = R q' + T e' (T: 1 at e's own slot, -m_i/m_p at its pivot).
    if (ne_ > 0) {
        xf_.noalias() = T_ * y_.head(ne_);
        vf_.noalias() = s * (T_ * y_.tail(ne_));
        xfm_.noalias() = absT_ * ymag_.head(ne_);
        vfm_.noalias() = s * (absT_ * ymag_.tail(ne_));
    } else {
        xf_.setZero();
        vf_.setZero();
        xfm_.setZero();
        vfm_.setZero();
    }
    for (std::size_t j = 0; j < rigid_.size(); ++j) {
        // q = q0 + q0' tau + f tau^2/2 + sum_h P_h (sin theta/W^2 + tau cos theta/W - sin(W tau + theta)/W^2).
        const Eigen::Index jj = static_cast<Eigen::Index>(j);
        double q = q0_(jj) + qd0_(jj) * tau + 0.5 * rigid_f_(jj) * tau * tau, qd = qd0_(jj) + rigid_f_(jj) * tau;
        double qm = std::abs(q0_(jj)) + std::abs(qd0_(jj) * tau) + std::abs(0.5 * rigid_f_(jj) * tau * tau);
        double qdm = std::abs(qd0_(jj)) + std::abs(rigid_f_(jj) * tau);
        for (int h = 0; h < nh_; ++h) {
            const double P = rigid_h_(jj, h), W = t_.h_omega(h), st = e_theta_(h).imag(), ct = e_theta_(h).real();
            q += P * (st / (W * W) + tau * ct / W - sn_(h) / (W * W));
            qd += P * (ct - cs_(h)) / W;
            qm += std::abs(P) * (2.0 / (W * W) + tau / W);
            qdm += 2.0 * std::abs(P) / W;
        }
        for (int r : rigid_[j].members) {
            xf_(r) += q;
            vf_(r) += qd;
            xfm_(r) += qm;
            vfm_(r) += qdm;
        }
    }
    for (int r = 0; r < nf_; ++r) {
        const int i = free_[r];
        out.x[i] = xf_(r);
        out.v[i] = vf_(r);
        xmag_(i) = xfm_(r);
        vmag_(i) = vfm_(r);
    }
    // a = x_F'' = T e'' + R q'', e'' = s (Re(V lambda eta) + b0 + b_h sin)'s velocity half
    // (state_space_solver.h: not M^-1 (f - K x - C v), which keeps the offset's rounding).
    if (ne_ > 0) {
        Eigen::VectorXd& ed = dy_;  // ne rows used
        ed.head(ne_) += fe_;
        for (int h = 0; h < nh_; ++h) ed.head(ne_) += bh_tail_.col(h) * sn_(h);
        af_.noalias() = s * (T_ * ed.head(ne_));
    } else {
        af_.setZero();
    }
    for (std::size_t j = 0; j < rigid_.size(); ++j) {
        const Eigen::Index jj = static_cast<Eigen::Index>(j);
        double qdd = rigid_f_(jj);
        for (int h = 0; h < nh_; ++h) qdd += rigid_h_(jj, h) * sn_(h);
        for (int r : rigid_[j].members) af_(r) += qdd;
    }
    for (int r = 0; r < nf_; ++r) out.a[free_[r]] = af_(r);

    write_sliders(t_, cfg_, slider_, out);
    for (int f = 0; f < ns_; ++f) {
        const SwitchFunction& sf = switches_[static_cast<std::size_t>(f)];
        double g, dg, scale;
        switch_value(sf, t_, t_.coupled() ? frel_ : fseg_, out, xmag_, vmag_, sn_, cs_, g, dg, scale);
        const double B = bound_sin_(f) + rigid_bound_(f) + (m > 0 ? B_(f) : 0.0);
        out.g[f] = g;
        out.dg[f] = dg;
        out.scale[f] = scale;
        out.bound[f] = B;
    }
}

std::vector<std::complex<double>> StateSpaceSolver::damped_modes() const {
    std::vector<cplx> modes;
    for (int k = 0; k < lambda_.size(); ++k)
        if (lambda_(k).imag() >= 0.0) modes.push_back(lambda_(k));
    std::sort(modes.begin(), modes.end(), [](cplx a, cplx b) {
        return std::abs(a) != std::abs(b) ? std::abs(a) < std::abs(b) : a.imag() > b.imag();
    });
    return modes;
}

// Mode k's coordinate is eta_k = C_k e^{lambda_k tau} plus the forced parts
// (beta0 E(lambda, 0) and the harmonics' E(lambda, +-i Omega)), C_k = eta0_k
// minus the forced parts' e^{lambda tau} coefficients: a term of rate
// |lambda_k| that decays as e^{Re lambda_k tau}. Its share of the state's
// position rows (y's first half: the coordinates e, mass-normalised for a
// coupled M) is |V_rk| |C_k| over row r's size (the static offset and every
// mode's whole magnitude). A mode near a forcing frequency (near_) counts
// throughout, as the forcing does.
void StateSpaceSolver::term_lifetimes(double tol) const {
    double forced = 0.0;
    for (int h = 0; h < nh_; ++h) forced = std::max(forced, t_.h_omega(h));
    lifetimes_.start(forced, tol);
    const int nr = static_cast<int>(rep_.size());
    for (int c = 0; c < nr; ++c) {  // |C_k| into eta_mag_, the mode's whole magnitude into b2_ (eval scratch)
        const int k = rep_[static_cast<std::size_t>(c)];
        cplx C = eta0_(k);
        double whole = mod_eta0_(k);
        if (beta0_(k) != cplx(0.0)) {
            C -= beta0_(k) * inv_d_(k, 0);
            whole += mod(beta0_(k) * inv_d_(k, 0));
        }
        for (int h = 0; h < nh_; ++h) {
            const cplx bh = beta_h_(k, h);
            if (bh == cplx(0.0)) continue;
            if (near_(k, 2 * h) || near_(k, 2 * h + 1)) lifetimes_.raise_forced(std::abs(lambda_(k)));
            const cplx ch = bh * cplx(0.0, -0.5);
            C -= ch * (e_theta_(h) * inv_d_(k, 1 + 2 * h) - std::conj(e_theta_(h)) * inv_d_(k, 2 + 2 * h));
            whole += mod(ch) * (mod(inv_d_(k, 1 + 2 * h)) + mod(inv_d_(k, 2 + 2 * h)));
        }
        eta_mag_(c) = mod(C);
        b2_(c) = whole + mod(C);
    }
    for (int r = 0; r < ne_; ++r) ymag_(r) = std::abs(ys_(r)) + absV_.row(r).dot(b2_);  // each row's size S_r
    for (int c = 0; c < nr; ++c) {
        const int k = rep_[static_cast<std::size_t>(c)];
        double share = 0.0;  // max_r |V_rk| / S_r over the position rows
        for (int r = 0; r < ne_; ++r)
            if (ymag_(r) > 0) share = std::max(share, absV_(r, c) / ymag_(r));
        lifetimes_.add(std::abs(lambda_(k)), -lambda_(k).real(), share * eta_mag_(c));
    }
}

double StateSpaceSolver::resolving_rate(double tau, double tol) const {
    if (!lifetimes_.valid(tol)) term_lifetimes(tol);
    return lifetimes_.rate_at(tau);
}

std::size_t StateSpaceSolver::memory_bytes() const {
    const std::size_t m = static_cast<std::size_t>(2 * nf_), n = static_cast<std::size_t>(n_);
    const std::size_t ns = static_cast<std::size_t>(ns_), nh = static_cast<std::size_t>(nh_);
    return sizeof(*this) + 16 * (3 * m * m + m * nh + 4 * m) + 8 * (m * m + ns * m + 2 * n * n + n * nh + 12 * n) +
           m * 2 * nh + 4 * ns;
}

}  // namespace hsnc
