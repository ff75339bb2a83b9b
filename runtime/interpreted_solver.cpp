#include "interpreted_solver.h"

#include <chrono>
#include <cstdio>
#include <cstring>

#include "kernel_abi.h"  // hsnc_phase, hsnc_phi2: the very helpers the printed kernels call

namespace hsnc {

namespace {

// Each case computes what generator/emitter.cpp (BodyPrinter) prints for the
// instruction, operation for operation: change both or neither.
void execute(const Program& p, const ProgramBody& body, double* r) {
    const double* K = p.constants.data();
    const ProgramTerm* T = p.terms.data();
    for (const ProgramInstr& in : body.code) {
        switch (in.op) {
            case ProgramOp::lincomb: {
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
                m[kModeMQ] += __builtin_fabs(y);
                m[kModeMDQ] += __builtin_fabs(dy);
                break;
            }
        }
    }
}

void copy_out(const Program& p, const double* r, const SegmentEval& out) {
    const std::size_t n = static_cast<std::size_t>(p.n_dof), ns = p.n_switch();
    const double* o = r + p.eval_outputs();
    double* dst[7] = {out.x, out.v, out.a, out.g, out.dg, out.bound, out.scale};
    for (int k = 0; k < 7; ++k) {
        const std::size_t len = k < 3 ? n : ns;
        if (len) std::memcpy(dst[k], o, len * sizeof(double));
        o += len;
    }
}

}  // namespace

void run_setup(const Program& p, double* regs, double* coef, double t0, double t0_lo, const double* x0,
               const double* v0, const signed char* sgn) {
    const std::size_t n = static_cast<std::size_t>(p.n_dof);
    regs[0] = 1.0;
    regs[Program::kSetupT0] = t0;
    regs[Program::kSetupT0Lo] = t0_lo;
    for (std::size_t i = 0; i < n; ++i) {
        regs[Program::kSetupX0 + i] = x0[i];
        regs[p.setup_v0() + i] = v0[i];
        regs[p.setup_sgn() + i] = sgn[i];
    }
    execute(p, p.setup, regs);
    for (std::size_t k = 0; k < p.setup_coef.size(); ++k) coef[k] = regs[p.setup_coef[k]];
}

void run_eval(const Program& p, double* regs, const double* coef, double tau, const SegmentEval& out) {
    regs[0] = 1.0;
    regs[Program::kEvalTau] = tau;
    if (p.n_coef) std::memcpy(regs + Program::kEvalCoef, coef, static_cast<std::size_t>(p.n_coef) * sizeof(double));
    execute(p, p.eval, regs);
    copy_out(p, regs, out);
}

InterpretedSolver::InterpretedSolver(Program program)
    : program_(std::move(program)),
      setup_regs_(program_.setup.registers(), 0.0),
      eval_regs_(program_.eval.registers(), 0.0) {
    eval_regs_[0] = 1.0;
}

void InterpretedSolver::setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) {
    run_setup(program_, setup_regs_.data(), eval_regs_.data() + Program::kEvalCoef, t0, t0_lo, x0, v0, sgn);
}

void InterpretedSolver::eval(double tau, const SegmentEval& out) const {
    double* r = eval_regs_.data();
    r[Program::kEvalTau] = tau;
    execute(program_, program_.eval, r);
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
