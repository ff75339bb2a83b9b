#include "event_kind.h"

namespace hsnc {

const char* event_kind_name(EventKind kind) {
    switch (kind) {
        case EventKind::contact_close: return "contact_close";
        case EventKind::contact_open: return "contact_open";
        case EventKind::stick: return "stick";
        case EventKind::release: return "release";
        case EventKind::reversal: return "reversal";
    }
    return "?";
}

}  // namespace hsnc
