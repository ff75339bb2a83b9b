// hsnc::inspect_report (api/hsnc/inspect.h): what `hsnc inspect MODEL
// [--config SPEC] [--format text|latex|cpp]` prints, the segment formulas of
// one configuration (interface.md section 3): the reduced matrices
// (paper Eq. 7-9), modal frequencies and damping ratios, the static offset,
// x_i(tau) in terms of tau = t - t0 and the segment's initial state, and the
// switch functions. --format cpp prints the generated kernel.
//
// Expressions come from the derivation's textbook closed forms
// (generator/derivation.h) with numbers rounded to 6 significant digits for
// reading; the matrices and modal values are printed with 17. --symbolic keeps
// the parameters as symbols (generator/symbolic_derivation.h) where the free
// system has at most 2 DOF, printed in sorted term order
// (generator/expression_printer.h).
#include "hsnc/inspect.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <memory>
#include <sstream>

#include "assembly.h"
#include "derivation.h"
#include "emitter.h"
#include "error.h"
#include "model_hash.h"
#include "expression_printer.h"
#include "modal.h"
#include "state_space_solver.h"
#include "symbolic_derivation.h"

namespace hsnc {
namespace {

using GiNaC::ex;
using GiNaC::numeric;

// Replace every non-integer number by a symbol named after its value with 6
// significant digits ("0.173913"), times -1 when negative: GiNaC would print
// the float with all its digits.
struct RoundNumbers : GiNaC::map_function {
    ex operator()(const ex& e) override {
        if (GiNaC::is_a<numeric>(e)) {
            const numeric& n = GiNaC::ex_to<numeric>(e);
            if (n.is_integer() || !n.is_real()) return e;
            const double v = n.to_double();
            char buf[32];
            std::snprintf(buf, sizeof buf, "%.6g", std::fabs(v));
            const ex shown = GiNaC::symbol(buf);
            return v < 0 ? -shown : shown;
        }
        return e.map(*this);
    }
};

enum class Format { text, latex };

struct Printer {
    Format fmt;
    std::ostream& out;

    // In sorted term order (expression_printer.h): GiNaC's own order follows
    // symbol serial numbers and hashes, and varied from run to run here.
    std::string expr(const ex& e) const {
        RoundNumbers round;
        return print_sorted(round(e.evalf()), fmt == Format::latex ? ExpressionFormat::latex : ExpressionFormat::text);
    }
    std::string num(const numeric& v) const { return format_number(v.to_double()); }
    std::string num(const DD& v) const { return format_number(v.to_double()); }
    static std::string format_number(double v) {
        char buf[40];
        std::snprintf(buf, sizeof buf, "%.17g", v);
        return buf;
    }
    void heading(const std::string& h, const std::string& latex_h) const {
        if (fmt == Format::latex)
            out << "\n\\paragraph{" << latex_h << "}\n";
        else
            out << "\n" << h << "\n";
    }
    void line(const std::string& text_form, const std::string& latex_form) const {
        if (fmt == Format::latex)
            out << latex_form << "\n";
        else
            out << "  " << text_form << "\n";
    }
};

std::string latex_name(const std::string& name) {  // m_1 style would mislead; escape underscores
    std::string s;
    for (char c : name) s += c == '_' ? std::string("\\_") : std::string(1, c);
    return s;
}

void print_matrix(const Printer& p, const std::string& name, const Derivation& d, const GiNaC::matrix* full,
                  const std::vector<numeric>* diag) {
    const std::size_t nf = d.n_free();
    auto entry = [&](std::size_t r, std::size_t s) -> numeric {
        if (diag) return r == s ? (*diag)[r] : numeric(0);
        return GiNaC::ex_to<numeric>((*full)(d.free_dofs[r], d.free_dofs[s]));
    };
    std::string text = name + " = [", latex = "\\[ " + name + " = \\begin{bmatrix} ";
    for (std::size_t r = 0; r < nf; ++r) {
        for (std::size_t s = 0; s < nf; ++s) {
            text += (s ? ", " : "") + p.num(entry(r, s));
            latex += (s ? " & " : "") + p.num(entry(r, s));
        }
        text += r + 1 < nf ? "; " : "";
        latex += r + 1 < nf ? " \\\\ " : "";
    }
    p.line(text + "]", latex + " \\end{bmatrix} \\]");
}

void inspect(const Model& model, const Configuration& cfg, Format fmt, std::ostream& out) {
    const Derivation d = derive(model, cfg);
    const Printer p{fmt, out};
    const std::size_t n = model.dof(), nf = d.n_free();
    char hash[32];
    std::snprintf(hash, sizeof hash, "0x%016llx", static_cast<unsigned long long>(model_hash(model)));
    std::string fr, st;
    for (int i : d.free_dofs) fr += (fr.empty() ? "" : ", ") + model.masses[i].name;
    for (int i : d.stuck_dofs) st += (st.empty() ? "" : ", ") + model.masses[i].name;
    std::string riders;  // stuck to their friction partner: they move with it
    for (int q : d.riders)
        riders += (riders.empty() ? "" : ", ") + model.masses[static_cast<std::size_t>(q)].name + " on " +
                  model.masses[static_cast<std::size_t>(model.friction_slot(static_cast<std::size_t>(q)).partner)].name;
    if (fmt == Format::latex) {
        out << "% hsnc inspect: model " << model.name << " (hash " << hash << "), configuration "
            << cfg.spec(model) << "\n";
        out << "\\paragraph{Model " << latex_name(model.name) << ", configuration \\texttt{" << latex_name(cfg.spec(model))
            << "}} Free masses: " << latex_name(fr.empty() ? "none" : fr)
            << "; stuck masses: " << latex_name(st.empty() ? "none" : st)
            << (riders.empty() ? "" : "; riding their partner: " + latex_name(riders)) << ".\n";
    } else {
        out << "model " << model.name << " (hash " << hash << ")\n";
        out << "configuration " << cfg.spec(model) << " (key " << cfg.key() << ")\n";
        out << "free masses: " << (fr.empty() ? "none" : fr) << "; stuck masses: " << (st.empty() ? "none" : st)
            << " (held at their x0)\n";
        if (!riders.empty()) out << "riding their friction partner: " << riders << " (one coordinate with it)\n";
    }

    // Symbols of the segment start, created in a fixed order.
    GiNaC::symbol tau("tau", "\\tau"), t0("t0", "t_0");
    SegmentInputs in;
    in.t0 = t0;
    std::vector<GiNaC::symbol> syms;
    for (std::size_t i = 0; i < n; ++i) {
        const std::string& nm = model.masses[i].name;
        in.x0.push_back(GiNaC::symbol("x0_" + nm, "x_{0," + latex_name(nm) + "}"));
        in.v0.push_back(GiNaC::symbol("v0_" + nm, "v_{0," + latex_name(nm) + "}"));
        const bool sliding_friction = model.has_friction(i) && !cfg.stuck[i];
        in.sgn.push_back(sliding_friction ? ex(GiNaC::symbol("sgn_" + nm, "s_{" + latex_name(nm) + "}")) : ex(0));
    }
    for (const Jenkins& e : model.jenkins)  // sliders after the masses
        in.x0.push_back(GiNaC::symbol("s0_" + e.name, "s_{0," + latex_name(e.name) + "}"));

    if (nf > 0) {
        p.heading("Reduced system of the free masses: M x'' + C x' + K x = f + sum_h F_h sin(Omega_h t + phase_h)",
                  "Reduced system of the free masses: $M \\ddot x + C \\dot x + K x = f + \\sum_h F_h \\sin(\\Omega_h t + \\varphi_h)$");
        // A rider's rows and columns fold into its partner's coordinate (T^T K T, T^T C T).
        GiNaC::matrix K = d.K, C = d.C;
        for (int q : d.riders) {
            const int pq = model.friction_slot(static_cast<std::size_t>(q)).partner;
            for (std::size_t k = 0; k < n; ++k) {
                K(pq, k) = K(pq, k) + K(q, k);
                C(pq, k) = C(pq, k) + C(q, k);
            }
            for (std::size_t k = 0; k < n; ++k) {
                K(k, pq) = K(k, pq) + K(k, q);
                C(k, pq) = C(k, pq) + C(k, q);
            }
        }
        print_matrix(p, "M", d, nullptr, &d.mass);
        print_matrix(p, "K", d, &K, nullptr);
        print_matrix(p, "C", d, &C, nullptr);
        for (std::size_t r = 0; r < nf; ++r) {
            const int i = d.free_dofs[r];
            const ex f = coordinate_force(d, in, r);
            const std::string nm = model.masses[i].name;
            p.line("f_" + nm + " = " + p.expr(f), "\\[ f_{" + latex_name(nm) + "} = " + p.expr(f) + " \\]");
        }
        p.heading("Modes (x = V q; q'' + c q' + lambda q = p + ...; c = alpha + beta lambda, xi = c/(2 omega))",
                  "Modes ($x = V q$, $\\ddot q + c \\dot q + \\lambda q = p + \\dots$, $c = \\alpha + \\beta\\lambda$, "
                  "$\\xi = c/(2\\omega)$)");
        for (std::size_t j = 0; j < d.modes.size(); ++j) {
            const Mode& m = d.modes[j];
            std::string shape, lshape;
            for (std::size_t r = 0; r < nf; ++r) {
                shape += (r ? ", " : "") + Printer::format_number(m.v[r].to_double());
                lshape += (r ? ", " : "") + Printer::format_number(m.v[r].to_double());
            }
            const std::string J = std::to_string(j + 1);
            p.line("mode " + J + ": lambda = " + p.num(m.lambda) + ", omega = " + p.num(m.omega) +
                       ", c = " + p.num(m.c) + ", xi = " + p.num(m.xi) + ", " + regime_name(m.regime) +
                       ", V = [" + shape + "]",
                   "\\[ \\lambda_{" + J + "} = " + p.num(m.lambda) + ",\\ \\omega_{" + J + "} = " + p.num(m.omega) +
                       ",\\ c_{" + J + "} = " + p.num(m.c) + ",\\ \\xi_{" + J + "} = " + p.num(m.xi) +
                       "\\ \\text{(" + regime_name(m.regime) + ")},\\ V_{" + J + "} = (" + lshape + ") \\]");
        }
        // Static offset x_st = V diag(1/lambda) V^T f over the elastic modes.
        p.heading("Static offset (elastic modes): x_st = sum_j V_j p_j / lambda_j",
                  "Static offset (elastic modes): $x_{\\mathrm{st}} = \\sum_j V_j p_j / \\lambda_j$");
        auto lf = [](const DD& x) { return GiNaC::ex_to<numeric>(exact(x).evalf()); };
        for (std::size_t r = 0; r < nf; ++r) {
            ex xst = 0;
            for (const Mode& m : d.modes) {
                if (m.lambda.is_zero()) continue;
                ex pj = 0;
                for (std::size_t s = 0; s < nf; ++s) {
                    const ex f = coordinate_force(d, in, s);
                    pj += lf(m.v[s]) * f;
                }
                xst += lf(m.v[r]) * pj / lf(m.lambda);
            }
            const std::string nm = model.masses[d.free_dofs[r]].name;
            p.line("x_st_" + nm + " = " + p.expr(xst),
                   "\\[ x_{\\mathrm{st}," + latex_name(nm) + "} = " + p.expr(xst) + " \\]");
        }
    }
    for (std::size_t h = 0; h < d.harmonics.size(); ++h)
        p.line("harmonic " + std::to_string(h + 1) + ": Omega = " + p.num(d.harmonics[h].omega) + ", phase = " +
                   p.num(d.harmonics[h].phase),
               "\\[ \\Omega_{" + std::to_string(h + 1) + "} = " + p.num(d.harmonics[h].omega) + " \\]");

    const SymbolicSegment s = symbolic_segment(d, in, tau);
    p.heading("Response, tau = t - t0 (x0_*, v0_* the state at t0; sgn_* the sliding directions)",
              "Response, $\\tau = t - t_0$ ($x_0$, $v_0$ the state at $t_0$; $s$ the sliding directions)");
    for (std::size_t i = 0; i < n; ++i) {
        const std::string nm = model.masses[i].name;
        p.line("x_" + nm + "(tau) = " + p.expr(s.x[i]),
               "\\[ x_{" + latex_name(nm) + "}(\\tau) = " + p.expr(s.x[i]) + " \\]");
    }
    for (std::size_t j = 0; j < model.jenkins.size(); ++j) {
        const std::string& nm = model.jenkins[j].name;
        const std::string how = cfg.slip[j] == 0 ? "stuck" : "slipping";
        p.line("s_" + nm + "(tau) = " + p.expr(s.x[n + j]) + "  (slider, " + how + ")",
               "\\[ s_{" + latex_name(nm) + "}(\\tau) = " + p.expr(s.x[n + j]) + " \\quad \\text{(slider, " + how +
                   ")} \\]");
    }
    p.heading("Switch functions (runtime/segment.h order)", "Switch functions");
    for (std::size_t f = 0; f < d.switches.size(); ++f) {
        const SwitchFunction& sf = d.switches[f];
        std::string what;
        switch (sf.kind) {
            case SwitchKind::gap: what = "gap of " + model.contacts[sf.element].name; break;
            case SwitchKind::velocity: what = "velocity of " + model.masses[sf.element].name; break;
            case SwitchKind::release_pos:
            case SwitchKind::release_neg: {
                const auto i = static_cast<std::size_t>(sf.element);
                const std::string force =
                    model.friction_slot(i).partner == kGround ? "A" : "D";  // D: against its partner
                what = (sf.kind == SwitchKind::release_pos ? "" : "-") + force + " - mu_s N of " + model.masses[i].name;
                break;
            }
            case SwitchKind::slip_pos: what = "k e - F_s of " + model.jenkins[static_cast<std::size_t>(sf.element)].name; break;
            case SwitchKind::slip_neg: what = "-k e - F_s of " + model.jenkins[static_cast<std::size_t>(sf.element)].name; break;
            case SwitchKind::slip_velocity:
                what = "relative velocity of " + model.jenkins[static_cast<std::size_t>(sf.element)].name;
                break;
        }
        const std::string F = std::to_string(f + 1);
        p.line("g_" + F + " (" + what + ") = " + p.expr(s.g[f]),
               "\\[ g_{" + F + "}(\\tau) = " + p.expr(s.g[f]) + " \\quad \\text{(" + latex_name(what) + ")} \\]");
    }
}


/// Non-proportional damping: the configuration as the state-space solver
/// takes it (runtime/solvers/state_space_solver.h): the reduced matrices in
/// numbers, the eigenvalues of the state matrix, the switch functions; and
/// whether the derivation (kernels, interpreter; --format cpp prints its
/// kernel) takes it as pseudo-modes, or leaves it to the Eigen solver.
void inspect_state_space(const Model& model, const Configuration& cfg, Format fmt, std::ostream& out) {
    const Printer p{fmt, out};
    // A (nearly) defective state matrix (critical damping) runs by the matrix
    // exponential instead (runtime/solvers/exponential_solver.h): no modes to print.
    std::unique_ptr<StateSpaceSolver> solver;
    std::string defective;
    try {
        solver = std::make_unique<StateSpaceSolver>(model, cfg);
    } catch (const DefectiveModes& e) {
        defective = e.what();
    }
    char hash[32];
    std::snprintf(hash, sizeof hash, "0x%016llx", static_cast<unsigned long long>(model_hash(model)));
    std::vector<int> free_dofs, stuck_dofs;
    std::string fr, st;
    for (std::size_t i = 0; i < model.dof(); ++i) {
        (cfg.stuck[i] ? stuck_dofs : free_dofs).push_back(static_cast<int>(i));
        (cfg.stuck[i] ? st : fr) += std::string((cfg.stuck[i] ? st : fr).empty() ? "" : ", ") + model.masses[i].name;
    }
    if (fmt == Format::latex) {
        out << "% hsnc inspect: model " << model.name << " (hash " << hash << "), configuration " << cfg.spec(model) << "\n";
        out << "\\paragraph{Model " << latex_name(model.name) << ", configuration \\texttt{" << latex_name(cfg.spec(model))
            << "}} Free masses: " << latex_name(fr.empty() ? "none" : fr)
            << "; stuck masses: " << latex_name(st.empty() ? "none" : st) << ". Non-proportional damping.\n";
    } else {
        out << "model " << model.name << " (hash " << hash << ")\n";
        out << "configuration " << cfg.spec(model) << " (key " << cfg.key() << ")\n";
        out << "free masses: " << (fr.empty() ? "none" : fr) << "; stuck masses: " << (st.empty() ? "none" : st)
            << " (held at their x0)\n";
        out << "non-proportional damping (dampers): solved through state-space modes\n";
        try {
            const Derivation d = derive(model, cfg);
            out << "derivation (kernels, interpreter): " << d.modes.size()
                << " state-space pseudo-modes in double-double (inspect --format cpp prints the kernel)\n";
        } catch (const NotDerivable& e) {
            out << "derivation (kernels, interpreter): not taken (" << e.what()
                << "); every kernel kind runs this configuration on the Eigen solver\n";
        }
    }
    const Eigen::MatrixXd K = stiffness_matrix(model, cfg), C = damping_matrix(model, cfg);
    auto matrix = [&](const std::string& name, auto entry) {
        std::string text = name + " = [", latex = "\\[ " + name + " = \\begin{bmatrix} ";
        for (std::size_t r = 0; r < free_dofs.size(); ++r) {
            for (std::size_t c = 0; c < free_dofs.size(); ++c) {
                const std::string v = Printer::format_number(entry(free_dofs[r], free_dofs[c]));
                text += (c ? ", " : "") + v;
                latex += (c ? " & " : "") + v;
            }
            text += r + 1 < free_dofs.size() ? "; " : "";
            latex += r + 1 < free_dofs.size() ? " \\\\ " : "";
        }
        p.line(text + "]", latex + " \\end{bmatrix} \\]");
    };
    if (!free_dofs.empty()) {
        p.heading("Reduced system of the free masses: M x'' + C x' + K x = f + sum_h F_h sin(Omega_h t + phase_h)",
                  "Reduced system of the free masses: $M \\ddot x + C \\dot x + K x = f + \\sum_h F_h \\sin(\\Omega_h t + \\varphi_h)$");
        matrix("M", [&](int i, int j) { return model.mass_entry(static_cast<std::size_t>(i), static_cast<std::size_t>(j)); });
        matrix("K", [&](int i, int j) { return K(i, j); });
        matrix("C", [&](int i, int j) { return C(i, j); });
    }
    p.heading("State-space modes: y' = A y, y = [x; v/s]; lambda = -xi |lambda| +- i |lambda| sqrt(1 - xi^2)",
              "State-space modes: $\\dot y = A y$, $\\lambda = -\\xi |\\lambda| \\pm i |\\lambda| \\sqrt{1 - \\xi^2}$");
    if (!solver)
        p.line("the state matrix is defective or nearly so (" + defective +
                   "): the segment is z(tau) = exp(Z tau) z(0) on z = (x, v, 1, sin, cos of each harmonic) "
                   "(runtime/solvers/exponential_solver.h)",
               "The state matrix is defective or nearly so (critical damping): the segment is $z(\\tau) = e^{Z \\tau} z(0)$.");
    int j = 0;
    for (const std::complex<double>& l : solver ? solver->damped_modes() : std::vector<std::complex<double>>()) {
        const double mag = std::abs(l), xi = mag > 0.0 ? -l.real() / mag : 0.0;
        const std::string J = std::to_string(++j);
        p.line("mode " + J + ": lambda = " + Printer::format_number(l.real()) + (l.imag() > 0.0 ? " +- i " + Printer::format_number(l.imag()) : "") +
                   ", |lambda| = " + Printer::format_number(mag) + " rad/s, xi = " + Printer::format_number(xi),
               "\\[ \\lambda_{" + J + "} = " + Printer::format_number(l.real()) +
                   (l.imag() > 0.0 ? " \\pm " + Printer::format_number(l.imag()) + " i" : "") + ", \\quad \\xi_{" + J +
                   "} = " + Printer::format_number(xi) + " \\]");
    }
    if (solver)
        p.line("eigenvector condition ||W|| ||W^-1|| (energy-scaled) = " + Printer::format_number(solver->condition()) +
                   (solver->rigid_translations() > 0
                        ? "; " + std::to_string(solver->rigid_translations()) +
                              " free translation(s) that no damping resists taken out of the state (q'' = r^T f / m)"
                        : std::string()),
               "Eigenvector condition (energy-scaled) $\\|W\\| \\|W^{-1}\\| = " +
                   Printer::format_number(solver->condition()) + "$.");
    p.heading("Switch functions (runtime/segment.h order)", "Switch functions");
    const std::vector<SwitchFunction> sw = switch_functions(model, cfg);
    for (std::size_t f = 0; f < sw.size(); ++f) {
        const SwitchFunction& sf = sw[f];
        std::string what;
        switch (sf.kind) {
            case SwitchKind::gap: {
                const Contact& c = model.contacts[static_cast<std::size_t>(sf.element)];
                auto body = [&](int b) { return "x_" + model.masses[static_cast<std::size_t>(b)].name; };
                if (!c.direction().weighted())
                    what = c.a == kGround ? "-" + body(c.b) : body(c.a) + (c.b == kGround ? "" : " - " + body(c.b));
                for (const Weight& t : c.weights)
                    what += (what.empty() ? "" : " + ") + Printer::format_number(t.w) + " " + body(t.body);
                what += " - " + Printer::format_number(c.gap) + " (gap of " + c.name + ")";
                break;
            }
            case SwitchKind::velocity: what = "v_" + model.masses[static_cast<std::size_t>(sf.element)].name + " (sliding)"; break;
            case SwitchKind::slip_pos:
            case SwitchKind::slip_neg:
            case SwitchKind::slip_velocity: {
                const Jenkins& j = model.jenkins[static_cast<std::size_t>(sf.element)];
                auto body = [&](int b) { return b == kGround ? std::string("0") : "x_" + model.masses[static_cast<std::size_t>(b)].name; };
                std::string u = j.weights.empty() ? body(j.a) + " - " + body(j.b) : "";
                for (const Weight& t : j.weights)
                    u += (u.empty() ? "" : " + ") + Printer::format_number(t.w) + " " + body(t.body);
                const std::string stretch = u + " - s_" + j.name;
                what = sf.kind == SwitchKind::slip_velocity
                           ? "relative velocity of " + j.name + " (slipping)"
                           : std::string(sf.kind == SwitchKind::slip_pos ? "" : "-") + Printer::format_number(j.k) + " (" +
                                 stretch + ") - " + Printer::format_number(j.slip_force) + " (slip of " + j.name + ")";
                break;
            }
            case SwitchKind::release_pos: what = "A - mu_s N of " + model.masses[static_cast<std::size_t>(sf.element)].name; break;
            case SwitchKind::release_neg: what = "-A - mu_s N of " + model.masses[static_cast<std::size_t>(sf.element)].name; break;
        }
        const std::string F = std::to_string(f + 1);
        p.line("g_" + F + " = " + what, "\\[ g_{" + F + "} = \\text{" + latex_name(what) + "} \\]");
    }
}

/// A coupled mass matrix with Rayleigh damping: the modes of the generalized
/// eigenproblem K phi = lambda M phi the Eigen solver uses (model/modal.h),
/// and whether the kernels derive the configuration (`--format cpp` prints
/// its program) or leave it to the Eigen solver.
void inspect_coupled(const Model& model, const Configuration& cfg, Format fmt, std::ostream& out) {
    const Printer p{fmt, out};
    const ModalDecomposition md = modal_analysis(model, cfg);
    std::string kernels = "the kernels derive these modes in double-double (inspect --format cpp prints the program)";
    try {
        (void)derive(model, cfg);
    } catch (const NotDerivable& e) {
        kernels = std::string("every kernel kind runs this configuration on the Eigen solver (") + e.what() + ")";
    }
    std::string fr;
    for (int i : md.free) fr += (fr.empty() ? "" : ", ") + model.masses[static_cast<std::size_t>(i)].name;
    if (fmt == Format::latex)
        out << "\\paragraph{Model " << latex_name(model.name) << ", configuration \\texttt{" << latex_name(cfg.spec(model))
            << "}} Free masses: " << latex_name(fr.empty() ? "none" : fr) << ". Coupled mass matrix.\n";
    else
        out << "model " << model.name << "\nconfiguration " << cfg.spec(model) << " (key " << cfg.key()
            << ")\nfree masses: " << (fr.empty() ? "none" : fr)
            << "\ncoupled mass matrix, the generalized eigenproblem of K and M: " << kernels << "\n";
    p.heading("Modes: K phi = lambda M phi, c_j = alpha + beta lambda_j", "Modes: $K \\phi = \\lambda M \\phi$");
    for (Eigen::Index j = 0; j < md.lambda.size(); ++j) {
        const double lam = md.lambda(j), w = std::sqrt(lam), c = model.alpha + model.beta * lam;
        const std::string J = std::to_string(j + 1);
        const std::string xi = w > 0.0 ? Printer::format_number(c / (2 * w)) : std::string("- (rigid)");
        p.line("mode " + J + ": omega = " + Printer::format_number(w) + " rad/s, xi = " + xi,
               "\\[ \\omega_{" + J + "} = " + Printer::format_number(w) + ", \\quad \\xi_{" + J + "} = " + xi + " \\]");
    }
}

/// The --symbolic view: the formulas of generator/symbolic_derivation.h.
void inspect_symbolic(const Model& model, const Configuration& cfg, const SymbolicDerivation& d, Format fmt,
                      std::ostream& out) {
    const Printer p{fmt, out};
    const ExpressionFormat ef = fmt == Format::latex ? ExpressionFormat::latex : ExpressionFormat::text;
    auto E = [&](const ex& e) { return print_sorted(e, ef); };
    auto S = [&](const ex& e) {  // a symbol's name in the output format
        std::ostringstream s;
        if (fmt == Format::latex)
            s << GiNaC::latex << e;
        else
            s << e;
        return s.str();
    };
    auto eq = [&](const std::string& text_lhs, const std::string& latex_lhs, const ex& rhs) {
        p.line(text_lhs + " = " + E(rhs), "\\[ " + latex_lhs + " = " + E(rhs) + " \\]");
    };
    std::string fr, st, params;
    for (int i : d.free_dofs) fr += (fr.empty() ? "" : ", ") + model.masses[i].name;
    for (int i : d.stuck_dofs) st += (st.empty() ? "" : ", ") + model.masses[i].name;
    for (const auto& [name, text] : model.parameter_expressions) params += (params.empty() ? "" : ", ") + name;
    if (fmt == Format::latex) {
        out << "% hsnc inspect --symbolic: model " << model.name << ", configuration " << cfg.spec(model) << "\n";
        out << "\\paragraph{Model " << latex_name(model.name) << ", configuration \\texttt{" << latex_name(cfg.spec(model))
            << "}, symbolic} Free masses: " << latex_name(fr) << "; stuck masses: " << latex_name(st.empty() ? "none" : st)
            << ". Parameters (symbols): " << latex_name(params) << ".\n";
    } else {
        out << "model " << model.name << " (symbolic: parameters " << params << ")\n";
        out << "configuration " << cfg.spec(model) << " (key " << cfg.key() << ")\n";
        out << "free masses: " << fr << "; stuck masses: " << (st.empty() ? "none" : st) << " (held at their x0)\n";
    }
    const std::size_t nf = d.free_dofs.size();
    p.heading("Reduced system of the free masses: M x'' + C x' + K x = f + sum_h F_h sin(Omega_h t + phase_h)",
              "Reduced system of the free masses: $M \\ddot x + C \\dot x + K x = f + \\sum_h F_h \\sin(\\Omega_h t + "
              "\\varphi_h)$");
    for (const auto& [name, mat] : {std::pair<std::string, const GiNaC::matrix*>{"M", &d.M}, {"K", &d.K}, {"C", &d.C}}) {
        std::string text = name + " = [", latex = "\\[ " + name + " = \\begin{bmatrix} ";
        for (std::size_t r = 0; r < nf; ++r) {
            for (std::size_t c = 0; c < nf; ++c) {
                text += (c ? ", " : "") + print_sorted((*mat)(r, c), ExpressionFormat::text);
                latex += (c ? " & " : "") + print_sorted((*mat)(r, c), ExpressionFormat::latex);
            }
            text += r + 1 < nf ? "; " : "";
            latex += r + 1 < nf ? " \\\\ " : "";
        }
        p.line(text + "]", latex + " \\end{bmatrix} \\]");
    }
    for (std::size_t r = 0; r < nf; ++r) {
        const std::string nm = model.masses[d.free_dofs[r]].name;
        eq("f_" + nm, "f_{" + latex_name(nm) + "}", d.f[r]);
    }
    for (std::size_t h = 0; h < d.harmonics.size(); ++h) {
        const std::string H = std::to_string(h + 1);
        eq("Omega_" + H, "\\Omega_{" + H + "}", d.harmonics[h].omega);
        eq("phase_" + H, "\\varphi_{" + H + "}", d.harmonics[h].phase);
        for (std::size_t r = 0; r < nf; ++r) {
            const std::string nm = model.masses[d.free_dofs[r]].name;
            eq("F_" + H + "_" + nm, "F_{" + H + "," + latex_name(nm) + "}", d.harmonics[h].amplitude[r]);
        }
    }
    p.heading("Modes: det(K - lambda M) = 0; omega = sqrt(lambda), c = alpha + beta lambda, xi = c/(2 omega)",
              "Modes: $\\det(K - \\lambda M) = 0$, $\\omega = \\sqrt{\\lambda}$, $c = \\alpha + \\beta\\lambda$, "
              "$\\xi = c/(2\\omega)$");
    for (std::size_t j = 0; j < d.lambda.size(); ++j) {
        const std::string J = std::to_string(j + 1);
        eq("lambda_" + J, "\\lambda_{" + J + "}", d.lambda[j]);
        eq("omega_" + J, "\\omega_{" + J + "}", d.omega[j]);
        eq("c_" + J, "c_{" + J + "}", d.c[j]);
        eq("xi_" + J, "\\xi_{" + J + "}", d.xi[j]);
        if (nf > 1)
            for (std::size_t r = 0; r < nf; ++r) {
                const std::string nm = model.masses[d.free_dofs[r]].name;
                eq("V_" + nm + "_" + J, "V_{" + latex_name(nm) + "," + J + "}", d.shapes[j][r]);
            }
    }
    p.heading("Static offset: x_st = K^-1 f", "Static offset: $x_{\\mathrm{st}} = K^{-1} f$");
    for (std::size_t r = 0; r < nf; ++r) {
        const std::string nm = model.masses[d.free_dofs[r]].name;
        eq("x_st_" + nm, "x_{\\mathrm{st}," + latex_name(nm) + "}", d.x_static[r]);
    }
    p.heading("Response (assumes every mode underdamped or undamped, 0 <= c_j < 2 omega_j, and no forcing at "
              "resonance: which regime holds depends on the parameter values)",
              "Response (assumes every mode underdamped or undamped, $0 \\le c_j < 2\\omega_j$, and no forcing at "
              "resonance: which regime holds depends on the parameter values)");
    for (const Definition& def : d.definitions) p.line(S(def.name) + " = " + E(def.value),
                                                       "\\[ " + S(def.name) + " = " + E(def.value) + " \\]");
    for (std::size_t j = 0; j < d.q.size(); ++j) {
        const std::string J = std::to_string(j + 1);
        eq("q_" + J + "(t)", "q_{" + J + "}(t)", d.q[j]);
    }
    for (std::size_t i = 0; i < d.x.size(); ++i) {
        const std::string nm = model.masses[i].name;
        eq("x_" + nm + "(t)", "x_{" + latex_name(nm) + "}(t)", d.x[i]);
    }
    p.heading("Switch functions (runtime/segment.h order; x_*, v_* at time t)", "Switch functions");
    for (std::size_t f = 0; f < d.switches.size(); ++f) {
        const std::string F = std::to_string(f + 1);
        const std::string& what = d.switches[f].first;
        p.line("g_" + F + " (" + what + ") = " + E(d.switches[f].second),
               "\\[ g_{" + F + "} = " + E(d.switches[f].second) + " \\quad \\text{(" + latex_name(what) + ")} \\]");
    }
}

}  // namespace

void inspect_report(const Model& model, const Configuration& cfg, const InspectOptions& options, std::ostream& out,
                    std::ostream& notes) {
    const Format fmt = options.format == InspectFormat::latex ? Format::latex : Format::text;
    const bool cpp = options.format == InspectFormat::cpp;
    if (options.symbolic && !model.proportional_damping()) {
        notes << "--symbolic: the model has non-proportional damping (dampers); printing numbers\n";
    } else if (options.symbolic && !cpp) {
        SymbolicDerivation sd;
        std::string why;
        if (derive_symbolic(model, cfg, sd, why)) {
            std::ostringstream text;  // nothing printed unless the whole view is
            inspect_symbolic(model, cfg, sd, fmt, text);
            out << text.str();
            return;
        }
        notes << "--symbolic: " << why << "; printing numbers\n";
    } else if (options.symbolic) {
        notes << "--symbolic does not apply to --format cpp (the kernel holds numbers)\n";
    }
    std::ostringstream text;  // nothing printed unless the whole view is
    if (cpp)
        text << emit_kernel(derive(model, cfg));  // NotDerivable (RunError): the Eigen solver takes it
    else if (model.coupled_mass() && model.proportional_damping())
        inspect_coupled(model, cfg, fmt, text);
    else if (!model.proportional_damping())
        inspect_state_space(model, cfg, fmt, text);
    else
        inspect(model, cfg, fmt, text);
    out << text.str();
}

}  // namespace hsnc
