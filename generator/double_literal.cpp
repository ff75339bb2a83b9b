#include "double_literal.h"

#include <cmath>
#include <cstdio>

namespace hsnc {

std::string format_double(double v) {
    if (std::isinf(v)) return v > 0 ? "__builtin_inf()" : "(-__builtin_inf())";
    if (v == 0.0) return "0.0";  // also -0
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    std::string s = buf;
    if (s.find_first_of(".e") == std::string::npos) s += ".0";
    return s;
}

}  // namespace hsnc
