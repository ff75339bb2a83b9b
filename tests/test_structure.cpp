// Tests of [structure] (matrices from Matrix Market files) and [[friction]]
// elements to ground (interface.md section 5; model/structure.h,
// model/matrix_market.h).
//
// Exact: a model given as matrices is the same model as its spring version
// (the bundled chain and both seed scenarios rewritten as [structure] give the
// same events to 1e-12 s); a free vibration of a structure whose K is no
// spring network (positive off-diagonal entries) against its closed form from
// the generalised eigenproblem of (K, M) computed here; a friction element
// with normal = m*g gives exactly the events of the mass's own mu_k.
// Bad input: every new key's errors, by message.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <sstream>
#include <string>

#include <Eigen/Eigenvalues>

#include "assembly.h"
#include "cli_runner.h"
#include "engine_runner.h"
#include "error.h"
#include "file_read.h"
#include "matrix_market.h"
#include "modal.h"
#include "model_reader.h"
#include "reference.h"
#include "derivation.h"
#include "emitter.h"
#include "interpreted_solver.h"
#include "jit_solver_provider.h"
#include "lowering.h"

namespace hsnc {
namespace {

namespace fs = std::filesystem;

std::string num(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

/// A folder of its own for the files of one test, removed at the end.
class Folder {
public:
    Folder() {
        path_ = fs::path(::testing::TempDir()) /
                ("hsnc_structure_" + std::to_string(::getpid()) + "_" +
                 ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(path_);
        fs::create_directories(path_);
    }
    ~Folder() { fs::remove_all(path_); }
    std::string write(const std::string& name, const std::string& text) const {
        const std::string p = (path_ / name).string();
        std::ofstream(p) << text;
        return p;
    }
    std::string path(const std::string& name) const { return (path_ / name).string(); }

private:
    fs::path path_;
};

/// A dense matrix in Matrix Market coordinate form (general storage, every nonzero).
std::string market(const Eigen::MatrixXd& A, const char* symmetry = "general") {
    std::ostringstream out;
    int nnz = 0;
    const bool sym = std::string(symmetry) == "symmetric";
    for (Eigen::Index i = 0; i < A.rows(); ++i)
        for (Eigen::Index j = 0; j < A.cols(); ++j)
            if (A(i, j) != 0.0 && (!sym || i >= j)) ++nnz;
    out << "%%MatrixMarket matrix coordinate real " << symmetry << "\n% written by test_structure\n";
    out << A.rows() << " " << A.cols() << " " << nnz << "\n";
    for (Eigen::Index i = 0; i < A.rows(); ++i)
        for (Eigen::Index j = 0; j < A.cols(); ++j)
            if (A(i, j) != 0.0 && (!sym || i >= j)) out << i + 1 << " " << j + 1 << " " << num(A(i, j)) << "\n";
    return out.str();
}

std::string body(const Model& m, int b) { return b == kGround ? "ground" : m.masses[static_cast<std::size_t>(b)].name; }

/// `lumped` written as a [structure]: M, K (springs, all contacts open) and,
/// with Rayleigh damping, C = alpha M + beta K in files; each mass's own
/// friction as a [[friction]] element "f_<mass>" to ground with normal m*g.
std::string as_structure(const Model& lumped, const Folder& dir) {
    const Configuration open = Configuration::all_open(lumped);
    const Eigen::MatrixXd M = mass_vector(lumped).asDiagonal();
    const Eigen::MatrixXd K = stiffness_matrix(lumped, open);
    dir.write("M.mtx", market(M, "symmetric"));
    dir.write("K.mtx", market(K));
    std::ostringstream t;
    t << "name = \"" << lumped.name << "-structure\"\n";
    t << "[structure]\ndofs = [";
    for (std::size_t i = 0; i < lumped.dof(); ++i) t << (i ? ", " : "") << "\"" << lumped.masses[i].name << "\"";
    t << "]\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n";
    if (lumped.alpha != 0.0 || lumped.beta != 0.0) {
        dir.write("C.mtx", market(damping_matrix(lumped, open)));
        t << "damping = \"C.mtx\"\n";
    }
    for (const Contact& c : lumped.contacts)
        t << "[[contact]]\nname = \"" << c.name << "\"\nbetween = [\"" << body(lumped, c.a) << "\", \""
          << body(lumped, c.b) << "\"]\ngap = " << num(c.gap) << "\nk = " << num(c.k) << "\n";
    for (std::size_t i = 0; i < lumped.dof(); ++i) {
        const Mass& m = lumped.masses[i];
        const FrictionSlot& f = lumped.friction_slot(i);
        if (!f.active) continue;
        t << "[[friction]]\nname = \"f_" << m.name << "\"\nbetween = [\"" << m.name
          << "\", \"ground\"]\nmu_k = " << num(f.mu_k) << "\nmu_s = " << num(f.mu_s)
          << "\nnormal = " << num(m.m * lumped.g) << "\n";
    }
    for (const Harmonic& h : lumped.forcing) {
        t << "[[forcing]]\nomega = " << num(h.omega) << "\nphase = " << num(h.phase) << "\namplitude = {";
        for (std::size_t i = 0; i < lumped.dof(); ++i) t << (i ? ", " : " ") << lumped.masses[i].name << " = " << num(h.amplitude[i]);
        t << " }\n";
    }
    t << "[load]\n";
    for (std::size_t i = 0; i < lumped.dof(); ++i) t << lumped.masses[i].name << " = " << num(lumped.load[i]) << "\n";
    t << "[initial]\nt0 = " << num(lumped.t0) << "\nx = {";
    for (std::size_t i = 0; i < lumped.dof(); ++i) t << (i ? ", " : " ") << lumped.masses[i].name << " = " << num(lumped.x0[i]);
    t << " }\nv = {";
    for (std::size_t i = 0; i < lumped.dof(); ++i) t << (i ? ", " : " ") << lumped.masses[i].name << " = " << num(lumped.v0[i]);
    t << " }\n";
    return dir.write("structure.toml", t.str());
}

class StructureEquivalence : public ::testing::TestWithParam<std::pair<const char*, double>> {};

// The bundled models and their matrix versions: same events (kind, element,
// time to 1e-12 s) and the same end state to 1e-9 of its size.
TEST_P(StructureEquivalence, MatricesGiveTheEventsOfTheSpringModel) {
    const auto [file, t_end] = GetParam();
    Folder dir;
    const Model lumped = read_model(testing::model_path(file));
    const Model structure = read_model(as_structure(lumped, dir));
    ASSERT_TRUE(structure.structure.present);
    ASSERT_EQ(structure.dof(), lumped.dof());
    const testing::Outcome a = testing::simulate(lumped, t_end), b = testing::simulate(structure, t_end);
    ASSERT_GT(a.events.size(), 5u) << "the scenario should switch";
    ASSERT_EQ(a.events.size(), b.events.size());
    double worst = 0.0;
    for (std::size_t e = 0; e < a.events.size(); ++e) worst = std::max(worst, std::fabs(a.events[e].t - b.events[e].t));
    std::printf("%s: %zu events, largest time difference %.3g s\n", file, a.events.size(), worst);
    for (std::size_t e = 0; e < a.events.size(); ++e) {
        EXPECT_NEAR(a.events[e].t, b.events[e].t, 1e-12) << "event " << e;
        EXPECT_EQ(a.events[e].kind, b.events[e].kind) << "event " << e;
        EXPECT_EQ(a.events[e].element, b.events[e].element) << "event " << e;
    }
    // The friction rows name the element, the others the contact.
    for (const testing::Recorded& r : b.events)
        if (r.kind == EventKind::stick || r.kind == EventKind::release || r.kind == EventKind::reversal)
            EXPECT_EQ(structure.friction_name(static_cast<std::size_t>(r.element)),
                      "f_" + lumped.masses[static_cast<std::size_t>(r.element)].name);
    double size = 0.0;
    for (std::size_t i = 0; i < lumped.dof(); ++i) size = std::max(size, std::fabs(a.summary.x[i]));
    for (std::size_t i = 0; i < lumped.dof(); ++i) EXPECT_NEAR(a.summary.x[i], b.summary.x[i], 1e-9 * size);
}

// Scenario 2 is weakly chaotic: 20 s keep rounding differences far below 1e-12 s.
INSTANTIATE_TEST_SUITE_P(StructureEquivalence, StructureEquivalence,
                         ::testing::Values(std::make_pair("chain-8.toml", 20.0), std::make_pair("seed-scenario-1.toml", 2.0),
                                           std::make_pair("seed-scenario-2.toml", 20.0)));

// A structure whose K is not a spring network (positive off-diagonal entries:
// the flexibility of a cantilever inverted), free vibration from an initial
// displacement with Rayleigh damping: the engine's trajectory against
// x(t) = Phi q(t) from the generalised eigenproblem K phi = lambda M phi,
// each mode a damped oscillator, computed here independently of hsnc's modal code.
TEST(StructureClosedForm, FreeVibrationOfADenseStiffnessMatrix) {
    Folder dir;
    const int n = 4;
    const double L = 0.25, EI = 50.0;
    Eigen::MatrixXd F(n, n);  // cantilever flexibility: F_ij = x_i^2 (3 x_j - x_i) / (6 EI), x_i <= x_j
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double a = L * (std::min(i, j) + 1), b = L * (std::max(i, j) + 1);
            F(i, j) = a * a * (3 * b - a) / (6 * EI);
        }
    Eigen::MatrixXd K = F.inverse();
    K = 0.5 * (K + K.transpose());
    bool positive_off_diagonal = false;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) positive_off_diagonal |= i != j && K(i, j) > 0;
    ASSERT_TRUE(positive_off_diagonal) << "the test needs a K that is no spring network";
    const Eigen::VectorXd m = Eigen::VectorXd::Constant(n, 0.5);
    const double alpha = 0.3, beta = 2e-4;
    dir.write("M.mtx", market(Eigen::MatrixXd(m.asDiagonal()), "symmetric"));
    dir.write("K.mtx", market(K, "symmetric"));
    dir.write("C.mtx", market(alpha * Eigen::MatrixXd(m.asDiagonal()) + beta * K));
    const std::string path = dir.write("beam.toml", R"(name = "beam"
[structure]
dofs = ["w1", "w2", "w3", "w4"]
mass = "M.mtx"
stiffness = "K.mtx"
damping = "C.mtx"
[initial]
x = { w4 = 0.01, w2 = -0.004 }
v = { w1 = 0.3 }
)");
    const Model model = read_model(path);
    // The fit recovers a and b to the rounding of C's entries (|C| <= c_max):
    // |da| m and |db| |K|max within a few ulps of c_max.
    const Eigen::MatrixXd C = alpha * Eigen::MatrixXd(m.asDiagonal()) + beta * K;
    const double c_max = C.cwiseAbs().maxCoeff(), k_max = K.cwiseAbs().maxCoeff(), eps = 2.220446049250313e-16;
    EXPECT_LE(std::fabs(model.alpha - alpha) * 0.5, 16 * eps * c_max) << model.alpha;
    EXPECT_LE(std::fabs(model.beta - beta) * k_max, 16 * eps * c_max) << model.beta;
    const testing::Outcome r = testing::simulate(model, 1.0, 0.01);
    ASSERT_EQ(r.samples.size(), 101u);

    // Closed form: M^-1/2 K M^-1/2 = V diag(lambda) V^T, Phi = M^-1/2 V.
    const Eigen::VectorXd s = m.cwiseSqrt().cwiseInverse();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(s.asDiagonal() * K * s.asDiagonal());
    const Eigen::MatrixXd phi = s.asDiagonal() * es.eigenvectors();
    Eigen::VectorXd x0(n), v0(n);
    x0 << 0, -0.004, 0, 0.01;
    v0 << 0.3, 0, 0, 0;
    const Eigen::VectorXd q0 = phi.transpose() * m.asDiagonal() * x0, qd0 = phi.transpose() * m.asDiagonal() * v0;
    double worst = 0.0;
    for (const testing::Recorded& row : r.samples) {
        Eigen::VectorXd q(n);
        for (int j = 0; j < n; ++j) {
            const double w = std::sqrt(es.eigenvalues()(j)), zeta = 0.5 * (alpha / w + beta * w);
            ASSERT_LT(zeta, 1.0);
            const double wd = w * std::sqrt(1 - zeta * zeta), sg = zeta * w;
            q(j) = std::exp(-sg * row.t) * (q0(j) * std::cos(wd * row.t) + (qd0(j) + sg * q0(j)) / wd * std::sin(wd * row.t));
        }
        const Eigen::VectorXd x = phi * q;
        for (int i = 0; i < n; ++i) worst = std::max(worst, std::fabs(x(i) - row.x[static_cast<std::size_t>(i)]));
    }
    EXPECT_LT(worst, 1e-13);  // of a 1e-2 m motion
}

/// A 3-dof structure with a dense K (one positive off-diagonal entry), two
/// friction elements to ground with their own normal forces, a contact and forcing.
Model friction_structure(const Folder& dir) {
    dir.write("M.mtx", "%%MatrixMarket matrix array real symmetric\n3 3\n1\n0\n0\n2\n0\n1.5\n");
    dir.write("K.mtx", "%%MatrixMarket matrix array real symmetric\n3 3\n300\n-150\n40\n320\n-120\n180\n");
    return read_model(dir.write("s.toml", R"(name = "s3"
[structure]
dofs = ["a", "b", "c"]
mass = "M.mtx"
stiffness = "K.mtx"
[[friction]]
name = "fa"
between = ["a", "ground"]
mu_k = 0.3
mu_s = 0.4
normal = 20
[[friction]]
between = ["ground", "c"]
mu_k = 0.2
normal = 35
[[contact]]
between = ["b", "c"]
gap = 0.05
k = 500
[[forcing]]
omega = 9
amplitude = { a = 30, c = -10 }
[initial]
x = { b = 0.1 }
)"));
}

// The bundled cracked beam (a dense K from a file, a breathing-crack contact):
// the double engine against the CLN reference at 30 digits (an independent
// arithmetic of the same method), and against the rk45 baseline at tight
// tolerances (an independent method): the same events, times within 1e-11 s
// of the reference and 1e-9 s of rk45.
TEST(StructureClosedForm, BundledCrackedBeamAgreesWithReferenceAndBaseline) {
    const Model model = read_model(std::string(HSNC_SOURCE_DIR) + "/examples/beam-crack/beam-crack.toml");
    const double t_end = 4.0;
    const testing::Outcome a = testing::simulate(model, t_end);
    testing::Recorder ref(model.dof());
    EngineOptions opt;
    opt.t_end = t_end;
    reference::simulate(model, 30, opt, ref);
    const testing::Outcome rk = testing::baseline(model, t_end, 1e-12, 1e-15);
    ASSERT_GT(a.events.size(), 10u);
    ASSERT_EQ(a.events.size(), ref.events.size());
    ASSERT_EQ(a.events.size(), rk.events.size());
    for (std::size_t e = 0; e < a.events.size(); ++e) {
        EXPECT_EQ(a.events[e].kind, ref.events[e].kind);
        EXPECT_EQ(a.events[e].kind, rk.events[e].kind);
        EXPECT_NEAR(a.events[e].t, ref.events[e].t, 1e-11) << "event " << e;
        EXPECT_NEAR(a.events[e].t, rk.events[e].t, 1e-9) << "event " << e;
    }
}

// A structure with dense K, friction elements to ground with their own normal
// forces and a contact: stick-slip against the reference.
TEST(StructureClosedForm, FrictionElementsOnAStructureAgreeWithReference) {
    Folder dir;
    const Model model = friction_structure(dir);
    EXPECT_EQ(model.frictions[1].name, "friction2");
    const double t_end = 6.0;
    const testing::Outcome a = testing::simulate(model, t_end);
    testing::Recorder ref(model.dof());
    EngineOptions opt;
    opt.t_end = t_end;
    reference::simulate(model, 30, opt, ref);
    int sticks = 0;
    for (const testing::Recorded& r : a.events) sticks += r.kind == EventKind::stick ? 1 : 0;
    EXPECT_GT(sticks, 3) << "the model should stick and slip";
    ASSERT_EQ(a.events.size(), ref.events.size());
    for (std::size_t e = 0; e < a.events.size(); ++e) {
        EXPECT_EQ(a.events[e].kind, ref.events[e].kind);
        EXPECT_EQ(a.events[e].element, ref.events[e].element);
        EXPECT_NEAR(a.events[e].t, ref.events[e].t, 1e-11) << "event " << e;
    }
}

/// Events of `model` run by the engine with `provider`.
std::vector<testing::Recorded> events_with(const Model& model, SolverProvider& provider, double t_end) {
    Engine engine(model, provider);
    testing::Recorder rec(model.dof());
    EngineOptions opt;
    opt.t_end = t_end;
    const RunSummary s = engine.run(opt, rec);
    EXPECT_EQ(s.status, RunStatus::ok) << s.message;
    return rec.events;
}

// The generator's programs for structures (negative springs, friction
// elements): the interpreted program and the JIT-compiled kernel give the same
// events bit for bit, and both agree with the generic solver to 1e-12 s.
TEST(StructureKernels, InterpreterJitAndGenericSolverAgree) {
    Folder dir;
    const Model beam = read_model(std::string(HSNC_SOURCE_DIR) + "/examples/beam-crack/beam-crack.toml");
    const Model pads = friction_structure(dir);
    for (const Model* m : {&beam, &pads}) {
        InterpretedSolverProvider interp([m](const Configuration& cfg) { return lower(derive(*m, cfg)); });
        JitSolverProvider jit(*m, [m](const Configuration& cfg) {
            return JitKernelSource{kernel_symbol(*m, cfg), emit_kernel(derive(*m, cfg))};
        });
        const auto ei = events_with(*m, interp, 4.0), ej = events_with(*m, jit, 4.0);
        const testing::Outcome g = testing::simulate(*m, 4.0);
        ASSERT_GT(ei.size(), 10u) << m->name;
        ASSERT_EQ(ei.size(), ej.size()) << m->name;
        ASSERT_EQ(ei.size(), g.events.size()) << m->name;
        for (std::size_t e = 0; e < ei.size(); ++e) {
            EXPECT_EQ(ei[e].t, ej[e].t) << m->name << " event " << e;
            EXPECT_EQ(ei[e].x, ej[e].x) << m->name << " event " << e;
            EXPECT_EQ(ei[e].kind, g.events[e].kind) << m->name << " event " << e;
            EXPECT_NEAR(ei[e].t, g.events[e].t, 1e-12) << m->name << " event " << e;
        }
    }
}

// A [[friction]] element to ground with normal = m*g is the mass's own mu_k:
// exactly the same events (bit for bit), named by the element.
TEST(FrictionElement, NormalMgIsTheMassOwnFriction) {
    const Model own = read_model(testing::model_path("seed-scenario-2.toml"));
    std::string text = R"(name = "seed-2-elements"
[parameters]
m1 = 1
m2 = 2
mu_k = 0.6
mu_s = 0.75
[[mass]]
name = "m1"
m = "m1"
[[mass]]
name = "m2"
m = "m2"
[[spring]]
between = ["ground", "m1"]
k = 5
[[spring]]
between = ["m1", "m2"]
k = 10
[[spring]]
between = ["m2", "ground"]
k = 40
[[contact]]
between = ["m1", "m2"]
gap = 0.2
k = 100
[[friction]]
name = "floor1"
between = ["m1", "ground"]
mu_k = "mu_k"
mu_s = "mu_s"
normal = "m1*g"
[[friction]]
name = "floor2"
between = ["ground", "m2"]
mu_k = "mu_k"
mu_s = "mu_s"
[[forcing]]
omega = 17.5515
amplitude = { m1 = 225, m2 = 150 }
[initial]
x = { m1 = 0.2, m2 = -0.1 }
v = { m1 = -5.0, m2 = -2.0 }
)";
    const Model elements = parse_model(text, "elements.toml");
    ASSERT_EQ(elements.frictions.size(), 2u);
    EXPECT_EQ(elements.friction_slot(0).mu_k, own.friction_slot(0).mu_k);
    EXPECT_EQ(elements.friction_slot(1).mu_s, own.friction_slot(1).mu_s);
    const testing::Outcome a = testing::simulate(own, 30.0), b = testing::simulate(elements, 30.0);
    ASSERT_GT(a.events.size(), 20u);
    ASSERT_EQ(a.events.size(), b.events.size());
    for (std::size_t e = 0; e < a.events.size(); ++e) {
        EXPECT_EQ(a.events[e].t, b.events[e].t) << "event " << e;
        EXPECT_EQ(a.events[e].kind, b.events[e].kind);
        EXPECT_EQ(a.events[e].element, b.events[e].element);
        EXPECT_EQ(a.events[e].x, b.events[e].x);
    }
    EXPECT_EQ(elements.friction_name(0), "floor1");
    EXPECT_EQ(elements.friction_name(1), "floor2");
    // The configuration spec names the element.
    Configuration cfg = Configuration::parse(elements, "stuck=floor2");
    EXPECT_EQ(cfg.spec(elements), "closed= stuck=floor2");
}

// A normal force other than m*g scales the friction force: N = 2 m g acts as mu_k doubled.
TEST(FrictionElement, NormalForceScalesTheFrictionForce) {
    const Model m = parse_model(R"(name = "n"
[[mass]]
name = "b"
m = 3
[[friction]]
between = ["b", "ground"]
mu_k = 0.2
mu_s = 0.3
normal = "2*3*g"
)", "n.toml");
    EXPECT_EQ(m.frictions[0].name, "friction1");
    EXPECT_NEAR(m.friction_slot(0).mu_k * m.normal_force(0), 0.2 * 6 * 9.81, 1e-14);
    EXPECT_NEAR(m.friction_slot(0).mu_s * m.normal_force(0), 0.3 * 6 * 9.81, 1e-14);
}

// A [[friction]] element's `normal` is used as given (FrictionSlot::normal in elements/friction.h),
// never carried through m*g: the same model under any g gives the same bits,
// on the Eigen solver and on the programs (interpreter, exact GiNaC
// products), and the reference at 30 digits the same events.
TEST(FrictionElement, AGivenNormalForceMakesTheRunIndependentOfG) {
    auto model = [](const char* g) {
        return parse_model(std::string("name = \"pad\"\n[parameters]\ng = ") + g + R"(
[[mass]]
name = "m1"
m = 1.3
[[mass]]
name = "m2"
m = 0.7
[[spring]]
between = ["ground", "m1"]
k = 200
[[spring]]
between = ["m1", "m2"]
k = 60
[[contact]]
between = ["m2", "ground"]
gap = 0.05
k = 900
[[friction]]
name = "pad"
between = ["m1", "ground"]
mu_k = 0.15
mu_s = 0.2
normal = 20
[[forcing]]
omega = 9.0
amplitude = { m2 = 12 }
[initial]
x = { m1 = 0.02, m2 = 0.0 }
v = { m1 = 0.1, m2 = 0.0 }
)", "pad.toml");
    };
    const Model base = model("9.81");
    EXPECT_EQ(base.friction_slot(0).mu_s, 0.2) << "the element's coefficients, not equivalent ones";
    EXPECT_EQ(base.normal_force(0), 20.0);
    for (testing::Solvers solvers : {testing::Solvers::generic, testing::Solvers::interp}) {
        const testing::Outcome a = testing::simulate(base, 6.0, 0.0, solvers);
        int sticks = 0;
        for (const testing::Recorded& r : a.events) sticks += r.kind == EventKind::stick ? 1 : 0;
        ASSERT_GT(sticks, 3) << "the model should stick and slip";
        for (const char* g : {"1", "1e6", "3.7e-3"}) {
            const testing::Outcome b = testing::simulate(model(g), 6.0, 0.0, solvers);
            ASSERT_EQ(a.events.size(), b.events.size()) << "g = " << g;
            for (std::size_t e = 0; e < a.events.size(); ++e) {
                EXPECT_EQ(a.events[e].t, b.events[e].t) << "g = " << g << ", event " << e;
                EXPECT_EQ(a.events[e].x, b.events[e].x) << "g = " << g << ", event " << e;
            }
        }
    }
    const testing::Outcome a = testing::simulate(base, 6.0);
    testing::Recorder ref(base.dof());
    EngineOptions opt;
    opt.t_end = 6.0;
    reference::simulate(base, 30, opt, ref);
    ASSERT_EQ(a.events.size(), ref.events.size());
    for (std::size_t e = 0; e < a.events.size(); ++e) {
        EXPECT_EQ(a.events[e].kind, ref.events[e].kind) << "event " << e;
        EXPECT_NEAR(a.events[e].t, ref.events[e].t, 1e-11) << "event " << e;
    }
}

// ---------------------------------------------------------------- Matrix Market

std::string market_error(const std::string& text) {
    try {
        parse_matrix_market(text, "A.mtx");
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected an InputError for:\n" << text;
    return "";
}

void expect_message(const std::string& message, std::initializer_list<const char*> parts) {
    for (const char* part : parts)
        EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
}

TEST(MatrixMarket, ReadsCoordinateAndArrayForms) {
    const MarketMatrix c = parse_matrix_market(
        "%%MatrixMarket matrix coordinate real symmetric\n%c\n\n2 2 2\n1 1 4.5\n2 1 -1e-3\n", "c.mtx");
    EXPECT_EQ(c.rows, 2u);
    EXPECT_EQ(c(0, 0), 4.5);
    EXPECT_EQ(c(0, 1), -1e-3);
    EXPECT_EQ(c(1, 0), -1e-3);
    EXPECT_EQ(c(1, 1), 0.0);
    const MarketMatrix a = parse_matrix_market("%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n4\n", "a.mtx");
    EXPECT_EQ(a(1, 0), 2.0);  // column by column
    EXPECT_EQ(a(0, 1), 3.0);
    const MarketMatrix s = parse_matrix_market("%%MatrixMarket matrix array integer symmetric\n2 2\n1\n2\n3\n", "s.mtx");
    EXPECT_EQ(s(0, 1), 2.0);
    EXPECT_EQ(s(1, 1), 3.0);
}

TEST(MatrixMarket, EveryErrorNamesFileAndLine) {
    expect_message(market_error(""), {"A.mtx: empty file"});
    expect_message(market_error("1 1 1\n"), {"A.mtx:1: expected the header"});
    expect_message(market_error("%%MatrixMarket matrix coordinate complex general\n"), {"A.mtx:1: field 'complex'"});
    expect_message(market_error("%%MatrixMarket matrix coordinate real hermitian\n"), {"A.mtx:1: symmetry 'hermitian'"});
    expect_message(market_error("%%MatrixMarket matrix coordinate real general\n"), {"A.mtx: missing the size line"});
    expect_message(market_error("%%MatrixMarket matrix coordinate real general\n2 2\n"), {"A.mtx:2: size line must be"});
    expect_message(market_error("%%MatrixMarket matrix coordinate real general\n2 2 1\n3 1 1.0\n"),
                   {"A.mtx:3: entry (3, 1) is outside the 2 x 2 matrix"});
    expect_message(market_error("%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1.0\n1 1 2.0\n"),
                   {"A.mtx:4: entry (1, 1) is given twice"});
    expect_message(market_error("%%MatrixMarket matrix coordinate real symmetric\n2 2 1\n1 2 1.0\n"),
                   {"A.mtx:3: entry (1, 2) is above the diagonal"});
    expect_message(market_error("%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1.0\n"),
                   {"A.mtx: the size line announces 2 entries, the file ends after 1"});
    expect_message(market_error("%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 1.0\n2 2 1.0\n"),
                   {"A.mtx:4: more entries than the size line announces"});
    expect_message(market_error("%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 abc\n"), {"A.mtx:3: 'abc' is not a number"});
    expect_message(market_error("%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 nan\n"), {"A.mtx:3: 'nan' is not a finite double"});
    expect_message(market_error("%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 1e-320\n"),
                   {"A.mtx:3: '1e-320' is below the smallest normal double"});
    expect_message(market_error("%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 1.0 7\n"),
                   {"A.mtx:3: expected an entry 'ROW COLUMN VALUE'"});
    expect_message(market_error("%%MatrixMarket matrix array real general\n2 1\n1\n"), {"A.mtx: the file ends before entry (2, 1)"});
    expect_message(market_error("%%MatrixMarket matrix array real symmetric\n2 3\n"), {"A.mtx:2: a symmetric matrix must be square"});
}

// A NUL ends the C string strtod reads ("1\0garbage" read as 1), and an
// integer file's "1.5" is no integer: each refused, by line.
template <std::size_t N>
std::string with_nul(const char (&text)[N]) {
    return std::string(text, N - 1);  // the whole literal, past its embedded NUL
}

TEST(MatrixMarket, NulBytesAndNonIntegersAreRefused) {
    expect_message(market_error(with_nul("%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 1\0garbage\n")),
                   {"A.mtx:3: contains a NUL byte"});
    expect_message(market_error(with_nul("%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 1\0\n")),
                   {"A.mtx:3: contains a NUL byte"});
    expect_message(market_error("%%MatrixMarket matrix coordinate integer general\n2 2 1\n1 1 1.5\n"),
                   {"A.mtx:3: '1.5' is not an integer (the header says the field is integer)"});
    expect_message(market_error("%%MatrixMarket matrix array integer general\n1 2\n3\n2e3\n"),
                   {"A.mtx:4: '2e3' is not an integer"});
    expect_message(market_error("%%MatrixMarket matrix array integer general\n1 2\n3\n-\n"), {"A.mtx:4: '-' is not an integer"});
    const MarketMatrix m = parse_matrix_market("%%MatrixMarket matrix array integer general\n1 3\n+3\n-2\n007\n", "i.mtx");
    EXPECT_EQ(m.values, (std::vector<double>{3.0, -2.0, 7.0}));
}

// ---------------------------------------------------------------- bad [structure] and [[friction]]

/// The message of reading `model` (written as s.toml beside `files`) in a fresh folder.
std::string structure_error(const std::string& model, const std::map<std::string, std::string>& files) {
    Folder dir;
    for (const auto& [name, text] : files) dir.write(name, text);
    const std::string path = dir.write("s.toml", model);
    try {
        read_model(path);
    } catch (const InputError& e) {
        std::string m = e.what();
        // Report paths relative to the folder, so messages can be compared.
        const std::string prefix = dir.path("");
        for (std::size_t p; (p = m.find(prefix)) != std::string::npos;) m.erase(p, prefix.size());
        return m;
    }
    ADD_FAILURE() << "expected an InputError for:\n" << model;
    return "";
}

const char* const kM2 = "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1\n2 2 2\n";
const char* const kK2 = "%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 20\n2 1 -10\n2 2 10\n";
const std::string kHead = "name = \"s\"\n[structure]\ndofs = [\"u1\", \"u2\"]\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n";

std::string with_matrices(const std::string& extra, const char* M = kM2, const char* K = kK2,
                          const char* C = nullptr) {
    std::map<std::string, std::string> files{{"M.mtx", M}, {"K.mtx", K}};
    if (C) files["C.mtx"] = C;
    return structure_error(kHead + extra, files);
}

TEST(StructureInput, AGoodStructureReads) {
    Folder dir;
    dir.write("M.mtx", kM2);
    dir.write("K.mtx", kK2);
    const Model m = read_model(dir.write("s.toml", kHead + "[[contact]]\nbetween = [\"u2\", \"ground\"]\ngap = 0.1\nk = 50\n"));
    ASSERT_EQ(m.dof(), 2u);
    EXPECT_EQ(m.masses[1].name, "u2");
    EXPECT_EQ(m.masses[1].m, 2.0);
    const Eigen::MatrixXd K = stiffness_matrix(m, Configuration::all_open(m));
    EXPECT_EQ(K(0, 0), 20.0);
    EXPECT_EQ(K(0, 1), -10.0);
    EXPECT_EQ(K(1, 1), 10.0);
    EXPECT_EQ(m.springs.size(), 2u);  // u1-u2 and u1 to ground; u2's row sums to 0
}

TEST(StructureInput, FilesAndMatrices) {
    expect_message(structure_error(kHead, {{"K.mtx", kK2}}),
                   {"s.toml:4: key 'structure.mass': cannot read matrix file 'M.mtx': No such file"});
    expect_message(with_matrices("", "%%MatrixMarket matrix coordinate real general\n2 2 1\n1 9 1\n"),
                   {"key 'structure.mass': M.mtx:3: entry (1, 9) is outside"});
    expect_message(with_matrices("", "%%MatrixMarket matrix coordinate real general\n3 3 3\n1 1 1\n2 2 1\n3 3 1\n"),
                   {"key 'structure.mass': M.mtx: M is 3 x 3, expected 2 x 2"});
    expect_message(with_matrices("", "%%MatrixMarket matrix coordinate real general\n2 2 3\n1 1 1\n2 2 1\n1 2 0.5\n"),
                   {"key 'structure.mass'", "M is not symmetric: M(u2, u1) = 0 but M(u1, u2) = 0.5"});
    expect_message(with_matrices("", "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1\n2 2 -2\n"),
                   {"key 'structure.mass'", "M is not positive definite: M(u2, u2) = -2"});
    expect_message(with_matrices("", "%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 1\n2 1 2\n2 2 1\n"),
                   {"key 'structure.mass'", "M is not positive definite"});
    expect_message(with_matrices("", kM2, "%%MatrixMarket matrix coordinate real general\n2 2 3\n1 1 20\n1 2 -10\n2 2 10\n"),
                   {"key 'structure.stiffness'", "K is not symmetric: K(u2, u1) = 0 but K(u1, u2) = -10"});
    expect_message(with_matrices("", kM2, "%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 1\n2 1 -10\n2 2 1\n"),
                   {"key 'structure.stiffness'", "K is not positive semi-definite"});
    expect_message(with_matrices("", kM2, "%%MatrixMarket matrix coordinate real symmetric\n2 2 2\n1 1 5\n2 2 -1\n"),
                   {"key 'structure.stiffness'", "K is not positive semi-definite: K(u2, u2) = -1"});
    // Singular with a null vector (1, -1): no free translation.
    expect_message(with_matrices("", kM2, "%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 1\n2 1 1\n2 2 1\n"),
                   {"key 'structure.stiffness'", "K is singular beyond a free translation (dofs u1, u2)"});
    expect_message(with_matrices("", kM2, "%%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 1\n"),
                   {"key 'structure.stiffness'", "K is 1 x 1, expected 2 x 2"});
}

TEST(StructureInput, FreeTranslationIsAccepted) {
    Folder dir;
    dir.write("M.mtx", kM2);
    dir.write("K.mtx", "%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 10\n2 1 -10\n2 2 10\n");
    const Model m = read_model(dir.write("s.toml", kHead));
    ASSERT_EQ(m.springs.size(), 1u);  // rows sum to zero: no spring to ground
    EXPECT_EQ(m.springs[0].k, 10.0);
}

TEST(StructureInput, Damping) {
    // C = 0.5 M + 0.01 K is Rayleigh damping.
    Folder dir;
    dir.write("M.mtx", kM2);
    dir.write("K.mtx", kK2);
    dir.write("C.mtx", "%%MatrixMarket matrix coordinate real general\n2 2 4\n1 1 0.7\n1 2 -0.1\n2 1 -0.1\n2 2 1.1\n");
    const Model m = read_model(dir.write("s.toml", kHead + "damping = \"C.mtx\"\n"));
    EXPECT_NEAR(m.alpha, 0.5, 1e-15);
    EXPECT_NEAR(m.beta, 0.01, 1e-17);
    // A C that is not proportional becomes dampers, as K becomes springs: a
    // lone dashpot on u2 (to ground), and a coupling u1-u2 with the row sums.
    dir.write("C.mtx", "%%MatrixMarket matrix coordinate real general\n2 2 1\n2 2 0.3\n");
    const Model lone = read_model(dir.path("s.toml"));
    EXPECT_EQ(lone.alpha, 0.0);
    EXPECT_EQ(lone.beta, 0.0);
    ASSERT_EQ(lone.dampers.size(), 1u);
    EXPECT_EQ(lone.dampers[0].a, 1);
    EXPECT_EQ(lone.dampers[0].b, kGround);
    EXPECT_EQ(lone.dampers[0].c, 0.3);
    EXPECT_TRUE(lone.dampers[0].from_structure);
    dir.write("C.mtx", "%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 0.5\n2 1 -0.2\n2 2 0.2\n");
    const Model coupled = read_model(dir.path("s.toml"));
    ASSERT_EQ(coupled.dampers.size(), 2u);  // 0.2 between u1 and u2, 0.3 from u1 to ground
    EXPECT_EQ(coupled.dampers[0].a, 0);
    EXPECT_EQ(coupled.dampers[0].b, 1);
    EXPECT_EQ(coupled.dampers[0].c, 0.2);
    EXPECT_EQ(coupled.dampers[1].b, kGround);
    EXPECT_NEAR(coupled.dampers[1].c, 0.3, 1e-16);
    EXPECT_TRUE(damping_matrix(coupled, Configuration::all_open(coupled))
                    .isApprox((Eigen::Matrix2d() << 0.5, -0.2, -0.2, 0.2).finished(), 1e-15));
    // The same physics as [[damper]]s: the same events, bit for bit.
    {
        const std::string extra = "[[contact]]\nname = \"stop\"\nbetween = [\"u2\", \"ground\"]\ngap = 0.01\nk = 500\n"
                                  "[initial]\nv = { u2 = 0.4 }\n";
        dir.write("C.mtx", "%%MatrixMarket matrix coordinate real general\n2 2 1\n2 2 0.3\n");
        const Model a = read_model(dir.write("a.toml", kHead + "damping = \"C.mtx\"\n" + extra));
        const Model b = read_model(dir.write("b.toml", kHead + "[[damper]]\nbetween = [\"u2\", \"ground\"]\nc = 0.3\n" + extra));
        const testing::Outcome ra = testing::simulate(a, 5.0), rb = testing::simulate(b, 5.0);
        ASSERT_GT(ra.events.size(), 4u);
        ASSERT_EQ(ra.events.size(), rb.events.size());
        for (std::size_t e = 0; e < ra.events.size(); ++e) EXPECT_EQ(ra.events[e].t, rb.events[e].t);
    }
    expect_message(with_matrices("damping = \"C.mtx\"\n", kM2, kK2, "%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 0.1\n2 1 -1\n2 2 0.1\n"),
                   {"s.toml:6: key 'structure.damping': C.mtx: C is not positive semi-definite"});
    expect_message(with_matrices("damping = \"C.mtx\"\n", kM2, kK2, "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 -1\n2 2 -2\n"),
                   {"key 'structure.damping'", "Rayleigh coefficients must be >= 0"});
    expect_message(with_matrices("damping = \"C.mtx\"\n[damping]\nalpha = 1\n", kM2, kK2,
                                 "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1\n2 2 2\n"),
                   {"key 'damping': [damping] and structure.damping both give the damping"});
}

TEST(StructureInput, KeysAndNames) {
    expect_message(structure_error("name = \"s\"\n[structure]\nmass = \"M.mtx\"\n", {}),
                   {"s.toml:2: key 'structure.dofs': required key is missing"});
    expect_message(structure_error("name = \"s\"\n[structure]\ndofs = []\n", {}),
                   {"key 'structure.dofs': expected a non-empty list of dof names"});
    expect_message(structure_error("name = \"s\"\n[structure]\ndofs = [\"u1\", \"u1\"]\n", {}),
                   {"key 'structure.dofs[2]': name 'u1' is already used by structure.dofs[1]"});
    expect_message(structure_error("name = \"s\"\n[structure]\ndofs = [\"ground\"]\n", {}),
                   {"key 'structure.dofs[1]': 'ground' is reserved"});
    expect_message(structure_error("name = \"s\"\n[structure]\ndofs = [\"1x\"]\n", {}),
                   {"key 'structure.dofs[1]': '1x' is not a valid name"});
    expect_message(structure_error("name = \"s\"\n[structure]\ndofs = [\"u\"]\nmass = \"M.mtx\"\nstiff = 1\n", {}),
                   {"s.toml:5: key 'structure.stiff': unknown key"});
    expect_message(structure_error("name = \"s\"\n[structure]\ndofs = [\"u\"]\n[[mass]]\nname = \"m\"\nm = 1\n", {}),
                   {"key 'mass': [[mass]] and [structure] exclude each other"});
    expect_message(with_matrices("[load]\nu3 = 1\n"), {"s.toml:7: key 'load.u3': unknown dof 'u3'"});
    expect_message(with_matrices("[[spring]]\nbetween = [\"u1\", \"m9\"]\nk = 1\n"),
                   {"key 'spring[1].between': unknown body 'm9' (expected 'ground' or a dof name)"});
    expect_message(with_matrices("[initial]\nx = { u9 = 1 }\n"), {"key 'initial.x.u9': unknown dof 'u9'"});
    expect_message(with_matrices("[[jenkins]]\nbetween = [\"u1\", \"ground\"]\n"),
                   {"key 'jenkins[1].k': required key is missing"});
}

TEST(FrictionInput, EveryKeyChecked) {
    const std::string f = "[[friction]]\nname = \"f\"\nbetween = [\"u1\", \"ground\"]\nmu_k = 0.3\n";
    expect_message(with_matrices(f), {"s.toml:6: key 'friction[1].normal': required key is missing (a dof has no weight"});
    expect_message(with_matrices(f + "normal = 0\n"), {"s.toml:10: key 'friction[1].normal': normal force must be > 0, got 0"});
    expect_message(with_matrices(f + "normal = 1\nmu_s = 0.2\n"),
                   {"key 'friction[1].mu_s': static coefficient must be >= mu_k = 0.3, got 0.2"});
    expect_message(with_matrices("[[friction]]\nbetween = [\"u1\", \"ground\"]\nmu_k = -1\nnormal = 1\n"),
                   {"key 'friction[1].mu_k': must be >= 0"});
    expect_message(with_matrices("[[friction]]\nbetween = [\"u1\", \"ground\"]\nnormal = 1\n"),
                   {"key 'friction[1].mu_k': required key is missing"});
    // Between two dofs (tests/test_friction_pair.cpp, test_shared_partner.cpp): u2 rides u1, which has
    // friction against the ground (a chain); a loop through the ground is refused.
    {
        Folder dir;
        dir.write("M.mtx", kM2);
        dir.write("K.mtx", kK2);
        const Model m = read_model(dir.write(
            "s.toml", kHead + f + "normal = 1\n[[friction]]\nbetween = [\"u2\", \"u1\"]\nmu_k = 0.1\nnormal = 1\n"));
        EXPECT_EQ(m.friction_slot(1).partner, 0);
        EXPECT_EQ(m.friction_slot(0).partner, kGround);
    }
    expect_message(
        with_matrices(f + "normal = 1\n[[friction]]\nbetween = [\"u2\", \"ground\"]\nmu_k = 0.1\nnormal = 1\n" +
                      "[[friction]]\nbetween = [\"u2\", \"u1\"]\nmu_k = 0.1\nnormal = 1\n"),
        {"key 'friction[3].between': 'u1' and 'u2' both have friction against the ground"});
    expect_message(with_matrices(f + "normal = 1\n[[friction]]\nbetween = [\"ground\", \"u1\"]\nmu_k = 0.1\nnormal = 1\n"),
                   {"key 'friction[2].between': 'u1' already has friction (element 'f')"});
    expect_message(with_matrices(f + "normal = 1\nmu = 2\n"), {"key 'friction[1].mu': unknown key"});
    expect_message(with_matrices("[[friction]]\nname = \"u2\"\nbetween = [\"u1\", \"ground\"]\nmu_k = 0.1\nnormal = 1\n"),
                   {"key 'friction[1].name': name 'u2' is already used by structure.dofs[2]"});
    expect_message(structure_error("name = \"s\"\n[[mass]]\nname = \"m\"\nm = 1\nmu_k = 0.1\n[[friction]]\nbetween = [\"m\", \"ground\"]\nmu_k = 0.2\n", {}),
                   {"key 'friction[1].between': 'm' already has friction (its own mu_k)"});
}

// A path holding a NUL would open the file named by its part before the NUL.
TEST(StructureInput, APathWithANulCharacterIsRefused) {
    Folder dir;
    dir.write("M.mtx", kM2);
    dir.write("K.mtx", kK2);
    const std::string model = "name = \"s\"\n[structure]\ndofs = [\"u1\", \"u2\"]\nmass = \"M.mtx\"\n"
                              "stiffness = \"K.mtx\\u0000.bak\"\n";
    expect_message(structure_error(model, {{"M.mtx", kM2}, {"K.mtx", kK2}}),
                   {"s.toml:5: key 'structure.stiffness': 'K.mtx .bak': a path cannot hold a NUL character"});
    const FileRead r = read_regular_file(dir.path("K.mtx") + std::string(1, '\0') + ".bak", 1 << 20);
    EXPECT_EQ(r.status, FileRead::Status::refused);
    EXPECT_EQ(r.problem, "the path contains a NUL character");
}

// A structure scaled by 1e200 or 1e-200 is the same structure: the Jacobi
// scaling of the definiteness checks took sqrt(d_i * d_j), which overflows
// beyond 1.3e154 (and underflows below 1.5e-154) and called such M and K
// "not positive definite". Same natural frequencies, same Rayleigh damping.
TEST(StructureInput, ScaledMatricesGiveTheSameFrequencies) {
    const std::string beam = std::string(HSNC_SOURCE_DIR) + "/examples/beam-crack/";
    const Model ref = read_model(beam + "beam-crack.toml");
    const ModalDecomposition ref_modes = modal_analysis(ref, Configuration::all_open(ref));
    for (const double scale : {1e200, 1e-200, 1e300, 1e-300}) {
        Folder dir;
        for (const char* name : {"M", "K", "C"}) {
            MarketMatrix A = read_matrix_market(beam + name + ".mtx");
            Eigen::MatrixXd scaled(A.rows, A.cols);
            for (std::size_t i = 0; i < A.rows; ++i)
                for (std::size_t j = 0; j < A.cols; ++j) scaled(i, j) = A(i, j) * scale;
            dir.write(std::string(name) + ".mtx", market(scaled));
        }
        std::ifstream in(beam + "beam-crack.toml");
        const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        const std::string path = dir.write("beam-crack.toml", text);
        Model m;
        try {
            m = read_model(path);
        } catch (const InputError& e) {
            ADD_FAILURE() << "scale " << scale << ": " << e.what();
            continue;
        }
        EXPECT_NEAR(m.alpha, ref.alpha, 1e-12 * ref.alpha) << scale;
        EXPECT_NEAR(m.beta, ref.beta, 1e-12 * ref.beta) << scale;
        const ModalDecomposition modes = modal_analysis(m, Configuration::all_open(m));
        ASSERT_EQ(modes.lambda.size(), ref_modes.lambda.size());
        for (Eigen::Index j = 0; j < modes.lambda.size(); ++j)
            EXPECT_NEAR(modes.lambda(j), ref_modes.lambda(j), 1e-9 * ref_modes.lambda(modes.lambda.size() - 1))
                << "scale " << scale << " mode " << j;
    }
}

// A 10,000-dof structure: `check` took over 120 s and 3.1 GB (dense matrices,
// cubic modal analysis). Refused at once with the stated limit
// (kMaxMatrixDimension), as are a matrix file and a [[mass]] model beyond it.
TEST(StructureInput, AStructureBeyondTheSizeLimitIsRefusedAtOnce) {
    Folder dir;
    const std::size_t n = 10000;
    std::ostringstream M, K, toml;
    M << "%%MatrixMarket matrix coordinate real symmetric\n" << n << " " << n << " " << n << "\n";
    K << "%%MatrixMarket matrix coordinate real symmetric\n" << n << " " << n << " " << 2 * n - 1 << "\n";
    toml << "name = \"big\"\n[structure]\ndofs = [";
    for (std::size_t i = 1; i <= n; ++i) {
        M << i << " " << i << " 1\n";
        K << i << " " << i << " 2e4\n";
        if (i > 1) K << i << " " << i - 1 << " -1e4\n";
        toml << (i > 1 ? ", " : "") << "\"u" << i << "\"";
    }
    toml << "]\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n";
    dir.write("M.mtx", M.str());
    dir.write("K.mtx", K.str());
    const std::string path = dir.write("big.toml", toml.str());
    const auto start = std::chrono::steady_clock::now();
    const testing::CliRun r = testing::run_hsnc("check '" + path + "'");
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(r.exit_code, 2) << r.out;
    EXPECT_EQ(r.err, "hsnc: " + path + ":3: key 'structure.dofs': 10000 degrees of freedom, more than the " +
                         std::to_string(kMaxMatrixDimension) + " hsnc takes for now: its matrices are dense and its "
                         "modal analysis is cubic in the dofs (at " + std::to_string(kMaxMatrixDimension) +
                         " dofs, check takes under a second and simulate seconds per configuration; at 10000 check "
                         "would take hours and gigabytes)\n");
    EXPECT_LT(seconds, 10.0);
    // Two dofs, and a matrix file announcing 10000 x 10000: refused at its size line.
    expect_message(with_matrices("", kM2, K.str().c_str()),
                   {"key 'structure.stiffness': K.mtx:2: larger than 500 rows or columns"});
    // [[mass]] models have the same limit.
    std::string masses = "name = \"many\"\n";
    for (std::size_t i = 1; i <= kMaxMatrixDimension + 1; ++i) masses += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = 1\n";
    expect_message(structure_error(masses, {}), {"s.toml:2: key 'mass': 501 degrees of freedom, more than the 500"});
}

// `hsnc check` reports the structure, its dofs, the friction elements and the frequencies.
TEST(Check, ReportsAStructure) {
    Folder dir;
    dir.write("M.mtx", kM2);
    dir.write("K.mtx", kK2);
    const std::string path = dir.write("s.toml", kHead + "[[friction]]\nname = \"pad\"\nbetween = [\"u2\", \"ground\"]\nmu_k = 0.3\nnormal = 12\n");
    const testing::CliRun r = testing::run_hsnc("check '" + path + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    for (const char* part : {"structure: M = M.mtx  K = K.mtx", "degrees of freedom: 2", "  2  u2  m = 2",
                             "stiffness matrix K: 2 couplings", "friction elements: 1",
                             "  pad  between u2 and ground  mu_k = 0.3  mu_s = 0.3  normal = 12", "natural frequencies"})
        EXPECT_NE(r.out.find(part), std::string::npos) << part << " not in:\n" << r.out;
}

}  // namespace
}  // namespace hsnc
