// hsnc -- the kinds of switch event (interface.md section 2), as the engine,
// the baselines and the reference report them and the events CSV names them.
#pragma once

#include <string>

#include "model.h"

namespace hsnc {

/// load_change is not a switch: a [[load_step]]'s instant, where a run goes on
/// with the new constant load (api/simulate.cpp); its element is the step's index.
/// impact: a rigid stop's velocity jump (contact.h impact(); element: the contact),
/// listed among the counts only for a model that has one (Model::has_impacts).
enum class EventKind { contact_close, contact_open, stick, release, reversal, load_change, impact };

/// The switch kinds, in the order the summary line and the Python counts list them.
inline constexpr EventKind kSwitchEventKinds[] = {EventKind::contact_close, EventKind::contact_open, EventKind::stick,
                                                  EventKind::release, EventKind::reversal};
/// Every kind: the switches, then load_change and impact.
inline constexpr EventKind kEventKinds[] = {EventKind::contact_close, EventKind::contact_open, EventKind::stick,
                                            EventKind::release,       EventKind::reversal,     EventKind::load_change,
                                            EventKind::impact};

/// The `kind` column of the events CSV.
const char* event_kind_name(EventKind kind);

/// The `element` column of the events CSV: the contact's name, the friction's
/// (Model::friction_event_name) or the load step's; "?" for an index out of range.
std::string event_element_name(const Model& model, EventKind kind, int element);

}  // namespace hsnc
