#include "switch_guard.h"
#include "number_text.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace hsnc {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

}  // namespace

SwitchGuard::SwitchGuard(const EngineOptions& options, double t0)
    : zeno_events_(options.zeno_events),
      zeno_span_(options.zeno_span),
      t0_(t0),
      last_t_(-std::numeric_limits<double>::infinity()) {}

void SwitchGuard::event(double t) {
    recent_.push_back(t);
    if (recent_.size() > zeno_events_) recent_.pop_front();
}

RunStatus SwitchGuard::after_switch(double t, std::size_t switch_functions) {
    // Chattering: switches that keep firing at one instant.
    same_instant_ = t == last_t_ ? same_instant_ + 1 : 0;
    last_t_ = t;
    if (same_instant_ > 4 * (switch_functions + 2)) return status_ = RunStatus::chattering;
    // Zeno: many switches within a vanishing time span, measured on the run's
    // own clock (time elapsed since t0), not relative to |t|: at t0 = 1e9 a
    // span relative to |t| was 1 s and took 16000 regular switches of a
    // 16 kHz oscillation for an accumulation. The second term is the time's
    // own resolution (8 eps |t| per switch, twice the smallest step):
    // switches that a method can only separate by its smallest step pile up there.
    if (!recent_.empty() && recent_.size() >= zeno_events_ &&
        recent_.back() - recent_.front() <= zeno_span_ * std::max(1.0, t - t0_) +
                                                static_cast<double>(zeno_events_) * 8 * kEps * std::fabs(t))
        return status_ = RunStatus::zeno;
    return status_ = RunStatus::ok;
}

std::string SwitchGuard::message(const std::string& configuration) const {
    if (status_ == RunStatus::chattering)
        return "configuration keeps switching at t = " + number_text(last_t_) + " (now '" + configuration + "')";
    if (status_ == RunStatus::zeno)
        return std::to_string(recent_.size()) + " switches between t = " + number_text(recent_.front()) + " and " +
               number_text(recent_.back()) + " (accumulating switches, configuration '" + configuration + "')";
    return "";
}

}  // namespace hsnc
