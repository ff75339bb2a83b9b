// hsnc -- what the two Eigen-based solvers (GenericSolver, StateSpaceSolver)
// share: the physical terms of a configuration, the value, rate and term
// size of one switch function from the physical state x, v, a, and e^w - 1. The kernels
// and the interpreter compute the same from their programs, independently.
//
// gap          G = x[a] - x[b] - gap, G' = v[a] - v[b]                 (assembly.h gap())
// velocity     v_i, v_i' = a_i
// release_pos  A_i - mu_s N_i,  release_neg -A_i - mu_s N_i, with
//              A_i = -(K x)_i - (C v)_i + f_i + F_i(t), A_i' = -(K v)_i - (C a)_i + F_i'(t)
//              over the full K(cfg), C(cfg) (a stuck row sees every mass).
// scale is the sum of the terms' magnitudes (segment_solver.h).
#pragma once

#include <cmath>
#include <complex>
#include <vector>

#include <Eigen/Core>

#include "configuration.h"
#include "model.h"
#include "segment_solver.h"
#include "switch_function.h"

namespace hsnc {

/// The physical terms of one configuration both Eigen-based solvers start
/// from (full n x n, stuck masses not removed; assembly.h): per mass m, N,
/// mu_k, mu_s and whether it has friction; K(cfg), C(cfg); the constant force
/// (loads, preloads, and the harmonics of omega = 0, F sin(phase)); the
/// contacts; the harmonics of omega != 0 with omega < 0 folded to |omega|
/// and phase pi - phase.
struct ConfigurationTerms {
    Eigen::VectorXd mass, normal, mu_k, mu_s;
    std::vector<char> friction;
    Eigen::MatrixXd K, C;
    Eigen::VectorXd f_const;
    std::vector<int> contact_a, contact_b;
    Eigen::VectorXd contact_gap;
    Eigen::VectorXd h_omega, h_phase;
    Eigen::MatrixXd h_amp;  ///< n x nh
};

ConfigurationTerms configuration_terms(const Model& model, const Configuration& cfg);

/// e^w - 1 for complex w = x + iy without cancellation:
/// Re = expm1(x) cos y - 2 sin^2(y/2), Im = e^x sin y.
inline std::complex<double> expm1c(std::complex<double> w) {
    const double x = w.real(), y = w.imag();
    const double s = std::sin(0.5 * y);
    return {std::expm1(x) * std::cos(y) - 2.0 * s * s, std::exp(x) * std::sin(y)};
}

/// g, g' and the size of g's terms; xmag, vmag the magnitudes of x and v,
/// sn, cs the sine and cosine of every harmonic's phase at the instant.
inline void switch_value(const SwitchFunction& sf, const ConfigurationTerms& in, const SegmentEval& out,
                         const Eigen::VectorXd& xmag, const Eigen::VectorXd& vmag, const Eigen::VectorXd& sn,
                         const Eigen::VectorXd& cs, double& g, double& dg, double& scale) {
    auto body = [](const double* y, int b) { return b == kGround ? 0.0 : y[b]; };
    auto body_mag = [](const Eigen::VectorXd& m, int b) { return b == kGround ? 0.0 : m(b); };
    const int e = sf.element;
    if (sf.kind == SwitchKind::gap) {
        const int a = in.contact_a[static_cast<std::size_t>(e)], b = in.contact_b[static_cast<std::size_t>(e)];
        g = body(out.x, a) - body(out.x, b) - in.contact_gap(e);
        dg = body(out.v, a) - body(out.v, b);
        scale = body_mag(xmag, a) + body_mag(xmag, b) + std::abs(in.contact_gap(e));
        return;
    }
    if (sf.kind == SwitchKind::velocity) {
        g = out.v[e];
        dg = out.a[e];
        scale = vmag(e);
        return;
    }
    double A = in.f_const(e), dA = 0.0, m = std::abs(in.f_const(e));
    for (Eigen::Index k = 0; k < in.K.cols(); ++k) {
        A -= in.K(e, k) * out.x[k] + in.C(e, k) * out.v[k];
        dA -= in.K(e, k) * out.v[k] + in.C(e, k) * out.a[k];
        m += std::abs(in.K(e, k)) * xmag(k) + std::abs(in.C(e, k)) * vmag(k);
    }
    for (Eigen::Index h = 0; h < in.h_omega.size(); ++h) {
        A += in.h_amp(e, h) * sn(h);
        dA += in.h_amp(e, h) * in.h_omega(h) * cs(h);
        m += std::abs(in.h_amp(e, h) * sn(h));
    }
    const double sg = sf.kind == SwitchKind::release_pos ? 1.0 : -1.0;
    const double mu_n = in.mu_s(e) * in.normal(e);
    g = sg * A - mu_n;
    dg = sg * dA;
    scale = m + mu_n;
}

}  // namespace hsnc
