// hsnc -- the library facade: the summary of a model that `hsnc check MODEL`
// prints (interface.md section 3): its degrees of freedom, contacts,
// friction and Jenkins elements, and the natural frequencies of the
// configuration with every contact open and every mass sliding (with
// dampers, the damped modes too), then "ok".
#pragma once

#include <ostream>

#include "model.h"

namespace hsnc {

/// Writes the summary of `model` to `out`, all of it or nothing: a modal
/// analysis that fails throws RunError before anything is written.
void check_report(const Model& model, std::ostream& out);

}  // namespace hsnc
