// hsnc -- the energy scaling of a state (x, v) with stiffness K and mass M:
// zb = (U_K x, U_M v), K = U_K^T U_K and M = U_M^T U_M (Cholesky). There the
// undamped modes are orthogonal whatever their frequencies, so an eigenvector
// matrix's condition measures closeness to critical damping rather than a
// finite-element structure's spread of frequencies, and a state matrix's norm is
// of the highest natural frequency rather than of M^-1 K. The state-space solver
// (its eigenvectors) and the matrix exponential (its generator) take their
// factors here; the derivation forms the same in double-double
// (generator/derivation.cpp energy_scaled()).
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace hsnc {

struct EnergyScaling {
    Eigen::MatrixXd UK, UK_inv, UM, UM_inv;  ///< U_K, U_K^-1, U_M, U_M^-1 (upper triangular)
};

/// The factors of K and M, or false (nothing set) where either is not positive
/// definite or K is regular by rounding only (a diagonal of its factor below
/// 1e-7 of the largest: a translation that only a damper holds).
inline bool energy_scaling(const Eigen::MatrixXd& K, const Eigen::MatrixXd& M, EnergyScaling& out) {
    if (K.rows() == 0) return false;
    const Eigen::LLT<Eigen::MatrixXd> lk(K), lm(M);
    if (lk.info() != Eigen::Success || lm.info() != Eigen::Success) return false;
    const Eigen::VectorXd d = lk.matrixL().toDenseMatrix().diagonal();
    if (!(d.minCoeff() > 1e-7 * d.maxCoeff())) return false;
    const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(K.rows(), K.rows());
    out.UK = lk.matrixU().toDenseMatrix();
    out.UM = lm.matrixU().toDenseMatrix();
    out.UK_inv = lk.matrixU().solve(I);
    out.UM_inv = lm.matrixU().solve(I);
    return true;
}

}  // namespace hsnc
