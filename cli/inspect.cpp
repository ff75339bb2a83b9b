// hsnc inspect MODEL [--config SPEC] [--format text|latex|cpp] [--symbolic]:
// the segment formulas of one configuration (interface.md section 3), as the
// library facade writes them (api/hsnc/inspect.h).
#include <iostream>
#include <memory>
#include <sstream>
#include <string>

#include "commands.h"
#include "hsnc/inspect.h"
#include "model_reader.h"

namespace hsnc::cli {

void add_inspect(CLI::App& app, int& exit_code) {
    auto* sub = app.add_subcommand("inspect", "the segment formulas of one configuration");
    struct Options {
        std::string model, config, format = "text";
        bool symbolic = false;
    };
    auto o = std::make_shared<Options>();
    sub->add_option("MODEL", o->model, "model file (TOML)")->required();
    sub->add_option("--config", o->config, "configuration, e.g. \"closed=c1 stuck=m2\" (default: all open, none stuck)");
    sub->add_option("--format", o->format, "text (default), latex, or cpp (the generated kernel)")
        ->check(CLI::IsMember({"text", "latex", "cpp"}));
    sub->add_flag("--symbolic", o->symbolic,
                  "keep the model's parameters as symbols; only where the configuration has at most 2 free DOF "
                  "(closed-form eigenvalues), else said on stderr and numbers are printed");
    sub->callback([&exit_code, o] {
        const Model model = read_model(o->model);
        const Configuration cfg = Configuration::parse(model, o->config);
        InspectOptions options;
        options.format = o->format == "latex" ? InspectFormat::latex
                         : o->format == "cpp" ? InspectFormat::cpp
                                              : InspectFormat::text;
        options.symbolic = o->symbolic;
        std::ostringstream text, notes;  // the notes (stderr) first, as they are found
        auto say_notes = [&notes] {
            std::istringstream lines(notes.str());
            for (std::string line; std::getline(lines, line);) std::cerr << "hsnc inspect: " << line << "\n";
        };
        try {
            inspect_report(model, cfg, options, text, notes);
        } catch (...) {
            say_notes();
            throw;
        }
        say_notes();
        std::cout << text.str();
        exit_code = 0;
    });
}

}  // namespace hsnc::cli
