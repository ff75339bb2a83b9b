// hsnc -- the Model: one plain value describing a piecewise-linear mechanical
// system with intermittent contacts and Coulomb friction.
//
// This is what the model file (docs/interface.md section 1) means,
// after every expression has been evaluated and every check has passed.
// The generator and the runtime both read it; nothing here depends on GiNaC,
// TOML or any other library, so the runtime can use it without them.
//
// Conventions (interface.md section 2):
//  - bodies are the masses 0..n-1 in file order, and `ground` (index kGround);
//  - springs have zero rest length: force -k*(x[a]-x[b]) on a, the opposite on b;
//  - a contact [a, b] with gap d has gap function G = x[a] - x[b] - d and, while
//    closed, acts as a spring of stiffness k on G;
//  - C = alpha*M + beta*K(configuration) (Rayleigh damping).
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace hsnc {

/// Body index of the ground (position 0, never moves).
inline constexpr int kGround = -1;

struct Mass {
    std::string name;
    double m = 1.0;             ///< mass value, > 0
    bool has_friction = false;  ///< true exactly when the file gave mu_k
    double mu_k = 0.0;          ///< kinetic friction coefficient, >= 0
    double mu_s = 0.0;          ///< static coefficient, >= mu_k
};

struct Spring {
    int a = kGround;  ///< body index (kGround or a mass)
    int b = kGround;
    double k = 0.0;   ///< stiffness, >= 0
};

struct Contact {
    std::string name;
    int a = kGround;
    int b = kGround;
    double gap = 0.0;  ///< closed while x[a] - x[b] >= gap
    double k = 0.0;    ///< contact stiffness, > 0
};

/// One forcing harmonic: force on mass i is amplitude[i]*sin(omega*t + phase).
struct Harmonic {
    double omega = 0.0;
    double phase = 0.0;
    std::vector<double> amplitude;  ///< one entry per mass
};

struct Model {
    std::string name;
    std::string description;
    std::string source;  ///< file the model was read from ("" when built in code)

    /// Parameters in file order with their evaluated values (includes g).
    std::vector<std::pair<std::string, double>> parameters;
    double g = 9.81;

    std::vector<Mass> masses;
    std::vector<Spring> springs;
    std::vector<Contact> contacts;
    double alpha = 0.0;  ///< Rayleigh mass coefficient
    double beta = 0.0;   ///< Rayleigh stiffness coefficient
    std::vector<Harmonic> forcing;
    std::vector<double> load;  ///< constant force per mass

    double t0 = 0.0;
    std::vector<double> x0;  ///< initial positions, one per mass
    std::vector<double> v0;  ///< initial velocities, one per mass

    std::optional<double> t_end;  ///< [simulate].t_end

    /// Source text of every parameter in file order (implicit g first when the
    /// file has none; a --set override replaces the file's text), for the
    /// symbolic view of `hsnc inspect --symbolic`. Empty when built in code.
    std::vector<std::pair<std::string, std::string>> parameter_expressions;
    /// Source text of every numeric field the file gave (a number literal as the
    /// shortest text that reads back to the same double), keyed by the path the
    /// reader's messages use: "mass[1].m", "mass[1].mu_k", "mass[1].mu_s",
    /// "spring[2].k", "contact[1].gap", "contact[1].k", "damping.alpha",
    /// "damping.beta", "forcing[1].omega", "forcing[1].phase",
    /// "forcing[1].amplitude.m1", "load.m2", "initial.t0", "initial.x.m1",
    /// "initial.v.m1", "simulate.t_end" (indices from 1, in file order). A field
    /// left out (its default applies) has no entry.
    std::map<std::string, std::string> field_expressions;

    std::size_t dof() const { return masses.size(); }

    /// Index of the mass called `name`, or -1.
    int mass_index(const std::string& name) const {
        for (std::size_t i = 0; i < masses.size(); ++i)
            if (masses[i].name == name) return static_cast<int>(i);
        return -1;
    }
    /// Index of the contact called `name`, or -1.
    int contact_index(const std::string& name) const {
        for (std::size_t i = 0; i < contacts.size(); ++i)
            if (contacts[i].name == name) return static_cast<int>(i);
        return -1;
    }
    /// Normal force of mass i (interface.md: always m*g).
    double normal_force(std::size_t i) const { return masses[i].m * g; }
};

}  // namespace hsnc
