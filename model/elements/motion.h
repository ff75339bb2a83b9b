// hsnc -- the motion most back ends read an element's coordinate from
// (direction.h): rows[k][body] the k-th time derivative of every body's
// position (x, v, a, then a Taylor series' higher orders), mags[k][body] the
// magnitudes of their terms, or |rows[k][body]| when a back end has no
// separate magnitudes. Rows is anything indexable twice: an array of
// pointers, a vector of vectors (double, cl_F, ex).
#pragma once

#include <cmath>

#include "direction.h"

namespace hsnc {

/// w in T, exactly: T(w) for double; a back end whose T needs more (CLN's
/// cl_F at the precision of `like`, GiNaC's exact rational) specializes it
/// where it instantiates RowsMotion.
template <class T>
struct ExactWeight {
    static T of(double w, const T&) { return T(w); }
};

template <class T, class Rows>
class RowsMotion {
public:
    RowsMotion(const Rows& rows, const Rows* mags, const T& zero) : rows_(rows), mags_(mags), zero_(zero) {}
    T x(int k, int body) const { return body == kGround ? zero_ : T(rows_[k][body]); }
    T mag(int k, int body) const {
        if (body == kGround) return zero_;
        return mags_ ? T((*mags_)[k][body]) : abs(T(rows_[k][body]));
    }
    T abs(const T& v) const {
        using std::abs;
        return abs(v);
    }
    T weight(double w) const { return ExactWeight<T>::of(w, zero_); }

private:
    const Rows& rows_;
    const Rows* mags_;
    T zero_;
};

/// A motion over rows of doubles.
template <class Rows>
RowsMotion<double, Rows> double_motion(const Rows& rows, const Rows* mags = nullptr) {
    return RowsMotion<double, Rows>(rows, mags, 0.0);
}

}  // namespace hsnc
