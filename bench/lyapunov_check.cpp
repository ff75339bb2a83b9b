// The largest Lyapunov exponent of a model (hsnc::lyapunov, exact tangent
// dynamics) against the divergence of two high-precision reference runs
// started `offset` apart in x of the first mass (docs/paper.md, "Lyapunov
// spectrum of scenario 2").
//
//   hsnc_lyapunov_check MODEL [T=300] [DIGITS=60] [OFFSET=1e-30] [WINDOW=10]
//
// Prints: the spectrum over T and longer horizons; for the reference pair,
// the separation of their switch instants |t_A,k - t_B,k| (same switch k, the
// sequences agree throughout), its envelope (max per WINDOW seconds), the
// least-squares exponential fit of the envelope from t = 20 s, and the
// separation of the end states at full precision; the reference's own
// error (event times at DIGITS against 2*DIGITS digits) beside it.
#include <cln/float.h>
#include <cln/real.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "hsnc/lyapunov.h"
#include "model_reader.h"
#include "reference_engine.h"

using namespace hsnc;

namespace {

class Quiet : public Observer {
public:
    void on_sample(double, const double*, const double*) override {}
    void on_event(double, EventKind, int, const double*, const double*) override {}
};

reference::PreciseRun run(const Model& m, int digits, double t_end, const std::vector<double>* offset) {
    EngineOptions o;
    o.t_end = t_end;
    o.samples = false;
    Quiet q;
    return reference::simulate_precise(m, digits, o, q, {}, offset);
}

struct Fit {
    double slope = 0, intercept = 0, rms = 0;
    int points = 0;
};

Fit fit_line(const std::vector<double>& x, const std::vector<double>& y) {
    Fit f;
    const double n = static_cast<double>(x.size());
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (std::size_t i = 0; i < x.size(); ++i) sx += x[i], sy += y[i], sxx += x[i] * x[i], sxy += x[i] * y[i];
    f.slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    f.intercept = (sy - f.slope * sx) / n;
    for (std::size_t i = 0; i < x.size(); ++i) {
        const double r = y[i] - f.intercept - f.slope * x[i];
        f.rms += r * r;
    }
    f.rms = std::sqrt(f.rms / n);
    f.points = static_cast<int>(x.size());
    return f;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s MODEL [T=300] [DIGITS=60] [OFFSET=1e-30] [WINDOW=10]\n", argv[0]);
        return 2;
    }
    const Model model = read_model(argv[1]);
    const double T = argc > 2 ? std::atof(argv[2]) : 300.0;
    const int digits = argc > 3 ? std::atoi(argv[3]) : 60;
    const double offset = argc > 4 ? std::atof(argv[4]) : 1e-30;
    const double window = argc > 5 ? std::atof(argv[5]) : 10.0;
    const std::size_t n = model.dof();

    std::printf("Lyapunov spectrum of %s (exact tangent dynamics, QR method), from t0 = %g:\n", model.name.c_str(),
                model.t0);
    for (double len : {T, 3 * T, 10 * T, 100 * T}) {
        LyapunovOptions lo;
        lo.t_end = len;
        const LyapunovResult r = lyapunov(model, lo);
        std::printf("  over %7g s (%zu switches): ", len, r.events);
        for (double e : r.exponents) std::printf("%.5f ", e);
        std::printf(" collapsed %zu  (%s)\n", r.collapsed, run_status_name(r.status));
    }
    {
        LyapunovOptions lo;
        lo.t_end = 10 * T;
        lo.transient = T;
        const LyapunovResult r = lyapunov(model, lo);
        std::printf("  over %7g s after a transient of %g s: ", lo.t_end, T);
        for (double e : r.exponents) std::printf("%.5f ", e);
        std::printf("\n");
    }

    std::vector<double> off(2 * n, 0.0);
    off[0] = offset;
    const reference::PreciseRun a = run(model, digits, T, nullptr);
    const reference::PreciseRun b = run(model, digits, T, &off);
    const reference::PreciseRun a2 = run(model, 2 * digits, T, nullptr);
    std::printf("\nreference at %d digits (%d bits), runs A and B (x_%s(t0) + %g), %g s: %zu and %zu switches\n", digits,
                reference::carried_bits(digits), model.masses[0].name.c_str(), offset, T, a.events.size(),
                b.events.size());
    const std::size_t common = std::min(a.events.size(), b.events.size());
    std::size_t same = 0;
    while (same < common && a.events[same].kind == b.events[same].kind && a.events[same].element == b.events[same].element)
        ++same;
    std::printf("same switch sequence for the first %zu switches\n", same);

    // Separation of the switch instants, and the reference's own error (N vs 2N digits).
    std::vector<double> tw, env;
    double own = 0.0;
    double w_end = model.t0 + window, w_max = 0.0;
    for (std::size_t k = 0; k < same; ++k) {
        const double t = cln::double_approx(a.events[k].t);
        const double d = cln::double_approx(cln::abs(a.events[k].t - b.events[k].t));
        if (k < a2.events.size()) own = std::max(own, cln::double_approx(cln::abs(a.events[k].t - a2.events[k].t)));
        while (t > w_end) {
            if (w_max > 0) tw.push_back(w_end - window / 2), env.push_back(std::log10(w_max));
            w_max = 0.0;
            w_end += window;
        }
        w_max = std::max(w_max, d);
    }
    if (w_max > 0) tw.push_back(w_end - window / 2), env.push_back(std::log10(w_max));
    std::printf("reference's own error: max |t_k(%d digits) - t_k(%d digits)| = %.3g s\n", digits, 2 * digits, own);
    std::printf("envelope of |t_A,k - t_B,k| (max per %g s window), log10 seconds:\n", window);
    for (std::size_t i = 0; i < tw.size(); ++i) std::printf("  t = %6.1f  %.3f\n", tw[i], env[i]);
    std::vector<double> fx, fy;
    for (std::size_t i = 0; i < tw.size(); ++i)
        if (tw[i] >= 20) fx.push_back(tw[i]), fy.push_back(env[i]);
    if (fx.size() > 2) {
        const Fit f = fit_line(fx, fy);
        std::printf("exponential fit from t = 20 s (%d windows): log10|dt| = %.4f + %.6f t -> rate %.5f 1/s, RMS "
                    "residual %.3f decades\n",
                    f.points, f.intercept, f.slope, f.slope * std::log(10.0), f.rms);
        std::vector<double> lx;
        for (double t : fx) lx.push_back(std::log10(t));
        const Fit p = fit_line(lx, fy);
        std::printf("power-law fit from t = 20 s: |dt| ~ t^%.3f, RMS residual %.3f decades\n", p.slope, p.rms);
    }
    double dy = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        dy = std::max(dy, cln::double_approx(cln::abs(a.x[i] - b.x[i])));
        dy = std::max(dy, cln::double_approx(cln::abs(a.v[i] - b.v[i])));
    }
    std::printf("end states at t = %g: max |y_A - y_B| = %.4g -> mean rate ln(%.3g / %g) / %g = %.5f 1/s\n", T, dy, dy,
                offset, T - model.t0, std::log(dy / offset) / (T - model.t0));
    return 0;
}
