// hsnc -- modal analysis of one configuration (paper, "Modal analysis", Eq. 11):
// the undamped eigenproblem K_F phi = lambda M_F phi of the free masses.
//
// Free masses F are the masses not stuck in the configuration; stuck masses are
// fixed supports, so K_F = K(cfg)[F,F] (their coupling K(cfg)[F,S] x_S is a
// constant force, paper Eq. 7-8). Because damping is Rayleigh,
// C_F = alpha*M_F + beta*K_F is diagonalised by the same modes, with modal
// damping c_j = alpha + beta*lambda_j.
//
// Rigid-body modes are decided structurally, never from a small eigenvalue:
// the free masses split into connected components (edges: springs and closed
// contacts with k > 0 between two free masses); a component with no k > 0 link
// to the ground or to a stuck mass is a free-floating body and has exactly one
// rigid-body mode, lambda = 0 exactly, phi = 1/sqrt(total mass) on the
// component. Its other modes are computed in the M-orthogonal complement of
// that vector, so they are M-orthogonal to it to rounding. Components are
// decoupled (K_F is block diagonal over them) and are decomposed one by one.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "configuration.h"
#include "model.h"

namespace hsnc {

struct ModalDecomposition {
    std::vector<int> free;       ///< F: indices of the free masses, in model order
    std::vector<int> stuck;      ///< S: indices of the masses stuck to the ground, in model order
    /// Masses stuck to their friction partner (elements/friction.h FrictionSlot::partner), which
    /// move with it: the partner's coordinate stands for both, with their
    /// summed mass and stiffness rows (x_rider = x_partner + a constant).
    std::vector<int> riders;
    Eigen::VectorXd mass;        ///< the diagonal of M_F: the mass of each free coordinate (with its riders)
    /// M_F whole when the model's M is coupled (Model::coupled_mass()); empty when lumped.
    Eigen::MatrixXd mass_matrix;
    std::vector<int> component;  ///< component id of each free mass (parallel to `free`)
    int n_components = 0;

    /// Mass-normalised modes, |F| x |F|, rows in the order of `free`:
    /// Phi^T M_F Phi = I, Phi^T K_F Phi = diag(lambda).
    Eigen::MatrixXd phi;
    Eigen::VectorXd lambda;    ///< eigenvalues, >= 0, ascending
    std::vector<char> rigid;   ///< 1 for the structural rigid-body modes (lambda == 0 exactly)
    std::vector<int> mode_component;  ///< component of each mode (coupled M: -1 for an elastic mode)

    /// Phi^T M_F, the projection of a physical state onto the modes (q = Phi^T M_F x_F).
    Eigen::MatrixXd phi_t_m() const {
        if (mass_matrix.size() > 0) return phi.transpose() * mass_matrix;
        return phi.transpose() * mass.asDiagonal();
    }
};

/// Modal decomposition of the free masses of `cfg` (see the file comment).
/// A coupled M (Model::coupled_mass()) is decomposed whole, K_F phi = lambda
/// M_F phi (Cholesky of M_F): the rigid-body modes are still the structural
/// ones (all ones on a floating component, M-orthonormalised), the elastic
/// modes those of the M-orthogonal complement; the components no longer
/// decouple, since M couples them.
ModalDecomposition modal_analysis(const Model& model, const Configuration& cfg);

}  // namespace hsnc
