#include "emitter.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <utility>

#include "code_writer.h"
#include "lowering.h"
#include "model_hash.h"

namespace hsnc {

using GiNaC::numeric;

std::string kernel_symbol(const Model& model, const Configuration& cfg) {
    std::string name;
    for (char ch : model.name)
        name += (std::isalnum(static_cast<unsigned char>(ch)) || ch == '_') ? ch : '_';
    return "hsnc_kernel_" + name + "_" + cfg.key();
}

namespace {

double dbl(const DD& x) { return x.to_double(); }

std::string idx(std::size_t k) { return std::to_string(k + 1); }  // 1-based names: q_1, ...

// ---- the printer: a Program (kernels/program.h) as C++ ----
// Every instruction prints as the statements that compute what the
// interpreter (runtime/solvers/interpreted_solver.cpp) computes, in the same order.

/// A constant: its name when it has one, else the literal (negative ones in parentheses).
std::string konst(const Program& p, std::uint32_t k) {
    if (!p.constant_names[k].empty()) return p.constant_names[k];
    return CodeWriter::operand(p.constants[k]);
}

/// c_0 r_0 + c_1 r_1 + ... with signs folded ("1.5 - 2.0*x + y"), terms given
/// as (c, register name; "" for the constant); "0.0" when empty.
std::string sum_text(const std::vector<std::pair<double, std::string>>& terms, bool ld) {
    auto cast = [&](const std::string& e) { return ld ? "static_cast<long double>(" + e + ")" : e; };
    if (terms.empty()) return "0.0";
    std::string s;
    for (std::size_t k = 0; k < terms.size(); ++k) {
        double c = terms[k].first;
        const std::string& name = terms[k].second;
        if (k == 0) {
            if (c < 0 && !name.empty()) {
                s += "-";
                c = -c;
            }
        } else {
            s += c < 0 ? " - " : " + ";
            c = std::fabs(c);
        }
        if (name.empty())
            s += cast(format_double(c));
        else if (c == 1.0)
            s += cast(name);
        else
            s += cast(format_double(c)) + "*" + name;
    }
    return ld ? "static_cast<double>(" + s + ")" : s;
}

std::vector<std::pair<double, std::string>> named_terms(const Program& p, const ProgramBody& b, std::uint32_t first,
                                                        std::uint32_t count) {
    std::vector<std::pair<double, std::string>> out;
    for (std::uint32_t k = 0; k < count; ++k) {
        const ProgramTerm& t = p.terms[first + k];
        out.push_back({t.c, t.reg == 0 ? std::string() : b.names[t.reg]});
    }
    return out;
}

std::string sum_text(const Program& p, const ProgramBody& b, const ProgramInstr& in) {
    return sum_text(named_terms(p, b, in.first, in.count), in.op == ProgramOp::lincomb_ld);
}

class BodyPrinter {
public:
    BodyPrinter(const Program& p, const ProgramBody& b, CodeWriter& out) : p_(p), b_(b), out_(out) {}

    void print() {
        const std::vector<ProgramInstr>& code = b_.code;
        const bool vector = vector_factors(b_);
        for (std::size_t i = 0; i < code.size(); ++i) {
            if (vector && takes_factors(code[i]) && factor_of_.count(i) == 0) factors(i);
            instr(code[i], i);
        }
    }

private:
    // The factors (e^{-sigma tau}, sin and cos(omega_d tau)) of the run of
    // consecutive modes from code[i] on that take them, printed before the
    // first: their arguments -sigma tau and omega_d tau (0.0 where the regime
    // takes none), then a call of kernel_abi.h's four-lane helpers per four
    // modes, the calls together so that they overlap, as the interpreter runs
    // them (a lane's bits are its own, so the grouping changes none).
    void factors(std::size_t i) {
        const std::vector<ProgramInstr>& code = b_.code;
        std::size_t end = i;
        bool exp = false;
        for (; end < code.size() && takes_factors(code[end]); ++end)
            exp = exp || static_cast<ProgramRegime>(code[end].regime) != ProgramRegime::undamped;
        comment("e^{-sigma tau} (modesG_e), sin and cos(omega_d tau) (modesG_s, modesG_c) of the " +
                std::to_string(end - i) + " modes below, four in the lanes of each call (kernel_abi.h).");
        std::vector<std::string> calls;
        for (std::size_t at = i; at < end; at += 4) {
            const std::string g = "modes" + std::to_string(++groups_) + "_";
            std::string xe, xt;
            for (std::size_t lane = 0; lane < 4; ++lane) {
                const std::string sep = lane ? ", " : "";
                if (at + lane >= end) {
                    xe += sep + "0.0", xt += sep + "0.0";
                    continue;
                }
                const ProgramInstr& in = code[at + lane];
                const auto regime = static_cast<ProgramRegime>(in.regime);
                const std::string tau = n(in.b);
                xe += sep + (regime == ProgramRegime::undamped ? std::string("0.0")
                                                                : "-" + k(in.first + kModeSigma) + "*" + tau);
                xt += sep + (regime == ProgramRegime::critical ? std::string("0.0")
                                                                : k(in.first + kModeOmegaD) + "*" + tau);
                factor_of_[at + lane] = {g, lane};
            }
            if (exp) out_.line(1, "const double " + g + "xe[4] = {" + xe + "};");
            out_.line(1, "const double " + g + "xt[4] = {" + xt + "};");
            out_.line(1, "double " + (exp ? g + "e[4], " : std::string()) + g + "s[4], " + g + "c[4];");
            calls.push_back("hsnc_sincos4(" + g + "xt, " + g + "s, " + g + "c);");
            if (exp) calls.push_back("hsnc_exp4(" + g + "xe, " + g + "e);");
        }
        for (const std::string& call : calls) out_.line(1, call);
    }
    // Mode code[i]'s factor f ('e', 's' or 'c'): its group's array, at its lane.
    std::string factor(std::size_t i, char f) const {
        const auto& [group, lane] = factor_of_.at(i);
        return group + f + "[" + std::to_string(lane) + "]";
    }

    const std::string& n(std::uint32_t r) const { return b_.names[r]; }
    std::string k(std::uint32_t c) const { return konst(p_, c); }
    // dst = expr;  declared const (or mutable: accumulators) unless an output.
    void assign(std::uint32_t dst, const std::string& expr, const std::string& note = "", bool mut = false) {
        const std::string lhs = b_.kinds[dst] == RegisterKind::output ? n(dst)
                                                                       : (mut ? "double " : "const double ") + n(dst);
        out_.line(1, lhs + " = " + expr + ";" + (note.empty() ? "" : "  // " + note));
    }
    void add_to(std::uint32_t dst, const std::string& expr) { out_.line(1, n(dst) + " += " + expr + ";"); }
    void comment(const std::string& text) { out_.comment(1, text); }

    void instr(const ProgramInstr& in, std::size_t i) {
        comment(b_.comment(in));
        switch (in.op) {
            case ProgramOp::lincomb: {
                const std::string sum = sum_text(p_, b_, in);
                assign(in.dst, in.a == kNoRegister ? sum : n(in.a) + " + (" + sum + ")", b_.note(in));
                break;
            }
            case ProgramOp::lincomb_ld: assign(in.dst, sum_text(p_, b_, in), b_.note(in)); break;
            case ProgramOp::copy: assign(in.dst, n(in.a), b_.note(in)); break;
            case ProgramOp::abs: assign(in.dst, "__builtin_fabs(" + n(in.a) + ")", b_.note(in)); break;
            case ProgramOp::sin: assign(in.dst, "__builtin_sin(" + n(in.a) + ")", b_.note(in)); break;
            case ProgramOp::cos: assign(in.dst, "__builtin_cos(" + n(in.a) + ")", b_.note(in)); break;
            case ProgramOp::phase:
                assign(in.dst, "hsnc_phase(" + k(in.first) + ", " + n(in.a) + ", " + n(in.b) + ", " +
                                   k(in.first + 1) + ")");
                break;
            case ProgramOp::harmonic:
                assign(in.dst, k(in.first) + "*" + n(in.b) + " + " + n(in.a));
                assign(in.dst + 1, "__builtin_sin(" + n(in.dst) + ")");
                assign(in.dst + 2, "__builtin_cos(" + n(in.dst) + ")");
                break;
            case ProgramOp::mode: mode(in, i); break;
            case ProgramOp::rigid_particular: {
                const std::uint32_t m = in.c;
                const std::string P = n(in.a), tau = n(in.b);
                add_to(m + kModeQ, "0.5*" + P + "*" + tau + "*" + tau);
                add_to(m + kModeDQ, P + "*" + tau);
                add_to(m + kModeDDQ, P);
                add_to(m + kModeMQ, "__builtin_fabs(0.5*" + P + "*" + tau + "*" + tau + ")");
                add_to(m + kModeMDQ, "__builtin_fabs(" + P + "*" + tau + ")");
                break;
            }
            case ProgramOp::rigid_damped_particular: {
                const std::uint32_t m = in.c;
                const std::string P = n(in.a), tau = n(in.b);
                assign(in.dst, P + "*" + tau + "*" + tau + "*hsnc_phi2(-" + k(in.first) + "*" + tau + ")");
                add_to(m + kModeQ, n(in.dst));
                add_to(m + kModeDQ, P + "*" + n(m + kModeES));
                add_to(m + kModeDDQ, P + "*(1.0 + " + n(m + kModeAux) + ")");
                add_to(m + kModeMQ, "__builtin_fabs(" + n(in.dst) + ")");
                add_to(m + kModeMDQ, "__builtin_fabs(" + P + "*" + n(m + kModeES) + ")");
                break;
            }
            case ProgramOp::resonant: resonant(in); break;
            case ProgramOp::mass_state: mass_state(in); break;
        }
    }

    // Five sums; the interpreter adds term k of all five before term k + 1,
    // each sum still in this order.
    void mass_state(const ProgramInstr& in) {
        using Terms = std::vector<std::pair<double, std::string>>;
        Terms rows[5];
        rows[0].push_back({1.0, n(in.a)});
        rows[3].push_back({1.0, "__builtin_fabs(" + n(in.a) + ")"});
        const std::uint32_t offset[5] = {kModeQ, kModeDQ, kModeDDQ, kModeMQ, kModeMDQ};
        for (std::uint32_t k = 0; k < in.count; ++k) {
            const ProgramTerm& t = p_.terms[in.first + k];
            for (int row = 0; row < 5; ++row)
                rows[row].push_back({row < 3 ? t.c : std::fabs(t.c), n(t.reg + offset[row])});
        }
        std::uint32_t first = in.first + in.count;
        for (int row = 0; row < 5; ++row) {
            const Terms tail = named_terms(p_, b_, first, in.tail[row]);
            rows[row].insert(rows[row].end(), tail.begin(), tail.end());
            first += in.tail[row];
        }
        const std::uint32_t dst[5] = {in.dst, in.b, in.c, in.d, in.d + 1};
        for (int row = 0; row < 5; ++row) assign(dst[row], sum_text(rows[row], false), row == 0 ? b_.note(in) : "");
    }

    void mode(const ProgramInstr& in, std::size_t i) {
        const std::uint32_t d = in.dst, c = in.first;
        const std::string tau = n(in.b), eC = n(d + kModeEC), eS = n(d + kModeES);
        const std::string aux = n(d + kModeAux), aux2 = n(d + kModeAux2);
        const bool given = factor_of_.count(i) != 0;  // its factors printed above (factors())
        switch (static_cast<ProgramRegime>(in.regime)) {
            case ProgramRegime::undamped:
                comment("eC = cos(omega tau), eS = sin(omega tau)/omega");
                assign(d + kModeEC, given ? factor(i, 'c') : "__builtin_cos(" + k(c + kModeOmegaD) + "*" + tau + ")");
                assign(d + kModeES, (given ? factor(i, 's') : "__builtin_sin(" + k(c + kModeOmegaD) + "*" + tau + ")") +
                                        "*" + k(c + kModeInvOmegaD));
                break;
            case ProgramRegime::underdamped:
                comment("eC = e^{-sigma tau} cos(omega_d tau), eS = e^{-sigma tau} sin(omega_d tau)/omega_d");
                assign(d + kModeAux, given ? factor(i, 'e') : "__builtin_exp(-" + k(c + kModeSigma) + "*" + tau + ")");
                assign(d + kModeEC,
                       aux + "*" + (given ? factor(i, 'c') : "__builtin_cos(" + k(c + kModeOmegaD) + "*" + tau + ")"));
                assign(d + kModeES,
                       aux + "*" + (given ? factor(i, 's') : "__builtin_sin(" + k(c + kModeOmegaD) + "*" + tau + ")") +
                           "*" + k(c + kModeInvOmegaD));
                break;
            case ProgramRegime::critical:
                comment("eC = e^{-sigma tau}, eS = tau e^{-sigma tau}");
                assign(d + kModeEC, given ? factor(i, 'e') : "__builtin_exp(-" + k(c + kModeSigma) + "*" + tau + ")");
                assign(d + kModeES, tau + "*" + eC);
                break;
            case ProgramRegime::overdamped:
                comment("e^{-sigma tau} cosh(gamma tau) = e^{r1 tau} (1 + E)/2, e^{-sigma tau} sinh(gamma tau)/gamma\n"
                        "= -e^{r1 tau} m/(2 gamma) with m = expm1(-2 gamma tau), E = 1 + m: no overflow.");
                assign(d + kModeAux, "__builtin_exp(" + k(c + kModeR1) + "*" + tau + ")");
                assign(d + kModeAux2, "__builtin_expm1(" + k(c + kModeNegTwoGamma) + "*" + tau + ")");
                assign(d + kModeEC, aux + "*(1.0 + 0.5*" + aux2 + ")");
                assign(d + kModeES, "-" + aux + "*" + aux2 + "*" + k(c + kModeHalfInvGamma));
                break;
            case ProgramRegime::rigid:
                comment("eC = 1, eS = tau");
                assign(d + kModeEC, "1.0");
                assign(d + kModeES, tau);
                break;
            case ProgramRegime::rigid_damped:
                comment("eC = (1 + e^{-c tau})/2, eS = (1 - e^{-c tau})/c with m = expm1(-c tau)");
                assign(d + kModeAux, "__builtin_expm1(-" + k(c + kModeC) + "*" + tau + ")");
                assign(d + kModeEC, "1.0 + 0.5*" + aux);
                assign(d + kModeES, "-" + aux + "*" + k(c + kModeInvC));
                break;
        }
        const std::string A = n(in.a), B = n(in.a + 1), A1 = n(in.a + 2), B1 = n(in.a + 3), A2 = n(in.a + 4),
                          B2 = n(in.a + 5);
        const std::string q = n(d + kModeQ), dq = n(d + kModeDQ);
        comment("Homogeneous q_h = A eC + B eS and its derivatives; sqrt(2E), E = (q_h'^2 + lambda q_h^2)/2,\n"
                "never grows (c >= 0); the magnitudes of the terms.");
        assign(d + kModeQ, A + "*" + eC + " + " + B + "*" + eS, "", in.accumulates);
        assign(d + kModeDQ, A1 + "*" + eC + " + " + B1 + "*" + eS, "", in.accumulates);
        assign(d + kModeDDQ, A2 + "*" + eC + " + " + B2 + "*" + eS, "", in.accumulates);
        assign(d + kModeR, "__builtin_sqrt(" + dq + "*" + dq + " + " + k(c + kModeLambda) + "*" + q + "*" + q + ")");
        assign(d + kModeMQ, "__builtin_fabs(" + A + "*" + eC + ") + __builtin_fabs(" + B + "*" + eS + ")", "",
               in.accumulates);
        // A1 = B - sigma A (setup) cancels to eps |sigma A|: that term counts in the
        // magnitude of q', else v(0) = 0 comes back as -1e-16 against a stated level
        // of 3e-17 and the engine takes it for a stop (a mass at rest against a stiff,
        // damped contact stopped as chattering at t0).
        std::string mdq = "__builtin_fabs(" + A1 + "*" + eC + ") + __builtin_fabs(" + B1 + "*" + eS + ")";
        if (p_.constants[c + kModeSigma] != 0.0)
            mdq += " + __builtin_fabs(" + k(c + kModeSigma) + "*" + A + "*" + eC + ")";
        assign(d + kModeMDQ, mdq, "", in.accumulates);
    }

    void resonant(const ProgramInstr& in) {
        const std::uint32_t d = in.dst, c = in.first, m = in.c;
        const std::string tau = n(in.b), theta = n(in.a), ct = n(in.d);
        const std::string w = n(d), dw = n(d + 1), Cb = n(d + 2), Sb = n(d + 3), y = n(d + 4), dy = n(d + 5),
                          ddy = n(d + 6);
        const std::string eC = n(m + kModeEC), eS = n(m + kModeES);
        if (p_.constants[c + kResHalfDiff] == 0.0) {
            assign(d, tau);
            assign(d + 1, "1.0");
        } else {
            assign(d, "__builtin_sin(" + k(c + kResHalfDiff) + "*" + tau + ")*" + k(c + kResInvHalfDiff));
            assign(d + 1, "__builtin_cos(" + k(c + kResHalfDiff) + "*" + tau + ")");
        }
        const std::string arg = k(c + kResMean) + "*" + tau + " + " + theta;
        assign(d + 2, "__builtin_cos(" + arg + ")");
        assign(d + 3, "__builtin_sin(" + arg + ")");
        const std::string Q = k(c + kResQ);
        assign(d + 4, Q + "*(" + ct + "*" + eS + " - " + w + "*" + Cb + ")");
        assign(d + 5, Q + "*(" + ct + "*" + eC + " - " + dw + "*" + Cb + " + " + k(c + kResMean) + "*" + w + "*" + Sb +
                          ")");
        assign(d + 6, Q + "*(" + k(c + kResH2W2) + "*" + w + "*" + Cb + " + " + k(c + kResTwoMean) + "*" + dw + "*" +
                          Sb + " - " + k(c + kResLambda) + "*" + ct + "*" + eS + ")");
        add_to(m + kModeQ, y);
        add_to(m + kModeDQ, dy);
        add_to(m + kModeDDQ, ddy);
        // The magnitude of the terms, not of their sum (y ~ tau^3 near tau = 0, its terms ~ tau).
        const std::string aQ = "__builtin_fabs(" + Q + ")";
        add_to(m + kModeMQ, aQ + "*(__builtin_fabs(" + ct + "*" + eS + ") + __builtin_fabs(" + w + "*" + Cb + "))");
        add_to(m + kModeMDQ, aQ + "*(__builtin_fabs(" + ct + "*" + eC + ") + __builtin_fabs(" + dw + "*" + Cb +
                                 ") + __builtin_fabs(" + k(c + kResMean) + "*" + w + "*" + Sb + "))");
    }

    const Program& p_;
    const ProgramBody& b_;
    CodeWriter& out_;
    std::map<std::size_t, std::pair<std::string, std::size_t>> factor_of_;  // mode instruction -> group ("modesG_"), lane
    int groups_ = 0;
};

}  // namespace

std::string emit_kernel(const Derivation& d) { return emit_kernel(d, lower(d)); }

namespace {

std::string model_hash_text(const Model& model) {
    char hash[32];
    std::snprintf(hash, sizeof hash, "0x%016llx", static_cast<unsigned long long>(model_hash(model)));
    return hash;
}

}  // namespace

void emit_provenance(CodeWriter& c, const Derivation& d, const std::string& what, const std::string& source) {
    const Model& model = *d.model;
    std::vector<std::string> fr, st;
    for (int i : d.free_dofs) fr.push_back(model.masses[i].name);
    for (int i : d.stuck_dofs) st.push_back(model.masses[i].name);
    c.line(0, "// " + what + " -- generated by hsnc " HSNC_VERSION " (" + source + "); do not edit.");
    c.line(0, "// model:         " + model.name + " (hash " + model_hash_text(model) + ")");
    c.line(0, "// configuration: " + d.cfg.spec(model) + " (key " + d.cfg.key() + ")");
    c.line(0, "// free masses:   " + (fr.empty() ? std::string("none") : CodeWriter::join(fr)));
    c.line(0, "// stuck masses:  " + (st.empty() ? std::string("none") : CodeWriter::join(st)));
    std::vector<std::string> rd;  // stuck to their friction partner (none in a model without pairs)
    for (int q : d.riders)
        rd.push_back(
            model.masses[static_cast<std::size_t>(q)].name + " on " +
            model.masses[static_cast<std::size_t>(model.friction_slot(static_cast<std::size_t>(q)).partner)].name);
    if (!rd.empty()) c.line(0, "// riders:        " + CodeWriter::join(rd));
}

std::string emit_kernel(const Derivation& d, const Program& p) {
    const Model& model = *d.model;
    const std::size_t nm = d.modes.size();
    const std::string sym = kernel_symbol(model, d.cfg);

    CodeWriter c;
    // ---- provenance ----
    emit_provenance(c, d, "hsnc kernel", "generator/emitter.cpp");
    c.line(0, "//");
    c.line(0, "// Free masses obey M x'' + C x' + K x = f + sum_h F_h sin(Omega_h t + phase_h) with");
    if (d.state_space) {
        c.line(0, "// f = loads + preload - K_FS x_S - mu_k N sgn (paper Eq. 7-9), C with dampers (not");
        c.line(0, "// proportional): x = K^-1 f + sum_h Im((K - W^2 M + i W C)^-1 F_h e^{i(W t + phase)}) + V q over");
        c.line(0, "// the state-space pseudo-modes q (generator/derivation.h): Re and Im of c e^{mu tau} for each");
        c.line(0, "// conjugate pair mu (q'' + 2 sigma q' + |mu|^2 q = 0), c e^{mu tau} for each real mu (critical");
        c.line(0, "// regime, B = 0); (q(0), q'(0)) from the homogeneous state by the rows of Psi^-1.");
    } else {
        c.line(0, "// f = loads + preload - K_FS x_S - mu_k N sgn (paper Eq. 7-9). In modal coordinates");
        c.line(0, "// x = V q, q = W x: q_j'' + c_j q_j' + lambda_j q_j = p_j + sum_h P_jh sin(...).");
    }
    c.line(0, "// Homogeneous part q_h = A eC + B eS with d/dtau (A, B) = (B - sigma A, -kappa A - sigma B).");
    for (std::size_t j = 0; j < nm; ++j) {
        const Mode& m = d.modes[j];
        c.line(0, std::string(d.state_space ? "// pseudo-mode " : "// mode ") + idx(j) + ": " + regime_name(m.regime) + ", lambda = " + c.literal(dbl(m.lambda)) +
                      ", omega = " + c.literal(dbl(m.omega)) + ", c = " + c.literal(dbl(m.c)) +
                      ", xi = " + c.literal(dbl(m.xi)));
    }
    c.line(0, "// The statements are the program of generator/lowering.cpp, printed in the order the");
    c.line(0, "// interpreter (runtime/interpreted_solver.cpp) runs it: both give the same bits.");
    c.blank();
    c.line(0, "#include \"kernel_abi.h\"");
    c.blank();
    // Internals in a namespace of their own, so that kernels may share a translation unit.
    const std::string ns = "k_" + sym.substr(std::string("hsnc_kernel_").size());
    c.line(0, "namespace {");
    c.line(0, "namespace " + ns + " {");
    c.blank();

    // ---- named constants ----
    c.line(0, "// Modal constants.");
    for (std::size_t k = 0; k < p.constants.size(); ++k)
        if (!p.constant_names[k].empty())
            c.line(0, "constexpr double " + p.constant_names[k] + " = " + c.literal(p.constants[k]) + ";");
    c.blank();
    {
        std::string block = "// Coefficient block (" + std::to_string(p.coef_names.size()) + " doubles):";
        for (std::size_t k = 0; k < p.coef_names.size(); ++k)
            block += (k % 6 == 0 ? "\n//  " : " ") + std::to_string(k) + ":" + p.coef_names[k];
        c.raw(block + "\n");
    }

    c.block(0, "void setup(double* coef, double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) {",
            "}", [&] {
                c.line(1, "(void)t0; (void)t0_lo; (void)x0; (void)v0; (void)sgn; (void)coef;");
                BodyPrinter(p, p.setup, c).print();
            });
    c.blank();
    c.line(0, "void eval(const double* coef, double tau, double* x, double* v, double* a, double* g, double* dg,");
    c.block(0, "          double* bound, double* scale) {", "}", [&] {
        c.line(1, "(void)tau; (void)coef;");
        BodyPrinter(p, p.eval, c).print();
    });
    c.blank();
    std::vector<std::string> switches;
    for (const SwitchFunction& sf : d.switches)
        switches.push_back("{" + std::to_string(static_cast<int>(sf.kind)) + ", " + std::to_string(sf.element) + "}, ");
    if (d.switches.empty()) switches.push_back("{0, -1}");  // C++ needs one element; n_switch = 0
    c.line(0, "const hsnc_switch switches[] = {" + CodeWriter::join(switches, "") + "};");
    c.blank();
    c.line(0, "}  // namespace " + ns);
    c.line(0, "}  // namespace");
    c.blank();
    emit_kernel_object(c, d, sym, ns, {std::to_string(p.coef_names.size()), c.literal(p.max_step)});
    return c.str();
}

void emit_kernel_object(CodeWriter& c, const Derivation& d, const std::string& sym, const std::string& ns,
                        const std::vector<std::string>& rest) {
    const Model& model = *d.model;
    c.line(0, "extern \"C\" const hsnc_kernel " + sym + ";");
    c.block(0, "extern \"C\" const hsnc_kernel " + sym + " = {", "};", [&] {
        c.line(1, "HSNC_KERNEL_ABI_VERSION,");
        c.line(1, "\"" + model.name + "\",");
        c.line(1, model_hash_text(model) + "ull,");
        c.line(1, "\"" + d.cfg.spec(model) + "\",");
        c.line(1, "\"" + d.cfg.key() + "\",");
        c.line(1, "\"" HSNC_VERSION "\",");
        c.line(1, std::to_string(model.dof()) + ",");
        c.line(1, std::to_string(model.jenkins.size()) + ",");
        c.line(1, std::to_string(d.switches.size()) + ",");
        c.line(1, ns + "::switches,");
        for (std::size_t k = 0; k < rest.size(); ++k) {
            const std::size_t comment = rest[k].find("  //");  // "value  // why": the comma goes after the value
            c.line(1, comment == std::string::npos ? rest[k] + "," : rest[k].substr(0, comment) + "," + rest[k].substr(comment));
            if (k == 1) c.line(1, ns + "::setup,").line(1, ns + "::eval,");
        }
    });
}

std::string emit_registry(const std::vector<std::string>& symbols, const std::string& function) {
    CodeWriter c;
    c.line(0, "// hsnc AOT kernel registry -- generated by hsnc " HSNC_VERSION "; do not edit.");
    c.line(0, "#include \"aot_registry.h\"");
    c.blank();
    for (const std::string& s : symbols) c.line(0, "extern \"C\" const hsnc_kernel " + s + ";");
    c.blank();
    c.line(0, "namespace hsnc {");
    c.line(0, "namespace {");
    c.blank();
    c.block(0, "const hsnc_kernel* const kernels[] = {", "};", [&] {
        for (const std::string& s : symbols) c.line(1, "&" + s + ",");
        if (symbols.empty()) c.line(1, "nullptr,");
    });
    c.blank();
    c.line(0, "}  // namespace");
    c.blank();
    c.line(0, "const AotRegistry& " + function + "();");
    c.blank();
    c.block(0, "const AotRegistry& " + function + "() {", "}", [&] {
        c.line(1, "static const AotRegistry registry{kernels, " + std::to_string(symbols.size()) + "};");
        c.line(1, "return registry;");
    });
    c.blank();
    c.line(0, "}  // namespace hsnc");
    return c.str();
}

}  // namespace hsnc
