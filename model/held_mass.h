// hsnc -- a coupled mass matrix with some dofs held still: the stuck
// friction dofs of a configuration (interface.md "Coupled mass matrices").
//
// With the dofs S held (a_S = 0) the others move by M_FF a_F = f_F, f every
// force on them (kinetic friction included); the force a held dof's friction
// must supply to keep it still is, from its own row of M a = f + r,
//     D_i = f_i - M_iF a_F = (P f)_i,   P_i = e_i - M_iF M_FF^-1 E_F^T,
// so D_i is a fixed combination of the forces of the configuration. On a
// lumped M, P_i = e_i and D_i = A_i (assembly.h driving_force); it sticks
// while |D_i| <= mu_s N_i. Every back end that takes a coupled M with friction
// (the Eigen solvers, the engine's decisions and tie series, rk45 and CVODE)
// reads D_i from here.
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
    /// M_FF factored for the dofs with held[i] == 0.
    HeldMass(const Model& model, const std::vector<char>& held) { hold(model, held); }
    /// Factors M_FF again when `held` differs from the last set (nothing to do otherwise).
    void hold(const Model& model, const std::vector<char>& held);
    const std::vector<char>& held() const { return held_; }

    /// a = M_FF^-1 f on the free dofs, 0 on the held ones (f and a over every dof).
    void accelerations(const double* f, double* a) const;
    /// D_i = f_i - (M a)_i for a held dof i, a = accelerations(f).
    double held_force(int i, const double* f, const double* a) const;
    /// P_i over every dof (i held): D_i = P_i . f.
    Eigen::VectorXd release_row(int i) const;
    /// M_FF^-1 spread over every dof (zero rows and columns on the held ones).
    Eigen::MatrixXd inverse() const;

private:
    const Model* model_ = nullptr;
    std::vector<char> held_;
    std::vector<int> free_;
    Eigen::LLT<Eigen::MatrixXd> llt_;
    mutable Eigen::VectorXd rhs_;
};

/// The kinetic friction -mu_k N_k sgn_k on every dof that slides (not held,
/// with friction), 0 on the others.
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
