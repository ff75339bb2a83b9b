// hsnc tests -- tie models that both the double engine's tests
// (test_engine.cpp) and the reference's (test_reference.cpp) run, each against
// the same closed form.
#pragma once

namespace hsnc::test {

/// |A| = mu_s N at t0 with v = 0 and A' = A'' = 0, A'''= 6 > 0 (two harmonics
/// whose rates cancel): |A| is increasing, so the mass slides from t0 with no
/// release row, and v(t) = (cos(w t) + 2 cos t - 3 cos 2t)/9 with w^2 = 10 (the
/// closed form of x'' + 10 x = -5 + 2 sin t - sin 2t from x0 = -0.5, v0 = 0).
inline constexpr const char* kFrictionTieModel = R"(
name = "friction-tie"
[parameters]
g = 10
[[mass]]
name = "m1"
m = 1
mu_k = 0.5
[[spring]]
between = ["ground", "m1"]
k = 10
[[forcing]]
omega = 1
amplitude = { m1 = 2 }
[[forcing]]
omega = 2
amplitude = { m1 = -1 }
[initial]
x = { m1 = -0.5 }
)";

}  // namespace hsnc::test
