#include "symbolic_derivation.h"

#include <cctype>

#include "assembly.h"  // stick_elements
#include "derivation.h"
#include "switch_function.h"

namespace hsnc {
namespace {

using GiNaC::ex;
using GiNaC::symbol;

/// TeX name of an identifier: "k_star" -> "k_{star}", "phi1" -> "\phi_{1}",
/// "mu_k" -> "\mu_{k}"; further underscores escaped.
std::string tex_name(const std::string& name) {
    static const char* const kGreek[] = {"alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta",
                                         "kappa", "lambda", "mu", "nu", "xi", "rho", "sigma", "tau", "phi",
                                         "chi", "psi", "omega", "Gamma", "Delta", "Theta", "Lambda", "Phi",
                                         "Psi", "Omega"};
    std::size_t split = name.find('_');
    if (split == std::string::npos) {
        split = name.size();
        while (split > 1 && std::isdigit(static_cast<unsigned char>(name[split - 1]))) --split;
    }
    std::string base = name.substr(0, split);
    std::string rest = split < name.size() ? name.substr(name[split] == '_' ? split + 1 : split) : "";
    for (const char* g : kGreek)
        if (base == g) base = "\\" + base;
    std::string sub;
    for (char ch : rest) sub += ch == '_' ? std::string("\\_") : std::string(1, ch);
    return sub.empty() ? base : base + "_{" + sub + "}";
}

class Builder {
public:
    explicit Builder(const Model& model) : model_(model) {
        for (const auto& [name, text] : model.parameter_expressions) table_[name] = symbol(name, tex_name(name));
    }

    /// The source text of field `key` parsed over the parameter symbols, or `fallback`.
    ex field(const std::string& key, const ex& fallback) const {
        const auto it = model_.field_expressions.find(key);
        if (it == model_.field_expressions.end()) return fallback;
        GiNaC::parser reader(table_, /*strict=*/true);
        return reader(it->second);
    }

    /// The symbol of parameter `name` (g is always one: implicit 9.81 when the file has none).
    ex parameter(const std::string& name) const { return table_.at(name); }

private:
    const Model& model_;
    GiNaC::symtab table_;
};

std::string idx(std::size_t i) { return std::to_string(i + 1); }

}  // namespace

namespace {

// Why the symbolic view does not take `model` at all, or "".
std::string not_taken(const Model& model) {
    if (model.parameter_expressions.empty()) return "the model has no source expressions (not read from a file)";
    if (const std::string what = stick_elements(model); !what.empty())
        return "the model has " + what + ", which the symbolic view does not take yet";
    if (model.coupled_mass())
        return "the model has a coupled (non-diagonal) mass matrix, which the symbolic view does not take yet";
    if (!model.proportional_damping())  // state-space modes: a quartic and up, not the symmetric 2x2 below
        return "the model has non-proportional damping (dampers), which the symbolic view does not take";
    return "";
}

// Eigenvalues of det(K - lambda M) = 0 and mode shapes (header comment), the
// modal frequencies and damping, and the static offset x_st = K^-1 f of the
// reduced 1x1 or 2x2 system in d.
void modes_and_offset(SymbolicDerivation& d, const ex& alpha, const ex& beta) {
    const std::size_t nf = d.f.size();
    // Eigenvalues of det(K - lambda M) = 0 and mode shapes (header comment).
    if (nf == 1) {
        d.lambda = {d.K(0, 0) / d.M(0, 0)};
        d.shapes = {{ex(1)}};
    } else {
        const ex k11 = d.K(0, 0), k12 = d.K(0, 1), k22 = d.K(1, 1), m1 = d.M(0, 0), m2 = d.M(1, 1);
        if (k12.expand().is_zero()) {
            d.lambda = {k11 / m1, k22 / m2};
            d.shapes = {{ex(1), ex(0)}, {ex(0), ex(1)}};
        } else {
            const ex root = GiNaC::sqrt(GiNaC::pow(k11 * m2 - k22 * m1, 2) + 4 * m1 * m2 * GiNaC::pow(k12, 2));
            d.lambda = {(k11 * m2 + k22 * m1 - root) / (2 * m1 * m2), (k11 * m2 + k22 * m1 + root) / (2 * m1 * m2)};
            for (const ex& l : d.lambda) d.shapes.push_back({-k12, k11 - l * m1});
        }
    }
    for (const ex& l : d.lambda) {
        d.omega.push_back(GiNaC::sqrt(l));
        d.c.push_back(alpha + beta * l);
        d.xi.push_back(d.c.back() / (2 * d.omega.back()));
    }

    // Static offset x_st = K^-1 f (2x2 by the adjugate).
    if (nf == 1) {
        d.x_static = {d.f[0] / d.K(0, 0)};
    } else {
        const ex det = d.K(0, 0) * d.K(1, 1) - d.K(0, 1) * d.K(1, 0);
        d.x_static = {(d.K(1, 1) * d.f[0] - d.K(0, 1) * d.f[1]) / det,
                      (d.K(0, 0) * d.f[1] - d.K(1, 0) * d.f[0]) / det};
    }
}
}  // namespace

bool derive_symbolic(const Model& model, const Configuration& cfg, SymbolicDerivation& d, std::string& why) {
    why = not_taken(model);
    if (!why.empty()) return false;
    const Derivation numeric = derive(model, cfg);  // free/stuck split, switch order, rigid modes
    const std::size_t n = model.dof(), nf = numeric.n_free();
    if (nf == 0) {
        why = "no mass is free in this configuration";
        return false;
    }
    if (nf > kMaxSymbolicDof) {
        why = "the configuration has " + std::to_string(nf) + " free DOF, more than " +
              std::to_string(kMaxSymbolicDof) + " (the limit for a closed-form eigen-decomposition)";
        return false;
    }
    for (const Mode& m : numeric.modes)
        if (m.regime == Regime::rigid || m.regime == Regime::rigid_damped) {
            why = "the free masses have a rigid-body mode (K singular): no static offset";
            return false;
        }
    d.free_dofs = numeric.free_dofs;
    d.stuck_dofs = numeric.stuck_dofs;

    // Symbols in a fixed order: time, parameters (Builder), initial state.
    d.t = symbol("t");
    d.t0 = symbol("t0", "t_{0}");
    Builder b(model);
    for (std::size_t i = 0; i < n; ++i) {
        const std::string& nm = model.masses[i].name;
        const std::string tn = tex_name(nm);
        d.x0.push_back(symbol("x0_" + nm, "x_{0," + tn + "}"));
        d.v0.push_back(symbol("v0_" + nm, "v_{0," + tn + "}"));
        d.sgn.push_back(symbol("sgn_" + nm, "s_{" + tn + "}"));
    }

    // Full matrices and forces (model/assembly.h, with symbols).
    std::vector<ex> m(n), f(n), mu_k(n), mu_s(n), normal(n);
    GiNaC::matrix K(n, n);
    for (std::size_t i = 0; i < n; ++i) {
        const std::string p = "mass[" + idx(i) + "]";
        m[i] = b.field(p + ".m", 1);
        mu_k[i] = b.field(p + ".mu_k", 0);
        mu_s[i] = b.field(p + ".mu_s", mu_k[i]);
        f[i] = b.field("load." + model.masses[i].name, 0);
    }
    auto add_spring = [&](int a, int c, const ex& k) {
        if (a >= 0) K(a, a) += k;
        if (c >= 0) K(c, c) += k;
        if (a >= 0 && c >= 0) {
            K(a, c) -= k;
            K(c, a) -= k;
        }
    };
    for (std::size_t s = 0; s < model.springs.size(); ++s)
        add_spring(model.springs[s].a, model.springs[s].b, b.field("spring[" + idx(s) + "].k", 0));
    std::vector<ex> gap(model.contacts.size());
    for (std::size_t c = 0; c < model.contacts.size(); ++c) {
        const std::string p = "contact[" + idx(c) + "]";
        gap[c] = b.field(p + ".gap", 0);
        if (!cfg.closed[c]) continue;
        const ex k = b.field(p + ".k", 0);
        // Closed: K += k w w^T and the preload +k gap w (-k (u - gap) along w).
        for_each_term(model.contacts[c].direction(), [&](int i, double wi) {
            for_each_term(model.contacts[c].direction(), [&](int j, double wj) { K(i, j) += k * exact(wi) * exact(wj); });
            f[i] += k * gap[c] * exact(wi);
        });
    }
    const ex alpha = b.field("damping.alpha", 0), beta = b.field("damping.beta", 0), g = b.parameter("g");
    for (std::size_t i = 0; i < n; ++i) {  // an element's normal force as given, else the weight m g (FrictionSlot)
        const double given = model.friction_slot(i).normal;
        normal[i] = given > 0.0 ? b.field("mass[" + idx(i) + "].normal", given) : m[i] * g;
    }

    // Reduced system of the free masses.
    d.M = GiNaC::matrix(nf, nf);
    d.K = GiNaC::matrix(nf, nf);
    d.C = GiNaC::matrix(nf, nf);
    d.f.assign(nf, 0);
    for (std::size_t r = 0; r < nf; ++r) {
        const int i = d.free_dofs[r];
        d.M(r, r) = m[i];
        for (std::size_t s = 0; s < nf; ++s) {
            const int j = d.free_dofs[s];
            d.K(r, s) = K(i, j);
            d.C(r, s) = (r == s ? alpha * m[i] : ex(0)) + beta * K(i, j);
        }
        d.f[r] = f[i];
        for (int s : d.stuck_dofs) d.f[r] -= K(i, s) * d.x0[s];
        if (model.has_friction(i)) d.f[r] -= mu_k[i] * normal[i] * d.sgn[i];
    }
    std::vector<std::vector<ex>> amplitude_all;  // per harmonic, all masses
    for (std::size_t h = 0; h < model.forcing.size(); ++h) {
        const std::string p = "forcing[" + idx(h) + "]";
        SymbolicDerivation::Harmonic hd;
        hd.omega = b.field(p + ".omega", 0);
        hd.phase = b.field(p + ".phase", 0);
        std::vector<ex> all(n);
        for (std::size_t i = 0; i < n; ++i) all[i] = b.field(p + ".amplitude." + model.masses[i].name, 0);
        for (int i : d.free_dofs) hd.amplitude.push_back(all[i]);
        amplitude_all.push_back(all);
        d.harmonics.push_back(hd);
    }

    modes_and_offset(d, alpha, beta);

    // Response over named quantities (the printout defines each of them).
    const ex tau = d.t - d.t0;
    std::vector<ex> xst_sym(nf);
    std::vector<std::vector<ex>> V(nf, std::vector<ex>(nf));  // V[r][j]
    for (std::size_t r = 0; r < nf; ++r) {
        const std::string& nm = model.masses[d.free_dofs[r]].name;
        xst_sym[r] = symbol("x_st_" + nm, "x_{\\mathrm{st}," + tex_name(nm) + "}");
        for (std::size_t j = 0; j < nf; ++j)
            V[r][j] = GiNaC::is_a<GiNaC::numeric>(d.shapes[j][r])
                          ? d.shapes[j][r]
                          : ex(symbol("V_" + nm + "_" + idx(j), "V_{" + tex_name(nm) + "," + idx(j) + "}"));
    }
    auto define = [&](const std::string& name, const std::string& tex, const ex& value) {
        const symbol s(name, tex);
        d.definitions.push_back({s, value});
        return ex(s);
    };
    d.q.assign(nf, 0);
    for (std::size_t j = 0; j < nf; ++j) {
        const std::string J = idx(j);
        const ex lambda = symbol("lambda_" + J, "\\lambda_{" + J + "}"), c = symbol("c_" + J, "c_{" + J + "}");
        ex mu = 0, q0 = 0, dq0 = 0;
        for (std::size_t r = 0; r < nf; ++r) mu += d.M(r, r) * GiNaC::pow(V[r][j], 2);
        const ex mu_j = nf == 1 ? mu : define("mu_" + J, "\\mu_{" + J + "}", mu);
        for (std::size_t r = 0; r < nf; ++r) {
            const int i = d.free_dofs[r];
            q0 += d.M(r, r) * V[r][j] * (d.x0[i] - xst_sym[r]);
            dq0 += d.M(r, r) * V[r][j] * d.v0[i];
        }
        const ex q0_j = define("q0_" + J, "q_{0," + J + "}", q0 / mu_j);
        const ex dq0_j = define("dq0_" + J, "\\dot q_{0," + J + "}", dq0 / mu_j);
        const ex omega_d = define("omega_d_" + J, "\\omega_{d," + J + "}",
                                  GiNaC::sqrt(lambda - GiNaC::pow(c, 2) / 4));
        // Particular response to each harmonic (non-resonant, damped or not).
        ex qp = 0;
        for (std::size_t h = 0; h < d.harmonics.size(); ++h) {
            const std::string H = idx(h);
            ex P = 0;
            for (std::size_t r = 0; r < nf; ++r) P += V[r][j] * d.harmonics[h].amplitude[r];
            if (P.is_zero()) continue;
            const ex P_jh = define("P_" + J + "_" + H, "P_{" + J + "," + H + "}", P / mu_j);
            const ex Om = d.harmonics[h].omega;
            const ex th = Om * d.t + d.harmonics[h].phase;
            const ex detuning = lambda - GiNaC::pow(Om, 2);
            qp += P_jh * (detuning * GiNaC::sin(th) - c * Om * GiNaC::cos(th)) /
                  (GiNaC::pow(detuning, 2) + GiNaC::pow(c, 2) * GiNaC::pow(Om, 2));
        }
        const ex qp0 = qp.subs(d.t == d.t0), dqp0 = qp.diff(d.t).subs(d.t == d.t0);
        const ex A = define("A_" + J, "A_{" + J + "}", qp.is_zero() ? q0_j : q0_j - qp0);
        const ex B = define("B_" + J, "B_{" + J + "}",
                            ((qp.is_zero() ? dq0_j : dq0_j - dqp0) + c * A / 2) / omega_d);
        d.q[j] = GiNaC::exp(-c * tau / 2) * (A * GiNaC::cos(omega_d * tau) + B * GiNaC::sin(omega_d * tau)) + qp;
    }
    d.x.assign(n, 0);
    for (int s : d.stuck_dofs) d.x[s] = d.x0[s];
    for (std::size_t r = 0; r < nf; ++r) {
        ex x = xst_sym[r];
        for (std::size_t j = 0; j < nf; ++j)
            x += V[r][j] * symbol("q_" + idx(j) + "(t)", "q_{" + idx(j) + "}(t)");
        d.x[d.free_dofs[r]] = x;
    }

    // Switch functions over x_i, v_i (x0_i and 0 for stuck masses).
    std::vector<ex> xs(n), vs(n);
    for (std::size_t i = 0; i < n; ++i) {
        const bool stuck = cfg.stuck[i];
        const std::string& nm = model.masses[i].name;
        xs[i] = stuck ? ex(d.x0[i]) : ex(symbol("x_" + nm, "x_{" + tex_name(nm) + "}"));
        vs[i] = stuck ? ex(0) : ex(symbol("v_" + nm, "v_{" + tex_name(nm) + "}"));
    }
    auto body = [&](int i, const std::vector<ex>& v) { return i >= 0 ? v[i] : ex(0); };
    for (const SwitchFunction& sf : numeric.switches) {
        const int e = sf.element;
        if (sf.kind == SwitchKind::gap) {
            const Contact& c = model.contacts[e];
            ex u = 0;
            for_each_term(c.direction(), [&](int i, double w) { u += exact(w) * xs[i]; });
            d.switches.push_back({"gap of " + c.name, u - gap[e]});
        } else if (sf.kind == SwitchKind::velocity) {
            d.switches.push_back({"velocity of " + model.masses[e].name, vs[e]});
        } else {
            ex A = f[e];
            for (std::size_t j = 0; j < n; ++j) {
                A -= K(e, j) * xs[j];
                A -= ((static_cast<int>(j) == e ? alpha * m[e] : ex(0)) + beta * K(e, j)) * vs[j];
            }
            for (std::size_t h = 0; h < d.harmonics.size(); ++h)
                A += amplitude_all[h][e] * GiNaC::sin(d.harmonics[h].omega * d.t + d.harmonics[h].phase);
            const ex N = normal[e];
            if (sf.kind == SwitchKind::release_pos)
                d.switches.push_back({"A - mu_s N of " + model.masses[e].name, A - mu_s[e] * N});
            else
                d.switches.push_back({"-A - mu_s N of " + model.masses[e].name, -A - mu_s[e] * N});
        }
    }
    return true;
}

}  // namespace hsnc
