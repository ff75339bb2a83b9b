#include "interpreted_solver.h"

#include <chrono>
#include <cstdio>
#include <cstring>

#include "kernel_abi.h"  // hsnc_phase, hsnc_phi2: the very helpers the printed kernels call

namespace hsnc {

namespace {

}  // namespace

/// One instruction as the interpreter runs it: the operands of ProgramInstr
/// without its comments, and `group`, the first of up to four independent
/// linear combinations run in lockstep (each still summed in its own order:
/// the same bits, more arithmetic in flight).
struct InterpretedSolver::Exec {
    ProgramOp op;
    std::uint8_t regime;
    std::uint8_t group;  ///< lincomb: how many lincombs from here form a group (1 = alone, 0 = inside one)
    std::uint32_t dst, a, b, c, d, first, count;
    std::uint32_t tail[5];  ///< mass_state
};

namespace {

using Exec = InterpretedSolver::Exec;

std::vector<Exec> compile(const ProgramBody& body, const std::vector<ProgramTerm>& terms) {
    std::vector<Exec> out;
    out.reserve(body.code.size());
    for (const ProgramInstr& in : body.code)
        out.push_back({in.op, in.regime, 1, in.dst, in.a, in.b, in.c, in.d, in.first, in.count,
                       {in.tail[0], in.tail[1], in.tail[2], in.tail[3], in.tail[4]}});
    // Groups of consecutive double lincombs, none reading what another writes.
    for (std::size_t i = 0; i < out.size();) {
        if (out[i].op != ProgramOp::lincomb || out[i].count == 0) {
            ++i;
            continue;
        }
        std::size_t j = i + 1;
        while (j < out.size() && j - i < 4 && out[j].op == ProgramOp::lincomb && out[j].count > 0) {
            bool independent = true;
            for (std::size_t g = i; g < j && independent; ++g) {
                independent = out[j].a != out[g].dst && out[j].dst != out[g].dst;
                for (std::uint32_t k = 0; k < out[j].count && independent; ++k)
                    independent = terms[out[j].first + k].reg != out[g].dst;
            }
            if (!independent) break;
            ++j;
        }
        out[i].group = static_cast<std::uint8_t>(j - i);
        for (std::size_t g = i + 1; g < j; ++g) out[g].group = 0;
        i = j;
    }
    return out;
}

// G independent linear combinations, their terms interleaved: term k of each
// is added to its own sum in the order of that sum.
template <int G>
void lincomb_group(const Exec* L, const ProgramTerm* T, double* r) {
    const ProgramTerm* t[G];
    double s[G];
    std::uint32_t m = L[0].count;
#pragma GCC unroll 4
    for (int l = 0; l < G; ++l) {
        t[l] = T + L[l].first;
        m = L[l].count < m ? L[l].count : m;
        s[l] = t[l][0].c * r[t[l][0].reg];
    }
    for (std::uint32_t k = 1; k < m; ++k) {
#pragma GCC unroll 4
        for (int l = 0; l < G; ++l) s[l] += t[l][k].c * r[t[l][k].reg];
    }
#pragma GCC unroll 4
    for (int l = 0; l < G; ++l) {
        for (std::uint32_t k = m; k < L[l].count; ++k) s[l] += t[l][k].c * r[t[l][k].reg];
        r[L[l].dst] = L[l].a == kNoRegister ? s[l] : r[L[l].a] + s[l];
    }
}

// Adds the tail terms [t, t + n) to s, left to right; a sum without terms so
// far (started = false) starts from the first of them, as a printed sum does,
// and is 0.0 when there are none at all.
inline const ProgramTerm* finish_sum(double& s, bool started, const ProgramTerm* t, std::uint32_t n,
                                     const double* r) {
    std::uint32_t k = 0;
    if (!started) {
        if (n == 0) {
            s = 0.0;
            return t;
        }
        s = t[0].c * r[t[0].reg];
        k = 1;
    }
    for (; k < n; ++k) s += t[k].c * r[t[k].reg];
    return t + n;
}

// Each case computes what generator/emitter.cpp (BodyPrinter) prints for the
// instruction, operation for operation: change both or neither.
void execute(const Program& p, const std::vector<Exec>& code, double* r) {
    const double* K = p.constants.data();
    const ProgramTerm* T = p.terms.data();
    for (std::size_t i = 0; i < code.size(); ++i) {
        const Exec& in = code[i];
        switch (in.op) {
            case ProgramOp::lincomb: {
                switch (in.group) {
                    case 0: continue;  // run with its group
                    case 2: lincomb_group<2>(&in, T, r); continue;
                    case 3: lincomb_group<3>(&in, T, r); continue;
                    case 4: lincomb_group<4>(&in, T, r); continue;
                    default: break;
                }
                double s = 0.0;
                if (in.count > 0) {
                    const ProgramTerm* t = T + in.first;
                    s = t[0].c * r[t[0].reg];
                    for (std::uint32_t k = 1; k < in.count; ++k) s += t[k].c * r[t[k].reg];
                }
                r[in.dst] = in.a == kNoRegister ? s : r[in.a] + s;
                break;
            }
            case ProgramOp::lincomb_ld: {
                long double s = 0.0L;
                if (in.count > 0) {
                    const ProgramTerm* t = T + in.first;
                    s = static_cast<long double>(t[0].c) * static_cast<long double>(r[t[0].reg]);
                    for (std::uint32_t k = 1; k < in.count; ++k)
                        s += static_cast<long double>(t[k].c) * static_cast<long double>(r[t[k].reg]);
                }
                r[in.dst] = static_cast<double>(s);
                break;
            }
            case ProgramOp::copy: r[in.dst] = r[in.a]; break;
            case ProgramOp::abs: r[in.dst] = __builtin_fabs(r[in.a]); break;
            case ProgramOp::sin: r[in.dst] = __builtin_sin(r[in.a]); break;
            case ProgramOp::cos: r[in.dst] = __builtin_cos(r[in.a]); break;
            case ProgramOp::phase: r[in.dst] = hsnc_phase(K[in.first], r[in.a], r[in.b], K[in.first + 1]); break;
            case ProgramOp::harmonic: {
                const double arg = K[in.first] * r[in.b] + r[in.a];
                r[in.dst] = arg;
                r[in.dst + 1] = __builtin_sin(arg);
                r[in.dst + 2] = __builtin_cos(arg);
                break;
            }
            case ProgramOp::mode: {
                const double* k = K + in.first;
                const double* A = r + in.a;  // A, B, A1, B1, A2, B2
                double* o = r + in.dst;
                const double tau = r[in.b];
                double eC = 0.0, eS = 0.0;
                switch (static_cast<ProgramRegime>(in.regime)) {
                    case ProgramRegime::undamped:
                        eC = __builtin_cos(k[kModeOmegaD] * tau);
                        eS = __builtin_sin(k[kModeOmegaD] * tau) * k[kModeInvOmegaD];
                        break;
                    case ProgramRegime::underdamped: {
                        const double e = __builtin_exp(-k[kModeSigma] * tau);
                        o[kModeAux] = e;
                        eC = e * __builtin_cos(k[kModeOmegaD] * tau);
                        eS = e * __builtin_sin(k[kModeOmegaD] * tau) * k[kModeInvOmegaD];
                        break;
                    }
                    case ProgramRegime::critical:
                        eC = __builtin_exp(-k[kModeSigma] * tau);
                        eS = tau * eC;
                        break;
                    case ProgramRegime::overdamped: {
                        const double e = __builtin_exp(k[kModeR1] * tau);
                        const double m = __builtin_expm1(k[kModeNegTwoGamma] * tau);
                        o[kModeAux] = e;
                        o[kModeAux2] = m;
                        eC = e * (1.0 + 0.5 * m);
                        eS = -e * m * k[kModeHalfInvGamma];
                        break;
                    }
                    case ProgramRegime::rigid:
                        eC = 1.0;
                        eS = tau;
                        break;
                    case ProgramRegime::rigid_damped: {
                        const double m = __builtin_expm1(-k[kModeC] * tau);
                        o[kModeAux] = m;
                        eC = 1.0 + 0.5 * m;
                        eS = -m * k[kModeInvC];
                        break;
                    }
                }
                o[kModeEC] = eC;
                o[kModeES] = eS;
                const double q = A[0] * eC + A[1] * eS;
                const double dq = A[2] * eC + A[3] * eS;
                o[kModeQ] = q;
                o[kModeDQ] = dq;
                o[kModeDDQ] = A[4] * eC + A[5] * eS;
                o[kModeR] = __builtin_sqrt(dq * dq + k[kModeLambda] * q * q);
                o[kModeMQ] = __builtin_fabs(A[0] * eC) + __builtin_fabs(A[1] * eS);
                o[kModeMDQ] = __builtin_fabs(A[2] * eC) + __builtin_fabs(A[3] * eS);
                // + |sigma A eC|: A1 = B - sigma A cancels (generator/emitter.cpp, mode()).
                if (k[kModeSigma] != 0.0) o[kModeMDQ] = o[kModeMDQ] + __builtin_fabs(k[kModeSigma] * A[0] * eC);
                break;
            }
            case ProgramOp::rigid_particular: {
                double* m = r + in.c;
                const double P = r[in.a], tau = r[in.b];
                m[kModeQ] += 0.5 * P * tau * tau;
                m[kModeDQ] += P * tau;
                m[kModeDDQ] += P;
                m[kModeMQ] += __builtin_fabs(0.5 * P * tau * tau);
                m[kModeMDQ] += __builtin_fabs(P * tau);
                break;
            }
            case ProgramOp::rigid_damped_particular: {
                double* m = r + in.c;
                const double P = r[in.a], tau = r[in.b];
                const double qp = P * tau * tau * hsnc_phi2(-K[in.first] * tau);
                r[in.dst] = qp;
                m[kModeQ] += qp;
                m[kModeDQ] += P * m[kModeES];
                m[kModeDDQ] += P * (1.0 + m[kModeAux]);
                m[kModeMQ] += __builtin_fabs(qp);
                m[kModeMDQ] += __builtin_fabs(P * m[kModeES]);
                break;
            }
            case ProgramOp::mass_state: {
                const ProgramTerm* t = T + in.first;
                const double xst = r[in.a];
                double sx = xst, sv = 0.0, sa = 0.0, smx = __builtin_fabs(xst), smv = 0.0;
                const bool started = in.count > 0;
                if (started) {
                    const double c = t[0].c, ac = __builtin_fabs(c);
                    const double* m = r + t[0].reg;
                    sx += c * m[kModeQ];
                    sv = c * m[kModeDQ];
                    sa = c * m[kModeDDQ];
                    smx += ac * m[kModeMQ];
                    smv = ac * m[kModeMDQ];
                    for (std::uint32_t k = 1; k < in.count; ++k) {
                        const double ck = t[k].c, ak = __builtin_fabs(ck);
                        const double* mk = r + t[k].reg;
                        sx += ck * mk[kModeQ];
                        sv += ck * mk[kModeDQ];
                        sa += ck * mk[kModeDDQ];
                        smx += ak * mk[kModeMQ];
                        smv += ak * mk[kModeMDQ];
                    }
                }
                const ProgramTerm* tl = t + in.count;
                tl = finish_sum(sx, true, tl, in.tail[0], r);
                tl = finish_sum(sv, started, tl, in.tail[1], r);
                tl = finish_sum(sa, started, tl, in.tail[2], r);
                tl = finish_sum(smx, true, tl, in.tail[3], r);
                finish_sum(smv, started, tl, in.tail[4], r);
                r[in.dst] = sx;
                r[in.b] = sv;
                r[in.c] = sa;
                r[in.d] = smx;
                r[in.d + 1] = smv;
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
                const double eC = m[kModeEC], eS = m[kModeES];
                const double y = k[kResQ] * (ct * eS - w * Cb);
                const double dy = k[kResQ] * (ct * eC - dw * Cb + k[kResMean] * w * Sb);
                const double ddy =
                    k[kResQ] * (k[kResH2W2] * w * Cb + k[kResTwoMean] * dw * Sb - k[kResLambda] * ct * eS);
                o[0] = w, o[1] = dw, o[2] = Cb, o[3] = Sb, o[4] = y, o[5] = dy, o[6] = ddy;
                m[kModeQ] += y;
                m[kModeDQ] += dy;
                m[kModeDDQ] += ddy;
                // The magnitude of the terms (y and y' cancel to ~tau^3 near tau = 0).
                const double Q = __builtin_fabs(k[kResQ]);
                m[kModeMQ] += Q * (__builtin_fabs(ct * eS) + __builtin_fabs(w * Cb));
                m[kModeMDQ] += Q * (__builtin_fabs(ct * eC) + __builtin_fabs(dw * Cb) + __builtin_fabs(k[kResMean] * w * Sb));
                break;
            }
        }
    }
}

void copy_out(const Program& p, const double* r, const SegmentEval& out) {
    const std::size_t n = static_cast<std::size_t>(p.n_dof), ns = p.n_switch();
    const double* o = r + p.eval_outputs();
    for (std::size_t i = 0; i < n; ++i) out.x[i] = o[i], out.v[i] = o[n + i], out.a[i] = o[2 * n + i];
    o += 3 * n;
    for (std::size_t f = 0; f < ns; ++f)
        out.g[f] = o[f], out.dg[f] = o[ns + f], out.bound[f] = o[2 * ns + f], out.scale[f] = o[3 * ns + f];
}

}  // namespace

InterpretedSolver::InterpretedSolver(Program program)
    : program_(std::move(program)),
      setup_code_(compile(program_.setup, program_.terms)),
      eval_code_(compile(program_.eval, program_.terms)),
      setup_regs_(program_.setup.registers(), 0.0),
      eval_regs_(program_.eval.registers(), 0.0) {
    eval_regs_[0] = 1.0;
}

InterpretedSolver::~InterpretedSolver() = default;

void InterpretedSolver::setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) {
    const Program& p = program_;
    const std::size_t n = static_cast<std::size_t>(p.n_dof);
    double* r = setup_regs_.data();
    r[0] = 1.0;
    r[Program::kSetupT0] = t0;
    r[Program::kSetupT0Lo] = t0_lo;
    for (std::size_t i = 0; i < n; ++i) {
        r[Program::kSetupX0 + i] = x0[i];
        r[p.setup_v0() + i] = v0[i];
        r[p.setup_sgn() + i] = sgn[i];
    }
    execute(p, setup_code_, r);
    // The coefficient block goes straight into eval's registers.
    for (std::size_t k = 0; k < p.setup_coef.size(); ++k) eval_regs_[Program::kEvalCoef + k] = r[p.setup_coef[k]];
}

void InterpretedSolver::eval(double tau, const SegmentEval& out) const {
    double* r = eval_regs_.data();
    r[Program::kEvalTau] = tau;
    execute(program_, eval_code_, r);
    copy_out(program_, r, out);
}

SegmentSolver& InterpretedSolverProvider::solver(const Configuration& cfg) {
    auto it = cache_.find(cfg);
    if (it != cache_.end()) return *it->second;
    const auto start = std::chrono::steady_clock::now();
    Program p = lower_(cfg);
    lower_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return *cache_.emplace(cfg, std::make_unique<InterpretedSolver>(std::move(p))).first->second;
}

std::string InterpretedSolverProvider::describe() const {
    char buf[128];
    std::snprintf(buf, sizeof buf, "interpreted programs: %zu configurations (derive+lower %.3f s)", cache_.size(),
                  lower_seconds_);
    return buf;
}

}  // namespace hsnc
