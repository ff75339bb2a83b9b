// The exact tangent dynamics (analysis/tangent.h) against finite differences
// of the high-precision reference: the Jacobian of the flow map over a run
// with switches of every kind, J = S_k Phi_k ... S_1 Phi_1, and the central
// difference (y(y0 + h e_j) - y(y0 - h e_j)) / 2h of two reference runs at 40
// digits (h = 1e-8: the difference is exact to about 1e-16 relative, its
// rounding 1e-30), on random models and on small models built for one switch
// kind each.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <cln/float.h>
#include <cln/real.h>

#include "engine_runner.h"
#include "random_model.h"
#include "reference_engine.h"
#include "kernel_mode.h"
#include "tangent.h"

namespace hsnc {
namespace {

using EventList = testing::EventSequence;

struct Run {
    bool ok = false;
    std::vector<std::pair<EventKind, int>> seq;
    std::vector<cln::cl_F> y;
};

Run reference_run(const Model& m, double t_end) {
    EngineOptions opt;
    opt.t_end = t_end;
    opt.samples = false;
    EventList ev;
    const reference::PreciseRun r = reference::simulate_precise(m, 40, opt, ev);
    Run out;
    out.ok = r.summary.status == RunStatus::ok;
    out.seq = ev.seq;
    out.y = r.x;
    out.y.insert(out.y.end(), r.v.begin(), r.v.end());
    return out;
}

struct Comparison {
    int columns = 0, skipped = 0;
    double max_error = 0.0;  // max |J - J_fd| / (1 + max |J_fd|)
    std::array<int, 5> kinds{};
};

// J of the double engine against the reference's central differences, column by column.
void compare(const Model& m, double t_end, Comparison& c, const std::string& what) {
    const std::size_t n = m.dof();
    GenericSolverProvider provider(m);
    Engine engine(m, provider);
    EventList base_events;
    analysis::JacobianObserver jac(m, &base_events);
    EngineOptions opt;
    opt.t_end = t_end;
    opt.samples = false;
    const RunSummary s = engine.run(opt, jac);
    ASSERT_EQ(s.status, RunStatus::ok) << what;
    ASSERT_EQ(jac.grazing(), 0u) << what;
    const Eigen::MatrixXd& J = jac.jacobian();
    Eigen::MatrixXd Jfd = Eigen::MatrixXd::Zero(2 * n, 2 * n);
    std::vector<char> used(2 * n, 0);
    for (std::size_t j = 0; j < 2 * n; ++j) {
        Model p = m, q = m;
        std::vector<double>& yp = j < n ? p.x0 : p.v0;
        std::vector<double>& yq = j < n ? q.x0 : q.v0;
        const std::size_t i = j % n;
        const double h = 1e-8;
        yp[i] += h;
        yq[i] -= h;
        const double hsum = (yp[i] - (j < n ? m.x0 : m.v0)[i]) + ((j < n ? m.x0 : m.v0)[i] - yq[i]);
        const Run rp = reference_run(p, t_end), rq = reference_run(q, t_end);
        // A perturbation that changes the switch sequence (a grazing switch,
        // a stuck mass set sliding) has no derivative to compare.
        if (!rp.ok || !rq.ok || rp.seq != base_events.seq || rq.seq != base_events.seq) {
            ++c.skipped;
            continue;
        }
        const cln::cl_F den = cln::cl_float(hsum, rp.y[0]);
        for (std::size_t r = 0; r < 2 * n; ++r) Jfd(r, j) = cln::double_approx((rp.y[r] - rq.y[r]) / den);
        used[j] = 1;
        ++c.columns;
    }
    const double scale = 1.0 + Jfd.cwiseAbs().maxCoeff();
    for (std::size_t j = 0; j < 2 * n; ++j) {
        if (!used[j]) continue;
        for (std::size_t r = 0; r < 2 * n; ++r) {
            const double e = std::fabs(J(r, j) - Jfd(r, j)) / scale;
            c.max_error = std::max(c.max_error, e);
            EXPECT_LT(e, 1e-7) << what << ": J(" << r << "," << j << ") = " << J(r, j) << ", finite difference "
                               << Jfd(r, j);
        }
    }
    for (const auto& ev : base_events.seq) ++c.kinds[static_cast<int>(ev.first)];
}

TEST(TangentReference, RandomModels) {
    Comparison c;
    int models = 0;
    for (unsigned seed = 1; seed <= 24; ++seed) {
        const int n = 1 + static_cast<int>(seed % 3);
        testing::Drawn d = testing::draw(1000 + seed, n);
        compare(d.model, d.model.t0 + 1.5, c, "seed " + std::to_string(1000 + seed) + ", n = " + std::to_string(n));
        ++models;
    }
    std::printf("random models: %d, columns compared %d, skipped %d, max error %.3g; events: close %d open %d "
                "stick %d release %d reversal %d\n",
                models, c.columns, c.skipped, c.max_error, c.kinds[0], c.kinds[1], c.kinds[2], c.kinds[3],
                c.kinds[4]);
    EXPECT_GT(c.columns, 3 * c.skipped);
    for (int k = 0; k < 5; ++k) EXPECT_GT(c.kinds[k], 0) << event_kind_name(static_cast<EventKind>(k));
}

// Two switches at one instant: a symmetric model (two equal masses, each
// with its own stop at the same gap, driven alike) closes and opens both
// stops at once, so the engine reports switch instants with two functions.
// The flow stays differentiable there (each stop's damper jump acts on its
// own mass: the two saltation matrices commute), but a perturbation of one
// mass splits the instant into two switches about 1e-8 s apart, in either
// order: the reference runs are compared with the events of one instant
// taken in a fixed order (kind, element).
class TimedEvents : public Observer {
public:
    void on_sample(double, const double*, const double*) override {}
    void on_event(double t, EventKind k, int e, const double*, const double*) override { ev.push_back({t, k, e}); }
    struct Event {
        double t;
        EventKind kind;
        int element;
    };
    std::vector<Event> ev;
    // The sequence with events less than `window` apart sorted by (kind, element).
    std::vector<std::pair<EventKind, int>> canonical(double window) const {
        std::vector<std::pair<EventKind, int>> out;
        for (std::size_t i = 0; i < ev.size();) {
            std::size_t j = i + 1;
            while (j < ev.size() && ev[j].t - ev[j - 1].t < window) ++j;
            std::vector<std::pair<EventKind, int>> group;
            for (std::size_t k = i; k < j; ++k) group.emplace_back(ev[k].kind, ev[k].element);
            std::sort(group.begin(), group.end());
            out.insert(out.end(), group.begin(), group.end());
            i = j;
        }
        return out;
    }
};

TEST(TangentReference, SimultaneousSwitches) {
    Model m;
    m.name = "twin_stops";
    m.masses = {{"m1", 1.0}, {"m2", 1.0}};
    m.springs = {{kGround, 0, 10.0}, {0, 1, 3.0}, {1, kGround, 10.0}};
    m.contacts = {{"c1", 0, kGround, 0.1, 40.0}, {"c2", 1, kGround, 0.1, 40.0}};
    m.alpha = 0.1;
    m.beta = 0.02;
    m.forcing.push_back({3.0, 0.0, {1.5, 1.5}});
    m.load = {0.0, 0.0};
    m.x0 = {0.0, 0.0};
    m.v0 = {1.0, 1.0};
    const double t_end = 2.5, h = 1e-8, window = 1e-6;
    const std::size_t n = m.dof();

    GenericSolverProvider provider(m);
    Engine engine(m, provider);
    TimedEvents base;
    analysis::JacobianObserver jac(m, &base);
    EngineOptions opt;
    opt.t_end = t_end;
    opt.samples = false;
    ASSERT_EQ(engine.run(opt, jac).status, RunStatus::ok);
    ASSERT_EQ(jac.grazing(), 0u);
    ASSERT_GE(jac.multiple_switches(), 2u) << "the stops close and open together";
    const Eigen::MatrixXd& J = jac.jacobian();
    const auto want = base.canonical(window);

    double worst = 0.0;
    for (std::size_t j = 0; j < 2 * n; ++j) {
        std::vector<cln::cl_F> y[2];
        double hsum = 0.0;
        for (int side = 0; side < 2; ++side) {
            Model p = m;
            std::vector<double>& yp = j < n ? p.x0 : p.v0;
            const double y0 = yp[j % n];
            yp[j % n] += side == 0 ? h : -h;
            hsum += side == 0 ? yp[j % n] - y0 : y0 - yp[j % n];
            TimedEvents ev;
            const reference::PreciseRun r = reference::simulate_precise(p, 40, opt, ev);
            ASSERT_EQ(r.summary.status, RunStatus::ok);
            ASSERT_EQ(ev.canonical(window), want) << "column " << j << " side " << side;
            // The perturbation splits each double instant into two.
            EXPECT_EQ(ev.ev.size(), base.ev.size());
            y[side] = r.x;
            y[side].insert(y[side].end(), r.v.begin(), r.v.end());
        }
        const cln::cl_F den = cln::cl_float(hsum, y[0][0]);
        Eigen::VectorXd fd(2 * n);
        for (std::size_t r = 0; r < 2 * n; ++r) fd(r) = cln::double_approx((y[0][r] - y[1][r]) / den);
        const double scale = 1.0 + fd.cwiseAbs().maxCoeff();
        for (std::size_t r = 0; r < 2 * n; ++r) {
            const double e = std::fabs(J(r, j) - fd(r)) / scale;
            worst = std::max(worst, e);
            EXPECT_LT(e, 1e-7) << "J(" << r << "," << j << ") = " << J(r, j) << ", finite difference " << fd(r);
        }
    }
    std::printf("simultaneous switches: %zu instants with two functions, %zu events, max error %.3g\n",
                jac.multiple_switches(), base.ev.size(), worst);
}

}  // namespace
}  // namespace hsnc

#include <unsupported/Eigen/MatrixFunctions>

namespace hsnc {
namespace {

// Phi(tau) against the matrix exponential of the segment's first-order
// system (free masses: x' = v, M v' = -K x - C v, stuck masses: x' = 0, v' = 0,
// with the dv columns of stuck masses then set to 0), on random models and
// configurations and durations up to 50 s.
TEST(TangentTransition, MatchesMatrixExponential) {
    double worst = 0.0;
    for (unsigned seed = 1; seed <= 60; ++seed) {
        const int n = 1 + static_cast<int>(seed % 4);
        const testing::Drawn d = testing::draw(2000 + seed, n);
        const Model& m = d.model;
        Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, n);
        auto link = [&](int a, int b, double k) {
            if (a != kGround) K(a, a) += k;
            if (b != kGround) K(b, b) += k;
            if (a != kGround && b != kGround) K(a, b) -= k, K(b, a) -= k;
        };
        for (const Spring& s : m.springs) link(s.a, s.b, s.k);
        for (std::size_t c = 0; c < m.contacts.size(); ++c)
            if (d.cfg.closed[c]) link(m.contacts[c].a, m.contacts[c].b, m.contacts[c].k);
        Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2 * n, 2 * n);
        for (int i = 0; i < n; ++i) {
            if (d.cfg.stuck[i]) continue;
            A(i, n + i) = 1.0;
            for (int j = 0; j < n; ++j) {
                A(n + i, j) = -K(i, j) / m.masses[i].m;
                A(n + i, n + j) = -(m.alpha * (i == j ? m.masses[i].m : 0.0) + m.beta * K(i, j)) / m.masses[i].m;
            }
        }
        analysis::Tangent tangent(m);
        for (double tau : {0.0, 1e-7, 0.01, 0.7, 5.0, 50.0}) {
            Eigen::MatrixXd want = (A * tau).exp();
            for (int i = 0; i < n; ++i)
                if (d.cfg.stuck[i]) want.col(n + i).setZero(), want.row(n + i).setZero();
            const Eigen::MatrixXd got = tangent.transition(d.cfg, tau);
            // The exponential (Pade with scaling and squaring) is itself good to
            // about eps times the norm of A tau.
            const double norm = std::max(1.0, (A * tau).cwiseAbs().colwise().sum().maxCoeff());
            const double err = (got - want).cwiseAbs().maxCoeff() / (1.0 + want.cwiseAbs().maxCoeff()) / norm;
            worst = std::max(worst, err);
            EXPECT_LT(err, 1e-14) << "seed " << 2000 + seed << " tau " << tau;
        }
    }
    std::printf("Phi against expm: worst relative difference per unit of |A tau| %.3g\n", worst);
}

}  // namespace
}  // namespace hsnc
