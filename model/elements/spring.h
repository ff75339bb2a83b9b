// hsnc -- the linear elements between two bodies: a spring and a dashpot
// (interface.md, [[spring]] and [[damper]]). With the nonlinear elements'
// links (contact.h, jenkins.h) they make K(cfg) and C(cfg); see direction.h
// for what a link is and who reads one.
#pragma once

#include "direction.h"

namespace hsnc {

/// A spring of zero rest length: force -k (x[a] - x[b]) on a, the opposite on b.
struct Spring {
    int a = kGround;  ///< body index (kGround or a mass)
    int b = kGround;
    double k = 0.0;   ///< stiffness, >= 0 (a spring of a [structure]'s K may be negative)
    /// True for the springs that represent a [structure]'s stiffness matrix
    /// (structure.h): K = sum over i<j of -K_ij (e_i - e_j)(e_i - e_j)^T
    /// + diag(row sums), so k = -K_ij between two dofs (any sign) and the
    /// row sum to ground.
    bool from_structure = false;

    Direction direction() const { return {a, b}; }
};

/// A viscous dashpot (interface.md section 5): force -c (v[a] - v[b]) on a, the
/// opposite on b. A model with dampers has non-proportional damping: its
/// segments are solved through state-space modes (state_space_solver.h).
struct Damper {
    int a = kGround;
    int b = kGround;
    double c = 0.0;  ///< >= 0 (a damper of a [structure]'s C may be negative)
    /// True for the dampers that represent a non-proportional [structure]
    /// damping matrix, written as K is written as springs (Spring::from_structure).
    bool from_structure = false;

    Direction direction() const { return {a, b}; }
};

namespace spring {
/// A spring is a link of stiffness k, Rayleigh damping beta k, rest length 0.
template <class T, class V>
void forces(const Direction& d, const T& k, const T& beta, V&& visit) {
    visit.link(d, k, beta * k, visit.zero());
}
}  // namespace spring

namespace damper {
/// A dashpot is a link of stiffness 0 and damping c.
template <class T, class V>
void forces(const Direction& d, const T& c, V&& visit) {
    visit.link(d, visit.zero(), c, visit.zero());
}
}  // namespace damper

}  // namespace hsnc
