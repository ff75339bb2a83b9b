// hsnc -- mp_eigen: the eigenpairs of a real symmetric matrix at high
// precision, in O(n^3) with a small constant: solved in double (Eigen), then
// refined in the working precision: double-double (DD, about 32 digits: the
// derivation's) or CLN long floats of any format (the tests' 40 digits).
//
// The matrix is split into the blocks its exact zeros leave uncoupled
// (connected components of the graph of its nonzero off-diagonal entries);
// each eigenvector lives on one block, exactly zero elsewhere. Per block of
// size b > 1:
//   1. A = X diag(mu) X^T in double (Eigen::SelfAdjointEigenSolver).
//   2. Mixed-precision Newton refinement of each pair (lambda_i, phi_i),
//      starting from (mu_i, X_i): the residual r = A phi - lambda phi and the
//      Rayleigh quotient lambda = phi.A phi / phi.phi in the working
//      precision, the correction in double through the double decomposition,
//          phi <- phi - sum_{k not in C(i)} X_k (X_k^T r) / (mu_k - lambda_i),
//      accumulated in the working precision. C(i) is i's cluster: the
//      eigenvalues of the double solve closer than kClusterGap (relative) to
//      a neighbour. A cluster's vectors are refined as a subspace (only the
//      components out of it are corrected), then orthonormalised
//      (Gram-Schmidt) and rotated by the Jacobi eigenvectors of the projected
//      matrix Phi^T A Phi (Rayleigh-Ritz): (near-)repeated eigenvalues get an
//      orthonormal basis of their invariant subspace.
//   3. Until every residual is below kResidualTol (DD: kDdResidualTol) times
//      |A|_F; each step gains about 16 digits times the separation of the
//      eigenvalues.
// The cost per step is a sparse product A phi and a few vector operations in
// the working precision per eigenpair and two dense double products:
// O(b nnz + b^2) working-precision operations, O(b^3) double ones.
#pragma once

#include <cln/lfloat.h>
#include <cln/real.h>

#include <cstddef>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "double_double.h"

namespace hsnc {

/// One eigenpair: A v = value v, v normalised (Euclidean), exactly zero (the
/// rational 0) off the eigenpair's block. A block of size 1 gives its
/// diagonal entry and the exact unit vector.
struct MpEigenpair {
    using Scalar = cln::cl_R;
    Scalar value;
    std::vector<cln::cl_R> vector;
};

/// Relative gap (to the largest |eigenvalue| of the block) below which
/// neighbouring eigenvalues of the double solve form one cluster.
inline constexpr double kClusterGap = 1e-8;
/// Residual |A v - value v| at which a pair is converged, relative to |A|_F:
/// long floats, and DD (a few units of its 2^-104 times sqrt(b)).
inline constexpr double kResidualTol = 1e-50;
inline constexpr double kDdResidualTol = 1e-29;

/// The eigenpairs of the symmetric matrix `a` (n x n; each entry the exact
/// rational 0 or a long float of `format`), in ascending order of value
/// (equal values: the earlier block first, then the block's own order).
/// Throws RunError when a refinement does not converge.
std::vector<MpEigenpair> mp_symmetric_eigen(const std::vector<std::vector<cln::cl_R>>& a,
                                            cln::float_format_t format);

/// The same in double-double: a block of size 1 gives its entry and the unit
/// vector, the other vectors are exactly 0 off their block.
struct DdEigenpair {
    using Scalar = DD;
    Scalar value;
    std::vector<DD> vector;
};
class DdEigenCache;
/// With a cache, each block solved is kept by its entries (bit for bit), and
/// a block met again is not solved again: the same numbers, as the solution
/// of a block depends on its entries alone. The configurations a run enters
/// share most of their blocks (one mass sticking splits one block in two).
std::vector<DdEigenpair> dd_symmetric_eigen(const std::vector<std::vector<DD>>& a, DdEigenCache* cache = nullptr);

/// Blocks dd_symmetric_eigen has solved, within max_bytes (when full, it
/// starts again empty). Not thread-safe: one user at a time.
class DdEigenCache {
public:
    explicit DdEigenCache(std::size_t max_bytes = std::size_t{32} << 20) : max_bytes_(max_bytes) {}
    /// Blocks taken from the cache instead of solved.
    std::size_t hits() const { return hits_; }

private:
    friend std::vector<DdEigenpair> dd_symmetric_eigen(const std::vector<std::vector<DD>>& a, DdEigenCache* cache);
    std::unordered_map<std::string, std::pair<std::vector<DD>, std::vector<std::vector<DD>>>> blocks_;
    std::size_t bytes_ = 0, max_bytes_, hits_ = 0;
};

/// Cyclic Jacobi rotations in DD throughout, on the whole matrix (slow,
/// unconditional: the refinement's fallback and reference): on return a's
/// diagonal holds the eigenvalues (unordered), vectors' columns the
/// eigenvectors. Throws RunError after 100 sweeps without convergence.
void dd_jacobi_eigen(std::vector<std::vector<DD>>& a, std::vector<std::vector<DD>>& vectors);

}  // namespace hsnc
