// hsnc -- the switch functions of a configuration: the functions of the state
// whose zero is a switch (a contact closes or opens, a sliding mass stops, a
// stuck mass releases). Every segment solver evaluates them in this order.
//
// Switch functions of a configuration, in this order (switch_functions()):
//   1. every contact c, in model order:       gap      g = G_c = x[a] - x[b] - gap_c
//   2. every mass i with friction, in order:
//        sliding:                             velocity g = v_i
//        stuck:                               release_pos g =  A_i - mu_s*N_i
//                                             release_neg g = -A_i - mu_s*N_i
//   3. every Jenkins element j, in order (stretch e = x[a] - x[b] - s_j):
//        stuck:                               slip_pos g =  k_j e - F_s
//                                             slip_neg g = -k_j e - F_s
//        slipping (stretch sign sigma):       slip_velocity g = w = v[a] - v[b]
// where A_i is the force on mass i from everything but friction (assembly.h)
// and N_i = m_i*g. The stuck-mass release condition |A_i| > mu_s*N_i is written
// as two smooth functions so that root finding never meets a kink.
#pragma once

#include <cstdint>
#include <vector>

#include "configuration.h"
#include "model.h"

namespace hsnc {

/// The kinds of switch function; the kernel ABI's HSNC_SWITCH_* carry the same
/// values (static_assert in runtime/solvers/kernel_solver.cpp). Each belongs to
/// one element kind, whose file in model/elements/ defines it.
enum class SwitchKind : std::uint8_t {
    gap,            ///< contact gap function G_c (elements/contact.h); element = contact index
    velocity,       ///< velocity of a sliding friction mass (elements/friction.h); element = mass index
    release_pos,    ///< A_i - mu_s*N_i of a stuck mass; element = mass index
    release_neg,    ///< -A_i - mu_s*N_i of a stuck mass; element = mass index
    slip_pos,       ///< k e - F_s of a stuck Jenkins element (elements/jenkins.h); element = its index
    slip_neg,       ///< -k e - F_s of a stuck Jenkins element
    slip_velocity,  ///< v[a] - v[b] of a slipping Jenkins element
};

/// Number of SwitchKind values (tables indexed by kind).
inline constexpr int kSwitchKinds = 7;

/// The kinds whose zero is a stop (a velocity that reaches 0, crossing or touching).
inline bool is_velocity(SwitchKind k) { return k == SwitchKind::velocity || k == SwitchKind::slip_velocity; }

struct SwitchFunction {
    SwitchKind kind;
    int element;
    bool operator==(const SwitchFunction& o) const { return kind == o.kind && element == o.element; }
};

/// The switch functions of `cfg`, in the documented order.
std::vector<SwitchFunction> switch_functions(const Model& model, const Configuration& cfg);

}  // namespace hsnc
