// hsnc -- a double as text that reads back as the same double (17 significant
// digits), for messages and outputs that name a time or a value: one printer,
// so every command and library message writes a number the same way.
#pragma once

#include <charconv>
#include <sstream>
#include <string>

namespace hsnc {

inline std::string number_text(double v) {
    std::ostringstream s;
    s.precision(17);
    s << v;
    return s.str();
}

/// The shortest text that reads back as v ("20", "0.1", "1e-05"), for
/// progress lines: not "2e+01", as the shortest %g would have it.
inline std::string shortest_text(double v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

}  // namespace hsnc
