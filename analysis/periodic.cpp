// Newton shooting for periodic orbits (api/hsnc/periodic.h).
#include "hsnc/periodic.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <Eigen/QR>

#include "flow.h"
#include "shooting.h"
#include "sweep_point.h"
#include "number_text.h"

namespace hsnc {
namespace {

constexpr const char* kPeriodic = "hsnc::periodic";

// The fastest angular frequency of the model: the forcing's, or the highest
// natural frequency with every contact closed (0 when there is neither).
double fastest_frequency(const Model& model) {
    double omega = 0.0;
    for (const Harmonic& h : model.forcing) omega = std::max(omega, std::fabs(h.omega));
    try {
        omega = std::max(omega, sweep_detail::highest_natural_frequency(model));
    } catch (const std::exception&) {
        // no modal form (a model the analyses refuse later, naming why)
    }
    return omega;
}

// A period P too short to say anything is refused: one over which every state
// repeats to the tolerance (Omega P below max(1e-6, 10 tol), Omega the
// fastest frequency: `status=ok` at the initial state, whatever it is), or
// one the time cannot resolve at the start of the search.
void refuse_unresolved_period(const Model& model, const PeriodicOptions& o, double P) {
    // (The forcing's own period is never too short: Omega P >= 2 pi.)
    const double omega = std::isnan(o.period) ? 0.0 : fastest_frequency(model), ts = model.t0 + o.transient;
    if (omega > 0 && omega * P < std::max(1e-6, 10 * o.tolerance))
        throw OptionError(kPeriodic, "period", number_text(P),
                          "too short for this model: over it every state repeats to the tolerance (period times "
                          "the fastest angular frequency " + number_text(omega) + " rad/s is below max(1e-6, 10 tol))");
    if (P < 1e-12 * std::fabs(ts))
        throw OptionError(kPeriodic, "period", number_text(P),
                          "too short to resolve at t = " + number_text(ts) + " (below 1e-12 of the time)");
}

}  // namespace

const char* periodic_status_name(PeriodicStatus status) {
    switch (status) {
    case PeriodicStatus::ok: return "ok";
    case PeriodicStatus::not_converged: return "not_converged";
    case PeriodicStatus::stopped: return "stopped";
    }
    return "?";
}

double forcing_fundamental(const Model& model) {
    std::vector<double> w;
    for (const Harmonic& h : model.forcing)
        if (h.omega != 0.0) w.push_back(std::fabs(h.omega));
    if (w.empty()) return NAN;
    const double lowest = *std::min_element(w.begin(), w.end());
    if (std::all_of(w.begin(), w.end(), [&](double x) { return x == lowest; }))
        return lowest;  // one frequency, exactly
    // The lowest is q omega0 for the smallest q that makes every other a whole multiple of omega0 = lowest/q.
    for (int q = 1; q <= kMaxHarmonicOrder; ++q) {
        const double omega0 = lowest / q;
        const bool whole = std::all_of(w.begin(), w.end(), [&](double x) {
            const double n = std::round(x / omega0);
            return n >= 1 && n <= kMaxHarmonicOrder && std::fabs(x - n * omega0) <= 1e-12 * x;
        });
        if (whole) return omega0;
    }
    return NAN;
}

double forcing_period(const Model& model) {
    const double omega0 = forcing_fundamental(model);
    return std::isnan(omega0) ? NAN : 2 * M_PI / omega0;
}

PeriodicResult periodic(const Model& model, const PeriodicOptions& o, Observer* orbit) {
    double T = o.period;
    if (std::isnan(T)) {
        T = forcing_period(model);
        if (std::isnan(T)) {
            bool forced = false;
            for (const Harmonic& h : model.forcing) forced = forced || h.omega != 0.0;
            throw OptionError(kPeriodic, "period", "NaN",
                              forced ? "the forcing's frequencies are not commensurate (no common period with "
                                       "harmonic orders up to 1000, to 1e-12): give the period (a quasi-periodic "
                                       "response: hsnc simulate --section period:OMEGA gives its section and "
                                       "rotation number)"
                                     : "the model has no harmonic forcing: give the period");
        }
    }
    analysis::check_number(kPeriodic, "period", T, true);
    if (o.harmonic < 1) throw OptionError(kPeriodic, "harmonic", std::to_string(o.harmonic), "must be >= 1");
    if (!(o.transient >= 0) || !std::isfinite(o.transient))
        throw OptionError(kPeriodic, "transient", number_text(o.transient), "must be finite and >= 0");
    analysis::check_number(kPeriodic, "tolerance", o.tolerance, true);
    if (o.max_iterations < 0)
        throw OptionError(kPeriodic, "max_iterations", std::to_string(o.max_iterations), "must be >= 0");
    const double P = T * o.harmonic;
    refuse_unresolved_period(model, o, P);
    if (!std::isnan(o.dt)) analysis::check_number(kPeriodic, "dt", o.dt, true);
    const double dt = std::isnan(o.dt) ? P / 1000 : o.dt;

    analysis::Flow flow(model, {o.kernels, o.cache_dir, o.use_cache}, kPeriodic);
    PeriodicProgress progress;
    if (o.progress)
        flow.set_progress([&](double t) {
            progress.t = t;
            return o.progress(progress);
        });
    auto stage = [&](PeriodicProgress::Stage st, double from, double to) {
        progress.stage = st;
        progress.t = progress.t_from = from;
        progress.t_to = to;
    };
    PeriodicResult stopped;
    stopped.status = PeriodicStatus::stopped;
    stopped.message = "stopped by the progress callback";
    const std::size_t n = model.dof(), nj = model.jenkins.size();
    const Eigen::Index N = static_cast<Eigen::Index>(2 * n + nj);

    // Start: the initial state, or the state after the transient at t0 + k*P;
    // y = (x, v, s), the Jenkins sliders last (at rest, unstretched, or slider0).
    Eigen::VectorXd y(N);
    for (std::size_t i = 0; i < n; ++i) y(static_cast<Eigen::Index>(i)) = model.x0[i], y(static_cast<Eigen::Index>(n + i)) = model.v0[i];
    for (std::size_t j = 0; j < nj; ++j)
        y(static_cast<Eigen::Index>(2 * n + j)) =
            model.slider0.empty() ? jenkins::unstretched_slider(model.jenkins[j], model.x0.data()) : model.slider0[j];
    double ts = model.t0;
    if (o.transient > 0) {
        const double k = std::ceil(o.transient / P * (1 - 1e-12));
        ts = model.t0 + k * P;
        analysis::NullObserver none;
        stage(PeriodicProgress::Stage::transient, model.t0, ts);
        const RunSummary s = flow.run(model.t0, model.x0.data(), model.v0.data(), ts, none, false, 0.0,
                                      nj ? y.data() + 2 * n : nullptr);
        if (flow.stopped()) return stopped;
        if (s.status != RunStatus::ok)
            throw RunError(std::string("periodic: the transient run ended with status ") + run_status_name(s.status) +
                           ": " + s.message);
        for (std::size_t i = 0; i < n; ++i) y(static_cast<Eigen::Index>(i)) = s.x[i], y(static_cast<Eigen::Index>(n + i)) = s.v[i];
        for (std::size_t j = 0; j < nj; ++j) y(static_cast<Eigen::Index>(2 * n + j)) = s.slider[j];
    }
    const double te = ts + P;

    auto evaluate = [&](const Eigen::VectorXd& state) {
        stage(PeriodicProgress::Stage::search, ts, te);
        ++progress.runs;
        return analysis::evaluate_period_map(flow, ts, te, state);
    };

    PeriodicResult r;
    r.period = P;
    r.t = ts;
    analysis::PeriodMapValue cur = evaluate(y);
    int it = 0;
    std::string why;
    while (true) {
        if (flow.stopped()) return stopped;
        progress.iterations = it;
        progress.residual = cur.residual;
        if (!cur.ok) {
            why = cur.message;
            break;
        }
        if (cur.residual <= o.tolerance) break;
        if (it >= o.max_iterations) {
            why = "no convergence in " + std::to_string(o.max_iterations) + " iterations";
            break;
        }
        if (cur.singular || !cur.M.allFinite()) {
            why = "the period map has no derivative here (a grazing switch with zero normal velocity)";
            break;
        }
        // Newton step on P(y) - y = 0, least squares where M - I is singular
        // (a multiplier 1: an unforced model, a family of orbits).
        const Eigen::MatrixXd A = cur.M - Eigen::MatrixXd::Identity(N, N);
        const Eigen::VectorXd step = A.completeOrthogonalDecomposition().solve(-(cur.Py - y));
        if (!step.allFinite()) {
            why = "the Newton step is not finite";
            break;
        }
        ++it;
        double lambda = 1.0;
        bool accepted = false;
        for (int halving = 0; halving <= 10; ++halving, lambda *= 0.5) {
            const Eigen::VectorXd trial = y + lambda * step;
            analysis::PeriodMapValue next = evaluate(trial);
            if (flow.stopped()) return stopped;
            if (next.ok && next.residual < cur.residual) {
                y = trial;
                cur = std::move(next);
                accepted = true;
                break;
            }
        }
        if (!accepted) {
            why = "the residual stops falling at " + number_text(cur.residual) + " (no step along the Newton direction "
                  "lowers it)";
            break;
        }
    }
    r.iterations = it;
    r.residual = cur.residual;
    r.grazing = cur.grazing;
    r.x.assign(y.data(), y.data() + n);
    r.v.assign(y.data() + n, y.data() + 2 * n);
    r.s.assign(y.data() + 2 * n, y.data() + N);
    if (cur.ok && cur.residual <= o.tolerance) {
        r.status = PeriodicStatus::ok;
        r.events = cur.events;
        r.monodromy.resize(static_cast<std::size_t>(N * N));
        for (Eigen::Index i = 0; i < N; ++i)
            for (Eigen::Index j = 0; j < N; ++j) r.monodromy[static_cast<std::size_t>(i * N + j)] = cur.M(i, j);
        r.multipliers = analysis::floquet_multipliers(cur.M);
        r.max_multiplier = r.multipliers.empty() ? 0.0 : std::abs(r.multipliers.front());
        r.neutral = analysis::family_multipliers(cur.M, r.multipliers);
        r.stable = analysis::orbit_stable(r.multipliers, r.neutral);
        if (orbit) {
            stage(PeriodicProgress::Stage::orbit, ts, te);
            const RunSummary s = flow.run(ts, y.data(), y.data() + n, te, *orbit, true, dt, nj ? y.data() + 2 * n : nullptr);
            if (flow.stopped()) return stopped;
            if (s.status != RunStatus::ok)
                throw RunError(std::string("periodic: the run of the orbit ended with status ") +
                               run_status_name(s.status) + ": " + s.message);
        }
    } else {
        r.status = PeriodicStatus::not_converged;
        r.message = why;
    }
    return r;
}

}  // namespace hsnc
