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
//  - C = alpha*M + beta*K(configuration) (Rayleigh damping) plus the dampers
//    (non-proportional damping, runtime/solvers/state_space_solver.h).
#pragma once

#include <algorithm>
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "elements/contact.h"
#include "elements/direction.h"
#include "elements/friction.h"
#include "elements/jenkins.h"
#include "elements/spring.h"

namespace hsnc {

struct Mass {
    std::string name;
    double m = 1.0;  ///< mass value, > 0 (its friction, if any: Model::friction_slot)
};

/// One forcing harmonic: force on mass i is amplitude[i]*sin(omega*t + phase).
struct Harmonic {
    double omega = 0.0;
    double phase = 0.0;
    std::vector<double> amplitude;  ///< one entry per mass
};

/// A harmonic motion of the ground (`[[base]]`, interface.md): x_g(t) moves
/// the dofs along `direction` (the influence vector r), and the model is
/// written relative to it, x = x_abs - r x_g, so the base acts as the
/// effective force -M r x_g''(t): the reader adds it to Model::forcing as a
/// Harmonic (index `harmonic`). Every element is attached to the moving base.
struct BaseMotion {
    enum class Given { displacement, velocity, acceleration };
    Given given = Given::acceleration;  ///< what `amplitude` and `phase` describe: x_g, x_g' or x_g''
    double omega = 0.0, amplitude = 0.0, phase = 0.0;
    std::vector<double> direction;  ///< r, one entry per mass
    std::size_t harmonic = 0;       ///< its effective force in Model::forcing
};

/// A change of the constant load at an instant (`[[load_step]]`,
/// interface.md): from `t` on, Model::load is `load` and the condensed dofs'
/// load (Condensation::load) is `condensed_load`. A run crosses it as an
/// event of its own kind (`load_change`) and goes on from that exact state
/// with the new constant forces (api/simulate.cpp runs the pieces).
struct LoadStep {
    std::string name;                    ///< `name`, or "load_step<N>" (N from 1, file order)
    double t = 0.0;                      ///< the instant (after t0; steps in increasing t)
    std::vector<double> load;            ///< every mass's constant force from t on
    std::vector<double> condensed_load;  ///< per condensed dof (empty when none is condensed)
};

/// The massless dofs of a [structure] (zero rows of M: rotations without
/// rotary inertia), condensed statically (Guyan): they are not among the
/// masses, and follow them as x_c = R x (interface.md, "Massless dofs").
struct Condensation {
    std::vector<std::string> dofs;  ///< every dof of the structure, in matrix order
    std::vector<int> mass;          ///< per dof: its mass index, or -1 when condensed
    /// Row-major, (condensed dofs) x dof(): x_c = R x, R = -K_cc^-1 K_cm, in the order of `dofs`.
    std::vector<double> recovery;
    /// Row-major, (condensed dofs) x (condensed dofs): K_cc^-1, the static
    /// response of the condensed dofs to forces on them.
    std::vector<double> flexibility;
    /// Forces given on condensed dofs, per condensed dof (in the order of
    /// their rows): the constant load, and each forcing harmonic's amplitude
    /// (Model::forcing order). The dofs with mass carry them as R^T f_c (the
    /// reader folds them into Model::load and Harmonic::amplitude); the
    /// recovered x_c adds K_cc^-1 f_c(t).
    std::vector<double> load;
    std::vector<std::vector<double>> amplitude;
    bool present() const { return !dofs.empty(); }
    /// Whether a load or a forcing amplitude is given on a condensed dof.
    bool loaded() const {
        auto any = [](const std::vector<double>& f) { return std::any_of(f.begin(), f.end(), [](double x) { return x != 0.0; }); };
        return any(load) || std::any_of(amplitude.begin(), amplitude.end(), any);
    }
    /// How many dofs are condensed.
    std::size_t condensed() const {
        return static_cast<std::size_t>(std::count(mass.begin(), mass.end(), -1));
    }
};

/// Where a [structure]'s matrices came from (the model then has one Mass per
/// dof, m = M_ii, and the springs of K, Spring::from_structure).
struct StructureSource {
    bool present = false;
    std::string mass_file, stiffness_file, damping_file;  ///< as written in the model file ("" when absent)
};

/// A [structure] reduced by [reduction] (reduction.h): the full model's size,
/// the method and what it kept. The model's dofs are then the boundary dofs
/// (full-model order) and the modal coordinates `modal_names`.
struct ReductionSource {
    bool present = false;
    std::string method;  ///< "craig-bampton" or "rubin"
    /// What the modal coordinates are, as messages name them.
    const char* modes_kind() const { return method == "rubin" ? "free-interface modes" : "fixed-interface modes"; }
    std::size_t full_dofs = 0;
    std::size_t boundary = 0;              ///< the first `boundary` dofs of the model are physical
    std::vector<std::string> modal_names;  ///< the kept modes' coordinates
    std::vector<double> interface_omega;   ///< their circular frequencies, rad/s
    /// The reduced matrices, row-major over the model's dofs (C empty when none): what `hsnc reduce` writes.
    std::vector<double> M, K, C;
    std::vector<std::size_t> boundary_index;  ///< each boundary dof's index in the full structure
    /// Read with ModelOverrides::full_frequencies: the lowest circular
    /// frequencies (at most kReportedFrequencies) of the full and of the
    /// reduced structure, every contact open and every contact closed
    /// (`closed` empty without contacts); `problem` says why `full` is
    /// missing ("" when it is there).
    struct Frequencies {
        std::vector<double> full, reduced;
        std::string problem;
    };
    Frequencies open, closed;
    /// Read with ModelOverrides::full_frequencies: the steady response of the
    /// structure alone (its M, K, C; the elements left out) to the constant
    /// load and to each forcing harmonic, full against reduced, as the
    /// largest difference over the boundary dofs relative to the largest
    /// full amplitude there; `what` names the load ("load", "forcing 2 at
    /// 20 rad/s"), error NaN with `problem` saying why it was not computed.
    struct Response {
        std::string what;
        double error = 0.0;
        std::string problem;
    };
    std::vector<Response> response;
};
inline constexpr std::size_t kReportedFrequencies = 10;

struct Model {
    std::string name;
    std::string description;
    std::string source;  ///< file the model was read from ("" when built in code)

    /// Parameters in file order with their evaluated values (includes g).
    std::vector<std::pair<std::string, double>> parameters;
    double g = 9.81;

    std::vector<Mass> masses;
    /// The full mass matrix, dof() x dof() row-major, when a [structure]'s M is
    /// coupled (consistent or reduced mass: an off-diagonal entry); empty for a
    /// lumped model, whose M is diag(masses[i].m). masses[i].m is M_ii either way.
    std::vector<double> mass_matrix;
    /// The smallest eigenvalue of a coupled M (a bound the switch search uses:
    /// lambda_max(K, M) <= lambda_max(K) / mass_floor); 0 when M is lumped.
    double mass_floor = 0.0;
    std::vector<Spring> springs;
    std::vector<Contact> contacts;
    std::vector<FrictionElement> frictions;
    /// Coulomb friction by slot (elements/friction.h FrictionSlot): slot i is
    /// mass i's friction (its own mu_k, or the [[friction]] element acting on
    /// it). It may be shorter than `masses`: a mass past its end has none.
    /// Read it through friction_slot(i); write it through set_friction(i).
    std::vector<FrictionSlot> friction_slots;
    std::vector<Damper> dampers;  ///< [[damper]]s, then those of a non-proportional structure.damping
    std::vector<Jenkins> jenkins;
    StructureSource structure;
    ReductionSource reduction;
    Condensation condensation;  ///< a [structure]'s massless dofs (empty when it has none)
    double alpha = 0.0;  ///< Rayleigh mass coefficient
    double beta = 0.0;   ///< Rayleigh stiffness coefficient
    std::vector<Harmonic> forcing;
    std::vector<BaseMotion> base;  ///< [[base]]: each also a harmonic of `forcing` (its effective force)
    std::vector<double> load;  ///< constant force per mass
    std::vector<LoadStep> load_steps;  ///< changes of `load` in time, in increasing t (none: constant)

    double t0 = 0.0;
    std::vector<double> x0;  ///< initial positions, one per mass
    std::vector<double> v0;  ///< initial velocities, one per mass
    /// Initial slider positions, one per Jenkins element, or empty: at rest,
    /// unstretched (s = x0[a] - x0[b], interface.md). Set by runs that
    /// continue from another run's end state (a sweep's points).
    std::vector<double> slider0;

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
    /// "initial.v.m1", "simulate.t_end" (indices from 1, in file order), and
    /// "mass[1].normal" for a [[friction]] element's `normal`. A field
    /// left out (its default applies) has no entry.
    std::map<std::string, std::string> field_expressions;

    std::size_t dof() const { return masses.size(); }
    /// True when M has off-diagonal entries (mass_matrix holds it).
    bool coupled_mass() const { return !mass_matrix.empty(); }
    /// M_ij, lumped or coupled.
    double mass_entry(std::size_t i, std::size_t j) const {
        if (coupled_mass()) return mass_matrix[i * masses.size() + j];
        return i == j ? masses[i].m : 0.0;
    }
    /// Positions the engine carries: the masses', then every Jenkins slider's.
    std::size_t state_size() const { return masses.size() + jenkins.size(); }
    /// The most switch functions a configuration has (switch_function.h).
    std::size_t max_switches() const { return contacts.size() + 2 * masses.size() + 2 * jenkins.size(); }
    /// C = alpha*M + beta*K(cfg) exactly: no dampers. Only then are the modes
    /// of K those of the damped system (the derivation, kernels, interpreter,
    /// reference and tangent need it; the state-space solver does not).
    bool proportional_damping() const {
        if (!dampers.empty()) return false;
        for (const Contact& c : contacts)
            if (c.c != 0.0) return false;  // a contact's own damping (contact.h)
        return true;
    }

    /// Whether a body is the partner of two or more frictions (several
    /// riders on one body: an under-platform damper, blades on a disk), or
    /// a partner has a friction of its own (a chain: a block on a block on
    /// the ground): a body taking part in several frictions.
    bool shared_partner() const {
        std::vector<int> riders(masses.size(), 0);
        for (const FrictionSlot& f : friction_slots)
            if (f.active && f.partner != kGround &&
                (++riders[static_cast<std::size_t>(f.partner)] > 1 ||
                 friction_slot(static_cast<std::size_t>(f.partner)).active))
                return true;
        return false;
    }
    /// Whether a partner has a friction of its own (a chain of frictions:
    /// a block on a block on the ground).
    bool friction_chain() const {
        return std::any_of(friction_slots.begin(), friction_slots.end(), [&](const FrictionSlot& f) {
            return f.active && f.partner != kGround && friction_slot(static_cast<std::size_t>(f.partner)).active;
        });
    }
    /// Whether the force a stuck friction must hold depends on the other
    /// frictions' states: a coupled M, or a shared partner. Such frictions
    /// are decided together, and every back end reads their held forces as
    /// P_i . f (held_mass.h).
    bool coupled_friction() const { return coupled_mass() || shared_partner(); }

    /// Whether a contact is a rigid stop with restitution (its events are impacts).
    bool has_impacts() const {
        return std::any_of(contacts.begin(), contacts.end(), [](const Contact& c) { return c.rigid(); });
    }

    /// The constant load on the condensed dofs at t: Condensation::load, or
    /// that of the last [[load_step]] at or before t (the load from t on).
    const std::vector<double>& condensed_load_at(double t) const {
        const std::vector<double>* f = &condensation.load;
        for (const LoadStep& s : load_steps)
            if (s.t <= t) f = &s.condensed_load;
        return *f;
    }

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
    /// Index of the Jenkins element called `name`, or -1.
    int jenkins_index(const std::string& name) const {
        for (std::size_t j = 0; j < jenkins.size(); ++j)
            if (jenkins[j].name == name) return static_cast<int>(j);
        return -1;
    }
    /// Mass i's friction slot (inactive when it has no friction).
    const FrictionSlot& friction_slot(std::size_t i) const {
        static const FrictionSlot none;
        return i < friction_slots.size() ? friction_slots[i] : none;
    }
    /// Mass i's friction slot, to be written (the slots grow to reach it).
    FrictionSlot& set_friction(std::size_t i) {
        if (friction_slots.size() <= i) friction_slots.resize(i + 1);
        return friction_slots[i];
    }
    /// Whether mass i has friction.
    bool has_friction(std::size_t i) const { return friction_slot(i).active; }
    /// Whether any mass has friction.
    bool any_friction() const {
        return std::any_of(friction_slots.begin(), friction_slots.end(),
                           [](const FrictionSlot& f) { return f.active; });
    }
    /// Normal force of mass i's friction: its element's `normal` as given, else m*g.
    double normal_force(std::size_t i) const {
        const double n = friction_slot(i).normal;
        return n > 0.0 ? n : masses[i].m * g;
    }
    /// The name that stands for mass i's friction in event rows and
    /// configuration specs: its [[friction]] element's name, else its own.
    const std::string& friction_name(std::size_t i) const {
        const int e = friction_slot(i).element;
        return e >= 0 ? frictions[static_cast<std::size_t>(e)].name : masses[i].name;
    }
    /// The element named in an event row of a friction kind (stick, release,
    /// reversal): element < dof() is a mass's friction, dof() + j Jenkins element j.
    const std::string& friction_event_name(int element) const {
        const auto e = static_cast<std::size_t>(element);
        return e < masses.size() ? friction_name(e) : jenkins[e - masses.size()].name;
    }
};

}  // namespace hsnc
