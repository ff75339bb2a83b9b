// hsnc -- ties: the time derivatives of the motion and of the switch functions
// at one instant, from the equation of motion itself, and bounds on them over
// a segment (interface.md "Ties and touches": where a switch function is 0
// at an instant, its first non-zero time derivative decides).
//
// The engine uses them at a segment start where a switch function sits at
// zero with a vanishing rate (a contact at rest on its gap, a mass released
// or stuck on a tie): the first non-zero derivative, of order m, says whether
// it heads across now (it switches at this instant) or into its safe side. In
// the latter case the guaranteed step bound h + h' s - B s^2/2 is useless
// (h = h' = 0 while h grows like s^m: the steps shrink with s^(m/2)), so the
// engine uses Taylor's theorem instead: with B' >= |h^(m+1)| over [0, T]
// (derivative_bound),
//     h(s) >= s^m/m! (|h^(m)(0)| - B' s/(m+1)) > 0   for s < (m+1)|h^(m)(0)|/B',
// so no root of h lies there (the same argument as the reference engine's,
// reference/reference.cpp, with B' from an energy bound instead of modes).
#pragma once

#include <vector>

#include "configuration.h"
#include "model.h"
#include "switch_function.h"

namespace hsnc {

/// Time derivatives of the motion at one instant (t + t_lo) in one
/// configuration, k = 0..order (x holds the Jenkins sliders after the masses;
/// A_i includes the Jenkins elements' forces, assembly.h):
///   x_i^(k+2) = (A_i^(k) - [k = 0] mu_k N_i sgn_i)/m_i for a free mass,
///   x_i^(k) = 0 for k >= 1 for a stuck one, where
///   A_i^(k) = [k = 0] (load_i + contact preloads) - (K x^(k))_i - (C x^(k+1))_i
///             + sum_h F_hi Omega_h^k sin(Omega_h t + phase_h + k pi/2)
/// (K, C of the configuration). Each derivative carries the magnitude of its
/// terms: it counts as zero within 16 eps of that (tie_noise).
struct MotionSeries {
    std::vector<std::vector<double>> x;    ///< x[k][i] = x_i^(k)
    std::vector<std::vector<double>> mag;  ///< the magnitude of the terms of x[k][i]
    std::vector<double> slider;            ///< slider position of every Jenkins element at the instant
    /// Coupled M: the kinetic friction force on every dof (0 on a stuck one),
    /// for the held force of held_mass.h; empty for a lumped M.
    std::vector<double> friction;
};

MotionSeries motion_series(const Model& model, const Configuration& cfg, const signed char* sgn, double t, double t_lo,
                           const double* x, const double* v, int order);

/// The motion together with the forcing harmonics is a linear system of
/// dimension at most 2n + 2H + 1, so a function whose derivatives up to this
/// order all vanish vanishes identically (Cayley-Hamilton).
int tie_order(const Model& model);

/// Rounding level of a derivative whose terms have magnitude `mag`.
double tie_noise(double mag);

/// Derivatives k = 0..order-1 of switch function f (segment.h) at the
/// series' instant, with the magnitudes of their terms, from a series of
/// order `order` (the configuration and time must be the series').
void switch_series(const Model& model, const Configuration& cfg, const SwitchFunction& f, double t, double t_lo,
                   const MotionSeries& series, std::vector<double>& d, std::vector<double>& mag);

/// Derivatives k = 0..order-1 of A_i (every force on mass i but friction, as
/// in motion_series) at the series' instant, with the magnitudes of their
/// terms, from a series of order `order` in cfg.
void force_series(const Model& model, const Configuration& cfg, int i, double t, double t_lo,
                  const MotionSeries& series, std::vector<double>& d, std::vector<double>& mag);

/// The magnitude of the terms of g_f' at (x, v) in cfg, as switch_series
/// computes them (its order-1 entry), without allocating or evaluating the
/// forcing: a cheap test of whether g_f' can be zero to rounding.
double rate_magnitude(const Model& model, const Configuration& cfg, const SwitchFunction& f, const double* x,
                      const double* v);

/// The sign of the first derivative of order 1 <= k <= max_order that is not
/// zero to rounding (|d_k| > tie_noise(mag_k)); 0 when none is. `order`
/// (when given) receives its order.
int first_nonzero_sign(const std::vector<double>& d, const std::vector<double>& mag, int max_order,
                       int* order = nullptr);

/// B >= |g_f^(k)(s)| for every s in [0, T] of the segment of `cfg` that
/// starts at the series' instant (k >= 2; the series of order >= k + 1).
/// Energy bound, valid for every damping C = alpha M + beta K with alpha,
/// beta >= 0: z = x^(j) (j >= 1) of the free masses solves
/// M z'' + C z' + K z = f^(j)(t) (constant forces drop), so
/// E_j = (z'^T M z' + z^T K z)/2 has dE_j/dt <= z'^T f^(j) <= sqrt(2 E_j) phi_j,
/// phi_j = sum_h |Omega_h|^j |M^(-1/2) F_h|, hence
///     |x_i^(j+1)(s)| <= R_j(T)/sqrt(m_i),  R_j(T) = sqrt(2 E_j(0)) + phi_j T.
/// +infinity when the damping is negative (not a valid model).
double derivative_bound(const Model& model, const Configuration& cfg, const SwitchFunction& f,
                        const MotionSeries& series, int k, double T);

}  // namespace hsnc
