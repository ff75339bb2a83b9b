// The derivation's eigen-solver (generator/mp_eigen.h: double solve, refined
// in long floats) against closed forms, and the refined derivation against the
// Jacobi one (EigenMethod::jacobi, the former path) on random and structured
// models: every double-double quantity the lowering rounds agrees to 1e-28.
// Repeated eigenvalues have no unique eigenvectors: there the projector onto
// each eigenspace (sum of v w^T over its modes) is compared.
#include <gtest/gtest.h>

#include <cln/cln.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "derivation.h"
#include "lowering.h"
#include "model_reader.h"
#include "mp_eigen.h"
#include "random_model.h"
#include "sample_models.h"

namespace hsnc {
namespace {

using cln::cl_F;
using cln::cl_R;
using GiNaC::numeric;

const cln::float_format_t kFormat = cln::float_format(kDerivationDigits);

cl_R lf(const cl_R& x) { return cln::cl_float(x, kFormat); }
double rel_gap(const cl_R& a, const cl_R& b, const cl_R& scale) {
    return cln::double_approx(cln::abs(a - b) / scale);
}

/// |A v - value v| and |v.v - 1|, |v_j.v_k| (largest over the pairs), relative to |A|.
void expect_eigenpairs(const std::vector<std::vector<cl_R>>& a, const std::vector<MpEigenpair>& pairs, double tol) {
    const std::size_t n = a.size();
    ASSERT_EQ(pairs.size(), n);
    cl_R norm = 0;
    for (const auto& row : a)
        for (const cl_R& e : row) norm = cln::max(norm, cln::abs(e));
    for (std::size_t j = 0; j < n; ++j) {
        for (std::size_t r = 0; r < n; ++r) {
            cl_R av = 0;
            for (std::size_t s = 0; s < n; ++s) av = av + a[r][s] * pairs[j].vector[s];
            EXPECT_LE(rel_gap(av, pairs[j].value * pairs[j].vector[r], norm), tol) << "pair " << j << " row " << r;
        }
        for (std::size_t k = j; k < n; ++k) {
            cl_R d = 0;
            for (std::size_t r = 0; r < n; ++r) d = d + pairs[j].vector[r] * pairs[k].vector[r];
            EXPECT_LE(cln::double_approx(cln::abs(d - (j == k ? 1 : 0))), tol) << "pairs " << j << ", " << k;
        }
        if (j > 0) EXPECT_LE(pairs[j - 1].value, pairs[j].value);
    }
}

cl_R exact_dd(const DD& x) { return cln::rational(cln::cl_DF(x.hi())) + cln::rational(cln::cl_DF(x.lo())); }

// DD (double_double.h) against exact rationals: every operation on random
// operands (signs and exponents mixed, lo parts random) within a few units of
// 2^-104 of the exact result, relative.
TEST(DoubleDouble, OperationsAgreeWithExactArithmetic) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> mant(-1.0, 1.0);
    std::uniform_int_distribution<int> expo(-30, 30);
    auto draw = [&] {
        const double hi = std::ldexp(mant(rng), expo(rng));
        return DD(hi) + DD(hi * std::ldexp(mant(rng), -53));
    };
    const cl_R unit = cln::expt(cl_R(2), -104);
    double worst[5] = {0, 0, 0, 0, 0};
    for (int k = 0; k < 4000; ++k) {
        const DD a = draw(), b = draw();
        const cl_R ea = exact_dd(a), eb = exact_dd(b);
        // normalised: |lo| <= ulp(hi)/2, so hi is the nearest double
        for (const DD& x : {a + b, a * b, a / b}) EXPECT_EQ(x.hi() + x.lo(), x.hi());
        const cl_R results[5] = {ea + eb, ea - eb, ea * eb, ea / eb, 0};
        const DD got[4] = {a + b, a - b, a * b, a / b};
        for (int op = 0; op < 4; ++op) {
            if (cln::zerop(results[op])) continue;
            const double e = cln::double_approx(cln::abs(exact_dd(got[op]) - results[op]) / cln::abs(results[op]) / unit);
            worst[op] = std::max(worst[op], e);
        }
        const DD r = sqrt(abs(a));
        const cl_R er = exact_dd(r);  // r^2 against |a|: twice the root's relative error
        const double e = cln::double_approx(cln::abs(er * er - cln::abs(ea)) / cln::abs(ea) / unit) / 2;
        worst[4] = std::max(worst[4], e);
    }
    std::printf("DD relative errors in units of 2^-104: + %.2g, - %.2g, * %.2g, / %.2g, sqrt %.2g\n", worst[0], worst[1],
                worst[2], worst[3], worst[4]);
    for (int op = 0; op < 5; ++op) EXPECT_LE(worst[op], 8.0) << "operation " << op;
    EXPECT_EQ(sqrt(DD(0.0)).hi(), 0.0);
    EXPECT_EQ((DD(1.0) / DD(3.0)).hi(), 1.0 / 3.0);
    EXPECT_EQ(pow(DD(3.0), 5).hi(), 243.0);
}

/// The 40-digit pairs of a DD matrix and its DD pairs, as MpEigenpairs (exactly).
std::vector<MpEigenpair> as_mp(const std::vector<DdEigenpair>& dd) {
    std::vector<MpEigenpair> out;
    for (const DdEigenpair& p : dd) {
        MpEigenpair q;
        q.value = exact_dd(p.value);
        for (const DD& e : p.vector) q.vector.push_back(exact_dd(e));
        out.push_back(q);
    }
    return out;
}

// The derivation's eigen-solver in double-double against the same refinement
// in 40-digit long floats: residuals, orthonormality and eigenvalues at DD's
// precision, on chains, dense random matrices, clusters and uncoupled blocks.
TEST(MpEigen, DoubleDoubleAgreesWithLongFloats) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int checked = 0;
    for (int trial = 0; trial < 40; ++trial) {
        const int n = 2 + trial % 19;
        std::vector<std::vector<DD>> a(n, std::vector<DD>(n));
        for (int i = 0; i < n; ++i)
            for (int j = i; j < n; ++j) {
                const bool coupled = trial % 3 == 0 ? std::abs(i - j) <= 1 : trial % 3 == 1 || (i + j) % 3 != 0;
                if (!coupled) continue;
                // trial % 4 == 3: near-repeated diagonal (clusters)
                const double v = i == j ? (trial % 4 == 3 ? 4.0 + 1e-10 * u(rng) : 5.0 * u(rng)) : u(rng);
                a[i][j] = a[j][i] = DD(v) + DD(v * 1e-17 * u(rng));
            }
        std::vector<std::vector<cl_R>> ea(n, std::vector<cl_R>(n));
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) ea[i][j] = a[i][j].is_zero() ? cl_R(0) : cl_R(lf(exact_dd(a[i][j])));
        const std::vector<MpEigenpair> dd = as_mp(dd_symmetric_eigen(a)), mp = mp_symmetric_eigen(ea, kFormat);
        SCOPED_TRACE("trial " + std::to_string(trial));
        // Residuals and orthonormality to DD's 2^-104 over the eigenvalues'
        // relative gaps (down to ~1e-3 in these draws; 3e-29 measured).
        expect_eigenpairs(ea, dd, 1e-27);
        cl_R norm = 0;
        for (const auto& row : ea)
            for (const cl_R& e : row) norm = cln::max(norm, cln::abs(e));
        for (int j = 0; j < n; ++j) EXPECT_LE(rel_gap(dd[j].value, mp[j].value, norm), 1e-30) << j;
        ++checked;
    }
    EXPECT_EQ(checked, 40);
}

// The uniform chain (2 on the diagonal, -1 beside it): lambda_j = 2 - 2 cos(j pi/(n+1)),
// v_j(i) = sqrt(2/(n+1)) sin(i j pi/(n+1)), computed in CLN at the same precision.
TEST(MpEigen, UniformChainClosedForm) {
    for (int n : {2, 3, 8, 17, 40}) {
        std::vector<std::vector<cl_R>> a(n, std::vector<cl_R>(n, cl_R(0)));
        for (int i = 0; i < n; ++i) {
            a[i][i] = lf(2);
            if (i + 1 < n) a[i][i + 1] = a[i + 1][i] = lf(-1);
        }
        const std::vector<MpEigenpair> pairs = mp_symmetric_eigen(a, kFormat);
        expect_eigenpairs(a, pairs, 1e-44);
        const cl_F pi = cln::pi(kFormat);
        const cl_F norm = cln::sqrt(cln::cl_float(2, kFormat) / (n + 1));
        for (int j = 0; j < n; ++j) {
            const cl_F theta = pi * cln::cl_float(j + 1, kFormat) / cln::cl_float(n + 1, kFormat);
            EXPECT_LE(rel_gap(pairs[j].value, 2 - 2 * cln::cos(theta), cln::cl_float(4, kFormat)), 1e-44) << n << " " << j;
            // Up to sign: compare against the closed form with the sign of the first component.
            const int sign = cln::minusp(pairs[j].vector[0]) ? -1 : 1;
            for (int i = 0; i < n; ++i)
                EXPECT_LE(rel_gap(pairs[j].vector[i], sign * norm * cln::sin(theta * (i + 1)), cln::cl_float(1, kFormat)),
                          1e-44)
                    << n << " " << j << " " << i;
        }
    }
}

// A = H D H with a Householder reflection H = I - 2 u u^T / u^T u (rational, orthogonal)
// and D with repeated and nearly repeated eigenvalues: one connected block whose
// eigenspaces are known exactly (H's columns).
TEST(MpEigen, RepeatedEigenvaluesInOneBlock) {
    const std::vector<cl_R> u = {1, 2, -1, 3, 1, -2};
    const std::vector<cl_R> d = {1, 1, 1, 2, cl_R(2) + cln::expt(cl_R(10), -12) * cl_R(3), 5};
    const std::size_t n = u.size();
    cl_R uu = 0;
    for (const cl_R& e : u) uu = uu + e * e;
    std::vector<std::vector<cl_R>> h(n, std::vector<cl_R>(n)), a(n, std::vector<cl_R>(n));
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j) h[i][j] = cl_R(i == j ? 1 : 0) - 2 * u[i] * u[j] / uu;
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j) {
            cl_R s = 0;
            for (std::size_t k = 0; k < n; ++k) s = s + h[i][k] * d[k] * h[j][k];
            a[i][j] = lf(s);
        }
    const std::vector<MpEigenpair> pairs = mp_symmetric_eigen(a, kFormat);
    expect_eigenpairs(a, pairs, 1e-44);
    for (std::size_t j = 0; j < n; ++j) EXPECT_LE(rel_gap(pairs[j].value, d[j], cl_R(5)), 1e-44) << j;
    // The projector onto the triple eigenspace equals sum_k H_k H_k^T over k < 3.
    for (std::size_t r = 0; r < n; ++r)
        for (std::size_t s = 0; s < n; ++s) {
            cl_R p = 0, q = 0;
            for (std::size_t k = 0; k < 3; ++k) {
                p = p + pairs[k].vector[r] * pairs[k].vector[s];
                q = q + h[r][k] * h[s][k];
            }
            EXPECT_LE(rel_gap(p, q, cl_R(1)), 1e-44) << r << " " << s;
        }
    // The pair 2, 2 + 3e-12 is resolved: each vector is H's column up to sign.
    for (std::size_t k = 3; k < 5; ++k) {
        const int sign = cln::minusp(pairs[k].vector[0] * h[0][k]) ? -1 : 1;
        for (std::size_t r = 0; r < n; ++r) EXPECT_LE(rel_gap(pairs[k].vector[r], sign * h[r][k], cl_R(1)), 1e-30) << k;
    }
}

// Exact zeros split the matrix into blocks: eigenvectors are exactly zero off
// their block, equal blocks give bit-equal eigenvalues, the earlier block first.
TEST(MpEigen, BlocksStayExactlyUncoupled) {
    const int n = 7;
    std::vector<std::vector<cl_R>> a(n, std::vector<cl_R>(n, cl_R(0)));
    for (int b0 : {0, 4}) {  // blocks {0, 1, 2} and {4, 5, 6}, equal; 3 alone
        for (int i = b0; i < b0 + 3; ++i) a[i][i] = lf(3);
        for (int i = b0; i < b0 + 2; ++i) a[i][i + 1] = a[i + 1][i] = lf(cl_R(-7) / 5);
    }
    a[3][3] = lf(cl_R(1) / 3);
    const std::vector<MpEigenpair> pairs = mp_symmetric_eigen(a, kFormat);
    expect_eigenpairs(a, pairs, 1e-44);
    for (int j = 0; j < n; ++j) {
        int lo = n, hi = -1;
        for (int r = 0; r < n; ++r)
            if (!cln::zerop(pairs[j].vector[r])) lo = std::min(lo, r), hi = std::max(hi, r);
        EXPECT_TRUE((lo == 3 && hi == 3) || (lo == 0 && hi <= 2) || (lo >= 4 && hi <= 6)) << j;
        for (int r = 0; r < n; ++r)
            if (r < lo || r > hi) EXPECT_TRUE(numeric(pairs[j].vector[r]).is_zero() && numeric(pairs[j].vector[r]).is_rational());
    }
    // pairs: 1/3 (block of 3 alone), then each of the blocks' eigenvalues twice.
    EXPECT_EQ(pairs[0].value, a[3][3]);
    for (int j = 1; j < n; j += 2) {
        EXPECT_TRUE(pairs[j].value == pairs[j + 1].value) << j;
        EXPECT_FALSE(cln::zerop(pairs[j].vector[0]) && cln::zerop(pairs[j].vector[1]) && cln::zerop(pairs[j].vector[2]));
        EXPECT_TRUE(cln::zerop(pairs[j + 1].vector[0]) && cln::zerop(pairs[j + 1].vector[1]));
    }
}

// A block solved once and met again, alone or beside others, in another place
// of another matrix: taken from the cache, and every pair the bits of a solve
// without it (the cache the interpreter's derivations share in one run).
TEST(MpEigen, ACachedBlockGivesTheBitsOfASolve) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.5, 2.0);
    auto block = [&](std::vector<std::vector<DD>>& a, int at, int size) {
        for (int i = at; i < at + size; ++i) a[i][i] = DD(4.0 + u(rng)) + DD(1e-20);
        for (int i = at; i + 1 < at + size; ++i) a[i][i + 1] = a[i + 1][i] = DD(-u(rng));
    };
    auto same = [](const std::vector<DdEigenpair>& p, const std::vector<DdEigenpair>& q) {
        ASSERT_EQ(p.size(), q.size());
        for (std::size_t j = 0; j < p.size(); ++j) {
            EXPECT_EQ(p[j].value.hi(), q[j].value.hi()) << j;
            EXPECT_EQ(p[j].value.lo(), q[j].value.lo()) << j;
            for (std::size_t r = 0; r < p[j].vector.size(); ++r) {
                EXPECT_EQ(p[j].vector[r].hi(), q[j].vector[r].hi()) << j << ' ' << r;
                EXPECT_EQ(p[j].vector[r].lo(), q[j].vector[r].lo()) << j << ' ' << r;
            }
        }
    };
    std::vector<std::vector<DD>> a(9, std::vector<DD>(9));
    block(a, 0, 4);  // blocks {0..3}, {4} and {5..8}
    a[4][4] = DD(3.0);
    block(a, 5, 4);
    DdEigenCache cache;
    same(dd_symmetric_eigen(a, &cache), dd_symmetric_eigen(a));
    EXPECT_EQ(cache.hits(), 0u);
    // The first block again, now at the end; the second and a new one before it.
    std::vector<std::vector<DD>> b(10, std::vector<DD>(10));
    for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 4; ++k) b[6 + i][6 + k] = a[i][k], b[1 + i][1 + k] = a[5 + i][5 + k];
    b[0][0] = DD(2.5);
    b[5][5] = DD(7.0);
    b[5][4] = b[4][5] = DD(-0.25);  // {1..5}: the second block grown by one mass
    same(dd_symmetric_eigen(b, &cache), dd_symmetric_eigen(b));
    EXPECT_EQ(cache.hits(), 1u);  // {6..9}; {0} is a block of one, never solved
    same(dd_symmetric_eigen(b, &cache), dd_symmetric_eigen(b));
    EXPECT_EQ(cache.hits(), 3u);  // {1..5} and {6..9}
}

// ---- the refined derivation against the Jacobi one ----

double gap(const numeric& a, const numeric& b, double scale) {
    return std::fabs((a - b).to_double()) / scale;
}

double gap(const DD& a, const DD& b, double scale) { return std::fabs((a - b).to_double()) / scale; }

double max_abs(const std::vector<DD>& v) {
    double m = 0;
    for (const DD& e : v) m = std::max(m, std::fabs(e.to_double()));
    return m;
}

double max_abs(const std::vector<numeric>& v) {
    double m = 0;
    for (const numeric& e : v) m = std::max(m, std::fabs(e.to_double()));
    return m;
}

/// Every double-double quantity lower() rounds, compared at `tol`: eigenvalues and
/// the scalars of each mode, V and W of each mode (of each eigenspace's
/// projector where eigenvalues repeat), the modal amplitudes and particular
/// solutions of each harmonic.
/// Counts of what the comparisons met: eigenspaces of more than one mode, rigid modes.
struct Seen {
    int repeated = 0, rigid = 0;
};

Seen expect_same_derivation(const Model& model, const Configuration& cfg, double tol, const std::string& what) {
    Seen seen;
    SCOPED_TRACE(what + " " + cfg.spec(model));
    const Derivation r = derive(model, cfg, EigenMethod::refined), j = derive(model, cfg, EigenMethod::jacobi);
    const std::size_t nm = r.modes.size(), nf = r.n_free();
    EXPECT_EQ(nm, j.modes.size());
    EXPECT_EQ(r.free_dofs, j.free_dofs);
    if (nm != j.modes.size() || r.free_dofs != j.free_dofs) return seen;
    double lmax = 1e-300;
    for (const Mode& m : j.modes) lmax = std::max(lmax, std::fabs(m.lambda.to_double()));
    for (std::size_t k = 0; k < nm; ++k) {
        const Mode &a = r.modes[k], &b = j.modes[k];
        EXPECT_EQ(static_cast<int>(a.regime), static_cast<int>(b.regime)) << "mode " << k;
        seen.rigid += b.regime == Regime::rigid || b.regime == Regime::rigid_damped;
        const double l = std::max(std::fabs(b.lambda.to_double()), 1e-300);
        EXPECT_LE(gap(a.lambda, b.lambda, l), tol) << "lambda " << k;
        EXPECT_LE(gap(a.c, b.c, std::max(std::fabs(b.c.to_double()), 1e-300)), tol) << "c " << k;
        EXPECT_LE(gap(a.omega, b.omega, std::max(b.omega.to_double(), 1e-300)), tol) << "omega " << k;
        EXPECT_LE(gap(a.sigma, b.sigma, std::max(std::fabs(b.sigma.to_double()), 1e-300)), tol) << "sigma " << k;
        // kappa = lambda - sigma^2: known to the working precision of the larger term.
        const double sigma2 = b.sigma.to_double() * b.sigma.to_double();
        EXPECT_LE(gap(a.kappa, b.kappa, std::max({l, sigma2, 1e-300})), tol) << "kappa " << k;
        EXPECT_LE(gap(a.omega_d, b.omega_d, std::max(b.omega.to_double(), 1e-300)), tol) << "omega_d " << k;
        EXPECT_LE(gap(a.gamma, b.gamma, std::max(b.gamma.to_double(), 1e-300)), tol) << "gamma " << k;
        EXPECT_LE(gap(a.r1, b.r1, std::max(std::fabs(b.r1.to_double()), 1e-300)), tol) << "r1 " << k;
    }
    // The Jacobi path stops once the off-diagonal part of Kt is below 2^-96
    // (1.3e-29) of its norm (|Kt|_F <= sqrt(nf) lambda_max): its eigenvectors
    // are off by up to that over the gap to the other eigenvalues. Vectors and
    // what is summed from them are compared at tol plus that bound.
    const double off = 1.3e-29 * std::sqrt(static_cast<double>(nf)) * lmax;
    double worst = 0;  // largest bound over the eigenspaces
    // Eigenspaces: runs of eigenvalues equal to 1e-20 of the largest.
    for (std::size_t k0 = 0, k1; k0 < nm; k0 = k1) {
        for (k1 = k0 + 1; k1 < nm && gap(j.modes[k1].lambda, j.modes[k1 - 1].lambda, lmax) <= 1e-20;) ++k1;
        double g = 1e300;
        if (k0 > 0) g = std::min(g, (j.modes[k0].lambda - j.modes[k0 - 1].lambda).to_double());
        if (k1 < nm) g = std::min(g, (j.modes[k1].lambda - j.modes[k1 - 1].lambda).to_double());
        const double vtol = tol + off / g;
        worst = std::max(worst, vtol);
        if (k1 == k0 + 1) {
            const double sv = max_abs(j.modes[k0].v), sw = max_abs(j.modes[k0].w);
            for (std::size_t s = 0; s < nf; ++s) {
                EXPECT_LE(gap(r.modes[k0].v[s], j.modes[k0].v[s], sv), vtol) << "V mode " << k0 << " mass " << s;
                EXPECT_LE(gap(r.modes[k0].w[s], j.modes[k0].w[s], sw), vtol) << "W mode " << k0 << " mass " << s;
            }
            for (std::size_t h = 0; h < j.harmonics.size(); ++h) {
                const ModalHarmonic &a = r.harmonics[h].modal[k0], &b = j.harmonics[h].modal[k0];
                EXPECT_EQ(a.resonant, b.resonant);
                const double sp = std::max(std::fabs(b.P.to_double()), sv * max_abs(j.harmonics[h].amplitude));
                EXPECT_LE(gap(a.P, b.P, std::max(sp, 1e-300)), vtol) << "P mode " << k0 << " harmonic " << h;
                if (b.resonant) continue;  // sinc form: no a_s, a_c
                const double sa = std::max(std::fabs(b.a_s.to_double()), std::fabs(b.a_c.to_double()));
                EXPECT_LE(gap(a.a_s, b.a_s, sa), tol) << "a_s mode " << k0 << " harmonic " << h;
                EXPECT_LE(gap(a.a_c, b.a_c, sa), tol) << "a_c mode " << k0 << " harmonic " << h;
            }
            continue;
        }
        ++seen.repeated;
        std::vector<DD> pr(nf * nf, 0), pj(nf * nf, 0);
        for (std::size_t k = k0; k < k1; ++k)
            for (std::size_t s = 0; s < nf; ++s)
                for (std::size_t t = 0; t < nf; ++t) {
                    pr[s * nf + t] += r.modes[k].v[s] * r.modes[k].w[t];
                    pj[s * nf + t] += j.modes[k].v[s] * j.modes[k].w[t];
                }
        const double sp = std::max(max_abs(pj), 1e-300);
        for (std::size_t e = 0; e < nf * nf; ++e)
            EXPECT_LE(gap(pr[e], pj[e], sp), vtol) << "projector, modes " << k0 << "-" << k1 - 1;
    }
    for (std::size_t h = 0; h < j.harmonics.size(); ++h) {
        const double sx = std::max({max_abs(j.harmonics[h].xs), max_abs(j.harmonics[h].xc), 1e-300});
        for (std::size_t s = 0; s < nf; ++s) {
            EXPECT_LE(gap(r.harmonics[h].xs[s], j.harmonics[h].xs[s], sx), worst) << "xs harmonic " << h;
            EXPECT_LE(gap(r.harmonics[h].xc[s], j.harmonics[h].xc[s], sx), worst) << "xc harmonic " << h;
        }
    }
    EXPECT_EQ(r.max_step, j.max_step);
    return seen;
}

constexpr double kAgreement = 1e-28;

TEST(RefinedDerivation, RandomModelsAgreeWithJacobi) {
    int rigid = 0;
    for (unsigned seed = 1; seed <= 160; ++seed) {
        const testing::Drawn d = testing::draw(seed, 1 + static_cast<int>(seed % 12));
        for (const Configuration& c : {d.cfg, Configuration::all_open(d.model)})
            rigid += expect_same_derivation(d.model, c, kAgreement, "random seed " + std::to_string(seed)).rigid;
    }
    EXPECT_GT(rigid, 10);  // floating draws
}

TEST(RefinedDerivation, SampleModelsAgreeWithJacobi) {
    for (const Model& m : sample_models()) {
        if (!m.proportional_damping()) continue;  // dampers: state-space modes, no symmetric eigenproblem
        Configuration c = Configuration::all_open(m);
        expect_same_derivation(m, c, kAgreement, m.name);
    }
}

// Uniform chains: stuck masses split them into equal free pieces (eigenvalues
// repeated across blocks, with exactly zero couplings), symmetric pieces have
// eigenvector components that vanish exactly; a free chain floats (a rigid mode).
TEST(RefinedDerivation, RepeatedEigenvaluesAndFloatingComponents) {
    auto chain = [](int n, bool grounded, double m0) {
        std::string t = "name = \"uniform\"\n[damping]\nalpha = 0.02\nbeta = 0.0005\n";
        for (int i = 1; i <= n; ++i)
            t += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = " + std::to_string(i == 1 ? m0 : 1.0) +
                 "\nmu_k = 0.1\nmu_s = 0.2\n";
        for (int i = grounded ? 0 : 1; i <= (grounded ? n : n - 1); ++i)
            t += "[[spring]]\nbetween = [\"" + (i == 0 ? std::string("ground") : "m" + std::to_string(i)) + "\", \"" +
                 (i == n ? std::string("ground") : "m" + std::to_string(i + 1)) + "\"]\nk = 100\n";
        t += "[[forcing]]\nomega = 7.0\namplitude = { m1 = 3.0, m2 = -1.0 }\n";
        return parse_model(t, "uniform");
    };
    const Model grounded = chain(11, true, 1.0), floating = chain(9, false, 1.0), mixed = chain(10, false, 2.5);
    Seen seen;
    for (const Model* m : {&grounded, &floating, &mixed}) {
        const int n = static_cast<int>(m->dof());
        for (unsigned pattern = 0; pattern < 40; ++pattern) {
            Configuration c = Configuration::all_open(*m);
            // stuck every k-th mass from an offset: equal pieces between them
            const int k = 2 + static_cast<int>(pattern % 4), off = static_cast<int>(pattern / 4) % k;
            if (pattern >= 1)
                for (int i = off; i < n; i += k) c.stuck[i] = 1;
            const Seen s = expect_same_derivation(*m, c, kAgreement, m->name + " pattern " + std::to_string(pattern));
            seen.repeated += s.repeated;
            seen.rigid += s.rigid;
        }
    }
    // A ring of equal masses and springs, each also held to ground: a circulant
    // K, its eigenvalues in pairs within one connected block.
    std::string t = "name = \"ring\"\n";
    const int n = 7;
    for (int i = 1; i <= n; ++i) t += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = 1.5\n";
    for (int i = 1; i <= n; ++i) {
        t += "[[spring]]\nbetween = [\"m" + std::to_string(i) + "\", \"m" + std::to_string(i % n + 1) + "\"]\nk = 30\n";
        t += "[[spring]]\nbetween = [\"m" + std::to_string(i) + "\", \"ground\"]\nk = 4\n";
    }
    t += "[[forcing]]\nomega = 3.0\namplitude = { m1 = 1.0 }\n";
    const Model ring = parse_model(t, "ring");
    EXPECT_EQ(expect_same_derivation(ring, Configuration::all_open(ring), kAgreement, "ring").repeated, 3);
    // Two equal floating pieces of four masses (no spring between m4 and m5,
    // none to ground): two rigid modes, every elastic eigenvalue twice; then
    // with one end mass of either piece held.
    std::string p = "name = \"pieces\"\n[damping]\nalpha = 0.1\n";
    for (int i = 1; i <= 8; ++i) p += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = 0.7\nmu_k = 0.1\n";
    for (int i = 1; i < 8; ++i)
        if (i != 4)
            p += "[[spring]]\nbetween = [\"m" + std::to_string(i) + "\", \"m" + std::to_string(i + 1) + "\"]\nk = 55\n";
    const Model pieces = parse_model(p, "pieces");
    for (int held : {-1, 0, 4, 7}) {
        Configuration c = Configuration::all_open(pieces);
        if (held >= 0) c.stuck[held] = 1;
        const Seen s = expect_same_derivation(pieces, c, kAgreement, "pieces held " + std::to_string(held));
        seen.repeated += s.repeated;
        seen.rigid += s.rigid;
    }
    EXPECT_GT(seen.repeated, 100);
    EXPECT_EQ(seen.rigid, 7);  // the free floating chains (2), the pieces (2, then 1 each held)
}

}  // namespace
}  // namespace hsnc
