// mp_complex_eigen (generator/mp_complex_eigen.h): the state-space modes of
// non-proportional damping at 40 digits. The state matrices of damper models
// (underdamped pairs, overdamped real roots, an undamped mode), checked at
// the working precision: A V_k = lambda_k V_k, V^-1 V = I, conjugate pairs
// exactly conjugate, and the eigenvalues against the double solve and, for a
// 1-DOF oscillator, against the roots of m s^2 + c s + k = 0.
#include <gtest/gtest.h>

#include <cln/cln.h>

#include <Eigen/Core>

#include <cmath>
#include <complex>
#include <cstdio>
#include <string>
#include <vector>

#include "assembly.h"
#include "configuration.h"
#include "error.h"
#include "mp_complex_eigen.h"

namespace hsnc {
namespace {

using cln::cl_N;
using cln::cl_R;

const cln::float_format_t kFormat = cln::float_format(40);

// The state matrix [0, I; -M^-1 K, -M^-1 C] of the free masses, from exact
// rationals of the model's doubles (converted to 40-digit long floats).
std::vector<std::vector<cl_R>> state_matrix(const Model& md) {
    const Configuration cfg = Configuration::all_open(md);
    const Eigen::MatrixXd K = stiffness_matrix(md, cfg), C = damping_matrix(md, cfg);
    const std::size_t n = md.dof();
    std::vector<std::vector<cl_R>> A(2 * n, std::vector<cl_R>(2 * n, cl_R(0)));
    auto F = [](double d) { return cln::cl_float(d, kFormat); };
    for (std::size_t i = 0; i < n; ++i) {
        A[i][n + i] = F(1.0);
        const cl_R m = F(md.masses[i].m);
        for (std::size_t j = 0; j < n; ++j) {
            const auto ii = static_cast<Eigen::Index>(i), jj = static_cast<Eigen::Index>(j);
            if (K(ii, jj) != 0.0) A[n + i][j] = -F(K(ii, jj)) / m;
            if (C(ii, jj) != 0.0) A[n + i][n + j] = -F(C(ii, jj)) / m;
        }
    }
    return A;
}

Model chain(const std::vector<double>& dampers) {
    Model md;
    md.name = "chain";
    for (int i = 0; i < 3; ++i) md.masses.push_back({"m" + std::to_string(i + 1), 1.0 + 0.5 * i});
    md.springs = {{kGround, 0, 40.0}, {0, 1, 25.0}, {1, 2, 30.0}, {2, kGround, 10.0}};
    for (std::size_t d = 0; d < dampers.size(); ++d)
        if (dampers[d] > 0) md.dampers.push_back({static_cast<int>(d), static_cast<int>(d + 1) % 3, dampers[d]});
    md.load.assign(3, 0.0);
    md.x0.assign(3, 0.0);
    md.v0.assign(3, 0.0);
    return md;
}

// Largest |.| of a vector of complex numbers, as a double.
double largest(const std::vector<cl_N>& v) {
    double m = 0.0;
    for (const cl_N& z : v) m = std::max(m, cln::double_approx(cln::abs(z)));
    return m;
}

void expect_exact_decomposition(const Model& md, const std::string& what) {
    const std::vector<std::vector<cl_R>> A = state_matrix(md);
    const std::size_t n = A.size();
    const MpComplexEigen e = mp_complex_eigen(A, kFormat);
    ASSERT_EQ(e.values.size(), n) << what;
    double norm = 0.0;
    for (const auto& row : A)
        for (const cl_R& x : row) norm = std::max(norm, std::fabs(cln::double_approx(x)));
    double residual = 0.0, identity = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
        std::vector<cl_N> r(n);
        for (std::size_t i = 0; i < n; ++i) {
            cl_N s = -(e.values[k] * e.vectors[k][i]);
            for (std::size_t j = 0; j < n; ++j) s = s + A[i][j] * e.vectors[k][j];
            r[i] = s;
        }
        residual = std::max(residual, largest(r) / (norm * largest(e.vectors[k])));
        for (std::size_t c = 0; c < n; ++c) {
            cl_N s = k == c ? cl_N(-1) : cl_N(0);
            for (std::size_t i = 0; i < n; ++i) s = s + e.inverse[k][i] * e.vectors[c][i];
            identity = std::max(identity, cln::double_approx(cln::abs(s)));
        }
        if (k + 1 < n && cln::double_approx(cln::imagpart(e.values[k])) > 0) {  // its conjugate follows, exactly
            EXPECT_TRUE(e.values[k + 1] == cln::conjugate(e.values[k])) << what;
            for (std::size_t i = 0; i < n; ++i) EXPECT_TRUE(e.vectors[k + 1][i] == cln::conjugate(e.vectors[k][i]));
        }
    }
    std::printf("%s: |A V - V Lambda| %.2g, |V^-1 V - I| %.2g (relative, 40 digits)\n", what.c_str(), residual, identity);
    EXPECT_LT(residual, 1e-36) << what;
    EXPECT_LT(identity, 1e-35) << what;
}

TEST(MpComplexEigen, StateMatricesOfDamperModelsAt40Digits) {
    expect_exact_decomposition(chain({0.5, 0.0, 0.0}), "one dashpot (underdamped pairs)");
    expect_exact_decomposition(chain({0.5, 2.0, 0.3}), "three dashpots");
    expect_exact_decomposition(chain({30.0, 0.0, 25.0}), "heavy dashpots (overdamped, real roots)");
}

// m s^2 + c s + k = 0: s = (-c +- sqrt(c^2 - 4 m k)) / (2m), at 40 digits.
TEST(MpComplexEigen, OneDofRootsAgainstTheQuadraticFormula) {
    for (double c : {0.4, 3.0, 30.0}) {
        Model md;
        md.name = "one";
        md.masses = {{"m1", 2.0}};
        md.springs = {{kGround, 0, 50.0}};
        md.dampers = {{0, kGround, c}};
        md.load = {0.0};
        md.x0 = md.v0 = {0.0};
        const MpComplexEigen e = mp_complex_eigen(state_matrix(md), kFormat);
        const cl_R m = cln::cl_float(2, kFormat), k = cln::cl_float(50, kFormat), cc = cln::cl_float(c, kFormat);
        const cl_N disc = cln::sqrt(cl_N(cc * cc - 4 * m * k));
        const cl_N s1 = (-cc + disc) / (2 * m), s2 = (-cc - disc) / (2 * m);
        double worst = 1.0;
        for (const cl_N& l : e.values) {
            const double d = std::min(cln::double_approx(cln::abs(l - s1)), cln::double_approx(cln::abs(l - s2)));
            worst = worst == 1.0 ? d : std::max(worst, d);
        }
        EXPECT_LT(worst, 1e-36) << "c = " << c;
    }
}

// The derivation's decomposition in double-double against the 40-digit one,
// on the same matrices (the DD matrix's exact value given to CLN): the
// eigenvalues to 1e-29 of |A|, and V and V^-1 (both with v_p = 1 for the
// largest component) to 1e-27 (DD's 2^-104 times the eigenvectors' condition).
TEST(MpComplexEigen, DoubleDoubleAgreesWith40Digits) {
    int checked = 0;
    for (const Model& md : {chain({0.5, 0.0, 0.0}), chain({0.5, 2.0, 0.3}), chain({30.0, 0.0, 25.0}), chain({0.0, 0.0, 0.0})}) {
        const std::vector<std::vector<cl_R>> A = state_matrix(md);
        const std::size_t n = A.size();
        std::vector<std::vector<DD>> a(n, std::vector<DD>(n));
        std::vector<std::vector<cl_R>> exact_a(n, std::vector<cl_R>(n, cl_R(0)));
        double norm = 0;
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t j = 0; j < n; ++j) {
                if (cln::zerop(A[i][j])) continue;
                const double hi = cln::double_approx(A[i][j]);
                a[i][j] = DD(hi) + DD(cln::double_approx(A[i][j] - cln::rational(cln::cl_DF(hi))));
                exact_a[i][j] = cln::cl_float(cln::rational(cln::cl_DF(a[i][j].hi())) + cln::rational(cln::cl_DF(a[i][j].lo())), kFormat);
                norm = std::max(norm, std::fabs(hi));
            }
        const DdComplexEigen d = dd_complex_eigen(a);
        const MpComplexEigen e = mp_complex_eigen(exact_a, kFormat);
        ASSERT_EQ(d.values.size(), n);
        auto gap = [](const DDComplex& x, const cl_N& y) {
            const cl_N z = cln::complex(cln::rational(cln::cl_DF(x.re.hi())) + cln::rational(cln::cl_DF(x.re.lo())),
                                        cln::rational(cln::cl_DF(x.im.hi())) + cln::rational(cln::cl_DF(x.im.lo())));
            return cln::double_approx(cln::abs(z - y));
        };
        double wv = 0, wvec = 0, winv = 0;
        for (std::size_t k = 0; k < n; ++k) {
            wv = std::max(wv, gap(d.values[k], e.values[k]) / norm);
            for (std::size_t i = 0; i < n; ++i) {
                wvec = std::max(wvec, gap(d.vectors[k][i], e.vectors[k][i]));
                winv = std::max(winv, gap(d.inverse[k][i], e.inverse[k][i]));
            }
        }
        EXPECT_LE(wv, 1e-29) << md.dampers.size();
        EXPECT_LE(wvec, 1e-27) << md.dampers.size();
        EXPECT_LE(winv, 1e-27) << md.dampers.size();
        std::printf("DD against 40 digits (%zu dampers): eigenvalues %.2g of |A|, V %.2g, V^-1 %.2g\n", md.dampers.size(), wv,
                    wvec, winv);
        ++checked;
    }
    EXPECT_EQ(checked, 4);
}

TEST(MpComplexEigen, CriticalDampingIsRefused) {
    Model md;
    md.name = "critical";
    md.masses = {{"m1", 2.0}};
    md.springs = {{kGround, 0, 50.0}};
    md.dampers = {{0, kGround, 20.0}};  // c = 2 sqrt(k m)
    md.load = {0.0};
    md.x0 = md.v0 = {0.0};
    EXPECT_THROW(mp_complex_eigen(state_matrix(md), kFormat), RunError);
}

}  // namespace
}  // namespace hsnc
