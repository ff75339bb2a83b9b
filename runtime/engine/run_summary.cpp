#include "run_summary.h"

namespace hsnc {

const char* run_status_name(RunStatus status) {
    switch (status) {
        case RunStatus::ok: return "ok";
        case RunStatus::chattering: return "chattering";
        case RunStatus::zeno: return "zeno";
        case RunStatus::max_events: return "max_events";
        case RunStatus::stopped: return "stopped";
        case RunStatus::failure: return "failure";
    }
    return "?";
}

}  // namespace hsnc
