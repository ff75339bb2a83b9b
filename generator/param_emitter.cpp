#include "param_emitter.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "emitter.h"  // CodeWriter, kernel_symbol, emit_provenance, emit_kernel_object
#include "assembly.h"  // stick_elements
#include "error.h"

namespace hsnc {

/// The text of generator/sweep_kernel_core.h after its marker line (embedded by CMake).
extern const char* const kSweepKernelCore;

using GiNaC::ex;
using GiNaC::numeric;

std::vector<std::string> kept_parameters(const Model& model, const std::string& list) {
    const std::string flag = "generate: --params '" + list + "'";
    if (model.parameter_expressions.empty())
        throw InputError(flag + ": the model has no parameter source texts (not read from a file)");
    if (const std::string what = stick_elements(model); !what.empty())
        throw InputError(flag + ": the model has " + what +
                         ", which sweep kernels do not take yet (generate without --params folds them)");
    // Sweep kernels redo the modal analysis of K over the lumped masses at run time (sweep_kernel_core.h):
    // a coupled M and state-space pseudo-modes there are still to come.
    if (model.condensation.loaded())
        throw InputError(flag + ": the model has a load or forcing on a massless (condensed) dof, which sweep kernels "
                                "do not take yet (generate without --params derives its kernels)");
    for (const Contact& c : model.contacts)
        if (c.direction().weighted())
            throw InputError(flag + ": contact '" + c.name + "' acts along a direction (direction = {...}), which sweep "
                                    "kernels do not take yet (generate without --params derives its kernels)");
    if (!model.base.empty())  // its effective force -M r x_g'' depends on m and omega: no field of its own
        throw InputError(flag +
                         ": the model has a base motion ([[base]]), which sweep kernels do not take yet "
                         "(generate without --params derives its kernels)");
    if (!model.load_steps.empty())
        throw InputError(flag +
                         ": the model has load steps ([[load_step]]), which sweep kernels do not take "
                         "(generate without --params derives the kernels of its first load)");
    if (model.coupled_mass())
        throw InputError(flag + ": the model has a coupled (non-diagonal) mass matrix, which sweep kernels do not "
                                "take yet (generate without --params derives its kernels)");
    if (!model.proportional_damping())
        throw InputError(flag + ": the model has non-proportional damping ([[damper]], a contact's c or a "
                                "non-proportional structure.damping), which sweep kernels do not take yet (generate without --params "
                                "derives its kernels)");
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
            return CodeWriter::operand(GiNaC::ex_to<numeric>(v).to_double());
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

// The masses' fields of a sweep kernel's configure(): m, and mu_k, mu_s and
// an element's normal force N where there is friction, each with the
// conditions that make it valid when it depends on a kept parameter.
void emit_mass_fields(CodeWriter& k, const Model& model, Fields& fields, std::vector<std::string>& checks) {
    auto check = [&](bool variable, const std::string& cond) {
        if (variable) checks.push_back(cond);
    };
    for (std::size_t i = 0; i < model.dof(); ++i) {
        const Mass& ms = model.masses[i];
        const FrictionSlot& fs = model.friction_slot(i);
        const std::string p = "mass[" + idx(i) + "]", I = std::to_string(i);
        const std::string mu_k = fields.field(p + ".mu_k", fs.mu_k);
        const std::string mu_k_var = fields.variable(p + ".mu_k") ? mu_k : "";
        k.line(1, "const double m_" + I + " = " + fields.field(p + ".m", ms.m) + ";  // " + ms.name);
        check(fields.variable(p + ".m"), "m_" + I + " > 0.0");
        if (fs.active) {
            k.line(1, "const double mu_k_" + I + " = " + mu_k + ";");
            k.line(1, "const double mu_s_" + I + " = " + fields.field(p + ".mu_s", fs.mu_s, mu_k_var) + ";");
            check(fields.variable(p + ".mu_k"), "mu_k_" + I + " >= 0.0");
            check(fields.variable(p + ".mu_k") || fields.variable(p + ".mu_s"), "mu_s_" + I + " >= mu_k_" + I);
            if (fs.normal > 0.0) {  // an element's normal force as given (FrictionSlot::normal)
                k.line(1, "const double N_" + I + " = " + fields.field(p + ".normal", fs.normal) + ";");
                check(fields.variable(p + ".normal"), "N_" + I + " > 0.0");
            }
        }
    }
}

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

    CodeWriter c;
    emit_provenance(c, d, "hsnc sweep kernel", "generator/param_emitter.cpp");
    {
        std::vector<std::string> derived;
        for (const auto& [name, text] : model.parameter_expressions)
            if (fields.variables().count(name) && std::find(kept.begin(), kept.end(), name) == kept.end())
                derived.push_back(name + " = " + text);
        c.line(0, "// parameters given to configure(), in this order: " + CodeWriter::join(kept));
        c.line(0, "// parameters computed from them: " + (derived.empty() ? std::string("none") : CodeWriter::join(derived)));
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
    c.line(0, "// ---- The model's own declarations (generator/param_emitter.cpp) ----");
    c.line(0, "// Sizes: masses, free masses, dynamic harmonics, switch functions, stuck masses, rigid modes,");
    c.line(0, "// contacts (arrays are sized at least 1).");
    c.line(0, "constexpr int N = " + std::to_string(n) + ", NF = " + std::to_string(nf) + ", NH = " + std::to_string(nh) +
                  ", NS = " + std::to_string(ns) + ", NS_STUCK = " + std::to_string(d.stuck_dofs.size()) +
                  ", NR = " + std::to_string(nr) + ", NC = " + std::to_string(nc) + ";");
    c.line(0, "constexpr int N1 = N > 0 ? N : 1, NF1 = NF > 0 ? NF : 1, NH1 = NH > 0 ? NH : 1, NS1 = NS > 0 ? NS : 1;");
    c.line(0, "constexpr int NR1 = NR > 0 ? NR : 1, NC1 = NC > 0 ? NC : 1, NST1 = NS_STUCK > 0 ? NS_STUCK : 1;");
    std::vector<int> free_of(n, -1);
    for (std::size_t r = 0; r < nf; ++r) free_of[d.free_dofs[r]] = static_cast<int>(r);
    c.line(0, "constexpr int free_dof[NF1] = {" + CodeWriter::list(d.free_dofs) + "};     // mass of each free index");
    c.line(0, "constexpr int stuck_dof[NST1] = {" + CodeWriter::list(d.stuck_dofs) + "};  // the stuck masses");
    c.line(0, "constexpr int free_of[N1] = {" + CodeWriter::list(free_of) + "};  // free index of each mass, -1 when stuck");
    {
        std::vector<int> ca, cb, cfa, cfb;
        for (const Contact& ct : model.contacts) {
            ca.push_back(ct.a);
            cb.push_back(ct.b);
            cfa.push_back(ct.a == kGround ? -1 : free_of[ct.a]);
            cfb.push_back(ct.b == kGround ? -1 : free_of[ct.b]);
        }
        c.line(0, "constexpr int contact_a[NC1] = {" + CodeWriter::list(ca) + "}, contact_b[NC1] = {" +
                      CodeWriter::list(cb) + "};  // bodies, -1 = ground");
        c.line(0, "constexpr int contact_a_free[NC1] = {" + CodeWriter::list(cfa) + "}, contact_b_free[NC1] = {" +
                      CodeWriter::list(cfb) + "};  // free index or -1");
    }
    {
        std::vector<std::string> rows;
        for (std::size_t j = 0; j < std::max<std::size_t>(nr, 1); ++j) {
            std::vector<int> mem(std::max<std::size_t>(nf, 1), 0);
            if (j < nr)
                for (std::size_t r = 0; r < nf; ++r) mem[r] = d.modes[j].v[r].is_zero() ? 0 : 1;
            rows.push_back("{" + CodeWriter::list(mem) + "}");
        }
        c.line(0, "constexpr int rigid_member[NR1][NF1] = {" + CodeWriter::join(rows) +
                      "};  // free masses of each floating component");
    }
    c.block(0, "const hsnc_switch switches[NS1] = {", "};", [&] {
        for (const SwitchFunction& sf : d.switches)
            c.line(1, "{" + std::to_string(static_cast<int>(sf.kind)) + ", " + std::to_string(sf.element) + "},");
        if (d.switches.empty()) c.line(1, "{0, -1},  // none (n_switch = 0)");
    });
    c.block(0, "const char* const param_names[] = {", "};", [&] {
        for (const std::string& k : kept) c.line(1, "\"" + k + "\",");
    });
    c.line(0, "// Relative band |Omega - omega| <= resonance_band omega of the resonance-stable form.");
    c.line(0, "constexpr double resonance_band = " + c.literal(kResonanceBand) + ";");
    c.blank();
    c.raw(kSweepKernelCore);
    c.blank();

    // ---- configure: the model-specific part ----
    CodeWriter& k = c;
    k.line(0, "// configure: everything that depends on the parameters; the rest is decompose()'s.");
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
    emit_mass_fields(k, model, fields, checks);
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
        const FrictionSlot& fs = model.friction_slot(i);
        const std::string I = std::to_string(i);
        k.line(1, "st.f_const[" + I + "] = " + fields.field("load." + ms.name, model.load[i]) + ";");
        const std::string N = fs.normal > 0.0 ? "N_" + I : "m_" + I + "*g";
        k.line(1, "st.mu_k_n[" + I + "] = " + (fs.active && !d.cfg.stuck[i] ? "mu_k_" + I + "*" + N : "0.0") + ";");
        k.line(1, "st.mu_s_n[" + I + "] = " + (fs.active ? "mu_s_" + I + "*" + N : "0.0") + ";");
    }
    for (std::size_t cc = 0; cc < nc; ++cc) {
        const Contact& ct = model.contacts[cc];
        const std::string C = idx(cc);
        k.line(1, "st.gap[" + std::to_string(cc) + "] = gap_" + C + ";");
        if (!d.cfg.closed[cc]) continue;
        if (ct.a != kGround) k.line(1, "st.f_const[" + std::to_string(ct.a) + "] += k_contact_" + C + "*gap_" + C + ";");
        if (ct.b != kGround) k.line(1, "st.f_const[" + std::to_string(ct.b) + "] -= k_contact_" + C + "*gap_" + C + ";");
    }
    k.line(1, "return decompose(st, alpha, beta, max_step);");
    k.line(0, "}");
    c.blank();
    c.line(0, "}  // namespace " + ns_name);
    c.line(0, "}  // namespace");
    c.blank();
    emit_kernel_object(c, d, sym, ns_name,
                       {ns_name + "::n_coef", "__builtin_nan(\"\")  // max_step: configure() gives it",
                        std::to_string(kept.size()), ns_name + "::param_names", ns_name + "::configure"});
    return c.str();
}

}  // namespace hsnc
