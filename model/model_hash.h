// hsnc -- a stable 64-bit fingerprint of what a kernel depends on in a Model.
//
// An ahead-of-time kernel is valid only for the exact numbers it was generated
// from. model_hash() is FNV-1a (64 bit; Fowler, Noll, Vo) over a canonical text
// of those numbers, each printed with 17 significant digits so that the text
// identifies the doubles exactly. Included: mass, contact names and values,
// springs, damping, forcing, loads and g. Not included: the initial state,
// t0, [simulate], description, source and parameter names -- kernels take the
// state at run time and parameters are already folded into the values.
#pragma once

#include <cstdint>
#include <string>

#include "model.h"

namespace hsnc {

/// The canonical text that model_hash() digests (one item per line).
std::string model_canonical_text(const Model& model);

/// FNV-1a 64 of model_canonical_text(model).
std::uint64_t model_hash(const Model& model);

/// FNV-1a 64 of arbitrary bytes.
std::uint64_t fnv1a64(const std::string& bytes);

}  // namespace hsnc
