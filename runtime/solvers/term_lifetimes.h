// hsnc -- the bookkeeping of SegmentSolver::resolving_rate for the solvers
// that know the terms of their motion (generic_solver.h, state_space_solver.h):
// each decaying term's rate and the instant from which it is below the
// tolerance, worked out once per segment.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace hsnc {

class TermLifetimes {
public:
    /// Forget the terms of the last segment; `forced` is the rate that counts
    /// throughout (the forcing's frequencies, terms that never decay).
    void start(double forced, double tol) {
        forced_ = forced;
        tol_ = tol;
        terms_.clear();
        valid_ = true;
    }
    void reserve(std::size_t n) { terms_.reserve(n); }
    /// Terms of the segment to come (setup calls it): resolving_rate starts anew.
    void invalidate() { valid_ = false; }
    bool valid(double tol) const { return valid_ && tol == tol_; }
    void raise_forced(double rate) { forced_ = std::max(forced_, rate); }
    double forced() const { return forced_; }

    /// A term of rate `rate` (rad/s) whose size at tau = 0 is `share` of its
    /// coordinate's and which decays as e^{-decay tau}: it counts while
    /// share e^{-decay tau} > tol (for ever when it does not decay).
    void add(double rate, double decay, double share) {
        if (!(rate > forced_) || !(share > tol_)) return;
        const double until = decay > 0 ? std::log(share / tol_) / decay : std::numeric_limits<double>::infinity();
        terms_.push_back({until, rate});
    }

    /// The fastest rate still counting at tau.
    double rate_at(double tau) const {
        double rate = forced_;
        for (const Term& t : terms_)
            if (t.until > tau) rate = std::max(rate, t.rate);
        return rate;
    }

private:
    struct Term {
        double until, rate;
    };
    std::vector<Term> terms_;
    double forced_ = 0.0, tol_ = 0.0;
    bool valid_ = false;
};

}  // namespace hsnc
