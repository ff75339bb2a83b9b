// hsnc tests and benches -- a 3D solid of trilinear hexahedra (hex8, full
// 2x2x2 Gauss integration, isotropic linear elasticity, consistent mass),
// assembled sparse: a plate clamped on its face x = 0, the finite-element
// structure that [reduction] (model/reduction.h) exists for. Written from
// the textbook element (no hsnc code), so it is an independent model.
#pragma once

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/SparseCore>

namespace hsnc::fe {

struct Solid {
    Eigen::SparseMatrix<double> M, K;
    std::vector<std::string> dofs;  ///< "n<node>x|y|z" of every free node
    std::size_t tip = 0;            ///< the z dof of the free corner (Lx, Ly, Lz)
};

/// Element stiffness and consistent mass of a dx x dy x dz brick.
inline void hex8_element(double dx, double dy, double dz, double E, double nu, double rho,
                         Eigen::Matrix<double, 24, 24>& ke, Eigen::Matrix<double, 24, 24>& me) {
    Eigen::Matrix<double, 6, 6> D = Eigen::Matrix<double, 6, 6>::Zero();
    const double l = E * nu / ((1 + nu) * (1 - 2 * nu)), mu = E / (2 * (1 + nu));
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) D(i, j) = l;
        D(i, i) = l + 2 * mu;
        D(3 + i, 3 + i) = mu;
    }
    const int corner[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                              {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
    const double g = 1.0 / std::sqrt(3.0), detJ = dx * dy * dz / 8.0;
    ke.setZero();
    me.setZero();
    for (int p = 0; p < 8; ++p) {
        const double xi = corner[p][0] * g, eta = corner[p][1] * g, zeta = corner[p][2] * g;
        Eigen::Matrix<double, 6, 24> B = Eigen::Matrix<double, 6, 24>::Zero();
        Eigen::Matrix<double, 3, 24> N = Eigen::Matrix<double, 3, 24>::Zero();
        for (int a = 0; a < 8; ++a) {
            const double sx = corner[a][0], sy = corner[a][1], sz = corner[a][2];
            const double n = (1 + sx * xi) * (1 + sy * eta) * (1 + sz * zeta) / 8.0;
            const double nx = sx * (1 + sy * eta) * (1 + sz * zeta) / 8.0 * 2.0 / dx;
            const double ny = sy * (1 + sx * xi) * (1 + sz * zeta) / 8.0 * 2.0 / dy;
            const double nz = sz * (1 + sx * xi) * (1 + sy * eta) / 8.0 * 2.0 / dz;
            B(0, 3 * a) = nx, B(1, 3 * a + 1) = ny, B(2, 3 * a + 2) = nz;
            B(3, 3 * a) = ny, B(3, 3 * a + 1) = nx;
            B(4, 3 * a + 1) = nz, B(4, 3 * a + 2) = ny;
            B(5, 3 * a) = nz, B(5, 3 * a + 2) = nx;
            for (int d = 0; d < 3; ++d) N(d, 3 * a + d) = n;
        }
        ke += B.transpose() * D * B * detJ;
        me += rho * N.transpose() * N * detJ;
    }
}

/// A plate Lx x Ly x Lz of nx x ny x nz bricks, clamped at x = 0.
inline Solid hex8_plate(int nx, int ny, int nz, double Lx, double Ly, double Lz, double E = 2.1e11, double nu = 0.3,
                        double rho = 7800.0) {
    Eigen::Matrix<double, 24, 24> ke, me;
    hex8_element(Lx / nx, Ly / ny, Lz / nz, E, nu, rho, ke, me);
    auto node = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
    const int nodes = (nx + 1) * (ny + 1) * (nz + 1);
    std::vector<int> dof(3 * static_cast<std::size_t>(nodes), -1);
    Solid s;
    for (int k = 0; k <= nz; ++k)
        for (int j = 0; j <= ny; ++j)
            for (int i = 1; i <= nx; ++i)  // i = 0 clamped
                for (int d = 0; d < 3; ++d) {
                    dof[3 * static_cast<std::size_t>(node(i, j, k)) + d] = static_cast<int>(s.dofs.size());
                    s.dofs.push_back("n" + std::to_string(node(i, j, k)) + "xyz"[d]);
                }
    s.tip = static_cast<std::size_t>(dof[3 * static_cast<std::size_t>(node(nx, ny, nz)) + 2]);
    std::vector<Eigen::Triplet<double>> K, M;
    const int at[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    for (int k = 0; k < nz; ++k)
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                std::array<int, 24> map{};
                for (int a = 0; a < 8; ++a)
                    for (int d = 0; d < 3; ++d)
                        map[3 * a + d] = dof[3 * static_cast<std::size_t>(node(i + at[a][0], j + at[a][1], k + at[a][2])) + d];
                for (int r = 0; r < 24; ++r)
                    for (int c = 0; c < 24; ++c)
                        if (map[r] >= 0 && map[c] >= 0) {
                            K.emplace_back(map[r], map[c], ke(r, c));
                            M.emplace_back(map[r], map[c], me(r, c));
                        }
            }
    const auto n = static_cast<Eigen::Index>(s.dofs.size());
    s.K.resize(n, n), s.M.resize(n, n);
    s.K.setFromTriplets(K.begin(), K.end());
    s.M.setFromTriplets(M.begin(), M.end());
    return s;
}

/// The lower triangle, Matrix Market coordinate symmetric, 17 digits.
inline void write_market(const std::string& path, const Eigen::SparseMatrix<double>& A) {
    std::vector<std::array<double, 3>> lower;
    for (Eigen::Index c = 0; c < A.outerSize(); ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator it(A, c); it; ++it)
            if (it.row() >= it.col() && it.value() != 0.0)
                lower.push_back({static_cast<double>(it.row() + 1), static_cast<double>(it.col() + 1), it.value()});
    std::FILE* f = std::fopen(path.c_str(), "w");
    if (!f) return;
    std::fprintf(f, "%%%%MatrixMarket matrix coordinate real symmetric\n%ld %ld %zu\n", static_cast<long>(A.rows()),
                 static_cast<long>(A.cols()), lower.size());
    for (const auto& e : lower) std::fprintf(f, "%.0f %.0f %.17g\n", e[0], e[1], e[2]);
    std::fclose(f);
}

/// The structure model's TOML head: name, [structure] over the solid's dofs, M.mtx and K.mtx.
inline std::string solid_structure(const std::string& name, const Solid& s) {
    std::string t = "name = \"" + name + "\"\n[structure]\ndofs = [";
    for (std::size_t i = 0; i < s.dofs.size(); ++i) t += (i ? ", \"" : "\"") + s.dofs[i] + "\"";
    return t + "]\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n";
}

}  // namespace hsnc::fe
