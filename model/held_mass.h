// hsnc -- the structure with its stuck frictions holding: some dofs held
// still (friction against the ground), others riding the body their friction
// acts against (interface.md "Coupled mass matrices", "Friction between two
// bodies").
//
// A stuck friction against the ground holds its dof (a = 0); one against a
// partner p moves its dof with p (a_i = a_p, a rider; p may carry several).
// With x = T q + d (T's row of a held dof zero, of a rider its partner's) the
// free coordinates move by (T^T M T) a_q = T^T f, f every force on every dof
// (kinetic friction included, its reaction on the partner too), and the force
// a stuck friction must hold to keep its relative velocity at 0 is, from the
// rows of M a = f + r over the dofs it carries (S_i: its own, and a rider's
// riders),
//     D_i = sum_{k in S_i} (f_k - (M a)_k) = (P_i f),   P_i = s - T (T^T M T)^-1 T^T M s,
// s the indicator of S_i: a fixed combination of the forces of the
// configuration. On a lumped M with each partner carrying one rider the
// back ends write D_i in closed form instead (assembly.h driving_force:
// A_i, or against_partner); where a held force depends on the other
// frictions' states (Model::coupled_friction(): a coupled M, a body
// carrying several riders, or a chain) every back end reads D_i from here: the Eigen
// solvers, the engine's decisions and tie series, rk45 and CVODE, the
// reference (its own arithmetic), it sticks while |D_i| <= mu_s N_i.
#pragma once

#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "configuration.h"
#include "model.h"

namespace hsnc {

class HeldMass {
public:
    HeldMass() = default;
    /// T^T M T factored for the stuck frictions `held` (per dof: its friction
    /// stuck; against the ground the dof is held, against a partner it rides it).
    HeldMass(const Model& model, const std::vector<char>& held) { hold(model, held); }
    /// Factors T^T M T again when `held` differs from the last set (nothing to do otherwise).
    void hold(const Model& model, const std::vector<char>& held);
    const std::vector<char>& held() const { return held_; }

    /// a = T (T^T M T)^-1 T^T f: the free dofs', a rider's its partner's, 0 on
    /// the held ones (f and a over every dof).
    void accelerations(const double* f, double* a) const;
    /// D_i = sum over S_i of f_k - (M a)_k for a stuck friction i, a = accelerations(f).
    double held_force(int i, const double* f, const double* a) const;
    /// P_i over every dof (i stuck): D_i = P_i . f.
    Eigen::VectorXd release_row(int i) const;
    /// T (T^T M T)^-1 T^T over every dof (zero rows and columns on the held ones).
    Eigen::MatrixXd inverse() const;

private:
    const Model* model_ = nullptr;
    std::vector<char> held_;
    std::vector<int> free_;
    std::vector<int> column_;  ///< per dof: its free coordinate (a rider its partner's), -1 when held
    Eigen::LLT<Eigen::MatrixXd> llt_;
    mutable Eigen::VectorXd rhs_;
};

/// The kinetic friction -mu_k N_k sgn_k on every dof that slides (not held,
/// with friction), and its reaction +mu_k N_k sgn_k on the partner of one
/// that slides against a body; 0 on the others.
void kinetic_friction(const Model& model, const std::vector<char>& held, const signed char* sgn, double* fr);

/// The forces f of HeldMass on every dof: A_k (assembly.h force_on_mass) and
/// the kinetic friction -mu_k N_k sgn_k of a sliding dof (none on a held one).
void held_forces(const Model& model, const Configuration& cfg, const std::vector<char>& held, const signed char* sgn,
                 double t, const double* x, const double* v, double* f);

/// D_i and dD_i/dt (the held motion's accelerations and jerks) at (t, x, v)
/// with dof i and every dof stuck in cfg held, the others sliding along sgn:
/// the force a coupled M's friction must hold (interface.md "Coupled mass matrices").
void held_driving_force(const Model& model, const Configuration& cfg, const signed char* sgn, int i, double t,
                        const double* x, const double* v, double& D, double& rate);

/// The direction w of contact c over every dof (w), M^-1 w (Mw) by M's own
/// factors (a coupled M: Cholesky with nothing held), and w^T M^-1 w returned:
/// what Newton's law at a rigid stop needs (elements/contact.h impact).
double impact_direction(const Model& model, int c, std::vector<double>& w, std::vector<double>& Mw);

}  // namespace hsnc
