#include "commands.h"
#include "error.h"

namespace hsnc::cli {

// Not yet implemented: registered so that --help lists it.
void add_simulate(CLI::App& app, int& exit_code) {
    auto* sub = app.add_subcommand("simulate", "(not implemented yet)");
    sub->allow_extras();
    sub->callback([&exit_code] {
        exit_code = 1;
        throw RunError("simulate: not implemented yet");
    });
}

}  // namespace hsnc::cli
