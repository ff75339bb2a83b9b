// A test oracle: the forced bilinear oscillator x'' + c x' + k(x) x = F sin(w t),
// k = 1 for x < 0 and 1 + kc for x > 0 (a stop at the equilibrium), in
// closed form: nothing of hsnc's solvers in it (its switches found on a grid
// and by bisection).
#pragma once

#include <cmath>
#include <complex>
#include <cstdio>
#include <string>

namespace hsnc::testing {

// The same oscillator as an hsnc model: its parameters omega, c, kc, F at
// these values.
inline std::string bilinear_model(double omega, double c, double kc, double F) {
    char values[160];
    std::snprintf(values, sizeof values, "omega = %.17g\nc = %.17g\nkc = %.17g\nF = %.17g\n", omega, c, kc, F);
    return std::string("name = \"bilinear\"\n[parameters]\n") + values + R"([[mass]]
name = "m"
m = 1.0
[[spring]]
between = ["ground", "m"]
k = 1.0
[damping]
alpha = "c"
[[contact]]
between = ["m", "ground"]
gap = 0.0
k = "kc"
[[forcing]]
omega = "omega"
amplitude = { m = "F" }
)";
}

// The bilinear oscillator in closed form: in each region x'' + c x' + K x =
// F sin(w t) has x = xp + e^{-c s/2} (A cos(wd s) + B sin(wd s)), s = t - ts,
// xp = F |H| sin(w t + arg H), H = 1/(K - w^2 + i c w).
struct Bilinear {
    double w, c, kc, F;

    struct Piece {
        double K, ts, A, B, wd;
        std::complex<double> H;
    };
    Piece piece(double t, double x, double v) const {
        Piece p;
        p.K = x > 0 || (x == 0 && v > 0) ? 1 + kc : 1.0;
        p.ts = t;
        p.H = 1.0 / std::complex<double>(p.K - w * w, c * w);
        p.wd = std::sqrt(p.K - c * c / 4);
        const double xp = F * std::abs(p.H) * std::sin(w * t + std::arg(p.H));
        const double vp = F * std::abs(p.H) * w * std::cos(w * t + std::arg(p.H));
        p.A = x - xp;
        p.B = (v - vp + c / 2 * p.A) / p.wd;
        return p;
    }
    void eval(const Piece& p, double t, double& x, double& v) const {
        const double s = t - p.ts, e = std::exp(-c / 2 * s), cs = std::cos(p.wd * s), sn = std::sin(p.wd * s);
        const double ph = w * t + std::arg(p.H), a = F * std::abs(p.H);
        x = a * std::sin(ph) + e * (p.A * cs + p.B * sn);
        v = a * w * std::cos(ph) + e * (-c / 2 * (p.A * cs + p.B * sn) + p.wd * (-p.A * sn + p.B * cs));
    }

    // From (x, v) at t to t_end, the switches at x = 0 found on a grid of
    // 1/4000 of a period and refined by bisection to rounding; every piece
    // passed to `visit(piece, from, to)`.
    template <class Visit>
    void run(double t, double& x, double& v, double t_end, Visit visit) const {
        const double h = 2 * 3.14159265358979323846 / w / 4000;
        Piece p = piece(t, x, v);
        double a = t;
        while (a < t_end) {
            const double b = std::min(a + h, t_end);
            double xa, va, xb, vb;
            eval(p, a, xa, va);
            eval(p, b, xb, vb);
            const bool above = p.K > 1;
            if ((above && xb < 0) || (!above && xb > 0)) {
                double lo = a, hi = b;
                for (int it = 0; it < 200 && hi - lo > 0; ++it) {
                    const double mid = 0.5 * (lo + hi);
                    if (mid == lo || mid == hi) break;
                    double xm, vm;
                    eval(p, mid, xm, vm);
                    ((above && xm >= 0) || (!above && xm <= 0) ? lo : hi) = mid;
                }
                visit(p, t, hi);
                eval(p, hi, x, v);
                x = 0.0;
                t = hi;
                p = piece(t, x, v);
                // The new region's sign from the velocity at the crossing.
                a = hi;
                continue;
            }
            a = b;
        }
        visit(p, t, t_end);
        eval(p, t_end, x, v);
    }
};

}  // namespace hsnc::testing
