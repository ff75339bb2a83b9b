#include "mp_eigen.h"

#include <Eigen/Dense>
#include <cln/float.h>

#include <algorithm>
#include <cmath>
#include <cstring>
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

/// The arithmetic of a refinement: CLN long floats of one format, or DD.
struct LongFloat {
    using S = cl_LF;
    cln::float_format_t format;
    S of(double x) const { return cln::the<cl_LF>(cln::cl_float(x, format)); }
    static double approx(const S& x) { return cln::double_approx(x); }
    static S root(const S& x) { return cln::sqrt(x); }
    static S inverse(const S& x) { return cln::recip(x); }
    static bool zero(const S& x) { return cln::zerop(x); }
    static bool negative(const S& x) { return cln::minusp(x); }
    long bits() const { return static_cast<long>(cln::float_digits(of(1.0))); }
    double residual_tol() const { return kResidualTol; }
};

struct DoubleDouble {
    using S = DD;
    static S of(double x) { return DD(x); }
    static double approx(const S& x) { return x.to_double(); }
    static S root(const S& x) { return sqrt(x); }
    static S inverse(const S& x) { return DD(1.0) / x; }
    static bool zero(const S& x) { return x.is_zero(); }
    static bool negative(const S& x) { return x.hi() < 0.0; }
    static long bits() { return 104; }
    static double residual_tol() { return kDdResidualTol; }
};

/// A block's matrix: sparse rows over the block's own (local) indices.
template <class S>
struct SparseRows {
    std::vector<std::vector<int>> col;
    std::vector<std::vector<S>> val;
};

template <class S>
S dot(const std::vector<S>& x, const std::vector<S>& y) {
    S s = x[0] * y[0];
    for (std::size_t k = 1; k < x.size(); ++k) s = s + x[k] * y[k];
    return s;
}

template <class S>
void multiply(const SparseRows<S>& a, const std::vector<S>& x, std::vector<S>& y) {
    for (std::size_t r = 0; r < a.col.size(); ++r) {
        const std::vector<int>& c = a.col[r];
        S s = a.val[r][0] * x[c[0]];
        for (std::size_t k = 1; k < c.size(); ++k) s = s + a.val[r][k] * x[c[k]];
        y[r] = s;
    }
}

template <class A>
void normalise(const A& ar, std::vector<typename A::S>& x) {
    const typename A::S f = ar.inverse(ar.root(dot(x, x)));
    for (auto& e : x) e = e * f;
}

/// Cyclic Jacobi rotations (Golub & Van Loan, Matrix Computations, 4th ed.,
/// Alg. 8.5.3) on a symmetric matrix h (m x m): on return h's diagonal holds
/// the eigenvalues and q (m x m) the eigenvectors as columns. The refinement
/// uses it on a cluster's projected matrix (m is its size).
template <class A>
void small_jacobi(const A& ar, std::vector<std::vector<typename A::S>>& h, std::vector<std::vector<typename A::S>>& q) {
    using S = typename A::S;
    const std::size_t m = h.size();
    const S zero = ar.of(0.0), one = ar.of(1.0);
    q.assign(m, std::vector<S>(m, zero));
    for (std::size_t i = 0; i < m; ++i) q[i][i] = one;
    S norm2 = zero;
    for (auto& row : h)
        for (auto& e : row) norm2 = norm2 + e * e;
    // Off-diagonal mass below 2^-2*(mantissa bits - 8) of the whole: converged.
    const S tol2 = norm2 * ar.of(std::ldexp(1.0, static_cast<int>(-2 * (ar.bits() - 8))));
    for (int sweep = 0; sweep < 100; ++sweep) {
        S off2 = zero;
        for (std::size_t p = 0; p < m; ++p)
            for (std::size_t s = p + 1; s < m; ++s) off2 = off2 + h[p][s] * h[p][s];
        if (off2 <= tol2) return;
        for (std::size_t p = 0; p < m; ++p)
            for (std::size_t s = p + 1; s < m; ++s) {
                if (ar.zero(h[p][s])) continue;
                const S theta = (h[s][s] - h[p][p]) / (h[p][s] + h[p][s]);
                const S abs_theta = ar.negative(theta) ? -theta : theta;
                // (For |theta| > 1e100, t = 1/(2 theta) to the working precision; theta^2 would overflow DD's products.)
                const S t = abs_theta > ar.of(1e100) ? one / (theta + theta)
                                                     : (ar.negative(theta) ? -one : one) / (abs_theta + ar.root(theta * theta + one));
                const S c = ar.inverse(ar.root(t * t + one)), sn = t * c;
                for (std::size_t k = 0; k < m; ++k) {
                    const S hkp = h[k][p], hks = h[k][s];
                    h[k][p] = c * hkp - sn * hks;
                    h[k][s] = sn * hkp + c * hks;
                }
                for (std::size_t k = 0; k < m; ++k) {
                    const S hpk = h[p][k], hsk = h[s][k];
                    h[p][k] = c * hpk - sn * hsk;
                    h[s][k] = sn * hpk + c * hsk;
                }
                for (std::size_t k = 0; k < m; ++k) {
                    const S qkp = q[k][p], qks = q[k][s];
                    q[k][p] = c * qkp - sn * qks;
                    q[k][s] = sn * qkp + c * qks;
                }
            }
    }
    throw RunError("mp_eigen::jacobi(): no convergence after 100 sweeps");
}

/// Rayleigh-Ritz on the cluster vectors v[c0..c1]: orthonormalised
/// (Gram-Schmidt), then rotated to the eigenvectors of the projected matrix
/// V^T A V (ascending).
template <class A>
void rayleigh_ritz(const A& ar, const SparseRows<typename A::S>& a, std::vector<std::vector<typename A::S>>& v, int c0,
                   int c1) {
    using S = typename A::S;
    const std::size_t b = v[c0].size();
    for (int i = c0; i <= c1; ++i) {
        for (int k = c0; k < i; ++k) {
            const S p = dot(v[k], v[i]);
            for (std::size_t r = 0; r < b; ++r) v[i][r] = v[i][r] - p * v[k][r];
        }
        normalise(ar, v[i]);
    }
    const int m = c1 - c0 + 1;
    std::vector<std::vector<S>> av(m, std::vector<S>(b, ar.of(0.0)));
    for (int p = 0; p < m; ++p) multiply(a, v[c0 + p], av[p]);
    std::vector<std::vector<S>> h(m, std::vector<S>(m, ar.of(0.0))), q;
    for (int p = 0; p < m; ++p)
        for (int s = p; s < m; ++s) h[p][s] = h[s][p] = dot(v[c0 + p], av[s]);
    small_jacobi(ar, h, q);
    std::vector<int> order(m);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int p, int s) { return h[p][p] < h[s][s]; });
    std::vector<std::vector<S>> rotated(m, std::vector<S>(b, ar.of(0.0)));
    for (int s = 0; s < m; ++s)
        for (std::size_t r = 0; r < b; ++r) {
            S e = v[c0][r] * q[0][order[s]];
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
template <class A>
void solve_block(const A& ar, const SparseRows<typename A::S>& a, const Eigen::MatrixXd& ad, const Eigen::MatrixXd& ad_lo,
                 std::vector<typename A::S>& values, std::vector<std::vector<typename A::S>>& vectors) {
    using S = typename A::S;
    const int b = static_cast<int>(ad.rows());
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(ad);
    if (es.info() != Eigen::Success) throw RunError("mp_symmetric_eigen(): the double eigen-solver failed");
    const Eigen::VectorXd& mu = es.eigenvalues();
    const Eigen::MatrixXd& x = es.eigenvectors();
    const double scale = std::max({std::fabs(mu(0)), std::fabs(mu(b - 1)), 1e-300});
    const double tol = ar.residual_tol() * std::max(ad.norm(), 1e-300);

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
    vectors.assign(b, std::vector<S>(b, ar.of(0.0)));
    values.assign(b, ar.of(0.0));
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
            vectors[i][r] = ar.of(x(r, i));
            if (delta(r) != 0.0) vectors[i][r] = vectors[i][r] - ar.of(delta(r));
        }
    }
    for (int c0 = 0; c0 < b; c0 = last[c0] + 1)
        if (last[c0] > c0) rayleigh_ritz(ar, a, vectors, c0, last[c0]);

    // Then in the working precision until converged: Rayleigh quotients and
    // residuals, corrections, the clusters' Rayleigh-Ritz again.
    std::vector<S> y(b, ar.of(0.0)), norm2(b, ar.of(1.0));
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
                res[i](r) = ar.approx(y[r] - values[i] * vectors[i][r]);
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
                const Eigen::VectorXd delta = correction(i, res[i], ar.approx(values[i]));
                for (int r = 0; r < b; ++r)
                    if (delta(r) != 0.0) vectors[i][r] = vectors[i][r] - ar.of(delta(r));
            }
            if (c1 > c0) {
                rayleigh_ritz(ar, a, vectors, c0, c1);
                for (int i = c0; i <= c1; ++i) done[i] = 0;
            }
        }
    }
    for (int i = 0; i < b; ++i) {
        const S inv = ar.inverse(ar.root(norm2[i]));
        for (S& e : vectors[i]) e = e * inv;
    }
}

/// The blocks of a: connected components of its nonzero off-diagonal entries,
/// numbered in the order of their first index.
template <class IsZero>
std::vector<std::vector<int>> blocks_of(std::size_t n, IsZero is_zero) {
    std::vector<int> parent(n);
    std::iota(parent.begin(), parent.end(), 0);
    auto find = [&](int i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    };
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = i + 1; j < n; ++j)
            if (!is_zero(i, j)) parent[find(static_cast<int>(i))] = find(static_cast<int>(j));
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
    return blocks;
}

/// The eigenpairs of `a` in the arithmetic `ar`: entry(r, s, hi, lo) gives the
/// working-precision value of a nonzero entry and its double-double split,
/// exact(r, s) the entry as it is (a block of size 1 keeps its diagonal entry).
/// `memo(idx, solve)` returns the block's (values, vectors), calling solve()
/// for them or taking them from where it kept them.
template <class A, class Pair, class Entry, class Exact, class IsZero, class Memo>
std::vector<Pair> symmetric_eigen(const A& ar, std::size_t n, Entry entry, Exact exact, IsZero is_zero,
                                  typename Pair::Scalar exact_zero, typename Pair::Scalar exact_one, Memo memo) {
    using S = typename A::S;
    std::vector<Pair> pairs;
    pairs.reserve(n);
    for (const std::vector<int>& idx : blocks_of(n, is_zero)) {
        const std::size_t b = idx.size();
        if (b == 1) {
            Pair p;
            p.value = exact(idx[0], idx[0]);
            p.vector.assign(n, exact_zero);
            p.vector[idx[0]] = exact_one;
            pairs.push_back(std::move(p));
            continue;
        }
        const auto& [values, vectors] = memo(idx, [&] {
            SparseRows<S> rows;
            rows.col.resize(b);
            rows.val.resize(b);
            Eigen::MatrixXd ad = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(b), static_cast<Eigen::Index>(b));
            Eigen::MatrixXd ad_lo = ad;  // A = ad + ad_lo to about 32 digits
            for (std::size_t r = 0; r < b; ++r)
                for (std::size_t s = 0; s < b; ++s) {
                    if (is_zero(idx[r], idx[s])) continue;  // exact zero (or a zero float: nothing to add)
                    double hi = 0, lo = 0;
                    rows.col[r].push_back(static_cast<int>(s));
                    rows.val[r].push_back(entry(idx[r], idx[s], hi, lo));
                    ad(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(s)) = hi;
                    ad_lo(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(s)) = lo;
                }
            for (std::size_t r = 0; r < b; ++r)
                if (rows.col[r].empty()) {  // a zero row: keep one explicit zero term for the products
                    rows.col[r].push_back(static_cast<int>(r));
                    rows.val[r].push_back(ar.of(0.0));
                }
            std::pair<std::vector<S>, std::vector<std::vector<S>>> solved;
            solve_block(ar, rows, ad, ad_lo, solved.first, solved.second);
            return solved;
        });
        for (std::size_t i = 0; i < b; ++i) {
            Pair p;
            p.value = values[i];
            p.vector.assign(n, exact_zero);
            for (std::size_t r = 0; r < b; ++r) p.vector[idx[r]] = vectors[i][r];
            pairs.push_back(std::move(p));
        }
    }
    std::stable_sort(pairs.begin(), pairs.end(), [](const Pair& p, const Pair& q) { return p.value < q.value; });
    return pairs;
}

}  // namespace

std::vector<MpEigenpair> mp_symmetric_eigen(const std::vector<std::vector<cl_R>>& a, cln::float_format_t format) {
    const LongFloat ar{format};
    auto entry = [&](int r, int s, double& hi, double& lo) {
        const cl_LF lf = cln::the<cl_LF>(cln::cl_float(a[r][s], format));
        hi = cln::double_approx(lf);
        lo = cln::double_approx(lf - ar.of(hi));
        return lf;
    };
    auto exact = [&](int r, int s) { return a[r][s]; };
    auto is_zero = [&](std::size_t r, std::size_t s) { return cln::zerop(a[r][s]); };
    return symmetric_eigen<LongFloat, MpEigenpair>(ar, a.size(), entry, exact, is_zero, cl_R(0), cl_R(1),
                                                   [](const std::vector<int>&, auto&& solve) { return solve(); });
}

void dd_jacobi_eigen(std::vector<std::vector<DD>>& a, std::vector<std::vector<DD>>& vectors) {
    small_jacobi(DoubleDouble{}, a, vectors);
}

std::vector<DdEigenpair> dd_symmetric_eigen(const std::vector<std::vector<DD>>& a, DdEigenCache* cache) {
    auto entry = [&](int r, int s, double& hi, double& lo) {
        hi = a[r][s].hi();
        lo = a[r][s].lo();
        return a[r][s];
    };
    auto exact = [&](int r, int s) { return a[r][s]; };
    auto is_zero = [&](std::size_t r, std::size_t s) { return a[r][s].is_zero(); };
    using Result = std::pair<std::vector<DD>, std::vector<std::vector<DD>>>;
    Result scratch;  // the block just solved, when it is not kept
    auto memo = [&](const std::vector<int>& idx, auto&& solve) -> const Result& {
        if (!cache) return scratch = solve();
        // The block's entries, bit for bit (its zeros too: they are its structure).
        std::string key(idx.size() * idx.size() * 2 * sizeof(double), '\0');
        char* at = key.data();
        for (int r : idx)
            for (int c : idx) {
                const double hl[2] = {a[r][c].hi(), a[r][c].lo()};
                std::memcpy(at, hl, sizeof hl);
                at += sizeof hl;
            }
        if (const auto it = cache->blocks_.find(key); it != cache->blocks_.end()) {
            ++cache->hits_;
            return it->second;
        }
        Result solved = solve();
        const std::size_t bytes = key.size() + sizeof(DD) * idx.size() * (idx.size() + 1);
        if (cache->bytes_ + bytes > cache->max_bytes_) {  // full: start again (a run's blocks recur soon)
            cache->blocks_.clear();
            cache->bytes_ = 0;
        }
        if (bytes > cache->max_bytes_) return scratch = std::move(solved);
        cache->bytes_ += bytes;
        return cache->blocks_.emplace(std::move(key), std::move(solved)).first->second;
    };
    return symmetric_eigen<DoubleDouble, DdEigenpair>(DoubleDouble{}, a.size(), entry, exact, is_zero, DD(0.0), DD(1.0),
                                                      memo);
}

}  // namespace hsnc
