#include "interpreted_solver.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <type_traits>
#include <unordered_map>

#include "kernel_abi.h"  // hsnc_phase, hsnc_phi2: the very helpers the printed kernels call
#include "mode_factors.h"

namespace hsnc {

namespace interpreter {

/// An instruction as compiled: the operands of ProgramInstr without its
/// comments. Every op but lincomb, lincomb_ld, copy, abs and mass_state
/// (which run in blocks) runs as one step.
struct Instr {
    ProgramOp op;
    std::uint8_t regime;
    std::uint32_t dst, a, b, c, d, first, count;
    std::uint32_t tail[5];
};

enum class StepKind : std::uint8_t {
    single,  ///< one instruction (Instr)
    lin,     ///< rows of `lincomb` with `count` terms each
    lin_ld,  ///< rows of `lincomb_ld`
    copy,    ///< rows of `copy`
    abs,     ///< rows of `abs`
    mass,    ///< rows of `mass_state` over the same mode blocks and tail registers
};

/// What the compiler makes of one instruction or of the instructions of one
/// level and one shape (`rows` of them): coefficients laid out [term][row], so
/// that a few rows advance together, each in its own order. Its data is in
/// the scheduler's two pools (BlockPools), in the order a Step reads it.
struct Block {
    StepKind kind = StepKind::single;
    bool shared = false;    ///< lin, lin_ld: term k reads one register in every row (reg[k])
    bool has_base = false;  ///< lin: every row adds its base register last
    std::uint32_t rows = 0, count = 0;
    std::uint32_t tail[5] = {};     ///< mass: terms of the tails of x, v, acc, mx, mv
    Instr single{};
    std::uint32_t cos_dst = kNoRegister;  ///< single sin: also cos of the same register, here
    /// Where its data starts in the pools: c (then the tails' c for a
    /// mass), reg (then the tails' registers), dst and src (a mass: src first).
    std::size_t c_at = 0, reg_at = 0, dst_at = 0, src_at = 0;
};

/// The data of a body's blocks, appended block by block:
///   lin, lin_ld: c [k][row]; reg [k] or [k][row], dst [row], src [row] (base)
///   copy, abs:   dst [row], src [row]
///   mass:        c [k][row], tail c [t][row]; reg [k], tail reg [t],
///                src (x_st), dst (x), v, acc, mag (mx) [row]
struct BlockPools {
    std::vector<double> doubles;
    std::vector<std::uint32_t> regs;
};

/// A step as run: its block's data in the body's two arrays (doubles, and
/// registers), which hold every step's data in the order the steps run.
///   lin, lin_ld: c [k][row]; reg [k] or [k][row], dst [row], src [row] (base)
///   copy, abs:   dst [row], src [row]
///   mass:        c [k][row], tail c [t][row]; reg [k], tail reg [t],
///                src (x_st), dst (x), v, acc, mag (mx) [row]
struct Step {
    std::uint8_t run = 0;  ///< the case of execute() that runs it (Run)
    std::uint32_t rows = 0, count = 0;
    std::uint32_t tail[5] = {};
    const double* c_ = nullptr;
    const std::uint32_t* reg_ = nullptr;
    const std::uint32_t* dst_ = nullptr;
    const std::uint32_t* src_ = nullptr;
    const Instr* single_ = nullptr;  ///< single: the instruction
    std::uint32_t cos_dst = kNoRegister;

    const double* c() const { return c_; }
    const double* tc() const { return c_ + static_cast<std::size_t>(count) * rows; }
    const std::uint32_t* reg() const { return reg_; }
    const std::uint32_t* treg() const { return reg_ + count; }
    const std::uint32_t* dst() const { return dst_; }
    const std::uint32_t* src() const { return src_; }
    const std::uint32_t* v() const { return dst_ + rows; }
    const std::uint32_t* acc() const { return dst_ + 2 * static_cast<std::size_t>(rows); }
    const std::uint32_t* mag() const { return dst_ + 3 * static_cast<std::size_t>(rows); }
    const Instr& single() const { return *single_; }
};

using RowRef = InterpretedSolver::RowRef;
constexpr std::uint32_t kNoStep = ~std::uint32_t{0};

}  // namespace interpreter

struct InterpretedSolver::Body {
    std::vector<interpreter::Step> steps;
    bool vector_factors = false;  ///< its modes take their factors four lanes at a time (program.h)
    std::vector<double> doubles;
    std::vector<std::uint32_t> regs;
    std::vector<interpreter::Instr> singles;
    /// Per group of four underdamped modes run as vectors (attach_lanes): their
    /// sigma, 1/omega_d, lambda and omega_d, four lanes each; the group's first
    /// step points to them (Step::c_).
    std::vector<double> lanes;
    std::size_t bytes() const {
        return sizeof(Body) + sizeof(interpreter::Step) * steps.capacity() + sizeof(double) * doubles.capacity() +
               sizeof(std::uint32_t) * regs.capacity() + sizeof(interpreter::Instr) * singles.capacity() +
               sizeof(double) * lanes.capacity();
    }
};

namespace {

using namespace interpreter;

#define ALWAYS_INLINE __attribute__((always_inline)) inline

// Eval's mode blocks are laid out by lane (lay_out_modes): four modes to a
// group, field f of a mode kLane * f registers from its first.
constexpr std::uint32_t kLane = 4;
constexpr std::uint32_t mf(std::uint32_t field) { return kLane * field; }

// ---- running ----

// The row loops below run W rows side by side (a sum per row, each in its own
// order): with AVX2 four rows are one vector operation. They are built for
// both (target_clones: the loader picks the clone the processor runs), which
// gives the same bits, as a vector lane adds and multiplies as a scalar does
// and -ffp-contract=off leaves no fused multiply-add to either. A 32-mass
// friction chain over 100 s ran 0.91x as long as without. Clang 14 refuses
// target_clones on a function template ("do not yet support function
// templates"): built with Clang (the fuzz targets, .ci/fuzz) they are built
// once, for the default target, with the same bits.
#if defined(__clang__)
#define HSNC_ROWS_CLONES
#else
#define HSNC_ROWS_CLONES __attribute__((target_clones("avx2", "default")))
#endif

// W rows of a `lin` block from `row` on: each row's sum left to right over its
// M terms (M = 0: s.count, at least 1), as a printed kernel sums it, its base
// added last.
template <int W, bool Shared, bool Base, int M>
HSNC_ROWS_CLONES void lin_rows(const Step& s, std::uint32_t row, double* r) {
    const std::uint32_t R = s.rows, m = M > 0 ? static_cast<std::uint32_t>(M) : s.count;
    const double* C = s.c() + row;
    double acc[W];
    if (Shared) {
        const std::uint32_t* I = s.reg();
        const double r0 = r[I[0]];
        for (int w = 0; w < W; ++w) acc[w] = C[w] * r0;
        for (std::uint32_t k = 1; k < m; ++k) {
            const double rk = r[I[k]];
            const double* Ck = C + static_cast<std::size_t>(k) * R;
            for (int w = 0; w < W; ++w) acc[w] += Ck[w] * rk;
        }
    } else {
        const std::uint32_t* I = s.reg() + row;
        for (int w = 0; w < W; ++w) acc[w] = C[w] * r[I[w]];
        for (std::uint32_t k = 1; k < m; ++k) {
            const double* Ck = C + static_cast<std::size_t>(k) * R;
            const std::uint32_t* Ik = I + static_cast<std::size_t>(k) * R;
            for (int w = 0; w < W; ++w) acc[w] += Ck[w] * r[Ik[w]];
        }
    }
    const std::uint32_t* D = s.dst() + row;
    if (Base) {
        const std::uint32_t* B = s.src() + row;
        for (int w = 0; w < W; ++w) r[D[w]] = r[B[w]] + acc[w];
    } else {
        for (int w = 0; w < W; ++w) r[D[w]] = acc[w];
    }
}

// W = 8 or 16 rows of a shared `lin` block (term k reads one register in
// every row), four rows to a vector (kernel_abi.h hsnc_v4d), the vectors side
// by side: the same sums, term by term, as lin_rows, written out because
// GCC's own vectorization of sixteen rows mixed vector and scalar operations.
template <int W, bool Base, int M>
HSNC_ROWS_CLONES void lin_rows_shared_wide(const Step& s, std::uint32_t row, double* r) {
    static_assert(W % 4 == 0, "four rows to a vector");
    constexpr int V = W / 4;
    const std::uint32_t R = s.rows, m = M > 0 ? static_cast<std::uint32_t>(M) : s.count;
    const double* C = s.c() + row;
    const std::uint32_t* I = s.reg();
    hsnc_v4d acc[V];
    {
        const double r0 = r[I[0]];
        for (int v = 0; v < V; ++v) {
            hsnc_v4d c;
            std::memcpy(&c, C + 4 * v, sizeof c);
            acc[v] = c * r0;
        }
    }
    for (std::uint32_t k = 1; k < m; ++k) {
        const double rk = r[I[k]];
        const double* Ck = C + static_cast<std::size_t>(k) * R;
        for (int v = 0; v < V; ++v) {
            hsnc_v4d c;
            std::memcpy(&c, Ck + 4 * v, sizeof c);
            acc[v] += c * rk;
        }
    }
    const std::uint32_t* D = s.dst() + row;
    double out[W];
    std::memcpy(out, acc, sizeof out);
    if (Base) {
        const std::uint32_t* B = s.src() + row;
        for (int w = 0; w < W; ++w) r[D[w]] = r[B[w]] + out[w];
    } else {
        for (int w = 0; w < W; ++w) r[D[w]] = out[w];
    }
}

// The same in long double, each term (long double)c * r, rounded once (no base).
template <int W, bool Shared>
inline void lin_ld_rows(const Step& s, std::uint32_t row, double* r) {
    const std::uint32_t R = s.rows, m = s.count;
    const double* C = s.c() + row;
    long double acc[W];
    if (Shared) {
        const std::uint32_t* I = s.reg();
        const long double r0 = r[I[0]];
        for (int w = 0; w < W; ++w) acc[w] = static_cast<long double>(C[w]) * r0;
        for (std::uint32_t k = 1; k < m; ++k) {
            const long double rk = r[I[k]];
            const double* Ck = C + static_cast<std::size_t>(k) * R;
            for (int w = 0; w < W; ++w) acc[w] += static_cast<long double>(Ck[w]) * rk;
        }
    } else {
        const std::uint32_t* I = s.reg() + row;
        for (int w = 0; w < W; ++w) acc[w] = static_cast<long double>(C[w]) * static_cast<long double>(r[I[w]]);
        for (std::uint32_t k = 1; k < m; ++k) {
            const double* Ck = C + static_cast<std::size_t>(k) * R;
            const std::uint32_t* Ik = I + static_cast<std::size_t>(k) * R;
            for (int w = 0; w < W; ++w) acc[w] += static_cast<long double>(Ck[w]) * static_cast<long double>(r[Ik[w]]);
        }
    }
    const std::uint32_t* D = s.dst() + row;
    for (int w = 0; w < W; ++w) r[D[w]] = static_cast<double>(acc[w]);
}

// Adds the n tail terms from term t on (t advanced past them) to W sums,
// left to right; a sum not started starts from the first of them (stays 0.0
// without any), as a printed sum does.
template <int W>
inline void tail_sum(double (&S)[W], bool started, std::uint32_t n, const double* TC, const std::uint32_t* TI,
                     std::uint32_t& t, std::uint32_t R, const double* r) {
    std::uint32_t j = 0;
    if (n > 0 && !started) {
        const double rt = r[TI[t]];
        const double* Ct = TC + static_cast<std::size_t>(t) * R;
        for (int w = 0; w < W; ++w) S[w] = Ct[w] * rt;
        j = 1;
    }
    for (; j < n; ++j) {
        const double rt = r[TI[t + j]];
        const double* Ct = TC + static_cast<std::size_t>(t + j) * R;
        for (int w = 0; w < W; ++w) S[w] += Ct[w] * rt;
    }
    t += n;
}

// W masses of a `mass` block: five sums in lockstep per mass,
//   x = x_st + sum_k c_k q_k + tail_x,    v = sum_k c_k q'_k + tail_v,    acc = sum_k c_k q''_k + tail_a,
//   mx = |x_st| + sum_k |c_k| mq_k + tail_mx,    mv = sum_k |c_k| mdq_k + tail_mv,
// each left to right; a sum without modal terms starts from its first tail
// term (0.0 without any), as a printed one does.
// Four rows (a vector, kernel_abi.h hsnc_v4d) or one row of coefficients.
template <class T>
ALWAYS_INLINE void load_rows(T& v, const double* p) {
    std::memcpy(&v, p, sizeof v);
}

// out = |v|: the sign bit cleared (a vector lane as fabs does it). By
// reference: a vector passed by value in a function built without AVX
// changes the ABI.
ALWAYS_INLINE void magnitude(const double& v, double& out) { out = __builtin_fabs(v); }
ALWAYS_INLINE void magnitude(const hsnc_v4d& v, hsnc_v4d& out) {
    hsnc_v4l bits;
    std::memcpy(&bits, &v, sizeof bits);
    bits &= 0x7fffffffffffffffll;
    std::memcpy(&out, &bits, sizeof out);
}

// The modal terms of a `mass` block's five sums, V units of T side by side
// (T = hsnc_v4d: four rows each; T = double: one), term by term in order.
template <class T, int V>
ALWAYS_INLINE void modal_sums(T (&x)[V], T (&v)[V], T (&a)[V], T (&mx)[V], T (&mv)[V], const Step& s,
                              const double* C, const double* r) {
    constexpr int L = sizeof(T) / sizeof(double);  // rows per unit
    const std::uint32_t R = s.rows;
    auto term = [&](std::uint32_t k, auto first) __attribute__((always_inline)) {
        const double* mk = r + s.reg()[k];
        const double q = mk[mf(kModeQ)], dq = mk[mf(kModeDQ)], ddq = mk[mf(kModeDDQ)], mq = mk[mf(kModeMQ)],
                     mdq = mk[mf(kModeMDQ)];
        const double* Ck = C + static_cast<std::size_t>(k) * R;
        for (int i = 0; i < V; ++i) {
            T c, ac;
            load_rows(c, Ck + L * i);
            magnitude(c, ac);
            x[i] += c * q;  // x and mx start from x_st, the others from their first term
            mx[i] += ac * mq;
            if constexpr (decltype(first)::value) {
                v[i] = c * dq;
                a[i] = c * ddq;
                mv[i] = ac * mdq;
            } else {
                v[i] += c * dq;
                a[i] += c * ddq;
                mv[i] += ac * mdq;
            }
        }
    };
    if (s.count > 0) term(0, std::true_type{});
    for (std::uint32_t k = 1; k < s.count; ++k) term(k, std::false_type{});
}

template <int W>
HSNC_ROWS_CLONES void mass_rows(const Step& s, std::uint32_t row, double* r) {
    double sx[W], sv[W], sa[W], smx[W], smv[W];
    for (int w = 0; w < W; ++w) {
        const double xst = r[s.src()[row + w]];
        sx[w] = xst;
        smx[w] = __builtin_fabs(xst);
        sv[w] = sa[w] = smv[w] = 0.0;
    }
    const double* C = s.c() + row;
    if constexpr (W % 4 == 0) {
        // Four rows to a vector: eight masses are ten sums side by side.
        hsnc_v4d x[W / 4], v[W / 4], a[W / 4], mx[W / 4], mv[W / 4];
        std::memcpy(x, sx, sizeof x), std::memcpy(v, sv, sizeof v), std::memcpy(a, sa, sizeof a);
        std::memcpy(mx, smx, sizeof mx), std::memcpy(mv, smv, sizeof mv);
        modal_sums(x, v, a, mx, mv, s, C, r);
        std::memcpy(sx, x, sizeof sx), std::memcpy(sv, v, sizeof sv), std::memcpy(sa, a, sizeof sa);
        std::memcpy(smx, mx, sizeof smx), std::memcpy(smv, mv, sizeof smv);
    } else {
        modal_sums(sx, sv, sa, smx, smv, s, C, r);
    }
    const std::uint32_t R = s.rows, m = s.count;
    const double* TC = s.tc() + row;
    const std::uint32_t* TI = s.treg();
    std::uint32_t t = 0;
    const bool started = m > 0;
    tail_sum<W>(sx, true, s.tail[0], TC, TI, t, R, r);
    tail_sum<W>(sv, started, s.tail[1], TC, TI, t, R, r);
    tail_sum<W>(sa, started, s.tail[2], TC, TI, t, R, r);
    tail_sum<W>(smx, true, s.tail[3], TC, TI, t, R, r);
    tail_sum<W>(smv, started, s.tail[4], TC, TI, t, R, r);
    for (int w = 0; w < W; ++w) {
        r[s.dst()[row + w]] = sx[w];
        r[s.v()[row + w]] = sv[w];
        r[s.acc()[row + w]] = sa[w];
        r[s.mag()[row + w]] = smx[w];
        r[s.mag()[row + w] + 1] = smv[w];
    }
}

// A block's rows from `row` on, four, then two, then one at a time.
template <template <int> class F>
inline void by_rows(const Step& s, double* r, std::uint32_t row = 0) {
    for (; row + 4 <= s.rows; row += 4) F<4>::run(s, row, r);
    if (s.rows - row >= 2) F<2>::run(s, row, r), row += 2;
    if (row < s.rows) F<1>::run(s, row, r);
}

// A block of long sums, sixteen or eight rows at a time first: a vector of
// four sums waits for its own previous addition at every term, so four
// vectors side by side go about four times as fast (a 32-mass setup, whose
// sums run over the modes, took 2.7 us at four rows). Each row still sums in
// its own order: the same bits.
template <template <int> class F>
inline void by_wide_rows(const Step& s, double* r) {
    std::uint32_t row = 0;
    for (; row + 16 <= s.rows; row += 16) F<16>::run(s, row, r);
    if (s.rows - row >= 8) F<8>::run(s, row, r), row += 8;
    by_rows<F>(s, r, row);
}

template <bool Shared, bool Base, int M>
struct Lin {
    template <int W>
    struct Rows {
        static void run(const Step& s, std::uint32_t row, double* r) {
            if constexpr (Shared && W >= 8)
                lin_rows_shared_wide<W, Base, M>(s, row, r);
            else
                lin_rows<W, Shared, Base, M>(s, row, r);
        }
    };
    ALWAYS_INLINE static void step(const Step& s, const double*, double* r) {
        if (M == 0)  // any number of terms: the long sums
            by_wide_rows<Rows>(s, r);
        else
            by_rows<Rows>(s, r);
    }
};

template <bool Shared>
struct LinLd {
    template <int W>
    struct Rows {
        static void run(const Step& s, std::uint32_t row, double* r) { lin_ld_rows<W, Shared>(s, row, r); }
    };
    ALWAYS_INLINE static void step(const Step& s, const double*, double* r) { by_rows<Rows>(s, r); }
};

template <int W>
struct MassRows {
    static void run(const Step& s, std::uint32_t row, double* r) { mass_rows<W>(s, row, r); }
};

// Masses eight at a time first (mass_rows: ten sums side by side), then as by_rows.
ALWAYS_INLINE void mass_step(const Step& s, const double*, double* r) {
    std::uint32_t row = 0;
    for (; row + 8 <= s.rows; row += 8) mass_rows<8>(s, row, r);
    by_rows<MassRows>(s, r, row);
}

// Linear combinations without terms: 0.0, or the base + 0.0.
template <bool Base>
ALWAYS_INLINE void lin_empty_step(const Step& s, const double*, double* r) {
    for (std::uint32_t i = 0; i < s.rows; ++i) r[s.dst()[i]] = Base ? r[s.src()[i]] + 0.0 : 0.0;
}

ALWAYS_INLINE void lin_ld_empty_step(const Step& s, const double*, double* r) {
    for (std::uint32_t i = 0; i < s.rows; ++i) r[s.dst()[i]] = static_cast<double>(0.0L);
}

ALWAYS_INLINE void copy_step(const Step& s, const double*, double* r) {
    for (std::uint32_t i = 0; i < s.rows; ++i) r[s.dst()[i]] = r[s.src()[i]];
}

ALWAYS_INLINE void abs_step(const Step& s, const double*, double* r) {
    for (std::uint32_t i = 0; i < s.rows; ++i) r[s.dst()[i]] = __builtin_fabs(r[s.src()[i]]);
}

/// What runs a step: one case of execute()'s switch. kLin + 10 shared + 5 base
/// + M: linear combinations of M terms (0: any number).
enum Run : std::uint8_t {
    kSingle,
    kSinCos,
    kHarmonic,
    kMode,  // + ProgramRegime
    kLinEmpty = kMode + 6,
    kLinEmptyBase,
    kLdEmpty,
    kCopy,
    kAbs,
    kMass,
    kLd,
    kLdShared,
    kLin,
    kRuns = kLin + 20
};

// Each case below computes what generator/emitter.cpp (BodyPrinter) prints for
// the instruction, operation for operation: change both or neither.
// Whether a step is a mode whose regime takes factors (program.h
// takes_factors): undamped, underdamped or critical (Run kMode + regime).
constexpr bool factored_run(std::uint8_t run) { return run >= kMode && run <= kMode + 2; }

// The arguments of mode step s's factors: -sigma tau and omega_d tau, as the
// printed kernel writes them (0.0 for the one its regime does not use).
ALWAYS_INLINE void factor_arguments(const Step& s, const double* K, const double* r, double& xe, double& xt) {
    const Instr& in = s.single();
    const double* k = K + in.first;
    const double tau = r[in.b];
    const auto regime = static_cast<ProgramRegime>(in.regime);
    xe = regime == ProgramRegime::undamped ? 0.0 : -k[kModeSigma] * tau;
    xt = regime == ProgramRegime::critical ? 0.0 : k[kModeOmegaD] * tau;
}

// One mode's homogeneous response at tau (ProgramOp::mode), its regime fixed.
// Given: e, sn, cs are its factors e^{-sigma tau}, sin and cos(omega_d tau)
// where the regime takes them (undamped: sin, cos; underdamped: all three;
// critical: e; program.h vector_factors), else libm computes them here.
template <ProgramRegime Regime, bool Given = false>
ALWAYS_INLINE void mode_step(const Step& s, const double* K, double* r, double e = 0.0, double sn = 0.0,
                             double cs = 0.0) {
    const Instr& in = s.single();
    const double* k = K + in.first;
    const double* A = r + in.a;  // A, B, A1, B1, A2, B2
    double* o = r + in.dst;
    const double tau = r[in.b];
    double eC = 0.0, eS = 0.0;
    if (Regime == ProgramRegime::undamped) {
        eC = Given ? cs : __builtin_cos(k[kModeOmegaD] * tau);
        eS = (Given ? sn : __builtin_sin(k[kModeOmegaD] * tau)) * k[kModeInvOmegaD];
    } else if (Regime == ProgramRegime::underdamped) {
        if (!Given) {
            e = __builtin_exp(-k[kModeSigma] * tau);
            cs = __builtin_cos(k[kModeOmegaD] * tau);
            sn = __builtin_sin(k[kModeOmegaD] * tau);
        }
        o[mf(kModeAux)] = e;
        eC = e * cs;
        eS = e * sn * k[kModeInvOmegaD];
    } else if (Regime == ProgramRegime::critical) {
        eC = Given ? e : __builtin_exp(-k[kModeSigma] * tau);
        eS = tau * eC;
    } else if (Regime == ProgramRegime::overdamped) {
        const double ex = __builtin_exp(k[kModeR1] * tau);
        const double m = __builtin_expm1(k[kModeNegTwoGamma] * tau);
        o[mf(kModeAux)] = ex;
        o[mf(kModeAux2)] = m;
        eC = ex * (1.0 + 0.5 * m);
        eS = -ex * m * k[kModeHalfInvGamma];
    } else if (Regime == ProgramRegime::rigid) {
        eC = 1.0;
        eS = tau;
    } else {  // rigid_damped
        const double m = __builtin_expm1(-k[kModeC] * tau);
        o[mf(kModeAux)] = m;
        eC = 1.0 + 0.5 * m;
        eS = -m * k[kModeInvC];
    }
    o[mf(kModeEC)] = eC;
    o[mf(kModeES)] = eS;
    const double q = A[0] * eC + A[1] * eS;
    const double dq = A[2] * eC + A[3] * eS;
    o[mf(kModeQ)] = q;
    o[mf(kModeDQ)] = dq;
    o[mf(kModeDDQ)] = A[4] * eC + A[5] * eS;
    o[mf(kModeR)] = __builtin_sqrt(dq * dq + k[kModeLambda] * q * q);
    o[mf(kModeMQ)] = __builtin_fabs(A[0] * eC) + __builtin_fabs(A[1] * eS);
    o[mf(kModeMDQ)] = __builtin_fabs(A[2] * eC) + __builtin_fabs(A[3] * eS);
    // + |sigma A eC|: A1 = B - sigma A cancels (generator/emitter.cpp, mode()).
    if (k[kModeSigma] != 0.0) o[mf(kModeMDQ)] = o[mf(kModeMDQ)] + __builtin_fabs(k[kModeSigma] * A[0] * eC);
}

// sin and cos of one register (ProgramOp::sin and ProgramOp::cos).
ALWAYS_INLINE void sincos_step(const Step& s, const double*, double* r) {
    const double x = r[s.single().a];
    r[s.single().dst] = __builtin_sin(x);
    r[s.cos_dst] = __builtin_cos(x);
}

// A forcing harmonic at tau (ProgramOp::harmonic).
ALWAYS_INLINE void harmonic_step(const Step& s, const double* K, double* r) {
    const Instr& in = s.single();
    const double arg = K[in.first] * r[in.b] + r[in.a];
    r[in.dst] = arg;
    r[in.dst + 1] = __builtin_sin(arg);
    r[in.dst + 2] = __builtin_cos(arg);
}

ALWAYS_INLINE void single_step(const Step& s, const double* K, double* r) {
    const Instr& in = s.single();
    switch (in.op) {
        case ProgramOp::sin: r[in.dst] = __builtin_sin(r[in.a]); break;
        case ProgramOp::cos: r[in.dst] = __builtin_cos(r[in.a]); break;
        case ProgramOp::phase: r[in.dst] = hsnc_phase(K[in.first], r[in.a], r[in.b], K[in.first + 1]); break;
        case ProgramOp::rigid_particular: {
            double* m = r + in.c;
            const double P = r[in.a], tau = r[in.b];
            m[mf(kModeQ)] += 0.5 * P * tau * tau;
            m[mf(kModeDQ)] += P * tau;
            m[mf(kModeDDQ)] += P;
            m[mf(kModeMQ)] += __builtin_fabs(0.5 * P * tau * tau);
            m[mf(kModeMDQ)] += __builtin_fabs(P * tau);
            break;
        }
        case ProgramOp::rigid_damped_particular: {
            double* m = r + in.c;
            const double P = r[in.a], tau = r[in.b];
            const double qp = P * tau * tau * hsnc_phi2(-K[in.first] * tau);
            r[in.dst] = qp;
            m[mf(kModeQ)] += qp;
            m[mf(kModeDQ)] += P * m[mf(kModeES)];
            m[mf(kModeDDQ)] += P * (1.0 + m[mf(kModeAux)]);
            m[mf(kModeMQ)] += __builtin_fabs(qp);
            m[mf(kModeMDQ)] += __builtin_fabs(P * m[mf(kModeES)]);
            break;
        }
        case ProgramOp::resonant: {
            const double* k = K + in.first;
            double* m = r + in.c;
            double* o = r + in.dst;
            const double tau = r[in.b], ct = r[in.d];
            double w = tau, dw = 1.0;
            if (k[kResHalfDiff] != 0.0) {
                w = __builtin_sin(k[kResHalfDiff] * tau) * k[kResInvHalfDiff];
                dw = __builtin_cos(k[kResHalfDiff] * tau);
            }
            const double arg = k[kResMean] * tau + r[in.a];
            const double Cb = __builtin_cos(arg), Sb = __builtin_sin(arg);
            const double eC = m[mf(kModeEC)], eS = m[mf(kModeES)];
            const double y = k[kResQ] * (ct * eS - w * Cb);
            const double dy = k[kResQ] * (ct * eC - dw * Cb + k[kResMean] * w * Sb);
            const double ddy =
                k[kResQ] * (k[kResH2W2] * w * Cb + k[kResTwoMean] * dw * Sb - k[kResLambda] * ct * eS);
            o[0] = w, o[1] = dw, o[2] = Cb, o[3] = Sb, o[4] = y, o[5] = dy, o[6] = ddy;
            m[mf(kModeQ)] += y;
            m[mf(kModeDQ)] += dy;
            m[mf(kModeDDQ)] += ddy;
            // The magnitude of the terms (y and y' cancel to ~tau^3 near tau = 0).
            const double Q = __builtin_fabs(k[kResQ]);
            m[mf(kModeMQ)] += Q * (__builtin_fabs(ct * eS) + __builtin_fabs(w * Cb));
            m[mf(kModeMDQ)] += Q * (__builtin_fabs(ct * eC) + __builtin_fabs(dw * Cb) + __builtin_fabs(k[kResMean] * w * Sb));
            break;
        }
        default: break;  // mode, harmonic: their own steps; lincomb, lincomb_ld, copy, abs, mass_state: blocks
    }
}

// Whether steps s[0 .. kLane) are underdamped modes in the lanes of one group
// (lay_out_modes): their fields are then vectors.
ALWAYS_INLINE bool lanes_of_one_group(const Step* s) {
    for (std::uint32_t l = 1; l < kLane; ++l)
        if (s[l].run != kMode + 1 || s[l].single().dst != s[0].single().dst + l) return false;
    return true;
}

// Marks each group of four underdamped modes in one group's lanes (from the
// first such step on, greedily, as factored_modes meets them) with its
// constants by lane in the body (Body::lanes).
void attach_lanes(InterpretedSolver::Body& body, const double* K) {
    std::vector<Step>& st = body.steps;
    std::vector<std::size_t> firsts;
    for (std::size_t i = 0; i + kLane <= st.size(); ++i)
        if (st[i].run == kMode + 1 && lanes_of_one_group(&st[i])) firsts.push_back(i), i += kLane - 1;
    body.lanes.assign(4 * kLane * firsts.size(), 0.0);
    for (std::size_t g = 0; g < firsts.size(); ++g) {
        double* out = body.lanes.data() + 4 * kLane * g;
        for (std::uint32_t l = 0; l < kLane; ++l) {
            const double* k = K + st[firsts[g] + l].single().first;
            out[l] = k[kModeSigma], out[kLane + l] = k[kModeInvOmegaD], out[2 * kLane + l] = k[kModeLambda];
            out[3 * kLane + l] = k[kModeOmegaD];
        }
        st[firsts[g]].c_ = out;
    }
}

// Four underdamped modes' steps as mode_step computes each, lane by lane: the
// same operations on the same operands, so the same bits.
ALWAYS_INLINE void underdamped_lanes(const Step* s, double* r, const double* e, const double* sn, const double* cs) {
    hsnc_v4d A0, A1, A2, A3, A4, A5, sigma, inv_omega, lambda, E, S, C;
    for (std::uint32_t l = 0; l < kLane; ++l) {
        const double* A = r + s[l].single().a;
        A0[l] = A[0], A1[l] = A[1], A2[l] = A[2], A3[l] = A[3], A4[l] = A[4], A5[l] = A[5];
    }
    const double* k = s->c();  // attach_lanes
    std::memcpy(&sigma, k, sizeof sigma), std::memcpy(&inv_omega, k + kLane, sizeof inv_omega);
    std::memcpy(&lambda, k + 2 * kLane, sizeof lambda);
    std::memcpy(&E, e, sizeof E), std::memcpy(&S, sn, sizeof S), std::memcpy(&C, cs, sizeof C);
    const hsnc_v4d eC = E * C, eS = E * S * inv_omega;
    const hsnc_v4d q = A0 * eC + A1 * eS, dq = A2 * eC + A3 * eS, ddq = A4 * eC + A5 * eS;
    const hsnc_v4d rr = dq * dq + lambda * q * q;
    hsnc_v4d R;
    for (std::uint32_t l = 0; l < kLane; ++l) R[l] = __builtin_sqrt(rr[l]);
    hsnc_v4d m0, m1, m2, m3, ms;
    magnitude(A0 * eC, m0), magnitude(A1 * eS, m1), magnitude(A2 * eC, m2), magnitude(A3 * eS, m3);
    magnitude(sigma * A0 * eC, ms);
    const hsnc_v4d mq = m0 + m1, mdq0 = m2 + m3, mdq1 = mdq0 + ms;
    const hsnc_v4d mdq = sigma != 0.0 ? mdq1 : mdq0;  // + |sigma A eC| where sigma is not 0, as mode_step
    double* o = r + s[0].single().dst;
    auto put = [&](std::uint32_t field, const hsnc_v4d& v) { std::memcpy(o + mf(field), &v, sizeof v); };
    put(kModeAux, E), put(kModeEC, eC), put(kModeES, eS), put(kModeQ, q), put(kModeDQ, dq), put(kModeDDQ, ddq);
    put(kModeR, R), put(kModeMQ, mq), put(kModeMDQ, mdq);
}

// The consecutive mode steps of the factored regimes from `first` (up to
// kFactorBatch), in a body whose modes take vector factors: their factors at
// once, then each step. Returns the step after them. Built for AVX2 too (the
// steps' scalar arithmetic in VEX form: the same operations, the same bits).
constexpr std::size_t kFactorBatch = 64;
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"  // xe, xt: set up to m, padded to a multiple of 4
HSNC_ROWS_CLONES const Step* factored_modes(const Step* first, const Step* end, const double* K, double* r) {
    double xe[kFactorBatch], xt[kFactorBatch], e[kFactorBatch], sn[kFactorBatch], cs[kFactorBatch];
    const Step* last = first;
    std::size_t m = 0;
    bool exp = false;
    while (last != end && m < kFactorBatch && factored_run(last->run)) {
        if (last->run == kMode + 1 && last->c_ && end - last >= static_cast<std::ptrdiff_t>(kLane) &&
            m + kLane <= kFactorBatch) {
            // A lane group (attach_lanes): -sigma tau and omega_d tau as factor_arguments.
            const double tau = r[last->single().b];
            for (std::uint32_t l = 0; l < kLane; ++l)
                xe[m + l] = -last->c()[l] * tau, xt[m + l] = last->c()[3 * kLane + l] * tau;
            last += kLane, m += kLane;
            exp = true;
            continue;
        }
        factor_arguments(*last, K, r, xe[m], xt[m]);
        exp = exp || last->run != kMode + 0;
        ++last, ++m;
    }
    for (std::size_t pad = m; pad % 4 != 0; ++pad) xe[pad] = xt[pad] = 0.0;
    bool at_zero = true;  // a segment's start: e^0, sin 0, cos 0 are 1, 0, 1, as the helpers give them
    for (std::size_t i = 0; i < m; ++i) at_zero = at_zero && xe[i] == 0.0 && xt[i] == 0.0;
    if (at_zero)
        for (std::size_t i = 0; i < m; ++i) e[i] = 1.0, sn[i] = 0.0, cs[i] = 1.0;
    else
        mode_factors(xe, xt, e, sn, cs, (m + 3) / 4 * 4, exp);
    m = 0;
    for (const Step* s = first; s != last; ++s, ++m) {
        if (s->run == kMode + 1 && s->c_ && last - s >= static_cast<std::ptrdiff_t>(kLane)) {
            underdamped_lanes(s, r, e + m, sn + m, cs + m);
            s += kLane - 1, m += kLane - 1;
            continue;
        }
        switch (s->run) {
            case kMode + 0: mode_step<ProgramRegime::undamped, true>(*s, K, r, 0.0, sn[m], cs[m]); break;
            case kMode + 1: mode_step<ProgramRegime::underdamped, true>(*s, K, r, e[m], sn[m], cs[m]); break;
            default: mode_step<ProgramRegime::critical, true>(*s, K, r, e[m], 0.0, 0.0); break;
        }
    }
    return last;
}
#pragma GCC diagnostic pop

// One step of a body, everything inlined: no call and no prologue per step.
ALWAYS_INLINE void run_step(const Step& s, const double* K, double* r) {
    switch (s.run) {
        case kSingle: single_step(s, K, r); break;
        case kSinCos: sincos_step(s, K, r); break;
        case kHarmonic: harmonic_step(s, K, r); break;
        case kMode + 0: mode_step<ProgramRegime::undamped>(s, K, r); break;
        case kMode + 1: mode_step<ProgramRegime::underdamped>(s, K, r); break;
        case kMode + 2: mode_step<ProgramRegime::critical>(s, K, r); break;
        case kMode + 3: mode_step<ProgramRegime::overdamped>(s, K, r); break;
        case kMode + 4: mode_step<ProgramRegime::rigid>(s, K, r); break;
        case kMode + 5: mode_step<ProgramRegime::rigid_damped>(s, K, r); break;
        case kLinEmpty: lin_empty_step<false>(s, K, r); break;
        case kLinEmptyBase: lin_empty_step<true>(s, K, r); break;
        case kLdEmpty: lin_ld_empty_step(s, K, r); break;
        case kCopy: copy_step(s, K, r); break;
        case kAbs: abs_step(s, K, r); break;
        case kMass: mass_step(s, K, r); break;
        case kLd: LinLd<false>::step(s, K, r); break;
        case kLdShared: LinLd<true>::step(s, K, r); break;
        case kLin + 0: Lin<false, false, 0>::step(s, K, r); break;
        case kLin + 1: Lin<false, false, 1>::step(s, K, r); break;
        case kLin + 2: Lin<false, false, 2>::step(s, K, r); break;
        case kLin + 3: Lin<false, false, 3>::step(s, K, r); break;
        case kLin + 4: Lin<false, false, 4>::step(s, K, r); break;
        case kLin + 5: Lin<false, true, 0>::step(s, K, r); break;
        case kLin + 6: Lin<false, true, 1>::step(s, K, r); break;
        case kLin + 7: Lin<false, true, 2>::step(s, K, r); break;
        case kLin + 8: Lin<false, true, 3>::step(s, K, r); break;
        case kLin + 9: Lin<false, true, 4>::step(s, K, r); break;
        case kLin + 10: Lin<true, false, 0>::step(s, K, r); break;
        case kLin + 11: Lin<true, false, 1>::step(s, K, r); break;
        case kLin + 12: Lin<true, false, 2>::step(s, K, r); break;
        case kLin + 13: Lin<true, false, 3>::step(s, K, r); break;
        case kLin + 14: Lin<true, false, 4>::step(s, K, r); break;
        case kLin + 15: Lin<true, true, 0>::step(s, K, r); break;
        case kLin + 16: Lin<true, true, 1>::step(s, K, r); break;
        case kLin + 17: Lin<true, true, 2>::step(s, K, r); break;
        case kLin + 18: Lin<true, true, 3>::step(s, K, r); break;
        case kLin + 19: Lin<true, true, 4>::step(s, K, r); break;
        default: break;
    }
}

void execute(const double* K, const InterpretedSolver::Body& body, double* r) {
    const Step* const end = body.steps.data() + body.steps.size();
    for (const Step* it = body.steps.data(); it != end;) {
        const Step& s = *it;
        if (body.vector_factors && factored_run(s.run)) {
            it = factored_modes(it, end, K, r);
            continue;
        }
        ++it;
        run_step(s, K, r);
    }
}

// One row of a batched step (lin, lin_ld, copy, abs, mass), as its block
// computes it: the rows of a block are independent sums.
template <bool Shared, bool Base, int M>
void lin_row(const Step& s, std::uint32_t row, double* r) {
    lin_rows<1, Shared, Base, M>(s, row, r);
}

using RowFn = void (*)(const Step&, std::uint32_t, double*);

constexpr RowFn lin_row_fn(int k) {
    constexpr RowFn fns[20] = {
        lin_row<false, false, 0>, lin_row<false, false, 1>, lin_row<false, false, 2>, lin_row<false, false, 3>,
        lin_row<false, false, 4>, lin_row<false, true, 0>,  lin_row<false, true, 1>,  lin_row<false, true, 2>,
        lin_row<false, true, 3>,  lin_row<false, true, 4>,  lin_row<true, false, 0>,  lin_row<true, false, 1>,
        lin_row<true, false, 2>,  lin_row<true, false, 3>,  lin_row<true, false, 4>,  lin_row<true, true, 0>,
        lin_row<true, true, 1>,   lin_row<true, true, 2>,   lin_row<true, true, 3>,   lin_row<true, true, 4>};
    return fns[k];
}

void run_row(const Step& s, std::uint32_t row, double* r) {
    switch (s.run) {
        case kLinEmpty: r[s.dst()[row]] = 0.0; break;
        case kLinEmptyBase: r[s.dst()[row]] = r[s.src()[row]] + 0.0; break;
        case kLdEmpty: r[s.dst()[row]] = static_cast<double>(0.0L); break;
        case kCopy: r[s.dst()[row]] = r[s.src()[row]]; break;
        case kAbs: r[s.dst()[row]] = __builtin_fabs(r[s.src()[row]]); break;
        case kMass: mass_rows<1>(s, row, r); break;
        case kLd: lin_ld_rows<1, false>(s, row, r); break;
        case kLdShared: lin_ld_rows<1, true>(s, row, r); break;
        default:
            if (s.run >= kLin && s.run < kRuns) lin_row_fn(s.run - kLin)(s, row, r);
            break;  // single steps are never a function's row (rows_by_function)
    }
}

// ---- scheduling: registers each instruction reads and writes ----

// Calls read(register) for every register an instruction reads and
// write(register) for every one it writes, in a fixed order.
template <class Read, class Write>
ALWAYS_INLINE void visit_accesses(const Instr& in, const std::vector<ProgramTerm>& terms, Read&& read, Write&& write) {
    auto block = [](auto&& to, std::uint32_t base, std::initializer_list<std::uint32_t> regs) {
        for (std::uint32_t k : regs) to(base + k);
    };
    const std::initializer_list<std::uint32_t> sums = {mf(kModeQ), mf(kModeDQ), mf(kModeDDQ), mf(kModeMQ),
                                                       mf(kModeMDQ)};
    switch (in.op) {
        case ProgramOp::lincomb:
        case ProgramOp::lincomb_ld:
            for (std::uint32_t k = 0; k < in.count; ++k) read(terms[in.first + k].reg);
            if (in.op == ProgramOp::lincomb && in.a != kNoRegister) read(in.a);
            write(in.dst);
            break;
        case ProgramOp::copy:
        case ProgramOp::abs:
        case ProgramOp::sin:
        case ProgramOp::cos:
            read(in.a);
            write(in.dst);
            break;
        case ProgramOp::phase:
            read(in.a);
            read(in.b);
            write(in.dst);
            break;
        case ProgramOp::harmonic:
            read(in.a);
            read(in.b);
            block(write, in.dst, {0, 1, 2});
            break;
        case ProgramOp::mode:
            for (std::uint32_t k = 0; k < 6; ++k) read(in.a + k);
            read(in.b);
            for (std::uint32_t k = 0; k < kModeRegisters; ++k) write(in.dst + mf(k));
            break;
        case ProgramOp::rigid_particular:
            read(in.a);
            read(in.b);
            block(read, in.c, sums);
            block(write, in.c, sums);
            break;
        case ProgramOp::rigid_damped_particular:
            read(in.a);
            read(in.b);
            block(read, in.c, sums);
            block(read, in.c, {mf(kModeES), mf(kModeAux)});
            write(in.dst);
            block(write, in.c, sums);
            break;
        case ProgramOp::resonant:
            read(in.a);
            read(in.b);
            read(in.d);
            block(read, in.c, sums);
            block(read, in.c, {mf(kModeEC), mf(kModeES)});
            block(write, in.dst, {0, 1, 2, 3, 4, 5, 6});
            block(write, in.c, sums);
            break;
        case ProgramOp::mass_state: {
            read(in.a);
            for (std::uint32_t k = 0; k < in.count; ++k) block(read, terms[in.first + k].reg, sums);
            const std::uint32_t tails = in.tail[0] + in.tail[1] + in.tail[2] + in.tail[3] + in.tail[4];
            for (std::uint32_t k = 0; k < tails; ++k) read(terms[in.first + in.count + k].reg);
            write(in.dst);
            write(in.b);
            write(in.c);
            write(in.d);
            write(in.d + 1);
            break;
        }
    }
}

/// Whether an instruction runs in a block with others of its level.
bool batched(ProgramOp op) {
    return op == ProgramOp::lincomb || op == ProgramOp::lincomb_ld || op == ProgramOp::copy || op == ProgramOp::abs ||
           op == ProgramOp::mass_state;
}

/// What instructions of one level must share to run as one block: the op, the
/// number of terms, a base (lincomb); for mass_state also the tails' lengths
/// and every term's register (the mode blocks, the tails' registers).
bool same_shape(const Instr& a, const Instr& b, const std::vector<ProgramTerm>& terms) {
    if (a.op != b.op) return false;
    switch (a.op) {
        case ProgramOp::lincomb: return a.count == b.count && (a.a != kNoRegister) == (b.a != kNoRegister);
        case ProgramOp::lincomb_ld: return a.count == b.count;
        case ProgramOp::mass_state: {
            if (a.count != b.count) return false;
            std::uint32_t n = a.count;
            for (int q = 0; q < 5; ++q) {
                if (a.tail[q] != b.tail[q]) return false;
                n += a.tail[q];
            }
            for (std::uint32_t t = 0; t < n; ++t)
                if (terms[a.first + t].reg != terms[b.first + t].reg) return false;
            return true;
        }
        default: return true;
    }
}

/// A hash of what same_shape compares.
std::uint64_t shape_hash(const Instr& in, const std::vector<ProgramTerm>& terms) {
    std::uint64_t h = 1469598103934665603ull;
    auto mix = [&h](std::uint64_t v) { h = (h ^ v) * 1099511628211ull; };
    mix(static_cast<std::uint64_t>(in.op));
    switch (in.op) {
        case ProgramOp::lincomb: mix(in.count), mix(in.a != kNoRegister); break;
        case ProgramOp::lincomb_ld: mix(in.count); break;
        case ProgramOp::mass_state: {
            std::uint32_t n = in.count;
            mix(in.count);
            for (int q = 0; q < 5; ++q) mix(in.tail[q]), n += in.tail[q];
            for (std::uint32_t t = 0; t < n; ++t) mix(terms[in.first + t].reg);
            break;
        }
        default: break;
    }
    return h;
}

/// The block of the R instructions rows[0 .. R) (one level, one shape), its
/// data appended to `pools`.
Block make_block(const Instr* const* rows, std::uint32_t R, const std::vector<ProgramTerm>& terms, BlockPools& pools) {
    const Instr& f = *rows[0];
    std::vector<double>& dbl = pools.doubles;
    std::vector<std::uint32_t>& reg = pools.regs;
    Block s;
    s.rows = R;
    s.c_at = dbl.size();
    s.reg_at = reg.size();
    switch (f.op) {
        case ProgramOp::lincomb:
        case ProgramOp::lincomb_ld: {
            s.kind = f.op == ProgramOp::lincomb ? StepKind::lin : StepKind::lin_ld;
            s.count = f.count;
            s.has_base = f.op == ProgramOp::lincomb && f.a != kNoRegister;
            s.shared = true;
            for (std::uint32_t k = 0; k < s.count && s.shared; ++k)
                for (std::uint32_t row = 0; row < R; ++row)
                    s.shared = s.shared && terms[rows[row]->first + k].reg == terms[f.first + k].reg;
            const std::size_t nc = static_cast<std::size_t>(s.count) * R;
            dbl.resize(s.c_at + nc);
            reg.resize(s.reg_at + (s.shared ? s.count : nc));
            s.dst_at = reg.size();
            s.src_at = s.dst_at + R;
            reg.resize(s.src_at + (s.has_base ? R : 0));
            double* c = dbl.data() + s.c_at;
            std::uint32_t* rg = reg.data() + s.reg_at;
            for (std::uint32_t row = 0; row < R; ++row) {
                const Instr& in = *rows[row];
                for (std::uint32_t k = 0; k < s.count; ++k) {
                    const ProgramTerm& t = terms[in.first + k];
                    c[static_cast<std::size_t>(k) * R + row] = t.c;
                    rg[s.shared ? k : static_cast<std::size_t>(k) * R + row] = t.reg;
                }
                reg[s.dst_at + row] = in.dst;
                if (s.has_base) reg[s.src_at + row] = in.a;
            }
            break;
        }
        case ProgramOp::copy:
        case ProgramOp::abs:
            s.kind = f.op == ProgramOp::copy ? StepKind::copy : StepKind::abs;
            s.dst_at = reg.size();
            s.src_at = s.dst_at + R;
            for (std::uint32_t row = 0; row < R; ++row) reg.push_back(rows[row]->dst);
            for (std::uint32_t row = 0; row < R; ++row) reg.push_back(rows[row]->a);
            break;
        case ProgramOp::mass_state: {
            s.kind = StepKind::mass;
            s.count = f.count;
            std::uint32_t tails = 0;
            for (int q = 0; q < 5; ++q) s.tail[q] = f.tail[q], tails += f.tail[q];
            const std::size_t nc = static_cast<std::size_t>(s.count) * R;
            dbl.resize(s.c_at + nc + static_cast<std::size_t>(tails) * R);
            double* c = dbl.data() + s.c_at;
            double* tc = c + nc;
            for (std::uint32_t k = 0; k < s.count; ++k) reg.push_back(terms[f.first + k].reg);
            for (std::uint32_t t = 0; t < tails; ++t) reg.push_back(terms[f.first + s.count + t].reg);
            s.src_at = reg.size();
            s.dst_at = s.src_at + R;
            reg.resize(s.src_at + 5 * static_cast<std::size_t>(R));  // src, dst, v, acc, mag
            std::uint32_t* src = reg.data() + s.src_at;
            for (std::uint32_t row = 0; row < R; ++row) {
                const Instr& in = *rows[row];
                for (std::uint32_t k = 0; k < s.count; ++k) {
                    c[static_cast<std::size_t>(k) * R + row] = terms[in.first + k].c;
                }
                for (std::uint32_t t = 0; t < tails; ++t)
                    tc[static_cast<std::size_t>(t) * R + row] = terms[in.first + s.count + t].c;
                src[row] = in.a;
                src[R + row] = in.dst;
                src[2 * R + row] = in.b;
                src[3 * R + row] = in.c;
                src[4 * R + row] = in.d;
            }
            break;
        }
        default: break;
    }
    return s;
}

// Registers read as part of a block (a mode's coefficients and registers, a
// harmonic's, a resonant term's): never renamed.
void mark_blocks(const Instr& in, const std::vector<ProgramTerm>& terms, std::vector<char>& block) {
    auto mark = [&](std::uint32_t base, std::uint32_t n) {
        for (std::uint32_t k = 0; k < n; ++k) block[base + k] = 1;
    };
    auto mark_mode = [&](std::uint32_t base) {  // a mode block, laid out by lane
        for (std::uint32_t k = 0; k < kModeRegisters; ++k) block[base + mf(k)] = 1;
    };
    switch (in.op) {
        case ProgramOp::mode: mark(in.a, 6), mark_mode(in.dst); break;
        case ProgramOp::harmonic: mark(in.dst, 3); break;
        case ProgramOp::rigid_particular:
        case ProgramOp::rigid_damped_particular: mark_mode(in.c); break;
        case ProgramOp::resonant: mark_mode(in.c), mark(in.dst, 7); break;
        case ProgramOp::mass_state:
            for (std::uint32_t k = 0; k < in.count; ++k) mark_mode(terms[in.first + k].reg);
            break;
        default: break;
    }
}

// Applies `to` to every register an instruction reads as a single value.
void rename_reads(Instr& in, std::vector<ProgramTerm>& terms, const std::vector<std::uint32_t>& to) {
    auto re = [&](std::uint32_t& r) {
        if (r != kNoRegister) r = to[r];
    };
    switch (in.op) {
        case ProgramOp::lincomb:
        case ProgramOp::lincomb_ld:
            for (std::uint32_t k = 0; k < in.count; ++k) re(terms[in.first + k].reg);
            re(in.a);
            break;
        case ProgramOp::copy:
        case ProgramOp::abs:
        case ProgramOp::sin:
        case ProgramOp::cos: re(in.a); break;
        case ProgramOp::phase:
        case ProgramOp::harmonic:
        case ProgramOp::rigid_particular:
        case ProgramOp::rigid_damped_particular: re(in.a), re(in.b); break;
        case ProgramOp::mode: re(in.b); break;
        case ProgramOp::resonant: re(in.a), re(in.b), re(in.d); break;
        case ProgramOp::mass_state: {
            re(in.a);
            const std::uint32_t tails = in.tail[0] + in.tail[1] + in.tail[2] + in.tail[3] + in.tail[4];
            for (std::uint32_t k = 0; k < tails; ++k) re(terms[in.first + in.count + k].reg);
            break;
        }
    }
}

// Copies forwarded: a copy into a register written only by it, not part of a
// block and not in [pinned_begin, pinned_end) (eval's outputs), from a
// register written at most once and before it, is dropped, and what read its
// destination reads its source (`exported`, setup's coefficient registers,
// too). A copy changes no bit.
void forward_copies(std::vector<Instr>& code, std::vector<ProgramTerm>& terms, std::size_t registers,
                    std::uint32_t pinned_begin, std::uint32_t pinned_end, std::vector<std::uint32_t>& exported) {
    std::vector<int> writes(registers, 0), writer(registers, -1);
    std::vector<char> block(registers, 0);
    for (std::size_t i = 0; i < code.size(); ++i) {
        visit_accesses(
            code[i], terms, [](std::uint32_t) {}, [&](std::uint32_t w) { ++writes[w], writer[w] = static_cast<int>(i); });
        mark_blocks(code[i], terms, block);
    }
    std::vector<std::uint32_t> to(registers);
    for (std::size_t r = 0; r < registers; ++r) to[r] = static_cast<std::uint32_t>(r);
    std::vector<char> drop(code.size(), 0);
    bool any = false;
    for (std::size_t i = 0; i < code.size(); ++i) {
        const Instr& in = code[i];
        if (in.op != ProgramOp::copy) continue;
        const std::uint32_t d = in.dst, a = in.a;
        const bool source_fixed = writes[a] == 0 || (writes[a] == 1 && writer[a] < static_cast<int>(i));
        if (writes[d] == 1 && !block[d] && !block[a] && source_fixed && !(d >= pinned_begin && d < pinned_end)) {
            to[d] = to[a];
            drop[i] = 1;
            any = true;
        }
    }
    if (!any) return;
    std::vector<Instr> kept;
    kept.reserve(code.size());
    for (std::size_t i = 0; i < code.size(); ++i) {
        if (drop[i]) continue;
        kept.push_back(code[i]);
        rename_reads(kept.back(), terms, to);
    }
    code = std::move(kept);
    for (std::uint32_t& e : exported) e = to[e];
}

/// The case of execute() that runs step `s`.
std::uint8_t pick(const Block& s) {
    switch (s.kind) {
        case StepKind::single:
            if (s.single.op == ProgramOp::harmonic) return kHarmonic;
            if (s.single.op == ProgramOp::sin && s.cos_dst != kNoRegister) return kSinCos;
            if (s.single.op == ProgramOp::mode) return static_cast<std::uint8_t>(kMode + s.single.regime);
            return kSingle;
        case StepKind::lin:
            if (s.count == 0) return s.has_base ? kLinEmptyBase : kLinEmpty;
            return static_cast<std::uint8_t>(kLin + (s.shared ? 10 : 0) + (s.has_base ? 5 : 0) +
                                             (s.count <= 4 ? s.count : 0));
        case StepKind::lin_ld:
            if (s.count == 0) return kLdEmpty;
            return s.shared ? kLdShared : kLd;
        case StepKind::copy: return kCopy;
        case StepKind::abs: return kAbs;
        case StepKind::mass: return kMass;
    }
    return kSingle;
}

/// The blocks as run: the pools become the body's arrays, which the steps
/// point into.
std::unique_ptr<InterpretedSolver::Body> freeze(const std::vector<Block>& blocks, BlockPools& pools) {
    auto body = std::make_unique<InterpretedSolver::Body>();
    body->doubles = std::move(pools.doubles);
    body->regs = std::move(pools.regs);
    body->doubles.shrink_to_fit();  // the memory budget counts capacity
    body->regs.shrink_to_fit();
    std::size_t ns = 0;
    for (const Block& b : blocks) ns += b.kind == StepKind::single;
    body->singles.reserve(ns);  // no reallocation below: the steps point into it
    body->steps.reserve(blocks.size());
    for (const Block& b : blocks) {
        Step s;
        s.run = pick(b);
        s.rows = b.rows;
        s.count = b.count;
        for (int q = 0; q < 5; ++q) s.tail[q] = b.tail[q];
        s.cos_dst = b.cos_dst;
        s.c_ = b.kind == StepKind::single ? nullptr : body->doubles.data() + b.c_at;
        s.reg_ = body->regs.data() + b.reg_at;
        s.dst_ = body->regs.data() + b.dst_at;
        s.src_ = body->regs.data() + b.src_at;
        if (b.kind == StepKind::single) {
            body->singles.push_back(b.single);
            s.single_ = &body->singles.back();
        }
        body->steps.push_back(s);
    }
    return body;
}

/// Mode blocks laid out by lane: the body's modes in program order, four to a
/// group of kLane * kModeRegisters registers appended to the body's, mode m's
/// field f at its group's first register + kLane * f + m % kLane. Every
/// register the instructions name is renamed; the coefficient registers and
/// the outputs keep their numbers. So four modes' fields are vectors
/// (factored_modes) and a value's operations do not change.
void lay_out_modes(std::vector<Instr>& code, std::vector<ProgramTerm>& terms, std::size_t& registers) {
    const std::size_t old = registers;
    std::vector<std::uint32_t> to;
    std::uint32_t m = 0;
    for (const Instr& in : code) {
        if (in.op != ProgramOp::mode) continue;
        if (to.empty()) {
            to.resize(old);
            for (std::size_t r = 0; r < old; ++r) to[r] = static_cast<std::uint32_t>(r);
        }
        const std::uint32_t first =
            static_cast<std::uint32_t>(old) + kLane * kModeRegisters * (m / kLane) + m % kLane;
        for (std::uint32_t f = 0; f < kModeRegisters; ++f) to[in.dst + f] = first + mf(f);
        ++m;
    }
    if (m == 0) return;
    registers = old + static_cast<std::size_t>(kLane) * kModeRegisters * ((m + kLane - 1) / kLane);
    auto re = [&](std::uint32_t& r) {
        if (r != kNoRegister && r < old) r = to[r];
    };
    for (Instr& in : code) {
        re(in.dst), re(in.a), re(in.b), re(in.c), re(in.d);
        std::uint32_t n = 0;
        if (in.op == ProgramOp::lincomb || in.op == ProgramOp::lincomb_ld) n = in.count;
        if (in.op == ProgramOp::mass_state)
            n = in.count + in.tail[0] + in.tail[1] + in.tail[2] + in.tail[3] + in.tail[4];
        for (std::uint32_t k = 0; k < n; ++k) re(terms[in.first + k].reg);
    }
}

/// A body's instructions as the scheduler takes them, with the copies that
/// only rename a register forwarded (forward_copies). `terms` are the
/// program's: the registers of this body's terms are renamed in place, the
/// other body's terms are not touched.
/// With `registers` (eval's), the modes laid out by lane first
/// (lay_out_modes), and the body's registers counted there; setup has no modes.
std::vector<Instr> prepare(const ProgramBody& body, std::vector<ProgramTerm>& terms, std::uint32_t pinned_begin,
                           std::uint32_t pinned_end, std::vector<std::uint32_t>& exported,
                           std::size_t* registers = nullptr) {
    // Field by field into place: a whole Instr built on the stack and copied
    // stalled on every copy (its scalar stores read back as vectors).
    std::vector<Instr> code(body.code.size());
    for (std::size_t i = 0; i < code.size(); ++i) {
        const ProgramInstr& in = body.code[i];
        Instr& x = code[i];
        x.op = in.op;
        x.regime = in.regime;
        x.dst = in.dst, x.a = in.a, x.b = in.b, x.c = in.c, x.d = in.d;
        x.first = in.first;
        x.count = in.count;
        for (int q = 0; q < 5; ++q) x.tail[q] = in.tail[q];
    }
    std::size_t count = body.registers();
    if (registers) lay_out_modes(code, terms, count), *registers = count;
    forward_copies(code, terms, count, pinned_begin, pinned_end, exported);
    return code;
}

/// Every instruction's reads and writes (visit_accesses()), row i of each
/// table from at[i] to at[i + 1]: taken once for the passes over one program.
struct AccessTable {
    std::vector<std::uint32_t> read_at, write_at, reads, writes;
    AccessTable(const std::vector<Instr>& code, const std::vector<ProgramTerm>& terms) {
        read_at.reserve(code.size() + 1);
        write_at.reserve(code.size() + 1);
        read_at.push_back(0);
        write_at.push_back(0);
        std::size_t nr = 0;
        for (const Instr& in : code) nr += in.count;  // most reads are terms (a mass state's are 5 per mode)
        reads.reserve(5 * nr + 2 * code.size());
        writes.reserve(2 * code.size());
        for (const Instr& in : code) {
            visit_accesses(
                in, terms, [this](std::uint32_t r) { reads.push_back(r); }, [this](std::uint32_t w) { writes.push_back(w); });
            read_at.push_back(static_cast<std::uint32_t>(reads.size()));
            write_at.push_back(static_cast<std::uint32_t>(writes.size()));
        }
    }
};

/// Which instructions the registers marked in `needed` depend on, beside
/// those `keep` marks already: an instruction is kept when it writes a
/// register that a kept instruction after it (or a marked register) reads.
/// Every writer of such a register is kept, so each kept instruction sees the
/// operands it sees in the whole program and computes the same bits.
std::vector<char> kept_for(const AccessTable& a, std::vector<char> keep, std::vector<char> needed) {
    for (std::size_t i = keep.size(); i-- > 0;) {
        for (std::uint32_t k = a.write_at[i]; k < a.write_at[i + 1] && !keep[i]; ++k) keep[i] = needed[a.writes[k]];
        if (keep[i])
            for (std::uint32_t k = a.read_at[i]; k < a.read_at[i + 1]; ++k) needed[a.reads[k]] = 1;
    }
    return keep;
}

/// The instructions of a program of `n` instructions that registers
/// [live_begin, live_end) depend on (kept_for), marked.
std::vector<char> needed_for(std::size_t n, const AccessTable& a, std::size_t registers, std::uint32_t live_begin,
                             std::uint32_t live_end) {
    std::vector<char> needed(registers, 0);
    for (std::uint32_t r = live_begin; r < live_end; ++r) needed[r] = 1;
    return kept_for(a, std::vector<char>(n, 0), std::move(needed));
}

/// The time `code` takes, estimated in multiply-adds of a batched mass state
/// (about 0.2 ns each, measured at 128 masses): a mass's state 5 per mode, a
/// term of any other sum 2, any other instruction 100 (a mode block's libm
/// calls, about 25 ns).
double estimated_work(const std::vector<Instr>& code, const std::vector<char>* only = nullptr) {
    double w = 0;
    for (std::size_t i = 0; i < code.size(); ++i) {
        if (only && !(*only)[i]) continue;
        const Instr& in = code[i];
        const double tails = in.tail[0] + in.tail[1] + in.tail[2] + in.tail[3] + in.tail[4];
        w += in.op == ProgramOp::mass_state                                   ? 5.0 * in.count + 2.0 * tails
             : in.op == ProgramOp::lincomb || in.op == ProgramOp::lincomb_ld ? 2.0 * (1.0 + in.count)
                                                                              : 100.0;
    }
    return w;
}

/// Each instruction's dependency level: one more than the level of every
/// instruction before it that writes what it reads, reads what it writes or
/// writes it too. each(i, read, write) calls read and write for instruction
/// i's registers; `keep(i)` says whether instruction i is scheduled (else -1).
template <class Keep, class Each>
std::vector<int> dependency_levels(std::size_t n, std::size_t registers, Keep&& keep, Each&& each) {
    std::vector<int> last_write(registers, -1), last_read(registers, -1), level(n, -1);
    for (std::size_t i = 0; i < n; ++i) {
        if (!keep(i)) continue;
        int l = 0;
        each(
            i, [&](std::uint32_t r) { l = std::max(l, last_write[r] + 1); },
            [&](std::uint32_t w) { l = std::max({l, last_write[w] + 1, last_read[w] + 1}); });
        each(
            i, [&](std::uint32_t r) { last_read[r] = std::max(last_read[r], l); },
            [&](std::uint32_t w) { last_write[w] = l; });
        level[i] = l;
    }
    return level;
}

/// The levels of the instructions `only` marks (all without it), from their
/// access table.
std::vector<int> table_levels(const AccessTable& a, std::size_t n, std::size_t registers,
                              const std::vector<char>* only) {
    return dependency_levels(
        n, registers, [&](std::size_t i) { return !only || (*only)[i]; },
        [&](std::size_t i, auto&& read, auto&& write) {
            for (std::uint32_t k = a.read_at[i]; k < a.read_at[i + 1]; ++k) read(a.reads[k]);
            for (std::uint32_t k = a.write_at[i]; k < a.write_at[i + 1]; ++k) write(a.writes[k]);
        });
}

/// The instructions scheduled by dependency level (an instruction
/// comes after every instruction that writes what it reads, reads what it
/// writes, or writes it too, before it in the program), each level's
/// instructions of one shape batched into a block, in order of first
/// appearance; a sin and a cos of one register in one step. Every value is
/// computed by the same operations from the same operands as in program order.
/// `level` is each instruction's (dependency_levels; -1: left out); `where`
/// is by instruction of `code`.
std::unique_ptr<InterpretedSolver::Body> schedule(const std::vector<Instr>& code, const std::vector<int>& level,
                                                  std::vector<ProgramTerm>& terms, std::vector<RowRef>* where) {
    const std::size_t n = code.size();
    if (where) where->assign(n, {kNoStep, 0});
    int levels = 0;
    for (int l : level) levels = std::max(levels, l + 1);
    // The instructions in order of level, in program order within one (a counting sort).
    std::vector<std::uint32_t> start(static_cast<std::size_t>(levels) + 1, 0);
    for (std::size_t i = 0; i < n; ++i)
        if (level[i] >= 0) ++start[static_cast<std::size_t>(level[i]) + 1];
    for (std::size_t l = 0; l < static_cast<std::size_t>(levels); ++l) start[l + 1] += start[l];
    std::vector<std::uint32_t> order(start.back());
    {
        std::vector<std::uint32_t> at(start.begin(), start.end() - 1);
        for (std::size_t i = 0; i < n; ++i)
            if (level[i] >= 0) order[at[static_cast<std::size_t>(level[i])]++] = static_cast<std::uint32_t>(i);
    }

    std::vector<Block> blocks;
    blocks.reserve(order.size());
    // The pools' room up front (growing them copied them again and again):
    // the coefficients exactly (a row's terms once each), the registers at
    // most a term's, a row's and the tail registers of every row.
    BlockPools pools;
    {
        std::size_t nd = 0, nr = 0;
        for (const std::uint32_t i : order) {
            const Instr& in = code[i];
            const std::size_t tails = in.op == ProgramOp::mass_state
                                          ? in.tail[0] + in.tail[1] + in.tail[2] + in.tail[3] + in.tail[4]
                                          : 0;
            if (in.op == ProgramOp::lincomb || in.op == ProgramOp::lincomb_ld || in.op == ProgramOp::mass_state)
                nd += in.count + tails;
            nr += in.count + tails + 5;
        }
        pools.doubles.reserve(nd);
        pools.regs.reserve(nr);
    }
    // Per level (kept across levels, so that a small program does not allocate
    // per level): each member's group, each group's first instruction and
    // whether it runs alone, the groups' members in order (rows, from offset[g]).
    std::vector<std::uint32_t> group, first, offset, at;
    std::vector<char> alone, fused;
    std::vector<const Instr*> rows;
    // shape -> its groups (groups stay in order of first appearance); a map
    // instead of a linear search: a wide level has hundreds of shapes.
    std::unordered_multimap<std::uint64_t, std::uint32_t> group_of;
    for (std::size_t l = 0; l < static_cast<std::size_t>(levels); ++l) {
        group.clear(), first.clear(), alone.clear(), group_of.clear();
        for (std::uint32_t k = start[l]; k < start[l + 1]; ++k) {
            const Instr& in = code[order[k]];
            auto g = static_cast<std::uint32_t>(first.size());
            if (batched(in.op)) {
                const std::uint64_t h = shape_hash(in, terms);
                const auto range = group_of.equal_range(h);
                for (auto it = range.first; it != range.second && g == first.size(); ++it)
                    if (same_shape(code[first[it->second]], in, terms)) g = it->second;
                if (g == first.size()) group_of.emplace(h, g);
            }
            if (g == first.size()) {
                first.push_back(order[k]);
                alone.push_back(!batched(in.op));
            }
            group.push_back(g);
        }
        const std::size_t G = first.size();
        offset.assign(G + 1, 0);
        for (std::uint32_t g : group) ++offset[g + 1];
        for (std::size_t g = 0; g < G; ++g) offset[g + 1] += offset[g];
        at.assign(offset.begin(), offset.end() - 1);
        rows.resize(group.size());
        for (std::size_t k = 0; k < group.size(); ++k) rows[at[group[k]]++] = &code[order[start[l] + k]];
        fused.assign(G, 0);
        for (std::size_t g = 0; g < G; ++g) {
            if (fused[g]) continue;
            if (!alone[g]) {
                if (where)
                    for (std::uint32_t k = offset[g]; k < offset[g + 1]; ++k)
                        (*where)[static_cast<std::size_t>(rows[k] - code.data())] = {static_cast<std::uint32_t>(blocks.size()),
                                                                                   k - offset[g]};
                blocks.push_back(make_block(rows.data() + offset[g], offset[g + 1] - offset[g], terms, pools));
                continue;
            }
            const Instr& in = code[first[g]];
            Block s;
            s.single = in;
            if (in.op == ProgramOp::sin)  // its cos in this level, if any
                for (std::size_t h = g + 1; h < G; ++h)
                    if (alone[h] && !fused[h] && code[first[h]].op == ProgramOp::cos && code[first[h]].a == in.a) {
                        s.cos_dst = code[first[h]].dst;
                        fused[h] = 1;
                        break;
                    }
            blocks.push_back(std::move(s));
        }
    }
    return freeze(blocks, pools);
}

/// A body run whole, in one block per level and shape (setup's).
std::unique_ptr<InterpretedSolver::Body> whole_body(const ProgramBody& body, std::vector<ProgramTerm>& terms,
                                                    std::vector<std::uint32_t>& exported) {
    const std::vector<Instr> code = prepare(body, terms, 0, 0, exported);
    const std::vector<int> level = dependency_levels(
        code.size(), body.registers(), [](std::size_t) { return true; },
        [&](std::size_t i, auto&& read, auto&& write) { visit_accesses(code[i], terms, read, write); });
    return schedule(code, level, terms, nullptr);
}

/// The rows of eval's body that function f's outputs need beyond the common
/// part (the modes, the harmonics and what they read: everything but the
/// sums, run once per instant): the states of the masses it reads and its
/// sums, in program order, each as where eval runs it (`where`, from
/// schedule()), so that a row computes from the operands it has in the whole
/// program: the same bits. `common` marks the common instructions. False when
/// a register that a function's rows write has two writers (then running a
/// part alone could leave another writer's value).
struct FunctionRows {
    std::vector<char> common;       ///< [instruction]
    std::vector<RowRef> rows;       ///< the parts, one after another
    std::vector<std::uint32_t> at;  ///< function f's rows: rows[at[f] .. at[f + 1])
};

bool rows_by_function(const std::vector<Instr>& code, const AccessTable& a, std::size_t registers,
                      std::uint32_t outputs, std::size_t ns, const std::vector<RowRef>& where, FunctionRows& out) {
    const std::size_t n = code.size();
    // Each register's writer, and how many it has.
    std::vector<int> writer(registers, -1), writers(registers, 0);
    for (std::size_t i = 0; i < n; ++i)
        for (std::uint32_t k = a.write_at[i]; k < a.write_at[i + 1]; ++k)
            writer[a.writes[k]] = static_cast<int>(i), ++writers[a.writes[k]];
    // Common: the unbatched instructions and every writer of what they read.
    std::vector<char> unbatched(n, 0);
    for (std::size_t i = 0; i < n; ++i) unbatched[i] = !batched(code[i].op);
    out.common = kept_for(a, std::move(unbatched), std::vector<char>(registers, 0));
    const std::vector<char>& is_common = out.common;
    // Each other instruction's dependencies outside the common part: the
    // writers of what it reads, each once (stamp).
    std::vector<std::uint32_t> dep_at(n + 1, 0), deps;
    std::vector<int> stamp(n, -1);
    for (std::size_t i = 0; i < n; ++i) {
        if (!is_common[i]) {
            for (std::uint32_t k = a.write_at[i]; k < a.write_at[i + 1]; ++k)
                if (writers[a.writes[k]] != 1) return false;
            if (where[i].step == kNoStep) return false;
            for (std::uint32_t k = a.read_at[i]; k < a.read_at[i + 1]; ++k) {
                const int w = writer[a.reads[k]];
                if (w < 0 || is_common[static_cast<std::size_t>(w)] || stamp[static_cast<std::size_t>(w)] == static_cast<int>(i))
                    continue;
                stamp[static_cast<std::size_t>(w)] = static_cast<int>(i);
                deps.push_back(static_cast<std::uint32_t>(w));
            }
        }
        dep_at[i + 1] = static_cast<std::uint32_t>(deps.size());
    }
    std::fill(stamp.begin(), stamp.end(), -1);  // now: the function whose part holds instruction i last
    std::vector<std::uint32_t> stack, part;
    out.rows.clear();
    out.at.assign(1, 0);
    for (std::size_t f = 0; f < ns; ++f) {
        part.clear();
        for (std::uint32_t q = 0; q < 4; ++q) {
            const int w = writer[outputs + static_cast<std::uint32_t>(q * ns + f)];
            if (w >= 0 && !is_common[static_cast<std::size_t>(w)]) stack.push_back(static_cast<std::uint32_t>(w));
        }
        while (!stack.empty()) {
            const std::uint32_t w = stack.back();
            stack.pop_back();
            if (stamp[w] == static_cast<int>(f)) continue;
            stamp[w] = static_cast<int>(f);
            part.push_back(w);
            stack.insert(stack.end(), deps.begin() + dep_at[w], deps.begin() + dep_at[w + 1]);
        }
        std::sort(part.begin(), part.end());
        for (std::uint32_t i : part) out.rows.push_back(where[i]);
        out.at.push_back(static_cast<std::uint32_t>(out.rows.size()));
    }
    return true;
}

}  // namespace

InterpretedSolver::InterpretedSolver(Program p)
    : cfg_(std::move(p.cfg)),
      switches_(p.switches),  // copied: eval_output_count() below reads p.switches
      max_step_(p.max_step),
      n_dof_(p.n_dof),
      n_slider_(p.n_slider),
      n_coef_(static_cast<std::size_t>(p.n_coef)),
      constants_(std::move(p.constants)),
      setup_coef_(p.setup_coef),
      setup_(whole_body(p.setup, p.terms, setup_coef_)),
      setup_regs_(p.setup.registers(), 0.0) {
    plan_ = std::move(p.restart);
    const std::uint32_t outputs = p.eval_outputs(), switch_outputs = outputs + static_cast<std::uint32_t>(
                                                                                   p.n_state() + 2 * p.n_dof);
    std::size_t registers = 0;  // eval's, its modes laid out by lane
    const std::vector<Instr> code =
        prepare(p.eval, p.terms, outputs, outputs + p.eval_output_count(), no_exports_, &registers);
    eval_regs_.assign(registers, 0.0);
    eval_regs_[0] = 1.0;
    const bool by_function = switches_.size() >= kScheduleFrom;  // eval_some() runs rows of eval_
    std::vector<RowRef> where;
    // eval's bodies, their modes' factors taken as the printer takes them (emitter.cpp).
    const bool vector = vector_factors(p.eval);
    const AccessTable table(code, p.terms);
    auto eval_body = [&](const std::vector<char>* only, std::vector<RowRef>* rows = nullptr) {
        std::unique_ptr<Body> body =
            schedule(code, table_levels(table, code.size(), registers, only), p.terms, rows);
        body->vector_factors = vector;
        if (vector) attach_lanes(*body, constants_.data());
        return body;
    };
    eval_ = eval_body(nullptr, by_function ? &where : nullptr);
    // The search's program: what g, dg, bound and scale need. Worth a body of
    // its own only when it leaves out a good part (the state of masses no
    // switch function reads).
    const std::vector<char> search =
        needed_for(code.size(), table, registers, switch_outputs, outputs + p.eval_output_count());
    const double work = estimated_work(code);
    const double share = estimated_work(code, &search) / std::max(1.0, work);
    if (share < 0.8) {
        switches_body_ = eval_body(&search);
        switch_share_ = share;
    }
    if (by_function) {
        // Rows by function for eval_some (rows_by_function); without them
        // eval_some() is eval_switches().
        FunctionRows parts;
        if (rows_by_function(code, table, registers, switch_outputs, switches_.size(), where, parts)) {
            common_ = eval_body(&parts.common);
            part_rows_.assign(parts.rows.begin(), parts.rows.end());  // no spare capacity: the budget counts it
            part_at_.assign(parts.at.begin(), parts.at.end());
            // eval_start: the common part, then the steps of eval_ that hold
            // what every function's bound needs beyond it (without the
            // masses' states that g, g' and the scale read), then a listed
            // function's rows as in eval_some. The other rows of those steps
            // compute what nothing read there needs: their registers are
            // their own (one writer each), and a listed function's rows
            // compute them again. No body is scheduled for it.
            const std::size_t ns = switches_.size();
            std::vector<char> needed(registers, 0);
            const std::uint32_t bounds_at = switch_outputs + 2 * static_cast<std::uint32_t>(ns);
            for (std::size_t f = 0; f < ns; ++f) needed[bounds_at + f] = 1;
            const std::vector<char> keep = kept_for(table, parts.common, std::move(needed));
            std::vector<char> used(eval_->steps.size(), 0), beyond(code.size(), 0);
            bool mapped = true;
            for (std::size_t i = 0; i < code.size(); ++i) {
                if (!keep[i] || parts.common[i]) continue;
                if (where[i].step == kNoStep) mapped = false;
                else used[where[i].step] = 1;
                beyond[i] = 1;
            }
            if (mapped && estimated_work(code, &beyond) < 0.4 * work)
                for (std::size_t k = 0; k < used.size(); ++k)
                    if (used[k]) start_steps_.push_back(static_cast<std::uint32_t>(k));
        }
    }
}

InterpretedSolver::~InterpretedSolver() = default;

std::size_t InterpretedSolver::memory_bytes() const {
    const std::size_t cut = (common_ ? common_->bytes() : 0) + sizeof(RowRef) * part_rows_.capacity() +
                            sizeof(std::uint32_t) * part_at_.capacity();
    return sizeof(*this) + setup_->bytes() + eval_->bytes() + (switches_body_ ? switches_body_->bytes() : 0) +
           sizeof(std::uint32_t) * start_steps_.capacity() + cut +
           sizeof(double) * (constants_.capacity() + setup_regs_.capacity() + eval_regs_.capacity()) +
           sizeof(std::uint32_t) * setup_coef_.capacity() + sizeof(SwitchFunction) * switches_.capacity() +
           sizeof(double) * (plan_.vt.capacity() + plan_.mu_k_n.capacity()) +
           sizeof(RestartPlan::Mode) * plan_.modes.capacity() +
           cfg_.closed.capacity() + cfg_.stuck.capacity();
}

void InterpretedSolver::setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) {
    const std::size_t n = static_cast<std::size_t>(n_dof_);
    double* r = setup_regs_.data();
    r[0] = 1.0;
    r[Program::kSetupT0] = t0;
    r[Program::kSetupT0Lo] = t0_lo;
    const std::size_t ns = n + static_cast<std::size_t>(n_slider_);  // x0: masses, then sliders
    const std::size_t v0_at = Program::kSetupX0 + ns, sgn_at = v0_at + n;
    for (std::size_t i = 0; i < ns; ++i) r[Program::kSetupX0 + i] = x0[i];
    for (std::size_t i = 0; i < n; ++i) {
        r[v0_at + i] = v0[i];
        r[sgn_at + i] = sgn[i];
    }
    execute(constants_.data(), *setup_, r);
    // The coefficient block goes straight into eval's registers.
    for (std::size_t k = 0; k < setup_coef_.size(); ++k) eval_regs_[Program::kEvalCoef + k] = r[setup_coef_[k]];
}

void InterpretedSolver::eval_switches(double tau, const SegmentEval& out) const {
    if (!switches_body_) return eval(tau, out);
    double* r = eval_regs_.data();
    r[Program::kEvalTau] = tau;
    execute(constants_.data(), *switches_body_, r);
    for (std::size_t f = 0; f < switches_.size(); ++f) switch_outputs(f, out);
}

void InterpretedSolver::eval_start(double tau, const std::uint32_t* which, std::size_t count,
                                   const SegmentEval& out) const {
    if (start_steps_.empty() || 4 * count > switches_.size()) return eval_switches(tau, out);
    double* r = eval_regs_.data();
    r[Program::kEvalTau] = tau;
    execute(constants_.data(), *common_, r);
    for (std::uint32_t k : start_steps_) run_step(eval_->steps[k], constants_.data(), r);
    const std::size_t ns = switches_.size();
    const double* bounds = switch_registers() + 2 * ns;
    for (std::size_t f = 0; f < ns; ++f) out.bound[f] = bounds[f];
    function_rows(which, count, out);
}

void InterpretedSolver::eval_some(double tau, const std::uint32_t* which, std::size_t count,
                                  const SegmentEval& out) const {
    if (!common_) return eval_switches(tau, out);
    double* r = eval_regs_.data();
    r[Program::kEvalTau] = tau;
    execute(constants_.data(), *common_, r);
    function_rows(which, count, out);
}

void InterpretedSolver::function_rows(const std::uint32_t* which, std::size_t count, const SegmentEval& out) const {
    double* r = eval_regs_.data();
    for (std::size_t k = 0; k < count; ++k) {
        const std::uint32_t f = which[k];
        for (std::uint32_t i = part_at_[f]; i < part_at_[f + 1]; ++i)
            run_row(eval_->steps[part_rows_[i].step], part_rows_[i].row, r);
        switch_outputs(f, out);
    }
}

void InterpretedSolver::eval(double tau, const SegmentEval& out) const {
    double* r = eval_regs_.data();
    r[Program::kEvalTau] = tau;
    execute(constants_.data(), *eval_, r);
    const std::size_t n = static_cast<std::size_t>(n_dof_), nx = n + static_cast<std::size_t>(n_slider_);
    const double* o = r + Program::kEvalCoef + n_coef_;
    for (std::size_t i = 0; i < nx; ++i) out.x[i] = o[i];
    for (std::size_t i = 0; i < n; ++i) out.v[i] = o[nx + i], out.a[i] = o[nx + n + i];
    for (std::size_t f = 0; f < switches_.size(); ++f) switch_outputs(f, out);
}

const double* InterpretedSolver::switch_registers() const {
    // eval's outputs: x, v, a, then g, dg, bound and scale of every function.
    const std::size_t n = static_cast<std::size_t>(n_dof_), nx = n + static_cast<std::size_t>(n_slider_);
    return eval_regs_.data() + Program::kEvalCoef + n_coef_ + nx + 2 * n;
}

void InterpretedSolver::switch_outputs(std::size_t f, const SegmentEval& out) const {
    const std::size_t ns = switches_.size();
    const double* o = switch_registers();
    out.g[f] = o[f], out.dg[f] = o[ns + f], out.bound[f] = o[2 * ns + f], out.scale[f] = o[3 * ns + f];
}

SegmentSolver& InterpretedSolverProvider::solver(const Configuration& cfg) {
    auto it = cache_.find(cfg);
    if (it != cache_.end()) {
        lru_.splice(lru_.begin(), lru_, it->second.lru);  // most recently used
        return *it->second.solver;
    }
    const auto start = std::chrono::steady_clock::now();
    auto s = std::make_unique<InterpretedSolver>(lower_(cfg));
    lower_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ++built_;
    seen_.insert(cfg);
    const std::size_t bytes = s->memory_bytes();
    lru_.push_front(cfg);
    it = cache_.emplace(cfg, Entry{std::move(s), bytes, lru_.begin()}).first;
    bytes_ += bytes;
    // Drop the least recently used until within budget; never the one returned now.
    while (bytes_ > max_bytes_ && lru_.size() > 1) {
        const auto victim = cache_.find(lru_.back());
        bytes_ -= victim->second.bytes;
        cache_.erase(victim);
        lru_.pop_back();
        ++evicted_;
    }
    return *it->second.solver;
}

std::string InterpretedSolverProvider::describe() const {
    std::string text = "generic solver for " + std::to_string(seen_.size()) + " configurations (interpreted programs";
    if (evicted_ > 0)
        text += "; " + std::to_string(cache_.size()) + " kept within " + std::to_string(max_bytes_ >> 20) + " MB, " +
                std::to_string(built_ - seen_.size()) + " rebuilt";
    return text + ")";
}

// The calls are independent, so they overlap: one alone is a long chain of
// dependent operations.
__attribute__((target_clones("avx2", "default"))) void mode_factors(const double* xe, const double* xt, double* e,
                                                                     double* sn, double* cs, std::size_t n,
                                                                     bool exp) {
    for (std::size_t i = 0; i < n; i += 4) hsnc_sincos4(xt + i, sn + i, cs + i);
    if (exp)
        for (std::size_t i = 0; i < n; i += 4) hsnc_exp4(xe + i, e + i);
}

}  // namespace hsnc
