#include "switch_function.h"

namespace hsnc {

std::vector<SwitchFunction> switch_functions(const Model& model, const Configuration& cfg) {
    std::vector<SwitchFunction> out;
    for (std::size_t c = 0; c < model.contacts.size(); ++c)
        out.push_back({SwitchKind::gap, static_cast<int>(c)});
    for (std::size_t i = 0; i < model.masses.size(); ++i) {
        if (!model.has_friction(i)) continue;
        const int e = static_cast<int>(i);
        if (cfg.stuck[i]) {
            out.push_back({SwitchKind::release_pos, e});
            out.push_back({SwitchKind::release_neg, e});
        } else {
            out.push_back({SwitchKind::velocity, e});
        }
    }
    for (std::size_t j = 0; j < model.jenkins.size(); ++j) {
        const int e = static_cast<int>(j);
        if (cfg.slip[j] == 0) {
            out.push_back({SwitchKind::slip_pos, e});
            out.push_back({SwitchKind::slip_neg, e});
        } else {
            out.push_back({SwitchKind::slip_velocity, e});
        }
    }
    return out;
}

}  // namespace hsnc
