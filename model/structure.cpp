#include "structure.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <numeric>
#include <sstream>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace hsnc {
namespace {

constexpr double kRelTol = 1e-12;  // symmetry, definiteness and proportionality, relative (structure.h)

std::string show(double v) {
    std::ostringstream out;
    out.precision(17);
    out << v;
    return out.str();
}

std::string entry(const char* m, const std::vector<std::string>& dofs, std::size_t i, std::size_t j) {
    return std::string(m) + "(" + dofs[i] + ", " + dofs[j] + ")";
}

std::string check_size(const char* m, const MarketMatrix& A, std::size_t n) {
    if (A.rows == n && A.cols == n) return "";
    return std::string(m) + " is " + std::to_string(A.rows) + " x " + std::to_string(A.cols) + ", expected " +
           std::to_string(n) + " x " + std::to_string(n) + " (one row and column per dof of structure.dofs)";
}

double max_abs(const MarketMatrix& A) {
    double m = 0.0;
    for (double v : A.values) m = std::max(m, std::fabs(v));
    return m;
}

/// Symmetric to kRelTol of the largest entry; then A is replaced by (A + A^T)/2.
std::string check_symmetric(const char* m, MarketMatrix& A, const std::vector<std::string>& dofs) {
    const double tol = kRelTol * max_abs(A);
    for (std::size_t i = 0; i < A.rows; ++i)
        for (std::size_t j = 0; j < i; ++j)
            if (std::fabs(A(i, j) - A(j, i)) > tol)
                return std::string(m) + " is not symmetric: " + entry(m, dofs, i, j) + " = " + show(A(i, j)) + " but " +
                       entry(m, dofs, j, i) + " = " + show(A(j, i));
    for (std::size_t i = 0; i < A.rows; ++i)
        for (std::size_t j = 0; j < i; ++j) {
            const double v = 0.5 * (A(i, j) + A(j, i));
            A.values[i * A.cols + j] = A.values[j * A.cols + i] = v;
        }
    return "";
}

std::string names_of(const std::vector<std::string>& dofs, const std::vector<std::size_t>& members) {
    std::string s;
    for (std::size_t i : members) s += (s.empty() ? "" : ", ") + dofs[i];
    return s;
}

/// Smallest and largest eigenvalue of the Jacobi-scaled block A[members, members]
/// (plus u u^T, u the scaled all-ones vector, when `deflate`: the block's
/// structural null vector then counts as eigenvalue 1). False when a diagonal
/// entry is <= 0 (then `bad` is its member).
bool scaled_extremes(const MarketMatrix& A, const std::vector<std::size_t>& members, bool deflate, double& lo,
                     double& hi, std::size_t& bad) {
    const auto c = static_cast<Eigen::Index>(members.size());
    Eigen::VectorXd d(c);
    for (Eigen::Index r = 0; r < c; ++r) {
        d(r) = A(members[r], members[r]);
        if (!(d(r) > 0.0)) {
            bad = members[r];
            return false;
        }
    }
    // S = D^-1/2 A D^-1/2 as (A_rs / sqrt(d_r)) / sqrt(d_s): sqrt(d_r * d_s) would
    // overflow beyond 1.3e154 (or underflow below 1.5e-154) where each factor does not.
    const Eigen::VectorXd root = d.cwiseSqrt();
    Eigen::MatrixXd S(c, c);
    for (Eigen::Index r = 0; r < c; ++r)
        for (Eigen::Index s = 0; s < c; ++s)
            S(r, s) = A(members[r], members[s]) / root(r) / root(s);
    if (deflate) {
        Eigen::VectorXd u = root;  // D^1/2 * 1: S u = D^-1/2 K 1 = 0
        u /= u.stableNorm();  // no overflow of the squares near the double range
        S += u * u.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(S, Eigen::EigenvaluesOnly);
    lo = es.eigenvalues()(0);
    hi = es.eigenvalues()(c - 1);
    return true;
}

}  // namespace

namespace {

MarketMatrix submatrix(const MarketMatrix& A, const std::vector<std::size_t>& rows, const std::vector<std::size_t>& cols) {
    MarketMatrix B;
    B.rows = rows.size();
    B.cols = cols.size();
    B.values.resize(B.rows * B.cols);
    for (std::size_t r = 0; r < rows.size(); ++r)
        for (std::size_t c = 0; c < cols.size(); ++c) B.values[r * B.cols + c] = A(rows[r], cols[c]);
    return B;
}

Eigen::MatrixXd dense(const MarketMatrix& A) {
    Eigen::MatrixXd D(static_cast<Eigen::Index>(A.rows), static_cast<Eigen::Index>(A.cols));
    for (std::size_t i = 0; i < A.rows; ++i)
        for (std::size_t j = 0; j < A.cols; ++j) D(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = A(i, j);
    return D;
}

}  // namespace

std::string condense_massless(MarketMatrix& M, MarketMatrix& K, MarketMatrix* C, std::vector<std::string>& names,
                              Condensation& out) {
    const std::size_t n = names.size();
    out = Condensation{};
    if (M.rows != n || M.cols != n || K.rows != n || K.cols != n) return "";  // the checks name the size
    std::vector<std::size_t> kept, massless;
    for (std::size_t i = 0; i < n; ++i) {
        bool zero = true;
        for (std::size_t j = 0; j < n && zero; ++j) zero = M(i, j) == 0.0 && M(j, i) == 0.0;
        (zero ? massless : kept).push_back(i);
    }
    if (massless.empty()) return "";
    if (kept.empty()) return "M is zero: no dof has mass";
    if (std::string why = check_symmetric("K", K, names); !why.empty()) return why;
    if (C && C->rows == n && C->cols == n)
        for (std::size_t c : massless)
            for (std::size_t j = 0; j < n; ++j)
                if (C->values[c * n + j] != 0.0 || C->values[j * n + c] != 0.0)
                    return "C damps the massless dof " + names[c] + " (" + entry("C", names, c, j) +
                           "): its motion would not be static; damp the dofs with mass, or give Rayleigh damping as "
                           "[damping] alpha, beta";
    const Eigen::MatrixXd Kcc = dense(submatrix(K, massless, massless)), Kcm = dense(submatrix(K, massless, kept));
    // K_cc must be positive definite (K is semi-definite): judged on its Jacobi-scaled form, as K is.
    std::string list;
    for (std::size_t c : massless) list += (list.empty() ? "" : ", ") + names[c];
    const Eigen::VectorXd d = Kcc.diagonal();
    if (!(d.minCoeff() > 0.0))
        return "K is singular on the massless dofs " + list + ": the static condensation needs every one held by stiffness";
    const Eigen::VectorXd root = d.cwiseSqrt().cwiseInverse();
    const Eigen::MatrixXd S = root.asDiagonal() * Kcc * root.asDiagonal();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (S + S.transpose()), Eigen::EigenvaluesOnly);
    if (!(es.eigenvalues()(0) > kRelTol * es.eigenvalues().maxCoeff()))
        return "K is singular on the massless dofs " + list + ": the static condensation needs every one held by stiffness";
    const Eigen::LLT<Eigen::MatrixXd> llt(Kcc);
    const Eigen::MatrixXd R = -Eigen::MatrixXd(llt.solve(Kcm));
    const Eigen::MatrixXd flex = llt.solve(Eigen::MatrixXd::Identity(Kcc.rows(), Kcc.cols()));
    const Eigen::MatrixXd Kmm = dense(submatrix(K, kept, kept));
    const Eigen::MatrixXd Kred = Kmm + Kcm.transpose() * R;
    MarketMatrix Kr = submatrix(K, kept, kept);
    for (std::size_t r = 0; r < kept.size(); ++r)
        for (std::size_t c = 0; c < kept.size(); ++c)
            Kr.values[r * kept.size() + c] =
                0.5 * (Kred(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) +
                       Kred(static_cast<Eigen::Index>(c), static_cast<Eigen::Index>(r)));
    out.dofs = names;
    out.mass.assign(n, -1);
    for (std::size_t r = 0; r < kept.size(); ++r) out.mass[kept[r]] = static_cast<int>(r);
    out.recovery.assign(R.data(), R.data() + R.size());  // column-major of (condensed x kept): transposed below
    for (Eigen::Index i = 0; i < R.rows(); ++i)
        for (Eigen::Index j = 0; j < R.cols(); ++j) out.recovery[static_cast<std::size_t>(i * R.cols() + j)] = R(i, j);
    for (Eigen::Index i = 0; i < flex.rows(); ++i)  // symmetric: its two halves averaged
        for (Eigen::Index j = 0; j < flex.cols(); ++j) out.flexibility.push_back(0.5 * (flex(i, j) + flex(j, i)));
    out.load.assign(massless.size(), 0.0);
    M = submatrix(M, kept, kept);
    K = Kr;
    if (C && C->rows == n && C->cols == n) *C = submatrix(*C, kept, kept);
    std::vector<std::string> kept_names;
    for (std::size_t i : kept) kept_names.push_back(names[i]);
    names = kept_names;
    return "";
}

std::string check_mass_matrix(const MarketMatrix& M_in, const std::vector<std::string>& dofs, std::vector<double>& mass,
                              std::vector<double>& coupled, double& floor) {
    const std::size_t n = dofs.size();
    if (std::string why = check_size("M", M_in, n); !why.empty()) return why;
    MarketMatrix M = M_in;
    if (std::string why = check_symmetric("M", M, dofs); !why.empty()) return why;
    std::vector<std::size_t> all(n);
    std::iota(all.begin(), all.end(), std::size_t{0});
    double lo = 0.0, hi = 0.0;
    std::size_t bad = 0;
    if (!scaled_extremes(M, all, false, lo, hi, bad))
        return "M is not positive definite: " + entry("M", dofs, bad, bad) + " = " + show(M(bad, bad));
    if (!(lo > kRelTol * hi))
        return "M is not positive definite (smallest eigenvalue of the scaled D^-1/2 M D^-1/2: " + show(lo) + ")";
    mass.assign(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) mass[i] = M(i, i);
    coupled.clear();
    floor = 0.0;
    bool diagonal = true;
    for (std::size_t e = 0; e < n * n && diagonal; ++e)
        if (e / n != e % n && M.values[e] != 0.0) diagonal = false;
    if (diagonal) return "";
    coupled = M.values;  // symmetrised by check_symmetric
    Eigen::MatrixXd A = Eigen::Map<const Eigen::MatrixXd>(coupled.data(), static_cast<Eigen::Index>(n),
                                                          static_cast<Eigen::Index>(n));
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(A, Eigen::EigenvaluesOnly);
    floor = es.eigenvalues()(0);
    if (!(floor > 0.0)) return "M is not positive definite (smallest eigenvalue " + show(floor) + ")";
    return "";
}

std::string check_stiffness_matrix(const MarketMatrix& K_in, const std::vector<std::string>& dofs,
                                   std::vector<Spring>& springs) {
    const std::size_t n = dofs.size();
    if (std::string why = check_size("K", K_in, n); !why.empty()) return why;
    MarketMatrix K = K_in;
    if (std::string why = check_symmetric("K", K, dofs); !why.empty()) return why;

    // Row sums, zero within rounding (structure.h).
    std::vector<double> ground(n, 0.0);
    const double slack = std::max<double>(16.0, static_cast<double>(n)) * DBL_EPSILON;
    for (std::size_t i = 0; i < n; ++i) {
        double sum = 0.0, mag = 0.0;
        for (std::size_t j = 0; j < n; ++j) sum += K(i, j), mag += std::fabs(K(i, j));
        ground[i] = std::fabs(sum) <= slack * mag ? 0.0 : sum;
    }

    // Groups of dofs coupled by K (union-find), anchored by a row sum != 0.
    std::vector<std::size_t> parent(n);
    std::iota(parent.begin(), parent.end(), std::size_t{0});
    auto find = [&](std::size_t s) {
        while (parent[s] != s) s = parent[s] = parent[parent[s]];
        return s;
    };
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < i; ++j)
            if (K(i, j) != 0.0) parent[find(i)] = find(j);
    std::vector<std::vector<std::size_t>> groups(n);
    std::vector<char> anchored(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        groups[find(i)].push_back(i);
        if (ground[i] != 0.0) anchored[find(i)] = 1;
    }
    for (std::size_t r = 0; r < n; ++r) {
        const std::vector<std::size_t>& members = groups[r];
        if (members.empty()) continue;
        const bool floating = !anchored[r];
        if (floating && members.size() == 1) continue;  // a dof K does not touch: its own translation
        double lo = 0.0, hi = 0.0;
        std::size_t bad = 0;
        if (!scaled_extremes(K, members, floating, lo, hi, bad))
            return "K is not positive semi-definite: " + entry("K", dofs, bad, bad) + " = " + show(K(bad, bad)) +
                   " while the dof is coupled to others";
        if (lo < -kRelTol * hi)
            return "K is not positive semi-definite (dofs " + names_of(dofs, members) +
                   ": smallest eigenvalue of the scaled D^-1/2 K D^-1/2 is " + show(lo) + ")";
        if (lo <= kRelTol * hi)
            return "K is singular beyond a free translation (dofs " + names_of(dofs, members) +
                   "): hsnc takes a rigid-body mode only where a group of dofs has every row sum of K zero; "
                   "hold the structure (a spring to ground) or remove the mode";
    }

    springs.clear();
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = i + 1; j < n; ++j)
            if (K(i, j) != 0.0) {
                Spring s;
                s.a = static_cast<int>(i);
                s.b = static_cast<int>(j);
                s.k = -K(i, j);
                s.from_structure = true;
                springs.push_back(s);
            }
    for (std::size_t i = 0; i < n; ++i)
        if (ground[i] != 0.0) {
            Spring s;
            s.a = static_cast<int>(i);
            s.b = kGround;
            s.k = ground[i];
            s.from_structure = true;
            springs.push_back(s);
        }
    return "";
}

std::string fit_rayleigh_damping(const MarketMatrix& C_in, const MarketMatrix& M, const MarketMatrix& K,
                                 const std::vector<std::string>& dofs, double& alpha, double& beta,
                                 bool& proportional) {
    proportional = false;
    const std::size_t n = dofs.size();
    if (std::string why = check_size("C", C_in, n); !why.empty()) return why;
    MarketMatrix C = C_in;
    if (std::string why = check_symmetric("C", C, dofs); !why.empty()) return why;
    // Least squares over the entries: [MM MK; MK KK] [a; b] = [CM; CK].
    long double mm = 0, mk = 0, kk = 0, cm = 0, ck = 0;
    for (std::size_t e = 0; e < n * n; ++e) {
        const long double m = M.values[e], k = K.values[e], c = C.values[e];
        mm += m * m, mk += m * k, kk += k * k, cm += c * m, ck += c * k;
    }
    const long double det = mm * kk - mk * mk;
    double a = 0.0, b = 0.0;
    if (kk == 0 || det <= 1e-24L * mm * kk) {
        a = static_cast<double>(cm / mm);  // M and K proportional: not separable, b = 0
    } else {
        a = static_cast<double>((cm * kk - ck * mk) / det);
        b = static_cast<double>((mm * ck - mk * cm) / det);
    }
    const double mmax = max_abs(M), kmax = max_abs(K);
    if (std::fabs(a) * mmax <= kRelTol * std::fabs(b) * kmax) a = 0.0;  // rounding of an exact b*K
    if (std::fabs(b) * kmax <= kRelTol * std::fabs(a) * mmax) b = 0.0;
    const double tol = kRelTol * (std::fabs(a) * mmax + std::fabs(b) * kmax);
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j) {
            const double r = C(i, j) - a * M(i, j) - b * K(i, j);
            if (std::fabs(r) > tol) return "";  // not proportional: check_damping_matrix
        }
    if (a < 0.0 || b < 0.0)
        return "C = a*M + b*K with a = " + show(a) + ", b = " + show(b) +
               ": Rayleigh coefficients must be >= 0 (a negative one feeds energy in)";
    alpha = a;
    beta = b;
    proportional = true;
    return "";
}

std::string check_damping_matrix(const MarketMatrix& C_in, const std::vector<std::string>& dofs,
                                 std::vector<Damper>& dampers) {
    const std::size_t n = dofs.size();
    if (std::string why = check_size("C", C_in, n); !why.empty()) return why;
    MarketMatrix C = C_in;
    if (std::string why = check_symmetric("C", C, dofs); !why.empty()) return why;
    Eigen::MatrixXd A(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j) A(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = C(i, j);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(A, Eigen::EigenvaluesOnly);
    const double lo = es.eigenvalues()(0), hi = es.eigenvalues()(static_cast<Eigen::Index>(n) - 1);
    if (!(hi > 0.0)) return "C has no positive eigenvalue (largest " + show(hi) + "): leave structure.damping out";
    if (lo < -kRelTol * hi)
        return "C is not positive semi-definite (smallest eigenvalue " + show(lo) + ", largest " + show(hi) +
               "): a damper with negative damping feeds energy in";
    // As K becomes springs: -C_ij between dofs i and j, the row sum to ground.
    const double slack = std::max<double>(16.0, static_cast<double>(n)) * DBL_EPSILON;
    dampers.clear();
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = i + 1; j < n; ++j)
            if (C(i, j) != 0.0) dampers.push_back({static_cast<int>(i), static_cast<int>(j), -C(i, j), true});
    for (std::size_t i = 0; i < n; ++i) {
        double sum = 0.0, mag = 0.0;
        for (std::size_t j = 0; j < n; ++j) sum += C(i, j), mag += std::fabs(C(i, j));
        if (std::fabs(sum) > slack * mag) dampers.push_back({static_cast<int>(i), kGround, sum, true});
    }
    return "";
}

}  // namespace hsnc
