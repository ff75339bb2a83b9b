// hsnc -- printing GiNaC expressions in a reproducible term order.
//
// GiNaC orders the terms of a sum and the factors of a product by symbol
// serial numbers and hashes, so its own output depends on how many symbols a
// process created before. This printer sorts instead: terms of a sum by their
// printed text (ignoring a leading minus sign), constants last; factors of a
// product by kind (number, symbol, power, function, sum) and then text; factors
// with a negative exponent go to a denominator. The text form reads back with
// GiNaC's parser (`^` for powers, `sqrt(...)`); the LaTeX form uses \frac,
// \sqrt and the symbols' TeX names.
#pragma once

#include <ginac/ginac.h>

#include <string>

namespace hsnc {

enum class ExpressionFormat { text, latex };

/// `e` printed in sorted term order (see above).
std::string print_sorted(const GiNaC::ex& e, ExpressionFormat format);

}  // namespace hsnc
