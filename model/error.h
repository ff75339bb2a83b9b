// hsnc -- the two kinds of failure the command line distinguishes
// (interface.md section 3): bad input (exit code 2) and a failure while
// running (exit code 1). Messages follow "where: what", e.g.
// "models/x.toml:12: key 'mass.m': must be > 0".
#pragma once

#include <stdexcept>
#include <string>

namespace hsnc {

/// Bad input: a model file, a flag or a file the user gave. Exit code 2.
class InputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// A failure while running on valid input (chattering, a kernel that cannot
/// be built, ...). Exit code 1.
class RunError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// A configuration the derivation does not take (generator/derivation.h:
/// state-space modes that are defective, rigid-body modes or an undamped
/// resonance under dampers). Every kernel kind runs such a configuration on the
/// generic solver instead, so all kinds still agree.
class NotDerivable : public RunError {
public:
    using RunError::RunError;
};

}  // namespace hsnc
