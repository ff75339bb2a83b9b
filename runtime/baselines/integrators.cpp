#include "integrators.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#if HSNC_WITH_CVODE
#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>
#endif

#include <Eigen/Cholesky>

#include "assembly.h"
#include "engine.h"
#include "error.h"
#include "held_mass.h"
#include "sample_grid.h"
#include "switch_guard.h"
#include "transitions.h"

namespace hsnc {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The Jenkins sliders of a run, kept beside the ODE state (x, v): fixed while
// an element is stuck, x[a] - x[b] - slip F_s/k while it slips (assembly.h
// slider_position), so they need no integration; settled at every switch.
struct Sliders {
    const Model& model;
    std::vector<double> s, buf;
    /// T^T M T (Model::coupled_friction(): a coupled M, or a shared partner)
    /// factored for the frictions stuck in the current configuration
    /// (held_mass.h), again only when they change.
    HeldMass held;
    std::vector<double> held_f, held_a;
    explicit Sliders(const Model& m) : model(m), buf(m.state_size()) {
        if (m.coupled_friction())
            held.hold(m, std::vector<char>(m.dof(), 0)), held_f.resize(m.dof()), held_a.resize(m.dof());
        if (m.slider0.size() == m.jenkins.size()) {
            s = m.slider0;
        } else {
            for (const Jenkins& j : m.jenkins) s.push_back(jenkins::unstretched_slider(j, m.x0.data()));
        }
    }
    // The masses' x followed by the sliders in cfg (x itself without Jenkins elements).
    const double* with(const Configuration& cfg, const double* x) {
        if (model.jenkins.empty()) return x;
        const std::size_t n = model.dof();
        std::copy(x, x + n, buf.begin());
        std::copy(s.begin(), s.end(), buf.begin() + static_cast<std::ptrdiff_t>(n));
        for (std::size_t j = 0; j < s.size(); ++j)
            if (cfg.slip[j] != 0) buf[n + j] = slider_position(model, cfg, j, buf.data());
        return buf.data();
    }
    // At a switch: every slipping slider where it stands at x (it stays there if it sticks).
    void settle(const Configuration& cfg, const double* x) {
        const double* xs = with(cfg, x);
        std::copy(xs + model.dof(), xs + model.state_size(), s.begin());
    }
};

// Accelerations with friction -mu_k*N*dir for the sliding friction masses
// (and its reaction on a partner, friction between two bodies); a mass stuck
// to the ground does not move, one stuck to its partner moves with it (their
// summed forces over their summed mass). dir[i] is the friction direction of mass i.
void accelerations(const Model& model, const Configuration& cfg, const std::vector<signed char>& dir, double t,
                   const double* x_masses, const double* v, double* a, Sliders& sl) {
    const std::size_t n = model.dof();
    const double* x = sl.with(cfg, x_masses);
    if (model.shared_partner()) {  // several riders on a body: T (T^T M T)^-1 T^T f (held_mass.h)
        sl.held.hold(model, cfg.stuck);
        held_forces(model, cfg, cfg.stuck, dir.data(), t, x, v, a);
        sl.held.accelerations(a, a);
        return;
    }
    for (std::size_t i = 0; i < n; ++i) {
        if (cfg.stuck[i]) {
            a[i] = 0.0;
            continue;
        }
        const FrictionSlot& fr = model.friction_slot(i);
        double f = force_on_mass(model, cfg, static_cast<int>(i), t, x, v);
        if (fr.active) f -= fr.mu_k * model.normal_force(i) * dir[i];
        a[i] = f;  // divided by the mass below
    }
    for (std::size_t i = 0; i < n; ++i) {
        const Mass& m = model.masses[i];
        const FrictionSlot& f = model.friction_slot(i);
        if (f.partner == kGround || !f.active) continue;
        const auto p = static_cast<std::size_t>(f.partner);
        if (cfg.stuck[i]) {
            a[p] += force_on_mass(model, cfg, static_cast<int>(i), t, x, v);
            a[p] /= m.m + model.masses[p].m;
            a[i] = a[p] * m.m;  // both divided by their own masses below
            a[p] *= model.masses[p].m;
        } else {
            a[p] += f.mu_k * model.normal_force(i) * dir[i];
        }
    }
    if (model.coupled_mass()) {  // a_F = M_FF^-1 f_F, the stuck dofs held (friction only against the ground there)
        sl.held.hold(model, cfg.stuck);
        sl.held.accelerations(a, a);
        return;
    }
    for (std::size_t i = 0; i < n; ++i)
        if (!fixed_in(model, cfg, i)) a[i] /= model.masses[i].m;
}

// After a switch: a mass stuck to the ground at rest, one stuck to its
// partner at the partner's velocity (the pair moves as one body).
void hold_stuck(const Model& model, const Configuration& cfg, std::vector<double>& v) {
    for (std::size_t i = 0; i < model.dof(); ++i)
        if (fixed_in(model, cfg, i)) v[i] = 0.0;
        else if (cfg.stuck[i])
            v[i] = v[static_cast<std::size_t>(carrier(model, cfg, i))];
}

// Switch functions with their watched side (as in the engine): each is > 0
// while its configuration holds.
void watched_values(const Model& model, const Configuration& cfg, const std::vector<signed char>& dir, double t,
                    const double* x_masses, const double* v, const std::vector<SwitchFunction>& sw, double* h,
                    Sliders& sl) {
    const double* x = sl.with(cfg, x_masses);
    for (std::size_t k = 0; k < sw.size(); ++k) {
        const SwitchFunction& s = sw[k];
        switch (s.kind) {
            case SwitchKind::gap: {
                const double G = gap(model, s.element, x);
                h[k] = cfg.closed[s.element] ? G : -G;
                break;
            }
            case SwitchKind::velocity: {  // w = v_i - v_partner
                const int p = model.friction_slot(static_cast<std::size_t>(s.element)).partner;
                h[k] = dir[s.element] * (v[s.element] - (p == kGround ? 0.0 : v[p]));
                break;
            }
            case SwitchKind::slip_pos:
            case SwitchKind::slip_neg: {  // F_s -+ k (u - s)
                const Jenkins& j = model.jenkins[static_cast<std::size_t>(s.element)];
                const double* rows[] = {x};
                const double e =
                    along(j.direction(), double_motion(rows), 0) - x[model.dof() + static_cast<std::size_t>(s.element)];
                h[k] = j.slip_force - (s.kind == SwitchKind::slip_pos ? j.k * e : -j.k * e);
                break;
            }
            case SwitchKind::slip_velocity: {  // slip * u'
                const Jenkins& j = model.jenkins[static_cast<std::size_t>(s.element)];
                const double* rows[] = {v};
                h[k] = cfg.slip[static_cast<std::size_t>(s.element)] * along(j.direction(), double_motion(rows), 0);
                break;
            }
            default: {
                double A;
                if (model.coupled_friction()) {  // the held force D_i = P_i . f (held_mass.h)
                    sl.held.hold(model, cfg.stuck);
                    held_forces(model, cfg, cfg.stuck, dir.data(), t, x, v, sl.held_f.data());
                    sl.held.accelerations(sl.held_f.data(), sl.held_a.data());
                    A = sl.held.held_force(s.element, sl.held_f.data(), sl.held_a.data());
                } else {
                    A = driving_force(model, cfg, s.element, t, x, v);
                }
                const double lim = model.friction_slot(s.element).mu_s * model.normal_force(s.element);
                h[k] = s.kind == SwitchKind::release_pos ? lim - A : lim + A;
            }
        }
    }
}

// The largest step rk45 and CVODE may take in configuration cfg (0: no limit).
// A stuck mass's release functions mu_s N_i -+ A_i depend on time through the
// forcing, which the state does not follow: a stuck mass does not move, and
// with every mass stuck the right-hand side is 0, so an error-controlled step
// grows without bound (5x a step in rk45, 10x in CVODE) and steps over the
// interval where |A_i| > mu_s N_i (the forced oscillator released at
// 8.30 s instead of 0.5225 s). Both see a switch only as a sign change between
// step ends, so while any mass is stuck under harmonic forcing the step is at
// most 1/kStepsPerForcingPeriod of the shortest forcing period: a release is
// missed only where |A_i| exceeds mu_s N_i for less than that.
constexpr double kStepsPerForcingPeriod = 32;
double stuck_step_limit(const Model& model, const Configuration& cfg) {
    if (std::none_of(cfg.stuck.begin(), cfg.stuck.end(), [](auto s) { return s != 0; })) return 0.0;
    double omega = 0.0;
    for (const Harmonic& h : model.forcing) omega = std::max(omega, std::fabs(h.omega));
    return omega > 0 ? 2 * M_PI / omega / kStepsPerForcingPeriod : 0.0;
}

// Cubic Hermite interpolation of (x, v) between two step ends from x, v, a.
struct Hermite {
    double t0, h;
    const std::vector<double>*x0, *v0, *a0, *x1, *v1, *a1;
    void at(double t, std::vector<double>& x, std::vector<double>& v) const {
        const double s = (t - t0) / h;
        const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s;
        const double h01 = -2 * s * s * s + 3 * s * s, h11 = s * s * s - s * s;
        const double d00 = (6 * s * s - 6 * s) / h, d10 = 3 * s * s - 4 * s + 1;
        const double d01 = (-6 * s * s + 6 * s) / h, d11 = 3 * s * s - 2 * s;
        for (std::size_t i = 0; i < x.size(); ++i) {
            x[i] = h00 * (*x0)[i] + h10 * h * (*v0)[i] + h01 * (*x1)[i] + h11 * h * (*v1)[i];
            v[i] = d00 * (*x0)[i] + d10 * (*v0)[i] + d01 * (*x1)[i] + d11 * (*v1)[i];
        }
    }
};

// Samples at t0 + k*dt (and t_end) that fall in [from, to) -- or [from, to] at the end.
struct Sampler {
    const Model& model;
    const EngineOptions& opt;
    Observer& obs;
    std::size_t k;
    bool done;
    SampleGrid grid;
    Sliders& sl;
    const Configuration& cfg;  // the run's current configuration (the sliders' state)
    Sampler(const Model& m, const EngineOptions& o, Observer& ob, Sliders& s, const Configuration& c)
        : model(m), opt(o), obs(ob), k(o.first_sample), done(!o.samples), grid(sample_grid(o, m.t0)), sl(s), cfg(c) {}
    template <class Interpolant>  // at(t, x, v): Hermite here, CVODE's own interpolant below
    void emit(double from, double to, bool last, const Interpolant& H) {
        std::vector<double> x(model.dof()), v(model.dof());
        while (!done) {
            const double tk = grid.time(k);
            if (last ? tk > to : tk >= to) return;
            if (tk >= from) {
                H.at(tk, x, v);
                obs.on_sample(tk, sl.with(cfg, x.data()), v.data());
            }
            if (grid.last(k)) done = true;
            ++k;
        }
    }
};

RunSummary finish(RunSummary s, RunStatus status, std::string message, double t, const std::vector<double>& x,
                  const std::vector<double>& v, const Configuration& cfg) {
    s.status = status;
    s.message = std::move(message);
    s.t = t;
    s.x = x;
    s.v = v;
    s.configuration = cfg;
    return s;
}

// ---------------------------------------------------------------- ab4 ----
// The instant in (lo, hi] where a watched function h, positive at lo and
// <= 0 at hi, first reaches 0, by bisection to about 4 ulp (rk45 and cvode
// locate sign changes their steps report this way).
template <class H>
double bisect_fall(double lo, double hi, H&& h) {
    for (int it = 0; it < 200 && hi - lo > 4e-16 * std::max(1.0, std::fabs(hi)); ++it) {
        const double mid = 0.5 * (lo + hi);
        (h(mid) <= 0 ? hi : lo) = mid;
    }
    return hi;
}

// Whether a function that was not armed at the restart (it started at zero,
// or a rounding below: the one just switched, a Jenkins element's slip
// function at its stick) has switched at a step end where it is h, having
// been h_start at the restart: it is negative and has fallen since. A
// function that starts a rounding below zero and heads into its safe side
// has not: taken as switched, CVODE's restarts stuck and released a Jenkins
// element one ulp of t apart for ever (tests/test_cvode.cpp).
bool falls_from_zero(double h, double h_start) { return h < 0 && h < h_start; }

// Keep the earliest root: function k at `root` replaces the roots found so far
// when earlier, and joins them when at the same instant (to 1e-15 relative).
void keep_earliest(double root, std::size_t k, double& t_root, std::vector<std::size_t>& hit) {
    const double tol = 1e-15 * std::max(1.0, std::fabs(root));
    if (root < t_root - tol) {
        t_root = root;
        hit.assign(1, k);
    } else if (std::fabs(root - t_root) <= tol) {
        hit.push_back(k);
    }
}

RunSummary run_ab4(const Model& model, const IntegratorOptions& io, const EngineOptions& eo, Observer& obs) {
    const std::size_t n = model.dof();
    const double h = io.h;
    std::vector<double> x = model.x0, v = model.v0;
    double t = model.t0;
    std::vector<signed char> dir;
    Sliders sl(model);
    Configuration cfg =
        entered_configuration(model, t, sl.with(eo.carried.value_or(Configuration::all_open(model)), x.data()),
                              v.data(), dir, eo.carried ? &*eo.carried : nullptr);  // stuck only where v = 0
    RunSummary sum;
    Sampler sampler(model, eo, obs, sl, cfg);
    SwitchGuard guard(eo, model.t0);  // chattering and Zeno, as the engine (switch_guard.h)

    // Contacts from the state (closed while G >= 0); friction along v, or along
    // the decided direction while v is exactly 0.
    Configuration c = cfg;             // per-evaluation copies, reused (no allocation per step)
    std::vector<signed char> d = dir;
    auto rhs = [&](double tt, const std::vector<double>& xx, const std::vector<double>& vv, std::vector<double>& a) {
        c.stuck = cfg.stuck;
        for (std::size_t k = 0; k < model.contacts.size(); ++k) c.closed[k] = gap(model, static_cast<int>(k), xx.data()) >= 0;
        for (std::size_t i = 0; i < n; ++i) d[i] = vv[i] != 0.0 ? (vv[i] > 0 ? 1 : -1) : dir[i];
        accelerations(model, c, d, tt, xx.data(), vv.data(), a.data(), sl);
    };

    std::array<std::vector<double>, 4> fv, fa;  // history of v and a, newest first
    int history = 0;
    std::vector<double> a(n), xn(n), vn(n), an(n), k1x, k1v, tmpx(n), tmpv(n), ta(n);
    rhs(t, x, v, a);
    const auto steps = static_cast<std::size_t>(std::ceil((eo.t_end - model.t0) / h - 1e-9));
    for (std::size_t step = 1; step <= steps; ++step) {
        const double t1 = std::min(model.t0 + static_cast<double>(step) * h, eo.t_end);
        const double hs = t1 - t;
        // Step ends are t0 + step*h (no drift); only the last step may be shorter.
        const bool short_step = hs < h * (1 - 1e-9);
        if (history < 3 || short_step) {
            // RK4 step (start of the multistep history, or the shorter last step).
            auto stage = [&](double frac, const std::vector<double>& dx, const std::vector<double>& dv,
                             std::vector<double>& outx, std::vector<double>& outv) {
                for (std::size_t i = 0; i < n; ++i) {
                    tmpx[i] = x[i] + frac * hs * dx[i];
                    tmpv[i] = v[i] + frac * hs * dv[i];
                    if (cfg.stuck[i]) tmpv[i] = 0.0;
                }
                rhs(t + frac * hs, tmpx, tmpv, ta);
                outx = tmpv;
                outv = ta;
            };
            std::vector<double> dx1 = v, dv1 = a, dx2, dv2, dx3, dv3, dx4, dv4;
            stage(0.5, dx1, dv1, dx2, dv2);
            stage(0.5, dx2, dv2, dx3, dv3);
            stage(1.0, dx3, dv3, dx4, dv4);
            for (std::size_t i = 0; i < n; ++i) {
                xn[i] = x[i] + hs / 6 * (dx1[i] + 2 * dx2[i] + 2 * dx3[i] + dx4[i]);
                vn[i] = v[i] + hs / 6 * (dv1[i] + 2 * dv2[i] + 2 * dv3[i] + dv4[i]);
            }
        } else {
            // y_{n+1} = y_n + h/24 (55 f_n - 59 f_{n-1} + 37 f_{n-2} - 9 f_{n-3})
            for (std::size_t i = 0; i < n; ++i) {
                xn[i] = x[i] + h / 24 * (55 * v[i] - 59 * fv[0][i] + 37 * fv[1][i] - 9 * fv[2][i]);
                vn[i] = v[i] + h / 24 * (55 * a[i] - 59 * fa[0][i] + 37 * fa[1][i] - 9 * fa[2][i]);
            }
        }
        for (std::size_t i = 0; i < n; ++i)
            if (cfg.stuck[i]) vn[i] = 0.0;
        rhs(t1, xn, vn, an);
        // Samples inside the step from the Hermite cubic through both ends.
        Hermite H{t, hs, &x, &v, &a, &xn, &vn, &an};
        sampler.emit(t, t1, step == steps, H);

        // Step-end decisions: contacts by G, friction by the stick rule.
        bool restart = false;
        const std::size_t events_before = sum.events;
        for (std::size_t c = 0; c < model.contacts.size(); ++c) {
            const bool closed = gap(model, static_cast<int>(c), xn.data()) >= 0;
            if (closed != static_cast<bool>(cfg.closed[c])) {
                cfg.closed[c] = closed;
                obs.on_event(t1, closed ? EventKind::contact_close : EventKind::contact_open, static_cast<int>(c),
                             xn.data(), vn.data());
                ++sum.events;
            }
        }
        for (std::size_t i = 0; i < n; ++i) {
            const FrictionSlot& f = model.friction_slot(i);
            if (!f.active) continue;
            const double A = force_on_mass(model, cfg, static_cast<int>(i), t1, xn.data(), vn.data());
            const double limit = f.mu_s * model.normal_force(i);
            const int ii = static_cast<int>(i);
            if (cfg.stuck[i]) {
                if (std::fabs(A) > limit) {
                    cfg.stuck[i] = 0;
                    dir[i] = A > 0 ? 1 : -1;
                    obs.on_event(t1, EventKind::release, ii, xn.data(), vn.data());
                    ++sum.events;
                    restart = true;
                }
            } else if (v[i] * vn[i] <= 0 && !(v[i] == 0 && vn[i] * dir[i] > 0)) {
                if (std::fabs(A) < limit) {
                    cfg.stuck[i] = 1;
                    vn[i] = 0.0;
                    obs.on_event(t1, EventKind::stick, ii, xn.data(), vn.data());
                    ++sum.events;
                    restart = true;
                } else {
                    const signed char d = A > 0 ? 1 : -1;
                    if (d != dir[i]) {
                        obs.on_event(t1, EventKind::reversal, ii, xn.data(), vn.data());
                        ++sum.events;
                    }
                    dir[i] = d;
                }
            } else if (vn[i] != 0.0) {
                dir[i] = vn[i] > 0 ? 1 : -1;
            }
        }
        if (restart) rhs(t1, xn, vn, an);
        if (sum.events > events_before) {  // the engine's guard (switch_guard.h)
            for (std::size_t e = events_before; e < sum.events; ++e) guard.event(t1);
            if (const RunStatus g = guard.after_switch(t1, switch_functions(model, cfg).size()); g != RunStatus::ok)
                return finish(sum, g, "ab4: " + guard.message(cfg.spec(model)), t1, xn, vn, cfg);
        }
        // Shift the history.
        fv[2] = fv[1], fv[1] = fv[0], fv[0] = v;
        fa[2] = fa[1], fa[1] = fa[0], fa[0] = a;
        history = restart ? 0 : history + 1;
        x.swap(xn), v.swap(vn), a.swap(an);
        t = t1;
        ++sum.segments;
        if ((step & 0xffff) == 0 && !obs.on_progress(t)) return finish(sum, RunStatus::stopped, "stopped", t, x, v, cfg);
        if (eo.max_events && sum.events >= eo.max_events)
            return finish(sum, RunStatus::max_events, "stopped after max events", t, x, v, cfg);
    }
    sum.configurations = 0;
    sl.settle(cfg, x.data());
    sum.slider = sl.s;
    return finish(sum, RunStatus::ok, "", t, x, v, cfg);
}

// ---------------------------------------------------------------- rk45 ----
// Dormand & Prince (1980), "A family of embedded Runge-Kutta formulae",
// J. Comp. Appl. Math. 6(1): the 5(4) pair with the 5th-order solution propagated.
constexpr double c2 = 1.0 / 5, c3 = 3.0 / 10, c4 = 4.0 / 5, c5 = 8.0 / 9;
constexpr double a21 = 1.0 / 5;
constexpr double a31 = 3.0 / 40, a32 = 9.0 / 40;
constexpr double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
constexpr double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561, a54 = -212.0 / 729;
constexpr double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247, a64 = 49.0 / 176,
                 a65 = -5103.0 / 18656;
constexpr double b1 = 35.0 / 384, b3 = 500.0 / 1113, b4 = 125.0 / 192, b5 = -2187.0 / 6784, b6 = 11.0 / 84;
constexpr double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920, e5 = -17253.0 / 339200,
                 e6 = 22.0 / 525, e7 = -1.0 / 40;

RunSummary run_rk45(const Model& model, const IntegratorOptions& io, const EngineOptions& eo, Observer& obs) {
    const std::size_t n = model.dof(), m2 = 2 * n;
    std::vector<double> x = model.x0, v = model.v0;
    double t = model.t0;
    std::vector<signed char> dir;
    Sliders sl(model);
    Configuration cfg =
        entered_configuration(model, t, sl.with(eo.carried.value_or(Configuration::all_open(model)), x.data()),
                              v.data(), dir, eo.carried ? &*eo.carried : nullptr);  // stuck only where v = 0
    RunSummary sum;
    Sampler sampler(model, eo, obs, sl, cfg);
    SwitchGuard guard(eo, model.t0);  // chattering and Zeno, as the engine (switch_guard.h)

    // y = (x, v); f(y) = (v, a) in the current configuration.
    auto f = [&](double tt, const std::vector<double>& y, std::vector<double>& dy) {
        accelerations(model, cfg, dir, tt, y.data(), y.data() + n, dy.data() + n, sl);
        for (std::size_t i = 0; i < n; ++i) dy[i] = fixed_in(model, cfg, i) ? 0.0 : y[n + i];
    };
    auto switch_values = [&](double tt, const std::vector<double>& xx, const std::vector<double>& vv,
                             const std::vector<SwitchFunction>& sw, std::vector<double>& h) {
        watched_values(model, cfg, dir, tt, xx.data(), vv.data(), sw, h.data(), sl);
    };

    std::vector<double> y(m2), y1(m2), k1(m2), k2(m2), k3(m2), k4(m2), k5(m2), k6(m2), k7(m2), tmp(m2), err(m2);
    std::vector<double> xa(n), va(n), aa(n), xb(n), vb(n), ab(n), xi(n), vi(n);
    double h = std::min(1e-3, (eo.t_end - t) / 10);
    std::string why;
    std::vector<Transition> tr;
    std::size_t steps = 0;
    while (t < eo.t_end) {
        const std::vector<SwitchFunction> sw = switch_functions(model, cfg);
        std::vector<double> h0(sw.size()), h1(sw.size());
        std::copy(x.begin(), x.end(), y.begin());
        std::copy(v.begin(), v.end(), y.begin() + n);
        switch_values(t, x, v, sw, h0);
        // Functions that start at zero (just switched) are watched once they leave it.
        std::vector<char> armed(sw.size());
        for (std::size_t k = 0; k < sw.size(); ++k) armed[k] = h0[k] > 0;
        f(t, y, k1);
        const double hmax = stuck_step_limit(model, cfg);
        bool switched = false;
        while (!switched && t < eo.t_end) {
            h = std::min(h, eo.t_end - t);
            if (hmax > 0) h = std::min(h, hmax);
            auto combo = [&](std::initializer_list<std::pair<double, const std::vector<double>*>> terms) {
                for (std::size_t i = 0; i < m2; ++i) {
                    double s = y[i];
                    for (const auto& [c, k] : terms) s += h * c * (*k)[i];
                    tmp[i] = s;
                }
            };
            combo({{a21, &k1}});
            f(t + c2 * h, tmp, k2);
            combo({{a31, &k1}, {a32, &k2}});
            f(t + c3 * h, tmp, k3);
            combo({{a41, &k1}, {a42, &k2}, {a43, &k3}});
            f(t + c4 * h, tmp, k4);
            combo({{a51, &k1}, {a52, &k2}, {a53, &k3}, {a54, &k4}});
            f(t + c5 * h, tmp, k5);
            combo({{a61, &k1}, {a62, &k2}, {a63, &k3}, {a64, &k4}, {a65, &k5}});
            f(t + h, tmp, k6);
            combo({{b1, &k1}, {b3, &k3}, {b4, &k4}, {b5, &k5}, {b6, &k6}});
            y1 = tmp;
            f(t + h, y1, k7);
            double enorm = 0;
            for (std::size_t i = 0; i < m2; ++i) {
                const double e = h * (e1 * k1[i] + e3 * k3[i] + e4 * k4[i] + e5 * k5[i] + e6 * k6[i] + e7 * k7[i]);
                const double sc = io.atol + io.rtol * std::max(std::fabs(y[i]), std::fabs(y1[i]));
                enorm = std::max(enorm, std::fabs(e) / sc);
            }
            if (!std::isfinite(enorm)) return finish(sum, RunStatus::failure, "rk45: non-finite state", t, x, v, cfg);
            const double factor = std::min(5.0, std::max(0.2, 0.9 * std::pow(std::max(enorm, 1e-300), -0.2)));
            if (enorm > 1) {
                h *= factor;
                if (h < 1e-15 * std::max(1.0, std::fabs(t)))
                    return finish(sum, RunStatus::failure, "rk45: step size underflow at t = " + std::to_string(t), t, x, v, cfg);
                continue;
            }
            ++steps;
            const double t1 = t + h;
            for (std::size_t i = 0; i < n; ++i) {
                xa[i] = y[i], va[i] = y[n + i], aa[i] = k1[n + i];
                xb[i] = y1[i], vb[i] = y1[n + i], ab[i] = k7[n + i];
            }
            Hermite H{t, h, &xa, &va, &aa, &xb, &vb, &ab};
            switch_values(t1, xb, vb, sw, h1);
            // Earliest sign change, located by bisection on the interpolant.
            double t_root = kInf;
            std::vector<std::size_t> hit;
            for (std::size_t k = 0; k < sw.size(); ++k) {
                const bool crossed = armed[k] ? h1[k] <= 0 : falls_from_zero(h1[k], h0[k]);
                if (!crossed) {
                    if (h1[k] > 0) armed[k] = 1;
                    continue;
                }
                std::vector<double> hv(sw.size());
                const double r = bisect_fall(t, t1, [&](double mid) {
                    H.at(mid, xi, vi);
                    switch_values(mid, xi, vi, sw, hv);
                    return hv[k];
                });
                keep_earliest(r, k, t_root, hit);
            }
            if (t_root < kInf) {
                sampler.emit(t, t_root, false, H);
                H.at(t_root, x, v);
                t = t_root;
                std::vector<SwitchFunction> s;
                for (std::size_t k : hit) s.push_back(sw[k]);
                tr.clear();
                sl.settle(cfg, x.data());
                if (!apply_switches(model, t, sl.with(cfg, x.data()), v.data(), nullptr, cfg, dir, s, tr, why))
                    return finish(sum, RunStatus::chattering, why, t, x, v, cfg);
                for (const Transition& e : tr) {
                    obs.on_event(t, e.kind, e.element, sl.with(cfg, x.data()), v.data());
                    ++sum.events;
                    guard.event(t);
                }
                hold_stuck(model, cfg, v);
                // Restarts that keep switching at one instant or one ulp apart (as the engine guards).
                if (const RunStatus g = guard.after_switch(t, sw.size()); g != RunStatus::ok)
                    return finish(sum, g, "rk45: " + guard.message(cfg.spec(model)), t, x, v, cfg);
                switched = true;
                ++sum.segments;
            } else {
                sampler.emit(t, t1, t1 >= eo.t_end, H);
                t = t1;
                y.swap(y1);
                k1.swap(k7);
                std::copy(y.begin(), y.begin() + n, x.begin());
                std::copy(y.begin() + n, y.end(), v.begin());
            }
            h *= factor;
            if ((steps & 0xffff) == 0 && !obs.on_progress(t)) return finish(sum, RunStatus::stopped, "stopped", t, x, v, cfg);
            if (eo.max_events && sum.events >= eo.max_events)
                return finish(sum, RunStatus::max_events, "stopped after max events", t, x, v, cfg);
        }
    }
    sum.evaluations = steps;
    sl.settle(cfg, x.data());
    sum.slider = sl.s;
    return finish(sum, RunStatus::ok, "", t, x, v, cfg);
}

// --------------------------------------------------------------- cvode ----
#if HSNC_WITH_CVODE
// SUNDIALS CVODE (Hindmarsh et al., ACM TOMS 31(3), 2005): variable-order
// Adams-Moulton (orders 1-12) inside each configuration, with CVODE's own root
// finding on the watched switch functions (the same ones rk45 watches, side >
// 0 while the configuration holds; roots only where they decrease), then the
// same transitions as hsnc and rk45. After a switch the integration restarts
// (CVodeReInit) from the switched state. A function that sits at zero there
// is the classic trap: CVODE deactivates a function that is exactly zero at
// the restart until it leaves zero, and one that starts a rounding below zero
// and keeps falling would never show a sign change. So, as in rk45, a
// function that starts at or below zero is armed once it is positive at a
// step end; one that is still unarmed and negative at a step end has switched
// (located by bisection on CVODE's interpolant, CVodeGetDky).
//
// The corrector: fixed-point (functional) iteration by default -- the usual
// choice for a non-stiff problem with Adams, and the faster one measured on
// the bundled models (bench/hsnc_bench prints both); Newton with a dense
// difference-quotient Jacobian with IntegratorOptions::cvode_newton.

struct CvodeProblem {
    const Model& model;
    Sliders& sl;
    Configuration cfg;
    std::vector<signed char> dir;
    std::vector<SwitchFunction> sw;
    std::size_t n;
    std::string error;
};

int cvode_rhs(realtype t, N_Vector y, N_Vector ydot, void* user) {
    auto& p = *static_cast<CvodeProblem*>(user);
    const double* yy = N_VGetArrayPointer(y);
    double* dy = N_VGetArrayPointer(ydot);
    accelerations(p.model, p.cfg, p.dir, t, yy, yy + p.n, dy + p.n, p.sl);
    for (std::size_t i = 0; i < p.n; ++i) dy[i] = fixed_in(p.model, p.cfg, i) ? 0.0 : yy[p.n + i];
    return 0;
}

int cvode_roots(realtype t, N_Vector y, realtype* g, void* user) {
    auto& p = *static_cast<CvodeProblem*>(user);
    const double* yy = N_VGetArrayPointer(y);
    watched_values(p.model, p.cfg, p.dir, t, yy, yy + p.n, p.sw, g, p.sl);
    return 0;
}

void cvode_error(int, const char* module, const char* function, char* msg, void* user) {
    auto& p = *static_cast<CvodeProblem*>(user);
    p.error = std::string(module) + "/" + function + ": " + msg;  // kept for the run's message, not printed
}

// Owns the SUNDIALS objects of one run.
class Cvode {
public:
    Cvode(std::size_t m2, const IntegratorOptions& io, double t0, CvodeProblem& problem) {
        if (SUNContext_Create(nullptr, &ctx_) != 0) throw RunError("cvode: cannot create a SUNDIALS context");
        y_ = N_VNew_Serial(static_cast<sunindextype>(m2), ctx_);
        dky_ = N_VNew_Serial(static_cast<sunindextype>(m2), ctx_);
        mem_ = CVodeCreate(CV_ADAMS, ctx_);
        if (!y_ || !dky_ || !mem_) throw RunError("cvode: out of memory");
        N_VConst(0.0, y_);
        check(CVodeSetErrHandlerFn(mem_, cvode_error, &problem), "CVodeSetErrHandlerFn");
        check(CVodeInit(mem_, cvode_rhs, t0, y_), "CVodeInit");
        check(CVodeSetUserData(mem_, &problem), "CVodeSetUserData");
        check(CVodeSStolerances(mem_, io.rtol, io.atol), "CVodeSStolerances");
        check(CVodeSetMaxNumSteps(mem_, -1), "CVodeSetMaxNumSteps");  // one step per call anyway
        check(CVodeSetNoInactiveRootWarn(mem_), "CVodeSetNoInactiveRootWarn");
        if (io.cvode_newton) {
            A_ = SUNDenseMatrix(static_cast<sunindextype>(m2), static_cast<sunindextype>(m2), ctx_);
            ls_ = SUNLinSol_Dense(y_, A_, ctx_);
            if (!A_ || !ls_) throw RunError("cvode: out of memory");
            check(CVodeSetLinearSolver(mem_, ls_, A_), "CVodeSetLinearSolver");
        } else {
            nls_ = SUNNonlinSol_FixedPoint(y_, 0, ctx_);
            if (!nls_) throw RunError("cvode: out of memory");
            check(CVodeSetNonlinearSolver(mem_, nls_), "CVodeSetNonlinearSolver");
        }
    }
    ~Cvode() {
        if (mem_) CVodeFree(&mem_);
        if (nls_) SUNNonlinSolFree(nls_);
        if (ls_) SUNLinSolFree(ls_);
        if (A_) SUNMatDestroy(A_);
        if (dky_) N_VDestroy(dky_);
        if (y_) N_VDestroy(y_);
        if (ctx_) SUNContext_Free(&ctx_);
    }
    Cvode(const Cvode&) = delete;
    Cvode& operator=(const Cvode&) = delete;

    static void check(int flag, const char* what) {
        if (flag < 0) throw RunError(std::string("cvode: ") + what + " failed (" + std::to_string(flag) + ")");
    }
    void* mem() const { return mem_; }
    double* y() const { return N_VGetArrayPointer(y_); }
    N_Vector y_vector() const { return y_; }
    N_Vector dky_vector() const { return dky_; }

private:
    SUNContext ctx_ = nullptr;
    N_Vector y_ = nullptr, dky_ = nullptr;
    void* mem_ = nullptr;
    SUNMatrix A_ = nullptr;
    SUNLinearSolver ls_ = nullptr;
    SUNNonlinearSolver nls_ = nullptr;
};

// CVODE's interpolant over its last step, for the samples and the bisection.
struct CvodeInterpolant {
    const Cvode& cv;
    std::size_t n;
    void at(double t, std::vector<double>& x, std::vector<double>& v) const {
        Cvode::check(CVodeGetDky(cv.mem(), t, 0, cv.dky_vector()), "CVodeGetDky");
        const double* d = N_VGetArrayPointer(cv.dky_vector());
        std::copy(d, d + n, x.begin());
        std::copy(d + n, d + 2 * n, v.begin());
    }
};

RunSummary run_cvode(const Model& model, const IntegratorOptions& io, const EngineOptions& eo, Observer& obs) {
    const std::size_t n = model.dof();
    std::vector<double> x = model.x0, v = model.v0;
    double t = model.t0;
    Sliders sl(model);
    CvodeProblem p{model, sl, {}, {}, {}, n, {}};
    p.cfg = entered_configuration(model, t, sl.with(eo.carried.value_or(Configuration::all_open(model)), x.data()),
                                  v.data(), p.dir, eo.carried ? &*eo.carried : nullptr);  // stuck only where v = 0
    Configuration& cfg = p.cfg;
    RunSummary sum;
    Sampler sampler(model, eo, obs, sl, cfg);
    Cvode cv(2 * n, io, t, p);
    const CvodeInterpolant interp{cv, n};
    std::string why;
    std::vector<Transition> tr;
    std::vector<double> h, h_start, hv, xi(n), vi(n);
    std::vector<int> found, rootdir;
    std::vector<char> armed;
    long steps = 0;
    SwitchGuard guard(eo, model.t0);  // chattering and Zeno, as the engine
    auto counted = [&] {  // the summary with CVODE's steps as its evaluations
        sum.evaluations = static_cast<std::size_t>(steps);
        return sum;
    };
    auto fail = [&](const std::string& what) {
        return finish(counted(), RunStatus::failure, "cvode: " + what + (p.error.empty() ? "" : " (" + p.error + ")"), t, x, v,
                      cfg);
    };
    while (t < eo.t_end) {
        p.sw = switch_functions(model, cfg);
        const std::size_t ns = p.sw.size();
        h.resize(ns), hv.resize(ns), found.assign(ns, 0), rootdir.assign(ns, -1), armed.resize(ns);
        double* y = cv.y();
        std::copy(x.begin(), x.end(), y);
        std::copy(v.begin(), v.end(), y + n);
        Cvode::check(CVodeReInit(cv.mem(), t, cv.y_vector()), "CVodeReInit");
        Cvode::check(CVodeRootInit(cv.mem(), static_cast<int>(ns), ns ? cvode_roots : nullptr), "CVodeRootInit");
        if (ns) Cvode::check(CVodeSetRootDirection(cv.mem(), rootdir.data()), "CVodeSetRootDirection");
        Cvode::check(CVodeSetStopTime(cv.mem(), eo.t_end), "CVodeSetStopTime");
        Cvode::check(CVodeSetMaxStep(cv.mem(), stuck_step_limit(model, cfg)), "CVodeSetMaxStep");  // 0: none
        watched_values(model, cfg, p.dir, t, x.data(), v.data(), p.sw, h.data(), sl);
        for (std::size_t k = 0; k < ns; ++k) armed[k] = h[k] > 0;
        h_start = h;
        for (bool switched = false; !switched;) {
            double tret = t;
            const int flag = CVode(cv.mem(), eo.t_end, cv.y_vector(), &tret, CV_ONE_STEP);
            if (flag < 0) return fail("step failed at t = " + std::to_string(t) + ", flag " + std::to_string(flag));
            ++steps;
            y = cv.y();
            watched_values(model, cfg, p.dir, tret, y, y + n, p.sw, h.data(), sl);
            // The earliest switch: CVODE's roots at tret, or an unarmed function
            // that went below zero (bisection from the last return on).
            double t_root = kInf;
            std::vector<std::size_t> hit;
            if (flag == CV_ROOT_RETURN) {
                Cvode::check(CVodeGetRootInfo(cv.mem(), found.data()), "CVodeGetRootInfo");
                for (std::size_t k = 0; k < ns; ++k)
                    if (found[k] != 0) t_root = tret, hit.push_back(k);
            }
            for (std::size_t k = 0; k < ns; ++k) {
                if (armed[k] || found[k] != 0 || !falls_from_zero(h[k], h_start[k])) continue;
                const double r = bisect_fall(t, tret, [&](double mid) {
                    interp.at(mid, xi, vi);
                    watched_values(model, cfg, p.dir, mid, xi.data(), vi.data(), p.sw, hv.data(), sl);
                    return hv[k];
                });
                keep_earliest(r, k, t_root, hit);
            }
            if (t_root < kInf) {
                sampler.emit(t, t_root, false, interp);
                interp.at(t_root, x, v);
                t = t_root;
                std::vector<SwitchFunction> s;
                for (std::size_t k : hit) s.push_back(p.sw[k]);
                tr.clear();
                sl.settle(cfg, x.data());
                if (!apply_switches(model, t, sl.with(cfg, x.data()), v.data(), nullptr, cfg, p.dir, s, tr, why))
                    return finish(counted(), RunStatus::chattering, why, t, x, v, cfg);
                for (const Transition& e : tr) {
                    obs.on_event(t, e.kind, e.element, sl.with(cfg, x.data()), v.data());
                    ++sum.events;
                    guard.event(t);
                }
                hold_stuck(model, cfg, v);
                // Restarts that keep switching at one instant or one ulp apart (as the engine guards).
                if (const RunStatus g = guard.after_switch(t, ns); g != RunStatus::ok)
                    return finish(counted(), g, "cvode: " + guard.message(cfg.spec(model)), t, x, v, cfg);
                switched = true;
                ++sum.segments;
            } else {
                for (std::size_t k = 0; k < ns; ++k)
                    if (h[k] > 0) armed[k] = 1;
                const bool last = flag == CV_TSTOP_RETURN || tret >= eo.t_end;
                if (last) tret = eo.t_end;
                sampler.emit(t, tret, last, interp);
                t = tret;
                std::copy(y, y + n, x.begin());
                std::copy(y + n, y + 2 * n, v.begin());
                if (last) break;
            }
            if ((steps & 0xffff) == 0 && !obs.on_progress(t))
                return finish(counted(), RunStatus::stopped, "stopped", t, x, v, cfg);
            if (eo.max_events && sum.events >= eo.max_events)
                return finish(counted(), RunStatus::max_events, "stopped after max events", t, x, v, cfg);
        }
    }
    sl.settle(cfg, x.data());
    sum.slider = sl.s;
    return finish(counted(), RunStatus::ok, "", t, x, v, cfg);
}
#else  // built with HSNC_WITH_CVODE=OFF
RunSummary run_cvode(const Model&, const IntegratorOptions&, const EngineOptions&, Observer&) {
    throw InputError("integrate(): method cvode: this build has no SUNDIALS CVODE (HSNC_WITH_CVODE=OFF)");
}
#endif  // HSNC_WITH_CVODE

}  // namespace

Method parse_method(const std::string& name) {
    if (name == "hsnc") return Method::hsnc;
    if (name == "ab4") return Method::ab4;
    if (name == "rk45") return Method::rk45;
    if (name == "cvode") return Method::cvode;
    throw InputError("--method '" + name + "': expected hsnc, ab4, rk45 or cvode");
}

void validate(Method method, const IntegratorOptions& o) {
    if (method == Method::ab4 && !(o.h > 0 && std::isfinite(o.h)))
        throw InputError("hsnc::integrate(): method ab4 needs a fixed step h > 0");
    if ((method == Method::rk45 || method == Method::cvode) &&
        !(o.rtol > 0 && o.atol > 0 && std::isfinite(o.rtol) && std::isfinite(o.atol)))
        throw InputError(std::string("hsnc::integrate(): method ") + (method == Method::rk45 ? "rk45" : "cvode") +
                         ": rtol and atol must be finite and > 0");
}

void validate(Method method, const IntegratorOptions& o, double t0, double t_end) {
    validate(method, o);
    if (method != Method::ab4) return;
    // A step longer than the run, or so short that it never ends (or that
    // t + h rounds to t), would be a run that silently does nothing.
    const double span = t_end - t0, h = o.h;
    std::ostringstream text;  // as given, not with 17 digits
    text << h;
    if (h > span) throw InputError("hsnc::integrate(): h = " + text.str() + ": longer than the run (t_end - t0)");
    if (span / h > kMaxSteps) throw InputError("hsnc::integrate(): h = " + text.str() + ": more than 1e12 steps over the run");
    const double t_max = std::max(std::abs(t0), std::abs(t_end));
    if (t_max + h == t_max) throw InputError("hsnc::integrate(): h = " + text.str() + ": below the rounding of t (t + h == t)");
}

RunSummary integrate(const Model& model, Method method, const IntegratorOptions& options,
                     const EngineOptions& engine_options, Observer& observer) {
    validate(method, options, model.t0, engine_options.t_end);
    refuse_load_steps(model, "hsnc::integrate()");
    if (method == Method::ab4)  // ab4 has its own stick rules, for masses against the ground
        require_no_stick_elements(model, "hsnc::integrate()");
    if (method == Method::ab4) return run_ab4(model, options, engine_options, observer);
    if (method == Method::rk45) return run_rk45(model, options, engine_options, observer);
    if (method == Method::cvode) return run_cvode(model, options, engine_options, observer);
    throw InputError("integrate: method hsnc is the engine, not an integrator");
}

}  // namespace hsnc
