// hsnc -- the input files of one run (the model file, its matrix files, the
// part files of sweep-merge), remembered by identity so that no output of the
// run replaces one of them.
//
// `hsnc simulate model.toml --out model.toml` would otherwise read the model,
// run, and rename the trajectory onto the model (exit 0, the model lost). The
// readers call note_input_file for every file they take; output_file.h's
// check_output refuses a path that is one of them (InputError, exit code 2,
// before the run), by device and inode, so that another name for the file (a
// hard or symbolic link, "./model.toml") is refused as well.
//
// Only inside an InputFileScope: the command line opens one per command. A
// library user (Python, a long-lived program) reads models without a scope and
// nothing accumulates; an inode freed and reused later could otherwise be
// mistaken for an input.
#pragma once

#include <sys/stat.h>

#include <string>

namespace hsnc {

/// While one exists, the files noted by note_input_file are remembered.
/// Scopes do not nest (a second one throws std::logic_error).
class InputFileScope {
public:
    InputFileScope();
    ~InputFileScope();
    InputFileScope(const InputFileScope&) = delete;
    InputFileScope& operator=(const InputFileScope&) = delete;
};

/// Remembers the file `path` (as the reader named it) with its fstat. No-op
/// outside a scope. Thread-safe.
void note_input_file(const std::string& path, const struct stat& status);
/// The same with stat(path); a path that cannot be stat'ed is not remembered
/// (its reader fails with its own message).
void note_input_file(const std::string& path);

/// The path an input with this identity was read under, or "" when none is.
std::string input_file_named(dev_t dev, ino_t ino);

}  // namespace hsnc
