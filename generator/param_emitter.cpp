#include "param_emitter.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "emitter.h"
#include "error.h"
#include "model_hash.h"

namespace hsnc {

using GiNaC::ex;
using GiNaC::numeric;

std::vector<std::string> kept_parameters(const Model& model, const std::string& list) {
    const std::string flag = "generate: --params '" + list + "'";
    if (model.parameter_expressions.empty())
        throw InputError(flag + ": the model has no parameter source texts (not read from a file)");
    std::vector<std::string> names;
    for (const auto& [name, text] : model.parameter_expressions) names.push_back(name);
    if (list == "all") return names;
    std::vector<std::string> kept;  // in the order given: configure() takes them so
    std::size_t start = 0;
    while (true) {
        const std::size_t comma = list.find(',', start);
        const std::string name = list.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        if (name.empty()) throw InputError(flag + ": empty parameter name (use NAME,NAME,... or all)");
        if (std::find(names.begin(), names.end(), name) == names.end()) {
            std::string known;
            for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
            throw InputError(flag + ": unknown parameter '" + name + "' (the model has: " + known + ")");
        }
        if (std::find(kept.begin(), kept.end(), name) != kept.end())
            throw InputError(flag + ": parameter '" + name + "' is named twice");
        kept.push_back(name);
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    return kept;
}

std::string sweep_kernel_symbol(const Model& model, const Configuration& cfg) {
    return "hsnc_sweep_" + kernel_symbol(model, cfg).substr(std::string("hsnc_kernel_").size());
}

namespace {

std::string idx(std::size_t k) { return std::to_string(k + 1); }

/// C text of a parameter expression over the variables `var` (C names
/// "p_<name>"); every sum and product printed in sorted operand order so the
/// text does not depend on GiNaC's term order.
class CPrinter {
public:
    explicit CPrinter(std::string where) : where_(std::move(where)) {}

    std::string print(const ex& e) const {
        if (GiNaC::is_a<GiNaC::numeric>(e) || GiNaC::is_a<GiNaC::constant>(e)) {
            const ex v = e.evalf();
            if (!GiNaC::is_a<GiNaC::numeric>(v) || !GiNaC::ex_to<numeric>(v).is_real()) fail(e);
            const double d = GiNaC::ex_to<numeric>(v).to_double();
            return d < 0 ? "(" + format_double(d) + ")" : format_double(d);
        }
        if (GiNaC::is_a<GiNaC::symbol>(e)) return "p_" + GiNaC::ex_to<GiNaC::symbol>(e).get_name();
        if (GiNaC::is_a<GiNaC::add>(e) || GiNaC::is_a<GiNaC::mul>(e)) {
            std::vector<std::string> ops;
            for (std::size_t k = 0; k < e.nops(); ++k) ops.push_back(print(e.op(k)));
            std::sort(ops.begin(), ops.end());
            std::string s;
            for (const std::string& o : ops) s += (s.empty() ? "" : (GiNaC::is_a<GiNaC::add>(e) ? " + " : "*")) + o;
            return "(" + s + ")";
        }
        if (GiNaC::is_a<GiNaC::power>(e)) {
            const std::string b = print(e.op(0));
            const ex x = e.op(1);
            if (GiNaC::is_a<GiNaC::numeric>(x)) {
                const numeric n = GiNaC::ex_to<numeric>(x);
                if (n == numeric(1, 2)) return "__builtin_sqrt(" + b + ")";
                if (n == numeric(-1, 2)) return "(1.0/__builtin_sqrt(" + b + "))";
                if (n == -1) return "(1.0/" + b + ")";
                if (n == 2) return "(" + b + "*" + b + ")";
                if (n == -2) return "(1.0/(" + b + "*" + b + "))";
            }
            return "__builtin_pow(" + b + ", " + print(x) + ")";
        }
        if (GiNaC::is_a<GiNaC::function>(e)) {
            static const std::map<std::string, std::string> kFunctions = {
                {"sin", "sin"},     {"cos", "cos"},   {"tan", "tan"},   {"asin", "asin"}, {"acos", "acos"},
                {"atan", "atan"},   {"sinh", "sinh"}, {"cosh", "cosh"}, {"tanh", "tanh"}, {"exp", "exp"},
                {"log", "log"},     {"abs", "fabs"},  {"sqrt", "sqrt"}};
            const std::string name = GiNaC::ex_to<GiNaC::function>(e).get_name();
            const auto it = kFunctions.find(name);
            if (it == kFunctions.end() || e.nops() != 1) fail(e);
            return "__builtin_" + it->second + "(" + print(e.op(0)) + ")";
        }
        fail(e);
    }

private:
    [[noreturn]] void fail(const ex& e) const {
        std::ostringstream s;
        s << e;
        throw InputError("generate: --params: " + where_ + ": '" + s.str() +
                         "' cannot be written in a sweep kernel (numbers, + - * /, powers and "
                         "sin cos tan asin acos atan sinh cosh tanh exp log abs sqrt only)");
    }
    std::string where_;
};

bool uses(const ex& e, const std::set<std::string>& vars) {
    if (GiNaC::is_a<GiNaC::symbol>(e)) return vars.count(GiNaC::ex_to<GiNaC::symbol>(e).get_name()) > 0;
    for (std::size_t k = 0; k < e.nops(); ++k)
        if (uses(e.op(k), vars)) return true;
    return false;
}

/// The model's parameters and fields as C expressions: kept parameters are
/// the inputs, what depends on them is written as its source expression, the
/// rest folded.
class Fields {
public:
    Fields(const Model& model, const std::vector<std::string>& kept) : model_(model) {
        GiNaC::Digits = kDerivationDigits;
        for (const auto& [name, text] : model.parameter_expressions) table_[name] = GiNaC::symbol(name);
        for (std::size_t p = 0; p < model.parameter_expressions.size(); ++p) {
            const auto& [name, text] = model.parameter_expressions[p];
            const auto k = std::find(kept.begin(), kept.end(), name);
            if (k != kept.end()) {
                vars_.insert(name);
                params_.push_back("const double p_" + name + " = params[" + std::to_string(k - kept.begin()) +
                                  "];  // kept (model value " + format_double(model.parameters[p].second) + ")");
                continue;
            }
            const ex e = parse(text, "parameter '" + name + "'");
            if (uses(e, vars_)) {
                vars_.insert(name);
                params_.push_back("const double p_" + name + " = " + CPrinter("parameter '" + name + "'").print(e) +
                                  ";  // " + name + " = " + text);
            }
        }
    }

    /// Lines defining p_<name> for the kept and derived parameters.
    const std::vector<std::string>& parameter_lines() const { return params_; }
    const std::set<std::string>& variables() const { return vars_; }

    /// C text of field `key` (folded value `value` when it does not depend on
    /// a kept parameter); `fallback` is used when the file did not give it.
    std::string field(const std::string& key, double value, const std::string& fallback = "") {
        const auto it = model_.field_expressions.find(key);
        if (it == model_.field_expressions.end()) return fallback.empty() ? format_double(value) : fallback;
        const ex e = parse(it->second, key);
        if (!uses(e, vars_)) return format_double(value);
        variable_fields_.insert(key);
        return CPrinter(key).print(e);
    }
    bool variable(const std::string& key) const { return variable_fields_.count(key) > 0; }

    /// C text of the parameter g.
    std::string g() const { return vars_.count("g") ? "p_g" : format_double(model_.g); }

private:
    ex parse(const std::string& text, const std::string& where) const {
        try {
            GiNaC::parser reader(table_, /*strict=*/true);
            return reader(text);
        } catch (const std::exception& e) {
            throw InputError("generate: --params: " + where + ": expression '" + text + "' does not parse: " + e.what());
        }
    }
    const Model& model_;
    GiNaC::symtab table_;
    std::set<std::string> vars_;
    std::set<std::string> variable_fields_;
    std::vector<std::string> params_;
};

class Code {
public:
    void line(int indent, const std::string& text) {
        out_ << std::string(static_cast<std::size_t>(4 * indent), ' ') << text << "\n";
    }
    void blank() { out_ << "\n"; }
    std::string str() const { return out_.str(); }

private:
    std::ostringstream out_;
};

std::string list_ints(const std::vector<int>& v) {
    std::string s;
    for (int x : v) s += (s.empty() ? "" : ", ") + std::to_string(x);
    return s.empty() ? "0" : s;
}

// The part of every sweep kernel that does not depend on the model: the
// eigen-solver. Printed verbatim.
const char* const kJacobi = R"(// Cyclic Jacobi eigenvalue algorithm for the symmetric a (Golub & Van Loan,
// Matrix Computations, Alg. 8.5.3): on return a is diagonal to rounding and
// a_in = vec diag(a) vec^T. An off-diagonal entry below 1e-18 of its diagonal
// pair is already below their rounding and is set to zero; the sweeps end when
// one changes nothing. False when 100 sweeps do not get there.
bool jacobi(double (&a)[NF1][NF1], double (&vec)[NF1][NF1]) {
    for (int p = 0; p < NF; ++p)
        for (int q = 0; q < NF; ++q) vec[p][q] = p == q ? 1.0 : 0.0;
    for (int sweep = 0; sweep < 100; ++sweep) {
        bool rotated = false;
        for (int p = 0; p < NF; ++p)
            for (int q = p + 1; q < NF; ++q) {
                const double apq = a[p][q];
                if (apq == 0.0) continue;
                if (__builtin_fabs(apq) <= 1e-18 * (__builtin_fabs(a[p][p]) + __builtin_fabs(a[q][q]))) {
                    a[p][q] = a[q][p] = 0.0;
                    continue;
                }
                rotated = true;
                // tan of the rotation angle, the smaller root of t^2 + 2 theta t - 1 = 0.
                const double theta = (a[q][q] - a[p][p]) / (2.0 * apq);
                const double t = __builtin_fabs(theta) > 1e150
                                     ? 0.5 / theta
                                     : (theta >= 0.0 ? 1.0 : -1.0) /
                                           (__builtin_fabs(theta) + __builtin_sqrt(theta * theta + 1.0));
                const double c = 1.0 / __builtin_sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < NF; ++k) {  // a <- a J
                    const double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < NF; ++k) {  // a <- J^T a
                    const double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                a[p][q] = a[q][p] = 0.0;
                for (int k = 0; k < NF; ++k) {  // vec <- vec J
                    const double vkp = vec[k][p], vkq = vec[k][q];
                    vec[k][p] = c * vkp - s * vkq;
                    vec[k][q] = s * vkp + c * vkq;
                }
            }
        if (!rotated) return true;
    }
    return false;
}
)";

// The model-independent part of configure after the assembly: modes, regimes,
// forcing responses, switch-bound coefficients.
const char* const kModes = R"(    // ---- Modal decomposition of Kt = M_F^-1/2 K_FF M_F^-1/2 (M is diagonal) ----
    double sqm[NF1], a[NF1][NF1], vec[NF1][NF1];
    for (int r = 0; r < NF; ++r) sqm[r] = __builtin_sqrt(st.M[free_dof[r]]);
    for (int r = 0; r < NF; ++r)
        for (int s = 0; s < NF; ++s) a[r][s] = st.K[free_dof[r]][free_dof[s]] / (sqm[r] * sqm[s]);
    if (!jacobi(a, vec)) return HSNC_CONFIGURE_EIGEN;
    int order[NF1];  // eigenvalues ascending (insertion sort: stable, no allocation)
    for (int j = 0; j < NF; ++j) {
        int k = j;
        while (k > 0 && a[order[k - 1]][order[k - 1]] > a[j][j]) {
            order[k] = order[k - 1];
            --k;
        }
        order[k] = j;
    }
    // Rigid-body modes (the NR floating components, fixed at generation) replace the
    // NR smallest eigenpairs: lambda = 0, shape sqrt(m) / sqrt(component mass); the
    // elastic shapes are made orthogonal to them (one Gram-Schmidt pass) and renormalised.
    double shape[NF1][NF1];  // shape[j][r] = Phi_rj (orthonormal)
    for (int j = 0; j < NF; ++j) {
        if (j < NR) {
            double mt = 0.0;
            for (int r = 0; r < NF; ++r)
                if (rigid_member[j][r]) mt += st.M[free_dof[r]];
            for (int r = 0; r < NF; ++r) shape[j][r] = rigid_member[j][r] ? sqm[r] / __builtin_sqrt(mt) : 0.0;
            st.lambda[j] = 0.0;
        } else {
            for (int r = 0; r < NF; ++r) shape[j][r] = vec[r][order[j]];
            for (int i = 0; i < NR; ++i) {
                double d = 0.0;
                for (int r = 0; r < NF; ++r) d += shape[i][r] * shape[j][r];
                for (int r = 0; r < NF; ++r) shape[j][r] -= d * shape[i][r];
            }
            double nn = 0.0;
            for (int r = 0; r < NF; ++r) nn += shape[j][r] * shape[j][r];
            if (NR > 0)
                for (int r = 0; r < NF; ++r) shape[j][r] /= __builtin_sqrt(nn);
            st.lambda[j] = a[order[j]][order[j]];
            if (!(st.lambda[j] > 0.0)) return HSNC_CONFIGURE_EIGEN;  // a mode not detected as rigid
        }
        // Deterministic sign: the largest component is positive.
        int big = 0;
        for (int r = 1; r < NF; ++r)
            if (__builtin_fabs(shape[j][r]) > __builtin_fabs(shape[j][big]) + 1e-6) big = r;
        if (shape[j][big] < 0.0)
            for (int r = 0; r < NF; ++r) shape[j][r] = -shape[j][r];
        for (int r = 0; r < NF; ++r) {
            st.V[r][j] = shape[j][r] / sqm[r];  // x_F = V q
            st.W[j][r] = shape[j][r] * sqm[r];  // q = W x_F
        }
    }

    // ---- Regime of each mode: q'' + c q' + lambda q, c = alpha + beta lambda ----
    // e^{-sigma tau} times (cos, sin/omega_d), (1, tau) or (cosh, sinh/gamma); the
    // root differences (omega - sigma)(omega + sigma) never cancel near xi = 1.
    for (int j = 0; j < NF; ++j) {
        const double lam = st.lambda[j], c = alpha + beta * lam;
        st.c[j] = c;
        st.omega[j] = st.omega_d[j] = st.gamma[j] = st.r1[j] = 0.0;
        if (lam == 0.0) {
            if (c == 0.0) {
                st.regime[j] = R_RIGID;
                st.sigma[j] = st.kappa[j] = 0.0;
            } else {  // q = A + B (1 - e^{-c tau})/c: the overdamped form with lambda = 0
                st.regime[j] = R_RIGID_DAMPED;
                st.sigma[j] = st.gamma[j] = 0.5 * c;
                st.kappa[j] = -st.sigma[j] * st.sigma[j];
            }
            continue;
        }
        const double w = __builtin_sqrt(lam), s = 0.5 * c;
        st.omega[j] = w;
        st.sigma[j] = s;
        if (c == 0.0) {
            st.regime[j] = R_UNDAMPED;
            st.kappa[j] = lam;
            st.omega_d[j] = w;
        } else if (s < w && (w - s) * (w + s) > 0.0) {
            st.regime[j] = R_UNDERDAMPED;
            st.kappa[j] = (w - s) * (w + s);
            st.omega_d[j] = __builtin_sqrt(st.kappa[j]);
        } else if (s > w && (s - w) * (s + w) > 0.0) {
            st.regime[j] = R_OVERDAMPED;
            st.kappa[j] = -((s - w) * (s + w));
            st.gamma[j] = __builtin_sqrt(-st.kappa[j]);
            st.r1[j] = -lam / (s + st.gamma[j]);  // slow root -sigma + gamma without cancellation
        } else {
            st.regime[j] = R_CRITICAL;
            st.kappa[j] = 0.0;
        }
    }

    // ---- Forcing: modal amplitudes P_jh = sum_r V_rj F_h,r and particular solutions ----
    // q_p = P (a_s sin + a_c cos)(Omega tau + theta), a_s = (lambda - Omega^2)/D,
    // a_c = -c Omega/D, D = (lambda - Omega^2)^2 + (c Omega)^2; an undamped mode within
    // 1% of Omega uses the resonance-stable form from rest instead (bounds then hold
    // for one forcing period: max_step).
    st.max_step = __builtin_inf();
    for (int h = 0; h < NH; ++h)
        for (int r = 0; r < NF; ++r) st.xs[h][r] = st.xc[h][r] = 0.0;
    for (int j = 0; j < NF; ++j)
        for (int h = 0; h < NH; ++h) {
            const double W = st.Omega[h], lam = st.lambda[j], c = st.c[j];
            double P = 0.0;
            for (int r = 0; r < NF; ++r) P += st.V[r][j] * st.F[h][free_dof[r]];
            st.P[j][h] = P;
            st.resonant[j][h] = st.regime[j] == R_UNDAMPED && __builtin_fabs(W - st.omega[j]) <= 1e-2 * st.omega[j];
            st.Pas[j][h] = st.Pac[j][h] = 0.0;
            if (st.resonant[j][h]) {
                const double period = 2.0 * 3.14159265358979323846 / W;
                if (period < st.max_step) st.max_step = period;
                continue;
            }
            const double det = lam - W * W, den = det * det + c * c * W * W;
            st.Pas[j][h] = P * (det / den);
            st.Pac[j][h] = P * (-c * W / den);
            for (int r = 0; r < NF; ++r) {
                st.xs[h][r] += st.V[r][j] * st.Pas[j][h];
                st.xc[h][r] += st.V[r][j] * st.Pac[j][h];
            }
        }
    for (int i = 0; i < N; ++i) st.hx[i] = st.hv[i] = 0.0;
    for (int r = 0; r < NF; ++r)
        for (int h = 0; h < NH; ++h) {
            const double m = __builtin_fabs(st.xs[h][r]) + __builtin_fabs(st.xc[h][r]);
            st.hx[free_dof[r]] += m;
            st.hv[free_dof[r]] += st.Omega[h] * m;
        }

    // ---- Switch functions as g_f = sum_j (al_fj q_j + be_fj q_j') + sum_h (Gs sin + Gc cos) + const ----
    // for the bound |g''| <= sum_j Hb_fj sqrt(2 E_j) + bconst_f (+ rigid and secular terms):
    // Hb = |al| (c + omega) + |be| (c (c + omega) + lambda), bconst = sum_h Omega^2 sqrt(Gs^2 + Gc^2).
    for (int f = 0; f < NS; ++f) {
        double al[NF1], be[NF1], Gs[NH1], Gc[NH1];
        for (int j = 0; j < NF; ++j) al[j] = be[j] = 0.0;
        for (int h = 0; h < NH; ++h) Gs[h] = Gc[h] = 0.0;
        const int e = switches[f].element;
        if (switches[f].kind == HSNC_SWITCH_GAP) {
            const int ra = contact_a_free[e], rb = contact_b_free[e];
            for (int j = 0; j < NF; ++j) al[j] = (ra >= 0 ? st.V[ra][j] : 0.0) - (rb >= 0 ? st.V[rb][j] : 0.0);
            for (int h = 0; h < NH; ++h) {
                Gs[h] = (ra >= 0 ? st.xs[h][ra] : 0.0) - (rb >= 0 ? st.xs[h][rb] : 0.0);
                Gc[h] = (ra >= 0 ? st.xc[h][ra] : 0.0) - (rb >= 0 ? st.xc[h][rb] : 0.0);
            }
        } else if (switches[f].kind == HSNC_SWITCH_VELOCITY) {
            const int r = free_of[e];
            for (int j = 0; j < NF; ++j) be[j] = st.V[r][j];
            for (int h = 0; h < NH; ++h) {
                Gs[h] = -st.Omega[h] * st.xc[h][r];
                Gc[h] = st.Omega[h] * st.xs[h][r];
            }
        } else {  // A_i = -K x - C v + f + sum_h F_h sin of a stuck mass i
            for (int j = 0; j < NF; ++j)
                for (int r = 0; r < NF; ++r) {
                    al[j] -= st.K[e][free_dof[r]] * st.V[r][j];
                    be[j] -= st.C[e][free_dof[r]] * st.V[r][j];
                }
            for (int h = 0; h < NH; ++h) {
                Gs[h] = st.F[h][e];
                for (int r = 0; r < NF; ++r) {
                    const double Kik = st.K[e][free_dof[r]], Cik = st.C[e][free_dof[r]];
                    Gs[h] += -Kik * st.xs[h][r] + Cik * st.Omega[h] * st.xc[h][r];
                    Gc[h] += -Kik * st.xc[h][r] - Cik * st.Omega[h] * st.xs[h][r];
                }
            }
        }
        double konst = 0.0, slope = 0.0, off = 0.0;
        for (int h = 0; h < NH; ++h)
            konst += __builtin_sqrt(Gs[h] * Gs[h] + Gc[h] * Gc[h]) * st.Omega[h] * st.Omega[h];
        for (int j = 0; j < NF; ++j) {
            const double c = st.c[j], w = st.omega[j], aa = __builtin_fabs(al[j]), bb = __builtin_fabs(be[j]);
            st.Hb[f][j] = aa * (c + w) + bb * (c * (c + w) + st.lambda[j]);
            // rigid-body modes: |q_p''| <= |p|, |q_p^(3)| <= c |p|
            st.rigid_al[f][j] = st.regime[j] == R_RIGID || st.regime[j] == R_RIGID_DAMPED ? aa + bb * c : 0.0;
            for (int h = 0; h < NH; ++h) {
                if (!st.resonant[j][h] || (aa == 0.0 && bb == 0.0)) continue;
                // |y''| <= Q ((h^2 + wbar^2) s + 2 wbar + omega),
                // |y'''| <= Q (wbar^3 s + 3 wbar^2 + 3 h wbar + h^2 + omega^2)
                const double W = st.Omega[h], Q = __builtin_fabs(st.P[j][h] / (w + W));
                const double hw = __builtin_fabs(W - w) / 2.0, wb = (W + w) / 2.0;
                slope += aa * Q * (hw * hw + wb * wb) + bb * Q * wb * wb * wb;
                off += aa * Q * (2.0 * wb + w) + bb * Q * (3.0 * wb * wb + 3.0 * hw * wb + hw * hw + st.lambda[j]);
            }
        }
        st.bconst[f] = konst;
        st.sec_slope[f] = slope;
        st.sec_off[f] = off;
    }
    *max_step = st.max_step;
    return HSNC_CONFIGURE_OK;
}
)";

const char* const kSetup = R"(// setup: the segment from (t0, x0, v0, sgn), as the folded kernels do it.
void setup(double* coef, double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) {
    const State& st = reinterpret_cast<const Block*>(coef)->st;
    Segment& sg = reinterpret_cast<Block*>(coef)->sg;
    // Constant force on the free masses: loads + preload - K_FS x_S - mu_k N sgn (Eq. 7-9).
    double f[NF1];
    for (int r = 0; r < NF; ++r) {
        const int i = free_dof[r];
        double fi = st.f_const[i];
        for (int k = 0; k < NS_STUCK; ++k) fi -= st.K[i][stuck_dof[k]] * x0[stuck_dof[k]];
        f[r] = fi - st.mu_k_n[i] * sgn[i];
    }
    // Modal forces p = V^T f.
    for (int j = 0; j < NF; ++j) {
        double p = 0.0;
        for (int r = 0; r < NF; ++r) p += st.V[r][j] * f[r];
        sg.p[j] = p;
    }
    // Forcing phases at the segment start: theta_h = Omega_h (t0 + t0_lo) + phase_h, reduced.
    for (int h = 0; h < NH; ++h) {
        sg.theta[h] = hsnc_phase(st.Omega[h], t0, t0_lo, st.phase[h]);
        sg.s_theta[h] = __builtin_sin(sg.theta[h]);
        sg.c_theta[h] = __builtin_cos(sg.theta[h]);
    }
    // Static offset x_st = V (p / lambda) over the elastic modes.
    for (int r = 0; r < NF; ++r) {
        double x = 0.0;
        for (int j = 0; j < NF; ++j)
            if (st.lambda[j] != 0.0) x += st.V[r][j] / st.lambda[j] * sg.p[j];
        sg.x_st[r] = x;
    }
    // Homogeneous part of the initial state in x: xh = x0 - x_p(0), vh = v0 - v_p(0) with
    // x_p = x_st + sum_h (xs sin + xc cos), exactly what eval adds back at tau = 0 (long double
    // sums); its modal coordinates q = W xh, refined once against the residuals xh - V q
    // (long double): removes the bias of V W = I + E.
    double xh[NF1], vh[NF1], q0[NF1], dq0[NF1], rx[NF1], rv[NF1];
    for (int r = 0; r < NF; ++r) {
        long double ex = static_cast<long double>(x0[free_dof[r]]) - sg.x_st[r];
        long double ev = v0[free_dof[r]];
        for (int h = 0; h < NH; ++h) {
            const double W = st.Omega[h];
            ex -= static_cast<long double>(st.xs[h][r]) * sg.s_theta[h] + static_cast<long double>(st.xc[h][r]) * sg.c_theta[h];
            ev -= static_cast<long double>(W * st.xs[h][r]) * sg.c_theta[h] -
                  static_cast<long double>(W * st.xc[h][r]) * sg.s_theta[h];
        }
        xh[r] = static_cast<double>(ex);
        vh[r] = static_cast<double>(ev);
    }
    for (int j = 0; j < NF; ++j) {
        double q = 0.0, dq = 0.0;
        for (int r = 0; r < NF; ++r) {
            q += st.W[j][r] * xh[r];
            dq += st.W[j][r] * vh[r];
        }
        q0[j] = q;
        dq0[j] = dq;
    }
    for (int r = 0; r < NF; ++r) {
        long double ex = xh[r], ev = vh[r];
        for (int j = 0; j < NF; ++j) {
            ex -= static_cast<long double>(st.V[r][j]) * q0[j];
            ev -= static_cast<long double>(st.V[r][j]) * dq0[j];
        }
        rx[r] = static_cast<double>(ex);
        rv[r] = static_cast<double>(ev);
    }
    for (int j = 0; j < NF; ++j) {
        double q = 0.0, dq = 0.0;
        for (int r = 0; r < NF; ++r) {
            q += st.W[j][r] * rx[r];
            dq += st.W[j][r] * rv[r];
        }
        q0[j] += q;
        dq0[j] += dq;
    }
    // One more refinement, against what eval will return at tau = 0: x(0) and v(0) summed
    // exactly as eval sums them, the residuals x0 - x(0), v0 - v(0) mapped back with W.
    // x(0) is a sum of terms larger than x itself (static offset, forcing response), so
    // without this its rounding depends on x0 only through its leading bits, and a state
    // restarted again and again moves the same way (tests/test_restart_drift.cpp).
    for (int r = 0; r < NF; ++r) {
        double xx = sg.x_st[r], vv = 0.0;
        for (int j = 0; j < NF; ++j) {
            xx += st.V[r][j] * q0[j];
            vv += st.V[r][j] * dq0[j];
        }
        for (int h = 0; h < NH; ++h) {
            const double W = st.Omega[h];
            xx += st.xs[h][r] * sg.s_theta[h] + st.xc[h][r] * sg.c_theta[h];
            vv += W * st.xs[h][r] * sg.c_theta[h] - W * st.xc[h][r] * sg.s_theta[h];
        }
        rx[r] = static_cast<double>(static_cast<long double>(x0[free_dof[r]]) - xx);
        rv[r] = static_cast<double>(static_cast<long double>(v0[free_dof[r]]) - vv);
    }
    for (int j = 0; j < NF; ++j) {
        double q = 0.0, dq = 0.0;
        for (int r = 0; r < NF; ++r) {
            q += st.W[j][r] * rx[r];
            dq += st.W[j][r] * rv[r];
        }
        q0[j] += q;
        dq0[j] += dq;
    }
    // Per mode: A = q_h(0), B = q_h'(0) + sigma A (every particular part starts at q_p(0) =
    // q_p'(0) = 0 or is in x_p) and the derivative pairs (A, B) -> (B - sigma A, -kappa A - sigma B).
    for (int j = 0; j < NF; ++j) {
        const double s = st.sigma[j], k = st.kappa[j];
        const double A = q0[j], B = dq0[j] + s * A;
        sg.A[j] = A;
        sg.B[j] = B;
        sg.A1[j] = B - s * A;
        sg.B1[j] = -k * A - s * B;
        sg.A2[j] = sg.B1[j] - s * sg.A1[j];
        sg.B2[j] = -k * sg.A1[j] - s * sg.B1[j];
    }
    for (int i = 0; i < N; ++i) sg.x_fix[i] = x0[i];
}

// phi2(x) = (e^x - 1 - x)/x^2, phi2(0) = 1/2; Taylor series where the subtraction cancels.
double phi2(double x) {
    if (__builtin_fabs(x) < 0.5) {
        double term = 0.5, sum = 0.5;  // x^k/(k+2)!
        for (int k = 1; k < 20; ++k) {
            term *= x / (k + 2);
            sum += term;
        }
        return sum;
    }
    return (__builtin_expm1(x) - x) / (x * x);
}

// eval: state, switch functions, bounds and term magnitudes at tau.
void eval(const double* coef, double tau, double* x, double* v, double* a, double* g, double* dg,
          double* bound, double* scale) {
    const State& st = reinterpret_cast<const Block*>(coef)->st;
    const Segment& sg = reinterpret_cast<const Block*>(coef)->sg;
    // Forcing harmonics: sin/cos(Omega_h tau + theta_h), once each.
    double sn[NH1], cs[NH1];
    for (int h = 0; h < NH; ++h) {
        const double arg = st.Omega[h] * tau + sg.theta[h];
        sn[h] = __builtin_sin(arg);
        cs[h] = __builtin_cos(arg);
    }
    // Secular terms are bounded at the end of the step, s_end = tau + max_step.
    const double s_end = tau + st.max_step;
    double q[NF1], dq[NF1], ddq[NF1], mq[NF1], mdq[NF1], rE[NF1];
    for (int j = 0; j < NF; ++j) {
        const double lam = st.lambda[j];
        double eC, eS;
        switch (st.regime[j]) {
            case R_UNDAMPED:  // eC = cos(omega tau), eS = sin(omega tau)/omega
                eC = __builtin_cos(st.omega_d[j] * tau);
                eS = __builtin_sin(st.omega_d[j] * tau) / st.omega_d[j];
                break;
            case R_UNDERDAMPED: {  // e^{-sigma tau} (cos, sin/omega_d)(omega_d tau)
                const double e = __builtin_exp(-st.sigma[j] * tau);
                eC = e * __builtin_cos(st.omega_d[j] * tau);
                eS = e * __builtin_sin(st.omega_d[j] * tau) / st.omega_d[j];
                break;
            }
            case R_CRITICAL:  // e^{-sigma tau} (1, tau)
                eC = __builtin_exp(-st.sigma[j] * tau);
                eS = tau * eC;
                break;
            case R_OVERDAMPED: {  // e^{r1 tau} (1 + E)/2, -e^{r1 tau} m/(2 gamma), m = expm1(-2 gamma tau)
                const double e = __builtin_exp(st.r1[j] * tau), m = __builtin_expm1(-2.0 * st.gamma[j] * tau);
                eC = e * (1.0 + 0.5 * m);
                eS = -e * m * (0.5 / st.gamma[j]);
                break;
            }
            case R_RIGID:  // 1, tau
                eC = 1.0;
                eS = tau;
                break;
            default: {  // rigid, damped: (1 + e^{-c tau})/2, (1 - e^{-c tau})/c
                const double m = __builtin_expm1(-st.c[j] * tau);
                eC = 1.0 + 0.5 * m;
                eS = -m / st.c[j];
                break;
            }
        }
        const double qh = sg.A[j] * eC + sg.B[j] * eS, dqh = sg.A1[j] * eC + sg.B1[j] * eS;
        double qq = qh, dd = dqh, aa = sg.A2[j] * eC + sg.B2[j] * eS;
        // sqrt(2E), E = (q_h'^2 + lambda q_h^2)/2 never grows (c >= 0).
        rE[j] = __builtin_sqrt(dqh * dqh + lam * qh * qh);
        double mag = __builtin_fabs(sg.A[j] * eC) + __builtin_fabs(sg.B[j] * eS);
        double dmag = __builtin_fabs(sg.A1[j] * eC) + __builtin_fabs(sg.B1[j] * eS) + __builtin_fabs(st.sigma[j] * sg.A[j] * eC);  // A1 = B - sigma A cancels to eps sigma A (emitter.cpp)
        if (st.regime[j] == R_RIGID || st.regime[j] == R_RIGID_DAMPED) {
            // q_p = p tau^2 phi2(-c tau) from rest (p tau^2/2 at c = 0): q_p' = p eS, q_p'' = p e^{-c tau}.
            // One form for every c >= 0: no p/c drift that cancels as c -> 0.
            const double p = sg.p[j], x = -st.c[j] * tau, qp = p * tau * tau * phi2(x), dqp = p * eS;
            qq += qp;
            dd += dqp;
            aa += p * (x == 0.0 ? 1.0 : __builtin_exp(x));
            mag += __builtin_fabs(qp);
            dmag += __builtin_fabs(dqp);
        }
        for (int h = 0; h < NH; ++h) {
            if (!st.resonant[j][h]) continue;
            // Resonant response from rest, stable through Omega = omega:
            // y = Q [-w cos(wbar tau + theta) + cos(theta) sin(omega tau)/omega], Q = P/(omega + Omega),
            // w = sin(h tau)/h -> tau (h = (Omega - omega)/2, wbar = (Omega + omega)/2).
            const double W = st.Omega[h], w0 = st.omega[j], Q = st.P[j][h] / (w0 + W);
            const double hw = (W - w0) / 2.0, wb = (W + w0) / 2.0, ct = sg.c_theta[h];
            const double w = hw == 0.0 ? tau : __builtin_sin(hw * tau) / hw;
            const double dw = hw == 0.0 ? 1.0 : __builtin_cos(hw * tau);
            const double Cb = __builtin_cos(wb * tau + sg.theta[h]), Sb = __builtin_sin(wb * tau + sg.theta[h]);
            const double y = Q * (ct * eS - w * Cb);
            const double dy = Q * (ct * eC - dw * Cb + wb * w * Sb);
            const double ddy = Q * ((hw * hw + wb * wb) * w * Cb + 2.0 * wb * dw * Sb - lam * ct * eS);
            qq += y;
            dd += dy;
            aa += ddy;
            mag += __builtin_fabs(y);
            dmag += __builtin_fabs(dy);
        }
        q[j] = qq;
        dq[j] = dd;
        ddq[j] = aa;
        mq[j] = mag;
        mdq[j] = dmag;
    }
    // Physical state: x = x_st + V q + sum_h (xs_h sin + xc_h cos); stuck masses rest.
    double mx[N1], mv[N1];
    for (int i = 0; i < N; ++i) {
        x[i] = sg.x_fix[i];
        v[i] = a[i] = 0.0;
        mx[i] = __builtin_fabs(sg.x_fix[i]);
        mv[i] = 0.0;
    }
    for (int r = 0; r < NF; ++r) {
        const int i = free_dof[r];
        double xx = sg.x_st[r], vv = 0.0, ac = 0.0, xm = __builtin_fabs(sg.x_st[r]), vm = 0.0;
        for (int j = 0; j < NF; ++j) {
            xx += st.V[r][j] * q[j];
            vv += st.V[r][j] * dq[j];
            ac += st.V[r][j] * ddq[j];
            xm += __builtin_fabs(st.V[r][j]) * mq[j];
            vm += __builtin_fabs(st.V[r][j]) * mdq[j];
        }
        for (int h = 0; h < NH; ++h) {
            const double W = st.Omega[h], xs = st.xs[h][r], xc = st.xc[h][r];
            xx += xs * sn[h] + xc * cs[h];
            vv += W * xs * cs[h] - W * xc * sn[h];
            ac += -W * W * xs * sn[h] - W * W * xc * cs[h];
        }
        x[i] = xx;
        v[i] = vv;
        a[i] = ac;
        mx[i] = xm + st.hx[i];
        mv[i] = vm + st.hv[i];
    }
    // Switch functions (runtime/segment.h order), derivatives, bounds on |g''| and term magnitudes.
    for (int f = 0; f < NS; ++f) {
        const int e = switches[f].element;
        double gf, dgf, sc;
        if (switches[f].kind == HSNC_SWITCH_GAP) {  // G = x[a] - x[b] - gap
            const int ba = contact_a[e], bb = contact_b[e];
            gf = (ba >= 0 ? x[ba] : 0.0) - (bb >= 0 ? x[bb] : 0.0) - st.gap[e];
            dgf = (ba >= 0 ? v[ba] : 0.0) - (bb >= 0 ? v[bb] : 0.0);
            sc = (ba >= 0 ? mx[ba] : 0.0) + (bb >= 0 ? mx[bb] : 0.0) + __builtin_fabs(st.gap[e]);
        } else if (switches[f].kind == HSNC_SWITCH_VELOCITY) {
            gf = v[e];
            dgf = a[e];
            sc = mv[e];
        } else {  // +-A - mu_s N, A = -K x - C v + f + sum_h F_h sin (force but friction)
            double A = st.f_const[e], dA = 0.0, m = 0.0;
            for (int k = 0; k < N; ++k) {
                A -= st.K[e][k] * x[k];
                dA -= st.K[e][k] * v[k];
                m += __builtin_fabs(st.K[e][k]) * mx[k];
                if (free_of[k] >= 0) {
                    A -= st.C[e][k] * v[k];
                    dA -= st.C[e][k] * a[k];
                    m += __builtin_fabs(st.C[e][k]) * mv[k];
                }
            }
            double mc = __builtin_fabs(st.f_const[e]) + st.mu_s_n[e];
            for (int h = 0; h < NH; ++h) {
                A += st.F[h][e] * sn[h];
                dA += st.F[h][e] * st.Omega[h] * cs[h];
                mc += __builtin_fabs(st.F[h][e]);
            }
            const double sgn_f = switches[f].kind == HSNC_SWITCH_RELEASE_POS ? 1.0 : -1.0;
            gf = sgn_f * A - st.mu_s_n[e];
            dgf = sgn_f * dA;
            sc = m + mc;
        }
        double b = st.bconst[f];
        for (int j = 0; j < NF; ++j) b += st.Hb[f][j] * rE[j] + st.rigid_al[f][j] * __builtin_fabs(sg.p[j]);
        if (st.sec_slope[f] != 0.0 || st.sec_off[f] != 0.0) b += st.sec_slope[f] * s_end + st.sec_off[f];
        g[f] = gf;
        dg[f] = dgf;
        bound[f] = b;
        scale[f] = sc;
    }
}
)";

}  // namespace

std::string emit_sweep_kernel(const Derivation& d, const std::vector<std::string>& kept) {
    const Model& model = *d.model;
    const std::size_t n = model.dof(), nf = d.n_free(), nh = d.harmonics.size(), ns = d.switches.size();
    const std::size_t nc = model.contacts.size();
    const std::string sym = sweep_kernel_symbol(model, d.cfg);
    const std::string ns_name = "ks_" + sym.substr(std::string("hsnc_sweep_").size());
    Fields fields(model, kept);

    // Rigid modes of the configuration (structural, from the derivation): the
    // first modes with lambda = 0; their members are the free masses they move.
    std::size_t nr = 0;
    while (nr < d.modes.size() && d.modes[nr].lambda.is_zero()) ++nr;

    Code c;
    char hash[32];
    std::snprintf(hash, sizeof hash, "0x%016llx", static_cast<unsigned long long>(model_hash(model)));
    c.line(0, "// hsnc sweep kernel -- generated by hsnc " HSNC_VERSION " (generator/param_emitter.cpp); do not edit.");
    c.line(0, "// model:         " + model.name + " (hash " + hash + ")");
    c.line(0, "// configuration: " + d.cfg.spec(model) + " (key " + d.cfg.key() + ")");
    {
        std::string fr, st, kp, dv;
        for (int i : d.free_dofs) fr += (fr.empty() ? "" : ", ") + model.masses[i].name;
        for (int i : d.stuck_dofs) st += (st.empty() ? "" : ", ") + model.masses[i].name;
        for (const std::string& k : kept) kp += (kp.empty() ? "" : ", ") + k;
        for (const auto& [name, text] : model.parameter_expressions)
            if (fields.variables().count(name) && std::find(kept.begin(), kept.end(), name) == kept.end())
                dv += (dv.empty() ? "" : ", ") + name + " = " + text;
        c.line(0, "// free masses:   " + (fr.empty() ? std::string("none") : fr));
        c.line(0, "// stuck masses:  " + (st.empty() ? std::string("none") : st));
        c.line(0, "// parameters given to configure(), in this order: " + kp);
        c.line(0, "// parameters computed from them: " + (dv.empty() ? std::string("none") : dv));
    }
    c.line(0, "// Every other parameter and model field is folded as a 17-digit constant.");
    c.line(0, "//");
    c.line(0, "// Free masses obey M x'' + C x' + K x = f + sum_h F_h sin(Omega_h t + phase_h) with");
    c.line(0, "// f = loads + preload - K_FS x_S - mu_k N sgn (paper Eq. 7-9). configure() assembles M, K(cfg),");
    c.line(0, "// C = alpha M + beta K(cfg) and f from the parameters and finds the modes x = V q, q = W x:");
    c.line(0, "// q_j'' + c_j q_j' + lambda_j q_j = p_j + sum_h P_jh sin(...), each with its regime decided");
    c.line(0, "// numerically. Homogeneous part q_h = A eC + B eS, d/dtau (A, B) = (B - sigma A, -kappa A - sigma B).");
    c.blank();
    c.line(0, "#include \"kernel_abi.h\"");
    c.blank();
    c.line(0, "namespace {");
    c.line(0, "namespace " + ns_name + " {");
    c.blank();
    c.line(0, "// Sizes: masses, free masses, dynamic harmonics, switch functions, stuck masses, rigid modes,");
    c.line(0, "// contacts (arrays are sized at least 1).");
    c.line(0, "constexpr int N = " + std::to_string(n) + ", NF = " + std::to_string(nf) + ", NH = " + std::to_string(nh) +
                  ", NS = " + std::to_string(ns) + ", NS_STUCK = " + std::to_string(d.stuck_dofs.size()) +
                  ", NR = " + std::to_string(nr) + ", NC = " + std::to_string(nc) + ";");
    c.line(0, "constexpr int N1 = N > 0 ? N : 1, NF1 = NF > 0 ? NF : 1, NH1 = NH > 0 ? NH : 1, NS1 = NS > 0 ? NS : 1;");
    c.line(0, "constexpr int NR1 = NR > 0 ? NR : 1, NC1 = NC > 0 ? NC : 1, NST1 = NS_STUCK > 0 ? NS_STUCK : 1;");
    c.line(0, "enum : int { R_UNDAMPED, R_UNDERDAMPED, R_CRITICAL, R_OVERDAMPED, R_RIGID, R_RIGID_DAMPED };");
    std::vector<int> free_of(n, -1);
    for (std::size_t r = 0; r < nf; ++r) free_of[d.free_dofs[r]] = static_cast<int>(r);
    c.line(0, "constexpr int free_dof[NF1] = {" + list_ints(d.free_dofs) + "};     // mass of each free index");
    c.line(0, "constexpr int stuck_dof[NST1] = {" + list_ints(d.stuck_dofs) + "};  // the stuck masses");
    c.line(0, "constexpr int free_of[N1] = {" + list_ints(free_of) + "};  // free index of each mass, -1 when stuck");
    {
        std::vector<int> ca, cb, cfa, cfb;
        for (const Contact& ct : model.contacts) {
            ca.push_back(ct.a);
            cb.push_back(ct.b);
            cfa.push_back(ct.a == kGround ? -1 : free_of[ct.a]);
            cfb.push_back(ct.b == kGround ? -1 : free_of[ct.b]);
        }
        c.line(0, "constexpr int contact_a[NC1] = {" + list_ints(ca) + "}, contact_b[NC1] = {" + list_ints(cb) +
                      "};  // bodies, -1 = ground");
        c.line(0, "constexpr int contact_a_free[NC1] = {" + list_ints(cfa) + "}, contact_b_free[NC1] = {" +
                      list_ints(cfb) + "};  // free index or -1");
    }
    {
        std::string rm;
        for (std::size_t j = 0; j < std::max<std::size_t>(nr, 1); ++j) {
            std::vector<int> mem(std::max<std::size_t>(nf, 1), 0);
            if (j < nr)
                for (std::size_t r = 0; r < nf; ++r) mem[r] = d.modes[j].v[r].is_zero() ? 0 : 1;
            rm += (rm.empty() ? "" : ", ") + std::string("{") + list_ints(mem) + "}";
        }
        c.line(0, "constexpr int rigid_member[NR1][NF1] = {" + rm + "};  // free masses of each floating component");
    }
    c.line(0, "const hsnc_switch switches[NS1] = {");
    for (const SwitchFunction& sf : d.switches)
        c.line(1, "{" + std::to_string(static_cast<int>(sf.kind)) + ", " + std::to_string(sf.element) + "},");
    if (d.switches.empty()) c.line(1, "{0, -1},  // none (n_switch = 0)");
    c.line(0, "};");
    c.line(0, "const char* const param_names[] = {");
    for (const std::string& k : kept) c.line(1, "\"" + k + "\",");
    c.line(0, "};");
    c.blank();
    c.line(0, "// What configure() computes from the parameters: the first part of the coefficient block.");
    c.line(0, "struct State {");
    c.line(1, "double M[N1], K[N1][N1], C[N1][N1];  // masses, K(cfg), C = alpha M + beta K(cfg)");
    c.line(1, "double f_const[N1];                  // loads + contact preloads");
    c.line(1, "double mu_k_n[N1], mu_s_n[N1];       // mu_k N of sliding friction masses, mu_s N of friction masses");
    c.line(1, "double gap[NC1];                     // contact gaps");
    c.line(1, "double Omega[NH1], phase[NH1], F[NH1][N1];  // forcing harmonics");
    c.line(1, "double lambda[NF1], c[NF1], omega[NF1], sigma[NF1], kappa[NF1], omega_d[NF1], gamma[NF1], r1[NF1];");
    c.line(1, "int regime[NF1];");
    c.line(1, "double V[NF1][NF1], W[NF1][NF1];     // x_F = V q, q = W x_F");
    c.line(1, "double P[NF1][NH1], Pas[NF1][NH1], Pac[NF1][NH1];  // modal forcing, P a_s, P a_c");
    c.line(1, "bool resonant[NF1][NH1];");
    c.line(1, "double xs[NH1][NF1], xc[NH1][NF1];   // non-resonant particular in x: xs sin + xc cos");
    c.line(1, "double hx[N1], hv[N1];               // their magnitudes per mass");
    c.line(1, "double Hb[NS1][NF1], rigid_al[NS1][NF1], bconst[NS1], sec_slope[NS1], sec_off[NS1];  // bounds");
    c.line(1, "double max_step;");
    c.line(0, "};");
    c.line(0, "// What setup() computes for one segment.");
    c.line(0, "struct Segment {");
    c.line(1, "double theta[NH1], s_theta[NH1], c_theta[NH1];");
    c.line(1, "double p[NF1], A[NF1], B[NF1], A1[NF1], B1[NF1], A2[NF1], B2[NF1];");
    c.line(1, "double x_st[NF1], x_fix[N1];");
    c.line(0, "};");
    c.line(0, "struct Block {");
    c.line(1, "State st;");
    c.line(1, "Segment sg;");
    c.line(0, "};");
    c.line(0, "constexpr int n_coef = static_cast<int>((sizeof(Block) + sizeof(double) - 1) / sizeof(double));");
    c.blank();
    std::string out = c.str() + kJacobi + "\n";
    if (nh > 0) out += std::string(kPhaseFunctionSource) + "\n";

    // ---- configure: the model-specific part ----
    Code k;
    k.line(0, "// configure: everything that depends on the parameters.");
    k.line(0, "int configure(double* coef, const double* params, double* max_step) {");
    k.line(1, "State& st = reinterpret_cast<Block*>(coef)->st;");
    k.line(1, "// Kept parameters and the ones computed from them (the model's own expressions).");
    for (const std::string& l : fields.parameter_lines()) k.line(1, l);
    for (const std::string& l : fields.parameter_lines()) {
        const std::string name = l.substr(std::string("const double ").size(), l.find(' ', 13) - 13);
        k.line(1, "if (!__builtin_isfinite(" + name + ")) return HSNC_CONFIGURE_INVALID;");
    }
    std::vector<std::string> checks;  // conditions for HSNC_CONFIGURE_INVALID (on values that can change)
    auto check = [&](bool variable, const std::string& cond) {
        if (variable) checks.push_back(cond);
    };
    std::vector<std::string> structure;
    k.line(1, "// Model fields (written with the parameters where they use a kept one).");
    k.line(1, "const double g = " + fields.g() + ";");
    k.line(1, "(void)g;  // unused without friction");
    for (std::size_t i = 0; i < n; ++i) {
        const Mass& ms = model.masses[i];
        const std::string p = "mass[" + idx(i) + "]", I = std::to_string(i);
        const std::string mu_k = fields.field(p + ".mu_k", ms.mu_k);
        const std::string mu_k_var = fields.variable(p + ".mu_k") ? mu_k : "";
        k.line(1, "const double m_" + I + " = " + fields.field(p + ".m", ms.m) + ";  // " + ms.name);
        check(fields.variable(p + ".m"), "m_" + I + " > 0.0");
        if (ms.has_friction) {
            k.line(1, "const double mu_k_" + I + " = " + mu_k + ";");
            k.line(1, "const double mu_s_" + I + " = " + fields.field(p + ".mu_s", ms.mu_s, mu_k_var) + ";");
            check(fields.variable(p + ".mu_k"), "mu_k_" + I + " >= 0.0");
            check(fields.variable(p + ".mu_k") || fields.variable(p + ".mu_s"), "mu_s_" + I + " >= mu_k_" + I);
        }
    }
    for (std::size_t s = 0; s < model.springs.size(); ++s) {
        const std::string key = "spring[" + idx(s) + "].k", S = idx(s);
        k.line(1, "const double k_spring_" + S + " = " + fields.field(key, model.springs[s].k) + ";");
        check(fields.variable(key), "k_spring_" + S + " >= 0.0");
        if (fields.variable(key))
            structure.push_back(std::string(model.springs[s].k > 0 ? "!" : "") + "(k_spring_" + S + " > 0.0)");
    }
    for (std::size_t cc = 0; cc < nc; ++cc) {
        const Contact& ct = model.contacts[cc];
        const std::string p = "contact[" + idx(cc) + "]", C = idx(cc);
        k.line(1, "const double k_contact_" + C + " = " + fields.field(p + ".k", ct.k) + ";  // " + ct.name);
        k.line(1, "const double gap_" + C + " = " + fields.field(p + ".gap", ct.gap) + ";");
        check(fields.variable(p + ".k"), "k_contact_" + C + " > 0.0");
        check(fields.variable(p + ".gap"), "__builtin_isfinite(gap_" + C + ")");
    }
    k.line(1, "const double alpha = " + fields.field("damping.alpha", model.alpha) + ";");
    k.line(1, "const double beta = " + fields.field("damping.beta", model.beta) + ";");
    check(fields.variable("damping.alpha"), "alpha >= 0.0");
    check(fields.variable("damping.beta"), "beta >= 0.0");
    std::size_t hd = 0;
    for (std::size_t h = 0; h < model.forcing.size(); ++h) {
        const Harmonic& hm = model.forcing[h];
        if (hm.omega == 0.0) continue;  // folded into the constant force (never from the file)
        const std::string p = "forcing[" + idx(h) + "]", H = std::to_string(hd++);
        k.line(1, "st.Omega[" + H + "] = " + fields.field(p + ".omega", hm.omega) + ";");
        k.line(1, "st.phase[" + H + "] = " + fields.field(p + ".phase", hm.phase) + ";");
        check(fields.variable(p + ".omega"), "st.Omega[" + H + "] > 0.0");
        check(fields.variable(p + ".phase"), "__builtin_isfinite(st.phase[" + H + "])");
        for (std::size_t i = 0; i < n; ++i) {
            k.line(1, "st.F[" + H + "][" + std::to_string(i) + "] = " +
                          fields.field(p + ".amplitude." + model.masses[i].name, hm.amplitude[i]) + ";");
            check(fields.variable(p + ".amplitude." + model.masses[i].name),
                  "__builtin_isfinite(st.F[" + H + "][" + std::to_string(i) + "])");
        }
    }
    k.line(1, "// Values outside the model file's rules are rejected, and so is a stiffness that crosses");
    k.line(1, "// zero (the floating components, so the rigid-body modes, were fixed at generation).");
    for (const std::string& ch : checks) k.line(1, "if (!(" + ch + ")) return HSNC_CONFIGURE_INVALID;");
    for (const std::string& ch : structure) k.line(1, "if (" + ch + ") return HSNC_CONFIGURE_STRUCTURE;");
    k.line(1, "// M, K(cfg) (springs and closed contacts), C = alpha M + beta K(cfg).");
    k.line(1, "for (int i = 0; i < N; ++i)");
    k.line(2, "for (int j = 0; j < N; ++j) st.K[i][j] = 0.0;");
    auto spring = [&](int a, int b, const std::string& kk) {
        if (a != kGround) k.line(1, "st.K[" + std::to_string(a) + "][" + std::to_string(a) + "] += " + kk + ";");
        if (b != kGround) k.line(1, "st.K[" + std::to_string(b) + "][" + std::to_string(b) + "] += " + kk + ";");
        if (a != kGround && b != kGround) {
            k.line(1, "st.K[" + std::to_string(a) + "][" + std::to_string(b) + "] -= " + kk + ";");
            k.line(1, "st.K[" + std::to_string(b) + "][" + std::to_string(a) + "] -= " + kk + ";");
        }
    };
    for (std::size_t s = 0; s < model.springs.size(); ++s) spring(model.springs[s].a, model.springs[s].b, "k_spring_" + idx(s));
    for (std::size_t cc = 0; cc < nc; ++cc)
        if (d.cfg.closed[cc]) spring(model.contacts[cc].a, model.contacts[cc].b, "k_contact_" + idx(cc));
    for (std::size_t i = 0; i < n; ++i) k.line(1, "st.M[" + std::to_string(i) + "] = m_" + std::to_string(i) + ";");
    k.line(1, "for (int i = 0; i < N; ++i)");
    k.line(2, "for (int j = 0; j < N; ++j) st.C[i][j] = beta * st.K[i][j] + (i == j ? alpha * st.M[i] : 0.0);");
    k.line(1, "// Constant forces: loads, the preload +-k d of each closed contact; friction forces.");
    for (std::size_t i = 0; i < n; ++i) {
        const Mass& ms = model.masses[i];
        const std::string I = std::to_string(i);
        k.line(1, "st.f_const[" + I + "] = " + fields.field("load." + ms.name, model.load[i]) + ";");
        k.line(1, "st.mu_k_n[" + I + "] = " + (ms.has_friction && !d.cfg.stuck[i] ? "mu_k_" + I + "*m_" + I + "*g" : "0.0") + ";");
        k.line(1, "st.mu_s_n[" + I + "] = " + (ms.has_friction ? "mu_s_" + I + "*m_" + I + "*g" : "0.0") + ";");
    }
    for (std::size_t cc = 0; cc < nc; ++cc) {
        const Contact& ct = model.contacts[cc];
        const std::string C = idx(cc);
        k.line(1, "st.gap[" + std::to_string(cc) + "] = gap_" + C + ";");
        if (!d.cfg.closed[cc]) continue;
        if (ct.a != kGround) k.line(1, "st.f_const[" + std::to_string(ct.a) + "] += k_contact_" + C + "*gap_" + C + ";");
        if (ct.b != kGround) k.line(1, "st.f_const[" + std::to_string(ct.b) + "] -= k_contact_" + C + "*gap_" + C + ";");
    }
    out += k.str() + kModes + "\n" + kSetup + "\n";
    out += "}  // namespace " + ns_name + "\n}  // namespace\n\n";
    out += emit_kernel_object(d, sym, ns_name,
                              {ns_name + "::n_coef", "__builtin_nan(\"\")  // max_step: configure() gives it",
                               std::to_string(kept.size()), ns_name + "::param_names", ns_name + "::configure"});
    return out;
}

}  // namespace hsnc
