// hsnc tests and benches -- an Euler-Bernoulli cantilever with consistent
// mass (Eigen only, no GoogleTest: bench/ builds it too).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Dense>

namespace hsnc::fe {

/// A cantilever of length 1 m, EI = 100 N m^2, 2 kg/m, in `elements`
/// Euler-Bernoulli elements with consistent mass; dofs w1, t1, ..., wN, tN
/// (the root clamped).
struct Beam {
    Eigen::MatrixXd M, K;
    std::vector<std::string> dofs;
    Eigen::Index tip = 0;  ///< the dof the forcing drives
};

/// An Euler-Bernoulli element of length h (dofs w, theta at both ends): its
/// stiffness and consistent mass.
inline void beam_element(double h, double EI, double rhoA, Eigen::Matrix4d& ke, Eigen::Matrix4d& me) {
    ke << 12, 6 * h, -12, 6 * h, 6 * h, 4 * h * h, -6 * h, 2 * h * h, -12, -6 * h, 12, -6 * h, 6 * h, 2 * h * h,
        -6 * h, 4 * h * h;
    ke *= EI / (h * h * h);
    me << 156, 22 * h, 54, -13 * h, 22 * h, 4 * h * h, 13 * h, -3 * h * h, 54, 13 * h, 156, -22 * h, -13 * h,
        -3 * h * h, -22 * h, 4 * h * h;
    me *= rhoA * h / 420;
}

inline Beam cantilever(int elements) {
    const double L = 1.0, EI = 100.0, rhoA = 2.0, h = L / elements;
    Eigen::Matrix4d ke, me;
    beam_element(h, EI, rhoA, ke, me);
    const int n = 2 * (elements + 1);
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n), K = Eigen::MatrixXd::Zero(n, n);
    for (int e = 0; e < elements; ++e) {
        M.block(2 * e, 2 * e, 4, 4) += me;
        K.block(2 * e, 2 * e, 4, 4) += ke;
    }
    Beam b{M.bottomRightCorner(n - 2, n - 2), K.bottomRightCorner(n - 2, n - 2), {}, n - 4};
    for (int k = 1; k <= elements; ++k) b.dofs.push_back("w" + std::to_string(k)), b.dofs.push_back("t" + std::to_string(k));
    return b;
}

}  // namespace hsnc::fe
