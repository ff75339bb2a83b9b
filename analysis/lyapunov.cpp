// The Lyapunov spectrum by the QR method on the exact tangent dynamics (api/hsnc/lyapunov.h).
#include "hsnc/lyapunov.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <sstream>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>

#include "flow.h"
#include "tangent.h"
#include "number_text.h"

namespace hsnc {
namespace {

constexpr const char* kLyapunov = "hsnc::lyapunov";
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A fixed generic orthonormal basis (QR of a pseudo-random matrix, fixed
// seed: runs are reproducible). Not the identity: the unit vectors of the
// positions span one direction in each mode's plane, and the linear motion
// keeps it so, so with Q = I the first two columns of a 2-DOF linear
// oscillator never approach the slow mode's plane (only rounding drives
// them there, over hundreds of seconds).
Eigen::MatrixXd initial_basis(Eigen::Index n) {
    std::mt19937_64 rng(20240601);
    std::normal_distribution<double> normal;
    Eigen::MatrixXd G(n, n);
    for (Eigen::Index j = 0; j < n; ++j)
        for (Eigen::Index i = 0; i < n; ++i) G(i, j) = normal(rng);
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(G);
    return qr.householderQ() * Eigen::MatrixXd::Identity(n, n);
}

// Carries the orthonormal basis through the run from t_start on.
class SpectrumObserver : public Observer {
public:
    SpectrumObserver(const Model& model, double t_start, double t_end, double row_interval,
                     const std::function<void(double, const std::vector<double>&)>& on_row, Observer* inner)
        : tangent_(model), grazing_(tangent_), n2_(static_cast<Eigen::Index>(tangent_.dim())), t_start_(t_start), t_end_(t_end),
          row_(row_interval), on_row_(on_row), inner_(inner),
          Q_(initial_basis(n2_)), logsum_(Eigen::VectorXd::Zero(n2_)), live_(n2_) {}

    bool wants_segments() const override { return true; }
    void on_sample(double, const double*, const double*) override {}
    void on_event(double t, EventKind kind, int element, const double* x, const double* v) override {
        if (t >= t_start_) ++events_;
        if (inner_) inner_->on_event(t, kind, element, x, v);
    }
    bool on_progress(double t) override { return inner_ ? inner_->on_progress(t) : true; }

    void on_segment(const SegmentRecord& s) override {
        const double start = s.t + s.t_lo, end = start + s.tau;
        if (end <= t_start_ && !(s.tau == 0 && start == t_start_)) return;
        const double from = std::max(start, t_start_);
        // A stuck mass (against the ground or its partner) and a slipping slider each take one
        // direction out (analysis/stick_tangent.h: the projection of the configuration).
        const std::size_t stuck = static_cast<std::size_t>(std::count(s.cfg->stuck.begin(), s.cfg->stuck.end(), 1)) +
                                  static_cast<std::size_t>(s.cfg->slip.size() -
                                                           static_cast<std::size_t>(std::count(s.cfg->slip.begin(), s.cfg->slip.end(), 0)));
        const Eigen::Index rank = n2_ - static_cast<Eigen::Index>(stuck);
        // Walk through the segment, factorising at every convergence row and
        // at least every 10/rate seconds, so that the directions part by at
        // most e^20 between two factorisations (a 2000 s segment of a damped
        // mode would underflow).
        const double rate = tangent_.max_rate(*s.cfg);
        double hmax = rate > 0 ? 10 / rate : kInf;
        // With every direction live, the last one's growth is known without
        // resolving it (Liouville): the steps need only keep the others
        // within e^20, so one stiff mode (a dashpot of 1e8) does not set them.
        const Liouville* last = rank == n2_ && live_ == n2_ ? &liouville(*s.cfg) : nullptr;
        if (last && !(last->step > hmax)) last = nullptr;  // no gain: the factorisations as they were
        if (last) hmax = last->step;
        double at = from;
        while (true) {
            double to = end;
            bool row = false;
            if (on_row_ && next_row_ <= end && next_row_ < t_end_ - 1e-9 * row_) to = std::max(next_row_, at), row = true;
            if (to - at > hmax) to = at + hmax, row = false;
            Eigen::MatrixXd Y = tangent_.transition(*s.cfg, to - at) * Q_.leftCols(live_);
            factor(Y, rank, logsum_, live_, &Q_, last ? last->trace * (to - at) : kNaN);
            at = to;
            if (row) {
                emit(next_row_, logsum_, live_);
                next_row_ = t_start_ + static_cast<double>(++row_k_) * row_;
                continue;
            }
            if (at >= end) break;
        }
        last_ = end;
    }

    void on_switch(const SwitchRecord& r) override {
        if (r.t < t_start_) return;
        Eigen::MatrixXd Y = Q_.leftCols(live_);
        const bool ok = tangent_.apply_saltation(r, Y);
        grazing_.on_switch(r, !ok);
        if (ok) Q_.leftCols(live_) = Y;
    }

    // The final row at the end of the run, and the exponents.
    std::vector<double> finish(double t) {
        std::vector<double> ex = exponents(logsum_, live_, t);
        if (on_row_ && last_row_ < t) on_row_(t, ex);
        return ex;
    }
    std::size_t collapsed() const { return static_cast<std::size_t>(n2_ - live_); }
    std::size_t events() const { return events_; }
    std::size_t grazing() const { return grazing_.count(); }
    std::size_t singular() const { return grazing_.singular(); }

private:
    // QR of Y (the live columns): the logarithms of |R_kk| added to logs,
    // the columns beyond `rank` dropped for good (collapsed), and the new
    // orthonormal basis written to Q when asked.
    // `log_det`, when not NaN: log |det Phi| of the step (every direction
    // live): the last |R_kk| is then exp(log_det) over the others' product
    // (the volume grows by det Phi), not the rounding left of its column.
    void factor(Eigen::MatrixXd& Y, Eigen::Index rank, Eigen::VectorXd& logs, Eigen::Index& live,
                Eigen::MatrixXd* Q, double log_det = kNaN) const {
        const Eigen::Index keep = std::min(live, rank);
        if (keep == 0) {
            live = 0;
            return;
        }
        Eigen::HouseholderQR<Eigen::MatrixXd> qr(Y);
        const Eigen::MatrixXd& R = qr.matrixQR();
        const Eigen::Index exact = std::isnan(log_det) ? keep : keep - 1;
        double others = 0.0;
        for (Eigen::Index k = 0; k < exact; ++k) {
            const double l = std::log(std::fabs(R(k, k)));
            logs(k) += l;
            others += l;
        }
        if (exact < keep) logs(exact) += log_det - others;
        if (Q) {
            Eigen::MatrixXd thin = qr.householderQ() * Eigen::MatrixXd::Identity(n2_, keep);
            Q->leftCols(keep) = thin;
        }
        live = keep;
    }

    std::vector<double> exponents(const Eigen::VectorXd& logs, Eigen::Index live, double t) const {
        std::vector<double> ex(static_cast<std::size_t>(n2_), -kInf);
        for (Eigen::Index k = 0; k < live; ++k) ex[static_cast<std::size_t>(k)] = logs(k) / (t - t_start_);
        std::sort(ex.begin(), ex.end(), std::greater<double>());
        return ex;
    }

    void emit(double t, const Eigen::VectorXd& logs, Eigen::Index live) {
        on_row_(t, exponents(logs, live, t));
        last_row_ = t;
    }

    // A configuration's generator A: tr A (log det Phi(tau) = tau tr A) and the
    // step that keeps every direction but the fastest-decaying one within
    // e^20 of each other and of 1: 20 / max(r_1 - r_(N-1), |r_1|, |r_(N-1)|),
    // r the real parts of A's eigenvalues, largest first, when r_N is apart
    // from the others by 10 times that spread. From Phi(tau) at
    // tau = 1/max_rate (no |mu| below e^-2 there: log |mu| / tau is each r
    // to rounding).
    struct Liouville {
        double trace = kNaN;
        double step = 0.0;  // 0: no gain (a collapsed direction, or NaN)
    };
    const Liouville& liouville(const Configuration& cfg) {
        auto found = liouville_.find(cfg);
        if (found != liouville_.end()) return found->second;
        Liouville l;
        const double rate = tangent_.max_rate(cfg);
        if (rate > 0 && n2_ >= 2) {
            const double tau = 1 / rate;
            const Eigen::MatrixXd P = tangent_.transition(cfg, tau);
            const Eigen::PartialPivLU<Eigen::MatrixXd> lu(P);
            double log_det = 0.0;
            for (Eigen::Index k = 0; k < n2_; ++k) log_det += std::log(std::fabs(lu.matrixLU()(k, k)));
            const Eigen::VectorXcd mu = Eigen::EigenSolver<Eigen::MatrixXd>(P, false).eigenvalues();
            std::vector<double> r;
            for (Eigen::Index k = 0; k < mu.size(); ++k) r.push_back(std::log(std::abs(mu(k))) / tau);
            std::sort(r.begin(), r.end(), std::greater<double>());
            if (std::isfinite(log_det) && std::isfinite(r.front()) && std::isfinite(r[r.size() - 2])) {
                l.trace = log_det / tau;
                // Also no growth or decay beyond e^20 of any of them (no overflow, no underflow).
                const double spread = std::max({r.front() - r[r.size() - 2], std::fabs(r.front()),
                                                std::fabs(r[r.size() - 2])});
                // Only for a fastest decay well apart from the rest (a stiff
                // dashpot); else the steps stay as they were, bit for bit.
                const bool apart = r[r.size() - 2] - r.back() >= 10 * spread;
                l.step = !apart ? 0.0 : spread > 0 ? 20 / spread : kInf;
            }
        }
        return liouville_.emplace(cfg, l).first->second;
    }

    analysis::Tangent tangent_;
    std::map<Configuration, Liouville> liouville_;
    analysis::GrazingMonitor grazing_;
    Eigen::Index n2_;
    double t_start_, t_end_, row_;
    const std::function<void(double, const std::vector<double>&)>& on_row_;
    Observer* inner_;
    Eigen::MatrixXd Q_;
    Eigen::VectorXd logsum_;
    Eigen::Index live_;
    double next_row_ = 0.0, last_row_ = -kInf, last_ = -kInf;
    std::size_t row_k_ = 0, events_ = 0;

public:
    void start_rows() { next_row_ = t_start_ + row_; row_k_ = 1; }
};

}  // namespace

double lyapunov_row_interval(const Model& model, const LyapunovOptions& o) {
    if (!std::isnan(o.row_interval)) return o.row_interval;
    double omega = 0.0;
    for (const Harmonic& h : model.forcing)
        if (h.omega != 0.0) omega = omega == 0.0 ? std::fabs(h.omega) : std::min(omega, std::fabs(h.omega));
    return omega == 0.0 ? 1.0 : 2 * M_PI / omega;
}

LyapunovResult lyapunov(const Model& model, const LyapunovOptions& o,
                        const std::function<void(double, const std::vector<double>&)>& on_row, Observer* observer) {
    if (std::isnan(o.t_end)) throw OptionError(kLyapunov, "t_end", "NaN", "required: the length of the measurement");
    analysis::check_number(kLyapunov, "t_end", o.t_end, true);
    if (!(o.transient >= 0) || !std::isfinite(o.transient))
        throw OptionError(kLyapunov, "transient", number_text(o.transient), "must be finite and >= 0");
    const double row = lyapunov_row_interval(model, o);
    analysis::check_number(kLyapunov, "row_interval", row, true);
    analysis::Flow flow(model, {o.kernels, o.cache_dir, o.use_cache}, kLyapunov);
    if (o.progress) flow.set_progress(o.progress);
    const double t_start = model.t0 + o.transient, t_end = t_start + o.t_end;
    if (!(t_end > t_start)) throw OptionError(kLyapunov, "t_end", number_text(o.t_end), "too short to measure at t0 + transient");

    SpectrumObserver spectrum(flow.model(), t_start, t_end, row, on_row, observer);
    spectrum.start_rows();
    const RunSummary s = flow.run(model.t0, model.x0.data(), model.v0.data(), t_end, spectrum, false, 0.0,
                                  model.slider0.empty() ? nullptr : model.slider0.data());
    LyapunovResult r;
    r.status = s.status;
    r.message = s.message;
    r.t_start = t_start;
    r.t = s.t;
    r.events = spectrum.events();
    r.grazing = spectrum.grazing();
    r.singular = spectrum.singular();
    if (s.status != RunStatus::ok) return r;
    r.exponents = spectrum.finish(s.t);
    r.collapsed = spectrum.collapsed();
    r.sum = 0.0;
    for (double e : r.exponents) r.sum += e;
    return r;
}

}  // namespace hsnc
