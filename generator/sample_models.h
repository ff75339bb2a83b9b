// hsnc -- a fixed catalogue of small models built in code, one or more per
// closed-form regime (under-, critically, over-damped, undamped, rigid body,
// resonance and its neighbourhood) plus pseudo-random ones. The build emits
// and compiles their kernels (hsnc_gen --samples), and tests/test_emitter.cpp
// checks those compiled kernels against the GiNaC derivation of the same
// models: the catalogue is the contract between the two.
#pragma once

#include <string>
#include <vector>

#include "configuration.h"
#include "derivation.h"
#include "model.h"

namespace hsnc {

/// Every sample model, in a fixed order; names are unique C identifiers.
std::vector<Model> sample_models();

/// Every configuration of `model` (2^(contacts + friction masses) times 3^(Jenkins
/// elements): stuck, slipping + and -), in a fixed order.
std::vector<Configuration> all_configurations(const Model& model);

}  // namespace hsnc
