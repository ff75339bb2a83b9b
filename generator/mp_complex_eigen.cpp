#include "mp_complex_eigen.h"

#include <cln/float.h>
#include <cln/lfloat.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <cmath>
#include <complex>
#include <string>

#include "error.h"

namespace hsnc {
namespace {

using cln::cl_N;
using cln::cl_R;
using Matrix = std::vector<std::vector<cl_N>>;

cl_N from_double(std::complex<double> z, cln::float_format_t format) {
    return cln::complex(cln::cl_float(z.real(), format), cln::cl_float(z.imag(), format));
}

}  // namespace

bool mp_solve(Matrix M, std::vector<cl_N>& b) {
    const std::size_t n = M.size();
    for (std::size_t c = 0; c < n; ++c) {
        std::size_t p = c;
        cl_R best = cln::abs(M[c][c]);
        for (std::size_t r = c + 1; r < n; ++r)
            if (const cl_R m = cln::abs(M[r][c]); m > best) best = m, p = r;
        if (cln::zerop(best)) return false;
        std::swap(M[c], M[p]);
        std::swap(b[c], b[p]);
        for (std::size_t r = c + 1; r < n; ++r) {
            if (cln::zerop(M[r][c])) continue;
            const cl_N f = M[r][c] / M[c][c];
            for (std::size_t k = c; k < n; ++k) M[r][k] = M[r][k] - f * M[c][k];
            b[r] = b[r] - f * b[c];
        }
    }
    for (std::size_t c = n; c-- > 0;) {
        cl_N s = b[c];
        for (std::size_t k = c + 1; k < n; ++k) s = s - M[c][k] * b[k];
        b[c] = s / M[c][c];
    }
    return true;
}

MpComplexEigen mp_complex_eigen(const std::vector<std::vector<cl_R>>& a, cln::float_format_t format) {
    const std::size_t n = a.size();
    MpComplexEigen out;
    if (n == 0) return out;
    Eigen::MatrixXd A(n, n);
    cl_R norm = cln::cl_float(0, format);
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j) {
            A(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = cln::double_approx(a[i][j]);
            norm = cln::max(norm, cln::abs(a[i][j]));
        }
    const Eigen::EigenSolver<Eigen::MatrixXd> es(A);
    if (es.info() != Eigen::Success) throw RunError("mp_complex_eigen(): the double eigen-solver did not converge");
    const Eigen::MatrixXcd V = es.eigenvectors();
    const Eigen::MatrixXcd Vinv = V.inverse();
    const double condition = V.cwiseAbs().colwise().sum().maxCoeff() * Vinv.cwiseAbs().colwise().sum().maxCoeff();
    if (!(condition <= kMaxEigenCondition))
        throw RunError("mp_complex_eigen(): the eigenvectors are nearly dependent (condition " +
                       std::to_string(condition) + " > " + std::to_string(static_cast<int>(kMaxEigenCondition)) + ": a defective matrix, critical damping)");

    const cl_R tol = cln::float_epsilon(format) * cln::cl_float(1024, format) * norm;
    out.values.resize(n);
    out.vectors.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
        const std::complex<double> l = es.eigenvalues()(static_cast<Eigen::Index>(k));
        if (k > 0 && l.imag() < 0.0 && es.eigenvalues()(static_cast<Eigen::Index>(k - 1)) == std::conj(l)) {
            // The conjugate of the pair's first: exactly.
            out.values[k] = cln::conjugate(out.values[k - 1]);
            out.vectors[k].resize(n);
            for (std::size_t i = 0; i < n; ++i) out.vectors[k][i] = cln::conjugate(out.vectors[k - 1][i]);
            continue;
        }
        const bool real = l.imag() == 0.0;
        // v scaled so that its largest component is 1.
        std::size_t p = 0;
        for (std::size_t i = 1; i < n; ++i)
            if (std::abs(V(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k))) >
                std::abs(V(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(k))))
                p = i;
        const std::complex<double> vp = V(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(k));
        std::vector<cl_N> v(n);
        for (std::size_t i = 0; i < n; ++i) {
            std::complex<double> c = V(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) / vp;
            if (real) c = c.real();
            v[i] = from_double(c, format);
        }
        v[p] = cln::cl_float(1, format);
        cl_N lam = from_double(real ? std::complex<double>(l.real(), 0.0) : l, format);
        // Simplified Newton first: the Jacobian of the double solution, factorised once in
        // double, each residual at the working precision; each step gains the digits of
        // double over the Jacobian's condition (16 -> ~30 -> ~45), at O(n^2) long-float
        // operations a step instead of the O(n^3) of an exact Newton step.
        Eigen::MatrixXcd J0 = Eigen::MatrixXcd::Zero(static_cast<Eigen::Index>(n + 1), static_cast<Eigen::Index>(n + 1));
        for (std::size_t i = 0; i < n; ++i) {
            for (std::size_t j = 0; j < n; ++j) J0(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = A(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
            J0(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i)) -= (real ? std::complex<double>(l.real(), 0.0) : l);
            J0(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(n)) = -std::complex<double>(cln::double_approx(cln::realpart(v[i])), cln::double_approx(cln::imagpart(v[i])));
        }
        J0(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(p)) = 1.0;
        const Eigen::PartialPivLU<Eigen::MatrixXcd> J0_lu(J0);
        auto residual = [&](std::vector<cl_N>& r) {  // r = -(A v - lam v); returns max |A v - lam v|
            cl_R worst = cln::cl_float(0, format);
            for (std::size_t i = 0; i < n; ++i) {
                cl_N s = -(lam * v[i]);
                for (std::size_t j = 0; j < n; ++j)
                    if (!cln::zerop(a[i][j])) s = s + a[i][j] * v[j];
                r[i] = -s;
                worst = cln::max(worst, cln::abs(s));
            }
            return worst;
        };
        bool converged = false;
        for (int it = 0; it < 8 && !converged; ++it) {
            std::vector<cl_N> r(n + 1);
            if (residual(r) <= tol) {
                converged = true;
                break;
            }
            Eigen::VectorXcd rd(static_cast<Eigen::Index>(n + 1));
            for (std::size_t i = 0; i < n; ++i)
                rd(static_cast<Eigen::Index>(i)) = {cln::double_approx(cln::realpart(r[i])), cln::double_approx(cln::imagpart(r[i]))};
            rd(static_cast<Eigen::Index>(n)) = 0.0;
            const Eigen::VectorXcd dd = J0_lu.solve(rd);
            for (std::size_t i = 0; i < n; ++i) v[i] = v[i] + from_double(real ? std::complex<double>(dd(static_cast<Eigen::Index>(i)).real(), 0.0) : dd(static_cast<Eigen::Index>(i)), format);
            v[p] = cln::cl_float(1, format);
            const std::complex<double> dl = dd(static_cast<Eigen::Index>(n));
            lam = lam + from_double(real ? std::complex<double>(dl.real(), 0.0) : dl, format);
        }
        // Then exact Newton steps, should the simplified ones stall (never seen).
        for (int it = 0; it < 12 && !converged; ++it) {
            std::vector<cl_N> r(n + 1);
            if (residual(r) <= tol) {
                converged = true;
                break;
            }
            r[n] = cln::cl_float(0, format);  // v_p stays 1
            Matrix J(n + 1, std::vector<cl_N>(n + 1, cln::cl_float(0, format)));
            for (std::size_t i = 0; i < n; ++i) {
                for (std::size_t j = 0; j < n; ++j) J[i][j] = a[i][j];
                J[i][i] = J[i][i] - lam;
                J[i][n] = -v[i];
            }
            J[n][p] = cln::cl_float(1, format);
            if (!mp_solve(J, r)) break;
            for (std::size_t i = 0; i < n; ++i) v[i] = v[i] + r[i];
            lam = lam + r[n];
        }
        if (!converged)
            throw RunError("mp_complex_eigen(): the refinement of eigenvalue " + std::to_string(l.real()) +
                           (l.imag() == 0.0 ? "" : " + " + std::to_string(l.imag()) + "i") + " did not converge");
        out.values[k] = lam;
        out.vectors[k] = v;
    }

    // W = V^-1 by Gauss-Jordan elimination with partial pivoting on [V | I]: one
    // factorisation for every column.
    Matrix Vm(n, std::vector<cl_N>(2 * n, cln::cl_float(0, format)));
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t k = 0; k < n; ++k) Vm[i][k] = out.vectors[k][i];
        Vm[i][n + i] = cln::cl_float(1, format);
    }
    for (std::size_t c = 0; c < n; ++c) {
        std::size_t piv = c;
        for (std::size_t r = c + 1; r < n; ++r)
            if (cln::abs(Vm[r][c]) > cln::abs(Vm[piv][c])) piv = r;
        if (cln::zerop(Vm[piv][c])) throw RunError("mp_complex_eigen(): the eigenvector matrix is singular");
        std::swap(Vm[c], Vm[piv]);
        const cl_N inv = cln::cl_float(1, format) / Vm[c][c];
        for (std::size_t k = c; k < 2 * n; ++k) Vm[c][k] = Vm[c][k] * inv;
        for (std::size_t r = 0; r < n; ++r) {
            if (r == c || cln::zerop(Vm[r][c])) continue;
            const cl_N f = Vm[r][c];
            for (std::size_t k = c; k < 2 * n; ++k)
                if (!cln::zerop(Vm[c][k])) Vm[r][k] = Vm[r][k] - f * Vm[c][k];
        }
    }
    out.inverse.assign(n, std::vector<cl_N>(n));
    for (std::size_t k = 0; k < n; ++k)
        for (std::size_t c = 0; c < n; ++c) out.inverse[k][c] = Vm[k][n + c];
    return out;
}

}  // namespace hsnc
