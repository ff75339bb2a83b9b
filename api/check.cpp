// hsnc::check_report (api/hsnc/check.h): the summary `hsnc check MODEL`
// prints (interface.md section 3): its DOFs, contacts and friction masses,
// and the modes of the configuration with every contact open and every mass
// sliding.
//
// Modes: the undamped generalised eigenproblem K phi = omega^2 M phi with
// K = K(all open), from the engine's own modal analysis (model/modal.h), so
// a rigid-body mode is what the engine takes for one: decided structurally (a
// group of masses with no spring or contact of k > 0 to ground), never from
// a small eigenvalue, which stiffness or mass ratios beyond 1e10 would give.
// Damping ratio of Rayleigh damping C = alpha*M + beta*K for a mode of
// frequency omega_n: xi = (alpha/omega_n + beta*omega_n)/2 (modal damping,
// paper Eq. 12-13). With dampers (non-proportional damping) the damped modes
// are the state matrix's eigenvalues (state_space_solver.h), printed apart.
#include "hsnc/check.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <iomanip>
#include <memory>
#include <sstream>
#include <vector>

#include "configuration.h"
#include "error.h"
#include "free_components.h"
#include "modal.h"
#include "state_space_solver.h"

namespace hsnc {
namespace {


constexpr double kPi = 3.14159265358979323846;

std::string body_name(const Model& model, int body) {
    return body == kGround ? std::string("ground") : model.masses[body].name;
}

std::string num(double value) {
    std::ostringstream out;
    out << std::setprecision(12) << value;
    return out.str();
}

// What an element acts on: "  between a and b", or "  along w1 dof1 w2 dof2 ...".
void acts_along(const Model& model, int a, int b, const std::vector<Weight>& weights, std::ostream& out) {
    if (weights.empty()) {
        out << "  between " << body_name(model, a) << " and " << body_name(model, b);
        return;
    }
    out << "  along";
    for (const Weight& w : weights) out << " " << num(w.w) << " " << body_name(model, w.body);
}

void print_summary(const Model& model, std::ostream& out) {
    out << "model: " << model.name << "\n";
    out << "source: " << model.source << "\n";
    if (!model.description.empty()) out << "description: " << model.description << "\n";

    if (model.structure.present) {
        out << "structure: M = " << model.structure.mass_file << "  K = " << model.structure.stiffness_file;
        if (!model.structure.damping_file.empty())
            out << "  C = " << model.structure.damping_file
                << (model.proportional_damping() ? " (proportional: alpha, beta below)" : " (non-proportional: dampers below)");
        out << "\n";
        if (model.reduction.present) {
            const ReductionSource& r = model.reduction;
            out << "reduction: " << r.method << ", " << r.full_dofs << " dofs -> " << r.boundary
                << " boundary dofs (those the model names) + " << r.modal_names.size() << " " << r.modes_kind();
            if (!r.interface_omega.empty())
                out << " (omega " << num(r.interface_omega.front()) << " to " << num(r.interface_omega.back()) << " rad/s)";
            out << "\n";
            auto table = [&](const ReductionSource::Frequencies& f, const char* contacts) {
                if (f.reduced.empty()) return;
                out << "  lowest frequencies, rad/s, every contact " << contacts << ": full  reduced  relative error\n";
                for (std::size_t k = 0; k < f.reduced.size(); ++k) {
                    out << "    " << k + 1 << "  ";
                    if (k < f.full.size())
                        out << num(f.full[k]) << "  " << num(f.reduced[k]) << "  " << num((f.reduced[k] - f.full[k]) / f.full[k]);
                    else
                        out << "-  " << num(f.reduced[k]) << "  -";
                    out << "\n";
                }
                if (!f.problem.empty()) out << "  (full structure: " << f.problem << ")\n";
            };
            table(r.open, "open");
            table(r.closed, "closed");
            if (!r.response.empty())
                out << "  response at the boundary dofs, the structure alone (elements left out): full vs reduced, "
                       "relative error\n";
            for (const ReductionSource::Response& e : r.response)
                out << "    " << e.what << ": " << (e.problem.empty() ? num(e.error) : "- (" + e.problem + ")") << "\n";
        }
        if (model.condensation.present()) {
            std::string list;
            for (std::size_t d = 0; d < model.condensation.dofs.size(); ++d)
                if (model.condensation.mass[d] < 0) list += (list.empty() ? "" : ", ") + model.condensation.dofs[d];
            out << "massless dofs: " << model.condensation.condensed() << " condensed statically (Guyan: "
                << list << "; recovered in the CSV outputs)\n";
        }
        if (model.coupled_mass()) {
            std::size_t couplings = 0;
            for (std::size_t i = 0; i < model.dof(); ++i)
                for (std::size_t j = i + 1; j < model.dof(); ++j) couplings += model.mass_entry(i, j) != 0.0 ? 1 : 0;
            out << "mass matrix M: coupled (" << couplings << " off-diagonal pairs; smallest eigenvalue "
                << num(model.mass_floor) << "); m below is M_ii\n";
        }
    }
    out << "degrees of freedom: " << model.dof() << "\n";
    for (std::size_t i = 0; i < model.dof(); ++i)
        out << "  " << i + 1 << "  " << model.masses[i].name << "  m = " << num(model.masses[i].m) << "\n";

    std::size_t from_structure = 0;
    for (const Spring& s : model.springs) from_structure += s.from_structure ? 1 : 0;
    out << "springs: " << model.springs.size() - from_structure << "\n";
    for (const Spring& s : model.springs)
        if (!s.from_structure)
            out << "  " << body_name(model, s.a) << " - " << body_name(model, s.b) << "  k = " << num(s.k) << "\n";
    if (model.structure.present)
        out << "stiffness matrix K: " << from_structure
            << " couplings (K = sum of -K_ij between dofs i, j and the row sums to ground)\n";

    out << "contacts: " << model.contacts.size() << "\n";
    for (const Contact& c : model.contacts) {
        out << "  " << c.name;
        acts_along(model, c.a, c.b, c.weights, out);
        out << "  gap = " << num(c.gap);
        if (c.rigid())
            out << "  rigid stop, restitution e = " << num(c.restitution);
        else
            out << "  k = " << num(c.k);
        if (c.c != 0.0) out << "  c = " << num(c.c) << " (while closed)";
        out << "\n";
    }

    std::size_t with_friction = 0;
    auto own = [&](std::size_t i) { return model.has_friction(i) && model.friction_slot(i).element < 0; };
    for (std::size_t i = 0; i < model.dof(); ++i) with_friction += own(i) ? 1 : 0;
    out << "friction masses: " << with_friction << "  (normal force m*g, g = " << num(model.g) << ")\n";
    for (std::size_t i = 0; i < model.dof(); ++i)
        if (own(i))
            out << "  " << model.masses[i].name << "  mu_k = " << num(model.friction_slot(i).mu_k)
                << "  mu_s = " << num(model.friction_slot(i).mu_s) << "\n";
    if (!model.frictions.empty()) {
        out << "friction elements: " << model.frictions.size() << "\n";
        for (const FrictionElement& f : model.frictions)
            out << "  " << f.name << "  between " << body_name(model, f.a) << " and " << body_name(model, f.b)
                << "  mu_k = " << num(f.mu_k) << "  mu_s = " << num(f.mu_s) << "  normal = " << num(f.normal) << "\n";
    }

    if (!model.jenkins.empty()) {
        out << "Jenkins elements: " << model.jenkins.size()
            << "  (spring in series with a slider; stuck at t0, unstretched)\n";
        for (const Jenkins& j : model.jenkins) {
            out << "  " << j.name;
            acts_along(model, j.a, j.b, j.weights, out);
            out << "  k = " << num(j.k) << "  slip_force = " << num(j.slip_force) << "  (slips at a stretch of "
                << num(j.slip_force / j.k) << ")\n";
        }
    }
    out << "forcing harmonics: " << model.forcing.size() << "\n";
    for (const Harmonic& h : model.forcing) out << "  omega = " << num(h.omega) << " rad/s  phase = " << num(h.phase) << "\n";
    for (const BaseMotion& b : model.base) {  // [[base]]: the ground's motion and the harmonic it makes
        static const char* given[] = {"x_g", "x_g'", "x_g''"};
        out << "  base motion: " << given[static_cast<int>(b.given)] << " = " << num(b.amplitude) << " sin("
            << num(b.omega) << " t + " << num(b.phase) << ") along";
        for (std::size_t i = 0; i < model.dof(); ++i)
            if (b.direction[i] != 0.0) out << " " << num(b.direction[i]) << " " << model.masses[i].name;
        out << "  (effective force -M r x_g'': harmonic " << b.harmonic + 1 << "; coordinates relative to the base)\n";
    }
    if (!model.load_steps.empty()) {  // [[load_step]]: the load from t on, the dofs it changes
        out << "load steps: " << model.load_steps.size() << "  (the constant load from t on)\n";
        const std::vector<double>* before = &model.load;
        for (const LoadStep& s : model.load_steps) {
            out << "  " << s.name << "  t = " << num(s.t);
            for (std::size_t i = 0; i < model.dof(); ++i)
                if (s.load[i] != (*before)[i]) out << "  " << model.masses[i].name << " = " << num(s.load[i]);
            out << "\n";
            before = &s.load;
        }
    }
    out << "damping: alpha = " << num(model.alpha) << "  beta = " << num(model.beta) << "\n";
    if (!model.proportional_damping()) {
        std::size_t from_c = 0;
        for (const Damper& d : model.dampers) from_c += d.from_structure ? 1 : 0;
        out << "dampers: " << model.dampers.size() - from_c << "  (non-proportional damping: state-space modes)\n";
        for (const Damper& d : model.dampers)
            if (!d.from_structure)
                out << "  " << body_name(model, d.a) << " - " << body_name(model, d.b) << "  c = " << num(d.c) << "\n";
        if (from_c > 0)
            out << "damping matrix C: " << from_c << " couplings (C = sum of -C_ij between dofs i, j and the row sums to ground)\n";
    }
}

// Non-proportional damping: the eigenvalues lambda = -xi omega +- i omega sqrt(1 - xi^2)
// of the state matrix, one line per pair (or real root), as the solver takes them.
void print_damped_modes(const Model& model, std::ostream& out) {
    std::unique_ptr<StateSpaceSolver> solver;
    try {
        solver = std::make_unique<StateSpaceSolver>(model, Configuration::all_open(model));
    } catch (const DefectiveModes& e) {  // critical damping: simulate takes it by the matrix exponential
        out << "damped modes: the state matrix is defective or nearly so (" << e.what()
            << "); its segments are the matrix exponential of the state (runtime/solvers/exponential_solver.h)\n";
        return;
    } catch (const RunError& e) {
        out << "damped modes: none: " << e.what() << "\n";  // simulate would stop there too
        return;
    }
    const StateSpaceSolver& s = *solver;
    out << "damped modes (all contacts open, all masses sliding" << (model.jenkins.empty() ? "" : ", Jenkins elements stuck")
        << "; eigenvalues of the state matrix):\n";
    out << "  mode  Re lambda [1/s]  Im lambda [rad/s]  |lambda| [rad/s]  xi\n";
    int j = 0;
    for (const std::complex<double>& l : s.damped_modes()) {
        const double mag = std::abs(l);
        out << "  " << ++j << "  " << num(l.real()) << "  " << num(l.imag()) << "  " << num(mag) << "  "
            << (mag > 0.0 ? num(-l.real() / mag) : std::string("-")) << "\n";
    }
    out << "  state-space eigenvector condition: " << num(s.condition()) << "\n";
}

void print_modes(const Model& model, std::ostream& out) {
    const ModalDecomposition modes = modal_analysis(model, Configuration::all_open(model));
    out << "natural frequencies (all contacts open, all masses sliding" << (model.jenkins.empty() ? "" : ", Jenkins elements stuck")
        << "; eigenvalues of (K, M)):\n";
    out << "  mode  omega_n [rad/s]  f [Hz]  xi\n";
    int rigid = 0;
    for (Eigen::Index j = 0; j < modes.lambda.size(); ++j) {
        out << "  " << j + 1 << "  ";
        if (modes.rigid[static_cast<std::size_t>(j)]) {
            out << "0 (rigid-body mode)\n";
            ++rigid;
            continue;
        }
        const double omega = std::sqrt(modes.lambda(j));  // lambda = omega_n^2, ascending
        const double xi = 0.5 * (model.alpha / omega + model.beta * omega);
        // With dampers the modes of (K, M) are not the damped ones: xi below, per damped mode.
        out << num(omega) << "  " << num(omega / (2.0 * kPi)) << "  "
            << (model.proportional_damping() ? num(xi) : std::string("-")) << "\n";
    }
    if (rigid > 0) {
        // The floating groups, by the rule that made those modes rigid (free_components.h).
        std::string groups;
        for (const std::vector<int>& members : free_components(model, Configuration::all_open(model)).floating_members()) {
            std::string names;
            for (int i : members) names += (names.empty() ? "" : ", ") + model.masses[i].name;
            groups += (groups.empty() ? " (" : "; ") + names;
        }
        out << "  note: " << rigid << " rigid-body mode(s): a mass or group of masses has no spring path to ground"
            << groups << (groups.empty() ? "" : ")") << "\n";
    }
}

}  // namespace

void check_report(const Model& model, std::ostream& out) {
    std::ostringstream text;  // nothing written unless the whole check passes
    print_summary(model, text);
    print_modes(model, text);
    if (!model.proportional_damping()) print_damped_modes(model, text);
    text << "ok\n";
    out << text.str();
}

}  // namespace hsnc
