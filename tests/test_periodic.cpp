// Periodic orbits by shooting (hsnc::periodic) and Lyapunov exponents
// (hsnc::lyapunov) against closed forms:
//  - Den Hartog's forced Coulomb oscillator in non-sticking motion
//    (Den Hartog 1931): amplitude and Floquet multipliers;
//  - linear damped oscillators: exponents = real parts of the eigenvalues;
//  - gap contacts with mass-proportional damping (the contacts engage at zero
//    force and change no damping): the product of the multipliers is
//    exp(-tr(M^-1 C) T), the exponents sum to -tr(M^-1 C), chaotic motion included;
//  - orbits found by shooting against long simulations that settle on them.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>

#include "hsnc/lyapunov.h"
#include "hsnc/periodic.h"
#include "model_reader.h"
#include "shooting.h"
#include "solver_provider.h"

namespace hsnc {
namespace {

// 1 mass (m = 1), spring k = 1 (omega_n = 1), Coulomb friction mu_k = mu_s
// = beta with g = 1 (friction force beta), forcing sin(r t) of amplitude 1.
Model den_hartog(double r, double beta) {
    Model m;
    m.name = "den_hartog";
    m.g = 1.0;
    m.masses.push_back({"m1", 1.0});
    m.set_friction(m.masses.size() - 1) = {true, beta, beta};
    m.springs.push_back({kGround, 0, 1.0});
    m.forcing.push_back({r, 0.0, {1.0}});
    m.load = {0.0};
    m.x0 = {0.0};
    m.v0 = {0.0};
    return m;
}

class Reversals : public Observer {
public:
    void on_sample(double, const double*, const double*) override {}
    void on_event(double, EventKind k, int, const double* x, const double*) override {
        if (k == EventKind::reversal) turning.push_back(x[0]);
        if (k == EventKind::stick) ++sticks;
    }
    std::vector<double> turning;
    int sticks = 0;
};

// Each expected value has a computed one within tol (and the counts agree).
void expect_same_set(std::vector<std::complex<double>> got, std::vector<std::complex<double>> want, double tol,
                     const std::string& what) {
    ASSERT_EQ(got.size(), want.size()) << what;
    for (const auto& w : want) {
        auto best = std::min_element(got.begin(), got.end(), [&](const auto& a, const auto& b) {
            return std::abs(a - w) < std::abs(b - w);
        });
        EXPECT_LT(std::abs(*best - w), tol) << what << ": expected multiplier " << w << ", nearest " << *best;
        got.erase(best);
    }
}

TEST(DenHartog, AmplitudeAndMultipliers) {
    int cases = 0;
    for (double r : {0.7, 0.8, 1.25, 1.5, 2.0, 3.0})
        for (double beta : {0.1, 0.3, 0.5}) {
            const std::string what = "r = " + std::to_string(r) + ", beta = " + std::to_string(beta);
            const double U = std::tan(M_PI / (2 * r)) / r, V = 1 / (1 - r * r);
            const double X = std::sqrt(V * V - beta * beta * U * U);
            const double rho = (r * r * X - beta) / (r * r * X + beta);
            // lambda^2 - cos(pi/r)(1 + rho) lambda + rho = 0, mu = lambda^2.
            const std::complex<double> b = -std::cos(M_PI / r) * (1 + rho), disc = std::sqrt(b * b - 4.0 * rho);
            const std::complex<double> l1 = (-b + disc) / 2.0, l2 = (-b - disc) / 2.0;

            Model m = den_hartog(r, beta);
            m.x0 = {X};  // a start near the orbit; Newton does the rest
            PeriodicOptions o;
            o.kernels = KernelChoice::generic;
            Reversals rev;
            const PeriodicResult p = periodic(m, o, &rev);
            ASSERT_EQ(p.status, PeriodicStatus::ok) << what << ": " << p.message;
            EXPECT_LE(p.residual, 1e-10) << what;
            // Non-sticking motion: two reversals a period, at +-X.
            ASSERT_EQ(rev.sticks, 0) << what;
            ASSERT_EQ(rev.turning.size(), 2u) << what;
            for (double xt : rev.turning) EXPECT_NEAR(std::fabs(xt), X, 1e-9 * X) << what;
            EXPECT_NEAR(rev.turning[0], -rev.turning[1], 1e-9 * X) << what;
            expect_same_set(p.multipliers, {l1 * l1, l2 * l2}, 1e-9, what);
            EXPECT_EQ(p.stable, std::abs(l1 * l1) < 1 && std::abs(l2 * l2) < 1) << what;
            std::printf("r %.2f beta %.1f: X %.6f (closed form %.6f), |mu| %.6f %.6f (closed form %.6f %.6f), "
                        "%d iterations\n",
                        r, beta, std::fabs(rev.turning[0]), X, std::abs(p.multipliers[0]), std::abs(p.multipliers[1]),
                        std::max(std::abs(l1 * l1), std::abs(l2 * l2)), std::min(std::abs(l1 * l1), std::abs(l2 * l2)),
                        p.iterations);
            ++cases;
        }
    EXPECT_EQ(cases, 18);
}

// 2-DOF chain with Rayleigh damping C = alpha M + beta K, no contacts.
Model linear_chain(double alpha, double beta) {
    Model m;
    m.name = "linear";
    m.masses = {{"m1", 1.0}, {"m2", 2.0}};
    m.springs = {{kGround, 0, 4.0}, {0, 1, 3.0}, {1, kGround, 1.0}};
    m.alpha = alpha;
    m.beta = beta;
    m.forcing.push_back({1.3, 0.0, {1.0, -0.5}});
    m.load = {0.0, 0.0};
    m.x0 = {0.1, 0.0};
    m.v0 = {0.0, 0.2};
    return m;
}

TEST(LinearLyapunov, ExponentsAreRealPartsOfEigenvalues) {
    for (auto [alpha, beta] : {std::pair{0.1, 0.02}, std::pair{0.0, 0.0}, std::pair{3.0, 0.5}}) {
        const Model m = linear_chain(alpha, beta);
        // Eigenvalues of the first-order system y' = A y.
        Eigen::MatrixXd A = Eigen::MatrixXd::Zero(4, 4);
        const Eigen::Matrix2d M = Eigen::Vector2d(1.0, 2.0).asDiagonal();
        Eigen::Matrix2d K;
        K << 7.0, -3.0, -3.0, 4.0;
        const Eigen::Matrix2d C = alpha * M + beta * K;
        A.topRightCorner(2, 2) = Eigen::Matrix2d::Identity();
        A.bottomLeftCorner(2, 2) = -M.inverse() * K;
        A.bottomRightCorner(2, 2) = -M.inverse() * C;
        Eigen::EigenSolver<Eigen::MatrixXd> es(A);
        std::vector<double> want;
        for (int i = 0; i < 4; ++i) want.push_back(es.eigenvalues()(i).real());
        std::sort(want.rbegin(), want.rend());

        LyapunovOptions o;
        o.t_end = 2000.0;
        o.kernels = KernelChoice::generic;
        const LyapunovResult r = lyapunov(m, o);
        ASSERT_EQ(r.status, RunStatus::ok);
        ASSERT_EQ(r.exponents.size(), 4u);
        for (int i = 0; i < 4; ++i)
            EXPECT_NEAR(r.exponents[i], want[i], 1e-3) << "alpha " << alpha << " beta " << beta << " exponent " << i;
        EXPECT_NEAR(r.sum, -(C.diagonal().array() / M.diagonal().array()).sum(), 1e-9);
    }
}

// A dashpot of 1e8 N s/m on m1 (and Rayleigh alpha): the generator has one
// eigenvalue near -1e8. The exponents are still the real parts of the
// eigenvalues, the stiff one included, and the measurement costs what the
// motion does: the QR steps are set by the other directions (the last one's
// growth is det Phi over theirs), not by 10/1e8 s (52 s of work per
// simulated second before).
TEST(LinearLyapunov, AStiffDashpotCostsWhatTheMotionDoes) {
    Model m = linear_chain(0.1, 0.0);
    m.dampers.push_back({kGround, 0, 1e8});
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(4, 4);
    const Eigen::Matrix2d M = Eigen::Vector2d(1.0, 2.0).asDiagonal();
    Eigen::Matrix2d K;
    K << 7.0, -3.0, -3.0, 4.0;
    Eigen::Matrix2d C = 0.1 * M;
    C(0, 0) += 1e8;
    A.topRightCorner(2, 2) = Eigen::Matrix2d::Identity();
    A.bottomLeftCorner(2, 2) = -M.inverse() * K;
    A.bottomRightCorner(2, 2) = -M.inverse() * C;
    Eigen::EigenSolver<Eigen::MatrixXd> es(A);
    std::vector<double> want;
    for (int i = 0; i < 4; ++i) want.push_back(es.eigenvalues()(i).real());
    std::sort(want.rbegin(), want.rend());
    ASSERT_LT(want[3], -0.9e8);

    LyapunovOptions o;
    o.t_end = 20000.0;  // the exponents' O(1/T) transient below 1e-4
    o.kernels = KernelChoice::generic;
    const auto start = std::chrono::steady_clock::now();
    const LyapunovResult r = lyapunov(m, o);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ASSERT_EQ(r.status, RunStatus::ok) << r.message;
    ASSERT_EQ(r.exponents.size(), 4u);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(r.exponents[i], want[i], 1e-3) << "exponent " << i;
    EXPECT_NEAR(r.exponents[3], want[3], 1e-9 * std::fabs(want[3]));
    EXPECT_NEAR(r.sum, -(C.diagonal().array() / M.diagonal().array()).sum(), 1e-9 * 1e8);
    EXPECT_LT(seconds, 5.0) << "20000 s of a linear motion";
}

// The rule for multipliers at +1 (hsnc/periodic.h, kNeutralMultiplier): with
// as many eigenvectors as such multipliers they are a family's (neutral, left
// out of stability); a Jordan block (a free body's drift) is not stable, and
// neither is a pair on the unit circle.
TEST(NeutralMultipliers, AFamilyIsNeutralADriftIsNot) {
    auto judge = [](const Eigen::MatrixXd& M) {
        const std::vector<std::complex<double>> mu = analysis::floquet_multipliers(M);
        const std::size_t k = analysis::family_multipliers(M, mu);
        return std::pair{k, analysis::orbit_stable(mu, k)};
    };
    Eigen::MatrixXd family(3, 3);
    family << 1.0 - 2e-16, 0.3, 0.0, 0.0, 0.5, 0.1, 0.0, 0.0, -0.2;
    EXPECT_EQ(judge(family), (std::pair<std::size_t, bool>{1, true}));
    Eigen::MatrixXd unstable = family;
    unstable(2, 2) = -1.5;
    EXPECT_EQ(judge(unstable), (std::pair<std::size_t, bool>{1, false}));
    Eigen::MatrixXd drift(2, 2);
    drift << 1.0, 0.7, 0.0, 1.0;  // a free body over one period: x += T v
    EXPECT_EQ(judge(drift), (std::pair<std::size_t, bool>{0, false}));
    Eigen::MatrixXd circle(2, 2);
    circle << std::cos(1.0), -std::sin(1.0), std::sin(1.0), std::cos(1.0);
    EXPECT_EQ(judge(circle), (std::pair<std::size_t, bool>{0, false}));
}

// A friction damper that never slips (forced above about 10.43 rad/s it stays
// stuck all period): a linear orbit whose slider may sit at any offset, so its
// multiplier 1 (to rounding) is a family's: stable, one neutral multiplier.
TEST(NeutralMultipliers, AFullyStuckOrbitIsStableWithOneNeutralMultiplier) {
    ModelOverrides set;
    set.set.emplace_back("omega=12");
    const Model m = read_model(std::string(HSNC_SOURCE_DIR) + "/examples/jenkins/friction_damper.toml", set);
    PeriodicOptions o;
    o.transient = 40.0;
    o.kernels = KernelChoice::generic;
    const PeriodicResult r = periodic(m, o);
    ASSERT_EQ(r.status, PeriodicStatus::ok) << r.message;
    EXPECT_EQ(r.events, 0u) << "stuck all period";
    EXPECT_NEAR(std::abs(r.multipliers.front() - 1.0), 0.0, 1e-12);
    EXPECT_EQ(r.neutral, 1u);
    EXPECT_TRUE(r.stable);
    EXPECT_LT(std::abs(r.multipliers[1]), 1.0);
}

// Two masses between walls with gap contacts (one-sided stops, and one
// between the masses), damping alpha*M only: the contacts engage at G = 0,
// so no force jumps and the saltation matrices are the identity; every
// segment shrinks phase volume by exp(-tr(M^-1 C) tau) = exp(-2 alpha tau).
Model gap_oscillator(double amplitude, double alpha) {
    Model m;
    m.name = "gaps";
    m.masses = {{"m1", 1.0}, {"m2", 1.5}};
    m.springs = {{kGround, 0, 10.0}, {0, 1, 5.0}};
    m.contacts = {{"stop", 1, kGround, 0.05, 400.0}, {"wall", kGround, 0, 0.08, 300.0}, {"pair", 0, 1, 0.03, 150.0}};
    m.alpha = alpha;
    m.forcing.push_back({3.1, 0.0, {amplitude, 0.4 * amplitude}});
    m.load = {0.0, 0.0};
    m.x0 = {0.0, 0.0};
    m.v0 = {0.0, 0.0};
    return m;
}

TEST(PhaseVolume, MultipliersOfGapContactOrbits) {
    // Stable and unstable orbits (shooting finds both), 2 to 12 switches a period.
    for (auto [amplitude, alpha] : {std::pair{0.2, 0.3}, std::pair{0.5, 0.3}, std::pair{1.0, 0.3}, std::pair{2.0, 1.0}}) {
        const Model m = gap_oscillator(amplitude, alpha);
        PeriodicOptions o;
        o.transient = 200.0;
        o.kernels = KernelChoice::generic;
        const PeriodicResult p = periodic(m, o);
        ASSERT_EQ(p.status, PeriodicStatus::ok) << amplitude << ": " << p.message;
        std::complex<double> product = 1.0;
        for (const auto& mu : p.multipliers) product *= mu;
        const double want = std::exp(-2 * m.alpha * p.period);
        std::printf("amplitude %g alpha %g: %zu switches a period, max |mu| %.6g, product of multipliers %.15g, "
                    "exp(-2 alpha T) %.15g\n",
                    amplitude, alpha, p.events, p.max_multiplier, product.real(), want);
        EXPECT_GT(p.events, 0u) << amplitude;
        EXPECT_NEAR(product.real(), want, 1e-9 * want) << amplitude;
        EXPECT_NEAR(product.imag(), 0.0, 1e-9 * want) << amplitude;
    }
}

TEST(PhaseVolume, ExponentsSumToTheDampingTrace) {
    for (double amplitude : {0.5, 1.0, 2.0}) {
        const Model m = gap_oscillator(amplitude, 0.05);
        LyapunovOptions o;
        o.t_end = 300.0;
        o.transient = 50.0;
        o.kernels = KernelChoice::generic;
        const LyapunovResult r = lyapunov(m, o);
        ASSERT_EQ(r.status, RunStatus::ok);
        std::printf("amplitude %g: %zu switches, exponents %.6g %.6g %.6g %.6g, sum %.15g\n", amplitude, r.events,
                    r.exponents[0], r.exponents[1], r.exponents[2], r.exponents[3], r.sum);
        EXPECT_GT(r.exponents[0], 0.1) << "chaotic motion (measured)";
        EXPECT_NEAR(r.sum, -2 * m.alpha, 1e-9) << amplitude;
    }
}

// The orbit found by shooting (from the initial state, no transient) is the
// state a long simulation reaches at t0 + k T.
TEST(PeriodicSettle, ShootingAgreesWithLongSimulation) {
    std::vector<Model> models = {den_hartog(1.5, 0.3), den_hartog(0.8, 0.1), gap_oscillator(0.5, 0.3),
                                 gap_oscillator(0.5, 1.0)};
    for (const Model& m : models) {
        PeriodicOptions o;
        o.kernels = KernelChoice::generic;
        const PeriodicResult p = periodic(m, o);
        ASSERT_EQ(p.status, PeriodicStatus::ok) << m.name << ": " << p.message;
        ASSERT_TRUE(p.stable) << m.name;
        // Long enough for the slowest multiplier to shrink a unit error below 1e-12.
        const double periods = std::ceil(std::log(1e-12) / std::log(p.max_multiplier));
        SimulateOptions so;
        so.t_end = m.t0 + periods * p.period;
        so.kernels = KernelChoice::generic;
        const SimulateSummary s = simulate(m, so);
        ASSERT_EQ(s.status, RunStatus::ok);
        for (std::size_t i = 0; i < m.dof(); ++i) {
            EXPECT_NEAR(s.x[i], p.x[i], 1e-9 * (1 + std::fabs(p.x[i]))) << m.name << " x" << i << " after " << periods;
            EXPECT_NEAR(s.v[i], p.v[i], 1e-9 * (1 + std::fabs(p.v[i]))) << m.name << " v" << i;
        }
        std::printf("%s: orbit found in %d iterations, a simulation of %g periods ends within %.3g of it\n",
                    m.name.c_str(), p.iterations, periods,
                    std::max(std::fabs(s.x[0] - p.x[0]), std::fabs(s.v[0] - p.v[0])));
    }
}

}  // namespace
}  // namespace hsnc
