// Structures with a coupled mass matrix (issue 36, stage b; interface.md
// section 5): consistent-mass finite elements, kept whole, never lumped.
//
// Checked against what the code does not compute itself:
//  - a consistent-mass Euler-Bernoulli cantilever (w and theta per node,
//    assembled here from the element matrices), forced at its tip: from the
//    steady state of its own M, C, K (the complex frequency response solved
//    here) the motion stays on it, to 1e-9 of its amplitude, with Rayleigh
//    and with non-proportional damping;
//  - the same beam against a tip stop: the events of CVODE at rtol 1e-12;
//  - a free-free consistent-mass bar hitting a wall: its momentum between
//    impacts (the rigid-body mode, decided structurally) and CVODE's events;
//  - a lumped model whose diagonal M goes through the coupled path gives the
//    lumped path's events to 1e-13 s.
//  - the CLN reference (Cholesky of M at N digits) at 30 and 60 digits, and
//    the double engine against it to 1e-11 s.
//  - friction against the ground on a coupled M: two frictions and a stop on
//    three lumped masses written in relative coordinates (M coupled) give the
//    lumped model's events (1e-12 s) and CVODE's.
// And what is not yet taken is refused by name (friction between two dofs of
// a coupled M, friction there in the reference and the tangent, the reference
// under non-proportional damping).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "assembly.h"
#include "cli_runner.h"
#include "derivation.h"
#include "engine_runner.h"
#include "fe_models.h"
#include "flow.h"
#include "interpreted_solver.h"
#include "lowering.h"
#include "modal.h"
#include "model_reader.h"
#include "reference_engine.h"
#include "sample_models.h"
#include "segment_start.h"
#include "shooting.h"
#include "temp_dir.h"

namespace hsnc {
namespace {

using cplx = std::complex<double>;

using namespace fe;  // the test structures (fe_models.h)

/// The beam forced at its tip, F sin(omega t), started on its steady state
/// X = (K - omega^2 M + i omega C)^-1 F (x = Im(X e^{i omega t})). Damping:
/// Rayleigh (alpha, beta) or, when `C` is given, that matrix.
struct Forced {
    std::string path;
    Eigen::VectorXcd X;
    double omega;
};

Forced forced_beam(const testing::TempDir& dir, const Beam& b, double omega, double F, const std::string& extra,
                   const Eigen::MatrixXd* C = nullptr) {
    const double alpha = 0.2, beta = 5e-4;
    const Eigen::Index n = b.M.rows();
    const Eigen::MatrixXd Cm = C ? *C : Eigen::MatrixXd(alpha * b.M + beta * b.K);
    Eigen::VectorXcd f = Eigen::VectorXcd::Zero(n);
    f(b.tip) = F;
    const Eigen::MatrixXcd Z = (b.K - omega * omega * b.M).cast<cplx>() + cplx(0.0, omega) * Cm.cast<cplx>();
    const Eigen::VectorXcd X = Z.partialPivLu().solve(f);
    write(dir / "M.mtx", market(b.M));
    write(dir / "K.mtx", market(b.K));
    std::string damping;
    if (C) {
        write(dir / "C.mtx", market(*C));
        damping = "damping = \"C.mtx\"\n";
    }
    std::ostringstream t;
    t << "name = \"consistent-cantilever\"\n[structure]\ndofs = " << dof_list(b.dofs)
      << "\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n"
      << damping << (C ? "" : "[damping]\nalpha = " + num(alpha) + "\nbeta = " + num(beta) + "\n")
      << "[[forcing]]\nomega = " << num(omega) << "\namplitude = { " << b.dofs[static_cast<std::size_t>(b.tip)]
      << " = " << num(F) << " }\n"
      << "[initial]\nx = " << table(b.dofs, X.imag()) << "\nv = " << table(b.dofs, omega * X.real()) << "\n"
      << extra;
    write(dir / "beam.toml", t.str());
    return {dir / "beam.toml", X, omega};
}

/// The 4-element cantilever forced at 15 rad/s against a stop 4 mm above its tip.
Forced beam_with_stop(const testing::TempDir& dir) {
    return forced_beam(dir, cantilever(4), 15.0, 5.0,
                       "[[contact]]\nname = \"stop\"\nbetween = [\"w4\", \"ground\"]\ngap = 0.004\nk = 2000.0\n");
}

/// Largest |x(t) - Im(X e^{i omega t})| over the samples, against max |X|.
double off_steady_state(const testing::Outcome& run, const Forced& f) {
    double worst = 0.0;
    for (const testing::Recorded& s : run.samples)
        for (Eigen::Index i = 0; i < f.X.size(); ++i) {
            const double exact = (f.X(i) * std::exp(cplx(0.0, f.omega * s.t))).imag();
            worst = std::max(worst, std::fabs(s.x[static_cast<std::size_t>(i)] - exact));
        }
    return worst / f.X.cwiseAbs().maxCoeff();
}

TEST(CoupledMass, ConsistentCantileverStaysOnItsFrequencyResponse) {
    testing::TempDir dir;
    const Beam b = cantilever(6);
    const Forced f = forced_beam(dir, b, 40.0, 5.0, "");
    const Model model = read_model(f.path);
    ASSERT_TRUE(model.coupled_mass());
    ASSERT_GT(model.mass_floor, 0.0);
    for (testing::Solvers s : {testing::Solvers::generic, testing::Solvers::interp}) {
        const testing::Outcome run = testing::simulate(model, 2.0, 0.01, s);
        ASSERT_EQ(run.samples.size(), 201u);
        const double off = off_steady_state(run, f);
        std::printf("%s: off the steady state by %.3g of its amplitude\n", testing::solvers_name(s), off);
        EXPECT_LT(off, 1e-9);
    }
}

TEST(CoupledMass, NonProportionalDampingOnAConsistentMassStaysOnItsFrequencyResponse) {
    testing::TempDir dir;
    const Beam b = clamped_bar(3);
    // A dashpot at the tip and one between u1 and u2 on top of Rayleigh: no
    // longer a combination of M and K (the state-space solver). A beam's
    // spread of frequencies is beyond that solver's conditioning (its
    // eigenvector condition exceeds 200: the matrix exponential would take it).
    Eigen::MatrixXd C = 0.2 * b.M + 1e-5 * b.K;
    C(2, 2) += 2.0;
    C(0, 0) += 5.0, C(1, 1) += 5.0, C(0, 1) -= 5.0, C(1, 0) -= 5.0;
    const Forced f = forced_beam(dir, b, 120.0, 40.0, "", &C);
    const Model model = read_model(f.path);
    ASSERT_TRUE(model.coupled_mass());
    ASSERT_FALSE(model.proportional_damping());
    // The Eigen solver's state-space modes in double, and the derivation's in
    // double-double (M_F^-1 K, M_F^-1 C through the Cholesky factor of M_F).
    for (testing::Solvers s : {testing::Solvers::generic, testing::Solvers::interp}) {
        const testing::Outcome run = testing::simulate(model, 1.0, 0.005, s);
        const double off = off_steady_state(run, f);
        std::printf("state space, %s: off the steady state by %.3g of its amplitude\n", testing::solvers_name(s), off);
        EXPECT_LT(off, 1e-9);
    }
    EXPECT_TRUE(derive(model, Configuration::all_open(model)).state_space);
}

TEST(CoupledMass, CantileverWithATipStopGivesTheEventsOfCvode) {
    testing::TempDir dir;
    const Forced f = beam_with_stop(dir);
    const Model model = read_model(f.path);
    const testing::Outcome exact = testing::simulate(model, 3.0);
    ASSERT_GE(exact.events.size(), 20u) << "the stop should close and open";
    const testing::Outcome cvode = testing::baseline(model, 3.0, 1e-12, 1e-14, Method::cvode);
    const double gap = event_gap(exact, cvode);
    std::printf("%zu events, CVODE at rtol 1e-12 within %.3g s\n", exact.events.size(), gap);
    EXPECT_LT(gap, 1e-9);
    // The programs (double-double derivation, derivation.cpp) take the coupled M
    // themselves: the same events as the Eigen solver's modal analysis in double.
    const testing::Outcome interp = testing::simulate(model, 3.0, 0.0, testing::Solvers::interp);
    const double programs = event_gap(exact, interp);
    std::printf("the programs within %.3g s of the Eigen solver\n", programs);
    EXPECT_LT(programs, 1e-11);
    EXPECT_GT(programs, 0.0) << "the same bits as the Eigen solver: the programs handed it the coupled M";
}

/// The double-double derivation's modes of cfg checked in double against the
/// model's own K and M: |V^T M V - I|, |K V - M V Lambda| / |K|, |W - V^T M| / |M|
/// (the modal rows), and the eigenvalues ascending.
struct ModalResiduals {
    double orth, eig, rows;
    bool ascending;
};
ModalResiduals modal_residuals(const Model& model, const Configuration& cfg) {
    const Derivation d = derive(model, cfg);
    const std::size_t n = model.dof();
    EXPECT_EQ(d.free_dofs.size(), n);
    EXPECT_EQ(d.modes.size(), n);
    const Eigen::MatrixXd K = stiffness_matrix(model, cfg);
    Eigen::MatrixXd M(n, n), V(n, n), W(n, n);
    Eigen::VectorXd lambda(n);
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j) M(i, j) = model.mass_entry(i, j);
    for (std::size_t j = 0; j < n; ++j) {
        lambda(j) = d.modes[j].lambda.to_double();
        for (std::size_t r = 0; r < n; ++r) V(r, j) = d.modes[j].v[r].to_double(), W(j, r) = d.modes[j].w[r].to_double();
    }
    ModalResiduals out{(V.transpose() * M * V - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff(),
                       (K * V - M * V * lambda.asDiagonal()).cwiseAbs().maxCoeff() / K.cwiseAbs().maxCoeff(),
                       (W - V.transpose() * M).cwiseAbs().maxCoeff() / M.cwiseAbs().maxCoeff(), true};
    for (std::size_t j = 1; j < n; ++j) out.ascending = out.ascending && lambda(j - 1) < lambda(j);
    std::printf("%s: |V'MV - I| %.3g, |KV - MV L|/|K| %.3g, |W - V'M|/|M| %.3g\n", cfg.spec(model).c_str(), out.orth,
                out.eig, out.rows);
    return out;
}

TEST(CoupledMass, TheDoubleDoubleDerivationSolvesTheGeneralizedEigenproblem) {
    testing::TempDir dir;
    const Forced f = beam_with_stop(dir);
    const Model model = read_model(f.path);
    ASSERT_TRUE(model.coupled_mass());
    Configuration closed = Configuration::all_open(model);
    closed.closed[0] = 1;
    for (const Configuration& cfg : {Configuration::all_open(model), closed}) {
        const ModalResiduals r = modal_residuals(model, cfg);
        EXPECT_LT(r.orth, 1e-13);
        EXPECT_LT(r.eig, 1e-13);
        EXPECT_LT(r.rows, 1e-14);
        EXPECT_TRUE(r.ascending);
    }
}

#if HSNC_WITH_JIT
TEST(CoupledMass, CompiledKernelsOfACoupledMWriteTheInterpretersBytes) {
    testing::TempDir dir;
    const Forced f = beam_with_stop(dir);
    const std::string flags = "--t-end 1 --no-cache --kernels ";
    const std::string interp = testing::events_csv(f.path, flags + "interp");
    ASSERT_GT(std::count(interp.begin(), interp.end(), '\n'), 5);
    EXPECT_EQ(testing::events_csv(f.path, flags + "jit"), interp);
}
#endif

TEST(CoupledMass, ADashpotOnAClampedBarWithATipStopGivesTheEventsOfCvodeOnThePrograms) {
    // Non-proportional damping on a coupled M: the derivation's state-space
    // modes (double-double, through the Cholesky factor of M_F) in every
    // configuration, open and closed.
    // A clamped bar: a bending beam's spread of frequencies is beyond the state
    // space's conditioning limit (its eigenvector condition above 200), which the
    // Eigen solver's matrix exponential would take.
    testing::TempDir free_dir, dir;
    const Beam b = clamped_bar(3);
    Eigen::MatrixXd C = 0.2 * b.M + 1e-5 * b.K;
    C(b.tip, b.tip) += 2.0;
    const double reach = std::abs(forced_beam(free_dir, b, 120.0, 40.0, "", &C).X(b.tip));  // without the stop
    const Forced f = forced_beam(dir, b, 120.0, 40.0,
                                 "[[contact]]\nname = \"stop\"\nbetween = [\"" + b.dofs[static_cast<std::size_t>(b.tip)] +
                                     "\", \"ground\"]\ngap = " + std::to_string(0.5 * reach) + "\nk = 5e4\n",
                                 &C);
    const Model model = read_model(f.path);
    ASSERT_FALSE(model.proportional_damping());
    Configuration closed = Configuration::all_open(model);
    closed.closed[0] = 1;
    EXPECT_TRUE(derive(model, Configuration::all_open(model)).state_space);
    EXPECT_TRUE(derive(model, closed).state_space);
    const testing::Outcome programs = testing::simulate(model, 3.0, 0.0, testing::Solvers::interp);
    ASSERT_GE(programs.events.size(), 10u) << "the stop should close and open";
    const testing::Outcome cvode = testing::baseline(model, 3.0, 1e-12, 1e-14, Method::cvode);
    const testing::Outcome eigen = testing::simulate(model, 3.0);
    const double gap = event_gap(programs, cvode), apart = event_gap(programs, eigen);
    std::printf("%zu events: the programs within %.3g s of CVODE (rtol 1e-12), %.3g s of the Eigen solver\n",
                programs.events.size(), gap, apart);
    EXPECT_LT(gap, 1e-9);
    EXPECT_LT(apart, 1e-11);
}

TEST(CoupledMass, CantileverWithATipStopGivesTheEventsOfTheReference) {
    // The reference solves K phi = lambda M phi at N digits (Cholesky of M_F):
    // at 30 and at 60 digits it agrees with itself far below the double
    // engine's rounding, and the double engine agrees with it to 1e-11 s.
    testing::TempDir dir;
    const Forced f = beam_with_stop(dir);
    const Model model = read_model(f.path);
    const testing::Outcome exact = testing::simulate(model, 3.0);
    ASSERT_GE(exact.events.size(), 20u);
    const std::vector<testing::Recorded> r30 = reference_events(model, 30, 3.0), r60 = reference_events(model, 60, 3.0);
    const double self = event_gap(r30, r60), gap = event_gap(exact.events, r30);
    std::printf("%zu events: the double engine within %.3g s of the reference, 30 against 60 digits %.3g s\n",
                exact.events.size(), gap, self);
    EXPECT_LT(self, 1e-20);
    EXPECT_LT(gap, 1e-11);
    const double programs = event_gap(testing::simulate(model, 3.0, 0.0, testing::Solvers::interp).events, r30);
    std::printf("the programs (double-double derivation) within %.3g s of the reference\n", programs);
    EXPECT_LT(programs, 1e-11);
}

/// The free-free bar (axial_bar), its left end 1 cm from a wall, moving towards it.
std::string free_bar(const testing::TempDir& dir, int elements, bool dampers) {
    const auto [M, K] = axial_bar(elements);
    const int n = elements + 1;
    write(dir / "M.mtx", market(M));
    write(dir / "K.mtx", market(K));
    std::vector<std::string> dofs;
    Eigen::VectorXd x0(n), v0 = Eigen::VectorXd::Constant(n, -0.5);
    for (int i = 0; i < n; ++i) dofs.push_back("u" + std::to_string(i + 1)), x0(i) = 1e-3 * std::sin(2.0 * i);
    std::string damping;
    if (dampers) {  // dashpots between neighbours: no damping of the translation
        Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n, n);
        for (int e = 0; e < elements; ++e) C.block(e, e, 2, 2) += 0.5 * (Eigen::Matrix2d() << 1, -1, -1, 1).finished();
        write(dir / "C.mtx", market(C));
        damping = "damping = \"C.mtx\"\n";
    }
    std::ostringstream t;
    t << "name = \"free-bar\"\n[structure]\ndofs = " << dof_list(dofs) << "\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n"
      << damping << "[[contact]]\nname = \"wall\"\nbetween = [\"ground\", \"u1\"]\ngap = 0.01\nk = 5e4\n"
      << "[initial]\nx = " << table(dofs, x0) << "\nv = " << table(dofs, v0) << "\n";
    write(dir / "bar.toml", t.str());
    return dir / "bar.toml";
}

TEST(CoupledMass, FreeBarKeepsItsMomentumBetweenImpactsAndGivesTheEventsOfCvode) {
    // On the Eigen solver and on the programs (the derivation's rigid-body mode
    // of a coupled M, y = L^T 1; with dampers the Eigen solver takes it in both).
    for (bool dampers : {false, true})
        for (testing::Solvers solvers : {testing::Solvers::generic, testing::Solvers::interp}) {
        SCOPED_TRACE(testing::solvers_name(solvers));
        testing::TempDir dir;
        const Model model = read_model(free_bar(dir, 4, dampers));
        ASSERT_TRUE(model.coupled_mass());
        const testing::Outcome run = testing::simulate(model, 0.5, 1e-3, solvers);
        ASSERT_GE(run.events.size(), 2u) << "the bar should hit the wall and leave it";
        ASSERT_EQ(run.events[0].kind, EventKind::contact_close);
        // Before the first impact nothing acts on the bar: p = 1^T M v stays -0.5 kg m/s (mass 1 kg).
        const Eigen::MatrixXd M = mass_matrix(model);
        const Eigen::VectorXd ones = Eigen::VectorXd::Ones(M.rows());
        double worst = 0.0;
        for (const testing::Recorded& s : run.samples) {
            if (s.t >= run.events[0].t) break;
            const Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(s.v.data(), M.rows());
            worst = std::max(worst, std::fabs(ones.dot(M * v) + 0.5));
        }
        EXPECT_LT(worst, 1e-14);
        // While the contact is open (after each open event, up to the next close) the momentum stays;
        // after the last impact it is positive: the bar moves away for good.
        double drift = 0.0, p_last = NAN;
        for (std::size_t e = 0; e < run.events.size(); ++e) {
            if (run.events[e].kind != EventKind::contact_open) continue;
            const double t_next = e + 1 < run.events.size() ? run.events[e + 1].t : INFINITY;
            double p_open = NAN;
            for (const testing::Recorded& s : run.samples) {
                if (s.t <= run.events[e].t || s.t >= t_next) continue;
                const Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(s.v.data(), M.rows());
                const double p = ones.dot(M * v);
                if (std::isnan(p_open)) p_open = p;
                drift = std::max(drift, std::fabs(p - p_open));
            }
            p_last = p_open;
        }
        EXPECT_EQ(run.events.back().kind, EventKind::contact_open);
        EXPECT_GT(p_last, 0.0);
        EXPECT_LT(drift, 1e-13);
        const testing::Outcome cvode = testing::baseline(model, 0.5, 1e-12, 1e-14, Method::cvode);
        const double gap = event_gap(run, cvode);
        std::printf("%s, %s: %zu events, CVODE within %.3g s\n", dampers ? "dampers" : "undamped",
                    testing::solvers_name(solvers), run.events.size(), gap);
        EXPECT_LT(gap, 1e-9);
        }
}

TEST(CoupledMass, TheDerivationsRigidBodyModeOfACoupledMIsTheTranslation) {
    testing::TempDir dir;
    const Model model = read_model(free_bar(dir, 4, false));
    const Configuration open = Configuration::all_open(model);
    const Derivation d = derive(model, open);
    ASSERT_EQ(d.modes[0].regime, Regime::rigid);
    EXPECT_TRUE(d.modes[0].lambda.is_zero());
    const double v0 = d.modes[0].v[0].to_double();  // 1 / sqrt(1^T M 1): the bar's mass is 1 kg
    EXPECT_NEAR(v0, 1.0, 1e-15);
    for (const DD& v : d.modes[0].v) EXPECT_NEAR(v.to_double(), v0, 1e-15);
    const ModalResiduals r = modal_residuals(model, open);
    EXPECT_LT(r.orth, 1e-13);
    EXPECT_LT(r.eig, 1e-13);
    EXPECT_LT(r.rows, 1e-14);
    EXPECT_NE(d.modes[1].regime, Regime::rigid);
}

TEST(CoupledMass, ADiagonalMassThroughTheCoupledPathGivesTheLumpedEvents) {
    Model lumped = read_model(testing::model_path("bilinear-1dof.toml"));
    // Two masses: a chain of the bilinear oscillator's mass with a second one.
    lumped.masses.push_back({"m2", 0.7});
    lumped.springs.push_back({});
    lumped.springs.back().a = 0;
    lumped.springs.back().b = 1;
    lumped.springs.back().k = 30.0;
    lumped.x0.push_back(0.02), lumped.v0.push_back(-0.3), lumped.load.push_back(0.0);
    for (Harmonic& h : lumped.forcing) h.amplitude.push_back(0.0);
    Model coupled = lumped;
    const std::size_t n = coupled.dof();
    coupled.mass_matrix.assign(n * n, 0.0);
    for (std::size_t i = 0; i < n; ++i) coupled.mass_matrix[i * n + i] = coupled.masses[i].m;
    coupled.mass_floor = std::min(coupled.masses[0].m, coupled.masses[1].m);
    ASSERT_TRUE(coupled.coupled_mass());
    ASSERT_GT(modal_analysis(coupled, Configuration::all_open(coupled)).mass_matrix.size(), 0) << "the coupled path";
    const testing::Outcome a = testing::simulate(lumped, 20.0), b = testing::simulate(coupled, 20.0);
    ASSERT_GE(a.events.size(), 10u);
    const double gap = event_gap(a, b);
    std::printf("%zu events, the coupled path within %.3g s\n", a.events.size(), gap);
    EXPECT_LT(gap, 1e-13);
}

TEST(CoupledMass, ThePeriodMapsExactJacobianMatchesCentralDifferences) {
    // The tangent (saltation and transitions with Phi^T M) of the beam against
    // its stop over one forcing period, from rest: 2 impacts.
    testing::TempDir dir;
    const Forced f = beam_with_stop(dir);
    const Model model = read_model(f.path);
    analysis::FlowKernels kernels;
    kernels.kernels = KernelChoice::eigen;
    analysis::Flow flow(model, kernels, "test");
    const Eigen::Index N = static_cast<Eigen::Index>(2 * model.dof());
    Eigen::VectorXd y(N);
    for (std::size_t i = 0; i < model.dof(); ++i)
        y(static_cast<Eigen::Index>(i)) = 0.5 * model.x0[i], y(static_cast<Eigen::Index>(model.dof() + i)) = 0.5 * model.v0[i];
    std::size_t events = 0;
    const double off = off_central_differences(flow, 2 * M_PI / f.omega, y, events);
    std::printf("%zu events a period, |J - central differences| / |J| = %.3g\n", events, off);
    EXPECT_GE(events, 2u);
    EXPECT_LT(off, 1e-6);
}

TEST(CoupledMass, TheFortyDofExampleIsTheTestedCantilever) {
    // examples/beam-40 (../fe-cantilever/make_matrices.py 20) is cantilever(20): the README's response curve
    // and the sweep tests of the stiff beam (test_sweep.cpp) run one structure.
    const Model model = read_model(std::string(HSNC_SOURCE_DIR) + "/examples/beam-40/beam-40.toml");
    const Beam b = cantilever(20);
    ASSERT_EQ(static_cast<Eigen::Index>(model.dof()), b.M.rows());
    for (std::size_t i = 0; i < model.dof(); ++i) EXPECT_EQ(model.masses[i].name, b.dofs[i]);
    const Eigen::MatrixXd M = mass_matrix(model), K = stiffness_matrix(model, Configuration::all_open(model));
    EXPECT_LT((M - b.M).cwiseAbs().maxCoeff(), 1e-15 * b.M.cwiseAbs().maxCoeff());
    EXPECT_LT((K - b.K).cwiseAbs().maxCoeff(), 1e-12 * b.K.cwiseAbs().maxCoeff());
}

TEST(CoupledMass, TheFiniteElementExampleIsTheTestedCantilever) {
    // examples/fe-cantilever (matrices from its make_matrices.py) is the beam these tests assemble.
    const Model model = read_model(std::string(HSNC_SOURCE_DIR) + "/examples/fe-cantilever/fe-cantilever.toml");
    const Beam b = cantilever(8);
    ASSERT_TRUE(model.coupled_mass());
    ASSERT_EQ(static_cast<Eigen::Index>(model.dof()), b.M.rows());
    const Eigen::MatrixXd M = mass_matrix(model), K = stiffness_matrix(model, Configuration::all_open(model));
    EXPECT_LT((M - b.M).cwiseAbs().maxCoeff(), 1e-15 * b.M.cwiseAbs().maxCoeff());
    EXPECT_LT((K - b.K).cwiseAbs().maxCoeff(), 1e-12 * b.K.cwiseAbs().maxCoeff());
    const testing::Outcome run = testing::simulate(model, 10.0);
    EXPECT_GE(run.events.size(), 40u) << "the tip should hit its stop about twice a period";
    EXPECT_EQ(run.summary.status, RunStatus::ok);
    // `inspect` prints the modes of (K, M): the first as solved here.
    const testing::CliRun r =
        testing::run_hsnc("inspect '" + std::string(HSNC_SOURCE_DIR) + "/examples/fe-cantilever/fe-cantilever.toml'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(b.K, b.M);
    const std::size_t at = r.out.find("mode 1: omega = ");
    ASSERT_NE(at, std::string::npos) << r.out;
    const double omega1 = std::stod(r.out.substr(at + 16));
    EXPECT_NEAR(omega1, std::sqrt(es.eigenvalues()(0)), 1e-12 * omega1);
    EXPECT_NEAR(omega1, 24.86, 0.01);  // 1.8751^2 sqrt(EI / (rho L^4)) = 24.86 rad/s, Euler-Bernoulli
    EXPECT_NE(r.out.find("the kernels derive these modes in double-double"), std::string::npos) << r.out;
}

/// The cantilever with its mass at the w dofs alone (no rotary inertia: zero
/// rows of M at the rotations), forced at its tip.
/// The cantilever's mass at its deflections alone (2 kg/m, 4 elements): zero rows at the rotations.
Eigen::MatrixXd deflection_mass(const Beam& b) {
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(b.M.rows(), b.M.cols());
    const Eigen::Index nodes = b.M.rows() / 2;
    for (Eigen::Index k = 0; k < nodes; ++k) M(2 * k, 2 * k) = k + 1 == nodes ? 0.2 : 0.4;
    return M;
}

std::string massless_rotations(const testing::TempDir& dir, const Beam& b, const std::string& extra) {
    const Eigen::MatrixXd M = deflection_mass(b);
    const Eigen::Index nodes = b.M.rows() / 2;
    write(dir / "M.mtx", market(M));
    write(dir / "K.mtx", market(b.K));
    std::ostringstream t;
    t << "name = \"massless-rotations\"\n[structure]\ndofs = " << dof_list(b.dofs)
      << "\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n[damping]\nalpha = 0.1\n"
      << "[[forcing]]\nomega = 20.0\namplitude = { w" << nodes << " = 2.0 }\n"
      << "[initial]\nx = { w2 = 0.003 }\n" << extra;
    write(dir / "beam.toml", t.str());
    return dir / "beam.toml";
}

TEST(MasslessDofs, ACantileverWithoutRotaryInertiaIsItsFlexibilityClosedForm) {
    // Condensed, the beam's stiffness at its w dofs is the inverse of its
    // flexibility, f_ij = x_i^2 (3 x_j - x_i) / (6 EI) for x_i <= x_j, and its
    // rotations follow as theta = G F^-1 w, g_ij = x_i (2 x_j - x_i) / (2 EI)
    // for x_i <= x_j, x_j^2 / (2 EI) beyond (the slope under a unit tip load).
    testing::TempDir dir;
    const Beam b = cantilever(4);
    const Model model = read_model(massless_rotations(dir, b, "[simulate]\nt_end = 1.0\n"));
    ASSERT_TRUE(model.condensation.present());
    ASSERT_EQ(model.dof(), 4u);
    EXPECT_EQ(model.condensation.condensed(), 4u);
    EXPECT_FALSE(model.coupled_mass());
    const double EI = 100.0;
    Eigen::Matrix4d F, G;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            const double xi = 0.25 * (i + 1), xj = 0.25 * (j + 1), a = std::min(xi, xj), c = std::max(xi, xj);
            F(i, j) = a * a * (3 * c - a) / (6 * EI);
            G(i, j) = xi <= xj ? xi * (2 * xj - xi) / (2 * EI) : xj * xj / (2 * EI);
        }
    const Eigen::Matrix4d Kw = F.inverse(), R = G * Kw;
    const Eigen::MatrixXd K = stiffness_matrix(model, Configuration::all_open(model));
    const double kerr = (K - Kw).cwiseAbs().maxCoeff() / Kw.cwiseAbs().maxCoeff();
    double rerr = 0.0;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            rerr = std::max(rerr, std::fabs(model.condensation.recovery[static_cast<std::size_t>(4 * i + j)] - R(i, j)) /
                                      R.cwiseAbs().maxCoeff());
    std::printf("condensed K against F^-1: %.3g, recovery against G F^-1: %.3g (relative)\n", kerr, rerr);
    EXPECT_LT(kerr, 1e-10);
    EXPECT_LT(rerr, 1e-10);

    // The CSVs carry every dof in the structure's order, the rotations recovered from the deflections.
    const std::string out = testing::temp_path("trajectory.csv");
    const testing::CliRun run = testing::run_hsnc("simulate '" + (dir / "beam.toml") + "' --dt 0.01 --out '" + out + "' --quiet");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    std::istringstream csv(testing::slurp(out));
    std::remove(out.c_str());
    std::string line;
    std::getline(csv, line);
    EXPECT_EQ(line, "t,x_w1,x_t1,x_w2,x_t2,x_w3,x_t3,x_w4,x_t4,v_w1,v_t1,v_w2,v_t2,v_w3,v_t3,v_w4,v_t4");
    std::size_t rows = 0;
    double worst = 0.0, size = 0.0;
    while (std::getline(csv, line)) {
        std::vector<double> f;
        std::istringstream fields(line);
        for (std::string cell; std::getline(fields, cell, ',');) f.push_back(std::stod(cell));
        ASSERT_EQ(f.size(), 17u);
        for (int half = 0; half < 2; ++half) {  // x, then v
            Eigen::Vector4d w, th;
            for (int k = 0; k < 4; ++k) w(k) = f[1 + 8 * half + 2 * k], th(k) = f[2 + 8 * half + 2 * k];
            worst = std::max(worst, (th - R * w).cwiseAbs().maxCoeff());
            size = std::max(size, th.cwiseAbs().maxCoeff());
        }
        ++rows;
    }
    EXPECT_EQ(rows, 101u);
    std::printf("rotations recovered to %.3g of their size\n", worst / size);
    EXPECT_LT(worst, 1e-10 * size);
}

/// The cantilever of massless_rotations without damping, loaded by `forces`
/// (TOML: [load], [[forcing]]) from `initial`.
std::string loaded_beam(const testing::TempDir& dir, const Beam& b, const std::string& forces, const std::string& initial) {
    return structure_model(dir, "beam.toml", "loaded-beam", deflection_mass(b), b.K, b.dofs,
                           forces + "[initial]\n" + initial + "[simulate]\nt_end = 1.0\n");
}

/// The rows of a trajectory CSV (t, then the state), header checked.
std::vector<std::vector<double>> trajectory_rows(const std::string& model, const std::string& header) {
    const std::string out = testing::temp_path("trajectory.csv");
    const testing::CliRun run = testing::run_hsnc("simulate '" + model + "' --dt 0.01 --out '" + out + "' --quiet");
    EXPECT_EQ(run.exit_code, 0) << run.err;
    std::istringstream csv(testing::slurp(out));
    std::remove(out.c_str());
    std::string line;
    std::getline(csv, line);
    EXPECT_EQ(line, header);
    std::vector<std::vector<double>> rows;
    while (std::getline(csv, line)) {
        rows.emplace_back();
        std::istringstream fields(line);
        for (std::string cell; std::getline(fields, cell, ',');) rows.back().push_back(std::stod(cell));
    }
    return rows;
}

TEST(MasslessDofs, ForcesOnCondensedRotationsAreCarriedByTheDeflectionsAndRecovered) {
    // A load on a massless dof is carried by the dofs with mass as R^T f_c, and
    // the condensed dof is recovered as x_c = R x + K_cc^-1 f_c(t).
    const Beam b = cantilever(4);
    const double EI = 100.0;
    const std::string header = "t,x_w1,x_t1,x_w2,x_t2,x_w3,x_t3,x_w4,x_t4,v_w1,v_t1,v_w2,v_t2,v_w3,v_t3,v_w4,v_t4";
    {
        // A moment M0 at the tip rotation, started on its static deflection w = M0 x^2 / (2 EI)
        // (theta = M0 x / EI): the beam stays there, its rotations recovered.
        testing::TempDir dir;
        const double M0 = 3.0;
        Eigen::Vector4d w, th;
        std::string x0 = "x = {";
        for (int k = 0; k < 4; ++k) {
            const double x = 0.25 * (k + 1);
            w(k) = M0 * x * x / (2 * EI), th(k) = M0 * x / EI;
            x0 += (k ? ", w" : " w") + std::to_string(k + 1) + " = " + num(w(k));
        }
        const std::string model = loaded_beam(dir, b, "[load]\nt4 = " + num(M0) + "\n", x0 + " }\n");
        double worst = 0.0;
        std::size_t rows = 0;
        for (const std::vector<double>& f : trajectory_rows(model, header)) {
            ASSERT_EQ(f.size(), 17u);
            for (int k = 0; k < 4; ++k) {
                worst = std::max({worst, std::fabs(f[1 + 2 * k] - w(k)) / w(3), std::fabs(f[2 + 2 * k] - th(k)) / th(3),
                                  std::fabs(f[9 + 2 * k]) * 0.01 / w(3), std::fabs(f[10 + 2 * k]) * 0.01 / th(3)});
            }
            ++rows;
        }
        EXPECT_EQ(rows, 101u);
        std::printf("tip moment: the static deflection and slope kept and recovered to %.3g (relative)\n", worst);
        EXPECT_LT(worst, 1e-12);
        // Sweep kernels would read the dofs' own load expressions, not the folded load: refused.
        testing::TempDir swept;
        const std::string with_parameter =
            loaded_beam(swept, b, "[parameters]\nM0 = 3.0\n[load]\nt4 = \"M0\"\n", x0 + " }\n");
        const testing::CliRun params =
            testing::run_hsnc("generate '" + with_parameter + "' -o '" + swept.path() + "/k' --params all");
        EXPECT_EQ(params.exit_code, 2) << params.err;
        EXPECT_NE(params.err.find("a load or forcing on a massless (condensed) dof"), std::string::npos) << params.err;
    }
    {
        // Forcing on a rotation and a deflection, undamped, started on the particular solution
        // x = X sin(omega t), (K - omega^2 M) X = F with M's zero rows: every dof follows it.
        testing::TempDir dir;
        const double omega = 20.0;
        Eigen::MatrixXd M = Eigen::MatrixXd::Zero(8, 8);
        for (int k = 0; k < 4; ++k) M(2 * k, 2 * k) = k == 3 ? 0.2 : 0.4;
        Eigen::VectorXd F = Eigen::VectorXd::Zero(8);
        F(3) = 1.5, F(4) = 0.5;  // t2, w3
        const Eigen::VectorXd X = (b.K - omega * omega * M).lu().solve(F);
        std::string v0 = "v = {";
        for (int k = 0; k < 4; ++k) v0 += (k ? ", w" : " w") + std::to_string(k + 1) + " = " + num(omega * X(2 * k));
        const std::string model =
            loaded_beam(dir, b, "[[forcing]]\nomega = " + num(omega) + "\namplitude = { t2 = 1.5, w3 = 0.5 }\n", v0 + " }\n");
        double worst = 0.0;
        for (const std::vector<double>& f : trajectory_rows(model, header)) {
            ASSERT_EQ(f.size(), 17u);
            for (Eigen::Index d = 0; d < 8; ++d) {
                const double scale = X.cwiseAbs().maxCoeff();
                worst = std::max({worst, std::fabs(f[1 + d] - X(d) * std::sin(omega * f[0])) / scale,
                                  std::fabs(f[9 + d] - omega * X(d) * std::cos(omega * f[0])) / (omega * scale)});
            }
        }
        std::printf("forcing on a rotation: every dof on X sin(omega t) to %.3g (relative)\n", worst);
        EXPECT_LT(worst, 1e-10);
    }
}

TEST(MasslessDofs, WhatCannotBeCondensedIsRefusedByName) {
    const Beam b = cantilever(2);
    {
        testing::TempDir dir;
        const std::string model = massless_rotations(dir, b, "[[contact]]\nbetween = [\"t2\", \"ground\"]\ngap = 0.1\nk = 5.0\n");
        const testing::CliRun r = testing::run_hsnc("check '" + model + "'");
        EXPECT_EQ(r.exit_code, 2);
        EXPECT_NE(r.err.find("key 'contact[1].between': 't2' is a massless dof (a zero row of M), condensed statically"),
                  std::string::npos)
            << r.err;
    }
    {
        testing::TempDir dir;
        const std::string model = massless_rotations(dir, b, "");
        const testing::CliRun c = testing::run_hsnc("check '" + model + "'");
        EXPECT_EQ(c.exit_code, 0) << c.err;
        EXPECT_NE(c.out.find("massless dofs: 2 condensed statically (Guyan: t1, t2; recovered in the CSV outputs)"),
                  std::string::npos)
            << c.out;
        // A rotation K does not hold: no static condensation exists.
        Eigen::MatrixXd K = Eigen::MatrixXd::Zero(3, 3), M = Eigen::MatrixXd::Zero(3, 3);
        K(0, 0) = 2, K(0, 1) = K(1, 0) = -1, K(1, 1) = 1;  // u1, u2 a chain; r free of K
        M(0, 0) = M(1, 1) = 1;
        write(dir / "M3.mtx", market(M));
        write(dir / "K3.mtx", market(K));
        write(dir / "free.toml", "name = \"free-rotation\"\n[structure]\ndofs = [\"u1\", \"u2\", \"r\"]\n"
                                 "mass = \"M3.mtx\"\nstiffness = \"K3.mtx\"\n");
        const testing::CliRun s = testing::run_hsnc("check '" + (dir / "free.toml") + "'");
        EXPECT_EQ(s.exit_code, 2);
        EXPECT_NE(s.err.find("key 'structure.stiffness': K3.mtx: K is singular on the massless dofs r"), std::string::npos)
            << s.err;
        // A dashpot on a massless dof: its motion would be first order.
        Eigen::MatrixXd C = Eigen::MatrixXd::Zero(3, 3);
        K(2, 2) = 1.0;
        C(2, 2) = 0.5;
        write(dir / "K3.mtx", market(K));
        write(dir / "C3.mtx", market(C));
        write(dir / "damped.toml", "name = \"damped-rotation\"\n[structure]\ndofs = [\"u1\", \"u2\", \"r\"]\n"
                                   "mass = \"M3.mtx\"\nstiffness = \"K3.mtx\"\ndamping = \"C3.mtx\"\n");
        const testing::CliRun d = testing::run_hsnc("check '" + (dir / "damped.toml") + "'");
        EXPECT_EQ(d.exit_code, 2);
        EXPECT_NE(d.err.find("key 'structure.damping': C3.mtx: C damps the massless dof r"), std::string::npos) << d.err;
    }
}

/// Three lumped masses y1, y2, y3 (friction on y1 and y2 against the ground,
/// a stop on y1, forcing on y3), and the same system in the coordinates
/// x1 = y1, x2 = y2, x3 = y3 - y1 - y2: y = T x, M_x = T^T M T (coupled: y3's
/// mass couples all three), K_x = T^T K T, forces T^T F, Rayleigh damping
/// alike. The physics is the same, so the coupled model's stick, release,
/// reversal and impact events are the lumped model's, which no coupled-mass
/// code computes. `damper`: a dashpot on y3 instead of Rayleigh damping
/// (C_x = c t t^T, t = T^T e3: the state-space solver).
double eval40(const GiNaC::ex& e, const GiNaC::symbol& tau, double t) {
    return GiNaC::ex_to<GiNaC::numeric>(e.subs(tau == exact(t)).evalf()).to_double();
}

struct RelativeChain {
    std::string lumped, coupled;
};

RelativeChain relative_chain(const testing::TempDir& dir, bool damper, bool jenkins = false) {
    const Eigen::Vector3d m(1.0, 1.5, 2.0);
    Eigen::Matrix3d K = Eigen::Matrix3d::Zero();  // y1-ground 100, y2-ground 80, y1-y3 50, y2-y3 40
    K(0, 0) = 100 + 50, K(1, 1) = 80 + 40, K(2, 2) = 50 + 40, K(0, 2) = K(2, 0) = -50, K(1, 2) = K(2, 1) = -40;
    Eigen::Matrix3d T;
    T << 1, 0, 0, 0, 1, 0, 1, 1, 1;
    const Eigen::Matrix3d Mx = T.transpose() * m.asDiagonal() * T, Kx = T.transpose() * K * T;
    const Eigen::Vector3d y0(0.05, -0.03, 0.02), w0(0.0, 0.2, 0.3);
    const Eigen::Vector3d x0 = T.inverse() * y0, v0 = T.inverse() * w0;
    const std::string common =
        "[[friction]]\nname = \"f1\"\nbetween = [\"u1\", \"ground\"]\nmu_k = 0.3\nmu_s = 0.4\nnormal = 10.0\n"
        "[[friction]]\nname = \"f2\"\nbetween = [\"u2\", \"ground\"]\nmu_k = 0.25\nmu_s = 0.35\nnormal = 12.0\n"
        "[[contact]]\nname = \"stop\"\nbetween = [\"u1\", \"ground\"]\ngap = 0.06\nk = 500.0\n" +
        std::string(damper ? "" : "[damping]\nalpha = 0.2\nbeta = 0.001\n") +  // structure.damping excludes [damping]
        std::string(jenkins ? "[[jenkins]]\nname = \"j2\"\nbetween = [\"u2\", \"ground\"]\nk = 60.0\nslip_force = 1.5\n" : "");
    std::ostringstream l;
    l << "name = \"chain-lumped\"\n";
    for (int i = 0; i < 3; ++i) l << "[[mass]]\nname = \"u" << i + 1 << "\"\nm = " << num(m(i)) << "\n";
    l << "[[spring]]\nbetween = [\"u1\", \"ground\"]\nk = 100.0\n[[spring]]\nbetween = [\"u2\", \"ground\"]\nk = 80.0\n"
      << "[[spring]]\nbetween = [\"u1\", \"u3\"]\nk = 50.0\n[[spring]]\nbetween = [\"u2\", \"u3\"]\nk = 40.0\n"
      << (damper ? "[[damper]]\nbetween = [\"u3\", \"ground\"]\nc = 0.8\n" : "") << common
      << "[[forcing]]\nomega = 6.0\namplitude = { u3 = 8.0 }\n[initial]\nx = { u1 = " << num(y0(0)) << ", u2 = "
      << num(y0(1)) << ", u3 = " << num(y0(2)) << " }\nv = { u1 = " << num(w0(0)) << ", u2 = " << num(w0(1))
      << ", u3 = " << num(w0(2)) << " }\n";
    write(dir / "lumped.toml", l.str());
    write(dir / "M.mtx", market(Mx));
    write(dir / "K.mtx", market(Kx));
    const std::vector<std::string> dofs = {"u1", "u2", "r3"};
    std::ostringstream c;
    c << "name = \"chain-relative\"\n[structure]\ndofs = " << dof_list(dofs) << "\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n";
    if (damper) {
        const Eigen::Vector3d t = T.transpose() * Eigen::Vector3d::UnitZ();
        write(dir / "C.mtx", market(0.8 * t * t.transpose()));
        c << "damping = \"C.mtx\"\n";
    }
    c << common << "[[forcing]]\nomega = 6.0\namplitude = { u1 = 8.0, u2 = 8.0, r3 = 8.0 }\n[initial]\nx = "
      << table(dofs, x0) << "\nv = " << table(dofs, v0) << "\n";
    write(dir / "coupled.toml", c.str());
    return {dir / "lumped.toml", dir / "coupled.toml"};
}

TEST(CoupledMass, TwoFrictionsCoupledThroughMGiveTheLumpedModelsEventsInOtherCoordinates) {
    for (bool damper : {false, true}) {
        testing::TempDir dir;
        const RelativeChain files = relative_chain(dir, damper);
        const Model lumped = read_model(files.lumped), coupled = read_model(files.coupled);
        ASSERT_TRUE(coupled.coupled_mass());
        ASSERT_FALSE(lumped.coupled_mass());
        const testing::Outcome a = testing::simulate(lumped, 6.0, 1e-2), b = testing::simulate(coupled, 6.0, 1e-2);
        int kinds[5] = {0, 0, 0, 0, 0}, stuck = 0, both = 0;  // both: stick events that leave f1 and f2 stuck
        for (const testing::Recorded& e : a.events) {
            ++kinds[static_cast<int>(e.kind)];
            stuck += e.kind == EventKind::stick ? 1 : e.kind == EventKind::release ? -1 : 0;
            both += e.kind == EventKind::stick && stuck == 2 ? 1 : 0;
        }
        ASSERT_GE(a.events.size(), 20u);
        for (EventKind k : {EventKind::contact_close, EventKind::stick, EventKind::release})
            EXPECT_GT(kinds[static_cast<int>(k)], 0) << "the run should close the stop, stick and release";
        EXPECT_GT(both, 0) << "both frictions should be stuck at once (D of each then holds the other still)";
        const double gap = event_gap(a, b);
        // The same motion: y = T x at every sample.
        double worst = 0.0;
        ASSERT_EQ(a.samples.size(), b.samples.size());
        for (std::size_t s = 0; s < a.samples.size(); ++s) {
            const std::vector<double>&y = a.samples[s].x, &x = b.samples[s].x;
            worst = std::max({worst, std::fabs(y[0] - x[0]), std::fabs(y[1] - x[1]), std::fabs(y[2] - (x[0] + x[1] + x[2]))});
        }
        const testing::Outcome cvode = testing::baseline(coupled, 6.0, 1e-12, 1e-14, Method::cvode);
        const double cv = event_gap(b, cvode);
        // The programs (double-double derivation: the held forces D_i = A_i - M_iF M_FF^-1 A_F lowered).
        const testing::Outcome programs = testing::simulate(coupled, 6.0, 1e-2, testing::Solvers::interp);
        const double on_programs = event_gap(a, programs);
        std::printf("%s: the programs on the coupled model within %.3g s of the lumped model\n", damper ? "dashpot" : "Rayleigh",
                    on_programs);
        EXPECT_LT(on_programs, 1e-12);
        std::printf("%s: %zu events (stick %d, %d of them with both stuck, release %d, reversal %d, impacts %d), the coupled model within %.3g s "
                    "and %.3g m of the lumped one; CVODE on the coupled one within %.3g s\n",
                    damper ? "dashpot" : "Rayleigh", a.events.size(), kinds[static_cast<int>(EventKind::stick)], both,
                    kinds[static_cast<int>(EventKind::release)], kinds[static_cast<int>(EventKind::reversal)],
                    kinds[static_cast<int>(EventKind::contact_close)], gap, worst, cv);
        EXPECT_LT(gap, 1e-12);
        EXPECT_LT(worst, 1e-12);
        EXPECT_LT(cv, 1e-8);
        if (damper) continue;  // the reference takes a coupled M with Rayleigh damping only
        // The CLN reference (held forces at N digits): 30 against 60 digits, and the double engine against it.
        const std::vector<testing::Recorded> r30 = reference_events(coupled, 30, 6.0), r60 = reference_events(coupled, 60, 6.0);
        ASSERT_EQ(r30.size(), b.events.size());
        ASSERT_EQ(r60.size(), b.events.size());
        double to_ref = 0.0, digits = 0.0;
        for (std::size_t e = 0; e < r30.size(); ++e) {
            EXPECT_EQ(r30[e].kind, b.events[e].kind) << "event " << e;
            EXPECT_EQ(r30[e].element, b.events[e].element) << "event " << e;
            to_ref = std::max(to_ref, std::fabs(r30[e].t - b.events[e].t));
            digits = std::max(digits, std::fabs(r30[e].t - r60[e].t));
        }
        std::printf("reference: the double engine within %.3g s, 30 against 60 digits %.3g s\n", to_ref, digits);
        EXPECT_LT(to_ref, 1e-11);
        EXPECT_LT(digits, 1e-15);
    }
}

/// A bar clamped at one end (3 consistent-mass axial elements, dofs u1..u3)
/// with Coulomb friction on u2 and u3 against the ground and a force on u3:
/// M couples the friction dofs, so the force a stuck dof's friction holds
/// depends on the kinetic friction of the other, D_i = A_i - M_iF M_FF^-1 A_F.
std::string friction_bar(const testing::TempDir& dir) {
    const Beam b = clamped_bar(3);
    return structure_model(
        dir, "bar.toml", "friction-bar", b.M, b.K, b.dofs,
        "[damping]\nalpha = 2.0\nbeta = 1e-5\n"
              "[[friction]]\nname = \"f2\"\nbetween = [\"u2\", \"ground\"]\nmu_k = 0.3\nmu_s = 0.4\nnormal = 20.0\n"
              "[[friction]]\nname = \"f3\"\nbetween = [\"u3\", \"ground\"]\nmu_k = 0.25\nmu_s = 0.35\nnormal = 24.0\n"
              "[[forcing]]\nomega = 60.0\namplitude = { u3 = 20.0 }\n"
              "[initial]\nx = { u1 = 0.0, u2 = 0.0, u3 = 0.0 }\nv = { u1 = 0.0, u2 = 0.01, u3 = -0.02 }\n");
}

TEST(CoupledMass, FrictionsCoupledThroughAConsistentMassGiveTheEventsOfTheReferenceOnThePrograms) {
    // The held force of each stuck dof reads the other's kinetic friction
    // through M: the programs (lowered in double-double) against the Eigen
    // solver (model/held_mass.h in double), CVODE and the CLN reference.
    testing::TempDir dir;
    const Model m = read_model(friction_bar(dir));
    ASSERT_TRUE(m.coupled_mass());
    const testing::Outcome programs = testing::simulate(m, 1.0, 0.0, testing::Solvers::interp),
                           eigen = testing::simulate(m, 1.0, 0.0, testing::Solvers::generic);
    int stick[2] = {0, 0}, release[2] = {0, 0};
    for (const testing::Recorded& e : programs.events) {
        const int which = e.element == 1 ? 0 : 1;  // u2, u3
        stick[which] += e.kind == EventKind::stick, release[which] += e.kind == EventKind::release;
    }
    for (int k = 0; k < 2; ++k) {
        EXPECT_GE(stick[k], 10) << "each friction should stick again and again";
        EXPECT_GE(release[k], 10);
    }
    const std::vector<testing::Recorded> r30 = reference_events(m, 30, 1.0);
    const testing::Outcome cvode = testing::baseline(m, 1.0, 1e-12, 1e-14, Method::cvode);
    const double to_eigen = event_gap(programs, eigen), to_ref = event_gap(programs.events, r30),
                 to_cvode = event_gap(programs, cvode);
    std::printf("%zu events: the programs within %.3g s of the Eigen solver, %.3g s of the reference (30 digits), "
                "%.3g s of CVODE\n",
                programs.events.size(), to_eigen, to_ref, to_cvode);
    EXPECT_LT(to_eigen, 1e-13);
    EXPECT_LT(to_ref, 1e-13);
    EXPECT_LT(to_cvode, 1e-9);
}

TEST(CoupledMass, AReversalWhileAnotherDofIsStuckRestartsWithTheNewKineticFriction) {
    // 20 consistent-mass elements (past restart.h's kRestartFrom modes, so an
    // event that keeps the configuration carries the coefficient block over):
    // friction at mid-span and at the tip. When the tip reverses while the
    // mid-span dof is stuck, the held force's kinetic-friction term changes
    // sign; a carried block kept the old one (events 5e-9 s off), so such a
    // configuration sets up instead. Programs against the Eigen solver and the
    // 30-digit reference.
    testing::TempDir dir;
    Beam b = clamped_bar(20);
    b.K *= 0.01;  // EA = 100 N
    const Model m = read_model(structure_model(
        dir, "bar.toml", "long-friction-bar", b.M, b.K, b.dofs,
        "[damping]\nalpha = 2.0\nbeta = 1e-6\n"
              "[[friction]]\nname = \"fm\"\nbetween = [\"u10\", \"ground\"]\nmu_k = 0.3\nmu_s = 0.4\nnormal = 8.0\n"
              "[[friction]]\nname = \"ft\"\nbetween = [\"u20\", \"ground\"]\nmu_k = 0.25\nmu_s = 0.35\nnormal = 0.3\n"
              "[[forcing]]\nomega = 5.0\namplitude = { u20 = 20.0 }\n"));
    // As the facade runs it: restarts on (EngineOptions::restart_plans).
    DerivationFallbackProvider interp(m, std::make_unique<InterpretedSolverProvider>(program_source(m)));
    const testing::Outcome programs = testing::run_engine(m, interp, 5.0, 0.0, kScheduleFrom, restart_plan_source(m)),
                           eigen = testing::simulate(m, 5.0, 0.0, testing::Solvers::generic);
    bool mid_stuck = false;
    int reversals_while_stuck = 0;
    for (const testing::Recorded& e : programs.events) {
        if (e.element == 9 && e.kind == EventKind::stick) mid_stuck = true;
        if (e.element == 9 && e.kind == EventKind::release) mid_stuck = false;
        reversals_while_stuck += e.element == 19 && e.kind == EventKind::reversal && mid_stuck;
    }
    EXPECT_GE(reversals_while_stuck, 1) << "the tip should reverse while mid-span is stuck";
    const std::vector<testing::Recorded> r30 = reference_events(m, 30, 5.0);
    const double to_eigen = event_gap(programs, eigen), to_ref = event_gap(programs.events, r30);
    std::printf("%zu events, %d tip reversals with mid-span stuck: the programs within %.3g s of the Eigen solver, "
                "%.3g s of the reference\n",
                programs.events.size(), reversals_while_stuck, to_eigen, to_ref);
    EXPECT_LT(to_eigen, 1e-11);
    EXPECT_LT(to_ref, 1e-11);
}

TEST(CoupledMass, TheProgramsHeldForcesAreTheClosedFormsAndTheirBoundsHold) {
    // Every configuration with a stuck friction on the coupled chain: the
    // program's release functions (D_i = A_i - c^T A_F, c = M_FF^-1 M_Fi, the
    // free dofs' forces with their kinetic friction) against the textbook
    // forms at 40 digits (D_i = A_i - M_iF a_F, a from GiNaC's diff of the
    // segment), and bound[f] >= |g_f''| over the step the bound covers.
    GiNaC::symbol tau("tau");
    for (int model : {0, 1, 2}) {  // the relative chain (Rayleigh, dashpot), the friction bar
        testing::TempDir dir;
        const Model m = read_model(model < 2 ? relative_chain(dir, model == 1).coupled : friction_bar(dir));
        int checked = 0;
        for (const Configuration& cfg : all_configurations(m)) {
            if (std::none_of(cfg.stuck.begin(), cfg.stuck.end(), [](auto s) { return s != 0; })) continue;
            const Derivation d = derive(m, cfg);
            ASSERT_EQ(d.held.size(), d.stuck_dofs.size());
            const testing::Start st = testing::start_of(m, cfg, 7);
            SegmentInputs in;
            in.t0 = exact(st.t0);  // t0_lo: 1e-17 s, far below what the comparison resolves
            for (std::size_t i = 0; i < m.dof(); ++i)
                in.x0.push_back(exact(st.x0[i])), in.v0.push_back(exact(st.v0[i])), in.sgn.push_back(int{st.sgn[i]});
            const SymbolicSegment sym = symbolic_segment(d, in, tau);
            InterpretedSolver solver(lower(d, ProgramNames::no));
            solver.setup(st.t0, st.t0_lo, st.x0.data(), st.v0.data(), st.sgn.data());
            const std::size_t nf = d.switches.size();
            const double step = std::min(solver.max_step(), 1.0);
            for (double t0 : {0.0, 0.3}) {
                std::vector<double> x(m.dof()), v(m.dof()), a(m.dof()), g(nf), dg(nf), bound(nf), scale(nf);
                solver.eval(t0, {x.data(), v.data(), a.data(), g.data(), dg.data(), bound.data(), scale.data()});
                for (std::size_t f = 0; f < nf; ++f) {
                    if (!is_release(d.switches[f].kind)) continue;
                    const double exact_g = eval40(sym.g[f], tau, t0), exact_dg = eval40(sym.dg[f], tau, t0);
                    EXPECT_NEAR(g[f], exact_g, 1e-13 * scale[f]) << cfg.spec(m) << " g" << f << " tau=" << t0;
                    EXPECT_NEAR(dg[f], exact_dg, 1e-12 * (1 + std::fabs(exact_dg))) << cfg.spec(m) << " dg" << f;
                    const GiNaC::ex g2 = sym.dg[f].diff(tau);
                    for (int k = 0; k <= 16; ++k) {
                        const double t = t0 + step * k / 16;
                        EXPECT_LE(std::fabs(eval40(g2, tau, t)), bound[f] * (1 + 1e-12)) << cfg.spec(m) << " g" << f << " at " << t;
                    }
                    ++checked;
                }
            }
        }
        EXPECT_GE(checked, 2 * 2 * 4) << "release functions of u1, u2 and both stuck, open and closed stop";
    }
}

TEST(CoupledMass, ThePeriodMapOfFrictionOnACoupledMIsTheLumpedOneInOtherCoordinates) {
    // The exact Jacobian through stick, release and impacts (saltation of the
    // held forces, held_mass.h): J_coupled = S^-1 J_lumped S with S = diag(T, T),
    // y = T x, against the lumped model's tangent, and against central differences.
    // With a Jenkins element on u2 (y2 = x2: the same element in both models)
    // the full-state tangent of stick elements (stick_tangent.cpp) takes the
    // coupled M too; its slider is the last coordinate, S's 1 there.
    for (bool jenkins : {false, true}) {
        testing::TempDir dir;
        const RelativeChain files = relative_chain(dir, false, jenkins);
        const Model lumped = read_model(files.lumped), coupled = read_model(files.coupled);
        analysis::FlowKernels kernels;
        kernels.kernels = KernelChoice::eigen;
        analysis::Flow fl(lumped, kernels, "test"), fc(coupled, kernels, "test");
        Eigen::Matrix3d T;
        T << 1, 0, 0, 0, 1, 0, 1, 1, 1;
        const Eigen::Index N = jenkins ? 7 : 6;
        Eigen::MatrixXd S = Eigen::MatrixXd::Identity(N, N);
        S.block(0, 0, 3, 3) = T;
        S.block(3, 3, 3, 3) = T;
        // From a state of the lumped run where both friction dofs slide and the Jenkins element
        // is stuck inside its slip force (no tie at the start: a slipping element's slider is a
        // function of x, so central differences in it would cross the slip boundary).
        const testing::Outcome run = testing::simulate(lumped, 3.0, 0.01);
        Eigen::VectorXd y(N);
        double t0 = -1.0;
        for (const testing::Recorded& s : run.samples)
            if (s.t > 1.0 && std::fabs(s.v[0]) > 0.02 && std::fabs(s.v[1]) > 0.02 &&
                (!jenkins || std::fabs(60.0 * (s.x[1] - s.x[3])) < 0.8 * 1.5)) {
                t0 = s.t;
                for (int i = 0; i < 3; ++i) y(i) = s.x[static_cast<std::size_t>(i)], y(3 + i) = s.v[static_cast<std::size_t>(i)];
                if (jenkins) y(6) = s.x[3];
                break;
            }
        ASSERT_GE(t0, 0.0);
        const Eigen::VectorXd x = S.inverse() * y;
        const double period = 2 * M_PI / 6.0;
        const analysis::PeriodMapValue a = analysis::evaluate_period_map(fl, t0, t0 + period, y),
                                       b = analysis::evaluate_period_map(fc, t0, t0 + period, x);
        ASSERT_TRUE(a.ok) << a.message;
        ASSERT_TRUE(b.ok) << b.message;
        ASSERT_EQ(a.events, b.events);
        ASSERT_GE(a.events, 4u);
        const double similar = (a.M * S - S * b.M).norm() / a.M.norm();
        Eigen::MatrixXd fd(N, N);
        for (Eigen::Index j = 0; j < N; ++j) {
            const double h = 1e-7 * std::max(1.0, std::fabs(x(j)));
            Eigen::VectorXd xp = x, xm = x;
            xp(j) += h, xm(j) -= h;
            const analysis::PeriodMapValue p = analysis::evaluate_period_map(fc, t0, t0 + period, xp),
                                           m = analysis::evaluate_period_map(fc, t0, t0 + period, xm);
            ASSERT_EQ(p.events, b.events);
            ASSERT_EQ(m.events, b.events);
            fd.col(j) = (p.Py - m.Py) / (2 * h);
        }
        const double off = (b.M - fd).norm() / fd.norm();
        std::printf("%s: %zu events a period: |J S - S J_coupled| / |J| = %.3g, |J_coupled - central differences| / |J| = %.3g\n",
                    jenkins ? "with a Jenkins element" : "frictions", a.events, similar, off);
        EXPECT_LT(similar, 1e-10);
        EXPECT_LT(off, 1e-6);
    }
}

std::string beam_model(const testing::TempDir& dir, const std::string& extra) {
    const Beam b = cantilever(2);
    return forced_beam(dir, b, 15.0, 1.0, extra).path;
}

TEST(CoupledMass, WhatIsNotYetTakenIsRefusedByName) {
    testing::TempDir dir;
    const std::string model =
        beam_model(dir, "[[friction]]\nbetween = [\"w2\", \"w1\"]\nmu_k = 0.2\nnormal = 10.0\n");
    const testing::CliRun r = testing::run_hsnc("check '" + model + "'");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("key 'friction[1].between'"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("friction between two dofs of a structure with a coupled (non-diagonal) mass matrix is not yet"),
              std::string::npos)
        << r.err;
    // Friction against the ground is taken (the engine, the reference).
    testing::TempDir grounded;
    const std::string ground = beam_model(grounded, "[[friction]]\nbetween = [\"w2\", \"ground\"]\nmu_k = 0.2\n"
                                                    "normal = 10.0\n[simulate]\nt_end = 0.2\n");
    EXPECT_EQ(testing::run_hsnc("simulate '" + ground + "'").exit_code, 0);
    EXPECT_EQ(testing::run_hsnc("simulate --precision mp:30 '" + ground + "'").exit_code, 0);
    // A stuck friction on a coupled M: the kernels derive it (the held force lowered), and inspect says so.
    const testing::CliRun stuck = testing::run_hsnc("inspect '" + ground + "' --config 'stuck=w2'");
    EXPECT_EQ(stuck.exit_code, 0) << stuck.err;
    EXPECT_NE(stuck.out.find("the kernels derive these modes in double-double"), std::string::npos) << stuck.out;
    EXPECT_EQ(stuck.out.find("Eigen solver ("), std::string::npos) << stuck.out;

    testing::TempDir plain;
    const std::string ok = beam_model(plain, "[simulate]\nt_end = 0.5\n");
    const testing::CliRun c = testing::run_hsnc("check '" + ok + "'");
    EXPECT_EQ(c.exit_code, 0) << c.err;
    EXPECT_NE(c.out.find("mass matrix M: coupled (5 off-diagonal pairs"), std::string::npos) << c.out;
    // Sweep kernels redo a lumped modal analysis at run time: refused, never a wrong M.
    testing::TempDir kernels;
    const testing::CliRun params = testing::run_hsnc("generate '" + ok + "' -o '" + kernels.path() + "/k' --params all");
    EXPECT_EQ(params.exit_code, 2) << params.err;
    EXPECT_NE(params.err.find("a coupled (non-diagonal) mass matrix, which sweep kernels do not take yet"), std::string::npos)
        << params.err;
    EXPECT_FALSE(std::filesystem::exists(kernels.path() + "/k"));
    const std::string events = testing::temp_path("events.csv");
    testing::TempDir damped;
    const Beam bar = clamped_bar(2);
    Eigen::MatrixXd C = 1e-3 * bar.K;
    C(0, 0) += 1.0;
    const std::string nonproportional = forced_beam(damped, bar, 50.0, 1.0, "[simulate]\nt_end = 0.1\n", &C).path;
    const testing::CliRun mp =
        testing::run_hsnc("simulate '" + nonproportional + "' --precision mp:30 --events '" + events + "'");
    EXPECT_EQ(mp.exit_code, 2);
    EXPECT_NE(mp.err.find("the reference (--precision mp:N): model 'consistent-cantilever' has a coupled "
                          "(non-diagonal) mass matrix with non-proportional damping"),
              std::string::npos)
        << mp.err;
    EXPECT_FALSE(testing::file_exists(events));
    const testing::CliRun sim = testing::run_hsnc("simulate '" + ok + "' --events '" + events + "' --quiet");
    EXPECT_EQ(sim.exit_code, 0) << sim.err;
    EXPECT_TRUE(testing::file_exists(events));
    std::remove(events.c_str());
}

}  // namespace
}  // namespace hsnc
