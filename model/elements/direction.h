// hsnc -- the direction an element acts along, and the motion it reads.
//
// Every nonlinear element acts on one coordinate of the structure,
// u = w^T x (the force direction vector of the field's convention): between
// two bodies, w = e_a - e_b (a body named `ground` is at 0, kGround), so
// u = x_a - x_b, or along a general w (`direction = { dof = w }`, contacts
// for now). The element files below compute u, its time derivatives and the
// magnitude of their terms only through along() and along_magnitude(); the
// back ends that stamp links between two bodies take a general w through
// PairLinks (k w w^T as pair links, below), so a general w changes this
// file and the readers, not the elements.
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

#include <utility>

namespace hsnc {

/// Body index of the ground (position 0, never moves).
inline constexpr int kGround = -1;

/// One term w_i e_i of a general direction.
struct Weight {
    int body = kGround;
    double w = 0.0;
};

/// The direction an element acts along: w = e_a - e_b between bodies a and b
/// (either may be kGround), or, when `count` > 0, the general
/// w = sum_i terms[i].w e_{terms[i].body} (the element's own storage; a and b
/// are then unused).
struct Direction {
    int a = kGround;
    int b = kGround;
    const Weight* terms = nullptr;
    int count = 0;

    bool weighted() const { return count > 0; }
};

/// u^(k) = w^T x^(k). A motion M that reads general directions also supplies
///     T M::weight(double w) const   // w in T, exactly
template <class M>
auto along(const Direction& d, const M& m, int k) {
    if (!d.weighted()) return m.x(k, d.a) - m.x(k, d.b);
    auto u = m.weight(d.terms[0].w) * m.x(k, d.terms[0].body);
    for (int i = 1; i < d.count; ++i) u = u + m.weight(d.terms[i].w) * m.x(k, d.terms[i].body);
    return u;
}

/// The magnitude of u^(k)'s terms: |w|^T mag^(k).
template <class M>
auto along_magnitude(const Direction& d, const M& m, int k) {
    if (!d.weighted()) return m.mag(k, d.a) + m.mag(k, d.b);
    auto u = m.weight(d.terms[0].w < 0 ? -d.terms[0].w : d.terms[0].w) * m.mag(k, d.terms[0].body);
    for (int i = 1; i < d.count; ++i)
        u = u + m.weight(d.terms[i].w < 0 ? -d.terms[i].w : d.terms[i].w) * m.mag(k, d.terms[i].body);
    return u;
}

/// fn(body, w_i) for every body the direction acts on (the ground left out).
template <class Fn>
void for_each_term(const Direction& d, Fn&& fn) {
    if (!d.weighted()) {
        if (d.a != kGround) fn(d.a, 1.0);
        if (d.b != kGround) fn(d.b, -1.0);
        return;
    }
    for (int i = 0; i < d.count; ++i)
        if (d.terms[i].body != kGround) fn(d.terms[i].body, d.terms[i].w);
}

/// Whether body i is one the direction acts on.
inline bool acts_on(const Direction& d, int i) {
    bool on = false;
    for_each_term(d, [&](int body, double) { on = on || body == i; });
    return on;
}

/// A link along a general direction in the two-body vocabulary of the back
/// ends that stamp links between two bodies: k w w^T is
///     sum_{i<j} (-k w_i w_j) (e_i - e_j)(e_i - e_j)^T + sum_i k w_i (sum_j w_j) e_i e_i^T,
/// the decomposition a [structure]'s K is read with (spring.h), so
/// pair(a, b, k_ab, c_ab) gets each pair link (b = kGround for the diagonal
/// rest, left out where sum_j w_j = 0, as for e_a - e_b) and force(i, f_i)
/// the preload k length w_i.
/// weight(w) is w in the back end's scalar T, exactly.
template <class T, class Weigh, class Pair, class Force>
void as_pair_links(const Direction& d, const T& k, const T& c, const T& length, const Weigh& weight, Pair&& pair,
                   Force&& force) {
    double sum = 0.0;  // sum_j w_j: whether the diagonal rest is there (zero for e_a - e_b)
    for (int i = 0; i < d.count; ++i) sum += d.terms[i].w;
    T sum_t = weight(d.terms[0].w);  // and its value, in T
    for (int i = 1; i < d.count; ++i) sum_t = sum_t + weight(d.terms[i].w);
    for (int i = 0; i < d.count; ++i) {
        const Weight& ti = d.terms[i];
        for (int j = i + 1; j < d.count; ++j) {
            const Weight& tj = d.terms[j];
            const T wij = -(weight(ti.w) * weight(tj.w));
            pair(ti.body, tj.body, wij * k, wij * c);
        }
        if (sum != 0.0) {
            const T wi = weight(ti.w) * sum_t;
            pair(ti.body, kGround, wi * k, wi * c);
        }
        force(ti.body, weight(ti.w) * k * length);
    }
}

/// A visitor (the vocabulary above) that hands a link or a constant force
/// along a general direction to `inner` as links between two bodies and
/// forces on one (as_pair_links), and the rest as it comes: so a back end's
/// visitor is written for two bodies once and takes every direction.
/// weight(w) is w in the back end's scalar, exactly.
template <class V, class Weigh>
struct PairLinks {
    V& inner;
    Weigh weight;
    template <class T>
    void link(const Direction& d, const T& k, const T& c, const T& length) {
        if (!d.weighted()) return inner.link(d, k, c, length);
        as_pair_links(d, k, c, length, weight,
                      [&](int a, int b, const auto& kab, const auto& cab) { inner.link(Direction{a, b}, kab, cab, inner.zero()); },
                      [&](int i, const auto& f) { inner.force(Direction{i, kGround}, f); });
    }
    template <class T>
    void force(const Direction& d, const T& f) {
        if (!d.weighted()) return inner.force(d, f);
        for_each_term(d, [&](int i, double w) { inner.force(Direction{i, kGround}, weight(w) * f); });
    }
    auto zero() const { return inner.zero(); }
};
template <class V, class Weigh>
PairLinks<V, Weigh> pair_links(V& inner, Weigh weight) {
    return {inner, std::move(weight)};
}

}  // namespace hsnc
