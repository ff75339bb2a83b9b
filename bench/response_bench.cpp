// hsnc response-curve benchmark (hsnc sweep, api/hsnc/sweep.h), in one run:
// a 200-point response curve (100 values of the forcing frequency, swept up
// and down: two independent tasks) of seed scenario 1 and of a 16-mass
// chain, by hsnc on 1 and 2 threads and by the same sweep with this build's
// CVODE baseline (method cvode, rtol 1e-10, atol 1e-12, through the same
// library: the same transient and settling rules, the same number of
// recorded periods; its xmax, xrms and a1 from samples). Prints, per case,
// the median wall time of `repeats` runs, the periods simulated, the ratio
// CVODE / hsnc, the speed-up of 2 threads and the parallel efficiency
// (speed-up / 2).
//
// Then what a recorded period costs on consistent-mass cantilevers of 5 to
// 40 elements (tests/fe_beam.h; a stop under the tip, Rayleigh damping,
// forced at 15 rad/s; omega_max from 1.0e4 to 1.7e5 rad/s): one sweep point
// recording 1 and 9 periods, the difference over 8 against the transient's
// cost per period. The recorder grids each segment at the terms that still
// move (SegmentSolver::resolving_rate); gridded at omega_max, as it was, the
// 40-element beam took 6 s per recorded period.
//
//   build/hsnc_response_bench [repeats] [--beams]   (default 3; --beams: the beams only)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "bench_common.h"
#include "fe_beam.h"
#include "file_read.h"
#include "hsnc/sweep.h"

using namespace hsnc;

namespace {

// 16 unit masses in a chain held to the ground at both ends, friction on
// every mass, contacts m4-m5, m11-m12 and m16 to ground, forced at m1.
std::string chain16() {
    std::string t = "name = \"chain-16\"\n[parameters]\nomega = 5.0\n[damping]\nalpha = 0.05\nbeta = 0.0005\n";
    for (int i = 1; i <= 16; ++i)
        t += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = 1\nmu_k = 0.3\nmu_s = 0.4\n";
    for (int i = 0; i <= 16; ++i)
        t += "[[spring]]\nbetween = [\"" + (i == 0 ? std::string("ground") : "m" + std::to_string(i)) + "\", \"" +
             (i == 16 ? std::string("ground") : "m" + std::to_string(i + 1)) + "\"]\nk = 100\n";
    t += "[[contact]]\nbetween = [\"m4\", \"m5\"]\ngap = 0.02\nk = 1000\n";
    t += "[[contact]]\nbetween = [\"m11\", \"m12\"]\ngap = 0.02\nk = 1000\n";
    t += "[[contact]]\nbetween = [\"m16\", \"ground\"]\ngap = 0.05\nk = 1000\n";
    t += "[[forcing]]\nomega = \"omega\"\namplitude = { m1 = 30.0 }\n";
    return t;
}

struct Case {
    std::string name, text, source;
    double from, to;
    std::size_t max_periods;
};

struct Timing {
    double seconds = 0;
    std::size_t periods = 0, settled = 0;
};

Timing time_sweep(const Case& c, Method method, unsigned threads, int repeats) {
    SweepOptions o;
    o.param = "omega";
    o.from = c.from;
    o.to = c.to;
    o.points = 100;
    o.direction = SweepDirection::both;
    o.max_periods = c.max_periods;
    o.record_periods = 16;
    o.threads = threads;
    o.method = method;
    const SweepPlan plan(c.text, c.source, {}, o);
    std::vector<double> t;
    Timing r;
    for (int k = 0; k < repeats; ++k) {
        const auto start = bench::Clock::now();
        const SweepResult res = plan.run();
        t.push_back(bench::seconds_since(start));
        r.periods = r.settled = 0;
        for (const SweepPoint& p : res.points) {
            r.periods += p.periods + o.record_periods;
            r.settled += p.settled;
        }
    }
    r.seconds = bench::median(t);
    return r;
}

void write_dense_market(const std::string& path, const Eigen::MatrixXd& A) {
    std::ofstream out(path);
    out.precision(17);
    std::size_t nnz = 0;
    for (Eigen::Index j = 0; j < A.cols(); ++j)
        for (Eigen::Index i = j; i < A.rows(); ++i) nnz += A(i, j) != 0.0;
    out << "%%MatrixMarket matrix coordinate real symmetric\n" << A.rows() << " " << A.cols() << " " << nnz << "\n";
    for (Eigen::Index j = 0; j < A.cols(); ++j)
        for (Eigen::Index i = j; i < A.rows(); ++i)
            if (A(i, j) != 0.0) out << i + 1 << " " << j + 1 << " " << A(i, j) << "\n";
}

// One sweep point of the cantilever of `elements` elements at 15 rad/s, recording `record` periods.
double beam_point(const std::filesystem::path& dir, int elements, std::size_t record, int repeats,
                  std::size_t& transient) {
    const fe::Beam b = fe::cantilever(elements);
    write_dense_market((dir / "M.mtx").string(), b.M);
    write_dense_market((dir / "K.mtx").string(), b.K);
    std::string dofs = "[";
    for (std::size_t k = 0; k < b.dofs.size(); ++k) dofs += (k ? ", \"" : "\"") + b.dofs[k] + "\"";
    const std::string tip = "w" + std::to_string(elements);
    const std::string text = "name = \"beam\"\n[parameters]\nomega = 15.0\n[structure]\ndofs = " + dofs +
                             "]\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n[damping]\nalpha = 0.2\nbeta = 2e-5\n"
                             "[[contact]]\nbetween = [\"" +
                             tip +
                             "\", \"ground\"]\ngap = 0.004\nk = 2000.0\n"
                             "[[forcing]]\nomega = \"omega\"\namplitude = { " +
                             tip + " = 5.0 }\n";
    SweepOptions o;
    o.param = "omega";
    o.from = o.to = 15.0;
    o.points = 1;
    o.max_periods = 2000;
    o.record_periods = record;
    const SweepPlan plan(text, (dir / "beam.toml").string(), {}, o);
    std::vector<double> t;
    for (int k = 0; k < repeats; ++k) {
        const auto start = bench::Clock::now();
        const SweepResult res = plan.run();
        t.push_back(bench::seconds_since(start));
        transient = res.points.at(0).periods;
    }
    return bench::median(t);
}

void beams(int repeats) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "hsnc_response_bench";
    std::filesystem::create_directories(dir);
    std::printf("One sweep point of a consistent-mass cantilever with a stop, omega = 15 rad/s, median of %d runs\n\n",
                repeats);
    std::printf("%8s %6s %14s %10s %16s %16s %8s\n", "elements", "dofs", "omega_max", "transient", "ms/period",
                "ms/period", "ratio");
    std::printf("%8s %6s %14s %10s %16s %16s %8s\n", "", "", "[rad/s]", "[periods]", "(transient)", "(recorded)", "");
    for (int elements : {5, 10, 20, 40}) {
        const fe::Beam b = fe::cantilever(elements);
        Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(b.K, b.M, Eigen::EigenvaluesOnly);
        std::size_t k1 = 0, k9 = 0;
        const double t1 = beam_point(dir, elements, 1, repeats, k1), t9 = beam_point(dir, elements, 9, repeats, k9);
        const double recorded = (t9 - t1) / 8, transient = t1 / static_cast<double>(k1 + 1);
        std::printf("%8d %6zu %14.4g %10zu %16.3f %16.3f %8.1f\n", elements, b.dofs.size(),
                    std::sqrt(eig.eigenvalues().maxCoeff()), k1, 1e3 * transient, 1e3 * recorded, recorded / transient);
    }
    std::filesystem::remove_all(dir);
}

}  // namespace

int main(int argc, char** argv) {
    const bool only_beams = argc > 1 && std::strcmp(argv[argc - 1], "--beams") == 0;
    const int repeats = argc > 1 && !(argc == 2 && only_beams) ? std::max(1, std::atoi(argv[1])) : 3;
    if (only_beams) {
        beams(repeats);
        return 0;
    }
    const std::string s1_path = std::string(HSNC_SOURCE_DIR) + "/models/seed-scenario-1.toml";
    const FileRead s1 = read_regular_file(s1_path, kMaxModelFileBytes);
    if (s1.status != FileRead::Status::ok) {
        std::fprintf(stderr, "cannot read %s\n", s1_path.c_str());
        return 1;
    }
    const std::vector<Case> cases = {
        {"seed scenario 1 (2 DOF), omega 150..200", s1.bytes, s1_path, 150.0, 200.0, 500},
        {"16-mass chain, omega 3..8", chain16(), "chain-16", 3.0, 8.0, 500},
    };
    std::printf("200-point response curves (100 values, up and down), median of %d runs\n\n", repeats);
    std::printf("%-40s %-16s %10s %9s %8s %12s\n", "case", "method", "wall [s]", "periods", "settled", "us/period");
    for (const Case& c : cases) {
        const Timing h1 = time_sweep(c, Method::hsnc, 1, repeats);
        const Timing h2 = time_sweep(c, Method::hsnc, 2, repeats);
        const Timing cv = time_sweep(c, Method::cvode, 1, repeats);
        auto row = [&](const char* method, const Timing& t) {
            std::printf("%-40s %-16s %10.3f %9zu %8zu %12.2f\n", c.name.c_str(), method, t.seconds, t.periods,
                        t.settled, 1e6 * t.seconds / static_cast<double>(t.periods));
        };
        row("hsnc, 1 thread", h1);
        row("hsnc, 2 threads", h2);
        row("cvode, 1 thread", cv);
        std::printf("%-40s cvode / hsnc (1 thread) = %.1f; 2 threads: speed-up %.2f, parallel efficiency %.0f%%\n\n",
                    "", cv.seconds / h1.seconds, h1.seconds / h2.seconds, 50 * h1.seconds / h2.seconds);
    }
    beams(repeats);
    return 0;
}
