// hsnc -- a double as text that reads back as the same double (17 significant
// digits), for messages and outputs that name a time or a value: one printer,
// so every command and library message writes a number the same way.
#pragma once

#include <sstream>
#include <string>

namespace hsnc {

inline std::string number_text(double v) {
    std::ostringstream s;
    s.precision(17);
    s << v;
    return s.str();
}

}  // namespace hsnc
