#include "generic_solver.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include "assembly.h"
#include "error.h"
#include "switch_values.h"
#include "kernel_abi.h"  // hsnc_phi2: phi_2(x) = (e^x - 1 - x)/x^2, defined once

namespace hsnc {
namespace {

using cplx = std::complex<double>;
constexpr double kTwoPi = 6.283185307179586;             // 2*pi rounded to double
constexpr double kTwoPiLo = 2.4492935982947064e-16;      // 2*pi - kTwoPi
constexpr double kPi = 3.141592653589793;
// Negative damping: the bounds hold over kGrowthHorizon / |c_min| (see max_step_).
constexpr double kGrowthHorizon = 0.5;
// A harmonic of mode j uses the transient-coupled form when
// sqrt(D) < kCoupled*lambda, D = (lambda - Omega^2)^2 + (c Omega)^2: the
// standard particular solution then has amplitude > 10x the static response and
// would cancel against the homogeneous part. Below this threshold the standard
// form loses at most a factor 10 in relative accuracy.
// This band is the generic solver's own on purpose, not kResonanceBand
// (generator/derivation.h) of the kernels and the interpreter: the generic
// solver is their independent oracle (docs/architecture.md "One program, printed and
// interpreted"), so it decides with another criterion (damped modes too,
// about 5% in frequency for an undamped one) and another resonance-stable form
// (the Duhamel integral), and agreement across both bands is what the tests see.
constexpr double kCoupled = 0.1;
// The stiff tail (the split bound's modes) starts this many times above the
// lowest flexible mode or the forcing, whichever is faster.
constexpr double kStiffFrom = 32.0;
// The split bound is scanned for a function only where the stiff tail holds
// more than this share of its curvature bound B: no cut lowers the slow part's
// bound below B - B_fast, so below this share the split buys little for its
// scan (an overdamped tail, as beam-40's, decays within a few of its periods
// and then holds next to nothing). The function's step is then the whole
// bound's, as the programs take it; either is safe.
constexpr double kSplitWorth = 0.05;

// phi_1(x) = (e^x - 1)/x, phi_1(0) = 1 (accurate for every x: expm1).
double phi1(double x) { return x == 0.0 ? 1.0 : std::expm1(x) / x; }

// Omega*(t0 + t0_lo) + phase reduced to [-pi, pi] with the rounding error of
// the product kept (fma) and 2*pi in two parts (Cody-Waite), so a large t0
// costs no phase accuracy beyond that of t0 + t0_lo itself. The emitted
// kernels do the same (generator/emitter.cpp, hsnc_phase).
double reduced_phase(double omega, double t0, double t0_lo, double phase) {
    const double hi = omega * t0;
    const double lo = std::fma(omega, t0, -hi) + omega * t0_lo;
    const double n = std::nearbyint(hi / kTwoPi);
    double r = std::fma(-n, kTwoPi, hi);
    r = std::fma(-n, kTwoPiLo, r);
    return std::remainder(r + lo + phase, kTwoPi);
}

}  // namespace

// The switch functions as modal combinations (for bound): rows W, Z, D
// (a release function's from D_i, over P_i when M is coupled: held_mass.h).
void GenericSolver::switch_rows(const Model& model) {
    const int ns = static_cast<int>(switches_.size());
    W_ = Eigen::MatrixXd::Zero(ns, nf_);
    Z_ = Eigen::MatrixXd::Zero(ns, nf_);
    D_ = Eigen::MatrixXd::Zero(ns, nh_);
    const std::vector<int>& slot = coord_;
    // Row j of x[a] - x[b] over the modes (ground and stuck masses do not move).
    auto difference = [&](int a, int b, int j) {
        double w = 0.0;
        if (a != kGround && slot[a] >= 0) w += phi_(slot[a], j);
        if (b != kGround && slot[b] >= 0) w -= phi_(slot[b], j);
        return w;
    };
    // Row j of u = w^T x along a direction (x[a] - x[b] between two bodies).
    auto along_row = [&](const Direction& d, int j) {
        if (!d.weighted()) return difference(d.a, d.b, j);
        double u = 0.0;
        for_each_term(d, [&](int b, double w) {
            if (slot[b] >= 0) u += w * phi_(slot[b], j);
        });
        return u;
    };
    for (int f = 0; f < ns; ++f) {
        const SwitchFunction& sf = switches_[f];
        if (sf.kind == SwitchKind::gap) {
            const Direction d = model.contacts[sf.element].direction();
            for (int j = 0; j < nf_; ++j) W_(f, j) = along_row(d, j);
        } else if (sf.kind == SwitchKind::velocity) {  // w = v_i - v_partner
            for (int j = 0; j < nf_; ++j)
                Z_(f, j) = difference(sf.element, t_.partner[static_cast<std::size_t>(sf.element)], j);
        } else if (sf.kind == SwitchKind::slip_pos || sf.kind == SwitchKind::slip_neg) {
            const Jenkins& J = model.jenkins[static_cast<std::size_t>(sf.element)];
            const double sg = sf.kind == SwitchKind::slip_pos ? J.k : -J.k;
            for (int j = 0; j < nf_; ++j) W_(f, j) = sg * along_row(J.direction(), j);
        } else if (sf.kind == SwitchKind::slip_velocity) {
            const Jenkins& J = model.jenkins[static_cast<std::size_t>(sf.element)];
            for (int j = 0; j < nf_; ++j) Z_(f, j) = along_row(J.direction(), j);
        } else {
            // +-A_i: A_i = -(K x)_i - (C v)_i + f_i + F_i(t); against a partner p,
            // +-D_i = +-(m_p A_i - m_i A_p)/(m_i + m_p) (assembly.h driving_force).
            const double sg = sf.kind == SwitchKind::release_pos ? 1.0 : -1.0;
            const int i = sf.element, p = t_.partner[static_cast<std::size_t>(i)];
            auto rows = [&](int e, int j, double& kw, double& cz) {
                kw = cz = 0.0;
                for (int r = 0; r < nf_; ++r) {
                    kw += t_.K(e, modal_.free[r]) * phi_(r, j);
                    cz += t_.C(e, modal_.free[r]) * phi_(r, j);
                }
                for (int q : modal_.riders) {
                    kw += t_.K(e, q) * phi_(slot[static_cast<std::size_t>(q)], j);
                    cz += t_.C(e, q) * phi_(slot[static_cast<std::size_t>(q)], j);
                }
            };
            if (t_.coupled()) {  // D_i = P_i . A (held_mass.h)
                const Eigen::Index row = t_.release_row[static_cast<std::size_t>(i)];
                for (int j = 0; j < nf_; ++j) {
                    double kw = 0.0, cz = 0.0;
                    for (int q = 0; q < n_; ++q) {
                        const double w = t_.release(row, q);
                        if (w == 0.0) continue;
                        double kq, cq;
                        rows(q, j, kq, cq);
                        kw += w * kq;
                        cz += w * cq;
                    }
                    W_(f, j) = -sg * kw;
                    Z_(f, j) = -sg * cz;
                }
                for (int h = 0; h < nh_; ++h) D_(f, h) = sg * t_.release.row(row).dot(t_.h_amp.col(h));
                continue;
            }
            for (int j = 0; j < nf_; ++j) {
                double kw, cz;
                rows(i, j, kw, cz);
                if (p != kGround) {
                    double kp, cp;
                    rows(p, j, kp, cp);
                    const double mi = t_.mass(i), mp = t_.mass(p);
                    kw = against_partner(mi, mp, kw, kp);
                    cz = against_partner(mi, mp, cz, cp);
                }
                W_(f, j) = -sg * kw;
                Z_(f, j) = -sg * cz;
            }
            for (int h = 0; h < nh_; ++h)
                D_(f, h) = sg * (p == kGround ? t_.h_amp(i, h)
                                              : against_partner(t_.mass(i), t_.mass(p), t_.h_amp(i, h), t_.h_amp(p, h)));
        }
    }
}

GenericSolver::GenericSolver(const Model& model, const Configuration& cfg)
    : cfg_(cfg), switches_(switch_functions(model, cfg)), modal_(modal_analysis(model, cfg)) {
    require_proportional_damping(model, "GenericSolver()");  // dampers: StateSpaceSolver
    n_ = static_cast<int>(model.dof());
    nf_ = static_cast<int>(modal_.free.size());
    alpha_ = model.alpha;
    const int ns = static_cast<int>(switches_.size());

    t_ = configuration_terms(model, cfg);
    nh_ = static_cast<int>(t_.h_omega.size());
    // The free coordinate of every mass that moves: its own, or its partner's
    // for a mass stuck to it (modal.h riders); -1 for the ground and stuck masses.
    coord_.assign(static_cast<std::size_t>(n_), -1);
    for (int r = 0; r < nf_; ++r) coord_[static_cast<std::size_t>(modal_.free[r])] = r;
    carrier_.resize(static_cast<std::size_t>(n_));
    for (int i = 0; i < n_; ++i)
        carrier_[static_cast<std::size_t>(i)] = carrier(model, cfg, static_cast<std::size_t>(i));
    for (int q : modal_.riders)
        coord_[static_cast<std::size_t>(q)] = coord_[static_cast<std::size_t>(carrier_[static_cast<std::size_t>(q)])];

    // Modes: M_F-normalised Phi, modal damping c = alpha + beta*lambda, regime.
    phi_ = modal_.phi;
    phi_max_ = phi_.cwiseAbs().colwise().maxCoeff().transpose();
    phi_t_m_.resize(nf_, nf_);
    if (model.coupled_mass()) {
        phi_t_m_ = modal_.phi_t_m();
    } else {
        for (int j = 0; j < nf_; ++j)
            for (int r = 0; r < nf_; ++r) phi_t_m_(j, r) = phi_(r, j) * modal_.mass(r);
    }
    regime_.resize(static_cast<std::size_t>(nf_));
    lambda_ = modal_.lambda;
    omega_.resize(nf_);
    c_.resize(nf_);
    sigma_.resize(nf_);
    omega_d_ = Eigen::VectorXd::Zero(nf_);
    gamma_ = Eigen::VectorXd::Zero(nf_);
    r1_ = Eigen::VectorXd::Zero(nf_);
    r2_ = Eigen::VectorXd::Zero(nf_);
    for (int j = 0; j < nf_; ++j) {
        const double lam = lambda_(j);
        omega_(j) = std::sqrt(lam);
        c_(j) = model.alpha + model.beta * lam;
        sigma_(j) = 0.5 * c_(j);
        const double w = omega_(j), s = sigma_(j);
        if (lam == 0.0) {
            regime_[j] = Regime::rigid;
        } else if (s < 0.0 && -s >= w) {
            throw RunError("GenericSolver(): configuration " + cfg.spec(model) + ": mode " + std::to_string(j + 1) +
                           " has negative damping c = " + std::to_string(c_(j)) +
                           " at or beyond critical (|c| >= 2 omega): a growing motion without oscillation is not "
                           "supported");
        } else if (s < w) {
            regime_[j] = Regime::underdamped;
            omega_d_(j) = std::sqrt((w - s) * (w + s));  // no cancellation near xi = 1
            if (omega_d_(j) == 0.0) regime_[j] = Regime::critical;
        } else if (s > w) {
            regime_[j] = Regime::overdamped;
            gamma_(j) = std::sqrt((s - w) * (s + w));
            r1_(j) = -lam / (s + gamma_(j));  // slow root -sigma + gamma without cancellation
            r2_(j) = -(s + gamma_(j));
            if (gamma_(j) == 0.0) regime_[j] = Regime::critical;
        } else {
            regime_[j] = Regime::critical;
        }
    }

    // Modal forcing and, per (mode, harmonic), the form of the particular part.
    P_.resize(nf_, nh_);
    for (int j = 0; j < nf_; ++j)
        for (int h = 0; h < nh_; ++h) {
            double s = 0.0;
            for (int r = 0; r < nf_; ++r) s += phi_(r, j) * t_.h_amp(modal_.free[r], h);
            for (int q : modal_.riders) s += phi_(coord_[static_cast<std::size_t>(q)], j) * t_.h_amp(q, h);
            P_(j, h) = s;
        }
    coupled_.setZero(nf_, nh_);
    pa_ = Eigen::MatrixXd::Zero(nf_, nh_);
    pb_ = Eigen::MatrixXd::Zero(nf_, nh_);
    zp_ = Eigen::MatrixXcd::Zero(nf_, nh_);
    zm_ = Eigen::MatrixXcd::Zero(nf_, nh_);
    h_has_coupled_.assign(static_cast<std::size_t>(nh_), 0);
    double min_coupled_omega = std::numeric_limits<double>::infinity();
    for (int j = 0; j < nf_; ++j)
        for (int h = 0; h < nh_; ++h) {
            const double W = t_.h_omega(h), lam = lambda_(j), c = c_(j);
            const double det = lam - W * W, cw = c * W;
            const double D = det * det + cw * cw;
            if (regime_[j] == Regime::underdamped && std::sqrt(D) < kCoupled * lam) {
                // Zero-state response y = Im[P e^{i theta} (E+ - E-)/(2 i omega_d)],
                // E+- = (e^{i Omega tau} - e^{r+- tau})/(i Omega - r+-), r+- = -sigma +- i omega_d
                // (Duhamel integral of the impulse response against e^{i Omega tau}).
                coupled_(j, h) = 1;
                h_has_coupled_[h] = 1;
                min_coupled_omega = std::min(min_coupled_omega, W);
                zp_(j, h) = cplx(sigma_(j), W - omega_d_(j));
                zm_(j, h) = cplx(sigma_(j), W + omega_d_(j));
            } else {
                // q_p = a cos + b sin: a = -P c Omega / D, b = P (lambda - Omega^2) / D.
                pa_(j, h) = -P_(j, h) * cw / D;
                pb_(j, h) = P_(j, h) * det / D;
            }
        }
    // Coupled terms grow (secular at exact undamped resonance): their bounds
    // hold over one forcing period.
    max_step_ = std::isinf(min_coupled_omega) ? std::numeric_limits<double>::infinity()
                                              : kTwoPi / min_coupled_omega;
    // Negative damping: a mode's energy E grows at most as e^{2 |c| s} (dE/dt = -c u'^2), so
    // over a step of kGrowthHorizon / |c| its sqrt(2E) grows at most by e^{kGrowthHorizon}.
    const double c_min = c_.size() > 0 ? c_.minCoeff() : 0.0;
    if (c_min < 0.0) {
        max_step_ = std::min(max_step_, kGrowthHorizon / -c_min);
        growth_ = std::exp(kGrowthHorizon);
    }
    // A rigid-body mode's terms grow as e^{-alpha s} with alpha < 0 (EPMC's
    // alpha - xi): their bound at the horizon's end needs a finite horizon.
    if (alpha_ < 0.0) max_step_ = std::min(max_step_, kGrowthHorizon / -alpha_);

    // The stiff tail: modes far above the motion's own rates (the lowest
    // flexible mode, the forcing), whose free oscillation the split bound
    // (segment_solver.h) may take by its amplitude; eval() chooses per
    // function how many of the fastest. Rigid modes and modes in a coupled
    // (resonant) pair never are. A configuration without such a tail is
    // searched on the curvature bound alone, at the same instants as the
    // programs (which do not split yet).
    double omega_slow = 0.0;
    for (int h = 0; h < nh_; ++h) omega_slow = std::max(omega_slow, t_.h_omega(h));
    double omega_first = std::numeric_limits<double>::infinity();
    for (int j = 0; j < nf_; ++j)
        if (regime_[j] != Regime::rigid) omega_first = std::min(omega_first, omega_(j));
    if (std::isfinite(omega_first)) omega_slow = std::max(omega_slow, omega_first);
    fast_.assign(static_cast<std::size_t>(nf_), 0);
    for (int j = 0; j < nf_; ++j) {
        bool coupled = false;
        for (int h = 0; h < nh_; ++h) coupled = coupled || coupled_(j, h);
        fast_[j] = regime_[j] != Regime::rigid && !coupled && omega_(j) > kStiffFrom * omega_slow;
        any_fast_ = any_fast_ || fast_[j];
    }
    by_omega_.resize(static_cast<std::size_t>(nf_));
    for (int j = 0; j < nf_; ++j) by_omega_[static_cast<std::size_t>(j)] = j;
    std::stable_sort(by_omega_.begin(), by_omega_.end(), [&](int i, int j) { return omega_(i) < omega_(j); });

    switch_rows(model);
    absW_ = W_.cwiseAbs();
    absZ_ = Z_.cwiseAbs();
    // Standard particular parts of harmonic h add up in g_f to ONE sinusoid
    // A cos + B sin; its second derivative has amplitude Omega^2 sqrt(A^2 + B^2).
    bound_sin_ = Eigen::VectorXd::Zero(ns);
    for (int f = 0; f < ns; ++f)
        for (int h = 0; h < nh_; ++h) {
            const double W = t_.h_omega(h);
            double A = 0.0, B = D_(f, h);
            for (int j = 0; j < nf_; ++j) {
                if (coupled_(j, h)) continue;
                A += W_(f, j) * pa_(j, h) + Z_(f, j) * W * pb_(j, h);
                B += W_(f, j) * pb_(j, h) - Z_(f, j) * W * pa_(j, h);
            }
            bound_sin_(f) += W * W * std::hypot(A, B);
        }

    // setup / eval storage.
    x_fix_ = fseg_ = rider_offset_ = Eigen::VectorXd::Zero(n_);
    slider_ = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(model.jenkins.size()));
    theta_ = Eigen::VectorXd::Zero(nh_);
    e_theta_ = Eigen::VectorXcd::Zero(nh_);
    force_ = Eigen::VectorXd::Zero(nf_);
    p_ = q0_ = qd0_ = u0_ = ud0_ = Eigen::VectorXd::Zero(nf_);
    rho_ = Eigen::VectorXd::Zero(ns);
    sn_ = cs_ = Eigen::VectorXd::Zero(nh_);
    e_omega_tau_ = Eigen::VectorXcd::Zero(nh_);
    q_ = qd_ = qdd_ = qmag_ = qdmag_ = b2_ = b3_ = Eigen::VectorXd::Zero(nf_);
    fu_ = fud_ = fudd_ = famp_ = fdamp_ = below_ = Eigen::VectorXd::Zero(nf_);
    xmag_ = vmag_ = Eigen::VectorXd::Zero(n_);
    lifetimes_.reserve(2 * static_cast<std::size_t>(nf_));  // resolving_rate: two terms per mode at most
}

void GenericSolver::setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) {
    lifetimes_.invalidate();
    for (int i = 0; i < n_; ++i) x_fix_(i) = x0[i];
    segment_force(t_, cfg_, x0, fseg_, slider_);
    release_force(t_, fseg_, sgn, frel_);
    for (int h = 0; h < nh_; ++h) {
        theta_(h) = reduced_phase(t_.h_omega(h), t0, t0_lo, t_.h_phase(h));
        e_theta_(h) = cplx(std::cos(theta_(h)), std::sin(theta_(h)));
    }
    // Constant force on the free masses (paper Eq. 7-9): loads and preloads,
    // the stiffness coupling to the stuck masses, kinetic friction.
    for (int r = 0; r < nf_; ++r) {
        force_(r) = free_mass_force(t_, fseg_, modal_.stuck, modal_.free[r], x0, sgn);
    }
    // A mass stuck to its partner adds its forces to the partner's coordinate;
    // its offset x_q - x_partner is a constant of the segment: x = T q + d,
    // f_F = T^T (f - K d). A sliding pair's friction pushes the partner back.
    for (int q : modal_.riders) {
        const double offset = x0[q] - x0[carrier_[static_cast<std::size_t>(q)]];
        rider_offset_(q) = offset;
        double f = fseg_(q);
        for (int s : modal_.stuck) f -= t_.K(q, s) * x0[s];
        force_(coord_[static_cast<std::size_t>(q)]) += f;
    }
    for (int q : modal_.riders)
        for (int i = 0; i < n_; ++i)
            if (coord_[static_cast<std::size_t>(i)] >= 0)
                force_(coord_[static_cast<std::size_t>(i)]) -= t_.K(i, q) * rider_offset_(q);
    for (int i = 0; i < n_; ++i) {
        const int p = t_.partner[static_cast<std::size_t>(i)];
        if (p != kGround && t_.friction[static_cast<std::size_t>(i)] && sgn[i] != 0 &&
            coord_[static_cast<std::size_t>(p)] >= 0)
            force_(coord_[static_cast<std::size_t>(p)]) += t_.mu_k(i) * t_.normal(i) * static_cast<double>(sgn[i]);
    }
    // Modal initial conditions q0 = Phi^T M_F x0 (and qd0 from v0), refined
    // by one step against the residual x0 - Phi q0 (in long double). Without
    // it the round trip x0 -> q0 -> Phi q0 is the fixed matrix Phi Phi^T M_F
    // = I + E, E ~ eps (Phi is M-orthonormal only to rounding), applied at
    // every segment start of the configuration: a bias, not noise. Measured
    // (tests/test_extremes.cpp, EnergySmall): an undamped 2-DOF contact
    // oscillator gained 1.0e-16 .. 1.5e-16 of its energy per switch,
    // linearly, all of it in the open configuration whose second mode had
    // phi^T M phi - 1 = 1.5e-16.
    for (int j = 0; j < nf_; ++j) {
        double q0 = 0.0, qd0 = 0.0;
        for (int r = 0; r < nf_; ++r) {
            q0 += phi_t_m_(j, r) * x0[modal_.free[r]];
            qd0 += phi_t_m_(j, r) * v0[modal_.free[r]];
        }
        q0_(j) = q0;
        qd0_(j) = qd0;
    }
    for (int r = 0; r < nf_; ++r) {  // residuals, in the eval scratch b2_, b3_
        long double rx = x0[modal_.free[r]], rv = v0[modal_.free[r]];
        for (int j = 0; j < nf_; ++j) {
            rx -= static_cast<long double>(phi_(r, j)) * q0_(j);
            rv -= static_cast<long double>(phi_(r, j)) * qd0_(j);
        }
        b2_(r) = static_cast<double>(rx);
        b3_(r) = static_cast<double>(rv);
    }
    for (int j = 0; j < nf_; ++j) {
        double dq = 0.0, dqd = 0.0;
        for (int r = 0; r < nf_; ++r) {
            dq += phi_t_m_(j, r) * b2_(r);
            dqd += phi_t_m_(j, r) * b3_(r);
        }
        q0_(j) += dq;
        qd0_(j) += dqd;
    }
    for (int j = 0; j < nf_; ++j) {
        double p = 0.0;
        for (int r = 0; r < nf_; ++r) p += phi_(r, j) * force_(r);
        p_(j) = p;
        const double q0 = q0_(j), qd0 = qd0_(j);
        // Initial value of the standard particular parts.
        double qp0 = 0.0, qpd0 = 0.0;
        for (int h = 0; h < nh_; ++h) {
            if (coupled_(j, h)) continue;  // zero-state: y(0) = y'(0) = 0
            const double st = std::sin(theta_(h)), ct = std::cos(theta_(h));
            qp0 += pa_(j, h) * ct + pb_(j, h) * st;
            qpd0 += t_.h_omega(h) * (-pa_(j, h) * st + pb_(j, h) * ct);
        }
        // Rigid: u0 is the constant base q0 - q_p(0); elastic: the homogeneous
        // part starts from the state minus the static (Eq. 10) and particular parts.
        u0_(j) = regime_[j] == Regime::rigid ? q0 - qp0 : q0 - p / lambda_(j) - qp0;
        ud0_(j) = qd0 - qpd0;
    }
    // Rigid-mode part of g_f'': sum_j (W_fj - c Z_fj)(p_j - c u0'_j) e^{-c tau}, c = alpha.
    for (int f = 0; f < rho_.size(); ++f) {
        double s = 0.0;
        for (int j = 0; j < nf_; ++j)
            if (regime_[j] == Regime::rigid)
                s += (W_(f, j) - c_(j) * Z_(f, j)) * (p_(j) - c_(j) * ud0_(j));
        rho_(f) = s;
    }
}

// The split bound of function f (segment_solver.h): the free oscillation
// r = W u + Z u' of the fastest modes apart, bounded by its amplitude
// (|u| <= sqrt(2E/lambda), |u'| <= sqrt(2E)), the rest by its curvature. How
// many of the fastest modes is chosen per function and instant: the cut that
// gives the longest safe step on g's present side (the engine takes its own
// step from whichever is written, so the choice never weakens the bound).
// The slow curvature at each cut is summed forwards (the modes below it in
// order, the ineligible ones above it), never by subtraction from B.
void GenericSolver::split_bound(int f, double g, double dg, double rigid_decay, const SegmentEval& out) const {
    const auto F = static_cast<Eigen::Index>(f);
    const double side = g >= 0.0 ? 1.0 : -1.0;
    double base = bound_sin_(F) + std::abs(rho_(F)) * rigid_decay;
    for (int k = 0; k < nf_; ++k) {  // below[k]: the curvature bound of the modes below the k-th by omega
        below_(k) = base;
        const int j = by_omega_[static_cast<std::size_t>(k)];
        base += absW_(F, j) * b2_(j) + absZ_(F, j) * b3_(j);
    }
    double r = 0.0, rd = 0.0, amp = 0.0, kept = 0.0;  // kept: ineligible modes above the cut
    double best = -1.0;
    out.slow[f] = g, out.slow_dg[f] = dg, out.fast[f] = 0.0, out.slow_bound[f] = base;
    for (int k = nf_ - 1; k >= 0; --k) {
        const int j = by_omega_[static_cast<std::size_t>(k)];
        const double aw = absW_(F, j), az = absZ_(F, j);
        if (!fast_[j]) {
            kept += aw * b2_(j) + az * b3_(j);
            continue;
        }
        if (aw == 0.0 && az == 0.0) continue;  // f does not see it
        const double w = W_(F, j), z = Z_(F, j);
        r += w * fu_(j) + z * fud_(j);
        rd += w * fud_(j) + z * fudd_(j);
        amp += aw * famp_(j) + az * fdamp_(j);
        const double h = side * (g - r) - amp;
        if (!(h > 0.0)) continue;
        const double Bs = below_(k) + kept;
        const double step = safe_step(h, side * (dg - rd), Bs);
        if (step > best) {
            best = step;
            out.slow[f] = g - r, out.slow_dg[f] = dg - rd, out.fast[f] = amp, out.slow_bound[f] = Bs;
        }
    }
}

void GenericSolver::eval(double tau, const SegmentEval& out) const {
    // Harmonics at tau, and the bound horizon of coupled terms.
    for (int h = 0; h < nh_; ++h) {
        const double ph = t_.h_omega(h) * tau + theta_(h);
        sn_(h) = std::sin(ph);
        cs_(h) = std::cos(ph);
        if (h_has_coupled_[h]) {
            const double wt = t_.h_omega(h) * tau;
            e_omega_tau_(h) = cplx(std::cos(wt), std::sin(wt));
        }
    }
    const double s_end = tau + max_step_;  // only used when max_step_ is finite

    for (int j = 0; j < nf_; ++j) {
        const double lam = lambda_(j), c = c_(j), sig = sigma_(j), w = omega_(j);
        const double p = p_(j), u0 = u0_(j), ud0 = ud0_(j);
        double q, qd, qdd, mag, dmag, b2 = 0.0, b3 = 0.0;
        double ed = 0.0, cd = 0.0, sd = 0.0;  // e^{-sigma tau}, cos, sin(omega_d tau)
        if (regime_[j] == Regime::rigid) {
            // q = u0 + u0' tau phi1(-c tau) + p tau^2 phi2(-c tau): exact for every c >= 0
            // (c = 0: q0 + qd0 tau + p tau^2/2), no p/c drift cancellation as c -> 0.
            const double x = -c * tau, e = std::exp(x), f1 = phi1(x), f2 = hsnc_phi2(x);
            q = u0 + ud0 * tau * f1 + p * tau * tau * f2;
            qd = ud0 * e + p * tau * f1;
            qdd = (p - c * ud0) * e;
            mag = std::abs(u0) + std::abs(ud0 * tau * f1) + std::abs(p * tau * tau * f2);
            dmag = std::abs(ud0 * e) + std::abs(p * tau * f1);
        } else {
            // u = EC u0 + ES (u0' + sigma u0), u' = EC u0' - ES (lambda u0 + sigma u0'),
            // EC = e^{-sigma tau} cos(omega_d tau), ES = e^{-sigma tau} sin(omega_d tau)/omega_d
            // (cosh, sinh/gamma when overdamped; 1, tau when critical).
            double EC, ES;
            if (regime_[j] == Regime::underdamped) {
                ed = std::exp(-sig * tau);
                cd = std::cos(omega_d_(j) * tau);
                sd = std::sin(omega_d_(j) * tau);
                EC = ed * cd;
                ES = ed * (sd / omega_d_(j));
            } else if (regime_[j] == Regime::overdamped) {
                // e^{-sigma tau} cosh(gamma tau) = e^{r1 tau} (1 + e^{-2 gamma tau})/2,
                // e^{-sigma tau} sinh(gamma tau)/gamma = e^{r1 tau} tau phi1(-2 gamma tau).
                const double e1 = std::exp(r1_(j) * tau);
                const double x = -2.0 * gamma_(j) * tau;
                EC = e1 * (0.5 * std::expm1(x) + 1.0);
                ES = e1 * tau * phi1(x);
            } else {
                ed = std::exp(-sig * tau);
                EC = ed;
                ES = ed * tau;
            }
            const double v0 = ud0 + sig * u0, a0 = lam * u0 + sig * ud0;
            const double u = EC * u0 + ES * v0;
            const double ud = EC * ud0 - ES * a0;
            q = p / lam + u;
            qd = ud;
            qdd = -c * ud - lam * u;
            mag = std::abs(p / lam) + std::abs(EC * u0) + std::abs(ES * v0);
            dmag = std::abs(EC * ud0) + std::abs(ES * a0);
            // Homogeneous bound: E = (u'^2 + lambda u^2)/2 never grows (dE/dt = -c u'^2; with
            // c < 0, by at most growth_ over max_step_), |u''| <= (|c| + omega) sqrt(2E),
            // |u'''| <= (|c| (|c| + omega) + omega^2) sqrt(2E).
            const double e2 = std::sqrt(ud * ud + lam * u * u) * growth_, ac = std::abs(c);
            b2 = (ac + w) * e2;
            b3 = (ac * (ac + w) + lam) * e2;
            if (fast_[j]) {  // for the split bound: |u| <= sqrt(2E/lambda), |u'| <= sqrt(2E) over the horizon
                fu_(j) = u;
                fud_(j) = ud;
                fudd_(j) = -c * ud - lam * u;
                famp_(j) = e2 / w;
                fdamp_(j) = e2;
            }
            if (regime_[j] == Regime::overdamped && gamma_(j) >= 0.5 * sig) {
                // Well separated real roots: u = U1 e^{r1 s} + U2 e^{r2 s}, each term decays.
                const double r1 = r1_(j), r2 = r2_(j), den = -2.0 * gamma_(j);
                const double U1 = std::abs((r2 * u - ud) / den), U2 = std::abs((ud - r1 * u) / den);
                b2 = std::min(b2, U1 * r1 * r1 + U2 * r2 * r2);
                b3 = std::min(b3, U1 * std::abs(r1 * r1 * r1) + U2 * std::abs(r2 * r2 * r2));
            }
        }
        for (int h = 0; h < nh_; ++h) {
            const double W = t_.h_omega(h);
            if (!coupled_(j, h)) {
                const double qp = pa_(j, h) * cs_(h) + pb_(j, h) * sn_(h);
                const double qpd = W * (-pa_(j, h) * sn_(h) + pb_(j, h) * cs_(h));
                q += qp;
                qd += qpd;
                qdd -= W * W * qp;
                mag += std::abs(qp);
                dmag += std::abs(qpd);
                continue;
            }
            // Transient-coupled zero-state response (see the constructor).
            const double Pj = P_(j, h), wd = omega_d_(j);
            const cplx rp(-sig, wd), rm(-sig, -wd);
            const cplx erp(ed * cd, ed * sd), erm(ed * cd, -ed * sd);
            const cplx eW = e_omega_tau_(h);
            const cplx zp = zp_(j, h), zm = zm_(j, h);
            const cplx wz = zp * tau;
            // E+ = e^{r+ tau} tau phi1(z+ tau) while |z+ tau| is small (no cancellation,
            // no overflow), else the plain divided difference.
            const cplx Ep = std::abs(wz) < 1.0 ? erp * tau * (wz == cplx(0.0) ? cplx(1.0) : expm1c(wz) / wz)
                                               : (eW - erp) / zp;
            const cplx Em = (eW - erm) / zm;
            const cplx k = Pj * e_theta_(h) * cplx(0.0, -0.5 / wd);  // P e^{i theta}/(2 i omega_d)
            const double y = (k * (Ep - Em)).imag();
            const double yd = (k * (rp * Ep - rm * Em)).imag();
            const double ydd = Pj * sn_(h) - c * yd - lam * y;
            q += y;
            qd += yd;
            qdd += ydd;
            // The magnitude of the terms, not of their sum: near tau = 0 (and at any
            // tau for the secular part) E+ and E- nearly cancel, and y is known to
            // eps |k| (|E+| + |E-|), not to eps |y| (a contact at rest under
            // resonant forcing: y ~ tau^3, its terms ~ tau).
            const double km = std::abs(k);
            mag += km * (std::abs(Ep) + std::abs(Em));
            dmag += km * (std::abs(rp * Ep) + std::abs(rm * Em));
            // |E+-(s)| <= min(s phi1(-sigma s), 2/|z+-|) for s <= s_end, so
            // |y| <= |P| (e+ + e-)/(2 omega_d), |y'| <= omega times that, and
            // y'' = P sin - c y' - lambda y, y''' = P Omega cos - c y'' - lambda y'.
            const double grow = s_end * phi1(-sig * s_end);
            const double ep = std::min(grow, 2.0 / std::abs(zp)), em = std::min(grow, 2.0 / std::abs(zm));
            const double Y0 = std::abs(Pj) * (ep + em) / (2.0 * wd), Y1 = w * Y0;
            const double Y2 = std::abs(Pj) + std::abs(c) * Y1 + lam * Y0;
            const double Y3 = std::abs(Pj) * W + std::abs(c) * Y2 + lam * Y1;
            b2 += Y2;
            b3 += Y3;
        }
        q_(j) = q;
        qd_(j) = qd;
        qdd_(j) = qdd;
        qmag_(j) = mag;
        qdmag_(j) = dmag;
        b2_(j) = b2;
        b3_(j) = b3;
    }

    // Physical state: x_F = Phi q (likewise v, a); stuck masses fixed.
    write_at_rest(x_fix_, out, xmag_, vmag_);
    for (int r = 0; r < nf_; ++r) {
        double x = 0.0, v = 0.0, a = 0.0, xm = 0.0, vm = 0.0;
        for (int j = 0; j < nf_; ++j) {
            const double ph = phi_(r, j);
            x += ph * q_(j);
            v += ph * qd_(j);
            a += ph * qdd_(j);
            xm += std::abs(ph) * qmag_(j);
            vm += std::abs(ph) * qdmag_(j);
        }
        const int i = modal_.free[r];
        out.x[i] = x;
        out.v[i] = v;
        out.a[i] = a;
        xmag_(i) = xm;
        vmag_(i) = vm;
    }
    for (int q : modal_.riders) {  // moving with the partner, at the segment's offset
        const int p = carrier_[static_cast<std::size_t>(q)];
        out.x[q] = out.x[p] + rider_offset_(q);
        out.v[q] = out.v[p];
        out.a[q] = out.a[p];
        xmag_(q) = xmag_(p) + std::abs(rider_offset_(q));
        vmag_(q) = vmag_(p);
    }

    write_sliders(t_, cfg_, slider_, out);

    // Switch functions (segment.h), their rates, scales (sum of |terms|) and bounds.
    // (e^{-alpha s} is largest at the horizon's end when alpha < 0.)
    const double rigid_decay = std::exp(-alpha_ * (alpha_ < 0.0 ? tau + max_step_ : tau));
    for (std::size_t f = 0; f < switches_.size(); ++f) {
        const SwitchFunction& sf = switches_[f];
        double g, dg, scale;
        switch_value(sf, t_, t_.coupled() ? frel_ : fseg_, out, xmag_, vmag_, sn_, cs_, g, dg, scale);
        // |g''(s)| for s in [tau, tau + max_step]: standard sinusoids, rigid modes
        // (exact, decaying as e^{-alpha s}), homogeneous and coupled modal bounds.
        const double rho = std::abs(rho_(static_cast<Eigen::Index>(f)));  // 0 without rigid-body modes
        double B = bound_sin_(static_cast<Eigen::Index>(f)) + (rho == 0.0 ? 0.0 : rho * rigid_decay);
        const bool split = out.fast && any_fast_;
        double B_fast = 0.0;  // the stiff tail's share of B
        for (int j = 0; j < nf_; ++j) {
            const double term =
                absW_(static_cast<Eigen::Index>(f), j) * b2_(j) + absZ_(static_cast<Eigen::Index>(f), j) * b3_(j);
            B += term;
            if (split && fast_[j]) B_fast += term;
        }
        out.g[f] = g;
        out.dg[f] = dg;
        out.scale[f] = scale;
        out.bound[f] = B;
        if (!split) continue;
        if (B_fast > kSplitWorth * B) {
            split_bound(f, g, dg, rigid_decay, out);
        } else {  // no cut can lengthen the step by more than about kSplitWorth / 2: the whole bound
            out.slow[f] = g, out.slow_dg[f] = dg, out.fast[f] = 0.0, out.slow_bound[f] = B;
        }
    }
}

// Each mode's homogeneous motion is a sum of terms A e^{-s tau} times a
// bounded oscillation at a rate r: underdamped, A = hypot(u0, (u0' + sigma
// u0)/omega_d), s = sigma, r = omega; critically and overdamped, the terms of
// the two real roots (near-critical ones bounded together, tau e^{r1 tau} <=
// 2/(e |r1|) e^{r1 tau/2}); a damped rigid mode's e^{-c tau}. The forcing's
// particular parts never decay and count at their frequencies whatever their
// size (so does a mode in the transient-coupled form, near its harmonic).
// Dof r's size S_r bounds its motion (its start position, its static offset
// and every term's |phi_rj| A); the term counts in dof r until |phi_rj| A
// e^{-s tau} <= tol S_r, so a dof of small motion (or in other units: a
// rotation beside a deflection) is resolved to tol of its own size. The
// instant each term stops counting is worked out once per segment.
void GenericSolver::term_lifetimes(double tol) const {
    double forced = 0.0;
    for (int h = 0; h < nh_; ++h) forced = std::max(forced, t_.h_omega(h));
    lifetimes_.start(forced, tol);
    struct Term {
        double size, decay, rate;
    };
    auto homogeneous = [&](int j, auto&& put) {
        const double u0 = u0_(j), ud0 = ud0_(j), sig = sigma_(j);
        switch (regime_[static_cast<std::size_t>(j)]) {
            case Regime::rigid:
                // q = u0 + u0' tau phi1(-c tau) + p tau^2 phi2(-c tau): e^{-c tau} (u0'/c - p/c^2) besides a
                // polynomial.
                if (c_(j) > 0) put(Term{std::abs(ud0 / c_(j) - p_(j) / (c_(j) * c_(j))), c_(j), c_(j)});
                break;
            case Regime::underdamped:
                put(Term{std::hypot(u0, (ud0 + sig * u0) / omega_d_(j)), sig, omega_(j)});
                break;
            case Regime::overdamped:
                if (gamma_(j) >= 0.5 * sig) {  // u = U1 e^{r1 tau} + U2 e^{r2 tau}
                    const double r1 = r1_(j), r2 = r2_(j), den = -2.0 * gamma_(j);
                    put(Term{std::abs((r2 * u0 - ud0) / den), -r1, -r1});
                    put(Term{std::abs((ud0 - r1 * u0) / den), -r2, -r2});
                    break;
                }
                [[fallthrough]];
            case Regime::critical: {  // |u| <= (|u0| + |u0' + sigma u0| tau) e^{-(sigma - gamma) tau}
                const double slow = sig - gamma_(j);
                put(Term{std::abs(u0) + 2.0 * std::abs(ud0 + sig * u0) / (std::exp(1.0) * slow), 0.5 * slow,
                         sig + gamma_(j)});
                break;
            }
        }
    };
    // Each mode's size (m) and each dof's (xmag_ as scratch).
    for (int j = 0; j < nf_; ++j) {
        double m = regime_[static_cast<std::size_t>(j)] == Regime::rigid ? 0.0 : std::abs(p_(j) / lambda_(j));
        homogeneous(j, [&](const Term& term) { m += term.size; });
        for (int h = 0; h < nh_; ++h) {
            if (!coupled_(j, h))
                m += std::hypot(pa_(j, h), pb_(j, h));
            else if (P_(j, h) != 0)
                lifetimes_.raise_forced(omega_(j));
        }
        qmag_(j) = m;
    }
    for (int r = 0; r < nf_; ++r) {
        double size = std::abs(x_fix_(modal_.free[static_cast<std::size_t>(r)]));
        for (int j = 0; j < nf_; ++j) size += std::abs(phi_(r, j)) * qmag_(j);
        xmag_(r) = size;
    }
    for (int j = 0; j < nf_; ++j) {
        double share = 0.0;  // max_r |phi_rj| / S_r
        for (int r = 0; r < nf_; ++r)
            if (xmag_(r) > 0) share = std::max(share, std::abs(phi_(r, j)) / xmag_(r));
        homogeneous(j, [&](const Term& term) { lifetimes_.add(term.rate, term.decay, share * term.size); });
    }
}

double GenericSolver::resolving_rate(double tau, double tol) const {
    if (!lifetimes_.valid(tol)) term_lifetimes(tol);
    return lifetimes_.rate_at(tau);
}

std::size_t GenericSolver::memory_bytes() const {
    // Dense storage dominates: n x n (K, C), nf x nf (Phi twice, modal Phi),
    // switches x nf (W, Z and their absolute values), mode x harmonic tables.
    const auto d = [](const auto& m) { return static_cast<std::size_t>(m.size()) * sizeof(typename std::decay_t<decltype(m)>::Scalar); };
    std::size_t b = sizeof(*this);
    b += d(t_.K) + d(t_.C) + d(phi_) + d(phi_t_m_) + d(modal_.phi) + d(W_) + d(Z_) + d(absW_) + d(absZ_) + d(D_);
    b += d(P_) + d(pa_) + d(pb_) + d(zp_) + d(zm_) + d(t_.h_amp) + d(coupled_);
    b += 24 * static_cast<std::size_t>(n_ + nf_ + static_cast<int>(switches_.size()) + nh_) * sizeof(double);
    b += static_cast<std::size_t>(nf_) * (6 * sizeof(double) + sizeof(int) + sizeof(char));  // the split bound's
    return b;
}

}  // namespace hsnc
