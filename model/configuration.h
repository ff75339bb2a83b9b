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
    /// One per Jenkins element: 0 stuck, +1 or -1 slipping with the stretch of
    /// that sign (its force -slip*slip_force on a is then a constant of the
    /// configuration). Empty when the model has none.
    std::vector<signed char> slip;

    /// All contacts open, no mass stuck.
    static Configuration all_open(const Model& model);

    /// Parse "closed=c1,c2 stuck=m2 slip=j1+,j2-" (any part may be empty or
    /// absent; slip names Jenkins elements with the sign of their stretch).
    /// Throws InputError naming the unknown contact or mass.
    static Configuration parse(const Model& model, const std::string& spec);

    /// Canonical text, "closed=c1,c2 stuck=m2", parts in model order; the empty
    /// parts are written as "closed= stuck=" so the text always round-trips;
    /// " slip=..." follows when the model has Jenkins elements.
    std::string spec(const Model& model) const;

    /// Compact identifier usable in C symbol and file names: "c" + one digit
    /// per contact, "_s" + one digit per mass, e.g. "c1_s01"; then "_j" and
    /// one of 0 (stuck), p, n per Jenkins element when the model has any.
    std::string key() const;

    bool operator==(const Configuration& o) const { return closed == o.closed && stuck == o.stuck && slip == o.slip; }
    bool operator!=(const Configuration& o) const { return !(*this == o); }
    bool operator<(const Configuration& o) const {
        return closed != o.closed ? closed < o.closed : stuck != o.stuck ? stuck < o.stuck : slip < o.slip;
    }
};

}  // namespace hsnc
