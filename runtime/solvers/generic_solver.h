// hsnc -- the generic closed-form segment solver: the reference "generic path"
// that the generated and JIT kernels are tested against to rounding.
//
// Constructed from (Model, Configuration): modal analysis of the free masses
// (modal.h), then every (mode, harmonic) pair is prepared once. `setup` turns
// the state at the segment start into modal initial conditions, and `eval`
// gives the exact state, switch functions, their rates, a bound on their second
// derivatives and the size of their terms at any tau = t - t0 >= 0.
//
// Per mode j (paper Eq. 11-14), q'' + c q' + lambda q = p + sum_h P_h sin(Omega_h tau + theta_h),
// with c = alpha + beta*lambda (Rayleigh damping is modal):
//   q = p/lambda (static, Eq. 10) + sum_h particular_h + u (homogeneous),
// the homogeneous part written for every damping ratio without cancellation or
// overflow (under-, critically and over-damped), rigid-body modes (lambda = 0)
// in closed form with phi-functions, and near-resonant lightly damped pairs in a
// "transient-coupled" form (the zero-state response of the harmonic, exact and
// stable through resonance, secular at exact undamped resonance).
//
// Negative modal damping (c < 0, e.g. the -xi M term of hsnc modes' extended
// periodic motion) is taken up to critical (|c| < 2 omega): the bounds then
// hold over a finite step only (max_step()), over which the energy grows by a
// known factor.
//
// No allocation in setup() or eval(): all storage is sized in the constructor.
// eval() writes to mutable scratch, so one solver must not be evaluated from two
// threads at once.
#pragma once

#include <complex>
#include <vector>

#include <Eigen/Core>

#include "configuration.h"
#include "modal.h"
#include "model.h"
#include "segment_solver.h"
#include "switch_values.h"
#include "term_lifetimes.h"

namespace hsnc {

class GenericSolver final : public SegmentSolver {
public:
    /// How the motion of one mode is written.
    enum class Regime : unsigned char {
        rigid,        ///< lambda = 0: q'' + c q' = forcing
        underdamped,  ///< sigma < omega
        critical,     ///< sigma == omega
        overdamped,   ///< sigma > omega
    };

    /// Analyse `cfg` (throws RunError if the eigen solver fails).
    GenericSolver(const Model& model, const Configuration& cfg);

    const Configuration& configuration() const override { return cfg_; }
    const std::vector<SwitchFunction>& switches() const override { return switches_; }
    using SegmentSolver::setup;
    void setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) override;
    void eval(double tau, const SegmentEval& out) const override;
    double max_step() const override { return max_step_; }
    bool splits_bound() const override { return any_fast_; }
    double resolving_rate(double tau, double tol) const override;

    /// Estimated heap memory of this solver (its matrices and vectors), bytes.
    std::size_t memory_bytes() const;

    /// The modal decomposition this solver uses (for inspection and tests).
    const ModalDecomposition& modes() const { return modal_; }
    /// Modal damping c_j = alpha + beta*lambda_j and the regime of mode j.
    double modal_damping(int j) const { return c_(j); }
    Regime regime(int j) const { return regime_[static_cast<std::size_t>(j)]; }
    /// True when harmonic h of mode j uses the transient-coupled (resonance-stable) form.
    bool coupled(int j, int h) const { return coupled_(j, h) != 0; }

private:
    void switch_rows(const Model& model);  // W_, Z_, D_ from the modes (constructor)
    // --- fixed by the configuration ---
    Configuration cfg_;
    std::vector<SwitchFunction> switches_;
    ModalDecomposition modal_;
    int n_ = 0;   // all masses
    int nf_ = 0;  // free masses (= modes)
    int nh_ = 0;  // harmonics with omega != 0
    double alpha_ = 0.0;
    double max_step_ = 0.0;
    // Negative modal damping (hsnc modes' extended periodic motion): a mode's
    // energy may grow by e^{2 |c| s}, so the bounds hold over max_step_ =
    // kGrowthHorizon / |c_min| and grow by e^{kGrowthHorizon}. 1 when c >= 0.
    double growth_ = 1.0;

    ConfigurationTerms t_;  // masses, friction, K(cfg), C(cfg), constant force, contacts, harmonics
    std::vector<int> coord_;       // free coordinate of each mass (its carrier's for a rider), -1: ground, stuck
    std::vector<int> carrier_;     // the body each mass moves with (model/assembly.h carrier())
    Eigen::MatrixXd phi_;          // nf x nf, rows in the order of modal_.free
    Eigen::VectorXd phi_max_;      // max_r |phi_(r, j)|: the largest share of mode j in a dof
    Eigen::MatrixXd phi_t_m_;      // Phi^T M_F (modal initial conditions)
    std::vector<Regime> regime_;
    Eigen::VectorXd lambda_, omega_, c_, sigma_, omega_d_, gamma_, r1_, r2_;

    // Harmonics (omega made >= 0 by flipping the phase); forcing F (n x nh).
    Eigen::MatrixXd P_;            // nf x nh modal forcing amplitudes Phi^T F_h[F]
    Eigen::Matrix<char, Eigen::Dynamic, Eigen::Dynamic> coupled_;  // nf x nh
    Eigen::MatrixXd pa_, pb_;      // standard particular a cos + b sin (nf x nh)
    std::vector<char> h_has_coupled_;
    Eigen::MatrixXcd zp_, zm_;     // i*Omega - r_plus, i*Omega - r_minus (coupled pairs)

    // Switch functions as modal combinations, for the bound:
    // g_f = sum_j W_fj q_j + Z_fj q_j' + sum_h D_fh sin(...) + const.
    Eigen::MatrixXd W_, Z_, absW_, absZ_, D_;
    Eigen::VectorXd bound_sin_;    // sum_h Omega_h^2 R_fh of the standard sinusoids

    // --- fixed by setup ---
    Eigen::VectorXd x_fix_;        // positions (stuck masses keep theirs)
    Eigen::VectorXd fseg_;         // constant force: f_const plus the stuck Jenkins sliders' preload
    Eigen::VectorXd frel_;  // coupled M: fseg_ plus the kinetic friction, for the held forces (release_force)
    Eigen::VectorXd slider_;       // stuck Jenkins sliders' positions
    Eigen::VectorXd rider_offset_; // x_q - x_partner of each mass stuck to its partner (modal.h riders)
    Eigen::VectorXd theta_;        // phase of each harmonic at tau = 0
    Eigen::VectorXcd e_theta_;     // exp(i theta)
    Eigen::VectorXd force_, p_, q0_, qd0_, u0_, ud0_;
    Eigen::VectorXd rho_;          // rigid-mode part of g_f'' at tau = 0 (times exp(-alpha tau))

    // The fast modes (SegmentEval's split bound): free oscillations bounded by
    // their amplitude, not their curvature (the constructor says which).
    std::vector<char> fast_;
    bool any_fast_ = false;
    std::vector<int> by_omega_;  // the modes by increasing omega
    void split_bound(int f, double g, double dg, double rigid_decay, const SegmentEval& out) const;

    // --- eval scratch ---
    mutable Eigen::VectorXd sn_, cs_, q_, qd_, qdd_, qmag_, qdmag_, b2_, b3_, xmag_, vmag_;
    // A fast mode's free oscillation u, u', u'' and the bound of |u| and |u'| over the horizon.
    mutable Eigen::VectorXd fu_, fud_, fudd_, famp_, fdamp_, below_;
    mutable Eigen::VectorXcd e_omega_tau_;

    // resolving_rate: until when each decaying term of the segment counts, and at what rate.
    void term_lifetimes(double tol) const;
    mutable TermLifetimes lifetimes_;
};

}  // namespace hsnc
