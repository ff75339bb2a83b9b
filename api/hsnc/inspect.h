// hsnc -- the library facade: the segment formulas of one configuration, as
// `hsnc inspect MODEL --config SPEC` prints them (interface.md section 3):
// the reduced matrices, modal frequencies and damping ratios, the static
// offset, the motion in terms of tau = t - t0 and the switch functions (text
// or LaTeX); or the configuration's generated kernel (cpp).
#pragma once

#include <ostream>

#include "configuration.h"
#include "model.h"

namespace hsnc {

enum class InspectFormat { text, latex, cpp };

struct InspectOptions {
    InspectFormat format = InspectFormat::text;
    /// Keep the model's parameters as symbols where the configuration has at
    /// most 2 free dofs (closed-form eigenvalues); else numbers, said in `notes`.
    bool symbolic = false;
};

/// Writes the view of cfg to `out`, all of it or nothing (a derivation that
/// fails throws before anything is written: RunError, NotDerivable for a
/// kernel the Eigen solver takes instead); what was asked for and not done
/// (--symbolic out of reach) goes to `notes`, one line each.
void inspect_report(const Model& model, const Configuration& cfg, const InspectOptions& options, std::ostream& out,
                    std::ostream& notes);

}  // namespace hsnc
