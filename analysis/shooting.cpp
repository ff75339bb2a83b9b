#include "shooting.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "hsnc/periodic.h"

#include "tangent.h"

namespace hsnc::analysis {
namespace {

class EventCounter : public Observer {
public:
    void on_sample(double, const double*, const double*) override {}
    void on_event(double, EventKind, int, const double*, const double*) override { ++events; }
    std::size_t events = 0;
};

}  // namespace

double period_residual(const Eigen::VectorXd& y, const Eigen::VectorXd& Py, std::size_t masses) {
    const Eigen::Index n = static_cast<Eigen::Index>(masses), nj = y.size() - 2 * n;
    // Lengths (the masses' positions and the sliders), then velocities.
    Eigen::VectorXd a(n + nj), b(n + nj);
    a << y.head(n), y.tail(nj);
    b << Py.head(n), Py.tail(nj);
    double res = 0.0;
    auto part = [&](const Eigen::VectorXd& p, const Eigen::VectorXd& q) {
        if (p.size() == 0) return;
        const double scale = std::max(p.cwiseAbs().maxCoeff(), q.cwiseAbs().maxCoeff());
        const double r = (q - p).cwiseAbs().maxCoeff();
        if (r > 0) res = std::max(res, scale > 0 ? r / scale : INFINITY);
    };
    part(a, b);
    part(y.segment(n, n), Py.segment(n, n));
    return res;
}

PeriodMapValue evaluate_period_map(Flow& flow, double ts, double te, const Eigen::VectorXd& y) {
    PeriodMapValue m;
    const std::size_t n = flow.model().dof(), nj = flow.model().jenkins.size();
    const Eigen::Index N = static_cast<Eigen::Index>(2 * n + nj);
    EventCounter events;
    JacobianObserver jac(flow.model(), &events);
    const RunSummary s = flow.run(ts, y.data(), y.data() + n, te, jac, false, 0.0, nj ? y.data() + 2 * n : nullptr);
    if (s.status != RunStatus::ok) {
        m.message =
            std::string("a run of the period map ended with status ") + run_status_name(s.status) + ": " + s.message;
        return m;
    }
    m.Py.resize(N);
    for (std::size_t i = 0; i < n; ++i)
        m.Py(static_cast<Eigen::Index>(i)) = s.x[i], m.Py(static_cast<Eigen::Index>(n + i)) = s.v[i];
    for (std::size_t j = 0; j < nj; ++j) m.Py(static_cast<Eigen::Index>(2 * n + j)) = s.slider[j];
    m.end = s.configuration;
    m.M = jac.jacobian();
    m.grazing = jac.grazing();
    m.singular = jac.singular();
    m.events = events.events;
    m.residual = period_residual(y, m.Py, n);
    m.ok = m.Py.allFinite() && std::isfinite(m.residual);
    if (!m.ok) m.message = "the period map gave non-finite values";
    return m;
}

std::vector<std::complex<double>> floquet_multipliers(const Eigen::MatrixXd& M) {
    std::vector<std::complex<double>> mu;
    if (M.size() == 0) return mu;
    Eigen::EigenSolver<Eigen::MatrixXd> es(M, false);
    for (Eigen::Index i = 0; i < M.rows(); ++i) mu.push_back(es.eigenvalues()(i));
    std::stable_sort(mu.begin(), mu.end(), [](const std::complex<double>& a, const std::complex<double>& b) {
        return std::abs(a) > std::abs(b);
    });
    return mu;
}

std::size_t family_multipliers(const Eigen::MatrixXd& M, const std::vector<std::complex<double>>& mu) {
    std::size_t at_one = 0;
    for (const std::complex<double>& m : mu) at_one += std::abs(m - 1.0) <= kNeutralMultiplier;
    if (at_one == 0) return 0;
    const Eigen::Index N = M.rows();
    const Eigen::VectorXd sigma = Eigen::JacobiSVD<Eigen::MatrixXd>(M - Eigen::MatrixXd::Identity(N, N)).singularValues();
    const double floor = 1e-8 * std::max(1.0, M.norm());
    std::size_t null = 0;
    for (Eigen::Index k = 0; k < sigma.size(); ++k) null += sigma(k) <= floor;
    return null >= at_one ? at_one : 0;
}

bool orbit_stable(const std::vector<std::complex<double>>& mu, std::size_t neutral) {
    for (const std::complex<double>& m : mu) {
        if (neutral > 0 && std::abs(m - 1.0) <= kNeutralMultiplier) {
            --neutral;
            continue;
        }
        if (!(std::abs(m) < 1.0 - kNeutralMultiplier)) return false;
    }
    return true;
}

}  // namespace hsnc::analysis
