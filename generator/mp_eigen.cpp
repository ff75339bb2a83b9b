#include "mp_eigen.h"

#include <Eigen/Dense>
#include <cln/float.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "error.h"

namespace hsnc {

using cln::cl_LF;
using cln::cl_R;

namespace {

/// Most refinement steps of one block (each gains about 16 digits times the
/// relative separation of the eigenvalues; 3 or 4 are typical).
constexpr int kMaxSteps = 40;

/// A block's matrix: sparse rows over the block's own (local) indices.
struct SparseRows {
    std::vector<std::vector<int>> col;
    std::vector<std::vector<cl_LF>> val;
};

cl_LF to_lf(double x, cln::float_format_t f) { return cln::the<cl_LF>(cln::cl_float(x, f)); }

cl_LF dot(const std::vector<cl_LF>& x, const std::vector<cl_LF>& y) {
    cl_LF s = x[0] * y[0];
    for (std::size_t k = 1; k < x.size(); ++k) s = s + x[k] * y[k];
    return s;
}

void multiply(const SparseRows& a, const std::vector<cl_LF>& x, std::vector<cl_LF>& y) {
    for (std::size_t r = 0; r < a.col.size(); ++r) {
        const std::vector<int>& c = a.col[r];
        cl_LF s = a.val[r][0] * x[c[0]];
        for (std::size_t k = 1; k < c.size(); ++k) s = s + a.val[r][k] * x[c[k]];
        y[r] = s;
    }
}

void normalise(std::vector<cl_LF>& x) {
    const cl_LF f = cln::recip(cln::sqrt(dot(x, x)));
    for (cl_LF& e : x) e = e * f;
}

/// Cyclic Jacobi on a small symmetric matrix h (m x m, long floats): on return
/// h's diagonal holds the eigenvalues and q (m x m) the eigenvectors as
/// columns. Used on a cluster's projected matrix only (m is its size).
void small_jacobi(std::vector<std::vector<cl_LF>>& h, std::vector<std::vector<cl_LF>>& q, cln::float_format_t f) {
    const std::size_t m = h.size();
    const cl_LF zero = to_lf(0.0, f), one = to_lf(1.0, f);
    q.assign(m, std::vector<cl_LF>(m, zero));
    for (std::size_t i = 0; i < m; ++i) q[i][i] = one;
    cl_LF norm2 = zero;
    for (auto& row : h)
        for (auto& e : row) norm2 = norm2 + e * e;
    // Off-diagonal mass below 2^-2*(mantissa bits - 8) of the whole: converged.
    const cl_LF tol2 = norm2 * cln::scale_float(one, -2 * (static_cast<long>(cln::float_digits(one)) - 8));
    for (int sweep = 0; sweep < 60; ++sweep) {
        cl_LF off2 = zero;
        for (std::size_t p = 0; p < m; ++p)
            for (std::size_t s = p + 1; s < m; ++s) off2 = off2 + h[p][s] * h[p][s];
        if (off2 <= tol2) return;
        for (std::size_t p = 0; p < m; ++p)
            for (std::size_t s = p + 1; s < m; ++s) {
                if (cln::zerop(h[p][s])) continue;
                const cl_LF theta = (h[s][s] - h[p][p]) / (h[p][s] + h[p][s]);
                const cl_LF t = (cln::minusp(theta) ? -one : one) / (cln::abs(theta) + cln::sqrt(theta * theta + one));
                const cl_LF c = cln::recip(cln::sqrt(t * t + one)), sn = t * c;
                for (std::size_t k = 0; k < m; ++k) {
                    const cl_LF hkp = h[k][p], hks = h[k][s];
                    h[k][p] = c * hkp - sn * hks;
                    h[k][s] = sn * hkp + c * hks;
                }
                for (std::size_t k = 0; k < m; ++k) {
                    const cl_LF hpk = h[p][k], hsk = h[s][k];
                    h[p][k] = c * hpk - sn * hsk;
                    h[s][k] = sn * hpk + c * hsk;
                }
                for (std::size_t k = 0; k < m; ++k) {
                    const cl_LF qkp = q[k][p], qks = q[k][s];
                    q[k][p] = c * qkp - sn * qks;
                    q[k][s] = sn * qkp + c * qks;
                }
            }
    }
    throw RunError("mp_symmetric_eigen(): no convergence of a cluster's Jacobi rotations");
}

/// Rayleigh-Ritz on the cluster vectors v[c0..c1]: orthonormalised
/// (Gram-Schmidt), then rotated to the eigenvectors of the projected matrix
/// V^T A V (ascending).
void rayleigh_ritz(const SparseRows& a, std::vector<std::vector<cl_LF>>& v, int c0, int c1, cln::float_format_t f) {
    const std::size_t b = v[c0].size();
    for (int i = c0; i <= c1; ++i) {
        for (int k = c0; k < i; ++k) {
            const cl_LF p = dot(v[k], v[i]);
            for (std::size_t r = 0; r < b; ++r) v[i][r] = v[i][r] - p * v[k][r];
        }
        normalise(v[i]);
    }
    const int m = c1 - c0 + 1;
    std::vector<std::vector<cl_LF>> av(m, std::vector<cl_LF>(b, to_lf(0.0, f)));
    for (int p = 0; p < m; ++p) multiply(a, v[c0 + p], av[p]);
    std::vector<std::vector<cl_LF>> h(m, std::vector<cl_LF>(m, to_lf(0.0, f))), q;
    for (int p = 0; p < m; ++p)
        for (int s = p; s < m; ++s) h[p][s] = h[s][p] = dot(v[c0 + p], av[s]);
    small_jacobi(h, q, f);
    std::vector<int> order(m);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int p, int s) { return h[p][p] < h[s][s]; });
    std::vector<std::vector<cl_LF>> rotated(m, std::vector<cl_LF>(b, to_lf(0.0, f)));
    for (int s = 0; s < m; ++s)
        for (std::size_t r = 0; r < b; ++r) {
            cl_LF e = v[c0][r] * q[0][order[s]];
            for (int p = 1; p < m; ++p) e = e + v[c0 + p][r] * q[p][order[s]];
            rotated[s][r] = e;
        }
    for (int s = 0; s < m; ++s) v[c0 + s] = std::move(rotated[s]);
}

/// s + t as a double-double (hi, lo) accumulation: hi += t exactly, the
/// rounding error into lo (Knuth's TwoSum).
inline void two_sum_into(double& hi, double& lo, double t) {
    const double s = hi + t, bb = s - hi;
    lo += (hi - (s - bb)) + (t - bb);
    hi = s;
}

/// The eigenpairs of one block (b > 1): values[i], vectors[i][r] over the
/// block's local indices, ascending.
void solve_block(const SparseRows& a, const Eigen::MatrixXd& ad, const Eigen::MatrixXd& ad_lo, cln::float_format_t f,
                 std::vector<cl_LF>& values, std::vector<std::vector<cl_LF>>& vectors) {
    const int b = static_cast<int>(ad.rows());
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(ad);
    if (es.info() != Eigen::Success) throw RunError("mp_symmetric_eigen(): the double eigen-solver failed");
    const Eigen::VectorXd& mu = es.eigenvalues();
    const Eigen::MatrixXd& x = es.eigenvectors();
    const double scale = std::max({std::fabs(mu(0)), std::fabs(mu(b - 1)), 1e-300});
    const double tol = kResidualTol * std::max(ad.norm(), 1e-300);

    // Clusters: runs of eigenvalues closer than kClusterGap * scale to a neighbour.
    std::vector<int> first(b), last(b);  // cluster of i = [first[i], last[i]]
    for (int i = 0; i < b; ++i) first[i] = (i > 0 && mu(i) - mu(i - 1) <= kClusterGap * scale) ? first[i - 1] : i;
    for (int i = b - 1; i >= 0; --i) last[i] = (i + 1 < b && first[i + 1] == first[i]) ? last[i + 1] : i;

    // The Newton correction of pair i from its residual (double), out of i's cluster.
    auto correction = [&](int i, const Eigen::VectorXd& residual, double lam) {
        Eigen::VectorXd w = x.transpose() * residual;
        for (int k = 0; k < b; ++k) w(k) = (k >= first[i] && k <= last[i]) ? 0.0 : w(k) / (mu(k) - lam);
        return Eigen::VectorXd(x * w);
    };

    // Step 1 in double-double: the residual of (mu_i, X_i) with error-free
    // products (A as hi + lo), accurate to about 1e-32 |A|; its correction
    // takes the pair from about 16 to about 32 digits.
    vectors.assign(b, std::vector<cl_LF>(b, to_lf(0.0, f)));
    values.assign(b, to_lf(0.0, f));
    Eigen::VectorXd residual(b);
    for (int i = 0; i < b; ++i) {
        for (int r = 0; r < b; ++r) {
            double hi = 0, lo = 0;
            const std::vector<int>& c = a.col[r];
            for (int s : c) {
                const double p = ad(r, s) * x(s, i);
                lo += std::fma(ad(r, s), x(s, i), -p) + ad_lo(r, s) * x(s, i);
                two_sum_into(hi, lo, p);
            }
            const double p = -mu(i) * x(r, i);
            lo += std::fma(-mu(i), x(r, i), -p);
            two_sum_into(hi, lo, p);
            residual(r) = hi + lo;
        }
        const Eigen::VectorXd delta = correction(i, residual, mu(i));
        for (int r = 0; r < b; ++r) {
            vectors[i][r] = to_lf(x(r, i), f);
            if (delta(r) != 0.0) vectors[i][r] = vectors[i][r] - to_lf(delta(r), f);
        }
    }
    for (int c0 = 0; c0 < b; c0 = last[c0] + 1)
        if (last[c0] > c0) rayleigh_ritz(a, vectors, c0, last[c0], f);

    // Then in long floats until converged: Rayleigh quotients and residuals,
    // corrections, the clusters' Rayleigh-Ritz again.
    std::vector<cl_LF> y(b, to_lf(0.0, f)), norm2(b, to_lf(1.0, f));
    std::vector<Eigen::VectorXd> res(b, Eigen::VectorXd(b));
    std::vector<char> done(b, 0);
    for (int step = 0;; ++step) {
        bool all = true;
        for (int i = 0; i < b; ++i) {
            if (done[i]) continue;
            multiply(a, vectors[i], y);
            norm2[i] = dot(vectors[i], vectors[i]);
            values[i] = dot(vectors[i], y) / norm2[i];
            double n2 = 0;
            for (int r = 0; r < b; ++r) {
                res[i](r) = cln::double_approx(y[r] - values[i] * vectors[i][r]);
                n2 += res[i](r) * res[i](r);
            }
            done[i] = std::sqrt(n2) <= tol;
            all = all && done[i];
        }
        if (all) break;
        if (step == kMaxSteps)
            throw RunError("mp_symmetric_eigen(): no convergence after " + std::to_string(kMaxSteps) + " steps");
        for (int c0 = 0; c0 < b; c0 = last[c0] + 1) {
            const int c1 = last[c0];
            bool pending = false;
            for (int i = c0; i <= c1; ++i) pending = pending || !done[i];
            if (!pending) continue;
            for (int i = c0; i <= c1; ++i) {
                if (done[i]) continue;
                const Eigen::VectorXd delta = correction(i, res[i], cln::double_approx(values[i]));
                for (int r = 0; r < b; ++r)
                    if (delta(r) != 0.0) vectors[i][r] = vectors[i][r] - to_lf(delta(r), f);
            }
            if (c1 > c0) {
                rayleigh_ritz(a, vectors, c0, c1, f);
                for (int i = c0; i <= c1; ++i) done[i] = 0;
            }
        }
    }
    for (int i = 0; i < b; ++i) {
        const cl_LF inv = cln::recip(cln::sqrt(norm2[i]));
        for (cl_LF& e : vectors[i]) e = e * inv;
    }
}

}  // namespace

std::vector<MpEigenpair> mp_symmetric_eigen(const std::vector<std::vector<cl_R>>& a, cln::float_format_t format) {
    const std::size_t n = a.size();
    // Blocks: connected components of the nonzero off-diagonal entries, numbered
    // in the order of their first index.
    std::vector<int> parent(n);
    std::iota(parent.begin(), parent.end(), 0);
    auto find = [&](int i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    };
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = i + 1; j < n; ++j)
            if (!cln::zerop(a[i][j])) parent[find(static_cast<int>(i))] = find(static_cast<int>(j));
    std::vector<std::vector<int>> blocks;
    std::vector<int> block_of_root(n, -1);
    for (std::size_t i = 0; i < n; ++i) {
        const int r = find(static_cast<int>(i));
        if (block_of_root[r] < 0) {
            block_of_root[r] = static_cast<int>(blocks.size());
            blocks.emplace_back();
        }
        blocks[block_of_root[r]].push_back(static_cast<int>(i));
    }

    std::vector<MpEigenpair> pairs;
    pairs.reserve(n);
    for (const std::vector<int>& idx : blocks) {
        const std::size_t b = idx.size();
        if (b == 1) {
            MpEigenpair p;
            p.value = a[idx[0]][idx[0]];
            p.vector.assign(n, cl_R(0));
            p.vector[idx[0]] = cl_R(1);
            pairs.push_back(std::move(p));
            continue;
        }
        SparseRows rows;
        rows.col.resize(b);
        rows.val.resize(b);
        Eigen::MatrixXd ad = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(b), static_cast<Eigen::Index>(b));
        Eigen::MatrixXd ad_lo = ad;  // A = ad + ad_lo to about 32 digits
        for (std::size_t r = 0; r < b; ++r)
            for (std::size_t s = 0; s < b; ++s) {
                const cl_R& e = a[idx[r]][idx[s]];
                if (cln::zerop(e)) continue;  // exact zero (or a zero float: nothing to add)
                const cl_LF lf = cln::the<cl_LF>(cln::cl_float(e, format));
                rows.col[r].push_back(static_cast<int>(s));
                rows.val[r].push_back(lf);
                const double hi = cln::double_approx(lf);
                ad(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(s)) = hi;
                ad_lo(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(s)) = cln::double_approx(lf - to_lf(hi, format));
            }
        for (std::size_t r = 0; r < b; ++r)
            if (rows.col[r].empty()) {  // a zero row: keep one explicit zero term for the products
                rows.col[r].push_back(static_cast<int>(r));
                rows.val[r].push_back(to_lf(0.0, format));
            }
        std::vector<cl_LF> values;
        std::vector<std::vector<cl_LF>> vectors;
        solve_block(rows, ad, ad_lo, format, values, vectors);
        for (std::size_t i = 0; i < b; ++i) {
            MpEigenpair p;
            p.value = values[i];
            p.vector.assign(n, cl_R(0));
            for (std::size_t r = 0; r < b; ++r) p.vector[idx[r]] = vectors[i][r];
            pairs.push_back(std::move(p));
        }
    }
    std::stable_sort(pairs.begin(), pairs.end(),
                     [](const MpEigenpair& p, const MpEigenpair& q) { return p.value < q.value; });
    return pairs;
}

}  // namespace hsnc
