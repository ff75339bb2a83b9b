// hsnc -- mp_complex_eigen: the eigenpairs of a real, non-symmetric matrix at
// high precision, and the inverse of its eigenvector matrix: the state-space
// modes of non-proportional damping, in double-double for the derivation
// (dd_complex_eigen) or in CLN numbers of any precision (mp_complex_eigen,
// the tests' 40 digits); one code, templated on the arithmetic. The generic
// path's StateSpaceSolver does the same in double.
//
//   1. A = V diag(lambda) V^-1 in double (Eigen::EigenSolver).
//   2. Each pair (lambda, v), v scaled so that its largest component p is 1,
//      refined by Newton's method on F(v, lambda) = ((A - lambda I) v, v_p - 1)
//      with the Jacobian [A - lambda I, -v; e_p^T, 0], solved by complex
//      Gaussian elimination with partial pivoting at the working precision
//      (first simplified steps, the double Jacobian factorised once; exact
//      steps only should those stall).
//      One of each conjugate pair is refined; the other is its exact
//      conjugate. A real eigenvalue keeps a real vector.
//   3. W = V^-1 by the same elimination.
// Refused (RunError): a matrix whose double eigenvectors are nearly
// dependent (condition above kMaxEigenCondition: critical damping, where the
// generic path uses the matrix exponential), or a refinement that does not
// converge.
#pragma once

#include <cln/complex.h>
#include <cln/lfloat.h>
#include <cln/real.h>

#include <vector>

#include "double_double.h"
#include "state_space_solver.h"

namespace hsnc {

/// Largest ||V||_1 ||V^-1||_1 of the double eigenvectors accepted: the one
/// bound at which the state-space solver, too, hands a configuration over to
/// the matrix exponential (StateSpaceSolver::kMaxCondition), both measured on
/// the balanced state matrix.
inline constexpr double kMaxEigenCondition = StateSpaceSolver::kMaxCondition;

struct MpComplexEigen {
    std::vector<cln::cl_N> values;               ///< lambda_k
    std::vector<std::vector<cln::cl_N>> vectors;  ///< vectors[k][i] = V_ik: A V_k = lambda_k V_k
    std::vector<std::vector<cln::cl_N>> inverse;  ///< inverse[k][i] = (V^-1)_ki
};

/// The eigen-decomposition of the real n x n matrix `a` (long floats of
/// `format` or exact rationals) at the precision of `format`, the
/// eigenvalues in the order of the double solve with each conjugate pair
/// adjacent (Im > 0 first).
MpComplexEigen mp_complex_eigen(const std::vector<std::vector<cln::cl_R>>& a, cln::float_format_t format);

/// Solves m x = b in place (b becomes x) by Gaussian elimination with
/// partial pivoting (pivots chosen by their magnitude in double), in the
/// arithmetic of the entries; false when a pivot is exactly zero.
bool mp_solve(std::vector<std::vector<cln::cl_N>> m, std::vector<cln::cl_N>& b);

/// The same decomposition in double-double (the derivation's working
/// precision): the refinement stops at 1024 units of 2^-104 of max |a_ij|.
struct DdComplexEigen {
    std::vector<DDComplex> values;
    std::vector<std::vector<DDComplex>> vectors;  ///< vectors[k][i] = V_ik
    std::vector<std::vector<DDComplex>> inverse;  ///< inverse[k][i] = (V^-1)_ki
};
DdComplexEigen dd_complex_eigen(const std::vector<std::vector<DD>>& a);
bool dd_solve(std::vector<std::vector<DDComplex>> m, std::vector<DDComplex>& b);

}  // namespace hsnc
