// hsnc -- the kinds of switch event (interface.md section 2), as the engine,
// the baselines and the reference report them and the events CSV names them.
#pragma once

namespace hsnc {

enum class EventKind { contact_close, contact_open, stick, release, reversal };

/// The `kind` column of the events CSV.
const char* event_kind_name(EventKind kind);

}  // namespace hsnc
