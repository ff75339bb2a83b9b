#include <cmath>
#include <cstdlib>
#include <iostream>

#include "commands.h"
#include "error.h"
#include "h5_archive.h"
#include "input_files.h"
#include "output_file.h"

namespace hsnc::cli {

CLI::Validator finite_number() {
    return CLI::Validator(
        [](std::string& text) {
            char* end = nullptr;
            const double v = std::strtod(text.c_str(), &end);
            if (end != text.c_str() && std::isfinite(v)) return std::string();
            return "must be a finite number, not '" + text + "'";
        },
        "");
}

int run(int argc, const char* const* argv) {
    set_command_line(argc, argv);  // recorded in --h5 files
    CLI::App app{
        "hsnc: exact response of piecewise-linear mechanical systems with intermittent\n"
        "contacts and Coulomb friction (hybrid symbolic-numeric method)."};
    app.set_version_flag("--version", std::string("hsnc ") + HSNC_VERSION);
    app.require_subcommand(1);
    int exit_code = 0;
    add_check(app, exit_code);
    add_simulate(app, exit_code);
    add_inspect(app, exit_code);
    add_generate(app, exit_code);
    add_cache(app, exit_code);
    add_tradeoff(app, exit_code);
    add_sweep(app, exit_code);
    add_periodic(app, exit_code);
    add_lyapunov(app, exit_code);
    add_modes(app, exit_code);
    add_reduce(app, exit_code);
    // Per command: no output may replace a file the command reads, and its
    // outputs are kept all or none (a failure leaves the files they would
    // have replaced as they were).
    InputFileScope inputs;
    OutputTransaction outputs;
    try {
        app.parse(argc, argv);
        outputs.commit();
    } catch (const CLI::Success& e) {
        return app.exit(e);  // --help, --version
    } catch (const CLI::ParseError& e) {
        // Bad flags are bad input: one message, exit code 2 (interface.md section 3).
        // CLI11 checks required options before it reports the arguments it did
        // not take, so `generate --bogus M` would say "--out-dir is required":
        // an unknown flag is named first, as it is most likely the cause.
        const std::vector<std::string> extras = app.remaining(true);
        if (e.get_name() == "RequiredError" && !extras.empty()) {
            std::cerr << "hsnc: " << CLI::ExtrasError(extras).what() << "\n";
            return 2;
        }
        std::cerr << "hsnc: " << e.what() << "\n";
        if (e.get_name() == "RequiredError" || e.get_name() == "CallForHelp") std::cerr << "Run with --help for usage.\n";
        return 2;
    } catch (const InputError& e) {
        std::cerr << "hsnc: " << e.what() << "\n";
        return 2;
    } catch (const RunError& e) {
        std::cerr << "hsnc: " << e.what() << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "hsnc: internal error: " << e.what() << "\n";
        return 1;
    }
    return exit_code;
}

}  // namespace hsnc::cli
