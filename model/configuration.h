// hsnc -- a configuration: which contacts are closed and which masses are stuck
// (interface.md section 2). Between two switches the system is linear with
// constant forces in one configuration; the sign of each sliding mass's
// velocity is a runtime input of the segment, not part of the configuration.
#pragma once

#include <string>
#include <vector>

#include "model.h"

namespace hsnc {

struct Configuration {
    std::vector<char> closed;  ///< one flag per contact
    std::vector<char> stuck;   ///< one flag per mass (only friction masses may stick)

    /// All contacts open, no mass stuck.
    static Configuration all_open(const Model& model);

    /// Parse "closed=c1,c2 stuck=m2" (either part may be empty or absent).
    /// Throws InputError naming the unknown contact or mass.
    static Configuration parse(const Model& model, const std::string& spec);

    /// Canonical text, "closed=c1,c2 stuck=m2", parts in model order; the empty
    /// parts are written as "closed= stuck=" so the text always round-trips.
    std::string spec(const Model& model) const;

    /// Compact identifier usable in C symbol and file names: "c" + one digit
    /// per contact, "_s" + one digit per mass, e.g. "c1_s01".
    std::string key() const;

    bool operator==(const Configuration& o) const { return closed == o.closed && stuck == o.stuck; }
    bool operator!=(const Configuration& o) const { return !(*this == o); }
    bool operator<(const Configuration& o) const {
        return closed != o.closed ? closed < o.closed : stuck < o.stuck;
    }
};

}  // namespace hsnc
