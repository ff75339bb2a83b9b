// hsnc -- a structure given by its matrices ([structure], interface.md section 5):
// the checks on M, K and C, and the lumped-model form the rest of hsnc reads.
//
// The Model keeps one representation of stiffness, springs (model.h), so a
// structure's K becomes springs exactly as written: any symmetric K is
//     K = sum_{i<j} (-K_ij) (e_i - e_j)(e_i - e_j)^T + diag(r),  r_i = sum_j K_ij,
// a spring -K_ij between dofs i and j (either sign) and a spring r_i from dof i
// to the ground. A row sum within rounding of zero (|r_i| <= max(16, n) eps
// sum_j |K_ij|) is zero: no spring to ground, so a structure whose rows sum to
// zero keeps its rigid-body translation (free_components.h).
//
// Readings where the contract leaves room (each one tested):
//  - M may be coupled (a consistent or reduced mass matrix): it is kept whole
//    (Model::mass_matrix) and never lumped; a diagonal M is the lumped model.
//  - K must be positive semi-definite, and singular only where hsnc decides
//    rigid-body modes structurally: a group of dofs coupled by K with every
//    row sum zero translates freely. Any other null vector (a free beam's
//    rotation) is refused. Symmetry and definiteness are judged to 1e-12
//    relative (symmetry entry by entry against the largest |entry|;
//    definiteness on the Jacobi-scaled matrix D^-1/2 K D^-1/2 of each group,
//    against its largest eigenvalue); a matrix symmetric to that level is
//    used as (K + K^T)/2.
//  - C (optional): when proportional, C = a M + b K to 1e-12 relative
//    (least-squares a, b, then entry by entry against a|M|max + b|K|max),
//    with a, b >= 0, it is Rayleigh damping alpha = a, beta = b, and as with
//    [damping] beta also scales [[spring]]s and closed contacts. When M and K
//    are proportional themselves (a and b not separable) the fit takes b = 0.
//    Any other C must be symmetric positive semi-definite (1e-12 relative)
//    and becomes dampers exactly as K becomes springs (model.h Damper,
//    from_structure): non-proportional damping, solved through state-space
//    modes.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "matrix_market.h"
#include "model.h"

namespace hsnc {

/// Each check returns "" when the matrix is acceptable, else the reason
/// (naming entries by dof: "M(u1, u2)"). `dofs` are the dof names in matrix order.

/// Massless dofs: a dof whose row of M is zero (a rotation without rotary
/// inertia) carries no inertia, so K_cm x_m + K_cc x_c = 0 holds at every
/// instant (no force may act on it): it is condensed statically (Guyan),
/// exact for such a model. M, K (and C) become those of the dofs with mass,
/// K_mm - K_mc K_cc^-1 K_cm, and `names` theirs; `out` records every dof and
/// R = -K_cc^-1 K_cm (model.h Condensation). "" when done or nothing is
/// massless, else the reason: M not square as the dofs, K singular on the
/// massless dofs (the condensation does not exist), or C damping a massless
/// dof (its motion would be first order, not static). Reasons about K start
/// "K ", about C "C ".
std::string condense_massless(MarketMatrix& M, MarketMatrix& K, MarketMatrix* C, std::vector<std::string>& names,
                              Condensation& out);

/// M: n x n, symmetric, positive definite. On success `mass` holds its
/// diagonal, and when M has an off-diagonal entry `coupled` holds all of it
/// (row-major) and `floor` its smallest eigenvalue (else both are empty / 0).
std::string check_mass_matrix(const MarketMatrix& M, const std::vector<std::string>& dofs, std::vector<double>& mass,
                              std::vector<double>& coupled, double& floor);

/// K: n x n, symmetric, positive semi-definite with structural null space.
/// On success `springs` holds its springs (Spring::from_structure), the
/// between-dof springs row by row (i < j), then the springs to ground.
std::string check_stiffness_matrix(const MarketMatrix& K, const std::vector<std::string>& dofs,
                                   std::vector<Spring>& springs);

/// C: n x n, symmetric. `proportional` tells whether C = a M + b K; then a, b
/// must be >= 0 and `alpha`, `beta` hold them. A C that is not proportional
/// is no error here (check_damping_matrix).
std::string fit_rayleigh_damping(const MarketMatrix& C, const MarketMatrix& M, const MarketMatrix& K,
                                 const std::vector<std::string>& dofs, double& alpha, double& beta,
                                 bool& proportional);

/// C: n x n, symmetric positive semi-definite. On success `dampers` holds its
/// dampers (Damper::from_structure), between dofs row by row (i < j), then to ground.
std::string check_damping_matrix(const MarketMatrix& C, const std::vector<std::string>& dofs,
                                 std::vector<Damper>& dampers);

}  // namespace hsnc
