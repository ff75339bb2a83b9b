#include "mp_complex_eigen.h"

#include <cln/float.h>
#include <cln/lfloat.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <complex>
#include <string>

#include "error.h"

namespace hsnc {
namespace {

using cln::cl_N;
using cln::cl_R;

/// The arithmetic of a refinement: CLN complex numbers of one float format,
/// or DDComplex. Magnitudes, pivots and tolerances are compared in double.
struct ClnArith {
    using C = cl_N;
    cln::float_format_t format;
    C of(std::complex<double> z) const {
        return cln::complex(cln::cl_float(z.real(), format), cln::cl_float(z.imag(), format));
    }
    static std::complex<double> approx(const C& z) {
        return {cln::double_approx(cln::realpart(z)), cln::double_approx(cln::imagpart(z))};
    }
    static double mag(const C& z) { return std::abs(approx(z)); }
    static bool zero(const C& z) { return cln::zerop(z); }
    static C conjugate(const C& z) { return cln::conjugate(z); }
    double epsilon() const { return cln::double_approx(cln::float_epsilon(format)); }
};

struct DDArith {
    using C = DDComplex;
    static C of(std::complex<double> z) { return {DD(z.real()), DD(z.imag())}; }
    static std::complex<double> approx(const C& z) { return {z.re.to_double(), z.im.to_double()}; }
    static double mag(const C& z) { return magnitude(z); }
    static bool zero(const C& z) { return z.is_zero(); }
    static C conjugate(const C& z) { return conj(z); }
    static double epsilon() { return std::ldexp(1.0, -104); }
};

template <class A>
bool solve(const A& ar, std::vector<std::vector<typename A::C>> M, std::vector<typename A::C>& b) {
    using C = typename A::C;
    const std::size_t n = M.size();
    for (std::size_t c = 0; c < n; ++c) {
        std::size_t p = c;
        double best = ar.mag(M[c][c]);
        for (std::size_t r = c + 1; r < n; ++r)
            if (const double m = ar.mag(M[r][c]); m > best) best = m, p = r;
        if (ar.zero(M[p][c])) return false;
        std::swap(M[c], M[p]);
        std::swap(b[c], b[p]);
        for (std::size_t r = c + 1; r < n; ++r) {
            if (ar.zero(M[r][c])) continue;
            const C f = M[r][c] / M[c][c];
            for (std::size_t k = c; k < n; ++k) M[r][k] = M[r][k] - f * M[c][k];
            b[r] = b[r] - f * b[c];
        }
    }
    for (std::size_t c = n; c-- > 0;) {
        C s = b[c];
        for (std::size_t k = c + 1; k < n; ++k) s = s - M[c][k] * b[k];
        b[c] = s / M[c][c];
    }
    return true;
}

/// The eigen-decomposition of the real matrix `a` (entries in the arithmetic
/// of `ar`, imaginary parts zero): see mp_complex_eigen().
template <class A, class Out>
Out complex_eigen(const A& ar, const std::vector<std::vector<typename A::C>>& a) {
    using C = typename A::C;
    using Matrix = std::vector<std::vector<C>>;
    const std::size_t n = a.size();
    Out out;
    if (n == 0) return out;
    std::vector<C>& values = out.values;
    std::vector<std::vector<C>>& vectors = out.vectors;
    std::vector<std::vector<C>>& inverse = out.inverse;
    Eigen::MatrixXd A_d(n, n);
    double norm = 0.0;  // the largest |a_ij|
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j) {
            A_d(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = ar.approx(a[i][j]).real();
            norm = std::max(norm, std::fabs(ar.approx(a[i][j]).real()));
        }
    const Eigen::EigenSolver<Eigen::MatrixXd> es(A_d);
    if (es.info() != Eigen::Success) throw RunError("mp_complex_eigen(): the double eigen-solver did not converge");
    const Eigen::MatrixXcd V = es.eigenvectors();
    const Eigen::MatrixXcd Vinv = V.inverse();
    const double condition = V.cwiseAbs().colwise().sum().maxCoeff() * Vinv.cwiseAbs().colwise().sum().maxCoeff();
    if (!(condition <= kMaxEigenCondition))
        throw RunError("mp_complex_eigen(): the eigenvectors are nearly dependent (condition " +
                       std::to_string(condition) + " > " + std::to_string(static_cast<int>(kMaxEigenCondition)) + ": a defective matrix, critical damping)");

    const double tol = ar.epsilon() * 1024 * norm;
    const C one = ar.of(1.0);
    values.resize(n);
    vectors.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
        const std::complex<double> l = es.eigenvalues()(static_cast<Eigen::Index>(k));
        if (k > 0 && l.imag() < 0.0 && es.eigenvalues()(static_cast<Eigen::Index>(k - 1)) == std::conj(l)) {
            // The conjugate of the pair's first: exactly.
            values[k] = ar.conjugate(values[k - 1]);
            vectors[k].resize(n);
            for (std::size_t i = 0; i < n; ++i) vectors[k][i] = ar.conjugate(vectors[k - 1][i]);
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
        std::vector<C> v(n);
        for (std::size_t i = 0; i < n; ++i) {
            std::complex<double> c = V(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) / vp;
            if (real) c = c.real();
            v[i] = ar.of(c);
        }
        v[p] = one;
        C lam = ar.of(real ? std::complex<double>(l.real(), 0.0) : l);
        // Simplified Newton first: the Jacobian of the double solution, factorised once in
        // double, each residual at the working precision; each step gains the digits of
        // double over the Jacobian's condition (16 -> ~30 -> ~45), at O(n^2) working-precision
        // operations a step instead of the O(n^3) of an exact Newton step.
        Eigen::MatrixXcd J0 = Eigen::MatrixXcd::Zero(static_cast<Eigen::Index>(n + 1), static_cast<Eigen::Index>(n + 1));
        for (std::size_t i = 0; i < n; ++i) {
            for (std::size_t j = 0; j < n; ++j) J0(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = A_d(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
            J0(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i)) -= (real ? std::complex<double>(l.real(), 0.0) : l);
            J0(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(n)) = -ar.approx(v[i]);
        }
        J0(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(p)) = 1.0;
        const Eigen::PartialPivLU<Eigen::MatrixXcd> J0_lu(J0);
        auto residual = [&](std::vector<C>& r) {  // r = -(A v - lam v); returns max |A v - lam v|
            double worst = 0.0;
            for (std::size_t i = 0; i < n; ++i) {
                C s = -(lam * v[i]);
                for (std::size_t j = 0; j < n; ++j)
                    if (!ar.zero(a[i][j])) s = s + a[i][j] * v[j];
                r[i] = -s;
                worst = std::max(worst, ar.mag(s));
            }
            return worst;
        };
        bool converged = false;
        for (int it = 0; it < 8 && !converged; ++it) {
            std::vector<C> r(n + 1);
            if (residual(r) <= tol) {
                converged = true;
                break;
            }
            Eigen::VectorXcd rd(static_cast<Eigen::Index>(n + 1));
            for (std::size_t i = 0; i < n; ++i) rd(static_cast<Eigen::Index>(i)) = ar.approx(r[i]);
            rd(static_cast<Eigen::Index>(n)) = 0.0;
            const Eigen::VectorXcd dd = J0_lu.solve(rd);
            for (std::size_t i = 0; i < n; ++i) v[i] = v[i] + ar.of(real ? std::complex<double>(dd(static_cast<Eigen::Index>(i)).real(), 0.0) : dd(static_cast<Eigen::Index>(i)));
            v[p] = one;
            const std::complex<double> dl = dd(static_cast<Eigen::Index>(n));
            lam = lam + ar.of(real ? std::complex<double>(dl.real(), 0.0) : dl);
        }
        // Then exact Newton steps, should the simplified ones stall (never seen).
        for (int it = 0; it < 12 && !converged; ++it) {
            std::vector<C> r(n + 1);
            if (residual(r) <= tol) {
                converged = true;
                break;
            }
            r[n] = ar.of(0.0);  // v_p stays 1
            Matrix J(n + 1, std::vector<C>(n + 1, ar.of(0.0)));
            for (std::size_t i = 0; i < n; ++i) {
                for (std::size_t j = 0; j < n; ++j) J[i][j] = a[i][j];
                J[i][i] = J[i][i] - lam;
                J[i][n] = -v[i];
            }
            J[n][p] = one;
            if (!solve(ar, J, r)) break;
            for (std::size_t i = 0; i < n; ++i) v[i] = v[i] + r[i];
            lam = lam + r[n];
        }
        if (!converged)
            throw RunError("mp_complex_eigen(): the refinement of eigenvalue " + std::to_string(l.real()) +
                           (l.imag() == 0.0 ? "" : " + " + std::to_string(l.imag()) + "i") + " did not converge");
        values[k] = lam;
        vectors[k] = v;
    }

    // W = V^-1 by Gauss-Jordan elimination with partial pivoting on [V | I]: one
    // factorisation for every column.
    Matrix Vm(n, std::vector<C>(2 * n, ar.of(0.0)));
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t k = 0; k < n; ++k) Vm[i][k] = vectors[k][i];
        Vm[i][n + i] = one;
    }
    for (std::size_t c = 0; c < n; ++c) {
        std::size_t piv = c;
        for (std::size_t r = c + 1; r < n; ++r)
            if (ar.mag(Vm[r][c]) > ar.mag(Vm[piv][c])) piv = r;
        if (ar.zero(Vm[piv][c])) throw RunError("mp_complex_eigen(): the eigenvector matrix is singular");
        std::swap(Vm[c], Vm[piv]);
        const C inv = one / Vm[c][c];
        for (std::size_t k = c; k < 2 * n; ++k) Vm[c][k] = Vm[c][k] * inv;
        for (std::size_t r = 0; r < n; ++r) {
            if (r == c || ar.zero(Vm[r][c])) continue;
            const C f = Vm[r][c];
            for (std::size_t k = c; k < 2 * n; ++k)
                if (!ar.zero(Vm[c][k])) Vm[r][k] = Vm[r][k] - f * Vm[c][k];
        }
    }
    inverse.assign(n, std::vector<C>(n));
    for (std::size_t k = 0; k < n; ++k)
        for (std::size_t c = 0; c < n; ++c) inverse[k][c] = Vm[k][n + c];
    return out;
}

}  // namespace

bool mp_solve(std::vector<std::vector<cl_N>> m, std::vector<cl_N>& b) {
    // solve() only combines the entries, in their own precision: the format is never used.
    return solve(ClnArith{cln::float_format(40)}, std::move(m), b);
}

bool dd_solve(std::vector<std::vector<DDComplex>> m, std::vector<DDComplex>& b) {
    return solve(DDArith{}, std::move(m), b);
}

MpComplexEigen mp_complex_eigen(const std::vector<std::vector<cl_R>>& a, cln::float_format_t format) {
    std::vector<std::vector<cl_N>> ac(a.size());
    for (std::size_t i = 0; i < a.size(); ++i) ac[i].assign(a[i].begin(), a[i].end());
    return complex_eigen<ClnArith, MpComplexEigen>(ClnArith{format}, ac);
}

DdComplexEigen dd_complex_eigen(const std::vector<std::vector<DD>>& a) {
    std::vector<std::vector<DDComplex>> ac(a.size());
    for (std::size_t i = 0; i < a.size(); ++i) ac[i].assign(a[i].begin(), a[i].end());
    return complex_eigen<DDArith, DdComplexEigen>(DDArith{}, ac);
}

}  // namespace hsnc
