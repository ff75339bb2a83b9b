// hsnc -- a double as a C++ literal that reads back to the same double.
#pragma once

#include <string>

namespace hsnc {

/// 17 significant digits (max_digits10, so it round-trips), always a C double
/// literal ("2.0", "1.5e-07"); infinities as __builtin_inf().
std::string format_double(double v);

}  // namespace hsnc
