// A bank of friction oscillators for the tests of segments carried over
// switches (tests/test_restart.cpp, tests/test_kernels_cli.cpp): n unit
// masses, each on a spring of its own to ground (k_i = 100 + 10 i N/m),
// neighbours coupled by 20 N/m, friction on each (mu_k 0.05, mu_s 0.06),
// beta = 0.002, forced at 7 rad/s. Reversals keep its configuration.
#pragma once

#include <string>

namespace hsnc::testing {

/// The model file: `amplitude(i)` is mass i's forcing amplitude (1-based),
/// every mass starts at x0 (0: at rest at the origin, no [initial]).
template <class Amplitude>
std::string friction_bank(const std::string& name, int n, Amplitude amplitude, double x0) {
    auto m = [](int i) { return "m" + std::to_string(i); };
    std::string t = "name = \"" + name + "\"\n[damping]\nbeta = 0.002\n";
    for (int i = 1; i <= n; ++i) t += "[[mass]]\nname = \"" + m(i) + "\"\nm = 1\nmu_k = 0.05\nmu_s = 0.06\n";
    for (int i = 1; i <= n; ++i)
        t += "[[spring]]\nbetween = [\"ground\", \"" + m(i) + "\"]\nk = " + std::to_string(100 + 10 * i) + "\n";
    for (int i = 1; i < n; ++i) t += "[[spring]]\nbetween = [\"" + m(i) + "\", \"" + m(i + 1) + "\"]\nk = 20\n";
    std::string forced;
    for (int i = 1; i <= n; ++i)
        if (amplitude(i) != 0.0) forced += (forced.empty() ? "" : ", ") + m(i) + " = " + std::to_string(amplitude(i));
    t += "[[forcing]]\nomega = 7.0\namplitude = { " + forced + " }\n";
    if (x0 != 0.0) {
        t += "[initial]\nx = { ";
        for (int i = 1; i <= n; ++i) t += (i > 1 ? ", " : "") + m(i) + " = " + std::to_string(x0);
        t += " }\n";
    }
    return t;
}

}  // namespace hsnc::testing
