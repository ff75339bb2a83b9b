// Accuracy measurement of the high-precision reference (not a test; see
// bench/reference_check.sh and docs/guide/reference.md):
//   hsnc_reference_check MODEL T_END N
// runs MODEL to T_END with the reference at N and 2N digits and with the
// double hsnc engine (ahead-of-time kernels when the model has them), and
// prints: event counts, how far the event sequences agree (same kind and
// element), the largest relative event-time difference over the matched
// prefix, the end-state difference, and the double engine's event-time error
// against the 2N-digit run, with where it parts (first event off by > 1e-6).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <cln/float.h>
#include <cln/real.h>

#include "aot_registry.h"
#include "engine.h"
#include "hsnc/simulate.h"
#include "kernel_mode.h"
#include "lowering.h"
#include "model_reader.h"
#include "reference_engine.h"

using namespace hsnc;
using cln::cl_F;

namespace {

struct Quiet : Observer {
    void on_sample(double, const double*, const double*) override {}
    void on_event(double, EventKind, int, const double*, const double*) override {}
};

struct Events : Observer {
    std::vector<double> t;
    std::vector<EventKind> kind;
    std::vector<int> element;
    void on_sample(double, const double*, const double*) override {}
    void on_event(double tt, EventKind k, int e, const double*, const double*) override {
        t.push_back(tt);
        kind.push_back(k);
        element.push_back(e);
    }
};

double seconds_since(std::chrono::steady_clock::time_point s) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - s).count();
}

// Largest relative time difference over the first `upto` events; count of the prefix with equal kinds/elements.
struct Match {
    std::size_t same = 0;    // events with equal kind and element, from the start
    double max_rel = 0;      // over the matched prefix
    std::size_t parted = 0;  // first event whose time differs by more than 1e-6 relative (or = same)
    std::vector<std::pair<std::size_t, double>> at;  // max_rel over the first k events, k = 10, 100, 1000...
};

}  // namespace

int main(int argc, char** argv) {
    if (argc != 4 && argc != 5) {
        std::fprintf(stderr, "usage: hsnc_reference_check MODEL T_END N [KERNELS: auto|aot|generic]\n");
        return 2;
    }
    const Model model = read_model(argv[1]);
    const double t_end = std::atof(argv[2]);
    const int N = std::atoi(argv[3]);
    EngineOptions opt;
    opt.t_end = t_end;
    opt.samples = false;

    Quiet quiet;
    auto s0 = std::chrono::steady_clock::now();
    const reference::PreciseRun lo = reference::simulate_precise(model, N, opt, quiet);
    const double t_lo = seconds_since(s0);
    s0 = std::chrono::steady_clock::now();
    const reference::PreciseRun hi = reference::simulate_precise(model, 2 * N, opt, quiet);
    const double t_hi = seconds_since(s0);
    const auto bits = [](const cl_F& x) { return static_cast<int>(cln::float_digits(x)); };
    std::printf("model %s, t_end %g\n", model.name.c_str(), t_end);
    std::printf("reference %d digits (%d bits): status %s, %zu events, %.2f s\n", N, bits(lo.t),
                run_status_name(lo.summary.status), lo.events.size(), t_lo);
    std::printf("reference %d digits (%d bits): status %s, %zu events, %.2f s\n", 2 * N, bits(hi.t),
                run_status_name(hi.summary.status), hi.events.size(), t_hi);

    auto compare = [&](std::size_t n, auto same_at, auto rel_at) {
        Match m;
        while (m.same < n && same_at(m.same)) ++m.same;
        m.parted = m.same;
        std::size_t next_mark = 10;
        for (std::size_t k = 0; k < m.same; ++k) {
            const double r = rel_at(k);
            if (r > 1e-6 && m.parted == m.same) m.parted = k;
            if (m.parted == m.same) m.max_rel = std::max(m.max_rel, r);
            if (k + 1 == next_mark) {  // 10, 100, 1000, 2000, 3000, ...
                m.at.push_back({k + 1, m.max_rel});
                next_mark = next_mark < 1000 ? next_mark * 10 : next_mark + 1000;
            }
        }
        return m;
    };
    const std::size_t n_ref = std::min(lo.events.size(), hi.events.size());
    const Match ref = compare(
        n_ref,
        [&](std::size_t k) {
            return lo.events[k].kind == hi.events[k].kind && lo.events[k].element == hi.events[k].element;
        },
        [&](std::size_t k) { return reference::relative_difference(lo.events[k].t, hi.events[k].t); });
    std::printf(
        "N vs 2N: events %zu vs %zu, same sequence for %zu, agree (< 1e-6) for %zu; max relative event-time "
        "difference over those %.3e\n",
        lo.events.size(), hi.events.size(), ref.same, ref.parted, ref.max_rel);
    for (auto& [k, r] : ref.at) std::printf("  first %zu events: max relative time difference %.3e\n", k, r);
    if (ref.parted == n_ref && lo.events.size() == hi.events.size()) {
        double dx = 0;
        for (std::size_t i = 0; i < model.dof(); ++i) {
            dx = std::max(dx, reference::relative_difference(lo.x[i], hi.x[i], 1e-300));
            dx = std::max(dx, reference::relative_difference(lo.v[i], hi.v[i], 1e-300));
        }
        std::printf("N vs 2N end state: max relative difference of x, v %.3e\n", dx);
    }

    // The double engine against the 2N-digit reference.
    Events dbl;
    const KernelChoice mode = argc == 5 ? kernel_choice_from_name(argv[4]) : KernelChoice::automatic;
    auto provider = make_solver_provider(model, mode, &aot_registry(), program_source(model));
    Engine engine(model, *provider);
    const RunSummary ds = engine.run(opt, dbl);
    const std::size_t n_dbl = std::min(dbl.t.size(), hi.events.size());
    const Match dm = compare(
        n_dbl,
        [&](std::size_t k) { return dbl.kind[k] == hi.events[k].kind && dbl.element[k] == hi.events[k].element; },
        [&](std::size_t k) {
            return reference::relative_difference(cln::cl_float(dbl.t[k], hi.events[k].t), hi.events[k].t);
        });
    std::printf(
        "double engine (%s): status %s, %zu events; same sequence as the %d-digit run for %zu, agrees "
        "(< 1e-6) for %zu; max relative event-time error over those %.3e\n",
        provider->describe().c_str(), run_status_name(ds.status), dbl.t.size(), 2 * N, dm.same, dm.parted, dm.max_rel);
    for (auto& [k, r] : dm.at) std::printf("  first %zu events: max relative time error %.3e\n", k, r);
    // Error in ulps of the event time, by kind: contact switches against friction switches.
    std::vector<double> contact_ulps, friction_ulps;
    for (std::size_t k = 0; k < dm.parted; ++k) {
        const double truth = cln::double_approx(hi.events[k].t);
        const double ulp = std::nextafter(std::abs(truth), INFINITY) - std::abs(truth);
        const double err = std::abs(cln::double_approx(cln::cl_float(dbl.t[k], hi.events[k].t) - hi.events[k].t)) / ulp;
        const bool contact = dbl.kind[k] == EventKind::contact_close || dbl.kind[k] == EventKind::contact_open;
        (contact ? contact_ulps : friction_ulps).push_back(err);
    }
    auto report = [](const char* what, std::vector<double> u) {
        if (u.empty()) return;
        std::sort(u.begin(), u.end());
        std::printf("  %s events: %zu, error median %.3g ulp, 90%% %.3g ulp, max %.3g ulp\n", what, u.size(),
                    u[u.size() / 2], u[u.size() * 9 / 10], u.back());
    };
    report("contact", contact_ulps);
    report("friction", friction_ulps);
    if (dm.parted < n_dbl)
        std::printf("  parts at event %zu, t = %.6f\n", dm.parted, cln::double_approx(hi.events[dm.parted].t));
    return 0;
}
