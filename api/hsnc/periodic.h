// hsnc -- periodic orbits of the forced response and their stability
// (interface.md section 6, `hsnc periodic`), without the command line.
//
//     const hsnc::Model model = hsnc::read_model("models/coulomb-1dof.toml");
//     hsnc::PeriodicOptions options;
//     options.transient = 20.0;
//     const hsnc::PeriodicResult orbit = hsnc::periodic(model, options);
//     if (orbit.status == hsnc::PeriodicStatus::ok) ... orbit.x, orbit.multipliers
//
// Newton shooting on the period map P (the exact motion over one period from
// a state at t_s = t0 + k*period): r(y) = P(y) - y is driven to zero with
// steps solving (M - I) dy = -r, M = dP/dy the exact monodromy matrix (segment
// transition matrices and the saltation matrix of every switch,
// analysis/tangent.h), each step halved up to 10 times until the residual
// falls. Converged when the residual -- |r| relative to the state's size,
// positions and velocities each against their own largest entry -- is at most
// `tolerance`. A search that does not get there is PeriodicStatus::not_converged
// with the last state and residual, never a wrong orbit.
#pragma once

#include <cmath>
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

/// Where a search is (PeriodicOptions::progress).
struct PeriodicProgress {
    enum class Stage { transient, search, orbit };
    Stage stage = Stage::transient;  ///< the transient, the Newton search, the final run of the orbit
    double t = 0.0;                  ///< time the run under way has reached
    double t_from = 0.0, t_to = 0.0; ///< that run's span
    int iterations = 0;              ///< Newton steps taken
    double residual = std::numeric_limits<double>::quiet_NaN();  ///< of the current state (NaN before the first)
    std::size_t runs = 0;            ///< period-map runs so far
};

struct PeriodicOptions {
    /// Period of the forcing T; NaN: 2*pi/omega of the model's forcing (an
    /// OptionError when the model has no forcing, or harmonics of different
    /// frequencies).
    double period = std::numeric_limits<double>::quiet_NaN();
    /// K: look for an orbit of period K*T (subharmonic).
    int harmonic = 1;
    /// Run this long from the initial state first; the search starts at the
    /// first t0 + k*K*T at or after t0 + transient.
    double transient = 0.0;
    /// Residual at which the search has converged.
    double tolerance = 1e-10;
    /// Newton iterations at most.
    int max_iterations = 50;
    /// Samples of the orbit's period passed to the observer every dt (and at
    /// its end); NaN: period/1000.
    double dt = std::numeric_limits<double>::quiet_NaN();
    /// Where the segment solvers come from, as for hsnc::simulate: automatic,
    /// aot, generic or jit (the tangent dynamics do not depend on it).
    KernelChoice kernels = KernelChoice::automatic;
    /// KernelChoice::jit: directory of the persistent kernel cache ("": the
    /// default, as SimulateOptions::cache_dir), and whether to use one.
    std::string cache_dir;
    bool use_cache = true;
    /// Called now and then from the calling thread (after every segment of
    /// every run, and at least every few hundred switches), for a progress
    /// report or a cancel check; return false to stop the search: the result
    /// is then PeriodicStatus::stopped (no orbit). May be empty.
    std::function<bool(const PeriodicProgress&)> progress;
};

/// ok: converged; not_converged: see the file comment; stopped: options.progress returned false.
enum class PeriodicStatus { ok, not_converged, stopped };
const char* periodic_status_name(PeriodicStatus status);

/// A multiplier within this of the unit circle is on it, whichever side
/// rounding puts it (|mu| = 1 comes out as 1 +- a few 1e-15). On it is not
/// stable (interface.md), except a family's multiplier: within this of +1
/// with as many independent eigenvectors as such multipliers (a stuck pair's
/// offset, a slider or a mass stuck all period: the orbit moved along it is
/// an orbit too), counted in PeriodicResult::neutral and left out of
/// `stable` (a perturbation along the family neither grows nor decays). An
/// undamped linear mode (a complex pair on the circle) or a free body's drift
/// (+1 without its eigenvectors: a Jordan block) stays not stable.
inline constexpr double kNeutralMultiplier = 1e-10;

struct PeriodicResult {
    PeriodicStatus status = PeriodicStatus::not_converged;
    std::string message;     ///< why the search did not converge ("" when ok)
    double period = 0.0;     ///< K*T
    double t = 0.0;          ///< time of the state below: t0 + k*period
    int iterations = 0;      ///< Newton steps taken
    double residual = 0.0;   ///< of the state below
    std::vector<double> x, v;  ///< the orbit's state at t (the last one tried when not converged)
    std::vector<double> s;     ///< and its Jenkins sliders' positions (Model::jenkins order)
    /// Floquet multipliers (eigenvalues of the monodromy matrix), 2 per
    /// mass and 1 per Jenkins element, largest |mu| first.
    std::vector<std::complex<double>> multipliers;
    double max_multiplier = 0.0;  ///< largest |mu|
    bool stable = false;          ///< every |mu| < 1 - kNeutralMultiplier, but the `neutral` ones
    /// Multipliers of a family of orbits (+1 to kNeutralMultiplier, with their eigenvectors; see
    /// kNeutralMultiplier), left out of `stable`.
    std::size_t neutral = 0;
    /// The monodromy matrix dP/dy, row-major, y = (x, v, s): 2n + nj square.
    std::vector<double> monodromy;
    std::size_t events = 0;  ///< switch events over one period of the orbit
    /// Grazing switch instants over one period of the orbit (of the last
    /// state tried when not converged): a contact closing or opening at a
    /// turning point of its gap, |G'| Omega / |G''| <= 1e-4 (Omega the
    /// largest natural or forcing frequency; analysis/tangent.h), or a switch
    /// without a saltation matrix. The period map is not smooth at a grazing orbit: its
    /// multipliers (and `stable`) are not reliable there.
    std::size_t grazing = 0;
};

/// Finds a periodic orbit (see the file comment). When converged, one period
/// of the orbit is run once more and reported to `orbit` (samples every
/// options.dt from t, switch events), if given. Throws OptionError for
/// options that do not fit the model, RunError when a run fails outright.
PeriodicResult periodic(const Model& model, const PeriodicOptions& options, Observer* orbit = nullptr);

/// The forcing's fundamental angular frequency: the largest omega0 of which
/// every harmonic's |omega| (omega != 0) is a whole multiple n omega0, n <=
/// kMaxHarmonicOrder, to 1e-12 relative (|omega| itself for one frequency;
/// the base of engine orders 2 omega, 3 omega; omega/2 for 2 omega and 3 omega).
/// NaN when there is no harmonic forcing or the frequencies are not so
/// commensurate (quasi-periodic forcing).
double forcing_fundamental(const Model& model);
inline constexpr int kMaxHarmonicOrder = 1000;

/// 2*pi/forcing_fundamental(model): the forcing's common period; NaN when
/// there is no harmonic forcing or its frequencies are not commensurate.
double forcing_period(const Model& model);

/// The rotation number of a stroboscopic Poincare section (the states at
/// t0 + k T of one dof, k = 0..n-1; interface.md, `--section period`): the
/// mean turn per period of the points about their centroid, clockwise in
/// the (x, v) plane as phase-plane motion runs, in [0, 1). On an invariant
/// circle (a quasi-periodic response) it is the torus's second frequency
/// over the section's, omega_2 / omega_1 modulo 1; on a periodic orbit of p
/// points it is q/p. Computed as a weighted Birkhoff average (weights
/// exp(-1/(s(1-s))) over the run, s in (0, 1): Das, Sander and Yorke 2017),
/// which converges faster than any power of n on a smooth invariant circle
/// where the plain mean converges as 1/n.
struct RotationNumber {
    double value = NAN;  ///< NaN: fewer than 8 points, or x or v the same in every point
    /// |the first half's average - the second half's|: at rounding level on an invariant
    /// circle, about 1/sqrt(n) on a chaotic set.
    double error = NAN;
};
RotationNumber rotation_number(const double* x, const double* v, std::size_t n, std::size_t stride = 1);

}  // namespace hsnc
