#include "reduction.h"

#include <complex>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <deque>
#include <limits>
#include <mutex>
#include <utility>

#include <Spectra/MatOp/SparseSymMatProd.h>
#include <Spectra/SymGEigsShiftSolver.h>
#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>

namespace hsnc {
namespace {

using Index = Eigen::Index;

/// Below this many dofs an eigenproblem is solved dense (Lanczos needs
/// room above the wanted modes, and a dense solve is quick there).
constexpr Index kDenseEigenLimit = 400;

/// A sparse LDL^T of K (or of K_II), factored once per reduction.
using Factor = Eigen::SimplicialLDLT<SparseMatrixD>;

/// Spectra's shift-and-invert operator y = (K - sigma M)^-1 x through a
/// sparse LDL^T (Spectra's own wrapper factors with a sparse LU). At
/// sigma = 0 it takes the reduction's own factor of K when given one, so K
/// is factored once however many eigensolves read it.
class ShiftInvert {
public:
    using Scalar = double;
    ShiftInvert(const SparseMatrixD& K, const SparseMatrixD& M, const Factor* k) : K_(K), M_(M), k_(k) {}
    Index rows() const { return K_.rows(); }
    Index cols() const { return K_.cols(); }
    void set_shift(double sigma) {
        own_ = sigma != 0.0 || !k_;
        if (own_) ldlt_.compute(SparseMatrixD(K_ - sigma * M_));
        ok_ = factor().info() == Eigen::Success;
    }
    void perform_op(const double* x, double* y) const {
        Eigen::Map<Eigen::VectorXd>(y, rows()) = factor().solve(Eigen::Map<const Eigen::VectorXd>(x, cols()));
    }
    bool ok() const { return ok_; }

private:
    const SparseMatrixD& K_;
    const SparseMatrixD& M_;
    const Factor& factor() const { return own_ ? ldlt_ : *k_; }
    const Factor* k_;
    Factor ldlt_;
    bool own_ = true;  // ldlt_ (K - sigma M), else the caller's factor of K
    bool ok_ = false;
};

/// Each mode scaled to phi^T M phi = 1 with its largest |component| (the
/// first of equals) positive, so the basis is the same on every machine.
void normalise(const SparseMatrixD& M, Eigen::MatrixXd& modes) {
    for (Index k = 0; k < modes.cols(); ++k) {
        auto phi = modes.col(k);
        Index at = 0;
        phi.cwiseAbs().maxCoeff(&at);
        const double norm = std::sqrt(phi.dot(M * phi));
        phi *= (phi(at) < 0.0 ? -1.0 : 1.0) / norm;
    }
}

/// The `count` lowest eigenpairs of K phi = lambda M phi (count < n), ascending;
/// fewer when M has zero rows and fewer than `count` modes have mass. `k`:
/// K's factor when the caller has one (the sparse path then factors nothing).
std::string lowest_modes(const SparseMatrixD& M, const SparseMatrixD& K, Index count, Eigen::VectorXd& lambda,
                         Eigen::MatrixXd& modes, const Factor* k) {
    const Index n = K.rows();
    if (n <= kDenseEigenLimit || 2 * count + 1 > n) {
        const Eigen::MatrixXd Kd = K, Md = M;
        if ((Md.diagonal().array() > 0.0).all()) {
            const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(Kd, Md);
            if (es.info() != Eigen::Success)
                return "the dense generalized eigensolver failed (M not positive definite?)";
            lambda = es.eigenvalues().head(count);
            modes = es.eigenvectors().leftCols(count);
        } else {
            // Massless dofs (a zero row of M, e.g. a lumped beam's rotations):
            // M phi = mu K phi with K positive definite, mu = 1/lambda; the
            // massless directions have mu = 0 (an infinite frequency).
            const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(Md, Kd);
            if (es.info() != Eigen::Success)
                return "the dense generalized eigensolver failed (K not positive definite)";
            // Ascending; a massless direction's mu is 0 to the solve's rounding, a few eps mu_max.
            const Eigen::VectorXd& mu = es.eigenvalues();
            const double massless = 64.0 * std::numeric_limits<double>::epsilon() * static_cast<double>(n) * mu(n - 1);
            const Index have = std::min<Index>(count, (mu.array() > massless).count());  // fewer: all that have mass
            lambda = mu.tail(have).reverse().cwiseInverse();
            modes = es.eigenvectors().rightCols(have).rowwise().reverse();
        }
    } else {
        ShiftInvert op(K, M, k);
        Spectra::SparseSymMatProd<double> Mop(M);
        const Index ncv = std::min(n, std::max<Index>(2 * count + 1, 20));
        Spectra::SymGEigsShiftSolver<ShiftInvert, Spectra::SparseSymMatProd<double>, Spectra::GEigsMode::ShiftInvert>
            solver(op, Mop, count, ncv, 0.0);
        if (!op.ok()) return "K is singular (a part moves rigidly)";
        solver.init();
        solver.compute(Spectra::SortRule::LargestMagn, 1000, 1e-12);
        if (solver.info() != Spectra::CompInfo::Successful)
            return "the Lanczos eigensolver did not converge on the " + std::to_string(count) + " lowest modes";
        lambda = solver.eigenvalues().reverse();  // Spectra sorts 1/lambda largest first: lambda descending
        modes = solver.eigenvectors().rowwise().reverse();
    }
    normalise(M, modes);
    return "";
}

/// A's blocks over the boundary (b[i] >= 0: its boundary index) and the
/// interior (in[i] >= 0: its interior index).
struct Blocks {
    SparseMatrixD BB, IB, II;
};
Blocks split(const SparseMatrixD& A, const std::vector<int>& b, const std::vector<int>& in, Index nb, Index ni) {
    std::vector<Eigen::Triplet<double, int>> bb, ib, ii;
    for (Index c = 0; c < A.outerSize(); ++c)
        for (SparseMatrixD::InnerIterator it(A, c); it; ++it) {
            const auto r = static_cast<std::size_t>(it.row()), col = static_cast<std::size_t>(it.col());
            if (b[r] >= 0 && b[col] >= 0) bb.emplace_back(b[r], b[col], it.value());
            else if (in[r] >= 0 && b[col] >= 0) ib.emplace_back(in[r], b[col], it.value());
            else if (in[r] >= 0 && in[col] >= 0) ii.emplace_back(in[r], in[col], it.value());
        }
    Blocks out{SparseMatrixD(nb, nb), SparseMatrixD(ni, nb), SparseMatrixD(ni, ni)};
    out.BB.setFromTriplets(bb.begin(), bb.end());
    out.IB.setFromTriplets(ib.begin(), ib.end());
    out.II.setFromTriplets(ii.begin(), ii.end());
    return out;
}

/// T^T A T for T = [I 0; Psi Phi] from A's blocks (A symmetric), symmetrised.
Eigen::MatrixXd project(const Blocks& A, const Eigen::MatrixXd& Psi, const Eigen::MatrixXd& Phi) {
    const Index nb = Psi.cols(), nq = Phi.cols();
    // A T's rows over B and I: [A_BB + A_BI Psi, A_BI Phi ; A_IB + A_II Psi, A_II Phi].
    const Eigen::MatrixXd AIT_b = Eigen::MatrixXd(A.IB) + A.II * Psi;
    const Eigen::MatrixXd AIT_q = A.II * Phi;
    const Eigen::MatrixXd ABT_b = Eigen::MatrixXd(A.BB) + A.IB.transpose() * Psi;
    const Eigen::MatrixXd ABT_q = A.IB.transpose() * Phi;
    Eigen::MatrixXd R(nb + nq, nb + nq);
    R.topLeftCorner(nb, nb) = ABT_b + Psi.transpose() * AIT_b;
    R.topRightCorner(nb, nq) = ABT_q + Psi.transpose() * AIT_q;
    R.bottomLeftCorner(nq, nb) = Phi.transpose() * AIT_b;
    R.bottomRightCorner(nq, nq) = Phi.transpose() * AIT_q;
    return (R + R.transpose()) / 2.0;
}

/// The modes a reduction keeps of K phi = lambda M phi: settings.modes of
/// them (at most `limit`), or every one with omega <= settings.cutoff;
/// `kind` ("fixed-interface", "free-interface") names them in messages; `k`
/// is K's factor (every eigensolve, each doubling of a cut-off's, reads it).
std::string kept_modes(const SparseMatrixD& M, const SparseMatrixD& K, const ReductionSettings& settings, Index limit,
                       const std::string& kind, const Factor& k, Eigen::VectorXd& lambda, Eigen::MatrixXd& Phi) {
    const Index n = K.rows();
    if (settings.cutoff > 0.0) {
        const double cut = settings.cutoff * settings.cutoff;
        for (Index want = std::min<Index>(10, limit);; want = std::min<Index>(2 * want, limit)) {
            if (std::string why = lowest_modes(M, K, want, lambda, Phi, &k); !why.empty()) return why;
            if (want == limit || lambda.size() < want || lambda(want - 1) > cut) break;  // fewer: every mode with mass
        }
        const auto keep =
            static_cast<Index>(std::count_if(lambda.begin(), lambda.end(), [&](double l) { return l <= cut; }));
        lambda.conservativeResize(keep);
        Phi.conservativeResize(Eigen::NoChange, keep);
    } else {
        if (settings.modes > static_cast<std::size_t>(limit))
            return "modes = " + std::to_string(settings.modes) + " is more than the " + std::to_string(limit) +
                   " interior dofs";
        if (settings.modes > 0) {
            if (std::string why = lowest_modes(M, K, static_cast<Index>(settings.modes), lambda, Phi, &k); !why.empty())
                return why;
            if (lambda.size() < static_cast<Index>(settings.modes))
                return "modes = " + std::to_string(settings.modes) + " but only " + std::to_string(lambda.size()) +
                       " " + kind + " modes have mass (the other " + (kind == "fixed-interface" ? "interior " : "") +
                       "dofs are massless)";
        }
        if (settings.modes == 0) Phi.resize(n, 0), lambda.resize(0);
    }
    if ((lambda.array() <= 0.0).any())
        return "a " + kind + " mode has omega^2 <= 0 (" + (kind == "fixed-interface" ? "K_II" : "K") +
               " is not positive definite)";
    return "";
}

}  // namespace

std::string craig_bampton(const SparseMatrixD& M, const SparseMatrixD& K, const SparseMatrixD* C,
                          const std::vector<std::size_t>& boundary, const ReductionSettings& settings,
                          ReducedStructure& out, const Eigen::MatrixXd* forces) {
    const auto n = static_cast<std::size_t>(K.rows());
    std::vector<int> b(n, -1), in(n, -1);
    int nb = 0, ni = 0;
    for (const std::size_t i : boundary) b[i] = nb++;
    for (std::size_t i = 0; i < n; ++i)
        if (b[i] < 0) in[i] = ni++;
    if (ni == 0) return "every dof is a boundary dof: there is nothing to reduce";
    const Blocks Mb = split(M, b, in, nb, ni), Kb = split(K, b, in, nb, ni);

    // Static constraint modes: K_II Psi = -K_IB.
    const Factor kii(Kb.II);
    if (kii.info() != Eigen::Success)
        return "K_II (the interior with the boundary held) is singular: a part moves rigidly once the boundary is "
               "held; name a dof of that part in [reduction].boundary";
    const Eigen::MatrixXd Psi = -kii.solve(Eigen::MatrixXd(Kb.IB));
    if (kii.info() != Eigen::Success || !Psi.allFinite()) return "the static constraint modes could not be solved";

    // Fixed-interface modes: `modes` of them, or every one below the cut-off.
    Eigen::VectorXd lambda;
    Eigen::MatrixXd Phi;
    if (std::string why = kept_modes(Mb.II, Kb.II, settings, ni, "fixed-interface", kii, lambda, Phi); !why.empty())
        return why;

    out.boundary = boundary;
    out.full_dofs = n;
    out.interface_omega = lambda.array().sqrt();
    out.M = project(Mb, Psi, Phi);
    // K_r in its closed form: the boundary's Schur complement and Lambda, no coupling.
    const Index nq = Phi.cols();
    out.K = Eigen::MatrixXd::Zero(nb + nq, nb + nq);
    const Eigen::MatrixXd S = Eigen::MatrixXd(Kb.BB) + Eigen::MatrixXd(Kb.IB.transpose() * Psi);
    out.K.topLeftCorner(nb, nb) = (S + S.transpose()) / 2.0;
    for (Index k = 0; k < nq; ++k) out.K(nb + k, nb + k) = lambda(k);
    if (C) out.C = project(split(*C, b, in, nb, ni), Psi, Phi);
    else out.C.resize(0, 0);
    // T^T F = [F_B + Psi^T F_I; Phi^T F_I].
    const Index nf = forces ? forces->cols() : 0;
    Eigen::MatrixXd FB(nb, nf), FI(ni, nf);
    for (std::size_t i = 0; i < n && nf > 0; ++i)
        (b[i] >= 0 ? FB.row(b[i]) : FI.row(in[i])) = forces->row(static_cast<Index>(i));
    out.forces.resize(nb + nq, nf);
    if (nf > 0) {
        out.forces.topRows(nb) = FB + Psi.transpose() * FI;
        out.forces.bottomRows(nq) = Phi.transpose() * FI;
    }
    return "";
}

std::string rubin(const SparseMatrixD& M, const SparseMatrixD& K, const SparseMatrixD* C,
                  const std::vector<std::size_t>& boundary, const ReductionSettings& settings, ReducedStructure& out,
                  const Eigen::MatrixXd* forces) {
    const auto n = static_cast<Index>(K.rows());
    const auto nb = static_cast<Index>(boundary.size());
    if (nb == n) return "every dof is a boundary dof: there is nothing to reduce";
    const Factor k(K);
    if (k.info() != Eigen::Success)
        return "K is singular (the structure moves rigidly with nothing held): Rubin's method needs a supported "
               "structure; use method = \"craig-bampton\"";

    // Free-interface modes of the whole structure.
    Eigen::VectorXd lambda;
    Eigen::MatrixXd Phi;
    if (std::string why = kept_modes(M, K, settings, n - nb, "free-interface", k, lambda, Phi); !why.empty())
        return why;
    const Index nq = Phi.cols();
    const std::vector<Index> on_b(boundary.begin(), boundary.end());  // B's rows
    const Eigen::MatrixXd PhiB = Phi(on_b, Eigen::all);

    // Residual flexibility of the boundary: G = K^-1 E_B - Phi Lambda^-1 Phi_B^T.
    Eigen::MatrixXd EB = Eigen::MatrixXd::Zero(n, nb);
    for (Index j = 0; j < nb; ++j) EB(on_b[static_cast<std::size_t>(j)], j) = 1.0;
    const Eigen::MatrixXd F = k.solve(EB);  // the full static flexibility's columns on B
    if (k.info() != Eigen::Success || !F.allFinite())
        return "the static flexibility of the boundary could not be solved";
    const Eigen::MatrixXd G = F - Phi * lambda.cwiseInverse().asDiagonal() * PhiB.transpose();
    const Eigen::MatrixXd FBB = F(on_b, Eigen::all);
    Eigen::MatrixXd GBB = G(on_b, Eigen::all);
    GBB = (GBB + GBB.transpose()) / 2.0;
    // G_BB is what the dropped modes leave of F_BB: when the kept modes
    // carry nearly all of it, G_BB is lost in the subtraction's rounding.
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> gs(GBB, Eigen::EigenvaluesOnly);
    const double floor = 1e-9 * FBB.diagonal().cwiseAbs().maxCoeff();
    if (gs.info() != Eigen::Success || !(gs.eigenvalues()(0) > floor))
        return "the residual flexibility of the boundary is singular or lost in rounding with " + std::to_string(nq) +
               " free-interface modes kept (the dropped modes no longer reach every boundary dof): keep fewer modes";

    // T = [Psi  Phi - Psi Phi_B], Psi = G G_BB^-1; its rows on B exactly [I 0].
    const Eigen::MatrixXd Psi = GBB.llt().solve(G.transpose()).transpose();
    Eigen::MatrixXd T(n, nb + nq);
    T.leftCols(nb) = Psi;
    T.rightCols(nq) = Phi - Psi * PhiB;
    T(on_b, Eigen::all) = Eigen::MatrixXd::Identity(nb, nb + nq);
    if (!T.allFinite()) return "the residual attachment modes could not be solved";
    auto project = [&T](const SparseMatrixD& A) {
        const Eigen::MatrixXd R = T.transpose() * (A * T);
        return Eigen::MatrixXd((R + R.transpose()) / 2.0);
    };
    out.boundary = boundary;
    out.full_dofs = static_cast<std::size_t>(n);
    out.interface_omega = lambda.array().sqrt();
    out.M = project(M);
    // T^T K T, not its closed form [G_BB^-1, -G_BB^-1 Phi_B; ., Lambda +
    // Phi_B^T G_BB^-1 Phi_B] (which assumes G^T M Phi = 0 exactly): the
    // projection on the computed T keeps M_r and K_r one Ritz pair (events
    // of the 40-element cantilever's tip stop with 16 modes: 1.8e-11 s from
    // the full model's, against 4.6e-10 s with the closed form).
    out.K = project(K);
    if (C)
        out.C = project(*C);
    else
        out.C.resize(0, 0);
    out.forces = forces ? Eigen::MatrixXd(T.transpose() * *forces) : Eigen::MatrixXd(nb + nq, 0);
    return "";
}

std::string harmonic_response(const SparseMatrixD& M, const SparseMatrixD& K, const SparseMatrixD& C, double w,
                              const Eigen::VectorXd& F, Eigen::VectorXcd& X) {
    using Complex = std::complex<double>;
    if (K.rows() > static_cast<Index>(kMaxResponseDofs))
        return "not computed above " + std::to_string(kMaxResponseDofs) + " dofs";
    const SparseMatrixD re = K - w * w * M;
    const Eigen::SparseMatrix<Complex> A = re.cast<Complex>() + Complex(0, w) * C.cast<Complex>();
    Eigen::SparseLU<Eigen::SparseMatrix<Complex>> lu;
    lu.compute(A);
    if (lu.info() == Eigen::Success) X = lu.solve(F.cast<Complex>());
    if (lu.info() != Eigen::Success || X.size() != K.rows() || !X.allFinite())
        return w == 0.0 ? "K is singular (a rigid-body motion)" : "the structure resonates there";
    return "";
}

std::string lowest_frequencies(const SparseMatrixD& M, const SparseMatrixD& K, std::size_t count, Eigen::VectorXd& omega) {
    const auto want = std::min<Index>(static_cast<Index>(count), K.rows() - 1);
    Eigen::VectorXd lambda;
    Eigen::MatrixXd modes;
    if (want < 1) return "the model has a single dof";
    if (std::string why = lowest_modes(M, K, want, lambda, modes, nullptr); !why.empty()) return why;
    omega = lambda.cwiseMax(0.0).cwiseSqrt();
    return "";
}

namespace {

// Two 64-bit lanes, each word mixed in by the splitmix64 finaliser with its
// own offset: a 128-bit fingerprint of the reduction's inputs.
class Fingerprint {
public:
    void add(std::uint64_t w) {
        a_ = mix(a_ ^ w);
        b_ = mix(b_ + w + 0x9E3779B97F4A7C15ull);
    }
    void add(double v) {
        std::uint64_t w = 0;
        std::memcpy(&w, &v, sizeof w);
        add(w);
    }
    void add(const SparseMatrixD& A) {
        add(static_cast<std::uint64_t>(A.rows()));
        add(static_cast<std::uint64_t>(A.cols()));
        add(static_cast<std::uint64_t>(A.nonZeros()));
        for (Eigen::Index c = 0; c < A.outerSize(); ++c)
            for (SparseMatrixD::InnerIterator it(A, c); it; ++it) {
                add(static_cast<std::uint64_t>(it.row()) << 32 | static_cast<std::uint64_t>(it.col()));
                add(it.value());
            }
    }
    std::array<std::uint64_t, 2> value() const { return {a_, b_}; }

private:
    static std::uint64_t mix(std::uint64_t x) {
        x ^= x >> 30;
        x *= 0xBF58476D1CE4E5B9ull;
        x ^= x >> 27;
        x *= 0x94D049BB133111EBull;
        return x ^ (x >> 31);
    }
    std::uint64_t a_ = 0x243F6A8885A308D3ull, b_ = 0x13198A2E03707344ull;
};

struct Memo {
    std::mutex lock;
    std::deque<std::pair<std::array<std::uint64_t, 2>, ReducedStructure>> kept;  // newest first
    ReductionMemoCounts counts;
};

Memo& memo() {
    static Memo m;
    return m;
}

}  // namespace

std::string reduce_memo(const SparseMatrixD& M, const SparseMatrixD& K, const SparseMatrixD* C,
                        const std::vector<std::size_t>& boundary, const ReductionSettings& settings,
                        ReducedStructure& out, const Eigen::MatrixXd* forces) {
    Fingerprint f;
    f.add(M);
    f.add(K);
    f.add(static_cast<std::uint64_t>(C != nullptr));
    if (C) f.add(*C);
    f.add(static_cast<std::uint64_t>(boundary.size()));
    for (const std::size_t b : boundary) f.add(static_cast<std::uint64_t>(b));
    f.add(static_cast<std::uint64_t>(settings.method));
    f.add(static_cast<std::uint64_t>(settings.modes));
    f.add(settings.cutoff);
    f.add(static_cast<std::uint64_t>(forces ? forces->cols() : 0));
    for (Eigen::Index j = 0; forces && j < forces->cols(); ++j)
        for (Eigen::Index i = 0; i < forces->rows(); ++i) f.add((*forces)(i, j));
    const std::array<std::uint64_t, 2> key = f.value();
    Memo& m = memo();
    {
        const std::lock_guard<std::mutex> guard(m.lock);
        for (const auto& [k, reduced] : m.kept)
            if (k == key) {
                out = reduced;
                ++m.counts.reused;
                return "";
            }
    }
    // Computed outside the lock: two threads may both reduce the same
    // structure once; each result is the same.
    const std::string why = settings.method == ReductionMethod::rubin
                                ? rubin(M, K, C, boundary, settings, out, forces)
                                : craig_bampton(M, K, C, boundary, settings, out, forces);
    if (!why.empty()) return why;
    const std::lock_guard<std::mutex> guard(m.lock);
    ++m.counts.computed;
    m.kept.emplace_front(key, out);
    if (m.kept.size() > kReductionMemo) m.kept.pop_back();
    return "";
}

void reduction_memo_clear() {
    Memo& m = memo();
    const std::lock_guard<std::mutex> guard(m.lock);
    m.kept.clear();
}

ReductionMemoCounts reduction_memo_counts() {
    Memo& m = memo();
    const std::lock_guard<std::mutex> guard(m.lock);
    return m.counts;
}

}  // namespace hsnc
