// hsnc -- Program: the closed-form solution of one configuration as a typed,
// straight-line program over a file of double registers.
//
// The generator lowers each configuration's derivation (generator/lowering.h,
// constants from the double-double derivation rounded once to double) to one
// Program. The emitter prints it as the C++ of a kernel (generator/emitter.h:
// AOT and JIT kernels); the interpreter (runtime/solvers/interpreted_solver.h) runs it
// as the generic path. Both follow the order of operations written here, with
// no contraction of a*b+c into an fma (-ffp-contract=off for every target and
// for the JIT) and the same libm calls, so a printed kernel and the interpreter
// give the same bits (tests/test_program.cpp). Anything that branches on data
// (the phase reduction, phi2's series) is a helper of kernels/kernel_abi.h,
// which the printed kernels and the interpreter both call.
//
// Two programs: `setup` (inputs t0, t0_lo, x0, v0, sgn -> the coefficient
// block) and `eval` (inputs tau and the coefficient block -> x, v, a, g, dg,
// bound, scale). Instructions are coarse where eval spends its time: a
// linear combination over a constant row, one closed-form block per mode.
//
// Register 0 holds 1.0 in both programs: a term c*r0 is the constant c.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "configuration.h"
#include "switch_function.h"

namespace hsnc {

enum class ProgramOp : std::uint8_t {
    /// r[dst] = (r[a] +) (c_0 r[s_0] + c_1 r[s_1] + ...), summed left to
    /// right over terms [first, first + count) (0.0 when count = 0); the base
    /// r[a] is added last when a != kNoRegister.
    lincomb,
    /// The same sum in long double, each term (long double)c_k * r[s_k],
    /// rounded once to double (no base).
    lincomb_ld,
    copy,  ///< r[dst] = r[a]
    abs,   ///< r[dst] = |r[a]|
    sin,   ///< r[dst] = sin(r[a])
    cos,   ///< r[dst] = cos(r[a])
    /// r[dst] = hsnc_phase(k[0], r[a], r[b], k[1]): Omega (t0 + t0_lo) + phase, reduced.
    phase,
    /// A forcing harmonic at tau = r[b]: dst+0 arg = k[0]*tau + r[a] (k[0] = Omega,
    /// r[a] = theta), dst+1 sin(arg), dst+2 cos(arg).
    harmonic,
    /// The homogeneous response of one mode (regime in `regime`) at tau = r[b]
    /// from its coefficients A, B, A1, B1, A2, B2 = r[a .. a+5]; constants k[0 ..
    /// kModeConstants) as laid out by ModeConstant. Writes the ModeRegister
    /// block at dst: eC, eS, q, q', q'', r = sqrt(q'^2 + lambda q^2) (homogeneous),
    /// the magnitudes |A eC| + |B eS|, |A1 eC| + |B1 eS|, and the auxiliary
    /// exponential (e or m) of the regime. Its e^{-sigma tau}, sin and
    /// cos(omega_d tau) are libm's, or kernel_abi.h's four-lane helpers'
    /// (vector_factors, below).
    mode,
    /// q_p = p tau^2/2 of a rigid mode, p = r[a], tau = r[b], added to the mode block at c.
    rigid_particular,
    /// q_p = p tau^2 phi2(-c tau) of a damped rigid mode: dst = q_p, p = r[a],
    /// tau = r[b], mode block at c, k[0] = c; added to the mode block.
    rigid_damped_particular,
    /// The state of one free mass from its modes, five sums in lockstep:
    ///   x = r[a] + sum_k c_k q_k + tail_x,        v = sum_k c_k q'_k + tail_v,
    ///   acc = sum_k c_k q''_k + tail_a,           mx = |r[a]| + sum_k |c_k| mq_k + tail_mx,
    ///   mv = sum_k |c_k| mdq_k + tail_mv,
    /// where term k of [first, first + count) is (c_k = V_ik, mode block register)
    /// and the tails (forcing terms, constants) follow in `terms`, tail[0..4]
    /// terms each; each sum left to right, as printed. x, v, acc go to dst, b, c;
    /// mx, mv to d, d+1.
    mass_state,
    /// The resonant (sinc) response of an undamped mode to one harmonic, from
    /// rest: dst+0..6 = w, w', Cb, Sb, y, y', y''; theta = r[a], tau = r[b],
    /// mode block at c, cos(theta) = r[d]; constants ResonantConstant. Added to
    /// the mode block.
    resonant,
};

/// Constants of a `mode` instruction, relative to its first constant.
enum ModeConstant : std::uint32_t {
    kModeLambda,
    kModeSigma,
    kModeKappa,
    kModeOmegaD,
    kModeInvOmegaD,      ///< 1/omega_d
    kModeGamma,
    kModeR1,             ///< slow root -lambda/(sigma + gamma)
    kModeNegTwoGamma,    ///< -2 gamma
    kModeHalfInvGamma,   ///< 0.5/gamma
    kModeC,              ///< c of a damped rigid mode
    kModeInvC,           ///< 1/c
    kModeConstants
};

/// Registers of a mode block, relative to the `mode` instruction's dst.
enum ModeRegister : std::uint32_t {
    kModeEC,
    kModeES,
    kModeQ,
    kModeDQ,
    kModeDDQ,
    kModeR,
    kModeMQ,
    kModeMDQ,
    kModeAux,  ///< e^{-sigma tau} (underdamped), e^{r1 tau} (overdamped), expm1(-c tau) (damped rigid)
    kModeAux2,  ///< expm1(-2 gamma tau) (overdamped)
    kModeRegisters
};

/// Constants of a `resonant` instruction.
enum ResonantConstant : std::uint32_t {
    kResHalfDiff,      ///< h = (Omega - omega)/2 (w = tau, w' = 1 when h = 0)
    kResInvHalfDiff,   ///< 1/h
    kResMean,          ///< wbar = (Omega + omega)/2
    kResQ,             ///< Q = P/(omega + Omega)
    kResH2W2,          ///< h^2 + wbar^2
    kResTwoMean,       ///< 2 wbar
    kResLambda,        ///< lambda of the mode
    kResConstants
};

inline constexpr std::uint32_t kNoRegister = 0xffffffffu;
inline constexpr std::uint32_t kNoText = 0xffffffffu;  ///< an instruction without comment or note

struct ProgramTerm {
    double c;
    std::uint32_t reg;
};

struct ProgramInstr {
    explicit ProgramInstr(ProgramOp o) : op(o) {}
    ProgramOp op;
    std::uint8_t regime = 0;          ///< `mode`: the Regime (generator/derivation.h order)
    bool accumulates = false;         ///< `mode`: particular terms are added to its q, q', q''
    std::uint32_t dst = kNoRegister;  ///< first destination register
    std::uint32_t a = kNoRegister, b = kNoRegister, c = kNoRegister, d = kNoRegister;  ///< operands
    std::uint32_t first = 0;          ///< first term (lincomb) or constant (the others)
    std::uint32_t count = 0;          ///< terms (lincomb, mass_state)
    std::uint32_t tail[5] = {};       ///< mass_state: terms of the tails of x, v, acc, mx, mv
    std::uint32_t text = kNoText;     ///< its comment and note: ProgramBody::texts[text] (named programs)
};

/// What the printer writes around an instruction: a comment above it and a
/// note after it, on its line (either may be empty).
struct ProgramText {
    std::string comment, note;
};

/// Mode regimes, the order of generator/derivation.h's Regime.
enum class ProgramRegime : std::uint8_t { undamped, underdamped, critical, overdamped, rigid, rigid_damped };

/// What a register is, for the printer; the interpreter only reads values.
enum class RegisterKind : std::uint8_t {
    one,     ///< 1.0 (register 0)
    input,   ///< t0, t0_lo, x0[i], v0[i], sgn[i] (setup); tau, coef[k] (eval)
    output,  ///< coef[k] (setup); x[i], v[i], a[i], g[f], dg[f], bound[f], scale[f] (eval)
    temp,    ///< named intermediate
};

struct ProgramBody {
    std::vector<ProgramInstr> code;
    /// Per register: its C++ name; empty in a program lowered without names
    /// (generator/lowering.h ProgramNames::no), which only the interpreter runs.
    std::vector<std::string> names;
    std::vector<RegisterKind> kinds;  ///< per register
    /// The instructions' comments and notes, kept apart from the code: only a
    /// named program has any (the printer's), and the interpreter copies the
    /// code of every configuration a run enters.
    std::vector<ProgramText> texts;
    std::size_t registers() const { return kinds.size(); }
    const std::string& comment(const ProgramInstr& in) const { return in.text == kNoText ? none() : texts[in.text].comment; }
    const std::string& note(const ProgramInstr& in) const { return in.text == kNoText ? none() : texts[in.text].note; }

private:
    static const std::string& none() {
        static const std::string empty;
        return empty;
    }
};

/// What restarting a segment at a reversal needs of a configuration
/// (runtime/solvers/restart.h): a reversal flips one sliding mass's kinetic
/// friction and keeps the configuration, so the modes stay and only the
/// modal forces change; the coefficient block can be carried over instead of
/// projecting the state again. Built by generator/lowering.h restart_plan()
/// for configurations of plain modes (no dampers' pseudo-modes, riders,
/// Jenkins elements, friction pairs, rigid modes or resonance); empty otherwise.
struct RestartPlan {
    struct Mode {
        std::uint32_t coef = 0;  ///< coef index of its A (B, A1, B1, A2, B2 follow)
        ProgramRegime regime = ProgramRegime::undamped;
        double sigma = 0, kappa = 0, omega_d = 0, lambda = 0;
        double r1 = 0, gamma = 0;  ///< overdamped: the slow root and gamma
    };
    struct Harmonic {
        std::uint32_t theta = 0, c_theta = 0;  ///< coef indices
        double omega = 0, phase = 0;
    };
    std::vector<Mode> modes;
    std::vector<int> free_mass;          ///< per free coordinate: its mass
    std::vector<double> mu_k_n;          ///< per free coordinate: mu_k N of its mass (0 without friction)
    /// V by modes: vt[j * free_mass.size() + r] is V_rj (mode j's column,
    /// contiguous, so that x_st moves by sum_j V_j Delta(p_j / lambda_j) in
    /// vector registers).
    std::vector<double> vt;
    /// Per mode j, the free coordinates [span[2j], span[2j + 1]) outside of
    /// which V_rj is 0 (a mode of one block of the chain a stuck mass cuts).
    std::vector<std::uint32_t> span;
    std::vector<std::uint32_t> x_st;     ///< per free coordinate: coef index of its static offset
    std::vector<Harmonic> harmonics;
    bool empty() const { return modes.empty(); }
};

/// Whether a mode instruction's regime takes e^{-sigma tau} or sin, cos(omega_d tau).
inline bool takes_factors(const ProgramInstr& in) {
    if (in.op != ProgramOp::mode) return false;
    const auto regime = static_cast<ProgramRegime>(in.regime);
    return regime == ProgramRegime::undamped || regime == ProgramRegime::underdamped ||
           regime == ProgramRegime::critical;
}

/// From this many such modes in eval, every one takes its factors from
/// kernel_abi.h's four-lane hsnc_exp4 and hsnc_sincos4, else each from libm.
/// Four lanes are fast when many modes' calls overlap; a few modes alone wait
/// for a longer chain than libm's (measured: bench/program_bench.cpp).
inline constexpr std::size_t kVectorFactorsFrom = 8;

/// Whether `eval`'s modes take their factors four lanes at a time (the
/// printer and the interpreter decide alike).
inline bool vector_factors(const ProgramBody& eval) {
    std::size_t n = 0;
    for (const ProgramInstr& in : eval.code) n += takes_factors(in);
    return n >= kVectorFactorsFrom;
}

struct Program {
    int n_dof = 0;
    int n_slider = 0;  ///< Jenkins elements: x0 and x carry their sliders after the masses
    int n_coef = 0;
    double max_step = 0;  ///< validity of `bound`: +inf unless secular terms
    Configuration cfg;
    std::vector<SwitchFunction> switches;

    std::vector<double> constants;
    std::vector<std::string> constant_names;  ///< "" for a constant printed as a literal
    std::vector<ProgramTerm> terms;

    /// Registers: 0 = 1.0, 1 = t0, 2 = t0_lo, then x0 (n_state(): the masses,
    /// then the sliders), v0 (n_dof), sgn (n_dof, as doubles); then temps. setup_coef[k] is the register
    /// copied to coef[k] at the end.
    ProgramBody setup;
    std::vector<std::uint32_t> setup_coef;
    std::vector<std::string> coef_names;  ///< what coef[k] holds ("A_1"), for the printed layout
    /// coef indices of what setup computes from the state: each mode's A (B,
    /// A1, B1, A2, B2 follow), each free coordinate's static offset x_st, each
    /// harmonic's phase theta and cos(theta) (restart_plan(), generator/lowering.h).
    std::vector<std::uint32_t> mode_coef, x_st_coef, theta_coef, c_theta_coef;
    /// How a segment is carried over an event that keeps the configuration
    /// (restart_plan(), generator/lowering.h); empty where it cannot be.
    RestartPlan restart;
    /// Registers: 0 = 1.0, 1 = tau, 2 .. 2+n_coef = coef, then x (n_state()),
    /// v, a (n_dof each), g, dg, bound, scale (n_switch each); then temps.
    ProgramBody eval;

    static constexpr std::uint32_t kSetupT0 = 1, kSetupT0Lo = 2, kSetupX0 = 3;
    static constexpr std::uint32_t kEvalTau = 1, kEvalCoef = 2;
    int n_state() const { return n_dof + n_slider; }
    std::uint32_t setup_v0() const { return kSetupX0 + static_cast<std::uint32_t>(n_state()); }
    std::uint32_t setup_sgn() const { return setup_v0() + static_cast<std::uint32_t>(n_dof); }
    std::uint32_t eval_outputs() const { return kEvalCoef + static_cast<std::uint32_t>(n_coef); }
    /// Eval's output registers: x, v, a, then four per switch function.
    std::uint32_t eval_output_count() const {
        return static_cast<std::uint32_t>(n_state() + 2 * n_dof) + 4 * static_cast<std::uint32_t>(n_switch());
    }
    std::size_t n_switch() const { return switches.size(); }
};

}  // namespace hsnc
