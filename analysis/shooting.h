// hsnc -- the period map of a forced model and its exact derivative, the
// building block of shooting (hsnc::periodic) and of the continuation of
// periodic orbits over a parameter (hsnc sweep --continuation).
//
// P(y): the exact motion from the state y = (x, v, s) at t_s to t_s + period
// (s: the Jenkins sliders, if any; analysis/stick_tangent.h);
// M = dP/dy its monodromy matrix, from the segment transition matrices and
// the saltation matrix of every switch (tangent.h).
#pragma once

#include <complex>
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "flow.h"

namespace hsnc::analysis {

struct PeriodMapValue {
    bool ok = false;        ///< the run went through and gave finite numbers
    std::string message;    ///< why not
    Eigen::VectorXd Py;     ///< P(y)
    Eigen::MatrixXd M;      ///< dP/dy (2n + nj square), y = (x, v, s)
    double residual = INFINITY;  ///< period_residual(y, P(y))
    std::size_t events = 0;      ///< switch events over the period
    std::size_t grazing = 0;     ///< grazing switches (near-zero normal velocity; tangent.h)
    std::size_t singular = 0;    ///< switches where the derivative does not exist
    Configuration end;           ///< the configuration P(y) is in (its vector field: hsnc::modes)
};

/// P(y) and dP/dy over [ts, te] with the flow's model.
PeriodMapValue evaluate_period_map(Flow& flow, double ts, double te, const Eigen::VectorXd& y);

/// |P(y) - y| with lengths (positions and sliders) and velocities each
/// relative to the largest of their kind in y and P(y) (INFINITY when such a
/// scale is 0 and the difference is not); `masses` = n.
double period_residual(const Eigen::VectorXd& y, const Eigen::VectorXd& Py, std::size_t masses);

/// The eigenvalues of M, largest |mu| first (stable order among equals).
std::vector<std::complex<double>> floquet_multipliers(const Eigen::MatrixXd& M);

/// The neutral multipliers of a family of orbits (hsnc/periodic.h,
/// PeriodicResult::neutral): how many of `mu` (the eigenvalues of M) lie
/// within kNeutralMultiplier of +1, when M - I has as many independent null
/// directions (singular values at most 1e-8 max(1, |M|)): each is then a
/// direction along which the orbit moved is an orbit too, to first order,
/// and a perturbation along it neither grows nor decays. 0 when there are
/// fewer (a Jordan block: perturbations drift, as a free body's position).
std::size_t family_multipliers(const Eigen::MatrixXd& M, const std::vector<std::complex<double>>& mu);

/// Stable: every multiplier inside the unit circle by kNeutralMultiplier,
/// but for `neutral` of those at +1 (family_multipliers).
bool orbit_stable(const std::vector<std::complex<double>>& mu, std::size_t neutral);

}  // namespace hsnc::analysis
