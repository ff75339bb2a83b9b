// [reduction]: a structure read sparse and reduced by Craig-Bampton to the
// dofs its elements name plus fixed-interface modes, or by Rubin's method
// to them plus free-interface modes (model/reduction.h).
// Checked against what does not depend on hsnc's own reduction:
//  - the reduced frequencies bound the full model's (a dense generalized
//    eigensolve of the test's own M, K) from above, come closer as modes
//    grow, and equal them when every interior mode is kept;
//  - the static tip flexibility of a cantilever, L^3 / (3 EI), which cubic
//    beam elements reproduce exactly: Craig-Bampton keeps it exactly;
//  - a tip stop on the reduced cantilever against the same stop on the
//    full model (the reduction error shrinking with the modes kept) and
//    against CVODE on the reduced model; likewise a friction pad and two
//    stops (stick-slip at a boundary dof), which with every interior mode
//    kept follows the full model to 1e-10 s (a change of basis);
//  - `hsnc reduce` writes matrices that, read back as a [structure], give
//    the reduced model's events bit for bit;
//  - large sparse files are read only for a reduction, and bad input is
//    refused by name.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "cli_runner.h"
#include "engine_runner.h"
#include "fe_models.h"
#include "hex8_solid.h"
#include "hsnc/sweep.h"
#include "model_reader.h"
#include "error.h"
#include "matrix_market.h"
#include "reduction.h"
#include "temp_dir.h"

namespace hsnc {
namespace {

using namespace fe;

constexpr int kElements = 40;  // 80 dofs; the tip deflection is w40

/// The forced cantilever, its tip against a stop, with `reduction` appended.
std::string tip_stop(const testing::TempDir& dir, const Beam& b, const std::string& file, const std::string& reduction) {
    return structure_model(dir, file, "reduced-cantilever", b.M, b.K, b.dofs,
                           "[damping]\nalpha = 0.5\nbeta = 1e-4\n"
                           "[[forcing]]\nomega = 20.0\namplitude = { w40 = 4.0 }\n"
                           "[[contact]]\nname = \"stop\"\nbetween = [\"w40\", \"ground\"]\ngap = 0.01\nk = 2e4\n"
                           "[simulate]\nt_end = 1.5\n" +
                               reduction);
}

Eigen::VectorXd full_omegas(const Beam& b) {
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(b.K, b.M, Eigen::EigenvaluesOnly);
    return es.eigenvalues().cwiseSqrt();
}

ModelOverrides with_frequencies() {
    ModelOverrides o;
    o.full_frequencies = true;
    return o;
}

TEST(Reduction, ReducedFrequenciesBoundTheFullOnesFromAboveAndReachThemWithEveryMode) {
    testing::TempDir dir;
    const Beam b = cantilever(kElements);
    const Eigen::VectorXd full = full_omegas(b);
    double previous_error = 1.0;
    for (const int modes : {2, 5, 10, 20, 79}) {  // 79: every interior mode (the boundary is w40 alone)
        const Model m = read_model(tip_stop(dir, b, "m.toml", "[reduction]\nmodes = " + std::to_string(modes) + "\n"),
                                   with_frequencies());
        ASSERT_TRUE(m.reduction.present);
        EXPECT_EQ(m.dof(), static_cast<std::size_t>(1 + modes));
        EXPECT_EQ(m.masses[0].name, "w40");
        EXPECT_EQ(m.masses[1].name, "q1");
        ASSERT_EQ(m.reduction.open.full.size(), m.reduction.open.reduced.size());
        double error = 0.0;
        for (std::size_t k = 0; k < m.reduction.open.reduced.size(); ++k) {
            const double exact = full(static_cast<Eigen::Index>(k));
            EXPECT_NEAR(m.reduction.open.full[k], exact, 1e-9 * exact) << "the sparse eigensolve, mode " << k + 1;
            // Rayleigh-Ritz: never below the full model's frequency (to the
            // rounding of two double eigensolves of a beam with cond(K) ~ 1e9).
            EXPECT_GE(m.reduction.open.reduced[k], exact * (1.0 - 1e-9)) << modes << " modes, mode " << k + 1;
            if (k < 2) error = std::max(error, std::fabs(m.reduction.open.reduced[k] - exact) / exact);
        }
        std::printf("%2d modes: lowest two frequencies within %.3g relative\n", modes, error);
        EXPECT_LE(error, previous_error) << "more modes should not be worse";
        previous_error = error;
        if (modes == 79) EXPECT_LT(std::fabs(error), 1e-9) << "every mode kept: the reduction is a change of basis";
    }
}

// The reduction's response error (`check`): the tip's steady response to
// the forcing (4 N at 20 rad/s, alpha 0.5, beta 1e-4) and to a static load,
// full against reduced, against the test's own dense solves of the full
// beam's and the reduced model's matrices; it shrinks as modes are kept,
// is at rounding with every interior mode, and the static one (which
// Craig-Bampton keeps exactly) is at rounding whatever the modes.
TEST(Reduction, TheResponseErrorIsTheTipsFullAgainstReducedFrequencyResponse) {
    testing::TempDir dir;
    const Beam b = cantilever(kElements);
    using Complex = std::complex<double>;
    const double w = 20.0, alpha = 0.5, beta = 1e-4;
    const auto frf = [&](const Eigen::MatrixXd& M, const Eigen::MatrixXd& K, Eigen::Index at) {
        const Eigen::MatrixXcd A =
            (K - w * w * M).cast<Complex>() + Complex(0, w) * (alpha * M + beta * K).cast<Complex>();
        Eigen::VectorXcd F = Eigen::VectorXcd::Zero(K.rows());
        F(at) = 4.0;
        return Complex(A.partialPivLu().solve(F)(at));
    };
    const auto tip = static_cast<Eigen::Index>(std::find(b.dofs.begin(), b.dofs.end(), "w40") - b.dofs.begin());
    ASSERT_LT(tip, b.M.rows());
    const Complex full = frf(b.M, b.K, tip);
    double previous = 1.0;
    for (const int modes : {2, 5, 20, 79}) {
        const Model m = read_model(
            tip_stop(dir, b, "m.toml", "[reduction]\nmodes = " + std::to_string(modes) + "\n[load]\nw40 = 0.3\n"),
            with_frequencies());
        ASSERT_EQ(m.reduction.response.size(), 2u);
        EXPECT_EQ(m.reduction.response[0].what, "load (static)");
        EXPECT_LT(m.reduction.response[0].error, 1e-9) << modes << " modes";
        EXPECT_EQ(m.reduction.response[1].what, "forcing 1 at 20 rad/s");
        const auto n = static_cast<Eigen::Index>(m.dof());
        const Eigen::MatrixXd M =
            Eigen::Map<const Eigen::Matrix<double, -1, -1, Eigen::RowMajor>>(m.reduction.M.data(), n, n);
        const Eigen::MatrixXd K =
            Eigen::Map<const Eigen::Matrix<double, -1, -1, Eigen::RowMajor>>(m.reduction.K.data(), n, n);
        const double error = std::abs(frf(M, K, 0) - full) / std::abs(full);
        // To the rounding of two LU solvers on a beam with cond(K) ~ 1e9 (1.7e-10 measured).
        EXPECT_NEAR(m.reduction.response[1].error, error, 1e-6 * error + 5e-10) << modes << " modes";
        EXPECT_LE(error, previous) << modes << " modes";
        previous = error;
        if (modes == 79) EXPECT_LT(error, 1e-9);
        std::printf("%2d modes: tip response error %.3g at 20 rad/s\n", modes, m.reduction.response[1].error);
    }
    EXPECT_GT(std::abs(full), 0.0);
    // check prints it.
    const auto r = testing::run_hsnc("check '" + tip_stop(dir, b, "m.toml", "[reduction]\nmodes = 5\n") + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("  response at the boundary dofs, the structure alone (elements left out): full vs reduced, "
                         "relative error\n    forcing 1 at 20 rad/s: "),
              std::string::npos)
        << r.out;
}

TEST(Reduction, TheStaticTipFlexibilityIsKeptExactly) {
    // Cubic elements are exact for a tip load: w = P L^3 / (3 EI) = P / 300.
    testing::TempDir dir;
    const Beam b = cantilever(kElements);
    for (const int modes : {0, 3}) {
        const Model m = read_model(tip_stop(dir, b, "m.toml", "[reduction]\nmodes = " + std::to_string(modes) + "\n"));
        const auto n = static_cast<Eigen::Index>(m.dof());
        const Eigen::MatrixXd K = Eigen::Map<const Eigen::Matrix<double, -1, -1, Eigen::RowMajor>>(m.reduction.K.data(), n, n);
        const double flexibility = K.inverse()(0, 0);
        EXPECT_NEAR(flexibility, 1.0 / 300.0, 1e-12 / 300.0) << modes << " modes";
    }
}

/// The tip stop on the cantilever reduced with 4, 8 and 16 modes (`reduction`
/// gives the [reduction] table): closer to the full model's events as modes
/// are kept, within `at16` s with 16, and within 1e-9 s of CVODE on it.
void tip_stop_follows_the_full_model(const std::function<std::string(int)>& reduction, double at16) {
    testing::TempDir dir;
    const Beam b = cantilever(kElements);
    const Model full = read_model(tip_stop(dir, b, "full.toml", ""));
    const testing::Outcome exact = testing::simulate(full, 1.5, 0.0, testing::Solvers::interp);
    ASSERT_GE(exact.events.size(), 6u);
    double previous = 1.0;
    for (const int modes : {4, 8, 16}) {
        const Model m = read_model(tip_stop(dir, b, "r.toml", reduction(modes)));
        const testing::Outcome reduced = testing::simulate(m, 1.5, 0.0, testing::Solvers::interp);
        const double off = event_gap(reduced, exact);
        std::printf("%s, %2d modes: %zu events, within %.3g s of the full model's\n", m.reduction.method.c_str(), modes,
                    reduced.events.size(), off);
        EXPECT_LT(off, previous) << modes << " modes should follow the full model closer";
        previous = off;
        if (modes == 16) {
            EXPECT_LT(off, at16) << "16 modes (up to " << m.reduction.interface_omega.back() << " rad/s)";
            const testing::Outcome cvode = testing::baseline(m, 1.5, 1e-12, 1e-14, Method::cvode);
            const double to_cvode = event_gap(reduced, cvode);
            std::printf("the reduced model within %.3g s of CVODE on it\n", to_cvode);
            EXPECT_LT(to_cvode, 1e-9);
        }
    }
}

TEST(Reduction, ATipStopOnTheReducedCantileverFollowsTheFullModelAndCvode) {
    tip_stop_follows_the_full_model([](int modes) { return "[reduction]\nmodes = " + std::to_string(modes) + "\n"; },
                                    1e-6);
}

/// The lightly damped cantilever with a friction pad at w30 and stops at the
/// tip and at mid-span: every force jump of the pad (a reversal, a stick)
/// rings through all of the mesh's modes.
std::string pad_and_stops(const testing::TempDir& dir, const Beam& b, const std::string& file,
                          const std::string& reduction) {
    return structure_model(
        dir, file, "reduced-pad", b.M, b.K, b.dofs,
        "[damping]\nalpha = 0.0\nbeta = 1e-6\n"
        "[[forcing]]\nomega = 20.0\namplitude = { w40 = 2.0 }\n"
        "[[contact]]\nname = \"tip\"\nbetween = [\"w40\", \"ground\"]\ngap = 0.004\nk = 2000.0\n"
        "[[contact]]\nname = \"mid\"\nbetween = [\"ground\", \"w20\"]\ngap = 0.002\nk = 5000.0\n"
        "[[friction]]\nname = \"pad\"\nbetween = [\"w30\", \"ground\"]\nmu_k = 0.3\nmu_s = 0.4\nnormal = 2.0\n" +
            reduction);
}

/// Event times of two runs of models whose dofs are numbered differently:
/// the same kinds on the same elements (a mass by its name), the largest
/// time difference.
double named_event_gap(const Model& ma, const testing::Outcome& a, const Model& mb, const testing::Outcome& b) {
    EXPECT_EQ(a.events.size(), b.events.size());
    const auto element = [](const Model& m, const testing::Recorded& e) {
        const bool friction =
            e.kind == EventKind::stick || e.kind == EventKind::release || e.kind == EventKind::reversal;
        const auto i = static_cast<std::size_t>(e.element);
        if (!friction) return "contact " + std::to_string(e.element);
        return i < m.masses.size() ? m.masses[i].name : "jenkins " + std::to_string(i - m.masses.size());
    };
    double worst = 0.0;
    for (std::size_t e = 0; e < std::min(a.events.size(), b.events.size()); ++e) {
        EXPECT_EQ(a.events[e].kind, b.events[e].kind) << "event " << e;
        EXPECT_EQ(element(ma, a.events[e]), element(mb, b.events[e])) << "event " << e;
        worst = std::max(worst, std::fabs(a.events[e].t - b.events[e].t));
    }
    return worst;
}

TEST(Reduction, AFrictionPadAndTwoStopsOnTheReducedBeamFollowTheFullModelAndCvode) {
    // Friction at a boundary dof: the reduced model keeps w30's stick-slip
    // (releases, sticks, reversals) and both stops, event for event, with an
    // error that falls as modes are kept; the full model's switch search pays
    // for the mesh's stiff modes, the reduced one does not carry them.
    testing::TempDir dir;
    const Beam b = cantilever(kElements);
    const double t_end = 0.4;
    const Model full = read_model(pad_and_stops(dir, b, "full.toml", ""));
    const testing::Outcome exact = testing::simulate(full, t_end, 0.0, testing::Solvers::interp);
    ASSERT_GE(exact.events.size(), 10u);
    std::set<EventKind> kinds;
    for (const auto& e : exact.events) kinds.insert(e.kind);
    EXPECT_TRUE(kinds.count(EventKind::release) && kinds.count(EventKind::stick) &&
                kinds.count(EventKind::contact_close))
        << "the run should exercise the pad and the stops";
    const auto per_switch = [](const testing::Outcome& o) {
        return static_cast<double>(o.summary.evaluations) /
               static_cast<double>(std::max<std::size_t>(1, o.summary.events));
    };
    double previous = 1.0;
    for (const int modes : {12, 24, 48, 77}) {  // 77: every interior mode
        const Model m =
            read_model(pad_and_stops(dir, b, "r.toml", "[reduction]\nmodes = " + std::to_string(modes) + "\n"));
        EXPECT_EQ(m.dof(), static_cast<std::size_t>(3 + modes)) << "w20, w30, w40 and the modes";
        const testing::Outcome reduced = testing::simulate(m, t_end, 0.0, testing::Solvers::interp);
        const double off = named_event_gap(m, reduced, full, exact);
        std::printf(
            "%2d modes: %zu events (full %zu), within %.3g s of the full model's; %.1f evaluations per switch "
            "(full %.1f)\n",
            modes, reduced.events.size(), exact.events.size(), off, per_switch(reduced), per_switch(exact));
        EXPECT_LT(off, previous) << modes << " modes should follow the full model closer";
        previous = off;
        if (modes == 77) EXPECT_LT(off, 1e-10) << "every mode kept: the reduction is a change of basis";
        if (modes == 24) {
            const testing::Outcome cvode = testing::baseline(m, t_end, 1e-12, 1e-14, Method::cvode);
            const double to_cvode = event_gap(reduced, cvode);
            std::printf("the reduced model within %.3g s of CVODE on it\n", to_cvode);
            EXPECT_LT(to_cvode, 1e-8);
        }
    }
}

TEST(Reduction, AModelReadAgainReusesItsReductionAndAChangedOneDoesNot) {
    // K scaled by a factor no other test uses: this test's structure is new to the process.
    testing::TempDir dir;
    Beam b = cantilever(kElements);
    b.K *= 1.000123;
    const std::string reduced = "[parameters]\nw = 20.0\n[reduction]\nmodes = 5\n";
    std::string model = structure_model(dir, "m.toml", "memo", b.M, b.K, b.dofs,
                                        "[[forcing]]\nomega = \"w\"\namplitude = { w40 = 4.0 }\n"
                                        "[[contact]]\nname = \"stop\"\nbetween = [\"w40\", \"ground\"]\ngap = 0.01\nk = 2e4\n" +
                                            reduced);
    const ReductionMemoCounts c0 = reduction_memo_counts();
    const Model first = read_model(model);
    const ReductionMemoCounts c1 = reduction_memo_counts();
    EXPECT_EQ(c1.computed, c0.computed + 1);
    const Model again = read_model(model);
    const ReductionMemoCounts c2 = reduction_memo_counts();
    EXPECT_EQ(c2.computed, c1.computed) << "the same files and settings: no second reduction";
    EXPECT_EQ(c2.reused, c1.reused + 1);
    EXPECT_EQ(again.reduction.M, first.reduction.M);
    EXPECT_EQ(again.reduction.K, first.reduction.K);
    EXPECT_EQ(again.reduction.interface_omega, first.reduction.interface_omega);

    // A sweep reads its model once per point: one reduction for all of them.
    SweepOptions o;
    o.param = "w";
    o.from = 18.0;
    o.to = 22.0;
    o.points = 3;
    o.max_periods = 20;
    o.record_periods = 2;
    const SweepResult r = SweepPlan::from_file(model, {}, o).run();
    EXPECT_EQ(r.points.size(), 3u);
    const ReductionMemoCounts c3 = reduction_memo_counts();
    EXPECT_EQ(c3.computed, c2.computed) << "the sweep's points reduce nothing again";
    EXPECT_GE(c3.reused, c2.reused + 3);

    // One entry of K changed, or another number of modes: reduced anew.
    b.K(0, 0) *= 1.01;
    model = structure_model(dir, "m.toml", "memo", b.M, b.K, b.dofs,
                            "[[forcing]]\nomega = \"w\"\namplitude = { w40 = 4.0 }\n" + reduced);
    const Model changed = read_model(model);
    EXPECT_EQ(reduction_memo_counts().computed, c3.computed + 1);
    EXPECT_NE(changed.reduction.K, first.reduction.K);
    const std::string six = dir / "six.toml";
    fe::write(six, "name = \"memo\"\n[structure]\ndofs = " + dof_list(b.dofs) +
                       "\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n[[forcing]]\nomega = 20.0\namplitude = { w40 = 4.0 }\n"
                       "[reduction]\nmodes = 6\n");
    const Model six_modes = read_model(six);
    EXPECT_EQ(six_modes.dof(), 7u);
    EXPECT_EQ(reduction_memo_counts().computed, c3.computed + 2);
}

TEST(Reduction, AStructureWithMasslessRotationsReducesAndKeepsTheCondensedFrequencies) {
    // A lumped cantilever: half an element's mass on each w, none on the
    // rotations (zero rows of M). The interior's eigenproblem is then solved
    // as M phi = mu K phi (mu = 1/omega^2, 0 for the massless directions);
    // the frequencies against the test's own static condensation of the
    // rotations, and with every mode that has mass the reduced model is the
    // full one in another basis (the same events).
    testing::TempDir dir;
    const int elements = 20;
    Beam b = cantilever(elements);
    const double h = 1.0 / elements, rhoA = 2.0;
    b.M.setZero();
    for (int k = 0; k < elements; ++k) b.M(2 * k, 2 * k) = rhoA * h * (k + 1 < elements ? 1.0 : 0.5);
    const std::string sections = "[[forcing]]\nomega = 20.0\namplitude = { w20 = 2.0 }\n"
                                 "[[contact]]\nname = \"tip\"\nbetween = [\"w20\", \"ground\"]\ngap = 0.004\nk = 2000.0\n";
    // Condensed: K_ww - K_wt K_tt^-1 K_tw against the w masses.
    Eigen::MatrixXd Kww(elements, elements), Kwt(elements, elements), Ktt(elements, elements);
    for (int i = 0; i < elements; ++i)
        for (int j = 0; j < elements; ++j) {
            Kww(i, j) = b.K(2 * i, 2 * j);
            Kwt(i, j) = b.K(2 * i, 2 * j + 1);
            Ktt(i, j) = b.K(2 * i + 1, 2 * j + 1);
        }
    const Eigen::MatrixXd Kc = Kww - Kwt * Ktt.ldlt().solve(Kwt.transpose());
    Eigen::MatrixXd Mw = Eigen::MatrixXd::Zero(elements, elements);
    for (int i = 0; i < elements; ++i) Mw(i, i) = b.M(2 * i, 2 * i);
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(Kc, Mw, Eigen::EigenvaluesOnly);
    const Model full = read_model(structure_model(dir, "full.toml", "lumped", b.M, b.K, b.dofs, sections));
    const testing::Outcome exact = testing::simulate(full, 1.0, 0.0, testing::Solvers::interp);
    ASSERT_GE(exact.events.size(), 4u);
    for (const int modes : {5, 19}) {  // 19: every interior dof with mass (w1 ... w19)
        const Model m = read_model(
            structure_model(dir, "r.toml", "lumped", b.M, b.K, b.dofs,
                            sections + "[reduction]\nmodes = " + std::to_string(modes) + "\n"),
            with_frequencies());
        EXPECT_EQ(m.dof(), static_cast<std::size_t>(1 + modes));
        for (std::size_t k = 0; k < 5; ++k) {
            const double exact_omega = std::sqrt(es.eigenvalues()(static_cast<Eigen::Index>(k)));
            EXPECT_NEAR(m.reduction.open.full[k], exact_omega, 1e-9 * exact_omega) << "mode " << k + 1;
            EXPECT_GE(m.reduction.open.reduced[k], exact_omega * (1.0 - 1e-9)) << modes << " modes, mode " << k + 1;
        }
        if (modes == 19) {
            for (std::size_t k = 0; k < 5; ++k)
                EXPECT_NEAR(m.reduction.open.reduced[k], m.reduction.open.full[k], 1e-9 * m.reduction.open.full[k]);
            const testing::Outcome reduced = testing::simulate(m, 1.0, 0.0, testing::Solvers::interp);
            const double off = event_gap(reduced, exact);
            std::printf("massless rotations, every mode with mass: %zu events within %.3g s of the full model's\n",
                        reduced.events.size(), off);
            EXPECT_LT(off, 1e-10);
        }
    }
    // More modes than the interior has masses: refused, by name.
    const std::string many = structure_model(dir, "many.toml", "lumped", b.M, b.K, b.dofs,
                                             sections + "[reduction]\nmodes = 25\n");
    const testing::CliRun r = testing::run_hsnc("check " + many);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("modes = 25 but only 19 fixed-interface modes have mass"), std::string::npos) << r.err;
    // A cut-off above every mode keeps all that have mass.
    const Model all = read_model(structure_model(dir, "all.toml", "lumped", b.M, b.K, b.dofs,
                                                 sections + "[reduction]\ncutoff = 1e9\n"));
    EXPECT_EQ(all.dof(), 20u);
}

TEST(Reduction, TheClosedContactsFrequenciesAreThoseOfTheStiffenedStructure) {
    // Every contact closed: the stop's k on the tip added to K, in the full
    // structure (a dense eigensolve of the test's own K + k e e^T) and the reduced one.
    testing::TempDir dir;
    const Beam b = cantilever(kElements);
    const Model m = read_model(tip_stop(dir, b, "m.toml", "[reduction]\nmodes = 12\n"), with_frequencies());
    Eigen::MatrixXd K = b.K;
    const Eigen::Index tip = static_cast<Eigen::Index>(std::find(b.dofs.begin(), b.dofs.end(), "w40") - b.dofs.begin());
    K(tip, tip) += 2e4;
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(K, b.M, Eigen::EigenvaluesOnly);
    const auto& closed = m.reduction.closed;
    ASSERT_EQ(closed.full.size(), 10u) << closed.problem;
    ASSERT_EQ(closed.reduced.size(), 10u);
    for (std::size_t k = 0; k < 10; ++k) {
        const double exact = std::sqrt(es.eigenvalues()(static_cast<Eigen::Index>(k)));
        EXPECT_NEAR(closed.full[k], exact, 1e-9 * exact) << "mode " << k + 1;
        EXPECT_GE(closed.reduced[k], exact * (1.0 - 1e-9)) << "mode " << k + 1;
        EXPECT_GT(closed.full[k], m.reduction.open.full[k] * (1.0 - 1e-12)) << "a closed stop stiffens";
    }
    EXPECT_GT(closed.full[0], m.reduction.open.full[0] * 1.01);
    EXPECT_LT((closed.reduced[0] - closed.full[0]) / closed.full[0], 1e-5);
}

TEST(Reduction, TheCutoffKeepsEveryFixedInterfaceModeBelowIt) {
    testing::TempDir dir;
    const Beam b = cantilever(kElements);
    const Model ten = read_model(tip_stop(dir, b, "m.toml", "[reduction]\nmodes = 10\n"));
    const std::vector<double>& w = ten.reduction.interface_omega;
    const double cut = (w[5] + w[6]) / 2.0;  // between the 6th and 7th
    const Model m = read_model(tip_stop(dir, b, "c.toml", "[reduction]\ncutoff = " + num(cut) + "\n"));
    ASSERT_EQ(m.reduction.interface_omega.size(), 6u);
    for (std::size_t k = 0; k < 6; ++k) EXPECT_DOUBLE_EQ(m.reduction.interface_omega[k], w[k]);
}

TEST(Reduction, ReduceWritesAStructureThatGivesTheSameEventsBitForBit) {
    testing::TempDir dir;
    const Beam b = cantilever(kElements);
    const std::string model = tip_stop(dir, b, "m.toml", "[reduction]\nmodes = 6\n");
    const testing::CliRun r = testing::run_hsnc("reduce " + model + " -o " + (dir / "red"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("80 dofs -> 1 boundary dofs + 6 fixed-interface modes"), std::string::npos) << r.out;
    std::ifstream in(dir / "red/structure.toml");
    std::stringstream table;
    table << in.rdbuf();
    EXPECT_NE(table.str().find("dofs = [\"w40\", \"q1\", \"q2\", \"q3\", \"q4\", \"q5\", \"q6\"]"), std::string::npos)
        << table.str();
    // The same model with the written structure instead of the reduction.
    fe::write(dir / "red/again.toml",
              "name = \"reduced-cantilever\"\n" + table.str() +
                  "[damping]\nalpha = 0.5\nbeta = 1e-4\n[[forcing]]\nomega = 20.0\namplitude = { w40 = 4.0 }\n"
                  "[[contact]]\nname = \"stop\"\nbetween = [\"w40\", \"ground\"]\ngap = 0.01\nk = 2e4\n"
                  "[simulate]\nt_end = 1.5\n");
    const std::string a = testing::events_csv(model, "--kernels interp");
    const std::string c = testing::events_csv(dir / "red/again.toml", "--kernels interp");
    EXPECT_GT(std::count(a.begin(), a.end(), '\n'), 5);
    EXPECT_EQ(a, c);
    std::ifstream f(dir / "red/frequencies.csv");
    std::string header, first;
    std::getline(f, header);
    std::getline(f, first);
    EXPECT_EQ(header, "contacts,mode,omega_full,omega_reduced,relative_error");
    EXPECT_EQ(first.rfind("open,1,", 0), 0u) << first;
    // check reports the same comparison.
    const testing::CliRun chk = testing::run_hsnc("check " + model);
    ASSERT_EQ(chk.exit_code, 0) << chk.err;
    EXPECT_NE(chk.out.find("reduction: craig-bampton, 80 dofs -> 1 boundary dofs"), std::string::npos) << chk.out;
    EXPECT_NE(chk.out.find("lowest frequencies, rad/s, every contact open"), std::string::npos) << chk.out;
    EXPECT_NE(chk.out.find("lowest frequencies, rad/s, every contact closed"), std::string::npos) << chk.out;
}

TEST(Reduction, ALargeSparseStructureIsReadOnlyToBeReduced) {
    // A chain of 1200 springs and masses (beyond the 500 dofs hsnc solves):
    // refused as it is, reduced to its end dof and 8 modes it runs.
    testing::TempDir dir;
    const int n = 1200;
    std::ostringstream M, K, dofs;
    M << "%%MatrixMarket matrix coordinate real symmetric\n" << n << " " << n << " " << n << "\n";
    K << "%%MatrixMarket matrix coordinate real symmetric\n" << n << " " << n << " " << 2 * n - 1 << "\n";
    dofs << "[";
    for (int i = 1; i <= n; ++i) {
        M << i << " " << i << " 0.001\n";
        K << i << " " << i << " " << (i < n ? 2.0e4 : 1.0e4) << "\n";
        if (i > 1) K << i << " " << i - 1 << " -1e4\n";
        dofs << (i > 1 ? ", " : "") << "\"u" << i << "\"";
    }
    dofs << "]";
    fe::write(dir / "M.mtx", M.str());
    fe::write(dir / "K.mtx", K.str());
    const std::string head = "name = \"long-chain\"\n[structure]\ndofs = " + dofs.str() +
                             "\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n[load]\nu1200 = 1.0\n";
    fe::write(dir / "plain.toml", head);
    const testing::CliRun plain = testing::run_hsnc("check " + (dir / "plain.toml"));
    EXPECT_EQ(plain.exit_code, 2);
    EXPECT_NE(plain.err.find("structure.dofs"), std::string::npos) << plain.err;
    fe::write(dir / "reduced.toml", head + "[reduction]\nmodes = 8\n");
    const Model m = read_model(dir / "reduced.toml", with_frequencies());
    EXPECT_EQ(m.dof(), 9u);
    // The chain's frequencies in closed form: omega_k = 2 sqrt(k/m) sin((2k-1) pi / (2 (2n + 1))).
    for (std::size_t k = 0; k < 3; ++k) {
        const double exact = 2.0 * std::sqrt(1e4 / 1e-3) * std::sin((2.0 * static_cast<double>(k) + 1.0) * M_PI / (2.0 * (2 * n + 1)));
        EXPECT_NEAR(m.reduction.open.full[k], exact, 1e-9 * exact) << "mode " << k + 1;
        EXPECT_GE(m.reduction.open.reduced[k], exact * (1.0 - 1e-11));
        EXPECT_NEAR(m.reduction.open.reduced[k], exact, 1e-3 * exact) << "mode " << k + 1;
    }
    // The same names from a file, one per line (a comment and a blank line skipped).
    std::string names = "# the chain's dofs\n\n";
    for (int i = 1; i <= n; ++i) names += "u" + std::to_string(i) + "\n";
    fe::write(dir / "dofs.txt", names);
    fe::write(dir / "file.toml", "name = \"long-chain\"\n[structure]\ndofs = \"dofs.txt\"\nmass = \"M.mtx\"\n"
                                 "stiffness = \"K.mtx\"\n[load]\nu1200 = 1.0\n[reduction]\nmodes = 8\n");
    const Model f = read_model(dir / "file.toml", with_frequencies());
    EXPECT_EQ(f.reduction.M, m.reduction.M);
    EXPECT_EQ(f.reduction.K, m.reduction.K);
    EXPECT_EQ(f.reduction.open.full, m.reduction.open.full);
    fe::write(dir / "dofs.txt", "u1\nu2\nnot a name\n");
    const testing::CliRun bad = testing::run_hsnc("check " + (dir / "file.toml"));
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_NE(bad.err.find("key 'structure.dofs': dofs.txt:3: 'not a name' is not a valid name"), std::string::npos)
        << bad.err;
}

TEST(Reduction, WhatCannotBeReducedIsRefusedByName) {
    testing::TempDir dir;
    const Beam b = cantilever(4);
    auto refused = [&](const std::string& reduction, const std::string& key, const std::string& words) {
        const std::string model = structure_model(dir, "bad.toml", "bad", b.M, b.K, b.dofs,
                                                  "[load]\nw4 = 1.0\n" + reduction);
        const testing::CliRun r = testing::run_hsnc("check " + model);
        EXPECT_EQ(r.exit_code, 2) << reduction;
        EXPECT_NE(r.err.find("key '" + key + "'"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find(words), std::string::npos) << r.err;
    };
    refused("[reduction]\nmodes = 3\ncutoff = 10.0\n", "reduction", "exactly one of 'modes'");
    refused("[reduction]\n", "reduction", "exactly one of 'modes'");
    refused("[reduction]\nmodes = 9\n", "reduction", "more than the 7 interior dofs");
    refused("[reduction]\nmodes = -1\n", "reduction.modes", "integer >= 0");
    refused("[reduction]\ncutoff = -5.0\n", "reduction.cutoff", "> 0");
    refused("[reduction]\nmodes = 2\nmethod = \"guyan\"\n", "reduction.method", "\"craig-bampton\" or \"rubin\"");
    refused("[reduction]\nmodes = 2\nboundary = [\"w9\"]\n", "reduction.boundary[1]", "not a dof");
    // w1..w3 are interior (gone); w4 is the boundary dof the load names.
    refused("[reduction]\nmodes = 4\nprefix = \"w\"\n", "reduction.prefix", "'w4' is already the name");
    refused("[reduction]\nmodes = 2\nbogus = 1\n", "reduction.bogus", "");
    // No [structure] to reduce.
    fe::write(dir / "masses.toml", "name = \"m\"\n[[mass]]\nname = \"a\"\nm = 1.0\n[reduction]\nmodes = 1\n");
    const testing::CliRun r = testing::run_hsnc("check " + (dir / "masses.toml"));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("reduces a [structure]"), std::string::npos) << r.err;
    // reduce into the model's own folder would replace its M.mtx: exit 2, the input as it was.
    const std::string ok = structure_model(dir, "ok.toml", "ok", b.M, b.K, b.dofs, "[load]\nw4 = 1.0\n[reduction]\nmodes = 2\n");
    std::ifstream before_file(dir / "M.mtx");
    const std::string before((std::istreambuf_iterator<char>(before_file)), std::istreambuf_iterator<char>());
    const testing::CliRun own = testing::run_hsnc("reduce " + ok + " -o " + dir.path());
    EXPECT_EQ(own.exit_code, 2);
    EXPECT_NE(own.err.find("M.mtx"), std::string::npos) << own.err;
    std::ifstream after_file(dir / "M.mtx");
    const std::string after((std::istreambuf_iterator<char>(after_file)), std::istreambuf_iterator<char>());
    EXPECT_EQ(before, after);
    EXPECT_FALSE(std::ifstream(dir / "dofs.csv").good()) << "no file of a failed reduce";
    // reduce on a model without [reduction]: exit 2, nothing written.
    const std::string plain = structure_model(dir, "plain.toml", "plain", b.M, b.K, b.dofs, "");
    const testing::CliRun p = testing::run_hsnc("reduce " + plain + " -o " + (dir / "out"));
    EXPECT_EQ(p.exit_code, 2);
    EXPECT_NE(p.err.find("no [reduction]"), std::string::npos) << p.err;
}

TEST(Reduction, AFloatingInteriorIsRefusedWithTheRemedy) {
    // Two separate chains; only the first has a named dof: the second moves
    // rigidly once the boundary is held.
    testing::TempDir dir;
    Eigen::MatrixXd M = Eigen::MatrixXd::Identity(4, 4), K = Eigen::MatrixXd::Zero(4, 4);
    K << 2, -1, 0, 0, -1, 1, 0, 0, 0, 0, 1, -1, 0, 0, -1, 1;
    const std::string model = structure_model(dir, "f.toml", "floating", M, K, {"a", "b", "c", "d"},
                                              "[load]\nb = 1.0\n[reduction]\nmodes = 1\n");
    const testing::CliRun r = testing::run_hsnc("check " + model);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("K_II"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("[reduction].boundary"), std::string::npos) << r.err;
}

TEST(Reduction, AHex8PlateWithATipStopReducesToItsCornerAndModes) {
    // A clamped steel plate 0.5 x 0.1 x 0.01 m of 20 x 4 x 2 bricks (900
    // dofs), its free corner's z against a stop: the full structure's
    // frequencies (sparse Lanczos) against a dense eigensolve of the same
    // matrices, the reduced ones above them and close, and the reduced
    // model's events against CVODE on it.
    testing::TempDir dir;
    const Solid s = hex8_plate(20, 4, 2, 0.5, 0.1, 0.01);
    ASSERT_EQ(s.dofs.size(), 900u);
    write_market(dir / "M.mtx", s.M);
    write_market(dir / "K.mtx", s.K);
    const std::string tip = s.dofs[s.tip];
    fe::write(dir / "plate.toml", solid_structure("hex8-plate", s) +
                                      "[damping]\nalpha = 1.0\nbeta = 1e-5\n"
                                      "[[forcing]]\nomega = 350.0\namplitude = { " + tip + " = 100.0 }\n"
                                      "[[contact]]\nname = \"stop\"\nbetween = [\"" + tip + "\", \"ground\"]\n"
                                      "gap = 0.002\nk = 1e6\n[simulate]\nt_end = 0.3\n[reduction]\nmodes = 24\n");
    const Model m = read_model(dir / "plate.toml", with_frequencies());
    ASSERT_EQ(m.dof(), 25u);
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(Eigen::MatrixXd(s.K), Eigen::MatrixXd(s.M),
                                                                        Eigen::EigenvaluesOnly);
    // The dense solve is backward stable: lambda_k is known to a few
    // eps lambda_max (4 eps lambda_max/lambda_k relative, half that in omega),
    // which for this plate (lambda_max/lambda_1 ~ 1e8) is ~5e-8 at mode 1: the
    // reference, not the sparse solve, sets the tolerance. (Against an
    // inverse-iteration Rayleigh quotient, scipy's eigsh and LAPACK's dsygv
    // the sparse value of mode 1 was within 1e-9; Eigen's dense one 2e-9 off.)
    const double lam_max = es.eigenvalues().maxCoeff();
    double worst = 0.0;
    for (std::size_t k = 0; k < m.reduction.open.full.size(); ++k) {
        const double lam = es.eigenvalues()(static_cast<Eigen::Index>(k)), exact = std::sqrt(lam);
        const double known = std::max(1e-12, 2 * std::numeric_limits<double>::epsilon() * lam_max / lam) * exact;
        EXPECT_NEAR(m.reduction.open.full[k], exact, known) << "mode " << k + 1;
        EXPECT_GE(m.reduction.open.reduced[k], exact - known) << "mode " << k + 1;
        if (k < 3) worst = std::max(worst, (m.reduction.open.reduced[k] - exact) / exact);
    }
    std::printf("the plate's lowest three frequencies (%.4g, %.4g, %.4g rad/s) reduced within %.3g relative\n",
                m.reduction.open.full[0], m.reduction.open.full[1], m.reduction.open.full[2], worst);
    EXPECT_LT(worst, 1e-3);
    const testing::Outcome reduced = testing::simulate(m, 0.3, 0.0, testing::Solvers::interp);
    ASSERT_GE(reduced.events.size(), 4u) << "the corner should reach the stop";
    const testing::Outcome cvode = testing::baseline(m, 0.3, 1e-12, 1e-14, Method::cvode);
    const double off = event_gap(reduced, cvode);
    std::printf("%zu events, within %.3g s of CVODE on the reduced plate\n", reduced.events.size(), off);
    EXPECT_LT(off, 1e-9);
}

TEST(Reduction, ADuplicateEntryOfALargeFileIsNamedByItsLine) {
    std::ostringstream text;
    text << "%%MatrixMarket matrix coordinate real general\n600 600 3\n1 1 1.0\n600 2 3.0\n1 1 2.0\n";
    try {
        parse_sparse_matrix_market(text.str(), "big.mtx");
        FAIL() << "a duplicate entry was accepted";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), "big.mtx:5: entry (1, 1) is given twice");
    }
}

// Rubin's free-interface reduction (method = "rubin"). The cantilever's
// tip is its only boundary dof, so its free-interface modes are the full
// beam's own: the reduced model must have them exactly (they lie in its
// basis), bound the others from above, and keep the static tip
// flexibility L^3 / (3 EI) exactly (the residual flexibility).
std::string rubin_reduction(int modes) {
    return "[reduction]\nmethod = \"rubin\"\nmodes = " + std::to_string(modes) + "\n";
}

TEST(Rubin, TheKeptFreeModesAreTheFullBeamsOwnAndTheRestBoundItFromAbove) {
    testing::TempDir dir;
    const Beam b = cantilever(kElements);
    const Eigen::VectorXd full = full_omegas(b);
    for (const int modes : {2, 5, 9}) {
        const Model m = read_model(tip_stop(dir, b, "m.toml", rubin_reduction(modes)), with_frequencies());
        ASSERT_EQ(m.dof(), static_cast<std::size_t>(1 + modes));
        EXPECT_EQ(m.masses[0].name, "w40");
        EXPECT_EQ(m.masses[1].name, "q1");
        EXPECT_EQ(m.reduction.method, "rubin");
        ASSERT_EQ(m.reduction.interface_omega.size(), static_cast<std::size_t>(modes));
        for (int k = 0; k < modes; ++k)
            EXPECT_NEAR(m.reduction.interface_omega[static_cast<std::size_t>(k)], full(k), 1e-9 * full(k)) << k;
        const std::vector<double>& reduced = m.reduction.open.reduced;
        ASSERT_GE(reduced.size(), static_cast<std::size_t>(modes + 1));
        for (std::size_t k = 0; k < reduced.size(); ++k) {
            const double exact = full(static_cast<Eigen::Index>(k));
            if (k < static_cast<std::size_t>(modes))
                EXPECT_NEAR(reduced[k], exact, 1e-9 * exact) << modes << " modes: mode " << k + 1 << " is kept";
            else
                EXPECT_GE(reduced[k], exact * (1.0 - 1e-9)) << modes << " modes, mode " << k + 1;
        }
        // The first mode not kept: the residual flexibility's (upper) estimate of it.
        std::printf("%d free-interface modes: mode %d within %.3g relative\n", modes, modes + 1,
                    (reduced[static_cast<std::size_t>(modes)] - full(modes)) / full(modes));
    }
}

TEST(Rubin, TheStaticTipFlexibilityIsKeptAndTheResponseErrorShrinks) {
    testing::TempDir dir;
    const Beam b = cantilever(kElements);
    for (const int modes : {0, 3}) {  // 0: the residual flexibility alone (static condensation to the tip)
        const Model m = read_model(tip_stop(dir, b, "m.toml", rubin_reduction(modes)));
        const auto n = static_cast<Eigen::Index>(m.dof());
        const Eigen::MatrixXd K =
            Eigen::Map<const Eigen::Matrix<double, -1, -1, Eigen::RowMajor>>(m.reduction.K.data(), n, n);
        // Rubin's K_r carries the flexibility F_BB = (K^-1)_BB as the sparse
        // LDL^T solves it, cond(K) ~ 1e9 (Craig-Bampton's Schur complement
        // avoids that solve: 1e-12): 6e-11 measured.
        EXPECT_NEAR(K.inverse()(0, 0), 1.0 / 300.0, 2e-10 / 300.0) << modes << " modes";
    }
    // Forced at the tip, at 20 rad/s (below the first mode, 35 rad/s): the
    // kept modes are exact and the residual flexibility carries the rest, so
    // two free-interface modes already give the response to the rounding of
    // the two LU solves (~5e-10), where two fixed-interface modes miss it by
    // 1.4e-4 (README's table).
    const auto response_error = [&](const std::string& reduction) {
        const Model m = read_model(tip_stop(dir, b, "m.toml", reduction + "[load]\nw40 = 0.3\n"), with_frequencies());
        EXPECT_EQ(m.reduction.response.size(), 2u);
        if (m.reduction.response.size() != 2u) return 1.0;
        EXPECT_LT(m.reduction.response[0].error, 1e-9) << reduction << ": the static response is kept";
        return m.reduction.response[1].error;
    };
    const double craig_bampton = response_error("[reduction]\nmodes = 2\n");
    for (const int modes : {2, 5, 20}) {
        const double error = response_error(rubin_reduction(modes));
        std::printf("%2d free-interface modes: tip response error %.3g at 20 rad/s (2 fixed-interface: %.3g)\n", modes,
                    error, craig_bampton);
        EXPECT_LT(error, 5e-9) << modes << " modes";
        EXPECT_LT(error, 1e-4 * craig_bampton) << modes << " modes";
    }
    const auto r = testing::run_hsnc("check '" + tip_stop(dir, b, "m.toml", rubin_reduction(5)) + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(
        r.out.find("reduction: rubin, 80 dofs -> 1 boundary dofs (those the model names) + 5 free-interface modes"),
        std::string::npos)
        << r.out;
    const auto reduce = testing::run_hsnc("reduce '" + (dir / "m.toml") + "' -o '" + (dir / "out") + "'");
    ASSERT_EQ(reduce.exit_code, 0) << reduce.err;
    EXPECT_NE(reduce.out.find("80 dofs -> 1 boundary dofs + 5 free-interface modes"), std::string::npos) << reduce.out;
    EXPECT_NE(testing::slurp(dir / "out/structure.toml").find(": rubin, 80 dofs"), std::string::npos);
}

TEST(Rubin, ATipStopOnTheRubinReducedCantileverFollowsTheFullModelAndCvode) {
    // Closer than Craig-Bampton for the same modes: 1.8e-11 s with 16 (1.5e-7 s).
    tip_stop_follows_the_full_model(rubin_reduction, 1e-9);
}

TEST(Rubin, WhatRubinCannotReduceIsRefusedByName) {
    testing::TempDir dir;
    auto refused = [&](const Eigen::MatrixXd& M, const Eigen::MatrixXd& K, const std::vector<std::string>& dofs,
                       const std::string& reduction, const std::string& words) {
        const std::string model =
            structure_model(dir, "bad.toml", "bad", M, K, dofs, "[load]\n" + dofs.back() + " = 1.0\n" + reduction);
        const testing::CliRun r = testing::run_hsnc("check " + model);
        EXPECT_EQ(r.exit_code, 2) << reduction;
        EXPECT_NE(r.err.find("key 'reduction'"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find(words), std::string::npos) << r.err;
    };
    // A free chain: K singular.
    Eigen::MatrixXd M = Eigen::MatrixXd::Identity(4, 4), K(4, 4);
    K << 1, -1, 0, 0, -1, 2, -1, 0, 0, -1, 2, -1, 0, 0, -1, 1;
    refused(M, K, {"a", "b", "c", "d"}, rubin_reduction(1), "Rubin's method needs a supported structure");
    const Beam b = cantilever(4);
    refused(b.M, b.K, b.dofs, rubin_reduction(8), "more than the 7 interior dofs");
    // Three springs to ground: the lowest mode is the boundary dof a alone,
    // so keeping it leaves a no residual flexibility (G_BB = 0 exactly).
    const Eigen::MatrixXd I3 = Eigen::MatrixXd::Identity(3, 3);
    const Eigen::MatrixXd K3 = Eigen::Vector3d(2.0, 3.0, 1.0).asDiagonal();  // b, c, a
    refused(I3, K3, {"b", "c", "a"}, rubin_reduction(1), "residual flexibility of the boundary is singular");
}

}  // namespace
}  // namespace hsnc
