// hsnc tests -- finite-element test structures written by the tests
// themselves: Euler-Bernoulli cantilevers with consistent mass, axial bars,
// the Matrix Market and TOML files a [structure] model reads them from,
// and the comparison of two runs' events.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "engine_runner.h"
#include "fe_beam.h"
#include "flow.h"
#include "reference_engine.h"
#include "shooting.h"
#include "temp_dir.h"

namespace hsnc::fe {

inline std::string num(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

inline std::string market(const Eigen::MatrixXd& A) {
    std::ostringstream out;
    int nnz = 0;
    for (Eigen::Index j = 0; j < A.cols(); ++j)
        for (Eigen::Index i = j; i < A.rows(); ++i) nnz += A(i, j) != 0.0 ? 1 : 0;
    out << "%%MatrixMarket matrix coordinate real symmetric\n" << A.rows() << " " << A.cols() << " " << nnz << "\n";
    for (Eigen::Index j = 0; j < A.cols(); ++j)
        for (Eigen::Index i = j; i < A.rows(); ++i)
            if (A(i, j) != 0.0) out << i + 1 << " " << j + 1 << " " << num(A(i, j)) << "\n";
    return out.str();
}

inline void write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

/// A free-free bar of length 1 m, EA = 1e4 N, 1 kg/m, in `elements`
/// consistent-mass axial elements: M and K of its elements + 1 nodes.
inline std::pair<Eigen::MatrixXd, Eigen::MatrixXd> axial_bar(int elements) {
    const double h = 1.0 / elements, EA = 1e4, rhoA = 1.0;
    const int n = elements + 1;
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n), K = Eigen::MatrixXd::Zero(n, n);
    for (int e = 0; e < elements; ++e) {
        M.block(e, e, 2, 2) += rhoA * h / 6 * (Eigen::Matrix2d() << 2, 1, 1, 2).finished();
        K.block(e, e, 2, 2) += EA / h * (Eigen::Matrix2d() << 1, -1, -1, 1).finished();
    }
    return {M, K};
}

/// The bar clamped at its root; dofs u1 ... uN (N at the tip).
inline Beam clamped_bar(int elements) {
    const auto [M, K] = axial_bar(elements);
    const int n = elements + 1;
    Beam b{M.bottomRightCorner(n - 1, n - 1), K.bottomRightCorner(n - 1, n - 1), {}, n - 2};
    for (int k = 1; k <= elements; ++k) b.dofs.push_back("u" + std::to_string(k));
    return b;
}

inline std::string dof_list(const std::vector<std::string>& dofs) {
    std::string s = "[";
    for (std::size_t i = 0; i < dofs.size(); ++i) s += (i ? ", \"" : "\"") + dofs[i] + "\"";
    return s + "]";
}

inline std::string table(const std::vector<std::string>& dofs, const Eigen::VectorXd& values) {
    std::string s = "{";
    for (std::size_t i = 0; i < dofs.size(); ++i)
        s += (i ? ", " : " ") + dofs[i] + " = " + num(values(static_cast<Eigen::Index>(i)));
    return s + " }";
}

/// A [structure] model in dir: M.mtx, K.mtx and `file` (named `name`, dofs
/// `dofs`), its other sections given as TOML text.
inline std::string structure_model(const testing::TempDir& dir, const std::string& file, const std::string& name,
                            const Eigen::MatrixXd& M, const Eigen::MatrixXd& K, const std::vector<std::string>& dofs,
                            const std::string& sections) {
    write(dir / "M.mtx", market(M));
    write(dir / "K.mtx", market(K));
    write(dir / file, "name = \"" + name + "\"\n[structure]\ndofs = " + dof_list(dofs) +
                          "\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n" + sections);
    return dir / file;
}

// ---- comparing runs

/// Event times of two runs: same kinds and elements, the largest time difference.
inline double event_gap(const testing::Outcome& a, const testing::Outcome& b) {
    EXPECT_EQ(a.events.size(), b.events.size());
    double worst = 0.0;
    for (std::size_t e = 0; e < std::min(a.events.size(), b.events.size()); ++e) {
        EXPECT_EQ(a.events[e].kind, b.events[e].kind) << "event " << e;
        EXPECT_EQ(a.events[e].element, b.events[e].element) << "event " << e;
        worst = std::max(worst, std::fabs(a.events[e].t - b.events[e].t));
    }
    return worst;
}

/// The events of the CLN reference at `digits`.
inline std::vector<testing::Recorded> reference_events(const Model& model, int digits, double t_end) {
    testing::Recorder rec(model.dof(), model.state_size());
    EngineOptions opt;
    opt.t_end = t_end;
    opt.samples = false;
    reference::simulate_precise(model, digits, opt, rec);
    return rec.events;
}

inline double event_gap(const std::vector<testing::Recorded>& a, const std::vector<testing::Recorded>& b) {
    testing::Outcome x, y;
    x.events = a, y.events = b;
    return event_gap(x, y);
}

/// How far the programs' events lie from the Eigen solver's, the reference's
/// at 30 digits and CVODE's (rtol 1e-12), and the reference at 30 from 60 digits.
struct BackEndGaps {
    double eigen, reference, digits, cvode;
};
inline BackEndGaps back_end_gaps(const Model& model, const testing::Outcome& programs, double t_end) {
    const testing::Outcome eigen = testing::simulate(model, t_end, 0.0, testing::Solvers::generic);
    const std::vector<testing::Recorded> r30 = reference_events(model, 30, t_end),
                                         r60 = reference_events(model, 60, t_end);
    const testing::Outcome cvode = testing::baseline(model, t_end, 1e-12, 1e-14, Method::cvode);
    return {event_gap(programs, eigen), event_gap(programs.events, r30), event_gap(r30, r60),
            event_gap(programs, cvode)};
}

/// The period map's exact Jacobian at y over [0, T] against central
/// differences (steps h max(1, |y_j|)): |J - J_fd| / |J_fd|, each perturbed
/// run with the events of the exact one (a failure otherwise); `events`
/// gets their number.
inline double off_central_differences(analysis::Flow& flow, double T, const Eigen::VectorXd& y, std::size_t& events) {
    const analysis::PeriodMapValue at = analysis::evaluate_period_map(flow, 0.0, T, y);
    EXPECT_TRUE(at.ok) << at.message;
    events = at.events;
    const Eigen::Index N = y.size();
    Eigen::MatrixXd fd(N, N);
    for (Eigen::Index j = 0; j < N; ++j) {
        const double h = 1e-7 * std::max(1.0, std::fabs(y(j)));
        Eigen::VectorXd yp = y, ym = y;
        yp(j) += h, ym(j) -= h;
        const analysis::PeriodMapValue p = analysis::evaluate_period_map(flow, 0.0, T, yp),
                                       m = analysis::evaluate_period_map(flow, 0.0, T, ym);
        EXPECT_EQ(p.events, at.events);
        EXPECT_EQ(m.events, at.events);
        fd.col(j) = (p.Py - m.Py) / (2 * h);
    }
    return (at.M - fd).norm() / fd.norm();
}

}  // namespace hsnc::fe
