#include "restart.h"

#include <cmath>
#include <vector>

#include "kernel_abi.h"  // hsnc_phase

namespace hsnc {

void restart_coefficients(const RestartPlan& plan, double* coef, double tau, double t0, double t0_lo,
                          const signed char* sgn_old, const signed char* sgn_new) {
    const std::size_t nm = plan.modes.size(), nf = plan.free_mass.size();
    // Delta(p / lambda) per mode: the modal force's change, V^T Delta f, over
    // the coordinates whose friction direction flipped.
    std::vector<double> delta(nm, 0.0);
    for (std::size_t r = 0; r < nf; ++r) {
        const int i = plan.free_mass[r];
        if (sgn_new[i] == sgn_old[i]) continue;
        const double df = -plan.mu_k_n[r] * (sgn_new[i] - sgn_old[i]);
        for (std::size_t j = 0; j < nm; ++j) delta[j] += plan.v[r * nm + j] * df;
    }
    for (std::size_t j = 0; j < nm; ++j) {
        const RestartPlan::Mode& m = plan.modes[j];
        delta[j] /= m.lambda;
        // The homogeneous response at tau, as the mode instruction forms it.
        double eC = 0.0, eS = 0.0;
        switch (m.regime) {
            case ProgramRegime::undamped:
                eC = std::cos(m.omega_d * tau), eS = std::sin(m.omega_d * tau) / m.omega_d;
                break;
            case ProgramRegime::underdamped: {
                const double e = std::exp(-m.sigma * tau);
                eC = e * std::cos(m.omega_d * tau), eS = e * std::sin(m.omega_d * tau) / m.omega_d;
                break;
            }
            case ProgramRegime::critical:
                eC = std::exp(-m.sigma * tau), eS = tau * eC;
                break;
            default: {  // overdamped (restart_plan() admits no rigid mode)
                const double e = std::exp(m.r1 * tau), em = std::expm1(-2 * m.gamma * tau);
                eC = e * (1.0 + 0.5 * em), eS = -e * em * (0.5 / m.gamma);
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
    for (std::size_t r = 0; r < nf; ++r) {
        double dx = 0.0;
        for (std::size_t j = 0; j < nm; ++j) dx += plan.v[r * nm + j] * delta[j];
        coef[plan.x_st[r]] += dx;
    }
    for (const RestartPlan::Harmonic& h : plan.harmonics) {
        coef[h.theta] = hsnc_phase(h.omega, t0, t0_lo, h.phase);
        coef[h.c_theta] = std::cos(coef[h.theta]);
    }
}

}  // namespace hsnc
