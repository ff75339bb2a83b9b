// hsnc -- the subcommands of the `hsnc` program (interface.md section 3).
// Each add_* registers one CLI11 subcommand whose callback sets `exit_code`.
// Callbacks throw InputError (exit 2) or RunError (exit 1); run() maps them.
#pragma once

#include <CLI/CLI.hpp>

namespace hsnc::cli {

void add_check(CLI::App& app, int& exit_code);
void add_simulate(CLI::App& app, int& exit_code);
void add_inspect(CLI::App& app, int& exit_code);
void add_generate(CLI::App& app, int& exit_code);
void add_cache(CLI::App& app, int& exit_code);
void add_tradeoff(CLI::App& app, int& exit_code);
void add_sweep(CLI::App& app, int& exit_code);  ///< sweep and sweep-merge (cli/sweep.cpp)
void add_periodic(CLI::App& app, int& exit_code);
void add_lyapunov(CLI::App& app, int& exit_code);
void add_modes(CLI::App& app, int& exit_code);
void add_reduce(CLI::App& app, int& exit_code);

/// A CLI11 check that a number flag is finite: "nan" and "inf" are refused
/// at parse time (exit code 2, the flag named), not taken as "not given".
CLI::Validator finite_number();

/// Parse argv, run the chosen subcommand, return the process exit code.
int run(int argc, const char* const* argv);

}  // namespace hsnc::cli
