// hsnc -- the segment solver of a configuration whose state-space modes are
// defective or nearly so (critically damped motion under non-proportional
// damping), where StateSpaceSolver's eigenvectors lose too many digits.
//
// The free masses' motion with its forcing is one linear autonomous system on
// the augmented state
//     z = (x_F, v_F, 1, sin(Omega_1 tau + theta_1), cos(...), ...),
//     z' = Z z,  Z = [0, I, 0, 0; -M^-1 K, -M^-1 C, M^-1 f, M^-1 F_h (on the
//                    sines); 0 ...; the rotations d(s, c)/dtau = Omega (c, -s)],
// so z(tau) = exp(Z tau) z(0) exactly, in every regime: a Jordan block (the
// critically damped e^{lambda tau}(1, tau)) is no special case of the
// exponential. It is taken by Eigen's scaling and squaring with Pade
// approximants (Higham 2005; to rounding, no integration), once per eval: an
// O(m^3) closed form for the configurations the modal forms cannot take.
//
// Where K_FF is regular the exponential is taken in the energy scaling zb = D z,
// D = diag(U_K, U_M, 1, I) with K_FF = U_K^T U_K and M_F = U_M^T U_M (Cholesky),
// Zb = D Z D^-1: its stiffness and mass blocks become U_K U_M^-1 and its
// negative transpose, so ||Zb|| is of the highest natural frequency rather
// than of M^-1 K (omega_max^2 with a finite element's rotations). On a 16-dof
// cantilever (tests/test_dampers.cpp) the steps grew from 6e-11 s to 1.5e-5 s
// and the motion's error from 1e-5 of it to 5e-10, the modal solver's.
//
// Bounds on |g''| (segment_solver.h): every switch function is affine in z,
// g = L z + g0 = L D^-1 zb, so g'' = L D^-1 Zb^2 zb; over [tau, tau + h] with
// h = 1/||Zb|| (max_step), ||exp(Zb u)|| <= e^{||Zb|| u} <= e, hence
//     |g''(s)| <= ||L D^-1 Zb^2||_1 e ||zb(tau)||_inf  (norms: the row's absolute sum, the largest |zb_k|),
// with 1% added for the rounding of L D^-1 Zb^2. Steps are shorter than the
// modal solvers' (at most 1/||Zb||), the price of taking every regime.
//
// Where K_FF is regular, x_F is written about its static offset x_s =
// K_FF^-1 f (the constant force then drives nothing: Z's column of 1 is 0),
// so that near the equilibrium x - x_s, v and a keep their relative rounding
// as they decay (as StateSpaceSolver, state_space_solver.h).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "configuration.h"
#include "model.h"
#include "segment_solver.h"
#include "switch_values.h"

namespace hsnc {

class ExponentialSolver final : public SegmentSolver {
public:
    ExponentialSolver(const Model& model, const Configuration& cfg);

    const Configuration& configuration() const override { return cfg_; }
    const std::vector<SwitchFunction>& switches() const override { return switches_; }
    using SegmentSolver::setup;
    void setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) override;
    void eval(double tau, const SegmentEval& out) const override;
    double max_step() const override { return max_step_; }

    /// Estimated heap memory of this solver, bytes.
    std::size_t memory_bytes() const;

private:
    Configuration cfg_;
    std::vector<SwitchFunction> switches_;
    int n_ = 0, nf_ = 0, nh_ = 0, ns_ = 0, m_ = 0;
    std::vector<int> free_, stuck_;
    ConfigurationTerms t_;
    double max_step_ = 0.0;

    // --- fixed by setup ---
    Eigen::MatrixXd minv_;        // M_F^-1 of a coupled M (empty when lumped)
    Eigen::MatrixXd Z_;           // the generator (its constant column holds this segment's force)
    Eigen::VectorXd z0_, absz0_;  // z(0) and |z(0)|
    Eigen::VectorXd xs_;          // the free masses' static offset (K_FF regular), else 0: x_F = xs + z_x
    bool free_offset_ = false;    // xs_ taken (Z's column of 1 is then 0)
    Eigen::VectorXd bound_row_;   // ||L_f Z^2||_1 per switch function
    Eigen::VectorXd x_fix_, fseg_, slider_, theta_;
    Eigen::VectorXd frel_;  // coupled M: fseg_ plus the kinetic friction, for the held forces (release_force)

    // The energy scaling zb = D z, D = diag(U_K, U_M, 1, I) (K_FF = U_K^T U_K, M_F = U_M^T U_M;
    // empty where K_FF is singular): the file comment.
    Eigen::MatrixXd D_, Dinv_, absDinv_;
    Eigen::MatrixXd Zb_;   // D Z D^-1 (Z itself without D)
    Eigen::VectorXd zb0_;  // D z(0)
    void balance(const Model& model);

    // --- eval scratch (no state between evals) ---
    mutable Eigen::MatrixXd E_;
    mutable Eigen::VectorXd z_, zb_, zbmag_, zmag_, xmag_, vmag_, sn_, cs_;
};

}  // namespace hsnc
