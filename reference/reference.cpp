// The reference engine: runtime/engine/engine.cpp's switch search written again on
// cl_F (see reference.h), with the contract's decision rules at a switch
// (runtime/engine/transition_rules.h, shared with the double engine) evaluated in its
// own arithmetic. The search is the same guaranteed one (docs/architecture.md "How switches
// are found"): each switch function is watched on the side its configuration
// fixes, every step is bounded by the smallest positive root of
// h + h' s - B s^2/2 (B >= |g''| from the segment), so no sign change is
// stepped over; a contact or release function switches when certainly negative
// (below its rounding level), a sliding velocity when it reaches zero; the
// root is then refined by Newton iterations (safeguarded by the bracket) to
// the working precision.
#include "reference_engine.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include <cln/integer.h>
#include <cln/rational.h>

#include "assembly.h"
#include "elements/contact.h"
#include "elements/friction.h"
#include "elements/jenkins.h"
#include "elements/motion.h"
#include "engine.h"
#include "error.h"
#include "mp_segment.h"
#include "number_text.h"
#include "sample_grid.h"
#include "switch_derivative.h"
#include "transition_rules.h"
#include "transitions.h"

namespace hsnc::reference {
namespace {

std::string time_text(const cl_F& t) { return number_text(cln::double_approx(t)); }

std::vector<double> to_double(const std::vector<cl_F>& y) {
    std::vector<double> d(y.size());
    for (std::size_t i = 0; i < y.size(); ++i) d[i] = cln::double_approx(y[i]);
    return d;
}

// Rounding level of a quantity of magnitude `scale` at this precision. 64 ulps:
// the terms of a switch function pass through a few dozen operations (modal
// projection, closed form, back-projection).
cl_F noise_of(const MpModel& mp, const cl_F& scale) { return mp.I(64) * mp.eps * scale; }

// ---- ties: the first non-zero time derivative (interface.md "Ties and touches") ----
//
// Derivatives of the motion at one instant, in one configuration, by the
// equation of motion itself: for a free mass
//     m_i x_i^(k+2) = A_i^(k) - [k = 0] mu_k N_i sgn_i,
//     A_i^(k) = [k = 0] f_i - (K x^(k))_i - (C x^(k+1))_i + sum_h F_hi Omega_h^k sin(Omega_h t + phase_h + k pi/2)
// (K, C of the configuration, contact preloads in f_i), and x_i^(k) = 0 for k >= 1 for a stuck one. Each
// derivative carries the magnitude of its terms, so "zero" means "within the rounding of its terms". The
// motion's state together with the forcing harmonics is a linear system of dimension 2n + 2H + 1, so a
// function whose first kTieOrder(n, H) derivatives all vanish vanishes identically (Cayley-Hamilton).
struct Taylor {
    std::vector<std::vector<cl_F>> x, xm;  ///< x^(k)_i and the magnitude of its terms, k = 0..order
    std::vector<cl_F> s;                   ///< the Jenkins sliders (constant while stuck)
    std::vector<cl_F> friction;            ///< a coupled M: the kinetic friction on every dof (MpModel::kinetic)
};

int tie_order(const MpModel& mp) { return 2 * mp.n + 2 * static_cast<int>(mp.h_omega.size()) + 2; }

// The k-th derivative of A_i (k >= 0) from x^(k), x^(k+1), with the magnitude of its terms.
void force_derivative(const MpModel& mp, const Configuration& cfg, int i, const cl_F& t, const Taylor& T, int k,
                      cl_F& value, cl_F& magnitude) {
    const std::vector<cl_F>&xk = T.x[static_cast<std::size_t>(k)], &xk1 = T.x[static_cast<std::size_t>(k) + 1];
    const std::vector<cl_F>&mk = T.xm[static_cast<std::size_t>(k)], &mk1 = T.xm[static_cast<std::size_t>(k) + 1];
    value = k == 0 ? mp.f_const[i] : mp.zero;
    magnitude = cln::abs(value);
    for (int j = 0; j < mp.n; ++j) {  // -alpha (M x^(k+1))_i
        const cl_F mij = mp.mass(i, j);
        if (j != i && cln::zerop(mij)) continue;
        value = value - mp.alpha * mij * xk1[j];
        magnitude = magnitude + cln::abs(mp.alpha * mij) * mk1[j];
    }
    // Every element's links and constant forces (model/elements/): a link -k (u - length) - c u'
    // gives -k u^(k) - c u^(k+1), and +k length at k = 0 only, as a constant force does.
    struct Derivative {
        const MpModel& mp;
        int i, k;
        const std::vector<cl_F>&xk, &xk1, &mk, &mk1;
        cl_F& value;
        cl_F& magnitude;
        void link(const Direction& d, const cl_F& kk, const cl_F& c, const cl_F& length) {
            if (d.a == d.b || !acts_on(d, i)) return;
            cl_F f = -(kk * (mp.body(xk, d.a) - mp.body(xk, d.b))) - c * (mp.body(xk1, d.a) - mp.body(xk1, d.b));
            cl_F fm = cln::abs(kk) * (mp.body(mk, d.a) + mp.body(mk, d.b)) + cln::abs(c) * (mp.body(mk1, d.a) + mp.body(mk1, d.b));
            if (k == 0) {
                f = f + kk * length;
                fm = fm + cln::abs(kk * length);
            }
            value = d.a == i ? value + f : value - f;
            magnitude = magnitude + fm;
        }
        void force(const Direction& d, const cl_F& f) {
            if (k != 0 || !acts_on(d, i)) return;
            value = d.a == i ? value + f : value - f;
            magnitude = magnitude + cln::abs(f);
        }
        const cl_F& zero() const { return mp.zero; }
    };
    mp.each_force(cfg, [&](std::size_t j) { return T.s[j]; }, Derivative{mp, i, k, xk, xk1, mk, mk1, value, magnitude});
    for (std::size_t h = 0; h < mp.h_omega.size(); ++h) {
        const cl_F& W = mp.h_omega[h];
        const cl_F arg = W * t + mp.h_phase[h];
        // d^k/dt^k sin(arg) = W^k sin(arg + k pi/2)
        cl_F d = (k % 2 == 0) ? cln::sin(arg) : cln::cos(arg);
        if (k % 4 == 2 || k % 4 == 3) d = -d;
        cl_F Wk = mp.one;
        for (int j = 0; j < k; ++j) Wk = Wk * W;
        value = value + mp.h_amp[h][i] * Wk * d;
        magnitude = magnitude + cln::abs(mp.h_amp[h][i]) * Wk;
    }
}

Taylor taylor(const MpModel& mp, const Configuration& cfg, const std::vector<signed char>& sgn, const cl_F& t,
              const std::vector<cl_F>& x, const std::vector<cl_F>& v, int order) {
    const int n = mp.n;
    Taylor T;
    T.x.assign(static_cast<std::size_t>(order) + 1, std::vector<cl_F>(static_cast<std::size_t>(n), mp.zero));
    T.xm = T.x;
    T.s.assign(x.begin() + n, x.end());
    // A mass stuck to its partner moves with it: one body of both masses (rider[p]).
    std::vector<int> rider(static_cast<std::size_t>(n), -1);
    for (int i = 0; i < n; ++i)
        if (mp.rides(cfg, i)) rider[static_cast<std::size_t>(mp.partner[i])] = i;
    for (int i = 0; i < n; ++i) {
        T.x[0][i] = x[i];
        T.xm[0][i] = cln::abs(x[i]);
        if (order >= 1 && !mp.fixed(cfg, i)) {
            T.x[1][i] = v[i];
            T.xm[1][i] = cln::abs(v[i]);
        }
    }
    if (mp.coupled_friction()) {  // x^(k+2) = T (T^T M T)^-1 T^T (A^(k) + [k = 0] friction) (held_mass.h)
        const auto inverse = mp.held_inverse(cfg.stuck);
        T.friction = mp.kinetic(cfg.stuck, sgn);
        std::vector<cl_F> A(static_cast<std::size_t>(n)), m(static_cast<std::size_t>(n));
        for (int k = 0; k + 2 <= order; ++k) {
            for (int i = 0; i < n; ++i) {
                force_derivative(mp, cfg, i, t, T, k, A[i], m[i]);
                if (k == 0) A[i] = A[i] + T.friction[i], m[i] = m[i] + cln::abs(T.friction[i]);
            }
            for (int i = 0; i < n; ++i) {
                cl_F a = mp.zero, am = mp.zero;
                for (int j = 0; j < n; ++j) a = a + inverse[i][j] * A[j], am = am + cln::abs(inverse[i][j]) * m[j];
                T.x[k + 2][i] = a;
                T.xm[k + 2][i] = am;
            }
        }
        return T;
    }
    for (int k = 0; k + 2 <= order; ++k)
        for (int i = 0; i < n; ++i) {
            if (cfg.stuck[i]) continue;  // held still, or moved with its partner below
            cl_F A, m, mass = mp.m[i];
            force_derivative(mp, cfg, i, t, T, k, A, m);
            const int r = rider[static_cast<std::size_t>(i)];
            if (r >= 0) {
                cl_F Ar, mr;
                force_derivative(mp, cfg, r, t, T, k, Ar, mr);
                A = A + Ar, m = m + mr, mass = mass + mp.m[r];
            }
            if (k == 0)  // kinetic friction of a sliding mass, and its reaction on the partner
                for (int q = 0; q < n; ++q) {
                    if (sgn[q] == 0 || (q != i && mp.partner[q] != i)) continue;
                    const cl_F fr = mp.mu_k[q] * mp.normal[q];
                    A = (q == i) == (sgn[q] > 0) ? A - fr : A + fr;
                    m = m + fr;
                }
            T.x[k + 2][i] = A / mass;
            T.xm[k + 2][i] = m / mass;
            if (r >= 0) {
                T.x[k + 2][r] = T.x[k + 2][i];
                T.xm[k + 2][r] = T.xm[k + 2][i];
            }
        }
    return T;
}

// Derivatives 0..order of G_c, from a Taylor expansion of order `order`.
void gap_series(const MpModel& mp, int c, const Taylor& T, std::vector<cl_F>& d, std::vector<cl_F>& m) {
    const auto& l = mp.contacts[static_cast<std::size_t>(c)];
    d.clear();
    m.clear();
    const RowsMotion<cl_F, std::vector<std::vector<cl_F>>> motion(T.x, &T.xm, mp.zero);
    for (std::size_t k = 0; k < T.x.size(); ++k) {
        d.push_back(contact::gap_value(l.direction(), l.gap, motion, static_cast<int>(k)));
        m.push_back(contact::gap_magnitude(l.direction(), l.gap, motion, static_cast<int>(k)));
    }
}

// Derivatives 0..order-1 of A_i, from a Taylor expansion of order `order`.
void force_series(const MpModel& mp, const Configuration& cfg, int i, const cl_F& t, const Taylor& T,
                  std::vector<cl_F>& d, std::vector<cl_F>& m) {
    d.clear();
    m.clear();
    for (std::size_t k = 0; k + 1 < T.x.size(); ++k) {
        cl_F A, mag;
        force_derivative(mp, cfg, i, t, T, static_cast<int>(k), A, mag);
        d.push_back(A);
        m.push_back(mag);
    }
}

// Derivatives 0..order-1 of D_i (assembly.h driving_force): A_i's, or against
// its partner p, (m_p A_i - m_i A_p)/(m_i + m_p).
void driving_series(const MpModel& mp, const Configuration& cfg, int i, const cl_F& t, const Taylor& T,
                    std::vector<cl_F>& d, std::vector<cl_F>& m) {
    if (mp.coupled_friction()) {  // D_i^(k) = P_i . (A^(k) + [k = 0] friction), i held (MpModel::held_row)
        const std::vector<cl_F> P = mp.held_row(mp.held_inverse(cfg.stuck), cfg.stuck, i);
        d.assign(T.x.size() - 1, mp.zero);
        m.assign(T.x.size() - 1, mp.zero);
        for (int q = 0; q < mp.n; ++q) {
            if (cln::zerop(P[static_cast<std::size_t>(q)])) continue;
            std::vector<cl_F> dq, mq;
            force_series(mp, cfg, q, t, T, dq, mq);
            const cl_F fr = T.friction.empty() ? mp.zero : T.friction[static_cast<std::size_t>(q)];
            for (std::size_t k = 0; k < d.size(); ++k) {
                const cl_F a = k == 0 ? dq[k] + fr : dq[k], am = k == 0 ? mq[k] + cln::abs(fr) : mq[k];
                d[k] = d[k] + P[static_cast<std::size_t>(q)] * a;
                m[k] = m[k] + cln::abs(P[static_cast<std::size_t>(q)]) * am;
            }
        }
        return;
    }
    force_series(mp, cfg, i, t, T, d, m);
    const int p = mp.partner[i];
    if (p == kGround) return;
    std::vector<cl_F> dp, mpart;
    force_series(mp, cfg, p, t, T, dp, mpart);
    for (std::size_t k = 0; k < d.size(); ++k) {
        d[k] = mp.against_partner(i, d[k], dp[k]);
        m[k] = mp.against_partner_magnitude(i, m[k], mpart[k]);
    }
}

// The reference's arithmetic for the decision rules (runtime/engine/transition_rules.h,
// shared with the double engine): forces and derivatives on cl_F from its own
// MpModel, its own Taylor expansions, zero meaning below noise_of().
struct MpArithmetic {
    using Scalar = cl_F;
    const MpModel& mp;
    int sign(const cl_F& y) const { return cln::plusp(y) ? 1 : cln::minusp(y) ? -1 : 0; }
    bool negligible(const cl_F& value, const cl_F& magnitude) const { return cln::abs(value) <= noise_of(mp, magnitude); }
    cl_F abs(const cl_F& y) const { return cln::abs(y); }
};

class MpPhysics : public MpArithmetic {
public:
    /// The state (t, x, v) at the instant; a: the accelerations just before (null at t0).
    /// sgn: the live friction directions the rules update (a coupled M's held force reads them).
    MpPhysics(const Model& model, const MpModel& mp, const cl_F& t, const std::vector<cl_F>& x,
              std::vector<cl_F>& v, const std::vector<cl_F>* a, const std::vector<signed char>& sgn)
        : MpArithmetic{mp}, model_(model), t_(t), x_(x), v_(v), a_(a), live_sgn_(sgn) {}

    std::size_t jenkins() const { return mp.jenkins.size(); }
    // A slipping element whose relative acceleration (just before) keeps the slip's sign: no stick.
    bool slips_on(const Configuration& cfg, int j) const {
        if (!a_) return false;
        const MpModel::Link& e = mp.jenkins[static_cast<std::size_t>(j)];
        const cl_F* rows[] = {a_->data()};
        const RowsMotion<cl_F, decltype(rows)> m(rows, nullptr, mp.zero);  // magnitudes |a|
        const cl_F w_rate = along(e.direction(), m, 0);
        const cl_F mag = along_magnitude(e.direction(), m, 0);
        return !negligible(w_rate, mag) && sign(w_rate) == cfg.slip[static_cast<std::size_t>(j)];
    }
    int dof() const { return mp.n; }
    std::size_t contacts() const { return mp.contacts.size(); }
    bool has_friction(int i) const { return model_.has_friction(i); }
    bool coupled() const { return mp.coupled_friction(); }
    // A friction acts on w = v_i - v_partner (the partner may be the ground).
    int velocity_sign(int i) const { return sign(v_[static_cast<std::size_t>(i)] - mp.body(v_, mp.partner[i])); }
    void stop(int i) { v_[static_cast<std::size_t>(i)] = mp.body(v_, mp.partner[i]); }
    cl_F force(const Configuration& cfg, int i) const {
        if (mp.coupled_friction()) return held_force(cfg, i, false);
        const cl_F A = mp.force_on_mass(cfg, i, t_, x_, v_);
        const int p = mp.partner[i];
        return p == kGround ? A : mp.against_partner(i, A, mp.force_on_mass(cfg, p, t_, x_, v_));
    }
    cl_F static_limit(int i) const { return mp.mu_s[i] * mp.normal[i]; }
    cl_F held_rate(const Configuration& cfg, int i) const {
        if (mp.coupled_friction()) return held_force(cfg, i, true);
        std::vector<cl_F> held = a_ ? *a_ : std::vector<cl_F>(v_.size(), mp.zero);
        const int p = mp.partner[i];
        if (p == kGround) {
            held[static_cast<std::size_t>(i)] = mp.zero;
            return mp.force_rate_on_mass(cfg, i, t_, v_, held);
        }
        // The pair held together: one acceleration, that of both masses as one body.
        Configuration hold = cfg;
        hold.stuck[static_cast<std::size_t>(i)] = 1;
        const cl_F a = (mp.force_on_mass(hold, i, t_, x_, v_) + mp.force_on_mass(hold, p, t_, x_, v_)) / (mp.m[i] + mp.m[p]);
        held[static_cast<std::size_t>(i)] = held[static_cast<std::size_t>(p)] = a;
        return mp.against_partner(i, mp.force_rate_on_mass(cfg, i, t_, v_, held), mp.force_rate_on_mass(cfg, p, t_, v_, held));
    }
    int tie_order() const { return reference::tie_order(mp); }
    rules::Series<cl_F> held_series(const Configuration& hold, const std::vector<signed char>& sgn, int i,
                                    int order) const {
        const Taylor T = taylor(mp, hold, sgn, t_, x_, v_, order + 1);
        rules::Series<cl_F> s;
        driving_series(mp, hold, i, t_, T, s.d, s.mag);
        return s;
    }
    rules::Series<cl_F> gap_now(int c) const {
        const auto& k = mp.contacts[static_cast<std::size_t>(c)];
        const Direction w = k.direction();
        const cl_F* rows[] = {x_.data(), v_.data()};
        const RowsMotion<cl_F, decltype(rows)> m(rows, nullptr, mp.zero);  // magnitudes |x|, |v|
        return {{contact::gap_value(w, k.gap, m, 0), contact::gap_value(w, k.gap, m, 1)},
                {contact::gap_magnitude(w, k.gap, m, 0), contact::gap_magnitude(w, k.gap, m, 1)}};
    }
    int slip_velocity_sign(int j) const {
        const MpModel::Link& e = mp.jenkins[static_cast<std::size_t>(j)];
        const cl_F* rows[] = {v_.data()};
        const RowsMotion<cl_F, decltype(rows)> m(rows, nullptr, mp.zero);  // magnitudes |v|
        const cl_F rate = along(e.direction(), m, 0);
        return negligible(rate, along_magnitude(e.direction(), m, 0)) ? 0 : sign(rate);
    }
    bool rigid(int c) const { return model_.contacts[static_cast<std::size_t>(c)].rigid(); }
    // Newton's law at rigid stop c (contact.h impact) at this precision: M^-1 w
    // from the exact inverse of a coupled M (held_inverse with nothing held).
    void impact(int c) {
        const Contact& k = model_.contacts[static_cast<std::size_t>(c)];
        const auto n = static_cast<std::size_t>(mp.n);
        std::vector<cl_F> w(n, mp.zero), Mw(n, mp.zero);
        for_each_term(k.direction(), [&](int i, double wi) {
            w[static_cast<std::size_t>(i)] = w[static_cast<std::size_t>(i)] + mp.F(wi);
        });
        if (mp.coupled()) {
            const auto inverse = mp.held_inverse(std::vector<char>(n, 0));
            for (std::size_t r = 0; r < n; ++r)
                for (std::size_t q = 0; q < n; ++q) Mw[r] = Mw[r] + inverse[r][q] * w[q];
        } else {
            for (std::size_t i = 0; i < n; ++i) Mw[i] = w[i] / mp.m[i];
        }
        cl_F wMw = mp.zero;
        for (std::size_t i = 0; i < n; ++i) wMw = wMw + w[i] * Mw[i];
        contact::impact(mp.F(k.restitution), gap_now(c).d[1], wMw, Mw, v_.data(), mp.one);
    }
    void prepare_ties(const Configuration& cfg, const std::vector<signed char>& sgn) {
        cfg_ = cfg;
        sgn_ = sgn;
    }
    rules::Series<cl_F> tied_gap_series(int c, int order) const {
        const Taylor T = taylor(mp, cfg_, sgn_, t_, x_, v_, order);
        rules::Series<cl_F> s;
        gap_series(mp, c, T, s.d, s.mag);
        return s;
    }

private:
    // A coupled M: D_i with dof i and the stuck dofs held, the others sliding
    // along the live directions (model/held_mass.h at this precision), or its
    // rate along the held motion (`rate`).
    cl_F held_force(const Configuration& cfg, int i, bool rate) const {
        Configuration hold = cfg;
        hold.stuck[static_cast<std::size_t>(i)] = 1;
        const auto inverse = mp.held_inverse(hold.stuck);
        const std::vector<cl_F> P = mp.held_row(inverse, hold.stuck, i), fr = mp.kinetic(hold.stuck, live_sgn_);
        const std::size_t n = static_cast<std::size_t>(mp.n);
        std::vector<cl_F> f(n, mp.zero);
        for (std::size_t q = 0; q < n; ++q) f[q] = mp.force_on_mass(hold, static_cast<int>(q), t_, x_, v_) + fr[q];
        if (rate) {  // the friction is constant along the held motion: f' = A'(v, a), a = M_FF^-1 f
            std::vector<cl_F> a(n, mp.zero);
            for (std::size_t r = 0; r < n; ++r)
                for (std::size_t q = 0; q < n; ++q) a[r] = a[r] + inverse[r][q] * f[q];
            for (std::size_t q = 0; q < n; ++q) f[q] = mp.force_rate_on_mass(hold, static_cast<int>(q), t_, v_, a);
        }
        cl_F D = mp.zero;
        for (std::size_t q = 0; q < n; ++q) D = D + P[q] * f[q];
        return D;
    }
    const Model& model_;
    const cl_F& t_;
    const std::vector<cl_F>& x_;
    std::vector<cl_F>& v_;
    const std::vector<cl_F>* a_;
    const std::vector<signed char>& live_sgn_;
    Configuration cfg_;
    std::vector<signed char> sgn_;
};

// runtime/engine/transitions.cpp apply_switches, on cl_F: the shared rules with this arithmetic.
bool apply_switches(const Model& model, const MpModel& mp, const cl_F& t, const std::vector<cl_F>& x,
                    std::vector<cl_F>& v, const std::vector<cl_F>& a, Configuration& cfg, std::vector<signed char>& sgn,
                    const std::vector<SwitchFunction>& switched, std::vector<Transition>& out, std::string& why) {
    MpPhysics p(model, mp, t, x, v, &a, sgn);
    int resting = -1;
    if (rules::apply_switches(p, cfg, sgn, switched, out, &resting)) return true;
    why = resting >= 0 ? resting_message(model, resting, time_text(t))
                       : "friction decisions at t = " + time_text(t) + " do not settle";
    return false;
}

// The configuration entered at (t, x, v) (interface.md "At t0 ..."), by the shared rules.
Configuration entered_configuration(const Model& model, const MpModel& mp, const cl_F& t, const std::vector<cl_F>& x,
                                    const std::vector<cl_F>& v, std::vector<signed char>& sgn,
                                    const Configuration* carried) {
    Configuration cfg = carried ? *carried : Configuration::all_open(model);
    std::vector<cl_F> v_copy = v;  // nothing stops at t0
    MpPhysics p(model, mp, t, x, v_copy, nullptr, sgn);
    if (carried)
        rules::carried_configuration(p, cfg, sgn);  // across a change of load (EngineOptions::carried)
    else
        rules::entered_configuration(p, cfg, sgn);
    return cfg;
}

// Largest s >= 0 with h + hd s - B s^2/2 > 0 before it (h > 0); `unbounded` when none.
bool safe_step(const MpModel& mp, const cl_F& h, const cl_F& hd, const cl_F& B, cl_F& step) {
    if (!cln::plusp(B)) {
        if (!cln::minusp(hd)) return false;
        step = h / -hd;
        return true;
    }
    const cl_F root = cln::sqrt(hd * hd + mp.two * B * h);
    step = !cln::minusp(hd) ? (hd + root) / B : mp.two * h / (root - hd);
    return true;
}

}  // namespace

double relative_difference(const cl_F& a, const cl_F& b, double floor) {
    // Bring both to the lower precision (CLN's float contagion does it for a - b).
    const cl_F d = cln::abs(a - b);
    const double den = std::max({std::fabs(cln::double_approx(a)), std::fabs(cln::double_approx(b)), floor});
    if (cln::zerop(d)) return 0.0;
    return den > 0 ? cln::double_approx(d / cln::cl_float(den, d)) : cln::double_approx(d);
}

std::size_t search_step_limit(double span, double fastest_rate, const SearchLimits& limits) {
    const double periods = std::fabs(span) * fastest_rate / (2 * 3.141592653589793);
    const double n = static_cast<double>(limits.base_steps) + static_cast<double>(limits.steps_per_period) * periods;
    return n >= 1e18 ? static_cast<std::size_t>(1e18) : static_cast<std::size_t>(n);
}

namespace {

// What the tie rules decide at a segment start, per switch function: heading
// across now (leaves_now), or leaving zero into its side up to clear_until.
struct StartTies {
    std::vector<char> leaving, leaves_now;
    std::vector<cl_F> clear_until;
};

// Ties at the segment start: a function at zero whose first derivative
// vanishes too. Its direction is its first non-zero derivative, of order m
// (interface.md "Ties and touches"). One that heads across (into the side its
// configuration forbids) switches now, at this instant. One that heads into
// its side is `leaving` zero: the guaranteed bound h + h' s - B s^2/2 is
// useless for it (h = h' = 0 while h grows like s^m: the step would shrink
// with s^(m/2), the search crawl on for ever). Taylor's theorem with the
// bound B' >= |h^(m+1)| of the segment (MpSegment::derivative_bound) gives
// instead h(s) >= s^m/m! (|h^(m)(0)| - B' s/(m+1)) > 0 for s <
// (m+1)|h^(m)(0)|/B', so it is left out of the bound up to half that
// (`clear_until`); from there, once above its rounding band (h > 2 noise),
// the bound takes over. A function with no non-zero derivative (identically
// zero to rounding) stays leaving, with steps of at most tau (tau doubles).
template <class Noise>
void start_ties(const MpModel& mp, const MpSegment& S, const Configuration& cfg, const std::vector<signed char>& sgn,
                const cl_F& t, const std::vector<cl_F>& x, const std::vector<cl_F>& v, const MpEval& buf,
                const std::vector<cl_F>& side, const cl_F& tau_end, Noise&& noise, StartTies& ties) {
    const std::vector<SwitchFunction>& sw = S.switches();
    std::fill(ties.leaving.begin(), ties.leaving.end(), 0);
    std::fill(ties.leaves_now.begin(), ties.leaves_now.end(), 0);
    // The first derivatives (Taylor order 2) decide almost every function at zero (the ones
    // that just switched); the full expansion only when h' vanishes too.
    Taylor T1, T;
    bool have_t1 = false, have_t = false;
    std::vector<cl_F> d, m;
    auto series = [&](std::size_t f, const Taylor& X) {
        const int e = sw[f].element;
        d.clear(), m.clear();
        const RowsMotion<cl_F, std::vector<std::vector<cl_F>>> motion(X.x, &X.xm, mp.zero);
        const auto ee = static_cast<std::size_t>(e);
        const int orders = static_cast<int>(X.x.size());
        if (!is_release(sw[f].kind)) {
            // Velocities' series are one order shorter: w^(k) needs x^(k+1).
            const auto p = mp_elements(mp, [&](int j) { return X.s[static_cast<std::size_t>(j)]; });
            const int last = is_velocity(sw[f].kind) ? orders - 1 : orders;
            for (int k = 0; k < last; ++k) {
                d.push_back(switch_derivative(p, sw[f], motion, k));
                m.push_back(switch_magnitude(p, sw[f], motion, k));
            }
        } else {
            driving_series(mp, cfg, e, t, X, d, m);
            const int sigma = sw[f].kind == SwitchKind::release_pos ? 1 : -1;
            const cl_F limit = mp.mu_s[ee] * mp.normal[ee];
            for (std::size_t k = 0; k < d.size(); ++k) {
                d[k] = friction::release_value(sigma, d[k], limit, static_cast<int>(k));
                m[k] = friction::release_magnitude(m[k], limit, static_cast<int>(k));
            }
        }
    };
    for (std::size_t f = 0; f < sw.size(); ++f) {
        if (cln::abs(side[f] * buf.g[f]) > noise(f)) continue;
        if (!have_t1) T1 = taylor(mp, cfg, sgn, t, x, v, 2), have_t1 = true;
        series(f, T1);
        if (cln::abs(d[1]) > noise_of(mp, m[1])) continue;  // h' decides: the bound works
        if (!have_t) T = taylor(mp, cfg, sgn, t, x, v, tie_order(mp) + 1), have_t = true;
        series(f, T);
        int order = 0;
        const int dir = rules::first_nonzero_sign(MpArithmetic{mp}, rules::Series<cl_F>{d, m}, 1, &order) *
                        (cln::plusp(side[f]) ? 1 : -1);
        if (dir < 0) {
            ties.leaves_now[f] = 1;
            continue;
        }
        ties.leaving[f] = 1;
        ties.clear_until[f] = mp.zero;
        if (dir > 0) {
            const cl_F Bn = S.derivative_bound(f, order + 1, tau_end);
            const cl_F dm = cln::abs(d[static_cast<std::size_t>(order)]);
            ties.clear_until[f] = cln::plusp(Bn) ? cln::min(tau_end, mp.I(order + 1) * dm / (mp.two * Bn)) : tau_end;
        }
    }
}

// The zero of h_f = side_f g_f, beyond its trigger level at tau: by Newton
// iterations inside [prev_tau, tau] (the function is on its safe side at
// prev_tau); a stop (an armed velocity) still at or above zero by a forward
// Newton step onto v = 0.
cl_F locate_root(const MpModel& mp, const MpSegment& S, std::size_t f, const cl_F& side_f, const cl_F& h, const cl_F& hd,
                 bool stop, const cl_F& prev_tau, const cl_F& tau, const cl_F& t, MpEval& probe, std::size_t& evaluations) {
    cl_F lo = prev_tau, hi = tau, r = tau;
    if (stop && !cln::minusp(h)) {
        if (cln::minusp(hd)) r = tau + h / -hd;  // tiny forward step
        return r;
    }
    for (int k = 0; k < 60; ++k) {
        S.eval(r, probe);
        ++evaluations;
        const cl_F hr = side_f * probe.g[f], hdr = side_f * probe.dg[f];
        if (cln::zerop(hr)) break;
        if (cln::minusp(hr))
            hi = r;
        else
            lo = r;
        // Converged when the Newton correction is below the time's own rounding
        // (checked before the bracket test: it may round onto a bracket end).
        if (cln::minusp(hdr) && cln::abs(hr / hdr) <= mp.I(4) * mp.eps * (cln::abs(t) + cln::abs(r))) {
            r = r - hr / hdr;
            break;
        }
        cl_F next = cln::minusp(hdr) ? r - hr / hdr : (lo + hi) * mp.half;
        if (!(next > lo && next < hi)) next = (lo + hi) * mp.half;
        r = next;
    }
    if (stop && cln::minusp(h) && !cln::minusp(hd)) r = tau;  // touched zero and turned back
    return r;
}

// The run's guards against switches that do not let time move on: the same
// instant too often (chattering), too many switches in too short a span (Zeno,
// on the run's clock, as the engine's SwitchGuard).
class MpGuard {
public:
    MpGuard(const EngineOptions& options, const cl_F& t0) : options_(options), t0_(t0), last_(t0) {}
    void event(const cl_F& t) {
        recent_.push_back(t);
        if (recent_.size() > options_.zeno_events) recent_.pop_front();
    }
    /// "" or why the run stops, after the switches at t (nsw functions in cfg).
    RunStatus after_switch(const cl_F& t, std::size_t nsw, const std::string& cfg, std::string& why) {
        same_instant_ = have_last_ && t == last_ ? same_instant_ + 1 : 0;
        last_ = t;
        have_last_ = true;
        if (same_instant_ > 4 * (nsw + 2)) {
            why = "configuration keeps switching at t = " + time_text(t) + " (now '" + cfg + "')";
            return RunStatus::chattering;
        }
        if (recent_.size() >= options_.zeno_events &&
            cln::double_approx(recent_.back() - recent_.front()) <=
                options_.zeno_span * std::max(1.0, cln::double_approx(t - t0_))) {
            why = std::to_string(recent_.size()) + " switches between t = " + time_text(recent_.front()) + " and " +
                  time_text(recent_.back()) + " (accumulating switches, configuration '" + cfg + "')";
            return RunStatus::zeno;
        }
        return RunStatus::ok;
    }

private:
    const EngineOptions& options_;
    cl_F t0_;
    std::deque<cl_F> recent_;
    std::size_t same_instant_ = 0;
    bool have_last_ = false;
    cl_F last_;
};

// The safe step of the search from tau: no function reaches its trigger
// level inside it (a leaving function: up to its clear instant, then
// doubling), at least the time's own rounding (at t = tau = 0, that of the
// run's span).
template <class Noise>
cl_F search_step(const MpModel& mp, const MpSegment& S, const MpEval& buf, const std::vector<cl_F>& side,
                 const std::vector<char>& armed, const StartTies& ties, const cl_F& t, const cl_F& tau,
                 const cl_F& tau_end, const cl_F& span, Noise&& noise) {
    const std::vector<SwitchFunction>& sw = S.switches();
    cl_F step = tau_end - tau;
    if (S.has_max_step()) step = cln::min(step, S.max_step());
    for (std::size_t f = 0; f < sw.size(); ++f) {
        if (ties.leaving[f]) continue;
        const bool stop = is_velocity(sw[f].kind) && armed[f];
        const cl_F level = stop ? mp.zero : -(mp.two * noise(f));
        cl_F s;
        if (safe_step(mp, side[f] * buf.g[f] - level, side[f] * buf.dg[f], buf.bound[f], s)) step = cln::min(step, s);
    }
    cl_F floor_step = mp.I(4) * mp.eps * (cln::abs(t) + cln::abs(tau));
    if (cln::zerop(floor_step)) floor_step = mp.I(4) * mp.eps * span;
    for (std::size_t f = 0; f < sw.size(); ++f)
        if (ties.leaving[f])
            step = cln::min(step, tau < ties.clear_until[f] ? ties.clear_until[f] - tau : cln::max(tau, floor_step));
    return cln::max(step, floor_step);
}

// The side on which switch function f is watched in cfg: h = side g > 0 until it switches.
cl_F side_of(const MpModel& mp, const SwitchFunction& f, const Configuration& cfg, const std::vector<signed char>& sgn) {
    switch (f.kind) {
        case SwitchKind::gap: return cfg.closed[f.element] ? mp.one : -mp.one;
        case SwitchKind::velocity: return sgn[f.element] >= 0 ? mp.one : -mp.one;
        case SwitchKind::slip_velocity:  // w has the sign of the slip
            return cfg.slip[static_cast<std::size_t>(f.element)] >= 0 ? mp.one : -mp.one;
        default: return -mp.one;  // release and slip functions are negative while stuck
    }
}

}  // namespace

PreciseRun simulate_precise(const Model& model, int digits, const EngineOptions& options, Observer& observer,
                            const SearchLimits& limits, const std::vector<double>* offset) {
    if (digits < 17) throw InputError("reference::simulate_precise(): digits " + std::to_string(digits) + " < 17");
    // Jenkins elements: their sliders are state (x after the masses); a stuck pair rides one coordinate.
    const MpModel mp(model, digits);
    const std::size_t n = model.dof();
    PreciseRun run;
    RunSummary& sum = run.summary;
    std::vector<cl_F> x = mp.x0, v = mp.v0;
    if (offset && offset->size() == 2 * n)
        for (std::size_t i = 0; i < n; ++i) x[i] = x[i] + mp.F((*offset)[i]), v[i] = v[i] + mp.F((*offset)[n + i]);
    cl_F t = mp.t0;
    const cl_F t_end = mp.F(options.t_end);
    std::vector<signed char> sgn;
    Configuration cfg = entered_configuration(model, mp, t, x, v, sgn, options.carried ? &*options.carried : nullptr);

    std::map<Configuration, std::unique_ptr<MpSegment>> segments;
    MpGuard guard(options, mp.t0);

    const SampleGrid grid = sample_grid(options, model.t0);  // as the double engine: in double
    std::size_t k_next = options.first_sample;
    bool samples_done = !options.samples;

    auto finish = [&](RunStatus status, const std::string& message) {
        sum.status = status;
        sum.message = message;
        sum.t = cln::double_approx(t);
        sum.x = to_double(x);
        sum.slider.assign(sum.x.begin() + static_cast<std::ptrdiff_t>(n), sum.x.end());  // the sliders after the masses
        sum.x.resize(n);
        sum.v = to_double(v);
        sum.configuration = cfg;
        sum.configurations = segments.size();
        run.t = t;
        run.x = x;
        run.v = v;
        return run;
    };

    const std::size_t max_switches = model.max_switches();
    const std::size_t stride = std::max({model.contacts.size(), n, model.jenkins.size()});
    std::vector<cl_F> inherited(kSwitchKinds * stride, mp.zero);
    auto slot = [stride](const SwitchFunction& f) {
        return static_cast<std::size_t>(f.kind) * stride + static_cast<std::size_t>(f.element);
    };
    std::vector<cl_F> side(max_switches, mp.one), floor(max_switches, mp.zero);
    std::vector<char> armed(max_switches), has_root(max_switches);
    std::vector<cl_F> root(max_switches, mp.zero);
    StartTies ties{std::vector<char>(max_switches), std::vector<char>(max_switches),
                   std::vector<cl_F>(max_switches, mp.zero)};
    MpEval buf, dense, probe;
    std::vector<SwitchFunction> switched;
    std::vector<Transition> transitions;
    std::string why;

    while (true) {
        auto it = segments.find(cfg);
        if (it == segments.end()) it = segments.emplace(cfg, std::make_unique<MpSegment>(model, mp, cfg)).first;
        MpSegment& S = *it->second;
        S.setup(t, x, v, sgn);
        ++sum.segments;
        const std::vector<SwitchFunction>& sw = S.switches();
        const std::size_t nsw = sw.size();
        const cl_F tau_end = t_end - t;
        for (std::size_t f = 0; f < nsw; ++f) {
            side[f] = side_of(mp, sw[f], cfg, sgn);
            floor[f] = inherited[slot(sw[f])];
        }
        cl_F tau_now = mp.zero;
        auto noise = [&](const MpEval& e, std::size_t f) {
            return cln::max(noise_of(mp, e.scale[f] + cln::abs(e.dg[f]) * (cln::abs(t) + tau_now)), floor[f]);
        };
        auto eval = [&](const cl_F& tau) {
            S.eval(tau, buf);
            tau_now = tau;
            ++sum.evaluations;
        };
        auto h_of = [&](const MpEval& e, std::size_t f) { return side[f] * e.g[f]; };
        auto hd_of = [&](const MpEval& e, std::size_t f) { return side[f] * e.dg[f]; };

        // ---- find the earliest switch in (0, tau_end] ----
        bool found = false;
        cl_F found_tau = mp.zero;
        switched.clear();
        cl_F tau = mp.zero, prev_tau = mp.zero;
        eval(tau);
        for (std::size_t f = 0; f < nsw; ++f)
            armed[f] = is_velocity(sw[f].kind) && h_of(buf, f) > noise(buf, f);
        start_ties(mp, S, cfg, sgn, t, x, v, buf, side, tau_end, [&](std::size_t f) { return noise(buf, f); }, ties);
        // Every loop is bounded: a legitimate search takes a few steps per period of the segment's
        // fastest motion (and a few dozen Newton-like steps onto each root); far more is a stall.
        const std::size_t max_iter = search_step_limit(options.t_end - cln::double_approx(t),
                                                       cln::double_approx(S.fastest_rate()), limits);
        for (std::size_t iter = 0;; ++iter) {
            if (iter > max_iter)
                return finish(RunStatus::failure, "switch search stalls at t = " + time_text(t + tau) + " (more than " +
                                                      std::to_string(max_iter) + " steps in configuration '" +
                                                      cfg.spec(model) + "')");
            bool any = false;
            cl_F tau_star = mp.zero;
            for (std::size_t f = 0; f < nsw; ++f) {
                has_root[f] = 0;
                if (iter == 0 && ties.leaves_now[f]) {  // the motion leaves this contact's configuration now
                    has_root[f] = 1;
                    root[f] = mp.zero;
                    tau_star = mp.zero;
                    any = true;
                    continue;
                }
                const cl_F h = h_of(buf, f), hd = hd_of(buf, f), eps_f = noise(buf, f);
                const bool stop = is_velocity(sw[f].kind) && armed[f];
                if (stop ? !rules::stops_here(h, hd, buf.bound[f], eps_f, mp.zero, [&] { return mp.zero; }) : h >= -eps_f) continue;
                has_root[f] = 1;
                root[f] = locate_root(mp, S, f, side[f], h, hd, stop, prev_tau, tau, t, probe, sum.evaluations);
                tau_star = any ? cln::min(tau_star, root[f]) : root[f];
                any = true;
            }
            if (any) {
                const cl_F tol = mp.I(64) * mp.eps * (cln::abs(t) + cln::abs(tau_star));
                found = true;
                found_tau = cln::min(tau_star, tau_end);
                for (std::size_t f = 0; f < nsw; ++f)
                    if (has_root[f] && root[f] <= tau_star + tol) switched.push_back(sw[f]);
                eval(found_tau);
                for (std::size_t f = 0; f < nsw; ++f) {
                    if (has_root[f] && root[f] <= tau_star + tol) continue;
                    const cl_F h = h_of(buf, f), hd = hd_of(buf, f), eps_f = noise(buf, f);
                    const bool stop = is_velocity(sw[f].kind) && armed[f];
                    if (stop ? rules::stops_here(h, hd, buf.bound[f], eps_f, mp.zero, [&] { return mp.zero; }) : (h < -eps_f || (h <= eps_f && cln::minusp(hd))))
                        switched.push_back(sw[f]);
                }
                std::fill(inherited.begin(), inherited.end(), mp.zero);
                for (std::size_t f = 0; f < nsw; ++f) inherited[slot(sw[f])] = noise(buf, f);
                break;
            }
            if (tau >= tau_end) break;
            const cl_F step = search_step(mp, S, buf, side, armed, ties, t, tau, tau_end, cln::abs(t_end - mp.t0),
                                          [&](std::size_t f) { return noise(buf, f); });
            prev_tau = tau;
            tau = cln::min(tau + step, tau_end);
            eval(tau);
            for (std::size_t f = 0; f < nsw; ++f) {
                if (is_velocity(sw[f].kind) && !armed[f] && h_of(buf, f) > mp.two * noise(buf, f))
                    armed[f] = 1;
                if (ties.leaving[f] && tau >= ties.clear_until[f] && h_of(buf, f) > mp.two * noise(buf, f))
                    ties.leaving[f] = 0;
            }
        }

        // ---- samples up to the event (or t_end), from the closed form ----
        const cl_F t_seg_end = found ? t + found_tau : t_end;
        while (!samples_done) {
            const double tkd = grid.time(k_next);
            const cl_F tk = mp.F(tkd);
            if (found ? tk >= t_seg_end : tk > t_end) break;
            if (tk != t) S.eval(cln::max(mp.zero, tk - t), dense);  // else the segment's start state itself
            const std::vector<double> xd = to_double(tk == t ? x : dense.x), vd = to_double(tk == t ? v : dense.v);
            observer.on_sample(tkd, xd.data(), vd.data());
            if (grid.last(k_next)) samples_done = true;
            ++k_next;
        }

        // ---- advance to the event instant ----
        if (!found) eval(tau_end);
        x = buf.x;
        v = buf.v;
        for (std::size_t i = 0; i < n; ++i)
            if (cfg.stuck[i]) v[i] = mp.body(v, mp.carrier(cfg, static_cast<int>(i)));  // still, or with its carrier
        if (!found) {
            t = t_end;
            break;
        }
        t = t + found_tau;

        transitions.clear();
        if (!apply_switches(model, mp, t, x, v, buf.a, cfg, sgn, switched, transitions, why))
            return finish(RunStatus::chattering, why);
        if (!transitions.empty()) {
            const double td = cln::double_approx(t);
            const std::vector<double> xd = to_double(x), vd = to_double(v);
            for (const Transition& tr : transitions) {
                observer.on_event(td, tr.kind, tr.element, xd.data(), vd.data());
                run.events.push_back({t, tr.kind, tr.element, x, v});
                ++sum.events;
                guard.event(t);
            }
        }
        if (const RunStatus g = guard.after_switch(t, nsw, cfg.spec(model), why); g != RunStatus::ok)
            return finish(g, why);
        if (options.max_events && sum.events >= options.max_events)
            return finish(RunStatus::max_events, "stopped after " + std::to_string(sum.events) + " events");
        // Every switch: one at N digits costs far more than the observer's check
        // (a 40-DOF model's switches take seconds each: a progress bar must move).
        if (!observer.on_progress(cln::double_approx(t)))
            return finish(RunStatus::stopped, "stopped at t = " + time_text(t));
    }
    return finish(RunStatus::ok, "");
}

int carried_bits(int digits) {
    return static_cast<int>(cln::float_digits(cln::cl_float(1, cln::float_format(static_cast<unsigned long>(digits)))));
}

RunSummary simulate(const Model& model, int digits, const EngineOptions& options, Observer& observer) {
    if (digits < kMinDigits || digits > kMaxDigits)
        throw InputError("reference::simulate(): digits " + std::to_string(digits) + " outside " +
                         std::to_string(kMinDigits) + ".." + std::to_string(kMaxDigits));
    refuse_load_steps(model, "reference::simulate()");
    return simulate_precise(model, digits, options, observer).summary;
}

}  // namespace hsnc::reference
