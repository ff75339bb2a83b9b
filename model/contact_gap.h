// hsnc -- what a contact's gap means (interface.md, [[contact]]), written once
// for every scalar type (double, CLN's cl_F, GiNaC's ex):
//
//   G = x_a - x_b - gap   (a body named "ground" is at 0)
//
// G > 0: the contact is engaged and acts as a spring k between a and b whose
// force on a is -k G (on b, +k G); split as -k (x_a - x_b) in the stiffness
// matrix and the preload +k gap on a (-k gap on b) in the constant force.
// G < 0: open, no force. The gap switch function of a contact is G itself
// (segment.h), the same in the kernels (generator/lowering.cpp,
// generator/sweep_kernel_core.h print it).
#pragma once

namespace hsnc {

/// G = x_a - x_b - gap, from the two bodies' positions (0 for the ground).
template <class T>
T contact_gap(const T& xa, const T& xb, const T& gap) {
    return xa - xb - gap;
}

}  // namespace hsnc
