// hsnc -- which masses float freely in a configuration: the one structural
// rule of rigid-body modes, used by the modal analysis (model/modal.h), the
// derivation (generator/derivation.cpp), the reference (reference/mp_segment.cpp)
// and, through the modal analysis, `hsnc check`.
//
// The free masses (not stuck) split into connected components; the edges are
// the springs and closed contacts of stiffness k > 0 between two free masses.
// A component with no k > 0 spring or closed contact to the ground or to a
// stuck mass floats (a mass stuck to its friction partner, model.h
// FrictionSlot::partner, is part of the partner's body, not an anchor): it has exactly one rigid-body mode (lambda = 0
// exactly, shape sqrt(m) on its masses). Decided from the structure, never from a small eigenvalue, which stiffness or
// mass ratios beyond 1e10 would give.
#pragma once

#include <vector>

#include "configuration.h"
#include "model.h"

namespace hsnc {

struct FreeComponents {
    std::vector<int> free;       ///< the free masses, in model order
    std::vector<int> component;  ///< component of each free mass (parallel to `free`), numbered by first member
    std::vector<char> floating;  ///< per component: 1 when it has no k > 0 link to ground or to a stuck mass

    int count() const { return static_cast<int>(floating.size()); }
    /// The number of floating components (of rigid-body modes).
    int n_floating() const;
    /// The masses (model indices, in model order) of each floating component, in component order.
    std::vector<std::vector<int>> floating_members() const;
};

/// The components of the free masses of `cfg` (see the file comment).
FreeComponents free_components(const Model& model, const Configuration& cfg);

}  // namespace hsnc
