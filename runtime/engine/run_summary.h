// hsnc -- how a run ended (its status) and where: what Engine::run, the
// baselines and the reference return.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "configuration.h"

namespace hsnc {

/// Named outcomes of a run (documented; the CLI maps them to exit codes).
enum class RunStatus {
    ok,          ///< reached t_end
    chattering,  ///< switches at one instant did not settle (a configuration cycle)
    zeno,        ///< switches accumulate in time (Zeno); stopped where they do
    max_events,  ///< EngineOptions::max_events reached
    stopped,     ///< the observer asked to stop
    failure,     ///< the solver gave non-finite values
};
const char* run_status_name(RunStatus status);

struct RunSummary {
    RunStatus status = RunStatus::ok;
    std::string message;              ///< what happened and where, for non-ok status
    double t = 0.0;                   ///< time reached
    std::vector<double> x, v;         ///< state reached (the masses')
    std::vector<double> slider;       ///< Jenkins sliders' positions reached (Model::jenkins order)
    Configuration configuration;      ///< configuration reached
    std::size_t events = 0;           ///< switch events (rows of the events CSV)
    std::size_t segments = 0;         ///< closed-form segments started
    std::size_t restarts = 0;         ///< of them, carried over an event that kept the
                                      ///  configuration (runtime/solvers/restart.h), not set up
    std::size_t evaluations = 0;      ///< segment evaluations made to find switches
    std::size_t configurations = 0;   ///< distinct configurations visited
};

}  // namespace hsnc
