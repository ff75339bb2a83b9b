#include "transitions.h"

#include <cmath>
#include <algorithm>
#include <limits>

#include "assembly.h"
#include "elements/contact.h"
#include "elements/friction.h"
#include "elements/jenkins.h"
#include "elements/motion.h"
#include "held_mass.h"
#include "number_text.h"
#include "tie_series.h"

namespace hsnc {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

// The double engine's arithmetic for the decision rules (transition_rules.h):
// forces and their derivatives from the equation of motion at (t, x, v) (the
// series of tie_series.h), zero meaning within 16 ulps of the magnitude of
// the terms.
class DoublePhysics {
public:
    using Scalar = double;
    // sgn: the live friction directions the rules update (a coupled M's
    // held force depends on how the other dofs slide, held_mass.h).
    DoublePhysics(const Model& model, double t, const double* x, double* v, const double* a,
                  const std::vector<signed char>& sgn, const ElementIndex* elements = nullptr)
        : model_(model), elements_(elements), t_(t), x_(x), v_(v), a_(a), n_(static_cast<int>(model.dof())),
          live_sgn_(sgn) {}

    int sign(double y) const { return y > 0 ? 1 : y < 0 ? -1 : 0; }
    bool negligible(double value, double magnitude) const { return std::fabs(value) <= 16 * kEps * magnitude; }
    double abs(double y) const { return std::fabs(y); }
    int dof() const { return n_; }
    std::size_t contacts() const { return model_.contacts.size(); }
    bool has_friction(int i) const { return model_.has_friction(i); }
    bool coupled() const { return model_.coupled_friction(); }
    // A friction acts on w = v_i - v_partner (the partner may be the ground).
    int partner(int i) const { return model_.friction_slot(static_cast<std::size_t>(i)).partner; }
    int velocity_sign(int i) const {
        const double* rows[] = {x_, v_};
        return sign(friction::velocity_value(Direction{i, partner(i)}, double_motion(rows), 0));
    }
    void stop(int i) { v_[i] = body(v_, partner(i)); }
    double force(const Configuration& cfg, int i) const {
        if (model_.coupled_friction()) {  // with i held, the rest moving (held_mass.h)
            double D, rate;
            held_driving_force(model_, cfg, live_sgn_.data(), i, t_, x_, v_, D, rate);
            return D;
        }
        return driving_force(model_, cfg, i, t_, x_, v_, elements_);
    }
    double static_limit(int i) const { return model_.friction_slot(i).mu_s * model_.normal_force(i); }
    double held_rate(const Configuration& cfg, int i) const {
        if (model_.coupled_friction()) {  // the held motion's own accelerations (held_mass.h)
            double D, rate;
            held_driving_force(model_, cfg, live_sgn_.data(), i, t_, x_, v_, D, rate);
            return rate;
        }
        std::vector<double> held(model_.dof(), 0.0);
        if (a_) held.assign(a_, a_ + model_.dof());
        const int p = partner(i);
        if (p == kGround) {
            held[i] = 0.0;
        } else {  // the pair held together: one acceleration, that of both masses as one body
            Configuration hold = cfg;
            hold.stuck[static_cast<std::size_t>(i)] = 1;
            const double mi = model_.masses[static_cast<std::size_t>(i)].m, mp = model_.masses[static_cast<std::size_t>(p)].m;
            held[i] = held[p] = (force_on_mass(model_, hold, i, t_, x_, v_) + force_on_mass(model_, hold, p, t_, x_, v_)) /
                                (mi + mp);
        }
        return driving_force_rate(model_, cfg, i, t_, v_, held.data());
    }
    int tie_order() const { return hsnc::tie_order(model_); }
    rules::Series<double> held_series(const Configuration& hold, const std::vector<signed char>& sgn, int i,
                                      int order) const {
        const MotionSeries m = motion_series(model_, hold, sgn.data(), t_, 0.0, x_, v_, order + 1);
        rules::Series<double> s;
        force_series(model_, hold, i, t_, 0.0, m, s.d, s.mag);
        return s;
    }
    rules::Series<double> gap_now(int c) const {
        const Contact& k = model_.contacts[static_cast<std::size_t>(c)];
        const double* rows[] = {x_, v_};
        const auto m = double_motion(rows);  // magnitudes |x|, |v|
        return {{contact::gap_value(k.direction(), k.gap, m, 0), contact::gap_value(k.direction(), k.gap, m, 1)},
                {contact::gap_magnitude(k.direction(), k.gap, m, 0), contact::gap_magnitude(k.direction(), k.gap, m, 1)}};
    }
    std::size_t jenkins() const { return model_.jenkins.size(); }
    bool slips_on(const Configuration& cfg, int j) const {
        if (!a_) return false;
        const Jenkins& e = model_.jenkins[static_cast<std::size_t>(j)];
        const double* rows[] = {x_, v_, a_};
        const auto m = double_motion(rows);  // magnitudes |x|, |v|, |a|
        const double w_rate = jenkins::slip_velocity_value(e.direction(), m, 1);
        const double mag = jenkins::slip_velocity_magnitude(e.direction(), m, 1);
        return !negligible(w_rate, mag) && sign(w_rate) == cfg.slip[static_cast<std::size_t>(j)];
    }
    int slip_velocity_sign(int j) const {
        const Jenkins& e = model_.jenkins[static_cast<std::size_t>(j)];
        const double* rows[] = {x_, v_};
        const auto m = double_motion(rows);  // magnitudes |x|, |v|
        const double rate = jenkins::slip_velocity_value(e.direction(), m, 0);
        return negligible(rate, jenkins::slip_velocity_magnitude(e.direction(), m, 0)) ? 0 : sign(rate);
    }
    bool rigid(int c) const { return model_.contacts[static_cast<std::size_t>(c)].rigid(); }
    // Newton's law at rigid stop c (contact.h impact), M^-1 w from held_mass.h.
    void impact(int c) {
        std::vector<double> w, Mw;
        const double wMw = impact_direction(model_, c, w, Mw);
        contact::impact(model_.contacts[static_cast<std::size_t>(c)].restitution, gap_now(c).d[1], wMw, Mw, v_, 1.0);
    }
    void prepare_ties(const Configuration& cfg, const std::vector<signed char>& sgn) {
        cfg_ = cfg;
        sgn_ = sgn;
    }
    // G^(k), k = 0..order, in the prepared configuration: the motion's
    // derivatives from the equation of motion (tie_series.h).
    rules::Series<double> tied_gap_series(int c, int order) const {
        const MotionSeries m = motion_series(model_, cfg_, sgn_.data(), t_, 0.0, x_, v_, order + 1);
        rules::Series<double> s;
        switch_series(model_, cfg_, SwitchFunction{SwitchKind::gap, c}, t_, 0.0, m, s.d, s.mag);
        return s;
    }

private:
    static double body(const double* y, int b) { return b == kGround ? 0.0 : y[b]; }
    const Model& model_;
    const ElementIndex* elements_;
    double t_;
    const double* x_;
    double* v_;
    const double* a_;
    int n_;
    Configuration cfg_;
    std::vector<signed char> sgn_;
    const std::vector<signed char>& live_sgn_;
};

}  // namespace

std::string resting_message(const Model& model, int contact, const std::string& t) {
    return "the motion comes to rest on the rigid stop '" + model.contacts[static_cast<std::size_t>(contact)].name +
           "' at t = " + t +
           " (it reaches the stop with no speed left and is pressed on): a resting contact on a rigid stop is not "
           "modelled; give the stop a stiffness k instead of restitution";
}

bool apply_switches(const Model& model, double t, const double* x, double* v, const double* a, Configuration& cfg,
                    std::vector<signed char>& sgn, const std::vector<SwitchFunction>& switched,
                    std::vector<Transition>& out, std::string& why, const ElementIndex* elements) {
    DoublePhysics p(model, t, x, v, a, sgn, elements);
    int resting = -1;
    if (rules::apply_switches(p, cfg, sgn, switched, out, &resting)) return true;
    why = resting >= 0 ? resting_message(model, resting, number_text(t))
                       : "friction decisions at t = " + std::to_string(t) + " do not settle";
    return false;
}

Configuration entered_configuration(const Model& model, double t, const double* x, const double* v,
                                    std::vector<signed char>& sgn, const Configuration* carried) {
    Configuration cfg = carried ? *carried : Configuration::all_open(model);
    // Nothing stops at t0: v is only read.
    DoublePhysics p(model, t, x, const_cast<double*>(v), nullptr, sgn);
    if (carried)
        rules::carried_configuration(p, cfg, sgn);
    else
        rules::entered_configuration(p, cfg, sgn);
    return cfg;
}

}  // namespace hsnc
