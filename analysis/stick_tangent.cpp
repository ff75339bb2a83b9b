#include "stick_tangent.h"

#include <vector>

#include "assembly.h"
#include "held_mass.h"

namespace hsnc::analysis {
namespace {

// Rows and columns of the full state z = (x, v, s).
struct Layout {
    Eigen::Index n, nj;
    Eigen::Index x(int i) const { return i; }
    Eigen::Index v(int i) const { return n + i; }
    Eigen::Index s(std::size_t j) const { return 2 * n + static_cast<Eigen::Index>(j); }
    Eigen::Index size() const { return 2 * n + nj; }
};

Layout layout(const Model& model) {
    return {static_cast<Eigen::Index>(model.dof()), static_cast<Eigen::Index>(model.jenkins.size())};
}

// The body mass i moves as: itself, its carrier when stuck to a partner (a
// rider, up a chain: assembly.h carrier()), or none (-1) when held still.
int body_of(const Model& model, const Configuration& cfg, std::size_t i) {
    return carrier(model, cfg, i);
}

// d A_i / dz: -K_i. on x, -C_i. on v, +-k on the sliders of the stuck Jenkins elements at i.
Eigen::RowVectorXd force_gradient(const Model& model, const Configuration& cfg, const Eigen::MatrixXd& K,
                                  const Eigen::MatrixXd& C, int i) {
    const Layout L = layout(model);
    Eigen::RowVectorXd g = Eigen::RowVectorXd::Zero(L.size());
    g.segment(0, L.n) = -K.row(i);
    g.segment(L.n, L.n) = -C.row(i);
    for (std::size_t j = 0; j < model.jenkins.size(); ++j) {
        if (cfg.slip[j] != 0) continue;
        const Jenkins& e = model.jenkins[j];
        for_each_term(e.direction(), [&](int b, double w) {
            if (b == i) g(L.s(j)) += e.k * w;
        });
    }
    return g;
}

}  // namespace

Eigen::MatrixXd stick_generator(const Model& model, const Configuration& cfg) {
    const Layout L = layout(model);
    const Eigen::MatrixXd K = stiffness_matrix(model, cfg), C = damping_matrix(model, cfg);
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(L.size(), L.size());
    if (model.coupled_mass()) {  // a_F = M_FF^-1 f_F with the stuck dofs held (held_mass.h; a coupled M has no riders)
        Eigen::MatrixXd grad(L.n, L.size());
        for (Eigen::Index i = 0; i < L.n; ++i) grad.row(i) = force_gradient(model, cfg, K, C, static_cast<int>(i));
        const Eigen::MatrixXd inv = HeldMass(model, cfg.stuck).inverse();
        for (Eigen::Index i = 0; i < L.n; ++i) {
            if (cfg.stuck[static_cast<std::size_t>(i)]) continue;
            A(L.x(static_cast<int>(i)), L.v(static_cast<int>(i))) = 1.0;
            A.row(L.v(static_cast<int>(i))) = inv.row(i) * grad;
        }
    }
    // Each body's acceleration row: its members' force gradients over their summed mass.
    std::vector<Eigen::RowVectorXd> row(model.dof(), Eigen::RowVectorXd::Zero(L.size()));
    std::vector<double> mass(model.dof(), 0.0);
    for (std::size_t i = 0; i < model.dof() && !model.coupled_mass(); ++i) {
        const int b = body_of(model, cfg, i);
        if (b < 0) continue;
        row[static_cast<std::size_t>(b)] += force_gradient(model, cfg, K, C, static_cast<int>(i));
        mass[static_cast<std::size_t>(b)] += model.masses[i].m;
    }
    for (std::size_t i = 0; i < model.dof() && !model.coupled_mass(); ++i) {
        const int b = body_of(model, cfg, i);
        if (b < 0) continue;
        const int ii = static_cast<int>(i);
        A(L.x(ii), L.v(ii)) = 1.0;
        A.row(L.v(ii)) = row[static_cast<std::size_t>(b)] / mass[static_cast<std::size_t>(b)];
    }
    for (std::size_t j = 0; j < model.jenkins.size(); ++j) {
        if (cfg.slip[j] == 0) continue;  // stuck: s' = 0
        for_each_term(model.jenkins[j].direction(), [&](int b, double w) { A(L.s(j), L.v(b)) += w; });
    }
    return A;
}

Eigen::MatrixXd stick_projection(const Model& model, const Configuration& cfg) {
    const Layout L = layout(model);
    Eigen::MatrixXd P = Eigen::MatrixXd::Identity(L.size(), L.size());
    std::vector<double> mass(model.dof(), 0.0);
    for (std::size_t i = 0; i < model.dof(); ++i)
        if (const int b = body_of(model, cfg, i); b >= 0) mass[static_cast<std::size_t>(b)] += model.masses[i].m;
    for (std::size_t i = 0; i < model.dof(); ++i) {
        const int ii = static_cast<int>(i), b = body_of(model, cfg, i);
        if (b < 0) {
            P.row(L.v(ii)).setZero();
            continue;
        }
        bool pair = b != ii;  // a rider, or a partner with riders: the pair's momentum-weighted velocity
        for (std::size_t q = 0; q < model.dof() && !pair; ++q) pair = q != i && body_of(model, cfg, q) == ii;
        if (!pair) continue;
        P.row(L.v(ii)).setZero();
        for (std::size_t q = 0; q < model.dof(); ++q)
            if (body_of(model, cfg, q) == b)
                P(L.v(ii), L.v(static_cast<int>(q))) = model.masses[q].m / mass[static_cast<std::size_t>(b)];
    }
    for (std::size_t j = 0; j < model.jenkins.size(); ++j) {
        if (cfg.slip[j] == 0) continue;
        P.row(L.s(j)).setZero();
        for_each_term(model.jenkins[j].direction(), [&](int b, double w) { P(L.s(j), L.x(b)) = w; });
    }
    return P;
}

Eigen::VectorXd stick_field(const Model& model, const Configuration& cfg, const signed char* sgn, double t,
                            const double* x, const double* v) {
    const Layout L = layout(model);
    Eigen::VectorXd f = Eigen::VectorXd::Zero(L.size());
    std::vector<double> force(model.dof(), 0.0), mass(model.dof(), 0.0);
    if (model.coupled_mass()) {  // M_FF a_F = f_F, kinetic friction included (held_mass.h)
        std::vector<double> a(model.dof());
        held_forces(model, cfg, cfg.stuck, sgn, t, x, v, force.data());
        HeldMass(model, cfg.stuck).accelerations(force.data(), a.data());
        for (std::size_t i = 0; i < model.dof(); ++i) {
            if (cfg.stuck[i]) continue;
            f(L.x(static_cast<int>(i))) = v[i];
            f(L.v(static_cast<int>(i))) = a[i];
        }
    }
    // Each dof's force (kinetic friction, and its reaction on the partner), then each body's sum.
    std::vector<double> on_dof(model.dof(), 0.0);
    for (std::size_t i = 0; i < model.dof() && !model.coupled_mass(); ++i) {
        on_dof[i] += force_on_mass(model, cfg, static_cast<int>(i), t, x, v);
        const FrictionSlot& fs = model.friction_slot(i);
        if (fs.active && !cfg.stuck[i] && sgn[i] != 0) {
            const double fk = fs.mu_k * model.normal_force(i) * sgn[i];
            on_dof[i] -= fk;
            if (fs.partner != kGround) on_dof[static_cast<std::size_t>(fs.partner)] += fk;
        }
    }
    for (std::size_t i = 0; i < model.dof() && !model.coupled_mass(); ++i) {
        const int b = body_of(model, cfg, i);
        if (b < 0) continue;
        force[static_cast<std::size_t>(b)] += on_dof[i];
        mass[static_cast<std::size_t>(b)] += model.masses[i].m;
    }
    for (std::size_t i = 0; i < model.dof() && !model.coupled_mass(); ++i) {
        const int ii = static_cast<int>(i), b = body_of(model, cfg, i);
        if (b < 0) continue;
        f(L.x(ii)) = v[i];
        f(L.v(ii)) = force[static_cast<std::size_t>(b)] / mass[static_cast<std::size_t>(b)];
    }
    for (std::size_t j = 0; j < model.jenkins.size(); ++j) {
        if (cfg.slip[j] == 0) continue;
        const double* rows[] = {v};
        f(L.s(j)) = along(model.jenkins[j].direction(), double_motion(rows), 0);
    }
    return f;
}

void stick_gradient(const Model& model, const Configuration& cfg, const SwitchFunction& f, double t,
                    Eigen::RowVectorXd& hz, double& ht) {
    const Layout L = layout(model);
    hz = Eigen::RowVectorXd::Zero(L.size());
    ht = 0.0;
    auto add = [&](Eigen::Index at, int body, double c) {
        if (body != kGround) hz(at + body) += c;
    };
    const int e = f.element;
    switch (f.kind) {
        case SwitchKind::gap: {
            for_each_term(model.contacts[static_cast<std::size_t>(e)].direction(), [&](int i, double w) { add(0, i, w); });
            return;
        }
        case SwitchKind::velocity:  // w = v_e - v_partner
            add(L.n, e, 1.0);
            add(L.n, model.friction_slot(static_cast<std::size_t>(e)).partner, -1.0);
            return;
        case SwitchKind::release_pos:
        case SwitchKind::release_neg: {
            const double sg = f.kind == SwitchKind::release_pos ? 1.0 : -1.0;
            const Eigen::MatrixXd K = stiffness_matrix(model, cfg), C = damping_matrix(model, cfg);
            const Eigen::VectorXd rate = forcing_rate(model, t);
            const int p = model.friction_slot(static_cast<std::size_t>(e)).partner;
            if (model.coupled_friction()) {  // D_e = P_e . f (held_mass.h: a coupled M, or several frictions on a body)
                const Eigen::VectorXd P = HeldMass(model, cfg.stuck).release_row(e);
                for (Eigen::Index q = 0; q < L.n; ++q) {
                    if (P(q) == 0.0) continue;
                    hz += sg * P(q) * force_gradient(model, cfg, K, C, static_cast<int>(q));
                    ht += sg * P(q) * rate(q);
                }
                return;
            }
            if (p == kGround) {
                hz = sg * force_gradient(model, cfg, K, C, e);
                ht = sg * rate(e);
                return;
            }
            // D = (m_p A_e - m_e A_p)/(m_e + m_p) (assembly.h driving_force).
            const double me = model.masses[static_cast<std::size_t>(e)].m,
                         mp = model.masses[static_cast<std::size_t>(p)].m;
            hz = sg * (mp * force_gradient(model, cfg, K, C, e) - me * force_gradient(model, cfg, K, C, p)) / (me + mp);
            ht = sg * against_partner(me, mp, rate(e), rate(p));
            return;
        }
        case SwitchKind::slip_pos:
        case SwitchKind::slip_neg: {  // +-k (x_a - x_b - s) - F_s
            const Jenkins& el = model.jenkins[static_cast<std::size_t>(e)];
            const double sk = f.kind == SwitchKind::slip_pos ? el.k : -el.k;
            for_each_term(el.direction(), [&](int b, double w) { add(0, b, sk * w); });
            hz(L.s(static_cast<std::size_t>(e))) = -sk;
            return;
        }
        case SwitchKind::slip_velocity: {
            for_each_term(model.jenkins[static_cast<std::size_t>(e)].direction(),
                          [&](int b, double w) { add(L.n, b, w); });
            return;
        }
    }
}

}  // namespace hsnc::analysis
