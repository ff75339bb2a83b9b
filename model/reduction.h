// hsnc -- reduction of a large structure to the dofs its elements act on
// ([reduction], interface.md "Reduction of a large structure").
//
// Craig-Bampton: the boundary dofs B (every dof the model's elements, loads,
// forcing and initial values name, and those listed in [reduction].boundary)
// stay physical; the interior I is spanned by the static constraint modes
// Psi = -K_II^-1 K_IB and the lowest fixed-interface modes Phi
// (K_II Phi = M_II Phi Lambda, Phi^T M_II Phi = I):
//     x = T [x_B; q],   T = [ I  0 ; Psi  Phi ],
//     M_r = T^T M T,  K_r = T^T K T = [ K_BB + K_BI Psi  0 ; 0  Lambda ],  C_r = T^T C T.
// The reduced model is exact for the static response to forces on B and
// for every motion of B alone with the interior quasi-static; its linear
// frequencies bound the full model's from above (Rayleigh-Ritz) and reach
// them as modes grow. Contacts, frictions and Jenkins elements act on B, so
// every configuration of the reduced model is the Ritz projection of the
// full model's configuration on the same basis.
//
// Rubin (MacNeal-Rubin, free interface with residual flexibility, the
// boundary dofs kept physical): the lowest free-interface modes Phi of the
// whole structure (K Phi = M Phi Lambda) and the residual flexibility of the
// boundary, G = K^-1 E_B - Phi Lambda^-1 Phi_B^T (what the dropped modes
// give statically to a force on B), with Psi = G G_BB^-1 (Psi_B = I):
//     x = T [x_B; q],   T = [ Psi  Phi - Psi Phi_B ]   (T's rows on B: [I 0]).
// It is exact for the static response to forces on B (span T = span [Phi,
// G]); its frequencies bound the full model's from above. It needs K
// nonsingular (a supported structure) and G_BB nonsingular (fewer modes
// than n - |B|).
//
// The sparse factorisation of K_II or K (and of K for the full model's
// frequencies) is Eigen's simplicial LDL^T with AMD ordering; the
// fixed-interface and free-interface modes come from Spectra's
// shift-and-invert Lanczos (a dense generalized eigensolver when the
// problem is small).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/SparseCore>

namespace hsnc {

using SparseMatrixD = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

enum class ReductionMethod { craig_bampton, rubin };

struct ReductionSettings {
    ReductionMethod method = ReductionMethod::craig_bampton;
    std::size_t modes = 0;  ///< modes kept (fixed-interface, or free-interface for Rubin; 0 when `cutoff` decides)
    double cutoff = 0.0;    ///< keep every such mode with omega <= cutoff (rad/s), when > 0
};

/// The reduced structure: boundary dofs (full-model order), then the modal
/// coordinates; dense matrices in that order.
struct ReducedStructure {
    std::vector<std::size_t> boundary;  ///< full-model index of each boundary dof
    Eigen::MatrixXd M, K, C;            ///< C empty when the full model has none
    Eigen::VectorXd interface_omega;    ///< the kept (fixed- or free-)interface modes' circular frequencies, rad/s
    std::size_t full_dofs = 0;
    /// T^T F of the full-model forces F given to the reduction (one column
    /// each: a base motion's M r), in the reduced dofs' order; 0 columns when none.
    Eigen::MatrixXd forces;
};

/// Craig-Bampton reduction of (M, K, C) to `boundary` (sorted, distinct
/// full-model indices) plus the fixed-interface modes `settings` asks for.
/// Returns "" and fills `out`, or the reason it cannot (K_II singular: the
/// interior moves rigidly once B is held; more modes than interior dofs;
/// an eigensolver that does not converge). `C` may be null; `forces`
/// (full dofs x k, may be null) are projected into out.forces.
std::string craig_bampton(const SparseMatrixD& M, const SparseMatrixD& K, const SparseMatrixD* C,
                          const std::vector<std::size_t>& boundary, const ReductionSettings& settings,
                          ReducedStructure& out, const Eigen::MatrixXd* forces = nullptr);

/// Rubin's free-interface reduction of (M, K, C) (above), with the same
/// arguments and results as craig_bampton; refused when K is singular (the
/// structure moves rigidly: use craig_bampton) or the boundary's residual
/// flexibility is (too many modes for the dofs left).
std::string rubin(const SparseMatrixD& M, const SparseMatrixD& K, const SparseMatrixD* C,
                  const std::vector<std::size_t>& boundary, const ReductionSettings& settings, ReducedStructure& out,
                  const Eigen::MatrixXd* forces = nullptr);

/// craig_bampton or rubin as settings.method says, remembered for the process: the same matrices (every
/// entry's bits), boundary and settings give the stored reduction without a
/// second factorisation (a sweep reads its model again for every point; a
/// 27,000-dof plate took 5 s to reduce). Keyed by a 128-bit hash of those
/// inputs; the last kReductionMemo results are kept. Thread-safe.
std::string reduce_memo(const SparseMatrixD& M, const SparseMatrixD& K, const SparseMatrixD* C,
                        const std::vector<std::size_t>& boundary, const ReductionSettings& settings,
                        ReducedStructure& out, const Eigen::MatrixXd* forces = nullptr);
inline constexpr std::size_t kReductionMemo = 4;

/// How often reduce_memo computed a reduction and how often it reused one.
struct ReductionMemoCounts {
    std::size_t computed = 0, reused = 0;
};
ReductionMemoCounts reduction_memo_counts();
/// Forget the remembered reductions (their memory is freed; the counts stay).
void reduction_memo_clear();

/// The steady response X of (K - w^2 M + i w C) X = F (M, K, C symmetric,
/// F real) by a sparse complex LU (Eigen's supernodal SparseLU, COLAMD).
/// Returns "" or why it has none: singular (a rigid-body motion at w = 0,
/// or w on an undamped mode), or a structure above kMaxResponseDofs (its
/// factor's fill: 15 s and 0.7 GB at 27,000 dofs of a hex8 plate).
std::string harmonic_response(const SparseMatrixD& M, const SparseMatrixD& K, const SparseMatrixD& C, double w,
                              const Eigen::VectorXd& F, Eigen::VectorXcd& X);
inline constexpr std::size_t kMaxResponseDofs = 30000;

/// The `count` lowest circular frequencies (rad/s) of K x = omega^2 M x, ascending;
/// "" or the reason they cannot be computed (K singular with M, a solver
/// that does not converge). Dense below a few hundred dofs, else shift-and-invert Lanczos.
std::string lowest_frequencies(const SparseMatrixD& M, const SparseMatrixD& K, std::size_t count,
                               Eigen::VectorXd& omega);

}  // namespace hsnc
