#include "commands.h"
#include "error.h"

namespace hsnc::cli {

// Not yet implemented: registered so that --help lists it.
void add_check(CLI::App& app, int& exit_code) {
    auto* sub = app.add_subcommand("check", "(not implemented yet)");
    sub->allow_extras();
    sub->callback([&exit_code] {
        exit_code = 1;
        throw RunError("check: not implemented yet");
    });
}

}  // namespace hsnc::cli
