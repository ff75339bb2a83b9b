#include "event_kind.h"

namespace hsnc {

const char* event_kind_name(EventKind kind) {
    switch (kind) {
        case EventKind::contact_close: return "contact_close";
        case EventKind::contact_open: return "contact_open";
        case EventKind::stick: return "stick";
        case EventKind::release: return "release";
        case EventKind::reversal: return "reversal";
        case EventKind::load_change:
            return "load_change";
        case EventKind::impact:
            return "impact";
    }
    return "?";
}

std::string event_element_name(const Model& model, EventKind kind, int element) {
    const auto e = static_cast<std::size_t>(element);
    switch (kind) {
        case EventKind::contact_close:
        case EventKind::contact_open:
        case EventKind::impact:
            return element >= 0 && e < model.contacts.size() ? model.contacts[e].name : "?";
        case EventKind::load_change:
            return element >= 0 && e < model.load_steps.size() ? model.load_steps[e].name : "?";
        default:
            return element >= 0 && e < model.state_size() ? model.friction_event_name(element) : "?";
    }
}

}  // namespace hsnc
