// hsnc -- Derivation: the closed-form solution of one configuration, derived
// with GiNaC at high precision (generator side; the runtime never sees GiNaC).
//
// For configuration cfg with free masses F and stuck masses S (paper Eq. 7-9):
//     M_FF x_F'' + C_FF x_F' + K_FF x_F = f(t),
//     f = loads_F + preload_F - K_FS x_S - mu_k N sgn + sum_h F_h,F sin(Omega_h t + phase_h),
// with K = K(cfg) (closed contact springs added), C = alpha M + beta K(cfg); the
// stuck coupling -K_FS x_S is the constant force of Eq. 7 and C_FS v_S = 0.
// Modal analysis: Kt = M^-1/2 K M^-1/2 = Phi diag(lambda) Phi^T (in double-double:
// solved in double and refined, or by Jacobi rotations; EigenMethod),
// x_F = V u with V = M^-1/2 Phi, u = W x_F with W = Phi^T M^1/2. Rayleigh damping is diagonal in these coordinates:
//     u_j'' + c_j u_j' + lambda_j u_j = p_j + sum_h P_jh sin(Omega_h t + phase_h),
//     c_j = alpha + beta lambda_j,  p_j = sum_i V_ij f_i,  P_jh = sum_i V_ij F_hi.
// Rigid-body modes (floating components of the free masses) are detected from
// the graph of springs: lambda = 0 exactly and a uniform shape.
//
// Each mode's homogeneous part is written u_h = A eC(tau) + B eS(tau) with
// eC = e^{-sigma tau} C, eS = e^{-sigma tau} S, C' = -kappa S, S' = C, so that
// d/dtau maps (A, B) to (B - sigma A, -kappa A - sigma B) in every regime
// (kappa = omega_d^2 underdamped, 0 critical, -gamma^2 overdamped).
#pragma once

#include <ginac/ginac.h>

#include <string>
#include <vector>

#include "configuration.h"
#include "double_double.h"
#include "elements/motion.h"
#include "model.h"
#include "mp_eigen.h"  // DdEigenCache
#include "switch_function.h"

namespace hsnc {

/// Working precision of the derivation: double-double (DD, double_double.h,
/// about 32 digits) for the modes, the harmonics and every constant of the
/// program; CLN long floats of kDerivationDigits decimal digits where
/// GiNaC works (the state-space eigenproblem of dampers, symbolic_segment).
inline constexpr int kDerivationDigits = 40;

enum class Regime {
    undamped,      ///< c = 0, lambda > 0: cos / sin
    underdamped,   ///< 0 < xi < 1: e^{-sigma tau} (cos, sin)(omega_d tau)
    critical,      ///< xi = 1: e^{-sigma tau} (1, tau)
    overdamped,    ///< xi > 1: e^{r1 tau} with expm1(-2 gamma tau)
    rigid,         ///< lambda = 0, c = 0: polynomial in tau
    rigid_damped,  ///< lambda = 0, c > 0: drift + expm1(-c tau)
};

const char* regime_name(Regime r);

struct Mode {
    Regime regime = Regime::undamped;
    DD lambda, c;        ///< u'' + c u' + lambda u = ...
    DD omega, xi;        ///< sqrt(lambda), c / (2 omega) (0 for rigid modes)
    DD sigma, kappa;     ///< e^{-sigma tau}; C' = -kappa S
    DD omega_d, gamma;   ///< sqrt(kappa) (under/undamped), sqrt(-kappa) (overdamped)
    DD r1;               ///< slow root -lambda/(sigma + gamma) (overdamped, rigid_damped)
    std::vector<DD> v;   ///< column j of V over the free masses
    std::vector<DD> w;   ///< row j of W over the free masses
    /// State-space pseudo-modes only (Derivation::state_space): q(0) = w.xh + w_v.vh,
    /// q'(0) = dw_x.xh + dw_v.vh from the homogeneous initial state (xh, vh). Empty
    /// for the modes of proportional damping, where q(0) = w.xh, q'(0) = w.vh.
    std::vector<DD> w_v, dw_x, dw_v;
};

/// The response of one mode to one forcing harmonic.
struct ModalHarmonic {
    DD P;                      ///< modal amplitude P_jh
    bool resonant = false;     ///< c = 0 and |Omega - omega| <= kResonanceBand omega: sinc form
    DD a_s, a_c;               ///< non-resonant particular: P (a_s sin + a_c cos)(Omega tau + theta)
};

struct HarmonicData {
    DD omega, phase;
    std::vector<DD> amplitude;         ///< F_hi, all masses
    std::vector<ModalHarmonic> modal;  ///< one per mode
    std::vector<DD> xs, xc;            ///< non-resonant particular in x: xs sin + xc cos (free masses)
};

/// Relative band |Omega - omega| / omega inside which an undamped mode uses the
/// resonance-stable (sinc) form of its forced response: the one band of the
/// folded kernels, the interpreter (both from the derivation) and the sweep
/// kernels (printed into them as resonance_band). Why 1%: outside it the
/// standard particular P/(lambda - Omega^2) is at most ~1/(2 * 0.01) = 50 times
/// the static response, so its cancellation against the homogeneous part costs
/// at most ~1.7 digits; inside it the sinc form is exact through Omega = omega
/// but grows secularly, so its bounds hold for one forcing period only (a step
/// limit), a cost worth paying only close to resonance. (The Eigen solver,
/// the kernels' independent oracle, keeps its own criterion: generic_solver.cpp.)
inline constexpr double kResonanceBand = 1e-2;

/// Non-proportional damping (dampers): the free coordinates' state z = (x, v)
/// obeys z' = S z + b, S = [0 I; -M^-1 K  -M^-1 C], decomposed in double-double
/// as S = Psi diag(mu) L (generator/mp_complex_eigen.h). Each conjugate pair
/// mu = -sigma + i omega_d, with c = L z_h(0), gives two real pseudo-modes that
/// the mode blocks of proportional damping already compute:
///     u = Re(c e^{mu tau}),  w = Im(c e^{mu tau}):  u'' + 2 sigma u' + |mu|^2 u = 0
/// (regime underdamped, or undamped when sigma = 0), x = sum 2 Re(psi) u - 2 Im(psi) w;
/// each real mu < 0 one pseudo-mode u = c e^{mu tau} (regime critical with
/// sigma = -mu, whose B is zero). The static offset is x_st = K^-1 f, a harmonic's
/// particular part X = (K - Omega^2 M + i Omega C)^-1 F (xs = Re X, xc = Im X).
/// Refused (NotDerivable, the Eigen solver takes the configuration):
/// rigid-body modes, nearly defective S (critical damping), an undamped
/// pseudo-mode forced within kResonanceBand of its frequency.
struct StateSpaceData {
    std::vector<DDComplex> values;               ///< mu_k, the order of dd_complex_eigen
    std::vector<std::vector<DDComplex>> vectors;  ///< vectors[k]: Psi_k over (x, v) of the free coordinates
    std::vector<std::vector<DDComplex>> inverse;  ///< inverse[k]: row k of L = Psi^-1
    std::vector<std::vector<DD>> static_inverse;  ///< K_FF^-1 (folded), for x_st
};

struct Derivation {
    const Model* model = nullptr;
    Configuration cfg;
    std::vector<int> free_dofs;   ///< mass indices of the free masses, in order: one coordinate each
    std::vector<int> stuck_dofs;  ///< mass indices of the masses stuck against the ground (held at x0)
    /// Masses stuck to their friction partner (elements/friction.h FrictionSlot::partner): each
    /// moves with its partner's coordinate at the offset x0[i] - x0[partner]
    /// it had at the segment start (x = T q + e), so the modes are those of
    /// T^T M T, T^T K T: a coordinate's mass and stiffness gather its riders'.
    std::vector<int> riders;
    std::vector<GiNaC::numeric> mass;  ///< per coordinate: its free mass plus its riders' (exact)
    /// Full n x n K(cfg), C (exact rationals), for the symbolic forms
    /// (symbolic_segment, segment_force) and the state-space solution; empty
    /// (0 x 0) when derive() was asked for Exact::no.
    GiNaC::matrix K, C;
    std::vector<std::vector<DD>> k_dd, c_dd;  ///< the same in DD, for the lowering
    std::vector<GiNaC::numeric> f_const;  ///< loads + preload, all masses (exact)
    std::vector<GiNaC::numeric> mu_k_n;   ///< mu_k N_i of free friction masses, else 0
    /// f_const and mu_k_n rounded once each, for the lowering (a conversion of
    /// a GiNaC number is not free).
    std::vector<double> f_const_double, mu_k_n_double;
    std::vector<double> mu_s_n;           ///< mu_s N_i of every friction mass, the exact product rounded once; else 0
    std::vector<Mode> modes;               ///< ascending lambda
    std::vector<HarmonicData> harmonics;   ///< Omega > 0 harmonics (Omega = 0 ones fold into f_const)
    std::vector<SwitchFunction> switches;
    /// Coupled M: per stuck dof (stuck_dofs order), c = M_FF^-1 M_Fi over the
    /// free coordinates. The force its friction holds is D_i = A_i - c^T A_F
    /// (model/held_mass.h), A_F the free dofs' forces with their kinetic
    /// friction. Empty for a lumped M.
    std::vector<std::vector<DD>> held;
    double max_step = 0;  ///< +inf unless resonant (secular) terms: then one forcing period
    bool state_space = false;  ///< dampers: `modes` are pseudo-modes of `state` (StateSpaceData)
    StateSpaceData state;

    std::size_t n_free() const { return free_dofs.size(); }
    /// Index into free_dofs of mass i, or -1 when stuck.
    int free_index(int mass) const;
    /// The coordinate mass i moves with: free_index(i), or its partner's for a
    /// rider; -1 for a mass stuck against the ground and for the ground.
    int coordinate(int mass) const;
    /// Mass i is one of `riders`.
    bool rides(int mass) const;
};

/// How derive() finds the modes of Kt = M^-1/2 K_FF M^-1/2 at the working
/// precision. refined: solved in double, refined to the working precision
/// (generator/mp_eigen.h; O(n^3) with a small constant). jacobi: cyclic
/// Jacobi rotations at the working precision throughout (the reference the
/// refined path is tested against, and its fallback; a sweep costs O(n^3)
/// long-float operations, about 10 sweeps).
enum class EigenMethod { refined, jacobi };

/// Whether derive() also fills Derivation::K and C as exact rationals. The
/// lowering reads only their double-double copies (k_dd, c_dd); building the
/// exact matrices costs an n x n GiNaC matrix and rational arithmetic per
/// entry, the largest share of deriving a configuration of a 128-mass chain
/// that is not modal analysis. Dampers need them (the state-space solution):
/// with dampers they are built whatever is asked.
enum class ExactMatrices { yes, no };

/// Derive configuration `cfg` of `model`. Throws RunError when the
/// eigen-solver does not converge (refined: when neither it nor Jacobi
/// converges), NotDerivable for what StateSpaceData refuses.
/// What a run's derivations of one model share: the blocks the refined
/// eigen-solver has solved (mp_eigen.h), and the friction forces mu N of each
/// mass, exact products of the model's numbers. One user at a time (the
/// derivation holds the GiNaC lock).
struct DerivationCache {
    DdEigenCache eigen;
    std::vector<GiNaC::numeric> mu_k_n;  ///< per mass (0 without friction)
    std::vector<double> mu_k_n_double;   ///< the same rounded once
    std::vector<double> mu_s_n;          ///< per mass, rounded once (0 without friction)
};

/// `cache` (may be null; for one model) keeps what the next configurations of
/// the same run reuse.
Derivation derive(const Model& model, const Configuration& cfg, EigenMethod method = EigenMethod::refined,
                  ExactMatrices exact_matrices = ExactMatrices::yes, DerivationCache* cache = nullptr);

/// Inputs of one segment as GiNaC expressions: numbers or symbols.
struct SegmentInputs {
    GiNaC::ex t0;
    std::vector<GiNaC::ex> x0, v0;  ///< all masses (x0: then every Jenkins slider)
    std::vector<GiNaC::ex> sgn;     ///< all masses, {-1, 0, +1} (or symbols)
};

/// The segment solution written in the textbook forms (cos/sin, cosh/sinh,
/// exp, the secular resonance term), independent of the emitter's
/// overflow-safe forms; derivatives by GiNaC diff.
struct SymbolicSegment {
    std::vector<GiNaC::ex> u;          ///< modal coordinates (empty with dampers: x from the state-space modes)
    std::vector<GiNaC::ex> x, v, a;    ///< all masses (x: then every Jenkins slider)
    std::vector<GiNaC::ex> g, dg;      ///< switch functions, as in switch_functions()
};

SymbolicSegment symbolic_segment(const Derivation& d, const SegmentInputs& in, const GiNaC::symbol& tau);

/// The preload k_j s_j on mass i of every Jenkins element stuck in the
/// configuration (+ on a, - on b; s_j = in.x0[n + j]).
GiNaC::ex slider_preload(const Derivation& d, const SegmentInputs& in, int i);

/// The constant force on mass i in a segment (paper Eq. 7-9):
/// f_const - mu_k N sgn (+ the reaction of a sliding rider's friction on its
/// partner) - K_iS x_S - K_iR (x0_R - x0_partner) + slider_preload.
GiNaC::ex segment_force(const Derivation& d, const SegmentInputs& in, int i);

/// The constant force on coordinate r: segment_force summed over its free
/// mass and its riders (T^T f).
GiNaC::ex coordinate_force(const Derivation& d, const SegmentInputs& in, std::size_t r);

/// High-precision number from a double, exactly (no rounding on the way in).
GiNaC::numeric exact(double v);
/// A DD exactly as a GiNaC number (the rational hi + lo), and a GiNaC real
/// number rounded to DD.
GiNaC::numeric exact(const DD& v);

/// A direction's weights in the derivation's motion (RowsMotion<ex>), exactly.
template <>
struct ExactWeight<GiNaC::ex> {
    static GiNaC::ex of(double w, const GiNaC::ex&) { return exact(w); }
};

/// Mass i's normal force exactly: its element's `normal` as given, else the
/// exact product m*g of the two doubles (FrictionSlot::normal in elements/friction.h).
GiNaC::numeric exact_normal(const Model& model, std::size_t i);
DD to_dd(const GiNaC::numeric& v);

}  // namespace hsnc
