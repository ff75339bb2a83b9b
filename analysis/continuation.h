// hsnc -- pseudo-arclength continuation of periodic orbits over a parameter
// (hsnc sweep --continuation; the method in api/hsnc/sweep.h). Private to
// the library.
#pragma once

#include <complex>
#include <functional>
#include <string>
#include <vector>

#include <map>
#include <memory>
#include <utility>

#include <Eigen/Core>

#include "flow.h"
#include "hsnc/periodic.h"
#include "hsnc/sweep.h"
#include "model.h"
#include "shooting.h"
#include "sweep_point.h"

namespace hsnc::sweep_detail {

/// One branch to follow.
struct Branch {
    /// The model with the parameter at a value; InputError when it is not
    /// valid there.
    std::function<Model(double)> model_at;
    /// The model at `start` (its initial state starts the transient).
    const Model* start_model = nullptr;
    double start = 0, end = 0;  ///< the parameter runs from start towards end
    double value2 = 0;          ///< the second parameter (NaN without): SweepPoint::value2
    std::string param;          ///< its name, for messages
    std::string where;          ///< the rest of a point's name (", beta = 0.3 (up)")
};

/// Follows the branch; calls `done(point, seconds)` after each point (in
/// order). Returns the points (see api/hsnc/sweep.h for what they hold).
/// SweepOptions::stop ends it after the point under way, `*cut` (when given) then true.
std::vector<SweepPoint> run_continuation(const Branch& branch, const SweepOptions& options,
                                         const std::function<void(const SweepPoint&, double)>& done,
                                         bool* cut = nullptr);

/// The bifurcations (fold, period_doubling, neimark_sacker, joined by '+')
/// crossed between orbits with multipliers `a` and `b` ("" for none).
/// `neutral_a`, `neutral_b`: each orbit's multipliers at +1 of a family of
/// orbits (stuck sliders or masses, hsnc/periodic.h): that many multipliers
/// closest to +1 count as just inside the unit circle (a family's +1 wobbles
/// about 1 by rounding: no fold; a multiplier leaving a family's +1 outward is one).
std::string bifurcations_between(const std::vector<std::complex<double>>& a, const std::vector<std::complex<double>>& b,
                                 std::size_t neutral_a = 0, std::size_t neutral_b = 0);

// ---- the pieces a branch and a curve of special points share ----

/// The period map over `multiple` forcing periods at parameter values (p,
/// and q: a curve's second parameter), the models and flows of a few values
/// kept (a corrector and its central differences come back to the same values).
class PeriodMaps {
public:
    /// `model_at(p, q)`: the model there (InputError when it is not valid);
    /// `param` names p in messages.
    PeriodMaps(std::function<Model(double, double)> model_at, std::string param, int multiple);
    /// A branch's (q unused).
    PeriodMaps(const Branch& b, int multiple);

    /// P(y) and dP/dy at (p, q); not ok (with the reason) when the model is invalid there.
    analysis::PeriodMapValue eval(double p, double q, const Eigen::VectorXd& y);
    analysis::PeriodMapValue eval(double p, const Eigen::VectorXd& y) { return eval(p, 0.0, y); }
    /// The model at (p, q) (InputError when invalid there).
    const Model& model(double p, double q) { return flow_at(p, q).model; }
    const Model& model(double p) { return model(p, 0.0); }

    std::size_t runs = 0;  ///< period-map runs so far

private:
    struct At {
        Model model;
        double period = 0;
        std::unique_ptr<analysis::Flow> flow;
    };
    At& flow_at(double p, double q);
    std::function<Model(double, double)> model_at_;
    std::string param_;
    int multiple_;
    std::map<std::pair<double, double>, std::unique_ptr<At>> cache_;
};

/// Whether `labels` (SweepPoint::bifurcation: '+'-joined) holds `name`.
bool has_label(const std::string& labels, const std::string& name);

/// A branch's one row when it cannot begin: a failed point at its start
/// (second parameter `value2`) saying why.
SweepPoint failed_start(const Branch& b, double value2, const std::string& reason, std::size_t masses,
                        std::size_t harmonics);
/// The state y = (x, v, s) as the sweep carries it (n masses).
State state_of(const Eigen::VectorXd& y, std::size_t n);
/// The state y = (x, v, s) of an orbit hsnc::periodic found.
Eigen::VectorXd orbit_state(const PeriodicResult& r);
/// Its monodromy matrix.
Eigen::MatrixXd monodromy_of(const PeriodicResult& r);
/// hsnc::periodic's orbit of `model` from `start` (on the Eigen solver, as
/// every point of a sweep), to the residual `tolerance`, of `multiple` forcing periods.
PeriodicResult shoot_orbit(Model model, const State& start, double tolerance, int multiple);
/// The unit null vector of the m x (m + 1) Jacobian J with no component along
/// the rows of F, turned the way of `previous`.
Eigen::VectorXd tangent(const Eigen::MatrixXd& J, const Eigen::VectorXd& previous, const Eigen::MatrixXd& F);

}  // namespace hsnc::sweep_detail
