// hsnc -- what the two Eigen-based solvers (GenericSolver, StateSpaceSolver)
// share: the physical terms of a configuration, the value, rate and term
// size of one switch function from the physical state x, v, a, and e^w - 1. The kernels
// and the interpreter compute the same from their programs, independently.
//
// gap          G = x[a] - x[b] - gap, G' = v[a] - v[b]                 (assembly.h gap())
// velocity     v_i, v_i' = a_i
// release_pos  A_i - mu_s N_i,  release_neg -A_i - mu_s N_i, with
//              A_i = -(K x)_i - (C v)_i + f_i + F_i(t), A_i' = -(K v)_i - (C a)_i + F_i'(t)
//              over the full K(cfg), C(cfg) (a stuck row sees every mass), f the
//              segment's constant force (f_const plus the stuck sliders' preload)
// slip_pos     k e - F_s, slip_neg -k e - F_s, e = x[a] - x[b] - s (s = x[n + j]), e' = w
// slip_velocity w = v[a] - v[b], w' = a[a] - a[b]
// scale is the sum of the terms' magnitudes (segment_solver.h).
#pragma once

#include <cmath>
#include <complex>
#include <vector>

#include <Eigen/Core>

#include "assembly.h"
#include "configuration.h"
#include "elements/contact.h"
#include "elements/friction.h"
#include "elements/jenkins.h"
#include "elements/motion.h"
#include "switch_derivative.h"
#include "model.h"
#include "segment_solver.h"
#include "switch_function.h"

namespace hsnc {

/// The physical terms of one configuration both Eigen-based solvers start
/// from (full n x n, stuck masses not removed; assembly.h): per mass m, N,
/// mu_k, mu_s and whether it has friction; K(cfg), C(cfg); the constant force
/// (loads, preloads, and the harmonics of omega = 0, F sin(phase)); the
/// contacts; the harmonics of omega != 0 with omega < 0 folded to |omega|
/// and phase pi - phase.
struct ConfigurationTerms {
    Eigen::VectorXd mass, normal, mu_k, mu_s;
    std::vector<char> friction;
    std::vector<int> partner;  ///< per mass: what its friction acts against (elements/friction.h FrictionSlot::partner)
    Eigen::MatrixXd K, C;
    Eigen::VectorXd f_const;
    std::vector<Contact> contacts;
    Eigen::VectorXd h_omega, h_phase;
    Eigen::MatrixXd h_amp;  ///< n x nh
    std::vector<Jenkins> jenkins;
    /// Model::coupled_friction(): row release_row[i] of `release` is P_i of a
    /// stuck dof i (held_mass.h), D_i = P_i . (A + kinetic friction); empty otherwise.
    Eigen::MatrixXd release;
    std::vector<int> release_row;
    bool coupled() const { return release_row.size() > 0; }
};

ConfigurationTerms configuration_terms(const Model& model, const Configuration& cfg);

/// The segment's constant force: f = f_const plus the preload k_j s_j of
/// every Jenkins element stuck in cfg along its w, s_j = x0[n + j] (kept in slider).
inline void segment_force(const ConfigurationTerms& in, const Configuration& cfg, const double* x0, Eigen::VectorXd& f,
                          Eigen::VectorXd& slider) {
    f = in.f_const;
    const std::size_t n = static_cast<std::size_t>(in.mass.size());
    for (std::size_t j = 0; j < cfg.slip.size(); ++j) {
        if (cfg.slip[j] != 0) continue;
        const Eigen::Index jj = static_cast<Eigen::Index>(j);
        slider(jj) = x0[n + j];
        const Jenkins& e = in.jenkins[j];
        const double p = e.k * slider(jj);
        for_each_term(e.direction(), [&](int i, double w) { f(i) += w * p; });
    }
}

/// The forces a held force D_i = P_i . f sums (held_mass.h;
/// Model::coupled_friction()): the segment's constant force f plus the
/// kinetic friction of every sliding dof and its reaction on a partner; f
/// itself otherwise (the release functions read A_i, no friction).
inline const Eigen::VectorXd& release_force(const ConfigurationTerms& in, const Eigen::VectorXd& f,
                                            const signed char* sgn, Eigen::VectorXd& scratch) {
    if (!in.coupled()) return f;
    scratch = f;
    for (Eigen::Index i = 0; i < f.size(); ++i)
        if (in.friction[static_cast<std::size_t>(i)]) scratch(i) -= in.mu_k(i) * in.normal(i) * static_cast<double>(sgn[i]);
    for (Eigen::Index i = 0; i < f.size(); ++i)  // a sliding rider's reaction on its partner
        if (const int p = in.partner[static_cast<std::size_t>(i)];
            in.friction[static_cast<std::size_t>(i)] && p != kGround)
            scratch(p) += in.mu_k(i) * in.normal(i) * static_cast<double>(sgn[i]);
    return scratch;
}

/// The constant force on free mass i in a segment (paper Eq. 7-9): f(i)
/// (segment_force: loads, preloads, the stuck sliders'), the stiffness
/// coupling -K_iS x_S to the masses held in `stuck`, and kinetic friction
/// -mu_k N sgn_i. The Eigen solvers' one sum, in one order.
inline double free_mass_force(const ConfigurationTerms& in, const Eigen::VectorXd& f, const std::vector<int>& stuck,
                              int i, const double* x0, const signed char* sgn) {
    double fi = f(i);
    for (int s : stuck) fi -= in.K(i, s) * x0[s];
    if (in.friction[static_cast<std::size_t>(i)]) fi -= in.mu_k(i) * in.normal(i) * static_cast<double>(sgn[i]);
    return fi;
}

/// out.x[n + j]: the slider of every Jenkins element, fixed while stuck,
/// u - slip*F_s/k while slipping (after the masses' x are written).
inline void write_sliders(const ConfigurationTerms& in, const Configuration& cfg, const Eigen::VectorXd& slider,
                          const SegmentEval& out) {
    const std::size_t n = static_cast<std::size_t>(in.mass.size());
    for (std::size_t j = 0; j < cfg.slip.size(); ++j) {
        const Eigen::Index jj = static_cast<Eigen::Index>(j);
        if (cfg.slip[j] == 0) {
            out.x[n + j] = slider(jj);
            continue;
        }
        const Jenkins& e = in.jenkins[j];
        const double* rows[] = {out.x};
        out.x[n + j] = along(e.direction(), double_motion(rows), 0) - jenkins::held_stretch(cfg.slip[j], e.k, e.slip_force);
    }
}

/// Every mass at its segment-start position, at rest (then the solver writes
/// the masses that move): x = x_fix, v = a = 0, and their magnitudes.
inline void write_at_rest(const Eigen::VectorXd& x_fix, const SegmentEval& out, Eigen::VectorXd& xmag,
                          Eigen::VectorXd& vmag) {
    for (Eigen::Index i = 0; i < x_fix.size(); ++i) {
        out.x[i] = x_fix(i);
        out.v[i] = 0.0;
        out.a[i] = 0.0;
        xmag(i) = std::abs(x_fix(i));
        vmag(i) = 0.0;
    }
}

/// e^w - 1 for complex w = x + iy without cancellation:
/// Re = expm1(x) cos y - 2 sin^2(y/2), Im = e^x sin y.
inline std::complex<double> expm1c(std::complex<double> w) {
    const double x = w.real(), y = w.imag();
    const double s = std::sin(0.5 * y);
    return {std::expm1(x) * std::cos(y) - 2.0 * s * s, std::exp(x) * std::sin(y)};
}

/// The elements' parameters as the switch functions read them
/// (model/switch_derivative.h), from a configuration's terms and the
/// state x (masses, then sliders).
struct TermsView {
    const ConfigurationTerms& in;
    const double* x;
    struct ContactView {
        Direction d;
        double gap;
    };
    struct JenkinsView {
        Direction d;
        double k, slip_force, s;
    };
    ContactView contact(int e) const {
        const Contact& c = in.contacts[static_cast<std::size_t>(e)];
        return {c.direction(), c.gap};
    }
    JenkinsView jenkins(int e) const {
        const Jenkins& j = in.jenkins[static_cast<std::size_t>(e)];
        return {j.direction(), j.k, j.slip_force, x[static_cast<std::size_t>(in.mass.size() + e)]};
    }
    Direction friction(int e) const { return {e, in.partner[static_cast<std::size_t>(e)]}; }
};

/// g, g' and the size of g's terms; xmag, vmag the magnitudes of x and v,
/// sn, cs the sine and cosine of every harmonic's phase at the instant.
/// f: the segment's constant force (f_const plus add_slider_preload).
inline void switch_value(const SwitchFunction& sf, const ConfigurationTerms& in, const Eigen::VectorXd& f,
                         const SegmentEval& out, const Eigen::VectorXd& xmag, const Eigen::VectorXd& vmag,
                         const Eigen::VectorXd& sn, const Eigen::VectorXd& cs, double& g, double& dg, double& scale) {
    // The motion: x, v, a and the magnitudes of x and v (element files, model/elements/).
    const double* rows[] = {out.x, out.v, out.a};
    const double* mags[] = {xmag.data(), vmag.data(), nullptr};
    const auto m = double_motion(rows, &mags);
    const int e = sf.element;
    if (!is_release(sf.kind)) {
        const TermsView p{in, out.x};
        g = switch_derivative(p, sf, m, 0);
        dg = switch_derivative(p, sf, m, 1);
        scale = switch_magnitude(p, sf, m, 0);
        return;
    }
    // A_i, A_i' and the size of A_i's terms.
    auto force = [&](int i, double& A, double& dA, double& size) {
        A = f(i), dA = 0.0, size = std::abs(f(i));
        for (Eigen::Index k = 0; k < in.K.cols(); ++k) {
            A -= in.K(i, k) * out.x[k] + in.C(i, k) * out.v[k];
            dA -= in.K(i, k) * out.v[k] + in.C(i, k) * out.a[k];
            size += std::abs(in.K(i, k)) * xmag(k) + std::abs(in.C(i, k)) * vmag(k);
        }
        for (Eigen::Index h = 0; h < in.h_omega.size(); ++h) {
            A += in.h_amp(i, h) * sn(h);
            dA += in.h_amp(i, h) * in.h_omega(h) * cs(h);
            size += std::abs(in.h_amp(i, h) * sn(h));
        }
    };
    double A, dA, mag;
    if (in.coupled()) {  // D = P_e . (A + friction), f carrying the friction (release_force)
        A = dA = mag = 0.0;
        const Eigen::Index r = in.release_row[static_cast<std::size_t>(e)];
        for (Eigen::Index q = 0; q < in.release.cols(); ++q) {
            const double w = in.release(r, q);
            if (w == 0.0) continue;
            double Aq, dAq, mq;
            force(static_cast<int>(q), Aq, dAq, mq);
            A += w * Aq;
            dA += w * dAq;
            mag += std::abs(w) * mq;
        }
    } else {
        force(e, A, dA, mag);
        if (const int p = in.partner[static_cast<std::size_t>(e)]; p != kGround) {
            // Against a partner: D = (m_p A_e - m_e A_p)/(m_e + m_p) (assembly.h driving_force).
            double Ap, dAp, mp_mag;
            force(p, Ap, dAp, mp_mag);
            const double me = in.mass(e), mp = in.mass(p);
            A = against_partner(me, mp, A, Ap);
            dA = against_partner(me, mp, dA, dAp);
            mag = against_partner_magnitude(me, mp, mag, mp_mag);
        }
    }
    const int sigma = sf.kind == SwitchKind::release_pos ? 1 : -1;
    const double mu_n = in.mu_s(e) * in.normal(e);
    g = friction::release_value(sigma, A, mu_n, 0);
    dg = friction::release_value(sigma, dA, mu_n, 1);
    scale = friction::release_magnitude(mag, mu_n, 0);
}

}  // namespace hsnc
