#include "emitter.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <sstream>

#include "model_hash.h"

namespace hsnc {

using GiNaC::numeric;

std::string format_double(double v) {
    if (std::isinf(v)) return v > 0 ? "__builtin_inf()" : "(-__builtin_inf())";
    if (v == 0.0) return "0.0";  // also -0
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    std::string s = buf;
    if (s.find_first_of(".e") == std::string::npos) s += ".0";
    return s;
}

std::string kernel_symbol(const Model& model, const Configuration& cfg) {
    std::string name;
    for (char ch : model.name)
        name += (std::isalnum(static_cast<unsigned char>(ch)) || ch == '_') ? ch : '_';
    return "hsnc_kernel_" + name + "_" + cfg.key();
}

namespace {

double dbl(const numeric& x) { return x.to_double(); }

bool cfg_stuck(const Derivation& d, std::size_t mass) { return d.cfg.stuck[mass] != 0; }

numeric to_numeric_sqrt(const numeric& x) { return GiNaC::ex_to<numeric>(GiNaC::sqrt(x).evalf()); }

/// A linear combination c0 + sum c_k * var_k printed with signs folded:
/// "1.5 - 2.0*x + y". Zero coefficients are left out.
class Lin {
public:
    Lin& add(double c, const std::string& var) {
        if (c != 0.0) terms_.push_back({c, var});
        return *this;
    }
    Lin& add(const numeric& c, const std::string& var) { return add(dbl(c), var); }
    Lin& add_const(double c) { return add(c, ""); }
    bool empty() const { return terms_.empty(); }
    std::string str() const {
        if (terms_.empty()) return "0.0";
        std::string s;
        for (std::size_t k = 0; k < terms_.size(); ++k) {
            double c = terms_[k].first;
            const std::string& v = terms_[k].second;
            if (k == 0) {
                if (c < 0 && !v.empty()) {
                    s += "-";
                    c = -c;
                }
            } else {
                s += c < 0 ? " - " : " + ";
                c = std::fabs(c);
            }
            if (v.empty())
                s += format_double(c);
            else if (c == 1.0)
                s += v;
            else
                s += format_double(c) + "*" + v;
        }
        return s;
    }

private:
    std::vector<std::pair<double, std::string>> terms_;
};

/// Lines of code at a fixed layout (4-space indent, one statement per line).
class Code {
public:
    void line(int indent, const std::string& text) {
        out_ << std::string(static_cast<std::size_t>(4 * indent), ' ') << text << "\n";
    }
    void blank() { out_ << "\n"; }
    void raw(const char* text) { out_ << text; }
    std::string str() const { return out_.str(); }

private:
    std::ostringstream out_;
};

std::string idx(std::size_t k) { return std::to_string(k + 1); }  // 1-based names: q_1, ...

}  // namespace

// The forcing phase at the segment start, as GenericSolver computes it
// (runtime/generic_solver.cpp, reduced_phase): emitted into every kernel with
// forcing, folded or sweep.
const char* const kPhaseFunctionSource =
    "// Omega (t0 + t0_lo) + phase reduced to [-pi, pi]: the product's rounding kept (fma) and\n"
    "// 2 pi in two parts (Cody-Waite), so a large t0 costs no phase accuracy beyond its own.\n"
    "double hsnc_phase(double omega, double t0, double t0_lo, double phase) {\n"
    "    const double hi = omega * t0;\n"
    "    const double lo = __builtin_fma(omega, t0, -hi) + omega * t0_lo;\n"
    "    const double n = __builtin_nearbyint(hi / 6.283185307179586);\n"
    "    double r = __builtin_fma(-n, 6.283185307179586, hi);\n"
    "    r = __builtin_fma(-n, 2.4492935982947064e-16, r);\n"
    "    return __builtin_remainder(r + lo + phase, 6.283185307179586);\n"
    "}\n";

namespace {

std::string body_name(const Model& m, int b) { return b == kGround ? "ground" : m.masses[b].name; }


// ---- setup, in blocks ----
// The homogeneous initial state is taken from the physical residual
// x0 - x_p(0), where x_p(0) = x_st + sum_h (xs_h sin theta_h + xc_h cos theta_h)
// is computed with exactly the constants eval adds back at tau = 0. Taking it
// as q(0) - q_p(0) in modal coordinates instead (modal constants P a_s, 1/lambda)
// made setup subtract a slightly different particular part than eval adds: a
// fixed offset per restart, so a state restarted at the same place walked
// away linearly (seed-scenario-1, contact closed: 4.1e-12 of |x| over 2000
// restarts, 1505 of 1509 moves the same way; tests/test_restart_drift.cpp).

using SlotFn = std::function<std::string(const std::string&)>;

void emit_setup_phases(const Derivation& d, Code& s, const SlotFn& slot) {
    if (d.harmonics.empty()) return;
    s.line(1, "// Forcing phases at the segment start: theta_h = Omega_h (t0 + t0_lo) + phase_h, reduced.");
    for (std::size_t h = 0; h < d.harmonics.size(); ++h) {
        const std::string H = idx(h);
        s.line(1, "const double theta_" + H + " = hsnc_phase(Omega_" + H + ", t0, t0_lo, " +
                      format_double(dbl(d.harmonics[h].phase)) + ");");
        s.line(1, "const double s_theta_" + H + " = __builtin_sin(theta_" + H + ");");
        s.line(1, "const double c_theta_" + H + " = __builtin_cos(theta_" + H + ");");
        s.line(1, slot("theta_" + H) + " = theta_" + H + ";");
        s.line(1, slot("c_theta_" + H) + " = c_theta_" + H + ";");
    }
}

void emit_setup_static_offset(const Derivation& d, Code& s, const SlotFn& slot) {
    const Model& model = *d.model;
    s.line(1, "// Static offset x_st = V (p / lambda) over the elastic modes.");
    for (std::size_t r = 0; r < d.n_free(); ++r) {
        Lin l;
        for (std::size_t j = 0; j < d.modes.size(); ++j)
            if (!d.modes[j].lambda.is_zero()) l.add(d.modes[j].v[r] / d.modes[j].lambda, "p_" + idx(j));
        s.line(1, "const double x_st_" + idx(r) + " = " + l.str() + ";  // " + model.masses[d.free_dofs[r]].name);
        s.line(1, slot("x_st_" + idx(r)) + " = x_st_" + idx(r) + ";");
    }
}

void emit_setup_homogeneous_state(const Derivation& d, Code& s) {
    const std::size_t nf = d.n_free(), nm = d.modes.size(), nh = d.harmonics.size();
    auto ld = [](const std::string& e) { return "static_cast<long double>(" + e + ")"; };
    s.line(1, "// Homogeneous part of the initial state in x: xh = x0 - x_p(0), vh = v0 - v_p(0), with");
    s.line(1, "// x_p = x_st + sum_h (xs sin + xc cos) and the same constants as eval (long double sums).");
    for (std::size_t r = 0; r < nf; ++r) {
        const std::string i = std::to_string(d.free_dofs[r]), R = idx(r);
        std::string xh = ld("x0[" + i + "]") + " - " + ld("x_st_" + R), vh = ld("v0[" + i + "]");
        for (std::size_t h = 0; h < nh; ++h) {
            const HarmonicData& hd = d.harmonics[h];
            const double W = dbl(hd.omega), xs = dbl(hd.xs[r]), xc = dbl(hd.xc[r]);
            const std::string H = idx(h);
            if (xs != 0.0) xh += " - " + ld(format_double(xs)) + "*s_theta_" + H;
            if (xc != 0.0) xh += " - " + ld(format_double(xc)) + "*c_theta_" + H;
            if (W * xs != 0.0) vh += " - " + ld(format_double(W * xs)) + "*c_theta_" + H;
            if (-W * xc != 0.0) vh += " - " + ld(format_double(-W * xc)) + "*s_theta_" + H;
        }
        s.line(1, "const double xh_" + R + " = static_cast<double>(" + xh + ");");
        s.line(1, "const double vh_" + R + " = static_cast<double>(" + vh + ");");
    }
    s.line(1, "// Its modal coordinates q = W xh, q' = W vh.");
    for (std::size_t j = 0; j < nm; ++j) {
        Lin q, dq;
        for (std::size_t r = 0; r < nf; ++r) {
            q.add(d.modes[j].w[r], "xh_" + idx(r));
            dq.add(d.modes[j].w[r], "vh_" + idx(r));
        }
        s.line(1, "const double q0u_" + idx(j) + " = " + q.str() + ";");
        s.line(1, "const double dq0u_" + idx(j) + " = " + dq.str() + ";");
    }
    // V and W are inverse only to rounding, so xh -> W xh -> V W xh is the
    // fixed matrix I + E (E ~ eps) of the configuration: applied at every
    // segment start it is a bias (a steady energy gain), not noise. One
    // refinement against the residual, accumulated in long double, removes it
    // (as GenericSolver::setup does).
    s.line(1, "// One refinement of q against the residuals r = xh - V q (long double): removes the bias of V W = I + E.");
    for (std::size_t r = 0; r < nf; ++r) {
        std::string rx = ld("xh_" + idx(r)), rv = ld("vh_" + idx(r));
        for (std::size_t j = 0; j < nm; ++j) {
            const std::string c = ld(format_double(dbl(d.modes[j].v[r])));
            rx += " - " + c + "*q0u_" + idx(j);
            rv += " - " + c + "*dq0u_" + idx(j);
        }
        s.line(1, "const double rx_" + idx(r) + " = static_cast<double>(" + rx + ");");
        s.line(1, "const double rv_" + idx(r) + " = static_cast<double>(" + rv + ");");
    }
    for (std::size_t j = 0; j < nm; ++j) {
        Lin q, dq;
        for (std::size_t r = 0; r < nf; ++r) {
            q.add(d.modes[j].w[r], "rx_" + idx(r));
            dq.add(d.modes[j].w[r], "rv_" + idx(r));
        }
        s.line(1, "const double q0_" + idx(j) + " = q0u_" + idx(j) + " + (" + q.str() + ");");
        s.line(1, "const double dq0_" + idx(j) + " = dq0u_" + idx(j) + " + (" + dq.str() + ");");
    }
}

// A second refinement, against what eval returns at tau = 0: x(0) and v(0)
// written with eval's constants in eval's order, the residuals x0 - x(0),
// v0 - v(0) (long double) mapped back with W. x(0) is a sum of terms larger
// than x (static offset, forcing response), so without it its rounding
// depends on x0 only through the leading bits and a state restarted again and
// again kept moving the same way (chain-8, contacts closed: 112 of 123 moves
// of x[0] one way; tests/test_restart_drift.cpp).
void emit_setup_output_refinement(const Derivation& d, Code& s) {
    const std::size_t nf = d.n_free(), nm = d.modes.size(), nh = d.harmonics.size();
    s.line(1, "// Refinement against eval at tau = 0 (same constants, same order): residuals x0 - x(0), v0 - v(0).");
    for (std::size_t r = 0; r < nf; ++r) {
        Lin x, v;
        x.add(1.0, "x_st_" + idx(r));
        for (std::size_t j = 0; j < nm; ++j) {
            x.add(d.modes[j].v[r], "q0_" + idx(j));
            v.add(d.modes[j].v[r], "dq0_" + idx(j));
        }
        for (std::size_t h = 0; h < nh; ++h) {
            const HarmonicData& hd = d.harmonics[h];
            const double W = dbl(hd.omega), xs = dbl(hd.xs[r]), xc = dbl(hd.xc[r]);
            const std::string H = idx(h);
            x.add(xs, "s_theta_" + H).add(xc, "c_theta_" + H);
            v.add(W * xs, "c_theta_" + H).add(-W * xc, "s_theta_" + H);
        }
        const std::string i = std::to_string(d.free_dofs[r]), R = idx(r);
        s.line(1, "const double xe_" + R + " = " + x.str() + ";");
        s.line(1, "const double ve_" + R + " = " + v.str() + ";");
        s.line(1, "const double ex_" + R + " = static_cast<double>(static_cast<long double>(x0[" + i +
                      "]) - static_cast<long double>(xe_" + R + "));");
        s.line(1, "const double ev_" + R + " = static_cast<double>(static_cast<long double>(v0[" + i +
                      "]) - static_cast<long double>(ve_" + R + "));");
    }
    for (std::size_t j = 0; j < nm; ++j) {
        Lin q, dq;
        for (std::size_t r = 0; r < nf; ++r) {
            q.add(d.modes[j].w[r], "ex_" + idx(r));
            dq.add(d.modes[j].w[r], "ev_" + idx(r));
        }
        s.line(1, "const double qh0_" + idx(j) + " = q0_" + idx(j) + " + (" + q.str() + ");");
        s.line(1, "const double dqh0_" + idx(j) + " = dq0_" + idx(j) + " + (" + dq.str() + ");");
    }
}

void emit_setup_modes(const Derivation& d, Code& s, const SlotFn& slot) {
    for (std::size_t j = 0; j < d.modes.size(); ++j) {
        const Mode& m = d.modes[j];
        const std::string J = idx(j);
        s.line(1, "// Mode " + J + " (" + regime_name(m.regime) + "): A = q_h(0), B = q_h'(0) + sigma A (the particular");
        s.line(1, "// parts start at rest or are in x_p) and the derivative pairs, consistent to rounding.");
        if (m.regime == Regime::rigid) {
            s.line(1, slot("p_" + J) + " = p_" + J + ";  // q_p = p tau^2 / 2");
        } else if (m.regime == Regime::rigid_damped) {
            s.line(1, slot("p_" + J) + " = p_" + J + ";  // q_p = p tau^2 phi2(-c tau)");
        }
        s.line(1, "const double A_" + J + " = qh0_" + J + ";");
        s.line(1, "const double B_" + J + " = dqh0_" + J + (m.sigma.is_zero() ? "" : " + sigma_" + J + "*A_" + J) + ";");
        s.line(1, slot("A_" + J) + " = A_" + J + ";");
        s.line(1, slot("B_" + J) + " = B_" + J + ";");
        s.line(1, "const double A1_" + J + " = B_" + J + " - sigma_" + J + "*A_" + J + ";");
        s.line(1, "const double B1_" + J + " = -kappa_" + J + "*A_" + J + " - sigma_" + J + "*B_" + J + ";");
        s.line(1, slot("A1_" + J) + " = A1_" + J + ";");
        s.line(1, slot("B1_" + J) + " = B1_" + J + ";");
        s.line(1, slot("A2_" + J) + " = B1_" + J + " - sigma_" + J + "*A1_" + J + ";");
        s.line(1, slot("B2_" + J) + " = -kappa_" + J + "*A1_" + J + " - sigma_" + J + "*B1_" + J + ";");
    }
}

}  // namespace

std::string emit_kernel(const Derivation& d) {
    const Model& model = *d.model;
    const std::size_t n = model.dof(), nf = d.n_free(), nm = d.modes.size(), nh = d.harmonics.size();
    const std::string sym = kernel_symbol(model, d.cfg);
    std::vector<std::string> coef;  // coefficient block layout, in order
    auto slot = [&](const std::string& name) {
        coef.push_back(name);
        return "coef[" + std::to_string(coef.size() - 1) + "]";
    };
    auto V = [&](int mass, std::size_t j) -> numeric {  // V_ij, 0 for stuck masses and ground
        if (mass == kGround) return 0;
        const int r = d.free_index(mass);
        return r < 0 ? numeric(0) : d.modes[j].v[r];
    };

    Code c;
    // ---- provenance ----
    char hash[32];
    std::snprintf(hash, sizeof hash, "0x%016llx", static_cast<unsigned long long>(model_hash(model)));
    c.line(0, "// hsnc kernel -- generated by hsnc " HSNC_VERSION " (generator/emitter.cpp); do not edit.");
    c.line(0, "// model:         " + model.name + " (hash " + hash + ")");
    c.line(0, "// configuration: " + d.cfg.spec(model) + " (key " + d.cfg.key() + ")");
    {
        std::string fr, st;
        for (int i : d.free_dofs) fr += (fr.empty() ? "" : ", ") + model.masses[i].name;
        for (int i : d.stuck_dofs) st += (st.empty() ? "" : ", ") + model.masses[i].name;
        c.line(0, "// free masses:   " + (fr.empty() ? std::string("none") : fr));
        c.line(0, "// stuck masses:  " + (st.empty() ? std::string("none") : st));
    }
    c.line(0, "//");
    c.line(0, "// Free masses obey M x'' + C x' + K x = f + sum_h F_h sin(Omega_h t + phase_h) with");
    c.line(0, "// f = loads + preload - K_FS x_S - mu_k N sgn (paper Eq. 7-9). In modal coordinates");
    c.line(0, "// x = V q, q = W x: q_j'' + c_j q_j' + lambda_j q_j = p_j + sum_h P_jh sin(...).");
    c.line(0, "// Homogeneous part q_h = A eC + B eS with d/dtau (A, B) = (B - sigma A, -kappa A - sigma B).");
    for (std::size_t j = 0; j < nm; ++j) {
        const Mode& m = d.modes[j];
        c.line(0, "// mode " + idx(j) + ": " + regime_name(m.regime) + ", lambda = " + format_double(dbl(m.lambda)) +
                      ", omega = " + format_double(dbl(m.omega)) + ", c = " + format_double(dbl(m.c)) +
                      ", xi = " + format_double(dbl(m.xi)));
    }
    c.blank();
    c.line(0, "#include \"kernel_abi.h\"");
    c.blank();
    // Internals in a namespace of their own, so that kernels may share a translation unit.
    const std::string ns = "k_" + sym.substr(std::string("hsnc_kernel_").size());
    c.line(0, "namespace {");
    c.line(0, "namespace " + ns + " {");
    c.blank();

    // ---- constants ----
    c.line(0, "// Modal constants.");
    for (std::size_t j = 0; j < nm; ++j) {
        const Mode& m = d.modes[j];
        const std::string J = idx(j);
        c.line(0, "constexpr double lambda_" + J + " = " + format_double(dbl(m.lambda)) + ";");
        c.line(0, "constexpr double sigma_" + J + " = " + format_double(dbl(m.sigma)) + ";");
        c.line(0, "constexpr double kappa_" + J + " = " + format_double(dbl(m.kappa)) + ";");
        switch (m.regime) {
            case Regime::undamped:
            case Regime::underdamped:
                c.line(0, "constexpr double omega_d_" + J + " = " + format_double(dbl(m.omega_d)) + ";");
                break;
            case Regime::overdamped:
                c.line(0, "constexpr double gamma_" + J + " = " + format_double(dbl(m.gamma)) + ";");
                c.line(0, "constexpr double r1_" + J + " = " + format_double(dbl(m.r1)) + ";  // slow root -lambda/(sigma+gamma)");
                break;
            case Regime::rigid_damped:
                c.line(0, "constexpr double c_" + J + " = " + format_double(dbl(m.c)) + ";");
                break;
            default:
                break;
        }
    }
    for (std::size_t h = 0; h < nh; ++h)
        c.line(0, "constexpr double Omega_" + idx(h) + " = " + format_double(dbl(d.harmonics[h].omega)) + ";");
    c.blank();
    if (nh > 0) {
        c.raw(kPhaseFunctionSource);
        c.blank();
    }
    if (std::any_of(d.modes.begin(), d.modes.end(), [](const Mode& m) { return m.regime == Regime::rigid_damped; })) {
        c.line(0, "// phi2(x) = (e^x - 1 - x)/x^2, phi2(0) = 1/2; Taylor series where the subtraction cancels.");
        c.line(0, "double phi2(double x) {");
        c.line(1, "if (__builtin_fabs(x) < 0.5) {");
        c.line(2, "double term = 0.5, sum = 0.5;  // x^k/(k+2)!");
        c.line(2, "for (int k = 1; k < 20; ++k) {");
        c.line(3, "term *= x / (k + 2);");
        c.line(3, "sum += term;");
        c.line(2, "}");
        c.line(2, "return sum;");
        c.line(1, "}");
        c.line(1, "return (__builtin_expm1(x) - x) / (x * x);");
        c.line(0, "}");
        c.blank();
    }

    // ================= setup =================
    Code s;
    s.line(0, "void setup(double* coef, double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) {");
    s.line(1, "(void)t0; (void)t0_lo; (void)x0; (void)v0; (void)sgn;");
    if (nf > 0) {
        s.line(1, "// Constant force on the free masses: loads + preload - K_FS x_S - mu_k N sgn (Eq. 7-9).");
        for (std::size_t r = 0; r < nf; ++r) {
            const int i = d.free_dofs[r];
            Lin l;
            l.add_const(dbl(d.f_const[i]));
            for (int st : d.stuck_dofs)
                l.add(-dbl(GiNaC::ex_to<numeric>(d.K(i, st))), "x0[" + std::to_string(st) + "]");
            l.add(-dbl(d.mu_k_n[i]), "sgn[" + std::to_string(i) + "]");
            s.line(1, "const double f_" + idx(r) + " = " + l.str() + ";  // " + model.masses[i].name);
        }
        s.line(1, "// Modal forces p = V^T f.");
        for (std::size_t j = 0; j < nm; ++j) {
            Lin p;
            for (std::size_t r = 0; r < nf; ++r) p.add(d.modes[j].v[r], "f_" + idx(r));
            s.line(1, "const double p_" + idx(j) + " = " + p.str() + ";");
        }
    }
    emit_setup_phases(d, s, slot);
    if (nf > 0) emit_setup_static_offset(d, s, slot);
    if (nf > 0) emit_setup_homogeneous_state(d, s);
    if (nf > 0) emit_setup_output_refinement(d, s);
    emit_setup_modes(d, s, slot);
    for (int st : d.stuck_dofs)
        s.line(1, slot("x_stuck_" + std::to_string(st)) + " = x0[" + std::to_string(st) + "];  // " +
                      model.masses[st].name + " is stuck");
    s.line(0, "}");

    // ================= eval =================
    Code e;
    e.line(0, "void eval(const double* coef, double tau, double* x, double* v, double* a, double* g, double* dg,");
    e.line(0, "          double* bound, double* scale) {");
    e.line(1, "(void)tau;");
    auto coef_of = [&](const std::string& name) {
        for (std::size_t k = 0; k < coef.size(); ++k)
            if (coef[k] == name) return "coef[" + std::to_string(k) + "]";
        return std::string("0.0 /* missing " + name + " */");
    };
    if (nh > 0) e.line(1, "// Forcing harmonics: sin/cos(Omega_h tau + theta_h), once each.");
    for (std::size_t h = 0; h < nh; ++h) {
        const std::string H = idx(h);
        e.line(1, "const double arg_" + H + " = Omega_" + H + "*tau + " + coef_of("theta_" + H) + ";");
        e.line(1, "const double sin_" + H + " = __builtin_sin(arg_" + H + ");");
        e.line(1, "const double cos_" + H + " = __builtin_cos(arg_" + H + ");");
    }
    for (std::size_t j = 0; j < nm; ++j) {
        const Mode& m = d.modes[j];
        const std::string J = idx(j);
        e.line(1, "// Mode " + J + " (" + regime_name(m.regime) + ").");
        switch (m.regime) {
            case Regime::undamped:
                e.line(1, "// eC = cos(omega tau), eS = sin(omega tau)/omega");
                e.line(1, "const double eC_" + J + " = __builtin_cos(omega_d_" + J + "*tau);");
                e.line(1, "const double eS_" + J + " = __builtin_sin(omega_d_" + J + "*tau)*" +
                              format_double(1.0 / dbl(m.omega_d)) + ";");
                break;
            case Regime::underdamped:
                e.line(1, "// eC = e^{-sigma tau} cos(omega_d tau), eS = e^{-sigma tau} sin(omega_d tau)/omega_d");
                e.line(1, "const double e_" + J + " = __builtin_exp(-sigma_" + J + "*tau);");
                e.line(1, "const double eC_" + J + " = e_" + J + "*__builtin_cos(omega_d_" + J + "*tau);");
                e.line(1, "const double eS_" + J + " = e_" + J + "*__builtin_sin(omega_d_" + J + "*tau)*" +
                              format_double(1.0 / dbl(m.omega_d)) + ";");
                break;
            case Regime::critical:
                e.line(1, "// eC = e^{-sigma tau}, eS = tau e^{-sigma tau}");
                e.line(1, "const double eC_" + J + " = __builtin_exp(-sigma_" + J + "*tau);");
                e.line(1, "const double eS_" + J + " = tau*eC_" + J + ";");
                break;
            case Regime::overdamped:
                e.line(1, "// e^{-sigma tau} cosh(gamma tau) = e^{r1 tau} (1 + E)/2, e^{-sigma tau} sinh(gamma tau)/gamma");
                e.line(1, "// = -e^{r1 tau} m/(2 gamma) with m = expm1(-2 gamma tau), E = 1 + m: no overflow.");
                e.line(1, "const double e_" + J + " = __builtin_exp(r1_" + J + "*tau);");
                e.line(1, "const double m_" + J + " = __builtin_expm1(" + format_double(-2.0 * dbl(m.gamma)) + "*tau);");
                e.line(1, "const double eC_" + J + " = e_" + J + "*(1.0 + 0.5*m_" + J + ");");
                e.line(1, "const double eS_" + J + " = -e_" + J + "*m_" + J + "*" + format_double(0.5 / dbl(m.gamma)) + ";");
                break;
            case Regime::rigid:
                e.line(1, "// eC = 1, eS = tau");
                e.line(1, "const double eC_" + J + " = 1.0;");
                e.line(1, "const double eS_" + J + " = tau;");
                break;
            case Regime::rigid_damped:
                e.line(1, "// eC = (1 + e^{-c tau})/2, eS = (1 - e^{-c tau})/c with m = expm1(-c tau)");
                e.line(1, "const double m_" + J + " = __builtin_expm1(-c_" + J + "*tau);");
                e.line(1, "const double eC_" + J + " = 1.0 + 0.5*m_" + J + ";");
                e.line(1, "const double eS_" + J + " = -m_" + J + "*" + format_double(1.0 / dbl(m.c)) + ";");
                break;
        }
        const std::string A = coef_of("A_" + J), B = coef_of("B_" + J), A1 = coef_of("A1_" + J),
                          B1 = coef_of("B1_" + J), A2 = coef_of("A2_" + J), B2 = coef_of("B2_" + J);
        e.line(1, "const double qh_" + J + " = " + A + "*eC_" + J + " + " + B + "*eS_" + J + ";");
        e.line(1, "const double dqh_" + J + " = " + A1 + "*eC_" + J + " + " + B1 + "*eS_" + J + ";");
        e.line(1, "const double ddqh_" + J + " = " + A2 + "*eC_" + J + " + " + B2 + "*eS_" + J + ";");
        e.line(1, "// sqrt(2E), E = (q_h'^2 + lambda q_h^2)/2 never grows (c >= 0).");
        e.line(1, "const double r_" + J + " = __builtin_sqrt(dqh_" + J + "*dqh_" + J + " + lambda_" + J + "*qh_" + J +
                      "*qh_" + J + ");");
        std::string q = "qh_" + J, dq = "dqh_" + J, ddq = "ddqh_" + J;
        std::string mag = "__builtin_fabs(" + A + "*eC_" + J + ") + __builtin_fabs(" + B + "*eS_" + J + ")";
        // A1 = B - sigma A (setup) cancels to eps |sigma A|: count that term in the
        // magnitude of q', else v(0) = 0 comes back as -1e-16 against a stated level
        // of 3e-17 and the engine takes it for a stop (a mass at rest against a stiff,
        // damped contact stopped as chattering at t0).
        std::string dmag = "__builtin_fabs(" + A1 + "*eC_" + J + ") + __builtin_fabs(" + B1 + "*eS_" + J + ")";
        if (!m.sigma.is_zero()) dmag += " + __builtin_fabs(sigma_" + J + "*" + A + "*eC_" + J + ")";
        if (m.regime == Regime::rigid) {
            const std::string p = coef_of("p_" + J);
            e.line(1, "// particular q_p = p tau^2/2");
            q += " + 0.5*" + p + "*tau*tau";
            dq += " + " + p + "*tau";
            ddq += " + " + p;
            mag += " + __builtin_fabs(0.5*" + p + "*tau*tau)";
            dmag += " + __builtin_fabs(" + p + "*tau)";
        } else if (m.regime == Regime::rigid_damped) {
            // One form for every c > 0, exact as c -> 0: the split (p/c) tau + (q'(0) - p/c) eS
            // lost eps |p/c| (6e-10 at alpha = 1e-6; tests/test_sweep_kernels.cpp, floating pair).
            const std::string p = coef_of("p_" + J);
            e.line(1, "// particular q_p = p tau^2 phi2(-c tau) from rest: q_p' = p eS, q_p'' = p e^{-c tau}");
            e.line(1, "const double qp_" + J + " = " + p + "*tau*tau*phi2(-c_" + J + "*tau);");
            q += " + qp_" + J;
            dq += " + " + p + "*eS_" + J;
            ddq += " + " + p + "*(1.0 + m_" + J + ")";
            mag += " + __builtin_fabs(qp_" + J + ")";
            dmag += " + __builtin_fabs(" + p + "*eS_" + J + ")";
        }
        for (std::size_t h = 0; h < nh; ++h) {
            const ModalHarmonic& mh = d.harmonics[h].modal[j];
            if (!mh.resonant) continue;
            const std::string JH = J + "_" + idx(h), H = idx(h);
            const numeric W = d.harmonics[h].omega;
            const double Q = dbl(mh.P / (m.omega + W)), hw = dbl((W - m.omega) / 2), wb = dbl((W + m.omega) / 2);
            const std::string ct = coef_of("c_theta_" + H);
            e.line(1, "// Resonant response to harmonic " + H + " from rest, stable through Omega = omega:");
            e.line(1, "// y = Q [-w cos(wbar tau + theta) + cos(theta) sin(omega tau)/omega], Q = P/(omega + Omega),");
            e.line(1, "// w = sin(h tau)/h -> tau (h = (Omega - omega)/2, wbar = (Omega + omega)/2): the secular term.");
            if (hw == 0.0) {
                e.line(1, "const double w_" + JH + " = tau;");
                e.line(1, "const double dw_" + JH + " = 1.0;");
            } else {
                e.line(1, "const double w_" + JH + " = __builtin_sin(" + format_double(hw) + "*tau)*" +
                              format_double(1.0 / hw) + ";");
                e.line(1, "const double dw_" + JH + " = __builtin_cos(" + format_double(hw) + "*tau);");
            }
            const std::string arg = format_double(wb) + "*tau + " + coef_of("theta_" + H);
            e.line(1, "const double Cb_" + JH + " = __builtin_cos(" + arg + ");");
            e.line(1, "const double Sb_" + JH + " = __builtin_sin(" + arg + ");");
            const std::string Qs = format_double(Q);
            e.line(1, "const double y_" + JH + " = " + Qs + "*(" + ct + "*eS_" + J + " - w_" + JH + "*Cb_" + JH + ");");
            e.line(1, "const double dy_" + JH + " = " + Qs + "*(" + ct + "*eC_" + J + " - dw_" + JH + "*Cb_" + JH +
                          " + " + format_double(wb) + "*w_" + JH + "*Sb_" + JH + ");");
            e.line(1, "const double ddy_" + JH + " = " + Qs + "*(" + format_double(hw * hw + wb * wb) + "*w_" + JH +
                          "*Cb_" + JH + " + " + format_double(2 * wb) + "*dw_" + JH + "*Sb_" + JH + " - lambda_" + J +
                          "*" + ct + "*eS_" + J + ");");
            q += " + y_" + JH;
            dq += " + dy_" + JH;
            ddq += " + ddy_" + JH;
            mag += " + __builtin_fabs(y_" + JH + ")";
            dmag += " + __builtin_fabs(dy_" + JH + ")";
        }
        e.line(1, "const double q_" + J + " = " + q + ";");
        e.line(1, "const double dq_" + J + " = " + dq + ";");
        e.line(1, "const double ddq_" + J + " = " + ddq + ";");
        e.line(1, "const double mq_" + J + " = " + mag + ";  // magnitude of the terms of q");
        e.line(1, "const double mdq_" + J + " = " + dmag + ";");
    }

    // x, v, a of every mass and the magnitudes of their terms.
    e.line(1, "// Physical state: x = x_st + V q + sum_h (xs_h sin + xc_h cos); stuck masses rest.");
    std::vector<double> hx(n, 0.0), hv(n, 0.0);  // magnitudes of the harmonic terms
    for (std::size_t i = 0; i < n; ++i) {
        const std::string I = std::to_string(i);
        const int r = d.free_index(static_cast<int>(i));
        if (r < 0) {
            const std::string xs = coef_of("x_stuck_" + I);
            e.line(1, "x[" + I + "] = " + xs + ";  // " + model.masses[i].name + " (stuck)");
            e.line(1, "v[" + I + "] = 0.0;");
            e.line(1, "a[" + I + "] = 0.0;");
            e.line(1, "const double mx_" + I + " = __builtin_fabs(" + xs + ");");
            e.line(1, "const double mv_" + I + " = 0.0;");
            continue;
        }
        Lin x, v, acc;
        x.add(1.0, coef_of("x_st_" + idx(static_cast<std::size_t>(r))));
        std::string mx = "__builtin_fabs(" + coef_of("x_st_" + idx(static_cast<std::size_t>(r))) + ")", mv;
        for (std::size_t j = 0; j < nm; ++j) {
            x.add(d.modes[j].v[r], "q_" + idx(j));
            v.add(d.modes[j].v[r], "dq_" + idx(j));
            acc.add(d.modes[j].v[r], "ddq_" + idx(j));
            const double vv = std::fabs(dbl(d.modes[j].v[r]));
            if (vv != 0.0) {
                const std::string f = vv == 1.0 ? "" : format_double(vv) + "*";
                mx += " + " + f + "mq_" + idx(j);
                mv += (mv.empty() ? "" : " + ") + f + "mdq_" + idx(j);
            }
        }
        for (std::size_t h = 0; h < nh; ++h) {
            const HarmonicData& hd = d.harmonics[h];
            const double W = dbl(hd.omega), xs = dbl(hd.xs[r]), xc = dbl(hd.xc[r]);
            const std::string H = idx(h);
            x.add(xs, "sin_" + H).add(xc, "cos_" + H);
            v.add(W * xs, "cos_" + H).add(-W * xc, "sin_" + H);
            acc.add(-W * W * xs, "sin_" + H).add(-W * W * xc, "cos_" + H);
            hx[i] += std::fabs(xs) + std::fabs(xc);
            hv[i] += W * (std::fabs(xs) + std::fabs(xc));
        }
        if (hx[i] != 0.0) mx += " + " + format_double(hx[i]);
        if (hv[i] != 0.0) mv += (mv.empty() ? "" : " + ") + format_double(hv[i]);
        e.line(1, "x[" + I + "] = " + x.str() + ";  // " + model.masses[i].name);
        e.line(1, "v[" + I + "] = " + v.str() + ";");
        e.line(1, "a[" + I + "] = " + acc.str() + ";");
        e.line(1, "const double mx_" + I + " = " + mx + ";");
        e.line(1, "const double mv_" + I + " = " + (mv.empty() ? "0.0" : mv) + ";");
    }

    // Switch functions.
    e.line(1, "// Switch functions (runtime/segment.h order), derivatives, bounds on |g''| and term magnitudes.");
    e.line(1, "// bound = sum_j (|alpha_j| (c_j + omega_j) + |beta_j| (c_j (c_j + omega_j) + lambda_j)) sqrt(2 E_j)");
    e.line(1, "//       + sum_h R_h Omega_h^2 (+ rigid-body and secular terms), for g = alpha.q + beta.q' + ...");
    bool any_secular = false;
    for (std::size_t f = 0; f < d.switches.size(); ++f) {
        const SwitchFunction& sf = d.switches[f];
        const std::string F = std::to_string(f);
        // g as a combination of the state: alpha (on q) and beta (on q') per mode, and the
        // harmonic sinusoid Gs sin + Gc cos of the non-resonant particular parts.
        std::vector<numeric> al(nm, 0), be(nm, 0);
        std::vector<numeric> Gs(nh, 0), Gc(nh, 0);
        std::string gx, gdx, gscale;
        if (sf.kind == SwitchKind::gap) {
            const Contact& ct = model.contacts[sf.element];
            e.line(1, "// g_" + F + ": gap of contact " + ct.name + " = x[" + body_name(model, ct.a) + "] - x[" +
                          body_name(model, ct.b) + "] - " + format_double(ct.gap));
            Lin g, dg;
            std::string sc;
            if (ct.a != kGround) {
                g.add(1.0, "x[" + std::to_string(ct.a) + "]");
                dg.add(1.0, "v[" + std::to_string(ct.a) + "]");
                sc += "mx_" + std::to_string(ct.a);
            }
            if (ct.b != kGround) {
                g.add(-1.0, "x[" + std::to_string(ct.b) + "]");
                dg.add(-1.0, "v[" + std::to_string(ct.b) + "]");
                sc += (sc.empty() ? "" : " + ") + std::string("mx_") + std::to_string(ct.b);
            }
            g.add_const(-ct.gap);
            gx = g.str();
            gdx = dg.str();
            gscale = sc + (ct.gap != 0.0 ? " + " + format_double(std::fabs(ct.gap)) : "");
            for (std::size_t j = 0; j < nm; ++j) al[j] = V(ct.a, j) - V(ct.b, j);
            for (std::size_t h = 0; h < nh; ++h) {
                auto xsb = [&](int b, bool sine) -> numeric {
                    if (b == kGround || d.free_index(b) < 0) return 0;
                    return sine ? d.harmonics[h].xs[d.free_index(b)] : d.harmonics[h].xc[d.free_index(b)];
                };
                Gs[h] = xsb(ct.a, true) - xsb(ct.b, true);
                Gc[h] = xsb(ct.a, false) - xsb(ct.b, false);
            }
        } else if (sf.kind == SwitchKind::velocity) {
            const int i = sf.element;
            const std::string I = std::to_string(i);
            e.line(1, "// g_" + F + ": velocity of " + model.masses[i].name + " (sliding)");
            gx = "v[" + I + "]";
            gdx = "a[" + I + "]";
            gscale = "mv_" + I;
            const int r = d.free_index(i);
            for (std::size_t j = 0; j < nm; ++j) be[j] = d.modes[j].v[r];
            for (std::size_t h = 0; h < nh; ++h) {
                Gs[h] = -d.harmonics[h].omega * d.harmonics[h].xc[r];
                Gc[h] = d.harmonics[h].omega * d.harmonics[h].xs[r];
            }
        } else {
            const int i = sf.element;
            const bool pos = sf.kind == SwitchKind::release_pos;
            const Mass& ms = model.masses[i];
            const double mu_s_n = dbl(exact(ms.mu_s) * exact(ms.m) * exact(model.g));
            e.line(1, std::string("// g_") + F + ": " + (pos ? "A" : "-A") + " - mu_s N of stuck " + ms.name +
                          ", A = -K x - C v + f + sum_h F_h sin (force but friction)");
            Lin A, dA;
            std::string sc;
            A.add_const(dbl(d.f_const[i]));
            double const_mag = std::fabs(dbl(d.f_const[i])) + mu_s_n;
            for (std::size_t k = 0; k < n; ++k) {
                const double Kik = dbl(GiNaC::ex_to<numeric>(d.K(i, k)));
                const double Cik = dbl(GiNaC::ex_to<numeric>(d.C(i, k)));
                const std::string K = std::to_string(k);
                A.add(-Kik, "x[" + K + "]");
                dA.add(-Kik, "v[" + K + "]");
                if (Kik != 0.0) sc += (sc.empty() ? "" : " + ") + format_double(std::fabs(Kik)) + "*mx_" + K;
                if (!cfg_stuck(d, k)) {
                    A.add(-Cik, "v[" + K + "]");
                    dA.add(-Cik, "a[" + K + "]");
                    if (Cik != 0.0) sc += (sc.empty() ? "" : " + ") + format_double(std::fabs(Cik)) + "*mv_" + K;
                }
            }
            for (std::size_t h = 0; h < nh; ++h) {
                const double F0 = dbl(d.harmonics[h].amplitude[i]), W = dbl(d.harmonics[h].omega);
                A.add(F0, "sin_" + idx(h));
                dA.add(F0 * W, "cos_" + idx(h));
                const_mag += std::fabs(F0);
            }
            const std::string Fs = pos ? "" : "-", I = std::to_string(i);
            if (pos) {  // release_pos comes first; release_neg reuses A_i
                e.line(1, "const double A_force_" + I + " = " + A.str() + ";");
                e.line(1, "const double dA_force_" + I + " = " + dA.str() + ";");
            }
            gx = Fs + "A_force_" + I + " - " + format_double(mu_s_n);
            gdx = Fs + "dA_force_" + I;
            gscale = (sc.empty() ? "" : sc + " + ") + format_double(const_mag);
            for (std::size_t j = 0; j < nm; ++j)
                for (std::size_t r = 0; r < nf; ++r) {
                    const int k = d.free_dofs[r];
                    al[j] -= GiNaC::ex_to<numeric>(d.K(i, k)) * d.modes[j].v[r];
                    be[j] -= GiNaC::ex_to<numeric>(d.C(i, k)) * d.modes[j].v[r];
                }
            for (std::size_t h = 0; h < nh; ++h) {
                const HarmonicData& hd = d.harmonics[h];
                Gs[h] = hd.amplitude[i];
                for (std::size_t r = 0; r < nf; ++r) {
                    const int k = d.free_dofs[r];
                    const numeric Kik = GiNaC::ex_to<numeric>(d.K(i, k)), Cik = GiNaC::ex_to<numeric>(d.C(i, k));
                    Gs[h] += -Kik * hd.xs[r] + Cik * hd.omega * hd.xc[r];
                    Gc[h] += -Kik * hd.xc[r] - Cik * hd.omega * hd.xs[r];
                }
            }
        }
        e.line(1, "g[" + F + "] = " + gx + ";");
        e.line(1, "dg[" + F + "] = " + gdx + ";");
        // bound
        numeric konst = 0;
        for (std::size_t h = 0; h < nh; ++h) {
            const numeric W = d.harmonics[h].omega;
            konst += to_numeric_sqrt(Gs[h] * Gs[h] + Gc[h] * Gc[h]) * W * W;
        }
        Lin b;
        b.add_const(dbl(konst));
        for (std::size_t j = 0; j < nm; ++j) {
            const Mode& m = d.modes[j];
            const numeric H = abs(al[j]) * (m.c + m.omega) + abs(be[j]) * (m.c * (m.c + m.omega) + m.lambda);
            b.add(H, "r_" + idx(j));
            if (m.regime == Regime::rigid || m.regime == Regime::rigid_damped)  // |q_p''| <= |p|, |q_p'''| <= c |p|
                b.add(abs(al[j]) + abs(be[j]) * m.c, "__builtin_fabs(" + coef_of("p_" + idx(j)) + ")");
            for (std::size_t h = 0; h < nh; ++h) {
                const ModalHarmonic& mh = d.harmonics[h].modal[j];
                if (!mh.resonant || (al[j].is_zero() && be[j].is_zero())) continue;
                any_secular = true;
                const numeric W = d.harmonics[h].omega, Q = abs(mh.P / (m.omega + W));
                const numeric hw = abs(W - m.omega) / 2, wb = (W + m.omega) / 2;
                // |y''| <= Q ((h^2 + wbar^2) s + 2 wbar + omega), |y'''| <= Q (wbar^3 s + 3 wbar^2 + 3 h wbar + h^2 + omega^2)
                const numeric slope = abs(al[j]) * Q * (hw * hw + wb * wb) + abs(be[j]) * Q * wb * wb * wb;
                const numeric off = abs(al[j]) * Q * (2 * wb + m.omega) +
                                    abs(be[j]) * Q * (3 * wb * wb + 3 * hw * wb + hw * hw + m.lambda);
                b.add(slope, "s_end").add_const(dbl(off));
            }
        }
        e.line(1, "bound[" + F + "] = " + b.str() + ";");
        e.line(1, "scale[" + F + "] = " + (gscale.empty() ? "0.0" : gscale) + ";");
    }
    e.line(0, "}");

    // Assemble: constants, setup, eval (with s_end when secular), switch table, kernel object.
    std::string eval_text = e.str();
    if (any_secular) {
        const std::string marker = "    (void)tau;\n";
        eval_text.replace(eval_text.find(marker), marker.size(),
                          marker + "    // Secular terms are bounded at the end of the step, s_end = tau + max_step.\n"
                                   "    const double s_end = tau + " + format_double(d.max_step) + ";\n");
    }
    std::string out = c.str();
    out += "// Coefficient block (" + std::to_string(coef.size()) + " doubles):";
    for (std::size_t k = 0; k < coef.size(); ++k) out += (k % 6 == 0 ? "\n//  " : " ") + std::to_string(k) + ":" + coef[k];
    out += "\n" + s.str() + "\n" + eval_text + "\n";
    out += "const hsnc_switch switches[] = {";
    for (const SwitchFunction& sf : d.switches)
        out += "{" + std::to_string(static_cast<int>(sf.kind)) + ", " + std::to_string(sf.element) + "}, ";
    if (d.switches.empty()) out += "{0, -1}";  // C++ needs one element; n_switch = 0
    out += "};\n\n}  // namespace " + ns + "\n}  // namespace\n\n";
    out += emit_kernel_object(d, sym, ns, {std::to_string(coef.size()), format_double(d.max_step)});
    return out;
}

std::string emit_kernel_object(const Derivation& d, const std::string& sym, const std::string& ns,
                               const std::vector<std::string>& rest) {
    const Model& model = *d.model;
    char hash[32];
    std::snprintf(hash, sizeof hash, "0x%016llx", static_cast<unsigned long long>(model_hash(model)));
    std::string out = "extern \"C\" const hsnc_kernel " + sym + ";\n";
    out += "extern \"C\" const hsnc_kernel " + sym + " = {\n";
    out += "    HSNC_KERNEL_ABI_VERSION,\n";
    out += "    \"" + model.name + "\",\n";
    out += "    " + std::string(hash) + "ull,\n";
    out += "    \"" + d.cfg.spec(model) + "\",\n";
    out += "    \"" + d.cfg.key() + "\",\n";
    out += "    \"" HSNC_VERSION "\",\n";
    out += "    " + std::to_string(model.dof()) + ",\n";
    out += "    " + std::to_string(d.switches.size()) + ",\n";
    out += "    " + ns + "::switches,\n";
    for (std::size_t k = 0; k < rest.size(); ++k) {
        const std::size_t comment = rest[k].find("  //");  // "value  // why": the comma goes after the value
        out += comment == std::string::npos ? "    " + rest[k] + ",\n"
                                            : "    " + rest[k].substr(0, comment) + "," + rest[k].substr(comment) + "\n";
        if (k == 1) out += "    " + ns + "::setup,\n    " + ns + "::eval,\n";
    }
    out += "};\n";
    return out;
}

std::string emit_registry(const std::vector<std::string>& symbols, const std::string& function) {
    std::string out = "// hsnc AOT kernel registry -- generated by hsnc " HSNC_VERSION "; do not edit.\n";
    out += "#include \"aot_registry.h\"\n\n";
    for (const std::string& s : symbols) out += "extern \"C\" const hsnc_kernel " + s + ";\n";
    out += "\nnamespace hsnc {\nnamespace {\n\nconst hsnc_kernel* const kernels[] = {\n";
    for (const std::string& s : symbols) out += "    &" + s + ",\n";
    if (symbols.empty()) out += "    nullptr,\n";
    out += "};\n\n}  // namespace\n\nconst AotRegistry& " + function + "();\n\nconst AotRegistry& " + function + "() {\n";
    out += "    static const AotRegistry registry{kernels, " + std::to_string(symbols.size()) + "};\n";
    out += "    return registry;\n}\n\n}  // namespace hsnc\n";
    return out;
}

}  // namespace hsnc
