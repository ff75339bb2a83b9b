#include "tie_series.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "assembly.h"
#include "elements/contact.h"
#include "elements/friction.h"
#include "elements/jenkins.h"
#include "elements/motion.h"
#include "held_mass.h"
#include "switch_derivative.h"
#include "kernel_abi.h"

namespace hsnc {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kInf = std::numeric_limits<double>::infinity();

double body(const std::vector<double>& y, int b) { return b == kGround ? 0.0 : y[static_cast<std::size_t>(b)]; }

// A_i^(k) and the magnitude of its terms, from x^(k), x^(k+1) of the series.
void force_derivative(const Model& model, const Configuration& cfg, int i, double t, double t_lo,
                      const MotionSeries& s, int k, double& value, double& magnitude) {
    const std::vector<double>&xk = s.x[static_cast<std::size_t>(k)], &xk1 = s.x[static_cast<std::size_t>(k) + 1];
    const std::vector<double>&mk = s.mag[static_cast<std::size_t>(k)], &mk1 = s.mag[static_cast<std::size_t>(k) + 1];
    const std::size_t ii = static_cast<std::size_t>(i);
    value = k == 0 ? model.load[ii] : 0.0;
    magnitude = std::fabs(value);
    if (model.coupled_mass()) {  // -alpha (M x^(k+1))_i over the row of M
        const std::size_t n = model.dof();
        for (std::size_t j = 0; j < n; ++j) {
            const double mij = model.mass_matrix[ii * n + j];
            value -= model.alpha * mij * xk1[j];
            magnitude += std::fabs(model.alpha * mij) * mk1[j];
        }
    } else {
        value -= model.alpha * model.masses[ii].m * xk1[ii];
        magnitude += std::fabs(model.alpha) * model.masses[ii].m * mk1[ii];
    }
    for_each_link(model, cfg, [&](int a, int b, double kk, double cc, double gap) {
        if (a == b || (a != i && b != i)) return;
        double f = -kk * (body(xk, a) - body(xk, b)) - cc * (body(xk1, a) - body(xk1, b));
        double fm = std::fabs(kk) * (body(mk, a) + body(mk, b)) + std::fabs(cc) * (body(mk1, a) + body(mk1, b));
        if (k == 0 && gap != 0.0) f += kk * gap, fm += std::fabs(kk * gap);
        value += a == i ? f : -f;
        magnitude += fm;
    }, s.slider.data());
    if (k == 0)
        for_each_constant(
            model, cfg,
            [&](int a, int b, double fa) {
                if (a != i && b != i) return;
                value += a == i ? fa : -fa;
                magnitude += std::fabs(fa);
            },
            s.slider.data());
    for (const Harmonic& h : model.forcing) {
        const double amp = h.amplitude[ii];
        if (amp == 0.0) continue;
        // d^k/dt^k sin(arg) = Omega^k sin(arg + k pi/2); the phase reduced accurately at large t.
        const double arg = hsnc_phase(h.omega, t, t_lo, h.phase);
        double trig = (k % 2 == 0) ? std::sin(arg) : std::cos(arg);
        if (k % 4 == 2 || k % 4 == 3) trig = -trig;
        const double wk = std::pow(h.omega, k);
        value += amp * wk * trig;
        magnitude += std::fabs(amp * wk);
    }
}

// D_i^(k) (assembly.h driving_force): A_i^(k), or against a partner p
// (m_p A_i^(k) - m_i A_p^(k))/(m_i + m_p).
void driving_derivative(const Model& model, const Configuration& cfg, int i, double t, double t_lo,
                        const MotionSeries& s, int k, double& value, double& magnitude) {
    if (model.coupled_friction()) {  // D_i^(k) = P_i . (A^(k) + [k = 0] kinetic friction), i held (held_mass.h)
        const Eigen::VectorXd P = HeldMass(model, cfg.stuck).release_row(i);
        value = magnitude = 0.0;
        for (Eigen::Index q = 0; q < P.size(); ++q) {
            if (P(q) == 0.0) continue;
            double A, m;
            force_derivative(model, cfg, static_cast<int>(q), t, t_lo, s, k, A, m);
            if (k == 0) A += s.friction[static_cast<std::size_t>(q)], m += std::fabs(s.friction[static_cast<std::size_t>(q)]);
            value += P(q) * A;
            magnitude += std::fabs(P(q)) * m;
        }
        return;
    }
    force_derivative(model, cfg, i, t, t_lo, s, k, value, magnitude);
    const int p = model.friction_slot(static_cast<std::size_t>(i)).partner;
    if (p == kGround) return;
    double Ap, mp_mag;
    force_derivative(model, cfg, p, t, t_lo, s, k, Ap, mp_mag);
    const double mi = model.masses[static_cast<std::size_t>(i)].m, mp = model.masses[static_cast<std::size_t>(p)].m;
    value = against_partner(mi, mp, value, Ap);
    magnitude = against_partner_magnitude(mi, mp, magnitude, mp_mag);
}

}  // namespace

int tie_order(const Model& model) { return static_cast<int>(2 * model.dof() + 2 * model.forcing.size() + 2); }

double tie_noise(double mag) { return 16 * kEps * mag; }

MotionSeries motion_series(const Model& model, const Configuration& cfg, const signed char* sgn, double t, double t_lo,
                           const double* x, const double* v, int order) {
    const std::size_t n = model.dof();
    MotionSeries s;
    s.x.assign(static_cast<std::size_t>(order) + 1, std::vector<double>(n, 0.0));
    s.mag = s.x;
    for (std::size_t j = 0; j < model.jenkins.size(); ++j) s.slider.push_back(slider_position(model, cfg, j, x));
    // A mass stuck to its partner moves with it: one body of both masses
    // (rider[p] = that mass), on which their friction is internal.
    std::vector<int> rider(n, -1);
    for (std::size_t i = 0; i < n; ++i)
        if (rides_partner(model, cfg, i))
            rider[static_cast<std::size_t>(model.friction_slot(i).partner)] = static_cast<int>(i);
    for (std::size_t i = 0; i < n; ++i) {
        s.x[0][i] = x[i];
        s.mag[0][i] = std::fabs(x[i]);
        if (order >= 1 && !fixed_in(model, cfg, i)) {
            s.x[1][i] = v[i];
            s.mag[1][i] = std::fabs(v[i]);
        }
    }
    if (model.coupled_friction()) {  // x^(k+2) = T (T^T M T)^-1 T^T (A^(k) + [k = 0] friction), |.| on the magnitudes
        const HeldMass held(model, cfg.stuck);  // riders only on a shared partner of a lumped M (model_reader)
        const Eigen::MatrixXd inv_abs = held.inverse().cwiseAbs();
        s.friction.assign(n, 0.0);
        kinetic_friction(model, cfg.stuck, sgn, s.friction.data());
        Eigen::VectorXd A(static_cast<Eigen::Index>(n)), m(static_cast<Eigen::Index>(n)), x(static_cast<Eigen::Index>(n));
        for (int k = 0; k + 2 <= order; ++k) {
            for (std::size_t i = 0; i < n; ++i) {
                const auto ii = static_cast<Eigen::Index>(i);
                force_derivative(model, cfg, static_cast<int>(i), t, t_lo, s, k, A(ii), m(ii));
                if (k == 0) A(ii) += s.friction[i], m(ii) += std::fabs(s.friction[i]);
            }
            held.accelerations(A.data(), x.data());
            const Eigen::VectorXd xm = inv_abs * m;
            for (std::size_t i = 0; i < n; ++i) {
                s.x[static_cast<std::size_t>(k) + 2][i] = x(static_cast<Eigen::Index>(i));
                s.mag[static_cast<std::size_t>(k) + 2][i] = xm(static_cast<Eigen::Index>(i));
            }
        }
        return s;
    }
    for (int k = 0; k + 2 <= order; ++k)
        for (std::size_t i = 0; i < n; ++i) {
            if (cfg.stuck[i]) continue;  // held still, or moved with its partner below
            double A, m, mass = model.masses[i].m;
            force_derivative(model, cfg, static_cast<int>(i), t, t_lo, s, k, A, m);
            if (rider[i] >= 0) {
                double Ar, mr;
                force_derivative(model, cfg, rider[i], t, t_lo, s, k, Ar, mr);
                A += Ar, m += mr, mass += model.masses[static_cast<std::size_t>(rider[i])].m;
            }
            if (k == 0)  // kinetic friction of a sliding mass, and its reaction on the partner
                for (std::size_t q = 0; q < n; ++q) {
                    const FrictionSlot& fq = model.friction_slot(q);
                    if (!fq.active || sgn[q] == 0 || (q != i && fq.partner != static_cast<int>(i))) continue;
                    const double fr = fq.mu_k * model.normal_force(q);
                    A += q == i ? -fr * sgn[q] : fr * sgn[q];
                    m += fr;
                }
            s.x[static_cast<std::size_t>(k) + 2][i] = A / mass;
            s.mag[static_cast<std::size_t>(k) + 2][i] = m / mass;
            if (rider[i] >= 0) {
                s.x[static_cast<std::size_t>(k) + 2][static_cast<std::size_t>(rider[i])] = A / mass;
                s.mag[static_cast<std::size_t>(k) + 2][static_cast<std::size_t>(rider[i])] = m / mass;
            }
        }
    return s;
}

void switch_series(const Model& model, const Configuration& cfg, const SwitchFunction& f, double t, double t_lo,
                   const MotionSeries& series, std::vector<double>& d, std::vector<double>& mag) {
    const std::size_t order = series.x.size() - 1;
    d.assign(order, 0.0);
    mag.assign(order, 0.0);
    const int e = f.element;
    const auto m = double_motion(series.x, &series.mag);
    const auto ee = static_cast<std::size_t>(e);
    const auto p = model_elements<double>(model, [](double v) { return v; },
                                          [&](int j) { return series.slider[static_cast<std::size_t>(j)]; });
    for (std::size_t k = 0; k < order; ++k) {
        const int kk = static_cast<int>(k);
        if (!is_release(f.kind)) {
            d[k] = switch_derivative(p, f, m, kk);
            mag[k] = switch_magnitude(p, f, m, kk);
            continue;
        }
        double A, Am;
        driving_derivative(model, cfg, e, t, t_lo, series, kk, A, Am);
        const double limit = model.friction_slot(ee).mu_s * model.normal_force(ee);
        d[k] = friction::release_value(f.kind == SwitchKind::release_pos ? 1 : -1, A, limit, kk);
        mag[k] = friction::release_magnitude(Am, limit, kk);
    }
}

void force_series(const Model& model, const Configuration& cfg, int i, double t, double t_lo,
                  const MotionSeries& series, std::vector<double>& d, std::vector<double>& mag) {
    const std::size_t order = series.x.size() - 1;
    d.assign(order, 0.0);
    mag.assign(order, 0.0);
    for (std::size_t k = 0; k < order; ++k)
        driving_derivative(model, cfg, i, t, t_lo, series, static_cast<int>(k), d[k], mag[k]);
}

double rate_magnitude(const Model& model, const Configuration& cfg, const SwitchFunction& f, const double* x,
                      const double* v) {
    auto at = [](const double* y, int b) { return b == kGround ? 0.0 : std::fabs(y[b]); };
    const int e = f.element;
    const double* rows[] = {x, v};
    const auto m = double_motion(rows);  // the magnitudes |x|, |v|
    if (f.kind == SwitchKind::gap) {
        const Contact& c = model.contacts[static_cast<std::size_t>(e)];
        return contact::gap_magnitude(c.direction(), c.gap, m, 1);
    }
    if (f.kind == SwitchKind::slip_pos || f.kind == SwitchKind::slip_neg) {
        const Jenkins& J = model.jenkins[static_cast<std::size_t>(e)];
        return jenkins::slip_magnitude(J.k, J.slip_force, J.direction(), 0.0, m, 1);
    }
    // The magnitude of the terms of x_i'' (0 for a stuck mass): A_i's terms and the friction force.
    auto force_magnitude = [&](int i) {
        const std::size_t ii = static_cast<std::size_t>(i);
        double m = std::fabs(model.load[ii]) + std::fabs(model.alpha) * model.masses[ii].m * std::fabs(v[ii]);
        if (model.coupled_mass()) m = std::fabs(model.load[ii]) + std::fabs(model.alpha * mass_times(model, ii, v));
        for_each_link(model, cfg, [&](int a, int b, double kk, double cc, double gap) {
            if (a == b || (a != i && b != i)) return;
            m += std::fabs(kk) * (at(x, a) + at(x, b)) + std::fabs(cc) * (at(v, a) + at(v, b)) + std::fabs(kk * gap);
        }, x + model.dof());
        for_each_constant(
            model, cfg,
            [&](int a, int b, double fa) {
                if (a == i || b == i) m += std::fabs(fa);
            },
            x + model.dof());
        for (const Harmonic& h : model.forcing) m += std::fabs(h.amplitude[ii]);
        for (std::size_t q = 0; q < model.dof(); ++q)  // its friction, and that of a mass it is the partner of
            if (model.has_friction(q) && (q == ii || model.friction_slot(q).partner == i))
                m += model.friction_slot(q).mu_k * model.normal_force(q);
        return m;
    };
    auto accel_magnitude = [&](int i) {
        const std::size_t ii = static_cast<std::size_t>(i);
        if (i == kGround || fixed_in(model, cfg, ii)) return 0.0;
        if (!model.coupled_mass()) return force_magnitude(i) / model.masses[ii].m;
        // |(M^-1 A)_i| <= ||A||_2 / lambda_min(M) <= sum_j |A_j| / lambda_min(M).
        double sum = 0.0;
        for (std::size_t j = 0; j < model.dof(); ++j) sum += force_magnitude(static_cast<int>(j));
        return sum / model.mass_floor;
    };
    const int partner =
        f.kind == SwitchKind::velocity || f.kind == SwitchKind::release_pos || f.kind == SwitchKind::release_neg
            ? model.friction_slot(static_cast<std::size_t>(e)).partner
            : kGround;
    if (f.kind == SwitchKind::velocity) return accel_magnitude(e) + accel_magnitude(partner);
    if (f.kind == SwitchKind::slip_velocity) {  // |w|^T |x''|
        double m = 0.0;
        for_each_term(model.jenkins[static_cast<std::size_t>(e)].direction(),
                      [&](int b, double w) { m += std::fabs(w) * accel_magnitude(b); });
        return m;
    }
    // A_i' = -(K v)_i - (C x'')_i + sum_h F_hi Omega_h cos(...); D_i' against a partner.
    auto force_rate_magnitude = [&](int i) {
        const std::size_t ii = static_cast<std::size_t>(i);
        double m = std::fabs(model.alpha) * model.masses[ii].m * accel_magnitude(i);
        if (model.coupled_mass()) {  // -alpha (M x'')_i over the row of M
            m = 0.0;
            for (std::size_t j = 0; j < model.dof(); ++j)
                m += std::fabs(model.alpha * model.mass_entry(ii, j)) * accel_magnitude(static_cast<int>(j));
        }
        for_each_link(model, cfg, [&](int a, int b, double kk, double cc, double) {
            if (a == b || (a != i && b != i)) return;
            m += std::fabs(kk) * (at(v, a) + at(v, b)) + std::fabs(cc) * (accel_magnitude(a) + accel_magnitude(b));
        });
        for (const Harmonic& h : model.forcing) m += std::fabs(h.amplitude[ii] * h.omega);
        return m;
    };
    if (model.coupled_friction()) {  // D_i' = P_i . A' (held_mass.h)
        const Eigen::VectorXd P = HeldMass(model, cfg.stuck).release_row(e);
        double m = 0.0;
        for (Eigen::Index q = 0; q < P.size(); ++q)
            if (P(q) != 0.0) m += std::fabs(P(q)) * force_rate_magnitude(static_cast<int>(q));
        return m;
    }
    if (partner == kGround) return force_rate_magnitude(e);
    const double mi = model.masses[static_cast<std::size_t>(e)].m, mp = model.masses[static_cast<std::size_t>(partner)].m;
    return against_partner_magnitude(mi, mp, force_rate_magnitude(e), force_rate_magnitude(partner));
}

int first_nonzero_sign(const std::vector<double>& d, const std::vector<double>& mag, int max_order, int* order) {
    const std::size_t last = std::min(d.size() - 1, static_cast<std::size_t>(std::max(max_order, 0)));
    for (std::size_t k = 1; k <= last; ++k)
        if (std::fabs(d[k]) > tie_noise(mag[k])) {
            if (order) *order = static_cast<int>(k);
            return d[k] > 0 ? 1 : -1;
        }
    return 0;
}

double derivative_bound(const Model& model, const Configuration& cfg, const SwitchFunction& f,
                        const MotionSeries& series, int k, double T) {
    if (!(model.alpha >= 0) || !(model.beta >= 0) || k < 2) return kInf;
    const std::size_t n = model.dof();
    auto free_mass = [&](int b) { return b != kGround && !fixed_in(model, cfg, static_cast<std::size_t>(b)); };
    // R_j(T) >= sqrt(2 E_j(s)) on [0, T], j >= 1; every value taken at its
    // magnitude plus its rounding level, and the result enlarged by a few ulps.
    auto R = [&](int j) {
        const std::vector<double>&z = series.x[static_cast<std::size_t>(j)], &zm = series.mag[static_cast<std::size_t>(j)];
        const std::vector<double>&zd = series.x[static_cast<std::size_t>(j) + 1],
                                  &zdm = series.mag[static_cast<std::size_t>(j) + 1];
        auto up = [](double value, double mag) { return std::fabs(value) + tie_noise(mag); };
        double two_e = 0.0;
        if (model.coupled_mass()) {  // z'^T M z' <= sum |M_ij| |z'_i| |z'_j| over the free dofs
            for (std::size_t i = 0; i < n; ++i)
                for (std::size_t l = 0; l < n; ++l)
                    if (!fixed_in(model, cfg, i) && !fixed_in(model, cfg, l))
                        two_e += std::fabs(model.mass_entry(i, l)) * up(zd[i], zdm[i]) * up(zd[l], zdm[l]);
        } else {
            for (std::size_t i = 0; i < n; ++i)
                if (!fixed_in(model, cfg, i)) two_e += model.masses[i].m * up(zd[i], zdm[i]) * up(zd[i], zdm[i]);
        }
        for_each_link(model, cfg, [&](int a, int b, double kk, double, double) {
            if (a == b) return;
            const double za = free_mass(a) ? z[static_cast<std::size_t>(a)] : 0.0;
            const double zb = free_mass(b) ? z[static_cast<std::size_t>(b)] : 0.0;
            const double ma = free_mass(a) ? zm[static_cast<std::size_t>(a)] : 0.0;
            const double mb = free_mass(b) ? zm[static_cast<std::size_t>(b)] : 0.0;
            const double dz = up(za - zb, ma + mb);
            two_e += std::fabs(kk) * dz * dz;  // >= the energy also with negative springs (structure.h)
        });
        double phi = 0.0;
        for (const Harmonic& h : model.forcing) {
            double norm = 0.0;
            for (std::size_t i = 0; i < n; ++i)
                if (!fixed_in(model, cfg, i))  // F^T M_FF^-1 F <= |F|^2 / lambda_min(M) on a coupled M
                    norm += h.amplitude[i] * h.amplitude[i] / (model.coupled_mass() ? model.mass_floor : model.masses[i].m);
            phi += std::pow(std::fabs(h.omega), j) * std::sqrt(norm);
        }
        return (std::sqrt(two_e) + phi * T) * (1 + 64 * kEps);
    };
    // |x_b^(j+1)| <= R_j / sqrt(m_b) for a free mass b, 0 for ground and stuck masses
    // (coupled M: z^T M z >= lambda_min(M) z_b^2, lambda_min(M_FF) >= lambda_min(M)).
    auto per_mass = [&](int b, double r) {
        if (!free_mass(b)) return 0.0;
        return r / std::sqrt(model.coupled_mass() ? model.mass_floor : model.masses[static_cast<std::size_t>(b)].m);
    };
    // |u^(k)| <= |w|^T of the bodies' bounds, u = w^T x.
    auto along_bound = [&](const Direction& d, double r) {
        double B = 0.0;
        for_each_term(d, [&](int b, double w) { B += std::fabs(w) * per_mass(b, r); });
        return d.weighted() ? B * (1 + 64 * kEps) : B;  // |w_i| products rounded
    };
    const int e = f.element;
    if (f.kind == SwitchKind::gap)  // G^(k) = w^T x^(k)
        return along_bound(model.contacts[static_cast<std::size_t>(e)].direction(), R(k - 1));
    if (f.kind == SwitchKind::velocity)  // w^(k) = x_e^(k+1) - x_partner^(k+1)
        return per_mass(e, R(k)) + per_mass(model.friction_slot(static_cast<std::size_t>(e)).partner, R(k));
    if (f.kind == SwitchKind::slip_pos || f.kind == SwitchKind::slip_neg) {  // k u^(k)
        const Jenkins& J = model.jenkins[static_cast<std::size_t>(e)];
        return J.k * along_bound(J.direction(), R(k - 1)) * (1 + 64 * kEps);
    }
    if (f.kind == SwitchKind::slip_velocity)  // u^(k+1)
        return along_bound(model.jenkins[static_cast<std::size_t>(e)].direction(), R(k));
    // A_i^(k) = -(K x^(k))_i - (C x^(k+1))_i + sum_h F_hi Omega_h^k sin(...): the neighbours' terms.
    const double rk1 = R(k - 1), rk = R(k);
    auto force_bound = [&](int i) {
        double B = 0.0;
        for_each_link(model, cfg, [&](int a, int b, double kk, double cc, double) {
            if (a == b || (a != i && b != i)) return;
            for (int o : {a, b}) B += std::fabs(kk) * per_mass(o, rk1) + std::fabs(cc) * per_mass(o, rk);
        });
        if (model.coupled_mass()) {
            for (std::size_t l = 0; l < n; ++l)
                B += std::fabs(model.alpha * model.mass_entry(static_cast<std::size_t>(i), l)) * per_mass(static_cast<int>(l), rk);
        } else {
            B += std::fabs(model.alpha) * model.masses[static_cast<std::size_t>(i)].m * per_mass(i, rk);
        }
        for (const Harmonic& h : model.forcing) B += std::fabs(h.amplitude[static_cast<std::size_t>(i)]) * std::pow(std::fabs(h.omega), k);
        return B;
    };
    if (model.coupled_friction()) {  // D_i^(k) = P_i . A^(k) (held_mass.h)
        const Eigen::VectorXd P = HeldMass(model, cfg.stuck).release_row(e);
        double B = 0.0;
        for (Eigen::Index q = 0; q < P.size(); ++q)
            if (P(q) != 0.0) B += std::fabs(P(q)) * force_bound(static_cast<int>(q));
        return B * (1 + 64 * kEps);
    }
    const int p = model.friction_slot(static_cast<std::size_t>(e)).partner;
    if (p == kGround) return force_bound(e) * (1 + 64 * kEps);
    const double mi = model.masses[static_cast<std::size_t>(e)].m, mp = model.masses[static_cast<std::size_t>(p)].m;
    return against_partner_magnitude(mi, mp, force_bound(e), force_bound(p)) * (1 + 64 * kEps);
}

}  // namespace hsnc
