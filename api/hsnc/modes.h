// hsnc -- nonlinear normal modes of a conservative piecewise-linear model:
// the backbone of a linear mode continued in amplitude (interface.md,
// `hsnc modes`), without the command line.
//
//     const hsnc::Model model = hsnc::read_model("examples/modes/bilinear.toml");
//     hsnc::ModesOptions options;
//     options.mode = 1;
//     options.to = 0.05;  // amplitude of the mode's largest dof, from its equilibrium
//     const hsnc::ModesResult backbone = hsnc::modes(model, options);
//     for (const hsnc::ModePoint& p : backbone.points) ... p.amplitude, p.omega, p.energy
//
// A point of the backbone is a periodic orbit of the free, undamped model
// (the harmonic forcing and base motion left out, the constant load kept) on
// which the amplitude dof k turns at x_k = x_eq,k + A (v_k = 0 there, the
// phase condition). Its period T and the rest of its state y = (x, v) at that
// instant are found by Newton shooting on P(y) = y, P the exact motion over
// T: the unknowns are y without x_k and v_k, and T; the 2n residuals' 2n - 1
// unknowns are solved in the least-squares sense (energy conservation makes
// one residual redundant), with the exact monodromy matrix dP/dy (segment
// transition matrices and saltation matrices, analysis/tangent.h) and
// dP/dT = f(P(y)), the vector field at the end. The backbone starts at the
// linear limit (the mode shape, T = 2 pi/omega) and is continued in amplitude
// (or in energy) through the points asked for, each from a secant prediction
// of the last two. A step is refused when Newton fails, when its correction
// is longer than 0.3 of the step (a jump onto another family), or when it
// turns another mode's multiplier pair by more than 0.5 rad (a pass through
// +1 or -1 missed); it is then halved, down to min_step of the parameter,
// and at that floor longer steps leap over the trouble (a branch point, a
// kink). A search that still cannot follow the branch stops with the points
// found so far and says where.
//
// Damped modes. A model with Jenkins elements, Coulomb friction or viscous
// damping (Rayleigh, dampers, a damping matrix, contact damping)
// has no free
// periodic orbits: its modes are computed by the extended periodic motion
// concept (EPMC, Krack 2015): a mass-proportional term -xi M v is added, and
// xi is one more unknown, the one that makes the damped motion periodic; the
// orbit is still found exactly (the closed-form segments and the exact
// monodromy), and xi / (2 omega) is the mode's equivalent damping ratio at that
// amplitude (ModePoint::damping_ratio; with mass-proportional damping alone
// xi = alpha on any backbone, the ratio alpha / (2 omega)). The
// linear limit is the configuration with every Jenkins element and friction
// mass stuck (with
// dampers, its xi puts the mode's eigenvalue of (M, C - xi M, K) on the
// imaginary axis, i linear_omega); the
// equilibrium is the one with every Jenkins spring unstretched. Runs with
// negative damping use the Eigen solver (ModesOptions::kernels is then
// ignored: runtime/solvers/generic_solver.h and state_space_solver.h bound a
// growing mode),
// and dP/dT and dP/dxi come from finite differences (one short run and one
// period run per Newton step; the orbit itself stays exact).
#pragma once

#include <complex>
#include <cstddef>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "engine.h"
#include "model.h"
#include "simulate.h"

namespace hsnc {

/// Where a backbone is (ModesOptions::progress).
struct ModesProgress {
    std::size_t point = 0, points = 0;                            ///< points found, points asked for
    double amplitude = std::numeric_limits<double>::quiet_NaN();  ///< the amplitude being solved
    int iterations = 0;                                           ///< Newton steps at it so far
    double residual = std::numeric_limits<double>::quiet_NaN();
    std::size_t runs = 0;  ///< period-map runs so far
};

/// What parameterises the backbone (ModesOptions::from, to).
enum class ModesParameter {
    amplitude,  ///< the amplitude dof's excursion from equilibrium at its turning point
    energy      ///< the energy above the equilibrium (J; the turning point of the amplitude dof on its positive side)
};

struct ModesOptions {
    /// The linear mode to continue: K = 1 the lowest natural frequency of the
    /// configuration at the static equilibrium.
    int mode = 1;
    /// The dof whose amplitude parameterises the backbone; "": the dof with
    /// the largest entry of the mode shape (mass-normalised).
    std::string dof;
    /// Amplitudes of that dof from its equilibrium position at its turning
    /// point, both of one sign (a negative one: the turning point on the
    /// negative side, which differs from the positive one where stops are
    /// not symmetric). `to` is required; `from` NaN: to/points.
    double from = std::numeric_limits<double>::quiet_NaN();
    double to = std::numeric_limits<double>::quiet_NaN();
    /// Whether `from` and `to` are amplitudes or energies (both > 0).
    ModesParameter parameter = ModesParameter::amplitude;
    /// Points of the backbone, evenly spaced from `from` to `to` (1: `to`
    /// alone); with `geometric`, in equal ratios (a frequency-energy plot
    /// over decades).
    int points = 50;
    bool geometric = false;
    /// Converged when |P(y) - y| (positions and velocities each relative to
    /// their largest entry) is at most this.
    double tolerance = 1e-11;
    /// Newton iterations at most per point (and per halved step).
    int max_iterations = 30;
    /// The shortest step, relative to the parameter's value: a step that
    /// fails is halved down to it, then longer steps leap over the trouble.
    double min_step = 1e-6;
    /// Where the segment solvers come from, as for hsnc::simulate.
    KernelChoice kernels = KernelChoice::automatic;
    std::string cache_dir;
    bool use_cache = true;
    /// Called now and then (after every segment of every run, and between
    /// Newton steps); return false to stop: the result is then
    /// ModesStatus::stopped with the points found so far. May be empty.
    std::function<bool(const ModesProgress&)> progress;
};

/// A multiplier of a conservative orbit off the unit circle by more than this
/// makes it unstable (the multipliers of a conservative orbit lie on the
/// circle or in pairs mu, 1/mu; a double one, as the family's pair at +1, is
/// computed to about the square root of the rounding).
inline constexpr double kConservativeMultiplier = 1e-6;

/// One periodic orbit of the backbone.
struct ModePoint {
    double amplitude = 0.0;  ///< x_k - x_eq,k at the turning point (k: ModesResult::dof)
    double period = 0.0;     ///< T, s
    double omega = 0.0;      ///< 2 pi / T, rad/s
    /// Energy above the static equilibrium: kinetic plus potential (springs,
    /// closed contacts, minus the work of the constant load), exact on the
    /// piecewise-quadratic potential.
    double energy = 0.0;
    std::vector<double> x, v;  ///< the state at the turning point (v[dof] = 0)
    std::vector<double> sliders;  ///< the Jenkins sliders' positions there (Model::jenkins order)
    /// Damped modes (ModesResult::damped): the negative mass-proportional
    /// damping coefficient that makes the motion periodic, 1/s, and the
    /// equivalent damping ratio xi / (2 omega). 0 on a conservative backbone.
    double xi = 0.0;
    double damping_ratio = 0.0;
    /// Every dof's largest |x_i - x_eq,i| over the orbit (its amplitude; on
    /// either side, at a turning point v_i = 0 found to rounding).
    std::vector<double> peaks;
    /// Floquet multipliers, 2 per mass (and one per Jenkins slider), largest
    /// |mu| first; two of them are the family's pair at +1 (the phase and the
    /// energy directions); of a damped mode, one (the phase), and they are
    /// those of the EPMC system (with the -xi M term), not of the physical one.
    std::vector<std::complex<double>> multipliers;
    /// The largest |mu| but the family's pair (1 when there is no other).
    double max_multiplier = 1.0;
    bool stable = false;      ///< max_multiplier <= 1 + kConservativeMultiplier
    /// Per other linear mode j (ModesResult::others): Theta_j / (2 pi), its
    /// pair's rotation over one period e^{+-i Theta_j} followed continuously
    /// from the linear limit, where it is omega_j / omega: the other mode's
    /// frequency in units of the backbone's.
    std::vector<double> ratios;  ///< empty for a damped mode (no rotations are followed)
    /// The internal resonances passed since the last point (or from the
    /// linear limit): "mode<j> <p>:1" where ratio j passed the whole number
    /// p (its multiplier passed +1: the backbone's p-th harmonic meets mode
    /// j, a branch of another family), "mode<j> <p>:2" where it passed p/2,
    /// p odd (-1: a period-doubled family). Empty: none.
    std::vector<std::string> resonances;
    std::size_t events = 0;   ///< switch events over one period
    std::size_t grazing = 0;  ///< grazing switches over one period (periodic.h PeriodicResult::grazing)
    int iterations = 0;       ///< Newton steps taken at this point
    double residual = 0.0;
};

/// ok: every point found; not_converged: the continuation stopped (message
/// says at which amplitude and why); stopped: the progress callback said so.
enum class ModesStatus { ok, not_converged, stopped };
const char* modes_status_name(ModesStatus status);

struct ModesResult {
    ModesStatus status = ModesStatus::not_converged;
    std::string message;
    int mode = 1;
    std::size_t dof = 0;              ///< the amplitude dof (Model::masses index)
    bool damped = false;  ///< computed by EPMC (the file comment): Jenkins elements, friction or viscous damping
    /// The linear mode's circular frequency, rad/s (Jenkins elements stuck; with dampers the
    /// damped mode's, where its eigenvalue with C - xi M is i omega)
    double linear_omega = 0.0;
    double linear_damping_ratio = 0.0;  ///< its xi / (2 omega): (alpha + beta omega^2) / (2 omega) when Rayleigh
    std::vector<double> shape;          ///< its undamped shape, mass-normalised, shape[dof] > 0
    std::vector<double> equilibrium;  ///< the static equilibrium x_eq
    std::string configuration;        ///< the equilibrium's configuration (Configuration::spec)
    std::vector<double> sliders;      ///< the Jenkins sliders' positions at the equilibrium (springs unstretched)
    std::vector<int> others;          ///< the other linear modes (numbers from 1), ModePoint::ratios order; empty when damped
    std::vector<ModePoint> points;    ///< in the order of the amplitudes asked for
};

/// The backbone (see the file comment). Throws InputError for a model with
/// elements it does not take (friction on masses, dampers or a damping matrix,
/// contact damping, load steps: named) or without a static equilibrium of
/// positive stiffness (a free body), OptionError for options that do not fit,
/// RunError when a run fails outright.
ModesResult modes(const Model& model, const ModesOptions& options);

}  // namespace hsnc
