#include "modal.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include "assembly.h"
#include "error.h"
#include "free_components.h"

namespace hsnc {
namespace {

// A coupled M (modal.h): one generalized eigenproblem over all free masses,
// M_FF and K_FF (a dof stuck to the ground is held still; no dof rides a
// partner: model_reader takes friction against the ground only on a coupled M).
void coupled_modes(const Model& model, const Configuration& cfg, const FreeComponents& fc, ModalDecomposition& md) {
    const int nf = static_cast<int>(md.free.size());
    if (!md.riders.empty())
        throw RunError("modal_analysis(): configuration " + cfg.spec(model) +
                       ": a dof stuck to another on a coupled mass matrix (not yet supported)");
    const Eigen::MatrixXd Kfull = stiffness_matrix(model, cfg);
    const Eigen::MatrixXd Kf = Kfull(md.free, md.free), Mf = mass_matrix(model, md.free);
    md.mass = Mf.diagonal();
    md.mass_matrix = Mf;
    // The structural rigid-body modes, M-orthonormalised in component order.
    const int nr = fc.n_floating();
    Eigen::MatrixXd R = Eigen::MatrixXd::Zero(nf, nr);
    std::vector<int> rigid_component;
    for (int comp = 0, col = 0; comp < fc.count(); ++comp) {
        if (!fc.floating[static_cast<std::size_t>(comp)]) continue;
        for (int s = 0; s < nf; ++s)
            if (md.component[static_cast<std::size_t>(s)] == comp) R(s, col) = 1.0;
        rigid_component.push_back(comp);
        ++col;
    }
    for (int c = 0; c < nr; ++c) {  // modified Gram-Schmidt in the M inner product
        for (int p = 0; p < c; ++p) R.col(c) -= (R.col(p).dot(Mf * R.col(c))) * R.col(p);
        R.col(c) /= std::sqrt(R.col(c).dot(Mf * R.col(c)));
    }
    // Elastic modes in the M-orthogonal complement {x : R^T M x = 0}.
    Eigen::MatrixXd Q = Eigen::MatrixXd::Identity(nf, nf);
    if (nr > 0) {
        const Eigen::MatrixXd Y = Mf * R;
        Eigen::HouseholderQR<Eigen::MatrixXd> qr(Y);
        Q = (qr.householderQ() * Eigen::MatrixXd::Identity(nf, nf)).rightCols(nf - nr);
    }
    Eigen::MatrixXd Z;
    Eigen::VectorXd lam;
    if (nf - nr > 0) {
        const Eigen::MatrixXd Kq = Q.transpose() * Kf * Q, Mq = Q.transpose() * Mf * Q;
        Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (Kq + Kq.transpose()),
                                                                    0.5 * (Mq + Mq.transpose()));
        if (es.info() != Eigen::Success)
            throw RunError("modal_analysis(): generalized eigen decomposition failed for configuration " +
                           cfg.spec(model));
        Z = es.eigenvectors();  // Z^T Mq Z = I
        lam = es.eigenvalues();
    }
    md.phi.resize(nf, nf);
    md.lambda.resize(nf);
    md.rigid.assign(static_cast<std::size_t>(nf), 0);
    md.mode_component.assign(static_cast<std::size_t>(nf), -1);
    for (int c = 0; c < nr; ++c) {
        md.phi.col(c) = R.col(c);
        md.lambda(c) = 0.0;
        md.rigid[static_cast<std::size_t>(c)] = 1;
        md.mode_component[static_cast<std::size_t>(c)] = rigid_component[static_cast<std::size_t>(c)];
    }
    for (int k = 0; k < nf - nr; ++k) {
        md.phi.col(nr + k) = Q * Z.col(k);
        md.lambda(nr + k) = std::max(lam(k), 0.0);
    }
}

}  // namespace

ModalDecomposition modal_analysis(const Model& model, const Configuration& cfg) {
    const int n = static_cast<int>(model.dof());
    ModalDecomposition md;
    // Components and the floating ones (free_components.h: the structural rule).
    const FreeComponents fc = free_components(model, cfg);
    md.free = fc.free;
    for (int i = 0; i < n; ++i)
        if (fixed_in(model, cfg, static_cast<std::size_t>(i))) md.stuck.push_back(i);
        else if (cfg.stuck[i]) md.riders.push_back(i);
    const int nf = static_cast<int>(md.free.size());
    md.component = fc.component;
    md.n_components = fc.count();
    if (model.coupled_mass()) {
        coupled_modes(model, cfg, fc, md);
        return md;
    }

    // The free coordinates: a free mass with its riders (their masses and
    // stiffness rows summed: T^T M T and T^T K T of x = T q + const).
    const Eigen::MatrixXd Kfull = stiffness_matrix(model, cfg);
    const Eigen::VectorXd mfull = mass_vector(model);
    std::vector<int> coordinate(static_cast<std::size_t>(n), -1);
    for (int s = 0; s < nf; ++s) coordinate[static_cast<std::size_t>(md.free[s])] = s;
    for (int i : md.riders)
        coordinate[static_cast<std::size_t>(i)] =
            coordinate[static_cast<std::size_t>(carrier(model, cfg, static_cast<std::size_t>(i)))];
    Eigen::MatrixXd Kf = Eigen::MatrixXd::Zero(nf, nf);
    md.mass = Eigen::VectorXd::Zero(nf);
    for (int i = 0; i < n; ++i) {
        const int r = coordinate[static_cast<std::size_t>(i)];
        if (r < 0) continue;
        md.mass(r) += mfull(i);
        for (int j = 0; j < n; ++j)
            if (coordinate[static_cast<std::size_t>(j)] >= 0) Kf(r, coordinate[static_cast<std::size_t>(j)]) += Kfull(i, j);
    }

    struct Mode {
        double lambda;
        bool rigid;
        int comp;
        Eigen::VectorXd shape;  // over F
    };
    std::vector<Mode> modes;
    modes.reserve(static_cast<std::size_t>(nf));

    for (int comp = 0; comp < md.n_components; ++comp) {
        std::vector<int> members;  // indices into F
        const bool anchored = !fc.floating[static_cast<std::size_t>(comp)];
        for (int s = 0; s < nf; ++s)
            if (md.component[s] == comp) members.push_back(s);
        const Eigen::Index nc = static_cast<Eigen::Index>(members.size());
        // Symmetric form Kt = M^-1/2 K M^-1/2; its orthonormal eigenvectors w
        // give the mass-normalised modes phi = M^-1/2 w.
        Eigen::VectorXd inv_sqrt_m(nc);
        Eigen::MatrixXd Kt(nc, nc);
        for (Eigen::Index r = 0; r < nc; ++r) inv_sqrt_m(r) = 1.0 / std::sqrt(md.mass(members[r]));
        for (Eigen::Index r = 0; r < nc; ++r)
            for (Eigen::Index c = 0; c < nc; ++c)
                Kt(r, c) = inv_sqrt_m(r) * Kf(members[r], members[c]) * inv_sqrt_m(c);

        Eigen::MatrixXd W;  // mass-weighted mode shapes (columns)
        Eigen::VectorXd lam;
        if (anchored) {
            Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Kt);
            if (es.info() != Eigen::Success)
                throw RunError("modal_analysis(): eigen decomposition failed for configuration " +
                               cfg.spec(model));
            W = es.eigenvectors();
            lam = es.eigenvalues();
        } else {
            // Rigid-body mode w0 = sqrt(m)/sqrt(M_total) (unit vector; Kt w0 = 0
            // because the component's K rows sum to zero). The other modes live in
            // its orthogonal complement Q (from a Householder reflection of w0).
            double total = 0.0;
            for (int s : members) total += md.mass(s);
            Eigen::VectorXd w0(nc);
            for (Eigen::Index r = 0; r < nc; ++r) w0(r) = std::sqrt(md.mass(members[r]) / total);
            W.resize(nc, nc);
            lam.resize(nc);
            W.col(0) = w0;
            lam(0) = 0.0;
            if (nc > 1) {
                Eigen::HouseholderQR<Eigen::MatrixXd> qr(w0);
                const Eigen::MatrixXd Qfull = qr.householderQ() * Eigen::MatrixXd::Identity(nc, nc);
                const Eigen::MatrixXd Q = Qfull.rightCols(nc - 1);
                const Eigen::MatrixXd Kq = Q.transpose() * Kt * Q;
                Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (Kq + Kq.transpose()));
                if (es.info() != Eigen::Success)
                    throw RunError("modal_analysis(): eigen decomposition failed for configuration " +
                                   cfg.spec(model));
                W.rightCols(nc - 1) = Q * es.eigenvectors();
                lam.tail(nc - 1) = es.eigenvalues();
            }
        }
        for (Eigen::Index k = 0; k < nc; ++k) {
            Mode md_k{std::max(lam(k), 0.0), !anchored && k == 0, comp, Eigen::VectorXd::Zero(nf)};
            for (Eigen::Index r = 0; r < nc; ++r) md_k.shape(members[r]) = inv_sqrt_m(r) * W(r, k);
            if (md_k.rigid) {
                // phi = 1/sqrt(total mass) exactly on the component.
                double total = 0.0;
                for (int s : members) total += md.mass(s);
                for (int s : members) md_k.shape(s) = 1.0 / std::sqrt(total);
            }
            modes.push_back(std::move(md_k));
        }
    }

    // Ascending lambda, rigid modes first; stable so the order is deterministic.
    std::stable_sort(modes.begin(), modes.end(), [](const Mode& a, const Mode& b) {
        if (a.rigid != b.rigid) return a.rigid;
        return a.lambda < b.lambda;
    });
    md.phi.resize(nf, nf);
    md.lambda.resize(nf);
    md.rigid.resize(static_cast<std::size_t>(nf));
    md.mode_component.resize(static_cast<std::size_t>(nf));
    for (int j = 0; j < nf; ++j) {
        md.phi.col(j) = modes[j].shape;
        md.lambda(j) = modes[j].lambda;
        md.rigid[j] = modes[j].rigid ? 1 : 0;
        md.mode_component[j] = modes[j].comp;
    }
    return md;
}

}  // namespace hsnc
