// hsnc -- reading a model file (interface.md section 1) into a Model.
//
// Numbers may be given as TOML numbers or as strings holding an expression
// over earlier [parameters], parsed by GiNaC ("2*k1", "sqrt(k/m)"). Every
// check that makes a model physically meaningful happens here; a Model that
// leaves this reader is valid. Every failure throws InputError with a message
// "FILE:LINE: key 'KEY': reason" (LINE where toml++ gives one).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "model.h"

namespace hsnc {

/// Command-line overrides, applied while reading (flags --set, --x0, --v0).
/// Each entry is the raw flag value "NAME=VALUE"; VALUE may be an expression
/// over the parameters.
struct ModelOverrides {
    std::vector<std::string> set;  ///< parameter overrides; later parameters see the new value
    std::vector<std::string> x0;   ///< initial position overrides
    std::vector<std::string> v0;   ///< initial velocity overrides
};

/// Read and validate the model file at `path`.
Model read_model(const std::string& path, const ModelOverrides& overrides = {});

/// Same, from TOML text; `source` names it in messages.
Model parse_model(const std::string& toml_text, const std::string& source,
                  const ModelOverrides& overrides = {});

}  // namespace hsnc
