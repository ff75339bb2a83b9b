#include "tangent.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <unsupported/Eigen/MatrixFunctions>

#include "assembly.h"
#include "error.h"
#include "held_mass.h"
#include "modal.h"
#include "stick_tangent.h"
#include "transitions.h"

namespace hsnc::analysis {
namespace {

// phi_1(x) = (e^x - 1)/x and phi_2(x) = (e^x - 1 - x)/x^2 without cancellation.
double phi1(double x) { return x == 0.0 ? 1.0 : std::expm1(x) / x; }
double phi2(double x) {
    if (std::abs(x) < 0.5) {
        double term = 0.5, sum = 0.5;  // x^k/(k+2)!
        for (int k = 1; k < 20; ++k) {
            term *= x / (k + 2);
            sum += term;
        }
        return sum;
    }
    return (std::expm1(x) - x) / (x * x);
}
// sinh(x)/x.
double sinhc(double x) { return x == 0.0 ? 1.0 : std::sinh(x) / x; }

}  // namespace

struct Tangent::ConfigData {
    ModalDecomposition modal;
    Eigen::MatrixXd E;  // Phi^T M_F: modal coordinates of (x_F, v_F)
    Eigen::MatrixXd G;  // Phi^T (-K_FS): modal force of a unit displacement of each stuck mass
    Eigen::VectorXd lambda, c;
    Eigen::MatrixXd K, C;  // full K(cfg), C(cfg) (the gradient of a release function)
    // Non-proportional damping: the generator of (x_F, v_F, x_S), whose
    // exponential is Phi (x_S constant), and the fastest decay rate.
    Eigen::MatrixXd generator;
    double rate = 0.0;
    // Stick elements: the full-state generator and projection (stick_tangent.h).
    Eigen::MatrixXd stick_A, stick_P;
};

Tangent::Tangent(const Model& model) : model_(model), stick_(!stick_elements(model).empty()) {}
Tangent::~Tangent() = default;
Tangent::Tangent(Tangent&&) noexcept = default;

const Tangent::ConfigData& Tangent::data(const Configuration& cfg) {
    auto it = cache_.find(cfg);
    if (it != cache_.end()) return *it->second;
    auto d = std::make_unique<ConfigData>();
    d->modal = modal_analysis(model_, cfg);
    const ModalDecomposition& md = d->modal;
    const int nf = static_cast<int>(md.free.size()), ns = static_cast<int>(md.stuck.size());
    d->K = stiffness_matrix(model_, cfg);
    d->C = damping_matrix(model_, cfg);
    const Eigen::VectorXd m = mass_vector(model_);
    d->E.resize(nf, nf);
    if (model_.coupled_mass()) {
        d->E = md.phi_t_m();
    } else {
        for (int j = 0; j < nf; ++j)
            for (int r = 0; r < nf; ++r) d->E(j, r) = md.phi(r, j) * m(md.free[r]);
    }
    d->G = Eigen::MatrixXd::Zero(nf, ns);
    for (int j = 0; j < nf; ++j)
        for (int s = 0; s < ns; ++s) {
            double g = 0.0;
            for (int r = 0; r < nf; ++r) g -= md.phi(r, j) * d->K(md.free[r], md.stuck[s]);
            d->G(j, s) = g;
        }
    if (stick_) {
        d->stick_A = stick_generator(model_, cfg);
        d->stick_P = stick_projection(model_, cfg);
        const Eigen::EigenSolver<Eigen::MatrixXd> es(d->stick_A, false);
        for (Eigen::Index k = 0; k < es.eigenvalues().size(); ++k) d->rate = std::max(d->rate, -es.eigenvalues()(k).real());
        return *cache_.emplace(cfg, std::move(d)).first->second;
    }
    d->lambda = md.lambda;
    d->c.resize(nf);
    for (int j = 0; j < nf; ++j) d->c(j) = model_.alpha + model_.beta * md.lambda(j);
    if (!model_.proportional_damping()) {
        // Dampers: the modes of K do not decouple C. dz/dt = A z for z = (x_F, v_F, x_S):
        // x_F' = v_F, v_F' = -M^-1 (K_FF x_F + C_FF v_F + K_FS x_S), x_S' = 0.
        Eigen::MatrixXd& A = d->generator;
        A = Eigen::MatrixXd::Zero(2 * nf + ns, 2 * nf + ns);
        for (int r = 0; r < nf; ++r) {
            const int i = md.free[r];
            A(r, nf + r) = 1.0;
            for (int q = 0; q < nf; ++q) {
                A(nf + r, q) = -d->K(i, md.free[q]) / m(i);
                A(nf + r, nf + q) = -d->C(i, md.free[q]) / m(i);
            }
            for (int s = 0; s < ns; ++s) A(nf + r, 2 * nf + s) = -d->K(i, md.stuck[s]) / m(i);
        }
        if (model_.coupled_mass() && nf > 0) {  // rows over M_F^-1, not over the diagonal
            const Eigen::MatrixXd D = m(md.free).asDiagonal();
            A.middleRows(nf, nf) = md.mass_matrix.llt().solve(D * A.middleRows(nf, nf));
        }
        if (nf > 0) {
            const Eigen::EigenSolver<Eigen::MatrixXd> es(A.topLeftCorner(2 * nf, 2 * nf), false);
            for (Eigen::Index k = 0; k < es.eigenvalues().size(); ++k)
                d->rate = std::max(d->rate, -es.eigenvalues()(k).real());
        }
    }
    return *cache_.emplace(cfg, std::move(d)).first->second;
}

Eigen::MatrixXd Tangent::transition(const Configuration& cfg, double tau) {
    const ConfigData& d = data(cfg);
    const ModalDecomposition& md = d.modal;
    const int n = static_cast<int>(model_.dof());
    const int nf = static_cast<int>(md.free.size()), ns = static_cast<int>(md.stuck.size());
    if (stick_) return (d.stick_A * tau).exp() * d.stick_P;  // stick_tangent.h
    if (!model_.proportional_damping()) {
        // exp(A tau) by Eigen's scaling and squaring with Pade approximants (Higham 2005):
        // the matrix exponential to rounding, not an integration.
        const Eigen::MatrixXd E = (d.generator * tau).exp();
        Eigen::MatrixXd Phi = Eigen::MatrixXd::Zero(2 * n, 2 * n);
        auto at = [&](int slot) { return slot < nf ? md.free[slot] : slot < 2 * nf ? n + md.free[slot - nf] : md.stuck[slot - 2 * nf]; };
        for (int r = 0; r < 2 * nf + ns; ++r)
            for (int q = 0; q < 2 * nf + ns; ++q) Phi(at(r), at(q)) = E(r, q);
        return Phi;  // a stuck mass's dv column stays 0, as in the modal form
    }
    // Per mode, the homogeneous motion q(tau) = a q0 + b q0', q'(tau) = c q0 + e q0'
    // (c = -lambda b), and the response to a unit constant modal force from rest:
    // q = st, q' = b.
    Eigen::VectorXd a(nf), b(nf), cc(nf), e(nf), st(nf);
    for (int j = 0; j < nf; ++j) {
        const double lam = d.lambda(j), c = d.c(j);
        if (lam == 0.0) {  // rigid: q'' + c q' = 0
            a(j) = 1.0;
            b(j) = tau * phi1(-c * tau);
            cc(j) = 0.0;
            e(j) = std::exp(-c * tau);
            st(j) = tau * tau * phi2(-c * tau);
            continue;
        }
        const double w = std::sqrt(lam), s = 0.5 * c;
        if (s < w && (w - s) * (w + s) > 0.0) {  // underdamped
            const double wd = std::sqrt((w - s) * (w + s));
            const double E = std::exp(-s * tau), cs = std::cos(wd * tau), sn = std::sin(wd * tau) / wd;
            a(j) = E * (cs + s * sn);
            b(j) = E * sn;
            e(j) = E * (cs - s * sn);
        } else if (s > w && (s - w) * (s + w) > 0.0) {  // overdamped
            const double gam = std::sqrt((s - w) * (s + w));
            if (2 * gam * tau > 0.5) {
                const double r1 = -lam / (s + gam), r2 = -(s + gam);  // slow root without cancellation
                const double e1 = std::exp(r1 * tau), e2 = std::exp(r2 * tau), den = 2 * gam;
                a(j) = (-r2 * e1 + r1 * e2) / den;
                b(j) = (e1 - e2) / den;
                e(j) = (r1 * e1 - r2 * e2) / den;
            } else {
                const double E = std::exp(-s * tau), ch = std::cosh(gam * tau), sh = tau * sinhc(gam * tau);
                a(j) = E * (ch + s * sh);
                b(j) = E * sh;
                e(j) = E * (ch - s * sh);
            }
        } else {  // critical
            const double E = std::exp(-s * tau);
            a(j) = E * (1 + s * tau);
            b(j) = E * tau;
            e(j) = E * (1 - s * tau);
        }
        cc(j) = -lam * b(j);
        st(j) = (1.0 - a(j)) / lam;
    }
    const Eigen::MatrixXd& P = md.phi;
    const Eigen::MatrixXd XX = P * a.asDiagonal() * d.E, XV = P * b.asDiagonal() * d.E;
    const Eigen::MatrixXd VX = P * cc.asDiagonal() * d.E, VV = P * e.asDiagonal() * d.E;
    const Eigen::MatrixXd XS = P * st.asDiagonal() * d.G, VS = P * b.asDiagonal() * d.G;
    Eigen::MatrixXd Phi = Eigen::MatrixXd::Zero(2 * n, 2 * n);
    for (int r = 0; r < nf; ++r) {
        const int i = md.free[r];
        for (int q = 0; q < nf; ++q) {
            const int k = md.free[q];
            Phi(i, k) = XX(r, q);
            Phi(i, n + k) = XV(r, q);
            Phi(n + i, k) = VX(r, q);
            Phi(n + i, n + k) = VV(r, q);
        }
        for (int s = 0; s < ns; ++s) {
            Phi(i, md.stuck[s]) = XS(r, s);
            Phi(n + i, md.stuck[s]) = VS(r, s);
        }
    }
    for (int s = 0; s < ns; ++s) Phi(md.stuck[s], md.stuck[s]) = 1.0;  // fixed support; its dv is gone
    return Phi;
}

double Tangent::max_rate(const Configuration& cfg) {
    const ConfigData& d = data(cfg);
    if (stick_ || !model_.proportional_damping()) return 2.0 * d.rate;  // -2 Re lambda: the fastest decay of u'' + c u' + ...
    return d.c.size() ? std::max(0.0, d.c.maxCoeff()) : 0.0;
}

void Tangent::apply_transition(const Configuration& cfg, double tau, Eigen::MatrixXd& Y) {
    Y = transition(cfg, tau) * Y;
}

namespace {

// Acceleration of mass i in cfg (friction directions sgn) at (t, x, v): 0 when stuck.
double acceleration(const Model& model, const Configuration& cfg, const signed char* sgn, int i, double t,
                    const double* x, const double* v) {
    if (cfg.stuck[i]) return 0.0;
    const double fr = model.has_friction(i) ? model.friction_slot(i).mu_k * model.normal_force(i) : 0.0;
    return (force_on_mass(model, cfg, i, t, x, v) - fr * sgn[i]) / model.masses[i].m;
}

// Every mass's acceleration in cfg (a coupled M: M_FF a_F = f_F with the
// stuck dofs held, model/held_mass.h).
std::vector<double> accelerations(const Model& model, const Configuration& cfg, const signed char* sgn, double t,
                                  const double* x, const double* v) {
    const int n = static_cast<int>(model.dof());
    std::vector<double> a(static_cast<std::size_t>(n));
    if (model.coupled_mass()) {
        std::vector<double> f(static_cast<std::size_t>(n));
        held_forces(model, cfg, cfg.stuck, sgn, t, x, v, f.data());
        HeldMass(model, cfg.stuck).accelerations(f.data(), a.data());
        return a;
    }
    for (int i = 0; i < n; ++i) a[static_cast<std::size_t>(i)] = acceleration(model, cfg, sgn, i, t, x, v);
    return a;
}

}  // namespace

namespace {

// One switch from (A, sgnA) to (B, sgnB) triggered by f at (t, x, v):
// Y <- (I + u h_y^T / hdot) Y with u = f+ - f- (velocity rows only).
// Returns false for a grazing switch (hdot = 0 with u != 0).
bool salt_step(const Model& model, const Eigen::MatrixXd& KA, const Eigen::MatrixXd& CA, const Configuration& A,
               const signed char* sgnA, const Configuration& B, const signed char* sgnB, const SwitchFunction* f,
               double t, const double* x, const double* v, Eigen::MatrixXd& Y) {
    const int n = static_cast<int>(model.dof());
    const std::vector<double> aA = accelerations(model, A, sgnA, t, x, v);
    // u: the jump of the accelerations. For a mass sliding on both sides it
    // is the jump of the dampers of the contacts that change (their springs
    // carry no force on G = 0) and of the friction direction, taken from
    // those terms alone, without the cancellation of two full accelerations.
    Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
    std::vector<double> dA(static_cast<std::size_t>(n), 0.0);
    for (std::size_t c = 0; c < model.contacts.size(); ++c) {
        if (A.closed[c] == B.closed[c]) continue;
        const Contact& k = model.contacts[c];
        const double damper = -(model.beta * k.k + k.c) * gap_rate(model, static_cast<int>(c), v);  // along w, while closed
        const double sign = B.closed[c] ? 1.0 : -1.0;
        for_each_term(k.direction(), [&](int i, double w) { dA[static_cast<std::size_t>(i)] += sign * damper * w; });
    }
    std::vector<char> stick(static_cast<std::size_t>(n), 0);
    for (int i = 0; i < n; ++i) {
        const double fr = model.has_friction(i) ? model.friction_slot(i).mu_k * model.normal_force(i) : 0.0;
        if (A.stuck[i] && B.stuck[i]) continue;
        if (A.stuck[i]) {
            u(i) = acceleration(model, B, sgnB, i, t, x, v);
        } else if (B.stuck[i]) {
            u(i) = -aA[i];
            stick[i] = 1;
        } else {
            u(i) = (dA[i] - fr * (sgnB[i] - sgnA[i])) / model.masses[i].m;
        }
    }
    if (model.coupled_mass()) {  // the held motion (held_mass.h): the jump of the forces over M_FF, or a_B - a_A
        if (A.stuck == B.stuck) {
            for (int i = 0; i < n; ++i)
                if (!A.stuck[i] && model.has_friction(i))
                    dA[i] -= model.friction_slot(i).mu_k * model.normal_force(i) * (sgnB[i] - sgnA[i]);
            HeldMass(model, A.stuck).accelerations(dA.data(), u.data());
        } else {
            const std::vector<double> aB = accelerations(model, B, sgnB, t, x, v);
            for (int i = 0; i < n; ++i) u(i) = aB[i] - aA[i];
        }
    }
    if (u.isZero(0.0) || !f) return true;
    // The switch function's gradient and rate before the switch.
    Eigen::RowVectorXd hy = Eigen::RowVectorXd::Zero(2 * n);
    double hdot = 0.0;
    const int e = f->element;
    switch (f->kind) {
        case SwitchKind::gap: {
            for_each_term(model.contacts[e].direction(), [&](int i, double w) { hy(i) += w; });
            hdot = gap_rate(model, e, v);
            break;
        }
        case SwitchKind::velocity:
            hy(n + e) = 1.0;
            hdot = aA[e];
            break;
        case SwitchKind::release_pos:
        case SwitchKind::release_neg: {
            const double sg = f->kind == SwitchKind::release_pos ? 1.0 : -1.0;
            if (model.coupled_mass()) {  // D_e = P_e . f (held_mass.h)
                const Eigen::VectorXd P = HeldMass(model, A.stuck).release_row(e);
                for (int j = 0; j < n; ++j) {
                    hy(j) = -sg * P.dot(KA.col(j));
                    hy(n + j) = -sg * P.dot(CA.col(j));
                }
                for (int q = 0; q < n; ++q)
                    if (P(q) != 0.0) hdot += sg * P(q) * force_rate_on_mass(model, A, q, t, v, aA.data());
                break;
            }
            for (int j = 0; j < n; ++j) {
                hy(j) = -sg * KA(e, j);
                hy(n + j) = -sg * CA(e, j);
            }
            hdot = sg * force_rate_on_mass(model, A, e, t, v, aA.data());
            break;
        }
        case SwitchKind::slip_pos:  // Jenkins elements never reach the tangent (Flow: require_no_stick_elements)
        case SwitchKind::slip_neg:
        case SwitchKind::slip_velocity: return false;
    }
    if (!(std::fabs(hdot) > 0.0) || !std::isfinite(hdot)) return false;
    const Eigen::RowVectorXd w = hy * Y;
    Y.bottomRows(n).noalias() += (u / hdot) * w;
    for (int i = 0; i < n; ++i)
        if (stick[i]) Y.row(n + i).setZero();  // exactly: u_i / hdot = -1 for the stopping mass
    return true;
}

// An impact at rigid stop c (contact.h impact) at (t, x), v+ the velocities
// after it: y+ = g(y-) = (x, R v-), R = I - (1 + e) M^-1 w w^T / (w^T M^-1 w),
// where G = w^T x - gap reaches 0; the saltation matrix of a state jump,
//     S = Dg + (f+ - Dg f-) h_y^T / (h_y^T f-),  h_y = (w, 0),  h_y^T f- = G'-,
// with f- = (v-, a-), f+ = (v+, a+) the vector fields on either side.
struct ImpactJump {
    Eigen::VectorXd w, vm;  // the stop's direction, the velocities before the jump
    Eigen::MatrixXd R;      // v+ = R v-
    double rate = 0.0;      // G'- = h_y^T f-
};

// The jump at stop c from the velocities after it; false for a grazing
// impact (G'- = 0: the period map has no derivative there).
bool impact_jump(const Model& model, int c, const double* v_after, ImpactJump& j) {
    const int n = static_cast<int>(model.dof());
    std::vector<double> wv, Mwv;
    const double wMw = impact_direction(model, c, wv, Mwv), e = model.contacts[static_cast<std::size_t>(c)].restitution;
    j.w = Eigen::Map<const Eigen::VectorXd>(wv.data(), n);
    const Eigen::Map<const Eigen::VectorXd> Mw(Mwv.data(), n), vp(v_after, n);
    j.rate = -j.w.dot(vp) / e;  // G' before the impact
    if (!(std::fabs(j.rate) > 0.0) || !std::isfinite(j.rate)) return false;
    j.vm = vp + ((1 + e) * j.rate / wMw) * Mw;
    j.R = Eigen::MatrixXd::Identity(n, n) - ((1 + e) / wMw) * Mw * j.w.transpose();
    return true;
}

// The saltation of an impact on the state (x, v). Only a lone impact that
// changes no configuration (no friction set moving) is taken; false
// otherwise, and for a grazing impact.
bool salt_impact(const Model& model, const Configuration& A, const signed char* sgnA, const Configuration& B,
                 const signed char* sgnB, int c, double t, const double* x, const double* v_after, Eigen::MatrixXd& Y) {
    ImpactJump j;
    if (A != B || !impact_jump(model, c, v_after, j)) return false;
    const int n = static_cast<int>(model.dof());
    const Eigen::Map<const Eigen::VectorXd> vp(v_after, n);
    const std::vector<double> am = accelerations(model, A, sgnA, t, x, j.vm.data()),
                              ap = accelerations(model, B, sgnB, t, x, v_after);
    const Eigen::VectorXd jump_a =
        Eigen::Map<const Eigen::VectorXd>(ap.data(), n) - j.R * Eigen::Map<const Eigen::VectorXd>(am.data(), n);
    const Eigen::RowVectorXd W = (j.w.transpose() * Y.topRows(n)) / j.rate;  // h_y^T Y / G'-
    const Eigen::MatrixXd top = Y.topRows(n) + (vp - j.vm) * W;
    const Eigen::MatrixXd bottom = j.R * Y.bottomRows(n) + jump_a * W;
    Y.topRows(n) = top;
    Y.bottomRows(n) = bottom;
    return true;
}

// The same jump on the full state z = (x, v, s) of a model with stick
// elements (stick_tangent.h): Dg = diag(I, R, I) (the sliders, like the
// positions, are continuous), f-+ the full vector fields (a slider's rate is
// u' while it slips). The impact may change the Jenkins elements' states
// only (one the jump turned against its slip sticks: its decision is that of
// the new velocity's sign, not of the perturbation); a friction it sets
// moving, or any other change, is not taken.
bool salt_impact_stick(const Model& model, const Configuration& A, const signed char* sgnA, const Configuration& B,
                       const signed char* sgnB, int c, double t, const double* x, const double* v_after,
                       Eigen::MatrixXd& Y) {
    ImpactJump j;
    if (A.stuck != B.stuck || A.closed != B.closed || !impact_jump(model, c, v_after, j)) return false;
    const int n = static_cast<int>(model.dof());
    const Eigen::VectorXd fm = stick_field(model, A, sgnA, t, x, j.vm.data()),
                          fp = stick_field(model, B, sgnB, t, x, v_after);
    Eigen::VectorXd jump = fp - fm;  // f+ - Dg f-
    jump.segment(n, n) = fp.segment(n, n) - j.R * fm.segment(n, n);
    const Eigen::RowVectorXd W = (j.w.transpose() * Y.topRows(n)) / j.rate;  // h_y^T Y / G'-
    Y.middleRows(n, n) = j.R * Y.middleRows(n, n);
    Y.noalias() += jump * W;
    return true;
}

// Whether the instant's switches include an impact (a rigid stop's gap).
const SwitchFunction* impact_of(const Model& model, const std::vector<SwitchFunction>& sw) {
    for (const SwitchFunction& f : sw)
        if (f.kind == SwitchKind::gap && model.contacts[static_cast<std::size_t>(f.element)].rigid()) return &f;
    return nullptr;
}

// The same switch on the full state of a model with stick elements
// (stick_tangent.h): u = f+ - f- of the whole vector field.
bool salt_step_stick(const Model& model, const Configuration& A, const signed char* sgnA, const Configuration& B,
                     const signed char* sgnB, const SwitchFunction* f, double t, const double* x, const double* v,
                     Eigen::MatrixXd& Y) {
    const Eigen::VectorXd fA = stick_field(model, A, sgnA, t, x, v);
    const Eigen::VectorXd u = stick_field(model, B, sgnB, t, x, v) - fA;
    if (u.isZero(0.0) || !f) return true;
    Eigen::RowVectorXd hz;
    double ht = 0.0;
    stick_gradient(model, A, *f, t, hz, ht);
    const double hdot = hz.dot(fA) + ht;
    if (!(std::fabs(hdot) > 0.0) || !std::isfinite(hdot)) return false;
    const Eigen::RowVectorXd w = hz * Y;
    Y.noalias() += (u / hdot) * w;
    return true;
}

}  // namespace

bool Tangent::apply_saltation(const SwitchRecord& r, Eigen::MatrixXd& Y) {
    const std::vector<SwitchFunction>& sw = *r.switched;
    const int n = static_cast<int>(model_.dof());
    if (const SwitchFunction* f = impact_of(model_, sw)) {  // a lone impact, else singular
        if (sw.size() > 1) return false;
        Eigen::MatrixXd Z = Y;
        if (stick_ ? !salt_impact_stick(model_, *r.before, r.sgn_before, *r.after, r.sgn_after, f->element, r.t, r.x,
                                        r.v, Z)
                   : !salt_impact(model_, *r.before, r.sgn_before, *r.after, r.sgn_after, f->element, r.t, r.x, r.v, Z))
            return false;
        Y = std::move(Z);
        return true;
    }
    if (sw.size() <= 1) {
        const ConfigData& d = data(*r.before);
        Eigen::MatrixXd Z = Y;
        const SwitchFunction* f = sw.empty() ? nullptr : &sw[0];
        if (stick_ ? !salt_step_stick(model_, *r.before, r.sgn_before, *r.after, r.sgn_after, f, r.t, r.x, r.v, Z)
                   : !salt_step(model_, d.K, d.C, *r.before, r.sgn_before, *r.after, r.sgn_after, f, r.t, r.x, r.v, Z))
            return false;
        Y = std::move(Z);
        return true;
    }
    // Several functions at once: one after the other, each with the
    // configuration the transitions so far give (the last: the engine's).
    Configuration cur = *r.before;
    std::vector<signed char> sgn(r.sgn_before, r.sgn_before + n);
    std::vector<double> v(r.v, r.v + n);
    Eigen::MatrixXd Z = Y;
    for (std::size_t k = 0; k < sw.size(); ++k) {
        Configuration next = *r.after;
        std::vector<signed char> sgn_next(r.sgn_after, r.sgn_after + n);
        if (k + 1 < sw.size()) {
            next = cur;
            sgn_next = sgn;
            std::vector<Transition> out;
            std::string why;
            if (!apply_switches(model_, r.t, r.x, v.data(), nullptr, next, sgn_next, {sw[k]}, out, why)) return false;
        }
        const ConfigData& d = data(cur);
        if (stick_ ? !salt_step_stick(model_, cur, sgn.data(), next, sgn_next.data(), &sw[k], r.t, r.x, r.v, Z)
                   : !salt_step(model_, d.K, d.C, cur, sgn.data(), next, sgn_next.data(), &sw[k], r.t, r.x, r.v, Z))
            return false;
        cur = next;
        sgn = sgn_next;
    }
    Y = std::move(Z);
    return true;
}

double Tangent::grazing_ratio(const SwitchRecord& r) {
    const int n = static_cast<int>(model_.dof());
    double omega = 0.0;
    for (const Harmonic& h : model_.forcing) omega = std::max(omega, std::fabs(h.omega));
    const ConfigData& d = data(*r.before);
    if (d.lambda.size()) omega = std::max(omega, std::sqrt(std::max(0.0, d.lambda.maxCoeff())));
    if (stick_) {  // the full generator's fastest frequency
        const Eigen::EigenSolver<Eigen::MatrixXd> es(d.stick_A, false);
        for (Eigen::Index k = 0; k < es.eigenvalues().size(); ++k) omega = std::max(omega, std::abs(es.eigenvalues()(k)));
    }
    std::vector<double> a;
    double ratio = INFINITY;
    for (const SwitchFunction& f : *r.switched) {
        if (f.kind != SwitchKind::gap) continue;
        if (a.empty()) {
            if (stick_) {
                const Eigen::VectorXd f = stick_field(model_, *r.before, r.sgn_before, r.t, r.x, r.v);
                a.resize(static_cast<std::size_t>(n));
                for (int i = 0; i < n; ++i) a[static_cast<std::size_t>(i)] = f(n + i);
            } else {
                a = accelerations(model_, *r.before, r.sgn_before, r.t, r.x, r.v);
            }
        }
        const Contact& k = model_.contacts[static_cast<std::size_t>(f.element)];
        const double rate = std::fabs(gap_rate(model_, f.element, r.v));
        double curvature = 0.0;  // G'' = w^T a
        for_each_term(k.direction(), [&](int i, double w) { curvature += w * a[static_cast<std::size_t>(i)]; });
        curvature = std::fabs(curvature);
        const double q = rate * omega / curvature;  // NaN for 0/0, +inf for a straight crossing
        if (std::isnan(q) || q < ratio) ratio = q;
        if (std::isnan(ratio)) break;
    }
    return ratio;
}

Eigen::MatrixXd Tangent::saltation(const SwitchRecord& instant) {
    Eigen::MatrixXd S = Eigen::MatrixXd::Identity(static_cast<Eigen::Index>(dim()), static_cast<Eigen::Index>(dim()));
    if (!apply_saltation(instant, S)) S.setConstant(std::numeric_limits<double>::quiet_NaN());
    return S;
}

void GrazingMonitor::on_switch(const SwitchRecord& r, bool singular) {
    singular_ += singular;
    if (singular || !(tangent_.grazing_ratio(r) > kGrazingRatio)) ++grazing_;
}

JacobianObserver::JacobianObserver(const Model& model, Observer* inner)
    : tangent_(model), inner_(inner),
      J_(Eigen::MatrixXd::Identity(static_cast<Eigen::Index>(tangent_.dim()), static_cast<Eigen::Index>(tangent_.dim()))),
      grazing_(tangent_) {}

void JacobianObserver::on_sample(double t, const double* x, const double* v) {
    if (inner_) inner_->on_sample(t, x, v);
}
void JacobianObserver::on_event(double t, EventKind kind, int element, const double* x, const double* v) {
    if (inner_) inner_->on_event(t, kind, element, x, v);
}
bool JacobianObserver::on_progress(double t) { return inner_ ? inner_->on_progress(t) : true; }

void JacobianObserver::on_segment(const SegmentRecord& s) { tangent_.apply_transition(*s.cfg, s.tau, J_); }

void JacobianObserver::on_switch(const SwitchRecord& r) {
    (r.switched->size() > 1 ? multiple_ : single_) += 1;
    grazing_.on_switch(r, !tangent_.apply_saltation(r, J_));
}

}  // namespace hsnc::analysis
