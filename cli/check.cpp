// hsnc check MODEL -- validate a model and summarise it (interface.md section 3):
// its DOFs, contacts and friction masses, and the modes of the configuration
// with every contact open and every mass sliding.
//
// Modes: the undamped generalised eigenproblem K phi = omega^2 M phi with
// K = K(all open) (runtime/assembly.h), solved by Eigen's
// GeneralizedSelfAdjointEigenSolver (M is diagonal and > 0, so it applies).
// Damping ratio of Rayleigh damping C = alpha*M + beta*K for a mode of
// frequency omega_n: xi = (alpha/omega_n + beta*omega_n)/2 (modal damping,
// paper Eq. 12-13).
#include <cmath>
#include <iomanip>
#include <iostream>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "assembly.h"
#include "commands.h"
#include "configuration.h"
#include "error.h"
#include "model_reader.h"

namespace hsnc::cli {
namespace {

// An eigenvalue omega^2 below kRigidTolerance * max_i(K_ii/M_ii) is taken as a
// rigid-body mode (K singular: a mass or group of masses with no spring path
// to ground). max_i K_ii/M_ii is a Rayleigh quotient, so it is <= the largest
// eigenvalue and sets the scale of the rounding error of the solver.
constexpr double kRigidTolerance = 1e-10;
constexpr double kPi = 3.14159265358979323846;

std::string body_name(const Model& model, int body) {
    return body == kGround ? std::string("ground") : model.masses[body].name;
}

std::string num(double value) {
    std::ostringstream out;
    out << std::setprecision(12) << value;
    return out.str();
}

void print_summary(const Model& model, std::ostream& out) {
    out << "model: " << model.name << "\n";
    out << "source: " << model.source << "\n";
    if (!model.description.empty()) out << "description: " << model.description << "\n";

    out << "degrees of freedom: " << model.dof() << "\n";
    for (std::size_t i = 0; i < model.dof(); ++i)
        out << "  " << i + 1 << "  " << model.masses[i].name << "  m = " << num(model.masses[i].m) << "\n";

    out << "springs: " << model.springs.size() << "\n";
    for (const Spring& s : model.springs)
        out << "  " << body_name(model, s.a) << " - " << body_name(model, s.b) << "  k = " << num(s.k) << "\n";

    out << "contacts: " << model.contacts.size() << "\n";
    for (const Contact& c : model.contacts)
        out << "  " << c.name << "  between " << body_name(model, c.a) << " and " << body_name(model, c.b)
            << "  gap = " << num(c.gap) << "  k = " << num(c.k) << "\n";

    std::size_t with_friction = 0;
    for (const Mass& m : model.masses) with_friction += m.has_friction ? 1 : 0;
    out << "friction masses: " << with_friction << "  (normal force m*g, g = " << num(model.g) << ")\n";
    for (const Mass& m : model.masses)
        if (m.has_friction) out << "  " << m.name << "  mu_k = " << num(m.mu_k) << "  mu_s = " << num(m.mu_s) << "\n";

    out << "forcing harmonics: " << model.forcing.size() << "\n";
    for (const Harmonic& h : model.forcing) out << "  omega = " << num(h.omega) << " rad/s  phase = " << num(h.phase) << "\n";
    out << "damping: alpha = " << num(model.alpha) << "  beta = " << num(model.beta) << "\n";
}

void print_modes(const Model& model, std::ostream& out) {
    const Configuration open = Configuration::all_open(model);
    const Eigen::MatrixXd K = stiffness_matrix(model, open);
    const Eigen::VectorXd m = mass_vector(model);
    const Eigen::MatrixXd M = m.asDiagonal();
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> solver(K, M, Eigen::EigenvaluesOnly);
    if (solver.info() != Eigen::Success)
        throw RunError("check::print_modes(): the eigenvalue solver did not converge for model '" + model.name + "'");
    const double scale = (K.diagonal().array() / m.array()).maxCoeff();
    const double threshold = kRigidTolerance * scale;

    out << "natural frequencies (all contacts open, all masses sliding; eigenvalues of (K, M)):\n";
    out << "  mode  omega_n [rad/s]  f [Hz]  xi\n";
    int rigid = 0;
    for (Eigen::Index j = 0; j < solver.eigenvalues().size(); ++j) {
        const double lambda = solver.eigenvalues()(j);  // omega_n^2, ascending
        out << "  " << j + 1 << "  ";
        if (lambda <= threshold) {
            out << "0 (rigid-body mode)\n";
            ++rigid;
            continue;
        }
        const double omega = std::sqrt(lambda);
        const double xi = 0.5 * (model.alpha / omega + model.beta * omega);
        out << num(omega) << "  " << num(omega / (2.0 * kPi)) << "  " << num(xi) << "\n";
    }
    if (rigid > 0)
        out << "  note: " << rigid << " rigid-body mode(s): a mass or group of masses has no spring path to ground"
            << " (eigenvalues <= " << kRigidTolerance << " * max(K_ii/M_ii) are taken as 0)\n";
}

}  // namespace

void add_check(CLI::App& app, int& exit_code) {
    auto* sub = app.add_subcommand(
        "check", "Validate a model; print its DOFs, contacts, friction masses and the natural frequencies of the "
                 "all-open, all-sliding configuration");
    auto path = std::make_shared<std::string>();
    sub->add_option("MODEL", *path, "model file (TOML)")->required();
    sub->callback([&exit_code, path] {
        const Model model = read_model(*path);
        std::ostringstream out;  // print nothing unless the whole check passes
        print_summary(model, out);
        print_modes(model, out);
        out << "ok\n";
        std::cout << out.str();
        exit_code = 0;
    });
}

}  // namespace hsnc::cli
