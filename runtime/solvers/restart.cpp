#include "restart.h"

#include <cmath>
#include <vector>

#include "kernel_abi.h"  // hsnc_phase
#include "mode_factors.h"

namespace hsnc {

namespace {

// dx[r] = sum_j vt[j * nf + r] * d[j], mode by mode over each mode's span
// (each dx[r] summed in the order of the modes, whatever the clone): the
// nonzeros of V, in vector registers.
__attribute__((target_clones("avx2", "default"))) void static_shift(const double* vt, const std::uint32_t* span,
                                                                      const double* d, double* dx, std::size_t nm,
                                                                      std::size_t nf) {
    for (std::size_t j = 0; j < nm; ++j) {
        const double dj = d[j];
        const double* col = vt + j * nf;
        for (std::size_t r = span[2 * j]; r < span[2 * j + 1]; ++r) dx[r] += col[r] * dj;
    }
}

}  // namespace

void restart_coefficients(const RestartPlan& plan, double* coef, double tau, double t0, double t0_lo,
                          const signed char* sgn_old, const signed char* sgn_new) {
    const std::size_t nm = plan.modes.size(), nf = plan.free_mass.size();
    // Per mode: Delta(p / lambda), then e^{-sigma tau}, sin and cos(omega_d tau);
    // per free coordinate the static offset's change.
    const std::size_t padded = 4 * ((nm + 3) / 4);
    thread_local std::vector<double> scratch;
    scratch.assign(4 * padded + nf, 0.0);
    double* delta = scratch.data();
    double* e = delta + padded;
    double* sn = e + padded;
    double* cs = sn + padded;
    double* dx = cs + padded;
    // Each flipped friction force changes the modal forces by V^T Delta f.
    bool moved = false;
    for (std::size_t r = 0; r < nf; ++r) {
        const int i = plan.free_mass[r];
        if (sgn_new[i] == sgn_old[i] || plan.mu_k_n[r] == 0.0) continue;
        const double df = -plan.mu_k_n[r] * (sgn_new[i] - sgn_old[i]);
        for (std::size_t j = 0; j < nm; ++j)
            if (r >= plan.span[2 * j] && r < plan.span[2 * j + 1]) delta[j] += plan.vt[j * nf + r] * df;
        moved = true;
    }
    for (std::size_t j = 0; j < nm; ++j) {
        delta[j] /= plan.modes[j].lambda;
        e[j] = -plan.modes[j].sigma * tau;
        sn[j] = plan.modes[j].omega_d * tau;
    }
    mode_factors(e, sn, e, sn, cs, padded, true);
    for (std::size_t j = 0; j < nm; ++j) {
        const RestartPlan::Mode& m = plan.modes[j];
        // The homogeneous response at tau, as the mode instruction forms it.
        double eC = 0.0, eS = 0.0;
        switch (m.regime) {
            case ProgramRegime::undamped:
                eC = cs[j], eS = sn[j] / m.omega_d;
                break;
            case ProgramRegime::underdamped:
                eC = e[j] * cs[j], eS = e[j] * sn[j] / m.omega_d;
                break;
            case ProgramRegime::critical:
                eC = e[j], eS = tau * eC;
                break;
            default: {  // overdamped (restart_plan() admits no rigid mode)
                const double ex = std::exp(m.r1 * tau), em = std::expm1(-2 * m.gamma * tau);
                eC = ex * (1.0 + 0.5 * em), eS = -ex * em * (0.5 / m.gamma);
                break;
            }
        }
        double* c = coef + m.coef;  // A, B, A1, B1, A2, B2
        const double q = c[0] * eC + c[1] * eS, dq = c[2] * eC + c[3] * eS;
        // The new segment's A = q_h(0), B = q_h'(0) + sigma A and the derivative pairs, as setup forms them.
        const double A = q - delta[j], B = dq + m.sigma * A;
        const double A1 = B - m.sigma * A, B1 = -m.kappa * A - m.sigma * B;
        c[0] = A, c[1] = B, c[2] = A1, c[3] = B1;
        c[4] = B1 - m.sigma * A1, c[5] = -m.kappa * A1 - m.sigma * B1;
    }
    // x_st moves by V Delta(p / lambda).
    if (moved) {
        static_shift(plan.vt.data(), plan.span.data(), delta, dx, nm, nf);
        for (std::size_t r = 0; r < nf; ++r) coef[plan.x_st[r]] += dx[r];
    }
    for (const RestartPlan::Harmonic& h : plan.harmonics) {
        coef[h.theta] = hsnc_phase(h.omega, t0, t0_lo, h.phase);
        coef[h.c_theta] = std::cos(coef[h.theta]);
    }
}

}  // namespace hsnc
