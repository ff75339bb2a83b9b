// hsnc check MODEL -- validate a model and summarise it (interface.md section 3)
// through the facade: hsnc::check_report (api/hsnc/check.h) writes the summary.
#include <iostream>
#include <memory>

#include "commands.h"
#include "hsnc/check.h"
#include "model_reader.h"

namespace hsnc::cli {

void add_check(CLI::App& app, int& exit_code) {
    auto* sub = app.add_subcommand(
        "check", "Validate a model; print its DOFs, contacts, friction masses and the natural frequencies of the "
                 "all-open, all-sliding configuration");
    auto path = std::make_shared<std::string>();
    sub->add_option("MODEL", *path, "model file (TOML)")->required();
    sub->callback([&exit_code, path] {
        ModelOverrides overrides;
        overrides.full_frequencies = true;  // with [reduction]: the reduction's accuracy is part of the report
        const Model model = read_model(*path, overrides);
        check_report(model, std::cout);  // nothing printed unless the whole check passes
        exit_code = 0;
    });
}

}  // namespace hsnc::cli
