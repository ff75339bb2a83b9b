// hsnc -- what happens at a switch (interface.md section 2): contact changes
// first, then the friction decisions (stick, release, reversal) with the
// forces of the configuration that results, repeated until nothing changes.
// Shared by the HSNC engine and the event-locating baseline integrator, so
// every method applies exactly the same physics; the decision rules
// themselves are runtime/engine/transition_rules.h, which the CLN reference
// instantiates too.
#pragma once

#include <string>
#include <vector>

#include "assembly.h"  // ElementIndex
#include "configuration.h"
#include "event_kind.h"
#include "model.h"
#include "switch_function.h"
#include "transition_rules.h"  // Transition, and the rules this file instantiates for double

namespace hsnc {

/// Apply the switch functions that reached zero at instant t with state
/// (x, v) and accelerations a just before it (may be null: taken as 0; used
/// only to break a tie |A_i| = mu_s*N_i): update cfg and sgn (friction direction of sliding masses); a mass
/// that stops gets v_i = 0 exactly. Appends the resulting events to `out`.
/// Returns false (and says why) when the decisions at this instant do not
/// settle (chattering) or the motion comes to rest on a rigid stop (resting_message). `elements` (the model's, may be
/// null) makes each force on a mass visit that mass's elements alone: the same bits, faster.
bool apply_switches(const Model& model, double t, const double* x, double* v, const double* a, Configuration& cfg,
                    std::vector<signed char>& sgn, const std::vector<SwitchFunction>& switched,
                    std::vector<Transition>& out, std::string& why, const ElementIndex* elements = nullptr);

/// Why a run stops where its motion comes to rest on rigid stop `contact` at
/// time `t` (its text): the message of the double engine, the baselines and the reference.
std::string resting_message(const Model& model, int contact, const std::string& t);

/// The configuration the motion enters at (t, x, v) (interface.md: "At t0 ...").
/// Contacts by G, a tie G = 0 by the first non-zero of G', G'', G''', ...
/// (closed if G is increasing; all zero counts as closed at t0, x[a]-x[b] >= gap);
/// friction masses with v_i = 0 stuck or sliding by A_i. With `carried` (the
/// configuration a run reached where its load changes: EngineOptions::carried),
/// its contacts and Jenkins elements are kept and friction is decided again.
Configuration entered_configuration(const Model& model, double t, const double* x, const double* v,
                                    std::vector<signed char>& sgn, const Configuration* carried = nullptr);

}  // namespace hsnc
