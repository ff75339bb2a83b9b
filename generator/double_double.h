// hsnc -- DD: a double-double number, hi + lo with |lo| <= ulp(hi)/2, about
// 32 significant digits (106 bits) in plain double arithmetic: the working
// precision of the derivation (generator/derivation.h).
//
// The algorithms are the classical error-free transformations (Knuth's
// TwoSum, Dekker's product by splitting; no fma, so the results are the same
// with or without hardware fma) and the accurate double-double add, mul, div
// and sqrt of Hida, Li and Bailey's QD library (2001), each correct to a few
// units of 2^-104 relative. Every operation is deterministic: the derivation
// gives the same bits on every machine and every build of hsnc, which is
// what makes the printed kernels and the interpreter bit-identical.
//
// The range is that of double, less a factor 2^27 at the top (Dekker's split
// of |x| > 2^996 would overflow: no derivation quantity comes near it).
#pragma once

#include <cmath>

namespace hsnc {

class DD {
public:
    constexpr DD() = default;
    constexpr DD(double x) : hi_(x) {}  // NOLINT(google-explicit-constructor): a double is exact in DD
    constexpr DD(int x) : hi_(x) {}     // NOLINT(google-explicit-constructor)
    /// The quotient num / den, correct to double-double precision.
    static DD ratio(double num, double den) { return DD(num) / DD(den); }

    double hi() const { return hi_; }
    double lo() const { return lo_; }
    /// The nearest double (hi: the pair is normalised).
    double to_double() const { return hi_; }
    bool is_zero() const { return hi_ == 0.0; }

    friend DD operator-(const DD& a) { return DD(-a.hi_, -a.lo_); }

    friend DD operator+(const DD& a, const DD& b) {
        double e;
        double s = two_sum(a.hi_, b.hi_, e);
        double f;
        const double t = two_sum(a.lo_, b.lo_, f);
        e += t;
        s = quick_two_sum(s, e, e);
        e += f;
        s = quick_two_sum(s, e, e);
        return DD(s, e);
    }
    friend DD operator-(const DD& a, const DD& b) { return a + (-b); }

    friend DD operator*(const DD& a, const DD& b) {
        double e;
        const double p = two_prod(a.hi_, b.hi_, e);
        e += a.hi_ * b.lo_ + a.lo_ * b.hi_;
        const double s = quick_two_sum(p, e, e);
        return DD(s, e);
    }

    friend DD operator/(const DD& a, const DD& b) {
        // Three quotient digits: q1 + q2 + q3 (QD's accurate division).
        const double q1 = a.hi_ / b.hi_;
        DD r = a - b * DD(q1);
        const double q2 = r.hi_ / b.hi_;
        r = r - b * DD(q2);
        const double q3 = r.hi_ / b.hi_;
        double e;
        const double s = quick_two_sum(q1, q2, e);
        return DD(s, e) + DD(q3);
    }

    DD& operator+=(const DD& b) { return *this = *this + b; }
    DD& operator-=(const DD& b) { return *this = *this - b; }
    DD& operator*=(const DD& b) { return *this = *this * b; }
    DD& operator/=(const DD& b) { return *this = *this / b; }

    friend bool operator==(const DD& a, const DD& b) { return a.hi_ == b.hi_ && a.lo_ == b.lo_; }
    friend bool operator!=(const DD& a, const DD& b) { return !(a == b); }
    friend bool operator<(const DD& a, const DD& b) { return a.hi_ < b.hi_ || (a.hi_ == b.hi_ && a.lo_ < b.lo_); }
    friend bool operator>(const DD& a, const DD& b) { return b < a; }
    friend bool operator<=(const DD& a, const DD& b) { return !(b < a); }
    friend bool operator>=(const DD& a, const DD& b) { return !(a < b); }

    friend DD abs(const DD& a) { return a.hi_ < 0.0 ? -a : a; }

    /// sqrt(a) for a >= 0 (0 for a = 0; NaN below): one Newton step from the
    /// double root (Karp's trick, QD's sqrt).
    friend DD sqrt(const DD& a) {
        if (a.hi_ == 0.0) return DD();
        if (a.hi_ < 0.0) return DD(std::nan(""));
        const double x = 1.0 / std::sqrt(a.hi_);
        const double ax = a.hi_ * x;
        double e;
        const double sq = two_prod(ax, ax, e);
        const DD diff = a - DD(sq, e);
        return DD(ax) + DD(diff.hi_ * (x * 0.5));
    }

    /// x^k for an integer k >= 0 (repeated squaring).
    friend DD pow(DD x, unsigned k) {
        DD r(1.0);
        for (; k; k >>= 1, x = x * x)
            if (k & 1u) r = r * x;
        return r;
    }

private:
    constexpr DD(double hi, double lo) : hi_(hi), lo_(lo) {}

    static double two_sum(double a, double b, double& err) {
        const double s = a + b, bb = s - a;
        err = (a - (s - bb)) + (b - bb);
        return s;
    }
    static double quick_two_sum(double a, double b, double& err) {  // |a| >= |b|
        const double s = a + b;
        err = b - (s - a);
        return s;
    }
    static void split(double a, double& hi, double& lo) {
        const double t = 134217729.0 * a;  // 2^27 + 1
        hi = t - (t - a);
        lo = a - hi;
    }
    static double two_prod(double a, double b, double& err) {
        const double p = a * b;
        double ah, al, bh, bl;
        split(a, ah, al);
        split(b, bh, bl);
        err = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
        return p;
    }

    double hi_ = 0.0, lo_ = 0.0;
};

/// A complex number of two DD parts: the state-space eigenproblem of dampers.
struct DDComplex {
    DD re, im;
    constexpr DDComplex() = default;
    constexpr DDComplex(DD r, DD i = DD()) : re(r), im(i) {}  // NOLINT(google-explicit-constructor)

    friend DDComplex operator-(const DDComplex& a) { return {-a.re, -a.im}; }
    friend DDComplex operator+(const DDComplex& a, const DDComplex& b) { return {a.re + b.re, a.im + b.im}; }
    friend DDComplex operator-(const DDComplex& a, const DDComplex& b) { return {a.re - b.re, a.im - b.im}; }
    friend DDComplex operator*(const DDComplex& a, const DDComplex& b) {
        return {a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re};
    }
    /// a / b = a conj(b) / |b|^2 (|b| far from DD's range limits here).
    friend DDComplex operator/(const DDComplex& a, const DDComplex& b) {
        const DD d = b.re * b.re + b.im * b.im;
        return {(a.re * b.re + a.im * b.im) / d, (a.im * b.re - a.re * b.im) / d};
    }
    friend DDComplex conj(const DDComplex& a) { return {a.re, -a.im}; }
    /// |a| to double precision (pivots, tolerances).
    friend double magnitude(const DDComplex& a) { return std::hypot(a.re.to_double(), a.im.to_double()); }
    bool is_zero() const { return re.is_zero() && im.is_zero(); }
};

}  // namespace hsnc
