// hsnc -- the Jenkins element (interface.md section 5): a spring k in series
// with a massless slider that slips at slip_force F_s, along its direction u
// (direction.h). The slider position s is state (the engine carries it after
// the masses' positions, Model::state_size); the stretch is e = u - s.
//
//   stuck:     force -k e along w (a link like a closed contact whose gap is s)
//              switches slip_pos  k e - F_s,  slip_neg  -k e - F_s
//   slipping:  the constant force -sigma F_s along w, sigma = the sign of the
//              stretch, held at e = sigma F_s / k (s follows u)
//              switch slip_velocity  u' (it sticks where u' reaches 0 and the
//              relative acceleration does not keep the slip's sign)
//
// The functions below are the only place these are written: every back end
// instantiates them with its own scalar and motion (direction.h).
#pragma once

#include <string>
#include <vector>

#include "direction.h"
#include "motion.h"

namespace hsnc {

struct Jenkins {
    std::string name;
    int a = kGround;
    int b = kGround;
    double k = 0.0;           ///< > 0
    double slip_force = 0.0;  ///< F_s > 0
    /// A general direction (`direction = { dof = w, ... }`): u = sum w_i x_i;
    /// empty for `between = [a, b]`, u = x[a] - x[b].
    std::vector<Weight> weights;

    Direction direction() const {
        return {a, b, weights.empty() ? nullptr : weights.data(), static_cast<int>(weights.size())};
    }
};

namespace jenkins {

/// The slider position that leaves the spring unstretched at positions x
/// (one per mass): s = u = w^T x.
inline double unstretched_slider(const Jenkins& j, const double* x) {
    const double* rows[] = {x};
    return along(j.direction(), double_motion(rows), 0);
}

/// d^k/dt^k of sigma k e - F_s (sigma = +1 slip_pos, -1 slip_neg) while stuck:
/// sigma k (u^(k) - [k = 0] s) - [k = 0] F_s.
template <class M, class T>
auto slip_value(int sigma, const T& k, const T& slip_force, const Direction& d, const T& s, const M& m, int order) {
    const T ks = sigma > 0 ? k : -k;
    auto u = along(d, m, order);
    return order == 0 ? ks * (u - s) - slip_force : ks * u;
}

/// The magnitude of slip_value's terms: k (|u^(k)| + [k = 0] |s|) + [k = 0] F_s.
template <class M, class T>
auto slip_magnitude(const T& k, const T& slip_force, const Direction& d, const T& s, const M& m, int order) {
    auto u = along_magnitude(d, m, order);
    return order == 0 ? k * (u + m.abs(s)) + slip_force : k * u;
}

/// d^k/dt^k of the relative velocity u' while slipping (slip_velocity).
template <class M>
auto slip_velocity_value(const Direction& d, const M& m, int k) {
    return along(d, m, k + 1);
}
template <class M>
auto slip_velocity_magnitude(const Direction& d, const M& m, int k) {
    return along_magnitude(d, m, k + 1);
}

/// d^k/dt^k of the stretch e = u - s while stuck (the slider s at rest).
template <class M, class T>
auto stretch(const Direction& d, const T& s, const M& m, int order) {
    auto u = along(d, m, order);
    return order == 0 ? u - s : u;
}

/// The spring's force magnitude k e at stretch e (its force on body a is
/// minus this along w, the slider's is plus), and its energy 1/2 k e^2.
template <class T>
T spring_force(const T& k, const T& e) {
    return k * e;
}
template <class T>
T energy(const T& k, const T& e) {
    return T(0.5) * k * e * e;
}

/// The stretch held while slipping with sign `slip`: slip F_s / k.
template <class T>
T held_stretch(int slip, const T& k, const T& slip_force) {
    return slip > 0 ? slip_force / k : -(slip_force / k);
}

/// The constant force on body a (its opposite on b) while slipping: -slip F_s.
template <class T>
T slipping_force(int slip, const T& slip_force) {
    return slip > 0 ? -slip_force : slip_force;
}

/// Stuck (slip = 0), a link of stiffness k, Rayleigh damping beta k and rest
/// length s (the slider); slipping with sign `slip`, the constant force
/// -slip F_s along w.
template <class T, class V>
void forces(int slip, const Direction& d, const T& k, const T& slip_force, const T& s, const T& beta, V&& visit) {
    if (slip == 0)
        visit.link(d, k, beta * k, s);
    else
        visit.force(d, slipping_force(slip, slip_force));
}

}  // namespace jenkins
}  // namespace hsnc
