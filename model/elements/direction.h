// hsnc -- the direction an element acts along, and the motion it reads.
//
// Every nonlinear element acts on one coordinate of the structure,
// u = w^T x (the force direction vector of the field's convention). Today an
// element acts between two bodies, w = e_a - e_b (a body named `ground` is at
// 0, kGround), so u = x_a - x_b; the element files below compute u, its time
// derivatives and the magnitude of their terms only through along() and
// along_magnitude(), so a general w changes this file and the readers, not
// the elements.
//
// A motion M is whatever a back end reads the state from, for any scalar T
// (double, CLN's cl_F, GiNaC's ex):
//     T M::x(int k, int body) const     // k-th time derivative of the body's position, 0 for the ground
//     T M::mag(int k, int body) const   // the magnitude of its terms (its rounding level), 0 for the ground
//     T M::abs(const T&) const          // |.| in T (only the magnitudes need it)
// k = 0 is the position, 1 the velocity, 2 the acceleration, and higher
// orders are a Taylor series' (runtime/engine/tie_series.h).
//
// What an element does to the structure in its current state is said by its
// forces(..., visit) in one vocabulary, for any scalar T:
//   visit.link(d, k, c, length)   a spring k and a dashpot c along direction d
//                                 (direction.h): force -k (u - length) - c u'
//                                 along w (on body a; the opposite on b)
//   visit.force(d, f)             a constant force f along w
//   visit.zero()                  the scalar 0 of the back end
// A back end supplies the visitor: it stamps K += k w w^T, C += c w w^T and
// the preload k length w (assembly.h, reference/mp_segment.cpp), or sums the
// force on one body or its time derivatives (the event rules, the tie
// series). So the force law of an element kind is written once, in its file;
// the link arithmetic once per back end, for every kind.
#pragma once

namespace hsnc {

/// Body index of the ground (position 0, never moves).
inline constexpr int kGround = -1;

/// w = e_a - e_b: an element between bodies a and b (either may be kGround).
struct Direction {
    int a = kGround;
    int b = kGround;
};

/// u^(k) = w^T x^(k).
template <class M>
auto along(const Direction& d, const M& m, int k) {
    return m.x(k, d.a) - m.x(k, d.b);
}

/// The magnitude of u^(k)'s terms: |w|^T mag^(k).
template <class M>
auto along_magnitude(const Direction& d, const M& m, int k) {
    return m.mag(k, d.a) + m.mag(k, d.b);
}

/// Whether body i is one the direction acts on.
inline bool acts_on(const Direction& d, int i) { return d.a == i || d.b == i; }

}  // namespace hsnc
