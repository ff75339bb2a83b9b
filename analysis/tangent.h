// hsnc -- the exact tangent dynamics of a run: how a small change of the
// state at one instant changes the state later, without finite differences.
//
// State y = (x, v), 2n numbers (positions, then velocities, in model order).
// Between two switches the motion is linear with constant forces, so a
// perturbation dy obeys dy' = A(cfg) dy and moves by the segment's state
// transition matrix Phi(tau) = exp(A tau), written here in closed form from
// the same modal decomposition the segment solver uses (model/modal.h) -- with
// dampers (non-proportional damping) as the matrix exponential of the state
// generator, by Eigen's scaling and squaring (to rounding, no integration) --
// per mode j, q'' + c_j q' + lambda_j q = 0 with c_j = alpha + beta lambda_j,
// in every regime (rigid, under-, critically, over-damped). Friction forces,
// loads and forcing are constant or given functions of time: they do not
// enter Phi. A stuck mass is a fixed support: its dx stays, its dv is 0, and
// its dx acts on the free masses through the stiffness coupling K_FS as a
// constant force (a static response per mode). A perturbation of a stuck
// mass's velocity is gone after any positive time (the mass stops again
// within a time proportional to it, a position change of second order), so
// the dv columns of stuck masses are 0.
//
// At a switch instant the state is continuous but the vector field f jumps,
// and the switch instant moves with the perturbation: the saltation matrix
//     S = I + (f+ - f-) h_y^T / (dh/dt)
// maps dy just before to just after (h: the switch function that reached
// zero, h_y its gradient, dh/dt = h_y f- + h_t its rate, f- and f+ the vector
// fields before and after every transition at that instant). f+ - f- has
// velocity components only (velocities are continuous):
//   contact close/open  the contact's Rayleigh damper appears/vanishes: -+beta k G' on a, the opposite on b;
//                       with h = G and dh/dt = G', S = I -+ beta k M^-1 (e_a - e_b)(e_a - e_b)^T (x columns)
//   stick               a_i -> 0 with h = v_i, dh/dt = a_i-: S zeroes dv_i (a direction collapses)
//   reversal            a_i- -> a_i+: dv_i is scaled by a_i+ / a_i-
//   release             a_i = 0 -> (A_i - mu_k N_i sgn)/m_i, h = +-A_i - mu_s N_i, h_y = -+(K_i., C_i.)
// and any cascade at one instant (a contact whose damper jump releases a
// stuck mass) is one switch with the final vector field. Several functions
// reaching zero at one instant (not generic: the flow is not differentiable
// there) are taken in the order the search reports them, each with the
// vector field the transitions so far give.
#pragma once

#include <map>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "configuration.h"
#include "engine.h"
#include "model.h"

namespace hsnc::analysis {

/// Closed-form Phi(tau) and saltation matrices of one model. Keeps a reference
/// to `model`, which must outlive it; caches the modal data of each
/// configuration it is asked for.
class Tangent {
public:
    explicit Tangent(const Model& model);
    Tangent(const Model&& model) = delete;  ///< would dangle
    ~Tangent();
    Tangent(Tangent&&) noexcept;

    /// State (x, v), then every Jenkins slider (analysis/stick_tangent.h).
    std::size_t dim() const { return 2 * model_.dof() + model_.jenkins.size(); }

    /// Phi(tau) of configuration cfg (2n x 2n).
    Eigen::MatrixXd transition(const Configuration& cfg, double tau);
    /// Y <- Phi(tau) Y.
    void apply_transition(const Configuration& cfg, double tau, Eigen::MatrixXd& Y);
    /// Largest modal damping c_j = alpha + beta lambda_j of cfg (>= the
    /// fastest decay rate of any mode): over 1/rate seconds no two directions
    /// part by more than a factor e^2.
    double max_rate(const Configuration& cfg);

    /// The saltation matrix of one switch instant (2n x 2n).
    Eigen::MatrixXd saltation(const SwitchRecord& instant);
    /// The grazing ratio |G'| Omega / |G''| of the contacts switching at the
    /// instant (the smallest; see GrazingMonitor); +infinity when no contact
    /// switches, NaN when G' = G'' = 0.
    double grazing_ratio(const SwitchRecord& instant);
    /// Y <- S Y. Returns false when a switch is grazing (dh/dt = 0 with a
    /// jump in the vector field: the derivative does not exist); Y is then
    /// left as it was.
    bool apply_saltation(const SwitchRecord& instant, Eigen::MatrixXd& Y);

private:
    struct ConfigData;
    const ConfigData& data(const Configuration& cfg);

    const Model& model_;
    /// Jenkins elements or stuck pairs: the full-state generator and field
    /// (analysis/stick_tangent.h) instead of the modal forms.
    bool stick_ = false;
    std::map<Configuration, std::unique_ptr<ConfigData>> cache_;
};

/// Grazing: a contact that closes or opens with (almost) zero normal velocity
/// G'. There the flow map is not smooth: a perturbation to one side makes the
/// contact engage for a time of order sqrt(depth), to the other it misses, so
/// the derivative the saltation matrices give (it exists at every transversal
/// switch) tells little about perturbations of the size of the penetration,
/// and where dh/dt = 0 exactly the saltation matrix does not exist (1/dh/dt).
/// Measured at the switch, without any scale of the motion: the ratio
/// r = |G'| Omega / |G''| (G'' from the accelerations before the switch,
/// Omega the largest of the configuration's natural frequencies and the
/// forcing frequencies). Near a turning point of G at phase distance d, r is
/// about tan d, and a stop reached with a penetration eps of the motion's
/// amplitude gives r about sqrt(2 eps); a transversal crossing gives r of order
/// 1 (less when the forcing is far above the natural frequencies). A switch
/// instant counts as grazing when a contact switches at it with
/// r <= kGrazingRatio (a penetration below about 5e-9 of the amplitude), or
/// when its saltation matrix does not exist. A touch that the engine resolves
/// without any switch (a gap reaching exactly 0 with G' = 0) is not seen.
inline constexpr double kGrazingRatio = 1e-4;

class GrazingMonitor {
public:
    /// `tangent` gives the configurations' natural frequencies; it must outlive the monitor.
    explicit GrazingMonitor(Tangent& tangent) : tangent_(tangent) {}
    /// A switch instant; `singular`: its saltation matrix does not exist.
    void on_switch(const SwitchRecord& instant, bool singular);
    /// Grazing switch instants so far.
    std::size_t count() const { return grazing_; }
    /// Switch instants without a saltation matrix (counted as grazing too).
    std::size_t singular() const { return singular_; }

private:
    Tangent& tangent_;
    std::size_t grazing_ = 0, singular_ = 0;
};

/// An Observer that accumulates the Jacobian of the flow map of a run, from
/// the run's start (or from `from`, a time inside it) to its end:
/// J = S_k Phi_k ... S_1 Phi_1. Forward samples and events to `inner` (may be null).
class JacobianObserver : public Observer {
public:
    JacobianObserver(const Model& model, Observer* inner = nullptr);
    bool wants_segments() const override { return true; }
    void on_sample(double t, const double* x, const double* v) override;
    void on_event(double t, EventKind kind, int element, const double* x, const double* v) override;
    bool on_progress(double t) override;
    void on_segment(const SegmentRecord& segment) override;
    void on_switch(const SwitchRecord& instant) override;

    const Eigen::MatrixXd& jacobian() const { return J_; }
    /// Grazing switch instants (GrazingMonitor), those without a derivative included.
    std::size_t grazing() const { return grazing_.count(); }
    /// Switch instants whose derivative does not exist (skipped: J is not the derivative).
    std::size_t singular() const { return grazing_.singular(); }
    /// Switch instants seen, by number of functions switching at once (1, more).
    std::size_t single_switches() const { return single_; }
    std::size_t multiple_switches() const { return multiple_; }

private:
    Tangent tangent_;
    Observer* inner_;
    Eigen::MatrixXd J_;
    GrazingMonitor grazing_;
    std::size_t single_ = 0, multiple_ = 0;
};

}  // namespace hsnc::analysis
