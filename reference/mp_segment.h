// hsnc -- one configuration's closed-form solution at N digits (CLN), the
// reference engine's SegmentSolver counterpart (model/switch_function.h has the
// switch functions and their order; runtime/solvers/generic_solver.h the same maths in
// double). Clarity over speed: plain vectors of cl_F, no tricks beyond what
// the regimes need.
//
// Modal analysis (paper Eq. 11): K_F phi = lambda M_F phi of the free masses,
// solved as the symmetric problem M^-1/2 K_F M^-1/2 v = lambda v by cyclic
// Jacobi rotations (Golub & Van Loan, Matrix Computations, 8.5) to the working
// precision. Rigid-body modes are counted structurally (a connected component
// of free masses with no spring or closed contact to the ground or a stuck
// mass has one) and their eigenvalues set to 0 exactly.
//
// Per mode j, q'' + c q' + lambda q = p + sum_h P_h sin(Omega_h tau + theta_h),
// c = alpha + beta*lambda:
//   q = p/lambda + sum_h q_p,h + u, with the homogeneous u under-, critically
//   or over-damped, or undamped (sigma = 0); rigid modes (lambda = 0):
//   q = u0 + u0' tau phi1(-c tau) + p tau^2 phi2(-c tau);
//   particular q_p = a cos + b sin, a = -P c Omega/D, b = P (lambda - Omega^2)/D,
//   D = (lambda - Omega^2)^2 + (c Omega)^2; at exact undamped resonance (D = 0)
//   the secular q_p = -P tau cos(Omega tau + theta)/(2 Omega). Near resonance
//   the standard form loses about log10(lambda/sqrt(D)) digits to
//   cancellation, which the working precision absorbs.
#pragma once

#include <utility>
#include <vector>

#include <cln/complex.h>
#include <cln/float.h>

#include "configuration.h"
#include "elements/contact.h"
#include "elements/jenkins.h"
#include "elements/motion.h"
#include "elements/spring.h"
#include "model.h"
#include "segment_solver.h"

namespace hsnc {
/// A direction's weights in the reference's motion (RowsMotion<cl_F>): at the
/// precision of the motion's zero, exactly.
template <>
struct ExactWeight<cln::cl_F> {
    static cln::cl_F of(double w, const cln::cl_F& like) { return cln::cl_float(w, like); }
};
}  // namespace hsnc

namespace hsnc::reference {

using cln::cl_F;

/// The model's values converted exactly to cl_F at one precision.
struct MpModel {
    cln::float_format_t format;
    cl_F zero, one, two, half;
    cl_F eps;  ///< 2^(1-bits): the unit roundoff of the format
    cl_F pi;
    int n = 0;
    cl_F g, alpha, beta;
    std::vector<cl_F> m, normal, mu_k, mu_s;
    /// A coupled M whole (Model::coupled_mass()); empty for a lumped model (M = diag(m)).
    std::vector<std::vector<cl_F>> M;
    bool coupled() const { return !M.empty(); }
    /// A body carries several riders (Model::shared_partner).
    bool shared = false;
    /// Whether held forces are P_i . f (Model::coupled_friction): a coupled M or a shared partner.
    bool coupled_friction() const { return coupled() || shared; }
    /// M_ij, lumped or coupled.
    cl_F mass(int i, int j) const;
    /// (M y)_i, lumped or coupled.
    cl_F mass_times(int i, const std::vector<cl_F>& y) const;
    /// The structure with the frictions `held` stuck (model/held_mass.h, at
    /// this precision): T (T^T M T)^-1 T^T over every dof (zero on the held ones).
    std::vector<std::vector<cl_F>> held_inverse(const std::vector<char>& held) const;
    /// P_i of held_mass.h from that inverse: the force a stuck friction i must
    /// hold is D_i = P_i . f (f every force, kinetic friction included).
    std::vector<cl_F> held_row(const std::vector<std::vector<cl_F>>& inverse, const std::vector<char>& held,
                               int i) const;
    /// The kinetic friction -mu_k N sgn on every dof not held (and its
    /// reaction on a partner), 0 on the held ones.
    std::vector<cl_F> kinetic(const std::vector<char>& held, const std::vector<signed char>& sgn) const;
    struct Link {
        int a, b;
        cl_F k, gap;
        cl_F c;                       ///< a contact's damping while closed (0 for the others)
        std::vector<Weight> weights;  ///< a general direction (contact.h), else empty

        Direction direction() const {
            return {a, b, weights.empty() ? nullptr : weights.data(), static_cast<int>(weights.size())};
        }
    };
    std::vector<Link> springs, contacts;   ///< gap = 0 for springs
    /// Jenkins elements (model.h Jenkins): k, and the slip force in `gap`.
    /// Stuck, a link whose gap is the slider x[n + j]; slipping, the constant
    /// force -slip * F_s on a (the opposite on b).
    std::vector<Link> jenkins;
    /// Dampers (model.h Damper): the coefficient c in `k`; force -c (v[a] - v[b]) on a.
    std::vector<Link> dampers;
    /// Each mass's friction partner (elements/friction.h FrictionSlot::partner; kGround: the ground).
    std::vector<int> partner;
    /// Held against the ground (stuck, its partner the ground), or moving with its
    /// partner (stuck to a partner body), in cfg.
    bool fixed(const Configuration& cfg, int i) const { return cfg.stuck[i] && carrier(cfg, i) == kGround; }
    bool rides(const Configuration& cfg, int i) const { return cfg.stuck[i] && carrier(cfg, i) != kGround; }
    /// The body mass i moves with (model/assembly.h carrier()): i, the first
    /// body up its chain of stuck partners whose friction is not stuck, or kGround.
    int carrier(const Configuration& cfg, int i) const {
        while (i != kGround && cfg.stuck[static_cast<std::size_t>(i)]) i = partner[static_cast<std::size_t>(i)];
        return i;
    }
    /// (m_p a_i - m_i a_p)/(m_i + m_p): what holds mass i to its partner p (assembly.h against_partner),
    /// and the magnitude of its terms.
    cl_F against_partner(int i, const cl_F& ai, const cl_F& ap) const;
    cl_F against_partner_magnitude(int i, const cl_F& mag_i, const cl_F& mag_p) const;
    std::vector<cl_F> h_omega, h_phase;    ///< harmonics with omega != 0, folded to omega > 0
    std::vector<std::vector<cl_F>> h_amp;  ///< [h][i]
    std::vector<cl_F> f_const;             ///< loads + omega = 0 harmonics
    cl_F t0;
    std::vector<cl_F> x0, v0;

    MpModel(const Model& model, int digits);
    /// The double `d` exactly, in this format.
    cl_F F(double d) const;
    cl_F I(long i) const;

    /// Visits every element's forces in cfg (model/elements/direction.h):
    /// springs, contacts, Jenkins elements (a stuck one's length is its
    /// slider, slider(j)), dampers.
    template <class S, class V>
    void each_force(const Configuration& cfg, S&& slider, V&& visit) const;
    /// A_i (assembly.h force_on_mass) in cfg at (t, x, v) (x: the masses, then
    /// the sliders), and dA_i/dt given the accelerations a.
    cl_F force_on_mass(const Configuration& cfg, int i, const cl_F& t, const std::vector<cl_F>& x,
                       const std::vector<cl_F>& v) const;
    cl_F force_rate_on_mass(const Configuration& cfg, int i, const cl_F& t, const std::vector<cl_F>& v,
                            const std::vector<cl_F>& a) const;
    /// G_c = x[a] - x[b] - gap and its rate.
    cl_F gap(int c, const std::vector<cl_F>& x) const;
    cl_F gap_rate(int c, const std::vector<cl_F>& v) const;
    cl_F body(const std::vector<cl_F>& y, int b) const { return b == kGround ? zero : y[static_cast<std::size_t>(b)]; }
};

/// What MpSegment::eval writes (each vector sized by the segment).
struct MpEval {
    std::vector<cl_F> x, v, a, g, dg, bound, scale;
};

class MpSegment {
public:
    enum class Regime { rigid, underdamped, critical, overdamped };
    struct CosSin {
        cl_F c, s;
    };

    /// Analyse cfg (throws RunError when Jacobi does not converge).
    MpSegment(const Model& model, const MpModel& mp, const Configuration& cfg);

    const Configuration& configuration() const { return cfg_; }
    const std::vector<SwitchFunction>& switches() const { return switches_; }
    /// Start at absolute time t0 (see SegmentSolver::setup; x0: the masses, then the sliders).
    void setup(const cl_F& t0, const std::vector<cl_F>& x0, const std::vector<cl_F>& v0,
               const std::vector<signed char>& sgn);
    /// State, switch functions, rates, bounds B_f >= |g_f''| over [tau, tau + max_step] and term scales at tau >= 0.
    void eval(const cl_F& tau, MpEval& out) const;
    /// Bounds hold for steps up to max_step() (only with a secular resonance term); has_max_step() false: unlimited.
    bool has_max_step() const { return has_max_step_; }
    const cl_F& max_step() const { return max_step_; }

    /// A bound on |g_f^(k)(tau)| for 0 <= tau <= horizon after setup(), k >= 2 (ties at a segment start,
    /// reference.cpp): per mode the homogeneous part's k-th derivative cannot exceed what its energy
    /// E_(k-1) = (u^(k)^2 + lambda u^(k-1)^2)/2 allows (E_(k-1) never grows: u^(k-1) solves the same damped
    /// equation), a rigid-body mode's |u^(k)| <= c^(k-2) |u''(0)|; each harmonic adds one sinusoid of amplitude
    /// Omega^k sqrt(A^2 + B^2), a secular term |A| (horizon Omega^k + k Omega^(k-1)).
    cl_F derivative_bound(std::size_t f, int k, const cl_F& horizon) const;

    /// The fastest rate of the segment's motion [1/s]: the largest of the modal frequencies sqrt(lambda_j), the modal
    /// damping rates c_j and the forcing frequencies (0 for a segment that cannot move). It sets how many search steps
    /// a segment may legitimately take (reference.cpp).
    cl_F fastest_rate() const;

    /// Dampers: the free coordinates' state by the matrix exponential (below).
    bool damped() const { return damped_; }

    // For tests.
    const std::vector<cl_F>& lambda() const { return lambda_; }
    Regime regime(int j) const { return regime_[static_cast<std::size_t>(j)]; }

private:
    // Dampers (non-proportional damping), independent of the derivation's
    // state-space modes: the homogeneous state z_h = (x_F, v_F) - z_p moves as
    // z_h(tau) = exp(S tau) z_h(0), S = [0 I; -M^-1 K  -M^-1 C], by scaling and
    // squaring of S's Taylor series at the working precision (a defective S,
    // critical damping, is no special case); x_st = K^-1 f and each harmonic's
    // X_h = (K - W^2 M + i W C)^-1 F_h by elimination. The bounds use the energy
    // E = (v_h^T M v_h + x_h^T K x_h)/2, which never grows (dE/dt = -v_h^T C v_h):
    // a row (p, q) on (x_h, v_h) is at most (sqrt(p^T K^-1 p) + sqrt(q^T M^-1 q))
    // sqrt(2 E), so |g^(k)| <= that of L_f S^k plus sum_h W^k |G_fh| over any
    // step. Rigid-body modes (K_FF singular) are refused (RunError).
    void init_damped(const Model& model);
    void setup_damped(const std::vector<cl_F>& force, const std::vector<cl_F>& v0);
    /// x, v, a of the free masses and their term magnitudes at tau; the energy of the homogeneous part.
    void eval_damped(const cl_F& tau, MpEval& out, std::vector<cl_F>& xm, std::vector<cl_F>& vm, cl_F& energy) const;
    /// sqrt(p^T K^-1 p) + sqrt(q^T M^-1 q) of the row L_f S^k.
    cl_F damped_weight(std::size_t f, int k) const;
    /// x, v, a of the free masses from the modes, their magnitudes, and per mode
    /// the bounds on the second and third derivatives from here on.
    void eval_modal(const cl_F& tau, const std::vector<CosSin>& hcs, MpEval& out, std::vector<cl_F>& xm,
                    std::vector<cl_F>& vm, std::vector<cl_F>& b2, std::vector<cl_F>& b3) const;
    /// The sliders, then the switch functions from x, v, a; bound(f) gives B_f.
    template <class Bound>
    void sliders_and_switches(MpEval& out, const std::vector<cl_F>& xm, const std::vector<cl_F>& vm,
                              const std::vector<CosSin>& hcs, Bound&& bound) const;

    const MpModel& mp_;
    Configuration cfg_;
    std::vector<SwitchFunction> switches_;
    int n_ = 0, nf_ = 0, nh_ = 0;
    std::vector<int> free_, slot_;  // slot_: each moving mass's coordinate (a rider: its partner's), else -1
    std::vector<int> riders_;       // masses stuck to their friction partner: x = x_partner + e
    std::vector<cl_F> mass_;        // per coordinate: its free mass plus its riders'
    std::vector<std::vector<cl_F>> mass_matrix_;  // M_F of a coupled M (empty when lumped)
    /// lambda_, phi_ of K_F phi = lambda M_F phi, the first n_rigid eigenvalues the structural zeros.
    void undamped_modes(const Model& model, const std::vector<std::vector<cl_F>>& Kf, int n_rigid);
    void switch_rows();  // W_, Z_, D_ (and release_rows_) from the modes
    std::vector<cl_F> offset_;      // setup: each rider's e = x0 - x0_partner
    std::vector<std::vector<cl_F>> K_, C_, phi_;  // full n x n; phi nf x nf (rows: free masses)
    std::vector<cl_F> f_const_;
    std::vector<Regime> regime_;
    std::vector<cl_F> lambda_, omega_, c_, sigma_, omega_d_, gamma_, r1_;
    std::vector<std::vector<cl_F>> P_, pa_, pb_;  // [j][h]
    std::vector<std::vector<char>> secular_;      // [j][h]: exact undamped resonance
    std::vector<std::vector<cl_F>> W_, Z_, D_;    // switch functions as modal combinations
    std::vector<cl_F> bound_sin_;
    bool has_max_step_ = false;
    cl_F max_step_;
    // setup
    std::vector<cl_F> x_fix_, theta_, p_, u0_, ud0_;
    std::vector<cl_F> v_start_;  // setup: the start velocities (eval(0) returns the start state itself)
    std::vector<cl_F> fseg_;  // f_const_ plus the stuck sliders' preload k s
    std::vector<cl_F> fric_;  // the segment's kinetic friction on every dof (setup)
    /// A coupled M: P_i of every stuck dof i (MpModel::held_row), else empty.
    std::vector<std::vector<cl_F>> release_rows_;
    std::vector<cl_F> slider_;  // the stuck sliders' positions
    // dampers
    bool damped_ = false;
    std::vector<std::vector<cl_F>> S_, Kinv_, Lx_, Lv_;  // S, K_FF^-1 (2nf, nf square); g_f's rows on x_F, v_F
    std::vector<std::vector<cln::cl_N>> X_, G_;          // [h][r] particular amplitudes; [f][h] g_f's
    std::vector<cl_F> weight2_;                          // damped_weight(f, 2)
    std::vector<cl_F> force_, x_st_, zh0_;               // setup: constant force, static offset, z_h(0)
    cl_F energy0_;
};

template <class S, class V>
void MpModel::each_force(const Configuration& cfg, S&& slider, V&& bodies) const {
    auto visit = pair_links(bodies, [this](double w) { return cln::cl_float(w, format); });
    for (const Link& s : springs) spring::forces(Direction{s.a, s.b}, s.k, beta, visit);
    for (std::size_t c = 0; c < contacts.size(); ++c)
        contact::forces(cfg.closed[c] != 0, contacts[c].direction(), contacts[c].k, contacts[c].gap, beta, contacts[c].c,
                        visit);
    for (std::size_t j = 0; j < jenkins.size(); ++j) {
        const Link& e = jenkins[j];
        jenkins::forces(cfg.slip[j], e.direction(), e.k, e.gap, cl_F(slider(j)), beta, visit);
    }
    for (const Link& d : dampers) damper::forces(Direction{d.a, d.b}, d.k, visit);
}

/// The elements' parameters at N digits as the switch functions read them
/// (model/switch_derivative.h); the slider of Jenkins element j
/// through slider(j).
template <class Slider>
struct MpElements {
    struct ContactView {
        Direction d;
        cl_F gap;
    };
    struct JenkinsView {
        Direction d;
        cl_F k, slip_force, s;
    };
    const MpModel& mp;
    Slider slider;
    ContactView contact(int e) const {
        const MpModel::Link& l = mp.contacts[static_cast<std::size_t>(e)];
        return {l.direction(), l.gap};
    }
    JenkinsView jenkins(int e) const {
        const MpModel::Link& l = mp.jenkins[static_cast<std::size_t>(e)];
        return {l.direction(), l.k, l.gap, slider(e)};
    }
    Direction friction(int e) const { return {e, mp.partner[static_cast<std::size_t>(e)]}; }
};
template <class Slider>
MpElements<Slider> mp_elements(const MpModel& mp, Slider slider) {
    return {mp, std::move(slider)};
}

}  // namespace hsnc::reference
