// hsnc -- the segment solver of non-proportional damping: state-space modes.
//
// With dampers (model.h Damper) C is not alpha*M + beta*K, the modes of K do
// not decouple the damped equations, and GenericSolver does not apply. The
// free masses' equations are written first order in y = [x_F; v_F/s]
// (s a frequency scale, so both halves have the same size):
//     y' = A y + b0 + sum_h b_h sin(Omega_h tau + theta_h),
//     A = [0, s I; -M^-1 K / s, -M^-1 C],  b0 = [0; M^-1 f / s],  b_h = [0; M^-1 F_h / s],
// and decoupled by A's eigenvectors, A = V diag(lambda) V^-1 (complex
// conjugate pairs for the underdamped motions, real lambda for the overdamped
// ones), eta = V^-1 y. Each modal coordinate then has the exact solution
//     eta_k(tau) = e^{lambda tau} eta_k(0) + beta0_k E(lambda, 0, tau)
//                + sum_h beta_hk/(2i) [e^{i theta} E(lambda, i Omega, tau) - e^{-i theta} E(lambda, -i Omega, tau)],
//     E(lambda, mu, tau) = int_0^tau e^{lambda (tau - s)} e^{mu s} ds,
// written without cancellation for every lambda and mu (e^{lambda tau} tau
// phi_1((mu - lambda) tau) while |mu - lambda| tau < 1, the divided difference
// (e^{mu tau} - e^{lambda tau})/(mu - lambda) beyond), so resonance (mu = lambda)
// and a constant force on a free translation (lambda = mu = 0) are exact too.
// y = V eta is real (conjugate pairs).
//
// Where A is regular (no rigid body that a damper alone holds: K_e regular),
// the constant force is taken by the static offset y_s = [K_e^-1 T^T f; 0]
// (its velocity half exactly 0) and the modes carry y - y_s alone (beta0 = 0):
// y = y_s + Re(V eta), and a = s (Re(V lambda eta) + b_h sin)'s velocity half,
// as the programs compute x = x_st + modes, a = the modes' second derivative.
// Summed about 0 instead (y = Re(V eta) with each eta_k tending to
// -beta0_k/lambda_k), the velocity and a = M^-1 (f - K x - C v) kept the
// absolute rounding of the offset (~eps |x_s| s) as the motion decayed, and an
// overdamped creep into equilibrium fell through v = 0 at an instant set by
// rounding (tests/test_dampers.cpp DamperCreep).
//
// Bounds on |g''| (segment_solver.h) for s in [tau, tau + max_step]: g is
// affine in y (and the forcing), g'' = Re sum_k G_k eta_k'' + forcing terms,
// and with Re lambda <= 0 every e^{lambda s} decays, so
//     |(e^{lambda s})''| <= |lambda|^2 |e^{lambda tau}|,
//     |E''(s)| <= min((|mu|^2 |e^{mu tau}| + |lambda|^2 |e^{lambda tau}|)/|mu - lambda|,
//                     |lambda|^2 (tau + max_step) + |lambda + mu|)
// (E'' = lambda^2 E + (lambda + mu) e^{mu s} and |E(s)| <= s); max_step is one
// forcing period where some |mu - lambda| < 0.1 |mu| (near resonance, where the
// first form is loose or infinite), else infinite. Negative damping (only hsnc
// modes' EPMC system, -xi M, builds such a model: a file cannot) makes modes
// with Re lambda > 0 grow: max_step is then at most 0.5 / max Re lambda, and a
// growing mode's |e^{lambda s}| is taken at the step's end, e^{Re lambda
// max_step} |e^{lambda tau}| (at most e^{0.5} times its value at tau), and
// |E(s)| <= s e^{Re lambda s} in the second form.
//
// A free translation that no damping resists (a floating component's r with
// C r = 0) would make A defective (a double zero eigenvalue): it is taken out
// first, x_F = R q + T e, q_j the component's mass-weighted mean position
// with q_j'' = r_j^T f(t) / m_j in closed form (R^T K = R^T C = 0), and the
// state above is written for e (mass T^T M T, stiffness T^T K T, ...).
//
// A is decomposed in the energy scaling z = B y, B = diag(L^T/s, R^T) (K_e = L
// L^T, M_e = R R^T, when K_e is regular), where undamped modes are orthogonal:
// V = B^-1 W from B A B^-1's eigenvectors W, and the condition below is W's.
// (In y itself a mode's velocity half is omega_k/s of its position half, and
// V's condition grows as omega_max/omega_1: 3e3 on a 16-dof cantilever.)
//
// Refused (RunError naming the configuration): a V whose condition number
// exceeds kMaxCondition (A nearly defective: critically damped motion; then
// DefectiveModes, and the providers take the configuration with the matrix
// exponential, exponential_solver.h), or, unless the model's Rayleigh damping is
// negative, an eigenvalue with a positive real part beyond rounding.
#pragma once

#include <complex>
#include <functional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include "configuration.h"
#include "error.h"
#include "model.h"
#include "segment_solver.h"
#include "switch_values.h"
#include "term_lifetimes.h"

namespace hsnc {

/// A configuration whose state-space modes are (nearly) defective: the
/// providers take it with ExponentialSolver (exponential_solver.h) instead.
class DefectiveModes : public RunError {
public:
    using RunError::RunError;
};

class StateSpaceSolver final : public SegmentSolver {
public:
    /// Largest accepted condition number ||W||_1 ||W^-1||_1 of the energy-scaled
    /// eigenvector matrix (the file comment; for one dof B = sqrt(m) I, so W's
    /// condition is V's). Near critical damping the modal form loses accuracy much faster
    /// than log10 of it (a 1-DOF oscillator against the matrix exponential,
    /// tests/test_dampers.cpp: condition 141 -> 1e-16, 447 -> 8.5e-14, 4.5e4
    /// -> 1.7e-9 of a 0.03 m motion, underdamped side); beyond this bound the
    /// configuration goes to ExponentialSolver.
    static constexpr double kMaxCondition = 200;

    /// Analyse `cfg` (throws RunError as above).
    StateSpaceSolver(const Model& model, const Configuration& cfg);

    const Configuration& configuration() const override { return cfg_; }
    const std::vector<SwitchFunction>& switches() const override { return switches_; }
    using SegmentSolver::setup;
    void setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) override;
    void eval(double tau, const SegmentEval& out) const override;
    double max_step() const override { return max_step_; }
    double resolving_rate(double tau, double tol) const override;

    /// Estimated heap memory of this solver, bytes.
    std::size_t memory_bytes() const;
    /// Eigenvalues of A (s^-1), in the solver's order.
    const Eigen::VectorXcd& eigenvalues() const { return lambda_; }
    /// The damped modes for a reader: one eigenvalue of each conjugate pair (Im > 0)
    /// and every real one, by |lambda| ascending.
    std::vector<std::complex<double>> damped_modes() const;
    /// ||W||_1 ||W^-1||_1 of this configuration (W the energy-scaled eigenvectors).
    double condition() const { return condition_; }
    /// Free translations taken out of the state (no damping resists them).
    std::size_t rigid_translations() const { return rigid_.size(); }

private:
    using cplx = std::complex<double>;

    Configuration cfg_;
    std::vector<SwitchFunction> switches_;
    int n_ = 0, nf_ = 0, nh_ = 0, ns_ = 0;
    std::vector<int> free_, stuck_;
    double scale_s_ = 1.0;  // s of y = [x; v/s]
    double max_step_ = 0.0;
    double condition_ = 0.0;
    double growth_ = 0.0;  // the largest Re lambda > 0 (negative damping), else 0

    /// lambda_, V_, Vinv_, condition_ and growth_ of the state matrix A (of e's mass Me and
    /// stiffness Ke); throws as the file comment says (`where` begins the message), a growing
    /// mode only unless `may_grow`.
    void decompose(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Me, const Eigen::MatrixXd& Ke, bool may_grow,
                   const std::string& where);

    ConfigurationTerms t_;  // masses, friction, K(cfg), C(cfg), constant force, contacts, harmonics

    // Undamped free translations, taken out of the state (x_F = R q + T e).
    struct Rigid {
        std::vector<int> members;  // slots in free_, the first is the pivot
        double mass = 0.0;         // the component's total mass
    };
    std::vector<Rigid> rigid_;
    Eigen::MatrixXd rigid_w_;       // nf x nr: M_F r_j (a coupled M; empty when lumped)
    Eigen::MatrixXd e_lt_;          // L^T of T^T M_F T = L L^T (a coupled M: e in mass-normalised form; else empty)
    /// The undamped free translations (rigid_), T_, absT_, e_slot_ and ne_; returns M_F.
    Eigen::MatrixXd rigid_basis(const Model& model, const Configuration& cfg);
    /// T_, e_slot_, rigid_w_ and the rigid masses r^T M_F r for a coupled M_F.
    void coupled_rigid_basis(const Eigen::MatrixXd& MF, const std::vector<char>& pivot,
                             const std::function<void(const std::string&)>& refuse);
    int ne_ = 0;                    // dimension of e: nf - number of rigid translations
    std::vector<int> e_slot_;       // e_c is the free slot e_slot_[c] (minus its component's mean)
    Eigen::MatrixXd T_, absT_;      // nf x ne, and |T|
    Eigen::PartialPivLU<Eigen::MatrixXd> Me_lu_;  // of T^T M_F T
    Eigen::MatrixXd rigid_h_;       // nr x nh: r_j^T F_h / m_j
    Eigen::MatrixXd rigid_lx_, rigid_lv_;  // ns x nr: switch rows summed over each component

    Eigen::VectorXcd lambda_;       // 2ne eigenvalues
    Eigen::MatrixXcd V_, Vinv_;     // 2nf x 2nf
    Eigen::MatrixXcd beta_h_;       // 2nf x nh: V^-1 b_h
    Eigen::MatrixXd bh_tail_;       // ne x nh: the velocity half of b_h (Me^-1 T^T F_h / s)
    bool offset_ = false;           // A regular: the constant force by the static offset y_s
    Eigen::PartialPivLU<Eigen::MatrixXd> Ke_lu_;  // of T^T K_F T (when offset_)
    std::vector<int> rep_;          // the modes eval computes: one of each conjugate pair, every real one
    Eigen::MatrixXd absV_, Vre_, Vim_;  // |V|, Re V, Im V over rep_, a pair's column doubled
    Eigen::MatrixXd absG_;          // ns x rep: |L_f V_k| (doubled for a pair), L_f the switch function's row over y
    Eigen::VectorXd bound_sin_;     // sum_h |d_fh| Omega_h^2 (the forcing in release functions)
    Eigen::Matrix<char, Eigen::Dynamic, Eigen::Dynamic> near_;  // 2nf x (2 nh): |mu - lambda| < 0.1 |mu|
    // Per mode k and forcing term u (mu = 0, then +-i Omega_h): 1/(mu - lambda_k), |mu - lambda_k|,
    // |mu + lambda_k|; |lambda_k|, |beta_hk|/2.
    Eigen::MatrixXcd inv_d_;
    Eigen::MatrixXd mod_d_, mod_sum_, mod_beta_h_;
    Eigen::VectorXd mod_lambda_;

    // --- fixed by setup ---
    Eigen::VectorXd x_fix_, theta_, force_;  // force_: constant force on the free masses
    Eigen::VectorXd fseg_, slider_;          // f_const plus the stuck Jenkins sliders' preload; their positions
    Eigen::VectorXd frel_;  // coupled M: fseg_ plus the kinetic friction, for the held forces (release_force)
    Eigen::VectorXd q0_, qd0_, rigid_f_;       // rigid coordinates and their constant acceleration
    Eigen::VectorXd rigid_bound_;              // rigid part of each |g''| bound
    Eigen::VectorXcd eta0_, beta0_, e_theta_;
    Eigen::VectorXd ys_, fe_;  // the static offset's e (offset_; else 0), the velocity half of b0 (else 0)
    Eigen::VectorXd mod_eta0_, mod_beta0_;  // |eta0|, |beta0|

    // --- eval scratch ---
    // --- eval scratch (no allocation in eval; one thread at a time) ---
    mutable Eigen::VectorXcd eta_, e_omega_, deta_;
    mutable Eigen::VectorXd dy_, af_;
    mutable Eigen::VectorXd eta_mag_, b2_, y_, ymag_, xmag_, vmag_, sn_, cs_, xf_, vf_, xfm_, vfm_, B_;

    // resolving_rate: until when each decaying mode of the segment counts, and at what rate.
    void term_lifetimes(double tol) const;
    mutable TermLifetimes lifetimes_;
};

}  // namespace hsnc
